"""Graph and property checks of automata and systems: what `hybrid check` runs.

:func:`check` analyses a model and returns a :class:`Report` of
:class:`Finding` s, each placed in the spec file. The location graph
(:func:`location_graph`) and the product graph of a system
(:func:`product_graph`) are networkx MultiDiGraphs.

Examples
--------
>>> import hybrid
>>> from hybrid.analysis import check
>>> report = check(hybrid.load("specs/bouncing_ball.yaml"))
>>> report.ok, report.findings
(True, ())
"""

from typing import TYPE_CHECKING

from hybrid.lazy import lazy_attributes

if TYPE_CHECKING:
    from hybrid.analysis.api import check, system_graph
    from hybrid.analysis.checks import run_checks
    from hybrid.analysis.context import Analysis, analyse
    from hybrid.analysis.findings import RULES, Finding, Report
    from hybrid.analysis.graph import location_graph, product_graph

__all__ = [
    "RULES",
    "Analysis",
    "Finding",
    "Report",
    "analyse",
    "check",
    "location_graph",
    "product_graph",
    "run_checks",
    "system_graph",
]

__getattr__, __dir__ = lazy_attributes(
    __name__,
    {
        "RULES": "hybrid.analysis.findings",
        "Analysis": "hybrid.analysis.context",
        "Finding": "hybrid.analysis.findings",
        "Report": "hybrid.analysis.findings",
        "analyse": "hybrid.analysis.context",
        "check": "hybrid.analysis.api",
        "location_graph": "hybrid.analysis.graph",
        "product_graph": "hybrid.analysis.graph",
        "run_checks": "hybrid.analysis.checks",
        "system_graph": "hybrid.analysis.api",
    },
)
