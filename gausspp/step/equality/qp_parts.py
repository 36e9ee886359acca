"""A step whose QP is solved between two compiled functions (:class:`QPParts`), by either route.

``build`` poses the QP from the step's inputs and carries on the numbers the outputs need; the QP is
solved — a casadi ``conic`` node inside one graph, or a qpsolvers backend from Python — and ``finish``
forms the step's outputs from its solution without computing the reduction a second time. The dense
route poses it in whitened reaction space (``min ½‖z‖²`` s.t. ``Ŝ z = r̂``, :mod:`gausspp.step.equality.expressions`),
the sparse route in the reaction unknowns with sparse matrices (``min ½ uᵀ H u`` s.t. ``S u = r``,
:mod:`gausspp.step.equality.sparse`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypeVar

import casadi as ca
import numpy as np

from ..bound import dense_outputs, only_outputs
from ..qp import QPBackend
from . import sparse
from .expressions import StepExpressions, outputs, reduce, well_conditioned_constant

T = TypeVar("T")


def guarded(parts: QPParts) -> QPParts:
    """``parts`` whose QP data have NaN/inf replaced by zeros: a plugin must never see them (casadi aborts the
    whole call). The step's own outputs still carry the NaN, which the checks then diagnose."""
    build = parts.build
    args = build.sx_in()
    H, S, rhs, *carried = build.call(args)
    total = ca.sum1(ca.vec(S)) + ca.sum1(rhs)
    finite = ca.fabs(total) < ca.inf  # false for NaN and ±inf
    safe = [H, ca.if_else(finite, S, ca.SX(S.sparsity(), 0)), ca.if_else(finite, rhs, 0 * rhs)]
    fn = ca.Function(f"{build.name()}_guarded", args, [*safe, *carried])
    return QPParts(fn, parts.finish, parts.backend)


def _stand_in(obj: T, packed: ca.SX, at: int) -> tuple[T, list[ca.SX], int]:
    """``obj`` (a dataclass of SX expressions) with each expression replaced by the entries of the symbol
    ``packed`` from ``at`` on, in its sparsity; the expressions' nonzeros; where the next entry is. To evaluate
    a graph in two functions without computing twice."""
    values, fields = [], {}
    for f in dataclasses.fields(obj):  # type: ignore[arg-type]
        value = getattr(obj, f.name)
        if isinstance(value, ca.SX):
            nnz = value.nnz()
            fields[f.name] = ca.SX(value.sparsity(), packed[at : at + nnz])
            values.append(ca.vec(value.nz[:]))
            at += nnz
    return dataclasses.replace(obj, **fields), values, at  # type: ignore[type-var]


@dataclass(frozen=True)
class QPParts:
    """A step whose QP is solved between two functions.

    ``build(inputs) -> [H, Ŝ (rows scaled), r̂ (scaled), *carried]`` poses the QP and carries on the
    numbers the step's outputs need (the problem's data, its reduction, the row scales);
    ``finish(*carried, z, y) -> OUTPUTS`` forms the outputs from the QP's solution ``z`` and
    multipliers ``y`` without computing the reduction a second time.
    """

    build: ca.Function
    finish: ca.Function
    backend: QPBackend

    def graph(self, args: Sequence[ca.MX], only: Sequence[int] | None = None) -> list[ca.MX]:
        """The step's outputs (or those at positions ``only``) as MX, the QP a node of the graph."""
        return self.graph_and_solution(args, only)[0]

    def graph_and_solution(self, args: Sequence[ca.MX], only: Sequence[int] | None = None) -> tuple[list[ca.MX], ca.MX]:
        """:meth:`graph`, and the QP's solution ``(z, y)`` stacked (to replay the step, :meth:`replay`)."""
        H, S, rhs, *carried = self.build(*args)
        z, y = self.backend.graph(H, S, rhs)
        finish = self.finish if only is None else only_outputs(self.finish, only)
        return list(finish(*carried, z, y)), ca.vertcat(z, y)

    def replay(self) -> ca.Function:
        """``(inputs, (z, y)) -> OUTPUTS``: the step's outputs from a known QP solution, no QP solved (an SX
        function: the build and the finish only). Given the solution the QP returned for the same inputs, the
        outputs are those of the step itself."""
        args = self.build.sx_in()
        _, S, rhs, *carried = self.build.call(args)
        solution = ca.SX.sym("solution", S.shape[1] + S.shape[0])
        z, y = solution[: S.shape[1]], solution[S.shape[1] :]
        return ca.Function("replay", [*args, solution], self.finish.call([*carried, z, y]))


def p_nnz(obj: object) -> int:
    """How many nonzeros the SX fields of a dataclass hold."""
    values = (getattr(obj, f.name) for f in dataclasses.fields(obj))  # type: ignore[arg-type]
    return int(np.sum([v.nnz() for v in values if isinstance(v, ca.SX)]))


def qp_parts(
    name: str,
    inputs: list[ca.SX],
    p: StepExpressions,
    backend: QPBackend,
    refine: bool,
    route: str = "dense",
    dense_data: bool = False,
) -> QPParts:
    """The QP solver's :class:`QPParts` for the step ``p`` (expressions of ``inputs``) by ``route``;
    ``dense_data``: the QP's matrices with every entry stored (for a backend reading numpy arrays)."""
    if route == "sparse":
        sred = sparse.sparse_reduce(p)
        rows = sparse.row_scales(sred)
        H, S, rhs = sparse.qp_matrices(sred, p, rows)
        red: object = sred
    else:
        dred = reduce(p)
        # Rows scaled to unit length: a small margin makes Ŝ small, which QP codes take for a
        # degenerate row; the scaled constraint is the same set, and y is scaled back for the checks.
        norms = ca.sqrt(ca.sum2(dred.S_hat * dred.S_hat))
        rows = ca.if_else(norms > 0, 1 / norms, 1)
        H, S, rhs = ca.SX.eye(dred.S_hat.shape[1]), ca.diag(rows) @ dred.S_hat, rows * dred.rhs_hat
        red = dred
    k, m = S.shape
    x, y = ca.SX.sym("x", m), ca.SX.sym("y", k)
    packed = ca.SX.sym("carried", p_nnz(p) + p_nnz(red) + k)
    p_in, p_values, at = _stand_in(p, packed, 0)
    red_in, red_values, at = _stand_in(red, packed, at)
    rows_in = packed[at:]
    carried = ca.vertcat(*p_values, *red_values, rows)
    data = [ca.densify(e) for e in (H, S, rhs)] if route == "dense" or dense_data else [H, S, ca.densify(rhs)]
    build = ca.Function(f"{name}_qp_data", inputs, ca.cse([*data, carried]))
    refines = refine and not well_conditioned_constant(p.A)  # decided on the data, not on their stand-ins
    if route == "sparse":
        results = sparse.sparse_outputs(p_in, red_in, x, y, refines, rows_in)  # type: ignore[arg-type]
    else:
        results = outputs(p_in, red_in, x, rows_in * y, refines)  # type: ignore[arg-type]
    finish = ca.Function(f"{name}_qp_finish", [packed, x, y], dense_outputs(results))
    return QPParts(build, finish, backend)
