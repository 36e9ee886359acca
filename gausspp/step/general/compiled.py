"""The general Gauss step compiled: one buffer-bound casadi call and an all-clear flag.

For one *pattern* — which contact rows are closed, which bilateral rows are kept (the others dependent on
them) and which reaction columns are kept — the step of :mod:`.solve` is one casadi graph of
``(t, q, v, λ, stab)``: the model's data, the unit-free form of :mod:`.scaling`, the QP posed for a
casadi ``conic`` plugin inside the graph (``qrqp`` by default), its answer finished as
:func:`.solve._solution` finishes it, and the checks. Written in the reaction unknowns ``ũ = c ⊙ u`` of
the kept columns ``K_c``, with ``W_s = L⁻¹D / c`` and ``S = J_n W_s`` (rows normalized in ``A⁻¹``)::

    compulsion:  min ½ ‖W_s ũ‖²   s.t.  S_K ũ = r_K,  S_T ũ = r_T,  S_C ũ ≥ r_C,  lo ≤ ũ ≤ hi

(``K`` kept bilateral rows, ``T`` tracked rows of bounded servos, ``C`` closed contacts). With tracked
rows, when the compulsion stage is infeasible (the actuators saturate), the *track* stage
``min ‖S_T ũ − r_T‖² + ε‖ũ‖²`` (same rows and bounds but ``T``) runs, then the compulsion stage with
``S_T ũ`` fixed at what it reached — the same lexicographic order as :mod:`.solve`. Dropped columns
(reaction directions dependent on the kept ones) carry the least-norm share of the reaction: with
``W_d = W_k C`` on the manifold, ``u`` is moved along the null directions ``N = [−C; I]`` to the least norm.

The flag is 1 when the Python step (:func:`.solve.solve_general`) would take the same decision at this state
or at the nearest state on the manifold, and the answer passes its checks:

* inputs and outputs finite, ``A`` positive definite (relative pivot ``> 0``);
* the closed contacts are those within ``contact_tol`` (unless the caller names them) and none of them
  approaches (``ġ_c ≥ −contact_tol``);
* every kept row's sine against the rows kept before it (in the metric ``A⁻¹``, the diagonal of the
  Cholesky factor of their Gram matrix) is at least :data:`KEPT_FLOOR`: the decision taken on an open piece
  of the manifold is kept through an isolated position where the rows' rank drops; every dropped
  row's sine against the kept rows before it at most :data:`~.redundancy.DEPENDENCE_TOL`, its right-hand
  side agrees with theirs to the consistency tolerance, and its residuals ``Φ_d``, ``g_d`` are the same
  combination of the kept rows' residuals to :data:`~.manifold.REACH_TOL` (the witness that the dropped rows hold
  together: to first order in the drift, what a state on the manifold would show) — each beyond its tolerance by
  :data:`~.drift.DRIFT_SLACK` times the state's relative drift ``δ`` (:func:`.drift.relative_drift`), at most
  :data:`~.drift.SLACK_CAP`: a dependence exact on the manifold holds to ``O(δ)`` at a state ``δ`` off it, as an
  integrator's stages are (DOP853's stages of a 10 s run of Bricard's mechanism in joint coordinates at
  ``rtol = 1e-10`` drift by 1e-6, median, up to 1.4e-4: 673 of 1618 evaluations left this step for the Python one
  without the slack, 3 with it, and the run took 0.63 s instead of 0.06 s); rows that become independent (a
  singular position left on another branch) have a sine of order one, and a state farther off goes to the Python
  step, which decides on the manifold;
* the kept rows stay realizable: the Cholesky pivots of ``S Sᵀ`` on the kept and tracked rows are at least
  :data:`REALIZABLE_PIVOT` times the squared pivots of the rows' Gram matrix (a nearly unrealizable state goes to
  the Python step, which decides it);
* the QP's answer is feasible (:data:`~.stage.FEASIBILITY_TOL`) and stationary (:data:`~.stage.DUAL_TOL`).

Otherwise the caller takes the Python step, which decides again (:mod:`.general_step`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ...c_code import c_function
from ..bound import Bound
from ..protocol import StepModel
from ..qp import QPBackend, short_name
from ..qp.casadi_conic import CasadiConic, stdout_silenced
from . import sparse_pattern
from .drift import DRIFT_SLACK, SLACK_CAP, relative_drift, row_size
from .kept_rows import AGREEMENT_SLACK
from .manifold import REACH_TOL
from .redundancy import CLEARLY_INDEPENDENT, DEPENDENCE_TOL
from .solve import TRACK_REGULARIZATION
from .stage import DUAL_TOL, FEASIBILITY_TOL

#: The kept rows' Cholesky pivots of ``S Sᵀ`` must be at least this times the squared ones of their Gram matrix
#: ``Jn Jnᵀ`` (what the ideal realization would give): below it, the Python step judges realizability.
REALIZABLE_PIVOT = 1e-6
#: Kept rows stay kept on the hot path while their sines against the rows kept before them exceed this — zero:
#: only a failed factorization (NaN, the rows dependent to round-off) hands the state to the Python step. The
#: decision of an open piece of the manifold holds through an isolated singular position (a parallelogram's
#: collinear one), where only the instantaneous rank drops; the step there stays on the branch of the motion.
KEPT_FLOOR = 0.0
#: A pattern decided where its kept rows were clearly independent (smallest sine ≥
#: :data:`~.redundancy.CLEARLY_INDEPENDENT`) hands the state back to the Python step once that sine falls below
#: this: the rows turning dependent while others take over (a spatial loop turning), the Python step chooses
#: anew (:func:`~.redundancy.chosen_rows`). A pattern decided with smaller sines (near a singular position, where
#: no choice does better) keeps :data:`KEPT_FLOOR`.
HOLD_FLOOR = 5e-3
#: Below this smallest pivot of ``S H⁻¹ Sᵀ`` (unit-free) the equality step is damped in proportion to the state's
#: drift from the manifold (:func:`_equality_qp`).
SINGULAR_BAND = 1e-6
#: At the singular position itself (smallest pivot² of ``S`` below this, ~10 round-offs of its unit diagonal) the
#: symmetric step adds this damping, so that the factorization exists; nowhere else.
SINGULAR_FLOOR = 1e-15


@dataclass(frozen=True)
class Pattern:
    """What one compiled general step is for (the same at every state of an open piece of the motion)."""

    closed: tuple[int, ...]  # closed contact rows (indices into the model's contact rows)
    kept_rows: tuple[int, ...]  # kept bilateral rows (of the model's k rows)
    kept_cols: tuple[int, ...]  # kept reaction unknowns (of the m + len(closed) unknowns)
    given: bool  # the caller names the closed contacts (no check against the gaps)
    floor: float = 0.0  # the kept rows' smallest sine below which the flag is down (:data:`HOLD_FLOOR` or 0)

    def compilable(self, model: StepModel) -> bool:
        """Dropped columns carry the least-norm share in closed form: only where no bound acts."""
        dropped = self.m_all(model) > len(self.kept_cols)
        return not (dropped and (self.closed or model.bounded))

    def m_all(self, model: StepModel) -> int:
        return model.m + len(self.closed)


#: The packed outputs, in order (sizes from the model and the pattern), then the flag and the auto-closed flag.
FIELDS = (
    "a",
    "u",
    "reaction",
    "compulsion",
    "residual",
    "Phi",
    "a_free",
    "S",
    "tracking_error",
    "at_bound",
    "saturated_branch",
    "qdot",
    "energy",
    "power",
    "power_reaction",
    "g",
    "gc",
)


def _bounds(model: StepModel, closed: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bounds on the unknowns (reactions, then contact forces ≥ 0) and the rows' roles as 0 eq / 1 track."""
    m, nc = model.m, len(closed)
    lower, upper = np.full(m + nc, -np.inf), np.full(m + nc, np.inf)
    lower[m:] = 0.0
    track = np.zeros(model.k, bool)
    for grp, bounds in zip(model.groups, model.group_bounds, strict=True):
        if bounds is not None:
            lower[grp.cols], upper[grp.cols] = bounds
            track[grp.rows] = True
    return lower, upper, track


