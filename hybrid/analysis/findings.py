"""Findings of `hybrid check`, their rules and severities, and the report holding them.

Severities, and why:

================================  ========  ============================================
rule                              severity  reason
================================  ========  ============================================
``property-violated``             error     a run of the model violates a property
``property-disproved``            error     a location declared reachable proved unreachable
``property-unproved``             warning   a property not proved and not refuted either
``property-proved``               note      ``hybrid reach`` proved a forbidden entry
``sink-location``                 error     a run that gets there ends ``blocked``
``blocked-start``                 error     every run ends at ``t = 0``, ``blocked``
``invalid-spec``                  error     the file cannot be checked at all
``unreachable-location``          warning   dead model text, often a typo in a guard
``dead-edge``                     warning   the same, for an edge
``nondeterminism``                warning   the simulator picks by file order; say so
``zero-time-cycle``               warning   a Zeno candidate; may be intended
``unused-declaration``            warning   usually a typo or leftover
``analysis-incomplete``           note      the product was too large to explore whole
``requirement-violated``          error     a run of ``hybrid sweep`` violates a requirement
``sweep-run-failed``              error     a run of ``hybrid sweep`` raised or timed out
``requirement-held``              note      a requirement holds in every run of a sweep
================================  ========  ============================================

The last three are reported by ``hybrid sweep --format ...`` (:data:`CAMPAIGN_RULES`),
never by ``hybrid check``.

``hybrid check`` exits 1 on any error finding, and with ``--strict`` on any
warning too; notes never fail a run.

Examples
--------
>>> from hybrid.errors import Position
>>> f = Finding.at("dead-edge", Position("a.yaml", 3, 5), "edge 'e' can never fire", where="e")
>>> f.text()
"a.yaml:3:5: warning dead-edge: edge 'e' can never fire"
>>> Report((f,)).ok, Report((f,)).failed(strict=True)
(True, True)
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from hybrid.errors import Position

__all__ = ["CAMPAIGN_RULES", "RULES", "SEVERITIES", "Finding", "Report", "Rule", "WitnessStep"]

SEVERITIES = ("error", "warning", "note")


@dataclass(frozen=True)
class Rule:
    """A rule id with its default severity and descriptions (used by SARIF too)."""

    id: str
    severity: str
    summary: str
    description: str


RULES: dict[str, Rule] = {
    r.id: r
    for r in (
        Rule(
            "unreachable-location",
            "warning",
            "Location cannot be reached",
            "No path from the initial location along edges whose guards can hold within the "
            "declared bounds (and, in a system, that can synchronise) reaches this location.",
        ),
        Rule(
            "sink-location",
            "error",
            "Location with no way out",
            "The invariant of this location can be left by the flow, but no edge out of it can "
            "ever fire: a run that gets here ends blocked.",
        ),
        Rule(
            "blocked-start",
            "error",
            "Every run blocked at its start",
            "Every initial state breaks the invariant of its initial location and no edge out "
            "of it can fire there: no run gets past its start (a lone automaton's ends blocked).",
        ),
        Rule(
            "dead-edge",
            "warning",
            "Edge can never fire",
            "The guard cannot hold anywhere within the declared bounds and the closure of the "
            "source invariant, or (in a system) its label never synchronises.",
        ),
        Rule(
            "nondeterminism",
            "warning",
            "Edges enabled at once",
            "Two edges of one location with the same priority have guards that can hold at the "
            "same point; the simulator then takes the first in file order.",
        ),
        Rule(
            "zero-time-cycle",
            "warning",
            "Cycle without time passing",
            "A cycle of edges each of whose guards can hold right after the previous edge's "
            "reset: the run may jump forever at one instant (a Zeno candidate).",
        ),
        Rule(
            "unused-declaration",
            "warning",
            "Declaration never used",
            "A parameter or input no expression reads, or a label no edge carries. Signals "
            "are outputs (written to the trajectory) and are never reported.",
        ),
        Rule(
            "property-violated",
            "error",
            "Declared property does not hold",
            "A property under `properties:` is refuted by a run of the model: a forbidden "
            "state reached by a simulated run (`hybrid reach`), given as a witness that "
            "`hybrid simulate` replays.",
        ),
        Rule(
            "property-disproved",
            "error",
            "Declared reachable location proved unreachable",
            "A location under `properties: reachable` that no run can reach: the analysis "
            "over-approximates every run and none enters it, a proof. No run can show an "
            "absence, so the message names the entries into it that can never fire.",
        ),
        Rule(
            "property-unproved",
            "warning",
            "Declared property not proved",
            "A property under `properties:` (unreachable, deadlock_free, deterministic, "
            "forbidden) that the analysis could neither prove nor refute: the "
            "over-approximation meets it, with a candidate path; no run was found that "
            "violates it. For an affine model, `checks: {reach: {t_end: T}}` lets "
            "`hybrid check` decide forbidden entries with `hybrid reach`.",
        ),
        Rule(
            "property-proved",
            "note",
            "Forbidden state proved unreachable",
            "`hybrid reach` proved that no run reaches the forbidden entry within the "
            "horizon and the jump bound.",
        ),
        Rule(
            "analysis-incomplete",
            "note",
            "Product too large to explore whole",
            "Exploration of the product stopped at its state limit; findings that need the "
            "whole reachable product are not reported.",
        ),
        Rule(
            "requirement-violated",
            "error",
            "Requirement violated in a sweep",
            "A run of the sweep violates a requirement under `requirements:`; the message "
            "names the varied values of a violating run (the one of lowest robustness).",
        ),
        Rule(
            "sweep-run-failed",
            "error",
            "Run of a sweep failed",
            "A run of the sweep raised an error or exceeded the run timeout; the message "
            "names its varied values and the error.",
        ),
        Rule(
            "requirement-held",
            "note",
            "Requirement held in a sweep",
            "Every run of the sweep satisfies the requirement; the message gives the lowest "
            "robustness and where it was found.",
        ),
        Rule(
            "invalid-spec",
            "error",
            "Spec cannot be loaded",
            "The file is not a valid spec; `hybrid validate` gives the same message.",
        ),
    )
}

CAMPAIGN_RULES = ("requirement-violated", "sweep-run-failed", "requirement-held")
"""Rules of ``hybrid sweep`` findings (no ``hybrid check`` report has them)."""

WitnessStep = tuple[str | None, str]  # (transition taken, mode reached); first: (None, initial)


@dataclass(frozen=True)
class Finding:
    """One finding, placed in a spec file.

    ``where`` names what it is about (a location, an edge, a property);
    ``witness`` is a path of ``(transition, mode)`` steps from the initial mode
    where one exists (the first step has no transition).
    """

    rule: str
    severity: str
    file: str
    line: int
    column: int
    message: str
    where: str = ""
    witness: tuple[WitnessStep, ...] = field(default=())

    @classmethod
    def at(
        cls,
        rule: str,
        position: Position,
        message: str,
        *,
        where: str = "",
        witness: Iterable[WitnessStep] = (),
        severity: str | None = None,
    ) -> Finding:
        """A finding of ``rule`` at ``position`` (severity: the rule's default)."""
        return cls(
            rule,
            severity or RULES[rule].severity,
            position.file,
            position.line,
            position.column,
            message,
            where,
            tuple(witness),
        )

    def text(self) -> str:
        """``file:line:column: severity rule-id: message``."""
        return f"{self.file}:{self.line}:{self.column}: {self.severity} {self.rule}: {self.message}"

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of the contract (plus ``witness``, a list of steps)."""
        return {
            "rule": self.rule,
            "severity": self.severity,
            "file": self.file,
            "line": self.line,
            "column": self.column,
            "message": self.message,
            "where": self.where,
            "witness": [{"transition": t, "mode": m} for t, m in self.witness],
        }

    def sort_key(self) -> tuple[str, int, int, str, str]:
        return (self.file, self.line, self.column, self.rule, self.message)


@dataclass(frozen=True)
class Report:
    """The findings of one model. ``ok`` is true when none of them is an error."""

    findings: tuple[Finding, ...] = ()
    name: str = ""
    file: str = ""
    repeated: int = 0
    """Findings left out because an earlier report of the same run had them."""
    bounded: str = ""
    """What a proof by reach held for (``"forbidden states: within t <= 4 and 10 jumps"``),
    shown beside ``ok``: those proofs say nothing of a run past the horizon."""
    ran: tuple[str, ...] = ()
    """The rules the command decided, when not every rule of ``check`` (``hybrid reach``
    decides its verdicts' three): a JUnit suite passes only those it ran."""

    @property
    def ok(self) -> bool:
        return not any(f.severity == "error" for f in self.findings)

    def count(self, severity: str) -> int:
        return sum(1 for f in self.findings if f.severity == severity)

    def failed(self, *, strict: bool = False) -> bool:
        """Whether `hybrid check` exits 1 for this report."""
        return not self.ok or (strict and self.count("warning") > 0)

    def by_rule(self, rule: str) -> list[Finding]:
        return [f for f in self.findings if f.rule == rule]

    def __repr__(self) -> str:
        from hybrid.analysis.display import report_text

        return report_text(self)

    def _repr_html_(self) -> str:
        from hybrid.analysis.display import report_html

        return report_html(self)
