"""Realizability of a constraint by a reaction: conditions (12) and (16) as a number — computed here only.

The step is solvable iff ``S = J A⁻¹ D`` is nonsingular. A scale-free measure: the singular
values of ``S`` after normalizing each row of ``J`` and each column of ``D`` in the kinetic
metric ``A⁻¹`` (``S_norm``). They do not depend on units or coordinates; for one constraint the
single value is the cosine of the angle between the constraint normal and the reaction direction
(1 for an ideal constraint); the smallest, the *margin* ``σ_k``, vanishes exactly when the
realization cannot keep the constraints — or when the constraint rows (or the reaction
directions) are redundant. By convention the margin is 1 with no constraint rows and 0 with
fewer reaction directions than rows (``k > m``: ``S`` cannot have rank ``k``).

Every margin of the package comes from here: from the data (:func:`cosines`, :func:`margin`,
:func:`cosines_and_margin`, :func:`normalized_cosines`), from a kernel's ``S_norm`` (:func:`singular_values`,
:func:`step_margin`, :func:`stacked_margins`), inside a casadi graph (:func:`margin_bound`, and exactly for one or two
rows :func:`graph_cosines`), all through the one rule :func:`margin_of`.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from scipy.linalg import eigvals_banded

from . import dense

#: Above this many constraint rows :func:`margin_bound` is ``+inf`` (it needs a symbolic k × k inverse):
#: the compiled lane then checks the margin at the recorded samples only.
MARGIN_BOUND_ROWS = 8


def normalized_S(A: np.ndarray, J: np.ndarray, D: np.ndarray) -> np.ndarray:
    """``S = J A⁻¹ D`` with each row of ``J`` and each column of ``D`` normalized in ``A⁻¹`` (one factorization of
    ``A``); a zero row or column gives a non-finite row or column."""
    A, J, D = (np.atleast_2d(np.asarray(x, float)) for x in (A, J, D))
    solved = np.linalg.solve(A, np.hstack([D, J.T]))
    AinvD, AinvJt = solved[:, : D.shape[1]], solved[:, D.shape[1] :]
    row = np.sqrt(np.einsum("ij,ji->i", J, AinvJt))
    col = np.sqrt(np.einsum("ij,ij->j", D, AinvD))
    with np.errstate(divide="ignore", invalid="ignore"):
        return (J @ AinvD) / np.outer(row, col)


def _singular_values(S: np.ndarray) -> np.ndarray:
    """Largest first; zeros where ``S`` has a non-finite entry (nothing to keep or nothing to push with)."""
    if not np.all(np.isfinite(S)):
        return np.zeros(min(S.shape))
    return np.linalg.svd(S, compute_uv=False)


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
    return _singular_values(normalized_S(A, J, D))


def group_margins(A: np.ndarray, J: np.ndarray, D: np.ndarray, blocks: list[tuple[slice, slice]]) -> list[float]:
    """:func:`margin` of each block ``(rows, cols)`` of ``J`` and ``D`` alone, on one factorization of ``A``: a
    block's normalized ``S`` is the block of the whole one (each row and column normalized by itself)."""
    S = normalized_S(A, J, D)
    return [margin_of(_singular_values(S[rows, cols]), *S[rows, cols].shape) for rows, cols in blocks]


def margin_of(cos: np.ndarray, k: int, m: int) -> float:
    """The margin ``σ_k`` from the cosines of ``k`` rows and ``m`` directions: 1 if ``k = 0``, 0 if ``k > m``
    (or no cosines), else the smallest — the last, as singular values come largest first (NaN in, NaN out:
    the caller's finite check fails)."""
    if k == 0:
        return 1.0
    if k > m or cos.size == 0:
        return 0.0
    return float(cos[-1])


