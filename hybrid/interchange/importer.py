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
from hybrid.expr.interval import Interval
from hybrid.expr.ranges import can_fail, can_hold
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.cfg import SpaceExConfig, parse_cfg, read_cfg
from hybrid.interchange.emit import SEMANTICS, automaton_text
from hybrid.interchange.flatten import Flat, Leaf, flatten
from hybrid.interchange.initial import InitialSet, Resolver, forbidden_set, initial_set
from hybrid.interchange.naming import system_names
from hybrid.interchange.safexml import parse_xml_file, parse_xml_text
from hybrid.interchange.sxmodel import SpaceExModel, read_model
from hybrid.interchange.template import Template, analyse
from hybrid.interchange.translate import condition_ir
from hybrid.interchange.yamltext import dump

__all__ = ["SEMANTICS", "ImportResult", "import_spaceex", "import_spaceex_text"]


@dataclass
class ImportResult:
    """The YAML files (name -> text), which one is the top-level spec, and the notes."""

    files: dict[str, str]
    top: str
    notes: list[str] = field(default_factory=list)


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
    templates = _templates(flat)
    owners = _owners(flat, templates)
    free = {v for v in flat.variable_ids if v not in owners}
    templates = _templates(flat, free)
    for t in templates.values():
        notes.extend(t.notes)
    open_constants = {c for leaf in flat.leaves for c in leaf.open_constants.values()}
    resolver = Resolver(
        [*flat.variable_ids, *sorted(open_constants)], [".".join(leaf.path) for leaf in flat.leaves]
    )
    init = InitialSet()
    if config is not None and config.initially is not None:
        init = initial_set(config.initially, resolver, open_constants)
        notes.extend(init.notes)
    _close_constants(flat, init, config)
    names = system_names(flat.variable_ids)
    label_names = system_names(flat.label_ids)
    forbidden: list[dict[str, Any]] = []
    if config is not None and config.forbidden is not None:
        for entry in forbidden_set(config.forbidden, resolver, lambda i: names.get(i, i)):
            item: dict[str, Any] = {}
            locs = {
                flat.leaves[k].name: _location_name(
                    templates[flat.leaves[k].component.id], v, config
                )
                for k, v in entry.locations.items()
            }
            if locs:
                item.update(
                    {"location": next(iter(locs.values()))}
                    if _single(flat)
                    else {"locations": locs}
                )
            if entry.when:
                item["when"] = entry.when
            forbidden.append(item)
    files: dict[str, str] = {}
    header_extra = f"From {Path(model.file).name}" + (
        f" and {Path(config.file).name}" if config is not None else ""
    )
    if _single(flat):
        leaf = flat.leaves[0]
        t = templates[leaf.component.id]
        start = _start(leaf, t, init, config)
        if start["exact"]:
            start["exact_comment"] = _exact_comment(start["exact"])
        if forbidden and config is not None and config.forbidden is not None:
            start["forbidden_comment"] = f"forbidden set of the .cfg: {config.forbidden.text}"
        files[t.file] = automaton_text(t, leaf, start, forbidden, header_extra, top=True)
        return ImportResult(files, t.file, notes)
    components: list[dict[str, Any]] = []
    comments: dict[tuple[str | int, ...], str] = {}
    for leaf in flat.leaves:
        t = templates[leaf.component.id]
        if t.file not in files:
            files[t.file] = automaton_text(t, leaf, None, [], header_extra, top=False)
        block: dict[str, Any] = {"spec": t.file, "as": leaf.name}
        rename = {t.names[k]: names[v] for k, v in leaf.variables.items() if t.names[k] != names[v]}
        rename |= {
            t.names[k]: label_names[v]
            for k, v in leaf.labels.items()
            if t.names[k] != label_names[v]
        }
        if rename:
            block["rename"] = rename
        if leaf.constants:
            block["parameters"] = {t.names[k]: v for k, v in leaf.constants.items()}
        start = _start(leaf, t, init, config)
        block["initial"] = {"location": start["location"], "state": start["state"]}
        if start["exact"]:
            comments[("components", len(components), "initial")] = _exact_comment(start["exact"])
        components.append(block)
    data: dict[str, Any] = {"system": _system_name(flat), "description": _description(flat)}
    data["components"] = components
    if forbidden:
        data["properties"] = {"forbidden": forbidden}
        comments[("properties",)] = (
            f"forbidden set of the .cfg: {config.forbidden.text if config and config.forbidden else ''}"
        )
    top = f"{_system_name(flat)}.yaml"
    if top in files:
        top = f"{_system_name(flat)}_system.yaml"
    header = f"Imported by `hybrid import spaceex`. {header_extra}, network component '{flat.system.id}'.\n{SEMANTICS}"
    files[top] = dump(data, comments, header)
    return ImportResult(files, top, notes)


