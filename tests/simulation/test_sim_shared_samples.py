"""The monitor takes the search's samples of a step (dense.StepCurve.samples) only where
they are its own: the whole step, cut in as many parts. The truth is the monitor's own
grid (monitor._grid without the shared samples), and runs with the sharing switched off.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import RK45

import hybrid
from hybrid.simulation import crossing, stay
from hybrid.simulation.dense import step_curve
from hybrid.simulation.monitor import _grid

HEATER = """
automaton: heater
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -0.1*x + sin(t)}}}
requirements:
  - {name: warm, always: "x >= 15"}
  - {name: mild, always: "x >= -20"}
  - {name: late, always: "x >= 12", within: [3.3, 17.9]}
"""


def _curve(first_step: float) -> object:
    solver = RK45(
        lambda t, y: [y[1], -y[0]], 0.0, np.array([1.0, 0.0]), 50.0, first_step=first_step
    )
    solver.step()
    return step_curve(solver)


class _Never:
    value = staticmethod(lambda t, x: 1.0 + t)
    pending, generation = False, 0


@pytest.mark.parametrize("first_step", [0.01, 0.5])  # 4 parts; more than 4 (spacing 0.05)
def test_the_shared_samples_are_the_monitors_own(first_step: float) -> None:
    curve = _curve(first_step)
    own = _grid(curve, curve.t0, curve.t1, 0.05)  # type: ignore[attr-defined]
    crossing.first_event(curve, _Never(), 1.0, 0.05)  # type: ignore[arg-type]
    assert curve.samples is not None  # type: ignore[attr-defined]
    shared = _grid(curve, curve.t0, curve.t1, 0.05)  # type: ignore[attr-defined]
    assert shared[0] is curve.samples[1]  # type: ignore[attr-defined]
    assert shared[0] == own[0] and len(shared[1]) == len(own[1]) >= 4
    assert all(np.array_equal(a, b) for a, b in zip(shared[1], own[1], strict=True))


def test_samples_not_shared_for_part_of_a_step_or_another_cut() -> None:
    curve = _curve(0.5)
    crossing.first_event(curve, _Never(), 1.0, 0.05)  # type: ignore[arg-type]
    t0, t1 = curve.t0, curve.t1  # type: ignore[attr-defined]
    kept = curve.samples[1]  # type: ignore[attr-defined]
    part = _grid(curve, t0, (t0 + t1) / 2, 0.05)  # a stay that ends inside the step
    assert part[0] is not kept and part[0][-1] == (t0 + t1) / 2
    other = _grid(curve, t0, t1, 0.001)  # another spacing: another number of parts
    assert other[0] is not kept and len(other[0]) > len(kept)


def test_requirements_are_the_same_without_the_shared_samples(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    model = hybrid.load_text(HEATER)
    ours = hybrid.simulate(model, t_end=25.0)

    def unshared(curve, *args, **kwargs):  # type: ignore[no-untyped-def]
        found = crossing.first_event(curve, *args, **kwargs)
        curve.samples = None
        return found

    monkeypatch.setattr(stay, "first_event", unshared)
    theirs = hybrid.simulate(model, t_end=25.0)
    assert ours.requirements == theirs.requirements
    assert not ours.requirements["warm"].holds and ours.requirements["mild"].holds
    assert np.array_equal(ours.t, theirs.t) and np.array_equal(ours.states, theirs.states)
