"""The guarantee, tested: every simulated state lies in a set of its location and time.

For every model of ``specs/``, ``tests/data`` and the shared external models that
reach accepts (affine ones; the others are refused with a SpecError, which is
asserted to name a place in a file), random runs start at points of the
initial set with piecewise-constant inputs within their ranges, simulated with
tight tolerances; every stored point ``(t, x)`` in location ``L`` must lie in
some set of ``L`` whose time interval holds ``t``, with ``x`` within the set's
box, up to 1e-9 relative. In the suite: 200 runs per model, fewer for a costly one
(:func:`_plan`); under ``make fuzz`` (``HYBRID_FUZZ=1``): 10,000 runs of every model over
its full horizon and jumps. The flowpipe is computed once per model; the runs are
simulated in two forked processes (each run from its own seeded generator, so the
same runs whichever process takes them) and their points checked against the sets
of their location at once (the sets whose time interval starts last before the point,
then every set for the few points left).
"""

from __future__ import annotations

import atexit
import hashlib
import multiprocessing
import os
import shutil
import tempfile
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from support import REPO

import hybrid
from hybrid.compose import as_system
from hybrid.errors import SpecError, UsageError
from hybrid.interchange import import_spaceex
from hybrid.simulation.inputs import PiecewiseConstant

EXTERNAL = REPO.parent / "shared" / "external-models"
"""The field's models, beside the repository as in CI (none there: only the repo's own)."""
T_END = 2.0
LARGE = 40
"""Models with more state variables than this are sampled over ``T_END_LARGE``."""
T_END_LARGE = 0.5
MAX_JUMPS = 6
STEP = 0.01
TOL = 1e-9


def _sources() -> list[tuple[str, Path, Path | None]]:
    found: list[tuple[str, Path, Path | None]] = []
    for spec in sorted((REPO / "specs").glob("*.yaml")):
        found.append((spec.name, spec, None))
    roots = (
        REPO / "tests" / "data" / "spaceex",
        *(EXTERNAL / d for d in ("spaceex", "hyst", "arch")),
    )
    for root in roots:
        for xml in sorted(root.glob("*/*.xml")):
            for cfg in sorted(xml.parent.glob("*.cfg")):
                if cfg.stem == xml.stem or cfg.stem.startswith(xml.stem.split("_flattened")[0]):
                    found.append((f"{xml.parent.name}/{cfg.name}", xml, cfg))
    return found


def _load(tmp: Path, source: Path, cfg: Path | None) -> hybrid.Automaton | hybrid.System | None:
    if cfg is None:
        return hybrid.load(source)
    try:
        result = import_spaceex(source, cfg)
    except SpecError:
        return None  # the importer refuses it (the interchange tests say why)
    tmp.mkdir(parents=True, exist_ok=True)
    for name, text in result.files.items():
        (tmp / name).write_text(text)
    try:
        return hybrid.load(tmp / result.top)
    except SpecError:
        return None  # an import gap, tested by the interchange tests


FUZZ = os.environ.get("HYBRID_FUZZ", "0") not in ("", "0")
POINTS = 600
"""In the suite, a model whose nominal run stores more points than this over its horizon
is sampled over a horizon that many points long (at least an eighth of it)."""
RUN_POINTS = 20_000
"""In the suite, a model is sampled by 200 runs, or by as many as store about this many
points in all (at least :data:`MIN_RUNS`), judged by one sampled run."""
MIN_RUNS = 40
FEW_JUMPS = 4
BRANCHING = 10_000
"""In the suite, a model whose flowpipe over :data:`FEW_JUMPS` jumps already holds more sets
than this is sampled (runs and flowpipe) up to that many jumps."""
# Measured on a 2-core machine before these limits: the 200 runs of the four costliest
# models (motor 0.53 s a run of 1,567 points, Building 0.92 s, ISS 0.64 s) and Fischer's
# flowpipe over 6 jumps (144,609 sets, 82 s; 22,961 over 4 jumps, 10 s) took 448 s of the
# suite's 16 minutes. ``make fuzz`` samples every model in full.


def _runs() -> int:
    return 10_000 if FUZZ else 200