def _unit_fallback(lower: np.ndarray, upper: np.ndarray) -> float:
    """The problem's size when the right-hand side vanishes: the largest finite bound, else 1 (as scaling._unit)."""
    b = np.abs(np.concatenate([lower, upper]))
    b = b[np.isfinite(b)]
    return float(b.max()) if b.size and b.max() else 1.0


def _violation(Aqp: Any, lba: Any, uba: Any, lbx: Any, ubx: Any, x: Any) -> Any:
    """The relative violation of :func:`.stage.violation` (rows: equalities and ``≥`` rows alike)."""
    size = 1.0 + ca.mmax(ca.fabs(x)) if x.numel() else 1.0
    viol = ca.DM(0) if isinstance(x, ca.DM) else type(x)(0)
    if Aqp.numel():
        y = Aqp @ x
        row = ca.fmax(ca.fmax(lba - y, y - uba), 0)
        viol = ca.fmax(viol, ca.mmax(row) / (size * (1 + ca.mmax(ca.fabs(Aqp)))))
    if x.numel():
        viol = ca.fmax(viol, ca.mmax(ca.fmax(ca.fmax(lbx - x, x - ubx), 0)) / size)
    return viol


def _pick(x: Any, idx: list[int]) -> Any:
    """Entries ``idx`` of the column ``x`` (an empty list gives an empty column, also for a 1×1 ``x``)."""
    return x[idx] if idx else ca.SX(0, 1)


