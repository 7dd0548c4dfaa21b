"""(7) The compiled backend against the scipy backend, and what compiling costs.

Ratios in one process after a warm-up call (so compiling is not timed there):
the bouncing ball for 40 bounces and the thermostat for 10 periods, each
``backend="compiled"`` / ``backend="scipy"`` with the same tolerances; an
ensemble of 10,000 thermostat runs (``simulate_many``, every core) against a
serial loop of scipy runs (timed on a sample, per run). Jump times of both are
compared in the same run. Compile times are measured in fresh processes with
their own cache directory: the first process on a machine (the kernel and the
model), a new model once the kernel is cached, and a process that finds both;
then UVMS mission 2 (its library's compiled forms), first and cached. UVMS
mission 2 over its 60 s (without its requirements: both backends monitor them
with the same Python monitor, and this compares the engines) and a ``hybrid.sweep`` of thermostat runs in this process
(one ``simulate_many`` call per batch against one scipy run per point) are
ratios like the others.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

import hybrid
from bench.harness import Comparison, compare, paired, time_call

__all__ = ["compile_times", "run", "single_runs"]

RTOL, ATOL = 1e-10, 1e-12
ROOT = Path(__file__).resolve().parent.parent


def _jumps(model: Any, backend: str, handle_sigint: bool = False, **kwargs: Any) -> list[float]:
    run = hybrid.simulate(model, rtol=RTOL, atol=ATOL, backend=backend,
                          handle_sigint=handle_sigint, **kwargs)  # fmt: skip
    return [j.t for j in run.jumps]


def run(repeats: int = 9, ensemble_size: int = 10_000) -> list[Comparison]:
    thermo = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    results = single_runs(repeats)
    results.append(_ensemble(thermo, ensemble_size, max(5, repeats // 3)))
    results.append(_mission(max(3, repeats // 3)))
    results.append(_sweep(thermo, 200 if ensemble_size >= 10_000 else 40, max(3, repeats // 3)))
    return results


IN_A_ROW = 10
"""Calls of one backend timed together (their mean) in each repeat of the single runs."""


def single_runs(repeats: int = 9) -> list[Comparison]:
    """The bouncing ball for 40 bounces and the thermostat for 10 periods, compiled / scipy.

    Both with ``handle_sigint=False``. Each repeat times :data:`IN_A_ROW` calls
    of one backend, then as many of the other (the order alternating), so a
    timing is a loop of runs after a warm-up call: the first compiled call of
    each follows the scipy calls, which leave the processor's caches cold, and
    the rest find the compiled code and Python's objects cached. Also, in the
    same run (extras): ``cold_call_ratio_median``, each compiled call timed
    alone right after a scipy call (the caches always cold; the harness's
    ``inner=1``), and ``compiled_handle_sigint_median_s``, the compiled call
    with the default ``handle_sigint=True`` (its loop on the worker thread while
    the main thread watches Ctrl-C). ``python -m bench.native_backend single``
    runs these two alone.
    """
    ball = hybrid.load(ROOT / "specs" / "bouncing_ball.yaml", parameters={"e": 0.95})
    thermo = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    results = []
    for name, model, kwargs in (
        ("bouncing ball, 40 bounces", ball, {"t_end": 1e3, "max_jumps": 40}),
        ("thermostat, 10 periods", thermo, {"t_end": 1e4, "max_jumps": 20}),
    ):
        sides = (
            ("backend='compiled'", lambda m=model, k=kwargs: _jumps(m, "compiled", **k)),
            ("backend='scipy'", lambda m=model, k=kwargs: _jumps(m, "scipy", **k)),
        )
        c = compare(f"compiled backend: {name}, {IN_A_ROW} calls in a row", *sides,
                    repeats=repeats, inner=IN_A_ROW)  # fmt: skip
        cold = compare(name, *sides, repeats=repeats)
        ours, reference = _jumps(model, "compiled", **kwargs), _jumps(model, "scipy", **kwargs)
        watched = [time_call(lambda m=model, k=kwargs: _jumps(m, "compiled", True, **k))
                   for _ in range(repeats)]  # fmt: skip
        c.extra = {
            "jumps": len(ours),
            "max_jump_time_difference_s": max(
                abs(a - b) for a, b in zip(ours, reference, strict=True)
            ),
            "cold_call_ratio_median": cold.ratio_median,
            "cold_call_ratio_min": cold.ratio_min,
            "cold_call_compiled_median_s": cold.contender_median_s,
            "compiled_handle_sigint_median_s": statistics.median(watched),
        }
        results.append(c)
    return results


def mission_without_requirements() -> Any:
    """UVMS mission 2 without its requirements (the same Python monitor on both backends)."""
    from dataclasses import replace

    mission = hybrid.load(ROOT / "specs" / "uvms_mission_2.yaml")
    parts = tuple(
        replace(c, automaton=replace(c.automaton, requirements=())) for c in mission.components
    )
    return replace(mission, requirements=(), components=parts)


def _mission(repeats: int) -> Comparison:
    """UVMS mission 2 over its 60 s (7 jumps, the singular vicinity crossed)."""
    mission = mission_without_requirements()
    kwargs = {"t_end": 60.0}
    c = compare(
        "compiled backend: UVMS mission 2, 60 s",
        ("backend='compiled'", lambda: _jumps(mission, "compiled", **kwargs)),
        ("backend='scipy'", lambda: _jumps(mission, "scipy", **kwargs)),
        repeats=repeats,
    )
    ours, reference = _jumps(mission, "compiled", **kwargs), _jumps(mission, "scipy", **kwargs)
    c.extra = {
        "jumps": len(ours),
        "max_jump_time_difference_s": max(abs(a - b) for a, b in zip(ours, reference, strict=True)),
    }
    return c


def _sweep(thermo: Any, n: int, repeats: int) -> Comparison:
    """``hybrid.sweep`` of ``n`` thermostat runs in this process, compiled against scipy, per run."""
    grid = {"T_high": list(np.linspace(21.0, 23.0, n // 4)), "init.T": [16.0, 17.0, 19.0, 20.0]}
    kwargs: dict[str, Any] = {"grid": grid, "summaries": ("jump_t:5",), "workers": 0,
                              "handle_sigint": False, "rtol": RTOL, "atol": ATOL}  # fmt: skip
    size = len(grid["T_high"]) * 4
    tables = {}

    def sweep(backend: str) -> None:
        tables[backend] = hybrid.sweep(thermo, 200.0, backend=backend, **kwargs)

    c = compare(
        f"compiled backend: hybrid.sweep of {size} thermostat runs (in process)",
        ("backend='compiled' (simulate_many per batch)", lambda: sweep("compiled")),
        ("backend='scipy'", lambda: sweep("scipy")),
        repeats=repeats,
    )
    difference = max(
        abs(a["jump_t:5"] - b["jump_t:5"])
        for a, b in zip(tables["compiled"].rows, tables["scipy"].rows, strict=True)
    )
    c.extra = {"runs": size, "max_jump_t5_difference_s": difference}
    return c


def _ensemble(thermo: Any, n: int, repeats: int) -> Comparison:
    """10,000 thermostat runs (10 periods each, initial temperatures spread) per run."""
    starts = np.linspace(18.5, 21.5, n)
    kwargs = {"t_end": 1e4, "max_jumps": 20, "rtol": 1e-8, "atol": 1e-10, "handle_sigint": False}

    def compiled() -> Any:
        return hybrid.simulate_many(thermo, parameters={"init.T": starts}, **kwargs)

    sample = starts[:: max(1, n // 40)]

    def serial() -> None:
        for t0 in sample:
            hybrid.simulate(thermo, initial={"T": float(t0)}, **kwargs)

    compiled()
    serial()
    c_times = [time_call(compiled) / n for _ in range(repeats)]
    s_times = [time_call(serial) / sample.size for _ in range(repeats)]
    ensemble = compiled()
    materialize = time_call(lambda: list(ensemble)) / n
    check = hybrid.simulate(thermo, initial={"T": float(starts[-1])}, **kwargs)
    return paired(
        f"compiled backend: ensemble of {n:,} thermostat runs, per run",
        "simulate_many (summaries)",
        "serial loop of backend='scipy' runs",
        c_times,
        s_times,
        {
            "throughput_gain": statistics.median(s_times) / statistics.median(c_times),
            "threads": os.cpu_count(),
            "every_Run_built_per_run_s": materialize,
            "last_run_jump_time_difference_s": float(
                np.max(np.abs(ensemble[n - 1].jump_times - check.jump_times))
            ),
        },
    )


_PROBE = """
import time
t0 = time.perf_counter()
import hybrid
import hybrid.simulation.engine
t1 = time.perf_counter()
import numba
t2 = time.perf_counter()
from hybrid.simulation.native.engine import compiled_native, kernel
kernel()
t3 = time.perf_counter()
model = hybrid.load({spec!r})
if getattr(model, "components", None):  # the engines compared, without the (Python) monitor
    from dataclasses import replace
    model = replace(model, requirements=(), components=tuple(
        replace(c, automaton=replace(c.automaton, requirements=())) for c in model.components))
