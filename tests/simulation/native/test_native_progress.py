"""Progress of a compiled run: read from the run's arrays while the loop runs on the worker."""

from __future__ import annotations

import threading

import pytest

import hybrid
from hybrid.progress import Status

pytest.importorskip("numba")

OSCILLATOR = """
automaton: oscillator
state: {x: {initial: 1.0}, y: {initial: 0.0}, c: {initial: 0.0}}
locations: {turning: {flow: {x: y, y: -x, c: 1}}}
edges: [{from: turning, to: turning, guard: "c >= 1", reset: {c: 0}}]
"""


@pytest.mark.parametrize("handle_sigint", [True, False])
def test_a_long_compiled_run_reports_progress_while_it_runs(handle_sigint: bool) -> None:
    # x = cos t and a clock reset every second: short steps (max_step) over a long
    # horizon make a run of a second or so;
    # reports come at most every 0.2 s, in time order, and the last is the end of the run
    model = hybrid.load_text(OSCILLATOR)
    seen: list[tuple[Status, bool]] = []

    def report(status: Status) -> None:
        seen.append((status, threading.current_thread() is threading.main_thread()))

    t_end = 1999.5
    run = hybrid.simulate(model, t_end=t_end, max_step=0.002, backend="compiled",
                          handle_sigint=handle_sigint, progress=report, max_jumps=10**6)  # fmt: skip
    assert run.termination.cause == "t_end"
    statuses = [s for s, _ in seen]
    assert all(main for _, main in seen)
    assert len(statuses) >= 2, "reported while running, not only at the end"
    done = [s.done for s in statuses]
    assert done == sorted(done) and 0.0 < done[0] < t_end
    final = statuses[-1]
    assert final.final and final.done == run.termination.t == t_end
    assert dict(final.counters) == {"jumps": len(run.jumps), "points": len(run)}
    # the counters grow with the run: a jump every second
    jumps = [dict(s.counters)["jumps"] for s in statuses]
    assert jumps == sorted(jumps) and jumps[-1] == len(run.jumps) == 1999
    for status in statuses[:-1]:  # the time reached and the jumps taken agree, to a second
        assert abs(dict(status.counters)["jumps"] - status.done) <= 1.0


def test_a_compiled_run_in_another_thread_reports_progress_there_while_it_runs() -> None:
    # the same run from a thread that is not the main one (a GUI's or a server's):
    # Ctrl-C is the main thread's, but progress comes while the loop runs, in the caller
    model = hybrid.load_text(OSCILLATOR)
    seen: list[tuple[Status, threading.Thread]] = []
    runs: list[hybrid.Run] = []

    def report(status: Status) -> None:
        seen.append((status, threading.current_thread()))

    def simulate() -> None:
        runs.append(hybrid.simulate(model, t_end=1999.5, max_step=0.002, backend="compiled",
                                    progress=report, max_jumps=10**6))  # fmt: skip

    caller = threading.Thread(target=simulate)
    caller.start()
    caller.join(timeout=120)
    (run,) = runs
    assert run.termination.cause == "t_end" and len(run.jumps) == 1999
    assert all(thread is caller for _, thread in seen)
    statuses = [s for s, _ in seen]
    assert len(statuses) >= 2 and 0.0 < statuses[0].done < 1999.5, "reported while running"
    assert [s.done for s in statuses] == sorted(s.done for s in statuses)
    assert statuses[-1].final and statuses[-1].done == 1999.5