def _chol_pivots(G: ca.SX) -> ca.SX:
    """The diagonal of the upper Cholesky factor of ``G`` (a failed factorization gives NaN, which fails ``≥``)."""
    return ca.diag(ca.chol(G)) if G.shape[0] else ca.SX(0, 1)


class _Graph:
    """The symbolic pieces of one pattern's step (see the module docstring)."""

    def __init__(self, model: StepModel, pat: Pattern, consistency_tol: float, cap: float = SLACK_CAP) -> None:
        self.cap = cap
        p, c = model.expressions, model.contact_expressions
        k = model.k
        cl = list(pat.closed)
        nc = len(cl)
        self.lower, self.upper, track = _bounds(model, pat.closed)
        J_all = ca.vertcat(p.J, c.J[cl, :]) if nc else p.J
        phi_all = ca.vertcat(p.phi, c.phi[cl]) if nc else p.phi
        D_all = ca.horzcat(p.D, c.J[cl, :].T) if nc else p.D
        R = ca.chol(p.A)  # RᵀR = A: L = Rᵀ
        diag = ca.diag(R)
        self.pivot = ca.mmin(ca.if_else(diag * diag > 0, diag * diag, -1)) / ca.mmax(ca.fabs(ca.diag(p.A)))
        self.a_free = ca.solve(R, ca.solve(R.T, p.f))
        self.a0 = ca.solve(R, ca.solve(R.T, p.f + p.r0))
        W = ca.solve(R.T, D_all)
        Jt = ca.solve(R.T, J_all.T).T
        norms = ca.sqrt(ca.sum2(Jt * Jt))
        cs = ca.sqrt(ca.sum1(W * W)).T
        cs = ca.if_else(cs == 0, 1, cs)
        Jn = Jt / norms
        self.norms = norms  # the rows' lengths in A⁻¹
        Ws = W / ca.repmat(cs.T, W.shape[0], 1)
        S = Jn @ Ws
        Ja0 = J_all @ self.a0
        r_raw = (phi_all - Ja0) / norms
        big = ca.mmax(ca.fabs(r_raw)) if k + nc else ca.SX(0)
        unit = ca.if_else(big > 0, big, _unit_fallback(self.lower, self.upper))
        r = r_raw / unit
        scale = ((ca.mmax(ca.fabs(phi_all / norms)) + ca.mmax(ca.fabs(Ja0 / norms))) / unit) if k + nc else ca.SX(0)
        self.R, self.W, self.Ws, self.S, self.r, self.unit, self.cs = R, W, Ws, S, r, unit, cs
        self.J_all, self.phi_all, self.D_all = J_all, phi_all, D_all
        kc = list(pat.kept_cols)
        K = list(pat.kept_rows)
        T = [i for i in range(k) if track[i]]
        C = list(range(k, k + nc))
        self.K, self.T, self.C, self.kc = K, T, C, kc
        inf = np.inf
        lo_t = ca.DM(self.lower[kc]) / unit * cs[kc]
        hi_t = ca.DM(self.upper[kc]) / unit * cs[kc]
        self.lbx, self.ubx = (
            ca.if_else(ca.DM(np.isfinite(self.lower[kc])), lo_t, -inf),
            ca.if_else(ca.DM(np.isfinite(self.upper[kc])), hi_t, inf),
        )
        Wk = Ws[:, kc]
        self.H = Wk.T @ Wk
        rows = K + T + C
        self.Aqp = S[rows, kc]
        self.lba = ca.vertcat(_pick(r, K + T), _pick(r, C))
        self.uba = ca.vertcat(_pick(r, K + T), ca.DM.inf(len(C)))
        # the track stage (bounded servos only)
        if T:
            St, rt = S[T, kc], r[T]
            self.Ht = St.T @ St + TRACK_REGULARIZATION * ca.DM.eye(len(kc))
            self.gt = -St.T @ rt
            rows_t = K + C
            self.At = S[rows_t, kc] if rows_t else ca.SX(0, len(kc))
            self.lbt = ca.vertcat(_pick(r, K), _pick(r, C))
            self.ubt = ca.vertcat(_pick(r, K), ca.DM.inf(len(C)))
        self.drift = relative_drift(model)
        self.checks = self._watch(model, pat, Jn, r, scale, consistency_tol, track)

    def _watch(
        self, model: StepModel, pat: Pattern, Jn: ca.SX, r: ca.SX, scale: ca.SX, tol: float, track: np.ndarray
    ) -> list[ca.SX]:
        """The redundancy decision and realizability still hold (module docstring)."""
        p = model.expressions
        K, k = self.K, model.k
        checks: list[ca.SX] = []
        slack = ca.fmin(DRIFT_SLACK * self.drift, self.cap)  # off the manifold by δ: O(δ) (module docstring)
        eq = [i for i in range(k) if not track[i]]
        dropped = [i for i in eq if i not in K]
        if K:
            G = Jn[K, :] @ Jn[K, :].T
            Rk = ca.chol(G)
            checks.append(ca.mmin(ca.diag(Rk)) >= max(KEPT_FLOOR, pat.floor))
            B = ca.solve(Rk.T, Jn[K, :])  # orthonormal rows spanning the kept rows, in their order
            # as kept_rows.kept_rows judges a gap: nearly dependent kept rows (near a singular position, where the
            # decision of the open piece holds) amplify drift and round-off in what the dropped rows are tested on
            relax = ca.fmin(1, ca.mmin(ca.diag(Rk)) / CLEARLY_INDEPENDENT)
            singular = ca.logic_not(relax > 0)  # the kept rows' rank drops here (NaN pivot): the open piece decides
        for d in dropped:
            before = sum(1 for i in K if i < d)
            row = Jn[d, :]
            if before:
                Bb = B[:before, :]
                for _ in range(2):
                    row = row - (Bb.T @ (Bb @ row.T)).T
            checks.append(ca.logic_or(singular, ca.norm_2(row) * relax <= DEPENDENCE_TOL + slack))
            if K:  # as kept_rows.kept_rows judges agreement (the dropped row's sine is below DEPENDENCE_TOL here)
                combo = ca.solve(G, Jn[K, :] @ Jn[d, :].T)
                y = Jn[K, :].T @ ca.solve(G, r[K])
                miss = ca.fabs(r[d] - combo.T @ r[K]) - AGREEMENT_SLACK * ca.norm_2(row) * ca.norm_2(y)
                agree = miss * relax <= (tol + slack) * ca.fmax(scale, 1e-300) * (1 + ca.sum1(ca.fabs(combo)))
                checks.append(ca.logic_or(singular, agree))
            else:
                checks.append(ca.fabs(r[d]) <= tol * ca.fmax(scale, 1e-300))
        if dropped:  # the witness that the dropped rows hold together: their residuals follow the kept rows'
            J, Phi, g = p.J, p.Phi, p.g if p.g is not None else ca.SX.zeros(k)
            q, v = model.mechanism.q, model.mechanism.v
            nrm = ca.sqrt(ca.sum2(J * J))
            nrm = ca.if_else(nrm == 0, 1, nrm)
            hol = set(model.holonomic_rows)
            for d in dropped:
                # d's row is (to its sine) the combination c of the kept rows, in A⁻¹-normalized units: to first
                # order in the drift its residuals are that combination of theirs (a row of another constraint,
                # e.g. a length that contradicts the loop, misses by the contradiction itself)
                c = ca.solve(G, Jn[K, :] @ Jn[d, :].T) if K else ca.SX(0, 1)
                w = c * self.norms[d] / self.norms[K] if K else c  # J_d ≈ Σ w_i J_i, unnormalized
                fit_v = (Phi[d] - (w.T @ Phi[K] if K else 0)) / nrm[d]
                checks.append(ca.fabs(fit_v) <= (REACH_TOL + slack) * (1 + row_size(J[d, :], v)))  # its own size
                if d in hol:
                    fit_g = (g[d] - (w.T @ g[K] if K else 0)) / nrm[d]
                    q_size = row_size(J[d, :], q) if q.numel() == v.numel() else ca.mmax(ca.fabs(q))
                    checks.append(ca.fabs(fit_g) <= (REACH_TOL + slack) * (1 + q_size))
        rows = K + self.T
        if rows:
            # as kept_rows.check_realizable: S against the rows' own Gram matrix (the ideal realization's S), so
            # that nearly dependent rows are not taken for a realization that cannot keep them
            Sk, Jk = self.S[rows, self.kc], Jn[rows, :]
            ideal = _chol_pivots(Jk @ Jk.T)
            checks.append(ca.mmin(_chol_pivots(Sk @ Sk.T) - REALIZABLE_PIVOT * ideal * ideal) >= 0)
        return checks