def cosines_and_margin(A: np.ndarray, J: np.ndarray, D: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`cosines` and :func:`margin_of` them, for ``J`` of shape (k, n) and ``D`` (n, m); ``k = 0`` allowed."""
    J2, D2 = np.atleast_2d(J), np.atleast_2d(D)
    k, m = (J2.shape[0] if np.size(J) else 0), D2.shape[1]
    cos = cosines(A, J2, D2) if k else np.zeros(0)
    return cos, margin_of(cos, k, m)


def normalized_cosines(S_norm: np.ndarray, D: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`cosines_and_margin` from ``S_norm``, the ``J A⁻¹ D`` already normalized (k × m, every row of ``J``
    nonzero), and ``D``: a zero column of ``D`` gives zero cosines, as in :func:`cosines`."""
    k, m = S_norm.shape
    if k == 0:
        cos = np.zeros(0)
    elif not D.any(axis=0).all():  # nothing to push with
        cos = np.zeros(min(k, m))
    else:
        cos = dense.singular_values(S_norm)
    return cos, margin_of(cos, k, m)


def margin(A: np.ndarray, J: np.ndarray, D: np.ndarray) -> float:
    """The realizability margin: the smallest of :func:`cosines` (0 if fewer directions than rows)."""
    return cosines_and_margin(A, J, D)[1]


def singular_values(S_norm: np.ndarray, k: int, m: int) -> np.ndarray:
    """Singular values of a kernel's normalized ``S`` (k × m), largest first; for one row, its length."""
    if k == 1:
        row = S_norm.ravel()
        return np.array([np.sqrt(float(row @ row))])
    S = S_norm.reshape(k, m, order="F")
    if k == m and k >= BANDED_FROM_ROWS and np.isfinite(S).all() and is_symmetric(S[None]):
        band = _band(S[None])
        if band is not None:  # every eigenvalue of the band (O(k² b)), not an SVD of the whole (O(k³))
            return np.sort(np.abs(eigvals_banded(band[0], lower=True)))[::-1]
    return np.linalg.svd(S, compute_uv=False)


def step_margin(S_norm: np.ndarray, k: int, m: int) -> float:
    """The margin ``σ_k`` of a kernel's normalized ``S`` (:func:`margin_of` its :func:`singular_values`)."""
    if k == 0 or k > m:
        return margin_of(np.zeros(0), k, m)
    return margin_of(singular_values(S_norm, k, m), k, m)


def symmetric_by_construction(J: ca.SX, D: ca.SX) -> bool:
    """Whether every reaction acts along its own constraint's normal, ``D = Jᵀ`` as expressions (ideal rows, or
    servo directions chosen along the normals): then the normalized ``S = J A⁻¹ Jᵀ`` is symmetric at every state."""
    return bool(D.shape == J.T.shape and ca.is_equal(D, J.T, 1))


def stacked_margins(S_norm: np.ndarray, k: int, m: int, symmetric: bool | None = None) -> np.ndarray:
    """:func:`step_margin` of each of ``n`` normalized ``S`` stacked as an ``(n, k, m)`` array, at once: the length
    of the row for ``k = 1``, the smallest singular value of a batched SVD otherwise (1 if ``k = 0``, 0 if
    ``k > m``, NaN for a sample with NaN or inf in its ``S``). ``symmetric``: whether each ``S`` is symmetric, if
    the caller knows (:func:`symmetric_by_construction`); checked on the numbers otherwise."""
    n = S_norm.shape[0]
    if k == 0 or k > m or n == 0:
        return np.full(n, margin_of(np.zeros(0), k, m))
    if k == 1:
        return np.sqrt(np.einsum("ij,ij->i", S_norm[:, 0, :], S_norm[:, 0, :]))
    out = np.full(n, np.nan)  # NaN in, NaN out (as margin_of): the SVD is not even tried on those
    finite = np.isfinite(S_norm.sum(axis=(1, 2)))  # a NaN or an inf anywhere makes the sum so
    S = S_norm if finite.all() else S_norm[finite]  # (no copy of a large stack when every sample is finite)
    if k == m and (is_symmetric(S) if symmetric is None else symmetric):
        # symmetric (ideal constraints: S = J A⁻¹ Jᵀ, rows and columns normalized alike): the singular values
        # are the eigenvalues' magnitudes, and a symmetric eigensolver is several times faster than the SVD
        out[finite] = _symmetric_margins(S)
    else:
        out[finite] = np.linalg.svd(S, compute_uv=False)[:, -1]
    return out


def is_symmetric(S: np.ndarray) -> bool:
    """Whether each of the stacked ``S`` is symmetric (to round-off of its largest entry); checked a few samples
    at a time (no copy of the whole stack), stopping at the first that is not."""
    size = max(S.max(initial=0.0), -S.min(initial=0.0))
    every = max(1, 2**20 // max(S[0].size, 1))  # about a million entries at a time
    for start in range(0, S.shape[0], every):
        block = S[start : start + every]
        if np.abs(block - block.transpose(0, 2, 1)).max(initial=0.0) > 1e-13 * size:
            return False
    return True


#: From this many rows on, a banded symmetric ``S`` has its smallest eigenvalue found in its band (O(k b²)).
BANDED_FROM_ROWS = 32


def _band(S: np.ndarray) -> np.ndarray | None:
    """The stacked symmetric ``S`` in LAPACK's lower band form (``band[:, d, j] = S[:, j + d, j]``), or ``None``
    unless they are large and banded (a bandwidth of at most a quarter of their size)."""
    n, k, _ = S.shape
    offsets = np.abs(np.subtract.outer(np.arange(k), np.arange(k)))
    width = int(offsets[np.any(S != 0, axis=0)].max(initial=0))
    if k < BANDED_FROM_ROWS or width > k // 4:
        return None
    band = np.zeros((n, width + 1, k))
    for d in range(width + 1):
        band[:, d, : k - d] = np.diagonal(S, offset=-d, axis1=1, axis2=2)
    return band


def _symmetric_margins(S: np.ndarray) -> np.ndarray:
    """The smallest eigenvalue magnitude of each stacked symmetric ``S``: of its band alone when it is banded and
    large (a chain's ``J A⁻¹ Jᵀ``: bandwidth 3 whatever its size), by the full symmetric eigensolver otherwise."""
    band = _band(S)
    if band is None:
        return np.abs(np.linalg.eigvalsh(S)).min(axis=1)
    out = np.empty(S.shape[0])
    for i in range(S.shape[0]):
        lowest = eigvals_banded(band[i], lower=True, select="i", select_range=(0, 0))[0]
        # positive semidefinite (as J A⁻¹ Jᵀ is): the lowest eigenvalue is the smallest magnitude
        out[i] = abs(lowest) if lowest > -1e-12 else np.abs(np.linalg.eigvalsh(S[i])).min()
    return out


def margin_bound(S: ca.SX, k: int, m: int) -> ca.SX:
    """In a casadi graph: ``b`` with ``b ≤ σ_min(S) ≤ √k · b``, the margin within a factor √k.

    ``b = 1 / √trace((S Sᵀ)⁻¹)``: ``trace((S Sᵀ)⁻¹) = Σ 1/σᵢ²`` lies between ``1/σ_min²`` and ``k/σ_min²``.
    For one row it is the row's length, the margin itself. ``+inf`` with no rows or more than
    :data:`MARGIN_BOUND_ROWS`; 0 when ``k > m`` (as :func:`margin_of`).
    """
    if k == 0 or k > MARGIN_BOUND_ROWS:
        return ca.SX(np.inf)
    if k > m:
        return ca.SX(margin_of(np.zeros(0), k, m))
    G = S @ S.T
    return 1 / ca.sqrt(ca.trace(ca.solve(G, ca.SX.eye(k)))) if k > 1 else ca.sqrt(G[0, 0])


#: Up to this many constraint rows :func:`graph_cosines` gives the cosines in closed form inside a graph.
GRAPH_COSINE_ROWS = 2


def graph_cosines(S: ca.SX, k: int, m: int) -> ca.SX | None:
    """In a casadi graph: the singular values of the normalized ``S`` (k × m), largest first, for ``k ≤ 2``.

    casadi has no SVD node; for one or two rows the values have a closed form as accurate as an SVD
    (absolute error of order ``ε σ₁``). With ``s = σ₁ + σ₂``, ``g = σ₁² − σ₂²`` and ``P = σ₁σ₂``:

    * ``P² = det(S Sᵀ) = Σ_{i<j} (S₀ᵢS₁ⱼ − S₀ⱼS₁ᵢ)²`` (Cauchy–Binet: a sum of squares, no cancellation);
    * ``s² = ‖S‖²_F + 2P``; ``g = √((G₀₀ − G₁₁)² + 4G₀₁²)`` with ``G = S Sᵀ`` (the eigenvalue gap of ``G``);
    * ``σ₁ = (s + g/s) / 2`` and ``σ₂ = P / σ₁`` (never ``s − …``: no subtraction of nearly equal numbers).

    One row: its length. ``m = 1`` with two rows: one value, the column's length. ``None`` for more than
    :data:`GRAPH_COSINE_ROWS` rows (use :func:`singular_values` on the numbers). A zero ``S`` gives zeros.
    """
    if k == 0 or k > GRAPH_COSINE_ROWS:
        return None
    if k == 1 or m == 1:
        return ca.sqrt(ca.sumsqr(S))
    r0, r1 = S[0, :], S[1, :]
    g00, g11, g01 = ca.dot(r0, r0), ca.dot(r1, r1), ca.dot(r0, r1)
    minors = [r0[i] * r1[j] - r0[j] * r1[i] for i in range(m) for j in range(i + 1, m)]
    P = ca.sqrt(sum(x * x for x in minors))
    s = ca.sqrt(g00 + g11 + 2 * P)
    g = ca.sqrt((g00 - g11) ** 2 + 4 * g01 * g01)
    s1 = ca.if_else(s > 0, (s + g / s) / 2, 0)
    s2 = ca.if_else(s1 > 0, P / s1, 0)
    return ca.vertcat(s1, s2)
