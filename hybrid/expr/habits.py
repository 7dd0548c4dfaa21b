"""Operators and functions people bring from C, MATLAB and other languages, and what to
write instead.

When an expression does not parse, :func:`habit` looks for the spellings that
engineers type out of habit (``=`` for a comparison, ``&&``, ``||``, ``!``, MATLAB's
``~=``, ``=>`` for ``>=``, ``2x`` for ``2 * x``, MATLAB's ``x'`` and ``;``) and names
the first with its column and our spelling, instead of Python's bare "invalid
syntax". :func:`function_habit` says what to write for a function we do not have
under the name C or MATLAB gives it (``pow``, ``mod``, ``ln``, ...).

Examples
--------
>>> habit("h = 0")
("'=' assigns; to compare, use '=='", 2)
>>> habit("h > 0 && v < 0")
("'&&' is not an operator here: write 'and'", 6)
>>> habit("h > 0") is None
True
>>> habit("2x + 1e-3y")
("'2x' is not a product here: write '2 * x'", 0)
>>> function_habit("pow")
'write a ** b for pow(a, b)'
"""

from __future__ import annotations

import re

__all__ = ["function_habit", "habit"]

# Longer spellings first: at one column, `=>` wins over `=`, `~=` and `!=` over `~`, `!`.
_HABITS: tuple[tuple[re.Pattern[str], str], ...] = (
    # (not after a digit: 2.*x is Python's 2.0 * x)
    (re.compile(r"(?<!\d)\.\*"), "'.*' is MATLAB's element-wise product: write '*'"),
    (re.compile(r"(?<!\d)\./"), "'./' is MATLAB's element-wise division: write '/'"),
    (re.compile(r"\.\^"), "'.^' is MATLAB's element-wise power: write '**'"),
    (re.compile(r"&&"), "'&&' is not an operator here: write 'and'"),
    (re.compile(r"\|\|"), "'||' is not an operator here: write 'or'"),
    (re.compile(r"=>"), "'=>' is not a comparison: write '>='"),
    (re.compile(r"=<"), "'=<' is not a comparison: write '<='"),
    (re.compile(r"~="), "'~=' is MATLAB's not-equal: write '!='"),
    (re.compile(r"===?"), ""),  # `==` is ours; `===` falls to Python's message
    (re.compile(r"[<>!]="), ""),  # ours
    (re.compile(r"="), "'=' assigns; to compare, use '=='"),
    (re.compile(r"!"), "'!' is not negation here: write 'not'"),
    (re.compile(r"'"), "a quote is not part of an expression: MATLAB's x' (a derivative or a "
                       "transpose) is written as the flow of x, and there are no strings"),
    (re.compile(r'"'), "a quote is not part of an expression: there are no strings"),
    (re.compile(r";"), "';' ends nothing here: an expression is one line without it"),
)

# A number written against a name (`2x`, `1e-3y`): Python reads "invalid decimal literal".
_JUXTAPOSED = re.compile(r"(?<![\w.])((?>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?))([A-Za-z_]\w*)")

_FUNCTIONS: dict[str, str] = {
    "pow": "write a ** b for pow(a, b)",
    "power": "write a ** b for power(a, b)",
    "square": "write x ** 2",
    "ln": "log is the natural logarithm: write log(x)",
    "log2": "write log(x) / log(2)",
    "mod": "there is no modulo function: for MATLAB's mod(x, m) write x - m * floor(x / m)",
    "rem": "there is no remainder function: for x >= 0, rem(x, m) is x - m * floor(x / m)",
    "fmod": "there is no remainder function: for x >= 0, fmod(x, m) is x - m * floor(x / m)",
    "round": "there is no round: write floor(x + 0.5)",
    "trunc": "there is no trunc: write sign(x) * floor(abs(x))",
    "fix": "there is no fix: write sign(x) * floor(abs(x))",
    "arctan": "write atan(x)",
    "arcsin": "write asin(x)",
    "arccos": "write acos(x)",
    "signum": "write sign(x)",
    "sgn": "write sign(x)",
    "fmin": "write min(a, b)",
    "fmax": "write max(a, b)",
}


def habit(text: str) -> tuple[str, int] | None:
    """The first habit in ``text`` that is not our syntax: ``(message, column)``, or None.

    Called only for text that does not parse, so a match is the likely cause.
    """
    col = 0
    while col < len(text):
        juxtaposed = _JUXTAPOSED.match(text, col)
        if juxtaposed is not None:
            number, name = juxtaposed.groups()
            if name in ("e", "E") and "e" not in number.lower():  # 3.0e: an exponent unfinished?
                return (f"'{number}{name}' is not a number: an exponent needs its digits "
                        f"({number}{name}3), a product its '*' ({number} * {name})", col)  # fmt: skip
            return f"'{number}{name}' is not a product here: write '{number} * {name}'", col
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


def function_habit(name: str) -> str | None:
    """What to write for the C or MATLAB function ``name`` that we spell otherwise, or None."""
    return _FUNCTIONS.get(name)
