"""The JSON Schema for the modeline, outside this repository: ``hybrid schema --out FILE``.

A project elsewhere writes the schema beside its specs and points the modeline
at it; the path in the modeline, resolved from the spec, must reach the file, and
the file must accept the spec and refuse a misspelt key, as the YAML language
server would.
"""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
import yaml
from support import DOCS, main_in_process

MODELINE = "# yaml-language-server: $schema="


def test_schema_out_writes_what_a_modeline_outside_the_repository_needs(tmp_path: Path) -> None:
    project = tmp_path / "project"
    (project / "specs").mkdir(parents=True)
    assert main_in_process("schema", "--out", project / "schemas" / "automaton.schema.json") == 2
    (project / "schemas").mkdir()
    target = project / "schemas" / "automaton.schema.json"
    assert main_in_process("schema", "--out", target) == 0
    assert target.read_bytes() == (DOCS / "schema" / "automaton.schema.json").read_bytes()
    spec = project / "specs" / "tank.yaml"
    spec.write_text(
        f"{MODELINE}../schemas/automaton.schema.json\n"
        + (DOCS / "examples" / "tank.yaml").read_text(encoding="utf-8")
    )
    first = spec.read_text().splitlines()[0]
    schema_path = (spec.parent / first.removeprefix(MODELINE)).resolve()
    assert schema_path == target.resolve()
    validator = jsonschema.Draft7Validator(json.loads(schema_path.read_text()))
    document = yaml.safe_load(spec.read_text())
    assert list(validator.iter_errors(document)) == []
    document["locations"]["filling"]["flwo"] = document["locations"]["filling"].pop("flow")
    assert [e.message for e in validator.iter_errors(document)]


def test_schema_prints_the_same_schema(capsys: pytest.CaptureFixture[str]) -> None:
    assert main_in_process("schema") == 0
    assert capsys.readouterr().out == (DOCS / "schema" / "automaton.schema.json").read_text()