from hybrid.compose import as_system
compiled_native(as_system(model))
t4 = time.perf_counter()
hybrid.simulate(model, t_end=1.0, backend="compiled", handle_sigint=False)
t5 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4)
"""


_FIRST = """
import time
import hybrid
import numba
from hybrid.simulation.native.engine import compiled_native
from hybrid.compose import as_system
model = as_system(hybrid.load({spec!r}))
t0 = time.perf_counter()
compiled_native(model)
print(time.perf_counter() - t0)
"""


def compile_times() -> dict[str, float]:
    """Seconds, in fresh processes sharing one new cache directory, to a compiled run.

    Each probe reports: importing hybrid's simulator (its entry: since a compiled run
    stopped loading the scipy engine, scipy is not among it), importing numba,
    compiling or loading the kernel, generating and compiling or loading the
    model, and the first run. The first process compiles both; the second a new
    model only; the third finds both cached. ``first_process_kernel_and_model_s``:
    a first process that asks for the model at once (as ``simulate`` does), so
    that it compiles the model while worker processes compile the kernel's
    pieces (the probes above compile the kernel, waiting for it, then the model);
    ``first_process_kernel_and_model_one_process_s``: the same with the compile in one
    process (``HYBRID_NATIVE_COMPILE_PROCESSES=1``), the measure of what sharing the
    kernel's compile among processes is worth.
    """

    def probe(spec: str, cache: str) -> list[float]:
        env = {**os.environ, "HYBRID_NATIVE_CACHE": cache}
        code = _PROBE.format(spec=str(ROOT / "specs" / spec))
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=env, cwd=ROOT, check=True)  # fmt: skip
        return [float(v) for v in out.stdout.split()]

    def first_compile(processes: str | None) -> float:
        """What a user's first compiled run waits for (``processes``: the compile's)."""
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "HYBRID_NATIVE_CACHE": cache}
            env.pop("HYBRID_NATIVE_COMPILE_PROCESSES", None)
            if processes is not None:
                env["HYBRID_NATIVE_COMPILE_PROCESSES"] = processes
            code = _FIRST.format(spec=str(ROOT / "specs" / "thermostat.yaml"))
            out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                 env=env, cwd=ROOT, check=True)  # fmt: skip
            return float(out.stdout.split()[-1])

    first_both = first_compile(None)  # the kernel's pieces shared among the CPUs
    first_alone = first_compile("1")  # all in this process: what the shares save
    with tempfile.TemporaryDirectory() as cache:
        first = probe("thermostat.yaml", cache)
        new_model = probe("bouncing_ball.yaml", cache)
        cached = probe("bouncing_ball.yaml", cache)
        mission = probe("uvms_mission_2.yaml", cache)
        mission_cached = probe("uvms_mission_2.yaml", cache)
    return {
        "uvms_mission_2_model_compile_s": mission[3],
        "uvms_mission_2_cached_model_load_s": mission_cached[3],
        "uvms_mission_2_cached_process_total_s": sum(mission_cached),
        "first_process_kernel_and_model_s": first_both,
        "first_process_kernel_and_model_one_process_s": first_alone,
        "parallel_compile_saving": 1.0 - first_both / first_alone,
        "first_process_kernel_s": first[2],
        "first_process_model_s": first[3],
        "new_model_compile_s": new_model[3],
        "cached_kernel_load_s": cached[2],
        "cached_model_load_s": cached[3],
        "cached_compiled_code_s": cached[2] + cached[3] + cached[4],
        "numba_import_s": cached[1],
        "cached_process_total_s": sum(cached),
    }


if __name__ == "__main__":
    if sys.argv[1:] == ["single"]:
        for result in single_runs():
            print(result.line(), result.extra)
        sys.exit()
    for result in run():
        print(result.line(), result.extra)
    print(compile_times())
