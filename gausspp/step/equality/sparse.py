"""The sparse step route: the step of :mod:`.expressions` with the sparsity of ``A``, ``J``, ``D`` kept.

The dense route whitens the reaction space with Cholesky factors ``L_J``, ``L_D`` of ``J A⁻¹ Jᵀ`` and
``Dᵀ A⁻¹ D``: robust to a badly conditioned ``A``, but their inverses are dense, so the graph has O(k³)
nodes. A mechanism of many bodies in maximal coordinates has a block-diagonal ``A`` and banded ``J`` and
``D`` (each joint couples two bodies): this route eliminates in the mechanism's own sparsity instead,

* ``A = Pᵀ L diag(d) Lᵀ P`` — casadi's symbolic sparse LDLᵀ with an approximate-minimum-degree order;
* ``a₀ = A⁻¹(f + r₀)``, ``A⁻¹D`` and ``S = J A⁻¹ D`` — as sparse as the mechanism's graph makes them;
* ``S u = φ − J a₀`` by a sparse LDLᵀ when the realization is ideal (``D = Jᵀ``: ``S`` symmetric positive
  definite), by a sparse Householder QR (minimum-degree column order) otherwise;
* ``q̈ = a₀ + A⁻¹ D u`` — then one step of iterative refinement on the original equations.

Entries casadi proves to vanish are dropped (``ca.sparsify``) before each factorization, so the ordering
sees the true pattern and the graph has as many nodes as the factors have entries: linear in the number of
bodies for chains and trees (Baraff's observation, here left to casadi's sparse factorizations). The QP
poses ``min ½ uᵀ H u`` with ``H = Dᵀ A⁻¹ D`` subject to ``S u = φ − J a₀`` with both matrices sparse.
The outputs are those of :data:`~gausspp.step.equality.expressions.OUTPUTS`, with the same meaning.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from ...errors import UnknownNameError
from .expressions import StepExpressions, step_outputs

ROUTES = ("auto", "dense", "sparse")

#: ``route="auto"`` takes the sparse route from this many constraint rows on (at 8 rows — four links — the
#: sparse direct step is already clearly faster on the planar chain, ``benchmarks/scaling.py`` prints it; below
#: it the dense route's whitening keeps its robustness to a badly conditioned ``A`` at no cost that matters).
SPARSE_FROM_ROWS = 8

#: ... and when ``A`` has at most this fraction of its entries (a mechanism of many bodies: block diagonal).
SPARSE_DENSITY = 0.5


def choose_route(p: StepExpressions, route: str = "auto") -> str:
    """The route of the step ``p``: ``route`` itself, or for ``"auto"`` the sparse one for
    :data:`SPARSE_FROM_ROWS` rows or more and a mass matrix no denser than :data:`SPARSE_DENSITY`."""
    if route not in ROUTES:
        raise UnknownNameError(f"route={route!r} is unknown; use one of {list(ROUTES)}")
    if route != "auto":
        return route
    n = p.A.shape[0]
    sparse_A = ca.sparsify(p.A).nnz() <= SPARSE_DENSITY * n * n
    return "sparse" if p.J.shape[0] >= SPARSE_FROM_ROWS and sparse_A else "dense"


@dataclass(frozen=True)
class SparseReduced:
    """The step eliminated in the mechanism's sparsity (module docstring): the factors and the reduced data."""

    dA: ca.SX  # LDLᵀ of A: pivots, strictly upper Lᵀ, order pA
    LtA: ca.SX
    a_free: ca.SX
    a0: ca.SX
    AinvD: ca.SX
    S: ca.SX
    S_norm: ca.SX
    rhs: ca.SX
    pivot: ca.SX
    fS: ca.SX  # factors of S: LDLᵀ (pivots, Lᵀ) or QR (V, R, β)
    gS: ca.SX
    hS: ca.SX
    pA: list[int] = field(default_factory=list)
    orders: tuple[list[int], ...] = ()  # the order(s) of the factorization of S
    symmetric: bool = True

    def solve_A(self, b: ca.SX) -> ca.SX:
        """``A⁻¹ b``."""
        return ca.ldl_solve(b, self.dA, self.LtA, self.pA)

    def solve_S(self, b: ca.SX) -> ca.SX:
        """``S⁻¹ b`` (square ``S``)."""
        if self.symmetric:
            return ca.ldl_solve(b, self.fS, self.gS, self.orders[0])
        return ca.qr_solve(b, self.fS, self.gS, self.hS, self.orders[0], self.orders[1], False)


def is_ideal(p: StepExpressions) -> bool:
    """Whether the reaction directions are the constraint normals (``D = Jᵀ``, so that ``S`` is symmetric)."""
    return p.D.shape == p.J.T.shape and bool(ca.is_equal(p.D, p.J.T, 64))


