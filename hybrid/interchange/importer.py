"""``hybrid import spaceex``: a SpaceEx model (and its ``.cfg``) as YAML spec files.

One automaton file per base component the system uses, and, when the system
is a network, one system file whose components are the base-component
instances, each with its ``rename`` map, ``parameters`` and ``initial`` set
(networks inside networks are unfolded: our system files compose automata).
When the system is a base component, its automaton file is the top-level file.

Examples
--------
>>> result = import_spaceex_text('''<sspaceex><component id="clock">
...   <param name="t" type="real" local="false" d1="1" d2="1" dynamics="any"/>
...   <location id="1" name="run"><flow>t' == 1</flow></location>
... </component></sspaceex>''', 'system = clock\\ninitially = "t == 0"\\n')
>>> result.top, result.notes[0]
('clock.yaml', "component 'clock': variable 't' is renamed 't_' ('t' is reserved in our expressions; t is the time)")
>>> print(result.files["clock.yaml"].split("automaton:")[1].split("locations:")[0], end="")
 clock
description: "SpaceEx base component 'clock'"
state:
  t_: {initial: 0.0}
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hybrid.errors import Position, SpecError
from hybrid.frames import in_frame_room
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.cfg import SpaceExConfig, parse_cfg, reach_checks, read_cfg
from hybrid.interchange.emit import CHECKS_COMMENT, SEMANTICS, automaton_text
from hybrid.interchange.flatten import Flat, Leaf, flatten
from hybrid.interchange.initial import InitialSet, Resolver, forbidden_set, initial_set
from hybrid.interchange.naming import component_name, system_names
from hybrid.interchange.safexml import parse_xml_file, parse_xml_text
from hybrid.interchange.selfcheck import check_loads
from hybrid.interchange.starts import exact_comment, location_name, start_of
from hybrid.interchange.sxmodel import SpaceExModel, read_model
from hybrid.interchange.template import Template, analyse
from hybrid.interchange.translate import changed_by, reset_nodes
from hybrid.interchange.yamltext import dump

__all__ = ["SEMANTICS", "ImportResult", "import_spaceex", "import_spaceex_text"]


@dataclass
class ImportResult:
    """The YAML files (name -> text), which one is the top-level spec, and the notes."""

    files: dict[str, str]
    top: str
    notes: list[str] = field(default_factory=list)


@in_frame_room
def import_spaceex(
    xml: str | Path, cfg: str | Path | None = None, system: str | None = None
) -> ImportResult:
    """Translate a SpaceEx model file (and ``.cfg``) into YAML spec texts.

    Parameters
    ----------
    xml : str or Path
        The SpaceEx model (untrusted: read by :mod:`hybrid.interchange.safexml`).
    cfg : str or Path, optional
        The configuration with ``system``, ``initially`` and ``forbidden``.
    system : str, optional
        The component to translate (default: the ``.cfg``'s ``system``, else
        the last component of the file).

    Raises
    ------
    SpecError
        ``MODEL.xml:line:column: message`` (or the ``.cfg``'s place) for what
        cannot be read or has no counterpart.
    """
    model = read_model(parse_xml_file(xml))
    config = read_cfg(cfg) if cfg is not None else None
    return _translate(model, config, system)


@in_frame_room
def import_spaceex_text(
    xml_text: str,
    cfg_text: str | None = None,
    system: str | None = None,
    *,
    xml_file: str = "model.xml",
    cfg_file: str = "model.cfg",
) -> ImportResult:
    """As :func:`import_spaceex`, from strings."""
    model = read_model(parse_xml_text(xml_text, xml_file))
    config = parse_cfg(cfg_text, cfg_file) if cfg_text is not None else None
    return _translate(model, config, system)


def _choose_system(model: SpaceExModel, config: SpaceExConfig | None, system: str | None) -> str:
    if system is not None:
        return system
    if config is not None and config.system:
        if config.system not in model.components:
            where = config.values["system"].where(0)
            raise SpecError(
                f"the .cfg names the system '{config.system}', which is not a component of "
                f"{model.file} (components: {', '.join(model.components)}); pass --system NAME",
                where,
            )
        return config.system
    return list(model.components)[-1]


def _translate(
    model: SpaceExModel, config: SpaceExConfig | None, system: str | None
) -> ImportResult:
    name = _choose_system(model, config, system)
    flat = flatten(model, name)
    notes: list[str] = []
    if config is None:
        notes.append("no .cfg: every state starts at 0, in the first location of each component")
    open_constants = {c for leaf in flat.leaves for c in leaf.open_constants.values()}
    resolver = Resolver(
        [*flat.variable_ids, *sorted(open_constants)],
        [".".join(leaf.path) or leaf.component.id for leaf in flat.leaves],
    )
    init = InitialSet()
    if config is not None and config.initially is not None:
        init = initial_set(config.initially, resolver, open_constants)
        notes.extend(init.notes)
    missing = _close_constants(flat, init, config)
    templates = _templates(flat)
    if missing is not None:
        raise missing
    owners = _owners(flat, templates)
    free = {v for v in flat.variable_ids if v not in owners}
    templates = _templates(flat, free)
    _refuse_partner_assignments(flat, templates)
    for t in templates.values():
        notes.extend(t.notes)
    names = system_names(flat.variable_ids)
    forbidden = _forbidden(flat, templates, resolver, names, config)
    reach = None if config is None else reach_checks(config, notes)
    checks = None if reach is None else {"reach": reach}
    source = f"From {Path(model.file).name}" + (
        f" and {Path(config.file).name}" if config is not None else ""
    )
    if _single(flat):
        leaf = flat.leaves[0]
        t = templates[leaf.component.id]
        start = start_of(leaf, t, init, config)
        notes.extend(start["notes"])
        if start["exact"]:
            start["exact_comment"] = exact_comment(start["exact"])
        if forbidden and config is not None and config.forbidden is not None:
            start["forbidden_comment"] = f"forbidden set of the .cfg: {config.forbidden.text}"
        files = {t.file: automaton_text(t, leaf, start, forbidden, source, top=True,
                                        checks=checks)}  # fmt: skip
        origins = {**t.origins, **_cfg_origins(config, ("initial",), ("properties",))}
        check_loads(files, t.file, {t.file: origins})
        return ImportResult(files, t.file, notes)
    files, top = _system_files(flat, templates, names, init, config, forbidden, source, notes,
                               checks)  # fmt: skip
    provenance = {t.file: t.origins for t in templates.values()}
    system_origins: dict[tuple[str | int, ...], Position] = {(): flat.system.position}
    for i, leaf in enumerate(flat.leaves):
        system_origins[("components", i)] = leaf.position
        system_origins |= _cfg_origins(config, ("components", i, "initial"), ("properties",))
    provenance[top] = system_origins
    check_loads(files, top, provenance)
    return ImportResult(files, top, notes)


def _cfg_origins(
    config: SpaceExConfig | None, initial: tuple[str | int, ...], forbidden: tuple[str | int, ...]
) -> dict[tuple[str | int, ...], Position]:
    """The ``.cfg`` places of a spec's initial set and forbidden states."""
    found: dict[tuple[str | int, ...], Position] = {}
    if config is not None and config.initially is not None:
        found[initial] = config.initially.where(0)
    if config is not None and config.forbidden is not None:
        found[forbidden] = config.forbidden.where(0)
    return found


def _forbidden(
    flat: Flat,
    templates: dict[str, Template],
    resolver: Resolver,
    names: dict[str, str],
    config: SpaceExConfig | None,
) -> list[dict[str, Any]]:
    """The ``properties.forbidden`` entries of the ``.cfg``'s forbidden set."""
    if config is None or config.forbidden is None:
        return []
    found: list[dict[str, Any]] = []
    for entry in forbidden_set(config.forbidden, resolver, lambda i: names.get(i, i)):
        item: dict[str, Any] = {}
        locations = {
            flat.leaves[k].name: location_name(
                templates[flat.leaves[k].component.id], v, entry.positions[k]
            )
            for k, v in entry.locations.items()
        }
        if locations and _single(flat):
            item["location"] = next(iter(locations.values()))
        elif locations:
            item["locations"] = locations
        if entry.when:
            item["when"] = entry.when
        found.append(item)
    return found


def _system_files(
    flat: Flat,
    templates: dict[str, Template],
    names: dict[str, str],
    init: InitialSet,
    config: SpaceExConfig | None,
    forbidden: list[dict[str, Any]],
    source: str,
    notes: list[str],
    checks: dict[str, Any] | None = None,
) -> tuple[dict[str, str], str]:
    """The automaton files of the base components and the system file (its name last)."""
    files: dict[str, str] = {}
    label_names = system_names(flat.label_ids)
    components: list[dict[str, Any]] = []
    comments: dict[tuple[str | int, ...], str] = {}
    for leaf in flat.leaves:
        t = templates[leaf.component.id]
        if t.file not in files:
            files[t.file] = automaton_text(t, leaf, None, [], source, top=False)
        block: dict[str, Any] = {"spec": t.file, "as": leaf.name}
        written = "_".join(leaf.path)
        if leaf.path and leaf.name != written:
            notes.append(f"instance '{'.'.join(leaf.path)}' is '{leaf.name}' here (not a name)")
        kept = {*t.states, *t.inputs, *t.signals}
        rename = {t.names[k]: names[v] for k, v in leaf.variables.items() if k in kept}
        for rate, var in t.rates.items():
            rename[rate] = f"{names[leaf.variables[var]]}_{rate.removeprefix(t.names[var] + '_')}"
        rename |= {t.names[k]: label_names[v] for k, v in leaf.labels.items()}
        rename = {k: v for k, v in rename.items() if k != v}
        if rename:
            block["rename"] = rename
        kept_constants = {t.names[k]: v for k, v in leaf.constants.items() if k in t.constants}
        if kept_constants:
            block["parameters"] = kept_constants
        start = start_of(leaf, t, init, config)
        notes.extend(start["notes"])
        block["initial"] = {"location": start["location"], "state": start["state"]}
        if start["exact"]:
            comments[("components", len(components), "initial")] = exact_comment(start["exact"])
        components.append(block)
    name = _system_name(flat)
    if name != flat.system.id:
        notes.append(
            f"component id '{flat.system.id}' is not one of our names: it is '{name}' here"
        )
    data: dict[str, Any] = {"system": name, "description": _description(flat)}
    data["components"] = components
    if forbidden and config is not None and config.forbidden is not None:
        data["properties"] = {"forbidden": forbidden}
        comments[("properties",)] = f"forbidden set of the .cfg: {config.forbidden.text}"
    if checks:
        data["checks"] = checks
        comments[("checks",)] = CHECKS_COMMENT
    top = f"{name}.yaml" if f"{name}.yaml" not in files else f"{name}_system.yaml"
    header = (
        f"Imported by `hybrid import spaceex`. {source}, network component "
        f"'{flat.system.id}'.\n{SEMANTICS}"
    )
    files[top] = dump(data, comments, header)
    return files, top


def _single(flat: Flat) -> bool:
    return not flat.system.is_network


def _system_name(flat: Flat) -> str:
    return component_name(flat.system.id)


def _description(flat: Flat) -> str:
    note = flat.system.note
    return note if note else f"SpaceEx network component '{flat.system.id}'"


def _templates(flat: Flat, free: set[str] | None = None) -> dict[str, Template]:
    """Each base component the system uses, read with the variables it leaves free.

    A constant's value is given to the reading when every instance has the same;
    a constant the ``.cfg`` gives a range (a variable of every instance) is a state.
    """
    found: dict[str, Template] = {}
    for leaf in flat.leaves:
        comp = leaf.component
        if comp.id in found:
            continue
        uses = [other for other in flat.leaves if other.component is comp]
        free_here = {
            v
            for v in comp.params
            if free is not None and all(other.variables.get(v) in free for other in uses)
        }
        values: dict[str, float] = {}
        for c in leaf.constants:
            seen = {other.constants.get(c) for other in uses}
            value = seen.pop() if len(seen) == 1 else None
            if value is not None:
                values[c] = value
        promoted = frozenset(
            p
            for p, param in comp.params.items()
            if param.dynamics == "const" and all(p in other.variables for other in uses)
        )
        t = analyse(comp, free_here, values, promoted)
        while t.name in {other.name for other in found.values()}:
            t.name += "_"  # two ids made the same name (a>b, a_b)
        found[comp.id] = t
    return found


def _refuse_partner_assignments(flat: Flat, templates: dict[str, Template]) -> None:
    """Refuse a synchronised transition whose target's invariant reads a variable that a
    partner's transition on the same label assigns.

    SpaceEx checks the target's invariant after every assignment of the joint jump;
    our guard reads the value before it (its own assignments are substituted, a
    partner's cannot be). The HyST buck converter does this: its converter's
    ``charging -> discharging`` needs ``mode_out == 1`` of the discharging
    invariant, which the controller's transition on ``hop`` sets. Read before the
    jump, the guard never held and every run ended blocked where SpaceEx switches
    (and ``check`` would prove the discharging location unreachable).
    """
    assigned: dict[str, dict[str, tuple[Leaf, Position]]] = {}  # label -> variable -> by whom
    for leaf in flat.leaves:
        for tr in leaf.component.transitions:
            if tr.label is None:
                continue
            label = leaf.labels.get(tr.label, tr.label)
            for var in changed_by(reset_nodes(sx.parse(tr.assignment))):
                outer = leaf.variables.get(var, var)
                assigned.setdefault(label, {}).setdefault(outer, (leaf, tr.position))
    for leaf in flat.leaves:
        t = templates[leaf.component.id]
        for tr, edge in zip(leaf.component.transitions, t.edges, strict=True):
            if tr.label is None or not edge.checked_after:
                continue
            label = leaf.labels.get(tr.label, tr.label)
            for var in sorted(edge.checked_after):
                setter = assigned.get(label, {}).get(leaf.variables.get(var, var))
                if setter is None or setter[0] is leaf:
                    continue
                raise SpecError(
                    f"the transition {edge.source} -> {edge.target} of '{leaf.name}' needs "
                    f"{edge.target}'s invariant after the jump, which reads '{var}', and the "
                    f"transition of '{setter[0].name}' at line {setter[1].line} on the same "
                    f"label '{tr.label}' assigns it: SpaceEx checks the invariant after both "
                    "assignments, a guard here reads the value before the jump, so the "
                    "translation would miss jumps SpaceEx takes. Write the condition on the "
                    "values before the jump (in the guard, without it in the target's "
                    "invariant); nothing was written",
                    tr.position,
                )


def _owners(flat: Flat, templates: dict[str, Template]) -> dict[str, Leaf]:
    """The one leaf that changes each system variable (its flow or jumps set it)."""
    owners: dict[str, Leaf] = {}
    for leaf in flat.leaves:
        seen: dict[str, str] = {}
        for inner, outer in leaf.variables.items():
            if outer in seen:
                raise SpecError(
                    f"variables '{seen[outer]}' and '{inner}' of component '{leaf.component.id}' "
                    f"are both bound to '{outer}' in instance '{leaf.name}': bind them to "
                    "different variables",
                    leaf.position if leaf.path else leaf.component.position,
                )
            seen[outer] = inner
        t = templates[leaf.component.id]
        for state in [*t.states, *t.signals]:
            outer = leaf.variables[state]
            if outer in owners:
                raise SpecError(
                    f"variable '{outer}' is changed by two components, '{owners[outer].name}' "
                    f"and '{leaf.name}': SpaceEx conjoins their flows and jumps, which has no "
                    "counterpart here (a variable has one owner; the others read it as an "
                    "input): give it one owner",
                    leaf.component.position,
                )
            owners[outer] = leaf
    return owners


def _close_constants(
    flat: Flat, init: InitialSet, config: SpaceExConfig | None
) -> SpecError | None:
    """Give every constant left open by the system the value the ``.cfg`` gives it.

    A constant the ``.cfg`` gives a range becomes a system variable (each
    instance's template makes it a state with derivative 0). Returns the error
    for a constant with no value (raised once the components are read, so that
    a component's own mistake is reported first).
    """
    missing: SpecError | None = None
    for leaf in flat.leaves:
        for inner, outer in list(leaf.open_constants.items()):
            if outer in init.ranged:
                leaf.variables[inner] = outer
                del leaf.constants[inner], leaf.open_constants[inner]
                if outer not in flat.variable_ids:
                    flat.variable_ids.append(outer)
                continue
            if outer not in init.constants:
                where = (
                    config.initially.where(0)
                    if config and config.initially
                    else flat.system.position
                )
                missing = missing or SpecError(
                    f"constant '{outer}' of the system has no value: add '{outer} == value' to "
                    "the .cfg's initially (or bind it to a number)",
                    where,
                )
                continue
            leaf.constants[inner] = init.constants[outer]
    return missing
