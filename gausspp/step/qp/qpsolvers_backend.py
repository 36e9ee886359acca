"""The qpsolvers family: any QP solver installed in Python, by name.

qpsolvers sets a solver up anew on every call, so this family pays the set-up each step
(tens of microseconds); it is here for reach (every solver qpsolvers knows), not for speed. It solves
both forms (:mod:`.base`): the equality form of the step and the general form of the stages,
through ``qpsolvers.solve_problem``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import warnings
from typing import Any

import numpy as np
import qpsolvers
import qpsolvers.solvers
import scipy.sparse as sp

from ...errors import QPSolveError
from .base import ALL_FORMS, QP, QPAnswer, QPBackend
from .casadi_conic import stdout_silenced

#: Options that make each solver accurate enough to agree with the direct solve.
OPTIONS: dict[str, dict[str, Any]] = {
    "osqp": {"eps_abs": 1e-12, "eps_rel": 1e-12, "polishing": True, "max_iter": 20000, "raise_error": False},
    "proxqp": {"eps_abs": 1e-12, "eps_rel": 0.0},
    "clarabel": {"tol_gap_abs": 1e-12, "tol_gap_rel": 1e-12, "tol_feas": 1e-12},
    "piqp": {"eps_abs": 1e-12, "eps_rel": 1e-12},
    "daqp": {"primal_tol": 1e-12, "dual_tol": 1e-12},
}
#: Solvers that print to the C-level stdout (silenced around their calls; that costs tens of microseconds).
CHATTY = ("osqp", "qpoases", "highs")
#: A point the solver itself calls inaccurate is accepted only if it is optimal to this (the problems are unit-sized).
INACCURATE_KKT_TOL = 1e-10


def available() -> list[str]:
    """qpsolvers' solvers installed on this machine."""
    return sorted(qpsolvers.available_solvers)


def known() -> list[str]:
    """Every solver qpsolvers has an interface for, installed or not (``<name>_solve_problem``)."""
    suffix = "_solve_problem"
    return sorted(n[: -len(suffix)] for n in dir(qpsolvers.solvers) if n.endswith(suffix))


class QpsolversBackend(QPBackend):
    """One qpsolvers solver, called from Python each step."""

    compiled = False
    forms = ALL_FORMS

    def __init__(self, solver: str) -> None:
        self.solver = solver
        self.name = f"qpsolvers:{solver}"
        self.sparse = solver not in qpsolvers.dense_solvers
        self.description = f"qpsolvers → {solver} ({'sparse' if self.sparse else 'dense'} input)"

    def _matrix(self, M: np.ndarray) -> Any:
        return sp.csc_matrix(M) if self.sparse else M

    def solve(self, H: np.ndarray, S: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        problem = qpsolvers.Problem(self._matrix(H), np.zeros(H.shape[0]), A=self._matrix(S), b=rhs)
        try:
            sol = qpsolvers.solve_problem(problem, solver=self.solver, **OPTIONS.get(self.solver, {}))
        except Exception as exc:  # the backend's own error, re-raised as ours (no abstraction leak)
            raise QPSolveError(
                f"{self.name} failed on the step QP: {exc}; check the realizability margin, or try another backend"
            ) from exc
        if not sol.found or sol.x is None or not np.all(np.isfinite(sol.x)):
            raise QPSolveError(f"{self.name} found no solution of the step QP; try another backend or solver='direct'")
        y = sol.y if sol.y is not None else np.full(S.shape[0], np.nan)
        return np.asarray(sol.x, float), np.asarray(y, float)

    def solve_qp(self, problem: QP) -> QPAnswer:
        """The general form by ``qpsolvers.solve_problem`` (the solver's own exceptions pass through).

        A point the solver calls inaccurate (OSQP's "solved inaccurate" at its iteration limit) counts
        only if it satisfies the optimality conditions of the unit-sized problem to
        :data:`INACCURATE_KKT_TOL` (primal and dual residuals, duality gap).
        """
        p, mat = problem, self._matrix
        qp = qpsolvers.Problem(
            mat(p.P),
            p.q,
            G=mat(p.G) if p.G.size else None,
            h=p.h if p.G.size else None,
            A=mat(p.E) if p.E.size else None,
            b=p.e if p.E.size else None,
            lb=p.lo if np.any(np.isfinite(p.lo)) else None,
            ub=p.hi if np.any(np.isfinite(p.hi)) else None,
        )
        with warnings.catch_warnings(), stdout_silenced() if self.solver in CHATTY else contextlib.nullcontext():
            warnings.simplefilter("ignore")  # the solvers' own status warnings: judged by the caller
            sol = qpsolvers.solve_problem(qp, solver=self.solver, **OPTIONS.get(self.solver, {}))
        if sol.found:
            return QPAnswer(sol.x, float(sol.dual_residual()))
        if sol.x is not None and _optimal_anyway(sol):
            return QPAnswer(sol.x, found=False)
        return QPAnswer(None, found=False)


def _optimal_anyway(sol: qpsolvers.Solution) -> bool:
    """A point not marked found that satisfies the KKT conditions (qpsolvers' residuals are inf for a
    point not marked found: judge the point itself)."""
    try:
        return bool(dataclasses.replace(sol, found=True).is_optimal(INACCURATE_KKT_TOL))
    except (TypeError, ValueError):  # no multipliers to judge with
        return False
