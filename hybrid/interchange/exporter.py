"""``hybrid export spaceex``: one of our models as a SpaceEx model file and ``.cfg``.

Each component becomes a base component (state variables controlled,
inputs uncontrolled, parameters constants, labels labels), bound by one
network component that sets every parameter to its value. Signals are inlined
into the expressions that use them (a location's own definitions in that
location); an input that another component's signal provides is replaced by
that signal's definition, whose variables the component then reads as shared
variables; an input no component provides stays a shared variable of the
network. A variable left out of a location's flow gets ``x' == 0`` (SpaceEx
would let it change arbitrarily). The time ``t``, if used, is the variable of
an added ``clock`` component. The ``.cfg`` gives the system, the initial
location and state, and the locations declared unreachable as the forbidden set.

What SpaceEx lacks is said in XML comments: our edges fire as soon as their
guard holds (SpaceEx: may fire while enabled) and by priority (SpaceEx: none).
What it cannot express (library functions, ``abs``/``min``/``max``, vector
signals, ``!=``, a signal that differs by location used by another component)
is refused with :class:`~hybrid.errors.SpecError` naming it.

Examples
--------
>>> import hybrid
>>> out = export_spaceex(hybrid.load("specs/bouncing_ball.yaml"))
>>> "<flow>h' == v &amp; v' == -g</flow>" in out.xml, out.cfg.splitlines()[0]
(True, 'system = "bouncing_ball_system"')
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from xml.sax.saxutils import escape, quoteattr

from hybrid.compose import System, as_system
from hybrid.errors import Position, SpecError
from hybrid.expr import ir
from hybrid.expr.transform import bind_parameters
from hybrid.interchange.cfgwrite import number_text as _number
from hybrid.interchange.cfgwrite import spaceex_cfg
from hybrid.interchange.sxprint import Unsupported, spaceex_text
from hybrid.model import Automaton, Forbidden

__all__ = ["ExportResult", "export_spaceex"]

_NS = "http://www-verimag.imag.fr/xml-namespaces/sspaceex"
MAX_INLINE_DEPTH = 64
"""Deepest chain of signals defined through signals that is inlined."""


@dataclass
class ExportResult:
    """The SpaceEx model text, the ``.cfg`` text, and what the translation had to say."""

    xml: str
    cfg: str
    notes: list[str] = field(default_factory=list)


def _comment(text: str) -> str:
    return "<!-- " + text.replace("--", "- -") + " -->"


def _inline(node: ir.Expr, defs: Mapping[str, ir.Expr], depth: int = 0) -> ir.Expr:
    """``node`` with every signal or input in ``defs`` replaced by its definition."""
    if depth > MAX_INLINE_DEPTH:
        raise Unsupported("signals defined through each other too deeply")
    if isinstance(node, ir.Var):
        if node.kind in (ir.SIGNAL, ir.INPUT) and node.name in defs:
            return _inline(defs[node.name], defs, depth + 1)
        return node
    if isinstance(node, ir.Index):
        raise Unsupported(f"vector signal '{node.name}[{node.index}]'")
    if isinstance(node, ir.Call):
        return replace(node, args=tuple(_inline(a, defs, depth) for a in node.args))
    if isinstance(node, ir.Unary | ir.Not):
        return replace(node, operand=_inline(node.operand, defs, depth))
    if isinstance(node, ir.Bin):
        return replace(
            node, left=_inline(node.left, defs, depth), right=_inline(node.right, defs, depth)
        )
    if isinstance(node, ir.Cmp):
        return replace(node, operands=tuple(_inline(o, defs, depth) for o in node.operands))
    if isinstance(node, ir.BoolOp):
        return replace(node, values=tuple(_inline(v, defs, depth) for v in node.values))
    return node


def _provided(system: System, index: int) -> dict[str, ir.Expr]:
    """Each input of component ``index`` that another component's signal provides -> definition."""
    found: dict[str, ir.Expr] = {}
    automaton = system.components[index].automaton
    for name in automaton.inputs:
        for j, other in enumerate(system.components):
            a = other.automaton
            if j == index or name not in a.signal_names:
                continue
            if any(name in loc.signals for loc in a.locations.values()):
                raise SpecError(
                    f"input '{name}' of component '{system.components[index].name}' is a signal "
                    f"of '{other.name}' that differs by location: SpaceEx has no counterpart "
                    "(a component cannot read another's location); define it once",
                    a.signal_positions.get(name, a.position),
                )
            own = {s: d for s, d in a.signals.items() if s != name}
            where = a.signal_positions.get(name, a.position)
            try:
                definition = _inline(a.signals[name], own)
            except Unsupported as exc:
                raise SpecError(
                    f"cannot export to SpaceEx: input '{name}' of component "
                    f"'{system.components[index].name}' reads {exc}, which has no SpaceEx "
                    "counterpart",
                    where,
                ) from None
            found[name] = bind_parameters(definition, a.parameters)
    return found


