"""Phase B of the SpaceEx interchange: imported models load, check and simulate.

Every ``.xml`` + ``.cfg`` pair of tests/data/spaceex imports to specs that
validate and check (or is refused where phase A refuses it), and the importable
ones simulate; the bouncing balls bounce and end as the closed form says; the
circle switches every pi; export, import and simulate give the same jump times on
every spec of specs/ that exports, and on a model that uses every construct of
the second wave.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from support import REPO, SPECS, spaceex_pairs

import hybrid
from hybrid.compose import as_system
from hybrid.errors import SpecError
from hybrid.interchange import export_spaceex, import_spaceex, import_spaceex_text
from hybrid.simulation.result import CAUSES

DATA = REPO / "tests" / "data" / "spaceex"
WRONG_SYSTEM = {"1st_order", "8th_order", "16th_order", "32th_order"}
TIGHT = {"rtol": 1e-12, "atol": 1e-12}


PAIRS = spaceex_pairs(DATA)


def _refused(xml: Path, cfg: Path | None) -> bool:
    """Phase A's refusals (tests/interchange/test_interchange_import.py): kept."""
    flattened_input = "with offset" in xml.read_text(encoding="latin-1")
    wrong_system = cfg is not None and cfg.stem.split(".")[-1] in WRONG_SYSTEM
    return flattened_input or wrong_system


def _load(tmp_path: Path, xml: Path, cfg: Path | None) -> hybrid.Automaton | hybrid.System:
    result = import_spaceex(xml, cfg)
    for name, text in result.files.items():
        (tmp_path / name).write_text(text)
    return hybrid.load(tmp_path / result.top)


@pytest.mark.parametrize(
    ("xml", "cfg"), PAIRS, ids=[f"{x.name}+{c.name if c else '-'}" for x, c in PAIRS]
)
def test_every_pair_validates_checks_and_simulates(
    tmp_path: Path, xml: Path, cfg: Path | None
) -> None:
    if _refused(xml, cfg):
        with pytest.raises(SpecError) as info:
            import_spaceex(xml, cfg)
        assert info.value.line >= 1 and info.value.file.endswith((".xml", ".cfg"))
        return
    model = _load(tmp_path, xml, cfg)
    report = hybrid.check(model)
    assert all(f.rule != "invalid-spec" for f in report.findings)
    run = hybrid.simulate(model, t_end=2.0, handle_sigint=False)
    assert run.termination.cause in CAUSES and len(run) >= 1
    assert run.t[0] == 0.0
    # the run starts at a point of the initial set, in an initial location
    for name, r in as_system(model).initial_set().items():
        assert r.lo <= run[name][0] <= r.hi


def _ball_times(h: float, g: float, c: float, n: int) -> tuple[list[float], float]:
    """Bounce times and the Zeno time of a ball dropped from rest, falling h to the bounce.

    The fall takes t1 = sqrt(2 h / g) and ends at speed g t1; each bounce keeps c of
    the speed, and a flight at speed w lasts 2 w / g: t_k = t1 (1 + 2 c (1 - c^(k-1)) /
    (1 - c)), and the flights add up to t1 (1 + c) / (1 - c).
    """
    t1 = math.sqrt(2.0 * h / g)
    times = [t1 * (1.0 + 2.0 * c * (1.0 - c**k) / (1.0 - c)) for k in range(n)]
    return times, t1 * (1.0 + c) / (1.0 - c)


@pytest.mark.parametrize(
    ("folder", "xml", "drop"),
    [("bball", "bball.xml", 10.1), ("bball_timed", "bball_timed.xml", 10.1 - 0.1)],
)
def test_the_bouncing_balls_bounce_and_end_as_the_closed_form_says(
    tmp_path: Path, folder: str, xml: str, drop: float
) -> None:
    # x starts at the midpoint 10.1 of [10, 10.2], v = 0; g = 1, c = 0.75; the
    # timed ball bounces at x = eps = 0.1
    path = DATA / folder / xml
    model = _load(tmp_path, path, path.with_suffix(".cfg"))
    run = hybrid.simulate(model, t_end=40.0, max_jumps=1000, **TIGHT)
    bounces = [j.t for j in run.jumps if j.label == "hop"]
    expected, zeno = _ball_times(drop, 1.0, 0.75, len(bounces))
    assert len(bounces) > 20
    assert max(abs(a - b) for a, b in zip(bounces, expected, strict=True)) < 1e-7
    assert run.termination.cause == "zeno"
    assert run.termination.zeno_time == pytest.approx(zeno, abs=1e-7)


