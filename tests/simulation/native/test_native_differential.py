"""Differential property: generated models of every structure run alike on both backends.

A seeded generator writes systems of one to three automata, each its own
structure (so each is compiled): clocks and affine flows, guards that are
thresholds, equalities at levels exact in binary (so that the events of
several components fall on the very same instants), conjunctions, invariants,
resets, priorities, urgent locations, labels shared by components (they jump
together or not at all) and signals one component defines and another reads
in its guards. The scipy backend and the compiled one must take the same
jumps, in the same order, at the same times (1e-9), with the same choices
at each instant (which edges were enabled, and why one was chosen), and end
alike (:func:`support.assert_backends_agree`).

``make test`` runs :data:`MODELS` of them; ``make fuzz`` (``HYBRID_FUZZ=1``)
:data:`FUZZ_MODELS`; ``HYBRID_DIFF_MODELS=N`` runs the first N.
"""

from __future__ import annotations

import os
import random

import pytest
from support import assert_backends_agree

import hybrid

pytest.importorskip("numba")

MODELS = 6
FUZZ_MODELS = 1000
SEED = 20261126
COUNT = int(os.environ.get("HYBRID_DIFF_MODELS", "0")) or (FUZZ_MODELS if os.environ.get("HYBRID_FUZZ") else MODELS)

LEVELS = ("0.5", "1", "1.5", "2", "3", "-1", "0")
RATES = ("1", "2", "0.5", "-1", "0")
T_END = 6.8
"""Off the grid of multiples of 1/4 where events of clocks with these rates and levels fall."""


class Writer:
    """One generated system: its components' YAML texts, from ``random.Random(seed)``."""

    def __init__(self, seed: int) -> None:
        self.rng = random.Random(seed)
        self.size = self.rng.choice((1, 2, 2, 3))
        self.labels = ("sync", "go")[: self.rng.choice((0, 1, 2))] if self.size > 1 else ()
        self.signals = self.size > 1 and self.rng.random() < 0.6

    def level(self) -> str:
        return self.rng.choice(LEVELS)

    def guard(self, k: int) -> str:
        rng = self.rng
        x, y = f"x{k}", f"y{k}"
        atoms = [
            f"{x} >= {self.level()}",
            f"{x} <= {self.level()}",
            f"{x} == {self.level()}",
            f"{y} >= {self.level()}",
            f"{y} == {self.level()}",
        ]
        if self.signals:
            other = (k % self.size) + 1
            atoms.append(f"s{other} >= {self.level()}")
        first = rng.choice(atoms)
        if rng.random() < 0.3:
            return f"{first} and {rng.choice(atoms)}"
        if rng.random() < 0.1:
            return f"{first} or {rng.choice(atoms)}"
        return first

    def component(self, k: int) -> str:
        rng = self.rng
        x, y = f"x{k}", f"y{k}"
        count = rng.choice((2, 3))
        lines = [
            f"automaton: c{k}",
            f"state: {{{x}: {{initial: {rng.choice(('0', '0.5', '1'))}}}, {y}: {{initial: 0}}}}",
        ]
        if self.signals:
            lines.append(f"signals: {{s{k}: {x} + {y}}}")
            others = [f"s{j}" for j in range(1, self.size + 1) if j != k]
            lines.append(f"inputs: [{', '.join(others)}]")
        if self.labels:
            lines.append(f"labels: [{', '.join(self.labels)}]")
        lines.append("locations:")
        for i in range(count):
            if rng.random() < 0.75:
                flow = f"{{{x}: {rng.choice(RATES)}, {y}: 1}}"
            else:
                flow = f"{{{x}: -0.5*{x} + {rng.choice(('1', '2', '-1'))}, {y}: 1}}"
            extra = ""
            if i > 0 and rng.random() < 0.1:
                extra += ", urgent: true"
            elif rng.random() < 0.25:
                extra += f", invariant: '{y} <= {rng.choice(('2', '3', '4'))}'"
            lines.append(f"  L{i}: {{flow: {flow}{extra}}}")
        lines.append("edges:")
        for e in range(rng.choice((2, 3, 4))):
            source, target = rng.randrange(count), rng.randrange(count)
            parts = [f"name: e{e}", f"from: L{source}", f"to: L{target}", f"guard: '{self.guard(k)}'"]
            reset = rng.choice(("", f"{y}: 0", f"{x}: 0, {y}: 0", f"{x}: {x} - 1"))
            if reset:
                parts.append(f"reset: {{{reset}}}")
            if rng.random() < 0.3:
                parts.append(f"priority: {rng.choice((1, 2))}")
            if self.labels and rng.random() < 0.35:
                parts.append(f"label: {rng.choice(self.labels)}")
            lines.append(f"  - {{{', '.join(parts)}}}")
        return "\n".join(lines) + "\n"

    def model(self) -> hybrid.Automaton | hybrid.System:
        texts = [self.component(k) for k in range(1, self.size + 1)]
        automata = [hybrid.load_text(text) for text in texts]
        if len(automata) == 1:
            return automata[0]
        return hybrid.compose(*automata, names=[f"c{k}" for k in range(1, self.size + 1)])


@pytest.mark.fuzz
@pytest.mark.parametrize("index", range(COUNT))
def test_a_generated_model_runs_alike_on_both_backends(index: int) -> None:
    model = Writer(SEED + index).model()
    reference, compiled = assert_backends_agree(model, t_end=T_END, max_jumps=60)
    assert [(j.enabled, j.chosen_by) for j in compiled.jumps] == [
        (j.enabled, j.chosen_by) for j in reference.jumps
    ]
    assert compiled.termination.j == reference.termination.j
    assert abs(compiled.termination.t - reference.termination.t) <= 1e-9