def _conic(name: str, backend: CasadiConic, mk: int, rows: int) -> ca.Function:
    """The backend's dense QP of ``mk`` unknowns and ``rows`` rows, as a casadi function."""
    sparsity = {"h": ca.Sparsity.dense(mk, mk), "a": ca.Sparsity.dense(rows, mk)}
    with stdout_silenced():
        return ca.conic(name, backend.plugin, sparsity, backend.options)


def _symmetric_qp(H: ca.SX, S: ca.SX, r: ca.SX, drift: ca.SX) -> tuple[ca.SX, ca.SX]:
    """:func:`_equality_qp` where ``S`` is square and symmetric positive definite by construction (ideal rows,
    ``D = Jᵀ``, kept rows and columns alike: ``S`` is the rows' Gram matrix in ``A⁻¹``): the rows fix ``x``,
    ``S x = r`` by a Cholesky factor of ``S`` alone — conditioning ``1/σ``, not the ``1/σ²`` of ``S H⁻¹ Sᵀ`` —
    damped in the band around a singular position as there."""
    rows = S.shape[0]
    if not rows:
        return ca.SX.zeros(H.shape[0]), ca.SX(0, 1)
    pivots = ca.diag(ca.chol(S))
    smallest = ca.mmin(ca.if_else(pivots * pivots >= 0, pivots * pivots, 0))
    band = SINGULAR_BAND
    damping = drift * band**4 / (band**4 + smallest**4)  # drift inside the band, (b/σ²)⁴ of it outside
    damping = ca.if_else(smallest > SINGULAR_FLOOR, damping, damping + SINGULAR_FLOOR)  # at the position itself
    Rs = ca.chol(S + damping * ca.DM.eye(rows))
    x = ca.solve(Rs, ca.solve(Rs.T, r))
    return x, ca.solve(Rs, ca.solve(Rs.T, -(H @ x)))  # S symmetric: λ = −S⁻¹ H x


