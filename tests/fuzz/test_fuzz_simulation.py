"""Generated models through ``simulate`` with every method: only user errors, no long runs.

A seeded generator writes automata and two-component systems from a grammar of
flows (with ``sqrt``, ``log``, division, powers, ``exp``, ``t`` and inputs),
guards (every comparison, equalities in all their spellings, ``and``, ``or``,
``not``, chains), invariants and resets. Each model is simulated; nothing but
:class:`hybrid.SimulationError` may escape, every run ends with a documented
cause and a consistent hybrid time, no warning is printed, and no run takes
longer than :data:`RUN_BUDGET_S` seconds of CPU (a watchdog turns a hang into a failure).

The size comes from the environment, so the suite stays quick and ``make fuzz``
runs the full campaign: ``HYBRID_FUZZ_MODELS`` models (default 60), each with
every method when ``HYBRID_FUZZ_ALL_METHODS=1`` (else one method each, in turn).
"""

from __future__ import annotations

import collections
import os
import random
import re
import signal
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

import hybrid
from hybrid.simulation import CAUSES, METHODS

MODELS = int(os.environ.get("HYBRID_FUZZ_MODELS", "60"))
ALL_METHODS = os.environ.get("HYBRID_FUZZ_ALL_METHODS", "0") == "1"
SEED = int(os.environ.get("HYBRID_FUZZ_SEED", "20240611"))
RUN_BUDGET_S = 10.0
"""Most CPU seconds a single run may take (CPU, not wall time: a loaded machine stretches the latter)."""
WATCHDOG_S = 60
"""A run still going after this long is stopped and reported as a hang."""

TERMS = [
    "x", "y", "t", "1", "0.5", "-2", "x*y", "sin(x)", "y - x", "x**2", "sqrt(x)", "log(y)",
    "1/x", "x/(y - 1)", "exp(x)", "sqrt(abs(y))", "log(1 + x*x)", "cos(t)", "-x", "2*y",
    "x**0.5", "atan(y)", "min(x, y)", "max(x, 0)", "abs(x - y)", "tanh(x)", "hypot(x, y)",
]  # fmt: skip
OPS = ["<", "<=", ">", ">=", "==", "!="]
LEVELS = ["0", "1", "0.5", "-1", "2"]


