"""The JSON Schema (draft-07) of spec files, for editors and other tools.

Examples
--------
>>> schema = spec_schema()
>>> schema["$schema"]
'http://json-schema.org/draft-07/schema#'
>>> sorted(option["$ref"] for option in schema["oneOf"])
['#/definitions/AutomatonSpec', '#/definitions/SystemSpec']
"""

from __future__ import annotations

import json
from typing import Any

from pydantic.json_schema import models_json_schema

from hybrid.spec.schema import AutomatonSpec, SystemSpec

__all__ = ["spec_schema", "spec_schema_text"]


def spec_schema() -> dict[str, Any]:
    """One schema accepting either an automaton file or a system file."""
    _, top = models_json_schema(
        [(AutomatonSpec, "validation"), (SystemSpec, "validation")],
        ref_template="#/definitions/{model}",
    )
    definitions = top.get("$defs", {})
    text = json.dumps(definitions)
    return {
        "$schema": "http://json-schema.org/draft-07/schema#",
        "$id": "https://hybrid.invalid/schema/automaton.schema.json",
        "title": "hybrid spec (automaton or system)",
        "oneOf": [
            {"$ref": "#/definitions/AutomatonSpec"},
            {"$ref": "#/definitions/SystemSpec"},
        ],
        "definitions": json.loads(text),
    }


def spec_schema_text() -> str:
    """The schema as committed under ``docs/schema/`` (stable key order, final newline)."""
    return json.dumps(spec_schema(), indent=2, sort_keys=True) + "\n"
