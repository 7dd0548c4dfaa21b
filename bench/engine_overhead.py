"""(1) Engine overhead: hybrid.simulate against a hand-written solve_ivp restart loop.

Same method, tolerances and events (terminal, direction set) on both sides; event
times of both are compared with the closed forms.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

import hybrid
from bench.harness import Comparison, compare

__all__ = ["run"]

RTOL, ATOL, METHOD = 1e-10, 1e-12, "RK45"
G, E, H0 = 9.81, 0.95, 10.0
N_IMPACTS = 100


def ball_closed_form(n: int) -> list[float]:
    t1 = math.sqrt(2 * H0 / G)
    return [t1 * (1 + 2 * E * (1 - E ** (k - 1)) / (1 - E)) for k in range(1, n + 1)]


def ball_baseline() -> list[float]:
    return _ball_loop(warm=False)


def ball_baseline_warm() -> list[float]:
    """The same loop, starting each segment with the previous one's last full step."""
    return _ball_loop(warm=True)


def _ball_loop(warm: bool) -> list[float]:
    def rhs(t: float, y: Any) -> list[float]:
        return [y[1], -G]

    def hit(t: float, y: Any) -> float:
        return max(y[0], y[1])

    hit.terminal = True  # type: ignore[attr-defined]
    hit.direction = -1  # type: ignore[attr-defined]
    t, y, times, h = 0.0, np.array([H0, 0.0]), [], None
    while len(times) < N_IMPACTS:
        sol = solve_ivp(
            rhs,
            (t, 1e3),
            y,
            method=METHOD,
            rtol=RTOL,
            atol=ATOL,
            events=hit,
            first_step=h if warm else None,
        )
        if sol.t.size >= 3:
            h = float(sol.t[-2] - sol.t[-3])
        t = float(sol.t_events[0][0])
        _h, v = sol.y_events[0][0]
        times.append(t)
        y = np.array([0.0, -E * v])
    return times


def thermostat_closed_form(n: int) -> list[float]:
    a, t_out, t_heat, low, high = 0.1, 10.0, 30.0, 18.0, 22.0
    times = [math.log((20 - t_out) / (low - t_out)) / a]
    up = math.log((t_heat - low) / (t_heat - high)) / a
    down = math.log((high - t_out) / (low - t_out)) / a
    while len(times) < n:
        times.append(times[-1] + (up if len(times) % 2 == 1 else down))
    return times


def thermostat_baseline(n: int) -> list[float]:
    a, t_out, t_heat, low, high = 0.1, 10.0, 30.0, 18.0, 22.0

    def cool(t: float, y: Any) -> list[float]:
        return [-a * (y[0] - t_out)]

    def heat(t: float, y: Any) -> list[float]:
        return [a * (t_heat - y[0])]

    def on(t: float, y: Any) -> float:
        return float(y[0] - low)

    def off(t: float, y: Any) -> float:
        return float(high - y[0])

    for ev in (on, off):
        ev.terminal = True  # type: ignore[attr-defined]
        ev.direction = -1  # type: ignore[attr-defined]
    t, y, heating, times = 0.0, np.array([20.0]), False, []
    while len(times) < n:
        sol = solve_ivp(
            heat if heating else cool,
            (t, 1e4),
            y,
            method=METHOD,
            rtol=RTOL,
            atol=ATOL,
            events=off if heating else on,
        )
        t = float(sol.t_events[0][0])
        y = sol.y_events[0][0].copy()
        times.append(t)
        heating = not heating
    return times


def run(repeats: int = 9) -> list[Comparison]:
    ball = hybrid.load("specs/bouncing_ball.yaml", parameters={"e": E})
    thermo = hybrid.load("specs/thermostat.yaml")

    def ours_ball() -> list[float]:
        r = hybrid.simulate(
            ball,
            t_end=1e3,
            max_jumps=N_IMPACTS,
            rtol=RTOL,
            atol=ATOL,
            method=METHOD,
            handle_sigint=False,
        )
        return [j.t for j in r.jumps]

    def ours_thermo() -> list[float]:
        r = hybrid.simulate(
            thermo,
            t_end=1e4,
            max_jumps=100,
            rtol=RTOL,
            atol=ATOL,
            method=METHOD,
            handle_sigint=False,
        )
        return [j.t for j in r.jumps]

    results = []
    truth = ball_closed_form(N_IMPACTS)
    c = compare(
        "engine overhead: bouncing ball, 100 impacts",
        ("hybrid.simulation", ours_ball),
        ("hand-written solve_ivp loop", ball_baseline),
        repeats=repeats,
    )
    c.extra = {
        "max_event_error_contender_s": max(
            abs(a - b) for a, b in zip(ours_ball(), truth, strict=True)
        ),
        "max_event_error_baseline_s": max(
            abs(a - b) for a, b in zip(ball_baseline(), truth, strict=True)
        ),
    }
    results.append(c)
    c = compare(
        "engine overhead: bouncing ball, like for like (both warm-start each segment)",
        ("hybrid.simulate", ours_ball),
        ("hand-written loop with the same warm start", ball_baseline_warm),
        repeats=repeats,
    )
    c.extra = {
        "max_event_error_baseline_s": max(
            abs(a - b) for a, b in zip(ball_baseline_warm(), truth, strict=True)
        )
    }
    results.append(c)
    truth = thermostat_closed_form(100)
    c = compare(
        "engine overhead: thermostat, 50 periods",
        ("hybrid.simulation", ours_thermo),
        ("hand-written solve_ivp loop", lambda: thermostat_baseline(100)),
        repeats=repeats,
    )
    c.extra = {
        "max_event_error_contender_s": max(
            abs(a - b) for a, b in zip(ours_thermo(), truth, strict=True)
        ),
        "max_event_error_baseline_s": max(
            abs(a - b) for a, b in zip(thermostat_baseline(100), truth, strict=True)
        ),
    }
    results.append(c)
    return results


if __name__ == "__main__":
    for result in run():
        print(result.line(), result.extra)
