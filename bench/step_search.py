"""(7) The cost of the search inside each step for the first event.

The simulator searches every accepted step for the first crossing of the watch
(docs/semantics.md, "First crossings inside a step"): at least 4 samples of
the interpolant per step, and one every thousandth of the run. The baseline is
the same engine with the samples removed (the watch tested at step ends only,
what ``solve_ivp``'s events do), so the ratio is the price of the search alone.
Event times of both are compared with the closed forms where there are events.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator
from typing import Any

import hybrid
from bench.harness import Comparison, compare
from hybrid.simulation import crossing

__all__ = ["run"]

RTOL, ATOL = 1e-10, 1e-12

# x' = 1 for 10 s in steps of 1 ms, a guard that never holds: 10,000 steps of the
# cheapest flow there is, so the search weighs as much as it ever can
RAMP = """
automaton: ramp
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: 1}}
  B: {flow: {x: 0}}
edges:
  - {name: never, from: A, to: B, guard: x >= 100}
"""


@contextlib.contextmanager
def step_ends_only() -> Iterator[None]:
    """The engine with the interior samples of the search removed."""
    real = crossing.parts
    crossing.parts = lambda h, spacing: 1  # type: ignore[assignment]
    try:
        yield
    finally:
        crossing.parts = real  # type: ignore[assignment]


def _pair(simulate: Callable[[], Any]) -> tuple[Callable[[], Any], Callable[[], Any]]:
    def without() -> Any:
        with step_ends_only():
            return simulate()

    return simulate, without


def run(repeats: int = 9) -> list[Comparison]:
    ball = hybrid.load("specs/bouncing_ball.yaml", parameters={"e": 0.95})
    thermo = hybrid.load("specs/thermostat.yaml")
    ramp = hybrid.load_text(RAMP)

    def ours_ball() -> list[float]:
        r = hybrid.simulate(
            ball, t_end=1e3, max_jumps=100, rtol=RTOL, atol=ATOL, handle_sigint=False
        )
        return [j.t for j in r.jumps]

    def ours_thermo() -> list[float]:
        r = hybrid.simulate(
            thermo, t_end=1e4, max_jumps=100, rtol=RTOL, atol=ATOL, handle_sigint=False
        )
        return [j.t for j in r.jumps]

    def ours_ramp() -> int:
        r = hybrid.simulate(ramp, t_end=10.0, max_step=1e-3, handle_sigint=False)
        return len(r)

    from uvms_model.missions import specs_dir

    mission = hybrid.load(specs_dir() / "uvms_mission_2.yaml")

    def ours_uvms() -> int:
        r = hybrid.simulate(mission, t_end=60.0, rtol=1e-8, atol=1e-10, handle_sigint=False)
        return len(r.jumps)

    results = []
    for name, fn in (
        ("in-step search: bouncing ball, 100 impacts", ours_ball),
        ("in-step search: thermostat, 50 periods", ours_thermo),
        ("in-step search: x' = 1, 10,000 steps, no event (worst case)", ours_ramp),
        ("in-step search: UVMS mission 2, 60 s", ours_uvms),
    ):
        contender, baseline = _pair(fn)
        c = compare(
            name,
            ("search of each step (samples, dips)", contender),
            ("watch at step ends only", baseline),
            repeats=repeats,
        )
        results.append(c)
    from bench.engine_overhead import ball_closed_form, thermostat_closed_form

    with step_ends_only():
        ends_ball, ends_thermo = ours_ball(), ours_thermo()
    results[0].extra = {
        "max_event_error_search_s": _error(ours_ball(), ball_closed_form(100)),
        "max_event_error_step_ends_s": _error(ends_ball, ball_closed_form(100)),
    }
    results[1].extra = {
        "max_event_error_search_s": _error(ours_thermo(), thermostat_closed_form(100)),
        "max_event_error_step_ends_s": _error(ends_thermo, thermostat_closed_form(100)),
    }
    results[2].extra = {"points": ours_ramp()}
    with step_ends_only():
        jumps_ends = ours_uvms()
    results[3].extra = {"jumps_search": ours_uvms(), "jumps_step_ends": jumps_ends}
    return results


def _error(found: list[float], truth: list[float]) -> float:
    return max((abs(a - b) for a, b in zip(found, truth, strict=True)), default=math.nan)


if __name__ == "__main__":
    for result in run():
        print(result.line(), result.extra)