def _exact_comment(exact: list[str]) -> str:
    return (
        "the .cfg's initial set " + " and ".join(exact) + " is not a box: these intervals are "
        "its bounding box, nominal its centre"
    )


def _single(flat: Flat) -> bool:
    return not flat.system.is_network


def _system_name(flat: Flat) -> str:
    from hybrid.interchange.naming import ours

    return ours(flat.system.id)


def _description(flat: Flat) -> str:
    note = flat.system.note
    return note if note else f"SpaceEx network component '{flat.system.id}'"


def _templates(flat: Flat, free: set[str] | None = None) -> dict[str, Template]:
    """Each base component the system uses, read with the variables it leaves free."""
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
        found[comp.id] = analyse(comp, free_here)
    return found


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
        for state in templates[leaf.component.id].states:
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


def _close_constants(flat: Flat, init: InitialSet, config: SpaceExConfig | None) -> None:
    """Give every constant left open by the system the value the ``.cfg`` gives it."""
    for leaf in flat.leaves:
        for inner, outer in leaf.open_constants.items():
            if outer not in init.constants:
                where = (
                    config.initially.where(0)
                    if config and config.initially
                    else flat.system.position
                )
                raise SpecError(
                    f"constant '{outer}' of the system has no value: add '{outer} == value' to "
                    "the .cfg's initially (or bind it to a number)",
                    where,
                )
            leaf.constants[inner] = init.constants[outer]


def _location_name(t: Template, spaceex_name: str, config: SpaceExConfig | None) -> str:
    loc = t.location(spaceex_name)
    if loc is None:
        where = (
            config.values["forbidden"].where(0)
            if config and "forbidden" in config.values
            else Position(t.component.position.file)
        )
        raise SpecError(
            f"component '{t.component.id}' has no location '{spaceex_name}' (locations: "
            f"{', '.join(loc.spaceex_name for loc in t.locations)})",
            where,
        )
    return loc.name


def _start(
    leaf: Leaf, t: Template, init: InitialSet, config: SpaceExConfig | None
) -> dict[str, Any]:
    """``{location: ..., state: {...}}`` for one instance, from the initial set."""
    state: dict[str, Any] = {}
    box: dict[str, Interval] = {}
    point: dict[str, Interval] = {}
    for inner in t.states:
        outer = leaf.variables[inner]
        ours = t.names[inner]
        if config is None or config.initially is None:
            lo = hi = 0.0
        elif outer in init.bounds:
            lo, hi = init.bounds[outer]
        else:
            lo, hi = float("-inf"), float("inf")
        if not (lo > float("-inf") and hi < float("inf")):
            where = config.initially.where(0) if config and config.initially else Position("<cfg>")
            raise SpecError(
                f"the initial set leaves '{outer}' {'unbounded' if lo > float('-inf') or hi < float('inf') else 'free (any real number)'}: "
                f"bound it in the .cfg's initially (e.g. {outer} == 0, or lo <= {outer} & {outer} <= hi)",
                where,
            )
        nominal = init.nominal.get(outer, (lo + hi) / 2) + 0.0  # no -0.0
        if lo == hi:
            state[ours] = lo
        elif outer in init.nominal:
            state[ours] = {"initial": [lo, hi], "nominal": nominal}
        else:
            state[ours] = [lo, hi]
        box[ours] = Interval(lo, hi)
        point[ours] = Interval(nominal, nominal)
    for inner, (lo, hi) in t.ranges.items():
        box[t.names[inner]] = Interval(lo, hi)
        point[t.names[inner]] = Interval((lo + hi) / 2, (lo + hi) / 2)
    chosen = _initial_locations(leaf, t, init, box, point, config)
    exact = sorted(
        {init.exact[leaf.variables[s]] for s in t.states if leaf.variables[s] in init.exact}
    )
    return {
        "location": chosen[0] if len(chosen) == 1 else chosen,
        "state": state,
        "exact": exact,
    }


def _initial_locations(
    leaf: Leaf,
    t: Template,
    init: InitialSet,
    box: dict[str, Interval],
    point: dict[str, Interval],
    config: SpaceExConfig | None,
) -> list[str]:
    if leaf.index in init.locations:
        return [_location_name(t, init.locations[leaf.index], config)]
    if config is None or config.initially is None:
        return [t.locations[0].name]
    rename = {**t.names, **{k: repr(v) for k, v in leaf.constants.items() if v is not None}}

    def name(n: str) -> str:
        return rename[n]

    possible: list[tuple[bool, str]] = []
    for loc in t.locations:
        cond = condition_ir(sx.And(tuple(loc.invariant), leaf.component.position), name)
        if can_hold(cond, box):
            possible.append((not can_fail(cond, point), loc.name))
    if not possible:
        raise SpecError(
            f"no location of '{leaf.name}' has an invariant that the initial set meets",
            config.initially.where(0),
        )
    return [n for holds, n in possible if holds] + [n for holds, n in possible if not holds]
