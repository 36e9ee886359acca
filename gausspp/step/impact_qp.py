"""The impact of ideal rows as one QP in the velocity after it, solved by a casadi conic and verified.

With every bilateral row ideal (reactions along the rows, ``D = J``) and no realization carrying ``λ``, the
impact problem of :mod:`gausspp.step.impact` is a QP in ``v⁺`` alone (docs/theory.md §6)::

    min ½ (v⁺ − v⁻)ᵀ A (v⁺ − v⁻)   s.t.   J v⁺ = J v⁻ − Φ(q, v⁻),   J_c v⁺ ≥ target,

whose multipliers are the impulses: ``A (v⁺ − v⁻) = Jᵀ μ + J_cᵀ p`` with ``p ≥ 0``. One call of a casadi conic
(:class:`~gausspp.step.qp.casadi_conic.CasadiConic`, the general QP's default backend) solves it, where the
general step (:func:`~gausspp.step.general.solve_general`) scales, tests the rows' rank and stages — about a
tenth of its time on the box dropped on the floor. The answer is then checked from the problem's data alone
(feasibility, the impulses' sign, complementarity, stationarity); any doubt — dependent rows the plugin
could not factor, a backend outside casadi, a check that fails — returns ``None`` and the general step answers.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .general.solve import resolve_backend
from .protocol import StepModel
from .qp.casadi_conic import CasadiConic

#: The checks' tolerance, relative to the data's scale (the plugins solve to round-off: measured ≤ 1e-14).
VERIFY_TOL = 1e-9


def applies(model: StepModel) -> bool:
    """Ideal bilateral rows (or none) and no realization carrying ``λ``."""
    return not model.n_lam and (model.k == 0 or bool(getattr(model, "symmetric_S", False)))


def ideal_impact(
    model: StepModel, backend: Any, A: np.ndarray, v: np.ndarray, J: np.ndarray, e: np.ndarray, Jc: np.ndarray,
    target: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:  # fmt: skip
    """``(v⁺, μ, p)`` of the QP above (``e = J v⁻ − Φ``), verified; ``None`` where the general step must answer."""
    if not applies(model):
        return None
    chosen = resolve_backend(backend)
    if not isinstance(chosen, CasadiConic):
        return None
    nv, k, nc = v.size, J.shape[0], Jc.shape[0]
    if not k + nc:  # nothing closed, no rows: the velocity is what it was
        return v.copy(), np.zeros(0), np.zeros(0)
    rows = np.vstack([J.reshape(k, nv), Jc.reshape(nc, nv)])
    solver = chosen._conic(nv, k + nc)
    lower = np.concatenate([e, target])
    upper = np.concatenate([e, np.full(nc, np.inf)])
    sol = solver(h=A, g=-(A @ v), a=rows, lba=lower, uba=upper)
    x = np.array(sol["x"]).ravel()
    impulses = -np.array(sol["lam_a"]).ravel()  # casadi: H x + g + aᵀλ = 0, so A(x − v) = aᵀ(−λ)
    if not verified(A, v, J, e, Jc, target, x, impulses[:k], impulses[k:]):
        return None
    return x, impulses[:k], impulses[k:]


def verified(
    A: np.ndarray, v: np.ndarray, J: np.ndarray, e: np.ndarray, Jc: np.ndarray, target: np.ndarray,
    x: np.ndarray, mu: np.ndarray, p: np.ndarray,
) -> bool:  # fmt: skip
    """The impact's optimality conditions at ``(x, μ, p)``, each to :data:`VERIFY_TOL` of the data's scale."""
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(mu)) and np.all(np.isfinite(p))):
        return False
    speed = 1.0 + float(np.max(np.abs(v), initial=0.0)) + float(np.max(np.abs(target), initial=0.0))
    row_scale = 1.0 + float(np.max(np.abs(np.concatenate([J.ravel(), Jc.ravel()])), initial=0.0))
    tol = VERIFY_TOL * speed * row_scale
    gap = Jc @ x - target
    momentum = A @ (x - v) - J.T @ mu - Jc.T @ p
    impulse = 1.0 + float(np.max(np.abs(np.concatenate([mu, p])), initial=0.0))
    return bool(
        np.all(np.abs(J @ x - e) <= tol)
        and np.all(gap >= -tol)
        and np.all(p >= -VERIFY_TOL * impulse)
        and np.all(np.abs(p * gap) <= tol * impulse)
        and np.all(np.abs(momentum) <= VERIFY_TOL * impulse * row_scale * (1.0 + float(np.max(np.abs(A)))))
    )
