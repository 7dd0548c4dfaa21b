"""Runs repeated and varied on the compiled backend: what is kept between calls is never stale.

``simulate`` keeps per-call work between runs (issue 14): the start description
per model and overrides, the loop's inputs for the last model and settings, the
compiled structure of the last model, the thread's run arrays, and per-layout
jump fields. Each test changes one thing between runs (parameters, initial
values, initial location, t_start, t_end, max_jumps, tolerances, the model,
the thread) and holds every run to a closed form: the bouncing ball's impact
times and the thermostat's switching times.
"""

from __future__ import annotations

import math
import pickle
import subprocess
import sys
import threading
from typing import Any

import numpy as np
import pytest
from support import REPO, SPECS

import hybrid
from hybrid.compose import as_system
from hybrid.held import HeldCache
from hybrid.simulation.native.assemble import PACKED_WIDTH, Layout
from hybrid.simulation.native.structure import NativeModel
from hybrid.simulation.result import Jump, Run
from hybrid.simulation.start import describe_start

pytest.importorskip("numba")

TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False, "backend": "compiled"}
BALL = hybrid.load(SPECS / "bouncing_ball.yaml")
THERMO = hybrid.load(SPECS / "thermostat.yaml")


def impacts(h0: float, g: float, e: float, n: int, t_start: float = 0.0) -> list[float]:
    """The first ``n`` impact times of a ball dropped from rest at ``h0`` at ``t_start``."""
    t1 = math.sqrt(2 * h0 / g)
    times, t, gap = [], t_start + t1, 2 * t1
    for _ in range(n):
        times.append(t)
        gap *= e
        t += gap
    return times


def switches(t0: float, a: float, out: float, heat: float, low: float, high: float,
             n: int) -> list[float]:  # fmt: skip
    """The thermostat's first ``n`` switching times from ``T = t0`` in ``off`` (t0 > low)."""
    cool = math.log((high - out) / (low - out)) / a
    warm = math.log((heat - low) / (heat - high)) / a
    t = math.log((t0 - out) / (low - out)) / a
    times = []
    for k in range(n):
        times.append(t)
        t += warm if k % 2 == 0 else cool
    return times


def ball(**kwargs: object) -> Run:
    return hybrid.simulate(BALL, **TOL, **kwargs)  # type: ignore[arg-type]


def assert_times(run: Run, expected: list[float]) -> None:
    assert len(run.jumps) == len(expected)
    np.testing.assert_allclose(run.jump_times, expected, rtol=0, atol=1e-7)


def test_each_change_between_runs_gives_its_own_closed_form() -> None:
    base = ball(t_end=1e3, max_jumps=10, parameters={"e": 0.9})
    assert_times(base, impacts(10.0, 9.81, 0.9, 10))
    assert_times(ball(t_end=1e3, max_jumps=10, parameters={"e": 0.5}), impacts(10.0, 9.81, 0.5, 10))
    assert_times(ball(t_end=1e3, max_jumps=10, parameters={"e": 0.9, "g": 1.62}),
                 impacts(10.0, 1.62, 0.9, 10))  # fmt: skip
    assert_times(ball(t_end=1e3, max_jumps=10, parameters={"e": 0.9}, initial={"h": 3.0}),
                 impacts(3.0, 9.81, 0.9, 10))  # fmt: skip
    assert_times(ball(t_end=1e3, max_jumps=10, parameters={"e": 0.9}, t_start=5.0),
                 impacts(10.0, 9.81, 0.9, 10, t_start=5.0))  # fmt: skip
    assert_times(ball(t_end=1e3, max_jumps=4, parameters={"e": 0.9}), impacts(10.0, 9.81, 0.9, 4))
    within = [t for t in impacts(10.0, 9.81, 0.9, 10) if t < 9.0]
    short = ball(t_end=9.0, max_jumps=10, parameters={"e": 0.9})
    assert_times(short, within)
    assert short.termination.cause == "t_end" and short.termination.t == 9.0
    loose = hybrid.simulate(BALL, t_end=1e3, max_jumps=10, parameters={"e": 0.9}, rtol=1e-8,
                            atol=1e-10, handle_sigint=False, backend="compiled")  # fmt: skip
    np.testing.assert_allclose(loose.jump_times, impacts(10.0, 9.81, 0.9, 10), atol=1e-5)
    assert loose.settings["rtol"] == 1e-8
    # and back to the first run: equal in every field, settings record included
    again = ball(t_end=1e3, max_jumps=10, parameters={"e": 0.9})
    assert pickle.dumps(again) == pickle.dumps(base)


