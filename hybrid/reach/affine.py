"""Affine forms of a model's flows, resets and conditions, over the reach vector.

The reach vector is the system's state variables in order, then the time ``t``
(flow 1, never reset). A flow is ``x' = A x + B u + c``, a reset
``x+ = R x + S u + r``; ``u`` are the free inputs with a range. A condition is a
disjunction of conjunctions of rows ``G x <= g`` (:class:`Rows`); a strict
comparison is read as its closure and an equality as two rows, both
over-approximations. An input in a condition is projected out row by row
(``exists u in U``: over-approximating; an unranged input drops the row), or
for a witness's checks ``for all u`` (under-approximating).

Anything not affine (``x*y``, ``sin(x)``, a vector signal, a function of a
library) is a :class:`~hybrid.errors.SpecError` at ``file:line:column`` naming
the expression.

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text('''
... automaton: heater
... parameters: {a: 0.5}
... inputs: {u: {range: [0, 1]}}
... state: {x: {initial: [1, 2]}}
... locations: {on: {flow: {x: -a * x + 2 * u + 1}}}
... ''')
>>> from hybrid.compose import as_system
>>> f = Forms(as_system(m))
>>> a, b, c = f.flow(("on",))
>>> a.tolist(), b.tolist(), c.tolist()
([[-0.5, 0.0], [0.0, 0.0]], [[2.0], [0.0]], [1.0, 1.0])
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from hybrid.analysis.linear import Affine, Linearizer, structural_key
from hybrid.compose import System
from hybrid.errors import Position, SpecError
from hybrid.expr import ir
from hybrid.expr.printer import expression_text
from hybrid.expr.ranges import IntervalEvaluator
from hybrid.expr.transform import bind_parameters

__all__ = ["TIME", "Condition", "Forms", "Rows"]

Array = NDArray[np.float64]
TIME = "t"
"""The name of the time coordinate, the last of the reach vector."""
DNF_CAP = 64
"""Largest number of cases a condition is split into; beyond it reading stops (a SpecError)."""


@dataclass(frozen=True)
class Rows:
    """A conjunction ``mat @ x <= vec`` over the reach vector (no rows: true); where ``strict``
    (a flag per row) is given, its rows that are strict are ``mat @ x < vec`` (sets use the
    closure; a witness's points are held to the condition as written)."""

    mat: Array
    vec: Array
    strict: NDArray[np.bool_] | None = None

    def bound(self, lhs: Array) -> NDArray[np.bool_]:
        """Per point (a row of ``lhs``, the rows' left-hand sides there) and row, whether the
        row holds as written: ``<=``, or ``<`` where it is strict."""
        vec = self.vec[None, :]
        if self.strict is None:
            return lhs <= vec
        return np.where(self.strict[None, :], lhs < vec, lhs <= vec)

    def conjoin(self, other: Rows) -> Rows:
        """These rows and ``other``'s, each keeping whether it is strict."""
        strict = None
        if self.strict is not None or other.strict is not None:
            strict = np.concatenate([part.flags() for part in (self, other)])
        return Rows(np.vstack([self.mat, other.mat]), np.concatenate([self.vec, other.vec]), strict)

    def flags(self) -> NDArray[np.bool_]:
        """Which rows are strict (all False where none is said to be)."""
        return np.zeros(len(self.vec), dtype=bool) if self.strict is None else self.strict


Condition = tuple[Rows, ...]
"""A disjunction of conjunctions; ``()`` is false."""
ModeKey = tuple[str, ...]


def _name_of(node: ir.Expr) -> str:
    """The expression as its user wrote it (``sin(t)``, not generated code's ``_sin(t)``)."""
    return expression_text(node)


class Forms:
    """Reads a model's expressions as affine forms over the reach vector.

    ``variables`` are the state names then ``t``; ``inputs`` the free inputs
    with a range (the columns of ``B``), ``u_lo``/``u_hi`` their ranges.
    """

    def __init__(self, system: System) -> None:
        self.system = system
        self.component_names = [c.name for c in self.system.components]
        self.variables: tuple[str, ...] = (*self.system.state_names, TIME)
        self.index = {v: i for i, v in enumerate(self.variables)}
        ranges = self.system.input_ranges()
        self.inputs = tuple(n for n in self.system.free_inputs if n in ranges)
        self.input_index = {v: i for i, v in enumerate(self.inputs)}
        self.u_lo = np.array([ranges[n].lo for n in self.inputs], dtype=float)
        self.u_hi = np.array([ranges[n].hi for n in self.inputs], dtype=float)
        self.unbounded = frozenset(n for n in self.system.free_inputs if n not in ranges)
        self._owner = {
            name: i
            for i, comp in enumerate(self.system.components)
            for name in comp.automaton.signal_names
        }
        self._flows: dict[tuple[str, ...], tuple[Array, Array, Array]] = {}

    # --- one expression ---------------------------------------------------------------

    def _signals(self, comp: int, location: str) -> dict[str, ir.Expr]:
        aut = self.system.components[comp].automaton
        merged = {**aut.signals, **aut.locations[location].signals}
        return {k: bind_parameters(v, aut.parameters) for k, v in merged.items()}

    def _read_signals(self, node: ir.Expr, comp: int, mode: tuple[str, ...]) -> dict[str, ir.Expr]:
        """The signals ``node`` of component ``comp`` may read: its own, as ``mode`` defines
        them, and those of other components it names (a system's condition), as their
        owners define them in ``mode``, with the ones those read in turn."""
        signals = self._signals(comp, mode[comp])
        pending = list(ir.names_in(node, ir.SIGNAL) - signals.keys())
        while pending:
            name = pending.pop()
            owner = self._owner.get(name)
            if owner is None or name in signals:
                continue
            if name in self.system.components[owner].automaton.vector_sizes:
                continue
            definition = self._signals(owner, mode[owner]).get(name)
            if definition is not None:
                signals[name] = definition
                pending.extend(ir.names_in(definition, ir.SIGNAL) - signals.keys())
        return signals

    def affine(
        self,
        node: ir.Expr,
        comp: int,
        mode: tuple[str, ...],
        position: Position,
        what: str,
        depth: int = 0,
    ) -> Affine:
        """The affine form of ``node`` (component ``comp`` in ``mode``), or a SpecError there."""
        aut = self.system.components[comp].automaton
        bound = bind_parameters(node, aut.parameters)
        lin = Linearizer(IntervalEvaluator({}, self._read_signals(bound, comp, mode)))
        form = lin.affine(bound)
        if any(k.startswith("#") for k in form.coeffs):
            raise SpecError(self._not_affine(bound, lin, what), position.shifted(_col(bound, lin)))
        return self._resolve(form, mode, position, what, depth)

    def _not_affine(self, node: ir.Expr, lin: Linearizer, what: str) -> str:
        culprit = _culprit(node, lin)
        text = f"'{_name_of(culprit)}'"
        chain = []
        for _ in range(8):  # signals defined by signals: follow them to the culprit
            if not (isinstance(culprit, ir.Var) and culprit.kind == ir.SIGNAL):
                break
            definition = lin.evaluator.signals.get(culprit.name)
            if definition is None:
                break
            chain.append(f"{culprit.name} = '{_name_of(definition)}'")
            culprit = _culprit(definition, lin)
        if chain:
            text += f" (signals: {'; '.join(chain)})"
        return (
            f"{what} is not affine in the state and inputs: {text}; "
            "reach handles x' = A x + B u + c, affine resets and linear conditions "
            "(nonlinear dynamics are not supported yet)"
        )

    def _resolve(
        self, form: Affine, mode: tuple[str, ...], position: Position, what: str, depth: int
    ) -> Affine:
        """Inputs another component provides replaced by their providers' forms."""
        out = Affine({}, form.const)
        for name, k in form.coeffs.items():
            if name in self.index or name == TIME:
                out = out + Affine({name: k}, 0.0)
                continue
            owner = self._owner.get(name)
            if owner is not None and depth < 32:
                aut = self.system.components[owner].automaton
                definition = self._signals(owner, mode[owner]).get(name)
                if definition is not None and name not in aut.vector_sizes:
                    sub = self.affine(definition, owner, mode, position, what, depth + 1)
                    out = out + sub.scaled(k)
                    continue
            if name in self.input_index or name in self.unbounded:
                out = out + Affine({name: k}, 0.0)
                continue
            raise SpecError(f"{what} reads '{name}', which reach cannot bound", position)
        return out

    # --- flows, resets, conditions ----------------------------------------------------

    def flow(self, mode: tuple[str, ...]) -> tuple[Array, Array, Array]:
        """``(A, B, c)`` of ``mode`` (a location per component), read once (read-only arrays)."""
        found = self._flows.get(mode)
        if found is None:
            found = self._flows[mode] = self._flow(mode)
            for array in found:
                array.flags.writeable = False
        return found

    def _flow(self, mode: tuple[str, ...]) -> tuple[Array, Array, Array]:
        n, m = len(self.variables), len(self.inputs)
        a, b, c = np.zeros((n, n)), np.zeros((n, m)), np.zeros(n)
        c[self.index[TIME]] = 1.0
        for i, comp in enumerate(self.system.components):
            loc = comp.automaton.locations[mode[i]]
            for var, node in loc.flow.items():
                where = loc.flow_positions.get(var, loc.position)
                what = f"the flow of {var} in location '{self.system.qualified(i, loc.name)}'"
                form = self.affine(node, i, mode, where, what)
                row = self.index[var]
                self._fill(form, a[row], b[row], where, what)
                c[row] = form.const
        return a, b, c

    def _fill(self, form: Affine, arow: Array, brow: Array, where: Position, what: str) -> None:
        for name, k in form.coeffs.items():
            if name in self.index:
                arow[self.index[name]] += k
            elif name in self.input_index:
                brow[self.input_index[name]] += k
            else:
                raise SpecError(
                    f"{what} reads the input '{name}', which has no range; "
                    "reach needs a range for every input a flow or reset reads "
                    "(inputs: {" + name + ": {range: [lo, hi]}})",
                    where,
                )

    def reset(
        self,
        comp: int,
        mode: tuple[str, ...],
        edge_reset: Mapping[str, ir.Expr],
        positions: Mapping[str, Position],
        default: Position,
        label: str,
    ) -> tuple[Array, Array, Array]:
        """``(R, S, r)``: ``x+ = R x + S u + r`` for one component's reset (identity elsewhere)."""
        n, m = len(self.variables), len(self.inputs)
        rmat, smat, rvec = np.eye(n), np.zeros((n, m)), np.zeros(n)
        for var, node in edge_reset.items():
            where = positions.get(var, default)
            what = f"the reset of {var} on edge '{label}'"
            form = self.affine(node, comp, mode, where, what)
            row = self.index[var]
            rmat[row] = 0.0
            self._fill(form, rmat[row], smat[row], where, what)
            rvec[row] = form.const
        return rmat, smat, rvec

    def condition(
        self,
        node: ir.Expr,
        comp: int,
        mode: tuple[str, ...],
        position: Position,
        what: str,
        *,
        for_all: bool = False,
    ) -> Condition:
        """A disjunction of conjunctions of rows; inputs as ``exists u`` (``for_all``: every u)."""
        cases = _dnf(node, negate=False)
        if cases is None:
            raise SpecError(f"{what} has more than {DNF_CAP} cases once split", position)
        result: list[Rows] = []
        for case in cases:
            rows: list[tuple[Array, float, bool]] = []
            false = False
            for cmp in case:
                if isinstance(cmp, ir.BoolConst):
                    false = false or not cmp.value
                    continue
                if not isinstance(cmp, ir.Cmp):
                    raise SpecError(
                        f"{what} is not a linear condition: '{_name_of(cmp)}'",
                        position.shifted(cmp.col),
                    )
                rows.extend(self._rows(cmp, comp, mode, position, what, for_all))
            if false:
                continue
            n = len(self.variables)
            mat = np.array([r for r, _, _ in rows], dtype=float).reshape(len(rows), n)
            vec = np.array([v for _, v, _ in rows], dtype=float)
            result.append(Rows(mat, vec, np.array([s for _, _, s in rows], dtype=bool)))
        return tuple(result)

    def _rows(
        self, cmp: ir.Cmp, comp: int, mode: ModeKey, position: Position, what: str, for_all: bool
    ) -> list[tuple[Array, float, bool]]:
        forms = [self.affine(o, comp, mode, position, what) for o in cmp.operands]
        out: list[tuple[Array, float, bool]] = []
        for i, op in enumerate(cmp.ops):
            left, right = forms[i], forms[i + 1]
            strict = op in ("<", ">")
            if op in ("<", "<="):
                rows = self._project(left - right, False, for_all)
            elif op in (">", ">="):
                rows = self._project(right - left, False, for_all)
            elif op == "==":
                rows = self._project(left - right, True, for_all)
            else:
                raise SpecError(f"{what}: '!=' is not a convex condition", position)
            out.extend((row, vec, strict) for row, vec in rows)
        return out

    def _project(self, form: Affine, equal: bool, for_all: bool) -> list[tuple[Array, float]]:
        """Rows for ``form <= 0`` (``== 0``) for some input value (``for_all``: for every one)."""
        row = np.zeros(len(self.variables))
        low, high = form.const, form.const
        for name, k in form.coeffs.items():
            if name in self.index:
                row[self.index[name]] += k
            elif name in self.input_index:
                j = self.input_index[name]
                ends = (k * self.u_lo[j], k * self.u_hi[j])
                low, high = low + min(ends), high + max(ends)
            else:  # an input with no range: some value satisfies the row, not every one
                low, high = -math.inf, math.inf
        low, high = (high, low) if for_all else (low, high)  # for_all: each row's worst value
        if not math.isfinite(low) or not math.isfinite(high):
            return [(np.zeros(len(self.variables)), -1.0)] if for_all else []
        rows = [(row, -low)]
        if equal:
            rows.append((-row, high))
        return rows


def _col(node: ir.Expr, lin: Linearizer) -> int:
    return _culprit(node, lin).col


def _culprit(node: ir.Expr, lin: Linearizer) -> ir.Expr:
    """The first sub-expression the linearizer had to stand in for with a bounded variable.

    A signal whose definition holds one counts as the culprit (its place is in
    ``node``; the message follows the definitions).
    """
    for sub in ir.walk(node):
        if _opaque(sub, lin) or _signal_hides(sub, lin, 0):
            return sub
    return node


def _opaque(node: ir.Expr, lin: Linearizer) -> bool:
    found = lin.aux.get(structural_key(node))
    return found is not None and not found[1].is_point


def _signal_hides(node: ir.Expr, lin: Linearizer, depth: int) -> bool:
    if depth > 8 or not (isinstance(node, ir.Var) and node.kind == ir.SIGNAL):
        return False
    definition = lin.evaluator.signals.get(node.name)
    if definition is None:
        return False
    return any(
        _opaque(sub, lin) or _signal_hides(sub, lin, depth + 1) for sub in ir.walk(definition)
    )


_NEGATE = {"<": ">=", "<=": ">", ">": "<=", ">=": "<"}


def _dnf(node: ir.Expr, *, negate: bool) -> list[list[ir.Expr]] | None:
    """Cases (each a list of comparisons or constants), ``None`` beyond :data:`DNF_CAP`."""
    if isinstance(node, ir.BoolConst):
        return [[ir.BoolConst(node.value != negate)]]
    if isinstance(node, ir.Not):
        return _dnf(node.operand, negate=not negate)
    if isinstance(node, ir.BoolOp):
        conj = (node.op == "and") != negate
        parts = [_dnf(v, negate=negate) for v in node.values]
        if any(p is None for p in parts):
            return None
        done = [p for p in parts if p is not None]
        if not conj:
            either = [case for p in done for case in p]
            return either if len(either) <= DNF_CAP else None
        product: list[list[ir.Expr]] = [[]]
        for p in done:
            product = [a + b for a in product for b in p]
            if len(product) > DNF_CAP:
                return None
        return product
    if isinstance(node, ir.Cmp):
        if not negate:
            if "!=" in node.ops:
                return _dnf(_split_ne(node), negate=False)
            return [[node]]
        links = [
            ir.Cmp((op,), (node.operands[i], node.operands[i + 1]), node.col)
            for i, op in enumerate(node.ops)
        ]
        cases: list[list[ir.Expr]] = []
        for link in links:
            op = link.ops[0]
            if op in _NEGATE:
                cases.append([ir.Cmp((_NEGATE[op],), link.operands, link.col)])
            elif op == "==":
                cases.append([ir.Cmp(("<",), link.operands, link.col)])
                cases.append([ir.Cmp((">",), link.operands, link.col)])
            else:
                cases.append([ir.Cmp(("==",), link.operands, link.col)])
        return cases if len(cases) <= DNF_CAP else None
    return [[node]]  # not a comparison: refused by Forms.condition


def _split_ne(node: ir.Cmp) -> ir.Expr:
    links: list[ir.Expr] = []
    for i, op in enumerate(node.ops):
        pair = (node.operands[i], node.operands[i + 1])
        if op == "!=":
            links.append(
                ir.BoolOp("or", (ir.Cmp(("<",), pair, node.col), ir.Cmp((">",), pair, node.col)))
            )
        else:
            links.append(ir.Cmp((op,), pair, node.col))
    return ir.BoolOp("and", tuple(links), node.col)
