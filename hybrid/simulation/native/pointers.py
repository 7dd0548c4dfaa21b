"""A numba first-class function from two addresses: how the kernel's pieces reach each other.

numba passes a first-class function argument from Python by asking Python
for its addresses on every call (unpickling the function's signature twice):
tens of microseconds per argument, as long as a short compiled run. The
compiled loop is called instead with one array of addresses (looked up once
per process: :func:`addresses`), and :func:`function_at` turns two of them
back into a function value inside compiled code: the address of the
function's C wrapper, and that of its compiled code (0 if it has none, as the
model's ``cfunc``), which numba calls directly.

Imported by the generated kernel modules only (it imports numba).

This is the one module that uses numba's private API: the fields of a
first-class function's data model (``c_addr``, ``jit_addr``, ``py_addr``) and
``numba.experimental.function_type._get_wrapper_address`` /
``_get_jit_address``. It was tested on the numba versions
:data:`TESTED_NUMBA` spans, and the ``fast`` extra is bounded to them
(``pyproject.toml``); ``tests/simulation/native/test_native_private_api.py``
fails, naming the version, on any other.
"""

from __future__ import annotations

from typing import Any

import numba.core.cgutils
import numba.experimental.function_type
import numba.extending

types: Any = numba.types
cgutils: Any = numba.core.cgutils
_function_type: Any = numba.experimental.function_type
intrinsic: Any = numba.extending.intrinsic

__all__ = ["TESTED_NUMBA", "addresses", "at", "function_at", "model_addresses"]

TESTED_NUMBA = ((0, 60), (0, 68))
"""The first and last numba ``(major, minor)`` this module's use of numba's private API is
tested on (the ``fast`` extra's ``numba>=0.60,<0.69``)."""


@intrinsic  # type: ignore[untyped-decorator]
def function_at(typingctx: Any, c_address: Any, jit_address: Any, kind: Any) -> Any:
    """The function of type ``kind`` (a numba ``FunctionType``) at these addresses."""
    function_type = kind.instance_type

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        value = cgutils.create_struct_proxy(function_type)(context, builder)
        pointer = context.get_value_type(types.voidptr)
        value.c_addr = builder.inttoptr(args[0], pointer)
        value.jit_addr = builder.inttoptr(args[1], pointer)
        value.py_addr = cgutils.get_null_value(pointer)
        return value._getvalue()

    return function_type(types.int64, types.int64, kind), codegen


@intrinsic  # type: ignore[untyped-decorator]
def at(typingctx: Any, array: Any, index: Any) -> Any:
    """A pointer to ``array[index]`` (a 1-d array), without touching its reference count.

    ``array.ctypes`` would increment and later decrement the array's reference
    count, an atomic operation each: in the model's hot calls that cost a
    quarter of a run.
    """
    pointer_type = types.CPointer(array.dtype)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        data = context.make_array(array)(context, builder, args[0]).data
        return builder.gep(data, [args[1]])

    return pointer_type(array, types.intp), codegen


def addresses(dispatcher: Any) -> tuple[int, int]:
    """``(C wrapper, compiled code)`` addresses of a dispatcher of one signature."""
    (arguments,) = dispatcher.signatures
    signature = dispatcher.overloads[arguments].signature
    return (
        int(_function_type._get_wrapper_address(dispatcher, signature)),
        int(_function_type._get_jit_address(dispatcher, signature)),
    )


def model_addresses(model: Any) -> tuple[int, int]:
    """``(C wrapper, compiled code)`` addresses of the model's ``cfunc``.

    The compiled loop calls the compiled code directly when it has its
    address (numba's calling convention, as between the kernel's pieces),
    which spares the C wrapper's call and conversions on every evaluation;
    0 if that code cannot be found (the wrapper is called then).
    """
    wrapper = str(model._wrapper_name or "")
    prefix = "cfunc."
    jit = 0
    if wrapper.startswith(prefix):
        try:
            jit = int(model._library.get_pointer_to_function(wrapper[len(prefix):]) or 0)
        except Exception:  # numba's internals moved: the wrapper, as before
            jit = 0
    return int(model.address), jit