def test_the_same_model_object_with_other_settings_and_starts() -> None:
    model = BALL.with_parameters({"e": 0.7})
    first = hybrid.simulate(model, t_end=1e3, max_jumps=6, **TOL)  # type: ignore[arg-type]
    assert_times(first, impacts(10.0, 9.81, 0.7, 6))
    fewer = hybrid.simulate(model, t_end=1e3, max_jumps=3, **TOL)  # type: ignore[arg-type]
    assert_times(fewer, impacts(10.0, 9.81, 0.7, 3))
    assert fewer.termination.message == "reached max_jumps=3"
    sooner = hybrid.simulate(model, t_end=5.0, max_jumps=6, **TOL)  # type: ignore[arg-type]
    assert_times(sooner, [t for t in impacts(10.0, 9.81, 0.7, 6) if t < 5.0])
    assert sooner.termination.cause == "t_end" and sooner.t[-1] == 5.0
    for h0 in (2.0, 5.0):
        run = hybrid.simulate(model, t_end=1e3, max_jumps=6, initial={"h": h0}, **TOL)  # type: ignore[arg-type]
        assert_times(run, impacts(h0, 9.81, 0.7, 6))
        assert run.settings["start"]["state"] == {"h": h0, "v": 0.0}
    again = hybrid.simulate(model, t_end=1e3, max_jumps=6, **TOL)  # type: ignore[arg-type]
    assert_times(again, impacts(10.0, 9.81, 0.7, 6))
    assert again.settings["start"]["state"] == {"h": 10.0, "v": 0.0}
    later = hybrid.simulate(model, t_end=1e3, max_jumps=6, t_start=2.5, **TOL)  # type: ignore[arg-type]
    assert_times(later, impacts(10.0, 9.81, 0.7, 6, t_start=2.5))
    assert later.settings["t_start"] == 2.5 and later.t[0] == 2.5


def test_models_interleaved_and_a_run_that_outgrows_the_arrays() -> None:
    thermo = {"t_end": 1e4, "max_jumps": 8}
    expected_thermo = switches(20.0, 0.1, 10.0, 30.0, 18.0, 22.0, 8)
    for _ in range(2):
        assert_times(ball(t_end=1e3, max_jumps=5, parameters={"e": 0.8}), impacts(10.0, 9.81, 0.8, 5))
        assert_times(hybrid.simulate(THERMO, **TOL, **thermo), expected_thermo)  # type: ignore[arg-type]
    # 70 jumps: more than the first arrays hold (64), so the run is made again, larger
    many = ball(t_end=1e3, max_jumps=70, parameters={"e": 0.95}, zeno=False)
    np.testing.assert_allclose(many.jump_times, impacts(10.0, 9.81, 0.95, 70), rtol=0, atol=1e-6)
    assert_times(ball(t_end=1e3, max_jumps=5, parameters={"e": 0.8}), impacts(10.0, 9.81, 0.8, 5))
    warm = hybrid.simulate(THERMO, initial_location="on", initial={"T": 19.0}, **TOL, **thermo)  # type: ignore[arg-type]
    heat_up = math.log((30.0 - 19.0) / (30.0 - 22.0)) / 0.1
    assert warm.jumps[0].t == pytest.approx(heat_up, abs=1e-7)
    assert warm.settings["start"]["location"] == "on"
    assert_times(hybrid.simulate(THERMO, **TOL, **thermo), expected_thermo)  # type: ignore[arg-type]


