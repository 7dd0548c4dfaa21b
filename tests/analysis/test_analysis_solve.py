"""Deciding conditions: normal forms, linear programs with strict rows, exits, zero-time steps."""

from __future__ import annotations

import math

import pytest

import hybrid
from hybrid.analysis.flows import derivative, exit_conditions
from hybrid.analysis.linear import Affine, Linearizer, Row
from hybrid.analysis.lp import lp_feasible
from hybrid.analysis.solve import Env, closure, contract, dnf, negate, nnf, satisfiable
from hybrid.analysis.static import AutomatonFacts, inline_signals
from hybrid.analysis.zerotime import ZeroTimeGraph
from hybrid.expr import ir
from hybrid.expr.interval import Interval
from hybrid.expr.parse import Scope, parse_expression
from hybrid.expr.printer import expression_text
from hybrid.expr.ranges import IntervalEvaluator

SCOPE = Scope({"x": "state", "y": "state", "u": "input", "g": "signal"})
BOX = {"x": Interval(0.0, 10.0), "y": Interval(0.0, 10.0)}


def cond(text: str) -> ir.Expr:
    return parse_expression(text, SCOPE, want="bool")


def num(text: str) -> ir.Expr:
    return parse_expression(text, SCOPE)


def text(node: ir.Expr) -> str:
    return expression_text(node)


def test_nnf_pushes_negation_and_splits_chains():
    assert text(nnf(cond("not (x < 1 or y >= 2)"))) == "x >= 1 and y < 2"
    assert text(nnf(cond("0 <= x < 3"))) == "0 <= x and x < 3"
    assert text(negate(cond("x == 1"))) == "x != 1"
    assert text(closure(cond("x < 1 and y != 2"))) == "x <= 1 and true"


def test_dnf_and_its_cap():
    terms = dnf(cond("(x < 1 or x > 2) and (y < 1 or y > 2)"))
    assert terms is not None and len(terms) == 4
    assert dnf(cond("x != 1")) is not None and len(dnf(cond("x != 1"))) == 2
    assert dnf(cond("true")) == [()] and dnf(cond("false")) == []
    wide = " and ".join(f"(x < {i} or y > {i})" for i in range(8))  # 2**8 conjunctions
    assert dnf(cond(wide)) is None
    assert satisfiable(cond(wide), Env(), BOX)  # beyond the cap: intervals, leaning to "may"


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("x + y >= 12 and x - y > 9", False),  # needs 2x > 21 with x <= 10
        ("x - y >= 1 and y - x >= 1", False),  # contraction alone cannot see it
        ("x + y >= 12 and x - y >= 5", True),
        ("x == 3 and x > 3", False),  # strict: exact
        ("x == 3 and x >= 3", True),
        ("x + y == 20 and x < 10", False),  # strict linear row, decided by the slack
        ("x + y == 20 and x <= 10", True),
        ("x*x + y*y <= 1 and x >= 2", False),  # non-linear: intervals
        ("sin(x) > 0.5 and sin(x) < 0.4", False),  # same non-linear term: one variable
        ("u > 3 and u < 2", False),  # inputs are unknown but still variables
        ("u > 3 and x < 2", True),
        ("x != 5", True),
        ("x < 0 or y > 10", False),
    ],
)
def test_satisfiable(source, expected):
    assert satisfiable(cond(source), Env(), BOX) is expected


def test_signals_are_read_through_the_environment():
    env = Env({"g": num("2*x + 1")})
    assert not satisfiable(cond("g > 21"), env, BOX)
    assert satisfiable(cond("g >= 21"), env, BOX)


def test_contract_narrows_and_hulls_disjunctions():
    assert contract(cond("x <= 3 and y > 4"), Env(), BOX) == {
        "x": Interval(0.0, 3.0),
        "y": Interval(4.0, 10.0),
    }
    narrowed = contract(cond("x <= 2 or x >= 8"), Env(), BOX)
    assert narrowed is not None and narrowed["x"] == Interval(0.0, 10.0)
    narrowed = contract(cond("(x <= 2 and y <= 1) or (x <= 3 and y <= 2)"), Env(), BOX)
    assert narrowed == {"x": Interval(0.0, 3.0), "y": Interval(0.0, 2.0)}
    assert contract(cond("x > 10"), Env(), BOX) is None
    assert contract(cond("2*x + y <= 4"), Env(), BOX) == {
        "x": Interval(0.0, 2.0),
        "y": Interval(0.0, 4.0),
    }


