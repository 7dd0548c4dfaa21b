"""The constructs of the field's benchmark sets, each on a small model written here.

Each translation of ``hybrid import spaceex`` that the ARCH-COMP and HyST models
need is shown on a model of a few lines: what it imports to, the note it prints,
the run it gives (against a hand computation), and a round trip (import,
export, import, simulate: the same jumps at the same times).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from support import assert_no_traceback, run_cli

import hybrid
from hybrid.errors import SpecError
from hybrid.interchange import ImportResult, export_spaceex, import_spaceex_text

HEAD = '<?xml version="1.0"?>\n<sspaceex version="0.2" math="SpaceEx">\n'
TAIL = "</sspaceex>\n"


def real(name: str, extra: str = "") -> str:
    return f'<param name="{name}" type="real" local="false" d1="1" d2="1" dynamics="any" {extra}/>'


def load(result: ImportResult, where: Path) -> hybrid.Automaton | hybrid.System:
    where.mkdir(parents=True, exist_ok=True)
    for name, text in result.files.items():
        (where / name).write_text(text)
    return hybrid.load(where / result.top)


def _plain(location: str) -> str:
    """A location without its component (an export wraps an automaton in a network)."""
    return "|".join(part.rsplit(".", 1)[-1] for part in location.split("|"))


def round_trip(
    xml: str, cfg: str, tmp_path: Path, t_end: float
) -> tuple[ImportResult, hybrid.Run, hybrid.Run]:
    """Import, simulate; export, import, simulate: both runs, after checking they jump alike."""
    first = import_spaceex_text(xml, cfg)
    model = load(first, tmp_path / "first")
    run = hybrid.simulate(model, t_end=t_end, rtol=1e-10, atol=1e-12, handle_sigint=False)
    out = export_spaceex(model)
    second = import_spaceex_text(out.xml, out.cfg, xml_file="back.xml", cfg_file="back.cfg")
    again = hybrid.simulate(
        load(second, tmp_path / "second"), t_end=t_end, rtol=1e-10, atol=1e-12, handle_sigint=False
    )
    assert [_plain(j.target) for j in again.jumps] == [_plain(j.target) for j in run.jumps]
    np.testing.assert_allclose(again.jump_times, run.jump_times, rtol=0, atol=1e-9)
    assert again.termination.cause == run.termination.cause
    return first, run, again


# --- output variables: y == e in every invariant is the signal y --------------------------

TANK = (
    HEAD
    + f"""<component id="tank">{real("x")}{real("y")}
<location id="1" name="fill"><invariant>y == 2*x &amp; x &lt;= 3</invariant><flow>x' == 1</flow></location>
<location id="2" name="drain"><invariant>y == 2*x &amp; x &gt;= 1</invariant><flow>x' == -1</flow></location>
<transition source="1" target="2"><guard>y &gt;= 6</guard></transition>
<transition source="2" target="1"><guard>y &lt;= 2</guard></transition>
</component>"""
    + TAIL
)


def test_an_output_defined_in_every_invariant_is_a_signal(tmp_path: Path) -> None:
    result, run, _ = round_trip(
        TANK, 'system = tank\ninitially = "loc(tank)==fill & x==0"', tmp_path, 10.0
    )
    assert 'signals: {"y": "2 * x"}' in result.files["tank.yaml"]
    assert any("'y' is an output" in n and "signal y" in n for n in result.notes)
    # x rises from 0 at rate 1 to y = 2x = 6 (t = 3), falls to y = 2 (x = 1, t = 5), ...
    np.testing.assert_allclose(run.jump_times, [3.0, 5.0, 7.0, 9.0], atol=1e-9)
    np.testing.assert_allclose(run["y"], 2 * run["x"], atol=1e-12)


def test_a_variable_nothing_reads_is_dropped_with_a_note() -> None:
    xml = TANK.replace(real("y"), real("y") + real("unused"))
    result = import_spaceex_text(xml, 'system = tank\ninitially = "loc(tank)==fill & x==0"')
    assert "unused" not in result.files["tank.yaml"].split("SpaceEx semantics")[1]
    assert any("'unused' is declared but nothing reads it" in n for n in result.notes)


@pytest.mark.parametrize("where", ["fill", "drain"])
def test_an_output_some_location_leaves_free_stays_an_input(where: str) -> None:
    xml = TANK.replace(f'name="{where}"><invariant>y == 2*x &amp; ', f'name="{where}"><invariant>')
    result = import_spaceex_text(xml, 'system = tank\ninitially = "loc(tank)==fill & x==0"')
    assert "signals:" not in result.files["tank.yaml"]
    assert "inputs:" in result.files["tank.yaml"]


# --- true conjuncts, x = e in an assignment, rectangular flows (Fischer's idiom) -----------

TIMER = (
    HEAD
    + f"""<component id="timer">{real("x")}
