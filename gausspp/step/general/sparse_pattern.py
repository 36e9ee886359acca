"""The compiled general step of a redundant linkage, in the mechanism's own sparsity.

A mechanism written in maximal coordinates with every joint's rows (a ladder of parallelograms, an
overconstrained loop) has a block-diagonal ``A`` and banded rows ``J``; when its realizations are ideal
(``D = Jᵀ``), its general step on an open piece of the manifold is the equality step of the *kept* rows ``K``
alone: the dropped rows are combinations of them and hold by themselves. The dense pattern of :mod:`.compiled`
whitens with a dense Cholesky factor of ``A`` and tests every dropped row against the kept ones one by one —
O(k³) nodes in the graph, 0.3 million at 82 rows. This call keeps the sparsity (casadi's symbolic sparse
``LDLᵀ`` with an approximate-minimum-degree order, as :mod:`gausspp.step.equality.sparse`), so that the graph grows with
the factors' entries:

* ``A = Pᵀ L diag(d) Lᵀ P``; ``a₀ = A⁻¹(f + r₀)``; rows normalized in ``A⁻¹``: ``Jn = J/‖J‖_{A⁻¹}``;
* the kept rows' Gram matrix ``G = Jn_K A⁻¹ Jn_Kᵀ`` (unit diagonal) by a sparse ``LDLᵀ``; ``G x = r_K`` with
  ``r = (φ − J a₀)/‖J‖_{A⁻¹}`` in the unit of :mod:`.scaling`. Near a singular position (a pivot of ``G`` below
  :data:`~.compiled.SINGULAR_BAND`) the flag is down and the Python step answers; elsewhere the kept rows'
  exact step, undamped (the dense pattern damps by ``drift · b²/(b² + σ⁴)``, which vanishes on the manifold);
* the multipliers: the least-norm split over all rows, as the dense pattern gives it, up to
  :data:`LEAST_NORM_ROWS` dropped rows (one more solve each); beyond, ``u_K = x/‖J_K‖`` and ``u_D = 0`` — the
  reaction is the same, its split among dependent rows is not unique, and for a long ladder the least-norm one
  would cost more than the step.

The dense pattern's watch, per dropped row, becomes one test of a fixed random combination ``ρ`` of the dropped
rows (one more sparse solve): ``j_ρ = ρᵀ Jn_D`` must lie in the kept rows' span (its sine in ``A⁻¹`` at most
:data:`~.redundancy.DEPENDENCE_TOL`), its right-hand side agree with theirs, and its residuals ``Φ``, ``g``
follow theirs (:data:`~.manifold.REACH_TOL`). A dropped row that leaves the span, or disagrees, moves the
combination with it unless ``ρ`` is orthogonal to the change — a set of measure zero the fixed ``ρ`` does not
meet by design. Plus the kept rows' ``LDLᵀ`` pivots (positive), ``A``'s pivots, finite inputs and outputs, and
the kept rows' feasibility. The step's ``S`` (dense ``k × m``) is not among the outputs: the margin of redundant
rows is zero by design.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..equality.sparse import sparse_reduce
from ..protocol import StepModel
from .drift import DRIFT_SLACK, SLACK_CAP, relative_drift
from .kept_rows import AGREEMENT_SLACK
from .manifold import REACH_TOL
from .redundancy import CLEARLY_INDEPENDENT, DEPENDENCE_TOL

#: From this many bilateral rows on, a pattern that can take this call takes it: on the double parallelogram
#: (12 rows) and larger, ``model.step`` is several times faster sparse than dense, the more so the more rows
#: (``benchmarks/general_step.py`` prints the figures).
SPARSE_FROM_ROWS = 8
#: ... and when ``A`` has at most this fraction of its entries.
SPARSE_DENSITY = 0.5
#: Up to this many dropped rows the multipliers are the least-norm split over all rows, as on the dense pattern;
#: beyond, the kept rows carry the reaction and the dropped rows' are 0. The split costs one solve per dropped row
#: and a product of their size, a cost that grows faster than the step's own with the number of dropped rows
#: (``benchmarks/general_step.py`` prints the ladder's figures).
LEAST_NORM_ROWS = 8
#: The fixed seed of the random combination of the dropped rows.
COMBINATION_SEED = 20261125


def applies(model: StepModel, kept_rows: tuple[int, ...], kept_cols: tuple[int, ...], closed: tuple[int, ...]) -> bool:
    """Whether a pattern takes this call: ideal rows (``S`` symmetric by construction), no contacts, no bounds, rows
    and columns kept alike, many rows and a sparse ``A``."""
    if closed or model.contact_row_names or model.bounded or kept_rows != kept_cols:
        return False
    if not getattr(model, "symmetric_S", False):
        return False
    if model.k < SPARSE_FROM_ROWS or model.k == len(kept_rows):
        return False
    A = model.expressions.A
    return ca.sparsify(A).nnz() <= SPARSE_DENSITY * A.shape[0] * A.shape[0]


def _combination(n: int) -> np.ndarray:
    """Fixed weights of magnitude 0.5 … 1.5 and random signs (the same for every call)."""
    rng = np.random.default_rng(COMBINATION_SEED)
    return rng.uniform(0.5, 1.5, n) * rng.choice([-1.0, 1.0], n)


def sparse_step(model: StepModel, kept: tuple[int, ...], tol: float, band: float, cap: float = SLACK_CAP) -> list[Any]:
    """The packed outputs of :data:`.compiled.FIELDS` (``S`` empty), the flag and the closed-contacts flag, as SX
    expressions of the model's inputs (module docstring). ``band``: below this smallest pivot of the kept rows'
    Gram matrix (unit diagonal) the flag is down — near a singular position the Python step answers."""
    p, mech = model.expressions, model.mechanism
    k, K = model.k, list(kept)
    D_rows = [i for i in range(k) if i not in kept]
    red = sparse_reduce(p)  # A's sparse LDLᵀ, a₀, A⁻¹f, A⁻¹Jᵀ (D = Jᵀ) and A's pivot, as the equality step's

    def solve_A(b: ca.SX) -> ca.SX:
        return ca.sparsify(red.solve_A(b))

    pivot_A, a_free, a0, AinvJt = red.pivot, red.a_free, red.a0, red.AinvD
    J = ca.sparsify(p.J)
    norms = ca.sqrt(ca.sum2(J * AinvJt.T))  # ‖Jᵢ‖ in A⁻¹
    norms = ca.if_else(norms > 0, norms, 1)
    Jn = ca.diag(1 / norms) @ J
    AinvJnt = AinvJt @ ca.diag(1 / norms)
    JnK, AinvJnK = Jn[K, :], AinvJnt[:, K]
    G = ca.sparsify(JnK @ AinvJnK)
    Ja0 = J @ a0
    r_raw = (p.phi - Ja0) / norms
    big = ca.mmax(ca.fabs(r_raw))
    unit = ca.if_else(big > 0, big, 1.0)
    r = r_raw / unit
    scale = (ca.mmax(ca.fabs(p.phi / norms)) + ca.mmax(ca.fabs(Ja0 / norms))) / unit

    # the kept rows' Gram matrix, factored as it is (pivots: independence) and damped near a singular position
    dG, LtG, pG = ca.ldl(G, True)
    pivots = ca.if_else(dG >= 0, dG, 0)  # NaN counts as 0
    smallest = ca.mmin(pivots)
    x = ca.ldl_solve(r[K], dG, LtG, pG)

    u = ca.SX.zeros(model.m)
    u_K = x * unit / norms[K]  # the kept rows' multipliers of the kept rows' own answer
    if D_rows and len(D_rows) <= LEAST_NORM_ROWS:
        # the least-norm split over dependent rows: J_D = C_uᵀ J_K (C_u from Jn_D = Cᵀ Jn_K, C = G⁻¹ Jn_K A⁻¹ Jn_Dᵀ),
        # so u_K − C_u u_D gives the same reaction for every u_D; the least ‖u‖ has (I + C_uᵀC_u) u_D = C_uᵀ u_K
        C = ca.ldl_solve(JnK @ AinvJnt[:, D_rows], dG, LtG, pG)
        C_u = ca.diag(1 / norms[K]) @ C @ ca.diag(norms[D_rows])
        u_D = ca.solve(ca.DM.eye(len(D_rows)) + C_u.T @ C_u, C_u.T @ u_K)
        u_K = u_K - C_u @ u_D
        u[D_rows] = u_D
    u[K] = u_K
    reaction_c = JnK.T @ x * unit  # J_Kᵀ u_K of the kept rows' own answer: the acceleration's
    a = a0 + AinvJnK @ x * unit
    # D = Jᵀ: with u_D = 0 the reaction is the kept rows' own (the same sum, computed once)
    reaction = p.r0 + (reaction_c if not D_rows or len(D_rows) > LEAST_NORM_ROWS else p.D @ u)
    residual = J @ a - p.phi

    # A positive definite; the kept rows clearly independent: in the band around a singular position (where the dense
    # pattern damps in proportion to the drift) the Python step answers (NaN fails too)
    checks = [pivot_A > 0, ca.mmin(dG) >= band]
    relax = ca.fmin(1, ca.sqrt(smallest) / CLEARLY_INDEPENDENT)
    singular = ca.logic_not(relax > 0)
    if D_rows:
        slack = ca.fmin(DRIFT_SLACK * relative_drift(model), cap)  # off the manifold by δ: O(δ) (.compiled)
        rho = ca.DM(_combination(len(D_rows)))
        j_rho = rho.T @ Jn[D_rows, :]
        Ainv_j = AinvJnt[:, D_rows] @ rho
        combo = ca.ldl_solve(JnK @ Ainv_j, dG, LtG, pG)  # j_ρ ≈ comboᵀ Jn_K
        rest = j_rho.T - JnK.T @ combo
        length = ca.sqrt(ca.fmax(ca.dot(j_rho.T, Ainv_j), 1e-300))
        sine = ca.sqrt(ca.fmax(ca.dot(rest, solve_A(rest)), 0)) / length
        checks.append(ca.logic_or(singular, sine * relax <= DEPENDENCE_TOL + slack))
        y_norm = ca.sqrt(ca.fmax(ca.dot(x, r[K]), 0))  # ‖y‖ of the kept rows' least-norm answer, in A⁻¹
        r_rho = ca.dot(rho, r[D_rows])
        miss = ca.fabs(r_rho - ca.dot(combo, r[K])) - AGREEMENT_SLACK * sine * length * y_norm
        agree = miss * relax <= (tol + slack) * ca.fmax(scale, 1e-300) * (
            ca.sum1(ca.fabs(rho)) + ca.sum1(ca.fabs(combo))
        )
        checks.append(ca.logic_or(singular, agree))
        # the witness that the dropped rows hold together: their residuals follow the kept rows' (to first order)
        w = combo / norms[K]  # in the rows' own units: Σ ρ_d J_d/‖J_d‖ ≈ Σ w_i J_i
        rho_u = rho / norms[D_rows]
        euclid = ca.fmax(ca.norm_2(j_rho), 1e-300)  # the combined row's length as a coordinate gradient
        v_size, q_size = 1 + ca.mmax(ca.fabs(mech.v)), 1 + ca.mmax(ca.fabs(mech.q))
        fit_v = (ca.dot(rho_u, p.Phi[D_rows]) - ca.dot(w, p.Phi[K])) / euclid
        # rows with a term of their own (a servo's prescribed speed: Φ = J v − b) pass on the error of w, which the
        # dropped rows' angle off the kept span makes (up to sine·length/smallest pivot of G), times b
        own = ca.fabs(p.Phi[K] - J[K, :] @ mech.v) / norms[K]
        noise = AGREEMENT_SLACK * sine * length * ca.sum1(own) / (ca.fmax(smallest, 1e-300) * euclid)
        # off the manifold (a Runge–Kutta stage) the combined row leaves the kept rows' span by its angle: what that
        # passes of v is not a contradiction
        angle = AGREEMENT_SLACK * ca.norm_2(rest) * ca.norm_2(mech.v) / euclid
        checks.append(ca.fabs(fit_v) <= (REACH_TOL + slack) * v_size * ca.sum1(ca.fabs(rho)) + noise + angle)
        hol = set(model.holonomic_rows)
        if p.g is not None and all(d in hol for d in D_rows) and all(i in hol for i in K):
            fit_g = (ca.dot(rho_u, p.g[D_rows]) - ca.dot(w, p.g[K])) / euclid
            checks.append(ca.fabs(fit_g) <= (REACH_TOL + slack) * q_size * ca.sum1(ca.fabs(rho)))
    feasible = ca.mmax(ca.fabs(G @ x - r[K])) / (1 + ca.mmax(ca.fabs(x)))
    checks.append(feasible <= 1e-9)

    outs = [
        a,
        u,
        reaction,
        ca.dot(reaction_c, a - a0),  # Z = rᵀ A⁻¹ r
        residual,
        p.Phi,
        a_free,
        ca.SX(0, 1),  # S: not computed in this call
        ca.SX(0),
        ca.SX.zeros(model.m),
        ca.SX(0),
        mech.qdot,
        mech.energy if mech.energy is not None else ca.SX(0),
        ca.dot(mech.v, mech.F_nc) if mech.F_nc is not None else ca.SX(0),
        ca.dot(mech.v, reaction),
        p.g if p.g is not None else ca.SX.zeros(k),
        ca.SX(0, 1),  # no contact rows in this call
    ]
    packed = ca.vertcat(*(ca.vec(ca.densify(ca.SX(o))) for o in outs))
    ins_finite = ca.fabs(sum(ca.sum1(ca.vec(s)) for s in model.inputs)) < ca.inf
    flag = ca.logic_and(ins_finite, ca.fabs(ca.sum1(packed)) < ca.inf)
    for chk in checks:
        flag = ca.logic_and(flag, chk)
    return [ca.vertcat(packed, flag, ca.SX(1))]
