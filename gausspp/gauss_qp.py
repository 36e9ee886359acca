"""Gauss's principle where no closed form exists: inequalities, bounds, tracking and redundancy.

The compiled step (:mod:`gausspp.step`) solves the square, equality-only case. This module
solves the *general* one at a single instant, numerically, with any QP backend qpsolvers
finds (DESIGN §3, last paragraph)::

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
   The acceleration is unique (``Z`` is strictly convex in ``a``).
3. **least norm** (only when ``W`` has dependent columns, e.g. redundant constraint rows):
   among the reactions that give that acceleration, the one of least ``‖u‖``.

Dependent equality rows are compressed to an orthonormal basis of their span (SVD) before
the QP sees them; that is the documented rule for redundant constraints: if the rows are
consistent, the unique acceleration and the least-norm multiplier; if not, an error.
A realization that cannot keep its constraint (``rank S < rank J``: conditions (12)/(16))
is an error here as everywhere else.
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import qpsolvers
import scipy.sparse as sp

from .errors import (
    BackendUnavailableError,
    NonFiniteError,
    NotPositiveDefiniteError,
    QPSolveError,
    RealizabilityError,
    ShapeError,
    UnknownNameError,
)
from .qp.casadi_conic import stdout_silenced
from .qp.qpsolvers_route import OPTIONS

#: Singular values below this fraction of the largest count as zero (rows are normalized first).
RANK_TOL = 1e-9
#: Relative size of the part of the right-hand side outside the span of dependent rows deemed inconsistent.
CONSISTENCY_TOL = 1e-8
#: Relative violation of a stage's constraints above which the backend is deemed to have failed.
FEASIBILITY_TOL = 1e-7
#: Tikhonov weight in the track stage (the problem is unit-sized): the tracking error is minimal to about this.
TRACK_REGULARIZATION = 1e-12
#: A point the backend itself calls inaccurate is accepted only if it is optimal to this (the problems are unit-sized).
INACCURATE_KKT_TOL = 1e-10
#: Backends that print to the C-level stdout (silenced around their calls; that costs tens of µs).
CHATTY = ("osqp", "qpoases", "highs")
#: Backends tried in this order when none is named: a dense active-set one, then OSQP (always installed).
PREFERRED = ("daqp", "osqp")


def default_backend() -> str:
    """The first of :data:`PREFERRED` installed here."""
    for name in PREFERRED:
        if name in qpsolvers.available_solvers:
            return name
    raise BackendUnavailableError("neither daqp nor osqp is installed: `pip install osqp`")


def check_backend(name: str | None) -> str:
    """A qpsolvers solver name for the general QP (``"osqp"``, ``"qpsolvers:daqp"``, ...).

    The compiled route's names map to their qpsolvers counterpart (``"casadi:osqp"`` → ``"osqp"``);
    a compiled plugin qpsolvers does not have (``"casadi:qrqp"``, the compiled default) maps to
    :func:`default_backend`.
    """
    if name is None:
        return default_backend()
    route, _, bare = name.rpartition(":")
    if route == "casadi":
        return bare if bare in qpsolvers.available_solvers else default_backend()
    if bare not in qpsolvers.available_solvers:
        raise UnknownNameError(
            f"QP backend {name!r} is not a qpsolvers solver installed here; "
            f"the general Gauss QP can use {sorted(qpsolvers.available_solvers)}"
        )
    return bare


@dataclass(frozen=True)
class GaussProblem:
    """One instant of the general problem (see the module docstring).

    Attributes
    ----------
    A : (n, n)         kinetic-energy matrix
    a0 : (n,)          ``A⁻¹(f + r₀)``, the acceleration with ``u = 0``
    D : (n, m)         reaction directions
    J : (k, n)         rows of every constraint
    phi : (k,)         right-hand sides
    kind : (k,) str    ``"eq"``, ``"track"`` or ``"ge"`` per row
    lower, upper : (m,) bounds on ``u`` (``±inf`` when free)
    rows : names of the rows, for messages
    t : time, for messages
    """

    A: np.ndarray
    a0: np.ndarray
    D: np.ndarray
    J: np.ndarray
    phi: np.ndarray
    kind: Sequence[str]
    lower: np.ndarray
    upper: np.ndarray
    rows: Sequence[str] = ()
    t: float = float("nan")

    def __post_init__(self) -> None:
        n = self.A.shape[0]
        m = self.D.shape[1] if self.D.ndim == 2 else -1
        k = self.J.shape[0] if self.J.ndim == 2 else -1
        expected = {
            "A": (self.A.shape, (n, n)),
            "a0": (self.a0.shape, (n,)),
            "D": (self.D.shape, (n, m)),
            "J": (self.J.shape, (k, n)),
            "phi": (self.phi.shape, (k,)),
            "lower": (self.lower.shape, (m,)),
            "upper": (self.upper.shape, (m,)),
        }
        for name, (got, want) in expected.items():
            if got != want:
                raise ShapeError(f"GaussProblem: {name} has shape {got}, expected {want}")
        if len(self.kind) != k or not set(self.kind) <= {"eq", "track", "ge"}:
            raise ShapeError(f"GaussProblem: kind needs one of 'eq', 'track', 'ge' per row ({k} rows)")
        for name in ("A", "a0", "D", "J", "phi"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise NonFiniteError(f"GaussProblem: {name} is not finite{_at(self.t)}")
        if np.any(self.lower > self.upper):
            raise ShapeError(f"GaussProblem: a lower bound exceeds its upper bound{_at(self.t)}")


@dataclass(frozen=True)
class GaussSolution:
    """The general step's answer.

    Attributes
    ----------
    a : (n,)              the acceleration
    u : (m,)              the reaction unknowns (least norm when not unique)
    compulsion : float    ``Z = ‖W u‖²``
    residual : (k,)       ``J a − φ`` per row (≥ 0 on contacts, the tracking error on bounded servo rows)
    tracking_error : float  ``(Σᵢ (Jᵢ a − φᵢ)² / (Jᵢ A⁻¹ Jᵢᵀ))^½`` over tracked rows (0 unless saturated)
    at_bound : (m,) bool  reaction components at one of their bounds (finite bounds only)
    stages : list of str  which stages ran (``track``, ``compulsion``, ``least-norm``)
    S_norm : (k, m)       ``J A⁻¹ D`` with rows and columns normalized in ``A⁻¹`` (the realizability cosines)
    redundant_rows : int  how many equality rows were dependent on the others
    """

    a: np.ndarray
    u: np.ndarray
    compulsion: float
    residual: np.ndarray
    tracking_error: float
    at_bound: np.ndarray
    stages: list[str] = field(default_factory=list)
    redundant_rows: int = 0
    S_norm: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))


def _at(t: float) -> str:
    return "" if np.isnan(t) else f" at t={t:.6g}"


def _svd_rank(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    if M.size == 0:
        return np.zeros((M.shape[0], 0)), np.zeros(0), np.zeros((0, M.shape[1])), 0
    U, s, Vt = np.linalg.svd(M, full_matrices=False)
    rank = int(np.sum(s > RANK_TOL * max(s[0], 1e-300))) if s.size else 0
    return U, s, Vt, rank


@dataclass
class _Stage:
    """``min ½xᵀPx + qᵀx`` s.t. ``E x = e``, ``G x ≤ h``, ``lo ≤ x ≤ hi``."""

    P: np.ndarray
    q: np.ndarray
    E: np.ndarray
    e: np.ndarray
    G: np.ndarray
    h: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    name: str


def _solve_stage(st: _Stage, backend: str, where: str, infeasible_ok: bool = False) -> np.ndarray | None:
    """One stage by the backend; ``None`` instead of an error when ``infeasible_ok`` and no point is found."""
    m = st.q.size
    if m == 0:  # nothing to choose
        return np.zeros(0)
    if st.E.size == 0 and st.G.size == 0 and np.all(st.lo <= 0) and np.all(st.hi >= 0) and not np.any(st.q):
        return np.zeros(m)  # unconstrained, and u = 0 minimizes the (convex, zero-gradient) objective
    sparse = backend not in qpsolvers.dense_solvers

    def mat(M: np.ndarray) -> Any:
        return sp.csc_matrix(M) if sparse else M

    problem = qpsolvers.Problem(
        mat(st.P),
        st.q,
        G=mat(st.G) if st.G.size else None,
        h=st.h if st.G.size else None,
        A=mat(st.E) if st.E.size else None,
        b=st.e if st.E.size else None,
        lb=st.lo if np.any(np.isfinite(st.lo)) else None,
        ub=st.hi if np.any(np.isfinite(st.hi)) else None,
    )
    try:
        with warnings.catch_warnings(), stdout_silenced() if backend in CHATTY else contextlib.nullcontext():
            warnings.simplefilter("ignore")  # the backends' own status warnings: judged below
            sol = qpsolvers.solve_problem(problem, solver=backend, **OPTIONS.get(backend, {}))
    except Exception as exc:  # the backend's own error, re-raised as ours
        hint = (
            " — it needs a positive definite Hessian, which redundant constraint rows or extra actuators make "
            "singular: use daqp or osqp"
            if "positive definite" in str(exc)
            else ""
        )
        raise QPSolveError(f"{backend} failed on the {st.name} stage of the Gauss QP{where}: {exc}{hint}") from exc
    x = sol.x
    # a point the backend calls inaccurate (OSQP's "solved inaccurate" at its iteration limit) counts only if it
    # satisfies the optimality conditions on the unit-sized problem: primal and dual residuals and duality gap
    if not sol.found and x is not None:
        try:
            optimal = bool(sol.is_optimal(INACCURATE_KKT_TOL))
        except (TypeError, ValueError):  # no multipliers to judge with
            optimal = False
        if not optimal:
            x = None
    if x is None or not np.all(np.isfinite(x)):
        if infeasible_ok:
            return None
        raise QPSolveError(
            f"{backend} found no solution of the {st.name} stage of the Gauss QP{where}; "
            "the contacts, bounds and constraints may contradict each other — check the state, or try another backend"
        )
    x = np.asarray(x, float)
    scale = 1.0 + float(np.max(np.abs(x), initial=0.0))
    viol = 0.0
    if st.E.size:
        viol = max(viol, float(np.max(np.abs(st.E @ x - st.e))) / (scale * (1 + np.max(np.abs(st.E)))))
    if st.G.size:
        viol = max(viol, float(np.max(st.G @ x - st.h, initial=0.0)) / (scale * (1 + np.max(np.abs(st.G)))))
    viol = max(viol, float(np.max(st.lo - x, initial=0.0)) / scale, float(np.max(x - st.hi, initial=0.0)) / scale)
    if viol > FEASIBILITY_TOL:
        if infeasible_ok:
            return None
        raise QPSolveError(
            f"{backend} returned a point that violates the {st.name} stage's constraints by {viol:.2e}{where}; "
            "try another backend (daqp is exact, osqp iterative)"
        )
    return np.clip(x, st.lo, st.hi)


def _compress(S: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Rows ``S u = r`` → an orthonormal basis of their span; returns (rows, rhs, inconsistency, rank)."""
    U, s, Vt, rank = _svd_rank(S)
    rows, rhs = Vt[:rank], (U[:, :rank].T @ r) / s[:rank]
    outside = r - U[:, :rank] @ (U[:, :rank].T @ r)
    return rows, rhs, float(np.linalg.norm(outside)), rank


