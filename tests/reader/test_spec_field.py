"""The field's constructs in spec files: what they read as, and every mistake at its place.

Initial sets (``initial: [lo, hi]``, ``nominal``), bounded inputs (``range``),
urgent locations, several initial locations, ``properties.forbidden``, and
``rename`` binds of one spec several times in a system.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import hybrid
from hybrid.model import Range

FULL = """
automaton: full
state:
  x: {initial: [0, 2], nominal: 0.5, bounds: [-1, 3]}
  y: {initial: 1}
inputs:
  u: {range: [-1, 1]}
  w: {}
locations:
  a: {flow: {x: u + w}}
  b: {urgent: true}
initial: {location: [b, a], state: {y: [0, 4]}}
edges:
  - {from: b, to: a}
properties:
  forbidden:
    - {location: a, when: "x >= 2.5"}
    - {when: "y < 0"}
"""


def test_every_construct_reads_as_written() -> None:
    m = hybrid.load_text(FULL)
    assert isinstance(m, hybrid.Automaton)
    assert m.initial_set() == {"x": Range(0.0, 2.0, 0.5, True), "y": Range(0.0, 4.0, 2.0, False)}
    assert m.initial_vector() == [0.5, 2.0]
    assert m.inputs == ("u", "w") and m.input_ranges() == {"u": Range(-1.0, 1.0, 0.0, False)}
    assert m.locations["b"].urgent and not m.locations["a"].urgent
    assert (m.initial_location, m.initial_locations) == ("b", ("b", "a"))
    first, second = m.properties.forbidden
    assert (dict(first.locations), first.when_source) == ({"": "a"}, "x >= 2.5")
    assert (dict(second.locations), second.text()) == ({}, "y < 0")


MISTAKES = [
    ("state: {x: {initial: [2, 1]}}", "2:22", "initial set of 'x' [2, 1] is empty: low > high"),
    (
        "state: {x: {initial: [0, 1], nominal: 3}}",
        "2:39",
        "nominal 3 is outside the initial set of 'x' [0, 1]",
    ),
    ("state: {x: {initial: 1, nominal: 1}}", "2:25", "`nominal` goes with an initial set"),
    (
        "state: {x: {initial: [0, 5], bounds: [0, 1]}}",
        "2:22",
        "initial set of 'x' [0, 5] is not inside its bounds",
    ),
    ("state: {x: {initial: [0, .inf]}}", "2:22", "must be finite"),
    ("state: {x: {initial: [1]}}", "2:22", "expected [low, high]: two numbers"),
    (
        "state: {x: {initial: 'a'}}",
        "2:23",
        "Input should be a valid number or an interval [low, high]",
    ),
    ("inputs: {u: {range: [1, 0]}}", "2:21", "range of 'u' [1, 0] is empty"),
    ("inputs: {u: {nominal: 0}}", "2:14", "input 'u' has no range"),
    (
        "inputs: {u: {rang: [0, 1]}}",
        "2:14",
        "unknown key 'rang' in inputs.u; did you mean 'range'?",
    ),
    ("inputs: 5", "2:9", "expected a list of input names, or a mapping"),
    ("initial: {location: [l, nowhere]}", "2:25", "initial location 'nowhere' is not a location"),
    ("initial: {location: [l, l]}", "2:25", "initial location 'l' is listed twice"),
    ("initial: {location: []}", "2:21", "List should have at least 1 item"),
    ("initial: {state: {x: {initial: [0, 1], nomnal: 0}}}", "2:40", "did you mean 'nominal'?"),
    (
        "properties: {forbidden: [{location: nowhere}]}",
        "2:37",
        "forbidden: unknown location 'nowhere'",
    ),
    ("properties: {forbidden: [{}]}", "2:26", "needs `location`, `locations` or a condition"),
    (
        "properties: {forbidden: [{locations: {a: l}}]}",
        "2:27",
        "in an automaton write `location: name`",
    ),
    ("properties: {forbidden: [{location: l, when: 'z > 1'}]}", "2:47", "unknown name 'z'"),
    ("properties: {forbidden: [{location: l, when: 'x + 1'}]}", "2:47", "expected a condition"),
]


@pytest.mark.parametrize(("text", "where", "message"), MISTAKES, ids=[m[0] for m in MISTAKES])
def test_a_mistake_is_reported_at_its_place(text: str, where: str, message: str) -> None:
    spec = f"automaton: a\n{text}\nlocations: {{l: {{}}}}\n"
    if "state:" not in text:
        spec = spec.replace("automaton: a\n", "automaton: a\nstate: {x: {}}\n").replace(
            "\n" + text, "\n" + text
        )
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load_text(spec, file="a.yaml")
    line = int(where.split(":")[0]) + (0 if "state:" in text else 1)
    got = [f"{p.line}:{p.column}: {m}" for p, m in info.value.problems]
    assert any(g.startswith(f"{line}:{where.split(':')[1]}: ") and message in g for g in got), got


TEMPLATE = """
automaton: lag
parameters: {k: 1.0}
state: {y: {initial: 0}}
signals: {out: 2 * y}
inputs: [u]
labels: [tick]
locations: {l: {flow: {y: k * (u - y)}}}
edges: [{from: l, to: l, label: tick, guard: y > 5}]
"""


def _system(tmp_path: Path, components: str, extra: str = "") -> Path:
    (tmp_path / "lag.yaml").write_text(TEMPLATE)
    (tmp_path / "src.yaml").write_text("automaton: src\nstate: {s: {}}\nlocations: {on: {}}\n")
    path = tmp_path / "sys.yaml"
    path.write_text("system: s\ncomponents:\n" + components + extra)
    return path


def test_a_rename_renames_everything_it_names(tmp_path: Path) -> None:
    path = _system(
        tmp_path,
        "  - {spec: src.yaml}\n"
        "  - {spec: lag.yaml, as: one, rename: {u: s, y: y1, out: out1, tick: t1}}\n"
        "  - {spec: lag.yaml, as: two, rename: {u: out1, y: y2, out: out2, tick: t2}}\n",
    )
    m = hybrid.load(path)
    assert isinstance(m, hybrid.System)
    one, two = m.components[1].automaton, m.components[2].automaton
    assert (one.state_names, one.inputs, one.signal_names, one.labels) == (
        ("y1",),
        ("s",),
        ("out1",),
        ("t1",),
    )
    assert two.inputs == ("out1",) and two.edges[0].label == "t2"
    assert m.free_inputs == () and m.providers["out1"] == 1 and m.providers["s"] == 0
    assert m.shared_labels == {}  # t1 and t2: the instances do not synchronise


RENAME_MISTAKES = [  # line 4: "  - {spec: lag.yaml, as: one, rename: {...}}", the map at 39
    (
        "{y: y1, nowhere: z}",
        "4:47",
        "rename: 'nowhere' is not a state variable, signal, input or label of 'lag'",
    ),
    ("{k: gain}", "4:40", "'k' is a parameter of 'lag': set it with `parameters:`"),
    ("{y: out}", "4:43", "state variable 'y' and signal 'out' of 'lag' would both be named 'out'"),
    ("{y: sin}", "4:43", "rename: 'sin' is a reserved name"),
    ("{y: 'not a name'}", "4:44", "must be a name"),
]


@pytest.mark.parametrize(("rename", "where", "message"), RENAME_MISTAKES)
def test_a_bad_rename_is_reported_at_its_place(
    tmp_path: Path, rename: str, where: str, message: str
) -> None:
    path = _system(
        tmp_path, f"  - {{spec: src.yaml}}\n  - {{spec: lag.yaml, as: one, rename: {rename}}}\n"
    )
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load(path)
    got = [f"{p.line}:{p.column}: {m}" for p, m in info.value.problems]
    assert any(g.startswith(where + ": ") and message in g for g in got), got


def test_an_unbound_input_needs_a_binding_or_a_range(tmp_path: Path) -> None:
    path = _system(tmp_path, "  - {spec: lag.yaml}\n")
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load(path)
    assert info.value.file.endswith("lag.yaml") and info.value.line == 6
    assert "bind it (rename: {u: other}), or give it a range" in info.value.message


def test_a_free_input_shared_by_two_components_has_one_range(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text(
        "automaton: a\nstate: {x: {}}\ninputs: {u: {range: [0, 1]}}\nlocations: {l: {flow: {x: u}}}\n"
    )
    (tmp_path / "b.yaml").write_text(
        "automaton: b\nstate: {y: {}}\ninputs: {u: {range: [0, 2]}}\nlocations: {l: {flow: {y: u}}}\n"
    )
    (tmp_path / "s.yaml").write_text("system: s\ncomponents: [{spec: a.yaml}, {spec: b.yaml}]\n")
    with pytest.raises(
        hybrid.SpecError, match=r"free input 'u' of component 'b' has the range \[0, 2\]"
    ):
        hybrid.load(tmp_path / "s.yaml")


def test_component_initial_sets_are_in_the_names_of_the_file(tmp_path: Path) -> None:
    path = _system(
        tmp_path,
        "  - {spec: src.yaml}\n"
        "  - spec: lag.yaml\n    rename: {u: s, y: y1}\n"
        "    initial: {state: {y: {initial: [0, 1], nominal: 0.25}}}\n",
    )
    m = hybrid.load(path)
    assert m.initial_set()["y1"] == Range(0.0, 1.0, 0.25, True)
    bad = _system(
        tmp_path,
        "  - {spec: src.yaml}\n"
        "  - spec: lag.yaml\n    rename: {u: s, y: y1}\n"
        "    initial: {state: {y1: [0, 1]}}\n",
    )
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.load(bad)
    assert (info.value.line, info.value.column) == (6, 23)
    assert "has no state variable 'y1' (in the names of its file: y)" in info.value.message


def test_system_forbidden_states_name_components_and_read_every_variable(tmp_path: Path) -> None:
    ok = _system(
        tmp_path,
        "  - {spec: src.yaml}\n  - {spec: lag.yaml, rename: {u: s}}\n",
        "properties:\n  forbidden:\n    - {locations: {lag: l, src: on}, when: 'y > s'}\n"
        "    - {location: lag.l}\n",
    )
    m = hybrid.load(ok)
    first, second = m.properties.forbidden
    assert dict(first.locations) == {"lag": "l", "src": "on"} and dict(second.locations) == {
        "lag": "l"
    }
    for extra, where, message in [
        ("    - {locations: {nope: l}}\n", "7:20", "unknown component 'nope'"),
        ("    - {locations: {lag: nope}}\n", "7:25", "component 'lag' has no location 'nope'"),
        ("    - {location: l}\n", "7:18", "unknown location 'l'; in a system write it qualified: 'lag.l'"),
        ("    - {location: lag.l, locations: {lag: l}}\n", "7:25", "not both"),
        ("    - {when: 'k > 1'}\n", "7:15", "unknown name 'k'"),
    ]:
        bad = _system(
            tmp_path,
            "  - {spec: src.yaml}\n  - {spec: lag.yaml, rename: {u: s}}\n",
            "properties:\n  forbidden:\n" + extra,
        )
        with pytest.raises(hybrid.SpecError) as info:
            hybrid.load(bad)
        assert (
            f"{info.value.line}:{info.value.column}" == where and message in info.value.message
        ), (
            extra,
            str(info.value),
        )
