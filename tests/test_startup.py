"""Start-up: ``import hybrid`` loads no heavy dependency; ``hybrid validate`` no numerics.

What is imported is checked, not how long it takes (speed is measured in
bench/import_time.py): each case runs in a fresh interpreter and lists which of
the heavy modules it loaded.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from support import REPO

HEAVY = ("pydantic", "yaml", "numpy", "scipy", "networkx", "matplotlib", "importlib.metadata")

CASES = [
    ("import hybrid", "import hybrid", set()),
    (
        "the model types",
        "import hybrid\nhybrid.Automaton, hybrid.System, hybrid.compose, hybrid.Range",
        set(),
    ),
    (
        "hybrid validate",
        "from hybrid.cli.main import main\nassert main(['validate', 'specs/bouncing_ball.yaml']) == 0",
        {"pydantic", "yaml", "importlib.metadata"},  # pydantic looks for its plugins
    ),
]


@pytest.mark.parametrize(("code", "loaded"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_only_what_is_needed_is_imported(code: str, loaded: set[str]) -> None:
    script = f"{code}\nimport sys\nprint(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=REPO, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert set(done.stdout.splitlines()[-1].split()) == loaded


def test_compose_is_the_function_after_its_module_is_imported() -> None:
    script = (
        "import hybrid, hybrid.compose\nprint(callable(hybrid.compose), hybrid.compose.__name__)"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=REPO, capture_output=True, text=True, timeout=120
    )
    assert done.stdout.split() == ["True", "compose"], done.stderr
