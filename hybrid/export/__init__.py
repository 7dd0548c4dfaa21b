"""Writing results: trajectories, events, diagrams, figures; every file written atomically."""

from typing import TYPE_CHECKING

from hybrid.lazy import lazy_attributes

if TYPE_CHECKING:
    from hybrid.export.atomic import atomic_write
    from hybrid.export.trajectory import events_document, write_csv, write_events, write_npz

__all__ = ["atomic_write", "events_document", "write_csv", "write_events", "write_npz"]

__getattr__, __dir__ = lazy_attributes(
    __name__,
    {
        "atomic_write": "hybrid.export.atomic",
        "events_document": "hybrid.export.trajectory",
        "write_csv": "hybrid.export.trajectory",
        "write_events": "hybrid.export.trajectory",
        "write_npz": "hybrid.export.trajectory",
    },
)