class _Component:
    """The XML of one base component."""

    def __init__(self, system: System, index: int, notes: list[str]) -> None:
        self.system = system
        self.index = index
        self.comp = system.components[index]
        self.a: Automaton = self.comp.automaton
        self.notes = notes
        self.provided = _provided(system, index)
        self.uses_time = False
        self.read: set[str] = set()
        taken = {*system.state_names, *system.signal_names, *system.free_inputs, "t"}
        self.clock = _fresh("urgent_clock", taken) if _urgent(self.a) else None
        """A clock that keeps time from passing in urgent locations (``clock <= 0`` there)."""

    def text(self, node: ir.Expr, location: str | None, where: Position) -> str:
        defs: dict[str, ir.Expr] = dict(self.a.signals)
        if location is not None:
            defs.update(self.a.locations[location].signals)
        defs.update(self.provided)
        try:
            inlined = _inline(node, defs)
            for n in ir.walk(inlined):
                if isinstance(n, ir.Var) and n.kind == ir.TIME:
                    self.uses_time = True
                elif isinstance(n, ir.Var) and n.kind in (ir.STATE, ir.INPUT):
                    self.read.add(n.name)
            return spaceex_text(inlined)
        except Unsupported as exc:
            raise SpecError(
                f"cannot export to SpaceEx: {exc} has no SpaceEx counterpart", where
            ) from None

    @property
    def states(self) -> list[str]:
        """The component's state variables, its urgent clock included."""
        return [*self.a.state_names, *([self.clock] if self.clock else [])]

    def xml(self) -> list[str]:
        a = self.a
        lines: list[str] = []
        body: list[str] = []
        ids = {name: str(i + 1) for i, name in enumerate(a.locations)}
        ranges = [
            f"{_number(r.lo)} <= {u} & {u} <= {_number(r.hi)}"
            for u, r in self.system.input_ranges().items()
            if u in a.inputs
        ]
        if ranges:
            self.read.update(u for u in self.system.input_ranges() if u in a.inputs)
        for name, loc in a.locations.items():
            flow = " & ".join(
                f"{s}' == {self.text(loc.flow[s], name, loc.position) if s in loc.flow else '0'}"
                for s in a.state_names
            )
            if self.clock is not None:
                flow += f"{' & ' if flow else ''}{self.clock}' == 1"
            body.append(f'    <location id="{ids[name]}" name={quoteattr(name)}>')
            if loc.urgent:
                body.append(
                    "      "
                    + _comment(
                        f"urgent location: no time may pass here ({self.clock} <= 0; "
                        f"{self.clock} := 0 on every transition into it)"
                    )
                )
            invariant = self.text(loc.invariant, name, loc.invariant_position)
            extra = [*ranges, *([f"{self.clock} <= 0"] if loc.urgent else [])]
            if extra:
                parts = [] if invariant == "true" else [_grouped(invariant)]
                invariant = " & ".join([*parts, *extra])
            if invariant != "true":
                body.append(f"      <invariant>{escape(invariant)}</invariant>")
            if flow:
                body.append(f"      <flow>{escape(flow)}</flow>")
            body.append("    </location>")
        for edge in a.edges:
            body.append(f'    <transition source="{ids[edge.source]}" target="{ids[edge.target]}">')
            if edge.priority:
                body.append(
                    "      "
                    + _comment(
                        f"edge '{edge.name}' has priority {edge.priority}: SpaceEx has no priorities "
                        "(it may take any enabled transition)"
                    )
                )
            if edge.label is not None:
                body.append(f"      <label>{escape(edge.label)}</label>")
            guard = self.text(edge.guard, edge.source, edge.guard_position)
            if guard != "true":
                body.append(f"      <guard>{escape(guard)}</guard>")
            assigned = [
                f"{k} := {self.text(v, edge.source, edge.position)}" for k, v in edge.reset.items()
            ]
            if self.clock is not None and a.locations[edge.target].urgent:
                assigned.append(f"{self.clock} := 0")
            if assigned:
                body.append(f"      <assignment>{escape(' & '.join(assigned))}</assignment>")
            body.append("    </transition>")
        lines.append(f"  <component id={quoteattr(self.comp.name)}>")
        for s in self.states:
            lines.append(_param(s, "any", controlled=True))
        for name in sorted(self.read - set(a.state_names)):
            lines.append(_param(name, "any", controlled=False))
        if self.uses_time:
            lines.append(_param("t", "any", controlled=False))
        for p in a.parameters:
            lines.append(_param(p, "const", controlled=None))
        for label in a.labels:
            lines.append(f'    <param name={quoteattr(label)} type="label" local="false" />')
        lines.extend(body)
        lines.append("  </component>")
        return lines


