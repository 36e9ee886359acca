"""Gauss's principle where no closed form exists: inequalities, bounds, tracking and redundancy.

The compiled step (:mod:`gausspp.step`) solves the square, equality-only case. This module
solves the *general* one at a single instant, numerically, with any backend of the registry
(:mod:`gausspp.step.qp`: the qpsolvers solvers and casadi's conic plugins; default
:data:`gausspp.step.qp.GENERAL_DEFAULTS`, daqp if installed, else OSQP) (docs/theory.md §3, last paragraph)::

    a = a₀ + A⁻¹ D u,    Z(u) = (A(a − a₀), a − a₀) = ‖W u‖²,   W = R⁻ᵀ D,  RᵀR = A

    minimize Z(u)  subject to
        J_e a  = φ_e                 bilateral constraints (hard)
        J_s a ≈ φ_s                  servo rows whose actuators are bounded (tracked, see below)
        J_c a ≥ φ_c                  closed unilateral contacts (second-order condition)
        lo ≤ u ≤ hi                  actuator bounds; contact forces u_c ≥ 0

Complementarity of contact forces comes from the QP's KKT conditions: a contact pushes only
while it would otherwise be violated. The problem is solved lexicographically, each stage a
convex QP, so every answer is exact (no penalty weight to tune):

1. **track** (only when bounded servo rows cannot be kept): minimize the tracking error
   ``Σᵢ (Jᵢ a − φᵢ)² / (Jᵢ A⁻¹ Jᵢᵀ)`` over those rows (plus a 1e-12 Tikhonov term on the
   unit-sized unknowns, so that over-actuated rows give every backend a definite Hessian) —
   for one row, exactly the compulsion an ideal constraint would need to correct the acceleration.
   Physically: a saturated actuator pushes at its bound in the direction that keeps the
   constraint best. The optimal error ``e*`` is unique; it is zero exactly when the bounds
   allow the constraint to be kept, and then the motion is the unbounded one.
2. **compulsion**: minimize ``Z`` with the tracked rows fixed at ``J_s a = φ_s + e*``.
   The acceleration is unique (``Z`` is strictly convex in ``a``). Without bounds the unknowns
   are the whitened reaction itself, ``w = W u = Q ξ`` with ``Q`` an orthonormal basis of
   ``range W`` (Hessian ``I``), however close the reaction columns are to dependent.
3. **least norm** (only when ``W`` has dependent columns, e.g. redundant constraint rows):
   among the reactions that give that acceleration, the one of least ``‖u‖``.

Redundant bilateral rows (:mod:`gausspp.step.redundancy`, :mod:`gausspp.step.kept_rows`): which rows are
kept — in the order declared, each independent of those before it — and whether the dropped ones agree is decided
on the constraint manifold (``reference``: the problem at the nearest state on it, see
:func:`solve_general`); the problem is then solved at the state with the kept rows, so the
acceleration is exactly the minimal model's, and the multiplier the least-norm one. Dependent
rows that disagree on the manifold are an error. A realization that cannot keep its
constraint (``rank S < rank J``: conditions (12)/(16)) is an error here as everywhere else.


Modules: :mod:`~gausspp.step.gauss_problem` (the data), :mod:`~gausspp.step.scaling` (the unit-free form),
:mod:`~gausspp.step.kept_rows` (the redundancy decision), :mod:`~gausspp.step.stage` (one stage by a backend,
and the feasibility and optimality checks), :mod:`~gausspp.step.dense` (their small linear algebra, through LAPACK);
here, the order of the stages.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .. import dense, qp
from ..qp import QP, QPBackend
from .gauss_problem import GaussProblem, GaussSolution, RowRoles, at, row_roles
from .kept_rows import NearManifold, Reference, decide_rows
from .redundancy import DEPENDENCE_TOL, chosen_rows
from .scaling import RANGE_TOL, RANK_TOL, Scaled, compress, range_basis, rank_of, scaled, svd_rank, truncated_pinv
from .stage import DUAL_TOL, FEASIBILITY_TOL, solve_stage

__all__ = [
    "CONSISTENCY_TOL",
    "DUAL_TOL",
    "FEASIBILITY_TOL",
    "RANK_TOL",
    "TRACK_REGULARIZATION",
    "GaussProblem",
    "GaussSolution",
    "check_backend",
    "default_backend",
    "resolve_backend",
    "solve_general",
]

#: Relative size of the part of the right-hand side outside the span of dependent rows deemed inconsistent.
CONSISTENCY_TOL = 1e-8
#: Tikhonov weight in the track stage (the problem is unit-sized): the tracking error is minimal to about this.
TRACK_REGULARIZATION = 1e-12


def default_backend() -> str:
    """The general QP's default backend by its short name (``"qrqp"``): :func:`.qp.default`."""
    return qp.short_name(qp.get(qp.default("general")))


