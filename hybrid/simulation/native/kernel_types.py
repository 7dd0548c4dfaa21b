"""The argument types of the kernel, named once for annotations and for numba.

Kernel functions are annotated with these names only (``Array``, ``Array2``,
``Ints``, ``Fns``, ``int``, ``float``, ``bool``, ``None`` and tuples of the
scalars); the generated kernel module turns each annotation into numba's
explicit signature (:func:`numba_signature`), so every function compiles once,
eagerly, for exactly these types (no specialisation per literal argument).

``Fns`` is the model: its five compiled functions as C function pointers
(numba first-class functions), so the kernel itself does not depend on the
model and is compiled once per machine:

- ``rhs(m, t, x*, p*, out*)``: ``out = dx/dt`` in mode ``m``;
- ``outputs(m, t, x*, p*, out*)``: every signal column in mode ``m``;
- ``value(f, t, x*, p*) -> float``: scalar form ``f`` (a rho, a level);
- ``truth(f, t, x*, p*) -> int``: boolean form ``f`` (1 holds, 0 not);
- ``reset(tr, t, x*, p*, out*)``: the state after global transition ``tr``;
- ``terms(m, t, x*, p*, out*)``: the watch's terms of mode ``m`` at once (each
  guard's rho, each equality level, each invariant's rho), one call a sample.

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
    "model_signatures",
    "numba_signature",
    "numba_types",
]

Array = NDArray[np.float64]
Array2 = NDArray[np.float64]
Array3 = NDArray[np.float64]
Ints = NDArray[np.int64]
Ints2 = NDArray[np.int64]
Fns = tuple[Callable[..., Any], ...]


def model_signatures() -> dict[str, Any]:
    """numba signatures of the model's functions: ``state`` (rhs, outputs, reset), ``value``, ``truth``."""
    import numba

    types: Any = numba.types
    pointer = types.CPointer(types.float64)
    return {
        "state": types.void(types.int64, types.float64, pointer, pointer, pointer),
        "value": types.float64(types.int64, types.float64, pointer, pointer),
        "truth": types.int64(types.int64, types.float64, pointer, pointer),
    }


def numba_types() -> dict[str, Any]:
    """The numba type of each annotation name (imports numba)."""
    import numba

    types: Any = numba.types
    signatures = model_signatures()
    state_fn = types.FunctionType(signatures["state"])
    value_fn = types.FunctionType(signatures["value"])
    truth_fn = types.FunctionType(signatures["truth"])
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
        "Fns": types.Tuple((state_fn, state_fn, value_fn, truth_fn, state_fn, state_fn)),
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
