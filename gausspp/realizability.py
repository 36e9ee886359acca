"""Realizability of a constraint by a reaction: conditions (12) and (16) as a number.

The step is solvable iff ``S = J A⁻¹ D`` is nonsingular. A scale-free measure: the cosines
of the principal angles between the constraint normals ``range(Jᵀ)`` and the reaction
directions ``range(D)`` in the kinetic metric ``A⁻¹``. They are the singular values of
``Ŝ = L_J⁻¹ S L_D⁻ᵀ`` (``L_J L_Jᵀ = J A⁻¹ Jᵀ``, ``L_D L_Dᵀ = Dᵀ A⁻¹ D``), do not depend on the
units or the coordinates, equal 1 for an ideal constraint (``D = Jᵀ``) and vanish exactly
when the realization cannot keep the constraint. The *margin* is the smallest of them.
"""

from __future__ import annotations

import numpy as np


def cosines(A: np.ndarray, J: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Cosines of the principal angles between ``range(Jᵀ)`` and ``range(D)`` in the metric ``A⁻¹``.

    Parameters
    ----------
    A : (n, n) array, symmetric positive definite
    J : (k, n) array
    D : (n, m) array

    Returns
    -------
    (min(k, m),) array, largest first; zeros if ``J`` or ``D`` is rank deficient.
    """
    A, J, D = (np.atleast_2d(np.asarray(x, float)) for x in (A, J, D))
    try:
        AinvD = np.linalg.solve(A, D)
        LJ = np.linalg.cholesky(J @ np.linalg.solve(A, J.T))
        LD = np.linalg.cholesky(D.T @ AinvD)
    except np.linalg.LinAlgError:
        return np.zeros(min(J.shape[0], D.shape[1]))
    S_hat = np.linalg.solve(LD, np.linalg.solve(LJ, J @ AinvD).T).T
    return np.linalg.svd(S_hat, compute_uv=False)


def margin(A: np.ndarray, J: np.ndarray, D: np.ndarray) -> float:
    """The realizability margin: the smallest cosine (0 if there are fewer directions than rows)."""
    J2, D2 = np.atleast_2d(J), np.atleast_2d(D)
    if D2.shape[1] < J2.shape[0]:
        return 0.0
    return float(np.min(cosines(A, J2, D2)))
