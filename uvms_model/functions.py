r"""The functions the UVMS specs call, registered under ``hybrid.functions``.

``pyproject.toml`` declares the entry point ``uvms_model = uvms_model.functions:registry``;
a spec says ``uses: [uvms_model]`` to call them. Every function takes and returns
plain floats (tuples for vector results, marked with ``hybrid_outputs``), because
the simulator calls them at every solver stage. Each formula has one implementation
elsewhere in the package (forward kinematics and the columns of N in
:mod:`uvms_model.chain`, the quintic law in :mod:`uvms_model.quintic`, the FM in
:mod:`uvms_model.functional_machine`); only the 3 x 3 solve has a fast scalar form
here (Cramer's rule) beside the numpy reference (:func:`uvms_model.chain.solve_partition`),
and the tests compare the two. ``uvms_resolve`` and ``uvms_sigma_min`` (the comparison's
baselines, :mod:`uvms_model.baselines`) are numpy functions with no compiled form.

The kinematic solves are Davies' method: the network matrix
:math:`N = [\$_x\ \$_y\ \$_\phi\ \$_{q1}\ \$_{q2}\ \$_{q3}\ -\$_{xe}\ -\$_{ye}\ -\$_{\phi e}]`
(columns in that order), :math:`N\Psi = 0` split into secondary and primary
columns, :math:`N_s \Psi_s = -N_p \Psi_p` solved by Cramer's rule.

Examples
--------
>>> q1d, q2d, q3d = uvms_q0(0, 0, 0, 0.3, 1.2, -0.4, 0, 0, 0, 0.1, 0.0, 0.0, 1, 1, 0.25, 0.5, 0)
>>> round(q1d + q2d + q3d, 12)   # end-effector heading rate 0, vehicle still
0.0
>>> sorted(registry())  # doctest: +NORMALIZE_WHITESPACE
['quintic', 'uvms_ee', 'uvms_fm', 'uvms_fm_rate', 'uvms_fm_raw', 'uvms_path', 'uvms_q0',
 'uvms_q0_acc', 'uvms_resolve', 'uvms_sigma_min', 'uvms_state3', 'uvms_state3_acc',
 'uvms_target', 'uvms_vehicle', 'uvms_vehicle_rate']
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from functools import lru_cache
from typing import Any

from uvms_model.baselines import uvms_resolve, uvms_sigma_min
from uvms_model.chain import (
    joint_point_rates,
    joint_points,
    network_column_rates,
    network_columns,
)
from uvms_model.functional_machine import (
    functional_machine,
    functional_machine_output,
    functional_machine_rate,
)
from uvms_model.paths import DeformedCircle, oval_geometry, path_state
from uvms_model.quintic import quintic_state, transition_target
from uvms_model.vehicle import limited_velocity, limited_velocity_rate

__all__ = [
    "SINGULAR_TOL",
    "path_formula",
    "quintic",
    "registry",
    "uvms_ee",
    "uvms_fm",
    "uvms_fm_rate",
    "uvms_fm_raw",
    "uvms_path",
    "uvms_q0",
    "uvms_q0_acc",
    "uvms_state3",
    "uvms_state3_acc",
    "uvms_target",
    "uvms_vehicle",
    "uvms_vehicle_rate",
]

SINGULAR_TOL = 1e-9
"""``|det Ns|`` below which a solve is refused as singular (ValueError)."""

Column = tuple[float, float, float]


def uvms_ee(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[float, float, float]:
    """End-effector pose ``(xe, ye, phie)`` by forward kinematics (:func:`joint_points`)."""
    pose = joint_points(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    return pose[6], pose[7], pose[8]


def _columns(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[Column, ...]:
    """The nine columns of N (:func:`network_columns` at :func:`joint_points`)."""
    p1x, p1y, p2x, p2y, p3x, p3y, ex, ey, _ = joint_points(
        x, y, phi, q1, q2, q3, a1, a2, a3, bx, by
    )
    return network_columns(x, y, (p1x, p1y), (p2x, p2y), (p3x, p3y), (ex, ey))


_PACK = struct.Struct("11d").pack
_LAST_COLUMNS: list[tuple[bytes, tuple[Column, ...]]] = [(b"", ())]
"""The configuration (its eleven doubles, bit for bit) and columns :func:`_shared_columns` last computed."""


def _shared_columns(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[Column, ...]:
    """:func:`_columns`, kept for the configuration last asked for.

    At a stored point the signals ask for the same configuration's columns up to three
    times (the state-3 rates, the state-3 and the joint accelerations). The key is the
    arguments' bits as doubles (a zero of the other sign is another configuration); one
    tuple is stored at once, so a thread never reads a key with another's columns.
    """
    key = _PACK(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    last_key, last_columns = _LAST_COLUMNS[0]
    if key == last_key:
        return last_columns
    cols = _columns(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    _LAST_COLUMNS[0] = (key, cols)
    return cols


def _det3(a: Column, b: Column, c: Column) -> float:
    return (
        a[0] * (b[1] * c[2] - b[2] * c[1])
        - b[0] * (a[1] * c[2] - a[2] * c[1])
        + c[0] * (a[1] * b[2] - a[2] * b[1])
    )


def _singular(det: float) -> tuple[float, float, float]:
    """A singular ``Ns``: ValueError here, NaNs in the compiled form (:mod:`uvms_model.compiled`)."""
    raise ValueError(f"kinematic singularity: |det Ns| = {abs(det):.3g}")


def _solve(
    columns: tuple[Column, ...],
    secondary: tuple[int, int, int],
    primary: tuple[float, ...],
    bias: Column = (0.0, 0.0, 0.0),
) -> tuple[float, float, float]:
    """Cramer's rule for ``Ns Psi_s = -(Np Psi_p + bias)``.

    ``primary`` holds the nine magnitudes in column order, 0 in the secondary places.
    """
    r0, r1, r2 = -bias[0], -bias[1], -bias[2]
    for k in range(9):
        col = columns[k]
        value = primary[k]
        r0 -= col[0] * value
        r1 -= col[1] * value
        r2 -= col[2] * value
    a, b, c = columns[secondary[0]], columns[secondary[1]], columns[secondary[2]]
    det = _det3(a, b, c)
    if abs(det) < SINGULAR_TOL:
        return _singular(det)
    r = (r0, r1, r2)
    return _det3(r, b, c) / det, _det3(a, r, c) / det, _det3(a, b, r) / det


def uvms_q0(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    xd: float,
    yd: float,
    phid: float,
    xed: float,
    yed: float,
    phied: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[float, float, float]:
    """Location q0: joint rates ``(q1d, q2d, q3d)`` from vehicle and end-effector rates."""
    cols = _columns(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    return _solve(cols, (3, 4, 5), (xd, yd, phid, 0.0, 0.0, 0.0, xed, yed, phied))


def uvms_state3(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    xed: float,
    yed: float,
    phied: float,
    phid: float,
    q1d: float,
    q3d: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[float, float, float]:
    """Kinematic state 3 (location q1): ``(xd, yd, q2d)`` from the other six rates."""
    cols = _shared_columns(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    return _solve(cols, (0, 1, 4), (0.0, 0.0, phid, q1d, 0.0, q3d, xed, yed, phied))


def _acceleration_setup(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    xd: float,
    yd: float,
    phid: float,
    q1d: float,
    q2d: float,
    q3d: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[tuple[Column, ...], Column]:
    """Columns of N and the bias ``N' Psi`` of the second-order closure."""
    cols = _shared_columns(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    p1xd, p1yd, p2xd, p2yd, p3xd, p3yd, exd, eyd = joint_point_rates(
        x, y, phi, q1, q2, q3, xd, yd, phid, q1d, q2d, q3d, a1, a2, a3, bx, by
    )
    rates = network_column_rates(xd, yd, (p1xd, p1yd), (p2xd, p2yd), (p3xd, p3yd), (exd, eyd))
    psi = (xd, yd, phid, q1d, q2d, q3d, exd, eyd, phid + q1d + q2d + q3d)
    b0 = b1 = b2 = 0.0
    for k in range(9):
        col = rates[k]
        b0 += col[0] * psi[k]
        b1 += col[1] * psi[k]
        b2 += col[2] * psi[k]
    return cols, (b0, b1, b2)


def uvms_q0_acc(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    xd: float,
    yd: float,
    phid: float,
    q1d: float,
    q2d: float,
    q3d: float,
    xdd: float,
    ydd: float,
    phidd: float,
    xedd: float,
    yedd: float,
    phiedd: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[float, float, float]:
    """Location q0 (and q2): joint accelerations ``(q1dd, q2dd, q3dd)``.

    From the configuration, the six rates of the chain and the accelerations of the
    primary magnitudes (vehicle and end effector), by the second-order closure
    ``Ns Psi_s' = -(Np Psi_p' + N' Psi)`` (:mod:`uvms_model.chain`).
    """
    cols, bias = _acceleration_setup(
        x, y, phi, q1, q2, q3, xd, yd, phid, q1d, q2d, q3d, a1, a2, a3, bx, by
    )
    primary = (xdd, ydd, phidd, 0.0, 0.0, 0.0, xedd, yedd, phiedd)
    return _solve(cols, (3, 4, 5), primary, bias)


def uvms_state3_acc(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    xd: float,
    yd: float,
    phid: float,
    q1d: float,
    q2d: float,
    q3d: float,
    phidd: float,
    q1dd: float,
    q3dd: float,
    xedd: float,
    yedd: float,
    phiedd: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[float, float, float]:
    """Kinematic state 3 (location q1): accelerations ``(xdd, ydd, q2dd)``.

    From the configuration, the six rates of the chain and the accelerations of the
    primary magnitudes (heading, q1, q3, end effector).
    """
    cols, bias = _acceleration_setup(
        x, y, phi, q1, q2, q3, xd, yd, phid, q1d, q2d, q3d, a1, a2, a3, bx, by
    )
    primary = (0.0, 0.0, phidd, q1dd, 0.0, q3dd, xedd, yedd, phiedd)
    return _solve(cols, (0, 1, 4), primary, bias)


@lru_cache(maxsize=64)
def _check_path(
    turns: float,
    off_x: float,
    off_y: float,
    sx: float,
    sy: float,
    duration: float,
    epsilon: float,
    heading: float,
    direction: float,
) -> None:
    """Refuse a path :class:`DeformedCircle` refuses (ValueError), once per geometry."""
    DeformedCircle((sx, sy), (off_x, off_y), turns, duration, epsilon, 0.0, 1, heading)


def path_formula(
    t: float,
    turns: float,
    off_x: float,
    off_y: float,
    sx: float,
    sy: float,
    duration: float,
    epsilon: float,
    heading: float,
    direction: float,
    follow: float = 0.0,
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """:func:`uvms_path` without the checks of its arguments (its compiled form)."""
    theta_s, big_r = oval_geometry(off_x, off_y, epsilon, 0.0)
    laps = turns if direction >= 0 else -turns
    return path_state(
        t, 0.0, duration, laps, theta_s, 0.0, big_r, epsilon, sx + off_x, sy + off_y, heading, follow
    )


def uvms_path(
    t: float,
    turns: float,
    off_x: float,
    off_y: float,
    sx: float,
    sy: float,
    duration: float,
    epsilon: float,
    heading: float,
    direction: float,
    follow: float = 0.0,
) -> tuple[float, ...]:
    """Commanded end effector on the mission path (:class:`uvms_model.paths.DeformedCircle`).

    Returns ``(xe, ye, phie, vxe, vye, wphie, axe, aye, dwphie)``; ``direction`` >= 0
    runs counter-clockwise, < 0 clockwise; ``follow`` 1 turns the heading with the path.
    """
    _check_path(turns, off_x, off_y, sx, sy, duration, epsilon, heading, direction)
    return path_formula(
        t, turns, off_x, off_y, sx, sy, duration, epsilon, heading, direction, follow
    )


def uvms_fm(gamma: float, theta_p: float, gamma_min: float, ramp: float = 0.0) -> float:
    """Functional machine output s >= 0 (tanh units; :func:`functional_machine_output`)."""
    return functional_machine_output(gamma, theta_p, gamma_min, "tanh", ramp)


def uvms_fm_raw(gamma: float, theta_p: float, gamma_min: float) -> float:
    """Functional machine's hidden sum before the output unit (negative: the FM rests)."""
    return functional_machine(gamma, theta_p, gamma_min, "tanh")


def uvms_fm_rate(
    gamma: float,
    gamma_dot: float,
    theta_p: float,
    theta_dot: float,
    gamma_min: float,
    ramp: float = 0.0,
) -> float:
    """Rate of :func:`uvms_fm` (:func:`uvms_model.functional_machine.functional_machine_rate`)."""
    return functional_machine_rate(gamma, gamma_dot, theta_p, theta_dot, gamma_min, "tanh", ramp)


def uvms_vehicle(cx: float, cy: float, v_max: float) -> tuple[float, float]:
    """Vehicle velocity: the command ``s alpha v_E`` under the smooth speed limit."""
    return limited_velocity(cx, cy, v_max)


def uvms_vehicle_rate(
    cx: float, cy: float, cx_dot: float, cy_dot: float, v_max: float
) -> tuple[float, float]:
    """Vehicle acceleration: the rate of :func:`uvms_vehicle`."""
    return limited_velocity_rate(cx, cy, cx_dot, cy_dot, v_max)


def uvms_target(p_i: float, gamma_j: float) -> float:
    """Eq. 9's final position ``alpha_j p_i`` (:func:`uvms_model.quintic.transition_target`)."""
    return transition_target(p_i, gamma_j)


def quintic(
    t: float, t0: float, p0: float, v0: float, a0: float, duration: float, pf: float
) -> tuple[float, float, float]:
    """Quintic law (eq. 9) from ``(p0, v0, a0)`` at ``t0`` to ``(pf, 0, 0)`` at ``t0 + duration``.

    Returns ``(p, v, a)`` by :func:`uvms_model.quintic.quintic_state` (held at
    ``(pf, 0, 0)`` after the end).
    """
    return quintic_state(t, t0, p0, v0, a0, t0 + duration, pf)


def _mark(
    fn: Callable[..., Any], arity: int, outputs: int = 1, optional: int = 0
) -> Callable[..., Any]:
    fn.hybrid_arity = (arity - optional, arity)  # type: ignore[attr-defined]
    fn.hybrid_outputs = outputs  # type: ignore[attr-defined]
    # the compiled form, named so that only the compiled backend imports numba
    fn.hybrid_compiled = f"uvms_model.compiled:{fn.__name__}"  # type: ignore[attr-defined]
    return fn


def registry() -> dict[str, Callable[..., Any]]:
    """The functions of the ``uvms_model`` library, by the name specs call them."""
    return {
        "uvms_ee": _mark(uvms_ee, 11, 3),
        "uvms_q0": _mark(uvms_q0, 17, 3),
        "uvms_state3": _mark(uvms_state3, 17, 3),
        "uvms_q0_acc": _mark(uvms_q0_acc, 23, 3),
        "uvms_state3_acc": _mark(uvms_state3_acc, 23, 3),
        "uvms_path": _mark(uvms_path, 11, 9, optional=1),
        "uvms_fm": _mark(uvms_fm, 4, optional=1),
        "uvms_fm_raw": _mark(uvms_fm_raw, 3),
        "uvms_fm_rate": _mark(uvms_fm_rate, 6, optional=1),
        "uvms_vehicle": _mark(uvms_vehicle, 3, 2),
        "uvms_vehicle_rate": _mark(uvms_vehicle_rate, 5, 2),
        "uvms_target": _mark(uvms_target, 2),
        "quintic": _mark(quintic, 7, 3),
        # the comparison's baselines (numpy, no compiled form: scipy backend only)
        "uvms_resolve": _plain(uvms_resolve, 19, 5),
        "uvms_sigma_min": _plain(uvms_sigma_min, 11),
    }


def _plain(fn: Callable[..., Any], arity: int, outputs: int = 1) -> Callable[..., Any]:
    fn.hybrid_arity = (arity, arity)  # type: ignore[attr-defined]
    fn.hybrid_outputs = outputs  # type: ignore[attr-defined]
    return fn
