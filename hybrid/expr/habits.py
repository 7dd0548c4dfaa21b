"""Operators people bring from C, MATLAB and other languages, and what to write instead.

When an expression does not parse, :func:`habit` looks for the spellings that
engineers type out of habit (``=`` for a comparison, ``&&``, ``||``, ``!``, MATLAB's
``~=``, ``=>`` for ``>=``) and names the first with its column and our spelling,
instead of Python's bare "invalid syntax".

Examples
--------
>>> habit("h = 0")
("'=' assigns; to compare, use '=='", 2)
>>> habit("h > 0 && v < 0")
("'&&' is not an operator here: write 'and'", 6)
>>> habit("h > 0") is None
True
"""

from __future__ import annotations

import re

__all__ = ["habit"]

# Longer spellings first: at one column, `=>` wins over `=`, `~=` and `!=` over `~`, `!`.
_HABITS: tuple[tuple[re.Pattern[str], str], ...] = (
    (re.compile(r"&&"), "'&&' is not an operator here: write 'and'"),
    (re.compile(r"\|\|"), "'||' is not an operator here: write 'or'"),
    (re.compile(r"=>"), "'=>' is not a comparison: write '>='"),
    (re.compile(r"=<"), "'=<' is not a comparison: write '<='"),
    (re.compile(r"~="), "'~=' is MATLAB's not-equal: write '!='"),
    (re.compile(r"===?"), ""),  # `==` is ours; `===` falls to Python's message
    (re.compile(r"[<>!]="), ""),  # ours
    (re.compile(r"="), "'=' assigns; to compare, use '=='"),
    (re.compile(r"!"), "'!' is not negation here: write 'not'"),
)


def habit(text: str) -> tuple[str, int] | None:
    """The first habit in ``text`` that is not our syntax: ``(message, column)``, or None.

    Called only for text that does not parse, so a match is the likely cause.
    """
    col = 0
    while col < len(text):
        for pattern, message in _HABITS:
            found = pattern.match(text, col)
            if found is None:
                continue
            if message:
                return message, col
            col = found.end() - 1
            break
        col += 1
    return None
