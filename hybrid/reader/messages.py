"""Pydantic validation errors rewritten to point at the user's text.

Each error's ``loc`` is a path of keys and indices into the YAML document; the
:class:`~hybrid.reader.yamlpos.PositionMap` turns it into ``file:line:column``.
An unknown key points at the key and suggests the closest valid one; a missing
key points at its parent mapping.
"""

from __future__ import annotations

import re
import types
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import BaseModel, ValidationError

from hybrid.errors import Position, did_you_mean
from hybrid.reader.yamlpos import PositionMap

__all__ = ["closest", "derivative_hint", "derivative_of", "describe_path", "validation_problems"]


def closest(name: str, candidates: list[str], aliases: dict[str, str] | None = None) -> str:
    """``"; did you mean 'x'?"`` for the closest candidate, or ``""`` (a looser match
    than for names in expressions: keys and locations are few; ``aliases`` as for
    :func:`~hybrid.errors.did_you_mean`)."""
    return did_you_mean(name, candidates, cutoff=0.5, aliases=aliases)


_DERIVATIVE = re.compile(
    r"d(?P<a>\w+)\s*/\s*dt|der\((?P<b>\w+)\)|d\((?P<c>\w+)\)\s*/\s*dt|"
    r"(?P<d>\w+?)(?:'|_dot|dot|_prime)|d(?P<e>\w+)"
)


def derivative_of(key: str, state_names: list[str] | Any) -> str | None:
    """The state variable ``key`` writes the derivative of, as other tools do, or None.

    >>> [derivative_of(k, ["x", "T"]) for k in ("x'", "dx/dt", "der(x)", "Tdot", "dT", "y'")]
    ['x', 'x', 'x', 'T', 'T', None]
    """
    found = _DERIVATIVE.fullmatch(key.strip())
    if found is None:
        return None
    name = next(v for v in found.groupdict().values() if v is not None)
    return name if name in state_names else None


def derivative_hint(key: str, state_names: list[str] | Any) -> str:
    """``": a flow is keyed by ..."`` for a flow key that writes a derivative, else ``""``."""
    name = derivative_of(key, state_names)
    if name is None:
        return ""
    return (
        f": a flow is keyed by the state variable itself, and its value is the derivative: "
        f"write {name}: ..."
    )


def describe_path(path: tuple[Any, ...]) -> str:
    """``locations.falling.flow`` style text for a path (indices as ``[i]``)."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "the top level"


def _field_names(model: type[BaseModel]) -> list[str]:
    return [info.alias or name for name, info in model.model_fields.items()]


def _options(tp: Any) -> list[Any]:
    """The types ``tp`` may be: the members of a union, annotations removed."""
    while get_origin(tp) is Annotated:
        tp = get_args(tp)[0]
    if get_origin(tp) in (Union, types.UnionType):
        return [o for a in get_args(tp) if a is not type(None) for o in _options(a)]
    return [tp]


def _model_at(root: Any, path: tuple[Any, ...]) -> type[BaseModel] | None:
    """The pydantic model of the mapping at ``path`` (trying every member of a union)."""
    for current in _options(root):
        if not path:
            if isinstance(current, type) and issubclass(current, BaseModel):
                return current
            continue
        part, rest = path[0], path[1:]
        if isinstance(current, type) and issubclass(current, BaseModel):
            by_alias = {info.alias or n: info for n, info in current.model_fields.items()}
            info = by_alias.get(part) or current.model_fields.get(str(part))
            found = None if info is None else _model_at(info.annotation, rest)
        else:
            origin, args = get_origin(current), get_args(current)
            if origin is dict and args and not isinstance(part, int):
                found = _model_at(args[1], rest)
            elif origin in (list, tuple) and args and isinstance(part, int):
                found = _model_at(args[0], rest)
            else:
                found = None
        if found is not None:
            return found
    return None


def validation_problems(
    error: ValidationError,
    root: type[BaseModel],
    positions: PositionMap,
    data: Any,
) -> list[tuple[Position, str]]:
    """One ``(position, message)`` per pydantic error, each at the user's text."""
    problems: list[tuple[Position, str]] = []
    for item in error.errors(include_url=False):
        # a union member's tag (``<list>``, see schema.py) is no place in the file
        loc = tuple(
            p for p in item["loc"] if isinstance(p, int) or (isinstance(p, str) and not _is_tag(p))
        )
        kind = item["type"]
        if kind == "extra_forbidden":
            parent, key = loc[:-1], str(loc[-1])
            model = _model_at(root, parent)
            valid = _field_names(model) if model else []
            hint = closest(key, valid, aliases=_KEY_SYNONYMS)
            if not parent and key in _OTHER_KIND and key not in valid:
                hint = _OTHER_KIND[key]
            if not hint and valid:
                hint = f"; valid keys here: {', '.join(valid)}"
            where = describe_path(parent)
            problems.append((positions.key(loc), f"unknown key '{key}' in {where}{hint}"))
        elif kind == "missing" and loc and isinstance(loc[-1], int):  # a pair with one item
            where = describe_path(loc[:-1])
            got = _value_at(data, loc[:-1])
            problems.append(
                (
                    positions.value(loc[:-1]),
                    f"{where}: expected [low, high]: two numbers (got {_short(got)})",
                )
            )
        elif kind == "missing":
            where = describe_path(loc[:-1])
            problems.append((positions.value(loc[:-1]), f"missing key '{loc[-1]}' in {where}"))
        else:
            got = _value_at(data, loc)
            shown = f" (got {_short(got)})" if got is not _MISSING else ""
            message = item["msg"].removeprefix("Value error, ")  # pydantic's word, not ours
            plain = _plain_type_message(kind, loc, got)
            if plain is not None:
                problems.append((positions.value(loc), f"{describe_path(loc)}: {plain}"))
                continue
            if kind == "string_pattern_mismatch":
                message = "must be a name: an ASCII letter or _ then ASCII letters, digits or _"
            elif (
                kind in ("too_long", "too_short")
                and item.get("ctx", {}).get("field_type") == "Tuple"
            ):
                message = "expected [low, high]: two numbers"
            elif kind in ("too_short", "string_too_short") and got == "":
                message = "must not be empty"
            if loc and loc[-1] == "[key]":  # a mapping key: point at the key itself
                key_path = loc[:-1]
                said = f"{describe_path(key_path)}: the key {message}"
                if len(key_path) >= 2 and key_path[-2] == "flow" and isinstance(data, dict):
                    state = data.get("state")
                    hint = derivative_hint(str(key_path[-1]), state if isinstance(state, dict) else [])
                    said = f"{describe_path(key_path)}{hint}" if hint else said
                problems.append((positions.key(key_path), said))
                continue
            problems.append((positions.value(loc), f"{describe_path(loc)}: {message}{shown}"))
    return problems


