"""Reading the documentation pages as the tests need them: pages, code blocks, links, anchors.

Every Markdown page under docs/ is a page of the site, except the generated
ones (``GENERATED``). Conventions (docs/writing-docs.md):

- a fenced block whose language is ``python`` (or a ``{hybrid-plot}`` block) runs,
  in file order, in one namespace per page, from the repository root;
- a block right after the comment ``<!-- docs: no-run: REASON -->`` does not run;
- any other language (``console``, ``yaml``, ``text``, ``toml``...) is shown, not run.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from support import DOCS

__all__ = [
    "GENERATED",
    "NO_RUN",
    "RUNNABLE",
    "Block",
    "Link",
    "code_blocks",
    "heading_slugs",
    "links",
    "outside_fences",
    "pages",
]

GENERATED = frozenset({"_build", "_generated", "api", "_static", "_templates", "_ext"})
"""Folders under docs/ that hold no hand-written page (written by the build, or support files)."""

RUNNABLE = frozenset({"python", "py", "{hybrid-plot}"})
NO_RUN = re.compile(r"^<!--\s*docs:\s*no-run\b(?P<reason>.*?)-->\s*$")

_FENCE = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})(?P<info>[^`]*)$")
_LINK = re.compile(
    r"(?<!!)\[(?P<text>[^\]]*)\]\((?P<target>[^)\s]+)\)|!\[[^\]]*\]\((?P<image>[^)\s]+)\)"
)
_HEADING = re.compile(r"^(#{1,6})\s+(?P<title>.+?)\s*#*\s*$")


def pages() -> list[Path]:
    """Every hand-written page under docs/, sorted."""
    return sorted(
        p for p in DOCS.rglob("*.md") if not (set(p.relative_to(DOCS).parts[:-1]) & GENERATED)
    )


@dataclass(frozen=True)
class Block:
    """A fenced code block: its language, code, first line of code, and the no-run reason."""

    language: str
    code: str
    line: int
    no_run: str | None

    @property
    def runs(self) -> bool:
        return self.language in RUNNABLE and self.no_run is None


def code_blocks(text: str) -> list[Block]:
    """The fenced code blocks of a Markdown text, outermost only, in order."""
    lines = text.splitlines()
    blocks: list[Block] = []
    i = 0
    while i < len(lines):
        match = _FENCE.match(lines[i])
        if not match:
            i += 1
            continue
        fence, info = match.group("fence"), match.group("info").strip()
        language = info.split()[0] if info else ""
        previous = next((lines[k] for k in range(i - 1, -1, -1) if lines[k].strip()), "")
        marker = NO_RUN.match(previous.strip())
        body: list[str] = []
        j = i + 1
        while j < len(lines):
            close = _FENCE.match(lines[j])
            if close and _closes(close, fence):
                break
            body.append(lines[j])
            j += 1
        if language.startswith("{"):
            while body and body[0].startswith(":"):  # a directive's options
                body.pop(0)
        code = "\n".join(body)
        blocks.append(
            Block(
                language, code + "\n", i + 2, marker.group("reason").strip(" :") if marker else None
            )
        )
        i = j + 1
    return blocks


@dataclass(frozen=True)
class Link:
    """A Markdown link or image: its target and the line it is on."""

    target: str
    line: int


def _closes(match: re.Match[str], fence: str) -> bool:
    found = match.group("fence")
    return found[0] == fence[0] and len(found) >= len(fence) and not match.group("info").strip()


def outside_fences(text: str) -> list[tuple[int, str]]:
    """``(line number, line)`` of every line that is not inside a fenced block."""
    out = []
    fence: str | None = None
    for number, line in enumerate(text.splitlines(), start=1):
        match = _FENCE.match(line)
        if match:
            if fence is None:
                fence = match.group("fence")
            elif _closes(match, fence):
                fence = None
            continue
        if fence is None:
            out.append((number, line))
    return out


def links(text: str) -> list[Link]:
    """Every link and image target outside code."""
    found = []
    for number, line in outside_fences(text):
        for match in _LINK.finditer(re.sub(r"`[^`]*`", "", line)):
            found.append(Link(match.group("target") or match.group("image"), number))
    return found


def slug(title: str) -> str:
    """The anchor GitHub and MyST (``myst_heading_anchors``) give a heading."""
    title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)  # a link: its text
    title = title.replace("`", "").strip().lower()
    return re.sub(r"[^\w\- ]", "", title).replace(" ", "-")


def heading_slugs(text: str) -> set[str]:
    """The anchors of every heading of a page (outside code)."""
    slugs = set()
    for _, line in outside_fences(text):
        match = _HEADING.match(line)
        if match:
            slugs.add(slug(match.group("title")))
    return slugs