<location id="1" name="wait"><invariant>true &amp;&amp; x &lt;= 3</invariant>
  <flow>true &amp;&amp; - x' &lt;= -1 &amp;&amp; x' &lt;= 3</flow></location>
<location id="2" name="go"><invariant>x &lt;= 3</invariant><flow>x' == 1</flow></location>
<transition source="1" target="2"><guard>true &amp;&amp; x &gt;= 3</guard><assignment>x = 0</assignment></transition>
<transition source="2" target="1"><guard>x &gt;= 1</guard><assignment>x = 00</assignment></transition>
</component>"""
    + TAIL
)
TIMER_CFG = 'system = timer\ninitially = "loc(timer)==wait & x==0 & true"'


def test_a_rectangular_flow_is_a_bounded_input_and_x_equals_e_a_reset(tmp_path: Path) -> None:
    result, run, _ = round_trip(TIMER, TIMER_CFG, tmp_path, 10.0)
    text = result.files["timer.yaml"]
    assert "x_rate: {range: [1.0, 3.0]}" in text
    assert "flow: {x: x_rate}" in text
    assert 'reset: {x: "0"}' in text
    spec = [line for line in text.splitlines() if not line.lstrip().startswith("#")]
    assert not any("true" in line for line in spec)  # the true conjuncts left no trace
    notes = " ".join(result.notes)
    assert "the flow x' in [1, 3] is nondeterministic: it is the input x_rate" in notes
    assert "is read as the reset x := e" in notes and "(and 1 more)" in notes
    # wait: x' held at the midpoint 2 from 0 to 3 (1.5 s); go: x' = 1 from 0 to 1 (1 s); ...
    np.testing.assert_allclose(run.jump_times, [1.5, 2.5, 4.0, 5.0, 6.5, 7.5, 9.0], atol=1e-9)


def test_a_bound_on_one_side_of_a_rate_is_refused_at_its_place() -> None:
    xml = TIMER.replace(" &amp;&amp; x' &lt;= 3</flow>", "</flow>")
    with pytest.raises(SpecError, match="bounded on one side only") as info:
        import_spaceex_text(xml, TIMER_CFG)
    assert (info.value.line, info.value.column) == (5, 25)  # the '- x'' conjunct


def test_x_equals_equals_e_in_an_assignment_is_still_refused() -> None:
    xml = TIMER.replace("<assignment>x = 0</assignment>", "<assignment>x == 0</assignment>")
    with pytest.raises(SpecError, match="a condition here belongs in the <guard>"):
        import_spaceex_text(xml, TIMER_CFG)


# --- flow false: urgent --------------------------------------------------------------------

PASS = (
    HEAD
    + f"""<component id="relay">{real("x")}
<location id="1" name="run"><invariant>x &lt;= 2</invariant><flow>x' == 1</flow></location>
<location id="2" name="pass"><flow>false</flow></location>
<transition source="1" target="2"><guard>x &gt;= 2</guard><assignment>x := 0</assignment></transition>
<transition source="2" target="1"></transition>
</component>"""
    + TAIL
)


def test_a_flow_false_is_an_urgent_location(tmp_path: Path) -> None:
    cfg = 'system = relay\ninitially = "loc(relay)==run & x==0"'
    result, run, _ = round_trip(PASS, cfg, tmp_path, 9.0)
    assert "pass: {urgent: true}" in result.files["relay.yaml"]
    assert any("'pass' has the flow false" in n and "urgent" in n for n in result.notes)
    # x reaches 2 every 2 s; the urgent location is left at the instant it is entered
    np.testing.assert_allclose(run.jump_times, [2, 2, 4, 4, 6, 6, 8, 8], atol=1e-9)
    assert [j.target for j in run.jumps[:2]] == ["pass", "run"]


# --- constants: in bounds by their values; given a range in the .cfg, a state ---------------

DRIFT = (
    HEAD
    + f"""<component id="clock">{real("x")}{real("w", 'controlled="false"')}
<param name="c" type="real" local="false" d1="1" d2="1" dynamics="const"/>
<location id="1" name="tick"><invariant>-c &lt;= w &lt;= c &amp; x &lt;= 2</invariant>
  <flow>x' == 1 + w</flow></location>
