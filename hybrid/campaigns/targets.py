"""What a varied name sets in a run: a parameter, an initial value or a constant input.

Examples
--------
>>> import hybrid
>>> from hybrid.compose import as_system
>>> ball = as_system(hybrid.load("specs/bouncing_ball.yaml"))  # as hybrid.sweep passes it
>>> check_names(ball, ["e", "init.h"])
>>> split({"e": 0.7, "init.h": 5.0})
Overrides(parameters={'e': 0.7}, initial={'h': 5.0}, inputs={})
>>> check_names(ball, ["init.z"])
Traceback (most recent call last):
...
hybrid.errors.UsageError: init.z: bouncing_ball has no state variable 'z' (state: h, v)
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from hybrid.compose import System
from hybrid.errors import SpecError, UsageError, did_you_mean

__all__ = ["INITIAL", "INPUT", "Constant", "Overrides", "check_names", "split"]

INITIAL = "init."
"""Prefix of an initial value: ``init.x``."""
INPUT = "input."
"""Prefix of a free input held constant: ``input.u``."""


@dataclass(frozen=True)
class Overrides:
    """A point's values, sorted by what they set."""

    parameters: dict[str, float] = field(default_factory=dict)
    initial: dict[str, float] = field(default_factory=dict)
    inputs: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Constant:
    """An input held at ``value`` (a callable of ``t`` that pickles, for workers)."""

    value: float

    def __call__(self, t: float) -> float:
        return self.value


def split(point: Mapping[str, float]) -> Overrides:
    """The values of ``point`` by what they set."""
    found = Overrides()
    for name, value in point.items():
        if name.startswith(INITIAL):
            found.initial[name[len(INITIAL) :]] = float(value)
        elif name.startswith(INPUT):
            found.inputs[name[len(INPUT) :]] = float(value)
        else:
            found.parameters[name] = float(value)
    return found


def check_names(model: System, names: Iterable[str], held: Iterable[str] = ()) -> None:
    """Raise a :class:`UsageError` naming the first varied name ``model`` does not have, or
    that is varied twice, or that ``held`` (the parameters held in every run) also sets."""
    seen: set[str] = set()
    fixed = set(held)
    states = list(model.state_names)
    inputs = list(model.free_inputs)
    for name in names:
        if name in seen:
            raise UsageError(f"{name} is varied twice")
        if name in fixed:
            raise UsageError(
                f"{name} is varied and also held by parameters (--param): give it once"
            )
        seen.add(name)
        if name.startswith(INITIAL):
            var = name[len(INITIAL) :]
            if var not in states:
                raise UsageError(
                    f"{name}: {model.name} has no state variable '{var}' "
                    f"(state: {', '.join(states) or 'none'}){did_you_mean(var, states)}"
                )
        elif name.startswith(INPUT):
            var = name[len(INPUT) :]
            if var not in inputs:
                raise UsageError(
                    f"{name}: {model.name} has no free input '{var}' "
                    f"(inputs: {', '.join(inputs) or 'none'}){did_you_mean(var, inputs)}"
                )
        else:
            try:
                model.with_parameters({name: 0.0})
            except SpecError as exc:  # where the parameters are declared, as simulate says it
                raise UsageError(exc.message, at=exc.position) from None
