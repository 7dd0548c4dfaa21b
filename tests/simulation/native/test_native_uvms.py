"""The UVMS missions run compiled (uvms_model's compiled forms) and agree with scipy.

The missions compose ``specs/uvms_singularity.yaml`` (every function of the
``uvms_model`` library) with ``specs/polarization.yaml``; both missions have one
structure, so they share one compiled module. Their ``requirements:`` are
monitored by the scipy backend only, so both backends run them without.
The compiled forms themselves are compared with the Python forms, value for value.
"""

from __future__ import annotations

import math
import random
from dataclasses import replace

import numpy as np
import pytest
from support import SPECS

import hybrid
from hybrid.compose import System

pytest.importorskip("numba")

TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}


def without_requirements(name: str) -> System:
    mission = hybrid.load(SPECS / f"{name}.yaml")
    assert isinstance(mission, System)
    parts = tuple(replace(c, automaton=replace(c.automaton, requirements=())) for c in mission.components)
    return replace(mission, requirements=(), components=parts)


@pytest.mark.parametrize(("name", "t_end", "jumps"), [("uvms_mission_1", 40.0, 4), ("uvms_mission_2", 59.0, 10)])
def test_mission_agrees_with_scipy(name: str, t_end: float, jumps: int) -> None:
    mission = without_requirements(name)
    compiled = hybrid.simulate(mission, t_end=t_end, backend="compiled", **TOL)  # type: ignore[arg-type]
    reference = hybrid.simulate(mission, t_end=t_end, **TOL)  # type: ignore[arg-type]
    assert len(reference.jumps) == jumps  # mission 2 crosses the singular vicinity: epsilon, then beta
    assert [(j.edge, j.source, j.target) for j in compiled.jumps] == [
        (j.edge, j.source, j.target) for j in reference.jumps
    ]
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    assert compiled.termination.cause == reference.termination.cause == "t_end"
    assert list(compiled.location) == list(reference.location)
    # the stored states agree to the tolerances (ill-conditioned near the singular vicinity)
    np.testing.assert_allclose(compiled["gamma"], reference["gamma"], rtol=1e-5, atol=1e-9)


def test_mission_requirements_agree_with_scipy() -> None:
    # the compiled run's steps shown to the same monitor: mission 2's dexterity
    # (always gamma >= 0.5) has the same robustness, the smallest |gamma| less 0.5
    mission = hybrid.load(SPECS / "uvms_mission_2.yaml")
    kwargs = {"t_end": 59.0, "rtol": 1e-8, "atol": 1e-10, "handle_sigint": False}
    compiled = hybrid.simulate(mission, backend="compiled", **kwargs)  # type: ignore[arg-type]
    reference = hybrid.simulate(mission, **kwargs)  # type: ignore[arg-type]
    mine, theirs = compiled.requirements["dexterity"], reference.requirements["dexterity"]
    assert mine.holds and theirs.holds
    assert mine.robustness == pytest.approx(theirs.robustness, abs=1e-6)
    assert 0.0 < mine.robustness < 0.2  # the dip after epsilon: min |gamma| between 0.5 and 0.7
    assert compiled.segments == [] and compiled.settings["dense"] is False


def test_compiled_forms_compute_the_python_forms() -> None:
    from uvms_model import compiled
    from uvms_model.functions import registry

    library = registry()
    rng = random.Random(14)
    for name in compiled.__all__:
        python = library[name]
        assert python.hybrid_compiled == f"uvms_model.compiled:{name}"
        for _ in range(3):
            args = [rng.uniform(0.3, 1.4) for _ in range(python.hybrid_arity[1])]
            if name == "uvms_path":  # a valid geometry: whole half laps, |epsilon| < 1
                args[1], args[7] = 1.5, 0.1
            expected = python(*args)
            got = getattr(compiled, name)(*args)
            # the same arithmetic; LLVM's sin, cos and pow may differ from libm's in the last bits
            assert np.asarray(got, dtype=float) == pytest.approx(np.asarray(expected, dtype=float), rel=1e-12, abs=1e-13), name
    # the error paths: NaN where the Python forms raise
    with pytest.raises(ValueError, match="kinematic singularity"):
        library["uvms_q0"](*([0.0] * 12 + [1.0, 1.0, 0.25, 0.5, 0.0]))
    assert all(math.isnan(v) for v in compiled.uvms_q0(*([0.0] * 12 + [1.0, 1.0, 0.25, 0.5, 0.0])))
    with pytest.raises(ValueError, match="tf > t0"):
        library["quintic"](0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
    assert all(math.isnan(v) for v in compiled.quintic(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0))


def test_importing_the_library_does_not_import_numba() -> None:
    import subprocess
    import sys

    code = "import sys, hybrid, uvms_model, uvms_model.functions; print('numba' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"
