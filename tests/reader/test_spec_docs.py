"""docs/spec-language.md stays true to the code it describes."""

from __future__ import annotations

import re

import pytest
from pydantic import BaseModel
from support import REPO as ROOT

from hybrid.expr.functions import BUILTINS
from hybrid.expr.parse import MAX_DEPTH, MAX_SOURCE_CHARS
from hybrid.reader.schema import (
    AutomatonSpec,
    ComponentSpec,
    EdgeSpec,
    ForbiddenSpec,
    InitialSpec,
    InputSpec,
    LocationSpec,
    PropertiesSpec,
    StateVarSpec,
    SystemSpec,
)
from hybrid.reader.yamlpos import MAX_FILE_BYTES, MAX_YAML_DEPTH

DOC = (ROOT / "docs" / "spec-language.md").read_text(encoding="utf-8")


def _table_keys(heading: str) -> set[str]:
    """The backquoted keys in the first column of the first table after ``heading``."""
    lines = DOC.split(f"\n{heading}\n", 1)[1].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    keys = set()
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        match = re.match(r"^\| `([a-z_]+)` \|", line)
        if match:
            keys.add(match.group(1))
    return keys


@pytest.mark.parametrize(
    "heading, model",
    [
        ("### Top level", AutomatonSpec),
        ("### State variables", StateVarSpec),
        ("### Locations", LocationSpec),
        ("### Initial", InitialSpec),
        ("### Edges", EdgeSpec),
        ("### Properties", PropertiesSpec),
        ("### Inputs", InputSpec),
        ("### Forbidden states", ForbiddenSpec),
        ("## System files", SystemSpec),
        ("Each component:", ComponentSpec),
    ],
)
def test_every_key_is_documented(heading: str, model: type[BaseModel]) -> None:
    keys = {info.alias or name for name, info in model.model_fields.items()}
    assert _table_keys(heading) == keys


def test_every_builtin_is_documented() -> None:
    section = DOC.split("### Built-in functions", 1)[1].split("###", 1)[0]
    for name in BUILTINS:
        assert f"`{name}(" in section, name


def test_limits_are_documented() -> None:
    section = DOC.split("## Limits", 1)[1].split("## ", 1)[0]
    assert f"{MAX_FILE_BYTES:,} bytes" in section
    assert f"| {MAX_YAML_DEPTH} levels" in section
    assert f"| {MAX_SOURCE_CHARS} characters" in section
    assert f"| {MAX_DEPTH} levels" in section
