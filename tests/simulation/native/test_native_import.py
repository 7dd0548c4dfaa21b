"""Importing a generated module does no work: it compiles nothing and starts no process.

The work is its ``build()``, which :func:`hybrid.simulation.native.cache.load_generated`
calls (and a compile worker, for its share of the kernel).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from support import REPO, import_source

import hybrid
from hybrid.compose import as_system
from hybrid.simulation.native.kernel_text import kernel_module
from hybrid.simulation.native.source import generate
from hybrid.simulation.native.structure import NativeModel

pytest.importorskip("numba")


def test_importing_the_generated_kernel_and_model_compiles_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_process(*args: object, **kwargs: object) -> None:
        raise AssertionError("a process was started at import")

    monkeypatch.setattr(subprocess, "Popen", no_process)
    model = hybrid.load(REPO / "specs" / "thermostat.yaml")
    generated = import_source(tmp_path / "hybrid_native_probe_model.py", generate(NativeModel(as_system(model))).source)
    kernel = import_source(tmp_path / "hybrid_native_probe_kernel.py", kernel_module().source)
    # still the plain Python functions: numba's dispatchers have py_func, a cfunc an address
    assert not hasattr(generated.model, "address") and not hasattr(generated.model, "py_func")
    assert callable(generated.build)
    assert not hasattr(kernel.run_one, "py_func") and callable(kernel.build)
    assert not list((tmp_path / "__pycache__").glob("*.nb*"))  # nothing compiled into a cache
