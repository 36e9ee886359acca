"""Small dense linear algebra for the general Gauss step, straight through LAPACK.

The general step works on matrices of a few rows and columns, many times per simulated second; there
numpy's wrappers (type dispatch, error state, copies) cost several times the arithmetic. These call the
same LAPACK routines numpy does (``gesv``, ``potrf``, ``gesdd``) through :mod:`scipy.linalg.lapack`, and
raise :class:`numpy.linalg.LinAlgError` as numpy does. Inputs are finite ``float64`` arrays (the callers
check); no finite check is repeated here.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import lapack


def solve(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A⁻¹ B`` by LU with partial pivoting (``B`` a vector or a matrix); raises if ``A`` is singular."""
    if B.size == 0:
        return np.zeros(B.shape)
    x, info = lapack.dgesv(A, B)[2:]
    if info > 0:
        raise np.linalg.LinAlgError("Singular matrix")
    return x  # type: ignore[no-any-return]


def cholesky(A: np.ndarray) -> np.ndarray:
    """``L`` lower triangular with ``L Lᵀ = A``; raises if ``A`` is not positive definite."""
    L, info = lapack.dpotrf(A, lower=1, clean=1)
    if info != 0:
        raise np.linalg.LinAlgError("Matrix is not positive definite")
    return L  # type: ignore[no-any-return]


def svd(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The thin SVD ``U, s, Vᵀ`` of ``M`` (singular values largest first)."""
    k, n = M.shape
    if M.size == 0:
        return np.zeros((k, 0)), np.zeros(0), np.zeros((0, n))
    U, s, Vt, info = lapack.dgesdd(M, full_matrices=0)
    if info != 0:
        raise np.linalg.LinAlgError("SVD did not converge")
    return U, s, Vt


def singular_values(M: np.ndarray) -> np.ndarray:
    """The singular values of ``M``, largest first."""
    if M.size == 0:
        return np.zeros(0)
    if M.shape[0] == 1 or M.shape[1] == 1:  # one row or column: its length (hypot: no overflow, no underflow)
        return np.array([math.hypot(*M.ravel().tolist())])
    s, info = lapack.dgesdd(M, compute_uv=0)[1::2]
    if info != 0:
        raise np.linalg.LinAlgError("SVD did not converge")
    return s  # type: ignore[no-any-return]


def lstsq(A: np.ndarray, B: np.ndarray, rcond: float | None = None) -> np.ndarray:
    """The least-squares solution of least norm of ``A X = B`` (``B`` a vector or a matrix), as
    :func:`numpy.linalg.lstsq`: singular values below ``rcond`` times the largest are dropped (``None``:
    machine precision times the larger dimension)."""
    m, n = A.shape
    vector = B.ndim == 1
    rhs = B.reshape(m, -1)
    nrhs = rhs.shape[1]
    if rcond is None:
        rcond = float(np.finfo(float).eps) * max(m, n)
    if A.size == 0 or nrhs == 0:
        return np.zeros(n) if vector else np.zeros((n, nrhs))
    if m < n:  # LAPACK returns the solution in B's storage: room for n rows
        rhs = np.vstack([rhs, np.zeros((n - m, nrhs))])
    work, iwork, info = lapack.dgelsd_lwork(m, n, nrhs, rcond)
    x, _, _, info = lapack.dgelsd(A, rhs, int(work), iwork, rcond)
    if info != 0:
        raise np.linalg.LinAlgError("SVD did not converge in Linear Least Squares")
    return x[:n, 0] if vector else x[:n]  # type: ignore[no-any-return]
