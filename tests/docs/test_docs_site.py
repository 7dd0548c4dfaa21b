"""The documentation site: it builds with warnings as errors, its generated references match
the code, its internal links resolve, and its pages render in a browser without errors.

The site is built once per session, into a temporary folder, exactly as ``make
docs`` builds it (``sphinx -W``). The screenshot test needs Debian's
``chromium``; it is skipped, saying so, where Chromium is not installed.
"""

from __future__ import annotations

import argparse
import functools
import html
import importlib
import io
import re
import runpy
import subprocess
import sys
import threading
from collections.abc import Iterator
from html.parser import HTMLParser
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import unquote, urlsplit

import matplotlib.image
import numpy as np
import pytest
from chromium import CHROMIUM, render
from support import DOCS, REPO

from hybrid.cli.main import build_parser


@pytest.fixture(scope="session")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("site")
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-b",
            "html",
            "-W",
            "--keep-going",
            "-q",
            "-d",
            str(out / "doctrees"),
            str(DOCS),
            str(out / "html"),
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, f"the site does not build:\n{result.stderr[-6000:]}"
    return out / "html"


def test_the_site_builds_with_warnings_as_errors(site: Path) -> None:
    for page in (
        "index",
        "getting-started",
        "composition",
        "export",
        "plots",
        "api",
        "cli-reference",
        "schema",
        "uvms",
        "semantics",
        "spec-language",
    ):
        assert (site / f"{page}.html").is_file(), page


class _Anchors(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.hrefs: list[str] = []
        self.images: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if values.get("id"):
            self.ids.add(str(values["id"]))
        if tag == "a" and values.get("href"):
            self.hrefs.append(str(values["href"]))
        if tag == "img" and values.get("src"):
            self.images.append(str(values["src"]))


@functools.cache
def _parsed(path: Path) -> _Anchors:
    parser = _Anchors()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


def _text(path: Path) -> str:
    return html.unescape(re.sub(r"<[^>]+>", " ", path.read_text(encoding="utf-8")))


def test_every_internal_link_of_the_built_site_resolves(site: Path) -> None:
    broken = []
    for page in sorted(site.rglob("*.html")):
        for href in _parsed(page).hrefs:
            parts = urlsplit(href)
            if parts.scheme or parts.netloc or href.startswith("mailto:"):
                continue
            target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{page.relative_to(site)}: {href}")
            elif (
                parts.fragment
                and target.suffix == ".html"
                and unquote(parts.fragment) not in _parsed(target).ids
            ):
                broken.append(f"{page.relative_to(site)}: {href} (no such anchor)")
    assert not broken, "broken links:\n" + "\n".join(broken[:40])


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_the_cli_reference_is_the_parser(site: Path) -> None:
    text = " ".join(_text(site / "cli-reference.html").split())
    ids = _parsed(site / "cli-reference.html").ids
    for name, command in _subcommands(build_parser()).items():
        assert f"hybrid-{name}" in ids, f"no section for 'hybrid {name}'"
        section = text.split(f"hybrid {name}", 1)[1]
        for action in command._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            for option in action.option_strings:
                assert option in section, f"hybrid {name} {option} is not in the reference"
            if action.help:
                assert " ".join(action.help.split()) in section, (
                    f"hybrid {name}: the help of {action.dest} is not in the reference"
                )


def _api_modules() -> list[str]:
    return list(runpy.run_path(str(DOCS / "conf.py"))["API_MODULES"])


def test_every_public_name_has_a_reference_page(site: Path) -> None:
    seen: set[int] = set()
    for module_name in _api_modules():
        module = importlib.import_module(module_name)
        for name in module.__all__:
            obj = getattr(module, name)
            if name.startswith("__") or id(obj) in seen:
                continue
            seen.add(id(obj))
            page = site / "api" / f"{module_name}.{name}.html"
            assert page.is_file(), f"{module_name}.{name} has no page"
            assert f"{module_name}.{name}" in _parsed(page).ids
    run_page = _text(site / "api" / "hybrid.Run.html")
    assert "to_pandas" in run_page and "Draw the run over hybrid time" in run_page


def test_the_schema_is_published_at_a_stable_path(site: Path) -> None:
    published = site / "schema" / "automaton.schema.json"
    assert published.read_bytes() == (DOCS / "schema" / "automaton.schema.json").read_bytes()


def test_figures_are_drawn_when_the_site_is_built(site: Path) -> None:
    images = [src for src in _parsed(site / "plots.html").images if "_images/" in src]
    assert len(images) == 3  # the ball, the ball against t and j, the UVMS mission
    for src in images:
        picture = matplotlib.image.imread(site / src)
        assert picture.shape[0] > 200 and picture.shape[1] > 500
        assert float(np.std(picture)) > 0.05  # not a blank image


@pytest.fixture(scope="module")
def served(site: Path) -> Iterator[str]:
    class Quiet(SimpleHTTPRequestHandler):
        def log_message(self, *args: object) -> None:
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(site)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    server.server_close()


@pytest.mark.skipif(
    CHROMIUM is None, reason="Chromium is not installed (Debian: apt-get install chromium)"
)
def test_pages_render_in_chromium_without_errors(served: str, tmp_path: Path) -> None:
    pages = render([served + "index.html", served + "getting-started.html"])
    for page, title in zip(pages, ("hybrid", "Getting started"), strict=True):
        assert page.errors == [], f"{page.url}: {page.errors}"
        assert page.outside_requests == [], f"{page.url} reaches outside: {page.outside_requests}"
        assert page.heading.rstrip("#").strip() == title
        assert page.title.startswith(title)
        picture = matplotlib.image.imread(io.BytesIO(page.screenshot), format="png")
        assert picture.shape[:2] == (900, 1280)
        assert float(np.std(picture[..., :3])) > 0.05  # something is drawn
        (tmp_path / Path(urlsplit(page.url).path).with_suffix(".png").name).write_bytes(
            page.screenshot
        )