def features(p: GaussProblem) -> frozenset[str]:
    """The QP forms (:data:`gausspp.step.qp.FORMS`) the stages of ``p`` may need."""
    roles = set(p.role)
    used = {"equality"}
    if np.isfinite(p.lower).any() or np.isfinite(p.upper).any():
        used.add("bounds")
    if "ge" in roles:
        used.add("inequalities")
    if "track" in roles:
        used.add("least-squares")
    return frozenset(used)


def resolve_backend(name: str | QPBackend | None, p: GaussProblem | None = None) -> QPBackend:
    """The registry's backend for ``name`` (``None``: the general default), checked against ``p``'s forms."""
    backend = qp.get(qp.default("general") if name is None else name)
    return backend if p is None else qp.require(backend, features(p))


def check_backend(name: str | QPBackend | None) -> str:
    """The short name (:func:`gausspp.step.qp.short_name`) of the general QP's backend for ``name``.

    Resolved through the registry only: ``"daqp"`` → ``"daqp"`` (qpsolvers), ``"casadi:qrqp"`` → ``"casadi:qrqp"``;
    an unknown name is an :class:`~gausspp.errors.UnknownNameError`, an uninstalled one a
    :class:`~gausspp.errors.BackendUnavailableError`.
    """
    return qp.short_name(resolve_backend(name))


@dataclass(frozen=True)
class _Setup:
    """What every stage of one step shares (unit-sized, unknowns scaled to ``ũ = cs ⊙ u``)."""

    p: GaussProblem
    s: Scaled
    kept: np.ndarray  # bilateral rows kept
    track: np.ndarray  # indices of tracked (bounded servo) rows
    ge: np.ndarray  # mask of contact rows
    G: np.ndarray  # contact rows as G ũ ≤ h
    h: np.ndarray
    lo: np.ndarray  # bounds on ũ
    hi: np.ndarray
    bounded: bool
    Ws: np.ndarray  # W / cs
    rank_W: int  # rank of the reaction columns, judged at the reference
    kept_cols: np.ndarray  # the reaction columns independent of those before them, at the reference
    Q: np.ndarray | None  # without bounds: an orthonormal basis of range(Ws) (the compulsion stage's unknowns)
    backend: QPBackend
    where: str

    @classmethod
    def build(cls, p: GaussProblem, s: Scaled, ref: Scaled, kept: np.ndarray, backend: QPBackend) -> _Setup:
        rows = row_roles(p)
        ge = rows.ge
        lo, hi = np.asarray(p.lower, float) / s.unit * s.cs, np.asarray(p.upper, float) / s.unit * s.cs
        bounded = bool(np.isfinite(lo).any() or np.isfinite(hi).any())
        Ws = s.W / s.cs
        # dependent reaction columns (judged at the reference, with the rows' dependence tolerance): their
        # least-norm multiplier leaves out the directions that only the drift separates. Without bounds the
        # compulsion stage needs the SVD of Ws itself: one SVD serves both when the reference is the state.
        Q = None
        if bounded:
            sv = dense.singular_values(ref.W / ref.cs)
        elif ref is s:
            U, sv, _ = dense.svd(Ws)
            Q = U[:, : rank_of(sv, RANGE_TOL)]
        else:
            sv = dense.singular_values(ref.W / ref.cs)
            Q = range_basis(Ws)
        return cls(
            p,
            s,
            kept,
            rows.tracked,
            ge,
            -s.S[ge],
            -s.r[ge],
            lo,
            hi,
            bounded,
            Ws,
            rank_of(sv, DEPENDENCE_TOL),
            _kept_cols(p, ref, kept, rows),
            Q,
            backend,
            at(p.t),
        )


def _kept_cols(p: GaussProblem, ref: Scaled, kept: np.ndarray, rows: RowRoles) -> np.ndarray:
    """The reaction columns kept: those of the kept rows where the reactions are the rows themselves (``D = Jᵀ``,
    every row an equality: the columns of ``W`` are the whitened rows, and the rows' choice, held or pivoted, is
    theirs); otherwise the columns independent of those before them (:func:`~.redundancy.chosen_rows`)."""
    if rows.eq.all() and p.D.shape == p.J.T.shape and np.array_equal(p.D, p.J.T):
        return np.asarray(kept, dtype=int)
    return chosen_rows((ref.W / ref.cs).T, DEPENDENCE_TOL)[0]