_MISSING = object()

_KEY_SYNONYMS = {
    "transitions": "edges", "jumps": "edges", "modes": "locations", "states": "state",
    "variables": "state", "vars": "state", "init": "initial", "initial_value": "initial",
    "x0": "initial", "start": "initial", "params": "parameters", "constants": "parameters",
    "ode": "flow", "odes": "flow", "dynamics": "flow", "derivatives": "flow", "der": "flow",
    "inv": "invariant", "condition": "guard", "when": "guard", "update": "reset",
    "assign": "reset", "assignment": "reset", "assignments": "reset", "action": "reset",
    "outputs": "signals", "source": "from", "target": "to", "dest": "to",
    "file": "spec", "path": "spec", "model": "spec", "alias": "as",
}  # fmt: skip
"""Keys other tools (and textbooks) use, and ours: suggested where ours is valid."""

_OTHER_KIND = {
    "components": ": components belong to a system, which starts with `system: NAME` "
    "(this spec starts with `automaton:`)",
    "locations": ": locations belong to an automaton, which starts with `automaton: NAME` "
    "(this spec starts with `system:`; its automata are its components' specs)",
}
"""A top-level key of the other kind of spec: what the spec's first key should be."""

_CONDITIONS = ("guard", "invariant", "when", "always", "eventually")


def _plain_type_message(kind: str, loc: tuple[Any, ...], got: Any) -> str | None:
    """A message without pydantic's words for the type errors a first spec makes, or None."""
    if kind == "model_type" and len(loc) == 2 and loc[0] == "state":
        shown = _short(got) if got is not _MISSING else "..."
        return (
            f"a state variable is a mapping: write {loc[1]}: {{initial: {shown}}} "
            "(with bounds: and unit: if you like)"
        )
    if kind == "model_type" and len(loc) == 2 and loc[0] == "components" and isinstance(got, str):
        return (
            f"a component is a mapping: write - spec: {got} (with as:, parameters: and "
            "initial: if you like)"
        )
    if kind in ("model_type", "dict_type"):
        return f"expected a mapping of names (got {_short(got)})"
    if kind in ("float_type", "float_parsing") and isinstance(got, str):
        spelled = got.strip().lstrip("+-").lower()
        if spelled in ("inf", "infinity", "nan"):
            sign = "-" if got.strip().startswith("-") else ""
            yaml_word = ".nan" if spelled == "nan" else f"{sign}.inf"
            return f"expected a number, got the text {got!r}: YAML writes it {yaml_word}"
        if "_" in got and got.replace("_", "").replace(".", "", 1).lstrip("+-").isdigit():
            return f"expected a number, got the text {got!r}: write {got.replace('_', '')} (no _)"
        return (
            f"expected a number, got the text {got!r} (a unit goes under a state "
            "variable's or signal's unit:, not in the value)"
            if any(c.isalpha() for c in got) and any(c.isdigit() for c in got)
            else None
        )
    if kind == "string_type" and isinstance(got, bool):  # from: true, a location named so
        word = str(got).lower()
        return f"expected a name, got the boolean {word}: quote it ('{word}') for a name"
    if kind == "string_type" and loc and loc[-1] in _CONDITIONS and isinstance(got, list):
        joined = " and ".join(str(c) for c in got)
        return f"one condition, not a list: join them with 'and': {joined}"
    return None


def _is_tag(part: str) -> bool:
    return part.startswith("<") and part.endswith(">")


def _value_at(data: Any, loc: tuple[Any, ...]) -> Any:
    current = data
    for part in loc:
        try:
            current = current[part]
        except (KeyError, IndexError, TypeError):
            return _MISSING
    return current


def _short(value: Any) -> str:
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
