"""Zero-time cycles: complete (strongly connected components), linear, with a witness.

The navigation benchmark of ARCH-COMP (a point moving through a grid of cells,
each cell with its own desired velocity; edges between neighbouring cells
guarded by equalities on the cell boundaries) has millions of simple cycles
for 27 cells: enumerating them never reached the zero-time 2-cycle across one
boundary. A 3x3 version is built here.
"""

from __future__ import annotations

import itertools
import time

import hybrid
from hybrid.analysis import check
from hybrid.analysis.static import AutomatonFacts
from hybrid.analysis.zerotime import ZeroTimeGraph

# desired velocity per cell (ARCH NAV style: a direction per cell)
VELOCITY = {
    (0, 0): (1.0, 0.0), (1, 0): (-1.0, 0.0), (2, 0): (0.0, 1.0),
    (0, 1): (0.0, -1.0), (1, 1): (1.0, 0.0), (2, 1): (0.0, 1.0),
    (0, 2): (1.0, 0.0), (1, 2): (1.0, 0.0), (2, 2): (0.0, -1.0),
}  # fmt: skip


def navigation(
    n: int = 3, *, equality: bool = True, start: tuple[float, ...] = (0.5, 0.5, 0.0, 0.0)
) -> str:
    """The n x n navigation grid; ``equality`` guards as in ARCH, else ``>=``/``<=`` pairs."""
    x0, y0, vx0, vy0 = start
    lines = [
        "automaton: nav",
        "state:",
        f"  x: {{initial: {x0}, bounds: [0, {n}]}}",
        f"  y: {{initial: {y0}, bounds: [0, {n}]}}",
        f"  vx: {{initial: {vx0}, bounds: [-5, 5]}}",
        f"  vy: {{initial: {vy0}, bounds: [-5, 5]}}",
        "locations:",
    ]
    for i, j in itertools.product(range(n), range(n)):
        dx, dy = VELOCITY.get((i, j), (1.0, 0.0))
        flow = (
            f"{{x: vx, y: vy, vx: -1.2*(vx - {dx}) + 0.1*(vy - {dy}), "
            f"vy: 0.1*(vx - {dx}) - 1.2*(vy - {dy})}}"
        )
        inv = f"{i} <= x and x <= {i + 1} and {j} <= y and y <= {j + 1}"
        lines.append(f"  c{i}{j}: {{flow: {flow}, invariant: '{inv}'}}")
    lines.append(f"initial: {{location: c{int(x0)}{int(y0)}}}")
    lines.append("edges:")
    for i, j in itertools.product(range(n), range(n)):
        band_y = f"{j} <= y and y <= {j + 1}"
        band_x = f"{i} <= x and x <= {i + 1}"
        if i + 1 < n:  # across x == i + 1
            up, down = (f"x == {i + 1}",) * 2 if equality else (f"x >= {i + 1}", f"x <= {i + 1}")
            lines.append(
                f"  - {{name: c{i}{j}_c{i + 1}{j}, from: c{i}{j}, to: c{i + 1}{j}, guard: '{up} and {band_y}'}}"
            )
            lines.append(
                f"  - {{name: c{i + 1}{j}_c{i}{j}, from: c{i + 1}{j}, to: c{i}{j}, guard: '{down} and {band_y}'}}"
            )
        if j + 1 < n:  # across y == j + 1
            up, down = (f"y == {j + 1}",) * 2 if equality else (f"y >= {j + 1}", f"y <= {j + 1}")
            lines.append(
                f"  - {{name: c{i}{j}_c{i}{j + 1}, from: c{i}{j}, to: c{i}{j + 1}, guard: '{up} and {band_x}'}}"
            )
            lines.append(
                f"  - {{name: c{i}{j + 1}_c{i}{j}, from: c{i}{j + 1}, to: c{i}{j}, guard: '{down} and {band_x}'}}"
            )
    return "\n".join(lines) + "\n"