def test_a_run_after_a_race_reports_only_its_own_enabled_edges() -> None:
    zoo = hybrid.load(REPO / "tests" / "data" / "native_zoo.yaml")
    for location, t_end in (("race", 3.0), ("timer_on", 30.0), ("race", 3.0), ("timer_on", 30.0)):
        runs = [
            hybrid.simulate(zoo, t_end=t_end, initial_location=location, rtol=1e-10, atol=1e-12,
                            handle_sigint=False, backend=backend, initial={"x": 1.0})
            for backend in ("compiled", "scipy")
        ]
        assert runs[0].jumps, location
        assert [(j.edge, j.enabled, j.chosen_by) for j in runs[0].jumps] == [
            (j.edge, j.enabled, j.chosen_by) for j in runs[1].jumps
        ]


def test_threads_each_get_their_own_runs() -> None:
    restitutions = [0.5, 0.6, 0.7, 0.8, 0.9, 0.95]
    found: dict[float, list[float]] = {}
    errors: list[BaseException] = []

    def work(e: float) -> None:
        try:
            for _ in range(5):
                run = ball(t_end=1e3, max_jumps=12, parameters={"e": e})
                np.testing.assert_allclose(run.jump_times, impacts(10.0, 9.81, e, 12), atol=1e-7)
            found[e] = run.jump_times.tolist()
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(e,)) for e in restitutions]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert not errors and sorted(found) == restitutions


def test_jump_records_are_plain_jumps() -> None:
    run = ball(t_end=1e3, max_jumps=3, parameters={"e": 0.8})
    for jump in run.jumps:
        rebuilt = Jump(jump.t, jump.j, jump.edge, jump.label, jump.source, jump.target,
                       dict(jump.before), dict(jump.after), jump.enabled, jump.chosen_by)  # fmt: skip
        assert type(jump) is Jump and jump == rebuilt and repr(jump) == repr(rebuilt)
        assert pickle.dumps(jump) == pickle.dumps(rebuilt)
        assert pickle.loads(pickle.dumps(jump)) == jump
        assert list(vars(jump)) == list(vars(rebuilt))
        assert type(jump.t) is float and type(jump.j) is int
        assert type(jump.before["v"]) is float
    first = run.jumps[0]
    assert first.before["v"] == pytest.approx(-math.sqrt(2 * 9.81 * 10.0), abs=1e-6)
    assert first.after["v"] == pytest.approx(0.8 * math.sqrt(2 * 9.81 * 10.0), abs=1e-6)
    assert (first.edge, first.source, first.target, first.enabled, first.chosen_by) == (
        "bounce", "falling", "falling", ("bounce",), "only")  # fmt: skip


def test_start_descriptions_are_copies_and_follow_the_overrides() -> None:
    model = hybrid.load_text(
        "automaton: a\n"
        "state: {x: {initial: [0, 2]}}\n"
        "inputs: {u: {range: [-1, 3]}}\n"
        "locations: {l: {flow: {x: u}}, k: {}}\n"
        "initial: {location: [l, k]}\n"
    )
    first = describe_start(model, None, None, None)
    assert first["state"] == {"x": 1.0} and first["inputs"] == {"u": 1.0}
    notes = list(first["notes"])
    first["notes"].append("changed by the caller")
    first["state"]["x"] = 99.0
    second = describe_start(model, None, None, None)
    assert second["notes"] == notes and second["state"] == {"x": 1.0}
    assert describe_start(model, None, None, "k")["location"] == "k"
    outside = describe_start(model, None, {"x": 5.0}, None)
    assert outside["state"] == {"x": 5.0} and any("outside its initial set" in n for n in outside["notes"])
    signed = describe_start(model, None, {"x": -0.0}, None)["state"]["x"]
    assert math.copysign(1.0, signed) == -1.0
    assert math.copysign(1.0, describe_start(model, None, {"x": 0.0}, None)["state"]["x"]) == 1.0
    # inputs are called at t_start: never taken from an earlier call
    ramp = {"u": lambda t: t}
    assert any("starts at 5" in n for n in describe_start(model, ramp, None, None, 5.0)["notes"])
    assert not any("input u" in n for n in describe_start(model, ramp, None, None, 1.0)["notes"])
    assert describe_start(model, None, None, None) == second


