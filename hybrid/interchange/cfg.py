"""The SpaceEx ``.cfg`` file: ``key = value`` lines, values quoted or bare.

Only what a model needs is read: ``system`` (the component to analyse),
``initially`` (the initial set) and ``forbidden`` (the bad states), and the
horizon and jump bound of its analysis (``time-horizon``, ``iter-max``: the
spec's ``checks: {reach: ...}``, :func:`reach_checks`); the other keys are
analysis options of SpaceEx (sampling time, directions...) and are kept as
they are, for the notes. ``#`` starts a comment outside quotes.

Examples
--------
>>> cfg = parse_cfg('system = "sys"\\ninitially = "x==1 & v==0"  # start\\n', "m.cfg")
>>> cfg.system, cfg.initially.text, str(cfg.initially.where(0))
('sys', 'x==1 & v==0', 'm.cfg:2:14')
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from hybrid.errors import Position, SpecError
from hybrid.interchange.safexml import SourceText

__all__ = ["MAX_CFG_BYTES", "SpaceExConfig", "parse_cfg", "reach_checks", "read_cfg"]

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


def reach_checks(config: SpaceExConfig, notes: list[str]) -> dict[str, float | int] | None:
    """The spec's ``checks.reach`` from the ``.cfg``'s ``time-horizon`` and ``iter-max``.

    ``None`` without a horizon (``t_end`` is what ``checks.reach`` needs). What is
    not taken is said in ``notes``: a value that is not a number, ``iter-max = -1``
    (no bound: reach's default bound applies), a ``sampling-time`` (reach's step
    is its own, ``t_end / 4000`` by default).

    Examples
    --------
    >>> notes = []
    >>> reach_checks(parse_cfg("time-horizon = 20.1\\niter-max = 1\\n"), notes), notes
    ({'t_end': 20.1, 'max_jumps': 1}, [])
    >>> reach_checks(parse_cfg("time-horizon = 5\\niter-max = -1\\n"), notes)
    {'t_end': 5.0}
    >>> notes[0]
    'iter-max = -1 of the .cfg (no bound) is not a jump bound here: reach bounds jumps at 10 unless checks.reach.max_jumps says otherwise'
    """
    horizon = config.get("time-horizon")
    if horizon is None:
        return None
    try:
        t_end = float(horizon.text)
    except ValueError:
        t_end = math.nan
    if not (math.isfinite(t_end) and t_end > 0):
        notes.append(f"time-horizon = {horizon.text} of the .cfg is not a horizon (a number > 0): "
                     "no checks.reach written")  # fmt: skip
        return None
    found: dict[str, float | int] = {"t_end": t_end}
    bound = config.get("iter-max")
    if bound is not None:
        try:
            jumps = int(bound.text)
        except ValueError:
            jumps = -2
        if jumps >= 0:
            found["max_jumps"] = jumps
        elif jumps == -1:
            notes.append("iter-max = -1 of the .cfg (no bound) is not a jump bound here: reach "
                         "bounds jumps at 10 unless checks.reach.max_jumps says otherwise")  # fmt: skip
        else:
            notes.append(f"iter-max = {bound.text} of the .cfg is not a jump bound (a whole "
                         "number): reach bounds jumps at 10")  # fmt: skip
    sampling = config.get("sampling-time")
    if sampling is not None:
        notes.append(f"sampling-time = {sampling.text} of the .cfg is not reach's step: its "
                     "default is t_end / 4000 (checks.reach.step sets it)")  # fmt: skip
    return found


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
