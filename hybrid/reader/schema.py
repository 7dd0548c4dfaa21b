"""Pydantic models of the two spec files: an automaton and a system.

They check shape and types only (``extra="forbid"``); cross-references and
expressions are checked afterwards by :mod:`hybrid.reader.build`, which knows
positions. Expressions are kept as strings here; numbers and booleans written
where an expression belongs are turned into their source text.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StringConstraints,
    WithJsonSchema,
)

__all__ = [
    "AutomatonSpec",
    "ChecksSpec",
    "ComponentSpec",
    "EdgeSpec",
    "InitialSpec",
    "LocationSpec",
    "PropertiesSpec",
    "RequirementSpec",
    "StateVarSpec",
    "SystemSpec",
]

NAME_PATTERN = r"^[A-Za-z_][A-Za-z0-9_]*$"
QUALIFIED_PATTERN = r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)?$"

Name = Annotated[str, StringConstraints(pattern=NAME_PATTERN, max_length=128)]
QualifiedName = Annotated[str, StringConstraints(pattern=QUALIFIED_PATTERN, max_length=257)]


def _expression_text(value: Any) -> Any:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError("an expression must be finite; write a number or a formula")
        return repr(value)
    return value


Expression = Annotated[
    str,
    BeforeValidator(_expression_text),
    Field(min_length=1),
    WithJsonSchema(
        {
            "type": ["string", "number", "boolean"],
            "description": "An expression (see docs/spec-language.md).",
        }
    ),
]
Number = Annotated[float, Field(strict=True)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True, frozen=True)


class StateVarSpec(_Strict):
    """One continuous state variable."""

    initial: Number = Field(0.0, description="Initial value (overridden by initial.state).")
    bounds: tuple[Number, Number] | None = Field(
        None, description="[low, high] the variable stays within; used by static checks."
    )
    unit: str | None = Field(None, description="Unit, for documentation and plots.")
    description: str = ""


class LocationSpec(_Strict):
    """A location (discrete mode): its flow, local signals and invariant."""

    flow: dict[Name, Expression] = Field(
        default_factory=dict, description="x' per state variable; one left out has derivative 0."
    )
    signals: dict[Name, Expression] = Field(
        default_factory=dict,
        description="Location-specific signal definitions (override `signals`).",
    )
    invariant: Expression = Field("true", description="Condition that must hold while here.")
    description: str = ""


class InitialSpec(_Strict):
    """Where a run starts."""

    location: Name
    state: dict[Name, Number] = Field(default_factory=dict)


class EdgeSpec(_Strict):
    """A discrete transition."""

    name: Name | None = Field(None, description='Default "<from>-><to>#<index>".')
    source: Name = Field(alias="from")
    target: Name = Field(alias="to")
    label: Name | None = None
    guard: Expression = "true"
    reset: dict[Name, Expression] = Field(default_factory=dict)
    priority: int = Field(0, description="Higher fires first among edges enabled at once.")
    description: str = ""


class PropertiesSpec(_Strict):
    """Properties `hybrid check` proves (or refutes with a witness)."""

    reachable: list[QualifiedName] = Field(default_factory=list)
    unreachable: list[QualifiedName] = Field(default_factory=list)
    deadlock_free: bool | None = None
    deterministic: bool | None = None


class RequirementSpec(_Strict):
    """A requirement every simulated trajectory is monitored for (docs/semantics.md)."""

    name: Name
    always: Expression | None = Field(
        None, description="A condition that must hold at every point in scope."
    )
    eventually: Expression | None = Field(
        None, description="A condition that must hold at some point in scope."
    )
    within: tuple[Number, Number] | None = Field(
        None, description="[start, end]: only this window of time t (ends included)."
    )
    location: QualifiedName | None = Field(
        None,
        alias="in",
        description="Only while in this location (comp.loc in a system file).",
    )
    description: str = ""


RULE_IDS = (
    "unreachable-location",
    "sink-location",
    "dead-edge",
    "nondeterminism",
    "zero-time-cycle",
    "unused-declaration",
    "property-violated",
    "analysis-incomplete",
)
"""The rules of `hybrid check` a spec may silence (hybrid.analysis.findings.RULES has them all)."""
RuleId = Literal[
    "unreachable-location",
    "sink-location",
    "dead-edge",
    "nondeterminism",
    "zero-time-cycle",
    "unused-declaration",
    "property-violated",
    "analysis-incomplete",
]


class ChecksSpec(_Strict):
    """How `hybrid check` treats this file."""

    ignore: list[RuleId] = Field(
        default_factory=list,
        description="Rules not to report for findings placed in this file.",
    )


class AutomatonSpec(_Strict):
    """A hybrid automaton M = (L, X, A, W, E, Inv, Act)."""

    model_config = ConfigDict(
        extra="forbid",
        populate_by_name=True,
        frozen=True,
        json_schema_extra={"title": "hybrid automaton"},
    )

    automaton: Name
    description: str = ""
    parameters: dict[Name, Number] = Field(default_factory=dict)
    state: dict[Name, StateVarSpec] = Field(default_factory=dict)
    signals: dict[Name, Expression] = Field(default_factory=dict)
    inputs: list[Name] = Field(default_factory=list)
    labels: list[Name] = Field(default_factory=list)
    locations: dict[Name, LocationSpec] = Field(min_length=1)
    initial: InitialSpec | None = None
    edges: list[EdgeSpec] = Field(default_factory=list)
    properties: PropertiesSpec | None = None
    requirements: list[RequirementSpec] = Field(default_factory=list)
    checks: ChecksSpec | None = None
    uses: list[Name] = Field(default_factory=list)


class ComponentSpec(_Strict):
    """One component of a system: a spec file and its overrides."""

    spec: str = Field(description="Path of an automaton spec, relative to this file.")
    name: Name | None = Field(None, alias="as")
    parameters: dict[Name, Number] = Field(default_factory=dict)
    initial: InitialSpec | None = None


class SystemSpec(_Strict):
    """Parallel composition of automata."""

    system: Name
    description: str = ""
    components: list[ComponentSpec] = Field(min_length=1)
    properties: PropertiesSpec | None = None
    requirements: list[RequirementSpec] = Field(default_factory=list)
    checks: ChecksSpec | None = None
