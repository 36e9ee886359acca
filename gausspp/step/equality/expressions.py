"""The per-step problem and its reduction to reaction space (docs/theory.md §2–3).

At one instant the realizations give::

    A q̈ = f + r₀ + D u,     J q̈ = φ,      f = F − h

Eliminating ``q̈ = a₀ + A⁻¹ D u`` with ``a₀ = A⁻¹(f + r₀)`` leaves, in reaction space,

* the step matrix ``S = J A⁻¹ D`` (k × m) and right-hand side ``φ − J a₀``;
* the compulsion ``Z = (A(q̈ − a₀), q̈ − a₀) = uᵀ H u`` with ``H = Dᵀ A⁻¹ D``.

Both solvers work on this reduction: the direct one solves ``S u = φ − J a₀``; the QP
minimizes ``½ uᵀ H u`` subject to it (the generalized Gauss principle, paper §3).

**Realizability margin.** The smallest singular value of ``S`` with each row of ``J`` and each
column of ``D`` normalized in the kinetic metric ``A⁻¹`` (docs/theory.md §2's σ_min(S)/(‖J‖·‖A⁻¹D‖), per
row and column): for one constraint the cosine of the angle between its normal and its
reaction direction, 1 for an ideal constraint, and 0 exactly when ``S`` is singular — the
realization cannot keep the constraint (12)/(16), or the constraint rows are redundant. It is
free of units and of the choice of coordinates.

The solve itself uses ``Ŝ = L_J⁻¹ S L_D⁻ᵀ`` (``L_J L_Jᵀ = J A⁻¹ Jᵀ``, ``L_D L_Dᵀ = Dᵀ A⁻¹ D``),
whose condition number does not inherit that of ``A``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np


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

    and, for trajectories (defaults: absent):

    v : (n,)     velocities, for the reaction's power ``v·R``
    qdot : (nq,) kinematics ``q̇ = K(q, v, t)``
    energy :     total energy ``T + V`` (0 when unknown)
    F_nc : (n,)  non-conservative applied forces, for their power ``v·F`` (zeros when unknown)
    g : (k,)     holonomic residuals ``g(q, t)`` (0 on velocity-level rows)
    """

    A: ca.SX
    f: ca.SX
    r0: ca.SX
    J: ca.SX
    phi: ca.SX
    D: ca.SX
    Phi: ca.SX
    v: ca.SX | None = None
    qdot: ca.SX | None = None
    energy: ca.SX | None = None
    F_nc: ca.SX | None = None
    g: ca.SX | None = None


@dataclass(frozen=True)
class Reduced:
    """The step in whitened reaction space, see the module docstring.

    ``S_hat z = rhs_hat`` with ``z = R_D u`` (``R_DᵀR_D = H``), so that ``Z = ‖z‖²``.
    """

    S_hat: ca.SX
    S_norm: ca.SX
    rhs_hat: ca.SX
    RD: ca.SX
    R: ca.SX
    RJ: ca.SX
    a0: ca.SX
    AinvD: ca.SX
    a_free: ca.SX
    pivot: ca.SX


def _solve_upper(R: ca.SX, B: ca.SX) -> ca.SX:
    """``A⁻¹ B`` from the Cholesky factor ``RᵀR = A``."""
    return ca.solve(R, ca.solve(R.T, B))


def reduce(p: StepExpressions) -> Reduced:
    """Eliminate the acceleration: whitened reaction-space data and the positive-definiteness check."""
    R = ca.chol(p.A)
    a_free = _solve_upper(R, p.f)
    a0 = _solve_upper(R, p.f + p.r0)
    W = ca.solve(R.T, p.D)  # R⁻ᵀD, so H = WᵀW is formed as a sum of squares
    AinvD = ca.solve(R, W)
    Jt = ca.solve(R.T, p.J.T).T  # J R⁻¹
    RJ = ca.chol(Jt @ Jt.T)
    RD = ca.chol(W.T @ W)
    S = Jt @ W
    S_hat = ca.solve(RD.T, ca.solve(RJ.T, S).T).T
    S_norm = S / (ca.sqrt(ca.sum2(Jt * Jt)) @ ca.sqrt(ca.sum1(W * W)))
    rhs_hat = ca.solve(RJ.T, p.phi - p.J @ a0)
    diagR = ca.diag(R)
    # Relative smallest pivot: ≤ 0 when A is not positive definite. A failed factorization leaves NaN on
    # the diagonal, which casadi's fmin would skip (and NaN·0 simplifies to 0 in SX): NaN > 0 is false,
    # so each pivot that is not positive counts as −1.
    squares = diagR * diagR
    pivot = ca.mmin(ca.if_else(squares > 0, squares, -1)) / ca.mmax(ca.fabs(ca.diag(p.A)))
    if not ca.is_equal(p.A, p.A.T, 20):
        asym = ca.mmax(ca.fabs(p.A - p.A.T)) / ca.mmax(ca.fabs(p.A))
        pivot = ca.if_else(asym > 1e-12, -1.0, pivot)
    return Reduced(
        S_hat=S_hat, S_norm=S_norm, rhs_hat=rhs_hat, RD=RD, R=R, RJ=RJ, a0=a0, AinvD=AinvD, a_free=a_free, pivot=pivot
    )