def _equality_qp(H: ca.SX, S: ca.SX, r: ca.SX, drift: ca.SX) -> tuple[ca.SX, ca.SX]:
    """``min ½ xᵀHx`` s.t. ``S x = r`` (H positive definite, S of full row rank) and the rows' multipliers in
    casadi's convention (``H x + Sᵀλ = 0``), by a Cholesky factor of ``H`` and one of ``M = S H⁻¹ Sᵀ``.

    Near a singular position (the smallest pivot ``σ²`` of ``M`` below :data:`SINGULAR_BAND`) a state off the
    manifold by ``drift`` (relative) would see that drift amplified by ``1/σ²`` in the multipliers: ``M`` is
    damped there by ``ε² = drift · b⁴/(b⁴ + σ⁸)`` — zero on the manifold, capping the amplification at
    ``1/drift`` inside the band (damped least squares, as near a kinematic singularity), and ``drift·(b/σ²)⁴``
    away from it: at the crane's margin 0.06 a state off its constraint by 0.17 is stepped as the Gauss step
    there to round-off (with ``b²/(b² + σ⁴)`` it was 3e-6 off, with the all-clear flag up —
    tests/test_step_reference.py). On the manifold the step is exact. (A QR solve of ``S x = r`` was measured less
    accurate here than these Cholesky factors: 5e-6 against 4e-12 at a parallelogram's crank angle of 1e-3.)
    """
    if not S.shape[0]:
        return ca.SX.zeros(H.shape[0]), ca.SX(0, 1)
    Rh = ca.chol(H)
    Y = ca.solve(Rh.T, S.T)  # R⁻ᵀ Sᵀ
    M = Y.T @ Y
    pivots = ca.diag(ca.chol(M))
    smallest = ca.mmin(ca.if_else(pivots * pivots >= 0, pivots * pivots, 0))  # NaN (singular M) counts as 0
    band = SINGULAR_BAND
    damping = drift * band**4 / (band**4 + smallest**4)  # drift inside the band, (b/σ²)⁴ of it outside
    Rm = ca.chol(M + damping * ca.DM.eye(M.shape[0]))
    mu = ca.solve(Rm, ca.solve(Rm.T, r))
    return ca.solve(Rh, Y @ mu), -mu


