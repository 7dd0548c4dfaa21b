"""Pydantic models of the two spec files: an automaton and a system.

They check shape and types only (``extra="forbid"``); cross-references and
expressions are checked afterwards by :mod:`hybrid.reader.build`, which knows
positions. Expressions are kept as strings here; numbers and booleans written
where an expression belongs are turned into their source text.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated, Any, Literal, Union, get_args

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    StringConstraints,
    Tag,
    WithJsonSchema,
)

from hybrid.model import NAME

__all__ = [
    "AutomatonSpec",
    "ChecksSpec",
    "ComponentSpec",
    "EdgeSpec",
    "ForbiddenSpec",
    "InitialSetSpec",
    "InitialSpec",
    "InputSpec",
    "LocationSpec",
    "PropertiesSpec",
    "ReachChecksSpec",
    "RequirementSpec",
    "SignalSpec",
    "StateVarSpec",
    "SystemSpec",
]

NAME_PATTERN = rf"^{NAME}$"
QUALIFIED_PATTERN = rf"^{NAME}(\.{NAME})?$"

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
FiniteNumber = Annotated[float, Field(strict=True, allow_inf_nan=False)]
"""A parameter's value: NaN or infinite, every expression reading it would be."""
Interval = Annotated[
    tuple[Number, Number],
    WithJsonSchema(
        {
            "type": "array",
            "items": {"type": "number"},
            "minItems": 2,
            "maxItems": 2,
            "description": "[low, high]: a closed interval.",
        }
    ),
]


def _shape(value: Any) -> str | None:
    """The tag of a union member (``<...>``: left out of error paths, see messages.py)."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        return "<number>"
    if isinstance(value, list | tuple):
        return "<list>"
    if isinstance(value, dict):
        return "<mapping>"
    if isinstance(value, str):
        return "<name>"
    return None


def _union(message: str, *members: tuple[Any, str]) -> Any:
    """A union decided by the shape of the value, one clear error when no shape fits."""
    options = tuple(Annotated[tp, Tag(tag)] for tp, tag in members)
    return Annotated[
        Union[options],  # noqa: UP007 - a tuple of members needs the subscript form
        Discriminator(_shape, custom_error_type="shape", custom_error_message=message),
    ]


if TYPE_CHECKING:  # the members, for mypy
    StartValue = float | tuple[float, float]
else:
    StartValue = _union(
        "Input should be a valid number or an interval [low, high]",
        (Number, "<number>"),
        (Interval, "<list>"),
    )


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True, frozen=True)


class SignalSpec(_Strict):
    """A signal written as a mapping, to give it a unit: ``{expr: 0.5*v**2, unit: J}``."""

    expr: Expression = Field(description="The signal's definition (an expression).")
    unit: str | None = Field(None, description="Unit, for documentation and plots.")
    description: str = ""


def _signal_shape(value: Any) -> str:
    return "<mapping>" if isinstance(value, dict) else "<expression>"


if TYPE_CHECKING:  # the members, for mypy
    SignalDefinition = str | SignalSpec
else:
    SignalDefinition = Annotated[
        Union[  # noqa: UP007 - tagged members need the subscript form
            Annotated[Expression, Tag("<expression>")],
            Annotated[SignalSpec, Tag("<mapping>")],
        ],
        Discriminator(_signal_shape),
    ]


class StateVarSpec(_Strict):
    """One continuous state variable."""

    initial: StartValue = Field(
        0.0,
        description="Initial value, or an initial set [low, high] (overridden by initial.state).",
    )
    nominal: Number | None = Field(
        None, description="Where a run starts in the initial set (default: its midpoint)."
    )
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
    urgent: bool = Field(
        False, description="No time may pass here: an edge must fire at once, else blocked."
    )
    description: str = ""


class InitialSetSpec(_Strict):
    """An initial set with its nominal point, in `initial.state`."""

    initial: Interval = Field(description="[low, high]: the initial set of the variable.")
    nominal: Number | None = Field(None, description="Where a run starts (default: midpoint).")


if TYPE_CHECKING:
    InitialValue = float | tuple[float, float] | InitialSetSpec
    Locations = str | list[str]
else:
    InitialValue = _union(
        "expected a number, an interval [low, high] or {initial: [low, high], nominal: value}",
        (Number, "<number>"),
        (Interval, "<list>"),
        (InitialSetSpec, "<mapping>"),
    )
    Locations = _union(
        "expected a location name or a list of location names",
        (Name, "<name>"),
        (Annotated[list[Name], Field(min_length=1)], "<list>"),
    )


class InitialSpec(_Strict):
    """Where a run starts."""

    location: Locations | None = Field(
        None,
        description="The initial location, or several (check explores all; simulate starts "
        "in the first). Default: the first location (in a system: the component's own).",
    )
    state: dict[Name, InitialValue] = Field(default_factory=dict)


class InputSpec(_Strict):
    """A free input, optionally bounded."""

    range: Interval | None = Field(
        None, description="[low, high] the input stays within; check reasons over it."
    )
    nominal: Number | None = Field(
        None, description="Value a run holds the input at when none is given (default: midpoint)."
    )
    unit: str | None = None
    description: str = ""


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


if TYPE_CHECKING:
    Inputs = list[str] | dict[str, InputSpec]
else:
    Inputs = _union(
        "expected a list of input names, or a mapping of names to {range: [low, high]}",
        (list[Name], "<list>"),
        (dict[Name, InputSpec], "<mapping>"),
    )


class ForbiddenSpec(_Strict):
    """A set of bad states: a location (or locations per component) and a condition."""

    location: QualifiedName | None = Field(
        None, description="The location (comp.location in a system); none: any location."
    )
    locations: dict[Name, Name] | None = Field(
        None, description="In a system: component -> location, all at once."
    )
    when: Expression | None = Field(None, description="Condition on the state (default: true).")
    description: str = ""


class PropertiesSpec(_Strict):
    """Properties `hybrid check` proves (or refutes with a witness)."""

    reachable: list[QualifiedName] = Field(default_factory=list)
    unreachable: list[QualifiedName] = Field(default_factory=list)
    deadlock_free: bool | None = None
    deterministic: bool | None = None
    forbidden: list[ForbiddenSpec] = Field(default_factory=list)


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


RuleId = Literal[
    "unreachable-location",
    "sink-location",
    "blocked-start",
    "dead-edge",
    "nondeterminism",
    "zero-time-cycle",
    "unused-declaration",
    "property-violated",
    "property-disproved",
    "property-unproved",
    "analysis-incomplete",
]
"""The rules of `hybrid check` a spec may silence (hybrid.analysis.findings.RULES has them all)."""
RULE_IDS: tuple[str, ...] = get_args(RuleId)
""":data:`RuleId`'s names, in its order."""


