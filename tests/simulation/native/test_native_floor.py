"""The floor the compiled backend is measured against (bench/floor.py) meets the closed forms.

Its loop runs as plain Python here (``NUMBA_DISABLE_JIT=1`` in a fresh
interpreter): the same code numba compiles for the benchmark, checked in
milliseconds instead of a compile of many seconds.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]

_CODE = """
import json
import numpy as np
from bench import floor
ball_points, ball = floor.single(floor.BALL, np.array([9.81, 0.95]), np.array([10.0, 0.0]),
                                1e3, 40)
p = np.array([0.1, 10.0, 30.0, 18.0, 22.0])
thermo_points, thermo = floor.single(floor.THERMOSTAT, p, np.array([20.0]), 1e4, 20)
times, counts = floor.ensemble(p, np.array([20.0, 21.0]), 1e4, 3)
print(json.dumps({"ball": ball.tolist(), "thermo": thermo.tolist(), "many": times.tolist(),
                  "counts": counts.tolist(), "ball_end": ball_points[-1].tolist(),
                  "thermo_end": thermo_points[-1].tolist()}))
"""


def _floor() -> dict[str, list[list[float]]]:
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", _CODE], capture_output=True, text=True, env=env,
                         cwd=ROOT, check=True, timeout=120)  # fmt: skip
    result: dict[str, list[list[float]]] = json.loads(out.stdout.splitlines()[-1])
    return result


def test_floor_meets_the_closed_forms() -> None:
    got = _floor()
    # the ball: first impact at t1 = sqrt(2 h0 / g), then flights of 2 e^k t1; v := -e v
    t1, e = math.sqrt(2 * 10.0 / 9.81), 0.95
    impacts = [t1 * (1 + 2 * sum(e**i for i in range(1, k))) for k in range(1, 42)]
    ball = got["ball"]
    assert len(ball) == 40
    # as hybrid's max_jumps: the run ends at the 41st impact, located but not taken
    t_end, h_end, v_end = got["ball_end"]
    assert abs(t_end - impacts[40]) < 1e-9 and abs(h_end) < 1e-9 and v_end < 0
    for (t, h, v, h_after, v_after), exact in zip(ball, impacts[:40], strict=True):
        assert abs(t - exact) < 1e-9
        assert abs(h) < 1e-9 and h_after == 0.0 and v < 0 and v_after == -e * v
    # the thermostat: 20 -> 18 cooling, then 18 <-> 22 each in 10 ln(12/8)
    switches = [10 * math.log(10 / 8) + k * 10 * math.log(12 / 8) for k in range(21)]
    thermo = got["thermo"]
    assert len(thermo) == 20
    t_end, temperature = got["thermo_end"]  # the 21st switch, where the run ends
    assert abs(t_end - switches[20]) < 1e-6 and abs(temperature - 18.0) < 1e-8
    for k, ((t, before, _), exact) in enumerate(zip(thermo, switches[:20], strict=True)):
        assert abs(t - exact) < 1e-6
        assert abs(before - (18.0 if k % 2 == 0 else 22.0)) < 1e-8
    # the ensemble: each run as alone; from 21 the first switch is at 10 ln(11/8)
    assert got["counts"] == [3, 3]
    assert max(abs(a - b) for a, b in zip(got["many"][0], switches[:3], strict=True)) < 1e-8
    assert abs(got["many"][1][0] - 10 * math.log(11 / 8)) < 1e-8


_POINTER = """
import json
import numpy as np
from bench import floor, floor_pointer
cases = [(floor.BALL, np.array([9.81, 0.95]), np.array([10.0, 0.0]), 1e3, 40),
         (floor.THERMOSTAT, np.array([0.1, 10.0, 30.0, 18.0, 22.0]), np.array([20.0]), 1e4, 20)]
found = []
for kind, p, x0, t_end, jumps in cases:
    plain, behind = floor.single(kind, p, x0, t_end, jumps), floor_pointer.single(kind, p, x0, t_end, jumps)
    found.append([[a.tolist() for a in plain], [a.tolist() for a in behind]])
print(json.dumps(found))
"""


def test_the_floor_with_its_model_behind_a_pointer_is_the_floor() -> None:
    """bench/floor_pointer.py: the floor's code, the model called through its address.

    Its points and jumps must be the floor's, bit for bit (the same arithmetic in
    the same order), or its time says nothing about the pointer. Compiled (the
    pointer is numba's), so it needs the ``fast`` extra.
    """
    pytest.importorskip("numba")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", _POINTER], capture_output=True, text=True, env=env,
                         cwd=ROOT, check=True, timeout=600)  # fmt: skip
    for (plain_points, plain_jumps), (points, jumps) in json.loads(out.stdout.splitlines()[-1]):
        assert len(plain_jumps) in (20, 40)
        assert jumps == plain_jumps and points == plain_points
