"""`check` never calls dead or unreachable what `simulate` fires or enters.

Hypothesis builds random small automata and systems of two (guards strict and
not, equalities, invariants that entries may violate, resets onto guard
boundaries, shared labels; initial sets, several initial locations, a free
input with a range, urgent locations, forbidden states); each is simulated
with today's simulator and checked. Every edge the run fires must not be a
``dead-edge``, every location it enters must not be an ``unreachable-location``
(nor a declared ``reachable`` one reported as not reached), and no state it
visits may be in a forbidden set that check proved unreachable. The claims of
``check`` are made for runs that stay within the declared bounds, from any point
of the initial set, in any initial location, with inputs within their ranges:
so the runs start at the nominal point and at random points of the set, in each
initial location, with the input held at random constants within its range, and
each is compared only up to the first stored point outside the bounds.

The in-suite size is small; ``make fuzz`` (``HYBRID_FUZZ=1``) runs
:data:`FULL_EXAMPLES`.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybrid
from hybrid.compose import as_system
from hybrid.expr import ir
from hybrid.expr.interval import Interval
from hybrid.expr.ranges import IntervalEvaluator

FULL_EXAMPLES = 5_000
IN_SUITE_EXAMPLES = 40


def examples(in_suite: int, full: int) -> int:
    """``full`` under ``make fuzz`` (env ``HYBRID_FUZZ`` set, not ``0``), else ``in_suite``."""
    return full if os.environ.get("HYBRID_FUZZ", "0") not in ("", "0") else in_suite


pytestmark = pytest.mark.fuzz

CONSTANTS = ["0", "1", "-1", "0.5", "2", "1e-7"]


def _terms(x: str, y: str) -> list[str]:
    return [x, y, "t", "1", "0.5", "-2", f"{x}*{y}", f"sin({x})", f"{y} - {x}", f"{x}**2"]


OPS = ["<", "<=", ">", ">=", "=="]


@st.composite
def automaton_text(
    draw: st.DrawFn, name: str = "fuzz", suffix: str = "", labels=(), u_range: str | None = None
) -> str:
    x, y = f"x{suffix}", f"y{suffix}"
    term_list = _terms(x, y) + (["u", f"u*{x}"] if u_range else [])
    terms = st.sampled_from(term_list)
    ops = st.sampled_from(OPS)
    # any two terms, the same one twice included (`x < x` is identically false: see
    # test_simulator_never_fires_an_identically_false_guard below)
    pairs = st.tuples(terms, terms)

    def comparison() -> str:
        a, b = draw(pairs)
        return f"{a} {draw(ops)} {b}"

    n = draw(st.integers(1, 3))
    locs = [f"L{i}" for i in range(n)]
    bounded = draw(st.booleans()) and draw(st.booleans())
    bounds = ", bounds: [-50, 50]" if bounded else ""
    x0 = draw(st.sampled_from(["0", "1", "-1", "0.5", "[0, 1]", "[-1, 0.5]"]))
    y0 = draw(st.sampled_from(["0", "1", "2", "[0, 2]"]))
    lines = [
        f"automaton: {name}",
        f"state: {{{x}: {{initial: {x0}{bounds}}}, {y}: {{initial: {y0}}}}}",
    ]
    if u_range:
        lines.append(f"inputs: {{u: {{range: {u_range}}}}}")
    if labels:
        lines.append(f"labels: [{', '.join(labels)}]")
    lines.append("locations:")
    for loc in locs:
        flow = f"{{{x}: {draw(terms)}, {y}: {draw(terms)}}}"
        inv = draw(
            st.sampled_from(
                [
                    "true",
                    f"{x} {draw(ops)} {draw(terms.filter(lambda a: a != x))}",
                    f"{x} <= {draw(st.sampled_from(CONSTANTS))}",
                ]
            )
        )
        urgent = ", urgent: true" if draw(st.integers(0, 5)) == 0 else ""
        lines.append(f"  {loc}: {{flow: {flow}, invariant: '{inv}'{urgent}}}")
    edges = []
    for _ in range(draw(st.integers(0, 4))):
        kind = draw(st.sampled_from(["true", "terms", "constant"]))
        if kind == "true":
            guard = "true"
        elif kind == "terms":
            guard = comparison()
        else:
            guard = f"{draw(terms)} {draw(ops)} {draw(st.sampled_from(CONSTANTS))}"
        if draw(st.booleans()):
            guard = f"{guard} and {comparison()}"
        reset = draw(
            st.sampled_from(
                [
                    "{}",
                    f"{{{x}: 0}}",
                    f"{{{x}: -{x}, {y}: {y} + 1}}",
                    f"{{{y}: 0.5*{x}}}",
                    f"{{{x}: 1}}",
                ]
            )
        )
        prio = draw(st.integers(0, 1))
        label = draw(st.sampled_from([None, *labels]))
        extra = f", label: {label}" if label else ""
        edges.append(
            f"  - {{from: {draw(st.sampled_from(locs))}, to: {draw(st.sampled_from(locs))}, "
            f"guard: '{guard}', reset: {reset}, priority: {prio}{extra}}}"
        )
    if edges:
        lines.append("edges:")
        lines.extend(edges)
    if n > 1 and draw(st.booleans()):
        lines.append(f"initial: {{location: [{locs[-1]}, {draw(st.sampled_from(locs[:-1]))}]}}")
    if draw(st.booleans()):
        where = draw(st.sampled_from([None, *locs]))
        at = f"location: {where}, " if where else ""
        lines.append(f"properties: {{forbidden: [{{{at}when: '{comparison()}'}}]}}")
    return "\n".join(lines) + "\n"


U_RANGES = [None, "[0, 1]", "[-1, 1]", "[0.5, 2]"]


def _load(text: str) -> hybrid.Automaton:
    m = hybrid.load_text(text)
    assert isinstance(m, hybrid.Automaton)
    return m


@st.composite
def model(draw: st.DrawFn) -> hybrid.Automaton | hybrid.System:
    u_range = draw(st.sampled_from(U_RANGES))
    if draw(st.booleans()):
        return _load(draw(automaton_text(u_range=u_range)))
    labels = draw(st.sampled_from([(), ("go",), ("go", "stop")]))
    first = _load(draw(automaton_text("p", "0", labels, u_range)))
    second = _load(draw(automaton_text("q", "1", labels, u_range)))
    return hybrid.compose(first, second)


def _bounded_prefix(m: hybrid.Automaton | hybrid.System, run: hybrid.Run) -> float:
    """The first stored time at which the state is outside its declared bounds (inf if never)."""
    first = math.inf
    for s in m.states:
        values = np.asarray(run[s.name])
        outside = (values < s.lower) | (values > s.upper) | ~np.isfinite(values)
        if outside.any():
            first = min(first, float(run.t[int(np.argmax(outside))]))
    return first


def _starts(
    m: hybrid.Automaton | hybrid.System, draw: Callable[[st.SearchStrategy[Any]], Any] | None
) -> list[tuple[hybrid.Automaton | hybrid.System, dict[str, float] | None, float | None]]:
    """Runs to compare: each initial location (mode) from the nominal point, and one
    random point of the initial set with the input at a random constant of its range."""
    system = as_system(m)
    parts = [c.automaton for c in system.components]
    variants: list[hybrid.Automaton | hybrid.System] = []
    for combo in itertools.product(*(a.initial_locations for a in parts)):
        started = [a.with_initial(loc) for a, loc in zip(parts, combo, strict=True)]
        if system.single:
            variants.append(started[0])
        else:
            names = [c.name for c in system.components]
            variants.append(hybrid.compose(*started, names=names, name=system.name))
    runs: list[tuple[hybrid.Automaton | hybrid.System, dict[str, float] | None, float | None]]
    runs = [(v, None, None) for v in variants]
    if draw is not None:
        point = {
            name: draw(st.floats(r.lo, r.hi)) for name, r in system.initial_set().items()
        }
        ranges = system.input_ranges()
        u = draw(st.floats(ranges["u"].lo, ranges["u"].hi)) if "u" in ranges else None
        runs.append((variants[0], point, u))
    return runs


def _surely(cond: ir.Expr, t: float, values: dict[str, float], u: float) -> bool:
    """``cond`` holds on a small box around the point (a margin for the solver's error)."""
    box = {
        k: Interval(v - 1e-6 * (1 + abs(v)), v + 1e-6 * (1 + abs(v))) for k, v in values.items()
    }
    box["t"] = Interval(t - 1e-9, t + 1e-9)
    box["u"] = Interval.point(u)
    can_be_true, can_be_false = IntervalEvaluator(box).truth(cond)
    return can_be_true and not can_be_false


def assert_check_agrees_with_run(
    m: hybrid.Automaton | hybrid.System,
    draw: Callable[[st.SearchStrategy[Any]], Any] | None = None,
) -> None:
    report = hybrid.check(m)
    dead = {f.where for f in report.findings if f.rule == "dead-edge"}
    unreachable = {f.where for f in report.findings if f.rule == "unreachable-location"}
    blocked = {f.where for f in report.findings if f.rule == "blocked-start"}
    reported = {f.where for f in report.findings if f.where.startswith("forbidden: ")}
    proved = [e for e in m.properties.forbidden if f"forbidden: {e.text()}" not in reported]
    ranges = as_system(m).input_ranges()
    for start, initial, u in _starts(m, draw):
        held = u if u is not None else (ranges["u"].nominal if "u" in ranges else 0.0)
        try:
            run = hybrid.simulate(
                start,
                t_end=3.0,
                max_jumps=40,
                max_jumps_per_instant=15,
                handle_sigint=False,
                initial=initial,
                inputs={"u": lambda t, v=held: v} if "u" in ranges else None,
            )
        except hybrid.SimulationError:
            continue
        horizon = _bounded_prefix(m, run)
        fired = {part for jump in run.jumps if jump.t < horizon for part in jump.edge.split("+")}
        entered = {
            part
            for t, loc in zip(run.t.tolist(), run.location.tolist(), strict=True)
            if t < horizon or t == 0.0
            for part in str(loc).split("|")
        }
        assert not (fired & dead), f"fired but called dead: {fired & dead}"
        started = set(str(run.location.tolist()[0]).split("|")) & blocked
        term = run.termination
        assert not started or (term.t == 0.0 and term.cause != "t_end"), (
            f"started in {started}, called blocked at its start, and ended {term.cause} "
            f"at t={term.t}"
        )
        assert not started or not isinstance(m, hybrid.Automaton) or term.cause == "blocked"
        assert not (entered & unreachable), (
            f"entered but called unreachable: {entered & unreachable}"
        )
        for entry in proved:
            where = {f"{c}.{loc}" if c else loc for c, loc in entry.locations.items()}
            for k, (t, loc) in enumerate(zip(run.t.tolist(), run.location.tolist(), strict=True)):
                if t >= horizon or not where <= set(str(loc).split("|")):
                    continue
                values = {n: float(run[n][k]) for n in run.state_names}
                assert entry.when is None or not _surely(entry.when, t, values, held), (
                    f"visits the forbidden state '{entry.text()}' proved unreachable, at t={t}"
                )


@settings(
    max_examples=examples(IN_SUITE_EXAMPLES, FULL_EXAMPLES),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    derandomize=os.environ.get("HYBRID_FUZZ", "0") in ("", "0"),
)
@given(model(), st.data())
def test_check_never_calls_dead_what_simulate_fires(
    m: hybrid.Automaton | hybrid.System, data: st.DataObject
) -> None:
    assert_check_agrees_with_run(m, data.draw)


def test_regression_entry_outside_the_invariant_fires_at_once() -> None:
    # the case (a): entered where the invariant is false, an edge fires at once
    m = hybrid.load_text(
        """
automaton: entry
state: {x: {initial: 0}}
locations:
  a: {flow: {x: 1}}
  b: {flow: {x: 1}, invariant: x <= -1}
  c: {flow: {x: 1}}
edges:
  - {name: go, from: a, to: b, guard: x >= 1}
  - {name: out, from: b, to: c, guard: x >= 0.5}
"""
    )
    run = hybrid.simulate(m, t_end=3.0, handle_sigint=False)
    assert [j.edge for j in run.jumps] == ["go", "out"] and run.jumps[1].t == run.jumps[0].t
    assert_check_agrees_with_run(m)
    assert not [f for f in hybrid.check(m).findings if f.rule in ("dead-edge", "sink-location")]


def test_regression_strict_window_below_the_old_margin() -> None:
    # the case (b): x > y and x < y + 1e-7 holds for a while; a 1e-6 margin called it dead
    m = hybrid.load_text(
        """
automaton: window
state: {x: {initial: 0}, y: {initial: 0}}
locations: {a: {flow: {x: 1, y: 0.95}}, b: {}}
edges:
  - {name: narrow, from: a, to: b, guard: x > y and x < y + 1e-7}
"""
    )
    run = hybrid.simulate(m, t_end=1.0, handle_sigint=False)
    assert [j.edge for j in run.jumps] == ["narrow"]
    assert_check_agrees_with_run(m)


def test_regression_an_equality_with_a_strict_comparison_entering() -> None:
    # found by the property test: the simulator snaps `t == 1` true on its level and takes
    # `1 < t` by the slope rule (t rises): the edge fires at t = 1 (docs/semantics.md,
    # equality guards); check dropped the entering boundary of a conjunction with an
    # equality and called the edge dead
    m = hybrid.load_text(
        """
automaton: level
state: {x: {initial: 0}}
locations: {a: {flow: {x: 1}}, b: {}}
edges:
  - {name: e, from: a, to: b, guard: "1 < t and t == 1"}
"""
    )
    run = hybrid.simulate(m, t_end=3.0, handle_sigint=False)
    assert [(j.edge, j.t) for j in run.jumps] == [("e", 1.0)]
    assert_check_agrees_with_run(m)
    assert not hybrid.check(m).findings


def test_simulator_never_fires_an_identically_false_guard() -> None:
    # `x < x and x < x*y`: its rho was ~4e-17 falling to 0 (not below it) where x = 0,
    # and the slope test fired it; a comparison that cannot change now has the rho of
    # `false`, and a rho that comes down to exactly 0 is decided by the boolean form
    m = hybrid.load_text(
        """
automaton: fuzz
state: {x: {initial: -1}, y: {initial: 2}}
locations:
  L0: {flow: {x: y, y: x}}
edges:
  - {from: L0, to: L0, guard: 'x < x and x < x*y'}
  - {from: L0, to: L0, guard: 'x < x*y'}
"""
    )
    assert [f.where for f in hybrid.check(m).by_rule("dead-edge")] == ["L0->L0#0"]
    run = hybrid.simulate(m, t_end=3.0, max_jumps_per_instant=15, handle_sigint=False)
    assert "L0->L0#0" not in {j.edge for j in run.jumps}
