"""Compiled per-step evaluators: one casadi call per step through ``Function.buffer()``.

A plain casadi call from Python costs ≈15–25 µs of argument handling; a buffer-bound call
costs ≈0.15 µs. A kernel binds numpy arrays to a compiled function's inputs and outputs once,
so a step is: copy the inputs in, one C call, read the outputs.

Two kinds, one interface (``kernel(*inputs) -> {name: array}``, or ``kernel.evaluate()``
on inputs written into ``kernel.inputs`` in place):

* :class:`CompiledKernel` — the direct solve, or a QP posed with a casadi ``conic`` plugin,
  is inside the graph: one call per step;
* :class:`PythonQPKernel` — the QP is solved from Python (qpsolvers route): one call builds
  the QP, the backend solves it, a second call finishes the step.

:func:`build_kernel` makes either from a step's expressions.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import casadi as ca
import numpy as np

from .direct import direct_reaction
from .expressions import OUTPUTS, StepExpressions, outputs, reduce, well_conditioned_constant
from .qp import QPBackend
from .qp.casadi_conic import stdout_silenced

T = TypeVar("T")


class Bound:
    """A casadi Function with numpy arrays bound to every input and output."""

    def __init__(self, fn: ca.Function) -> None:
        self.fn = fn
        self.args = [np.zeros(fn.nnz_in(i)) for i in range(fn.n_in())]
        self.res = [np.zeros(fn.nnz_out(i)) for i in range(fn.n_out())]
        self._buf, self.eval = fn.buffer()
        for i, arr in enumerate(self.args):
            self._buf.set_arg(i, memoryview(arr))  # type: ignore[call-arg, arg-type]  # casadi's stubs
        for i, arr in enumerate(self.res):
            self._buf.set_res(i, memoryview(arr))  # type: ignore[call-arg, arg-type]
        #: each output's (rows, cols)
        self.shapes = [fn.size_out(i) for i in range(fn.n_out())]
        # matrix-shaped views of the dense output buffers, made once (casadi stores column-major);
        # a sparse output stays its nonzeros
        self.outputs = [
            r.reshape(fn.size_out(i), order="F") if fn.size_out(i)[1] > 1 and fn.sparsity_out(i).is_dense() else r
            for i, r in enumerate(self.res)
        ]

    def output(self, i: int) -> np.ndarray:
        """Output ``i`` in its matrix shape (a view into the bound buffer)."""
        return self.outputs[i]


def load_inputs(targets: Sequence[np.ndarray], values: Sequence[Any]) -> None:
    for target, value in zip(targets, values, strict=True):
        target[:] = np.ravel(value, order="F")


class CompiledKernel:
    """A whole step in one compiled function."""

    compiled = True

    def __init__(self, fn: ca.Function, qp_parts: QPParts | None = None) -> None:
        self._f = Bound(fn)
        self.inputs = self._f.args
        #: for a QP posed in the graph: its :class:`QPParts`, to compose larger graphs
        self.qp_parts = qp_parts

    @property
    def function(self) -> ca.Function:
        """The compiled step as a casadi Function ``inputs -> OUTPUTS`` (to build larger graphs)."""
        return self._f.fn

    def evaluate(self) -> None:
        """Re-evaluate on the values now in ``inputs`` (the hot path)."""
        self._f.eval()

    def result(self) -> dict[str, np.ndarray]:
        """The last evaluation's outputs, by name (views into the bound buffers)."""
        return dict(zip(OUTPUTS, self._f.outputs, strict=True))

    def __call__(self, *values: Any) -> dict[str, np.ndarray]:
        load_inputs(self.inputs, values)
        self._f.eval()
        return self.result()


class PythonQPKernel:
    """Build the QP in one call, solve it from Python, finish the step in a second call."""

    compiled = False

    def __init__(self, parts: QPParts) -> None:
        self._build = Bound(parts.build)
        self._finish = Bound(parts.finish)
        self.backend = parts.backend
        self.inputs = self._build.args

    def evaluate(self) -> None:
        """Re-evaluate on the values now in ``inputs``."""
        b = self._build
        b.eval()
        H, S, rhs = b.output(0), b.output(1), b.output(2)
        if np.isfinite(S.sum() + rhs.sum()):
            u, y = self.backend.solve(H, S, rhs)
        else:  # a singular or non-finite step: no QP to pose; the checks diagnose the NaN that follows
            u, y = np.full(H.shape[0], np.nan), np.full(S.shape[0], np.nan)
        load_inputs(self._finish.args, [*b.res[3:], u, y])  # the carried numbers as stored (nonzeros)
        self._finish.eval()

    def result(self) -> dict[str, np.ndarray]:
        """The last evaluation's outputs, by name."""
        return dict(zip(OUTPUTS, self._finish.outputs, strict=True))

    def __call__(self, *values: Any) -> dict[str, np.ndarray]:
        load_inputs(self.inputs, values)
        self.evaluate()
        return self.result()


