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

from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["FRAME_PREFIX", "define"]

FRAME_PREFIX = "<hybrid:"
"""Start of the file name of every generated function's code object."""


def define(name: str, source: str, scope: Mapping[str, Any]) -> Callable[..., Any]:
    """Compile ``source``, run it in a fresh namespace built from ``scope``, return ``name``."""
    namespace: dict[str, Any] = {"__builtins__": {}, **scope}
    code = compile(source, f"{FRAME_PREFIX}{name}>", "exec")
    exec(code, namespace)  # the source is generated from checked IR (module docstring)
    function: Callable[..., Any] = namespace[name]
    return function