def _compulsion(
    c: _Setup, rows: np.ndarray, rhs: np.ndarray, infeasible_ok: bool = False
) -> tuple[np.ndarray, np.ndarray | None] | None:
    """The whitened reaction ``w = W u`` of least ``‖w‖² = Z`` with ``rows · L⁻ᵀ w = rhs`` (rows of ``Jn``),
    and the scaled unknowns ``ũ`` when bounds act on them; ``None`` if infeasible and ``infeasible_ok``."""
    m = c.Ws.shape[1]
    if c.bounded:  # bounds act on u itself
        E, e = compress(rows @ c.Ws, rhs)
        st = QP(c.Ws.T @ c.Ws, np.zeros(m), E, e, c.G, c.h, c.lo, c.hi, "compulsion")
        x = solve_stage(st, c.backend, c.where, infeasible_ok)
        return None if x is None else (c.Ws @ x, x)
    # no bounds: the unknowns are the reaction itself, w = Q ξ with Q an orthonormal basis of range(W) at this
    # state (Hessian I for every backend, however close the reaction columns are to dependent). Off the
    # manifold redundant columns are independent by the drift; range(W) still holds the kept rows'
    # reactions there, so the acceleration is exactly the minimal model's.
    Q = c.Q
    assert Q is not None
    E, e = compress(rows @ Q, rhs)
    free = np.full(Q.shape[1], np.inf)
    st = QP(np.eye(Q.shape[1]), np.zeros(Q.shape[1]), E, e, -c.s.Jn[c.ge] @ Q, c.h, -free, free, "compulsion")
    xi = solve_stage(st, c.backend, c.where, infeasible_ok)
    return None if xi is None else (Q @ xi, None)


def _reaction(c: _Setup, stages: list[str]) -> tuple[np.ndarray, np.ndarray | None, float]:
    """Stages 1–2 of the module docstring: ``(w, ũ or None, tracking error)`` at unit size."""
    s, kept, track = c.s, c.kept, c.track
    if track.size:  # first as if the bounds allowed the constraint to be kept: then nothing saturates
        both = np.concatenate([kept, track])
        stages.append("compulsion")
        found = _compulsion(c, s.Jn[both], s.r[both], True)
        if found is not None:
            return found[0], found[1], 0.0
        # saturated: the least tracking error first, then the least compulsion
        stages.append("track")
        St, rt = s.S[track], s.r[track]
        m = St.shape[1]
        # ‖S ũ − r‖² is only semidefinite when there are more actuators than rows; a Tikhonov term of
        # TRACK_REGULARIZATION (on the unit-sized problem) makes it definite for every backend
        E, e = compress(s.S[kept], s.r[kept])
        st = QP(St.T @ St + TRACK_REGULARIZATION * np.eye(m), -St.T @ rt, E, e, c.G, c.h, c.lo, c.hi, "track")
        x_track = solve_stage(st, c.backend, c.where)
        assert x_track is not None
        # at the onset of saturation the error may be round-off small: the actuator is at its bound either way
        tracking_error = float(np.linalg.norm(St @ x_track - rt))
        found = _compulsion(c, s.Jn[both], np.concatenate([s.r[kept], St @ x_track]))
        assert found is not None
        return found[0], found[1], tracking_error
    stages.append("compulsion")
    found = _compulsion(c, s.Jn[kept], s.r[kept])
    assert found is not None
    return found[0], found[1], 0.0


def _least_norm(c: _Setup, w: np.ndarray, x: np.ndarray | None, stages: list[str]) -> np.ndarray:
    """Stage 3: the reaction unknowns ``u`` (unit-sized) of least norm among those with ``W u = w``."""
    s, m = c.s, c.Ws.shape[1]
    u = x / s.cs if x is not None else truncated_pinv(s.W, c.rank_W) @ w
    if c.rank_W < m:
        stages.append("least-norm")
        if c.bounded:  # least ‖u‖ within the bounds, W u = w on the row space of W
            VtW = svd_rank(s.W)[2]
            rows, rhs = VtW[: c.rank_W], VtW[: c.rank_W] @ u
            st = QP(
                np.diag(s.cs**-2.0),
                np.zeros(m),
                rows / s.cs,
                rhs,
                np.zeros((0, m)),
                np.zeros(0),
                c.lo,
                c.hi,
                "least-norm",
            )
            x_norm = solve_stage(st, c.backend, c.where)
            assert x_norm is not None
            u = x_norm / s.cs
    return u


