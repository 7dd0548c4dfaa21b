"""Writing results: trajectories, events, figures; every file written atomically."""

from hybrid.export.atomic import atomic_write
from hybrid.export.trajectory import events_document, write_csv, write_events, write_npz

__all__ = ["atomic_write", "events_document", "write_csv", "write_events", "write_npz"]
