"""The import loads what it wrote: a translation that does not load is refused at its source.

``hybrid import spaceex`` never succeeds with specs that ``hybrid validate``
refuses. After translating, the files are written to a temporary directory
and loaded as a user would load them; a problem there is a mistranslation, and
is reported (exit 2) at the place in the SpaceEx model (or ``.cfg``) of the
construct that gave the faulty YAML: each generated file carries a map from
its YAML paths (``("edges", 3)``, ``("signals", "y")``) to the SpaceEx
positions they come from, and the problem is placed at the nearest path at or
above its line.

Examples
--------
>>> from hybrid.errors import Position
>>> files = {"a.yaml": "automaton: a\\nlocations: {l: {flow: {x: y}}}\\n"}
>>> try:
...     check_loads(files, "a.yaml", {"a.yaml": {(): Position("m.xml", 3, 1)}})
... except SpecError as exc:
...     print(exc.position, exc.message)
m.xml:3:1 the translation of this construct does not load (a.yaml:2:24: flow of 'x': not a state variable): nothing was written
"""

from __future__ import annotations

import tempfile
from collections.abc import Mapping
from pathlib import Path

from hybrid.errors import Position, SpecError

__all__ = ["Provenance", "check_loads"]

Path_ = tuple[str | int, ...]
Provenance = Mapping[str, Mapping[Path_, Position]]
"""Generated file name -> {YAML path: the SpaceEx position it comes from}."""


def check_loads(files: Mapping[str, str], top: str, provenance: Provenance) -> None:
    """Load ``files`` (``top`` first) as ``hybrid validate`` would.

    Raises
    ------
    SpecError
        At the SpaceEx position of the construct whose translation does not
        load, with the loader's message on the generated file.
    """
    from hybrid.reader.loader import load

    with tempfile.TemporaryDirectory(prefix="hybrid-import-") as folder:
        base = Path(folder)
        for name, text in files.items():
            (base / name).write_text(text, encoding="utf-8")
        try:
            load(base / top)
        except SpecError as exc:
            where, message = exc.problems[0]
            message = message.replace(f"{base}/", "")
            name = Path(where.file).name
            source = _source(files.get(name, ""), name, where, provenance.get(name, {}))
            shown = f"{name}:{where.line}:{where.column}" if where.line else name
            raise SpecError(
                f"the translation of this construct does not load ({shown}: {message}): "
                "nothing was written",
                source,
            ) from None


def _source(text: str, name: str, where: Position, origins: Mapping[Path_, Position]) -> Position:
    """The SpaceEx position of the nearest translated construct at or above ``where``."""
    from hybrid.reader.yamlpos import read_yaml_text

    fallback = origins.get((), Position(name))
    try:
        doc = read_yaml_text(text, name)
    except SpecError:
        return fallback
    best: tuple[int, int, Position] | None = None
    for path, origin in origins.items():
        at = doc.positions.keys.get(path) or doc.positions.values.get(path)
        if at is None or at.line > where.line:
            continue
        rank = (at.line, len(path))
        if best is None or rank > best[:2]:
            best = (*rank, origin)
    return best[2] if best is not None else fallback
