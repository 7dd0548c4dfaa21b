"""Names on our side: reserved words renamed, locations made names, instance paths shortened.

- A SpaceEx variable named like one of our reserved words (``t`` is the time in
  our expressions; ``pi``, ``true``, ``and``, the built-in functions...) gets a
  trailing ``_`` (``t`` becomes ``t_``), with a note.
- A location name that is not a name (``[A-Za-z_][A-Za-z0-9_]*``) has its
  other characters replaced by ``_``; a missing or repeated one gets its id.
- A local variable of an instance (``osc.osci.y``) keeps its own name (``y``)
  when no other variable of the system has it, else the path joined by ``_``
  (``f8a_f4a_x1``).

Examples
--------
>>> ours("t"), ours("x"), ours("lambda"), ours("sin")
('t_', 'x', 'lambda_', 'sin_')
>>> system_names(["x", "x1", "osc.osci.y", "f4.x1"])
{'x': 'x', 'x1': 'x1', 'osc.osci.y': 'y', 'f4.x1': 'f4_x1'}
>>> location_names([("1", "on"), ("2", "on"), ("3", "2 fast"), ("4", "")])
{'1': 'on', '2': 'on_2', '3': 'l_2_fast', '4': 'loc4'}
"""

from __future__ import annotations

import keyword
import re
from collections.abc import Iterable, Sequence

from hybrid.expr.functions import BUILTINS

__all__ = ["RESERVED", "component_name", "location_names", "ours", "system_names"]

RESERVED = frozenset(
    {"t", "j", "location", "pi", "true", "false", "and", "or", "not", "inf", "nan"}
    | set(keyword.kwlist)
    | set(keyword.softkwlist)
    | set(BUILTINS)
)
"""Names our specs reserve: the time ``t``, a run's columns ``j`` and ``location``,
constants, keywords, built-in functions."""


def ours(name: str, taken: Iterable[str] = ()) -> str:
    """``name``, or ``name_`` (more ``_`` until free) if it is reserved."""
    if name not in RESERVED:
        return name
    used = set(taken)
    candidate = name + "_"
    while candidate in used or candidate in RESERVED:
        candidate += "_"
    return candidate


def component_name(cid: str) -> str:
    """A component id or instance name as one of our names (``a>b``, ``a b`` -> ``a_b``; ``1ab`` -> ``c_1ab``).

    Examples
    --------
    >>> component_name("a>b"), component_name("1ab"), component_name("plant"), component_name("")
    ('a_b', 'c_1ab', 'plant', 'c_')
    """
    candidate = _NOT_NAME.sub("_", cid.strip())
    if not candidate or not (candidate[0].isalpha() or candidate[0] == "_"):
        candidate = "c_" + candidate
    return ours(candidate)


def system_names(ids: Sequence[str]) -> dict[str, str]:
    """Our name for each system-level variable or label id (see the module docstring)."""
    result: dict[str, str] = {}
    plain = [i for i in ids if "." not in i]
    for i in plain:
        result[i] = ours(i, plain)
    used = set(result.values())
    dotted = [i for i in ids if "." in i]
    last = [i.rsplit(".", 1)[1] for i in dotted]
    for i, tail in zip(dotted, last, strict=True):
        joined = component_name(i.replace(".", "_"))
        candidate = ours(tail) if last.count(tail) == 1 else joined
        if candidate in used:
            candidate = joined
        while candidate in used:
            candidate += "_"
        result[i] = candidate
        used.add(candidate)
    return result


_NOT_NAME = re.compile(r"[^A-Za-z0-9_]")


def location_names(locations: Sequence[tuple[str, str]]) -> dict[str, str]:
    """Location id -> our location name, unique (see the module docstring)."""
    result: dict[str, str] = {}
    used: set[str] = set()
    for lid, name in locations:
        candidate = _NOT_NAME.sub("_", name.strip())
        if candidate and not (candidate[0].isalpha() or candidate[0] == "_"):
            candidate = "l_" + candidate
        if not candidate:
            candidate = "loc" + _NOT_NAME.sub("_", lid)
        if candidate in used:
            candidate = f"{candidate}_{_NOT_NAME.sub('_', lid)}"
        while candidate in used:
            candidate += "_"
        result[lid] = candidate
        used.add(candidate)
    return result
