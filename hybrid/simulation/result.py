"""What a simulation returns: the hybrid trajectory, its jumps and how it ended.

Examples
--------
>>> import hybrid
>>> run = hybrid.simulate(hybrid.load("specs/bouncing_ball.yaml"), t_end=2.0)
>>> run.termination.cause, len(run.jumps)
('t_end', 1)
>>> bool(run.j[-1] == 1), run["h"].shape == run.t.shape
(True, True)
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import numpy as np
from numpy.typing import NDArray

from hybrid.errors import UnknownName, UsageError, did_you_mean

if TYPE_CHECKING:
    from hybrid.simulation.bounds import Extremes

__all__ = ["CAUSES", "PLOT_BACKEND", "Jump", "RequirementResult", "Run", "Termination"]

_TABLE_COLUMNS = ("t", "j", "location")
"""The columns of a run's table before its states and signals (the names are reserved)."""

CAUSES = ("t_end", "max_jumps", "zeno", "blocked", "nonfinite", "solver_failure", "interrupted")
"""Every way a run can end; only ``t_end`` is a normal end."""

PLOT_BACKEND = "hybrid.export.plot"
"""The module that draws :meth:`Run.plot` (named, like pandas' plotting backend, because
figures belong to the export layer above the simulator: docs/architecture.md)."""


@dataclass(frozen=True)
class Jump:
    """One discrete transition: at time ``t``, from hybrid time ``j`` to ``j + 1``.

    ``enabled`` lists every transition enabled at that instant and ``chosen_by``
    says how this one was picked (``only``, ``priority`` or ``file order``).
    """

    t: float
    j: int
    edge: str
    label: str | None
    source: str
    target: str
    before: Mapping[str, float]
    after: Mapping[str, float]
    enabled: tuple[str, ...] = ()
    chosen_by: str = "only"

    def as_dict(self) -> dict[str, Any]:
        return {
            "t": self.t,
            "j": self.j,
            "edge": self.edge,
            "label": self.label,
            "source": self.source,
            "target": self.target,
            "before": dict(self.before),
            "after": dict(self.after),
            "enabled": list(self.enabled),
            "chosen_by": self.chosen_by,
        }


@dataclass(frozen=True)
class Termination:
    """How and where (``t``, ``j``) a run ended."""

    cause: str
    t: float
    j: int
    message: str
    zeno_time: float | None = None
    location: str | None = None

    @property
    def ok(self) -> bool:
        return self.cause == "t_end"

    def as_dict(self) -> dict[str, Any]:
        return {
            "cause": self.cause,
            "t": self.t,
            "j": self.j,
            "message": self.message,
            "zeno_time": self.zeno_time,
            "location": self.location,
        }


@dataclass(frozen=True)
class RequirementResult:
    """What the monitor found of one requirement on one run (docs/semantics.md, "Requirements").

    ``robustness`` is the usual quantitative semantics of signal temporal logic:
    for ``always`` the smallest margin by which the condition holds over the
    scope (negative where it fails), for ``eventually`` the largest; ``inf``
    (``always``) or ``-inf`` (``eventually``) when no point of the run is in
    scope. ``violated_at`` is the first time it fails (``always``: the exact
    crossing; ``eventually``: where its scope closed), None when it holds.
    ``message`` says why it could not be evaluated, when it could not.
    """

    name: str
    holds: bool
    robustness: float
    violated_at: float | None = None
    message: str = ""

    def as_dict(self) -> dict[str, Any]:
        """``{"holds", "robustness", "violated_at"}`` (and ``"message"`` when there is one)."""
        found: dict[str, Any] = {
            "holds": self.holds,
            "robustness": self.robustness,
            "violated_at": self.violated_at,
        }
        if self.message:
            found["message"] = self.message
        return found


