"""User-facing errors: every mistake a user can make ends in one of these.

All derive from :class:`HybridError`. ``SpecError`` carries a place in the
user's file (``file:line:column``); ``SimulationError`` carries a place in
hybrid time (``t`` and ``j``); ``UsageError``, a ``SimulationError``, is an
invalid argument or setting (the command line exits 2 for it). Anything else
escaping the public API is a bug in ``hybrid``.

Examples
--------
>>> issubclass(SpecError, HybridError), issubclass(UsageError, SimulationError)
(True, True)
"""

from __future__ import annotations

import difflib
import os
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

__all__ = [
    "CannotWrite",
    "HybridError",
    "Note",
    "OutOfRange",
    "Position",
    "SimulationError",
    "SpecError",
    "UnknownArgument",
    "UnknownName",
    "UsageError",
    "brief",
    "did_you_mean",
    "users_stacklevel",
]


@dataclass(frozen=True, slots=True)
class Position:
    """A place in a spec file; ``line`` and ``column`` count from 1.

    Examples
    --------
    >>> str(Position("ball.yaml", 3, 5))
    'ball.yaml:3:5'
    """

    file: str
    line: int = 1
    column: int = 1

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"

    def shifted(self, offset: int) -> Position:
        """The position ``offset`` characters further along the same line."""
        return Position(self.file, self.line, self.column + offset)


class HybridError(Exception):
    """The root of every error a user of ``hybrid`` can cause."""


class SpecError(HybridError):
    """A spec that cannot be accepted, with the place of each problem.

    ``message`` is the first problem; ``problems`` lists all of them as
    ``(position, message)`` pairs, sorted by place. ``str()`` gives one
    ``file:line:column: message`` line per problem.

    Examples
    --------
    >>> err = SpecError("unknown key 'flwo'", Position("a.yaml", 4, 5))
    >>> str(err)
    "a.yaml:4:5: unknown key 'flwo'"
    >>> (err.file, err.line, err.column)
    ('a.yaml', 4, 5)
    """

    def __init__(self, message: str, position: Position | None = None) -> None:
        self.problems: list[tuple[Position, str]] = [(position or Position("<spec>"), message)]
        super().__init__(str(self))

    @classmethod
    def many(cls, problems: list[tuple[Position, str]]) -> SpecError:
        """One error holding several problems (at least one), sorted by place."""
        ordered = sorted(problems, key=lambda p: (p[0].file, p[0].line, p[0].column))
        err = cls(ordered[0][1], ordered[0][0])
        err.problems = ordered
        err.args = (str(err),)
        return err

    @property
    def message(self) -> str:
        return self.problems[0][1]

    @property
    def position(self) -> Position:
        return self.problems[0][0]

    @property
    def file(self) -> str:
        return self.position.file

    @property
    def line(self) -> int:
        return self.position.line

    @property
    def column(self) -> int:
        return self.position.column

    def __str__(self) -> str:
        return "\n".join(f"{pos}: {msg}" for pos, msg in self.problems)


class SimulationError(HybridError):
    """A simulation that cannot start or go on, with its place in hybrid time.

    Examples
    --------
    >>> str(SimulationError("t_end must be > 0", t=0.0, j=0))
    't=0 j=0: t_end must be > 0'
    """

    def __init__(
        self,
        message: str,
        *,
        t: float | None = None,
        j: int | None = None,
        location: str | None = None,
    ) -> None:
        self.message = message
        self.t = t
        self.j = j
        self.location = location
        super().__init__(str(self))

    def __str__(self) -> str:
        where = []
        if self.t is not None:
            where.append(f"t={self.t:.12g}")
        if self.j is not None:
            where.append(f"j={self.j}")
        if self.location is not None:
            where.append(f"location {self.location}")
        return f"{' '.join(where)}: {self.message}" if where else self.message


class UsageError(SimulationError):
    """An invalid argument or setting of a call or command (no place in time).

    ``at`` is the place in the user's spec the mistake concerns, when there is one
    (the declaration of an input given no value); ``str()`` then starts with it.

    Examples
    --------
    >>> str(UsageError("rtol must be > 0, got -1"))
    'rtol must be > 0, got -1'
    >>> str(UsageError("input 'u' needs a value", at=Position("tank.yaml", 3, 10)))
    "tank.yaml:3:10: input 'u' needs a value"
    """

    def __init__(self, message: str, *, at: Position | None = None) -> None:
        self.at = at
        super().__init__(message)

    def __str__(self) -> str:
        return f"{self.at}: {self.message}" if self.at is not None else self.message


