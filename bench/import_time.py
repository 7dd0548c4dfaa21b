"""Start-up: ``import hybrid`` and ``hybrid validate`` in a fresh process, against bare Python.

Each contender is a new interpreter (``python -c ...``), timed from outside, against
``python -c pass`` (the floor every command pays) and ``python -c "import scipy"``
(what a scientific Python tool usually costs). ``python -X importtime`` gives the
cumulative import time of the ``hybrid`` package itself, the part the package
controls. ``python -m bench.import_time`` prints them alone.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bench.harness import Comparison, compare

__all__ = ["hybrid_import_us", "run"]

ROOT = Path(__file__).resolve().parent.parent


def _process(*args: str) -> Callable[[], Any]:
    def go() -> None:
        subprocess.run(
            [sys.executable, *args], cwd=ROOT, check=True, capture_output=True, timeout=120
        )

    return go


def hybrid_import_us(repeats: int = 9) -> float:
    """Median over ``repeats`` processes of ``import hybrid``'s cumulative import time, in us."""
    found = []
    for _ in range(repeats):
        done = subprocess.run(
            [sys.executable, "-X", "importtime", "-c", "import hybrid"],
            cwd=ROOT,
            check=True,
            capture_output=True,
            text=True,
            timeout=120,
        )
        rows = [line.split("|") for line in done.stderr.splitlines() if line.endswith("| hybrid")]
        found.append(float(rows[-1][1]))
    return statistics.median(found)


def run(repeats: int = 9) -> list[Comparison]:
    bare = ("python -c pass", _process("-c", "pass"))
    results = [
        compare(
            "start-up: import hybrid",
            ("import hybrid", _process("-c", "import hybrid")),
            bare,
            repeats=repeats,
        ),
        compare(
            "start-up: import hybrid against import scipy",
            ("import hybrid", _process("-c", "import hybrid")),
            ("import scipy", _process("-c", "import scipy")),
            repeats=repeats,
        ),
        compare(
            "start-up: hybrid validate (one spec)",
            ("validate", _process("-m", "hybrid", "validate", "specs/bouncing_ball.yaml")),
            bare,
            repeats=repeats,
        ),
    ]
    first = results[0]
    first.extra = {
        "above_bare_s": first.contender_median_s - first.baseline_median_s,
        "importtime_hybrid_ms": hybrid_import_us(repeats) / 1e3,
    }
    last = results[-1]
    last.extra = {"above_bare_s": last.contender_median_s - last.baseline_median_s}
    return results


if __name__ == "__main__":
    for result in run():
        print(result.line(), result.extra)
