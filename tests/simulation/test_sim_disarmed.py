"""A disarmed guard or invariant is still watched: leaving its band on the active side is an event.

A guard or invariant that sits on its boundary at the start of a stay is
disarmed (docs/semantics.md, "Re-arming"); it used to take part again only once
it had been strictly on its safe side. A state that leaves the boundary on the
*other* side (the guard starts to hold, the invariant stops holding), for
instance at second order while the slope test saw a zero slope, was then never
seen: the bouncing ball at rest on its floor fell through it to h = -250.

The rule now: a disarmed term is watched from the far edge of the band, so it
is an event when a guard's rho falls to ``-b0`` or an invariant's rho rises to
``+b0`` (``b0`` the band at the start of the stay). Each answer below is a hand
computation from that rule: for ``x = 5 + t**2 / 2`` the event is where
``t**2 / 2 = b0``. Both backends are held to it (the compiled one lacked the
rule until the second wave's review: the ball at rest fell through its floor).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hybrid

H0, G, E = 10.0, 9.81, 0.8
T1 = math.sqrt(2 * H0 / G)
T_ZENO = T1 * (1 + E) / (1 - E)




def band(*x: float) -> float:
    return 1e-10 * (1.0 + max(abs(v) for v in x))


def test_the_ball_at_rest_on_its_floor_keeps_bouncing_and_never_passes_it(
    ball: hybrid.Automaton, backend: str
) -> None:
    # before: 176 jumps, then the ball fell through the floor to h = -250.7 at t_end
    run = hybrid.simulate(ball, t_end=20.0, zeno=False, max_jumps=400, backend=backend)
    assert run.termination.cause == "max_jumps" and len(run.jumps) == 400
    # never below the floor by more than the band (b = 1e-10 (1 + |v|) near rest)
    assert float(np.min(run["h"])) > -1e-9
    # the bounces accumulate at the Zeno time t1 (1 + e) / (1 - e) and go on there
    assert run.termination.t == pytest.approx(T_ZENO, abs=1e-3)
    assert all(j.t < T_ZENO + 1e-3 for j in run.jumps)
    assert all(j.edge == "bounce" for j in run.jumps)


SITTING_INVARIANT = """
automaton: sit
state: {x: {initial: 5.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: y, y: 1}, invariant: 'INV'}
"""


@pytest.mark.parametrize(("inv", "level"), [("x <= 5", 5.0), ("x == 5", 5.0)])
def test_an_invariant_sitting_on_its_boundary_is_left_at_second_order(
    inv: str, level: float, backend: str
) -> None:
    # x = 5 + t^2 / 2: the slope of x - 5 is 0 at t = 0 (the invariant holds and is
    # disarmed), then x leaves the invariant; before, it was never noticed
    model = hybrid.load_text(SITTING_INVARIANT.replace("INV", inv))
    run = hybrid.simulate(model, t_end=1.0, rtol=1e-10, atol=1e-14, backend=backend)
    end = run.termination
    assert end.cause == "blocked", end
    b0 = band(5.0, 0.0)
    assert end.t == pytest.approx(math.sqrt(2 * b0), rel=1e-4)
    assert float(run["x"][-1]) - level == pytest.approx(b0, rel=1e-3)


WIDE_BAND_INVARIANT = """
automaton: band_inv
state:
  big: {initial: 1.0e9}
  y: {initial: -0.001}
locations:
  a:
    flow: {y: 0.01}
    invariant: y <= 0
"""


def test_an_invariant_sitting_in_a_wide_band_is_left_at_its_far_edge(backend: str) -> None:
    # b0 = 1e-10 (1 + 1e9) = 0.1000000001 (big sets the band). At t = 0, rho = y = -0.001 is
    # within the band and so is its slope 0.01: sitting, `y <= 0` holds within the band, so
    # the invariant holds and is disarmed, watched as b0 - y. That term reaches 0 where
    # y = b0, at t = (b0 + 0.001) / 0.01 = 10.10000001: there the invariant is being left
    # ("Re-arming"), nothing is enabled, and the run is blocked. The slope test alone still
    # read it as sitting there: scipy stopped 1000 times at that instant and ended
    # solver_failure, the compiled backend went on to its next sample (t = 10.1199, y 2e-4
    # past the far edge) and ended blocked there
    model = hybrid.load_text(WIDE_BAND_INVARIANT)
    run = hybrid.simulate(model, t_end=20.0, backend=backend, handle_sigint=False)
    end = run.termination
    b0 = band(1e9, 0.001)
    assert end.cause == "blocked", end
    assert end.message == "invariant of a is about to be left and no transition is enabled"
    assert end.t == pytest.approx((b0 + 0.001) / 0.01, rel=1e-12)
    assert float(run["y"][-1]) == pytest.approx(b0, rel=1e-12)
    assert float(np.max(run["y"])) <= b0 * (1 + 1e-12)  # never past the far edge of the band
    assert len(run.jumps) == 0


WIDE_BAND_GUARD = """
automaton: band_guard
state:
  big: {initial: 1.0e9}
  y: {initial: 0.001}
locations:
  a: {flow: {y: -0.01}}
  b: {flow: {y: 0}}
edges:
  - {name: go, from: a, to: b, guard: y < 0}
