"""Result types: small frozen dataclasses of numpy arrays."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class StepResult:
    """Everything one step computes (DESIGN §2–3).

    Attributes
    ----------
    t : float
        Time of the step.
    a : (nv,) array
        The acceleration ``q̈`` (for a rigid body, ``ω̇``).
    u : (m,) array
        The reaction unknowns: ``λ`` for ideal and force realizations, ``λ̇`` for those with
        ``λ`` as state.
    reaction : (nv,) array
        ``R = [T] − F = r₀ + D u`` (paper eq. (5)).
    compulsion : float
        Gauss's compulsion ``Z = (A(a − a₀), a − a₀) = uᵀ Dᵀ A⁻¹ D u`` with
        ``a₀ = A⁻¹(F − h + r₀)``, the quantity the step minimizes.
    margin : float
        Realizability margin: the smallest singular value of ``S = J A⁻¹ D`` with rows and
        columns normalized in the metric ``A⁻¹`` (see :mod:`gausspp.realizability`): 1 for one
        ideal constraint, 0 when (12)/(16) fail or the constraint rows are redundant.
    cosines : (k,) array
        All those singular values, largest first (the cosine of the angle between normal and
        reaction direction, for one constraint).
    residual : (k,) array
        ``J a − φ``: how well the acceleration keeps the differentiated constraint.
    constraint_value : (k,) array
        ``Φ(q, v, t)`` at the state: nonzero means the state is off the constraint.
    free_acceleration : (nv,) array
        ``A⁻¹(F − h)``, the motion with the constraint released (eq. (1)).
    solver : str
        ``"direct"`` or the QP backend's name.
    qp_residuals : (float, float) or None
        The QP's own relative primal ``‖S u − rhs‖∞`` and dual ``‖H u + Sᵀ y‖∞`` residuals
        (each divided by the size of its terms).
    """

    t: float
    a: np.ndarray
    u: np.ndarray
    reaction: np.ndarray
    compulsion: float
    margin: float
    cosines: np.ndarray
    residual: np.ndarray
    constraint_value: np.ndarray
    free_acceleration: np.ndarray
    solver: str
    qp_residuals: tuple[float, float] | None = None

    def disagreement(self, other: StepResult) -> float:
        """Largest relative difference in ``a`` and in ``u`` from another result of the same step.

        Each is measured against the larger of the two results' norms (``a`` also against the
        free acceleration), so a zero answer compared with round-off gives round-off.
        """
        da = _relative(self.a - other.a, self.a, other.a, self.free_acceleration)
        du = _relative(self.u - other.u, self.u, other.u)
        return max(da, du)


def _relative(diff: np.ndarray, *scales: np.ndarray) -> float:
    scale = max(float(np.max(np.abs(s), initial=0.0)) for s in scales)
    size = float(np.max(np.abs(diff), initial=0.0))
    return size / scale if scale > 0 else size