def test_the_flattened_ball_bounces_as_the_closed_form_says(tmp_path: Path) -> None:
    path = DATA / "bball" / "bball_flattened.xml"
    model = _load(tmp_path, path, path.with_suffix(".cfg"))
    run = hybrid.simulate(model, t_end=31.42, max_jumps=1000, **TIGHT)
    bounces = [j.t for j in run.jumps]
    expected, _ = _ball_times(10.1, 1.0, 0.75, len(bounces))
    assert len(bounces) >= 20
    assert max(abs(a - b) for a, b in zip(bounces, expected, strict=True)) < 1e-7


def test_the_flattened_ball_never_goes_below_the_floor(tmp_path: Path) -> None:
    path = DATA / "bball" / "bball_flattened.xml"
    model = _load(tmp_path, path, path.with_suffix(".cfg"))
    run = hybrid.simulate(model, t_end=40.0, max_jumps=1000, **TIGHT)
    assert run["x"].min() > -1e-9 and run.termination.cause == "zeno"


@pytest.mark.parametrize("xml", ["circle.xml", "circle_flattened.xml"])
def test_the_circle_switches_every_pi(tmp_path: Path, xml: str) -> None:
    # x' = -y, y' = x from (1, 0): y = sin t; p (y >= 0) and n (y <= 0) switch at
    # each zero of sin t after the start, where the flow leaves the starting level
    path = DATA / "circle" / xml
    model = _load(tmp_path, path, path.with_suffix(".cfg"))
    assert isinstance(model, hybrid.Automaton) and model.initial_locations == ("p", "n")
    run = hybrid.simulate(model, t_end=20.0, **TIGHT)
    assert [j.source for j in run.jumps] == ["p", "n"] * 3
    for k, jump in enumerate(run.jumps, start=1):
        assert jump.t == pytest.approx(k * math.pi, abs=1e-7)
    assert run.settings["start"]["notes"] == [
        "starts in 'p', the first of its initial locations p, n"
    ]


def _round_trip(
    model: hybrid.Automaton | hybrid.System, tmp_path: Path
) -> hybrid.Automaton | hybrid.System:
    out = export_spaceex(model)
    back = import_spaceex_text(out.xml, out.cfg)
    for name, text in back.files.items():
        (tmp_path / name).write_text(text)
    return hybrid.load(tmp_path / back.top)


@pytest.mark.parametrize("name", sorted(p.name for p in SPECS.glob("*.yaml")))
def test_every_spec_that_exports_simulates_the_same_after_a_round_trip(
    tmp_path: Path, name: str
) -> None:
    model = hybrid.load(SPECS / name)
    try:
        export_spaceex(model)
    except SpecError as exc:  # vector signals: SpaceEx cannot express them
        assert "vector signal" in exc.message and "no SpaceEx counterpart" in exc.message
        return
    again = _round_trip(model, tmp_path)
    first = hybrid.simulate(model, t_end=30.0, **TIGHT)
    second = hybrid.simulate(again, t_end=30.0, **TIGHT)
    assert len(first.jumps) == len(second.jumps) > 5
    for a, b in zip(first.jumps, second.jumps, strict=True):
        assert b.t == pytest.approx(a.t, abs=1e-9)
    assert second.termination.cause == first.termination.cause


EVERYTHING = """
automaton: shuttle
parameters: {k: 2.0}
state:
  x: {initial: [0, 1], bounds: [-1, 2.2]}
  n: {initial: 0}
inputs: {u: {range: [0.5, 1.5]}}
labels: [go]
locations:
  out: {flow: {x: u}}
  turn: {urgent: true}
  back: {flow: {x: -k}, invariant: x >= -1}
initial: {location: [out, back]}
edges:
  - {name: far, from: out, to: turn, guard: x >= 2, label: go}
  - {name: now, from: turn, to: back, reset: {n: n + 1}}
  - {name: home, from: back, to: out, guard: x <= 0}
properties:
  forbidden:
    - {location: back, when: "x < -1"}
    - {location: turn, when: "x > 2.5 or x < 1"}
"""


