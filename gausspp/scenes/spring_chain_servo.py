"""A chain of masses and springs, pushed at the first mass so that the last follows a path (index 2n + 1).

``n`` masses ``m`` on a line, displacements ``x₁ … xₙ`` from rest, springs ``k`` between neighbours (none
to a wall):

    T = ½ m Σ ẋᵢ²,   V = ½ k Σ (xᵢ₊₁ − xᵢ)².

A force ``u`` on the first mass (``gp.Force(M = [[1, 0, …, 0]])``) keeps the servo-constraint
``xₙ − yd(t) = 0``: it reaches the last mass through ``n − 1`` springs, so ``u`` appears in the ``2n``-th
derivative of the constraint and the servo DAE has index ``2n + 1`` (Altmann and Heiland's chain); the
one-step matrix ``J A⁻¹ Mᵀ`` is zero for ``n ≥ 2`` (for ``n = 1`` the servo is orthogonal, index 3).
``yd = σ_p(t/T)`` moves the last mass by 1 from rest to rest, ``σ_p`` the Hermite smoothstep of degree
``4n + 3`` with zero derivatives up to order ``p = 2n + 1`` at both ends (:mod:`.smooth_paths`).

**Exact solution (flatness).** ``xₙ`` is a flat output. From the last mass back,

    m ẍₙ = k (xₙ₋₁ − xₙ)                      ⇒  xₙ₋₁ = xₙ + m ẍₙ / k,
    m ẍᵢ = k (xᵢ₋₁ − xᵢ) − k (xᵢ − xᵢ₊₁)      ⇒  xᵢ₋₁ = xᵢ + (m ẍᵢ + k (xᵢ − xᵢ₊₁)) / k,
    m ẍ₁ = u − k (x₁ − x₂)                    ⇒  u = m ẍ₁ + k (x₁ − x₂),

each ``xᵢ`` a numpy polynomial in ``t`` (sums of ``yd``'s even derivatives), velocities by their derivatives
(:func:`flat_chain`).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from numpy.polynomial import Polynomial

from ..errors import InputError
from ..model.constraints import Holonomic
from ..model.mechanism import Lagrangian
from ..model.model import Model
from ..model.realizations import Force
from . import smooth_paths
from .scene import Scene, numbered

#: Largest chain (index reduction differentiates ``yd`` ``2n`` times).
MAX_MASSES = 6


def flat_chain(yd: Polynomial, n: int, m: float, k: float) -> tuple[list[Polynomial], Polynomial]:
    """The positions ``x₁ … xₙ`` and the force ``u`` as polynomials in ``t``, from ``xₙ = yd`` (module docstring)."""
    x = [yd]  # from the last mass back: x[0] = xₙ, x[1] = xₙ₋₁, …
    for i in range(n - 1):
        following = x[i - 1] if i > 0 else x[i]  # xᵢ₊₁; none beyond the last mass (no spring: zero term)
        x.append(x[i] + (m * x[i].deriv(2) + k * (x[i] - following)) / k)
    x.reverse()
    second = x[1] if n > 1 else x[0]  # no spring on a single mass
    u = m * x[0].deriv(2) + k * (x[0] - second)
    return x, u


def build(n: int = 3, m: float = 1.0, k: float = 4.0, T: float = 4.0, distance: float = 1.0) -> Scene:
    """Spring chain of n masses, force on the first, the last's position prescribed: tangential servo, index 2n+1.

    ``scene.exact(t)`` and ``scene.forces(t) = (u,)`` are the flat solution.

    Parameters
    ----------
    n : int
        Number of masses (-). Allowed: integer, 1 ≤ n ≤ 6.
    m : float
        Mass of each body (kg). Allowed: > 0.
    k : float
        Stiffness of the springs between neighbours (N/m). Allowed: > 0.
    T : float
        Duration of the last mass's rest-to-rest move, also the scene's horizon ``t_end`` (s). Allowed: > 0.
    distance : float
        Displacement of the last mass over the move (m). Allowed: any finite number.
    """
    if not 1 <= n <= MAX_MASSES:
        raise InputError(f"spring-chain-servo: n must be between 1 and {MAX_MASSES} (masses), got {n!r}")
    for name, value in (("m", m), ("k", k), ("T", T)):
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"spring-chain-servo: {name} must be positive and finite, got {value!r}")
    yd = smooth_paths.rest_to_rest(2 * n + 1, T, distance)
    x, u = flat_chain(yd, n, m, k)
    velocities = [xi.deriv() for xi in x]

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        tc = float(np.clip(t, 0.0, T))  # at rest outside the move
        return np.array([xi(tc) for xi in x]), np.array([vi(tc) for vi in velocities])

    def forces(t: float) -> np.ndarray:
        return np.array([u(float(np.clip(t, 0.0, T)))])

    return Scene(
        name="spring-chain-servo",
        model=_model(n, m, k, yd, T),
        q0=np.zeros(n),
        v0=np.zeros(n),
        coordinates=numbered(["x (m)"], n),
        lam0=None,
        t_end=float(T),
        exact=exact,
        description=f"chain of {n} masses and springs: force on the first, the last follows a path; index {2 * n + 1}",
        params=dict(n=n, m=m, k=k, T=T, distance=distance, index=2 * n + 1),
        forces=forces,
    )


def _model(n: int, m: float, k: float, yd: Polynomial, T: float) -> Model:
    """The chain's Lagrangian and the servo ``xₙ = yd(t)`` with the force on the first mass."""

    def potential(q: Any, t: Any) -> Any:
        return sum((0.5 * k * (q[i + 1] - q[i]) ** 2 for i in range(n - 1)), ca.SX(0))

    body = Lagrangian(n=n, T=lambda q, v, t: 0.5 * m * ca.sumsqr(v), V=potential)
    push = [[1.0] + [0.0] * (n - 1)]
    servo = Holonomic(
        lambda q, t: q[n - 1] - smooth_paths.evaluate(yd, t, T),
        name="last mass follows yd(t)",
        realization=Force(lambda q, v, t: push),
    )
    return Model(body, [servo])
