"""Pydantic validation errors rewritten to point at the user's text.

Each error's ``loc`` is a path of keys and indices into the YAML document; the
:class:`~hybrid.reader.yamlpos.PositionMap` turns it into ``file:line:column``.
An unknown key points at the key and suggests the closest valid one; a missing
key points at its parent mapping.
"""

from __future__ import annotations

import types
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import BaseModel, ValidationError

from hybrid.errors import Position, did_you_mean
from hybrid.reader.yamlpos import PositionMap

__all__ = ["closest", "describe_path", "validation_problems"]


def closest(name: str, candidates: list[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest candidate, or ``""`` (a looser match
    than for names in expressions: keys and locations are few)."""
    return did_you_mean(name, candidates, cutoff=0.5)


def describe_path(path: tuple[Any, ...]) -> str:
    """``locations.falling.flow`` style text for a path (indices as ``[i]``)."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "the top level"


def _field_names(model: type[BaseModel]) -> list[str]:
    return [info.alias or name for name, info in model.model_fields.items()]


def _unwrap(tp: Any) -> Any:
    while True:
        origin = get_origin(tp)
        if origin is Annotated:
            tp = get_args(tp)[0]
        elif origin in (Union, types.UnionType):
            options = [a for a in get_args(tp) if a is not type(None)]
            tp = options[0] if len(options) == 1 else tp
            if len(options) != 1:
                return tp
        else:
            return tp


def _model_at(root: type[BaseModel], path: tuple[Any, ...]) -> type[BaseModel] | None:
    current: Any = root
    for part in path:
        current = _unwrap(current)
        if isinstance(current, type) and issubclass(current, BaseModel):
            by_alias = {info.alias or n: info for n, info in current.model_fields.items()}
            info = by_alias.get(part) or current.model_fields.get(str(part))
            if info is None:
                return None
            current = info.annotation
            continue
        origin = get_origin(current)
        args = get_args(current)
        if origin is dict and args:
            current = args[1]
        elif origin in (list, tuple) and args:
            current = args[0]
        else:
            return None
    current = _unwrap(current)
    if isinstance(current, type) and issubclass(current, BaseModel):
        return current
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
        loc = tuple(p for p in item["loc"] if isinstance(p, int | str))
        kind = item["type"]
        if kind == "extra_forbidden":
            parent, key = loc[:-1], str(loc[-1])
            model = _model_at(root, parent)
            valid = _field_names(model) if model else []
            hint = closest(key, valid)
            if not hint and valid:
                hint = f"; valid keys here: {', '.join(valid)}"
            where = describe_path(parent)
            problems.append((positions.key(loc), f"unknown key '{key}' in {where}{hint}"))
        elif kind == "missing":
            where = describe_path(loc[:-1])
            problems.append((positions.value(loc[:-1]), f"missing key '{loc[-1]}' in {where}"))
        else:
            got = _value_at(data, loc)
            shown = f" (got {_short(got)})" if got is not _MISSING else ""
            message = item["msg"]
            if kind == "string_pattern_mismatch":
                message = "must be a name: an ASCII letter or _ then ASCII letters, digits or _"
            elif kind in ("too_short", "string_too_short") and got == "":
                message = "must not be empty"
            if loc and loc[-1] == "[key]":  # a mapping key: point at the key itself
                key_path = loc[:-1]
                problems.append(
                    (positions.key(key_path), f"{describe_path(key_path)}: the key {message}")
                )
                continue
            problems.append((positions.value(loc), f"{describe_path(loc)}: {message}{shown}"))
    return problems


_MISSING = object()


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