def _solution(
    c: _Setup, u: np.ndarray, w: np.ndarray, tracking_error: float, stages: list[str], redundant: int
) -> GaussSolution:
    """Back to the problem's units; a saturated actuator delivers exactly its bound."""
    p, s = c.p, c.s
    lo, hi = np.asarray(p.lower, float), np.asarray(p.upper, float)
    u, tracking_error = u * s.unit, tracking_error * s.unit
    finite_lo, finite_hi = np.isfinite(lo), np.isfinite(hi)
    if finite_lo.any() or finite_hi.any():
        u = np.clip(u, lo, hi)
        tol = 1e-9 * (1.0 + np.abs(u))
        at_lo, at_hi = finite_lo & (u - lo <= tol), finite_hi & (hi - u <= tol)
    else:  # no bounds: nothing to clip, nothing at a bound
        at_lo = at_hi = np.zeros(u.size, bool)
    if c.bounded:  # a saturated actuator delivers its bound (not the backend's round-off of it): the reaction
        u = np.where(at_hi, hi, np.where(at_lo, lo, u))
        w = s.W @ u / s.unit
    reaction = w * s.unit
    a = p.a0 + dense.solve(s.L.T, reaction)
    return GaussSolution(
        a=a,
        u=u,
        compulsion=float(reaction @ reaction),
        residual=p.J @ a - p.phi,
        tracking_error=tracking_error,
        at_bound=at_lo | at_hi,
        stages=stages,
        redundant_rows=redundant,
        S_norm=s.S,
        kept_rows=tuple(int(i) for i in c.kept),
        kept_cols=tuple(int(j) for j in c.kept_cols),
    )


def solve_general(
    p: GaussProblem,
    backend: str | QPBackend | None = None,
    consistency_tol: float = CONSISTENCY_TOL,
    reference: Reference = None,
    near_manifold: NearManifold = False,
    kept_before: tuple[int, ...] | None = None,
) -> GaussSolution:
    """Solve the general Gauss step (see the module docstring) with a registry ``backend``.

    ``backend``: a name of :func:`gausspp.step.qp.names` (or a bare solver name, or a backend); default
    :func:`gausspp.step.qp.default` ``("general")``. ``reference``: the same problem at the nearest state on the
    constraint manifold, or a function that builds it (called only when the rows at ``p`` are nearly but not
    clearly dependent, or disagree, or rows were dropped and ``near_manifold`` is false). Which bilateral rows are
    redundant, and whether they agree, is decided there (:mod:`gausspp.step.kept_rows`); ``p`` is then solved with
    the kept rows. ``near_manifold``: the state itself satisfies the constraints to within the caller's
    tolerance, so dropped rows need no reference to show that they can hold together (or a function that
    tells, called only when rows were dropped). ``kept_before``: the rows the decision on the open piece of the
    manifold kept (:func:`~gausspp.step.general.kept_rows.decide_rows`). ``consistency_tol``: how
    far (relative) dependent rows may disagree at the reference before it is an error.

    Raises
    ------
    UnknownNameError, BackendUnavailableError
        ``backend`` is not a backend name, or not installed here.
    InputError
        ``backend`` does not solve the QP forms ``p`` needs (the message names those that do).
    NotPositiveDefiniteError
        ``A`` is not symmetric positive definite.
    RealizabilityError
        A realization cannot keep its constraint (``rank S < rank J`` on bilateral rows), or
        dependent bilateral rows contradict each other.
    QPSolveError
        The backend found no solution (e.g. contacts and bounds that contradict each other), or its
        answer fails the feasibility (:data:`FEASIBILITY_TOL`) or optimality (:data:`DUAL_TOL`) check.
    """
    chosen = resolve_backend(backend, p)
    s = scaled(p)
    rows = decide_rows(p, s, consistency_tol, reference, near_manifold, kept_before)
    setup = _Setup.build(p, s, rows.ref, rows.kept, chosen)
    stages: list[str] = []
    w, x, tracking_error = _reaction(setup, stages)
    u = _least_norm(setup, w, x, stages)
    solution = replace(_solution(setup, u, w, tracking_error, stages, rows.redundant), kept_sine=rows.sine)
    return replace(solution, isolated_rank_drop=True) if rows.isolated else solution
