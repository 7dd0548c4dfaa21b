"""Function libraries: a compiled form registered beside the Python one is what the compiled backend calls."""

from __future__ import annotations

import numpy as np
import pytest

import hybrid
from hybrid.errors import UsageError

pytest.importorskip("numba")

SPEC = """
automaton: orbit
uses: [testlib]
parameters: {k: 2.0}
state: {x: {initial: 1.0}, y: {initial: 0.0}}
signals:
  p: polar(x, y)
  w: k * spin(p[0])
locations:
  out: {flow: {x: -w * y, y: w * x}}
  back: {flow: {x: -w * y, y: w * x}}
edges:
  - name: half
    from: out
    to: back
    guard: "p[1] <= -3 and y <= 0"
  - name: again
    from: back
    to: out
    guard: y >= 0.5
"""

PLAIN = SPEC.replace("w: k * spin(p[0])", "w: k * plain(p[0])")


@pytest.fixture
def testlib(monkeypatch: pytest.MonkeyPatch) -> None:
    from support import native_library

    from hybrid.expr.functions import Function, load_library

    def fake(name: str) -> dict[str, Function]:
        if name != "testlib":
            return dict(load_library(name))
        return {
            n: Function(n, fn, *getattr(fn, "hybrid_arity", (0, None)),
                        outputs=int(getattr(fn, "hybrid_outputs", 1)), builtin=False)
            for n, fn in native_library().items()
        }  # fmt: skip

    monkeypatch.setattr("hybrid.reader.build.load_library", fake)


def test_compiled_forms_run_and_agree(testlib: None) -> None:
    model = hybrid.load_text(SPEC)
    kwargs = {"t_end": 12.0, "rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}
    compiled = hybrid.simulate(model, backend="compiled", **kwargs)  # type: ignore[arg-type]
    reference = hybrid.simulate(model, **kwargs)  # type: ignore[arg-type]
    assert [j.edge for j in compiled.jumps] == [j.edge for j in reference.jumps]
    assert len(compiled.jumps) >= 2
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(compiled["p[0]"], 1.0, rtol=1e-8)  # the radius stays 1
    np.testing.assert_allclose(compiled["w"], 1.0, rtol=1e-8)  # k / (1 + 1)


def test_a_function_without_a_compiled_form_is_named(testlib: None) -> None:
    model = hybrid.load_text(PLAIN)
    with pytest.raises(UsageError, match="library function 'plain' has no compiled form"):
        hybrid.simulate(model, t_end=1.0, backend="compiled")
    assert hybrid.simulate(model, t_end=1.0).termination.cause == "t_end"


RAISING = """
automaton: growth
uses: [testlib]
state: {x: {initial: 1.0}}
locations:
  a: {flow: {x: limited(x)}}
"""


def test_a_compiled_form_that_raises_is_an_evaluation_failure(testlib: None) -> None:
    """As on scipy: the run ends ``nonfinite`` where the function raised, and says why."""
    model = hybrid.load_text(RAISING)
    kwargs = {"t_end": 2.0, "rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}
    compiled = hybrid.simulate(model, backend="compiled", **kwargs)  # type: ignore[arg-type]
    reference = hybrid.simulate(model, **kwargs)  # type: ignore[arg-type]
    assert compiled.termination.cause == reference.termination.cause == "nonfinite"
    assert "limited(1.5" in compiled.termination.message
    assert "defined up to 1.5" in compiled.termination.message
    assert compiled.termination.message == reference.termination.message
    assert abs(compiled.termination.t - 0.5) < 1e-6  # x = 1 + t passes 1.5 at t = 0.5
