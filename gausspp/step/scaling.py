"""The general Gauss step in the unit-free form every stage works in, and its linear algebra.

With ``L Lᵀ = A`` (Cholesky), ``W = L⁻¹ D`` so that ``Z(u) = ‖W u‖²``; each constraint row ``J_i``
is normalized in ``A⁻¹`` (``Jn = J L⁻ᵀ / ‖J_i L⁻ᵀ‖``), each unknown to a unit column of ``W``
(``ũ = c ⊙ u``), and the whole problem, homogeneous in (right-hand side, bounds) → ``u``, brought to
unit size, so that the backends' absolute tolerances do not decide tiny steps such as slow impacts.
Then ``S = Jn (W / c)`` is ``J A⁻¹ D`` normalized by rows and columns: the realizability cosines.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import NotPositiveDefiniteError, RealizabilityError
from .gauss_problem import GaussProblem, at, row_names

#: Singular values below this fraction of the largest count as zero (rows are normalized first).
RANK_TOL = 1e-9


@dataclass(frozen=True)
class Scaled:
    """A problem in the unit-free form (see the module docstring)."""

    L: np.ndarray  # L Lᵀ = A
    W: np.ndarray  # L⁻¹ D: Z(u) = ‖W u‖²
    Jn: np.ndarray  # J L⁻ᵀ, rows of unit length
    norms: np.ndarray  # the rows' lengths in A⁻¹
    cs: np.ndarray  # column lengths of W (unknowns scaled to ũ = cs ⊙ u)
    S: np.ndarray  # Jn (W / cs): J A⁻¹ D normalized by rows and columns
    r: np.ndarray  # (φ − J a₀) / norms / unit
    scale: float  # size of the right-hand side's terms, for the consistency test
    unit: float  # the problem's size (the QP is solved at unit size)


def _factor(p: GaussProblem) -> np.ndarray:
    """``L`` with ``L Lᵀ = A``; names a mass matrix that is not symmetric positive definite."""
    where = at(p.t)
    try:
        L = np.linalg.cholesky(p.A)
    except np.linalg.LinAlgError:
        raise NotPositiveDefiniteError(
            f"the mass matrix A is not positive definite{where}; check the model's inertia"
        ) from None
    if np.max(np.abs(p.A - p.A.T)) > 1e-12 * np.max(np.abs(p.A)):
        raise NotPositiveDefiniteError(f"the mass matrix A is not symmetric{where}")
    return L


def scaled(p: GaussProblem) -> Scaled:
    """Factor ``A``, normalize rows and columns and bring the problem to unit size; names bad data."""
    L = _factor(p)
    # (LAPACK's general solve: on small matrices scipy's triangular solve was measured 100× slower on a
    # loaded machine, through BLAS threading)
    W = np.linalg.solve(L, p.D)  # L⁻¹ D
    Jt = np.linalg.solve(L, p.J.T).T  # J L⁻ᵀ
    norms = np.linalg.norm(Jt, axis=1)
    names = row_names(p)
    for i in np.flatnonzero(norms == 0):
        raise RealizabilityError(
            f"constraint row {names[i]!r} has a zero gradient{at(p.t)}: it does not restrict the acceleration",
            t=p.t,
            constraint=names[i],
            margin=0.0,
        )
    # unknowns scaled to unit columns of W (ũ = c ⊙ u): H has a unit diagonal, whatever the units of u
    cs = np.linalg.norm(W, axis=0)
    cs[cs == 0] = 1.0
    Jn = Jt / norms[:, None]
    S = (Jn @ W) / cs
    r = (p.phi - p.J @ p.a0) / norms
    scale = float(np.max(np.abs(p.phi / norms), initial=0.0) + np.max(np.abs(p.J @ p.a0 / norms), initial=0.0))
    finite_bounds = np.abs(np.concatenate([p.lower, p.upper]))
    finite_bounds = finite_bounds[np.isfinite(finite_bounds)]
    unit = float(np.max(np.abs(r), initial=0.0)) or float(np.max(finite_bounds, initial=0.0)) or 1.0
    return Scaled(L, W, Jn, norms, cs, S, r / unit, scale / unit, unit)


def svd_rank(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``U, s, Vᵀ`` of ``M`` and its numerical rank (singular values above :data:`RANK_TOL` of the largest)."""
    if M.size == 0:
        return np.zeros((M.shape[0], 0)), np.zeros(0), np.zeros((0, M.shape[1])), 0
    U, s, Vt = np.linalg.svd(M, full_matrices=False)
    rank = int(np.sum(s > RANK_TOL * max(s[0], 1e-300))) if s.size else 0
    return U, s, Vt, rank


def compress(S: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``S u = r`` → an orthonormal basis of their span and its right-hand side."""
    U, s, Vt, rank = svd_rank(S)
    return Vt[:rank], (U[:, :rank].T @ r) / s[:rank]


def range_basis(M: np.ndarray) -> np.ndarray:
    """An orthonormal basis of ``range(M)`` (numerical rank: singular values above 1e-13 of the largest)."""
    U, s, _ = np.linalg.svd(M, full_matrices=False)
    return U[:, : int(np.sum(s > 1e-13 * max(float(s[0]) if s.size else 0.0, 1e-300)))]


def truncated_pinv(M: np.ndarray, rank: int) -> np.ndarray:
    """The pseudo-inverse of ``M`` restricted to its ``rank`` largest singular values."""
    U, s, Vt = np.linalg.svd(M, full_matrices=False)
    return (Vt[:rank].T / s[:rank]) @ U[:, :rank].T
