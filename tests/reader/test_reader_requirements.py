"""Requirements in spec files: what is accepted, and every mistake at its line and column."""

from __future__ import annotations

from pathlib import Path

import pytest

import hybrid
from hybrid.errors import SpecError

BASE = """automaton: a
parameters: {limit: 5.0}
state: {x: {initial: 0.0}}
signals: {y: 2*x}
locations: {moving: {flow: {x: 1}}, resting: {}}
edges: [{from: moving, to: resting, guard: x >= 3}]
requirements:
"""


def _problems(lines: str) -> list[tuple[int, int, str]]:
    with pytest.raises(SpecError) as info:
        hybrid.load_text(BASE + lines, file="a.yaml")
    return [(p.line, p.column, m) for p, m in info.value.problems]


def test_a_valid_list_is_read_in_order() -> None:
    model = hybrid.load_text(
        BASE
        + """  - {name: low, always: "x <= limit"}
  - {name: settles, eventually: "abs(y - 6) <= 0.01", within: [0, 10]}
  - {name: moves, always: "x >= 0", in: moving, within: [1, .inf]}
"""
    )
    assert isinstance(model, hybrid.Automaton)
    low, settles, moves = model.requirements
    assert (low.kind, low.location, low.within) == ("always", None, None)
    assert (settles.kind, settles.within) == ("eventually", (0.0, 10.0))
    assert moves.location == "moving" and moves.within == (1.0, float("inf"))
    # a parameter read only by a requirement is used: no unused-declaration finding
    assert not hybrid.check(model).by_rule("unused-declaration")


@pytest.mark.parametrize(
    ("lines", "expected"),
    [
        ("  - {name: r}\n", (8, 5, "needs `always:` or `eventually:`")),
        ('  - {name: r, always: "x > 1", eventually: "x > 2"}\n', (8, 32, "not both")),
        ('  - {name: r, always: "x >> 1"}\n', (8, 24, "'>>' is not supported")),
        ('  - {name: r, always: "z > 1"}\n', (8, 24, "unknown name 'z'")),
        ('  - {name: r, always: "x + 1"}\n', (8, 24, "expected a condition")),
        ('  - {name: r, always: "x > 1", in: movin}\n', (8, 36, "did you mean 'moving'")),
        ('  - {name: r, always: "x > 1", within: [3, 1]}\n', (8, 40, "starts after it ends")),
        ('  - {name: r, always: "x > 1", within: [-.inf, 1]}\n', (8, 40, "finite start")),
        ('  - {name: r, always: "x > 1"}\n  - {name: r, always: "x > 2"}\n', (9, 12, "used twice")),
        ('  - {name: r, alwayz: "x > 1"}\n', (8, 15, "did you mean 'always'")),
    ],
)
def test_mistakes_are_placed(lines: str, expected: tuple[int, int, str]) -> None:
    problems = _problems(lines)
    line, column, text = expected
    assert any(p[0] == line and p[1] == column and text in p[2] for p in problems), problems


SYSTEM = """system: both
components:
  - spec: a.yaml
  - spec: b.yaml
requirements:
"""
OTHER = """automaton: b
state: {w: {initial: 0.0}}
locations: {moving: {flow: {w: 2}}}
"""


def test_system_requirements_read_every_component_and_qualify_locations(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text(BASE + '  - {name: own, always: "x <= limit"}\n')
    (tmp_path / "b.yaml").write_text(OTHER)
    (tmp_path / "s.yaml").write_text(
        SYSTEM + '  - {name: sum, always: "y + w <= 5", in: b.moving}\n'
    )
    system = hybrid.load(tmp_path / "s.yaml")
    assert isinstance(system, hybrid.System)
    assert [r.name for r in system.requirements] == ["sum"]
    run = hybrid.simulate(system, t_end=2.0, rtol=1e-10, atol=1e-12)
    assert sorted(run.requirements) == ["a.own", "sum"]
    # y + w = 2 t + 2 t reaches 5 at t = 1.25; the component's own bound holds (x <= 2)
    assert run.requirements["sum"].violated_at == pytest.approx(1.25, abs=1e-9)
    assert run.requirements["a.own"].robustness == pytest.approx(3.0, abs=1e-9)
    (tmp_path / "bad.yaml").write_text(SYSTEM + '  - {name: sum, always: "x > 1", in: moving}\n')
    with pytest.raises(SpecError) as info:
        hybrid.load(tmp_path / "bad.yaml")
    (position, message), *_ = info.value.problems
    assert (position.line, position.column) == (6, 38)
    assert "unknown location 'moving'" in message and "did you mean 'b.moving'" in message
