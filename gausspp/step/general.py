"""Gauss's principle where no closed form exists: inequalities, bounds, tracking and redundancy.

The compiled step (:mod:`gausspp.step`) solves the square, equality-only case. This module
solves the *general* one at a single instant, numerically, with any QP backend qpsolvers
finds (docs/theory.md §3, last paragraph)::

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

Redundant bilateral rows (:mod:`gausspp.redundancy`): which rows are kept — in the order
declared, each independent of those before it — and whether the dropped ones agree is decided
on the constraint manifold (``reference``: the problem at the nearest state on it, see
:func:`solve_general`); the problem is then solved at the state with the kept rows, so the
acceleration is exactly the minimal model's, and the multiplier the least-norm one. Dependent
rows that disagree on the manifold are an error. A realization that cannot keep its
constraint (``rank S < rank J``: conditions (12)/(16)) is an error here as everywhere else.
"""

from __future__ import annotations

import contextlib
import dataclasses
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import qpsolvers
import scipy.sparse as sp

from ..errors import (
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
from .redundancy import CLEARLY_INDEPENDENT, DEPENDENCE_TOL, independent_rows

#: Singular values below this fraction of the largest count as zero (rows are normalized first).
RANK_TOL = 1e-9
#: Relative size of the part of the right-hand side outside the span of dependent rows deemed inconsistent.
CONSISTENCY_TOL = 1e-8
#: Relative violation of a stage's constraints above which the backend is deemed to have failed.
FEASIBILITY_TOL = 1e-7
#: Relative dual residual (stationarity) of a stage's answer above which it is deemed not optimal.
DUAL_TOL = 1e-7
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
            # (qpsolvers' residuals are inf for a point not marked found: judge the point itself)
            optimal = bool(dataclasses.replace(sol, found=True).is_optimal(INACCURATE_KKT_TOL))
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
    if sol.found:  # optimality, not only feasibility: the dual residual where the backend reports multipliers
        dual = float(sol.dual_residual())
        size = 1.0 + float(np.max(np.abs(st.P @ x), initial=0.0)) + float(np.max(np.abs(st.q), initial=0.0))
        if np.isfinite(dual) and dual > DUAL_TOL * size:
            if infeasible_ok:
                return None
            raise QPSolveError(
                f"{backend} returned a point that is not optimal on the {st.name} stage of the Gauss QP{where} "
                f"(relative dual residual {dual / size:.2e}); try another backend (daqp is exact, osqp iterative)"
            )
    return np.clip(x, st.lo, st.hi)


def _compress(S: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Rows ``S u = r`` → an orthonormal basis of their span; returns (rows, rhs, inconsistency, rank)."""
    U, s, Vt, rank = _svd_rank(S)
    rows, rhs = Vt[:rank], (U[:, :rank].T @ r) / s[:rank]
    outside = r - U[:, :rank] @ (U[:, :rank].T @ r)
    return rows, rhs, float(np.linalg.norm(outside)), rank


@dataclass(frozen=True)
class _Scaled:
    """A problem in the unit-free form every stage works in (see :func:`solve_general`)."""

    L: np.ndarray  # L Lᵀ = A
    W: np.ndarray  # L⁻¹ D: Z(u) = ‖W u‖²
    Jn: np.ndarray  # J L⁻ᵀ, rows of unit length
    norms: np.ndarray  # the rows' lengths in A⁻¹
    cs: np.ndarray  # column lengths of W (unknowns scaled to ũ = cs ⊙ u)
    S: np.ndarray  # Jn (W / cs): J A⁻¹ D normalized by rows and columns
    r: np.ndarray  # (φ − J a₀) / norms / unit
    scale: float  # size of the right-hand side's terms, for the consistency test
    unit: float  # the problem's size (the QP is solved at unit size)


def _scaled(p: GaussProblem) -> _Scaled:
    """Factor ``A``, normalize rows and columns and bring the problem to unit size; names bad data."""
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
    names = _row_names(p)
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
    Jn = Jt / norms[:, None]
    S = (Jn @ W) / cs
    r = (p.phi - p.J @ p.a0) / norms
    scale = float(np.max(np.abs(p.phi / norms), initial=0.0) + np.max(np.abs(p.J @ p.a0 / norms), initial=0.0))
    # The problem is homogeneous in (r, bounds) → u: solve it at unit size, so that the backends'
    # absolute tolerances (daqp: 1e-6 by default) do not decide tiny steps such as slow impacts.
    finite_bounds = np.abs(np.concatenate([p.lower, p.upper]))
    finite_bounds = finite_bounds[np.isfinite(finite_bounds)]
    unit = float(np.max(np.abs(r), initial=0.0)) or float(np.max(finite_bounds, initial=0.0)) or 1.0
    return _Scaled(L, W, Jn, norms, cs, S, r / unit, scale / unit, unit)


def _row_names(p: GaussProblem) -> list[str]:
    return list(p.rows) or [f"row {i}" for i in range(p.J.shape[0])]


def _kept_rows(ref: _Scaled, eq: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """The bilateral rows kept (:func:`gausspp.redundancy.independent_rows` at the reference) and how far
    the dropped ones contradict the kept ones there (relative to the right-hand side's size), and each row's sine
    against the rows kept before it."""
    eq_rows = np.flatnonzero(eq)
    kept_local, sines = independent_rows(ref.Jn[eq_rows])
    kept = eq_rows[kept_local]
    gap = 0.0
    if kept.size < eq_rows.size:
        dropped = eq_rows[np.isin(np.arange(eq_rows.size), kept_local, invert=True)]
        if kept.size:  # each dropped row as a combination of the kept ones; its right-hand side must follow
            combo = np.linalg.lstsq(ref.Jn[kept].T, ref.Jn[dropped].T, rcond=None)[0]
            gap = float(np.max(np.abs(ref.r[dropped] - combo.T @ ref.r[kept])))
        else:
            gap = float(np.max(np.abs(ref.r[dropped])))
    return kept, gap / max(ref.scale, 1e-300), sines


def solve_general(
    p: GaussProblem,
    backend: str | None = None,
    consistency_tol: float = CONSISTENCY_TOL,
    reference: GaussProblem | Callable[[], GaussProblem | None] | None = None,
    near_manifold: bool = False,
) -> GaussSolution:
    """Solve the general Gauss step (see the module docstring) with a qpsolvers ``backend``.

    ``reference``: the same problem at the nearest state on the constraint manifold, or a function
    that builds it (called only when the rows at ``p`` are nearly but not clearly dependent, or
    disagree, or rows were dropped and ``near_manifold`` is false). Which bilateral rows are redundant,
    and whether they agree, is decided there (:mod:`gausspp.redundancy`); ``p`` is then solved with the
    kept rows. ``near_manifold``: the state itself satisfies the constraints to within the caller's
    tolerance, so dropped rows need no reference to show that they can hold together. ``consistency_tol``: how
    far (relative) dependent rows may disagree at the reference before it is an error.

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
    s = _scaled(p)
    names = _row_names(p)
    S, r, cs, unit = s.S, s.r, s.cs, s.unit
    kind = np.asarray(p.kind)
    eq, track, ge = kind == "eq", kind == "track", kind == "ge"
    m = p.D.shape[1]
    Ws = s.W / cs
    H = Ws.T @ Ws
    stages: list[str] = []

    def realizable(mask: np.ndarray) -> None:
        if not mask.any():
            return
        # compare S = J A⁻¹ D with the Gram matrix J A⁻¹ Jᵀ (the ideal realization's S): both square the
        # smallness of nearly dependent rows, so near-redundancy is not mistaken for a failing realization
        Jn = ref.Jn[mask]
        rank_J = _svd_rank(Jn @ Jn.T)[3]
        rank_S = _svd_rank(ref.S[mask])[3]
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

    ref = s
    kept, gap, sines = _kept_rows(ref, eq)
    # rows that are independent here but not clearly so, or dependent rows that disagree, may be an artefact of
    # the state's distance from the manifold: decide at the nearest state on it
    ambiguous = bool(np.any((sines > DEPENDENCE_TOL) & (sines < CLEARLY_INDEPENDENT))) or gap > consistency_tol
    # dropped rows must hold together near the state: checked at the reference unless the state is a witness
    ambiguous = ambiguous or (kept.size < int(eq.sum()) and not near_manifold)
    if ambiguous and reference is not None:
        on_manifold = reference() if callable(reference) else reference
        if on_manifold is not None:
            ref = _scaled(on_manifold)
            kept, gap, sines = _kept_rows(ref, eq)
    realizable(eq | track)
    redundant = int(eq.sum()) - kept.size
    if gap > consistency_tol:
        involved = sorted({names[i].split("[")[0] for i in np.flatnonzero(eq)})
        raise RealizabilityError(
            f"the constraint rows of {', '.join(map(repr, involved))} are dependent and contradict each other{where} "
            f"(relative inconsistency {gap:.2e} on the constraint manifold): the redundant rows describe different "
            "constraints — remove one of them",
            t=p.t,
            constraint=names[int(np.flatnonzero(eq)[0])],
            margin=0.0,
        )
    G, h = -S[ge], -r[ge]
    lo, hi = p.lower.astype(float) / unit * cs, p.upper.astype(float) / unit * cs
    tracking_error = 0.0
    bounded = bool(np.any(np.isfinite(lo)) or np.any(np.isfinite(hi)))
    # dependent reaction columns (judged at the reference, with the rows' dependence tolerance): their least-norm
    # multiplier leaves out the directions that only the drift separates
    sv = np.linalg.svd(ref.W / ref.cs, compute_uv=False)
    rank_W = int(np.sum(sv > DEPENDENCE_TOL * max(float(sv[0]) if sv.size else 0.0, 1e-300)))

    scaled_u: list[np.ndarray] = []  # the last u-space stage's unknowns ũ (exact at the bounds)

    def compulsion(rows: np.ndarray, rhs: np.ndarray, infeasible_ok: bool = False) -> np.ndarray | None:
        """The whitened reaction ``w = W u`` of least ``‖w‖² = Z`` with ``rows · L⁻ᵀ w = rhs`` (rows of ``Jn``)."""
        if bounded:  # bounds act on u itself
            E, e, _gap, _rank = _compress(rows @ Ws, rhs)
            x = _solve_stage(_Stage(H, np.zeros(m), E, e, G, h, lo, hi, "compulsion"), solver, where, infeasible_ok)
            if x is None:
                return None
            scaled_u.append(x)
            return Ws @ x
        # no bounds: the unknowns are the reaction itself, w = Q ξ with Q an orthonormal basis of range(W) at this
        # state (Hessian I for every backend, however close the reaction columns are to dependent). Off the
        # manifold redundant columns are independent by the drift; range(W) still holds the kept rows'
        # reactions there, so the acceleration is exactly the minimal model's.
        Q = _range_basis(Ws)
        E, e, _gap, _rank = _compress(rows @ Q, rhs)
        free = np.full(Q.shape[1], np.inf)
        st = _Stage(np.eye(Q.shape[1]), np.zeros(Q.shape[1]), E, e, -s.Jn[ge] @ Q, h, -free, free, "compulsion")
        xi = _solve_stage(st, solver, where, infeasible_ok)
        return None if xi is None else Q @ xi

    w: np.ndarray | None = None
    x_track: np.ndarray | None = None
    if track.any():  # first as if the bounds allowed the constraint to be kept: then nothing saturates
        St, rt = S[track], r[track]
        both = np.concatenate([kept, np.flatnonzero(track)])
        stages.append("compulsion")
        w = compulsion(s.Jn[both], r[both], True)
        if w is None:  # saturated: the least tracking error first, then the least compulsion
            stages.append("track")
            # ‖S ũ − r‖² is only semidefinite when there are more actuators than rows; a Tikhonov term of
            # TRACK_REGULARIZATION (on the unit-sized problem) makes it definite for every backend
            P = St.T @ St + TRACK_REGULARIZATION * np.eye(m)
            E, e, _gap, _rank = _compress(S[kept], r[kept])
            x_track = _solve_stage(_Stage(P, -St.T @ rt, E, e, G, h, lo, hi, "track"), solver, where)
            assert x_track is not None
            # at the onset of saturation the error may be round-off small: the actuator is at its bound either way
            tracking_error = float(np.linalg.norm(St @ x_track - rt))
            w = compulsion(s.Jn[both], np.concatenate([r[kept], St @ x_track]))
    if w is None:
        stages.append("compulsion")
        w = compulsion(s.Jn[kept], r[kept])
        assert w is not None
    # the reaction unknowns: least norm among those with W u = w (unique unless the columns are dependent)
    u = scaled_u[-1] / cs if scaled_u else _truncated_pinv(s.W, rank_W) @ w
    if rank_W < m:
        stages.append("least-norm")
        if bounded:  # least ‖u‖ within the bounds, W u = w on the row space of W
            _, _, VtW, _r = _svd_rank(s.W)
            rows, rhs = VtW[:rank_W], VtW[:rank_W] @ u
            x = _solve_stage(
                _Stage(
                    np.diag(cs**-2.0), np.zeros(m), rows / cs, rhs, np.zeros((0, m)), np.zeros(0), lo, hi, "least-norm"
                ),
                solver,
                where,
            )
            u = x / cs
    lo, hi = p.lower.astype(float), p.upper.astype(float)
    u, tracking_error = np.clip(u * unit, lo, hi), tracking_error * unit
    finite_lo, finite_hi = np.isfinite(lo), np.isfinite(hi)
    tol = 1e-9 * (1.0 + np.abs(u))
    at_lo, at_hi = finite_lo & (u - lo <= tol), finite_hi & (hi - u <= tol)
    at_bound = at_lo | at_hi
    if bounded:  # a saturated actuator delivers its bound (not the backend's round-off of it), and that is the reaction
        u = np.where(at_hi, hi, np.where(at_lo, lo, u))
        w = s.W @ u / unit
    a = p.a0 + np.linalg.solve(s.L.T, w * unit)
    return GaussSolution(
        a=a,
        u=u,
        compulsion=float(np.sum((w * unit) ** 2)),
        residual=p.J @ a - p.phi,
        tracking_error=tracking_error,
        at_bound=at_bound,
        stages=stages,
        redundant_rows=redundant,
        S_norm=S,
    )


def _range_basis(M: np.ndarray) -> np.ndarray:
    """An orthonormal basis of ``range(M)`` (numerical rank: singular values above 1e-13 of the largest)."""
    U, s, _ = np.linalg.svd(M, full_matrices=False)
    return U[:, : int(np.sum(s > 1e-13 * max(float(s[0]) if s.size else 0.0, 1e-300)))]


def _truncated_pinv(M: np.ndarray, rank: int) -> np.ndarray:
    """The pseudo-inverse of ``M`` restricted to its ``rank`` largest singular values."""
    U, s, Vt = np.linalg.svd(M, full_matrices=False)
    return (Vt[:rank].T / s[:rank]) @ U[:, :rank].T
