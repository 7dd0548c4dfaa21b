"""``--out traj.mat`` and ``write_mat``: the trajectory as MATLAB loads it.

Read back with scipy's ``loadmat`` (what MATLAB's ``load`` gives): the same points
as the CSV of the same run, columns as ``ode45`` returns them, and the first
bounce of the ball where the closed form puts it (t = sqrt(2 h0 / g), two rows).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.io import loadmat
from support import SPECS, assert_no_traceback, read_csv, run_cli

FLAGS = ("--t-end", "2", "--rtol", "1e-10", "--atol", "1e-12")


def test_the_mat_file_holds_the_run_as_matlab_reads_it(tmp_path: Path) -> None:
    mat, csv = tmp_path / "ball.mat", tmp_path / "ball.csv"
    for out in (mat, csv):
        done = run_cli("simulate", SPECS / "bouncing_ball.yaml", *FLAGS, "--out", out)
        assert done.returncode == 0, done.stderr
    back = loadmat(mat)
    _, rows = read_csv(csv)
    n = len(rows)
    assert back["t"].shape == (n, 1) and back["j"].shape == (n, 1)
    assert back["states"].shape == (n, 2) and back["signals"].shape == (n, 1)
    for name in ("t", "j", "h", "v", "energy"):
        assert np.array_equal(back[name][:, 0], [float(r[name]) for r in rows]), name
    assert [s.strip() for s in back["state_names"]] == ["h", "v"]
    assert {s.strip() for s in back["location"]} == {"falling"}
    first = math.sqrt(2 * 10.0 / 9.81)
    at_jump = np.flatnonzero(np.isclose(back["t"][:, 0], first, rtol=0, atol=1e-9))
    assert at_jump.size == 2 and list(back["j"][at_jump, 0]) == [0.0, 1.0]


def test_another_suffix_is_refused(tmp_path: Path) -> None:
    done = run_cli("simulate", SPECS / "bouncing_ball.yaml", *FLAGS, "--out", tmp_path / "x.txt")
    assert done.returncode == 2
    assert_no_traceback(done.stderr)
    assert "--out: use a .csv, .npz or .mat file name" in done.stderr
