"""Importing a generated module does no work: it compiles nothing and starts no process.

The work is its ``build()``, which :func:`hybrid.simulation.native.cache.load_generated`
calls (and a compile worker, for its share of the kernel).
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest
from support import REPO

import hybrid
from hybrid.compose import as_system
from hybrid.simulation.native.kernel_text import kernel_module
from hybrid.simulation.native.source import generate
from hybrid.simulation.native.structure import NativeModel

pytest.importorskip("numba")


def _import_only(path: Path, text: str) -> object:
    path.write_text(text, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(path.stem, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module
    try:
        spec.loader.exec_module(module)
    finally:
        del sys.modules[path.stem]
    return module


def test_importing_the_generated_kernel_and_model_compiles_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_process(*args: object, **kwargs: object) -> None:
        raise AssertionError("a process was started at import")

    monkeypatch.setattr(subprocess, "Popen", no_process)
    model = hybrid.load(REPO / "specs" / "thermostat.yaml")
    generated = _import_only(tmp_path / "hybrid_native_probe_model.py", generate(NativeModel(as_system(model))).source)
    kernel = _import_only(tmp_path / "hybrid_native_probe_kernel.py", kernel_module().source)
    # still the plain Python functions: numba's dispatchers have py_func, a cfunc an address
    assert not hasattr(generated.model, "address") and not hasattr(generated.model, "py_func")
    assert callable(generated.build)
    assert not hasattr(kernel.run_one, "py_func") and callable(kernel.build)
    assert not list((tmp_path / "__pycache__").glob("*.nb*"))  # nothing compiled into a cache
