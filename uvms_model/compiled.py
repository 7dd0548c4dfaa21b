"""The compiled forms of the ``uvms_model`` functions (numba), for ``backend="compiled"``.

Imported only by the compiled backend, through the ``hybrid_compiled`` attribute
that :mod:`uvms_model.functions` sets to ``"uvms_model.compiled:<name>"`` (a
string, so that ``import uvms_model`` never imports numba). Nothing here is a
second implementation: the module marks the package's own functions as numba
compilable (:func:`numba.extending.register_jitable`), so that numba compiles
the one implementation of each formula when the compiled model calls it. Only
the error paths differ: where the Python form raises ``ValueError`` (a
singular ``Ns``, a quintic with ``tf <= t0``), the compiled form returns NaN
(the quintic: wherever it reads the law's coefficients),
which the compiled backend reports as an evaluation failure at that point. The
compiled ``uvms_path`` does not check its geometry arguments (the Python form
refuses a bad one): check a model with the scipy backend first.

Examples
--------
>>> from uvms_model import compiled, functions
>>> compiled.quintic(0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0) == functions.quintic(
...     0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0)
True
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from typing import Any

from numba import njit
from numba.extending import overload, register_jitable

import uvms_model.chain as _chain
import uvms_model.functions as _functions
import uvms_model.indices as _indices
import uvms_model.paths as _paths
import uvms_model.screws as _screws
import uvms_model.vehicle as _vehicle

# the package exports functions of these names: take the modules themselves
_fm = importlib.import_module("uvms_model.functional_machine")
_quintic = importlib.import_module("uvms_model.quintic")

__all__ = [
    "quintic",
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

_OPTIONS: Any = {"error_model": "numpy"}

_HELPERS: tuple[Callable[..., Any], ...] = (
    _screws.revolute,
    _chain.joint_points,
    _chain.network_columns,
    _chain.joint_point_rates,
    _chain.network_column_rates,
    _quintic.quintic_coefficients,
    _quintic._evaluate,
    _quintic.quintic_state,
    _quintic.transition_target,
    _indices.alpha,
    _indices.w_hat,
    _fm.sigmoid,
    _fm._activate,
    _fm._slope,
    _fm.functional_machine_units,
    _fm.functional_machine,
    _fm.smooth_ramp,
    _fm.functional_machine_output,
    _fm.functional_machine_rate,
    _vehicle.limited_velocity,
    _vehicle.limited_velocity_rate,
    _paths.oval_geometry,
    _paths.path_state,
    _functions._columns,
    _functions._det3,
    _functions._solve,
    _functions._acceleration_setup,
)

for _helper in _HELPERS:
    register_jitable(**_OPTIONS)(_helper)


@overload(_functions._singular, jit_options=_OPTIONS)
def _singular_nan(det: float) -> Callable[[float], tuple[float, float, float]]:
    def nan3(det: float) -> tuple[float, float, float]:
        return math.nan, math.nan, math.nan

    return nan3


@overload(_quintic._bad_duration, jit_options=_OPTIONS)
def _bad_duration_nan(t0: float, tf: float) -> Callable[[float, float], float]:
    def nan(t0: float, tf: float) -> float:
        return math.nan

    return nan


@overload(_functions._shared_columns, jit_options=_OPTIONS)
def _shared_columns_each_time(
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
) -> Callable[..., Any]:
    # the compiled form computes the columns at each call (the kept ones are the Python's)
    def columns(
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
    ) -> Any:
        return _functions._columns(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)

    return columns


@overload(_fm._unknown_activation, jit_options=_OPTIONS)
def _unknown_activation_nan(activation: str) -> Callable[[str], float]:
    def nan(activation: str) -> float:
        return math.nan

    return nan


def _compiled(fn: Callable[..., Any]) -> Any:
    # not cached by numba: it would not notice a change of the helpers (the model's cache does)
    return njit(nogil=True, error_model="numpy")(fn)


uvms_ee = _compiled(_functions.uvms_ee)
uvms_q0 = _compiled(_functions.uvms_q0)
uvms_state3 = _compiled(_functions.uvms_state3)
uvms_q0_acc = _compiled(_functions.uvms_q0_acc)
uvms_state3_acc = _compiled(_functions.uvms_state3_acc)
uvms_path = _compiled(_functions.path_formula)
uvms_fm = _compiled(_functions.uvms_fm)
uvms_fm_raw = _compiled(_functions.uvms_fm_raw)
uvms_fm_rate = _compiled(_functions.uvms_fm_rate)
uvms_vehicle = _compiled(_functions.uvms_vehicle)
uvms_vehicle_rate = _compiled(_functions.uvms_vehicle_rate)
uvms_target = _compiled(_functions.uvms_target)
quintic = _compiled(_functions.quintic)
