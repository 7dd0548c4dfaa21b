"""Pictures of location and product graphs: SVG and PNG drawn by Graphviz.

The DOT source comes from :func:`hybrid.export.diagrams.to_dot`; Graphviz's
``dot`` program lays it out and draws it, through the ``graphviz`` Python
package (the ``graph`` extra). Both must be installed: the package from the
package index, ``dot`` from the system (``apt-get install graphviz``,
``brew install graphviz``, ``conda install graphviz``). Without either, the
error says which one is missing and how to install it.

Examples
--------
>>> import hybrid
>>> from hybrid.analysis import location_graph
>>> svg = render(location_graph(hybrid.load("specs/thermostat.yaml")), "svg")  # doctest: +SKIP
>>> svg.startswith(b"<?xml")  # doctest: +SKIP
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from hybrid.errors import UsageError
from hybrid.export.diagrams import to_dot
from hybrid.version import install_hint

if TYPE_CHECKING:
    import networkx as nx

__all__ = ["RENDERED_FORMATS", "render"]

RENDERED_FORMATS = ("svg", "png")
"""The picture formats of ``hybrid graph --format`` (drawn by Graphviz)."""

DOT_HINT = "apt-get install graphviz, brew install graphviz or conda install graphviz"


def render(graph: nx.MultiDiGraph, fmt: str) -> bytes:
    """``graph`` drawn by Graphviz ``dot`` as ``fmt`` (``svg`` or ``png``) bytes.

    Raises :class:`hybrid.UsageError` when the ``graphviz`` package or the ``dot``
    program is missing (saying how to install it), or for an unknown format.
    """
    if fmt not in RENDERED_FORMATS:
        raise UsageError(f"cannot draw '{fmt}'; use one of {', '.join(RENDERED_FORMATS)}")
    try:
        import graphviz
    except ImportError:
        raise UsageError(
            f"--format {fmt} draws with Graphviz: install the Python package "
            f"({install_hint('graph')}) and the dot program ({DOT_HINT}); "
            f"or print DOT text (--format dot) and draw it elsewhere"
        ) from None
    try:
        return bytes(graphviz.Source(to_dot(graph)).pipe(format=fmt))
    except graphviz.ExecutableNotFound:
        raise UsageError(
            f"--format {fmt} draws with Graphviz, but its dot program is not on PATH: "
            f"install it ({DOT_HINT}); or print DOT text (--format dot) and draw it elsewhere"
        ) from None