<transition source="1" target="1"><guard>x &gt;= 2</guard><assignment>x := 0</assignment></transition>
</component>
<component id="sys">{real("x")}{real("w")}
<bind component="clock" as="clk"><map key="x">x</map><map key="w">w</map><map key="c">0.5</map></bind>
</component>"""
    + TAIL
)


def test_bounds_written_with_constants_use_their_values(tmp_path: Path) -> None:
    cfg = 'system = sys\ninitially = "x == 0"'
    result, run, _ = round_trip(DRIFT, cfg, tmp_path, 9.0)
    assert "w: {range: [-0.5, 0.5]}" in result.files["clock.yaml"]
    assert any("written with the constants c" in n and "[-0.5, 0.5]" in n for n in result.notes)
    np.testing.assert_allclose(run.jump_times, [2, 4, 6, 8], atol=1e-9)  # w held at 0
    # c is read by nothing left once its bounds are the range: no parameter, so `hybrid
    # check` of the imported files does not warn about a declaration of the importer's
    assert "parameters" not in result.files["clock.yaml"]
    assert "parameters" not in result.files[result.top]
    assert any("constant 'c' is read by nothing kept here" in n for n in result.notes)
    report = hybrid.check(load(result, tmp_path / "checked"))
    assert [f.message for f in report.findings if f.rule == "unused-declaration"] == []


RAMP = (
    HEAD
    + f"""<component id="ramp">{real("x")}
<param name="u" type="real" local="false" d1="1" d2="1" dynamics="const"/>
<location id="1" name="up"><invariant>x &lt;= 4</invariant><flow>x' == u</flow></location>
<transition source="1" target="1"><guard>x &gt;= 4</guard><assignment>x := 0</assignment></transition>
</component>
<component id="sys">{real("x")}
<param name="u" type="real" local="false" d1="1" d2="1" dynamics="const"/>
<bind component="ramp" as="r"><map key="x">x</map><map key="u">u</map></bind>
</component>"""
    + TAIL
)


def test_a_constant_given_a_range_in_the_cfg_is_a_state_that_stays(tmp_path: Path) -> None:
    cfg = 'system = sys\ninitially = "x == 0 & u >= 1 & u <= 3"'
    result, run, _ = round_trip(RAMP, cfg, tmp_path, 9.0)
    assert "u: [1.0, 3.0]" in result.files["sys.yaml"]
    assert 'flow: {x: u, u: "0"}' in result.files["ramp.yaml"]
    assert any("constant 'u' is given a range in the .cfg" in n for n in result.notes)
    np.testing.assert_allclose(run.jump_times, [2, 4, 6, 8], atol=1e-9)  # u starts at 2
    assert set(run["u"]) == {2.0}


# --- the initial set within the initial location's invariant --------------------------------

HOLD = (
    HEAD
    + f"""<component id="hold">{real("x")}{real("u")}
<location id="1" name="on"><invariant>0.8 &lt;= u &amp; u &lt;= 1 &amp; x &lt;= 4</invariant>
  <flow>x' == u &amp; u' == 0</flow></location>
