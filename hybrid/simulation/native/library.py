"""Where the compiled form of a library function is imported from.

A library gives a function a compiled form by its ``hybrid_compiled``
attribute (see docs/backends.md): a top-level function of an importable module,
a numba dispatcher of one, or the name ``"package.module:function"`` of one,
so that only the compiled backend imports that module (and numba).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from hybrid.errors import UsageError

__all__ = ["importable"]


def importable(name: str, impl: Callable[..., object] | str) -> tuple[str, str]:
    """``(module, name)`` that import ``impl``, a top-level function or numba dispatcher.

    ``impl`` may also name one, as ``"package.module:function"``: the library's
    module of compiled forms is then imported by the compiled backend only.
    """
    if isinstance(impl, str):
        return _named(name, impl)
    py = getattr(impl, "py_func", impl)
    module, qualname = getattr(py, "__module__", None), getattr(py, "__qualname__", "")
    found = None
    if module and qualname.isidentifier():
        try:
            found = getattr(importlib.import_module(module), qualname, None)
        except ImportError:
            found = None
    if found is not impl and getattr(found, "py_func", None) is not py:
        raise UsageError(
            f"the compiled form of library function '{name}' must be a top-level function "
            f"of an importable module (got {impl!r})"
        )
    assert module is not None
    return module, qualname


def _named(name: str, reference: str) -> tuple[str, str]:
    """``(module, name)`` of a compiled form named ``"package.module:function"``."""
    module, _, qualname = reference.partition(":")
    if not (qualname.isidentifier() and all(p.isidentifier() for p in module.split("."))):
        raise UsageError(
            f"the compiled form of library function '{name}' must be a function or "
            f"'package.module:function' (got {reference!r})"
        )
    try:
        found = getattr(importlib.import_module(module), qualname, None)
    except ImportError as exc:
        raise UsageError(
            f"the compiled form of library function '{name}' ({reference}) cannot be "
            f"imported: {exc}"
        ) from None
    if not callable(found):
        raise UsageError(
            f"the compiled form of library function '{name}' ({reference}) is not a function"
        )
    return module, qualname