class UnknownName(UsageError, KeyError):
    """A name asked of something that does not have it (``run["zz"]``): a :class:`UsageError`,
    and a ``KeyError`` for code that looks names up as in a mapping.

    Examples
    --------
    >>> error = UnknownName("no state variable or signal 'zz'")
    >>> isinstance(error, KeyError), str(error)
    (True, "no state variable or signal 'zz'")
    """


class UnknownArgument(UsageError, TypeError):
    """A keyword a function does not take (``tspan=`` for ``t_end=``): a :class:`UsageError`
    that names the one meant, and the ``TypeError`` Python would have raised.

    Examples
    --------
    >>> isinstance(UnknownArgument("f() got an unexpected keyword argument 'x'"), TypeError)
    True
    """


class OutOfRange(UsageError, IndexError):
    """An index a sequence of results does not have (``ensemble[10]`` of ten runs): a
    :class:`UsageError`, and an ``IndexError`` for code that iterates by index.

    Examples
    --------
    >>> isinstance(OutOfRange("run 10 of 10"), IndexError)
    True
    """


class CannotWrite(UsageError, OSError):
    """An output that cannot be written: a :class:`UsageError` for callers of the API, and an
    ``OSError`` (with the system's ``errno`` and ``strerror``) for code that handles failed
    writes (the command line keeps the output elsewhere).

    Examples
    --------
    >>> error = CannotWrite.of("out.csv", IsADirectoryError(21, "Is a directory"))
    >>> str(error), isinstance(error, OSError), error.errno
    ("cannot write 'out.csv': Is a directory", True, 21)
    """

    @classmethod
    def of(cls, path: object, exc: OSError, hint: str = "") -> CannotWrite:
        """The error for writing ``path`` failing with ``exc`` (its reason, then ``hint``)."""
        error = cls(f"cannot write '{path}': {exc.strerror or exc}{hint}")
        error.errno, error.strerror, error.filename = exc.errno, exc.strerror, str(path)
        return error


def brief(value: object, width: int = 60) -> str:
    """``repr(value)`` for a message, cut to ``width`` characters.

    Examples
    --------
    >>> brief("x" * 100)[-5:], len(brief("x" * 100))
    ('xx...', 60)
    """
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def did_you_mean(
    name: str,
    candidates: Iterable[str],
    cutoff: float = 0.6,
    aliases: Mapping[str, str] | None = None,
) -> str:
    """``"; did you mean 'x'?"`` for the closest candidate, or ``""`` if none is close.

    First another tool's spelling of a candidate (``aliases``: lowercased spelling to
    ours, where that is a candidate), then the same name in another case (difflib
    finds ``x`` no closer to ``X`` than to ``y``), then the closest by difflib.

    Examples
    --------
    >>> did_you_mean("flwo", ["flow", "signals"]), did_you_mean("X", ["y", "x"])
    ("; did you mean 'flow'?", "; did you mean 'x'?")
    >>> did_you_mean("RelTol", ["rtol", "atol"], aliases={"reltol": "rtol"})
    "; did you mean 'rtol'?"
    """
    names = list(candidates)
    meant = aliases.get(name.lower()) if aliases else None
    match = [meant] if meant in names else []
    match = match or [c for c in names if c != name and c.lower() == name.lower()][:1]
    match = match or difflib.get_close_matches(name, names, n=1, cutoff=cutoff)
    return f"; did you mean '{match[0]}'?" if match else ""


class Note(UserWarning):
    """Something ``hybrid`` did that the user should know, though nothing failed.

    Raised as a warning (``warnings.warn``), so a program decides what to do with
    it; the command line prints each as one line, ``hybrid: note: message``.
    """


def users_stacklevel() -> int:
    """The ``stacklevel`` of the user's call, for a ``warnings.warn`` made by the caller.

    Counted from the function that calls this (1) back to the first frame outside
    the ``hybrid`` package, however many of ours lie between: a warning points at
    the line of the user's program that led to it, wherever inside ``hybrid`` it is
    raised.
    """
    frame = sys._getframe(1)
    level = 1
    while frame.f_back is not None and frame.f_code.co_filename.startswith(_PACKAGE):
        frame = frame.f_back
        level += 1
    return level


_PACKAGE = os.path.dirname(__file__) + os.sep
"""The directory of the ``hybrid`` package (with its separator)."""
