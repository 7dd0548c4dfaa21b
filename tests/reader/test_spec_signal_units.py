"""A signal can carry a unit: ``name: {expr: ..., unit: ...}``, shown where state units are.

The short form ``name: expression`` stays; the mapping form gives the same signal
(same values on the same run) plus a unit, which reaches ``run.units``, the
legend of the signals panel and a system's runs (renamed with the signal); its
mistakes are placed in the mapping.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hybrid

SPEC = """\
automaton: ball
parameters: {g: 9.81}
state:
  h: {initial: 10.0, unit: m}
  v: {initial: 0.0, unit: m/s}
signals:
  energy: ENERGY
  speed: abs(v)
locations:
  falling: {flow: {h: v, v: -g}}
"""


def _load(energy: str, tmp_path: Path) -> hybrid.Automaton:
    path = tmp_path / "ball.yaml"
    path.write_text(SPEC.replace("ENERGY", energy))
    model = hybrid.load(path)
    assert isinstance(model, hybrid.Automaton)
    return model


def test_the_mapping_form_is_the_same_signal_with_a_unit(tmp_path: Path) -> None:
    short = _load("0.5*v**2 + g*h", tmp_path)
    long = _load("{expr: 0.5*v**2 + g*h, unit: J/kg}", tmp_path)
    assert (short.signal_units, long.signal_units) == ({}, {"energy": "J/kg"})
    assert long.signal_names == ("energy", "speed")
    a, b = hybrid.simulate(short, t_end=1.0), hybrid.simulate(long, t_end=1.0)
    # Free fall from rest: the energy per kilogram stays g h0 = 98.1.
    assert np.allclose(b["energy"], 98.1) and np.array_equal(a["energy"], b["energy"])
    assert b.units == {"h": "m", "v": "m/s", "energy": "J/kg"}


def test_the_unit_is_in_the_signals_legend(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    run = hybrid.simulate(_load("{expr: 0.5*v**2 + g*h, unit: J/kg}", tmp_path), t_end=1.0)
    fig = run.plot()
    legend = fig.axes[-1].get_legend()
    assert [text.get_text() for text in legend.get_texts()] == ["energy [J/kg]", "speed"]


@pytest.mark.parametrize(
    ("energy", "where", "message"),
    [
        ("{expr: 0.5*v**2 + g*hh, unit: J}", "7:31", "unknown name 'hh'; did you mean 'h'?"),
        (
            "{expr: 0.5*v**2, unti: J}",
            "7:28",
            "unknown key 'unti' in signals.energy; did you mean 'unit'?",
        ),
        ("{unit: J}", "7:11", "missing key 'expr' in signals.energy"),
    ],
    ids=["expression", "key", "missing"],
)
def test_mistakes_in_the_mapping_are_placed(
    energy: str, where: str, message: str, tmp_path: Path
) -> None:
    with pytest.raises(hybrid.SpecError) as info:
        _load(energy, tmp_path)
    assert str(info.value) == f"{tmp_path / 'ball.yaml'}:{where}: {message}"


def test_a_renamed_signal_keeps_its_unit(tmp_path: Path) -> None:
    _load("{expr: 0.5*v**2 + g*h, unit: J/kg}", tmp_path)
    (tmp_path / "two.yaml").write_text(
        "system: two\n"
        "components:\n"
        "  - {spec: ball.yaml, as: a, rename: {h: h1, v: v1, energy: e1, speed: s1}}\n"
        "  - {spec: ball.yaml, as: b, rename: {h: h2, v: v2, energy: e2, speed: s2}}\n"
    )
    run = hybrid.simulate(hybrid.load(tmp_path / "two.yaml"), t_end=0.5)
    assert {k: run.units[k] for k in ("e1", "e2", "h1")} == {"e1": "J/kg", "e2": "J/kg", "h1": "m"}
