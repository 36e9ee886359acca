"""Realizability of a constraint by a reaction: conditions (12) and (16) as a number.

The step is solvable iff ``S = J A⁻¹ D`` is nonsingular. A scale-free measure: the singular
values of ``S`` after normalizing each row of ``J`` and each column of ``D`` in the kinetic
metric ``A⁻¹``. They do not depend on units or coordinates; for one constraint the single
value is the cosine of the angle between the constraint normal and the reaction direction
(1 for an ideal constraint); the smallest, the *margin*, vanishes exactly when the
realization cannot keep the constraints — or when the constraint rows (or the reaction
directions) are redundant.
"""

from __future__ import annotations

import numpy as np


def cosines(A: np.ndarray, J: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Singular values of ``S = J A⁻¹ D`` with rows of ``J`` and columns of ``D`` normalized in ``A⁻¹``.

    Parameters
    ----------
    A : (n, n) array, symmetric positive definite
    J : (k, n) array
    D : (n, m) array

    Returns
    -------
    (min(k, m),) array, largest first (cosines of angles for one constraint).
    """
    A, J, D = (np.atleast_2d(np.asarray(x, float)) for x in (A, J, D))
    AinvD, AinvJt = np.linalg.solve(A, D), np.linalg.solve(A, J.T)
    row = np.sqrt(np.einsum("ij,ji->i", J, AinvJt))
    col = np.sqrt(np.einsum("ij,ij->j", D, AinvD))
    with np.errstate(divide="ignore", invalid="ignore"):
        S = (J @ AinvD) / np.outer(row, col)
    if not np.all(np.isfinite(S)):  # a zero row or column: nothing to keep or nothing to push with
        return np.zeros(min(J.shape[0], D.shape[1]))
    return np.linalg.svd(S, compute_uv=False)


def margin(A: np.ndarray, J: np.ndarray, D: np.ndarray) -> float:
    """The realizability margin: the smallest of :func:`cosines` (0 if fewer directions than rows)."""
    J2, D2 = np.atleast_2d(J), np.atleast_2d(D)
    if D2.shape[1] < J2.shape[0]:
        return 0.0
    return float(np.min(cosines(A, J2, D2)))
