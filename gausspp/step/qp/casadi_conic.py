"""The compiled family: casadi's ``conic`` plugins, posed inside the model's casadi graph.

A step that uses one of these backends is a single C call (through ``Function.buffer()``),
the QP included. Each plugin's options below ask for the accuracy the cross-check against
the direct solution needs. The same plugins solve the general form (bounds, inequalities, a
linear term) from Python, through casadi's ``conic`` inputs ``lba ≤ a x ≤ uba``, ``lbx ≤ x ≤ ubx``
(measured: every plugin listed solves it; ``daqp`` refuses a semidefinite Hessian, which the
stages then report).
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import sys
from collections.abc import Iterator
from typing import Any

import casadi as ca
import numpy as np

from ...errors import QPSolveError
from .base import ALL_FORMS, QP, QPAnswer, QPBackend

_QUIET = {"print_iter": False, "print_header": False, "print_info": False}

#: Plugin → (options, one-line description). Tolerances are set for agreement with the direct solve.
#: Left out: ``ipqp`` (its LDL factorization breaks down on the pendulum's two-row step and returns
#: NaN), ``hpipm`` (rejects a dense Hessian), and the commercial plugins (cplex, gurobi, mosek, ...).
PLUGINS: dict[str, tuple[dict[str, Any], str]] = {
    "qrqp": (dict(_QUIET), "casadi's own active-set QP (sparse QR); round-off accurate, fastest measured"),
    "daqp": ({}, "dual active-set (DAQP); round-off accurate"),
    "qpoases": ({"printLevel": "none", "sparse": False}, "online active-set (qpOASES)"),
    "osqp": (
        {"osqp": {"verbose": False, "eps_abs": 1e-12, "eps_rel": 1e-12, "polishing": True, "max_iter": 20000}},
        "operator splitting (OSQP) with polishing",
    ),
    "proxqp": ({"proxqp": {"eps_abs": 1e-12, "eps_rel": 0.0}}, "proximal augmented Lagrangian (ProxQP)"),
    "piqp": ({"piqp": {"eps_abs": 1e-12, "eps_rel": 1e-12}}, "proximal interior point (PIQP)"),
    "highs": ({"highs": {"output_flag": False}}, "HiGHS (LP/QP); slow and ~1e-8 accurate here"),
}


@contextlib.contextmanager
def stdout_silenced() -> Iterator[None]:
    """Some plugins (qpOASES) print a banner from C at set-up; keep the user's terminal clean."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        yield
        return
    sys.stdout.flush()
    saved = os.dup(fd)
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), fd)
        try:
            yield
        finally:
            _flush_c_stdout()  # C's stdio buffers what the plugin printed: flush it into /dev/null
            os.dup2(saved, fd)
            os.close(saved)


def _flush_c_stdout() -> None:
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # no C library to reach: nothing buffered there to worry about
        pass


@functools.cache
def plugin_available(plugin: str) -> bool:
    """True if casadi on this machine can load ``plugin`` (checked once)."""
    try:
        with stdout_silenced():
            ca.conic("probe", plugin, {"h": ca.Sparsity.dense(1, 1), "a": ca.Sparsity.dense(1, 1)}, PLUGINS[plugin][0])
    except RuntimeError:
        return False
    return True


class CasadiConic(QPBackend):
    """A casadi ``conic`` plugin; the QP becomes a node of the model's graph."""

    compiled = True
    forms = ALL_FORMS

    def __init__(self, plugin: str, options: dict[str, Any] | None = None, name: str | None = None) -> None:
        """``options`` replace the plugin's defaults of :data:`PLUGINS` (give ``name`` to tell them apart)."""
        self.plugin = plugin
        self.name = name or f"casadi:{plugin}"
        self.options = {"error_on_fail": False, **(PLUGINS[plugin][0] if options is None else options)}
        self.description = PLUGINS[plugin][1]
        self._sparse: dict[tuple[Any, ...], ca.Function] = {}  # conics posed with sparse patterns, by pattern

    @functools.cache  # noqa: B019 - backends are few, long-lived singletons
    def _conic(self, m: int, k: int) -> ca.Function:
        with stdout_silenced():
            return ca.conic(
                f"gauss_qp_{self.plugin}",
                self.plugin,
                {"h": ca.Sparsity.dense(m, m), "a": ca.Sparsity.dense(k, m)},
                self.options,
            )

    def graph(self, H: ca.MX, S: ca.MX, rhs: ca.MX) -> tuple[ca.MX, ca.MX]:
        """The QP ``min ½ xᵀHx`` s.t. ``S x = rhs`` as a node of an MX graph, posed with the sparsity ``H`` and
        ``S`` have there (a sparse step's QP stays sparse for the plugin)."""
        m, k = H.shape[0], S.shape[0]
        if H.sparsity().is_dense() and S.sparsity().is_dense():
            conic = self._conic(m, k)
        else:
            conic = self._sparse_conic(H.sparsity(), S.sparsity())
        sol = conic(h=H, g=ca.MX.zeros(m), a=S, lba=rhs, uba=rhs)
        return sol["x"], sol["lam_a"]

    def _sparse_conic(self, h: ca.Sparsity, a: ca.Sparsity) -> ca.Function:
        key = tuple((sp.size(), *map(tuple, sp.get_triplet())) for sp in (h, a))  # the two patterns
        if key not in self._sparse:
            with stdout_silenced():
                name = f"gauss_qp_{self.plugin}_sparse"
                self._sparse[key] = ca.conic(name, self.plugin, {"h": h, "a": a}, self.options)
        return self._sparse[key]

    def solve(self, H: np.ndarray, S: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m, k = H.shape[0], S.shape[0]
        solver = self._conic(m, k)
        with stdout_silenced():
            sol = solver(h=H, g=np.zeros(m), a=S, lba=rhs, uba=rhs)
        u = np.array(sol["x"]).ravel()
        if not solver.stats().get("success", True) or not np.all(np.isfinite(u)):
            raise QPSolveError(
                f"{self.name} did not solve the step QP (status {solver.stats().get('return_status')!r}); "
                "try another backend or solver='direct'"
            )
        return u, np.array(sol["lam_a"]).ravel()

    def solve_qp(self, problem: QP) -> QPAnswer:
        """The general form: ``E`` and ``G`` stacked as ``a`` with ``lba = [e; −∞]``, ``uba = [e; h]``.

        casadi's multipliers follow ``P x + q + aᵀ λ_a + λ_x = 0``, from which the dual residual is computed.
        """
        p = problem
        m = p.q.size
        a = np.vstack([p.E.reshape(-1, m), p.G.reshape(-1, m)])
        lba = np.concatenate([p.e, np.full(p.h.size, -np.inf)])
        uba = np.concatenate([p.e, p.h])
        solver = self._conic(m, a.shape[0])
        with stdout_silenced():
            sol = solver(h=p.P, g=p.q, a=a, lba=lba, uba=uba, lbx=p.lo, ubx=p.hi)
        x = np.array(sol["x"]).ravel()
        if not solver.stats().get("success", True) or not np.all(np.isfinite(x)):
            return QPAnswer(None, found=False)
        lam_a, lam_x = np.array(sol["lam_a"]).ravel(), np.array(sol["lam_x"]).ravel()
        dual = float(np.max(np.abs(p.P @ x + p.q + a.T @ lam_a + lam_x), initial=0.0))
        return QPAnswer(x, dual)
