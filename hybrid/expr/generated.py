"""The one place generated Python source is compiled and run.

Generated source is built by this package from checked IR and fixed templates
only: user text never reaches it except as numbers and names that the parser
has accepted. It runs with no builtins; everything it may call is passed in
``scope``. The file name ``<hybrid:NAME>`` marks its frames in tracebacks
(the simulator reads the failing point from them).

Examples
--------
>>> double = define("double", "def double(x):\\n    return 2.0 * x\\n", {})
>>> double(21.0)
42.0
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from types import CodeType, FunctionType
from typing import Any

from hybrid.held import HeldCache

__all__ = ["FRAME_PREFIX", "define"]

FRAME_PREFIX = "<hybrid:"
"""Start of the file name of every generated function's code object."""


def define(name: str, source: str, scope: Mapping[str, Any]) -> Callable[..., Any]:
    """Compile ``source``, run it in a fresh namespace built from ``scope``, return ``name``.

    Functions defined with the same scope (the same names bound to the very same
    objects) share one namespace: the function is taken out of the namespace it
    was run in (generated code never calls itself by name), and the first such
    namespace serves the others. A large system keeps thousands of generated
    functions, most with one of a few scopes; each namespace is one more object
    that the cyclic garbage collector counts and follows.
    """
    namespace: dict[str, Any] = {"__builtins__": {}, **scope}
    code = _code(name, source)
    exec(code, namespace)  # the source is generated from checked IR (module docstring)
    function: Callable[..., Any] = namespace.pop(name)
    if len(namespace) != len(scope) + 1 or not isinstance(function, FunctionType):
        return function  # the source defined more than the function: its namespace is its own
    key = tuple(sorted((k, id(v)) for k, v in scope.items()))  # ids held alive by the namespace
    with _LOCK:
        shared = _SHARED.get(key)
        if shared is None:
            if len(_SHARED) >= _SHARED_MAX:
                del _SHARED[next(iter(_SHARED))]
            _SHARED[key] = namespace
            return function
    again = FunctionType(function.__code__, shared, function.__name__, function.__defaults__,
                         function.__closure__)  # fmt: skip
    again.__kwdefaults__ = function.__kwdefaults__
    return again


def _code(name: str, source: str) -> CodeType:
    """``source`` compiled, once per name and text: the variants of a sweep generate the
    same source for every function their changed parameters do not reach."""
    filename = f"{FRAME_PREFIX}{name}>"
    return _CODES.get((name, source), None, lambda: compile(source, filename, "exec"))


_CODES = HeldCache[CodeType](4096)
"""Compiled sources by function name and text."""
_SHARED: dict[tuple[tuple[str, int], ...], dict[str, Any]] = {}
"""A namespace per scope (by its names and the identities of their objects), oldest first."""
_SHARED_MAX = 256
_LOCK = threading.Lock()
