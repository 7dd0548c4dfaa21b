"""Keywords and attributes from scipy's ``solve_ivp`` and MATLAB, named with ours.

Before, ``hybrid.simulate(model, tspan=[0, 10])`` raised Python's bare "got an
unexpected keyword argument", ``sweep(..., n_jobs=2)`` "got an unexpected keyword",
and ``run.y`` (scipy's ``sol.y``) or ``run.h`` an AttributeError naming nothing.
Each refused keyword is now an ``UnknownArgument`` (a ``UsageError`` and still the
``TypeError`` Python raised), and an attribute a run lacks says where it is.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from support import SPECS

import hybrid
from hybrid.errors import UnknownArgument

BALL = hybrid.load(SPECS / "bouncing_ball.yaml")

KEYWORDS: list[tuple[Callable[..., Any], dict[str, Any], str]] = [
    (hybrid.simulate, {"tspan": [0, 10]},
     "simulate() got an unexpected keyword argument 'tspan'; did you mean 't_end'? (the run goes from t_start"),
    (hybrid.simulate, {"t_end": 1.0, "RelTol": 1e-8},
     "simulate() got an unexpected keyword argument 'RelTol'; did you mean 'rtol'?"),
    (hybrid.simulate, {"t_end": 1.0, "x0": {"h": 3.0}},
     "simulate() got an unexpected keyword argument 'x0'; did you mean 'initial'?"),
    (hybrid.simulate, {"t_end": 1.0, "events": True},
     "simulate() got an unexpected keyword argument 'events': a run's events are its model's guards"),
    (hybrid.simulate, {"t_end": 1.0, "rtl": 1e-8},
     "simulate() got an unexpected keyword argument 'rtl'; did you mean 'rtol'?"),
    (hybrid.simulate_many, {"t_end": 1.0, "y0": {"h": [1.0, 2.0]}},
     "simulate_many() got an unexpected keyword argument 'y0'; did you mean 'initial'?"),
    (hybrid.sweep, {"t_end": 1.0, "grid": {"e": [0.5]}, "n_jobs": 2},
     "sweep() got an unexpected keyword argument 'n_jobs'; did you mean 'workers'?"),
    (hybrid.sweep, {"t_end": 1.0, "grid": {"e": [0.5]}, "params": {"g": 9.0}},
     "sweep() got an unexpected keyword argument 'params'; did you mean 'parameters'?"),
    (hybrid.reach, {"tspan": 3.0}, "reach() got an unexpected keyword argument 'tspan'; did you mean 't_end'?"),
]  # fmt: skip


@pytest.mark.parametrize(("function", "keywords", "said"), KEYWORDS,
                         ids=[f"{f.__name__}-{next(iter(k))}" for f, k, _ in KEYWORDS])  # fmt: skip
def test_a_keyword_of_another_tool_is_named_with_ours(
    function: Callable[..., Any], keywords: dict[str, Any], said: str
) -> None:
    with pytest.raises(UnknownArgument) as caught:
        function(BALL, **keywords)
    assert str(caught.value).startswith(said)
    assert isinstance(caught.value, TypeError) and isinstance(caught.value, hybrid.UsageError)


def test_another_refusal_of_the_call_is_left_as_python_says_it() -> None:
    """A missing model beside a keyword the campaign takes (rtol goes to its **solver):
    Python's "missing 1 required positional argument", not a refused 'rtol'."""
    with pytest.raises(TypeError) as caught:
        hybrid.sweep(t_end=1.0, grid={"e": [0.5]}, rtol=1e-8)  # type: ignore[call-arg]
    assert not isinstance(caught.value, UnknownArgument)
    assert "missing 1 required positional argument: 'model'" in str(caught.value)


def test_a_type_error_inside_the_function_is_not_taken_for_a_keyword() -> None:
    """Only the refusal of the call itself is renamed: a TypeError raised while the
    function runs (here by the model's input, a function of the wrong arity) is not."""
    from hybrid.keywords import named_keywords

    @named_keywords
    def run(model: Any, *, rtol: float = 1e-6) -> Any:
        return model(1, 2)

    with pytest.raises(TypeError) as caught:
        run(lambda x: x, rtol=1e-8)
    assert not isinstance(caught.value, UnknownArgument)


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
@pytest.mark.parametrize(
    ("attribute", "said"),
    [
        ("y", "the states are run.states, one row per point (scipy's sol.y is run.states.T"),
        ("x", "MATLAB's [t, x] = ode45(...) is run.t, run.states"),
        ("h", "a state variable's or signal's column is run['h']"),
        ("energy", "a state variable's or signal's column is run['energy']"),
        ("status", "how the run ended is run.termination"),
        ("t_events", "the jumps are run.jumps"),
        ("termnation", "; did you mean 'termination'?"),
    ],
)
def test_an_attribute_a_run_lacks_says_where_it_is(backend: str, attribute: str, said: str) -> None:
    if backend == "compiled":
        pytest.importorskip("numba")
    run = hybrid.simulate(BALL, t_end=1.0, backend=backend, handle_sigint=False)
    with pytest.raises(AttributeError) as caught:
        getattr(run, attribute)
    assert str(caught.value).startswith(f"'Run' object has no attribute '{attribute}'")
    assert said in str(caught.value)
    assert not hasattr(run, "__no_such_dunder__")  # copy and pickle probe these
    with pytest.raises(AttributeError) as probed:  # IPython probes _repr_latex_ and others: no search
        run._repr_latex_  # noqa: B018
    assert str(probed.value) == "'Run' object has no attribute '_repr_latex_'"
