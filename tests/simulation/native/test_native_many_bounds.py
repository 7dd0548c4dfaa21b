"""``hybrid.simulate_many`` watches declared bounds as ``hybrid.simulate`` does.

The model climbs at known rates from known values on a 0.1 s grid (as in
tests/simulation/test_sim_bounds.py), so where each run leaves its bounds is known
by hand: h = h0 + 0.5 t passes 3 at t = 6 - 2 h0, first beyond one grid step later
(h = 3.05); v = v0 - 0.25 t passes -1 at t = 4 (v0 + 1), first beyond one step later
(v = -1.025); the only jump is at t = 2, so every excursion is at j = 1.

An ensemble warns once per variable, however many runs leave its bounds: the count
of those runs, and the first one's t and j.
"""

from __future__ import annotations

import warnings

import pytest
from support import LEAKY_SPEC

import hybrid

pytest.importorskip("numba")


# run 0 leaves h at 3.1 and v at 4.1; run 1 stays within; run 2 leaves h at 4.1 only
INITIAL = {"h": [1.5, 0.0, 1.0], "v": [0.0, 1.0, 1.0]}
EXPECTED = {
    0: [("h", 3.1, 1, 3.05), ("v", 4.1, 1, -1.025)],
    2: [("h", 4.1, 1, 3.05)],
}
WARNED = [
    "h left its declared bounds [0, 3] in 2 of 3 runs; the first, run 0, at t=3.1 j=1 (h = 3.05)",
    "v left its declared bounds [-1, 1] in 1 of 3 runs; the first, run 0, at t=4.1 j=1 "
    "(v = -1.025)",
]


def _many(**kwargs: object) -> tuple[hybrid.Ensemble, list[warnings.WarningMessage]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runs = hybrid.simulate_many(
            hybrid.load_text(LEAKY_SPEC), dt=0.1, handle_sigint=False, **kwargs  # type: ignore[arg-type]
        )
    return runs, [w for w in caught if issubclass(w.category, hybrid.BoundsWarning)]


def _as_tuples(excursions: object) -> list[tuple[str, float, int, float]]:
    return [(e.variable, e.t, e.j, e.value) for e in excursions]  # type: ignore[attr-defined]


def test_an_ensemble_warns_once_per_variable_with_the_count_and_the_first_run() -> None:
    runs, caught = _many(t_end=5.0, initial=INITIAL)
    assert list(runs.causes) == ["t_end"] * 3 and list(runs.n_jumps) == [1, 1, 1]
    assert [str(w.message) for w in caught] == WARNED
    assert caught[0].filename == __file__  # points at the caller's line
    assert sorted(runs.out_of_bounds) == sorted(EXPECTED)
    for i, expected in EXPECTED.items():
        found = _as_tuples(runs.out_of_bounds[i])
        assert [(name, j) for name, _, j, _ in found] == [(name, j) for name, _, j, _ in expected]
        assert [t for _, t, _, _ in found] == pytest.approx([t for _, t, _, _ in expected])
        assert [x for *_, x in found] == pytest.approx([x for *_, x in expected])
    assert [len(run.out_of_bounds) for run in runs] == [2, 0, 1]  # each Run says it too


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
def test_each_run_agrees_with_simulate_on_either_backend(backend: str) -> None:
    runs, _ = _many(t_end=5.0, initial=INITIAL)
    model = hybrid.load_text(LEAKY_SPEC)
    for i, run in enumerate(runs):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", hybrid.BoundsWarning)
            alone = hybrid.simulate(
                model, t_end=5.0, dt=0.1, initial={"h": INITIAL["h"][i], "v": INITIAL["v"][i]},
                backend=backend, handle_sigint=False,
            )  # fmt: skip
        assert [(e.variable, e.j) for e in run.out_of_bounds] == [
            (e.variable, e.j) for e in alone.out_of_bounds
        ]
        assert [e.t for e in run.out_of_bounds] == pytest.approx([e.t for e in alone.out_of_bounds])


def test_an_ensemble_within_its_bounds_says_nothing() -> None:
    runs, caught = _many(t_end=2.9, initial=INITIAL)  # h reaches at most 2.95, v -0.725
    assert caught == [] and runs.out_of_bounds == {}
    assert all(run.out_of_bounds == () for run in runs)


def test_a_run_rerun_alone_is_watched_too() -> None:
    # run 1 jumps every 0.1 s, far more than the first run: its row overflows and it is
    # run again alone; it climbs at 0.5 and passes 3 at t = 6, the first run never does
    text = """\
automaton: counter
parameters: {p: 5.0, r: 0.1}
state:
  h: {initial: 0.0, bounds: [0, 3]}
  c: {initial: 0.0}
locations:
  a: {flow: {h: r, c: 1}}
edges:
  - {from: a, to: a, guard: c >= p, reset: {c: 0}}
"""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runs = hybrid.simulate_many(
            hybrid.load_text(text), t_end=8.0, parameters={"p": [5.0, 0.1], "r": [0.1, 0.5]},
            handle_sigint=False,
        )  # fmt: skip
    assert list(runs.n_jumps) == [1, 80] and list(runs._alone) == [1]
    (excursion,) = runs.out_of_bounds[1]
    assert sorted(runs.out_of_bounds) == [1] and runs[1].out_of_bounds == (excursion,)
    # the first stored point after t = 6, before the 61st jump (at 6.1)
    assert excursion.variable == "h" and 6.0 < excursion.t <= 6.1 + 1e-9 and excursion.j == 60
    assert excursion.value == pytest.approx(0.5 * excursion.t, rel=1e-9)
    assert [str(w.message).split(";")[0] for w in caught] == [
        "h left its declared bounds [0, 3] in 1 of 2 runs"
    ]


def test_a_compiled_sweep_stays_quiet_as_a_scipy_one() -> None:
    # a campaign's runs are rows of a table: its batches of simulate_many do not warn
    model = hybrid.load_text(LEAKY_SPEC)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = hybrid.sweep(
            model, t_end=5.0, grid={"init.h": INITIAL["h"]}, workers=0, backend="compiled", dt=0.1
        )
    assert [row["cause"] for row in table.rows] == ["t_end"] * 3
    assert [w for w in caught if issubclass(w.category, hybrid.BoundsWarning)] == []
