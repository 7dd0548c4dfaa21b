"""Every SpaceEx model of tests/data/spaceex imports (or is refused where it must be).

The emitted YAML is read back as data (``read_yaml_text``) and checked against
the XML, read independently with the standard library's ElementTree (these
files are trusted test data), and against values computed by hand.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from support import REPO, run_cli, spaceex_pairs

from hybrid.errors import SpecError
from hybrid.interchange import ImportResult, import_spaceex
from hybrid.reader.yamlpos import read_yaml_text

DATA = REPO / "tests" / "data" / "spaceex"
NS = "{http://www-verimag.imag.fr/xml-namespaces/sspaceex}"


PAIRS = spaceex_pairs(DATA)
WRONG_SYSTEM = {"1st_order", "8th_order", "16th_order", "32th_order"}


def _id(pair: tuple[Path, Path | None]) -> str:
    return f"{pair[0].name}+{pair[1].name if pair[1] else '-'}"


def _expected_refusal(xml: Path, cfg: Path | None) -> tuple[Path, int, int, str] | None:
    """Where and why an import must be refused, worked out from the raw files."""
    for number, line in enumerate(xml.read_text(encoding="latin-1").splitlines(), start=1):
        if "with offset" in line:
            return xml, number, line.index("with") + 1, "flattened form of a nondeterministic input"
    if cfg is not None and cfg.stem.split(".")[-1] in WRONG_SYSTEM:
        line = cfg.read_text().splitlines()[0]
        return cfg, 1, line.index('"') + 2, "which is not a component of"
    return None


def _data(result: ImportResult) -> dict[str, Any]:
    return {name: read_yaml_text(text, name).data for name, text in result.files.items()}


def _leaves(root: ET.Element, component: str) -> int:
    comp = next(c for c in root.iter(f"{NS}component") if c.get("id") == component)
    binds = comp.findall(f"{NS}bind")
    return sum(_leaves(root, b.get("component", "")) for b in binds) if binds else 1


def _ours(name: str) -> str:
    return "t_" if name == "t" else name


@pytest.mark.parametrize(("xml", "cfg"), PAIRS, ids=[_id(p) for p in PAIRS])
def test_every_pair_imports_or_is_refused_where_it_must_be(xml: Path, cfg: Path | None) -> None:
    refusal = _expected_refusal(xml, cfg)
    if refusal is not None:
        where, line, column, message = refusal
        with pytest.raises(SpecError) as info:
            import_spaceex(xml, cfg)
        assert (info.value.file, info.value.line, info.value.column) == (str(where), line, column)
        assert message in info.value.message
        return
    result = import_spaceex(xml, cfg)
    data = _data(result)
    assert result.top in data
    root = ET.parse(xml).getroot()
    components = {c.get("id"): c for c in root.iter(f"{NS}component")}
    for doc in data.values():
        if "automaton" not in doc:
            continue
        comp = components[doc["automaton"]]
        locations = comp.findall(f"{NS}location")
        names = {loc.get("id"): loc.get("name") for loc in locations}
        assert list(doc["locations"]) == [loc.get("name") for loc in locations]
        for loc in locations:
            primed = set(re.findall(r"(\w+)'", loc.findtext(f"{NS}flow") or ""))
            assert set(doc["locations"][loc.get("name")].get("flow", {})) == {
                _ours(p) for p in primed
            }
        transitions = comp.findall(f"{NS}transition")
        assert [(e["from"], e["to"], e.get("label")) for e in doc.get("edges", [])] == [
            (names[t.get("source")], names[t.get("target")], t.findtext(f"{NS}label"))
            for t in transitions
        ]
    top = data[result.top]
    if "system" in top:
        system = next(iter(top["system"].split()))
        expected = _leaves(root, cfg_system(cfg) or system)
        assert len(top["components"]) == expected
        assert all(c["spec"] in data for c in top["components"])


def cfg_system(cfg: Path | None) -> str | None:
    if cfg is None:
        return None
    match = re.search(r'^system\s*=\s*"?([\w.]+)"?', cfg.read_text(), re.MULTILINE)
    return match.group(1) if match else None


def _import(folder: str, xml: str, cfg: str | None = None) -> tuple[ImportResult, dict[str, Any]]:
    result = import_spaceex(DATA / folder / xml, DATA / folder / cfg if cfg else None)
    return result, _data(result)


def test_bouncing_ball_network_with_constants_from_the_bind() -> None:
    result, data = _import("bball", "bball.xml", "bball.cfg")
    assert result.top == "system.yaml"
    (ball,) = data["system.yaml"]["components"]
    assert ball == {
        "spec": "ball_template.yaml",
        "as": "ball",
        "parameters": {"g": 1.0, "c": 0.75, "eps": 0.0},
        "initial": {"location": "always", "state": {"x": [10.0, 10.2], "v": 0.0}},
    }
    (edge,) = data["ball_template.yaml"]["edges"]
    # x >= 0 (the target's invariant) is the source's too and x is not reset: already holds
    assert (edge["guard"], edge["reset"]) == ("x <= eps and v < 0", {"v": "-c * v"})


def test_circle_starts_in_both_locations_and_guards_keep_their_levels() -> None:
    _, data = _import("circle", "circle.xml", "circle.cfg")
    spec = data["circle.yaml"]
    assert spec["initial"] == {"location": ["p", "n"]}  # (1, 0) meets y >= 0 and y <= 0
    assert [e["guard"] for e in spec["edges"]] == ["y <= 0", "y >= 0"]
    assert spec["state"] == {"x": {"initial": 1.0}, "y": {"initial": 0.0}}


def test_oscillator_guards_are_the_target_invariants_and_one_location_can_start() -> None:
    _, data = _import("filtered_oscillator", "filtered_oscillator.xml", "filtered_oscillator.cfg")
    guards = {(e["from"], e["to"]): e["guard"] for e in data["oscillator_template.yaml"]["edges"]}
    # SpaceEx guards are empty: the target's invariant, minus the conjunct both share
    assert guards == {
        ("nn", "np"): "y >= -c / x0 * x",
        ("np", "pp"): "x >= 0",
        ("pp", "pn"): "y <= -c / x0 * x",
        ("pn", "nn"): "x <= 0",
    }
    top = data["osc_w_4th_order.yaml"]
    osc, *filters = top["components"]
    # x in [0.2, 0.3], y in [-0.1, 0.1]: x >= 0 rules out np and nn; pn needs
    # y <= -(0.5/0.7) x <= -0.1428 < -0.1: only pp can start
    assert osc["initial"] == {"location": "pp", "state": {"x": [0.2, 0.3], "y": [-0.1, 0.1]}}
    assert [(f["as"], f["rename"]) for f in filters] == [
        ("f4_f1", {"u": "x", "x": "x1"}),
        ("f4_f2", {"u": "x1", "x": "x2"}),
        ("f4_f3", {"u": "x2", "x": "x3"}),
        ("f4_f4", {"u": "x3", "x": "z"}),
    ]
    assert all(f["parameters"] == {"c": -5.0} for f in filters)
    assert data["filter_t.yaml"]["inputs"] == ["u"]


def test_nested_locals_are_named_by_their_path_when_their_name_is_taken() -> None:
    _, data = _import(
        "filtered_oscillator_16", "filtered_oscillator_16.xml", "filtered_oscillator_16.cfg"
    )
    comps = data["osc_w_16th_order.yaml"]["components"]
    assert len(comps) == 17
    renames = {c["as"]: c.get("rename", {}) for c in comps}
    assert renames["osc_osci"] == {}  # y is the only y: it keeps its name
    assert renames["f8a_f4a_f1"] == {"u": "x", "x": "f8a_f4a_x1"}
    assert renames["f8a_f4b_f4"] == {"u": "f8a_f4b_x3", "x": "x1"}  # x1 of the system itself
    assert renames["f8b_f4b_f4"] == {"u": "f8b_f4b_x3", "x": "z"}


def test_a_disc_initial_set_gives_its_bounding_box_and_centre() -> None:
    result, data = _import(
        "hamiltonian_system_1", "hamiltonian_system_1.xml", "hamiltonian_system_1.cfg"
    )
    spec = data["hamiltonian_system_1.yaml"]
    r = math.sqrt(1 / 24)
    x, y = spec["state"]["x"], spec["state"]["y"]
    assert x["initial"] == pytest.approx([-2 / 3 - r, -2 / 3 + r], abs=1e-15)
    assert y["initial"] == pytest.approx([-r, r], abs=1e-15)
    assert (x["nominal"], y["nominal"]) == (pytest.approx(-2 / 3, abs=1e-15), 0.0)
    assert spec["properties"] == {"forbidden": [{"when": "x > 0"}]}
    assert "not a box" in result.notes[0]
    assert "(2/3 + x)^2 + y^2 <= 1/24" in result.files["hamiltonian_system_1.yaml"]


def test_forbidden_sets_and_nonlinear_flows() -> None:
    _, lotka = _import(
        "lotka_volterra_fourth_quadrant",
        "lotka_volterra_fourth_quadrant.xml",
        "lotka_volterra_fourth_quadrant.cfg",
    )
    spec = lotka["lotka_volterra_fourth_quadrant.yaml"]
    assert spec["properties"] == {"forbidden": [{"when": "y < 0"}]}
    assert spec["locations"]["p"]["flow"] == {"x": "x * (1 - y)", "y": "-((1 - x) * y)"}
    _, vdp = _import(
        "van_der_pol_fourth_quadrant",
        "van_der_pol_fourth_quadrant.xml",
        "van_der_pol_fourth_quadrant.cfg",
    )
    assert vdp["van_der_pol_fourth_quadrant.yaml"]["properties"]["forbidden"] == [
        {"when": "x ** 2 + y ** 2 > 10"}
    ]


def test_bounded_uncontrolled_variables_become_inputs_with_ranges() -> None:
    result, data = _import("motor", "motor.xml", "motor.cfg")
    spec = data["core.yaml"]
    assert spec["inputs"] == {"u1": {"range": [0.16, 0.3]}, "u2": {"range": [0.2, 0.4]}}
    assert "invariant" not in spec["locations"]["Model"]  # it only bounded the inputs
    assert spec["state"]["t_"] == {"initial": 0.0}
    assert spec["state"]["x1"] == {"initial": [0.002, 0.0025]}
    assert any("'t' is renamed 't_'" in note for note in result.notes)
    _, nondet = _import(
        "bball_nondet_revised", "bball_nondet_revised.xml", "bball_nondet_revised.cfg"
    )
    ball = nondet["ball_template.yaml"]
    assert ball["inputs"] == {"w1": {"range": [-0.05, 0.05]}, "w2": {"range": [-0.1, 0.1]}}
    assert ball["locations"]["always"] == {
        "flow": {"x": "v", "v": "-g + w1"},
        "invariant": "x >= 0",
    }
    assert ball["edges"][0]["reset"] == {"v": "-c * v + w2"}


def test_a_clock_named_t_is_renamed_in_the_template_and_the_system() -> None:
    _, data = _import("bball_timed", "bball_timed.xml", "bball_timed.cfg")
    timer = data["timer_template.yaml"]
    assert timer["locations"]["running"]["flow"] == {"t_": "1"}
    comps = {c["as"]: c for c in data["system.yaml"]["components"]}
    assert "rename" not in comps["timer"]
    assert comps["timer"]["initial"]["state"] == {"t_": 0.0}


def test_the_system_can_be_chosen_and_defaults_to_the_cfg_then_the_last_component() -> None:
    xml = DATA / "filtered_oscillator" / "filtered_oscillator.xml"
    only = import_spaceex(xml, xml.with_name("filtered_oscillator.only_osc.cfg"))
    assert only.top == "oscillator.yaml"
    chosen = import_spaceex(xml, system="oscillator")
    assert chosen.top == "oscillator.yaml"
    assert "no .cfg" in chosen.notes[0]
    last = import_spaceex(xml)
    assert last.top == "osc_w_4th_order.yaml"


def test_the_command_writes_the_specs_and_prints_the_top_level_file(tmp_path: Path) -> None:
    xml = DATA / "bball" / "bball.xml"
    done = run_cli("import", "spaceex", xml, "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"{tmp_path / 'out' / 'system.yaml'}\n"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "ball_template.yaml",
        "system.yaml",
    ]
    assert "note: using the configuration" in done.stderr  # bball.cfg beside it


def test_an_edited_spec_is_not_replaced_without_force(tmp_path: Path) -> None:
    """Importing into the same folder again replaced a user's edits to the specs."""
    xml, out = DATA / "bball" / "bball.xml", tmp_path / "out"
    assert run_cli("import", "spaceex", xml, "--out", out).returncode == 0
    assert run_cli("import", "spaceex", xml, "--out", out).returncode == 0  # unchanged: fine
    edited = (out / "system.yaml").read_text() + "# tuned by hand\n"
    (out / "system.yaml").write_text(edited)
    before = {p.name: p.read_text() for p in out.iterdir()}
    done = run_cli("import", "spaceex", xml, "--out", out)
    assert done.returncode == 2 and done.stdout == ""
    assert "holds system.yaml, different from what this import writes" in done.stderr
    assert "--force to replace them (nothing was written)" in done.stderr
    assert {p.name: p.read_text() for p in out.iterdir()} == before
    forced = run_cli("import", "spaceex", xml, "--out", out, "--force")
    assert forced.returncode == 0 and "tuned by hand" not in (out / "system.yaml").read_text()


def test_the_command_refuses_with_the_place_and_exit_2(tmp_path: Path) -> None:
    xml = DATA / "filtered_oscillator" / "filtered_oscillator.xml"
    cfg = xml.with_name("filtered_oscillator.16th_order.cfg")
    done = run_cli("import", "spaceex", xml, "--cfg", cfg, "--out", tmp_path)
    assert done.returncode == 2
    assert done.stderr.startswith(f"{cfg}:1:11: the .cfg names the system 'osc_w_16th_order'")
    assert "Traceback" not in done.stderr
