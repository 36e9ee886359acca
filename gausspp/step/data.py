"""A step's data as numbers: :class:`StepProblem`, ``A, f, r₀, J, φ, D`` of docs/theory.md §2 at one instant.

What :meth:`Model.step_data` returns, what :func:`gausspp.step.problem.solve` takes, and what the
diagnosis of a failed step (:mod:`gausspp.step.outcome`) reads.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, NonFiniteError, ShapeError


@dataclass(frozen=True)
class StepProblem:
    """``A q̈ = f + r₀ + D u``, ``J q̈ = φ`` at one instant.

    Attributes
    ----------
    A : (n, n) array     kinetic-energy (mass) matrix, symmetric positive definite
    f : (n,) array       ``F − h``
    r0 : (n,) array      known part of the reaction
    J : (k, n) array     ``∂Φ/∂v``
    phi : (k,) array     right-hand side of ``J q̈ = φ``
    D : (n, m) array     reaction directions
    Phi : (k,) array     constraint value at the state
    """

    A: np.ndarray
    f: np.ndarray
    r0: np.ndarray
    J: np.ndarray
    phi: np.ndarray
    D: np.ndarray
    Phi: np.ndarray

    @classmethod
    def create(
        cls,
        A: object,
        f: object,
        J: object,
        phi: object,
        D: object | None = None,
        r0: object | None = None,
    ) -> StepProblem:
        """Check shapes and values; ``D`` defaults to ``Jᵀ`` (ideal), ``r0`` to zero."""
        A_ = _array("A", A, 2)
        n = A_.shape[0]
        if A_.shape != (n, n):
            raise ShapeError(f"A must be square, got shape {A_.shape}")
        J_ = _array("J", J, 2)
        k = J_.shape[0]
        if J_.shape[1] != n:
            raise ShapeError(f"J has shape {J_.shape}, expected ({k}, {n}) to match A")
        D_ = J_.T.copy() if D is None else _array("D", D, 2)
        if D_.shape[0] != n:
            raise ShapeError(f"D has shape {D_.shape}, expected ({n}, m)")
        f_ = _vector("f", f, n)
        r0_ = np.zeros(n) if r0 is None else _vector("r0", r0, n)
        return cls(A=A_, f=f_, r0=r0_, J=J_, phi=_vector("phi", phi, k), D=D_, Phi=np.zeros(k))

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(n, k, m)``: coordinates, constraint rows, reaction directions."""
        return self.A.shape[0], self.J.shape[0], self.D.shape[1]


def _array(name: str, value: object, ndim: int) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float, ndmin=ndim)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be numeric: {exc}") from None
    if arr.ndim != ndim:
        raise ShapeError(f"{name} must have {ndim} dimensions, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"{name} contains NaN or inf")
    return arr


def _vector(name: str, value: object, size: int) -> np.ndarray:
    arr = _array(name, value, 1).ravel()
    if arr.shape != (size,):
        raise ShapeError(f"{name} has {arr.size} entries, expected {size}")
    return arr
