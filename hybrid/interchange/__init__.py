"""Interchange with the field's formats: SpaceEx import and export.

- :func:`import_spaceex` reads a SpaceEx model (``.xml``, untrusted input read
  by a hardened parser) and its ``.cfg`` into YAML spec texts;
- :func:`export_spaceex` writes one of our models as SpaceEx XML and ``.cfg``.

See ``docs/interchange.md`` for the mapping, construct by construct.
"""

from hybrid.interchange.exporter import ExportResult, export_spaceex
from hybrid.interchange.importer import ImportResult, import_spaceex, import_spaceex_text

__all__ = [
    "ExportResult",
    "ImportResult",
    "export_spaceex",
    "import_spaceex",
    "import_spaceex_text",
]
