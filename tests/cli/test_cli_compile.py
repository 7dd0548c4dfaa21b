"""``hybrid compile FILE...``: the compiled backend's cache filled ahead of the runs."""

from __future__ import annotations

from pathlib import Path

import pytest
from support import SPECS, assert_no_traceback, run_cli

import hybrid

pytest.importorskip("numba")


def test_compile_leaves_the_model_and_the_kernels_in_the_cache() -> None:
    from hybrid.simulation.native.choice import cached

    files = [SPECS / "thermostat.yaml", SPECS / "bouncing_ball.yaml"]
    done = run_cli("compile", *files, timeout=900)  # a cold cache compiles the kernel
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 2
    for line, path in zip(lines, files, strict=True):
        assert line.startswith(f"{path}: ") and (" compiled" in line or "found in the cache" in line)
    for path in files:  # sealed on disk (or loaded already by this test session)
        assert set(cached(hybrid.load(path))[:2]) <= {"cached", "loaded"}
    again = run_cli("compile", files[0])
    assert again.returncode == 0 and "found in the cache" in again.stderr


def test_compile_refuses_an_invalid_file_with_its_position(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("automaton: a\nstate: {x: {}}\nlocations: {l: {flow: {x: y +}}}\n")
    done = run_cli("compile", bad)
    assert done.returncode == 2
    assert_no_traceback(done.stderr)
    assert done.stderr.startswith(f"{bad}:3:")


def test_the_compile_notice_names_what_a_first_run_compiles(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from hybrid.compose import as_system
    from hybrid.simulation.native import cache
    from hybrid.simulation.native.choice import KERNEL_COMPILE_S, compile_notice
    from hybrid.simulation.native.kernel_text import Generated, kernel_module
    from hybrid.simulation.native.source import generate
    from hybrid.simulation.native.structure import NativeModel

    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path))  # an empty cache
    monkeypatch.setattr(cache, "_LOADED", {})  # and nothing loaded in this process
    model = hybrid.load(SPECS / "thermostat.yaml")
    notice = compile_notice(model)
    assert notice is not None
    assert f"the compiled loop (once per machine, about {KERNEL_COMPILE_S:.0f} s)" in notice
    assert "the model (about 1 s)" in notice  # the thermostat's estimate rounds to 1 s
    import numba

    def seal(source: Generated) -> None:  # what a finished compile leaves
        folder = tmp_path / cache.cache_key(source, numba.__version__)
        folder.mkdir()
        (folder / "manifest.json").write_text("{}")

    seal(kernel_module())
    assert compile_notice(model) == "compiling the model (about 1 s); later runs load them from the cache"
    seal(generate(NativeModel(as_system(model))))
    assert compile_notice(model) is None
