"""The argument types of the kernel, named once for annotations and for numba.

Kernel functions are annotated with these names only (``Array``, ``Array2``,
``Ints``, ``Fns``, ``int``, ``float``, ``bool``, ``None`` and tuples of the
scalars); the generated kernel module turns each annotation into numba's
explicit signature (:func:`numba_signature`), so every function compiles once,
eagerly, for exactly these types (no specialisation per literal argument).

``Fns`` is the model: one compiled function, ``model(op, index, t, x*, p*,
out*) -> float``, passed as a C function pointer (a numba first-class
function), so the kernel itself does not depend on the model and is compiled
once per machine. By ``op`` (``OP_*`` of :mod:`~hybrid.simulation.native.buffers`):

- ``OP_RHS``, ``index`` a mode: ``out = dx/dt``;
- ``OP_OUTPUTS``, a mode: every signal column;
- ``OP_VALUE``, a form: returns the scalar form (a rho, an equality level);
- ``OP_TRUTH``, a form: returns 1.0 if the boolean form holds, else 0.0;
- ``OP_RESET``, a global transition: the state after it;
- ``OP_WATCH``, a mode: the watch's terms at once (each guard's oriented
  rho, then each invariant's rho), one call a sample;
- ``OP_ARM``, a mode: what arming reads (each guard's plain rho, then each
  equality level ``a - b`` of the mode's guards).

``p*`` is the run's parameter vector followed by the mode's level slots: the
sign of each equality level (its oriented reading) and its snap (-1 at the
level, +1 not), which the oriented and snapped forms read.

One function rather than six: each function pointer costs a load from the
cache and a conversion on every call from Python.

NaN from any of them is an evaluation failure (docs/semantics.md).

**Pieces.** The kernel is compiled as a few separate units, the *pieces*
(:data:`PIECES`: the integrator's step, the search of a step, the decisions
at a point, a stay, a run), which call each other through function pointers
(``StepFn``, ``SearchFn``, ``DecideFn``, ``StayFn``, ``RunFn``: numba
first-class functions, like the model). numba links the code of every
function a function calls into it and optimizes the whole again, so a call
tree of depth five compiled the deepest code five times; as pieces each is
compiled once. Python passes the addresses of the model and of the pieces in
one array (``fp``, slots ``FP_*``), which the run turns into functions
(:func:`~hybrid.simulation.native.pointers.function_at`; the names
``*_FN_T`` below are bound to the function types in the generated module).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "DECIDE_FN_T",
    "FUNCTION_TYPES",
    "MODEL_FN_T",
    "PIECES",
    "RUN_FN_T",
    "SEARCH_FN_T",
    "STAY_FN_T",
    "STEP_FN_T",
    "Array",
    "Array2",
    "Array3",
    "DecideFn",
    "Fns",
    "Ints",
    "Ints2",
    "RunFn",
    "SearchFn",
    "StayFn",
    "StepFn",
    "at",
    "function_at",
    "model_signature",
    "numba_signature",
    "numba_types",
]

Array = NDArray[np.float64]
Array2 = NDArray[np.float64]
Array3 = NDArray[np.float64]
Ints = NDArray[np.int64]
Ints2 = NDArray[np.int64]
Fns = Callable[..., float]
StepFn = Callable[..., tuple[bool, float, float, float]]
SearchFn = Callable[..., tuple[int, float, float]]
DecideFn = Callable[..., int]
StayFn = Callable[..., tuple[int, float, int]]
RunFn = Callable[..., None]

PIECES = (
    ("rk45_step", "StepFn"),
    ("first_event", "SearchFn"),
    ("decide", "DecideFn"),
    ("flow_stay", "StayFn"),
    ("run_one", "RunFn"),
)
"""The separately compiled pieces of the kernel and the names of their function types."""

FUNCTION_TYPES = (
    ("Fns", "MODEL_FN_T"),
    ("StepFn", "STEP_FN_T"),
    ("SearchFn", "SEARCH_FN_T"),
    ("DecideFn", "DECIDE_FN_T"),
    ("StayFn", "STAY_FN_T"),
    ("RunFn", "RUN_FN_T"),
)
"""Each function type and the global the kernel reads it from (bound in the generated module)."""

MODEL_FN_T: Any = None
STEP_FN_T: Any = None
SEARCH_FN_T: Any = None
DECIDE_FN_T: Any = None
STAY_FN_T: Any = None
RUN_FN_T: Any = None


def at(array: Any, index: int) -> Any:
    """Stand-in for :func:`hybrid.simulation.native.pointers.at` (numba's intrinsic)."""
    raise NotImplementedError("only in compiled code")


def function_at(c_address: int, jit_address: int, kind: Any) -> Any:
    """Stand-in for :func:`hybrid.simulation.native.pointers.function_at` (numba's intrinsic)."""
    raise NotImplementedError("only in compiled code")


def model_signature() -> Any:
    """numba's signature of the model's function ``model(op, index, t, x*, p*, out*) -> float``."""
    import numba

    types: Any = numba.types
    pointer = types.CPointer(types.float64)
    return types.float64(types.int64, types.int64, types.float64, pointer, pointer, pointer)


def numba_types() -> dict[str, Any]:
    """The numba type of each annotation name (imports numba)."""
    import numba

    types: Any = numba.types
    return {
        "int": types.int64,
        "float": types.float64,
        "bool": types.boolean,
        "None": types.void,
        "Array": types.float64[::1],
        "Array2": types.float64[:, ::1],
        "Array3": types.float64[:, :, ::1],
        "Ints": types.int64[::1],
        "Ints2": types.int64[:, ::1],
        "Fns": types.FunctionType(model_signature()),
    }


def numba_signature(annotations: dict[str, str], known: dict[str, Any]) -> Any:
    """numba's signature of a kernel function from its (string) annotations."""

    def of(text: str) -> Any:
        text = text.strip()
        if text.startswith("tuple[") and text.endswith("]"):
            import numba

            types: Any = numba.types
            return types.Tuple(tuple(of(part) for part in text[6:-1].split(",")))
        return known[text]

    args = [of(v) for k, v in annotations.items() if k != "return"]
    return of(annotations["return"])(*args)
