"""A hardened reader of untrusted XML: standard-library expat, no DTD, no entities.

An imported SpaceEx file comes from anyone, so the reader refuses, before any
expansion and with ``file:line:column``:

- any document type declaration (``<!DOCTYPE``): no DTD is read, so no entity
  can be declared (billion laughs) and no external entity or DTD is fetched;
- entity declarations and external entity references (a second line of
  defence: expat calls these handlers only inside a DTD, which is refused first);
- files over :data:`MAX_XML_BYTES` (refused from their size, unread), elements
  nested deeper than :data:`MAX_XML_DEPTH`, more than :data:`MAX_XML_ELEMENTS`
  elements (refused by a pass of expat that only counts them, before any node is
  built, when the file has more ``<`` than that: in about the time and memory of
  a bare expat parse);
- malformed XML (expat's own message, at expat's position).

Nothing is fetched and nothing is executed: processing instructions and
comments are ignored. The standard library is used rather than ``defusedxml``
because it needs no new dependency and is stricter here: SpaceEx files never
have a DTD, so refusing every DTD loses nothing, and expat's callbacks give
the line and column of every text chunk, which the error messages need.

Examples
--------
>>> root = parse_xml_text('<a x="1"><b>y &amp; z</b></a>', "m.xml")
>>> root.tag, root.attrs, root.children[0].text.text
('a', {'x': '1'}, 'y & z')
>>> str(root.children[0].text.where(2))  # the '&' written '&amp;' is at column 15
'm.xml:1:15'
>>> parse_xml_text('<!DOCTYPE a [<!ENTITY e "x">]><a>&e;</a>', "m.xml")
Traceback (most recent call last):
...
hybrid.errors.SpecError: m.xml:1:1: a document type declaration (<!DOCTYPE ...>) is refused: SpaceEx models have none, and a DTD can declare entities that expand without bound or fetch files
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from hybrid.errors import Position, SpecError

__all__ = [
    "MAX_XML_BYTES",
    "MAX_XML_DEPTH",
    "MAX_XML_ELEMENTS",
    "SourceText",
    "XmlNode",
    "parse_xml_bytes",
    "parse_xml_file",
    "parse_xml_text",
]

MAX_XML_BYTES = 16 * 1024 * 1024
"""Largest XML file accepted (16 MiB, the spec files' cap): beyond it a file is refused unread."""
MAX_XML_DEPTH = 64
"""Deepest element nesting accepted (a SpaceEx model needs four levels)."""
MAX_XML_ELEMENTS = 1_000_000
"""Most elements accepted in one document."""


@dataclass
class SourceText:
    """The text of an element with the file position of each of its characters.

    ``chunks`` holds ``(offset in text, line, column)`` for each piece expat
    reported; an entity reference such as ``&amp;`` is a piece of its own, so
    positions stay exact in the raw file.
    """

    file: str
    text: str = ""
    chunks: list[tuple[int, int, int]] = field(default_factory=list)
    start: Position | None = None

    def where(self, offset: int) -> Position:
        """The file position of character ``offset`` of :attr:`text`."""
        if not self.chunks:
            return self.start or Position(self.file)
        offset = max(0, min(offset, len(self.text)))
        chosen = self.chunks[0]
        for chunk in self.chunks:
            if chunk[0] <= offset:
                chosen = chunk
            else:
                break
        start, line, column = chosen
        piece = self.text[start:offset]
        newlines = piece.count("\n")
        if newlines:
            return Position(self.file, line + newlines, len(piece) - piece.rfind("\n"))
        return Position(self.file, line, column + len(piece))


@dataclass
class XmlNode:
    """An element: tag (namespace removed), attributes, children, text, position."""

    tag: str
    attrs: dict[str, str]
    position: Position
    children: list[XmlNode] = field(default_factory=list)
    text: SourceText = field(default_factory=lambda: SourceText("<xml>"))

    def find_all(self, tag: str) -> list[XmlNode]:
        """The children with this tag, in file order."""
        return [c for c in self.children if c.tag == tag]

    def find(self, tag: str) -> XmlNode | None:
        """The first child with this tag, or ``None``."""
        return next((c for c in self.children if c.tag == tag), None)


class _Refused(Exception):
    def __init__(self, message: str, line: int, column: int) -> None:
        super().__init__(message)
        self.message = message
        self.line = line
        self.column = column


class _Builder:
    """Expat callbacks that build :class:`XmlNode` trees and refuse what is dangerous."""

    def __init__(
        self, parser: expat.XMLParserType, file: str, lines: list[bytes], raw: bytes
    ) -> None:
        self.parser = parser
        self.raw = raw
        self.file = file
        self.lines = lines
        self.stack: list[XmlNode] = []
        self.root: XmlNode | None = None
        self.count = 0

    def here(self) -> tuple[int, int]:
        """Expat's current (line, 1-based column); expat counts columns in characters."""
        return self.parser.CurrentLineNumber, self.parser.CurrentColumnNumber + 1

    def refuse(self, message: str) -> None:
        raise _Refused(message, *self.here())

    def start(self, tag: str, attrs: dict[str, str]) -> None:
        self.count += 1
        if self.count > MAX_XML_ELEMENTS:
            self.refuse(f"more than {MAX_XML_ELEMENTS} elements: refused")
        if len(self.stack) >= MAX_XML_DEPTH:
            self.refuse(f"elements nested more than {MAX_XML_DEPTH} levels deep: refused")
        line, column = self.here()
        position = Position(self.file, line, column)
        node = XmlNode(tag.rsplit(" ", 1)[-1], dict(attrs), position)
        node.text = SourceText(self.file, start=position)
        if self.stack:
            self.stack[-1].children.append(node)
        else:
            self.root = node
        self.stack.append(node)

    def end(self, tag: str) -> None:
        self.stack.pop()

    def data(self, text: str) -> None:
        if not self.stack:
            return
        line, column = self.here()
        target = self.stack[-1].text
        target.chunks.append((len(target.text), line, column))
        target.text += text

    def doctype(self, *args: object) -> None:
        at = self.raw.find(b"<!DOCTYPE")
        line = self.raw.count(b"\n", 0, at) + 1 if at >= 0 else self.parser.CurrentLineNumber
        column = at - (self.raw.rfind(b"\n", 0, at) + 1) if at >= 0 else 0
        raise _Refused(
            "a document type declaration (<!DOCTYPE ...>) is refused: SpaceEx models have none, "
            "and a DTD can declare entities that expand without bound or fetch files",
            line,
            _char_column(self.lines, line, column) + 1,
        )

    def entity(self, *args: object) -> None:
        self.refuse("entity declarations are refused (they can expand without bound)")

    def external(self, *args: object) -> int:
        self.refuse("external entities are refused: nothing is fetched")
        return 0


def _char_column(lines: list[bytes], line: int, byte_column: int) -> int:
    """A UTF-8 byte column (found in the raw bytes) in characters."""
    if 1 <= line <= len(lines):
        raw = lines[line - 1][:byte_column]
        if raw.isascii():
            return byte_column
        return len(raw.decode("utf-8", errors="replace"))
    return byte_column


def parse_xml_bytes(raw: bytes, file: str, *, max_bytes: int = MAX_XML_BYTES) -> XmlNode:
    """Parse untrusted XML bytes into an :class:`XmlNode` tree (see the module docstring).

    Raises
    ------
    SpecError
        ``file:line:column: message`` for anything refused or malformed.
    """
    if len(raw) > max_bytes:
        raise SpecError(
            f"file is {len(raw)} bytes, over the limit of {max_bytes} bytes: refused unread",
            Position(file),
        )
    utf8 = _declared_encoding(raw) in ("utf-8", "utf8", "")
    lines = raw.split(b"\n") if utf8 else []
    if raw.count(b"<") > MAX_XML_ELEMENTS:  # every element starts with '<': else within the cap
        _refuse_too_many_elements(raw, file, lines)
    parser, builder = _hardened(_Builder, raw, file, lines)
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    parser.buffer_text = False
    try:
        parser.Parse(raw, True)
    except _Refused as exc:
        raise SpecError(exc.message, Position(file, exc.line, exc.column)) from None
    except expat.ExpatError as exc:
        line = exc.lineno or 1
        column = (exc.offset or 0) + 1
        message = expat.errors.messages.get(exc.code, str(exc)) if exc.code else str(exc)
        raise SpecError(f"malformed XML: {message}", Position(file, line, column)) from None
    except (ValueError, LookupError) as exc:  # unknown encoding names and the like
        raise SpecError(f"malformed XML: {exc}", Position(file)) from None
    if builder.root is None:
        raise SpecError("malformed XML: no element", Position(file))
    return builder.root


class _Counter(_Builder):
    """The builder's refusals, counting elements instead of building them."""

    def start(self, tag: str, attrs: dict[str, str]) -> None:
        self.count += 1
        if self.count > MAX_XML_ELEMENTS:
            self.refuse(f"more than {MAX_XML_ELEMENTS} elements: refused")

    def end(self, tag: str) -> None:
        pass


def _hardened(
    kind: type[_Builder], raw: bytes, file: str, lines: list[bytes]
) -> tuple[expat.XMLParserType, _Builder]:
    """An expat parser whose DTD, entity and element callbacks are ``kind``'s refusals."""
    parser = expat.ParserCreate(namespace_separator=" ")
    handler = kind(parser, file, lines, raw)
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    parser.StartDoctypeDeclHandler = handler.doctype
    parser.EntityDeclHandler = handler.entity
    parser.UnparsedEntityDeclHandler = handler.entity
    parser.ExternalEntityRefHandler = handler.external
    parser.StartElementHandler = handler.start
    return parser, handler


def _refuse_too_many_elements(raw: bytes, file: str, lines: list[bytes]) -> None:
    """A first pass of expat that refuses a document over the element cap, building nothing.

    Malformed XML and a document type declaration are left to the building pass
    (which refuses them with its own words) unless the cap is passed first.
    """
    parser, _ = _hardened(_Counter, raw, file, lines)
    try:
        parser.Parse(raw, True)
    except _Refused as exc:
        raise SpecError(exc.message, Position(file, exc.line, exc.column)) from None
    except (expat.ExpatError, ValueError, LookupError):
        return


def _declared_encoding(raw: bytes) -> str:
    head = raw[:200].lower()
    if not head.startswith(b"<?xml"):
        return ""
    marker = head.find(b"encoding=")
    if marker < 0:
        return ""
    rest = head[marker + 9 :]
    quote = rest[:1]
    end = rest.find(quote, 1)
    return rest[1:end].decode("ascii", errors="replace") if end > 0 else ""


def parse_xml_text(text: str, file: str = "<xml>") -> XmlNode:
    """Parse XML given as a string (encoded as UTF-8; an encoding declaration is dropped)."""
    if text.startswith("<?xml"):
        end = text.find("?>")
        if end > 0:
            text = text[end + 2 :]
    return parse_xml_bytes(text.encode("utf-8"), file)


def parse_xml_file(path: str | Path, *, max_bytes: int = MAX_XML_BYTES) -> XmlNode:
    """Parse an XML file; a file over ``max_bytes`` is refused from its size, unread."""
    name = str(path)
    try:
        size = os.stat(path).st_size
        if size > max_bytes:
            raise SpecError(
                f"file is {size} bytes, over the limit of {max_bytes} bytes: refused unread",
                Position(name),
            )
        with open(path, "rb") as handle:
            raw = handle.read(max_bytes + 1)
    except OSError as exc:
        raise SpecError(f"cannot read the file: {exc.strerror or exc}", Position(name)) from None
    return parse_xml_bytes(raw, name, max_bytes=max_bytes)
