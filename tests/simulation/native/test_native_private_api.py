"""numba's private API, used by one module (``native/pointers.py``), on a tested numba only.

If pip resolves a numba outside the bound of the ``fast`` extra (or the bound is
widened), this fails with the version and what to check, before any kernel
test fails obscurely.
"""

from __future__ import annotations

import re
import tomllib

import pytest
from support import REPO

numba = pytest.importorskip("numba")


def _minor(version: str) -> tuple[int, int]:
    major, minor = re.match(r"(\d+)\.(\d+)", version).groups()  # type: ignore[union-attr]
    return int(major), int(minor)


def test_the_installed_numba_is_one_the_private_api_was_tested_on() -> None:
    from hybrid.simulation.native.pointers import TESTED_NUMBA

    first, last = TESTED_NUMBA
    assert first <= _minor(numba.__version__) <= last, (
        f"numba {numba.__version__} is not in the tested range {first}..{last} of "
        "hybrid/simulation/native/pointers.py: check its private API there, then widen "
        "TESTED_NUMBA and the 'fast' extra's bound together"
    )


def test_the_fast_extra_is_bounded_to_the_tested_versions() -> None:
    from hybrid.simulation.native.pointers import TESTED_NUMBA

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    (spec,) = [r for r in project["optional-dependencies"]["fast"] if r.startswith("numba")]
    low, high = re.fullmatch(r"numba>=([\d.]+),<([\d.]+)", spec).groups()  # type: ignore[union-attr]
    first, last = TESTED_NUMBA
    assert _minor(low) == first
    assert _minor(high) == (last[0], last[1] + 1)


def test_the_private_names_it_reads_are_there() -> None:
    from numba.experimental import function_type

    assert callable(function_type._get_wrapper_address)
    assert callable(function_type._get_jit_address)
    kind = numba.types.FunctionType(numba.types.float64(numba.types.float64))
    from numba.core import datamodel

    model = datamodel.default_manager.lookup(kind)
    assert {"c_addr", "jit_addr", "py_addr"} <= set(model._fields)


def test_a_models_compiled_code_is_found_behind_its_cfunc() -> None:
    """The loop calls the model's code directly: its name is the wrapper's without ``cfunc.``."""
    from hybrid.simulation.native.pointers import model_addresses

    signature = numba.types.float64(numba.types.float64)

    def twice(a: float) -> float:
        return 2.0 * a

    wrapped = numba.cfunc(signature)(twice)
    c_address, jit_address = model_addresses(wrapped)
    assert c_address == wrapped.address
    assert jit_address not in (0, c_address)
    assert wrapped._wrapper_name == "cfunc." + wrapped._library.get_function(
        wrapped._wrapper_name[len("cfunc."):]
    ).name


def test_without_a_wrapper_name_the_wrapper_alone_is_called() -> None:
    from hybrid.simulation.native.pointers import model_addresses

    class Moved:  # numba's internals renamed: no compiled code found, no error
        address = 1234
        _wrapper_name = "renamed"
        _library = None

    assert model_addresses(Moved()) == (1234, 0)
