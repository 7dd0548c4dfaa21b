"""The field's benchmark sets, imported as a user would: ARCH-COMP, HyST, SpaceExParser.jl.

Every ``.xml``/``.cfg`` pair of ``../shared/external-models/{arch,hyst,spaceex}``
(models nobody here wrote) imports, loads (``hybrid validate``), checks with no
invalid-spec finding, and simulates on both backends with the same jumps
(:func:`support.assert_backends_agree`), or is one of the refusals listed in
docs/interchange.md with its reason. A fast subset runs in ``make test``; the
whole set (the 270-state ISS model and the 16th/32nd-order oscillators with it)
under ``make fuzz`` (``HYBRID_FUZZ=1``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from support import REPO, assert_backends_agree

import hybrid
from hybrid.errors import SpecError
from hybrid.interchange import import_spaceex

FIELD = REPO.parent / "shared" / "external-models"
FULL = os.environ.get("HYBRID_FUZZ", "0") not in ("", "0")
REFUSED = {
    # .cfg files naming a system filtered_oscillator.xml does not define (the 16th and
    # 32nd order systems are in filtered_oscillator_16.xml and _32.xml)
    "filtered_oscillator.1st_order.cfg": "not a component",
    "filtered_oscillator.8th_order.cfg": "not a component",
    "filtered_oscillator.16th_order.cfg": "not a component",
    "filtered_oscillator.32th_order.cfg": "not a component",
    # SpaceEx's flattened form of a nondeterministic input
    "bball_nondet_flattened.xml": "with offset",
    "bball_nondet_revised_flattened_problem.xml": "with offset",
    # the converter's target invariants read mode_out, which the controller's transition on
    # the same label assigns: SpaceEx checks them after that assignment (imported before,
    # every run blocked at the first switch)
    "buck_dcm_vs1.cfg": "SpaceEx checks the invariant after both assignments",
}
SLOW_TO_COMPILE = {
    # five components synchronised on 20 labels: 752 product modes, 56,000 generated lines,
    # whose numba compile took 639 s on the shared 2-core machine (one structure: the two
    # .cfg files share it). Both backends under make fuzz; scipy alone in make test.
    "FISCS04-UBD04.cfg",
    "FISCU04-UBD04.cfg",
}
FAST = {  # DISC02-UBS02 (74 s in a make test on an empty compiled cache) is in the whole set
    "BLDF01-BDS01.cfg",
    "PLAD01-BND42-spec.cfg",
    "heaterLygeros.cfg",
    "toy_unsafe.cfg",
}


def _pairs() -> list[tuple[Path, Path | None]]:
    """Each ``.cfg`` with the model whose name is the longest start of its own; models without one."""
    found: list[tuple[Path, Path | None]] = []
    for folder in ("arch", "hyst", "spaceex"):
        for directory in sorted(p for p in (FIELD / folder).glob("*") if p.is_dir()):
            xmls = sorted(directory.glob("*.xml"))
            used: set[Path] = set()
            for cfg in sorted(directory.glob("*.cfg")):
                stem = cfg.name[: -len(".cfg")]
                matches = [x for x in xmls if stem.startswith(x.stem)]
                xml = max(matches, key=lambda x: len(x.stem))
                used.add(xml)
                found.append((xml, cfg))
            found.extend((x, None) for x in xmls if x not in used)
    return found


PAIRS = _pairs() if FIELD.is_dir() else []


def _name(xml: Path, cfg: Path | None) -> str:
    return cfg.name if cfg is not None else xml.name


def _param(xml: Path, cfg: Path | None) -> object:
    name = _name(xml, cfg)
    marks = [pytest.mark.fuzz]
    if name not in FAST and name not in REFUSED:
        marks.append(pytest.mark.skipif(not FULL, reason="the whole set runs under make fuzz"))
    return pytest.param(xml, cfg, marks=marks, id=f"{xml.parent.parent.name}/{name}")


def _horizon(cfg: Path | None) -> float:
    """The ``.cfg``'s time horizon, at most 10 (10 without one)."""
    if cfg is None:
        return 10.0
    for line in cfg.read_text(encoding="latin-1").splitlines():
        key, _, value = line.partition("=")
        if key.strip() == "time-horizon":
            try:
                t = float(value.split("#")[0].strip().strip('"'))
            except ValueError:
                return 10.0
            return min(t, 10.0) if t > 0 else 10.0
    return 10.0


@pytest.mark.parametrize(("xml", "cfg"), [_param(x, c) for x, c in PAIRS])
def test_every_field_pair_imports_checks_and_runs_alike_on_both_backends(
    tmp_path: Path, xml: Path, cfg: Path | None
) -> None:
    name = _name(xml, cfg)
    if name in REFUSED:
        with pytest.raises(SpecError, match=REFUSED[name]) as info:
            import_spaceex(xml, cfg)
        assert info.value.line >= 1
        return
    result = import_spaceex(xml, cfg)
    for file, text in result.files.items():
        (tmp_path / file).write_text(text)
    model = hybrid.load(tmp_path / result.top)
    report = hybrid.check(model)
    assert all(f.rule != "invalid-spec" for f in report.findings)
    if name in SLOW_TO_COMPILE and not FULL:
        run = hybrid.simulate(model, t_end=_horizon(cfg), max_jumps=200, handle_sigint=False)
        assert run.termination.cause in ("t_end", "max_jumps", "blocked", "zeno")
    else:
        run, _ = assert_backends_agree(model, t_end=_horizon(cfg), max_jumps=200)
    assert run.t[0] == 0.0


def test_the_set_is_there_and_whole() -> None:
    """The folders hold the 24 models the issue names (with their .cfg variants)."""
    if not FIELD.is_dir():
        pytest.skip("../shared/external-models is not beside the repository")
    names = {_name(x, c) for x, c in PAIRS}
    assert {"BLDF01-BDS01.cfg", "BLDF01-BDU01.cfg", "BLDF01-BDU02.cfg"} <= names
    assert {"FISCS04-UBD04.cfg", "FISCU04-UBD04.cfg", "DISC02-UBS02.cfg"} <= names
    assert {"PLAD01-BND42.cfg", "PLAD01-BND42-spec.cfg", "iss_full_model.cfg"} <= names
    assert len(PAIRS) == 45
