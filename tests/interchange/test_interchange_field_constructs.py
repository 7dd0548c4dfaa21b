"""The constructs of the field's benchmark sets, each on a small model written here.

Each translation of ``hybrid import spaceex`` that the ARCH-COMP and HyST models
need is shown on a model of a few lines: what it imports to, the note it prints,
the run it gives (against a hand computation), and a round trip (import,
export, import, simulate: the same jumps at the same times).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hybrid
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
