"""Where a run starts when the model gives sets: the point chosen, and saying so.

A spec may give an initial *set* (``initial: [lo, hi]``), several initial
locations, and free inputs with a *range*; one run takes one point of each:

- a state variable starts at its ``nominal`` value, else at the midpoint of its set;
- the run starts in the first initial location (of each component);
- a free input given no value (``inputs=``, ``--input``) is held at its
  ``nominal`` value, else at the midpoint of its range (:func:`held_inputs`).

:func:`describe_start` records those choices for ``run.settings["start"]``,
with a note for each, which ``hybrid simulate`` prints.

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text('''
... automaton: a
... state: {x: {initial: [0, 2]}}
... inputs: {u: {range: [-1, 3]}}
... locations: {l: {flow: {x: u}}, k: {}}
... initial: {location: [l, k]}
... ''')
>>> start = describe_start(m, None, None, None)
>>> start["state"], start["inputs"]
({'x': 1.0}, {'u': 1.0})
>>> for note in start["notes"]:
...     print(note)
starts in 'l', the first of its initial locations l, k
x starts at the midpoint 1 of its initial set [0, 2]
input u is held at the midpoint 1 of its range [-1, 3] (give it a value with --input or inputs= for another)
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from hybrid.compose import Model, System, as_system
from hybrid.errors import UsageError, did_you_mean
from hybrid.model import Automaton, Range

__all__ = ["Held", "describe_start", "held_inputs", "initial_vector", "run_inputs", "state_slot"]


class Held:
    """An input held at one value: ``Held(0.5)(t) == 0.5``."""

    def __init__(self, value: float) -> None:
        self.value = float(value)

    def __call__(self, t: float) -> float:
        return self.value

    def __repr__(self) -> str:
        return f"Held({self.value!r})"


def held_inputs(
    model: Model, given: Mapping[str, Callable[[float], float]] | None
) -> dict[str, Callable[[float], float]]:
    """The free inputs with a range that ``given`` leaves out, each held at its nominal value."""
    ranges = model.input_ranges()
    return {name: Held(r.nominal) for name, r in ranges.items() if name not in (given or {})}


def run_inputs(
    model: Model, given: Mapping[str, Callable[[float], float]] | None
) -> dict[str, Callable[[float], float]]:
    """The inputs a run of ``model`` reads: those ``given``, and the others held (:func:`held_inputs`)."""
    return {**held_inputs(model, given), **(given or {})}


def _how(r: Range) -> str:
    return "its nominal" if r.given else "the midpoint"


_STARTS: dict[tuple[Any, ...], tuple[Automaton | System, dict[str, Any]]] = {}
_STARTS_SIZE = 32
_STARTS_LOCK = threading.Lock()


def describe_start(
    model: Automaton | System,
    inputs: Mapping[str, Callable[[float], float]] | None,
    initial: Mapping[str, float] | None,
    initial_location: str | None,
    t_start: float = 0.0,
) -> dict[str, Any]:
    """Where a run of ``model`` starts and why: ``{location, state, inputs, notes}``.

    ``initial`` and ``initial_location`` are the caller's overrides (a value
    given is not a choice to report, but one outside the spec's set is: the
    claims of ``hybrid check`` do not cover it); ``inputs`` the inputs given.

    Without ``inputs`` (functions, called at ``t_start``), the answer depends on
    the model (frozen) and the overrides only: it is kept for the last few
    models and overrides seen (a run costs little more than this on the compiled
    backend), and every call gets its own copy.
    """
    key = None if inputs else _start_key(model, initial, initial_location, t_start)
    if key is None:
        return _describe_start(model, inputs, initial, initial_location, t_start)
    hit = _STARTS.get(key)  # one lookup needs no lock; the updates below hold it
    if hit is None or hit[0] is not model:
        start = _describe_start(model, inputs, initial, initial_location, t_start)
        with _STARTS_LOCK:
            if len(_STARTS) >= _STARTS_SIZE:
                _STARTS.pop(next(iter(_STARTS)))
            # the cache holds the model, so no other object can take its id
            _STARTS[key] = hit = (model, start)
    found = hit[1]
    return {"location": found["location"], "state": dict(found["state"]),
            "inputs": dict(found["inputs"]), "notes": list(found["notes"])}  # fmt: skip


def _start_key(
    model: Automaton | System,
    initial: Mapping[str, float] | None,
    initial_location: str | None,
    t_start: float,
) -> tuple[Any, ...] | None:
    """The cache key of a start without inputs, or None for overrides that are not plain
    numbers and names.

    Values are keyed by their type and exact bits (``float.hex``): ``-0.0`` and
    ``0.0``, equal as numbers, start differently. ``t_start`` is not in it: only
    the inputs (not cached) are read at ``t_start``.
    """
    if not initial and (initial_location is None or initial_location.__class__ is str):
        return (id(model), (), initial_location)
    try:
        values = tuple((k, v.__class__, float(v).hex()) for k, v in (initial or {}).items())
        key = (id(model), values, initial_location)
        hash(key)
    except (TypeError, ValueError, OverflowError):
        return None
    return key


def _describe_start(
    model: Automaton | System,
    inputs: Mapping[str, Callable[[float], float]] | None,
    initial: Mapping[str, float] | None,
    initial_location: str | None,
    t_start: float,
) -> dict[str, Any]:
    original = model
    if isinstance(model, Automaton) and (initial or initial_location):
        model = model.with_initial(initial_location, initial)
    system = as_system(model)
    notes: list[str] = []
    for comp in system.components:
        a = comp.automaton
        if len(a.initial_locations) > 1:
            who = "" if system.single else f"component '{comp.name}' "
            notes.append(
                f"{who}starts in '{a.initial_location}', the first of its initial locations "
                f"{', '.join(a.initial_locations)}"
            )
    sets = original.initial_set()
    state: dict[str, float] = {}
    for name, value in zip(system.state_names, system.initial_vector(), strict=True):
        if initial and name in initial:
            state[name] = float(initial[name])
            if not sets[name].contains(state[name]):
                notes.append(
                    f"{name} starts at {state[name]:g}, outside its initial set "
                    f"{sets[name].text()} (the claims of hybrid check do not cover this run)"
                )
            continue
        state[name] = value
        r = sets[name]
        if not r.is_point:
            notes.append(f"{name} starts at {_how(r)} {r.nominal:g} of its initial set {r.text()}")
    held: dict[str, float] = {}
    for name, r in system.input_ranges().items():
        if inputs and name in inputs:
            try:
                first = float(inputs[name](t_start))
            except Exception:  # the run itself reports an input that fails
                continue
            if not r.contains(first):
                notes.append(
                    f"input {name} starts at {first:g}, outside its range {r.text()} (the "
                    "claims of hybrid check do not cover this run)"
                )
            continue
        held[name] = r.nominal
        notes.append(
            f"input {name} is held at {_how(r)} {r.nominal:g} of its range {r.text()} "
            "(give it a value with --input or inputs= for another)"
        )
    return {
        "location": system.mode_name(system.initial_mode),
        "state": state,
        "inputs": held,
        "notes": notes,
    }


def initial_vector(
    model: System, state_names: Sequence[str], initial: Mapping[str, float] | None
) -> list[float]:
    """The initial state, ``initial`` overriding some values (names as in ``state_names``)."""
    x0 = model.initial_vector()
    for name, value in (initial or {}).items():
        x0[state_slot(state_names, name)] = float(value)
    return x0


def state_slot(state_names: Sequence[str], name: str) -> int:
    """The place of state variable ``name`` given an initial value (else a UsageError).

    >>> state_slot(("h", "v"), "v")
    1
    >>> state_slot(("h", "v"), "hh")
    Traceback (most recent call last):
    hybrid.errors.UsageError: initial value for unknown state variable 'hh'; did you mean 'h'?
    >>> state_slot(("x", "n"), "ctrl.n")
    Traceback (most recent call last):
    hybrid.errors.UsageError: initial value for unknown state variable 'ctrl.n'; a system's state variables are named without their component: 'n'
    """
    if name not in state_names:
        _, dot, plain = name.rpartition(".")
        hint = (f"; a system's state variables are named without their component: '{plain}'"
                if dot and plain in state_names else did_you_mean(name, state_names))  # fmt: skip
        raise UsageError(f"initial value for unknown state variable '{name}'{hint}")
    return list(state_names).index(name)
