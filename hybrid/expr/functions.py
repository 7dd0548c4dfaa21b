"""Functions an expression may call: the built-ins and registered libraries.

Built-ins are fixed here. Libraries come only from installed packages, through
the entry-point group ``hybrid.functions``; a spec names the ones it uses in
``uses``. An entry point resolves to a callable returning a mapping of
function name to callable. A callable may carry ``hybrid_outputs = n`` to say
it returns ``n`` values (a vector signal indexed with ``name[k]``), and
``hybrid_arity = (min, max)`` for its argument count.

Examples
--------
>>> BUILTINS["hypot"].fn(3.0, 4.0)
5.0
>>> BUILTINS["clip"].fn(5.0, 0.0, 1.0)
1.0
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cache
from typing import Any

__all__ = ["BUILTINS", "ENTRY_POINT_GROUP", "Function", "available_libraries", "load_library"]

ENTRY_POINT_GROUP = "hybrid.functions"


@dataclass(frozen=True)
class Function:
    """A callable with its accepted argument count and number of outputs (1: scalar)."""

    name: str
    fn: Callable[..., Any]
    min_args: int
    max_args: int | None
    outputs: int = 1
    builtin: bool = True


def _sign(x: float) -> float:
    # not (x > 0) - (x < 0): numpy booleans cannot be subtracted
    return 1.0 if x > 0 else -1.0 if x < 0 else 0.0


def _clip(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


def _min(*args: float) -> float:
    return min(args)


def _max(*args: float) -> float:
    return max(args)


def _hypot(*args: float) -> float:
    return math.hypot(*args)


def _f(name: str, fn: Callable[..., Any], lo: int, hi: int | None) -> tuple[str, Function]:
    return name, Function(name, fn, lo, hi)


BUILTINS: Mapping[str, Function] = dict(
    [
        _f("sin", math.sin, 1, 1),
        _f("cos", math.cos, 1, 1),
        _f("tan", math.tan, 1, 1),
        _f("asin", math.asin, 1, 1),
        _f("acos", math.acos, 1, 1),
        _f("atan", math.atan, 1, 1),
        _f("atan2", math.atan2, 2, 2),
        _f("sinh", math.sinh, 1, 1),
        _f("cosh", math.cosh, 1, 1),
        _f("tanh", math.tanh, 1, 1),
        _f("exp", math.exp, 1, 1),
        _f("log", math.log, 1, 1),
        _f("log10", math.log10, 1, 1),
        _f("sqrt", math.sqrt, 1, 1),
        _f("abs", abs, 1, 1),
        _f("min", _min, 2, None),
        _f("max", _max, 2, None),
        _f("floor", lambda x: float(math.floor(x)), 1, 1),
        _f("ceil", lambda x: float(math.ceil(x)), 1, 1),
        _f("sign", _sign, 1, 1),
        _f("clip", _clip, 3, 3),
        _f("hypot", _hypot, 2, None),
    ]
)


def available_libraries() -> list[str]:
    """Names of the function libraries installed packages register."""
    from importlib.metadata import entry_points  # tens of ms: only when a library is looked for

    return sorted(ep.name for ep in entry_points(group=ENTRY_POINT_GROUP))


@cache
def load_library(name: str) -> Mapping[str, Function]:
    """The functions of library ``name``; raises ``LookupError`` if none is installed."""
    from importlib.metadata import entry_points

    matches = [ep for ep in entry_points(group=ENTRY_POINT_GROUP) if ep.name == name]
    if not matches:
        raise LookupError(name)
    factory = matches[0].load()
    table = factory() if callable(factory) else factory
    functions: dict[str, Function] = {}
    for fname, fn in dict(table).items():
        lo, hi = getattr(fn, "hybrid_arity", (0, None))
        functions[fname] = Function(
            fname, fn, int(lo), hi, int(getattr(fn, "hybrid_outputs", 1)), builtin=False
        )
    return functions
