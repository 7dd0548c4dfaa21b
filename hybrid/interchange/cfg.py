"""The SpaceEx ``.cfg`` file: ``key = value`` lines, values quoted or bare.

Only what a model needs is read: ``system`` (the component to analyse),
``initially`` (the initial set) and ``forbidden`` (the bad states); the other
keys are analysis options of SpaceEx (sampling time, directions...) and are
kept as they are, for the notes. ``#`` starts a comment outside quotes.

Examples
--------
>>> cfg = parse_cfg('system = "sys"\\ninitially = "x==1 & v==0"  # start\\n', "m.cfg")
>>> cfg.system, cfg.initially.text, str(cfg.initially.where(0))
('sys', 'x==1 & v==0', 'm.cfg:2:14')
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from hybrid.errors import Position, SpecError
from hybrid.interchange.safexml import SourceText

__all__ = ["MAX_CFG_BYTES", "SpaceExConfig", "parse_cfg", "read_cfg"]

MAX_CFG_BYTES = 4 * 1024 * 1024
"""Largest ``.cfg`` file accepted."""


@dataclass
class SpaceExConfig:
    """The keys of a ``.cfg`` file (each value with the position of its first character)."""

    file: str
    values: dict[str, SourceText] = field(default_factory=dict)

    def get(self, key: str) -> SourceText | None:
        return self.values.get(key)

    @property
    def system(self) -> str | None:
        value = self.values.get("system")
        return value.text if value is not None else None

    @property
    def initially(self) -> SourceText | None:
        return self.values.get("initially")

    @property
    def forbidden(self) -> SourceText | None:
        return self.values.get("forbidden")


def _value(line: str, start: int, number: int, file: str) -> tuple[str, int]:
    """The value text from column ``start`` (quotes removed, comment dropped) and its column."""
    rest = line[start:]
    lead = len(rest) - len(rest.lstrip())
    rest = rest.lstrip()
    column = start + lead
    if rest.startswith('"'):
        end = rest.find('"', 1)
        if end < 0:
            raise SpecError("unclosed '\"' in the value", Position(file, number, column + 1))
        trailing = rest[end + 1 :].strip()
        if trailing and not trailing.startswith("#"):
            raise SpecError(
                f"unexpected text after the closing quote: '{trailing}'",
                Position(file, number, column + end + 2),
            )
        return rest[1:end], column + 1
    hash_at = rest.find("#")
    if hash_at >= 0:
        rest = rest[:hash_at]
    return rest.rstrip(), column


def parse_cfg(text: str, file: str = "<cfg>") -> SpaceExConfig:
    """Parse ``.cfg`` text.

    Raises
    ------
    SpecError
        For a line that is not ``key = value``, with its position.
    """
    config = SpaceExConfig(file)
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        equals = line.find("=")
        if equals < 0:
            column = len(line) - len(line.lstrip()) + 1
            raise SpecError(
                f"expected 'key = value', got '{stripped[:40]}'", Position(file, number, column)
            )
        key = line[:equals].strip()
        value, column = _value(line, equals + 1, number, file)
        config.values[key] = SourceText(
            file, value, [(0, number, column + 1)], Position(file, number, column + 1)
        )
    return config


def read_cfg(path: str | Path) -> SpaceExConfig:
    """Read a ``.cfg`` file (refused unread over :data:`MAX_CFG_BYTES`)."""
    name = str(path)
    try:
        with open(path, "rb") as handle:
            raw = handle.read(MAX_CFG_BYTES + 1)
    except OSError as exc:
        raise SpecError(f"cannot read the file: {exc.strerror or exc}", Position(name)) from None
    if len(raw) > MAX_CFG_BYTES:
        raise SpecError(f"file is over the limit of {MAX_CFG_BYTES} bytes: refused", Position(name))
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SpecError(f"the file is not UTF-8 text (byte {exc.start})", Position(name)) from None
    return parse_cfg(text, name)
