"""A process that runs only compiled code does not load the scipy engine.

scipy's integrators and optimizers (with the reference engine that uses them) cost
0.45 to 0.65 s of CPU to import, a quarter of a warm compiled command: a compiled
``simulate``, ``simulate_many`` or sweep leaves them out, and a scipy run loads them.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from support import SPECS

pytest.importorskip("numba")

SCIPY_ENGINE = ("hybrid.simulation.reference", "hybrid.simulation.loop", "scipy.integrate",
                "scipy.optimize")  # fmt: skip


def _loaded_after(code: str) -> list[str]:
    """The modules of :data:`SCIPY_ENGINE` loaded by a fresh process that runs ``code``."""
    script = (
        "import json, sys, hybrid\n"
        f"model = hybrid.load({str(SPECS / 'thermostat.yaml')!r})\n"
        f"{code}\n"
        f"print(json.dumps(sorted(m for m in {SCIPY_ENGINE!r} if m in sys.modules)))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)  # fmt: skip
    loaded: list[str] = json.loads(done.stdout.strip().splitlines()[-1])
    return loaded


@pytest.mark.parametrize(
    "code",
    [
        "hybrid.simulate(model, 10.0, backend='compiled')",
        "hybrid.simulate_many(model, 10.0, parameters={'a': [0.1, 0.2]})",
        "hybrid.sweep(model, 10.0, grid={'a': [0.1, 0.2]}, workers=0, backend='compiled')",
    ],
)
def test_a_compiled_run_leaves_the_scipy_engine_out(code: str) -> None:
    assert _loaded_after(code) == []


REQUIREMENT = (
    "model = hybrid.load_text(open({path!r}).read()"
    " + '\\nrequirements: [{{name: r, always: \"{condition}\"}}]\\n')\n"
)


def test_a_compiled_runs_requirement_monitor_loads_only_scipys_optimizers() -> None:
    """Replayed over a compiled run, a requirement's margins are searched between samples
    (scipy.optimize, imported then), without the scipy engine or its integrators."""
    code = REQUIREMENT.format(path=str(SPECS / "thermostat.yaml"), condition="T <= 21.5")
    code += (
        "run = hybrid.simulate(model, 10.0, backend='compiled')\n"
        "assert not run.requirements['r'].holds\n"
    )
    assert _loaded_after(code) == ["scipy.optimize"]


def test_a_scipy_run_loads_it() -> None:
    """The check above can fail: a scipy run in the same kind of process loads all of it."""
    loaded = _loaded_after("hybrid.simulate(model, 10.0)")
    assert {"hybrid.simulation.reference", "scipy.integrate", "scipy.optimize"} <= set(loaded)


def test_the_choice_knows_whether_the_scipy_engine_is_loaded() -> None:
    """``auto`` credits a campaign with scipy's import only where it is still to come: not
    after a scipy run, and still after a compiled one (which loads ``simulate``'s module)."""
    script = (
        "import hybrid\n"
        "from hybrid.simulation.native.choice import _scipy_loaded\n"
        f"model = hybrid.load({str(SPECS / 'thermostat.yaml')!r})\n"
        "hybrid.simulate(model, 10.0, backend='compiled')\n"
        "after_compiled = _scipy_loaded()\n"
        "hybrid.simulate(model, 10.0)\n"
        "print(after_compiled, _scipy_loaded())\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)  # fmt: skip
    assert done.stdout.strip().splitlines()[-1] == "False True"