def test_navigation_grid_zero_time_two_cycle_is_found_quickly():
    model = hybrid.load_text(navigation(), file="nav.yaml")
    start = time.process_time()
    report = check(model)
    cpu = time.process_time() - start
    cycles = report.by_rule("zero-time-cycle")
    # one strongly connected component: every boundary edge can chain with another at an instant
    assert len(cycles) == 1
    (finding,) = cycles
    # the witness is a 2-cycle across one boundary: there and straight back
    steps = [t for t, _ in finding.witness if t is not None]
    assert len(steps) == 2
    a, b = steps
    assert a.split("_") == list(reversed(b.split("_")))
    assert finding.witness[0][1] == finding.witness[-1][1]
    assert "more edge(s)" in finding.message  # the rest of the component is counted
    assert cpu < 30  # a bound on work (CPU seconds), not a speed test: bench/zero_time.py times it


def test_every_boundary_pair_is_in_the_component():
    facts = AutomatonFacts(hybrid.load_text(navigation()))
    (component,) = ZeroTimeGraph(facts).components()
    # 3x3 grid: 12 inner boundaries, two edges each
    assert len(component.edges) == 24 == len(facts.edges)


def test_the_cycle_the_simulator_enters_is_reported():
    # at rest on the boundary x == 1 between c00 and c10: with >=/<= guards both hold and
    # stay put (no flow moves the point away), so the run jumps back and forth at t = 0
    text = navigation(equality=False, start=(1.0, 0.5, 0.0, 0.0))
    text = text.replace("initial: {location: c10}", "initial: {location: c00}")
    text = text.replace("vx: -1.2*(vx - 1.0) + 0.1*(vy - 0.0)", "vx: -1.2*vx + 0.1*vy")
    text = text.replace("vx: -1.2*(vx - -1.0) + 0.1*(vy - 0.0)", "vx: -1.2*vx + 0.1*vy")
    model = hybrid.load_text(text)
    run = hybrid.simulate(
        model, t_end=1.0, max_jumps=60, max_jumps_per_instant=50, handle_sigint=False
    )
    assert run.termination.cause in ("zeno", "max_jumps")
    entered = {j.edge for j in run.jumps}
    assert entered == {"c00_c10", "c10_c00"} and run.jumps[-1].t == 0.0
    cycles = check(model).by_rule("zero-time-cycle")
    assert cycles, "the cycle the simulator runs is not reported"
    component = next(c for c in ZeroTimeGraph(AutomatonFacts(model)).components())
    names = {model.edges[e].name for e in component.edges}
    assert entered <= names


def test_label_without_guard_synchronised_with_a_timer_is_no_cycle():
    # a standard idiom: the controller's edges are unguarded, the timer decides when
    timer = hybrid.load_text(
        """
automaton: timer
state: {c: {initial: 0, bounds: [0, 10]}}
labels: [tick]
locations: {run: {flow: {c: 1}, invariant: c <= 1}}
edges:
  - {name: fire, from: run, to: run, label: tick, guard: c >= 1, reset: {c: 0}}
"""
    )
    ctrl = hybrid.load_text(
        """
automaton: ctrl
labels: [tick]
locations: {a: {}, b: {}}
edges:
  - {name: ab, from: a, to: b, label: tick}
  - {name: ba, from: b, to: a, label: tick}
"""
    )
    assert check(hybrid.compose(timer, ctrl)).by_rule("zero-time-cycle") == []
    # alone, the controller's unguarded loop is one
    assert [f.where for f in check(ctrl).by_rule("zero-time-cycle")] == ["ab"]
    # and when the timer can repeat at one instant (no reset), the system's cycle is kept
    eager = hybrid.load_text(
        """
automaton: timer
state: {c: {initial: 0, bounds: [0, 10]}}
labels: [tick]
locations: {run: {flow: {c: 1}, invariant: c <= 1}}
edges:
  - {name: fire, from: run, to: run, label: tick, guard: c >= 1}
"""
    )
    found = check(hybrid.compose(eager, ctrl)).by_rule("zero-time-cycle")
    assert {f.where for f in found} == {"timer.fire", "ctrl.ab"}
