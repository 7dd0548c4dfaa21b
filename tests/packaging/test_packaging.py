"""The install works as written: the wheel and the sdist, each in a clean environment.

The sdist is built from a copy of the source tree and the wheel from the unpacked
sdist (what ``python -m build`` does), with setuptools' own build backend in a
virtual environment of their own. The wheel is then installed with no extras into
a fresh virtual environment (no site packages but its own), where the ``hybrid``
command must answer ``--help``, ``validate`` and ``simulate`` a spec (the tank of
getting-started, whose jump times are known in closed form), and the UVMS case
study must be absent: neither importable nor registered as a function library.
The wheel is then uninstalled and the sdist installed in its place, and the same
must hold. The sdist finds its runtime dependencies there; that it asks for the
same ones as the wheel is checked, so a second fresh environment (half a minute of
installing numpy and scipy again) would show nothing more. Installing needs a
package index; where pip cannot reach one, the tests are skipped and say so.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tarfile
import zipfile
from collections.abc import Sequence
from pathlib import Path

import pytest
from support import REPO

# What pip prints when it cannot reach an index (as opposed to a failure of ours).
_OFFLINE = (
    "Failed to establish a new connection",
    "Temporary failure in name resolution",
    "Name or service not known",
    "Network is unreachable",
    "Connection refused",
    "ConnectTimeoutError",
    "Read timed out",
    "No matching distribution found",
)

# Left out of the copy the sdist is built from: what a checkout's work leaves behind.
_NOT_SOURCE = {
    ".git",
    ".venv",
    "__pycache__",
    ".mypy_cache",
    ".ruff_cache",
    ".pytest_cache",
    "build",
    "dist",
    "out",
    "_build",
}


def _clean_env(bytecode: bool) -> dict[str, str]:
    drop = {"PYTHONPATH", "VIRTUAL_ENV", "PYTHONDONTWRITEBYTECODE"}
    env = {k: v for k, v in os.environ.items() if k not in drop}
    if not bytecode:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def _run(
    args: Sequence[str | Path], cwd: Path, timeout: float = 600.0, bytecode: bool = False
) -> subprocess.CompletedProcess[str]:
    """``args`` in ``cwd``; ``bytecode``: Python may write ``.pyc`` files (in a test's venv)."""
    return subprocess.run(
        [str(a) for a in args],
        cwd=cwd,
        env=_clean_env(bytecode),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


def _venv(where: Path) -> Path:
    """A fresh virtual environment; its Python."""
    made = _run([sys.executable, "-m", "venv", where], cwd=where.parent)
    assert made.returncode == 0, made.stderr
    return where / "bin" / "python"


def _pip_install(python: Path, *what: str | Path, compile_all: bool = True) -> None:
    """``pip install WHAT``; skips the test when pip cannot reach an index.

    ``compile_all=False``: pip writes no bytecode for what it installs (half the
    time of installing numpy and scipy); the commands run then compile what they import.
    """
    flags = [] if compile_all else ["--no-compile"]
    done = _run([python, "-m", "pip", "install", "--quiet", *flags, *what], cwd=python.parent)
    if done.returncode != 0:
        said = done.stdout + done.stderr
        if any(mark in said for mark in _OFFLINE):
            last = said.strip().splitlines()[-1]
            pytest.skip(f"pip cannot reach a package index to install {what}: {last}")
        raise AssertionError(f"pip install {what} failed:\n{said}")


def _ignore(folder: str, names: list[str]) -> set[str]:
    return {n for n in names if n in _NOT_SOURCE or n.endswith(".egg-info")}


@pytest.fixture(scope="module")
def artifacts(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The sdist (built from a copy of the tree) and the wheel (built from the sdist)."""
    root = tmp_path_factory.mktemp("build")
    python = _venv(root / "venv")
    _pip_install(python, "setuptools>=77")
    source = root / "source"
    shutil.copytree(REPO, source, ignore=_ignore)
    dist = root / "dist"
    dist.mkdir()
    backend = "from setuptools import build_meta as b; import sys; print(b.build_{}(sys.argv[1]))"
    made = _run([python, "-c", backend.format("sdist"), dist], cwd=source)
    assert made.returncode == 0, made.stderr
    sdist = dist / made.stdout.strip().splitlines()[-1]
    unpacked = root / "unpacked"
    with tarfile.open(sdist) as archive:
        archive.extractall(unpacked, filter="data")
    (tree,) = unpacked.iterdir()
    made = _run([python, "-c", backend.format("wheel"), dist], cwd=tree)
    assert made.returncode == 0, made.stderr
    wheel = dist / made.stdout.strip().splitlines()[-1]
    return {"sdist": sdist, "wheel": wheel}


def test_both_artifacts_carry_the_license(artifacts: dict[str, Path]) -> None:
    with tarfile.open(artifacts["sdist"]) as archive:
        sdist = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    with zipfile.ZipFile(artifacts["wheel"]) as archive:
        wheel = set(archive.namelist())
    assert "LICENSE" in sdist
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in wheel), sorted(wheel)
    license_text = (REPO / "LICENSE").read_text()
    assert license_text.startswith("MIT License")
    with zipfile.ZipFile(artifacts["wheel"]) as archive:
        metadata = archive.read(next(n for n in wheel if n.endswith(".dist-info/METADATA")))
    assert b"License-Expression: MIT" in metadata


def test_the_sdist_carries_what_its_tests_and_docs_need(artifacts: dict[str, Path]) -> None:
    with tarfile.open(artifacts["sdist"]) as archive:
        names = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    needed = {
        "conftest.py",
        "Makefile",
        "tests/support.py",
        "tests/packaging/test_packaging.py",
        "specs/bouncing_ball.yaml",
        "specs/uvms_mission_1.yaml",
        "docs/conf.py",
        "docs/index.md",
        "docs/examples/tank.yaml",
        "uvms_model/pyproject.toml",
        "uvms_model/functions.py",
    }
    assert needed <= names, sorted(needed - names)
    assert not any("__pycache__" in n or n.endswith(".pyc") for n in names)


def test_the_wheel_holds_hybrid_only(artifacts: dict[str, Path]) -> None:
    with zipfile.ZipFile(artifacts["wheel"]) as archive:
        names = archive.namelist()
        entry_points = archive.read(
            next(n for n in names if n.endswith(".dist-info/entry_points.txt"))
        ).decode()
    tops = {n.split("/", 1)[0] for n in names if not n.split("/", 1)[0].endswith(".dist-info")}
    assert tops == {"hybrid"}
    assert "hybrid.functions" not in entry_points
    assert "hybrid = hybrid.__main__:entry" in entry_points


_REQUIRES = (
    "from importlib.metadata import distribution;"
    "d = distribution('hybrid-automata');"
    "print(d.version); print(*sorted(d.requires or []), sep='\\n')"
)


def test_a_clean_install_works_as_written(artifacts: dict[str, Path], tmp_path: Path) -> None:
    python = _venv(tmp_path / "venv")
    _pip_install(python, artifacts["wheel"], compile_all=False)
    work = tmp_path / "work"
    work.mkdir()
    shutil.copy(REPO / "docs" / "examples" / "tank.yaml", work / "tank.yaml")
    shutil.copy(REPO / "specs" / "uvms_singularity.yaml", work / "uvms_singularity.yaml")
    _works_as_written(python, work, "wheel")
    from_wheel = _run([python, "-c", _REQUIRES], cwd=work)
    assert from_wheel.returncode == 0, from_wheel.stderr

    removed = _run([python, "-m", "pip", "uninstall", "--yes", "hybrid-automata"], cwd=work)
    assert removed.returncode == 0, removed.stderr
    assert not (python.parent / "hybrid").exists()
    _pip_install(python, "--no-deps", artifacts["sdist"], compile_all=False)
    from_sdist = _run([python, "-c", _REQUIRES], cwd=work)
    assert from_sdist.returncode == 0, from_sdist.stderr
    # the same version and runtime requirements (one line each), so the same environment
    assert from_sdist.stdout == from_wheel.stdout
    assert "numpy" in from_sdist.stdout and "scipy" in from_sdist.stdout
    for output in work.glob("tank.*"):
        if output.suffix != ".yaml":
            output.unlink()
    _works_as_written(python, work, "sdist")


def _works_as_written(python: Path, work: Path, kind: str) -> None:
    """The README's first steps in ``work``, with the ``hybrid`` installed beside ``python``."""
    hybrid = python.parent / "hybrid"
    shown = _run([hybrid, "--help"], cwd=work, bytecode=True)
    assert shown.returncode == 0, (kind, shown.stderr)
    assert "validate" in shown.stdout and "simulate" in shown.stdout, kind

    valid = _run([hybrid, "validate", "tank.yaml"], cwd=work, bytecode=True)
    assert (valid.returncode, valid.stdout.strip()) == (0, "tank.yaml: ok"), (kind, valid.stderr)

    ran = _run(
        [hybrid, "simulate", "tank.yaml", "--t-end", "12", "--out", "tank.csv",
         "--events", "tank.json", "--rtol", "1e-9", "--atol", "1e-12"],
        cwd=work,
        bytecode=True,
    )  # fmt: skip
    assert ran.returncode == 0, (kind, ran.stderr)
    events = json.loads((work / "tank.json").read_text())
    assert events["termination"]["cause"] == "t_end", kind
    # 1.5 -> 2 at 0.3 m/s, 2 -> 1 at 0.2 m/s, 1 -> 2 at 0.3 m/s: 5/3, 5/3 + 5, 5/3 + 5 + 10/3
    times = [jump["t"] for jump in events["jumps"]]
    assert times == pytest.approx([5 / 3, 20 / 3, 10.0], abs=1e-7), kind
    assert (work / "tank.csv").read_text().startswith("t,j,location,h,volume"), kind

    # The case study is not installed, nor its function library registered.
    absent = _run([python, "-c", "import uvms_model"], cwd=work, bytecode=True)
    assert absent.returncode == 1 and "ModuleNotFoundError" in absent.stderr, kind
    libraries = _run(
        [python, "-c",
         "from importlib.metadata import entry_points;"
         "print(sorted(e.name for e in entry_points(group='hybrid.functions')))"],
        cwd=work,
        bytecode=True,
    )  # fmt: skip
    assert libraries.stdout.strip() == "[]", (kind, libraries.stderr)
    refused = _run([hybrid, "validate", "uvms_singularity.yaml"], cwd=work, bytecode=True)
    assert refused.returncode == 2, kind
    assert "Traceback" not in refused.stderr, kind
    assert refused.stderr.startswith("uvms_singularity.yaml:"), kind
    assert "function library 'uvms_model'" in refused.stderr, kind
    assert "pip install ./uvms_model" in refused.stderr, kind  # what to do, in one line
    assert len(refused.stderr.strip().splitlines()) == 1, (kind, refused.stderr)