def _carry(model: StepModel, pat: Pattern, gr: _Graph) -> dict[str, Any]:
    """What the function after the QP reads of the model's data (computed once, before the QP)."""
    p, mech, c = model.expressions, model.mechanism, model.contact_expressions
    ins = model.inputs
    ins_finite = ca.fabs(sum(ca.sum1(ca.vec(s)) for s in ins)) < ca.inf
    watch = ca.logic_and(gr.pivot > 0, ins_finite)
    for chk in gr.checks:
        watch = ca.logic_and(watch, chk)
    closed_ok = ca.SX(1)
    if pat.closed:
        watch = ca.logic_and(watch, ca.mmin(c.gdot[list(pat.closed)]) >= -model.contact_tol)
    nc_all = len(model.contact_row_names)
    if nc_all:
        want = np.zeros(nc_all)
        want[list(pat.closed)] = 1
        closed_ok = ca.mmin(ca.if_else((c.g <= model.contact_tol) == ca.DM(want), 1, 0))
    carry = dict(
        unit=gr.unit, cs=gr.cs, W=gr.W, Wk=gr.Ws[:, gr.kc], a0=gr.a0, R=gr.R, r0=p.r0, D_all=gr.D_all,
        J_all=gr.J_all, phi_all=gr.phi_all, H=gr.H, Aqp=gr.Aqp, lbx=gr.lbx, ubx=gr.ubx, watch=watch,
        Phi=p.Phi, a_free=gr.a_free, S=gr.S, qdot=mech.qdot,
        energy=mech.energy if mech.energy is not None else ca.SX(0),
        power=ca.dot(mech.v, mech.F_nc) if mech.F_nc is not None else ca.SX(0),
        v=mech.v, g=p.g if p.g is not None else ca.SX.zeros(model.k), gc=c.g, closed_ok=closed_ok,
    )  # fmt: skip
    if gr.T:
        carry["St"], carry["rt"] = gr.S[gr.T, gr.kc], gr.r[gr.T]
    return carry


