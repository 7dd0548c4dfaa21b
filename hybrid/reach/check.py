"""``hybrid.check`` with reach: forbidden entries the analysis could not prove, decided by flowpipes.

:func:`hybrid.analysis.check` reports a forbidden entry it cannot prove as
``property-unproved`` (a warning, with a candidate path). For an affine model
with a horizon (``checks: {reach: {t_end: T, max_jumps: J}}`` in the spec, or
the arguments here), :func:`check` runs :func:`hybrid.reach` on those entries:

- proved: the finding is dropped (no run reaches it within the horizon);
- refuted: it becomes ``property-violated`` (an error) naming the simulated
  run that reaches it;
- unknown: it stays ``property-unproved``, with reach's earliest contact.

With a horizon, the entries the analysis did prove are put to reach too: the
analysis decides conditions exactly, the simulator within a band that grows with
the largest variable of the state (docs/check.md, "a known gap"). A run that
reaches one of them is reported (``property-violated``); reach's "unknown"
there leaves the analysis's proof standing.

A model reach cannot handle (not affine) keeps the analysis's findings, with
a sentence saying why reach was not used. This module sits above
``analysis/`` and ``simulation/`` (a witness is a simulated run).

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: [18, 19], bounds: [0, 100]}}
... locations: {on: {flow: {x: -0.1 * x + 2}}}
... properties: {forbidden: [{when: x > 25}]}
... ''')
>>> [f.rule for f in check(m).findings]
['property-unproved']
>>> check(m, reach_t_end=10.0).findings
()
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from dataclasses import replace

from hybrid.analysis.api import check as analysis_check
from hybrid.analysis.explore import DEFAULT_MAX_BYTES, DEFAULT_MAX_STATES, Progress
from hybrid.analysis.findings import Finding, Report
from hybrid.compose import System, expect_model
from hybrid.errors import SpecError, UsageError
from hybrid.frames import in_frame_room
from hybrid.model import Automaton

__all__ = ["check"]


@in_frame_room
def check(
    model: Automaton | System,
    *,
    max_states: int = DEFAULT_MAX_STATES,
    max_bytes: int = DEFAULT_MAX_BYTES,
    ignore: Iterable[str] = (),
    progress: Progress | None = None,
    reach_t_end: float | None = None,
    reach_max_jumps: int | None = None,
    reach_step: float | None = None,
) -> Report:
    """Run every check on ``model``, deciding unproved forbidden entries with reach.

    Parameters
    ----------
    model
        An automaton or a system, as :func:`hybrid.load` returns it.
    max_states, max_bytes
        Limits of the exploration of a product (see :func:`hybrid.analysis.check`).
    ignore
        Rule ids not to report (on top of the spec files' ``checks: {ignore: [...]}``).
    progress
        Called as ``progress(modes, frontier)`` while exploring a large product.
    reach_t_end, reach_max_jumps, reach_step
        Horizon, jump bound and step of :func:`hybrid.reach` for the forbidden
        entries the analysis could not prove (default: the spec's
        ``checks: {reach: {t_end, max_jumps, step}}``; no horizon, no reach).

    Returns
    -------
    Report
        ``ok`` when no finding is an error: ``property-violated`` only for a
        forbidden entry a simulated run reaches (or a property refuted by proof).

    Examples
    --------
    >>> import hybrid
    >>> tank = hybrid.load_text('''
    ... automaton: tank
    ... state: {level: {initial: 1, bounds: [0, 10]}}
    ... locations: {filling: {flow: {level: 1}}}
    ... properties: {forbidden: [{when: level > 3}]}
    ... ''')
    >>> [(f.rule, f.severity) for f in check(tank).findings]
    [('property-unproved', 'warning')]
    >>> check(tank, reach_t_end=1.0).findings
    ()
    >>> [(f.rule, f.severity) for f in check(tank, reach_t_end=3.0).findings]
    [('property-violated', 'error')]
    """
    expect_model(model, "check")
    ignore = (ignore,) if isinstance(ignore, str) else tuple(ignore)  # one rule, not its letters
    _check_arguments(max_states, max_bytes, progress, reach_t_end, reach_max_jumps, reach_step)
    report = analysis_check(
        model, max_states=max_states, max_bytes=max_bytes, ignore=ignore, progress=progress
    )
    props = model.properties
    t_end = reach_t_end if reach_t_end is not None else props.reach_t_end
    unproved = [
        f
        for f in report.findings
        if f.rule == "property-unproved" and f.where.startswith("forbidden: ")
    ]
    if t_end is None and (reach_max_jumps is not None or reach_step is not None):
        import warnings

        from hybrid.errors import Note

        given = ("reach_max_jumps (--reach-max-jumps)" if reach_max_jumps is not None
                 else "reach_step")  # fmt: skip
        warnings.warn(
            Note(
                f"{model.name}: {given} is not used: reach runs over a horizon, and none is "
                "given (reach_t_end, --reach-t-end, or checks: {reach: {t_end: ...}} in the spec)"
            ),
            stacklevel=2,
        )
    if t_end is None or not props.forbidden:
        return report
    max_jumps = reach_max_jumps if reach_max_jumps is not None else props.reach_max_jumps
    jumps = 10 if max_jumps is None else max_jumps
    step = reach_step if reach_step is not None else props.reach_step
    from hybrid.reach.api import reach

    try:
        result = reach(
            model,
            t_end,
            max_jumps=jumps,
            step=step,
            refute_first=True,  # only the verdicts are needed: no sets for a refuted entry
        )
    except (SpecError, UsageError) as exc:
        why = str(exc).splitlines()[0]
        notes = {
            id(f): replace(f, message=f"{f.message}; reach was not used: {why}") for f in unproved
        }
        return replace(report, findings=tuple(notes.get(id(f), f) for f in report.findings))
    verdicts = {f"forbidden: {p.entry.text()}": p for p in result.properties}
    bounded = f"forbidden states: within t <= {t_end:g} and {jumps} jumps"
    if result.jump_past_bound:
        bounded += f"; {result.jump_past_bound}, not covered"
    silenced = set(ignore) | set(props.ignore)
    kept: list[Finding] = []
    reported = {f.where for f in report.findings}
    for where, verdict in verdicts.items():  # proved by the analysis, reached by a run
        if (where not in reported and verdict.verdict == "refuted"
                and "property-violated" not in silenced):  # fmt: skip
            kept.append(
                Finding.at("property-violated", verdict.entry.position, verdict.message, where=where)
            )
    for f in report.findings:
        p = verdicts.get(f.where) if f in unproved else None
        if p is None:
            kept.append(f)
        elif p.verdict == "refuted":
            if "property-violated" not in silenced:
                kept.append(
                    replace(
                        f, rule="property-violated", severity="error", message=p.message, witness=()
                    )
                )
        elif p.verdict == "unknown":
            kept.append(replace(f, message=f"{f.message}; reach: {p.message}"))
    return replace(report, findings=tuple(kept), bounded=bounded)


def _check_arguments(max_states: object, max_bytes: object, progress: object,
                     reach_t_end: object, reach_max_jumps: object, reach_step: object) -> None:  # fmt: skip
    """A :class:`UsageError` for an argument of :func:`check` it cannot use (as the command
    line refuses the same values)."""
    for name, value, least in (("max_states", max_states, 1), ("max_bytes", max_bytes, 1),
                               ("reach_max_jumps", reach_max_jumps, 0)):  # fmt: skip
        if name == "reach_max_jumps" and value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or int(value) < least:
            raise UsageError(f"{name} must be a whole number >= {least}, got {value!r}")
    for name, value in (("reach_t_end", reach_t_end), ("reach_step", reach_step)):
        if value is None:
            continue
        if (isinstance(value, bool) or not isinstance(value, numbers.Real)
                or not math.isfinite(float(value)) or not float(value) > 0):  # fmt: skip
            raise UsageError(f"{name} must be a finite number > 0, got {value!r}")
    if progress is not None and not callable(progress):
        raise UsageError(f"progress must be a function of a status, got {progress!r}")