def _urgent(a: Automaton) -> bool:
    return any(loc.urgent for loc in a.locations.values())


def _fresh(stem: str, taken: set[str]) -> str:
    name, k = stem, 1
    while name in taken:
        k += 1
        name = f"{stem}{k}"
    return name


def _grouped(condition: str) -> str:
    """A condition to conjoin: in parentheses when it has a disjunction."""
    return f"({condition})" if "|" in condition else condition


def _param(name: str, dynamics: str, controlled: bool | None) -> str:
    extra = "" if controlled is None else f' controlled="{str(controlled).lower()}"'
    return (
        f'    <param name={quoteattr(name)} type="real" local="false" d1="1" d2="1" '
        f'dynamics="{dynamics}"{extra} />'
    )


def export_spaceex(model: Automaton | System) -> ExportResult:
    """The SpaceEx model and ``.cfg`` of ``model`` (see the module docstring).

    Raises
    ------
    SpecError
        At the construct that has no SpaceEx counterpart.
    """
    system = as_system(model)
    notes: list[str] = []
    parts = [_Component(system, i, notes) for i in range(len(system.components))]
    bodies = [p.xml() for p in parts]
    clock = any(p.uses_time for p in parts)
    network = f"{system.name}_system"
    head = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<sspaceex xmlns="{_NS}" version="0.2" math="SpaceEx">',
        "  "
        + _comment(
            f"Exported by `hybrid export spaceex` from '{system.name}'. Our edges fire as soon as "
            "their guard holds, by priority; SpaceEx may take an enabled transition at any time "
            "and has no priorities: SpaceEx's runs include ours and more."
        ),
    ]
    lines = list(head)
    for body in bodies:
        lines.extend(body)
    shared = sorted({v for p in parts for v in [*p.read, *p.states]})
    if clock:
        lines += [
            '  <component id="clock">',
            _param("t", "any", controlled=True),
            '    <location id="1" name="running">',
            "      <flow>t' == 1</flow>",
            "    </location>",
            "  </component>",
        ]
        notes.append("the time t is the variable of an added 'clock' component (t' == 1, t == 0)")
    lines.append(f"  <component id={quoteattr(network)}>")
    for name in shared + (["t"] if clock else []):
        lines.append(_param(name, "any", controlled=True))
    for label in system.labels:
        lines.append(f'    <param name={quoteattr(label)} type="label" local="false" />')
    for p in parts:
        lines.append(f"    <bind component={quoteattr(p.comp.name)} as={quoteattr(p.comp.name)}>")
        for name in [*p.states, *sorted(p.read - set(p.states))]:
            lines.append(f"      <map key={quoteattr(name)}>{escape(name)}</map>")
        if p.uses_time:
            lines.append('      <map key="t">t</map>')
        for key, value in p.a.parameters.items():
            lines.append(f"      <map key={quoteattr(key)}>{_number(value)}</map>")
        for label in p.a.labels:
            lines.append(f"      <map key={quoteattr(label)}>{escape(label)}</map>")
        lines.append("    </bind>")
    if clock:
        lines.append('    <bind component="clock" as="clock">')
        lines.append('      <map key="t">t</map>')
        lines.append("    </bind>")
    lines += ["  </component>", "</sspaceex>", ""]
    for p in parts:
        if p.clock is not None:
            notes.append(
                f"component '{p.comp.name}': urgent locations keep time from passing with the "
                f"added clock '{p.clock}' (<= 0 there, reset on entry): SpaceEx has no urgency"
            )
    ranges = [*system.initial_set().values(), *system.input_ranges().values()]
    if any(r.given and not r.is_point for r in ranges):
        notes.append(
            "nominal values have no SpaceEx counterpart: the .cfg gives the sets; an import "
            "starts simulations at their midpoints"
        )
    notes.extend(_not_exported(system))
    clocks = [p.clock for p in parts if p.clock is not None]
    cfg = spaceex_cfg(system, network, clock, clocks, _forbidden(system))
    return ExportResult("\n".join(lines), cfg, notes)


