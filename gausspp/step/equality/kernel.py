"""Compiled per-step evaluators: one casadi call per step through ``Function.buffer()`` (:mod:`.bound`).

Two kinds, one interface (``kernel(*inputs) -> {name: array}``, or ``kernel.evaluate()``
on inputs written into ``kernel.inputs`` in place):

* :class:`CompiledKernel` — the direct solve, or a QP posed with a casadi ``conic`` plugin,
  is inside the graph: one call per step;
* :class:`PythonQPKernel` — the QP is solved from Python (the qpsolvers family): one call builds
  the QP, the backend solves it, a second call finishes the step.

:func:`build_kernel` makes either from a step's expressions, by the dense route (whitened reaction space,
:mod:`.expressions`) or the sparse one (the mechanism's sparsity, :mod:`.sparse`).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..bound import Bound, dense_outputs, load_inputs, only_outputs
from ..qp import QPBackend
from ..qp.casadi_conic import stdout_silenced
from . import sparse
from .direct import direct_reaction, require_square
from .expressions import OUTPUTS, StepExpressions, outputs, reduce, well_conditioned_constant
from .qp_parts import QPParts, guarded, qp_parts

__all__ = ["Bound", "CompiledKernel", "Kernel", "PythonQPKernel", "build_kernel", "dense_outputs", "load_inputs"]
__all__ += ["only_outputs"]


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


def build_kernel(
    name: str,
    inputs: list[ca.SX],
    p: StepExpressions,
    solver: str,
    backend: QPBackend | None,
    refine: bool = True,
    route: str = "dense",
) -> Kernel:
    """Compile the step ``p`` (expressions of ``inputs``) for ``solver`` ∈ {"direct", "qp"} by ``route`` ∈
    {"dense", "sparse"} (:func:`gausspp.step.equality.sparse.choose_route` picks one)."""
    if solver == "direct":
        if route == "sparse":
            sred = sparse.sparse_reduce(p)
            require_square(*sred.S.shape)
            refines = refine and not well_conditioned_constant(p.A)  # as the dense route's outputs decide
            results = sparse.sparse_outputs(p, sred, sred.solve_S(sred.rhs), None, refines)
        else:
            red = reduce(p)
            results = outputs(p, red, direct_reaction(red), None, refine)
        return CompiledKernel(ca.Function(f"{name}_direct", inputs, dense_outputs(results)))
    assert backend is not None
    parts = qp_parts(name, inputs, p, backend, refine, route, dense_data=not backend.compiled)
    if not backend.compiled:
        return PythonQPKernel(parts)
    mx_in = [ca.MX.sym(f"in{i}", s.sparsity()) for i, s in enumerate(inputs)]
    safe = guarded(parts)
    kernel = CompiledKernel(ca.Function(f"{name}_qp", mx_in, safe.graph(mx_in)), safe)
    with stdout_silenced():  # some plugins (qpOASES) print a banner on their first solve
        try:
            kernel.evaluate()
        except RuntimeError:
            pass  # zeros need not be a valid state; this call only primes the plugin
    return kernel
