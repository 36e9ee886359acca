"""Compiled casadi functions called from Python at C speed: numpy arrays bound to their inputs and outputs.

A plain casadi call from Python costs tens of microseconds of argument handling; a buffer-bound call
(``Function.buffer()``) costs well under one. :class:`Bound` binds numpy arrays to a function's inputs
and outputs once, so a call is: copy the inputs in, one C call, read the outputs. And the helpers that
shape the functions bound here: :func:`dense_outputs`, :func:`only_outputs`, :func:`sparse_output`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np


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


def dense_outputs(exprs: list[ca.SX]) -> list[ca.SX]:
    """Outputs with every entry stored: buffers are sized by stored entries, and a structural
    zero (say, a residual casadi proves to vanish) must still come out as a number."""
    return ca.cse([ca.densify(e) for e in exprs])  # and each common subexpression computed once


def only_outputs(fn: ca.Function, outputs: Sequence[int]) -> ca.Function:
    """An SX function computing only the chosen outputs of ``fn`` (the rest is dropped from the graph)."""
    args = fn.sx_in()
    res = fn.call(args)
    return ca.Function(f"{fn.name()}_part", args, [res[i] for i in outputs])


def sparse_output(fn: ca.Function, index: int) -> ca.Function:
    """``fn`` (an SX function) with output ``index`` stored by its nonzeros only: the entries that are the
    constant zero in every evaluation (those :func:`dense_outputs` stored anyway) are dropped. For a large
    banded matrix (a chain's normalized ``S``: 1 528 nonzeros of 65 536 at 128 links) the function does and
    writes a fraction of the work. Any other function is returned as it is."""
    if not fn.is_a("SXFunction"):
        return fn
    args = fn.sx_in()
    res = fn.call(args)
    res[index] = ca.sparsify(res[index])
    return ca.Function(f"{fn.name()}_sparse{index}", args, res)
