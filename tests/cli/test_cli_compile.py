"""``hybrid compile FILE...``: the compiled backend's cache filled ahead of the runs."""

from __future__ import annotations

import re
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
    # the files after it are still compiled, one line each (it used to stop at the first)
    ball = SPECS / "bouncing_ball.yaml"
    done = run_cli("compile", bad, ball)
    assert done.returncode == 2
    lines = done.stderr.splitlines()
    assert lines[0].startswith(f"{bad}:3:") and lines[1].startswith(f"{ball}: ")
    assert len(lines) == 2


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


def _fresh_structure() -> hybrid.Automaton:
    """A model whose compiled form no cache holds: a flow constant of its own."""
    import uuid

    rate = 1.0 + uuid.uuid4().int % 10**9 / 1e12
    return hybrid.load_text(
        f"automaton: drift\nstate: {{x: {{initial: [0, 2]}}}}\ninputs: {{u: {{range: [1, 3]}}}}\n"
        f"locations: {{go: {{flow: {{x: {rate!r} * u}}}}}}\n",
        file="drift.yaml",
    )


def test_a_first_compiled_run_says_what_it_compiles_once_the_run_is_accepted(
    tmp_path: Path,
) -> None:
    """The note was printed by the command before the run: also for runs then refused,
    which compile nothing. It is now said as the compile starts, and only then."""
    from hybrid.simulation.native.choice import compile_notices

    model = _fresh_structure()
    said: list[str] = []
    with compile_notices(said.append):
        with pytest.raises(hybrid.UsageError, match="method 'RK23'"):
            hybrid.simulate(model, t_end=1.0, backend="compiled", method="RK23")
        with pytest.raises(hybrid.UsageError, match="cannot hold input 'u'"):
            hybrid.sweep(model, t_end=1.0, grid={"input.u": [1.0, 3.0]}, backend="compiled")
        out = tmp_path / "table.csv"
        parts = tmp_path / "table.csv.parts"
        parts.mkdir()
        (parts / "campaign.json").write_text('{"fingerprint": "another"}')
        with pytest.raises(hybrid.UsageError, match="another campaign"):
            hybrid.sweep(model, t_end=1.0, grid={"init.x": [0.0, 1.0]}, out=out, resume=True,
                         backend="compiled", workers=0)  # fmt: skip
        assert said == []  # refused, nothing compiled: nothing said
        run = hybrid.simulate(model, t_end=1.0, backend="compiled")
        # the thermostat-sized estimate, in this machine's seconds after a first compile here
        assert re.search(r"the model \(about \d+ s( here)?\)", said[0]) and len(said) == 1
        again = hybrid.simulate(model, t_end=2.0, backend="compiled")
    assert len(said) == 1  # compiled once: said once
    u = hybrid.simulate(model, t_end=1.0, backend="scipy").states[-1, 0]  # x' = rate * u
    assert run.states[-1, 0] == pytest.approx(u, rel=1e-9)
    assert again.termination.cause == "t_end"


def test_a_refused_compiled_sweep_says_no_compile_note(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from hybrid.simulation.native import cache

    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "cache"))  # nothing compiled there
    spec = tmp_path / "drift.yaml"
    spec.write_text("automaton: drift\nstate: {x: {initial: [0, 2]}}\n"
                    "inputs: {u: {range: [1, 3]}}\nlocations: {go: {flow: {x: u}}}\n")  # fmt: skip
    done = run_cli("sweep", spec, "--t-end", "4", "--grid", "input.u=1:3:3", "--backend",
                   "compiled", "--workers", "0", "--out", tmp_path / "t.csv")  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert_no_traceback(done.stderr)
    assert "note: compiling" not in done.stderr  # it said so before refusing
    assert done.stderr.startswith(f"{spec}: the compiled backend cannot hold input 'u'")
    done = run_cli("simulate", spec, "--t-end", "4", "--backend", "compiled", "--method", "RK23")
    assert done.returncode == 2 and "note: compiling" not in done.stderr, done.stderr