@dataclass(eq=False)
class Run:
    """A hybrid trajectory: one entry per stored point, two points per jump.

    ``run.t``, ``run.j`` and ``run.location`` are arrays; ``run["name"]`` is the
    column of a state variable or signal. Two runs are equal only if they are the
    same object (compare their columns to compare their values): the fields' arrays
    have no single truth value.
    """

    model: str
    state_names: tuple[str, ...]
    signal_names: tuple[str, ...]
    t: NDArray[np.float64]
    j: NDArray[np.int64]
    location: NDArray[np.object_]
    """The location of each point: its name, a ``str`` (one object per location, shared by
    every point in it, so a system's long product names cost a reference a point)."""
    states: NDArray[np.float64]
    signals: NDArray[np.float64]
    jumps: Sequence[Jump]
    """The jumps in order: a list, or (compiled backend) a sequence over arrays equal to one."""
    termination: Termination
    settings: dict[str, Any] = field(default_factory=dict)
    segments: list[tuple[int, float, float, Any]] = field(default_factory=list, repr=False)
    """With ``dense=True``: ``(j, t0, t1, interpolant)`` per stay in a mode."""
    units: Mapping[str, str] = field(default_factory=dict)
    """The ``unit:`` of each state variable or signal that declares one (labels of plots)."""
    components: tuple[tuple[str, tuple[str, ...]], ...] = ()
    """In a system: each component's name and its columns; empty for an automaton."""
    requirements: Mapping[str, RequirementResult] = field(default_factory=dict)
    """Each requirement of the model, by name, as monitored on this run."""
    out_of_bounds: tuple[Any, ...] = ()
    """Per state variable, where the run first left its declared ``bounds:``
    (:class:`hybrid.simulation.bounds.BoundExcursion`); empty when it stayed within."""

    def __getitem__(self, name: str) -> NDArray[Any]:
        """The column of the state variable or signal ``name`` (also ``t``, ``j``, ``location``);
        of a vector signal ``v``, one column per element ``v[0]``, ``v[1]``, ...

        An unknown name (or something else than a name) is an
        :class:`~hybrid.errors.UnknownName`: a ``UsageError`` and a ``KeyError``.
        """
        if not isinstance(name, str):
            raise UnknownName(
                f"run[...] takes the name of a state variable or signal, got {name!r}; "
                "the values at point k are run.t[k], run.states[k] and run.signals[k]"
            )
        if name in self.state_names:
            return self.states[:, self.state_names.index(name)]
        if name in self.signal_names:
            return self.signals[:, self.signal_names.index(name)]
        if name in _TABLE_COLUMNS:  # the first columns of the CSV and of to_pandas()
            column: NDArray[Any] = getattr(self, name)
            return column
        elements = self._vector(name)
        if elements:  # a vector signal: one column per element, as run.plot("ee") draws it
            return self.signals[:, elements]
        matlab = re.fullmatch(r"(\w+)\((\d+)\)", name)
        if matlab and int(matlab[2]) >= 1 and f"{matlab[1]}[{int(matlab[2]) - 1}]" in self.signal_names:
            k = int(matlab[2]) - 1
            raise UnknownName(
                f"no state variable or signal '{name}'; did you mean '{matlab[1]}[{k}]'? "
                f"(elements count from 0: MATLAB's {name} is {matlab[1]}[{k}])"
            )
        hint = did_you_mean(name, [*self.state_names, *self.signal_names])
        raise UnknownName(f"no state variable or signal '{name}'{hint}")

    def _vector(self, name: str) -> list[int]:
        """The columns of the elements ``name[0]``, ``name[1]``, ... of a vector signal."""
        found: list[int] = []
        while f"{name}[{len(found)}]" in self.signal_names:
            found.append(self.signal_names.index(f"{name}[{len(found)}]"))
        return found

    def __contains__(self, name: object) -> bool:
        """Whether ``run[name]`` is a column (``"h" in run``): ``t``, ``j``, ``location``,
        a state variable or a signal."""
        return isinstance(name, str) and (
            name in _TABLE_COLUMNS
            or name in self.state_names
            or name in self.signal_names
            or bool(self._vector(name))
        )

    def __iter__(self) -> NoReturn:
        """A run is not a sequence of points: say what to write instead of ``list(run)``."""
        raise TypeError(
            "a run is not iterated: its columns are run[name] (name in run.state_names, "
            "run.signal_names, or t, j, location), point k is run.t[k], run.states[k]; "
            "run.to_pandas() gives the table"
        )

    def __getattr__(self, name: str) -> Any:
        """Called only for a name a run does not have: what to write instead.

        scipy's ``sol.y``, ``sol.status`` and ``sol.t_events``, and a column read as
        ``run.h``, are named with ours; anything else gets the closest attribute.
        """
        raise AttributeError(_no_attribute(self.__dict__, name), name=name, obj=self)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def checked_columns(self) -> tuple[NDArray[np.float64], Any, NDArray[np.float64]]:
        """``(t, j, states)`` as the checks after a run read them (a compiled run's without
        making its columns): rows in order, ``j`` as numbers."""
        return self.t, self.j, self.states

    def stored_extremes(self) -> Extremes | None:
        """The smallest and largest value of each state over the points, NaNs left out, where
        the run kept them as it went (a compiled run); else None (not worked out here)."""
        return None

    @property
    def columns(self) -> tuple[str, ...]:
        return (*self.state_names, *self.signal_names)

    @property
    def jump_times(self) -> NDArray[np.float64]:
        times = getattr(self.jumps, "times", None)  # a compiled run's, an array already
        if times is not None:
            return np.asarray(times, dtype=float)
        return np.array([jump.t for jump in self.jumps], dtype=float)

    def plot(
        self,
        *names: str,
        component: str | None = None,
        against: str = "t",
        signals: bool = True,
        path: str | Path | None = None,
        show: bool = False,
    ) -> Any:
        """Draw the run over hybrid time and return the matplotlib figure.

        Needs the ``plot`` extra (matplotlib). Nothing is shown or saved unless asked.

        Parameters
        ----------
        *names : str
            State variables and signals to draw (default: all of them).
        component : str, optional
            In a system, draw only this component (default: one section per component).
        against : {"t", "j", "both"}
            Draw values against time ``t``, against the jump count ``j``, or both side
            by side (the hybrid-time view).
        signals : bool
            Draw the signals too (one panel, a legend entry per signal).
        path : str or Path, optional
            Also write the figure there (format from the suffix: ``.png``, ``.svg``,
            ``.pdf``), atomically.
        show : bool
            Also show it in a window (``matplotlib.pyplot.show``).

        Returns
        -------
        matplotlib.figure.Figure
            A location lane on top, a panel per state variable (its ``unit:`` on the
            axis), the signals; jumps marked before (hollow) and after (filled).

        Examples
        --------
        >>> import hybrid
        >>> run = hybrid.simulate(hybrid.load("specs/bouncing_ball.yaml"), t_end=3.0)
        >>> fig = run.plot()
        >>> [ax.get_ylabel() for ax in fig.axes]
        ['location', 'h [m]', 'v [m/s]', 'signals']
        """
        for name in names:
            if not isinstance(name, str):
                raise UsageError(f"plot() takes names of state variables or signals, got {name!r}")
        if path is not None and not isinstance(path, str | Path):
            raise UsageError(f"plot(path=) names a file with a str or Path, got {path!r}")
        backend = importlib.import_module(PLOT_BACKEND)
        return backend.plot(
            self,
            *names,
            component=component,
            against=against,
            signals=signals,
            path=path,
            show=show,
        )

    def to_pandas(self) -> Any:
        """The trajectory as a :class:`pandas.DataFrame` (needs pandas).

        Columns ``t``, ``j``, ``location``, then the state variables and the signals,
        as in the CSV file: one row per stored point, two rows (same ``t``, ``j`` and
        ``j + 1``) per jump.

        Examples
        --------
        >>> import hybrid
        >>> run = hybrid.simulate(hybrid.load("specs/bouncing_ball.yaml"), t_end=2.0)
        >>> frame = run.to_pandas()
        >>> list(frame.columns)
        ['t', 'j', 'location', 'h', 'v', 'energy']
        >>> frame.groupby("j").size().tolist() == [int((run.j == k).sum()) for k in (0, 1)]
        True
        """
        try:
            import pandas as pd
        except ImportError:
            from hybrid.version import install_hint

            raise UsageError(f"to_pandas needs pandas: {install_hint('pandas')}") from None
        time = pd.DataFrame({"t": self.t, "j": self.j, "location": self.location.astype(str)})
        values = pd.DataFrame(np.hstack([self.states, self.signals]), columns=list(self.columns))
        return pd.concat([time, values], axis=1)

    def __repr__(self) -> str:
        from hybrid.simulation.display import run_text

        return run_text(self)

    def _repr_html_(self) -> str:
        from hybrid.simulation.display import run_html

        return run_html(self)


