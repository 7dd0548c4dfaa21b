"""The ``backend`` and ``simulate`` fixtures: a semantics test runs on both backends.

``simulate`` is :func:`hybrid.simulate` on the test's backend. On the compiled
backend, a run it refuses (``hybrid.simulation.native.features.refusal``, the one
list of what it does not do) is skipped with that reason; any other difference
fails the test.
"""

from __future__ import annotations

import importlib.util
from typing import Any

import pytest

import hybrid

BACKENDS = [
    "scipy",
    pytest.param("compiled", marks=pytest.mark.skipif(
        importlib.util.find_spec("numba") is None, reason="the compiled backend needs numba")),
]  # fmt: skip


@pytest.fixture(scope="module", params=BACKENDS)
def backend(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture(scope="module")
def simulate(backend: str) -> Any:
    def run(model: Any, *args: Any, **settings: Any) -> hybrid.Run:
        if backend == "compiled":
            from hybrid.simulation.native.features import refusal

            reason = refusal(model, **settings)
            if reason is not None:
                pytest.skip(f"the compiled backend refuses it: {reason}")
        return hybrid.simulate(model, *args, backend=backend, **settings)

    return run
