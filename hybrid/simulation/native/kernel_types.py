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
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "Array",
    "Array2",
    "Array3",
    "Fns",
    "Ints",
    "Ints2",
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