def _not_exported(system: System) -> list[str]:
    """Notes on what the spec says that SpaceEx has no place for (left out, not silently)."""
    props = system.properties
    left = []
    if props.reachable:
        left.append(f"reachable: {', '.join(props.reachable)}")
    for name in ("deadlock_free", "deterministic"):
        if getattr(props, name) is not None:
            left.append(name)
    if props.reach_t_end is not None:
        left.append("checks: reach")
    notes = []
    if left:
        notes.append(
            f"properties not exported ({'; '.join(left)}): a .cfg states forbidden sets only "
            "(unreachable locations and forbidden states are exported as its forbidden set)"
        )
    if any(c.automaton.requirements for c in system.components):
        notes.append("requirements: are not exported: SpaceEx has no trajectory requirements")
    named = (  # an edge without a name is called source->target#k, as an import calls it
        e.name != f"{e.source}->{e.target}#{k}"
        for c in system.components
        for k, e in enumerate(c.automaton.edges)
    )
    if any(named):
        notes.append(
            "edge names are not exported (SpaceEx transitions have labels only): an import "
            "names each edge source->target#k"
        )
    return notes


def _forbidden(system: System) -> list[str]:
    """The ``.cfg``'s forbidden disjuncts: unreachable locations, then forbidden states."""
    found = []
    for name in system.properties.unreachable:
        comp, _, loc = name.rpartition(".")
        found.append(f"loc({comp or system.components[0].name})=={loc}")
    for entry in system.properties.forbidden:
        parts = [
            f"loc({comp or system.components[0].name})=={loc}"
            for comp, loc in entry.locations.items()
        ]
        if entry.when is not None:
            parts.append(_grouped(_condition(system, entry)))
        found.append(" & ".join(parts) or "true")
    return found


def _condition(system: System, entry: Forbidden) -> str:
    """The ``when`` of a forbidden entry in SpaceEx syntax, signals and parameters inlined."""
    assert entry.when is not None
    defs: dict[str, ir.Expr] = {}
    when = entry.when
    for i, c in enumerate(system.components):
        a = c.automaton
        location = entry.locations.get("" if system.single else c.name)
        signals = dict(a.signals)
        if location is not None:
            signals.update(a.locations[location].signals)
        varying = {n for loc in a.locations.values() for n in loc.signals}
        for name, definition in signals.items():
            if location is None and name in varying:
                definition = ir.Var(name, "varying")  # refused below if read
            defs[name] = bind_parameters(definition, a.parameters)
        defs.update(_provided(system, i))
        if system.single:
            when = bind_parameters(when, a.parameters)
    try:
        inlined = _inline(when, defs)
        varying_read = [
            n.name for n in ir.walk(inlined) if isinstance(n, ir.Var) and n.kind == "varying"
        ]
        if varying_read:
            raise Unsupported(
                f"signal '{varying_read[0]}', which differs by location, read without a location"
            )
        return spaceex_text(inlined)
    except Unsupported as exc:
        raise SpecError(
            f"cannot export to SpaceEx: the forbidden state reads {exc}, which has no SpaceEx "
            "counterpart",
            entry.position,
        ) from None
