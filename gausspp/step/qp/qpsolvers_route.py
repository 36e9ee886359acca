"""The qpsolvers route: any QP solver installed in Python, by name.

qpsolvers sets a solver up anew on every call, so this route pays the set-up each step
(tens of µs); it is here for reach (every solver qpsolvers knows), not for speed.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import qpsolvers
import scipy.sparse as sp

from ...errors import QPSolveError
from .base import QPBackend

#: Options that make each solver accurate enough to agree with the direct solve.
OPTIONS: dict[str, dict[str, Any]] = {
    "osqp": {"eps_abs": 1e-12, "eps_rel": 1e-12, "polishing": True, "max_iter": 20000, "raise_error": False},
    "proxqp": {"eps_abs": 1e-12, "eps_rel": 0.0},
    "clarabel": {"tol_gap_abs": 1e-12, "tol_gap_rel": 1e-12, "tol_feas": 1e-12},
    "piqp": {"eps_abs": 1e-12, "eps_rel": 1e-12},
    "daqp": {"primal_tol": 1e-12, "dual_tol": 1e-12},
}


def available() -> list[str]:
    """qpsolvers' solvers installed on this machine."""
    return sorted(qpsolvers.available_solvers)


class QpsolversBackend(QPBackend):
    """One qpsolvers solver, called from Python each step."""

    compiled = False

    def __init__(self, solver: str) -> None:
        self.solver = solver
        self.name = f"qpsolvers:{solver}"
        self.sparse = solver not in qpsolvers.dense_solvers
        self.description = f"qpsolvers → {solver} ({'sparse' if self.sparse else 'dense'} input)"

    def solve(self, H: np.ndarray, S: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        P, A = (sp.csc_matrix(H), sp.csc_matrix(S)) if self.sparse else (H, S)
        problem = qpsolvers.Problem(P, np.zeros(H.shape[0]), A=A, b=rhs)
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
