"""Network components unfolded into their leaves: base components with renamings.

A network binds components ``as`` instance names, mapping each inner
parameter to a parameter of the network (or, for a constant, to a number).
Unfolding the binds from the chosen system down gives the *leaves*: one per
base-component instance, with the system-level variable each of its variables
stands for and the value of each of its constants.

System-level variables are identified as SpaceEx's ``.cfg`` names them: a
parameter of the system itself by its name (``x``), a local variable of an
instance by the instance path (``osc.osci.y``, ``f4.x1``). A non-local
parameter left out of a bind's maps stands for the network's parameter of the
same name, if there is one; otherwise it is local to the instance.

Examples
--------
>>> from hybrid.interchange.safexml import parse_xml_text
>>> from hybrid.interchange.sxmodel import read_model
>>> model = read_model(parse_xml_text('''<sspaceex>
... <component id="k"><param name="x" type="real" local="false" dynamics="any"/>
...   <param name="y" type="real" local="true" dynamics="any"/>
...   <param name="c" type="real" local="false" dynamics="const"/>
...   <location id="1" name="l"><flow>x' == c &amp; y' == 1</flow></location></component>
... <component id="sys"><param name="z" type="real" local="false" dynamics="any"/>
...   <bind component="k" as="a"><map key="x">z</map><map key="c">2</map></bind></component>
... </sspaceex>''', "m.xml"))
>>> leaf = flatten(model, "sys").leaves[0]
>>> leaf.name, leaf.variables, leaf.constants
('a', {'x': 'z', 'y': 'a.y'}, {'c': 2.0})
"""

from __future__ import annotations

from dataclasses import dataclass, field

from hybrid.errors import Position, SpecError
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.naming import component_name
from hybrid.interchange.safexml import SourceText
from hybrid.interchange.sxmodel import Component, SpaceExModel
from hybrid.interchange.translate import constant_value

__all__ = ["Flat", "Leaf", "flatten"]

MAX_LEAVES = 10_000
"""Most base-component instances one system may unfold into."""


@dataclass
class Leaf:
    """One instance of a base component inside the system."""

    path: tuple[str, ...]
    component: Component
    variables: dict[str, str]
    """Real variable of the base component -> system-level variable id."""
    labels: dict[str, str]
    """Label of the base component -> system-level label id."""
    constants: dict[str, float | None]
    """Constant -> its value (``None``: a constant of the system itself, left open)."""
    open_constants: dict[str, str] = field(default_factory=dict)
    """Constant -> the system constant it stands for, where the value is left open."""
    position: Position = field(default_factory=lambda: Position("<xml>"))
    index: int = 0
    """Place among the system's leaves."""

    @property
    def name(self) -> str:
        """The component name in our system: the instance path joined by ``_`` (made a name)."""
        return component_name("_".join(self.path) if self.path else self.component.id)


@dataclass
class Flat:
    """The leaves of a system and its own variables."""

    system: Component
    leaves: list[Leaf]
    variable_ids: list[str]
    """Every system-level real variable id, in order of first appearance."""
    label_ids: list[str]
    notes: list[str] = field(default_factory=list)


_Binding = tuple[str, str | float | None]
"""``("var", id)``, ``("label", id)``, ``("const", value or None)`` or ``("open", name)``."""


def _top_env(system: Component) -> dict[str, _Binding]:
    env: dict[str, _Binding] = {}
    for p in system.params.values():
        if p.kind == "label":
            env[p.name] = ("label", p.name)
        elif p.dynamics == "const":
            env[p.name] = ("open", p.name)
        else:
            env[p.name] = ("var", p.name)
    return env


def flatten(model: SpaceExModel, system: str) -> Flat:
    """Unfold ``system`` (a component id of ``model``) into its leaves.

    Raises
    ------
    SpecError
        For an unknown system, a bind cycle, or a map that does not fit the
        parameter it sets.
    """
    if system not in model.components:
        raise SpecError(
            f"the system '{system}' is not a component of the model (components: "
            f"{', '.join(model.components)})",
            model.position,
        )
    top = model.components[system]
    flat = Flat(top, [], [], [])
    _unfold(model, top, (), _top_env(top), flat, (system,), top.position)
    seen_vars: dict[str, None] = {}
    seen_labels: dict[str, None] = {}
    for p in top.params.values():
        (seen_labels if p.kind == "label" else seen_vars).setdefault(p.name)
    for leaf in flat.leaves:
        for vid in leaf.variables.values():
            seen_vars.setdefault(vid)
        for lid in leaf.labels.values():
            seen_labels.setdefault(lid)
    flat.variable_ids = [v for v in seen_vars if v not in _open_names(top)]
    flat.label_ids = list(seen_labels)
    return flat


