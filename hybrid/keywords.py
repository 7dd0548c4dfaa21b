"""Keyword arguments people bring from MATLAB and scipy, named with ours when refused.

``hybrid.simulate(model, tspan=[0, 10])`` would raise Python's "got an unexpected
keyword argument 'tspan'"; :func:`named_keywords` turns that (and only that: an
error raised inside the function passes unchanged) into an
:class:`~hybrid.errors.UnknownArgument` that says what to write: the keyword of
``solve_ivp`` or ``odeset`` that has another name here, or the closest keyword.

Examples
--------
>>> @named_keywords
... def run(model, t_end=None, *, rtol=None, initial=None):
...     return t_end
>>> run("m", RelTol=1e-8)
Traceback (most recent call last):
hybrid.errors.UnknownArgument: run() got an unexpected keyword argument 'RelTol'; did you mean 'rtol'?
>>> run("m", t_end=3)
3
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import ParamSpec, TypeVar

__all__ = ["keywords_of", "named_keywords", "refused_argument"]

P = ParamSpec("P")
R = TypeVar("R")

_HABITS = {
    "tspan": "t_end", "t_span": "t_end", "tf": "t_end", "tfinal": "t_end", "t_final": "t_end",
    "t0": "t_start", "reltol": "rtol", "abstol": "atol", "maxstep": "max_step",
    "x0": "initial", "y0": "initial", "ic": "initial", "init": "initial",
    "initial_state": "initial", "params": "parameters", "param": "parameters",
    "p": "parameters", "args": "parameters", "solver": "method", "options": "settings",
    "dense_output": "dense", "tol": "rtol", "n_jobs": "workers",
}  # fmt: skip
"""Keywords of ``solve_ivp``, ``odeset`` and habit, and ours (looked up lowercased)."""

_WHY = {
    "tspan": " (the run goes from t_start, default 0, to t_end: t_end=10)",
    "t_span": " (the run goes from t_start, default 0, to t_end: t_end=10)",
    "events": ": a run's events are its model's guards, and its jumps are run.jumps",
}
"""What a keyword with no counterpart of its own means here."""


def keywords_of(function: Callable[..., object]) -> tuple[str, ...]:
    """The names of ``function``'s arguments (of the function a decorator wraps)."""
    code = getattr(function, "__wrapped__", function).__code__
    return tuple(code.co_varnames[: code.co_argcount + code.co_kwonlyargcount])


def named_keywords(function: Callable[P, R]) -> Callable[P, R]:
    """``function``, whose refused keyword arguments are named with the ones it takes."""
    taken = keywords_of(function)
    positional = getattr(function, "__wrapped__", function).__code__.co_argcount

    @functools.wraps(function)
    def call(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            return function(*args, **kwargs)
        except TypeError as exc:
            tb, said = exc.__traceback__, str(exc)
            too_many = "positional argument" in said and "were given" in said
            if tb is not None and tb.tb_next is None and too_many:
                from hybrid.errors import UsageError

                keywords = ", ".join(f"{k}=" for k in taken[positional:][:6])
                raise UsageError(
                    f"{said}: give the others by keyword ({keywords} ...); MATLAB's "
                    "(f, [t0 tf], x0) is t_start=t0, t_end=tf, initial={name: value}"
                ) from None
            if tb is None or tb.tb_next is not None or "unexpected keyword argument" not in said:
                raise  # raised inside the function, or a refusal of another kind
            refused = [k for k in kwargs if k not in taken and f"'{k}'" in said]
            if not refused:
                raise
            raise refused_argument(function.__name__, refused[0], taken) from None

    return call


def refused_argument(name: str, keyword: str, taken: Sequence[str]) -> Exception:
    """The :class:`~hybrid.errors.UnknownArgument` of ``name()`` given ``keyword``, which is
    none of ``taken``: it names the keyword meant (another tool's name, or the closest)."""
    from hybrid.errors import UnknownArgument, did_you_mean

    said = f"{name}() got an unexpected keyword argument '{keyword}'"
    if keyword in _WHY and _HABITS.get(keyword.lower()) not in taken:  # nothing to name
        return UnknownArgument(said + _WHY[keyword])
    meant = did_you_mean(keyword, [t for t in taken if t != "self"], aliases=_HABITS)
    return UnknownArgument(said + meant + _WHY.get(keyword, ""))