<transition source="1" target="1"><guard>x &gt;= 3.6</guard><assignment>x := 0</assignment></transition>
</component>"""
    + TAIL
)


def test_a_variable_the_cfg_leaves_free_starts_within_the_invariant(tmp_path: Path) -> None:
    result, run, _ = round_trip(HOLD, 'system = hold\ninitially = "x == 0"', tmp_path, 9.0)
    assert "u: {initial: [0.8, 1.0]}" in result.files["hold.yaml"]
    assert any("leaves it free for 'u'" in n and "[0.8, 1]" in n for n in result.notes)
    # u starts at the midpoint 0.9 and stays: x reaches 3.6 every 4 s
    np.testing.assert_allclose(run.jump_times, [4.0, 8.0], atol=1e-9)


def test_the_cfg_set_is_narrowed_by_the_invariant() -> None:
    result = import_spaceex_text(HOLD, 'system = hold\ninitially = "x == 0 & u >= 0.9 & u <= 2"')
    assert "u: {initial: [0.9, 1.0]}" in result.files["hold.yaml"]
    assert any("gives [0.9, 2] for 'u'" in n for n in result.notes)


# --- component ids that are not names -------------------------------------------------------


def test_component_ids_that_are_not_names_are_renamed(tmp_path: Path) -> None:
    xml = TANK.replace('id="tank"', 'id="1 tank>"') + ""
    result = import_spaceex_text(xml, 'system = "1 tank>"\ninitially = "x == 0 & loc() == fill"')
    assert result.top == "c_1_tank_.yaml"
    assert "automaton: c_1_tank_" in result.files[result.top]
    assert any("'1 tank>' is not one of our names: it is 'c_1_tank_'" in n for n in result.notes)
    network = DRIFT.replace('as="clk"', 'as="the clock"').replace('id="sys"', 'id="sys-1"')
    result = import_spaceex_text(network, 'system = "sys-1"\ninitially = "x == 0"')
    assert "as: the_clock" in result.files[result.top] and result.top == "sys_1.yaml"
    assert any("instance 'the clock' is 'the_clock'" in n for n in result.notes)
    load(result, tmp_path)


# --- an import that would not load is refused at the construct -------------------------------

TWO_OUTPUTS = (
    HEAD
    + f"""<component id="tank"><param name="x" type="real" local="true" d1="1" d2="1" dynamics="any"/>
{real("y")}
<location id="1" name="fill"><invariant>y == 2*x</invariant><flow>x' == 1</flow></location>
</component>
<component id="sys">{real("y")}
<bind component="tank" as="a"><map key="y">y</map></bind>
<bind component="tank" as="b"><map key="y">y</map></bind>
</component>"""
    + TAIL
)


def test_a_translation_that_does_not_load_is_refused_where_it_comes_from() -> None:
    """Two instances define the same output: no counterpart (a signal has one owner)."""
    with pytest.raises(SpecError, match="the translation of this construct does not load") as info:
        import_spaceex_text(TWO_OUTPUTS, 'system = sys\ninitially = "a.x == 0 & b.x == 1"')
    assert (info.value.file, info.value.line, info.value.column) == ("model.xml", 5, 41)  # y == 2*x
    assert "clashes with the signal of component 'a'" in info.value.message
    assert "hybrid-import-" not in info.value.message  # no temporary path shown


def test_the_command_refuses_it_with_exit_2_and_writes_nothing(tmp_path: Path) -> None:
    (tmp_path / "two.xml").write_text(TWO_OUTPUTS)
    (tmp_path / "two.cfg").write_text('system = sys\ninitially = "a.x == 0 & b.x == 1"\n')
    done = run_cli("import", "spaceex", tmp_path / "two.xml", "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    assert f"{tmp_path / 'two.xml'}:5:41: the translation of this construct" in done.stderr
    assert_no_traceback(done.stderr)
    assert not (tmp_path / "out").exists() and done.stdout == ""


def test_the_command_prints_the_notes_and_writes_what_loads(tmp_path: Path) -> None:
    (tmp_path / "timer.xml").write_text(TIMER)
    (tmp_path / "timer.cfg").write_text(TIMER_CFG + "\n")
    done = run_cli("import", "spaceex", tmp_path / "timer.xml", "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(tmp_path / "out" / "timer.yaml")
    assert (
        f"{tmp_path / 'timer.xml'}: note: component 'timer': the flow x' in [1, 3]" in done.stderr
    )
    assert "is read as the reset x := e" in done.stderr
    checked = run_cli("validate", tmp_path / "out" / "timer.yaml")
    assert checked.returncode == 0, checked.stderr


def test_x_prime_equals_a_bounded_uncontrolled_variable_is_a_bounded_input(tmp_path: Path) -> None:
    """``x' == w`` with ``lo <= w <= hi`` in every invariant: the input w with that range."""
    xml = DRIFT.replace("x' == 1 + w", "x' == w").replace(
        "-c &lt;= w &lt;= c", "0.5 &lt;= w &lt;= 1.5"
    )
    result, run, _ = round_trip(xml, 'system = sys\ninitially = "x == 0"', tmp_path, 9.0)
    assert "w: {range: [0.5, 1.5]}" in result.files["clock.yaml"]
    assert any("'w' is changed by nothing" in n and "range [0.5, 1.5]" in n for n in result.notes)
    np.testing.assert_allclose(run.jump_times, [2, 4, 6, 8], atol=1e-9)  # w held at 1


def test_a_renamed_component_round_trips(tmp_path: Path) -> None:
    xml = TANK.replace('id="tank"', 'id="a>b"')
    result, run, _ = round_trip(
        xml, 'system = "a>b"\ninitially = "x==0 & loc()==fill"', tmp_path, 10.0
    )
    assert result.top == "a_b.yaml"
    np.testing.assert_allclose(run.jump_times, [3.0, 5.0, 7.0, 9.0], atol=1e-9)


def test_a_long_sum_is_written_in_groups_that_load_and_keep_its_value(tmp_path: Path) -> None:
    """A flow of 200 terms (flat: 200 levels of nesting, over our 64) gives the same derivative."""
    terms = " + ".join(f"{k}*x" if k % 3 else f"-{k}*x" for k in range(1, 201)).replace("+ -", "- ")
    xml = TANK.replace(
        'x\' == 1</flow></location>\n<location id="2"',
        f'x\' == 1e-6*({terms}) + 1</flow></location>\n<location id="2"',
        1,
    )
    result = import_spaceex_text(xml, 'system = tank\ninitially = "loc(tank)==fill & x==2"')
    model = load(result, tmp_path)
    run = hybrid.simulate(model, t_end=0.5, rtol=1e-11, atol=1e-12, handle_sigint=False)
    a = 1e-6 * sum(k if k % 3 else -k for k in range(1, 201))  # x' = a x + 1, x(0) = 2
    assert math.isclose(run["x"][-1], (2 + 1 / a) * math.exp(a / 2) - 1 / a, rel_tol=1e-9)
    assert re.search(r"\* x [+-] \(\d+ \* x", result.files["tank.yaml"])  # a group starts