def _open_names(top: Component) -> set[str]:
    return {p.name for p in top.params.values() if p.kind == "real" and p.dynamics == "const"}


def _unfold(
    model: SpaceExModel,
    comp: Component,
    path: tuple[str, ...],
    env: dict[str, _Binding],
    flat: Flat,
    stack: tuple[str, ...],
    position: Position,
) -> None:
    if not comp.is_network:
        _add_leaf(comp, path, env, flat, position)
        return
    for bind in comp.binds:
        if bind.component in stack:
            raise SpecError(
                f"component '{bind.component}' binds itself (through {' -> '.join(stack)})",
                bind.position,
            )
        child = model.components[bind.component]
        unknown = [k for k in bind.maps if k not in child.params]
        if unknown:
            raise SpecError(
                f"map key '{unknown[0]}' is not a parameter of component '{child.id}'",
                bind.maps[unknown[0]][1],
            )
        child_env: dict[str, _Binding] = {}
        child_path = (*path, bind.name)
        for p in child.params.values():
            mapped = bind.maps.get(p.name)
            local_id = ".".join((*child_path, p.name))
            if mapped is None:
                if not p.local and p.name in comp.params:
                    child_env[p.name] = env[p.name]
                elif p.kind == "label":
                    child_env[p.name] = ("label", local_id)
                elif p.dynamics == "const":
                    raise SpecError(
                        f"constant '{p.name}' of component '{child.id}' gets no value in the bind "
                        f"'{bind.name}': add <map key=\"{p.name}\">value</map>",
                        bind.position,
                    )
                else:
                    child_env[p.name] = ("var", local_id)
                continue
            text, where = mapped
            child_env[p.name] = _mapped(p.kind, p.dynamics == "const", text, where, env, comp)
        _unfold(model, child, child_path, child_env, flat, (*stack, child.id), bind.position)


def _mapped(
    kind: str, const: bool, text: str, where: Position, env: dict[str, _Binding], comp: Component
) -> _Binding:
    if text in env:
        binding = env[text]
        if kind == "label" and binding[0] != "label":
            raise SpecError(f"label mapped to '{text}', which is not a label", where)
        if kind != "label" and binding[0] == "label":
            raise SpecError(f"variable mapped to '{text}', which is a label", where)
        if const and binding[0] == "var":
            raise SpecError(
                f"a constant is mapped to '{text}', a variable of '{comp.id}': map it to a "
                "number or to a constant",
                where,
            )
        if not const and binding[0] in ("const", "open"):
            raise SpecError(
                f"a variable is mapped to '{text}', a constant of '{comp.id}': a variable must be "
                "mapped to a variable",
                where,
            )
        return binding
    if kind == "label" or not const:
        raise SpecError(
            f"'{text}' is not a parameter of component '{comp.id}' (known: "
            f"{', '.join(env) or 'none'})",
            where,
        )
    values = {k: float(v[1]) for k, v in env.items() if v[0] == "const" and v[1] is not None}
    try:
        node = sx.parse(SourceText(where.file, text, [(0, where.line, where.column)]))
    except SpecError as exc:
        raise SpecError(f"the value of a constant must be a number: {exc.message}", where) from None
    value = constant_value(node, values)
    if value is None:
        raise SpecError(
            f"the value '{text}' of a constant is not a number (nor an expression of numbers "
            "and known constants)",
            where,
        )
    return ("const", value)


def _add_leaf(
    comp: Component,
    path: tuple[str, ...],
    env: dict[str, _Binding],
    flat: Flat,
    position: Position,
) -> None:
    if len(flat.leaves) >= MAX_LEAVES:
        raise SpecError(f"the system unfolds into more than {MAX_LEAVES} instances", comp.position)
    leaf = Leaf(path, comp, {}, {}, {}, position=position, index=len(flat.leaves))
    for p in comp.params.values():
        kind, value = env[p.name]
        if kind == "label":
            leaf.labels[p.name] = str(value)
        elif kind == "var":
            leaf.variables[p.name] = str(value)
        elif kind == "open":
            leaf.constants[p.name] = None
            leaf.open_constants[p.name] = str(value)
        else:
            leaf.constants[p.name] = None if value is None else float(value)
    flat.leaves.append(leaf)
