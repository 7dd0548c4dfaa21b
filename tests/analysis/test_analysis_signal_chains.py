"""Signals defined through each other in long chains: the analyses follow them without recursion.

A chain ``s0 = x``, ``s{k} = s{k-1} + 1`` has ``s{k} = x + k`` in closed form.
Evaluated over a box, linearised, or differentiated along a flow, each analysis
must give that (or say it cannot form a derivative that deep), at any length:
before, a chain of about 300 ended ``check``, ``graph`` and ``reach`` in a
RecursionError.
"""

from __future__ import annotations

import pytest

import hybrid
from hybrid.analysis.flows import MAX_DERIVATIVE_DEPTH, derivative
from hybrid.analysis.graph import location_graph
from hybrid.analysis.linear import Linearizer
from hybrid.expr import ir
from hybrid.expr.interval import Interval
from hybrid.expr.ranges import IntervalEvaluator

LENGTH = 3000


def chain(n: int) -> dict[str, ir.Expr]:
    """``s0 = x`` and ``s{k} = s{k-1} + 1``: ``s{k} = x + k``."""
    defs: dict[str, ir.Expr] = {"s0": ir.Var("x", ir.STATE)}
    for k in range(1, n):
        defs[f"s{k}"] = ir.Bin("+", ir.Var(f"s{k - 1}", ir.SIGNAL), ir.Num(1.0))
    return defs


def chain_spec(n: int) -> str:
    lines = ["automaton: chain", "state:", "  x: {initial: [0.0, 1.0]}", "signals:", "  s0: x"]
    lines += [f"  s{k}: s{k - 1} + 1" for k in range(1, n)]
    lines += [
        "locations:",
        "  a:",
        "    flow: {x: -1}",
        f"    invariant: s{n - 1} <= {n + 5}",
        "initial: {location: a}",
        "edges:",
        f"  - {{from: a, to: a, guard: s{n - 1} >= {n + 10}, reset: {{x: 0}}}}",
    ]
    return "\n".join(lines) + "\n"


def test_a_chain_evaluates_over_a_box_to_its_closed_form() -> None:
    evaluator = IntervalEvaluator({"x": Interval(0.0, 1.0)}, chain(LENGTH))
    last = evaluator.number(ir.Var(f"s{LENGTH - 1}", ir.SIGNAL))
    assert (last.lo, last.hi) == (LENGTH - 1.0, LENGTH + 0.0)
    middle = evaluator.number(ir.Var("s1234", ir.SIGNAL))  # cached on the way
    assert (middle.lo, middle.hi) == (1234.0, 1235.0)


def test_a_chain_linearises_to_its_closed_form() -> None:
    defs = chain(LENGTH)
    form = Linearizer(IntervalEvaluator({}, defs)).affine(ir.Var(f"s{LENGTH - 1}", ir.SIGNAL))
    assert dict(form.coeffs) == {"x": 1.0} and form.const == LENGTH - 1.0


def test_a_derivative_follows_a_chain_of_any_length() -> None:
    """d/dt (x + k) = x' = -1, however long the chain (each link simplifies)."""
    found = derivative(ir.Var(f"s{LENGTH - 1}", ir.SIGNAL), {"x": ir.Num(-1.0)}, chain(LENGTH))
    assert isinstance(found, ir.Num) and found.value == -1.0


def powers(n: int) -> dict[str, ir.Expr]:
    """``p0 = x`` and ``p{k} = p{k-1} * x``: ``p{k} = x ** (k + 1)``."""
    defs: dict[str, ir.Expr] = {"p0": ir.Var("x", ir.STATE)}
    for k in range(1, n):
        defs[f"p{k}"] = ir.Bin("*", ir.Var(f"p{k - 1}", ir.SIGNAL), ir.Var("x", ir.STATE))
    return defs


def test_a_derivative_through_a_chain_is_its_closed_form_until_too_deep() -> None:
    """d/dt x ** (k + 1) = (k + 1) x ** k x'; a chain whose derivative nests deeper than the
    limit gives none (before, it ended in a RecursionError)."""
    flow, k = {"x": ir.Num(2.0)}, 20
    found = derivative(ir.Var(f"p{k}", ir.SIGNAL), flow, powers(k + 1))
    assert found is not None
    x = 1.1
    value = IntervalEvaluator({"x": Interval(x, x)}, powers(k + 1)).number(found)
    assert value.lo == pytest.approx((k + 1) * x**k * 2.0, rel=1e-12)
    assert value.hi == pytest.approx(value.lo, rel=1e-12)
    deep = derivative(ir.Var(f"p{LENGTH - 1}", ir.SIGNAL), flow, powers(LENGTH))
    assert deep is None and MAX_DERIVATIVE_DEPTH < LENGTH


@pytest.mark.parametrize("n", [300, 1000])
def test_check_graph_and_reach_take_a_deep_chain(n: int) -> None:
    """The guard ``x + n - 1 >= n + 10`` needs ``x >= 11``: x starts in [0, 1] and falls."""
    model = hybrid.load_text(chain_spec(n), file="chain.yaml")
    assert isinstance(model, hybrid.Automaton)
    report = hybrid.check(model)  # the guard needs x >= 11: the edge is dead, nothing else
    assert [(f.rule, f.where) for f in report.findings] == [("dead-edge", "a->a#0")]
    graph = location_graph(model)
    assert graph.has_edge("a", "a")
    result = hybrid.reach(model, t_end=1.0, max_jumps=2, step=0.01)
    lo, hi = result.hull("a")
    x = result.variables.index("x")
    assert lo[x] <= -1.0 + 1e-6 and hi[x] <= 1.0 + 1e-6  # from [0, 1], falling at rate 1 for 1 s
