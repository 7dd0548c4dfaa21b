"""Writing spec data as YAML text, with comments, in the style of our hand-written specs.

Only plain data is written: mappings, lists, strings, numbers, booleans.
Small mappings and lists of scalars go on one line (``{x: v, v: "-g"}``),
everything else in block style; a string is written plain only when it is a
name that every YAML reader reads back as the same string, quoted otherwise.
Comments are attached to paths (``("edges", 0)``) and written above them.

Examples
--------
>>> print(dump({"automaton": "ball", "parameters": {"g": 1.0}, "locations":
...     {"fall": {"flow": {"x": "v", "v": "-g"}}}}, {("locations",): "one location"}), end="")
automaton: ball
parameters: {g: 1.0}
# one location
locations:
  fall:
    flow: {x: v, v: "-g"}
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

__all__ = ["dump", "scalar"]

Path_ = tuple[str | int, ...]
_PLAIN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_SPECIAL = {"y", "n", "yes", "no", "on", "off", "true", "false", "null", "none", "nan", "inf"}
_WIDTH = 96


def scalar(value: Any) -> str:
    """One scalar as YAML text.

    Examples
    --------
    >>> scalar("x"), scalar("on"), scalar("-g*x"), scalar(0.1), scalar(float("inf")), scalar(True)
    ('x', '"on"', '"-g*x"', '0.1', '.inf', 'true')
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    text = str(value)
    if _PLAIN.match(text) and text.lower() not in _SPECIAL:
        return text
    return json.dumps(text)


def _is_scalar(value: Any) -> bool:
    return not isinstance(value, Mapping | list | tuple)


def _inline(value: Any) -> str | None:
    """The one-line form of a small collection of scalars, or ``None``."""
    if isinstance(value, Mapping):
        if not all(_is_scalar(v) or _flat_list(v) for v in value.values()):
            return None
        parts = [
            f"{scalar(k)}: {_inline(v) if not _is_scalar(v) else scalar(v)}"
            for k, v in value.items()
        ]
        return "{" + ", ".join(parts) + "}"
    if isinstance(value, list | tuple):
        if not all(_is_scalar(v) for v in value):
            return None
        return "[" + ", ".join(scalar(v) for v in value) + "]"
    return None


def _flat_list(value: Any) -> bool:
    return isinstance(value, list | tuple) and all(_is_scalar(v) for v in value)


def _comment(lines: list[str], text: str | None, indent: str) -> None:
    if text:
        for line in text.splitlines():
            lines.append(f"{indent}# {line}".rstrip())


def _has_comment(comments: Mapping[Path_, str], path: Path_) -> bool:
    return any(p[: len(path)] == path and len(p) > len(path) for p in comments)


def _mapping(
    lines: list[str],
    data: Mapping[str, Any],
    comments: Mapping[Path_, str],
    path: Path_,
    indent: str,
    first_prefix: str | None = None,
) -> None:
    for i, (key, value) in enumerate(data.items()):
        here = (*path, key)
        lead = first_prefix if (i == 0 and first_prefix is not None) else indent
        if i > 0 or first_prefix is None:
            _comment(lines, comments.get(here), indent)
        head = f"{lead}{scalar(key)}:"
        _value(lines, head, value, comments, here, indent)


def _value(
    lines: list[str], head: str, value: Any, comments: Mapping[Path_, str], here: Path_, indent: str
) -> None:
    if _is_scalar(value):
        lines.append(f"{head} {scalar(value)}")
        return
    inline = _inline(value) if not _has_comment(comments, here) else None
    if inline is not None and (len(head) + len(inline) < _WIDTH or not value):
        lines.append(f"{head} {inline}")
        return
    lines.append(head)
    inner = indent + "  "
    if isinstance(value, Mapping):
        _mapping(lines, value, comments, here, inner)
        return
    for j, item in enumerate(value):
        _comment(lines, comments.get((*here, j)), inner)
        if isinstance(item, Mapping) and item:
            _mapping(lines, item, comments, (*here, j), inner + "  ", first_prefix=f"{inner}- ")
        else:
            _value(lines, f"{inner}-", item, comments, (*here, j), inner)


def dump(
    data: Mapping[str, Any], comments: Mapping[Path_, str] | None = None, header: str = ""
) -> str:
    """YAML text of ``data`` with ``comments`` above their paths and ``header`` on top."""
    lines: list[str] = []
    _comment(lines, header, "")
    _mapping(lines, data, comments or {}, (), "")
    return "\n".join(lines) + "\n"
