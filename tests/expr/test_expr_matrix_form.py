"""A long linear flow is compiled as one matrix product and computes what its terms compute.

The field's linear models (ARCH-COMP's Building: 48 states, 1,176 terms) write
their flows out term by term; from :data:`~hybrid.expr.codegen.MATRIX_MIN_TERMS`
products on, the flow is compiled as ``M x + N u + c``. Checked against the
matrices the terms were written from, against the term-by-term compilation (the
same products summed in another order: a few units in the last place), against
the closed form of a run, and for the same failure report when an input fails.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hybrid
from hybrid.compose import as_system
from hybrid.expr import codegen
from hybrid.simulation.compiled import CompiledModel

N = 70


def _linear_text(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> str:
    """A spec whose flow of x_i is ``sum_j a[i, j] x_j + b[i] u + c[i]``, written term by term."""
    n = len(c)
    flows = []
    for i in range(n):
        terms = [f"{float(a[i, j])!r} * x{j}" for j in range(n) if a[i, j] != 0.0]
        terms += [f"{float(b[i])!r} * u", repr(float(c[i]))]
        flows.append(f"      x{i}: {' + '.join(terms)}")
    states = ", ".join(f"x{i}: {{initial: {1.0 + i / n!r}}}" for i in range(n))  # floats
    return (
        "automaton: linear\n"
        "inputs: {u: {range: [0, 1]}}\n"
        f"state: {{{states}}}\n"
        "locations:\n"
        "  only:\n"
        "    flow:\n" + "\n".join(flows) + "\n"
    )


def _system(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    a = rng.normal(0.0, 1.0, (N, N)) * (rng.uniform(size=(N, N)) < 0.3) - 2.0 * np.eye(N)
    return a, rng.normal(0.0, 1.0, N), rng.normal(0.0, 1.0, N)


def _rhs(text: str, u: float = 0.7) -> tuple[object, str]:
    model = hybrid.load_text(text)
    compiled = CompiledModel(as_system(model), {"u": lambda t: u})
    mode = compiled.mode(compiled.initial_key)
    return mode.rhs, mode.rhs.__doc__ or ""


@pytest.mark.parametrize("seed", [0, 1])
def test_a_long_flow_is_one_product_and_equals_its_matrices(seed: int) -> None:
    a, b, c = _system(seed)
    rhs, source = _rhs(_linear_text(a, b, c))
    assert "_M @ x" in source and len(source) < 1000  # not the 1,500 terms
    x = np.random.default_rng(seed + 10).normal(0.0, 1.0, N)
    got = np.array(rhs(0.5, x))  # type: ignore[operator]
    np.testing.assert_allclose(got, a @ x + 0.7 * b + c, rtol=1e-12, atol=1e-12)


def test_it_agrees_with_the_terms_summed_in_order(monkeypatch: pytest.MonkeyPatch) -> None:
    a, b, c = _system(2)
    text = _linear_text(a, b, c)
    product, source = _rhs(text)
    monkeypatch.setattr(codegen, "MATRIX_MIN_TERMS", 10**9)
    terms, term_source = _rhs(text)
    assert "_M @ x" in source and "_M" not in term_source
    x = np.random.default_rng(3).normal(0.0, 1.0, N)
    p, q = np.array(product(0.0, x)), np.array(terms(0.0, x))  # type: ignore[operator]
    scale = np.abs(a) @ np.abs(x) + np.abs(b) * 0.7 + np.abs(c)  # the size of each sum's terms
    assert np.all(np.abs(p - q) <= 64 * np.finfo(float).eps * scale)


def test_a_run_follows_the_closed_form() -> None:
    """``x_i' = -k_i x_i``, 70 of them: ``x_i(t) = x_i(0) e^{-k_i t}``."""
    k = 0.1 + np.arange(N) / N
    a = -np.diag(k)
    a[np.arange(N - 1), np.arange(1, N)] = 0.0
    text = _linear_text(a, np.zeros(N), np.zeros(N))
    assert "_M @ x" in _rhs(text)[1]
    run = hybrid.simulate(hybrid.load_text(text), 3.0, rtol=1e-10, atol=1e-12,
                          inputs={"u": lambda t: 0.5}, handle_sigint=False)  # fmt: skip
    x0 = 1.0 + np.arange(N) / N
    np.testing.assert_allclose(run.states[-1], x0 * np.exp(-k * 3.0), rtol=1e-8)


