"""`check` never calls dead or unreachable what `simulate` fires or enters.

Hypothesis builds random small automata and systems of two (guards strict and
not, equalities, invariants that entries may violate, resets onto guard
boundaries, shared labels); each is simulated with today's simulator and
checked. Every edge the run fires must not be a ``dead-edge`` and every
location it enters must not be an ``unreachable-location`` (nor a declared
``reachable`` one reported as not reached). The claims of ``check`` are made
for runs that stay within the declared bounds, so a run is compared only up
to the first stored point outside them.

The in-suite size is small; ``make fuzz`` (``HYBRID_FUZZ=1``) runs
:data:`FULL_EXAMPLES`.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybrid

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
def automaton_text(draw: st.DrawFn, name: str = "fuzz", suffix: str = "", labels=()) -> str:
    x, y = f"x{suffix}", f"y{suffix}"
    terms = st.sampled_from(_terms(x, y))
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
    lines = [
        f"automaton: {name}",
        f"state: {{{x}: {{initial: {draw(st.sampled_from([0, 1, -1, 0.5]))}{bounds}}}, "
        f"{y}: {{initial: {draw(st.sampled_from([0, 1, 2]))}}}}}",
    ]
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
        lines.append(f"  {loc}: {{flow: {flow}, invariant: '{inv}'}}")
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
    return "\n".join(lines) + "\n"


@st.composite
def model(draw: st.DrawFn) -> hybrid.Automaton | hybrid.System:
    if draw(st.booleans()):
        return hybrid.load_text(draw(automaton_text()))
    labels = draw(st.sampled_from([(), ("go",), ("go", "stop")]))
    first = hybrid.load_text(draw(automaton_text("p", "0", labels)))
    second = hybrid.load_text(draw(automaton_text("q", "1", labels)))
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


def assert_check_agrees_with_run(m: hybrid.Automaton | hybrid.System) -> None:
    try:
        run = hybrid.simulate(
            m, t_end=3.0, max_jumps=40, max_jumps_per_instant=15, handle_sigint=False
        )
    except hybrid.SimulationError:
        return
    horizon = _bounded_prefix(m, run)
    fired = {part for jump in run.jumps if jump.t < horizon for part in jump.edge.split("+")}
    entered = {
        part
        for t, loc in zip(run.t.tolist(), run.location.tolist(), strict=True)
        if t < horizon or t == 0.0
        for part in str(loc).split("|")
    }
    report = hybrid.check(m)
    dead = {f.where for f in report.findings if f.rule == "dead-edge"}
    unreachable = {f.where for f in report.findings if f.rule == "unreachable-location"}
    assert not (fired & dead), f"fired but called dead: {fired & dead}"
    assert not (entered & unreachable), f"entered but called unreachable: {entered & unreachable}"


@settings(
    max_examples=examples(IN_SUITE_EXAMPLES, FULL_EXAMPLES),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    derandomize=os.environ.get("HYBRID_FUZZ", "0") in ("", "0"),
)
@given(model())
def test_check_never_calls_dead_what_simulate_fires(m: hybrid.Automaton | hybrid.System) -> None:
    assert_check_agrees_with_run(m)


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
