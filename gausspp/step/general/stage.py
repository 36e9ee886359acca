"""One stage of the general Gauss QP: the backend call, and the checks every answer passes.

A stage is a :class:`~gausspp.step.qp.QP` (``min ½xᵀPx + qᵀx`` s.t. ``E x = e``, ``G x ≤ h``,
``lo ≤ x ≤ hi``, posed at unit size by :mod:`gausspp.step.general`). Whatever the backend, its
point is accepted only if it is

* **feasible**: ``max(|E x − e|, (G x − h)₊) / ((1 + max|x|)(1 + max|M|))`` and the bound violations
  ``/ (1 + max|x|)`` at most :data:`FEASIBILITY_TOL`;
* **optimal**: where the backend reports multipliers, the dual residual
  ``max |P x + q + Eᵀy + Gᵀz + z_box|`` at most :data:`DUAL_TOL` ``· (1 + max|P x| + max|q|)``.
"""

from __future__ import annotations

import numpy as np

from ...errors import QPSolveError
from ..qp import QP, QPAnswer, QPBackend, short_name

#: Relative violation of a stage's constraints above which the backend is deemed to have failed.
FEASIBILITY_TOL = 1e-7
#: Relative dual residual (stationarity) of a stage's answer above which it is deemed not optimal.
DUAL_TOL = 1e-7

_EXACT_HINT = "try another backend (daqp is exact, osqp iterative)"


def _trivial(st: QP) -> np.ndarray | None:
    """The answer without a backend: no unknowns, or ``x = 0`` for an unconstrained zero-gradient stage."""
    m = st.q.size
    if m == 0:  # nothing to choose
        return np.zeros(0)
    if st.E.size == 0 and st.G.size == 0 and (st.lo <= 0).all() and (st.hi >= 0).all() and not st.q.any():
        return np.zeros(m)  # u = 0 minimizes the (convex, zero-gradient) objective
    return None


def _call(st: QP, backend: QPBackend, where: str) -> QPAnswer:
    """The backend's answer; its own exceptions re-raised as ours."""
    try:
        return backend.solve_qp(st)
    except Exception as exc:  # the backend's own error, re-raised as ours
        hint = (
            " — it needs a positive definite Hessian, which redundant constraint rows or extra actuators make "
            "singular: use daqp or osqp"
            if "positive definite" in str(exc)
            else ""
        )
        raise QPSolveError(
            f"{short_name(backend)} failed on the {st.name} stage of the Gauss QP{where}: {exc}{hint}"
        ) from exc


def violation(st: QP, x: np.ndarray) -> float:
    """The relative violation of the stage's constraints at ``x`` (see the module docstring)."""
    scale = 1.0 + float(np.abs(x).max(initial=0.0))
    viol = 0.0
    if st.E.size:
        viol = max(viol, float(np.abs(st.E @ x - st.e).max()) / (scale * (1 + float(np.abs(st.E).max()))))
    if st.G.size:
        viol = max(viol, float((st.G @ x - st.h).max(initial=0.0)) / (scale * (1 + float(np.abs(st.G).max()))))
    return max(viol, float((st.lo - x).max(initial=0.0)) / scale, float((x - st.hi).max(initial=0.0)) / scale)


def solve_stage(st: QP, backend: QPBackend, where: str, infeasible_ok: bool = False) -> np.ndarray | None:
    """One stage by ``backend``; ``None`` instead of an error when ``infeasible_ok`` and no point is accepted."""
    trivial = _trivial(st)
    if trivial is not None:
        return trivial
    answer = _call(st, backend, where)
    x = answer.x
    if x is None or not np.isfinite(x).all():
        if infeasible_ok:
            return None
        raise QPSolveError(
            f"{short_name(backend)} found no solution of the {st.name} stage of the Gauss QP{where}; "
            "the contacts, bounds and constraints may contradict each other — check the state, or try another backend"
        )
    x = np.asarray(x, float)
    viol = violation(st, x)
    if viol > FEASIBILITY_TOL:
        if infeasible_ok:
            return None
        raise QPSolveError(
            f"{short_name(backend)} returned a point that violates the {st.name} stage's constraints "
            f"by {viol:.2e}{where}; " + _EXACT_HINT
        )
    if answer.found:  # optimality, not only feasibility: the dual residual where the backend reports multipliers
        size = 1.0 + float(np.abs(st.P @ x).max(initial=0.0)) + float(np.abs(st.q).max(initial=0.0))
        if np.isfinite(answer.dual) and answer.dual > DUAL_TOL * size:
            if infeasible_ok:
                return None
            raise QPSolveError(
                f"{short_name(backend)} returned a point that is not optimal on the {st.name} stage of the Gauss "
                f"QP{where} "
                f"(relative dual residual {answer.dual / size:.2e}); " + _EXACT_HINT
            )
    return np.clip(x, st.lo, st.hi)
