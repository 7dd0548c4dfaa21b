"""Witnesses: concrete simulated runs into a forbidden set, searched from the flowpipe's hint.

For an affine flow the reachable set's support in a direction ``d`` at a step
point ``T`` is attained by a concrete run: the initial point at the corner of
the initial box that ``e^{A^T T} d`` points to, and the input at the corner of
its box that ``(Phi1 B)^T e^{A^T (T - t_{i+1})} d`` points to on each step
``[t_i, t_{i+1}]`` (bang-bang, piecewise constant; Le Guernic and Girard's
support function is a sum of such maxima). :func:`support_candidate` builds
that run for the direction in which a forbidden case is met; it is simulated
with :func:`hybrid.simulate` and kept only if a stored point of the run lies in
the forbidden set (:func:`reaches`). Other candidates (the nominal run, the
corners of the initial box, a few seeded random runs) are tried the same way.

The inputs are held piecewise constant
(:class:`~hybrid.simulation.inputs.PiecewiseConstant`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.errors import HybridError
from hybrid.model import Automaton
from hybrid.reach.affine import Condition, Forms
from hybrid.reach.flowpipe import exp_matrices
from hybrid.simulation.engine import simulate
from hybrid.simulation.inputs import PiecewiseConstant
from hybrid.simulation.result import Run

__all__ = [
    "Candidate",
    "bisect_entry",
    "corner_candidates",
    "inside",
    "random_candidates",
    "reaches",
    "simulate_candidate",
    "support_candidate",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Candidate:
    """A run to try: its initial state and inputs, and the time to simulate until."""

    initial: dict[str, float]
    inputs: dict[str, Callable[[float], float]]
    t_end: float
    how: str
    location: tuple[str, ...] | None = None
    """The initial location of each component (None: the model's first initial mode)."""


def support_candidate(
    forms: Forms,
    a: Array,
    b: Array,
    x_lo: Array,
    x_hi: Array,
    direction: Array,
    h: float,
    steps: int,
) -> Candidate:
    """The run maximising ``direction . x(steps * h)`` over the initial box and step-wise inputs."""
    phi, phi1, _ = exp_matrices(a, h)
    gain = phi1 @ b
    w = direction.copy()
    coefs = np.zeros((steps, b.shape[1]))
    for i in range(steps - 1, -1, -1):
        coefs[i] = gain.T @ w
        w = phi.T @ w
    x0 = np.where(w > 0.0, x_hi, x_lo)
    starts = np.arange(steps, dtype=np.float64) * h
    inputs: dict[str, Callable[[float], float]] = {}
    for j, name in enumerate(forms.inputs):
        values = np.where(coefs[:, j] > 0.0, forms.u_hi[j], forms.u_lo[j])
        inputs[name] = PiecewiseConstant(starts, values)
    names = forms.system.state_names
    initial = {v: float(x0[i]) for i, v in enumerate(names)}
    return Candidate(initial, inputs, steps * h, "support")


def corner_candidates(forms: Forms, x_lo: Array, x_hi: Array, t_end: float) -> list[Candidate]:
    """The nominal run and the two extreme corners of the initial box, inputs at their ends."""
    names = forms.system.state_names
    found = []
    nominal = dict(zip(names, forms.system.initial_vector(), strict=True))
    found.append(Candidate(nominal, {}, t_end, "nominal"))
    for side, point, inputs in (("low", x_lo, forms.u_lo), ("high", x_hi, forms.u_hi)):
        found.append(
            Candidate(
                {v: float(point[i]) for i, v in enumerate(names)},
                {
                    n: PiecewiseConstant(np.zeros(1), np.array([inputs[j]]))
                    for j, n in enumerate(forms.inputs)
                },
                t_end,
                f"{side} corner",
            )
        )
    return found


def random_candidates(
    forms: Forms, x_lo: Array, x_hi: Array, t_end: float, count: int, seed: int = 24
) -> list[Candidate]:
    """``count`` seeded random runs: initial points in the box, inputs switching 4 times."""
    rng = np.random.default_rng(seed)
    names = forms.system.state_names
    found = []
    for k in range(count):
        point = rng.uniform(x_lo, x_hi)
        starts = np.concatenate([[0.0], np.sort(rng.uniform(0.0, max(t_end, 0.0), 4))])
        inputs: dict[str, Callable[[float], float]] = {
            n: PiecewiseConstant(starts, rng.uniform(forms.u_lo[j], forms.u_hi[j], 5))
            for j, n in enumerate(forms.inputs)
        }
        initial = {v: float(point[i]) for i, v in enumerate(names)}
        found.append(Candidate(initial, inputs, t_end, f"random sample {k + 1}"))
    return found


def simulate_candidate(
    model: Automaton | System, forms: Forms, candidate: Candidate, max_jumps: int
) -> Run | None:
    """The simulated run of ``candidate`` (``None`` if the simulator refuses it)."""
    inputs: dict[str, Callable[[float], float]] = dict(candidate.inputs)
    for name in forms.unbounded:
        inputs.setdefault(name, PiecewiseConstant(np.zeros(1), np.zeros(1)))
    if candidate.location is not None and candidate.location != _initial_mode(model):
        model = starting_in(model, candidate.location)  # a model of its own: compiled again
    try:
        return simulate(
            model,
            candidate.t_end,
            max_jumps=max_jumps,
            rtol=1e-9,
            atol=1e-12,
            initial=candidate.initial,
            inputs=inputs,
            handle_sigint=False,
            dense=True,  # where the run enters the set, between its stored points
        )
    except HybridError:
        return None


def _initial_mode(model: Automaton | System) -> tuple[str, ...]:
    return (model.initial_location,) if isinstance(model, Automaton) else model.initial_mode


def starting_in(model: Automaton | System, location: tuple[str, ...]) -> Automaton | System:
    """``model`` with each component starting in its location of ``location``."""
    if isinstance(model, Automaton):
        return model.with_initial(location[0])
    parts = tuple(
        replace(c, automaton=c.automaton.with_initial(name))
        for c, name in zip(model.components, location, strict=True)
    )
    return replace(model, components=parts)


BETWEEN = 8
"""Parts each interval between two stored points of a witness is cut into, to find a visit of
the forbidden set that leaves it again before the next point (the run's interpolant)."""


def reaches(run: Run, forms: Forms, conditions: Mapping[str, Condition]) -> float | None:
    """The time ``run`` enters the forbidden set, or ``None`` if it is not seen in it.

    ``conditions`` gives the entry's condition per mode name (``run.location``) of
    the modes in the entry's locations (a location may define the signals it
    reads its own way); a point is in the set when its mode is one of them and
    every row of one case holds as written, a strict row strictly: a point on the
    boundary of ``x > 1``, or a hair below ``x >= 1 + 5e-10``, is not a witness.
    The run is looked at in its stored points and, with its dense output, at
    :data:`BETWEEN` parts of each interval between them (a visit between two
    points counts); the time is where the interpolant enters the set, bisected
    after the last point seen outside it (in the same stay), else the first
    stored point's in the set.
    """
    locations = [str(loc) for loc in run.location.tolist()]
    points = np.column_stack([run.states, run.t])
    hits = np.zeros(len(points), dtype=bool)
    for name, condition in conditions.items():
        here = np.array([loc == name for loc in locations], dtype=bool)
        if here.any():
            hits |= here & inside(points, condition)
    first = int(np.argmax(hits)) if hits.any() else len(points)
    sampled = _sampled_entry(run, locations, conditions, first)
    if sampled is not None:
        return bisect_entry(*sampled)
    if first == len(points):
        return None
    t = float(run.t[first])
    if first == 0 or run.j[first] != run.j[first - 1]:
        return t
    curve = next((c for j, t0, t1, c in run.segments if j == run.j[first]
                  and t0 <= run.t[first - 1] and t <= t1), None)  # fmt: skip
    if curve is None:
        return t
    return bisect_entry(float(run.t[first - 1]), t, conditions[locations[first]], curve)


def _sampled_entry(
    run: Run, locations: list[str], conditions: Mapping[str, Condition], upto: int
) -> tuple[float, float, Condition, Callable[[float], Array]] | None:
    """The first interval between stored points before point ``upto`` whose interpolant is in
    the set at one of its :data:`BETWEEN` parts: ``(outside, inside, condition, curve)``, the
    last time seen outside and the first seen inside; None if there is none."""
    for j, t0, t1, curve in run.segments:
        rows = np.flatnonzero((run.j[:upto] == j) & (run.t[:upto] >= t0) & (run.t[:upto] <= t1))
        if len(rows) < 2 or locations[rows[0]] not in conditions:
            continue
        condition = conditions[locations[rows[0]]]
        starts, ends = run.t[rows[:-1]], run.t[rows[1:]]
        parts = np.arange(1, BETWEEN) / BETWEEN
        times = (starts[:, None] + (ends - starts)[:, None] * parts[None, :]).ravel()
        states = np.asarray(curve(times), dtype=float).reshape(len(run.state_names), -1).T
        seen = inside(np.column_stack([states, times]), condition)
        if seen.any():
            k = int(np.argmax(seen))
            outside = float(times[k - 1]) if k % (BETWEEN - 1) else float(starts[k // (BETWEEN - 1)])
            return outside, float(times[k]), condition, curve
    return None


def bisect_entry(
    before: float, t: float, condition: Condition, curve: Callable[[float], Array]
) -> float:
    """Where ``curve`` (the state at a time, time left out) enters ``condition`` in
    ``(before, t]``: outside at ``before``, inside at ``t``."""
    for _ in range(200):
        middle = 0.5 * (before + t)
        if not before < middle < t:
            break
        point = np.append(np.asarray(curve(middle), dtype=float), middle)
        if inside(point[None, :], condition)[0]:
            t = middle
        else:
            before = middle
    return t


def inside(points: NDArray[np.float64], condition: Condition) -> NDArray[np.bool_]:
    """Which ``points`` (rows: state, then time) satisfy a case of ``condition`` exactly."""
    found = np.zeros(len(points), dtype=bool)
    for case in condition:
        found |= np.all(case.bound(points @ case.mat.T), axis=1)
    return found