Kernel = CompiledKernel | PythonQPKernel


def dense_outputs(exprs: list[ca.SX]) -> list[ca.SX]:
    """Outputs with every entry stored: buffers are sized by stored entries, and a structural
    zero (say, a residual casadi proves to vanish) must still come out as a number."""
    return ca.cse([ca.densify(e) for e in exprs])  # and each common subexpression computed once


def _guard(build: ca.Function) -> ca.Function:
    """QP data with NaN/inf replaced by zeros: a plugin must never see them (casadi aborts the whole
    call). The step's own outputs still carry the NaN, which the checks then diagnose."""
    args = build.sx_in()
    H, S, rhs, *carried = build.call(args)
    total = ca.sum1(ca.vec(S)) + ca.sum1(rhs)
    finite = ca.fabs(total) < ca.inf  # false for NaN and ±inf
    guarded = [H, ca.if_else(finite, S, ca.SX.zeros(S.shape)), ca.if_else(finite, rhs, 0 * rhs)]
    return ca.Function(f"{build.name()}_guarded", args, [*guarded, *carried])


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


def only_outputs(fn: ca.Function, outputs: Sequence[int]) -> ca.Function:
    """An SX function computing only the chosen outputs of ``fn`` (the rest is dropped from the graph)."""
    args = fn.sx_in()
    res = fn.call(args)
    return ca.Function(f"{fn.name()}_part", args, [res[i] for i in outputs])


def p_nnz(obj: object) -> int:
    """How many nonzeros the SX fields of a dataclass hold."""
    values = (getattr(obj, f.name) for f in dataclasses.fields(obj))  # type: ignore[arg-type]
    return int(np.sum([v.nnz() for v in values if isinstance(v, ca.SX)]))


def qp_parts(name: str, inputs: list[ca.SX], p: StepExpressions, backend: QPBackend, refine: bool) -> QPParts:
    """The QP route's :class:`QPParts` for the step ``p`` (expressions of ``inputs``)."""
    red = reduce(p)
    k, m = red.S_hat.shape
    z, y = ca.SX.sym("z", m), ca.SX.sym("y", k)
    # Rows scaled to unit length: a small margin makes Ŝ small, which QP codes take for a
    # degenerate row; the scaled constraint is the same set, and y is scaled back for the checks.
    norms = ca.sqrt(ca.sum2(red.S_hat * red.S_hat))
    rows = ca.if_else(norms > 0, 1 / norms, 1)
    scaled = ca.diag(rows) @ red.S_hat
    size = p_nnz(p) + p_nnz(red) + k
    packed = ca.SX.sym("carried", size)
    p_in, p_values, at = _stand_in(p, packed, 0)
    red_in, red_values, at = _stand_in(red, packed, at)
    rows_in = packed[at:]
    carried = ca.vertcat(*p_values, *red_values, rows)
    qp_data = [ca.densify(e) for e in (ca.SX.eye(m), scaled, rows * red.rhs_hat)]
    build = ca.Function(f"{name}_qp_data", inputs, ca.cse([*qp_data, carried]))
    refines = refine and not well_conditioned_constant(p.A)  # decided on the data, not on their stand-ins
    results = outputs(p_in, red_in, z, rows_in * y, refines)
    finish = ca.Function(f"{name}_qp_finish", [packed, z, y], dense_outputs(results))
    return QPParts(build, finish, backend)


def build_kernel(
    name: str, inputs: list[ca.SX], p: StepExpressions, solver: str, backend: QPBackend | None, refine: bool = True
) -> Kernel:
    """Compile the step ``p`` (expressions of ``inputs``) for ``solver`` ∈ {"direct", "qp"}."""
    if solver == "direct":
        red = reduce(p)
        return CompiledKernel(
            ca.Function(f"{name}_direct", inputs, dense_outputs(outputs(p, red, direct_reaction(red), None, refine)))
        )
    assert backend is not None
    parts = qp_parts(name, inputs, p, backend, refine)
    if not backend.compiled:
        return PythonQPKernel(parts)
    mx_in = [ca.MX.sym(f"in{i}", s.sparsity()) for i, s in enumerate(inputs)]
    guarded = QPParts(_guard(parts.build), parts.finish, backend)
    kernel = CompiledKernel(ca.Function(f"{name}_qp", mx_in, guarded.graph(mx_in)), guarded)
    with stdout_silenced():  # some plugins (qpOASES) print a banner on their first solve
        try:
            kernel.evaluate()
        except RuntimeError:
            pass  # zeros need not be a valid state; this call only primes the plugin
    return kernel
