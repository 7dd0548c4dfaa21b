"""The ``.cfg`` of ``hybrid export spaceex``: the system, the initial set, the forbidden set.

``initially`` is a conjunction of the initial location of each component and
the initial set of each state variable (``x == v``, or ``lo <= x & x <= hi`` for
an interval). Several initial locations make it a disjunction, one conjunction
per combination of initial locations (SpaceEx starts in all of them).
``forbidden`` is a disjunction: the locations declared unreachable and the
forbidden states.

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text('''
... automaton: a
... state: {x: {initial: [0, 1]}}
... locations: {l: {}, k: {}}
... initial: {location: [l, k]}
... ''')
>>> for line in spaceex_cfg(hybrid.compose(m), "a_system", False, []).splitlines()[:2]:
...     print(line)
system = "a_system"
initially = "loc(a)==l & 0 <= x & x <= 1 | loc(a)==k & 0 <= x & x <= 1"
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from hybrid.compose import System
from hybrid.errors import SpecError

__all__ = ["MAX_INITIAL_COMBINATIONS", "number_text", "spaceex_cfg"]

MAX_INITIAL_COMBINATIONS = 64
"""Most combinations of initial locations written out in ``initially``."""


def number_text(value: float) -> str:
    """A number as SpaceEx reads it: ``2`` for a whole number, else Python's repr."""
    return repr(float(value)) if value != int(value) or abs(value) >= 1e15 else str(int(value))


def spaceex_cfg(
    system: System,
    network: str,
    clock: bool,
    clocks: Sequence[str],
    forbidden: Sequence[str] = (),
) -> str:
    """The ``.cfg`` text (``forbidden``: its disjuncts, already in SpaceEx syntax)."""
    state: list[str] = []
    for name, r in system.initial_set().items():
        if r.is_point:
            state.append(f"{name}=={number_text(r.lo)}")
        else:
            state.append(f"{number_text(r.lo)} <= {name} & {name} <= {number_text(r.hi)}")
    state += [f"{c}==0" for c in clocks]
    if clock:
        state.append("t==0")
    choices = [c.automaton.initial_locations for c in system.components]
    if math.prod(len(c) for c in choices) > MAX_INITIAL_COMBINATIONS:
        raise SpecError(
            f"cannot export to SpaceEx: the initial locations make more than "
            f"{MAX_INITIAL_COMBINATIONS} combinations of the components' initial locations; "
            "give fewer initial locations",
            system.position,
        )
    disjuncts = []
    for combo in itertools.product(*choices):
        where = [f"loc({c.name})=={loc}" for c, loc in zip(system.components, combo, strict=True)]
        disjuncts.append(" & ".join([*where, *state]))
    lines = [f'system = "{network}"', f'initially = "{" | ".join(disjuncts)}"']
    if forbidden:
        lines.append(f'forbidden = "{" | ".join(forbidden)}"')
    lines += [
        'scenario = "supp"',
        'directions = "box"',
        "iter-max = 10",
        'output-format = "GEN"',
        "",
    ]
    return "\n".join(lines)