class ReachChecksSpec(_Strict):
    """The horizon of `hybrid reach`, used by `hybrid check` for forbidden entries."""

    t_end: Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)] = Field(
        description="Horizon: reach proves or refutes forbidden entries over [0, t_end]."
    )
    max_jumps: Annotated[int, Field(strict=True, ge=0)] = Field(
        10, description="Jump bound of the proof."
    )
    step: Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)] | None = Field(
        None, description="Flowpipe step (default t_end / 4000): smaller is tighter and slower."
    )


class ChecksSpec(_Strict):
    """How `hybrid check` treats this file."""

    ignore: list[RuleId] = Field(
        default_factory=list,
        description="Rules not to report for findings placed in this file.",
    )
    reach: ReachChecksSpec | None = Field(
        None,
        description="Decide forbidden entries with `hybrid reach` over this horizon "
        "(affine models; docs/reach.md).",
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
    parameters: dict[Name, FiniteNumber] = Field(default_factory=dict)
    state: dict[Name, StateVarSpec] = Field(default_factory=dict)
    signals: dict[Name, SignalDefinition] = Field(
        default_factory=dict,
        description="Signals: name: expression, or name: {expr: expression, unit: unit}.",
    )
    inputs: Inputs = Field(default_factory=list)
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
    rename: dict[Name, Name] = Field(
        default_factory=dict,
        description="old: new names of the spec's state variables, signals, inputs and labels.",
    )
    parameters: dict[Name, FiniteNumber] = Field(default_factory=dict)
    initial: InitialSpec | None = None


class SystemSpec(_Strict):
    """Parallel composition of automata."""

    system: Name
    description: str = ""
    components: list[ComponentSpec] = Field(min_length=1)
    properties: PropertiesSpec | None = None
    requirements: list[RequirementSpec] = Field(default_factory=list)
    checks: ChecksSpec | None = None