class GeneralCall:
    """One pattern's compiled general step, called through bound buffers (see the module docstring)."""

    def __init__(
        self, model: StepModel, pat: Pattern, backend: QPBackend, consistency_tol: float, cap: float = SLACK_CAP
    ) -> None:
        assert isinstance(backend, CasadiConic)
        self.pattern, self.backend = pat, backend
        self.model, self.consistency_tol = model, consistency_tol
        self.nv, self.nq, self.k, self.m = model.nv, model.nq, model.k, model.m
        self.nc_all = len(model.contact_row_names)
        #: the pattern of a large redundant linkage, in its own sparsity (:mod:`.sparse_pattern`): no ``S`` output
        self.sparse = sparse_pattern.applies(model, pat.kept_rows, pat.kept_cols, pat.closed)
        self.sizes = self._sizes(model, pat)
        if self.sparse:
            band = max(SINGULAR_BAND, pat.floor**2)
            outs = sparse_pattern.sparse_step(model, pat.kept_rows, consistency_tol, band, cap)
            fn = ca.Function("general_step_sparse", model.inputs, [ca.cse(o) for o in outs])
        else:
            fn = self._function(model, pat, backend, consistency_tol, cap)
        if getattr(model, "codegen", False) and fn.is_a("SXFunction"):  # as C where a compiler is (c_code)
            fn = c_function(fn) or fn
        self._bound = Bound(fn)
        self._args = self._bound.args
        self._out = self._bound.res[0]
        starts = np.concatenate([[0], np.cumsum(list(self.sizes.values()))]).astype(int)
        self.slices = {name: slice(int(a), int(b)) for name, a, b in zip(FIELDS, starts[:-1], starts[1:], strict=True)}
        m_all = model.m + len(pat.closed)
        #: what every result of this pattern shares: the rows' counts, the stages, where the contact forces go
        self.m_all, self.k_all = m_all, model.k + len(pat.closed)
        self.closed = np.array(pat.closed, dtype=int)
        dropped = m_all - len(pat.kept_cols)
        # the sparse route splits least-norm up to LEAST_NORM_ROWS dropped rows; beyond, u_D = 0
        self.least_norm = dropped > 0 and (not self.sparse or dropped <= sparse_pattern.LEAST_NORM_ROWS)
        eq = sum(1 for grp, b in zip(model.groups, model.group_bounds, strict=True) if b is None for _ in range(
            grp.rows.start, grp.rows.stop))  # fmt: skip
        self.redundant = eq - len(pat.kept_rows)
        self.solver = f"gauss-qp:{short_name(backend)}"

    def _sizes(self, model: StepModel, pat: Pattern) -> dict[str, int]:
        nv, k, nc = model.nv, model.k, len(pat.closed)
        m_all = model.m + nc
        return dict(
            a=nv,
            u=m_all,
            reaction=nv,
            compulsion=1,
            residual=k + nc,
            Phi=k,
            a_free=nv,
            S=0 if self.sparse else (k + nc) * m_all,
            tracking_error=1,
            at_bound=m_all,
            saturated_branch=1,
            qdot=model.nq,
            energy=1,
            power=1,
            power_reaction=1,
            g=k,
            gc=self.nc_all,
        )

    def _function(self, model: StepModel, pat: Pattern, backend: CasadiConic, tol: float, cap: float) -> ca.Function:
        """One MX graph: the model's data and the QP's data in one SX function, the QP(s), one SX function after."""
        gr = _Graph(model, pat, tol, cap)
        ins = model.inputs
        mk, n_rows = len(gr.kc), gr.Aqp.shape[0]
        carry = _carry(model, pat, gr)
        syms = {name: ca.SX.sym(name, ca.Sparsity.dense(*ca.SX(value).shape)) for name, value in carry.items()}
        if not (gr.T or gr.C or pat.closed or np.isfinite(gr.lower).any() or np.isfinite(gr.upper).any()):
            # equality rows only: the QP in closed form, ũ = H⁻¹Sᵀ(S H⁻¹ Sᵀ)⁻¹ r — one flat SX function
            post = self._post(model, pat, gr, syms, mk, n_rows)
            symmetric = bool(getattr(model, "symmetric_S", False)) and pat.kept_rows == pat.kept_cols
            x, lam_a = (_symmetric_qp if symmetric else _equality_qp)(gr.H, gr.Aqp, gr.lba, gr.drift)
            outs = post.call([*carry.values(), x, lam_a, ca.SX.zeros(mk), gr.lba, gr.uba, ca.SX(0), ca.SX.zeros(mk)])
            return ca.Function("general_step", ins, ca.cse([ca.densify(o) for o in outs]))
        qp_data = [gr.H, gr.Aqp, gr.lba, gr.uba, gr.lbx, gr.ubx]
        if gr.T:
            qp_data += [gr.Ht, gr.gt, gr.At, gr.lbt, gr.ubt, gr.S[gr.T, gr.kc]]
        pre = ca.Function("general_pre", ins, ca.cse([ca.densify(ca.SX(x)) for x in [*qp_data, *carry.values()]]))
        mx_in = [ca.MX.sym(f"in{i}", s.sparsity()) for i, s in enumerate(ins)]
        parts = pre.call(mx_in)
        H, Aqp, lba, uba, lbx, ubx = parts[:6]
        carried = parts[len(qp_data) :]
        conic = _conic("general_qp", backend, mk, n_rows)
        sol = conic(h=H, g=ca.MX.zeros(mk), a=Aqp, lba=lba, uba=uba, lbx=lbx, ubx=ubx)
        x, lam_a, lam_x = sol["x"], sol["lam_a"], sol["lam_x"]
        saturated = ca.MX(0)
        x_track = ca.MX.zeros(mk)
        if gr.T:
            Ht, gt, At, lbt, ubt, St = parts[6:12]
            feasible = _violation(Aqp, lba, uba, lbx, ubx, x) <= FEASIBILITY_TOL
            track = _conic("general_track", backend, mk, At.shape[0])
            xt = track(h=Ht, g=gt, a=At, lba=lbt, uba=ubt, lbx=lbx, ubx=ubx)["x"]
            reached = St @ xt
            nK = len(gr.K)
            before, after = range(nK), range(nK + len(gr.T), n_rows)
            lba2 = ca.vertcat(*(lba[i] for i in before), reached, *(lba[i] for i in after))
            uba2 = ca.vertcat(*(uba[i] for i in before), reached, *(uba[i] for i in after))
            sol2 = conic(h=H, g=ca.MX.zeros(mk), a=Aqp, lba=lba2, uba=uba2, lbx=lbx, ubx=ubx)
            x = ca.if_else(feasible, x, sol2["x"], True)
            lam_a = ca.if_else(feasible, lam_a, sol2["lam_a"], True)
            lam_x = ca.if_else(feasible, lam_x, sol2["lam_x"], True)
            lba = ca.if_else(feasible, lba, lba2, True)
            uba = ca.if_else(feasible, uba, uba2, True)
            saturated = 1 - feasible
            x_track = xt
        post = self._post(model, pat, gr, syms, mk, n_rows)
        packed = post.call([*carried, x, lam_a, lam_x, lba, uba, saturated, x_track])
        return ca.Function("general_step", mx_in, packed)

    def _post(
        self, model: StepModel, pat: Pattern, gr: _Graph, G: dict[str, ca.SX], mk: int, n_rows: int
    ) -> ca.Function:
        """``(carried data, x, λ_a, λ_x, lba, uba, saturated, x_track) ↦ [packed, flag, closed as the gaps say]``."""
        x, lam_a, lam_x = ca.SX.sym("x", mk), ca.SX.sym("lam_a", n_rows), ca.SX.sym("lam_x", mk)
        lba, uba = ca.SX.sym("lba", n_rows), ca.SX.sym("uba", n_rows)
        sat, x_track = ca.SX.sym("saturated"), ca.SX.sym("x_track", mk)
        m_all = model.m + len(pat.closed)
        lower, upper = gr.lower, gr.upper
        unit, cs = G["unit"], G["cs"]
        # back to the problem's units (u scaled to unit size: ũ / c)
        u = ca.SX.zeros(m_all)
        u[gr.kc] = x / cs[gr.kc]
        dropped_cols = [j for j in range(m_all) if j not in gr.kc]
        if dropped_cols:  # least norm along the null directions N = [−C; I] of W (no bounds act here)
            Wk, Wd = G["W"][:, gr.kc], G["W"][:, dropped_cols]
            Cmb = ca.solve(Wk.T @ Wk, Wk.T @ Wd)
            N = ca.SX.zeros(m_all, len(dropped_cols))
            N[gr.kc, :] = -Cmb
            N[dropped_cols, :] = ca.DM.eye(len(dropped_cols))
            u = u - N @ ca.solve(N.T @ N, N.T @ u)
        u = u * unit
        fin_lo, fin_hi = np.isfinite(lower), np.isfinite(upper)
        at_bound = ca.SX.zeros(m_all)
        if fin_lo.any() or fin_hi.any():
            lo_c = ca.DM(np.where(fin_lo, lower, -1e300))
            hi_c = ca.DM(np.where(fin_hi, upper, 1e300))
            u = ca.fmin(ca.fmax(u, lo_c), hi_c)
            tol = 1e-9 * (1 + ca.fabs(u))
            at_lo = ca.logic_and(ca.DM(fin_lo), (u - lo_c) <= tol)
            at_hi = ca.logic_and(ca.DM(fin_hi), (hi_c - u) <= tol)
            u = ca.if_else(at_hi, hi_c, ca.if_else(at_lo, lo_c, u))
            at_bound = ca.logic_or(at_lo, at_hi)
            reaction_w = G["W"] @ u  # a saturated actuator delivers exactly its bound
        else:
            reaction_w = G["Wk"] @ x * unit  # the reaction from the QP's own point
        a = G["a0"] + ca.solve(G["R"], reaction_w)
        reaction = G["r0"] + G["D_all"] @ u
        residual = G["J_all"] @ a - G["phi_all"]
        tracking = ca.SX(0)
        if gr.T:
            tracking = sat * ca.norm_2(G["St"] @ x_track - G["rt"]) * unit
        H, Aqp = G["H"], G["Aqp"]
        checks = [G["watch"] > 0]
        checks.append(_violation(Aqp, lba, uba, G["lbx"], G["ubx"], x) <= FEASIBILITY_TOL)
        stat = H @ x + (Aqp.T @ lam_a if n_rows else 0) + lam_x
        dual_scale = 1 + ca.mmax(ca.fabs(H @ x)) if mk else 1
        checks.append((ca.mmax(ca.fabs(stat)) if mk else ca.SX(0)) <= DUAL_TOL * dual_scale)
        outs = [
            a,
            u,
            reaction,
            ca.dot(reaction_w, reaction_w),
            residual,
            G["Phi"],
            G["a_free"],
            G["S"],
            tracking,
            at_bound,
            sat,
            G["qdot"],
            G["energy"],
            G["power"],
            ca.dot(G["v"], reaction),
            G["g"],
            G["gc"],
        ]
        packed = ca.vertcat(*(ca.vec(ca.densify(ca.SX(o))) for o in outs))
        checks.append(ca.fabs(ca.sum1(packed)) < ca.inf)
        flag = checks[0]
        for chk in checks[1:]:
            flag = ca.logic_and(flag, chk)
        return ca.Function(
            "general_post",
            [*G.values(), x, lam_a, lam_x, lba, uba, sat, x_track],
            [ca.vertcat(packed, flag, G["closed_ok"])],
        )

    @property
    def function(self) -> ca.Function:
        """The compiled step ``(t, q, v, λ, stab) ↦ [packed outputs (:attr:`slices`), flag, closed as the gaps say]``
        (to build larger graphs: a pattern with equality rows only is one SX function)."""
        return self._bound.fn

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, stab: np.ndarray) -> np.ndarray | None:
        """The packed outputs (a copy), or ``None`` when the flag is down (or the gaps close other contacts and the
        caller did not name them)."""
        args = self._args
        args[0][0] = t
        args[1][:] = q
        args[2][:] = v
        args[3][:] = lam
        args[4][:] = stab
        self._bound.eval()
        out = self._out
        if out[-2] != 1.0 or (not self.pattern.given and out[-1] != 1.0):
            return None
        return out[:-2].copy()
