"""Which characters an expression may hold: ASCII only.

Python's parser reads ``ｘ`` (fullwidth) and ``𝐱`` (mathematical bold) as
``x`` (it normalises names to NFKC), so a spec could use names that are not
the ones written, and messages would name a name that is not in the file.
The language needs nothing beyond ASCII, so expressions are refused at the
first other character, and every column in them counts characters.
"""

from __future__ import annotations

from hybrid.expr.parse import ExprError

__all__ = ["ascii_only"]


def ascii_only(source: str) -> None:
    """Refuse an expression holding a character beyond ASCII, at its column.

    Python would read ``ｘ`` and ``𝐱`` as ``x`` (NFKC normalisation of names),
    and messages would then name a name that is not in the file; names are
    ASCII letters, digits and ``_``, and nothing else in the language needs
    more. (It also keeps every column a count of characters.)

    Examples
    --------
    >>> ascii_only("x + 1")
    >>> ascii_only("2*ｘ")
    Traceback (most recent call last):
    ...
    hybrid.expr.parse.ExprError: character 'ｘ' (U+FF58) is not allowed in an expression: names are ASCII letters, digits and '_'
    """
    for col, char in enumerate(source):
        if ord(char) > 127:
            raise ExprError(
                f"character {char!r} (U+{ord(char):04X}) is not allowed in an expression: "
                "names are ASCII letters, digits and '_'",
                col,
            )
