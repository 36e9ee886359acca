"""The per-step problem and its reduction to reaction space (DESIGN §2–3).

At one instant the realizations give::

    A q̈ = f + r₀ + D u,     J q̈ = φ,      f = F − h

Eliminating ``q̈ = a₀ + A⁻¹ D u`` with ``a₀ = A⁻¹(f + r₀)`` leaves, in reaction space,

* the step matrix ``S = J A⁻¹ D`` (k × m) and right-hand side ``φ − J a₀``;
* the compulsion ``Z = (A(q̈ − a₀), q̈ − a₀) = uᵀ H u`` with ``H = Dᵀ A⁻¹ D``.

Both solvers work on this reduction: the direct one solves ``S u = φ − J a₀``; the QP
minimizes ``½ uᵀ H u`` subject to it (the generalized Gauss principle, paper §3).

**Realizability margin.** The singular values of ``Ŝ = L_J⁻¹ S L_D⁻ᵀ``, with
``L_J L_Jᵀ = J A⁻¹ Jᵀ`` and ``L_D L_Dᵀ = Dᵀ A⁻¹ D``, are the cosines of the principal angles
between the constraint normals ``range(Jᵀ)`` and the reaction directions ``range(D)`` in the
kinetic metric ``A⁻¹``. Their minimum is the margin: 1 for an ideal constraint, 0 exactly
when conditions (12)/(16) fail, and free of units and of the choice of coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca


@dataclass(frozen=True)
class StepExpressions:
    """The step's data as expressions (symbolic or of fixed-shape inputs).

    Attributes
    ----------
    A : (n, n)   kinetic-energy matrix
    f : (n,)     ``F − h``
    r0 : (n,)    known part of the reaction
    J : (k, n)   constraint Jacobian ``∂Φ/∂v``
    phi : (k,)   right-hand side of ``J q̈ = φ``
    D : (n, m)   reaction directions
    Phi : (k,)   the constraint's value at the state (zero on the constraint)
    """

    A: ca.SX
    f: ca.SX
    r0: ca.SX
    J: ca.SX
    phi: ca.SX
    D: ca.SX
    Phi: ca.SX


@dataclass(frozen=True)
class Reduced:
    """The step in reaction space, see the module docstring."""

    H: ca.SX
    S: ca.SX
    rhs: ca.SX
    a0: ca.SX
    AinvD: ca.SX
    a_free: ca.SX
    S_hat: ca.SX
    pivot: ca.SX


def _solve_upper(R: ca.SX, B: ca.SX) -> ca.SX:
    """``A⁻¹ B`` from the Cholesky factor ``RᵀR = A``."""
    return ca.solve(R, ca.solve(R.T, B))


def reduce(p: StepExpressions) -> Reduced:
    """Eliminate the acceleration: reaction-space data, realizability, positive-definiteness check."""
    R = ca.chol(p.A)
    a_free = _solve_upper(R, p.f)
    a0 = _solve_upper(R, p.f + p.r0)
    AinvD = _solve_upper(R, p.D)
    AinvJt = _solve_upper(R, p.J.T)
    H = p.D.T @ AinvD
    S = p.J @ AinvD
    RJ = ca.chol(p.J @ AinvJt)
    RD = ca.chol(H)
    S_hat = ca.solve(RD, ca.solve(RJ.T, S).T).T
    diagR = ca.diag(R)
    # Relative smallest pivot: NaN or ≤ 0 when A is not positive definite.
    # (casadi's fmin ignores NaN, so NaN from a failed factorization is added back explicitly)
    pivot = ca.mmin(diagR * diagR) / ca.mmax(ca.fabs(ca.diag(p.A))) + ca.sum1(diagR * 0)
    if not ca.is_equal(p.A, p.A.T, 20):
        asym = ca.mmax(ca.fabs(p.A - p.A.T)) / ca.mmax(ca.fabs(p.A))
        pivot = ca.if_else(asym > 1e-12, -1.0, pivot)
    return Reduced(H=H, S=S, rhs=p.phi - p.J @ a0, a0=a0, AinvD=AinvD, a_free=a_free, S_hat=S_hat, pivot=pivot)


#: Names of a step kernel's outputs, in order.
OUTPUTS = ("a", "u", "reaction", "compulsion", "S_hat", "residual", "Phi", "pivot", "a_free", "qp_primal", "qp_dual")


def outputs(p: StepExpressions, red: Reduced, u: ca.SX, y: ca.SX | None) -> list[ca.SX]:
    """Everything a step reports, given the reaction unknowns ``u`` (and QP multipliers ``y``)."""
    a = red.a0 + red.AinvD @ u
    if y is None:
        primal = dual = ca.SX(0)
    else:  # relative residuals: scale-free, so one threshold fits every model
        tiny = 1e-300
        size_S, size_u = ca.mmax(ca.fabs(red.S)), ca.mmax(ca.fabs(u))
        primal = ca.mmax(ca.fabs(red.S @ u - red.rhs)) / (ca.mmax(ca.fabs(red.rhs)) + size_S * size_u + tiny)
        dual = ca.mmax(ca.fabs(red.H @ u + red.S.T @ y)) / (
            ca.mmax(ca.fabs(red.H)) * size_u + size_S * ca.mmax(ca.fabs(y)) + tiny
        )
    return [
        a,
        u,
        p.r0 + p.D @ u,
        u.T @ red.H @ u,
        red.S_hat,
        p.J @ a - p.phi,
        p.Phi,
        red.pivot,
        red.a_free,
        primal,
        dual,
    ]