def _fanned(n: int) -> hybrid.Automaton:
    """One location with ``n`` edges ``e0``, ``e1``, ... to another, priorities 0, 1, 0, ..."""
    edges = "\n".join(
        f"  - {{name: e{k}, from: a, to: b, guard: x >= {k % 3}, priority: {k % 2}}}"
        for k in range(n)
    )
    model = hybrid.load_text(
        "automaton: wide\nstate: {x: {initial: 0}}\n"
        "locations: {a: {flow: {x: 1}}, b: {}}\nedges:\n" + edges + "\n"
    )
    assert isinstance(model, hybrid.Automaton)
    return model


@pytest.mark.parametrize("n", [5, PACKED_WIDTH + 3])
def test_jump_keys_name_the_edge_the_enabled_set_and_how_it_was_chosen(n: int) -> None:
    layout = Layout.of(NativeModel(as_system(_fanned(n))))
    order = [tr.view.name for _, _, tr in layout.transitions]
    rng = np.random.default_rng(7)
    flags = (rng.random((20, n)) < 0.3).astype(float)
    chosen = rng.integers(0, n, 20)
    flags[np.arange(20), chosen] = 1.0
    keys = layout.jump_keys(chosen.astype(float), flags)
    assert all(isinstance(k, int if n <= PACKED_WIDTH else tuple) for k in keys)
    for row, tr, key in zip(flags, chosen.tolist(), keys, strict=True):
        fields = layout.fields(key, n)
        on = [order[k] for k in range(n) if row[k]]
        priority = {f"e{k}": k % 2 for k in range(n)}
        top = [name for name in on if priority[name] == priority[order[tr]]]
        how = "only" if len(on) == 1 else "priority" if len(top) == 1 else "file order"
        assert fields == {"t": None, "j": None, "edge": order[tr], "label": None, "source": "a",
                          "target": "b", "before": None, "after": None, "enabled": tuple(on),
                          "chosen_by": how}  # fmt: skip
        assert layout.fields((tr, bytes(int(f) for f in row)), n) == fields  # either key form



@pytest.mark.parametrize("n", [5, PACKED_WIDTH + 3])
def test_the_loops_packed_key_is_the_key_of_its_transition_and_flags(n: int) -> None:
    """``J_KEY``, packed by the compiled loop, equals :meth:`Layout.jump_keys` of the row (-1 when
    too wide), and the jump it names is the scipy backend's."""
    from hybrid.simulation.native import buffers as b
    from hybrid.simulation.native.engine import compiled_native, run_arrays
    from hybrid.simulation.settings import Settings

    model = _fanned(n)
    compiled = compiled_native(as_system(model))
    settings = Settings(t_end=2.0, max_jumps=1)
    p = np.array(compiled.native.parameter_vector(model))
    x0 = np.array(model.initial_vector())
    arrays = run_arrays(compiled, p, x0, compiled.initial_mode(model), settings, False)
    rows = arrays.jps[: int(arrays.oi[b.I_JUMPS])]
    assert rows.shape[0] == 1
    z = b.J_X + 2 * len(compiled.native.state_names)
    expected = compiled.layout.jump_keys(rows[:, b.J_TR], rows[:, z:])
    assert compiled.layout.packed == (n <= PACKED_WIDTH)
    if n <= PACKED_WIDTH:
        assert rows[:, b.J_KEY].tolist() == expected
    else:
        assert rows[:, b.J_KEY].tolist() == [-1.0]
    ours = hybrid.simulate(model, t_end=2.0, max_jumps=1, **TOL).jumps
    reference = hybrid.simulate(model, t_end=2.0, max_jumps=1, handle_sigint=False).jumps
    assert ours == reference
    assert ours[0].enabled == tuple(f"e{k}" for k in range(0, n, 3))  # x >= k % 3 at x = 0