class Generator:
    """Random model text from a seeded ``random.Random``."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng

    def term(self, extra: tuple[str, ...] = ()) -> str:
        return self.rng.choice([*TERMS, *extra])

    def comparison(self, extra: tuple[str, ...] = ()) -> str:
        rng = self.rng
        kind = rng.random()
        var = rng.choice(["x", "y"])
        level = rng.choice(LEVELS)
        if kind < 0.15:
            return f"{var} == {level}"
        if kind < 0.22:
            return f"{var} >= {level} and {var} <= {level}"
        if kind < 0.27:
            return f"{level} <= {var} <= {level}"
        if kind < 0.35:
            return (
                f"{self.term(extra)} {rng.choice(OPS)} {self.term(extra)} {rng.choice(OPS)} {level}"
            )
        return f"{self.term(extra)} {rng.choice(OPS)} {self.term(extra)}"

    def condition(self, extra: tuple[str, ...] = ()) -> str:
        rng = self.rng
        text = self.comparison(extra)
        for _ in range(rng.choice([0, 0, 1, 2])):
            op = rng.choice(["and", "or"])
            other = self.comparison(extra)
            if rng.random() < 0.2:
                other = f"not ({other})"
            text = f"({text}) {op} ({other})"
        return text

    def automaton(
        self, name: str, states: tuple[str, str], extra: tuple[str, ...] = (), header: str = ""
    ) -> str:
        rng = self.rng
        x, y = states
        n = rng.randint(1, 3)
        locs = [f"L{i}" for i in range(n)]

        def rename(text: str) -> str:  # the grammar speaks of x and y
            return re.sub(r"\b[xy]\b", lambda m: x if m.group(0) == "x" else y, text)

        lines = [
            f"automaton: {name}",
            header,
            f"state: {{{x}: {{initial: {rng.choice([0, 1, -1, 0.5, 2])}}}, "
            f"{y}: {{initial: {rng.choice([0, 1, 2, -0.5])}}}}}",
            "locations:",
        ]
        for loc in locs:
            flow = f"{{{x}: '{rename(self.term(extra))}', {y}: '{rename(self.term(extra))}'}}"
            inv = "true" if rng.random() < 0.4 else rename(self.condition(extra))
            lines.append(f"  {loc}: {{flow: {flow}, invariant: '{inv}'}}")
        edges = []
        for _ in range(rng.randint(0, 4)):
            reset = rng.choice(
                ["{}", "{x: 0}", "{x: -x, y: y + 1}", "{y: 0.5*x}", "{x: sqrt(y)}", "{y: log(x)}",
                 "{x: 1/y}", "{x: x*2, y: -y}"]
            )  # fmt: skip
            label = rng.choice(["", "", ", label: sync"])
            edges.append(
                f"  - {{from: {rng.choice(locs)}, to: {rng.choice(locs)}, "
                f"guard: '{rename(self.condition(extra))}', reset: {rename(reset)}, "
                f"priority: {rng.randint(0, 1)}{label}}}"
            )
        if edges:
            lines += ["edges:", *edges]
        if any("label: sync" in e for e in edges):
            lines.insert(2, "labels: [sync]")
        return "\n".join(line for line in lines if line) + "\n"

    def model(self) -> tuple[hybrid.Automaton | hybrid.System, str]:
        """A model and its text (a system's two component texts, one after the other)."""
        if self.rng.random() < 0.75:
            text = self.automaton("fuzz", ("x", "y"))
            return hybrid.load_text(text), text
        left = self.automaton("left", ("x", "y"), header="signals: {s: 'x - y'}")
        right = self.automaton("right", ("p", "q"), extra=("s",), header="inputs: [s]")
        system = hybrid.compose(hybrid.load_text(left), hybrid.load_text(right))
        return system, f"{left}---\n{right}"


class Hang(Exception):
    """A run went on past the watchdog."""


@contextmanager
def watchdog(seconds: int) -> Iterator[None]:
    if sys.platform == "win32":
        yield
        return

    def alarm(signum: int, frame: object) -> None:
        raise Hang(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def cases() -> Iterator[tuple[int, hybrid.Automaton | hybrid.System, str, list[str]]]:
    gen = Generator(random.Random(SEED))
    made = 0
    while made < MODELS:
        try:
            model, text = gen.model()
        except hybrid.SpecError:
            continue  # the grammar can write a spec the reader refuses (a clash): not a case
        methods = list(METHODS) if ALL_METHODS else [METHODS[made % len(METHODS)]]
        yield made, model, text, methods
        made += 1


@pytest.mark.filterwarnings("error")  # a warning would reach the user's terminal
def test_generated_models_end_with_a_named_cause_in_time() -> None:
    causes: collections.Counter[str] = collections.Counter()
    slowest = (0.0, "")
    runs, refused = 0, 0
    started = time.perf_counter()
    for index, model, text, methods in cases():
        for method in methods:
            where = f"model {index} (seed {SEED}), method {method}:\n{text}"
            t0 = time.process_time()
            try:
                with watchdog(WATCHDOG_S):
                    run = hybrid.simulate(
                        model,
                        t_end=3.0,
                        max_jumps=50,
                        max_jumps_per_instant=20,
                        method=method,
                        handle_sigint=False,
                    )
            except hybrid.SimulationError:
                refused += 1
                continue
            except Hang:
                pytest.fail(f"hang: {where}")
            except Exception as exc:  # anything else escaping is a bug
                pytest.fail(f"{type(exc).__name__}: {exc}\n{where}")
            elapsed = time.process_time() - t0
            runs += 1
            slowest = max(slowest, (elapsed, where))
            term = run.termination
            causes[term.cause] += 1
            assert term.cause in CAUSES, where
            assert len(run.t) == len(run.j) == len(run.location) >= 1, where
            assert run.t[-1] <= 3.0 + 1e-9, where
            steps = set((run.j[1:] - run.j[:-1]).tolist())
            assert steps <= {0, 1}, where
            assert all(run.t[1:] >= run.t[:-1]), where
            assert len(run.jumps) == int(run.j[-1]), where
    total = time.perf_counter() - started
    print(
        f"\nfuzz: {MODELS} models, {runs} runs ({refused} refused as SimulationError), "
        f"methods {'all' if ALL_METHODS else 'in turn'}, {total:.1f} s, slowest run "
        f"{slowest[0]:.2f} s of CPU; causes {dict(causes)}"
    )
    assert slowest[0] <= RUN_BUDGET_S, f"a run took {slowest[0]:.1f} s of CPU: {slowest[1]}"
