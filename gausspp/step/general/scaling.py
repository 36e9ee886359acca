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

from ...errors import NotPositiveDefiniteError, RealizabilityError
from .. import dense
from .gauss_problem import GaussProblem, at, row_names

#: Singular values below this fraction of the largest count as zero (rows are normalized first).
RANK_TOL = 1e-9
#: :func:`range_basis` keeps the singular directions above this fraction of the largest singular value.
RANGE_TOL = 1e-13


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
    try:
        L = dense.cholesky(p.A)
    except np.linalg.LinAlgError:
        raise NotPositiveDefiniteError(
            f"the mass matrix A is not positive definite{at(p.t)}; check the model's inertia"
        ) from None
    if np.abs(p.A - p.A.T).max() > 1e-12 * np.abs(p.A).max():
        raise NotPositiveDefiniteError(f"the mass matrix A is not symmetric{at(p.t)}")
    return L


def _zero_row(p: GaussProblem, i: int) -> RealizabilityError:
    name = row_names(p)[i]
    return RealizabilityError(
        f"constraint row {name!r} has a zero gradient{at(p.t)}: it does not restrict the acceleration",
        t=p.t,
        constraint=name,
        margin=0.0,
    )


def _unit(r: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> float:
    """The problem's size: the largest ``|r|``, else the largest finite bound, else 1."""
    if r.size and (largest := float(np.abs(r).max())):
        return largest
    bounds = np.abs(np.concatenate([lower, upper]))
    bounds = bounds[np.isfinite(bounds)]
    return float(bounds.max()) if bounds.size and bounds.max() else 1.0


def scaled(p: GaussProblem) -> Scaled:
    """Factor ``A``, normalize rows and columns and bring the problem to unit size; names bad data."""
    L = _factor(p)
    m = p.D.shape[1]
    # L⁻¹ [D, Jᵀ] in one LAPACK general solve (on small matrices scipy's triangular solve can be far slower on a
    # loaded machine, through BLAS threading)
    X = dense.solve(L, np.hstack([p.D, p.J.T]))
    W, Jt = X[:, :m], X[:, m:].T  # L⁻¹ D and J L⁻ᵀ
    norms = np.sqrt(np.einsum("ij,ij->i", Jt, Jt))
    if norms.size and not norms.all():
        raise _zero_row(p, int(np.flatnonzero(norms == 0)[0]))
    # unknowns scaled to unit columns of W (ũ = c ⊙ u): H has a unit diagonal, whatever the units of u
    cs = np.sqrt(np.einsum("ij,ij->j", W, W))
    cs[cs == 0] = 1.0
    Jn = Jt / norms[:, None]
    S = (Jn @ W) / cs
    Ja0 = p.J @ p.a0
    r = (p.phi - Ja0) / norms
    scale = float(np.abs(p.phi / norms).max() + np.abs(Ja0 / norms).max()) if r.size else 0.0
    unit = _unit(r, p.lower, p.upper)
    return Scaled(L, W, Jn, norms, cs, S, r / unit, scale / unit, unit)


def svd_rank(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``U, s, Vᵀ`` of ``M`` and its numerical rank (singular values above :data:`RANK_TOL` of the largest)."""
    U, s, Vt = dense.svd(M)
    return U, s, Vt, rank_of(s)


def rank_of(s: np.ndarray, tol: float = RANK_TOL) -> int:
    """How many of the singular values ``s`` (largest first) exceed ``tol`` times the largest."""
    return int(np.count_nonzero(s > tol * max(float(s[0]), 1e-300))) if s.size else 0


def compress(S: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``S u = r`` → an orthonormal basis of their span and its right-hand side."""
    U, s, Vt, rank = svd_rank(S)
    return Vt[:rank], (U[:, :rank].T @ r) / s[:rank]


def range_basis(M: np.ndarray) -> np.ndarray:
    """An orthonormal basis of ``range(M)`` (numerical rank: :data:`RANGE_TOL`)."""
    U, s, _ = dense.svd(M)
    return U[:, : rank_of(s, RANGE_TOL)]


def truncated_pinv(M: np.ndarray, rank: int) -> np.ndarray:
    """The pseudo-inverse of ``M`` restricted to its ``rank`` largest singular values."""
    U, s, Vt = dense.svd(M)
    return (Vt[:rank].T / s[:rank]) @ U[:, :rank].T