CTRL_C = """
import os, signal, threading, time
import hybrid
zoo = hybrid.load({zoo!r})
endless = dict(t_end=1e7, initial_location="moving", max_step=1e-4, backend="compiled")
hybrid.simulate(zoo, t_end=1.0, initial_location="moving", backend="compiled")  # compiled, warm
for _ in range(2):  # the same worker thread serves the next run
    threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
    run = hybrid.simulate(zoo, **endless)
    print(run.termination.cause, run.termination.t < 1e7)
after = hybrid.simulate(zoo, t_end=2.0, initial_location="moving", backend="compiled")
print(after.termination.cause, after.termination.t)
"""


def test_ctrl_c_ends_compiled_runs_as_interrupted_and_the_next_run_normally() -> None:
    code = CTRL_C.format(zoo=str(REPO / "tests" / "data" / "native_zoo.yaml"))
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=REPO, timeout=600)  # fmt: skip  (a hang guard: a cold compile)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[:3] == ["interrupted True", "interrupted True", "t_end 2.0"]


def test_an_abandoned_run_does_not_hold_up_the_next() -> None:
    """A second Ctrl-C abandons a run still in the worker; the next run does not wait for it.

    (A run with progress runs on the worker thread: ``tick`` given; one without runs in
    the main thread, where nothing is left behind to abandon.)"""
    import _thread

    from hybrid.simulation.interrupts import Interrupts
    from hybrid.simulation.native.interruptible import run_in_worker

    release, finished = threading.Event(), threading.Event()

    def stuck() -> None:
        release.wait(60)
        finished.set()

    stop = Interrupts()
    stop.press()  # a run was interrupted: in the writing phase the next Ctrl-C abandons
    with stop.installed(), stop.writing():
        threading.Timer(0.2, _thread.interrupt_main).start()
        with pytest.raises(KeyboardInterrupt):
            run_in_worker(lambda flag: stuck(), True, tick=lambda: None)  # ignores its flag
    ran: list[int] = []
    assert run_in_worker(lambda flag: ran.append(int(flag[0])), True, tick=lambda: None) is False
    assert ran == [0]
    assert not finished.is_set()  # the abandoned run still waits; the next one did not
    release.set()


def test_a_run_in_the_main_thread_is_stopped_by_ctrl_c_through_the_watcher() -> None:
    """The loop runs in the main thread; Python's handler cannot run until it returns, so
    the watcher thread sets its flag (from the signal wake-up pipe); a wake-up descriptor
    installed before (asyncio's) still receives the signal and is restored."""
    import os
    import signal
    import time

    from hybrid.simulation.native.interruptible import run_in_worker

    seen: list[float] = []

    def loop(flag: Any) -> None:  # polls its flag as the compiled loop does at every step
        start = time.monotonic()
        while not flag[0] and time.monotonic() - start < 20.0:
            time.sleep(0.01)
        seen.append(time.monotonic() - start)

    theirs_read, theirs_write = os.pipe()
    os.set_blocking(theirs_write, False)
    old = signal.set_wakeup_fd(theirs_write)
    # Python's own handler, also in a process started ignoring SIGINT (a shell's background
    # job without job control), whose handler would be SIG_IGN before and after
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT)).start()
        assert run_in_worker(loop, True) is True
        assert signal.set_wakeup_fd(theirs_write) == theirs_write  # theirs again after the run
        assert seen and seen[0] < 10.0
        passed_on = b""
        for _ in range(200):  # the watcher passes it on right after setting the flag
            os.set_blocking(theirs_read, False)
            try:
                passed_on += os.read(theirs_read, 64)
            except BlockingIOError:
                time.sleep(0.01)
            if passed_on:
                break
        assert signal.SIGINT in passed_on
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, inherited)
        signal.set_wakeup_fd(old)
        os.close(theirs_read)
        os.close(theirs_write)