_SCIPY_HABITS = {
    "y": "the states are run.states, one row per point (scipy's sol.y is run.states.T; "
    "the names are run.state_names), and one variable is run['name']",
    "x": "the states are run.states, one row per point (MATLAB's [t, x] = ode45(...) is "
    "run.t, run.states; the names are run.state_names), and one variable is run['name']",
    "status": "how the run ended is run.termination (.cause, .message, .t, .j)",
    "success": "how the run ended is run.termination (.cause == 't_end' when it ran to the end)",
    "message": "how the run ended is run.termination (.cause, .message, .t, .j)",
    "t_events": "the jumps are run.jumps (each with .t, .edge, .source, .target)",
    "y_events": "the jumps are run.jumps (each with .t, .edge, .before, .after)",
    "sol": "with dense=True the interpolants of the stays are run.segments",
}
"""Attributes of scipy's ``solve_ivp`` result (``sol.y``...) and where a run has them."""


def _no_attribute(found: Mapping[str, Any], name: str) -> str:
    """The message of an attribute a run does not have (``found``: its ``__dict__``)."""
    said = f"'Run' object has no attribute '{name}'"
    if name.startswith("_"):  # probes (copy, pickle, IPython's _repr_latex_): no search
        return said
    if name in _SCIPY_HABITS:
        return f"{said}: {_SCIPY_HABITS[name]}"
    names = (*found.get("state_names", ()), *found.get("signal_names", ()))
    if name in names:
        return f"{said}: a state variable's or signal's column is run[{name!r}]"
    public = [a for a in (*dir(Run), *found) if not a.startswith("_")]
    return said + did_you_mean(name, public)
