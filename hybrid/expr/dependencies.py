"""Signals defined through each other: cycles and evaluation order (stdlib ``graphlib``).

A signal's definition may read other signals; the simulator computes them
dependencies first, and a circular definition is refused when a spec or a
system is loaded.

Examples
--------
>>> find_dependency_cycle({"a": ["b"], "b": ["a"], "c": []})
['a', 'b']
>>> from hybrid.expr import ir
>>> defs = {"p": ir.Var("k", ir.SIGNAL), "k": ir.Num(2.0)}
>>> evaluation_order({"p"}, defs)
['k', 'p']
>>> signals_read([ir.Bin("+", ir.Var("p", ir.SIGNAL), ir.Var("x", ir.STATE))], defs)
['k', 'p']
"""

from __future__ import annotations

from collections.abc import Callable, Container, Iterable, Mapping
from graphlib import CycleError, TopologicalSorter

from hybrid.expr import ir

__all__ = [
    "evaluation_order",
    "find_cycle",
    "find_dependency_cycle",
    "signal_dependencies",
    "signals_read",
]


def find_dependency_cycle(deps: Mapping[str, Iterable[str]]) -> list[str] | None:
    """A cycle in a dependency graph (name -> names it uses), or ``None``.

    The cycle is given in the direction of use (``a`` uses ``b`` uses ... ``a``),
    starting at its smallest name, so messages do not depend on dict order.
    """
    graph = {n: sorted(d for d in ds if d in deps) for n, ds in deps.items()}
    try:
        TopologicalSorter(graph).prepare()
    except CycleError as exc:
        # graphlib lists each node before the one that uses it: reverse to "uses" order
        cycle = list(reversed(exc.args[1][:-1]))
        start = cycle.index(min(cycle))
        return cycle[start:] + cycle[:start]
    return None


def signal_dependencies(definitions: Mapping[str, ir.Expr]) -> dict[str, set[str]]:
    """For each defined signal, the defined signals its definition reads.

    Inputs count too: a component's input is a use of the signal of the same
    name that another component defines.
    """
    return {n: ir.names_in(e) & definitions.keys() for n, e in definitions.items()}


def find_cycle(definitions: Mapping[str, ir.Expr]) -> list[str] | None:
    """A list of signal names forming a cycle of definitions, or ``None``."""
    return find_dependency_cycle(signal_dependencies(definitions))


def evaluation_order(
    needed: Iterable[str], definitions: Mapping[str, ir.Expr], done: Container[str] = ()
) -> list[str]:
    """The signals ``needed`` and those they read, each after its dependencies.

    Signals in ``done`` (evaluated already) are neither listed nor followed.
    Raises ``ValueError`` on a circular definition (loading refuses those first).
    """
    graph: dict[str, set[str]] = {}
    pending = sorted(n for n in needed if n in definitions and n not in done)
    while pending:
        name = pending.pop()
        if name in graph:
            continue
        graph[name] = {n for n in ir.names_in(definitions[name]) & definitions.keys()
                       if n not in done}  # fmt: skip
        pending.extend(sorted(graph[name] - graph.keys()))
    try:
        # sorted predecessors: the same order in every process (generated source is cached by it)
        return list(TopologicalSorter({n: sorted(d) for n, d in graph.items()}).static_order())
    except CycleError as exc:
        raise ValueError(f"signals form a circular definition through '{exc.args[1][0]}'") from None


def signals_read(
    exprs: Iterable[ir.Expr],
    definitions: Mapping[str, ir.Expr],
    reads: Callable[[ir.Expr], Iterable[str]] = ir.names_in,
) -> list[str]:
    """The defined signals ``exprs`` read, directly or through other definitions, sorted.

    ``reads`` gives the names an expression reads (a caller may pass a cached one);
    only names ``definitions`` defines are followed.
    """
    seen: set[str] = set()
    todo = [n for e in exprs for n in reads(e)]
    while todo:
        name = todo.pop()
        if name in seen or name not in definitions:
            continue
        seen.add(name)
        todo.extend(reads(definitions[name]))
    return sorted(seen)
