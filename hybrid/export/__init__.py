"""Writing results: trajectories, events, figures, diagrams; every file written atomically.

Trajectories and events (:mod:`~hybrid.export.trajectory`), figures of a run over
hybrid time (:mod:`~hybrid.export.plot`, needs matplotlib), diagrams of the
automaton as DOT and Mermaid text (:mod:`~hybrid.export.diagrams`) or drawn by
Graphviz (:mod:`~hybrid.export.pictures`).
"""

from typing import TYPE_CHECKING

from hybrid.lazy import lazy_attributes

if TYPE_CHECKING:
    from hybrid.export.diagrams import to_dot, to_mermaid
    from hybrid.export.pictures import render
    from hybrid.export.plot import figure_of, figures_of, plot_run, save_figure
    from hybrid.export.trajectory import (
        events_document,
        write_csv,
        write_events,
        write_mat,
        write_npz,
    )
    from hybrid.files import atomic_write

__all__ = [
    "atomic_write",
    "events_document",
    "figure_of",
    "figures_of",
    "plot_run",
    "render",
    "save_figure",
    "to_dot",
    "to_mermaid",
    "write_csv",
    "write_events",
    "write_mat",
    "write_npz",
]

__getattr__, __dir__ = lazy_attributes(
    __name__,
    {
        "atomic_write": "hybrid.files",
        "events_document": "hybrid.export.trajectory",
        "figure_of": "hybrid.export.plot",
        "figures_of": "hybrid.export.plot",
        "plot_run": "hybrid.export.plot",
        "render": "hybrid.export.pictures",
        "save_figure": "hybrid.export.plot",
        "to_dot": "hybrid.export.diagrams",
        "to_mermaid": "hybrid.export.diagrams",
        "write_csv": "hybrid.export.trajectory",
        "write_events": "hybrid.export.trajectory",
        "write_mat": "hybrid.export.trajectory",
        "write_npz": "hybrid.export.trajectory",
    },
)
