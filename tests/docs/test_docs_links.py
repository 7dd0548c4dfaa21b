"""Every internal link of every page (and of README.md) points at something that exists.

Checked on the Markdown, as GitHub shows it: the target file exists, and a
``#anchor`` names a heading of the target page (GitHub's and MyST's anchors are
the same). Anchors of generated pages (the CLI and API references) are checked on
the built site instead (tests/docs/test_docs_site.py).
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
from doc_pages import heading_slugs, links, pages, slug
from support import DOCS, REPO

GENERATED_MARK = "<!-- hybrid-docs:"
SOURCES = [*pages(), REPO / "README.md"]


def _id(path: Path) -> str:
    return str(path.relative_to(REPO)) if path.is_relative_to(REPO) else path.name


def _broken(page: Path) -> list[str]:
    text = page.read_text(encoding="utf-8")
    found = []
    for link in links(text):
        parts = urlsplit(link.target)
        if parts.scheme or parts.netloc:
            continue
        target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
        where = f"{_id(page)}:{link.line}: {link.target}"
        if not target.exists():
            found.append(f"{where}: no such file")
            continue
        if parts.fragment and target.suffix == ".md":
            target_text = target.read_text(encoding="utf-8")
            if GENERATED_MARK not in target_text and parts.fragment not in heading_slugs(
                target_text
            ):
                found.append(f"{where}: no heading with that anchor")
    return found


@pytest.mark.parametrize("page", SOURCES, ids=_id)
def test_internal_links_resolve(page: Path) -> None:
    broken = _broken(page)
    assert not broken, "\n".join(broken)


def test_the_link_check_catches_a_broken_link_and_anchor(tmp_path: Path) -> None:
    (tmp_path / "a.md").write_text("# A\n\n## Some `code` here\n\nsee [b](b.md) and [x](#nope)\n")
    (tmp_path / "c.md").write_text("# C\n\n[ok](a.md#some-code-here) [bad](a.md#some-code)\n")
    assert [b.split(": ", 1)[1] for b in _broken(tmp_path / "a.md")] == [
        "b.md: no such file",
        "#nope: no heading with that anchor",
    ]
    assert len(_broken(tmp_path / "c.md")) == 1


def test_anchors_are_githubs() -> None:
    assert slug("Narrow guards and `--max-step`") == "narrow-guards-and---max-step"
    assert slug("YAML: what is read, and how") == "yaml-what-is-read-and-how"
    assert slug("`hybrid check`") == "hybrid-check"
    assert DOCS.is_dir()
