"""Property: on generated small models, the compiled backend agrees with the scipy backend.

The models are one structure (so one compilation) with generated parameters
and initial states: speeds, levels, growth rates, reset factors, a priority
race between a level guard and a threshold, an invariant that can block.
Both backends run with the step capped, so that the scipy engine's step-end
checks see every crossing the compiled backend's first-crossing rule sees.
``HYBRID_FUZZ=1`` (``make fuzz``) runs many more examples.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybrid

pytest.importorskip("numba")

TEMPLATE = """
automaton: generated
parameters: {va: 1.0, vb: 1.0, hi: 1.0, lo: -1.0, wa: 0.0, ua: 0.5, wb: 0.0, ub: -0.5,
             r: 0.9, ymax: 10.0, ycut: 2.0}
state: {x: {initial: 0.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: va, y: wa*y + ua}, invariant: y <= ymax}
  B: {flow: {x: -vb, y: wb*y + ub}}
  C: {flow: {x: 0.5*va, y: -1}}
edges:
  - {name: ab, from: A, to: B, guard: x >= hi, reset: {y: r*y}}
  - {name: ac, from: A, to: C, guard: y >= ycut, priority: 1}
  - {name: ba, from: B, to: A, guard: x <= lo}
  - {name: ca, from: C, to: A, guard: y <= 0 and x >= lo, reset: {x: lo + 0.5*(hi - lo)}}
"""

EXAMPLES = 400 if os.environ.get("HYBRID_FUZZ") else 15

MODEL = hybrid.load_text(TEMPLATE)

parameters = st.fixed_dictionaries(
    {
        "va": st.floats(0.3, 3.0),
        "vb": st.floats(0.3, 3.0),
        "hi": st.floats(0.5, 2.0),
        "lo": st.floats(-2.0, -0.2),
        "wa": st.floats(-0.5, 0.5),
        "ua": st.floats(0.2, 1.5),
        "wb": st.floats(-0.5, 0.5),
        "ub": st.floats(-1.5, 1.5),
        "r": st.floats(-1.0, 1.0),
        "ymax": st.floats(1.0, 20.0),
        "ycut": st.floats(0.5, 5.0),
    }
)


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(values=parameters, x0=st.floats(-0.1, 0.4), y0=st.floats(-1.0, 0.4),
       dt=st.one_of(st.none(), st.floats(0.05, 1.0)))  # fmt: skip
def test_generated_models_agree(
    values: dict[str, float], x0: float, y0: float, dt: float | None
) -> None:
    model = MODEL.with_parameters(values)
    common = {"t_end": 6.0, "max_jumps": 40, "rtol": 1e-10, "atol": 1e-12, "dt": dt,
              "initial": {"x": x0, "y": y0}, "handle_sigint": False}  # fmt: skip
    compiled = hybrid.simulate(model, backend="compiled", **common)  # type: ignore[arg-type]
    reference = hybrid.simulate(model, **common)  # type: ignore[arg-type]
    assert [(j.edge, j.target) for j in compiled.jumps] == [(j.edge, j.target) for j in reference.jumps]
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    assert compiled.termination.cause == reference.termination.cause
    assert compiled.termination.location == reference.termination.location
    if dt is not None:  # the grid's points away from the jumps, at the same times and states
        # (a grid point that falls on a jump's time is kept or not as the two event times,
        # equal to an ulp or so, fall on either side of it)
        mine, theirs = _away_from_jumps(compiled), _away_from_jumps(reference)
        np.testing.assert_allclose(compiled.t[mine], reference.t[theirs], rtol=1e-10, atol=1e-9)
        for name in ("x", "y"):
            np.testing.assert_allclose(
                compiled[name][mine], reference[name][theirs], rtol=1e-7, atol=1e-8
            )


def _away_from_jumps(run: hybrid.Run) -> np.ndarray:
    times = np.asarray(run.jump_times, dtype=float)
    if times.size == 0:
        return np.ones(len(run.t), dtype=bool)
    return np.min(np.abs(run.t[:, None] - times[None, :]), axis=1) > 1e-9
