"""Export to SpaceEx: every spec of specs/ exports (or is refused naming the construct), and our
own importer reads the export back to the same automaton; the specs that load today also
simulate to the same jump times."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from support import REPO, SPECS, run_cli

import hybrid
from hybrid.compose import as_system
from hybrid.errors import SpecError
from hybrid.expr import ir
from hybrid.expr.parse import Scope, parse_expression
from hybrid.expr.printer import expression_text
from hybrid.interchange import export_spaceex, import_spaceex_text
from hybrid.reader.yamlpos import read_yaml_text

NS = "{http://www-verimag.imag.fr/xml-namespaces/sspaceex}"
def _vector_signals(model: hybrid.Automaton | hybrid.System) -> set[str]:
    return {n for c in as_system(model).components for n in c.automaton.vector_sizes}

ALL_SPECS = sorted(p.name for p in SPECS.glob("*.yaml"))
GUARDS = {  # by hand: our guard, and the target's invariant where SpaceEx needs it said
    "bouncing_ball.yaml": ["h <= 0 and v < 0"],  # h >= 0 after h := 0 is 0 >= 0: holds
    "thermostat.yaml": ["T <= T_low and T <= T_high", "T >= T_high and T >= T_low"],
}


def _same(a: str, b: str, names: set[str]) -> bool:
    """Two expressions print alike once parsed (our printer is the normal form)."""
    scope = Scope(dict.fromkeys(names, "state"))
    want = "bool" if any(op in a for op in "<>=") or a in ("true", "false") else "number"
    return expression_text(parse_expression(a, scope, want=want)) == expression_text(
        parse_expression(b, scope, want=want)
    )


def _plain(node: ir.Expr) -> bool:
    """No signal or input in ``node``: the export writes it as it is (nothing inlined)."""
    return not (ir.names_in(node, ir.SIGNAL) | ir.names_in(node, ir.INPUT))


@pytest.mark.parametrize("name", ALL_SPECS)
def test_every_spec_exports_and_reads_back(name: str) -> None:
    model = hybrid.load(SPECS / name)
    vectors = _vector_signals(model)
    if vectors:  # the library's vector-valued functions have no SpaceEx counterpart
        with pytest.raises(SpecError) as info:
            export_spaceex(model)
        named = info.value.message.split("vector signal '")[1].split("[")[0]
        assert named in vectors and "has no SpaceEx counterpart" in info.value.message
        assert info.value.file.endswith(".yaml") and info.value.line > 1
        return
    out = export_spaceex(model)
    root = ET.fromstring(out.xml)  # well-formed, for an independent parser
    assert root.tag == f"{NS}sspaceex"
    back = import_spaceex_text(out.xml, out.cfg)
    data = {n: read_yaml_text(t, n).data for n, t in back.files.items()}
    system = as_system(model)
    for comp in system.components:
        a = comp.automaton
        spec = data[f"{comp.name}.yaml"]
        names = {*a.state_names, *a.parameters, *a.inputs, *system.state_names}
        assert list(spec["locations"]) == list(a.locations)
        for loc_name, loc in a.locations.items():
            flow = spec["locations"][loc_name].get("flow", {})
            for state in a.state_names:
                mine = loc.flow.get(state)
                if mine is None:
                    assert flow[state] == "0"
                elif _plain(mine):
                    assert _same(flow[state], expression_text(mine), names)
        assert [(e["from"], e["to"], e.get("label")) for e in spec.get("edges", [])] == [
            (e.source, e.target, e.label) for e in a.edges
        ]
        assert [e["guard"] for e in spec.get("edges", [])] == GUARDS[name]
        for edge, imported in zip(a.edges, spec.get("edges", []), strict=True):
            if _plain(edge.guard):
                assert set(imported.get("reset", {})) == {
                    k for k, v in edge.reset.items() if expression_text(v) != k
                }
    top = data[back.top]
    initial = {c["as"]: c["initial"] for c in top["components"]}
    for comp, loc in zip(system.components, system.initial_mode, strict=True):
        assert initial[comp.name]["location"] == loc
        values = dict(zip(comp.automaton.state_names, comp.automaton.initial_vector(), strict=True))
        assert initial[comp.name]["state"] == values


def _load_back(model: hybrid.Automaton | hybrid.System, tmp_path: Path) -> Any:
    out = export_spaceex(model)
    back = import_spaceex_text(out.xml, out.cfg)
    for n, text in back.files.items():
        (tmp_path / n).write_text(text)
    return hybrid.load(tmp_path / back.top)


@pytest.mark.parametrize("name", ["bouncing_ball.yaml", "thermostat.yaml"])
def test_round_trip_simulates_to_the_same_jump_times(name: str, tmp_path: Path) -> None:
    model = hybrid.load(SPECS / name)
    again = _load_back(model, tmp_path)
    first = hybrid.simulate(model, t_end=30.0, rtol=1e-10, atol=1e-12)
    second = hybrid.simulate(again, t_end=30.0, rtol=1e-10, atol=1e-12)
    assert len(first.jumps) == len(second.jumps) > 5
    for a, b in zip(first.jumps, second.jumps, strict=True):
        assert b.t == pytest.approx(a.t, abs=1e-9)
    assert second.termination.cause == first.termination.cause


PLANT = """
automaton: plant
parameters: {k: 2.0}
state: {x: {initial: 1.0}}
signals: {y: k*x}
locations:
  grow: {flow: {x: x}}
"""
CONTROLLER = """
automaton: controller
state: {n: {initial: 0.0}}
inputs: [y]
locations:
  waiting: {invariant: y <= 9}
  done: {}
