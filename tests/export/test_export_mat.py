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


NAMES = """
automaton: names
state:
  states: {initial: 1.0}
  _u: {initial: 2.0}
  end_time: {initial: 3.0}
  NAME_LONG: {initial: 4.0}
signals: {signals: 2 * states}
locations: {a: {flow: {states: 1, _u: 0, end_time: 0, NAME_LONG: 0}}}
""".replace("NAME_LONG", "v" * 70)


def test_every_column_is_in_the_mat_file_under_a_name_matlab_takes(tmp_path: Path) -> None:
    """A state named 'states' or 'signals' was overwritten by the matrix of that name, one
    starting with '_' left out (savemat drops it), and a name over 63 characters written
    as it is (MATLAB refuses it): silently, though the CSV had every column."""
    import warnings

    import pytest

    import hybrid
    from hybrid.errors import Note
    from hybrid.export.trajectory import write_mat

    run = hybrid.simulate(hybrid.load_text(NAMES), t_end=1.0)
    path = tmp_path / "names.mat"
    with pytest.warns(Note, match="'states' is states_, .*'_u' is x_u"):
        write_mat(run, path)
    back = loadmat(path)
    assert back["states"].shape == (len(run), 4)  # the matrix keeps its name
    for name, written in (("states", "states_"), ("_u", "x_u"), ("end_time", "end_time"),
                          ("v" * 70, "v" * 63), ("signals", "signals_")):  # fmt: skip
        assert np.array_equal(back[written][:, 0], run[name]), name
    assert all(len(key) <= 63 and key[0].isalpha() for key in back if not key.startswith("__"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # names MATLAB takes as they are: no note
        write_mat(hybrid.simulate(hybrid.load(SPECS / "bouncing_ball.yaml"), t_end=1.0), path)