#: Names of a step kernel's outputs, in order.
OUTPUTS = (
    "a",
    "u",
    "reaction",
    "compulsion",
    "S_norm",
    "residual",
    "Phi",
    "pivot",
    "a_free",
    "qp_primal",
    "qp_dual",
    "qdot",
    "energy",
    "power_reaction",
    "power_forces",
    "g",
    "checksum",
)


def _refine(p: StepExpressions, red: Reduced, z: ca.SX, u: ca.SX, a: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """One step of iterative refinement on ``A a − D u = f + r₀``, ``J a = φ`` (square ``S``).

    ``a = a₀ + A⁻¹D u`` cancels when ``A`` is ill-conditioned and the constraints nearly fix ``a``
    (losing up to ``cond(A)·ε`` of relative accuracy); the residuals of the original equations
    are formed without that cancellation, and one correction by the same reduction restores
    ``J a = φ`` and the dynamics to round-off.
    """
    r1 = p.f + p.r0 - (p.A @ a - p.D @ u)
    Ainv_r1 = _solve_upper(red.R, r1)
    r2 = p.phi - p.J @ (a + Ainv_r1)
    dz = ca.solve(red.S_hat, ca.solve(red.RJ.T, r2))
    du = ca.solve(red.RD, dz)
    return z + dz, u + du, a + Ainv_r1 + red.AinvD @ du


def well_conditioned_constant(A: ca.SX) -> bool:
    """A constant ``A`` with ``cond(A) < 10⁴`` loses at most ~1e-12 to the cancellation: no refinement needed."""
    if not A.is_constant():
        return False
    values = np.array(ca.DM(A))
    return bool(np.all(np.isfinite(values)) and np.linalg.cond(values) < 1e4)


def outputs(p: StepExpressions, red: Reduced, z: ca.SX, y: ca.SX | None, refine: bool = True) -> list[ca.SX]:
    """Everything a step reports, given the whitened reaction ``z`` (and the QP's multipliers ``y``).

    With ``refine`` (and a square ``S``) the solver's answer gets one step of iterative
    refinement (:func:`_refine`); the QP residuals always describe the solver's own answer.
    """
    z_solver = z
    u = ca.solve(red.RD, z)
    a = red.a0 + red.AinvD @ u
    if refine and red.S_hat.shape[0] == red.S_hat.shape[1] and not well_conditioned_constant(p.A):
        z, u, a = _refine(p, red, z, u, a)
    if y is None:
        primal = dual = ca.SX(0)
    else:  # relative residuals: scale-free, so one threshold fits every model
        tiny = 1e-300
        size_S, size_z = ca.mmax(ca.fabs(red.S_hat)), ca.mmax(ca.fabs(z_solver))
        primal = ca.mmax(ca.fabs(red.S_hat @ z_solver - red.rhs_hat)) / (
            ca.mmax(ca.fabs(red.rhs_hat)) + size_S * size_z + tiny
        )
        dual = ca.mmax(ca.fabs(z_solver + red.S_hat.T @ y)) / (size_z + size_S * ca.mmax(ca.fabs(y)) + tiny)
    return step_outputs(p, a, u, ca.sumsqr(z), red.S_norm, red.pivot, red.a_free, primal, dual)


def step_outputs(
    p: StepExpressions,
    a: ca.SX,
    u: ca.SX,
    compulsion: ca.SX,
    S_norm: ca.SX,
    pivot: ca.SX,
    a_free: ca.SX,
    primal: ca.SX,
    dual: ca.SX,
) -> list[ca.SX]:
    """The outputs :data:`OUTPUTS` of a step solved by either route (dense or :mod:`~gausspp.step.equality.sparse`)."""
    R = p.r0 + p.D @ u
    vel = p.v if p.v is not None else ca.SX.zeros(R.numel())
    values = [a, u, R, compulsion, S_norm, p.J @ a - p.phi, p.Phi, pivot, a_free, primal, dual]
    values += [
        p.qdot if p.qdot is not None else ca.SX(0, 1),
        p.energy if p.energy is not None else ca.SX(0),
        ca.dot(vel, R),
        ca.dot(vel, p.F_nc) if p.F_nc is not None else ca.SX(0),
        p.g if p.g is not None else ca.SX.zeros(p.Phi.numel()),
    ]
    # non-finite iff some output entry is (NaN and ±inf survive a sum): one number to check per step
    checksum = ca.SX(0)
    for value in values:
        checksum += ca.sum1(ca.vec(value))
    return [*values, checksum]
