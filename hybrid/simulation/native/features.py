"""What the compiled backend refuses: constructs whose semantics it does not implement (yet).

Every refusal is one :class:`~hybrid.errors.UsageError` that names the
construct and where it is, and suggests ``backend='scipy'``, which runs it. The
list, all here: a method other than RK45 and inputs given as Python functions
(:func:`check_supported`), a free input without a ``range``
(:func:`refuse_unsupported`), more than :data:`MAX_MODES` modes
(:func:`too_many_modes`), a library function without a compiled form
(:func:`no_compiled_form`), and requirements in an ensemble
(:func:`refuse_requirements`); :func:`refusal` says any of the first three in words. A
campaign asked to run compiled is refused the same way before its first run
(:func:`hybrid.campaigns.choosing.refuse_compiled`).
Everything not refused here runs as the scipy backend runs it (the agreement
tests of ``tests/simulation/native`` show each construct).

Examples
--------
>>> import hybrid
>>> from hybrid.compose import as_system
>>> tank = hybrid.load_text('''
... automaton: tank
... inputs: {u: {}}
... state: {h: {initial: 2.0}}
... locations: {fill: {flow: {h: u}}}
... ''')
>>> refuse_unsupported(as_system(tank))
Traceback (most recent call last):
...
hybrid.errors.UsageError: <string>:3:10: input 'u' of tank needs a value, and the compiled backend cannot take inputs given as expressions or functions: use the scipy backend (--backend scipy; backend='scipy' in Python) with --input u=EXPR (inputs={'u': f} in Python), or compose tank with an automaton that defines 'u'

A free input with a ``range`` is held at its nominal value, as the scipy
backend holds it (a slot of the run's parameter vector,
:class:`~hybrid.simulation.native.structure.NativeModel`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from hybrid.compose import System, as_system
from hybrid.errors import UsageError
from hybrid.model import Automaton
from hybrid.simulation.settings import Settings
from hybrid.simulation.watched import watched_requirements

__all__ = [
    "MAX_MODES",
    "METHOD",
    "check_supported",
    "no_compiled_form",
    "refusal",
    "refuse_method",
    "refuse_requirements",
    "refuse_unsupported",
    "too_many_modes",
    "unheld_inputs",
]

METHOD = "RK45"
"""The one integration method of the compiled backend (Dormand–Prince 5(4))."""

MAX_MODES = 4096
"""Most modes the compiled backend generates code for (reachable through the transition
graph, guards ignored): a larger product is the scipy backend's, which compiles the modes a
run meets."""


def check_supported(settings: Settings, inputs: Mapping[str, Any] | None) -> None:
    """Refuse the settings and inputs the compiled backend does not take, naming them."""
    refuse_method(settings.method)
    if inputs:
        raise UsageError(
            "the compiled backend cannot call inputs given as expressions or functions "
            f"(--input, inputs=...); use {SCIPY}"
        )


SCIPY = "the scipy backend (--backend scipy; backend='scipy' in Python)"
"""How a refusal names the backend that runs what the compiled one refuses, in both spellings."""


def refuse_method(method: str, instead: str = SCIPY) -> None:
    """Raise :class:`UsageError` for a ``method`` other than :data:`METHOD`, pointing at
    ``instead``."""
    if method != METHOD:
        raise UsageError(
            f"the compiled backend integrates with {METHOD} (Dormand–Prince 5(4)); method "
            f"'{method}' needs {instead}"
        )


def too_many_modes(name: str) -> UsageError:
    """The refusal of a model with more than :data:`MAX_MODES` modes."""
    return UsageError(
        f"the compiled backend generates code for at most {MAX_MODES} modes; "
        f"{name} has more (use {SCIPY})"
    )


def no_compiled_form(name: str, function: str) -> UsageError:
    """The refusal of a model calling a library function that registers no compiled form."""
    return UsageError(
        f"the compiled backend cannot run {name}: library function "
        f"'{function}' has no compiled form (its library registers none; see "
        f"docs/backends.md), so use {SCIPY}"
    )


def unheld_inputs(system: System) -> list[str]:
    """The free inputs of ``system`` without a ``range``: only a Python function can give them."""
    ranges = system.input_ranges()
    return [n for n in system.free_inputs if n not in ranges]


def refusal(model: Automaton | System, **settings: Any) -> str | None:
    """Why the compiled backend refuses to simulate ``model`` with ``settings``, or ``None``.

    ``settings`` are :func:`hybrid.simulate`'s keyword arguments. The list:
    a ``method`` other than RK45; ``inputs`` given as Python functions; a free
    input without a ``range`` (it needs a function).

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> refusal(ball) is None, refusal(ball, method="Radau")
    (True, "method 'Radau' (it integrates with RK45)")
    """
    method = settings.get("method", METHOD)
    if method != METHOD:
        return f"method '{method}' (it integrates with {METHOD})"
    if settings.get("inputs"):
        return "inputs given as Python functions"
    unheld = unheld_inputs(as_system(model))
    if unheld:
        return f"input '{unheld[0]}' has no range, so it needs a Python function"
    return None


def refuse_unsupported(system: System) -> None:
    """Raise :class:`UsageError` if ``system`` uses a construct the compiled backend lacks."""
    name = system.name
    unheld = unheld_inputs(system)
    if unheld:
        raise UsageError(
            f"input '{unheld[0]}' of {name} needs a value, and the compiled backend cannot take "
            f"inputs given as expressions or functions: use {SCIPY} with --input "
            f"{unheld[0]}=EXPR (inputs={{'{unheld[0]}': f}} in Python), or compose {name} with an "
            f"automaton that defines '{unheld[0]}'",
            at=system.input_position(unheld[0]),
        )


def refuse_requirements(system: System) -> None:
    """Raise :class:`UsageError` if ``system`` has requirements (the ensemble does not monitor them)."""
    requirements = [w.name for w in watched_requirements(system)]
    if requirements:
        raise UsageError(
            f"the compiled ensemble cannot run {system.name}: it does not monitor requirements "
            f"({', '.join(requirements)}); run hybrid.simulate(..., backend='compiled') per "
            "row, which does, or hybrid.sweep"
        )