edges:
  - {from: waiting, to: done, guard: "y >= 4 and not t < 1", reset: {n: n + 1}, priority: 2}
  - {from: waiting, to: done, guard: "y > 8 or x ** 2 >= 16"}
"""


def test_inputs_are_inlined_time_gets_a_clock_and_priorities_a_comment() -> None:
    from hybrid.compose import compose

    plant = hybrid.load_text(PLANT)
    controller = hybrid.load_text(CONTROLLER.replace("x ** 2", "y ** 2"))
    assert isinstance(plant, hybrid.Automaton) and isinstance(controller, hybrid.Automaton)
    out = export_spaceex(compose(plant, controller, name="loop"))
    root = ET.fromstring(out.xml)
    comps = {c.get("id"): c for c in root.iter(f"{NS}component")}
    assert set(comps) == {"plant", "controller", "clock", "loop_system"}
    guards = [t.findtext(f"{NS}guard") for t in comps["controller"].iter(f"{NS}transition")]
    assert guards == ["2 * x >= 4 & t >= 1", "2 * x > 8 | (2 * x) ^ 2 >= 16"]
    params = {p.get("name"): p.get("controlled") for p in comps["controller"].iter(f"{NS}param")}
    assert params == {"n": "true", "x": "false", "t": "false"}
    assert "priority 2: SpaceEx has no priorities" in out.xml
    assert "<flow>n' == 0</flow>" in out.xml  # left out of our flow: SpaceEx needs it said
    assert out.cfg.splitlines()[:2] == [
        'system = "loop_system"',
        'initially = "loc(plant)==grow & loc(controller)==waiting & x==1 & n==0 & t==0"',
    ]
    back = import_spaceex_text(out.xml, out.cfg)
    controller_back = read_yaml_text(back.files["controller.yaml"], "c.yaml").data
    assert controller_back["inputs"] == ["x", "t_"]
    assert controller_back["edges"][0]["guard"] == "2 * x >= 4 and t_ >= 1"


@pytest.mark.parametrize(
    ("flow", "message"),
    [("abs(x)", "function 'abs'"), ("min(x, 1)", "function 'min'")],
)
def test_what_spaceex_lacks_is_refused_at_its_place(flow: str, message: str) -> None:
    model = hybrid.load_text(
        f'automaton: a\nstate: {{x: {{}}}}\nlocations:\n  l:\n    flow: {{x: "{flow}"}}\n',
        file="a.yaml",
    )
    with pytest.raises(SpecError) as info:
        export_spaceex(model)
    assert (info.value.file, info.value.line) == ("a.yaml", 4)
    assert f"cannot export to SpaceEx: {message} has no SpaceEx counterpart" in info.value.message


def test_a_not_equal_guard_is_refused() -> None:
    model = hybrid.load_text(
        "automaton: a\nstate: {x: {}}\nlocations: {l: {flow: {x: 1}}}\n"
        "edges:\n  - {from: l, to: l, guard: x != 1}\n",
        file="a.yaml",
    )
    with pytest.raises(SpecError, match="'!='"):
        export_spaceex(model)


def test_unreachable_locations_become_the_forbidden_set() -> None:
    model = hybrid.load_text(
        "automaton: a\nstate: {x: {}}\nlocations: {l: {flow: {x: 1}}, bad: {}}\n"
        "properties: {unreachable: [bad]}\n"
    )
    out = export_spaceex(model)
    assert 'forbidden = "loc(a)==bad"' in out.cfg.splitlines()
    back = import_spaceex_text(out.xml, out.cfg)
    top = read_yaml_text(back.files[back.top], "t.yaml").data
    assert top["properties"] == {"forbidden": [{"locations": {"a": "bad"}}]}


def test_the_command_writes_xml_and_cfg(tmp_path: Path) -> None:
    done = run_cli("export", "spaceex", SPECS / "thermostat.yaml", "--out", tmp_path / "t.xml")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [str(tmp_path / "t.xml"), str(tmp_path / "t.cfg")]
    ET.parse(tmp_path / "t.xml")
    assert (tmp_path / "t.cfg").read_text().startswith('system = "thermostat_system"')
    bad = run_cli("export", "spaceex", SPECS / "thermostat.yaml", "--out", tmp_path / "t.txt")
    assert bad.returncode == 2 and "must name a .xml file" in bad.stderr
    refused = run_cli(
        "export", "spaceex", SPECS / "uvms_singularity.yaml", "--out", tmp_path / "u.xml"
    )
    assert refused.returncode == 2
    assert refused.stderr.startswith("specs/uvms_singularity.yaml:") or refused.stderr.startswith(
        str(REPO / "specs")
    )
    assert not (tmp_path / "u.xml").exists()


def test_what_is_left_out_of_an_export_is_said_in_notes() -> None:
    # the tank's reachable/deadlock_free/deterministic and its edge names went without a word
    tank = hybrid.load(REPO / "docs" / "examples" / "tank.yaml")
    notes = export_spaceex(tank).notes
    assert (
        "properties not exported (reachable: filling, draining; deadlock_free; deterministic): "
        "a .cfg states forbidden sets only (unreachable locations and forbidden states are "
        "exported as its forbidden set)"
    ) in notes
    assert any(n.startswith("edge names are not exported") for n in notes)
    bare = hybrid.load_text(
        "automaton: m\nstate: {x: {initial: 1}}\nlocations: {a: {flow: {x: 1}}}\n"
        "edges: [{from: a, to: a, guard: x >= 2, reset: {x: 0}}]\n"
    )
    assert export_spaceex(bare).notes == []  # nothing named, nothing declared: nothing lost
