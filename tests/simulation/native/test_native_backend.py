"""Choosing the backend: the CLI flag, refusals that name the construct, numba's absence, the cache."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate._ivp.rk import RK45
from support import (
    REPO,
    SPECS,
    assert_no_traceback,
    in_the_frame_room,
    read_csv,
    read_json,
    run_cli,
)

import hybrid
from hybrid.compose import as_system
from hybrid.errors import UsageError
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.native import buffers, integrator, stay
from hybrid.simulation.native.cache import CACHE_ENV
from hybrid.version import install_hint

pytest.importorskip("numba")


def _thermostat_closed_form(t: float, location: str, t0: float, temp0: float) -> float:
    """specs/thermostat.yaml between switches: an exponential towards T_out or T_heat."""
    target = 10.0 if location == "off" else 30.0
    return target + (temp0 - target) * np.exp(-0.1 * (t - t0))


def test_cli_backend_compiled_writes_what_scipy_writes(tmp_path: Path) -> None:
    """Both backends' files hold the same switches and points on the closed form.

    Row k of one file is not compared with row k of the other: the two integrators
    take the same steps only while their error estimates agree to the last bit,
    and that estimate is a sum of nearly equal stage values whose rounding moves
    with the summation order (numpy 2.4's ``dot`` against the kernel's loop moved a
    step by 2e-7 s). Each point is held against the closed form at its own time.
    """
    outputs = {}
    for backend in ("scipy", "compiled"):
        out, events = tmp_path / f"{backend}.csv", tmp_path / f"{backend}.json"
        done = run_cli("simulate", SPECS / "thermostat.yaml", "--t-end", "40", "--rtol", "1e-10",
                       "--atol", "1e-12", "--backend", backend, "--out", out, "--events", events)  # fmt: skip
        assert done.returncode == 0, done.stderr
        outputs[backend] = (read_csv(out), read_json(events))
    (header_s, _), events_s = outputs["scipy"]
    (header_c, _), events_c = outputs["compiled"]
    assert header_c == header_s
    assert [j["edge"] for j in events_c["jumps"]] == [j["edge"] for j in events_s["jumps"]]
    np.testing.assert_allclose([j["t"] for j in events_c["jumps"]],
                               [j["t"] for j in events_s["jumps"]], rtol=1e-9)  # fmt: skip
    for (_, rows), doc in outputs.values():
        jumps = doc["jumps"]
        for row in rows:
            t, j = float(row["t"]), int(row["j"])
            t0, temp0 = (jumps[j - 1]["t"], jumps[j - 1]["after"]["T"]) if j else (0.0, 20.0)
            expected = _thermostat_closed_form(t, row["location"], t0, temp0)
            assert float(row["T"]) == pytest.approx(expected, abs=1e-8), row
    assert events_c["settings"]["backend"] == "compiled"
    assert events_c["termination"]["cause"] == events_s["termination"]["cause"] == "t_end"


HEATER = """
automaton: heater
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -0.1*x}}}
requirements: [{name: warm, always: "x >= 15"}]
"""


def test_a_violated_requirement_is_reported_alike_on_the_command_line(tmp_path: Path) -> None:
    # x = 20 e^(-t/10) reaches 15 at t = 10 ln(4/3) = 2.87682...
    spec = tmp_path / "heater.yaml"
    spec.write_text(HEATER)
    said = {}
    for backend in ("scipy", "compiled"):
        done = run_cli("simulate", spec, "--t-end", "5", "--rtol", "1e-10", "--atol", "1e-12",
                       "--backend", backend, "--out", tmp_path / f"{backend}.csv")  # fmt: skip
        assert_no_traceback(done.stderr)
        said[backend] = (done.returncode, [line for line in done.stderr.splitlines() if "warm" in line])
    assert said["compiled"] == said["scipy"]
    code, lines = said["compiled"]
    assert code == 1 and len(lines) == 1 and "violated at t=2.87682" in lines[0], lines


def test_a_compiled_run_is_monitored_without_compiling_the_scipy_sides_modes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The monitor replays a compiled run with the requirements' margins only.

    Each run with other parameters is another model to the scipy side: compiling
    its modes as well made a compiled sweep of 48 UVMS variants take 14.9 s instead
    of 3.6 s. Off at 20 degC, the thermostat cools to 18 at t1 = 10 ln(10/8) and
    then heats past 21.5 at t1 + 10 ln(12/8.5); its highest point is 22.
    """
    text = (SPECS / "thermostat.yaml").read_text()
    model = hybrid.load_text(text + '\nrequirements: [{name: mild, always: "T <= 21.5"}]\n')
    asked: list[object] = []
    original = CompiledModel.mode

    def mode(self: CompiledModel, key: object) -> object:
        asked.append(key)
        return original(self, key)  # type: ignore[arg-type]

    monkeypatch.setattr(CompiledModel, "mode", mode)
    run = hybrid.simulate(model, t_end=10.0, rtol=1e-10, atol=1e-12, backend="compiled")
    mild = run.requirements["mild"]
    t1 = 10 * np.log(10 / 8)
    assert len(run.jumps) >= 2
    assert not mild.holds
    assert mild.violated_at == pytest.approx(t1 + 10 * np.log(12 / 8.5), abs=1e-7)
    assert mild.robustness == pytest.approx(-0.5, abs=1e-7)
    assert asked == []


