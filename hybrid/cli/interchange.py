"""``hybrid import spaceex`` and ``hybrid export spaceex``.

Import writes one YAML file per translated component into ``--out`` and
prints the path of the top-level spec; export writes ``MODEL.xml`` and
``MODEL.cfg`` beside it. Notes on what the translation did go to stderr as
``file: note: ...``. Files are written whole or not at all.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from hybrid.cli.exits import EXIT_OK
from hybrid.errors import UsageError
from hybrid.files import atomic_write

__all__ = ["add_interchange_commands", "run_export", "run_import"]


def add_interchange_commands(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``import`` and ``export`` command groups to the ``hybrid`` parser."""
    p = sub.add_parser("import", help="translate a model from another tool into YAML specs")
    formats = p.add_subparsers(dest="format", required=True, parser_class=type(p))
    q = formats.add_parser("spaceex", help="a SpaceEx model (.xml) and its configuration (.cfg)")
    q.add_argument("file", metavar="MODEL.xml")
    q.add_argument("--cfg", metavar="MODEL.cfg", help="default: MODEL.cfg beside MODEL.xml, if any")
    q.add_argument("--system", metavar="NAME", help="the component to translate")
    q.add_argument("--out", metavar="DIR", required=True, help="directory for the YAML specs")
    q.add_argument("--force", action="store_true",
                   help="replace specs in DIR that differ from this import's (edits to them are lost)")  # fmt: skip
    p = sub.add_parser("export", help="write a spec in another tool's format")
    formats = p.add_subparsers(dest="format", required=True, parser_class=type(p))
    q = formats.add_parser("spaceex", help="SpaceEx model (.xml) and configuration (.cfg)")
    q.add_argument("file", metavar="FILE")
    q.add_argument("--out", metavar="MODEL.xml", required=True, help="MODEL.cfg is written beside")


def _write(path: Path, text: str) -> None:
    try:
        with atomic_write(path) as handle:
            handle.write(text.encode("utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot write {path}: {exc.strerror or exc}") from None


def _refuse_replacing(out: Path, files: dict[str, str]) -> None:
    """A :class:`UsageError`, before anything is written, if a spec of this import would
    replace a file in ``out`` that differs from it: imported specs are starting points
    their users edit, and an import into the same folder again replaced the edits."""
    differ = []
    for name, text in files.items():
        path = out / name
        try:
            if path.is_file() and path.read_bytes() != text.encode("utf-8"):
                differ.append(name)
        except OSError:  # unreadable: the write says what is wrong with it
            continue
    if differ:
        shown = ", ".join(differ[:3]) + (f" and {len(differ) - 3} more" if len(differ) > 3 else "")
        raise UsageError(
            f"--out: {out} holds {shown}, different from what this import writes (edited, or "
            "another model's): give another folder, or --force to replace them (nothing was "
            "written)"
        )


def run_import(args: argparse.Namespace) -> int:
    """``hybrid import spaceex``: exit 0, or a SpecError (exit 2) for a refused model."""
    from hybrid.export.outputs import make_directory, writable_directory
    from hybrid.interchange import import_spaceex

    xml = Path(args.file)
    if xml.suffix.lower() in (".yaml", ".yml"):  # the other direction
        raise UsageError(
            "import reads a SpaceEx model (.xml); to write this spec as one, "
            f"use hybrid export spaceex {xml} --out MODEL.xml"
        )
    if xml.suffix.lower() == ".cfg":  # the configuration given in the model's place
        model = f"{xml.with_suffix('.xml')}" if xml.with_suffix(".xml").is_file() else "MODEL.xml"
        raise UsageError(
            f"this is a SpaceEx configuration (.cfg); give the model (.xml) first: hybrid "
            f"import spaceex {model} --cfg {xml}"
        )
    writable_directory(args.out, "--out")
    cfg = Path(args.cfg) if args.cfg else None
    if cfg is None and xml.with_suffix(".cfg").is_file():
        cfg = xml.with_suffix(".cfg")
        print(f"{xml}: note: using the configuration {cfg}", file=sys.stderr)
    result = import_spaceex(xml, cfg, args.system)
    if not args.force:
        _refuse_replacing(Path(args.out), result.files)
    out = make_directory(Path(args.out), "--out")
    for name, text in result.files.items():
        _write(out / name, text)
    for note in result.notes:
        print(f"{xml}: note: {note}", file=sys.stderr)
    print(out / result.top)
    return EXIT_OK


def run_export(args: argparse.Namespace) -> int:
    """``hybrid export spaceex``: exit 0, or a SpecError (exit 2) for what SpaceEx lacks."""
    from hybrid.export.outputs import writable_file
    from hybrid.interchange import export_spaceex
    from hybrid.reader.loader import load

    xml = Path(args.out)
    if Path(args.file).suffix.lower() in (".xml", ".cfg"):  # the other direction
        raise UsageError(
            "export writes a spec as SpaceEx; to read this SpaceEx model, "
            f"use hybrid import spaceex {args.file} --out DIR"
        )
    if xml.suffix.lower() != ".xml":
        raise UsageError(
            f"--out must name a .xml file (its .cfg is written beside it), got '{xml}'"
        )
    writable_file(xml, "--out")
    writable_file(xml.with_suffix(".cfg"), "--out (its .cfg)")
    result = export_spaceex(load(args.file))
    _write(xml, result.xml)
    _write(xml.with_suffix(".cfg"), result.cfg)
    for note in result.notes:
        print(f"{args.file}: note: {note}", file=sys.stderr)
    print(xml)
    print(xml.with_suffix(".cfg"))
    return EXIT_OK