def test_lp_rows():
    x = Affine({"x": 1.0}, 0.0)
    box = {"x": Interval(0.0, 1.0)}
    assert lp_feasible([Row(x - Affine({}, 1.0), "==")], box)
    assert not lp_feasible([Row(x - Affine({}, 2.0), "==")], box)
    assert lp_feasible([Row(Affine({}, -1.0), "<")], box)  # constant -1 < 0
    assert not lp_feasible([Row(Affine({}, 0.0), "<")], box)
    lin = Linearizer(IntervalEvaluator(BOX))
    (row,) = lin.atom(cond("3*x - y/2 + 1 <= 2*y"))
    assert row.form.coeffs == {"x": 3.0, "y": -2.5} and row.form.const == 1.0 and row.op == "<="
    (row,) = lin.atom(cond("x*y > 1"))
    assert list(row.form.coeffs) == ["#0"] and lin.bounds(BOX)["#0"] == Interval(0.0, 100.0)


def test_exit_conditions_follow_the_flow():
    scope = Scope({"h": "state", "v": "state", "T": "state"})
    inv = parse_expression("h >= 0", scope, want="bool")
    (exit_,) = exit_conditions(inv, {"h": parse_expression("v", scope)})
    assert text(exit_) == "h == 0 and v < 0"
    # constant rate pointing inward: never left; outward: the whole face
    assert exit_conditions(inv, {"h": parse_expression("2", scope)}) == []
    (face,) = exit_conditions(inv, {"h": parse_expression("-2", scope)})
    assert text(face) == "h == 0"
    band = parse_expression("18 <= T and T <= 22", scope, want="bool")
    faces = exit_conditions(band, {"T": parse_expression("0.1*(30 - T)", scope)})
    assert [text(f) for f in faces] == [
        "T <= 22 and 18 == T and -(0.1 * (30 - T)) > 0",
        "18 <= T and T == 22 and 0.1 * (30 - T) > 0",
    ]
    assert exit_conditions(ir.BoolConst(True), {}) == []


def test_derivatives():
    flow = {"x": num("y"), "y": num("-x")}
    assert text(derivative(num("sin(x)"), flow, {})) == "cos(x) * y"
    assert text(derivative(num("x**3"), flow, {})) == "3 * x ** 2 * y"
    assert derivative(num("u + x"), flow, {}) is None  # an input: unknown rate
    assert text(derivative(num("g"), flow, {"g": num("2*x")})) == "2 * y"
    assert derivative(ir.Index("w", 0), flow, {}) is None


def test_inline_signals():
    signals = {"g": num("2*x"), "h": ir.Var("u", "input")}
    assert text(inline_signals(cond("g > 1"), signals)) == "2 * x > 1"
    assert inline_signals(ir.Var("h", "signal"), signals) is None
    assert inline_signals(ir.Index("w", 1), signals) is None
    deep = {
        f"s{i}": num("x")
        if i == 0
        else ir.Bin("+", ir.Var(f"s{i - 1}", "signal"), ir.Var(f"s{i - 1}", "signal"))
        for i in range(20)
    }
    assert inline_signals(ir.Var("s19", "signal"), deep) is None  # would grow to 2**19 nodes


GAMMA = """
automaton: gamma
state:
  q: {{initial: 1.3, bounds: [-3.1416, 3.1416]}}
  k: {{initial: 0}}
signals: {{gamma: sin(q) / sin(0.78)}}
locations: {{a: {{flow: {{q: -1}}}}, b: {{flow: {{q: 1}}}}}}
edges:
  - {{name: low, from: a, to: b, guard: gamma < 0.65, reset: {reset}}}
  - {{name: high, from: b, to: a, guard: gamma > 1, reset: {back}}}
"""


def test_zero_time_cycles_remember_what_a_reset_leaves_alone():
    def cycles(reset: str, back: str = "{}") -> list[tuple[int, ...]]:
        facts = AutomatonFacts(hybrid.load_text(GAMMA.format(reset=reset, back=back)))
        return [c.cycle for c in ZeroTimeGraph(facts).components()]

    assert cycles("{k: 1}") == []  # q untouched: gamma < 0.65 still holds after 'low'
    assert cycles("{q: 1.5}") == []  # q := 1.5 enables 'high', which keeps gamma > 1
    assert cycles("{q: 0.2 + k}", "{q: k}") == [(0, 1)]  # k unbounded: q may be anything


def test_post_box_of_the_bouncing_ball():
    facts = AutomatonFacts(hybrid.load("specs/bouncing_ball.yaml"))
    bounce = facts.edges[0]
    assert bounce.fires is not None
    # the bounce fires on the floor (h = 0) going down, v in [-20, 0]
    assert bounce.fires["h"] == Interval(0.0, 0.0)
    assert bounce.fires["v"].lo == -20.0 and bounce.fires["v"].hi == 0.0
    after = facts.reset_box("falling", bounce.reset, bounce.fires)
    assert after is not None
    assert after["h"] == Interval(0.0, 0.0)
    assert after["v"].lo == 0.0 and math.isclose(after["v"].hi, 16.0)
    assert ZeroTimeGraph(facts).components() == []  # v >= 0 after it: no bounce at once
