"""The SpaceEx model file as a small intermediate representation.

A ``<sspaceex>`` document holds components. A *base* component declares
parameters (``<param>``: real variables, constants, labels), locations (each
with an ``<invariant>`` and a ``<flow>``) and transitions (``<guard>``,
``<assignment>``, ``<label>``). A *network* component declares parameters and
``<bind>`` elements, each instantiating another component ``as`` a name with
``<map key="inner">outer-name-or-number</map>`` renamings. Expressions stay
text (with positions) until :mod:`hybrid.interchange.translate` reads them.

Examples
--------
>>> from hybrid.interchange.safexml import parse_xml_text
>>> doc = read_model(parse_xml_text('''<sspaceex><component id="c">
...   <param name="x" type="real" local="false" d1="1" d2="1" dynamics="any"/>
...   <location id="1" name="run"><flow>x' == 1</flow></location>
... </component></sspaceex>''', "m.xml"))
>>> base = doc.components["c"]
>>> base.is_network, list(base.params), base.locations[0].name
(False, ['x'], 'run')
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from hybrid.errors import Position, SpecError
from hybrid.interchange.safexml import SourceText, XmlNode

__all__ = ["Bind", "Component", "Location", "Param", "SpaceExModel", "Transition", "read_model"]

_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class Param:
    """A ``<param>``: ``kind`` is ``real`` or ``label``; ``dynamics`` ``any``, ``const``..."""

    name: str
    kind: str
    local: bool
    dynamics: str
    controlled: bool | None
    position: Position


@dataclass(frozen=True)
class Location:
    id: str
    name: str
    invariant: SourceText
    flow: SourceText
    position: Position


@dataclass(frozen=True)
class Transition:
    source: str
    target: str
    label: str | None
    guard: SourceText
    assignment: SourceText
    position: Position
    label_position: Position


@dataclass(frozen=True)
class Bind:
    """``<bind component="K" as="name">`` with its ``key -> text`` maps."""

    component: str
    name: str
    maps: dict[str, tuple[str, Position]]
    position: Position


@dataclass
class Component:
    id: str
    params: dict[str, Param]
    position: Position
    locations: list[Location] = field(default_factory=list)
    transitions: list[Transition] = field(default_factory=list)
    binds: list[Bind] = field(default_factory=list)
    note: str = ""

    @property
    def is_network(self) -> bool:
        return bool(self.binds)


@dataclass
class SpaceExModel:
    """The components of one file, in file order."""

    file: str
    components: dict[str, Component]
    position: Position


def _attr(node: XmlNode, name: str, default: str | None = None) -> str:
    value = node.attrs.get(name, default)
    if value is None:
        raise SpecError(f"<{node.tag}> needs the attribute '{name}'", node.position)
    return value


def _flag(node: XmlNode, name: str) -> bool | None:
    value = node.attrs.get(name)
    if value is None:
        return None
    if value.strip().lower() in ("true", "1", "yes"):
        return True
    if value.strip().lower() in ("false", "0", "no"):
        return False
    raise SpecError(f"attribute {name}='{value}' must be true or false", node.position)


def _identifier(value: str, what: str, position: Position) -> str:
    if not _IDENT.match(value):
        raise SpecError(
            f"{what} '{value}' is not a name ([A-Za-z_][A-Za-z0-9_]*); rename it in the model",
            position,
        )
    return value


def _text(node: XmlNode | None, owner: XmlNode) -> SourceText:
    if node is None:
        return SourceText(owner.text.file, "", [], owner.position)
    return node.text


def _param(node: XmlNode) -> Param:
    name = _identifier(_attr(node, "name"), "parameter", node.position)
    kind = _attr(node, "type", "real")
    if kind not in ("real", "label", "int", "integer"):
        raise SpecError(f"parameter type '{kind}' is not supported (real or label)", node.position)
    for dim in ("d1", "d2"):
        if node.attrs.get(dim, "1").strip() != "1":
            raise SpecError(
                f"parameter '{name}' has {dim}={node.attrs[dim]}: only scalars (d1=d2=1) are "
                "supported; write one parameter per entry",
                node.position,
            )
    dynamics = node.attrs.get("dynamics", "any")
    if kind == "real" and dynamics not in ("any", "const", "explicit"):
        raise SpecError(f"dynamics='{dynamics}' is not supported (any or const)", node.position)
    return Param(
        name,
        "label" if kind == "label" else "real",
        bool(_flag(node, "local")),
        dynamics,
        _flag(node, "controlled"),
        node.position,
    )


def _component(node: XmlNode) -> Component:
    cid = _attr(node, "id")
    params: dict[str, Param] = {}
    for p in node.find_all("param"):
        param = _param(p)
        if param.name in params:
            raise SpecError(
                f"parameter '{param.name}' is declared twice (also at line "
                f"{params[param.name].position.line})",
                p.position,
            )
        params[param.name] = param
    note = node.find("note")
    comp = Component(cid, params, node.position, note=note.text.text.strip() if note else "")
    for loc in node.find_all("location"):
        comp.locations.append(
            Location(
                _attr(loc, "id"),
                loc.attrs.get("name", "").strip(),
                _text(loc.find("invariant"), loc),
                _text(loc.find("flow"), loc),
                loc.position,
            )
        )
    for tr in node.find_all("transition"):
        label = tr.find("label")
        comp.transitions.append(
            Transition(
                _attr(tr, "source"),
                _attr(tr, "target"),
                label.text.text.strip() or None if label is not None else None,
                _text(tr.find("guard"), tr),
                _text(tr.find("assignment"), tr),
                tr.position,
                label.position if label is not None else tr.position,
            )
        )
    for bind in node.find_all("bind"):
        maps: dict[str, tuple[str, Position]] = {}
        for m in bind.find_all("map"):
            key = _attr(m, "key")
            start = m.text.chunks[0] if m.text.chunks else None
            where = Position(m.text.file, start[1], start[2]) if start else m.position
            maps[key] = (m.text.text.strip(), where)
        comp.binds.append(
            Bind(
                _attr(bind, "component"),
                _attr(bind, "as").strip(),
                maps,
                bind.position,
            )
        )
    if comp.binds and comp.locations:
        raise SpecError(
            f"component '{cid}' has both locations and binds; SpaceEx components have one or "
            "the other",
            node.position,
        )
    ids = [loc.id for loc in comp.locations]
    for transition in comp.transitions:
        for end in (transition.source, transition.target):
            if end not in ids:
                raise SpecError(
                    f"transition refers to unknown location id '{end}'", transition.position
                )
    return comp


def read_model(root: XmlNode) -> SpaceExModel:
    """Read a parsed ``<sspaceex>`` document into a :class:`SpaceExModel`.

    Raises
    ------
    SpecError
        With the position of the first element that does not fit.
    """
    if root.tag != "sspaceex":
        raise SpecError(
            f"the root element is <{root.tag}>, not <sspaceex>: is this a SpaceEx model?",
            root.position,
        )
    components: dict[str, Component] = {}
    for node in root.find_all("component"):
        comp = _component(node)
        if comp.id in components:
            raise SpecError(f"component id '{comp.id}' is used twice", node.position)
        components[comp.id] = comp
    if not components:
        raise SpecError("the model has no <component>", root.position)
    for comp in components.values():
        for bind in comp.binds:
            if bind.component not in components:
                raise SpecError(
                    f"bind of unknown component '{bind.component}' (known: "
                    f"{', '.join(components)})",
                    bind.position,
                )
    return SpaceExModel(root.position.file, components, root.position)