def test_every_construct_survives_a_round_trip(tmp_path: Path) -> None:
    model = hybrid.load_text(EVERYTHING)
    out = export_spaceex(model)
    assert "urgent_clock &lt;= 0" in out.xml and "0.5 &lt;= u &amp; u &lt;= 1.5" in out.xml
    assert not any("nominal" in note for note in out.notes)  # none is written
    initially = re.search(r'initially = "(.*)"', out.cfg)
    assert initially is not None and initially.group(1).count("|") == 1  # two locations
    again = _round_trip(model, tmp_path)
    assert as_system(again).initial_set()["x"].text() == "[0, 1]"
    assert as_system(again).input_ranges()["u"].text() == "[0.5, 1.5]"
    assert as_system(again).components[0].automaton.initial_locations == ("out", "back")
    assert len(as_system(again).properties.forbidden) == 2
    # x = 0.5 + t (u held at 1) reaches 2 at t = 1.5, turns at once, x = 2 - 2 (t - 1.5)
    # is 0 at t = 2.5, and so on: the same jumps at the same times, after the round trip
    first = hybrid.simulate(model, t_end=10.0, **TIGHT)
    second = hybrid.simulate(again, t_end=10.0, **TIGHT)
    assert [j.t for j in first.jumps][:3] == pytest.approx([1.5, 1.5, 2.5], abs=1e-12)
    assert len(first.jumps) == len(second.jumps) > 8
    for a, b in zip(first.jumps, second.jumps, strict=True):
        assert b.t == pytest.approx(a.t, abs=1e-9)
    # the forbidden states are proved unreachable before the round trip; after it the
    # analysis proves one of them, and neither it nor reach (whose may-semantics lets
    # `out` flow past the guard the simulator fires on at once) finds a run into the other
    before = hybrid.check(model)
    assert not before.by_rule("property-violated") and not before.by_rule("property-unproved")
    after = hybrid.check(again, reach_t_end=10.0)
    assert not after.by_rule("property-violated") and len(after.by_rule("property-unproved")) == 1


def test_a_union_over_locations_is_several_initial_locations() -> None:
    xml = (DATA / "circle" / "circle.xml").read_text()
    cfg = 'system = "circle"\ninitially = "loc(circle)==n & x==1 & y==0 | loc(circle)==p & x==1 & y==0"\n'
    result = import_spaceex_text(xml, cfg)
    assert (
        'location: ["n", p]' in result.files["circle.yaml"]
        or "location: [n, p]" in result.files["circle.yaml"]
    )
    mixed = 'system = "circle"\ninitially = "loc(circle)==n & x==1 & y==0 | loc(circle)==p & x==2 & y==0"\n'
    with pytest.raises(SpecError, match="these parts differ in their variables"):
        import_spaceex_text(xml, mixed)


def test_templates_and_shared_variables_survive_a_round_trip(tmp_path: Path) -> None:
    # the filtered oscillator: one filter template bound four times, each reading the
    # state variable of the one before (x, x1, x2, x3)
    folder = DATA / "filtered_oscillator"
    model = _load(
        tmp_path, folder / "filtered_oscillator.xml", folder / "filtered_oscillator.4th_order.cfg"
    )
    assert isinstance(model, hybrid.System)
    assert [c.automaton.inputs for c in model.components[1:]] == [("x",), ("x1",), ("x2",), ("x3",)]
    (tmp_path / "again").mkdir()
    again = _round_trip(model, tmp_path / "again")
    first = hybrid.simulate(model, t_end=10.0, **TIGHT)
    second = hybrid.simulate(again, t_end=10.0, **TIGHT)
    assert len(first.jumps) == len(second.jumps) > 8
    for a, b in zip(first.jumps, second.jumps, strict=True):
        assert b.t == pytest.approx(a.t, abs=1e-9)
    # the last filter follows the oscillator's x through three more filters: at t = 10
    # the state is the same, to the solver's accuracy
    assert second["z"][-1] == pytest.approx(first["z"][-1], abs=1e-9)
