"""Two YAML pitfalls named in our words: tabs, and a comma inside ``{...}``.

A tab where YAML expects indentation gives PyYAML's "found character that cannot
start any token"; :func:`tab_at` tells the reader that this was a tab. A value
starting with ``!`` is a YAML tag, not C's negation; :func:`bang_at` finds it. In YAML's
flow style a comma ends the entry, so ``reset: {h: max(h, 0)}`` reads as
``h: "max(h"`` plus a key ``"0)"``; :func:`cut_expression` finds the cut value (a
plain scalar with an unclosed ``(``) and says to quote it.

Examples
--------
>>> import yaml
>>> text = "reset: {h: max(h, 0)}\\n"
>>> message, mark = cut_expression(yaml.compose(text), text)
>>> message.split(";")[-1]
" quote it: h: 'max(h, 0)'"
>>> (mark.line, mark.column)
(0, 11)
"""

from __future__ import annotations

import re
from typing import Any

import yaml

_BANG = re.compile(r"(?:^|[:\[{,-])\s+(!)(?!=)")

__all__ = ["bang_at", "cut_expression", "tab_at"]


def tab_at(text: str, mark: Any) -> bool:
    """Whether the YAML error at ``mark`` is a tab (in the indentation or where it points)."""
    lines = text.splitlines()
    if not 0 <= mark.line < len(lines):
        return False
    line = lines[mark.line]
    indentation = line[: len(line) - len(line.lstrip(" \t"))]
    return "\t" in indentation or line[mark.column : mark.column + 1] == "\t"


def bang_at(text: str, mark: Any) -> int | None:
    """The column of a value starting with ``!`` on the line of a YAML error, or None.

    ``guard: !(h > 0)`` is YAML's tag syntax, not a negation, and fails to parse.
    """
    lines = text.splitlines()
    if not 0 <= mark.line < len(lines):
        return None
    found = _BANG.search(lines[mark.line])
    return None if found is None else found.start(1)


def cut_expression(root: Any, text: str) -> tuple[str, Any] | None:
    """The first value of a flow ``{...}`` or ``[...]`` that a comma cut: (message, mark)."""
    stack = [root]
    while stack:
        node = stack.pop()
        if isinstance(node, yaml.MappingNode):
            items = [(key.value, value) for key, value in node.value]
        elif isinstance(node, yaml.SequenceNode):
            items = [(None, value) for value in node.value]
        else:
            continue
        stack.extend(value for _, value in reversed(items))
        if not node.flow_style:
            continue
        for key, item in items:
            plain = isinstance(item, yaml.ScalarNode) and not item.style
            if plain and item.value.count("(") > item.value.count(")"):
                whole = _up_to_closing(text, item.start_mark)
                quoted = f"{key}: '{whole}'" if key is not None else f"'{whole}'"
                return (
                    f"a comma cut '{whole}' in two: inside {{...}} or [...] a comma ends "
                    f"the entry; quote it: {quoted}",
                    item.start_mark,
                )
    return None


def _up_to_closing(text: str, mark: Any) -> str:
    """The entry as typed: from ``mark`` to the ``,`` ``}`` or ``]`` after its parentheses close.

    (Or to the end of the line, where they do not.)
    """
    lines = text.splitlines()
    line = lines[mark.line] if 0 <= mark.line < len(lines) else ""
    depth, end = 0, mark.column
    while end < len(line):
        char = line[end]
        if depth == 0 and char in ",}]" and end > mark.column:
            break
        depth += {"(": 1, ")": -1}.get(char, 0)
        end += 1
    return line[mark.column : end].rstrip()