def solve_general(
    p: GaussProblem, backend: str | None = None, consistency_tol: float = CONSISTENCY_TOL
) -> GaussSolution:
    """Solve the general Gauss step (see the module docstring) with a qpsolvers ``backend``.

    ``consistency_tol``: how far (relative) dependent equality rows may disagree before it is an
    error; up to it they are solved in the least-squares sense. A simulation passes a looser value
    than a single step: its states drift off the constraints by the integration error.

    Raises
    ------
    NotPositiveDefiniteError
        ``A`` is not symmetric positive definite.
    RealizabilityError
        A realization cannot keep its constraint (``rank S < rank J`` on bilateral rows), or
        dependent bilateral rows contradict each other.
    QPSolveError
        The backend found no solution (e.g. contacts and bounds that contradict each other).
    """
    solver = check_backend(backend)
    where = _at(p.t)
    try:
        L = np.linalg.cholesky(p.A)  # L Lᵀ = A
    except np.linalg.LinAlgError:
        raise NotPositiveDefiniteError(
            f"the mass matrix A is not positive definite{where}; check the model's inertia"
        ) from None
    if np.max(np.abs(p.A - p.A.T)) > 1e-12 * np.max(np.abs(p.A)):
        raise NotPositiveDefiniteError(f"the mass matrix A is not symmetric{where}")
    # (LAPACK's general solve: on small matrices scipy's triangular solve was measured 100× slower on a
    # loaded machine, through BLAS threading)
    W = np.linalg.solve(L, p.D)  # L⁻¹ D
    Jt = np.linalg.solve(L, p.J.T).T  # J L⁻ᵀ
    norms = np.linalg.norm(Jt, axis=1)
    names = list(p.rows) or [f"row {i}" for i in range(p.J.shape[0])]
    for i in np.flatnonzero(norms == 0):
        raise RealizabilityError(
            f"constraint row {names[i]!r} has a zero gradient{where}: it does not restrict the acceleration",
            t=p.t,
            constraint=names[i],
            margin=0.0,
        )
    # unknowns scaled to unit columns of W (ũ = c ⊙ u): H has a unit diagonal, whatever the units of u
    cs = np.linalg.norm(W, axis=0)
    cs[cs == 0] = 1.0
    S = (Jt @ W) / norms[:, None] / cs
    r = (p.phi - p.J @ p.a0) / norms
    scale = float(np.max(np.abs(p.phi / norms), initial=0.0) + np.max(np.abs(p.J @ p.a0 / norms), initial=0.0))
    # The problem is homogeneous in (r, bounds) → u: solve it at unit size, so that the backends'
    # absolute tolerances (daqp: 1e-6 by default) do not decide tiny steps such as slow impacts.
    finite_bounds = np.abs(np.concatenate([p.lower, p.upper]))
    finite_bounds = finite_bounds[np.isfinite(finite_bounds)]
    unit = float(np.max(np.abs(r), initial=0.0)) or float(np.max(finite_bounds, initial=0.0)) or 1.0
    r, scale = r / unit, scale / unit
    kind = np.asarray(p.kind)
    eq, track, ge = kind == "eq", kind == "track", kind == "ge"
    m = p.D.shape[1]
    H = (W / cs).T @ (W / cs)
    stages: list[str] = []

    def realizable(mask: np.ndarray) -> None:
        if not mask.any():
            return
        # compare S = J A⁻¹ D with the Gram matrix J A⁻¹ Jᵀ (the ideal realization's S): both square the
        # smallness of nearly dependent rows, so near-redundancy is not mistaken for a failing realization
        Jn = Jt[mask] / norms[mask, None]
        rank_J = _svd_rank(Jn @ Jn.T)[3]
        rank_S = _svd_rank(S[mask])[3]
        if rank_S < rank_J:
            raise RealizabilityError(
                f"the realization cannot keep the constraint(s) "
                f"{sorted({names[i].split('[')[0] for i in np.flatnonzero(mask)})}{where}: "
                f"J A⁻¹ D has rank {rank_S} < rank J = {rank_J} (conditions (12)/(16)); "
                "choose reaction directions that are not A-orthogonal to the constraint's normal",
                t=p.t,
                constraint=names[int(np.flatnonzero(mask)[0])],
                margin=0.0,
            )

    realizable(eq | track)
    E, e, gap, rank = _compress(S[eq], r[eq])
    redundant = int(eq.sum()) - rank
    if gap > consistency_tol * max(scale, 1e-300):
        involved = sorted({names[i].split("[")[0] for i in np.flatnonzero(eq)})
        raise RealizabilityError(
            f"the constraint rows of {', '.join(map(repr, involved))} are dependent and contradict each other{where} "
            f"(inconsistency {gap:.2e}): "
            "the state is off the constraints (in a simulation: the drift has grown — reduce dt, tighten rtol or "
            "stabilize), or the redundant rows describe different constraints",
            t=p.t,
            constraint=names[int(np.flatnonzero(eq)[0])],
            margin=0.0,
        )
    G, h = -S[ge], -r[ge]
    lo, hi = p.lower.astype(float) / unit * cs, p.upper.astype(float) / unit * cs
    tracking_error = 0.0
    bounded = bool(np.any(np.isfinite(lo)) or np.any(np.isfinite(hi)))
    _, _, VtWs, rank_Ws = _svd_rank(W / cs)

    def compulsion(E: np.ndarray, e: np.ndarray, infeasible_ok: bool = False) -> np.ndarray | None:
        if rank_Ws == m or bounded:
            return _solve_stage(_Stage(H, np.zeros(m), E, e, G, h, lo, hi, "compulsion"), solver, where, infeasible_ok)
        # dependent reaction columns and no bounds: only the row space of W matters (Z and every
        # constraint act through W u), and there the Hessian is positive definite for every backend
        V = VtWs[:rank_Ws].T
        Er, er, _gap, _rank = _compress(E @ V, e)
        free = np.full(rank_Ws, np.inf)
        st = _Stage(V.T @ H @ V, np.zeros(rank_Ws), Er, er, G @ V, h, -free, free, "compulsion")
        xi = _solve_stage(st, solver, where, infeasible_ok)
        return None if xi is None else V @ xi

    u: np.ndarray | None = None
    if track.any():  # first as if the bounds allowed the constraint to be kept: then nothing saturates
        St, rt = S[track], r[track]
        Ek, ek, _gap, _rank = _compress(np.vstack([S[eq], St]), np.concatenate([r[eq], rt]))
        stages.append("compulsion")
        u = compulsion(Ek, ek, True)
        if u is None:  # saturated: the least tracking error first, then the least compulsion
            stages.append("track")
            # ‖S ũ − r‖² is only semidefinite when there are more actuators than rows; a Tikhonov term of
            # TRACK_REGULARIZATION (on the unit-sized problem) makes it definite for every backend
            P = St.T @ St + TRACK_REGULARIZATION * np.eye(m)
            u1 = _solve_stage(_Stage(P, -St.T @ rt, E, e, G, h, lo, hi, "track"), solver, where)
            assert u1 is not None
            # at the onset of saturation the error may be round-off small: the actuator is at its bound either way
            tracking_error = float(np.linalg.norm(St @ u1 - rt))
            E, e, gap, rank = _compress(np.vstack([S[eq], St]), np.concatenate([r[eq], St @ u1]))
        else:
            E, e = Ek, ek
    if u is None:
        stages.append("compulsion")
        u = compulsion(E, e)
        assert u is not None
    if rank_Ws < m:  # the acceleration fixes W u only: pick the least-norm reaction among those
        _, _, VtW, rank_W = _svd_rank(W)  # (the unscaled unknowns: their norm is the one to minimize)
        stages.append("least-norm")
        rows, rhs = VtW[:rank_W], VtW[:rank_W] @ (u / cs)  # W u = W u*, in the original unknowns
        if bounded:
            u = _solve_stage(
                _Stage(
                    np.diag(cs**-2.0), np.zeros(m), rows / cs, rhs, np.zeros((0, m)), np.zeros(0), lo, hi, "least-norm"
                ),
                solver,
                where,
            )
        else:
            u = (rows.T @ rhs) * cs
    lo, hi = p.lower.astype(float), p.upper.astype(float)
    u, tracking_error = np.clip(u / cs * unit, lo, hi), tracking_error * unit
    a = p.a0 + np.linalg.solve(L.T, W @ u)
    finite_lo, finite_hi = np.isfinite(lo), np.isfinite(hi)
    tol = 1e-9 * (1.0 + np.abs(u))
    at_bound = (finite_lo & (u - lo <= tol)) | (finite_hi & (hi - u <= tol))
    at_bound &= finite_lo | finite_hi
    return GaussSolution(
        a=a,
        u=u,
        compulsion=float(np.sum((W @ u) ** 2)),
        residual=p.J @ a - p.phi,
        tracking_error=tracking_error,
        at_bound=at_bound,
        stages=stages,
        redundant_rows=redundant,
        S_norm=S,
    )
