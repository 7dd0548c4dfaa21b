"""Safe YAML reading that remembers where every key and value came from.

Only plain data is accepted: mappings, sequences and scalars. Anchors and
aliases, explicit tags, duplicate keys, non-UTF-8 bytes, files over
:data:`MAX_FILE_BYTES` and collections nested deeper than :data:`MAX_YAML_DEPTH`
are refused with a position. Plain scalars resolve as in the YAML 1.2 core
schema: booleans are ``true``/``false`` only, so a location named ``on`` or
``off`` stays a string; ``017`` is seventeen (not octal), ``1e3`` and ``1.0e3``
are numbers, and ``1:30``, ``1_000``, ``0b101`` or ``2001-12-14`` stay strings.

Examples
--------
>>> doc = read_yaml_text("a: 1\\nb: [x, y]\\n", "f.yaml")
>>> doc.data
{'a': 1, 'b': ['x', 'y']}
>>> str(doc.positions.value(("b", 1)))
'f.yaml:2:8'
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from hybrid.errors import Position, SpecError
from hybrid.reader.files import MAX_FILE_BYTES, read_bytes
from hybrid.reader.yamlhints import bang_at, cut_expression, tab_at

__all__ = [
    "MAX_FILE_BYTES",
    "MAX_YAML_DEPTH",
    "PositionMap",
    "YamlDocument",
    "read_yaml_file",
    "read_yaml_text",
]

MAX_YAML_DEPTH = 64
"""Deepest nesting of mappings and sequences accepted (a spec needs about six)."""

_PLAIN_TAGS = {
    "tag:yaml.org,2002:str",
    "tag:yaml.org,2002:int",
    "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:bool",
    "tag:yaml.org,2002:null",
    "tag:yaml.org,2002:map",
    "tag:yaml.org,2002:seq",
}

Path_ = tuple[str | int, ...]


class _Resolver(yaml.resolver.Resolver):
    """YAML 1.1 resolution minus its surprises: 1.2 core booleans and numbers, no timestamps.

    (YAML 1.1 reads ``on``/``no`` as booleans, ``017`` as octal 15, ``1:30`` as
    90 and ``1.0e3`` as a string.)
    """


_REPLACED = (
    "tag:yaml.org,2002:bool",
    "tag:yaml.org,2002:int",
    "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:timestamp",
)
_Resolver.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag not in _REPLACED]
    for first, resolvers in yaml.resolver.Resolver.yaml_implicit_resolvers.items()
}
_Resolver.add_implicit_resolver(
    "tag:yaml.org,2002:bool",
    re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
    list("tTfF"),
)
# int before float: the 1.2 float pattern also matches whole numbers
_Resolver.add_implicit_resolver(
    "tag:yaml.org,2002:int",
    re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"),
    list("-+0123456789"),
)
_Resolver.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(
        r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
        r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"
    ),
    list("-+0123456789."),
)


class _Checks(yaml.composer.Composer):
    """Our composer: refuses aliases, anchors, tags and deep nesting at each node."""

    _depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        event = self.peek_event()  # type: ignore[attr-defined]
        if isinstance(event, yaml.AliasEvent):
            raise _Refused("YAML aliases (*name) are not allowed in specs", event.start_mark)
        anchor = getattr(event, "anchor", None)
        if anchor is not None:
            raise _Refused("YAML anchors (&name) are not allowed in specs", event.start_mark)
        tag = getattr(event, "tag", None)
        if tag == "!":  # YAML's non-specific tag: '! x > 3' would read as 'x > 3'
            raise _Refused(
                "'!' is not negation here (YAML reads '! ' as a tag and drops it): write 'not'",
                event.start_mark,
            )
        if tag is not None:
            raise _Refused(
                f"YAML tags ({tag}) are not allowed in specs"
                + ("; if '!' meant negation, write 'not'" if tag.startswith("!") else ""),
                event.start_mark,
            )
        if isinstance(event, yaml.CollectionStartEvent):
            if self._depth >= MAX_YAML_DEPTH:
                raise _Refused(
                    f"YAML is nested more than {MAX_YAML_DEPTH} levels deep", event.start_mark
                )
            self._depth += 1
            try:
                return super().compose_node(parent, index)
            finally:
                self._depth -= 1
        return super().compose_node(parent, index)


class _PyLoader(
    _Checks,
    yaml.reader.Reader,
    yaml.scanner.Scanner,
    yaml.parser.Parser,
    _Resolver,
):
    """Pure-Python scanning and parsing."""

    def __init__(self, stream: str) -> None:
        yaml.reader.Reader.__init__(self, stream)
        yaml.scanner.Scanner.__init__(self)
        yaml.parser.Parser.__init__(self)
        yaml.composer.Composer.__init__(self)
        _Resolver.__init__(self)


_CParser: Any = None
if getattr(yaml, "__with_libyaml__", False):
    import yaml.cyaml

    _CParser = getattr(yaml.cyaml, "CParser", None)

if _CParser is not None:

    class _CLoader(_Checks, _CParser, _Resolver):  # type: ignore[misc]
        """libyaml scans and parses (in C); our composer, first in the MRO, builds the nodes."""

        def __init__(self, stream: str) -> None:
            _CParser.__init__(self, stream)
            yaml.composer.Composer.__init__(self)
            _Resolver.__init__(self)

    _Loader: type = _CLoader
else:  # pragma: no cover - libyaml ships in PyYAML's wheels
    _Loader = _PyLoader


class _Refused(Exception):
    def __init__(self, message: str, mark: Any) -> None:
        super().__init__(message)
        self.message = message
        self.mark = mark


@dataclass
class PositionMap:
    """Where each node of a document starts, by path of keys and indices."""

    file: str
    keys: dict[Path_, Position] = field(default_factory=dict)
    values: dict[Path_, Position] = field(default_factory=dict)

    def value(self, path: Path_) -> Position:
        """Position of the value at ``path``, or of its nearest recorded ancestor."""
        return self._nearest(self.values, path)

    def key(self, path: Path_) -> Position:
        """Position of the key that ends ``path`` (falls back to the value's)."""
        if path in self.keys:
            return self.keys[path]
        return self.value(path)

    def _nearest(self, table: dict[Path_, Position], path: Path_) -> Position:
        for end in range(len(path), -1, -1):
            pos = table.get(path[:end])
            if pos is not None:
                return pos
        return Position(self.file)


@dataclass
class YamlDocument:
    """Plain data read from YAML, with the position of every node."""

    data: Any
    positions: PositionMap


def _position(file: str, mark: Any) -> Position:
    return Position(file, mark.line + 1, mark.column + 1)


def read_yaml_file(
    path: str | Path, *, max_bytes: int = MAX_FILE_BYTES, where: Position | None = None
) -> YamlDocument:
    """Read a spec file safely; every refusal is a :class:`SpecError` with a place.

    Only a regular file is read, and at most ``max_bytes`` of it
    (:func:`~hybrid.reader.files.read_bytes`); ``where`` is the position an
    error reading the file points at (default: the file itself).
    """
    raw = read_bytes(path, max_bytes=max_bytes, where=where)
    return read_yaml_bytes(raw, str(path), max_bytes=max_bytes)


def read_yaml_bytes(raw: bytes, file: str, *, max_bytes: int = MAX_FILE_BYTES) -> YamlDocument:
    """Decode UTF-8 strictly, then read as :func:`read_yaml_text`."""
    if len(raw) > max_bytes:
        raise SpecError(
            f"spec is {len(raw)} bytes, over the limit of {max_bytes} bytes", Position(file)
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = raw[: exc.start]
        line = before.count(b"\n") + 1
        column = len(before) - (before.rfind(b"\n") + 1) + 1
        raise SpecError(
            f"file is not valid UTF-8: byte 0x{raw[exc.start]:02x} cannot be decoded",
            Position(file, line, column),
        ) from None
    return read_yaml_text(text, file, max_bytes=max_bytes)


# YAML's printable set (YAML 1.2, 5.1): tab, line breaks and printable Unicode.
_NOT_PRINTABLE = re.compile(
    "[^\x09\x0a\x0d\x20-\x7e\x85\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]"
)


def read_yaml_text(
    text: str, file: str = "<string>", *, max_bytes: int = MAX_FILE_BYTES
) -> YamlDocument:
    """Parse YAML text into plain data plus a :class:`PositionMap`."""
    if len(text) > max_bytes:
        raise SpecError(
            f"spec is {len(text)} characters, over the limit of {max_bytes}", Position(file)
        )
    if text.startswith("\ufeff"):
        text = text[1:]
    if text.lstrip().startswith(("<?xml", "<sspaceex", "<!--")):
        raise SpecError(
            "this is XML, not a YAML spec; a SpaceEx model is imported first: "
            f"hybrid import spaceex {file} --out DIR",
            Position(file, 1, 1),
        )
    bad = _NOT_PRINTABLE.search(text)
    if bad is not None:
        at = bad.start()
        line = text.count("\n", 0, at) + 1
        column = at - (text.rfind("\n", 0, at) + 1) + 1
        raise SpecError(
            f"character U+{ord(bad.group()):04X} is not allowed in YAML "
            "(control characters other than tab and line breaks are refused)",
            Position(file, line, column),
        )
    try:
        node = _compose_checked(text)
    except _Refused as exc:
        raise SpecError(exc.message, _position(file, exc.mark)) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        problem = exc.problem or exc.context or "invalid YAML"
        pos = _position(file, mark) if mark is not None else Position(file)
        if mark is not None and tab_at(text, mark):
            problem = "a tab: YAML indents with spaces only (replace the tab with spaces)"
        elif mark is not None and (bang := bang_at(text, mark)) is not None:
            pos = Position(file, mark.line + 1, bang + 1)
            message = "'!' is not negation here (YAML reads it as a tag): write 'not'"
            raise SpecError(message, pos) from None
        raise SpecError(f"invalid YAML: {problem}", pos) from None
    except yaml.YAMLError as exc:
        raise SpecError(f"invalid YAML: {exc}", Position(file)) from None
    if node is None or (
        isinstance(node, yaml.ScalarNode)
        and node.tag == "tag:yaml.org,2002:null"
        and not node.value
    ):
        raise SpecError(
            "file is empty: a spec is a mapping starting with 'automaton:' or 'system:'",
            Position(file),
        )
    cut = cut_expression(node, text)
    if cut is not None:
        raise SpecError(cut[0], _position(file, cut[1]))
    positions = PositionMap(file)
    data = _convert(node, (), positions)
    return YamlDocument(data, positions)


def _compose(loader_type: type, text: str) -> Any:
    """The single document's node tree; our refusals surface as :class:`_Refused`."""
    loader = loader_type(text)
    try:
        return loader.get_single_node()
    finally:
        loader.dispose()


def _compose_checked(text: str) -> Any:
    """The node tree, with our own limits acting before libyaml's.

    libyaml's scanner reads up to 1024 characters of flow nesting ahead of the
    composer and, from libyaml 0.2.6 (PyYAML 6.0.4's wheels), refuses at its own
    depth limit of 1000 before our composer sees the 65th level. On that refusal
    the pure-Python reader, whose composer asks for no more than it needs, reads
    the text again, so the refusal is ours, at the place where it applies.
    """
    try:
        return _compose(_Loader, text)
    except yaml.MarkedYAMLError as exc:
        if _Loader is _PyLoader or "nesting depth" not in f"{exc.problem} {exc.context}":
            raise
    return _compose(_PyLoader, text)


def _convert(node: Any, path: Path_, positions: PositionMap) -> Any:
    file = positions.file
    start = _position(file, node.start_mark)
    quoted = isinstance(node, yaml.ScalarNode) and node.style in ("'", '"')
    positions.values[path] = start.shifted(1) if quoted else start
    if node.tag not in _PLAIN_TAGS:
        raise SpecError(
            f"YAML tag {node.tag} is not allowed in specs", _position(file, node.start_mark)
        )
    if isinstance(node, yaml.MappingNode):
        result: dict[Any, Any] = {}
        seen: dict[Any, Position] = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                raise SpecError(
                    "mapping keys must be plain names, not lists or mappings",
                    _position(file, key_node.start_mark),
                )
            key = _scalar(key_node, file)
            key_pos = _position(file, key_node.start_mark)
            if isinstance(key, (int, float, bool)) or key is None:
                key = key_node.value
            if key in seen:
                first = seen[key]
                raise SpecError(
                    f"duplicate key '{key}': first defined at line {first.line}, "
                    f"again at line {key_pos.line}",
                    key_pos,
                )
            seen[key] = key_pos
            positions.keys[(*path, key)] = key_pos
            result[key] = _convert(value_node, (*path, key), positions)
        return result
    if isinstance(node, yaml.SequenceNode):
        return [_convert(item, (*path, i), positions) for i, item in enumerate(node.value)]
    return _scalar(node, file)


def _scalar(node: Any, file: str) -> Any:
    tag, value = node.tag, node.value
    try:
        if tag == "tag:yaml.org,2002:null":
            return None
        if tag == "tag:yaml.org,2002:bool":
            return value.lower() == "true"
        if tag == "tag:yaml.org,2002:int":
            if value.startswith("0o"):
                return int(value[2:], 8)
            if value.startswith("0x"):
                return int(value[2:], 16)
            return int(value, 10)
        if tag == "tag:yaml.org,2002:float":
            lowered = value.lower()
            if lowered.endswith(".inf"):
                return -math.inf if value.startswith("-") else math.inf
            if lowered == ".nan":
                return math.nan
            return float(value)
    except ValueError:
        raise SpecError(f"cannot read number {value!r}", _position(file, node.start_mark)) from None
    return str(value)
