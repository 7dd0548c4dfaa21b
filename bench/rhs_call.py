"""(2) Right-hand side: the compiled location function against hand-written Python, per call."""

from __future__ import annotations

from typing import Any

import numpy as np

import hybrid
from bench.harness import Comparison, compare
from hybrid.compose import as_system
from hybrid.simulation.compiled import CompiledModel

__all__ = ["linear_spec", "run"]

N_CALLS = 20_000


def linear_spec(n: int = 10) -> str:
    """A chain of n coupled states: x_k' = -k x_k + x_(k+1) (the last one without coupling)."""
    state = ", ".join(f"x{k}: {{initial: {k + 1}.0}}" for k in range(n))
    flow = ", ".join(
        f"x{k}: -{k + 1}.0*x{k}" + (f" + 0.5*x{k + 1}" if k + 1 < n else "") for k in range(n)
    )
    return f"automaton: linear{n}\nstate: {{{state}}}\nlocations: {{run: {{flow: {{{flow}}}}}}}\n"


def run(repeats: int = 9) -> list[Comparison]:
    results = []
    ball = CompiledModel(as_system(hybrid.load("specs/bouncing_ball.yaml")))
    rhs = ball.mode(ball.initial_key).rhs
    g = 9.81

    def hand_ball(t: float, y: Any) -> list[float]:
        return [y[1], -g]

    y = np.array([3.0, -1.0])

    def loop(f: Any) -> Any:
        def go() -> None:
            for _ in range(N_CALLS):
                f(0.1, y)

        return go

    c = compare(
        "right-hand side: bouncing ball, per call",
        ("compiled", loop(rhs)),
        ("hand-written", loop(hand_ball)),
        repeats=repeats,
    )
    c.extra = {"calls_per_repeat": N_CALLS}
    results.append(c)

    lin = CompiledModel(as_system(hybrid.load_text(linear_spec(10))))
    rhs10 = lin.mode(lin.initial_key).rhs

    def hand_linear(t: float, x: Any) -> list[float]:
        # the faster of the usual idioms (unpacking the array directly is ~4x slower)
        x0, x1, x2, x3, x4, x5, x6, x7, x8, x9 = x.tolist()
        return [
            -1.0 * x0 + 0.5 * x1,
            -2.0 * x1 + 0.5 * x2,
            -3.0 * x2 + 0.5 * x3,
            -4.0 * x3 + 0.5 * x4,
            -5.0 * x4 + 0.5 * x5,
            -6.0 * x5 + 0.5 * x6,
            -7.0 * x6 + 0.5 * x7,
            -8.0 * x7 + 0.5 * x8,
            -9.0 * x8 + 0.5 * x9,
            -10.0 * x9,
        ]

    x = np.linspace(1.0, 2.0, 10)
    assert np.allclose(rhs10(0.0, x), hand_linear(0.0, x))
    y = x
    c = compare(
        "right-hand side: 10-state linear system, per call",
        ("compiled", loop(rhs10)),
        ("hand-written", loop(hand_linear)),
        repeats=repeats,
    )
    c.extra = {"calls_per_repeat": N_CALLS}
    results.append(c)
    return results


if __name__ == "__main__":
    for result in run():
        print(result.line())
