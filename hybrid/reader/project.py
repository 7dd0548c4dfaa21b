"""A repository's defaults for `hybrid check`, from ``[tool.hybrid.check]`` in pyproject.toml.

The ``pyproject.toml`` looked for is the nearest one from the current
directory upwards, stopping at the root of a Git work tree (a directory
holding ``.git``). The table may hold:

.. code-block:: toml

    [tool.hybrid.check]
    ignore = ["unused-declaration"]   # rules not to report, on top of --ignore
    strict = true                     # warnings fail the run, as with --strict

Anything else in the table, a value of the wrong type, or a file that is not
valid TOML is a :class:`~hybrid.errors.SpecError` at its place in the file.

Examples
--------
>>> import pathlib, tempfile
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> _ = (folder / "pyproject.toml").write_text('[tool.hybrid.check]\\nignore = ["dead-edge"]\\n')
>>> read_check_config(folder)
CheckConfig(ignore=('dead-edge',), strict=False, file='...pyproject.toml')
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from hybrid.errors import Position, SpecError, did_you_mean
from hybrid.reader.files import read_bytes

__all__ = ["CheckConfig", "find_pyproject", "read_check_config"]

_KEYS = ("ignore", "strict")


@dataclass(frozen=True)
class CheckConfig:
    """``hybrid check`` defaults of a repository (``file`` is where they came from, or "")."""

    ignore: tuple[str, ...] = ()
    strict: bool = False
    file: str = ""

    def __repr__(self) -> str:
        name = "..." + Path(self.file).name if self.file else ""
        return f"CheckConfig(ignore={self.ignore!r}, strict={self.strict!r}, file={name!r})"


def find_pyproject(start: Path) -> Path | None:
    """The nearest ``pyproject.toml`` from ``start`` upwards, not above a Git work tree's root."""
    folder = start.resolve()
    while True:
        candidate = folder / "pyproject.toml"
        if candidate.is_file():
            return candidate
        if (folder / ".git").exists() or folder.parent == folder:
            return None
        folder = folder.parent


def read_check_config(start: Path | None = None, rules: Sequence[str] = ()) -> CheckConfig:
    """The ``[tool.hybrid.check]`` table of the nearest pyproject.toml (defaults if none).

    With ``rules`` (the rule ids ``hybrid check`` knows), an id in ``ignore`` that is
    none of them is a :class:`SpecError` at its place in the file, with the closest one.
    """
    path = find_pyproject(start or Path.cwd())
    if path is None:
        return CheckConfig()
    name = str(path)
    text = read_bytes(path).decode("utf-8", errors="replace")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        match = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        if match:
            where = Position(name, int(match[1]), int(match[2]))
        elif "end of document" in str(exc):
            where = Position(name, text.count("\n") + 1, 1)
        else:
            where = Position(name)
        reason = re.sub(r" \(at (line \d+, column \d+|end of document)\)", "", str(exc))
        raise SpecError(f"invalid TOML: {reason}", where) from None
    table = data.get("tool", {}).get("hybrid", {})
    if not isinstance(table, dict):
        raise SpecError("[tool.hybrid] must be a table", _line_of(text, name, "tool.hybrid"))
    check = table.get("check", {})
    if not isinstance(check, dict):
        raise SpecError("[tool.hybrid.check] must be a table", _line_of(text, name, "check"))
    for key in check:
        if key not in _KEYS:
            raise SpecError(
                f"unknown key '{key}' in [tool.hybrid.check]; valid keys: {', '.join(_KEYS)}",
                _line_of(text, name, key),
            )
    ignore = check.get("ignore", [])
    if not isinstance(ignore, list) or not all(isinstance(r, str) for r in ignore):
        raise SpecError(
            "[tool.hybrid.check] ignore must be a list of rule ids", _line_of(text, name, "ignore")
        )
    for rule in ignore if rules else ():
        if rule not in rules:
            raise SpecError(
                f"unknown rule '{rule}' in [tool.hybrid.check] ignore"
                f"{did_you_mean(rule, rules) or '; rules: ' + ', '.join(rules)}",
                _line_of(text, name, f'"{rule}"'),
            )
    strict = check.get("strict", False)
    if not isinstance(strict, bool):
        raise SpecError(
            "[tool.hybrid.check] strict must be true or false", _line_of(text, name, "strict")
        )
    return CheckConfig(tuple(ignore), strict, name)


def _line_of(text: str, file: str, key: str) -> Position:
    """Where ``key`` is first written (a plain search: TOML parsers keep no positions)."""
    for number, line in enumerate(text.splitlines(), start=1):
        column = line.find(key)
        if column >= 0 and not line.lstrip().startswith("#"):
            return Position(file, number, column + 1)
    return Position(file)
