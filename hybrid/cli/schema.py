"""``hybrid schema``: the JSON Schema of spec and system files, for editors.

Printed on stdout, or written with ``--out FILE`` (atomically) where the
``# yaml-language-server: $schema=...`` modeline of a project's specs points.
The schema is the one of the installed version of ``hybrid``: write it again
after an upgrade.

Examples
--------
>>> import json, pathlib, tempfile
>>> target = pathlib.Path(tempfile.mkdtemp()) / "automaton.schema.json"
>>> run_schema(str(target))
0
>>> json.loads(target.read_text())["$schema"]
'http://json-schema.org/draft-07/schema#'
"""

from __future__ import annotations

import sys

from hybrid.cli.exits import EXIT_OK
from hybrid.files import atomic_write
from hybrid.reader.jsonschema import spec_schema_text

__all__ = ["run_schema"]


def run_schema(path: str | None = None) -> int:
    """Print the schema, or write it to ``path``; returns the exit code (0)."""
    text = spec_schema_text()
    if path is None:
        sys.stdout.write(text)
        return EXIT_OK
    from hybrid.export.outputs import writable_file

    writable_file(path, "--out")
    with atomic_write(path) as handle:
        handle.write(text.encode("utf-8"))
    return EXIT_OK
