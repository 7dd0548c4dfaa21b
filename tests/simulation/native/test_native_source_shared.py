"""A model's generated operations compute the same with what their cases share written once.

:func:`hybrid.simulation.native.source._shared` moves the lines every case of an
operation runs alike before the dispatch, and ``_alike`` writes cases that are
alike once, and ``_hoisted`` loads each slot once before the dispatch (UVMS:
6,300 generated lines become 2,500, and its first compile takes half the time).
The truth here is the module generated as before, each case loading the slots it
reads, nothing shared: both are imported as plain Python (not compiled) and every
operation, at every index, is called at random points; the outputs must be the
same bit for bit.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support import REPO, import_source

import hybrid
from hybrid.compose import as_system
from hybrid.simulation.native import buffers, source
from hybrid.simulation.native.structure import NativeModel

pytest.importorskip("numba")

OPERATIONS = {"model_rhs": "OP_RHS", "model_outputs": "OP_OUTPUTS", "model_value": "OP_VALUE",
              "model_truth": "OP_TRUTH", "model_reset": "OP_RESET", "model_watch": "OP_WATCH",
              "model_arm": "OP_ARM"}  # fmt: skip
"""Each operation's function (a large model's) and its code in ``model``'s dispatch."""
RING = """
automaton: th{i}
state: {{T{i}: {{initial: 19.0}}}}
signals: {{p{i}: 0}}
inputs: [p{j}]
locations:
  off: {{flow: {{T{i}: -0.1*(T{i} - 10) + 0.05*p{j}}}, invariant: T{i} >= 18}}
  on: {{flow: {{T{i}: 0.1*(30 - T{i}) + 0.05*p{j}}}, signals: {{p{i}: 1}}, invariant: T{i} <= 22}}
edges:
  - {{name: heat, from: off, to: on, guard: T{i} <= 18, reset: {{T{i}: T{i} + 0.0}}}}
  - {{name: rest, from: on, to: off, guard: T{i} >= 22}}
"""


def _loads_in_each_case(
    cases: list[list[str]], hoisted: Callable[..., Any] = source._hoisted
) -> tuple[list[str], list[list[str]]]:
    """Each case loading the slots it reads itself, as the generator did before."""
    each = []
    for case in cases:
        loads, (read,) = hoisted([case])
        each.append(loads + read)
    return [], each


def _models() -> dict[str, hybrid.System]:
    ring = hybrid.compose(*[hybrid.load_text(RING.format(i=i, j=(i - 1) % 3)) for i in range(3)])
    return {
        "uvms_mission_2": as_system(hybrid.load(REPO / "specs" / "uvms_mission_2.yaml")),
        "thermostat": as_system(hybrid.load(REPO / "specs" / "thermostat.yaml")),
        "ring of 3": ring,
    }


@pytest.mark.parametrize("name", ["uvms_mission_2", "thermostat", "ring of 3"])
def test_every_operation_computes_what_it_computed_unshared(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    native = NativeModel(_models()[name])
    shared = source.generate(native).source
    with monkeypatch.context() as patch:
        patch.setattr(source, "_hoisted", _loads_in_each_case)
        patch.setattr(source, "_shared", lambda cases: ([], cases))
        patch.setattr(source, "_alike", source._dispatch)
        unshared = source.generate(native).source
    assert shared != unshared
    if name == "uvms_mission_2":
        assert shared.count("\n") < 0.5 * unshared.count("\n")
    tag = "".join(c for c in name if c.isalnum())
    ours = import_source(tmp_path / f"hybrid_probe_shared_{tag}.py", shared)
    theirs = import_source(tmp_path / f"hybrid_probe_unshared_{tag}.py", unshared)
    for module in (ours, theirs):  # `model` as plain Python, its arrays passed as themselves
        module.carray = lambda array, shape: array
    if name in ("thermostat", "uvms_mission_2"):  # a small model's operations are in `model`
        assert ("def model_rhs(" in shared) == (name == "uvms_mission_2")
    rng = random.Random(name)
    n_states = len(native.state_names)
    for _ in range(4):
        x = np.array([rng.uniform(-1.5, 1.5) for _ in range(max(1, n_states))])
        p = np.array([rng.uniform(0.2, 1.5) for _ in range(400)])
        t = rng.uniform(0.0, 30.0)
        for op, code in OPERATIONS.items():
            # every case, and the index past the last, which returns the fallback
            for index in range(_cases(unshared, op, code) + 1):
                a, b = np.full(400, -7.0), np.full(400, -7.0)
                got = ours.model(getattr(buffers, code), index, t, x, p, a)
                expected = theirs.model(getattr(buffers, code), index, t, x, p, b)
                assert a.tobytes() == b.tobytes(), (op, index)
                assert np.array([got], dtype=float).tobytes() == np.array([expected], dtype=float).tobytes()


def _cases(unshared: str, op: str, code: str) -> int:
    """How many cases ``op`` has in a module generated unshared (one comparison fewer)."""
    if f"def {op}(" in unshared:
        text = unshared.split(f"def {op}(")[1].split("\ndef ")[0]
    else:  # written into `model`'s branch for its code
        text = unshared.split(f"op == {code}:")[1].split("op == OP_")[0]
    return text.count(" < ") + 1


def test_a_line_is_shared_only_when_what_it_reads_is_shared_too() -> None:
    # y reads a, which the cases define apart: y's line is alike in both, yet stays in each
    cases = [["a = x[0]", "y = a * 2.0", "z = x[1]", "out[0] = y + z"],
             ["a = x[1]", "y = a * 2.0", "z = x[1]", "out[0] = y + z"]]  # fmt: skip
    shared, rest = source._shared(cases)
    assert shared == ["z = x[1]"]
    assert rest == [["a = x[0]", "y = a * 2.0", "out[0] = y + z"],
                    ["a = x[1]", "y = a * 2.0", "out[0] = y + z"]]  # fmt: skip


def test_returns_and_cases_that_define_a_name_twice_are_left_as_they_are() -> None:
    assert source._shared([["a = 1.0", "return a"], ["a = 1.0", "return a"]]) == (
        ["a = 1.0"], [["return a"], ["return a"]])  # fmt: skip
    twice = [["a = 1.0", "a = a + 1.0", "out[0] = a"], ["a = 1.0", "out[0] = a"]]
    assert source._shared(twice) == ([], twice)