def test_a_compiled_runs_monitor_replays_it_with_room_on_the_frame_stack(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The replay calls the margins at every step: a chunk's end at its depth would cost a
    mapped chunk each call (:mod:`hybrid.frames`), so it runs in the room."""
    from hybrid.simulation.monitor import Monitor

    text = (SPECS / "thermostat.yaml").read_text()
    model = hybrid.load_text(text + '\nrequirements: [{name: mild, always: "T <= 21.5"}]\n')
    seen: list[bool] = []
    original = Monitor.point

    def point(self: Monitor, *args: object) -> object:
        seen.append(in_the_frame_room())
        return original(self, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(Monitor, "point", point)
    run = hybrid.simulate(model, t_end=10.0, rtol=1e-10, atol=1e-12, backend="compiled")
    assert not run.requirements["mild"].holds
    assert seen and all(seen)


def test_what_the_compiled_backend_cannot_do_is_refused(ball: hybrid.Automaton) -> None:
    with pytest.raises(UsageError, match="method 'LSODA' needs the scipy backend"):
        hybrid.simulate(ball, t_end=1.0, method="LSODA", backend="compiled")
    polarization = hybrid.load(SPECS / "polarization.yaml")
    with pytest.raises(UsageError, match=r"cannot call inputs given as expressions or functions \(--input, inputs=...\); use the scipy backend \(--backend scipy; "):
        hybrid.simulate(polarization, t_end=1.0, inputs={"gamma": lambda t: 1.0}, backend="compiled")
    with pytest.raises(UsageError, match="input 'gamma' of polarization needs a value"):
        hybrid.simulate(polarization, t_end=1.0, backend="compiled")
    with pytest.raises(UsageError, match="unknown backend 'gpu'"):
        hybrid.simulate(ball, t_end=1.0, backend="gpu")


BLOCK_NUMBA = "import sys; sys.modules['numba'] = None; from hybrid.cli import main; raise SystemExit(main(sys.argv[1:]))"


def test_without_numba_the_compiled_backend_exits_2_with_the_install_hint() -> None:
    done = subprocess.run(
        [sys.executable, "-c", BLOCK_NUMBA, "simulate", str(SPECS / "bouncing_ball.yaml"),
         "--t-end", "1", "--backend", "compiled"],
        capture_output=True, text=True, cwd=REPO, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert install_hint("fast") in done.stderr
    assert_no_traceback(done.stderr)


def test_the_default_path_never_imports_numba() -> None:
    code = (
        "import sys, hybrid\n"
        "run = hybrid.simulate(hybrid.load('specs/bouncing_ball.yaml'), t_end=2.0)\n"
        "from hybrid.cli import main\n"
        "assert main(['simulate', 'specs/thermostat.yaml', '--t-end', '5']) == 0\n"
        "print(sorted(m for m in sys.modules if m == 'numba' or m.startswith('numba.')))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO,
                          timeout=120, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"


def test_a_second_process_loads_the_compiled_code_from_the_cache(ball: hybrid.Automaton) -> None:
    hybrid.simulate(ball, t_end=1.0, backend="compiled")  # compiled (or loaded) here
    code = (
        "import hybrid\n"
        "from hybrid.simulation.native.engine import compiled_native, kernel\n"
        "ball = hybrid.load('specs/bouncing_ball.yaml')\n"
        "run = hybrid.simulate(ball, t_end=1.0, backend='compiled')\n"
        "stats = kernel().run_one.stats\n"
        "print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))\n"
    )
    import os

    env = {**os.environ}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO,
                          timeout=300, check=False, env=env)  # fmt: skip
    assert done.returncode == 0, done.stderr
    hits, misses = map(int, done.stdout.split())
    assert (hits, misses) == (1, 0)
    assert CACHE_ENV == "HYBRID_NATIVE_CACHE"


def test_the_integrator_is_scipys_rk45() -> None:
    a, b, e, p = RK45.A, RK45.B, RK45.E, RK45.P
    mine_a = [
        [integrator.A21], [integrator.A31, integrator.A32],
        [integrator.A41, integrator.A42, integrator.A43],
        [integrator.A51, integrator.A52, integrator.A53, integrator.A54],
        [integrator.A61, integrator.A62, integrator.A63, integrator.A64, integrator.A65],
    ]  # fmt: skip
    for row, values in enumerate(mine_a, start=1):
        np.testing.assert_array_equal(a[row, :row], values)
    np.testing.assert_array_equal(b, [integrator.B1, 0, integrator.B3, integrator.B4, integrator.B5, integrator.B6])
    np.testing.assert_array_equal(e, [integrator.E1, 0, integrator.E3, integrator.E4, integrator.E5, integrator.E6, integrator.E7])
    np.testing.assert_allclose(integrator.P_DENSE, p, rtol=1e-15)
    # the step loops over these tables: stage s at y + h * sum(TABLEAU[s, :s] K), the 7th at y_new
    np.testing.assert_array_equal(integrator.TABLEAU[:6, :5], a)
    np.testing.assert_array_equal(integrator.TABLEAU[6, :6], b)
    np.testing.assert_array_equal(integrator.STAGE_C, [*RK45.C, 1.0])
    np.testing.assert_array_equal(integrator.ERROR, e)


def test_the_minimum_step_is_worked_out_wherever_it_can_bind() -> None:
    # the step works out scipy's minimum, 10 * spacing(t), only when the step is below
    # TEN_EPS * |t| + 1e-300: that must bound it for every t (numpy's spacing, the truth)
    rng = np.random.default_rng(7)
    ts = np.concatenate([
        2.0 ** np.arange(-1074, 1024, dtype=np.float64),  # every power of two, subnormals too
        np.nextafter(2.0 ** np.arange(-1022, 1023, dtype=np.float64), 0.0),  # just below them
        rng.uniform(-1e6, 1e6, 10_000), rng.lognormal(0.0, 50.0, 10_000), [0.0, 5e-324, 1e308],
    ])  # fmt: skip
    ts = np.concatenate([ts, -ts])
    minimum = 10.0 * np.abs(np.nextafter(ts, np.inf) - ts)
    assert np.all(minimum <= integrator.TEN_EPS * np.abs(ts) + 1e-300)
    assert integrator.TEN_EPS == 10 * 2.0**-52
    # and where it is worked out, it is that minimum (the kernel's helper, run as Python)
    picked = slice(None, None, 97)
    assert [integrator.min_step_at(float(t)) for t in ts[picked]] == minimum[picked].tolist()


def test_a_collapsing_step_ends_the_run_as_on_scipy() -> None:
    # x' = x**2 from 1 blows up at t = 1: both backends' steps collapse just before it, after
    # as many steps, where the step falls below scipy's minimum (10 * spacing(t))
    blowup = hybrid.load_text(
        "automaton: blowup\nstate: {x: {initial: 1.0}}\n"
        "locations:\n  run: {flow: {x: x**2}}\ninitial: {location: run}\n"
    )
    tolerances = {"rtol": 1e-10, "atol": 1e-12}
    runs = [
        hybrid.simulate(blowup, t_end=2.0, backend=backend, handle_sigint=False, **tolerances)
        for backend in ("scipy", "compiled")
    ]
    for run in runs:
        assert run.termination.cause == "solver_failure"
        assert "step size is less than spacing" in run.termination.message
        assert 1.0 - 1e-10 < run.termination.t < 1.0
    assert len(runs[0].t) == len(runs[1].t)
    assert abs(runs[1].termination.t - runs[0].termination.t) < 1e-13


def test_small_models_compile_as_one_function_large_ones_apart() -> None:
    from hybrid.simulation.native.source import INLINE_LINES, generate
    from hybrid.simulation.native.structure import NativeModel

    def op_lines(source: str) -> int:  # the operations: in `model`, or functions before it
        model = source[source.index("def model(") :].split("\n\n\n")[0]
        if "def model_rhs" not in source:
            return len(model.splitlines())
        return len(source[source.index("def model_rhs") : source.index("def model(")].splitlines())

    small = generate(NativeModel(as_system(hybrid.load(REPO / "specs" / "thermostat.yaml"))))
    large = generate(NativeModel(as_system(hybrid.load(REPO / "specs" / "uvms_mission_2.yaml"))))
    assert op_lines(small.source) < INLINE_LINES < op_lines(large.source)
    # the small model's operations are written in `model`'s branches: one function to compile
    assert "def model_rhs" not in small.source and "op == OP_RHS:\n        p_0 = p[0]" in small.source
    assert "def model_rhs" in large.source and "inline=" not in large.source
    # the estimate that plans the first compile grows with the model (measured 0.5 s and 15.6 s)
    assert 0.3 < small.compile_estimate < 1.5 < 10.0 < large.compile_estimate < 40.0


def test_cause_codes_follow_the_reference() -> None:
    from hybrid.simulation.result import CAUSES

    assert buffers.CAUSE_CODES == CAUSES
    codes = (stay.C_T_END, stay.C_BLOCKED, stay.C_NONFINITE, stay.C_SOLVER_FAILURE, stay.C_INTERRUPTED)
    assert [CAUSES[c] for c in codes] == ["t_end", "blocked", "nonfinite", "solver_failure", "interrupted"]


def test_runs_are_built_like_the_reference(thermostat: hybrid.Automaton) -> None:
    from dataclasses import fields

    from hybrid.simulation.native.assemble import settings_record
    from hybrid.simulation.settings import Settings

    run = hybrid.simulate(thermostat, t_end=30.0, backend="compiled", handle_sigint=False)
    reference = hybrid.simulate(thermostat, t_end=30.0, handle_sigint=False)
    assert run.jumps[0] == hybrid.Jump(**{f.name: getattr(run.jumps[0], f.name) for f in fields(hybrid.Jump)})
    assert run.jumps[0].as_dict().keys() == reference.jumps[0].as_dict().keys()
    settings = Settings(t_end=3.0, dt=0.5, backend="compiled")
    assert settings_record(settings) == settings.as_dict()
    assert run.settings == {**reference.settings, "backend": "compiled"}
