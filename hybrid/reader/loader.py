"""Load spec files (automaton or system) into frozen models.

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text("automaton: a\\nlocations: {only: {}}\\n")
>>> m.name, list(m.locations)
('a', ['only'])
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from hybrid.allocation import gc_paused
from hybrid.compose import System
from hybrid.errors import Position, SpecError, UsageError, brief, did_you_mean
from hybrid.frames import in_frame_room
from hybrid.model import Automaton
from hybrid.reader.build import build_automaton
from hybrid.reader.messages import closest, validation_problems
from hybrid.reader.schema import AutomatonSpec, SystemSpec
from hybrid.reader.system import build_system
from hybrid.reader.yamlpos import YamlDocument, read_yaml_file, read_yaml_text

__all__ = ["load", "load_document", "load_text"]


@in_frame_room
def load(path: str | Path, parameters: Mapping[str, float] | None = None) -> Automaton | System:
    """Load an automaton or system spec file.

    Parameters
    ----------
    path : str or Path
        The YAML file (``automaton:`` or ``system:``); a system's component
        specs are found relative to it.
    parameters : mapping, optional
        Overrides of declared parameters: ``name`` in an automaton; in a system
        ``comp.name``, or ``name`` where only one component declares it.

    Returns
    -------
    Automaton or System
        The frozen model.

    Raises
    ------
    SpecError
        With ``file``, ``line`` and ``column`` of every problem found.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml", parameters={"e": 0.7})
    >>> ball.parameters["e"], ball.initial_location
    (0.7, 'falling')
    """
    path = _path_given(path)
    with gc_paused():
        doc = read_yaml_file(path)
        return load_document(doc, Path(path).parent, parameters)


_SPEC_START = re.compile(r"\s*(\{|(automaton|system)\s*:)")
"""How the text of a spec on one line starts (``{automaton: x, ...}``, ``automaton: x``)."""


def _path_given(path: object) -> str | Path:
    """``path`` if it names a file (bytes decoded); a :class:`UsageError` saying what to pass if not."""
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if isinstance(path, str) and ("\n" in path or (_SPEC_START.match(path) and not os.path.exists(path))):
        raise UsageError(
            "load() takes the path of a spec file; this is the text of one: "
            "use hybrid.load_text(text)"
        )
    if isinstance(path, os.PathLike):
        path = Path(os.fspath(path))
    if not isinstance(path, str | Path):
        raise UsageError(
            f"load() takes the path of a spec file (a str or Path), got {type(path).__name__}: "
            f"{brief(path)}"
        )
    return path


@in_frame_room
def load_text(
    text: str,
    parameters: Mapping[str, float] | None = None,
    *,
    file: str = "<string>",
    base_dir: str | Path = ".",
) -> Automaton | System:
    """Load a spec from a string, as :func:`load` does from a file.

    Parameters
    ----------
    text : str
        The YAML text.
    parameters : mapping, optional
        Overrides of declared parameters (see :func:`load`).
    file : str
        The name errors give as the file (default ``<string>``).
    base_dir : str or Path
        Where a system's component specs are found.

    Examples
    --------
    >>> import hybrid
    >>> m = hybrid.load_text("automaton: a\\nlocations: {only: {}}\\n", file="a.yaml")
    >>> m.name, m.file
    ('a', 'a.yaml')
    """
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SpecError(
                f"the text is not UTF-8 (byte {exc.start}): decode it first", Position(file)
            ) from None
    if not isinstance(text, str):
        raise UsageError(f"load_text() takes the YAML text as a str, got {type(text).__name__}")
    with gc_paused():
        doc = read_yaml_text(text, file)
        return load_document(doc, Path(base_dir), parameters)


def load_document(
    doc: YamlDocument,
    base_dir: Path,
    parameters: Mapping[str, float] | None = None,
    *,
    _stack: tuple[str, ...] = (),
) -> Automaton | System:
    """Validate a parsed YAML document and build its model."""
    data: Any = doc.data
    where = doc.positions.value(())
    if not isinstance(data, dict):
        raise SpecError(
            f"a spec must be a mapping starting with 'automaton:' or 'system:', got {_kind(data)}",
            where,
        )
    if "automaton" in data:
        spec = _validate(AutomatonSpec, doc)
        model = build_automaton(spec, doc.positions)
        return model.with_parameters(parameters) if parameters else model
    if "system" in data:
        system_spec = _validate(SystemSpec, doc)
        automata = _components(system_spec, doc, base_dir, _stack)
        system = build_system(system_spec, doc.positions, automata)
        return system.with_parameters(parameters) if parameters else system
    keys = [str(k) for k in data]
    hint = next(
        (closest(k, ["automaton", "system"]) for k in keys if closest(k, ["automaton", "system"])),
        "",
    )
    raise SpecError(f"a spec must have an 'automaton:' or a 'system:' key at the top{hint}", where)


def _components(
    spec: SystemSpec, doc: YamlDocument, base_dir: Path, stack: tuple[str, ...]
) -> list[Automaton | None]:
    """Read each component's spec file (``None`` for one that failed; all problems raised)."""
    automata: list[Automaton | None] = []
    problems: list[tuple[Position, str]] = []
    for i, comp in enumerate(spec.components):
        where = doc.positions.value(("components", i, "spec"))
        automata.append(None)
        # shown as the user would write it (relative stays relative); resolved for cycles
        path = Path(os.path.normpath(base_dir / comp.spec))
        try:
            document = read_yaml_file(path, where=where)
        except SpecError as exc:
            if exc.position == where and exc.message.endswith(": not found"):
                exc = SpecError(
                    f"component spec '{comp.spec}' not found (looked in {base_dir})"
                    + _nearby_spec(base_dir, comp.spec),
                    where,
                )
            problems.extend(exc.problems)
            continue
        try:
            real = str(path.resolve())
        except (OSError, RuntimeError) as exc:
            problems.append((where, f"component spec '{comp.spec}' cannot be resolved: {exc}"))
            continue
        if real in stack:
            problems.append((where, f"component spec '{comp.spec}' includes itself"))
            continue
        try:
            model = load_document(document, path.parent, _stack=(*stack, real))
        except SpecError as exc:
            problems.extend(exc.problems)
            continue
        if not isinstance(model, Automaton):
            problems.append(
                (where, f"component spec '{comp.spec}' is a system; components must be automata")
            )
            continue
        automata[-1] = model
    if problems:
        raise SpecError.many(problems)
    return automata


def _validate(model: type[Any], doc: YamlDocument) -> Any:
    try:
        return model.model_validate(doc.data)
    except ValidationError as exc:
        raise SpecError.many(validation_problems(exc, model, doc.positions, doc.data)) from None


def _kind(data: Any) -> str:
    if isinstance(data, list):
        return "a list"
    if data is None:
        return "nothing"
    return f"a {type(data).__name__} value"


def _nearby_spec(base_dir: Path, name: str) -> str:
    """``"; did you mean 'x.yaml'?"`` for the closest spec file beside the system, or ``""``."""
    try:
        found = [p.name for p in base_dir.iterdir() if p.suffix in (".yaml", ".yml")][:1000]
    except OSError:
        return ""
    return did_you_mean(Path(name).name, found)
