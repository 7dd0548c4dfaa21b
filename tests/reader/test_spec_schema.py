"""The JSON Schema of spec files: committed, up to date, draft-07, and true of specs/."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from support import REPO as ROOT

import hybrid
from hybrid.reader.jsonschema import spec_schema, spec_schema_text
from hybrid.reader.yamlpos import read_yaml_file, read_yaml_text

SCHEMA_PATH = ROOT / "docs" / "schema" / "automaton.schema.json"
SPECS = sorted((ROOT / "specs").rglob("*.yaml"))
MODELINE = "# yaml-language-server: $schema=../docs/schema/automaton.schema.json"


@pytest.fixture(scope="module")
def committed() -> dict[str, Any]:
    result: dict[str, Any] = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    return result


@pytest.fixture(scope="module")
def validator(committed: dict[str, Any]) -> jsonschema.Draft7Validator:
    return jsonschema.Draft7Validator(committed)


def test_committed_schema_is_up_to_date() -> None:
    assert SCHEMA_PATH.read_text(encoding="utf-8") == spec_schema_text(), (
        "docs/schema/automaton.schema.json is out of date; regenerate it with\n"
        "  python -c 'from hybrid.reader.jsonschema import spec_schema_text as s; "
        'print(s(), end="")\' > docs/schema/automaton.schema.json'
    )


def test_schema_is_valid_draft_07(committed: dict[str, Any]) -> None:
    assert committed["$schema"] == "http://json-schema.org/draft-07/schema#"
    jsonschema.Draft7Validator.check_schema(committed)
    assert committed == spec_schema()


def test_schema_uses_only_draft_07_keywords(committed: dict[str, Any]) -> None:
    """Keywords of later drafts (``prefixItems``, ``$defs``...) would be silently ignored."""
    later = {"prefixItems", "$defs", "unevaluatedProperties", "dependentRequired", "$dynamicRef"}
    found: set[str] = set()

    def walk(node: Any, parent: str | None) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                if parent not in ("properties", "patternProperties", "definitions"):
                    found.add(key)
                walk(value, key)
        elif isinstance(node, list):
            for item in node:
                walk(item, None)

    walk(committed, None)
    assert not found & later


def test_there_are_specs() -> None:
    assert len(SPECS) >= 2


@pytest.mark.parametrize("path", SPECS, ids=[p.name for p in SPECS])
def test_spec_has_the_schema_modeline(path: Path) -> None:
    first = path.read_text(encoding="utf-8").splitlines()[0]
    if path.parent == ROOT / "specs":
        assert first == MODELINE
    prefix = "# yaml-language-server: $schema="
    assert first.startswith(prefix), f"{path.name}: first line must be the schema modeline"
    target = (path.parent / first[len(prefix) :]).resolve()
    assert target == SCHEMA_PATH


@pytest.mark.parametrize("path", SPECS, ids=[p.name for p in SPECS])
def test_spec_validates_against_committed_schema(
    path: Path, validator: jsonschema.Draft7Validator
) -> None:
    data = read_yaml_file(path).data
    errors = sorted(validator.iter_errors(data), key=lambda e: list(e.absolute_path))
    assert not errors, "\n".join(f"{list(e.absolute_path)}: {e.message}" for e in errors)


@pytest.mark.parametrize("path", SPECS, ids=[p.name for p in SPECS])
def test_spec_loads(path: Path) -> None:
    hybrid.load(path)


@pytest.mark.parametrize(
    "text",
    [
        "automaton: a\nlocations: {l: {flwo: {}}}\n",  # unknown key
        "automaton: a\nstate: {x: {bounds: [0, high]}}\nlocations: {l: {}}\n",  # tuple items
        "automaton: a\nstate: {x: {bounds: [0, 1, 2]}}\nlocations: {l: {}}\n",  # tuple length
        "automaton: a\nparameters: {g: fast}\nlocations: {l: {}}\n",  # number
        "automaton: my a\nlocations: {l: {}}\n",  # name pattern
        "automaton: a\n",  # required key
        "system: s\ncomponents: []\n",  # at least one component
        "automaton: a\nsystem: s\nlocations: {l: {}}\ncomponents: [{spec: b.yaml}]\n",  # not both
    ],
)
def test_schema_rejects_what_the_loader_rejects(
    text: str, validator: jsonschema.Draft7Validator
) -> None:
    data = read_yaml_text(text).data
    assert not validator.is_valid(data)
    with pytest.raises(hybrid.SpecError):
        hybrid.load_text(text)


def test_schema_accepts_a_system_file(validator: jsonschema.Draft7Validator) -> None:
    data = read_yaml_text(
        "system: s\ncomponents:\n  - spec: a.yaml\n    as: first\n    parameters: {g: 1.0}\n"
    ).data
    validator.validate(data)
