"""(6) Peers: another hybrid simulator on the bouncing ball, where one installs here.

Candidates from PyPI: assimulo and PyDSTool. On this machine (Python 3.11,
NumPy 2) neither runs, for the reasons below, checked when this file was
written and re-checked at each run by trying to import them. Where one
imports, extend :func:`run` with its bouncing-ball model.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["REASONS", "run"]

REASONS = {
    "assimulo": "PyPI has only the 3.0 source release; its build script imports numpy "
    "before declaring it and it needs the SUNDIALS C library, so `pip install assimulo` "
    "fails at 'getting requirements to build wheel'.",
    "PyDSTool": "0.91.0 (the newest) installs but cannot be imported on Python 3.11: it "
    "imports `numpy.Inf`/`numpy.int` (removed in NumPy 2 and 1.24) and the standard "
    "module `parser` (removed in Python 3.10).",
}


def run() -> dict[str, Any]:
    found: dict[str, Any] = {}
    for name, reason in REASONS.items():
        try:
            importlib.import_module(name)
        except Exception as exc:  # any import failure means: not usable here
            found[name] = {"available": False, "reason": reason, "import_error": repr(exc)[:200]}
        else:
            found[name] = {"available": True, "reason": "imports; benchmark not written yet"}
    return found


if __name__ == "__main__":
    print(run())