def sparse_reduce(p: StepExpressions) -> SparseReduced:
    """Eliminate the acceleration in the sparsity of ``A``, ``J``, ``D`` (module docstring)."""
    dA, LtA, pA = ca.ldl(ca.sparsify(p.A), True)

    def solve_A(b: ca.SX) -> ca.SX:
        return ca.sparsify(ca.ldl_solve(b, dA, LtA, pA))

    a_free, a0 = solve_A(p.f), solve_A(p.f + p.r0)
    AinvD = solve_A(p.D)
    ideal = is_ideal(p)
    AinvJt = AinvD if ideal else solve_A(p.J.T)
    S = ca.sparsify(p.J @ AinvD)
    rhs = p.phi - p.J @ a0
    row = ca.sqrt(ca.sum2(p.J * AinvJt.T))  # √(J A⁻¹ Jᵀ)ᵢᵢ: the rows' lengths in the metric A⁻¹
    col = ca.sqrt(ca.sum1(p.D * AinvD))  # √(Dᵀ A⁻¹ D)ⱼⱼ: the directions' lengths
    S_norm = ca.diag(1 / row) @ S @ ca.diag(1 / col.T)
    k, m = S.shape
    empty: list[int] = []
    if k == 0 or m == 0:
        fS = gS = hS = ca.SX(0, 1)
        orders: tuple[list[int], ...] = (empty, empty)
    elif ideal:
        fS, gS, order = ca.ldl(S, True)
        hS, orders = ca.SX(0, 1), (order,)
    else:
        fS, gS, hS, prinv, pc = ca.qr_sparse(S, True)
        orders = (prinv, pc)
    # Relative smallest pivot of A: ≤ 0 when A is not positive definite (NaN counts as −1, see expressions.reduce).
    pivot = ca.mmin(ca.if_else(dA > 0, dA, -1)) / ca.mmax(ca.fabs(ca.diag(p.A)))
    if not ca.is_equal(p.A, p.A.T, 20):
        asym = ca.mmax(ca.fabs(p.A - p.A.T)) / ca.mmax(ca.fabs(p.A))
        pivot = ca.if_else(asym > 1e-12, -1.0, pivot)
    return SparseReduced(
        dA=dA,
        LtA=LtA,
        a_free=a_free,
        a0=a0,
        AinvD=AinvD,
        S=S,
        S_norm=S_norm,
        rhs=rhs,
        pivot=pivot,
        fS=fS,
        gS=gS,
        hS=hS,
        pA=list(pA),
        orders=tuple(list(o) for o in orders),
        symmetric=ideal,
    )


def row_scales(red: SparseReduced) -> ca.SX:
    """``1/‖Sᵢ‖`` (1 for a zero row): the QP's rows scaled to unit length, as in the dense route."""
    norms = ca.sqrt(ca.sum2(red.S * red.S))
    return ca.if_else(norms > 0, 1 / norms, 1)


def qp_matrices(red: SparseReduced, p: StepExpressions, rows: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """The QP ``min ½ uᵀ H u`` s.t. ``S' u = r'``: ``H = Dᵀ A⁻¹ D`` (symmetrized), the rows of ``S`` and ``r``
    scaled by ``rows``."""
    H = ca.sparsify(p.D.T @ red.AinvD)
    return 0.5 * (H + H.T), ca.diag(rows) @ red.S, rows * red.rhs


def sparse_outputs(
    p: StepExpressions, red: SparseReduced, u: ca.SX, y: ca.SX | None, refine: bool, rows: ca.SX | None = None
) -> list[ca.SX]:
    """The step's :data:`~.expressions.OUTPUTS` from the reaction unknowns ``u`` (and, for a QP, its
    multipliers ``y`` of the rows scaled by ``rows``: the QP residuals describe the solver's own answer)."""
    u_solver = u
    a = red.a0 + red.AinvD @ u
    if refine and red.S.shape[0] == red.S.shape[1] and red.S.shape[0] > 0:
        r1 = p.f + p.r0 - (p.A @ a - p.D @ u)
        Ainv_r1 = red.solve_A(r1)
        du = red.solve_S(p.phi - p.J @ (a + Ainv_r1))
        u, a = u + du, a + Ainv_r1 + red.AinvD @ du
    compulsion = ca.dot(p.D @ u, red.AinvD @ u)  # uᵀ Dᵀ A⁻¹ D u
    if y is None:
        primal = dual = ca.SX(0)
    else:  # relative residuals of the scaled QP, as the dense route's
        assert rows is not None
        H, S, rhs = qp_matrices(red, p, rows)
        tiny = 1e-300
        size_S, size_u = ca.mmax(ca.fabs(S)), ca.mmax(ca.fabs(u_solver))
        primal = ca.mmax(ca.fabs(S @ u_solver - rhs)) / (ca.mmax(ca.fabs(rhs)) + size_S * size_u + tiny)
        Hu = H @ u_solver
        dual = ca.mmax(ca.fabs(Hu + S.T @ y)) / (ca.mmax(ca.fabs(Hu)) + size_S * ca.mmax(ca.fabs(y)) + tiny)
    return step_outputs(p, a, u, compulsion, red.S_norm, red.pivot, red.a_free, primal, dual)