def test_a_system_started_in_another_mode_is_another_structure(tmp_path: Any) -> None:
    """The modes generated are those reachable from the initial one: the structure of
    (c4, d2) has no (c1, d1), and a run started there raised KeyError once the other had
    been compiled in the process. Closed forms (no edges): x = t in c1 and 0 in c4,
    y = 2 t in d1 and -t in d2."""
    (tmp_path / "c.yaml").write_text(
        "automaton: c\nstate: {x: {initial: 0}}\n"
        "locations: {c1: {flow: {x: 1}}, c4: {flow: {x: 0}}}\ninitial: {location: [c1, c4]}\n"
    )
    (tmp_path / "d.yaml").write_text(
        "automaton: d\nstate: {y: {initial: 0}}\n"
        "locations: {d1: {flow: {y: 2}}, d2: {flow: {y: -1}}}\ninitial: {location: [d1, d2]}\n"
    )
    (tmp_path / "cd.yaml").write_text("system: cd\ncomponents: [{spec: c.yaml}, {spec: d.yaml}]\n")
    from hybrid.reach.witness import starting_in

    system = hybrid.load(tmp_path / "cd.yaml")
    late = hybrid.simulate(starting_in(system, ("c4", "d2")), 3.0, backend="compiled")
    early = hybrid.simulate(starting_in(system, ("c1", "d1")), 3.0, backend="compiled")
    assert (late["x"][-1], late["y"][-1]) == (0.0, pytest.approx(-3.0))
    assert (early["x"][-1], early["y"][-1]) == (pytest.approx(3.0), pytest.approx(6.0))
    assert early.location[-1] == "c.c1|d.d1"


def test_the_source_is_generated_once_per_structure(monkeypatch: pytest.MonkeyPatch) -> None:
    """The backend's choice, the compile notice and the compile each need the model's
    source: it is generated once, and again only for another structure."""
    from hybrid.simulation.native import choice, source

    made: list[Any] = []
    real = source.generate
    monkeypatch.setattr(source, "generate", lambda native: made.append(native) or real(native))
    monkeypatch.setattr(source, "_SOURCES", HeldCache(16))
    thermostat = hybrid.load(SPECS / "thermostat.yaml")
    choice.cached(thermostat)
    choice.compile_notice(thermostat)
    first = source.native_source(as_system(thermostat))
    variant = thermostat.with_parameters({"a": 0.2})  # another value: the same structure
    assert source.native_source(as_system(variant)) == first
    assert len(made) == 1
    restarted = thermostat.with_initial(location="on")  # another first mode: another structure
    assert source.native_source(as_system(restarted)) != first
    assert len(made) == 2 and made[1].system.initial_mode != made[0].system.initial_mode


ENSEMBLE_CTRL_C = """
import os, signal, threading
import numpy as np
import hybrid
th = hybrid.load({thermostat!r})
hybrid.simulate_many(th, t_end=10.0)  # compiled, warm
# the first run alone sizes the rows: a Ctrl-C while it runs ends every run
threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
one = hybrid.simulate_many(th, t_end=1e8, max_jumps=10**9)
print(sorted(set(one.causes.tolist())), bool(one.t[0] < 1e8))
# the first row switches 50 times, the others about 250,000 times: each outgrows the room
# the first sized and is run again alone (about 0.7 s each); a Ctrl-C during those ends
# the one in progress and every later one at once
rates = np.array([0.001] + [0.2] * 49)
threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT)).start()
many = hybrid.simulate_many(th, t_end=5e5, max_jumps=10**9, parameters={{"a": rates}}, threads=1)
print(len(many), len(many._alone), many.causes[0])
print(sorted({{run.termination.cause for run in many._alone.values()}}))
"""


def test_ctrl_c_during_an_ensemble_ends_its_runs_including_the_first_and_the_rerun() -> None:
    # a Ctrl-C while the first run sized the rows went unseen, and one while a row that
    # outgrew its room ran again alone raised KeyboardInterrupt with a traceback
    code = ENSEMBLE_CTRL_C.format(thermostat=str(REPO / "specs" / "thermostat.yaml"))
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=REPO, timeout=600)  # fmt: skip  (a hang guard: a cold compile)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "['interrupted'] True"
    assert lines[1] == "50 49 t_end"
    assert lines[2] in ("['interrupted']", "['interrupted', 't_end']"), lines[2]
