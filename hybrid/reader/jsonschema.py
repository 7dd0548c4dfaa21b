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

from hybrid.reader.schema import AutomatonSpec, SystemSpec

__all__ = ["spec_schema", "spec_schema_text"]


def spec_schema() -> dict[str, Any]:
    """One schema accepting either an automaton file or a system file."""
    _, top = models_json_schema(
        [(AutomatonSpec, "validation"), (SystemSpec, "validation")],
        ref_template="#/definitions/{model}",
    )
    definitions = _draft07(json.loads(json.dumps(top.get("$defs", {}))))
    return {
        "$schema": "http://json-schema.org/draft-07/schema#",
        "$id": "https://hybrid.invalid/schema/automaton.schema.json",
        "title": "hybrid spec (automaton or system)",
        "oneOf": [
            {"$ref": "#/definitions/AutomatonSpec"},
            {"$ref": "#/definitions/SystemSpec"},
        ],
        "definitions": definitions,
    }


def _draft07(node: Any) -> Any:
    """Rewrite the few draft 2020-12 keywords pydantic emits into their draft-07 form.

    A fixed-length tuple is ``prefixItems`` in 2020-12 but ``items`` as a list in
    draft-07; a draft-07 validator would silently ignore ``prefixItems``.
    """
    if isinstance(node, list):
        return [_draft07(item) for item in node]
    if not isinstance(node, dict):
        return node
    out = {key: _draft07(value) for key, value in node.items()}
    if "prefixItems" in out:
        out["items"] = out.pop("prefixItems")
    return out


def spec_schema_text() -> str:
    """The schema as committed under ``docs/schema/`` (stable key order, final newline)."""
    return json.dumps(spec_schema(), indent=2, sort_keys=True) + "\n"