"""


def test_a_strict_guard_sitting_in_a_wide_band_fires_at_its_far_edge(backend: str) -> None:
    # the mirror of the invariant above: b0 = 0.1000000001, y = 0.001 - 0.01 t. At t = 0
    # rho = y is within the band, slope -0.01 too: the strict guard sits and does not hold,
    # so it is disarmed and watched as y + b0, which reaches 0 where y = -b0, at
    # t = (0.001 + b0) / 0.01. A band beyond its boundary the guard holds and fires there.
    # The slope test alone read it as sitting again: scipy stopped 1000 times at that
    # instant and ended solver_failure, the compiled backend jumped at its next sample
    # (t = 10.1199, y = -0.1002)
    model = hybrid.load_text(WIDE_BAND_GUARD)
    run = hybrid.simulate(model, t_end=20.0, backend=backend, handle_sigint=False)
    b0 = band(1e9, 0.001)
    assert run.termination.cause == "t_end", run.termination
    (jump,) = run.jumps
    assert jump.edge == "go" and jump.target == "b"
    assert jump.t == pytest.approx((0.001 + b0) / 0.01, rel=1e-12)
    assert jump.before["y"] == pytest.approx(-b0, rel=1e-12)
    assert float(np.min(run["y"])) >= -b0 * (1 + 1e-12)  # never past the far edge


def test_a_strict_guard_sitting_on_its_boundary_fires_when_entered_at_second_order(
    backend: str,
) -> None:
    text = """
automaton: enter
state: {x: {initial: 5.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: y, y: 1}}
  B: {flow: {x: 0, y: 0}}
edges:
  - {name: go, from: A, to: B, guard: x > 5}
"""
    run = hybrid.simulate(hybrid.load_text(text), t_end=1.0, rtol=1e-10, atol=1e-14,
                          backend=backend)  # fmt: skip
    (jump,) = run.jumps  # before: no jump at all
    b0 = band(5.0, 0.0)
    assert jump.t == pytest.approx(math.sqrt(2 * b0), rel=1e-4)
    assert jump.before["x"] - 5.0 == pytest.approx(b0, rel=1e-3)


def test_an_equality_guard_whose_level_the_flow_keeps_fires_when_the_rest_holds(
    backend: str,
) -> None:
    # x stays exactly on the level x == 0; the guard holds from y = 1 (t = 1) on
    text = """
automaton: keep
state: {x: {initial: 0.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: 0, y: 1}}
  B: {flow: {x: 0, y: 0}}
edges:
  - {name: go, from: A, to: B, guard: x == 0 and y >= 1}
"""
    run = hybrid.simulate(hybrid.load_text(text), t_end=3.0, rtol=1e-10, atol=1e-12,
                          backend=backend)  # fmt: skip
    (jump,) = run.jumps  # before: no jump (a level exactly at 0 never armed)
    assert jump.t == pytest.approx(1.0, abs=1e-9)
    assert run.termination.cause == "t_end"


def test_a_level_the_state_starts_on_and_leaves_fires_where_the_state_returns(
    backend: str,
) -> None:
    # x = t/2 - t^2/2 leaves the level x == 0 at t = 0 (where y <= 0 is false, so the
    # guard is armed with the level read as itself) and returns to it at t = 1 with
    # y = -1/2: a level reached fires there (before: only |x| was watched, which never
    # falls below 0, and the return went unseen until the invariant blocked at t = 2)
    text = """
automaton: back
state: {x: {initial: 0.0}, y: {initial: 0.5}}
locations:
  A: {flow: {x: y, y: -1}, invariant: x >= -1}
  B: {flow: {x: 0, y: 0}}
edges:
  - {name: go, from: A, to: B, guard: x == 0 and y <= 0}
"""
    run = hybrid.simulate(hybrid.load_text(text), t_end=3.0, rtol=1e-10, atol=1e-12,
                          backend=backend)  # fmt: skip
    (jump,) = run.jumps
    assert jump.t == pytest.approx(1.0, abs=1e-9)
    assert jump.before["y"] == pytest.approx(-0.5, abs=1e-9)
    assert run.termination.cause == "t_end" and run.termination.location == "B"


@pytest.mark.parametrize("x0", [-1e-13, 0.0, 1e-13])
def test_a_short_hop_off_a_level_fires_where_it_returns_whatever_the_rounding_side(
    backend: str, x0: float
) -> None:
    # x = x0 + y0 t - t^2 hops 2.5e-9 above the level x == 0 (25 bands) for 1e-4 s, far
    # shorter than the search's sample spacing (3e-3 s): the return must be a crossing
    # whichever side of the level rounding put the start on, so the level is oriented by
    # where the flow takes the state (up), not by the sign of x0 (before: from x0 < 0 the
    # atom read x >= 0, the samples never saw the hop, and the run fell to the invariant)
    text = f"""
automaton: hop
state: {{x: {{initial: {x0!r}}}, y: {{initial: 1e-4}}}}
locations:
  A: {{flow: {{x: y, y: -2}}, invariant: x >= -1}}
  B: {{flow: {{x: 0, y: 0}}}}
edges:
  - {{name: go, from: A, to: B, guard: x == 0 and y <= 0}}
"""
    run = hybrid.simulate(hybrid.load_text(text), t_end=3.0, rtol=1e-10, atol=1e-14,
                          backend=backend)  # fmt: skip
    (jump,) = run.jumps
    y0 = 1e-4
    assert jump.t == pytest.approx((y0 + math.sqrt(y0 * y0 + 4 * x0)) / 2, abs=1e-12)
    assert run.termination.location == "B"