def _sampled_run(
    model: hybrid.Automaton | hybrid.System,
    t_end: float,
    rng: np.random.Generator,
    max_jumps: int = MAX_JUMPS,
) -> tuple[hybrid.Run, dict[str, float]]:
    """One run from a random initial point, each bounded input piecewise constant at random."""
    system = as_system(model)
    initial = {v: float(rng.uniform(r.lo, r.hi)) for v, r in system.initial_set().items()}
    given = {}
    for name, r in system.input_ranges().items():
        starts = np.concatenate([[0.0], np.sort(rng.uniform(0.0, t_end, 3))])
        given[name] = PiecewiseConstant(starts, rng.uniform(r.lo, r.hi, 4))
    for name in (n for n in system.free_inputs if n not in system.input_ranges()):
        given[name] = PiecewiseConstant(np.zeros(1), np.zeros(1))
    run = hybrid.simulate(model, t_end, max_jumps=max_jumps, rtol=1e-10, atol=1e-12,
                          initial=initial, inputs=given, handle_sigint=False)  # fmt: skip
    return run, initial


def _plan(model: hybrid.Automaton | hybrid.System, seed: int) -> tuple[float, int]:
    """The sampled horizon and number of runs: the model's full horizon and :func:`_runs`,
    both cut in the suite for a costly model (judged by one sampled run over the full
    horizon)."""
    t_end = T_END if len(model.state_names) <= LARGE else T_END_LARGE
    if FUZZ:
        return t_end, _runs()
    probe, _ = _sampled_run(model, t_end, np.random.default_rng(seed))
    if len(probe) > POINTS:
        t_end = max(t_end / 8, t_end * POINTS / len(probe))
        probe, _ = _sampled_run(model, t_end, np.random.default_rng(seed))
    return t_end, max(MIN_RUNS, min(_runs(), RUN_POINTS // max(1, len(probe))))


def _flowpipe(
    model: hybrid.Automaton | hybrid.System, t_end: float
) -> tuple[hybrid.ReachResult, int]:
    """The flowpipe the runs are checked against, and the jumps both stop at."""
    if not FUZZ:
        few = hybrid.reach(model, t_end, max_jumps=FEW_JUMPS, step=STEP, witness=False)
        if len(few.sets) > BRANCHING:
            return few, FEW_JUMPS
    return hybrid.reach(model, t_end, max_jumps=MAX_JUMPS, step=STEP, witness=False), MAX_JUMPS


def _accepted(tmp: Path) -> list[tuple[str, hybrid.Automaton | hybrid.System]]:
    seen: set[str] = set()
    models = []
    for name, source, cfg in _sources():
        model = _load(tmp / hashlib.sha1(name.encode()).hexdigest()[:8], source, cfg)
        if model is None:
            continue
        try:
            result = hybrid.reach(model, 0.1, max_jumps=0, step=0.01, witness=False)
        except SpecError as exc:
            assert exc.line >= 1 and ("not affine" in exc.message or "condition" in exc.message)
            continue
        except UsageError:
            continue  # bounds that overflow at this step: not a model to sample here
        key = hashlib.sha1(repr((model.state_names, len(result.sets), name.split("/")[0])).encode())
        if key.hexdigest() in seen:
            continue
        seen.add(key.hexdigest())
        models.append((name, model))
    return models


class _Sets:
    """One location's sets, sorted by the start of their time interval."""

    def __init__(self, times: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> None:
        order = np.argsort(times[:, 0], kind="stable")
        self.times, self.lo, self.hi = times[order], lo[order], hi[order]

    def outside(self, t: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Which points ``(t[i], x[i])`` lie in no set whose time interval holds ``t[i]``."""
        slack_t = TOL * np.maximum(1.0, np.abs(t))
        pad = TOL * np.maximum(1.0, np.abs(x))
        left = np.ones(len(t), dtype=bool)
        # first the sets that start last at or before t, and the one before (a step's end)
        last = np.searchsorted(self.times[:, 0], t + slack_t, side="right") - 1
        for k in (last, last - 1):
            k = np.clip(k, 0, len(self.times) - 1)
            holds = (self.times[k, 0] - slack_t <= t) & (t <= self.times[k, 1] + slack_t)
            inside = np.all((self.lo[k] - pad <= x) & (x <= self.hi[k] + pad), axis=1)
            left &= ~(holds & inside)
        for i in np.flatnonzero(left):  # the rest against every set (overlapping flowpipes)
            near = (self.times[:, 0] - slack_t[i] <= t[i]) & (t[i] <= self.times[:, 1] + slack_t[i])
            box = np.all(
                (self.lo[near] - pad[i] <= x[i]) & (x[i] <= self.hi[near] + pad[i]), axis=1
            )
            left[i] = not box.any()
        return left


WORKERS = max(1, min(2, os.cpu_count() or 1))
"""Processes the runs are simulated in (forked: they share the parent's models and sets)."""
CHUNK = 50
"""Runs per task given to a worker."""


def _chunk(
    name: str,
    t_end: float,
    max_jumps: int,
    sets: dict[str, _Sets],
    seed: int,
    first: int,
    count: int,
) -> tuple[int, list[str]]:
    """Runs ``first .. first + count - 1`` of model ``name``: stored points and escapes.

    Run ``k`` draws from its own generator (``seed``, ``k``): the same runs whichever
    worker simulates them.
    """
    model = MODELS[name]
    points = 0
    problems: list[str] = []
    for k in range(first, first + count):
        run, initial = _sampled_run(model, t_end, np.random.default_rng([seed, k]), max_jumps)
        points += len(run)
        locations = run.location.astype(str)
        for loc in np.unique(locations):
            here = np.flatnonzero(locations == loc)
            found = sets.get(str(loc))
            left = here if found is None else here[found.outside(run.t[here], run.states[here])]
            problems.extend(
                f"run {k}: t={run.t[i]!r} {loc} x={run.states[i].tolist()} initial={initial}"
                for i in left
            )
    return points, problems


def _escapes(
    name: str, seed: int, progress: Callable[[int, int, int], None] | None = None
) -> tuple[int, int, list[str]]:
    """Sampled runs of model ``name`` against its sets (:func:`_plan`): runs, points, escapes."""
    model = MODELS[name]
    t_end, runs = _plan(model, seed)
    result, max_jumps = _flowpipe(model, t_end)
    sets: dict[str, _Sets] = {}
    for loc in {s.location for s in result.sets}:
        chosen = [s for s in result.sets if s.location == loc]
        sets[loc] = _Sets(
            np.array([s.t for s in chosen]),
            np.array([s.lo for s in chosen]),
            np.array([s.hi for s in chosen]),
        )
    tasks = [
        (name, t_end, max_jumps, sets, seed, k, min(CHUNK, runs - k)) for k in range(0, runs, CHUNK)
    ]
    done = points = 0
    problems: list[str] = []

    def add(count: int, found: tuple[int, list[str]]) -> None:
        nonlocal done, points
        done += count
        points += found[0]
        problems.extend(found[1])
        if progress is not None:
            progress(done, points, len(problems))

    if WORKERS == 1:
        for task in tasks:
            add(task[-1], _chunk(*task))
    else:
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(WORKERS, mp_context=context) as pool:
            futures = [(task[-1], pool.submit(_chunk, *task)) for task in tasks]
            for count, future in futures:
                add(count, future.result())
    return done, points, problems


def _import_folder() -> Path:
    """A folder of this process's own for the imported specs, removed at its exit: processes
    that collect the suite at once (pytest's workers) each write and load their own."""
    folder = Path(tempfile.mkdtemp(prefix="hybrid-reach-models-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


ACCEPTED = _accepted(_import_folder())
MODELS = dict(ACCEPTED)


def test_reach_accepts_the_affine_models() -> None:
    names = {n for n, _ in ACCEPTED}
    assert "bouncing_ball.yaml" in names and "thermostat.yaml" in names
    assert any(n.startswith("filtered_oscillator") for n in names)
    assert any(n.startswith("circle") for n in names)


@pytest.mark.fuzz
@pytest.mark.parametrize("name", list(MODELS))
def test_every_simulated_state_is_in_a_set(name: str) -> None:
    runs, points, problems = _escapes(name, seed=24)
    assert runs >= MIN_RUNS and points >= runs
    assert not problems, f"{len(problems)} escapes, first: {problems[:3]}"