def test_short_or_nonlinear_flows_stay_term_by_term() -> None:
    a, b, c = _system(4)
    text = _linear_text(a, b, c)
    nonlinear = text.replace("      x0: ", "      x0: x1 * x2 + ", 1)  # a product of two
    assert nonlinear != text and "_M" not in _rhs(nonlinear)[1]
    small = _linear_text(-np.eye(3), np.ones(3), np.zeros(3))
    assert "_M" not in _rhs(small)[1]


def test_a_failing_input_is_reported_as_before(monkeypatch: pytest.MonkeyPatch) -> None:
    a, b, c = _system(5)
    model = hybrid.load_text(_linear_text(a, b, c))

    def broken(t: float) -> float:
        if t > 0.25:
            return math.sqrt(-1.0)  # ValueError: math domain error
        return 0.5

    said = []
    for threshold in (codegen.MATRIX_MIN_TERMS, 10**9):
        monkeypatch.setattr(codegen, "MATRIX_MIN_TERMS", threshold)
        run = hybrid.simulate(model, 1.0, inputs={"u": broken}, handle_sigint=False)
        said.append((run.termination.cause, run.termination.message))
    assert said[0] == said[1]
    assert said[0][0] != "t_end" and "math domain error" in said[0][1]


def test_the_product_array_steps_as_its_list_did(monkeypatch: pytest.MonkeyPatch) -> None:
    """The flow gives the product's array; a run is bit for bit the run of its ``tolist()``."""
    a, b, c = _system(6)
    model = hybrid.load_text(_linear_text(a, b, c))
    assert not isinstance(_rhs(_linear_text(a, b, c))[0](0.0, np.ones(N)), list)  # type: ignore[operator]

    def simulate() -> hybrid.Run:
        return hybrid.simulate(model, 2.0, rtol=1e-9, atol=1e-12, dt=0.01,
                               inputs={"u": lambda t: math.sin(3.0 * t)}, handle_sigint=False)  # fmt: skip

    product = simulate()
    compile_function = codegen.compile_function

    def as_list(*args: object, **kwargs: object) -> object:
        fn = compile_function(*args, **kwargs)  # type: ignore[arg-type]
        if "_M @ x" not in (fn.__doc__ or ""):
            return fn
        return lambda t, x: fn(t, x).tolist()

    monkeypatch.setattr("hybrid.simulation.compiled.compile_function", as_list)
    listed = simulate()
    assert len(product.t) == len(listed.t) > 200
    assert np.array_equal(product.t, listed.t) and np.array_equal(product.states, listed.states)


def test_long_linear_signal_columns_are_one_product() -> None:
    """A signal defined as a long sum of products is computed by one product per stored point."""
    a, b, c = _system(7)
    weights = np.random.default_rng(8).normal(0.0, 1.0, (2, N))
    weights[:, 50:] = 0.0  # 50 products each (a sum nests one level per term, 64 at most)
    text = _linear_text(a, b, c).replace("locations:", "signals:\n" + "".join(
        f"  y{k}: {' + '.join(f'{float(w)!r} * x{j}' for j, w in enumerate(weights[k, :50]))}"
        " + 0.5 * u + 1.25\n" for k in range(2)
    ) + "locations:")  # fmt: skip
    model = hybrid.load_text(text)
    compiled = CompiledModel(as_system(model), {"u": lambda t: 0.7})
    outputs = compiled.mode(compiled.initial_key).outputs
    assert "_M @ x" in (outputs.__doc__ or "")
    x = np.random.default_rng(9).normal(0.0, 1.0, N)
    got = outputs(0.0, x)
    assert isinstance(got, tuple) and all(type(v) is float for v in got)
    exact = weights @ x + 0.5 * 0.7 + 1.25
    scale = np.abs(weights) @ np.abs(x) + 0.35 + 1.25
    assert np.all(np.abs(np.array(got) - exact) <= 64 * np.finfo(float).eps * scale)
    run = hybrid.simulate(model, 0.5, inputs={"u": lambda t: 0.7}, handle_sigint=False)
    np.testing.assert_allclose(run.signals, run.states @ weights.T + 0.35 + 1.25, rtol=1e-12,
                               atol=1e-12)  # fmt: skip
