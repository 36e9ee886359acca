"""The integral principle (paper §6, inequality (23); docs/theory.md §4): is a path a motion of a model?

For a path ``x(t)`` on the constraint put ``R(t) = [T] − F = A ẍ − f`` along it. The path is a
motion of the model iff, for every variation ``η`` vanishing at ``t₁, t₂`` and satisfying the
realization's relation (20) ``E1 η̇ + E0 η = 0``,

    (1/T) ∫ (G⁻¹(R + Gη), R + Gη) dt  ≥  (1/T) ∫ (G⁻¹R, R) dt            (23)

for any positive definite ``G`` (the paper's ``A``). The left side minus the right is
``(1/T) ∫ 2(R, η) + (Gη, η) dt``: its minimum over admissible ``η`` is ``−gap ≤ 0``, and
``gap = 0`` exactly when ``R`` does no work on any admissible variation (21).

Discretization: ``η`` at the path's nodes with ``η = 0`` at both ends; the integral by the
trapezoid rule; a pointwise relation (``N = 0``: ideal and force realizations) at each interior
node; a differential one (``N ≠ 0``) by the midpoint rule on each interval — second order, so
for a true motion the relative gap falls like ``h⁴`` (pointwise relations: like the error of
the path's acceleration, squared), while a path of another realization keeps a gap of order
one. The result is a sparse convex QP posed with casadi's ``conic`` interface. For pointwise
relations it decouples in time and has a closed form, a second path that cross-checks the QP.

The multipliers of the discrete (20) reproduce ``λ(t)``: ``λ = −μ/w`` at nodes (trapezoid
weight ``w``) and ``λ = −ν/h`` at interval midpoints.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.interpolate import make_interp_spline

from ..errors import InitialDataError, InputError, NonFiniteError, QPSolveError, ShapeError, UnknownNameError
from ..model.model import Model
from ..step.general import RANK_TOL
from ..validation import array, positive, short
from ..workspace import workspace

#: Relative gap below which a path counts as a motion whatever the refinement says (round-off).
GAP_FLOOR = 1e-8


@dataclass(frozen=True)
class Verification:
    """What :func:`verify` found.

    Attributes
    ----------
    t : (N+1,) array
        Nodes of the discretization.
    value_at_zero : float
        ``(1/T) ∫ (G⁻¹R, R) dt``, the right side of (23).
    minimum : float
        The minimum of the left side of (23) over admissible variations.
    gap, relative_gap : float
        ``value_at_zero − minimum ≥ 0`` and the gap over :func:`normalizer` (``value_at_zero``
        unless the path has no relation rows).
    coarse_relative_gap : float
        The relative gap on every other node: a motion's gap falls under refinement, a
        non-motion's does not.
    tolerance : float
        The relative gap below which ``is_motion`` holds: ``max(GAP_FLOOR, coarse_relative_gap/8)``.
    is_motion : bool
    delta_x : (N+1, nv) array
        The minimizing variation: where and how the path fails.
    multipliers : (N+1, k) array
        ``λ`` recovered from the discrete (20), at the nodes (NaN where undefined: the ends of
        pointwise rows).
    method : str
    pieces : tuple of Verification
        A trajectory with events (contacts) or actuator saturation is verified piece by piece
        (:mod:`gausspp.verification.pieces`): the verification of each smooth piece; empty for one smooth path.
    skipped : tuple of dict
        Pieces that were not verified, each ``{"t": (t1, t2), "reason": str}``.
    message : str
        What was checked, in words (and what was not).
    """

    t: np.ndarray
    value_at_zero: float
    minimum: float
    gap: float
    relative_gap: float
    coarse_relative_gap: float
    tolerance: float
    is_motion: bool
    delta_x: np.ndarray
    multipliers: np.ndarray
    method: str
    pieces: tuple[Verification, ...] = ()
    skipped: tuple[dict[str, Any], ...] = ()
    message: str = ""


@dataclass(frozen=True)
class Discretized:
    """(23) on nodes: ``R``, metric ``G`` and the relation (20) per constraint row.

    ``E1``/``E0`` are ``(N+1, k, n)``; rows with ``pointwise[r]`` true have ``E1 = 0`` and hold
    at each interior node, the others on each interval by the midpoint rule. ``f`` (optional)
    is the known force ``F − h`` (plus any known reaction), the scale of a path with no relation
    rows (see :func:`normalizer`).
    """

    t: np.ndarray
    R: np.ndarray
    G: np.ndarray
    E1: np.ndarray
    E0: np.ndarray
    pointwise: np.ndarray
    f: np.ndarray | None = None

    def every_other(self) -> Discretized:
        idx = np.arange(0, self.t.size, 2)
        if idx[-1] != self.t.size - 1:
            idx = np.append(idx, self.t.size - 1)
        f = None if self.f is None else self.f[idx]
        return Discretized(self.t[idx], self.R[idx], self.G[idx], self.E1[idx], self.E0[idx], self.pointwise, f)


# -- model side: the data of (23) along a path --------------------------------------------------
def data_function(model: Model) -> ca.Function:
    """``(t, q, v, a) -> (R, A, E1, E0, Φ, g, f)`` along a path (kept in the model's workspace)."""
    return workspace(model).get(("integral-data",), lambda: _build_data_function(model))


def _build_data_function(model: Model) -> ca.Function:
    mech = model.mechanism
    a = ca.SX.sym("a", mech.nv)
    E1s, E0s, pointwise = [], [], []
    for c in model.constraints:
        rel = c.realization.virtual_displacements(mech, c.expressions(mech), a)
        k = rel.E0.shape[0]
        E1s.append(rel.E1 if rel.E1 is not None else ca.SX.zeros(k, mech.nv))
        E0s.append(rel.E0)
        pointwise += [rel.E1 is None] * k
    p = model.expressions
    assert p.g is not None  # a model's step always carries its holonomic residuals
    R = p.A @ a - p.f
    E1, E0 = (ca.vertcat(ca.SX(0, mech.nv), *E) for E in (E1s, E0s))  # no rows: a free model (contact flight)
    fn = ca.Function("integral_data", [mech.t, mech.q, mech.v, a], [R, p.A, E1, E0, p.Phi, p.g, p.f])
    fn.pointwise = np.array(pointwise, dtype=bool)  # type: ignore[attr-defined]
    return fn


def _window(window: Any) -> tuple[float, float]:
    """``window`` as two finite times ``(t1, t2)``."""
    ends = array("verify", "window", window)
    if ends.shape != (2,):
        raise ShapeError(f"window must be two times (t1, t2), got {short(window)}")
    return float(ends[0]), float(ends[1])


def path_samples(trajectory: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    get = trajectory.get if isinstance(trajectory, Mapping) else lambda k, d=None: getattr(trajectory, k, d)
    missing = [k for k in ("t", "q", "v") if get(k, None) is None]
    if missing:
        raise InputError(
            f"trajectory must be a gp.Trajectory (from gp.simulate) or a mapping with t, q and v; got "
            f"{type(trajectory).__name__} {short(trajectory)} without {', '.join(missing)}"
        )
    t, q, v = (array("trajectory", k, get(k), finite=False) for k in ("t", "q", "v"))  # located below if not
    a = get("a", None)
    a = None if a is None else array("trajectory", "a", a, finite=False)
    return t, np.atleast_2d(q.T).T, np.atleast_2d(v.T).T, None if a is None else np.atleast_2d(a.T).T


def check_samples(t: np.ndarray, q: np.ndarray, v: np.ndarray, *, monotone: bool = True) -> None:
    """Finite samples, at least 2, with ``t`` strictly increasing (or, ``monotone=False``, non-decreasing:
    a trajectory with velocity jumps records two samples at each jump's time)."""
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
        bad = int(np.flatnonzero(~(np.isfinite(q).all(1) & np.isfinite(v).all(1) & np.isfinite(t)))[0])
        raise NonFiniteError(f"trajectory: sample {bad} (t={t[bad]:.6g}) is not finite; cut the window before it")
    step = np.diff(t)
    if t.size < 2 or np.any(step <= 0 if monotone else step < 0):
        order = "strictly increasing" if monotone else "non-decreasing"
        raise InputError(f"trajectory: t must be {order} with at least 2 samples")


def check_model(model: Any) -> None:
    if not isinstance(model, Model):
        raise InputError(f"model must be a gp.Model, got {short(model)}")


def discretize(
    model: Model,
    trajectory: Any,
    *,
    window: tuple[float, float] | None = None,
    nodes: int | None = None,
    metric: str | np.ndarray = "A",
    acceleration: str = "path",
    constraint_tol: float = 1e-6,
) -> Discretized:
    """Evaluate ``R``, the metric and (20) on the nodes of a path (checked)."""
    check_model(model)
    if nodes is not None:
        nodes = positive("nodes", nodes, integer=True, hint=" (uniform nodes in the window, at least 5)")
    t, q, v, a = path_samples(trajectory)
    N = t.size
    if q.shape != (N, model.nq) or v.shape != (N, model.nv):
        raise ShapeError(
            f"trajectory: q and v must be ({N}, {model.nq}) and ({N}, {model.nv}), got {q.shape}, {v.shape}"
        )
    check_samples(t, q, v)
    # samples closer than 1e-9 of the span (an adaptive integrator's last sliver of a step) carry no
    # information and would spoil the splines: keep the later of each such pair
    keep = np.append(np.diff(t) > 1e-9 * (t[-1] - t[0]), True)
    keep[0] = True
    t, q, v = t[keep], q[keep], v[keep]
    a = a[keep] if a is not None else None
    N = t.size
    t1, t2 = (t[0], t[-1]) if window is None else _window(window)
    if not (t[0] <= t1 < t2 <= t[-1]):
        raise InputError(f"window ({t1:g}, {t2:g}) is outside the data [{t[0]:g}, {t[-1]:g}] or empty")
    if acceleration not in ("path", "recorded"):
        raise UnknownNameError(f"acceleration={acceleration!r} is unknown; use 'path' (from v(t)) or 'recorded'")
    if acceleration == "recorded" and a is None:
        raise InputError("acceleration='recorded' needs the trajectory's accelerations a")
    recorded = a if a is not None else v  # (only read when acceleration == "recorded")
    if N < 6:
        raise InputError(f"trajectory: {N} samples; the path's acceleration needs at least 6")
    v_spline = make_interp_spline(t, v, k=5, axis=0)  # quintic: ẍ from v(t) with O(h⁵) error
    path_a = v_spline.derivative()
    if nodes is None:
        inside = (t >= t1 - 1e-12) & (t <= t2 + 1e-12)
        tn, qn, vn = t[inside], q[inside], v[inside]
        an = recorded[inside] if acceleration == "recorded" else path_a(tn)
    else:
        tn = np.linspace(t1, t2, int(nodes))
        qn = np.array([model.mechanism.normalize_array(x) for x in make_interp_spline(t, q, k=5, axis=0)(tn)])
        vn = v_spline(tn)
        an = make_interp_spline(t, recorded, k=5, axis=0)(tn) if acceleration == "recorded" else path_a(tn)
    if tn.size < 5:
        raise InputError(
            f"too few nodes in the window: {tn.size}; the discretization needs at least 5 (pass nodes=...)"
        )
    fn = data_function(model)
    out = fn.map(tn.size)(tn[None, :], qn.T, vn.T, an.T)
    R, A, E1, E0, Phi, g, f = (np.array(x) for x in out)
    n, k, N1 = model.nv, model.k, tn.size
    r = fn.pointwise.size  # type: ignore[attr-defined]  # rows of the relations (20): k unless a realization has more
    Phi, g = Phi.reshape(k, N1), g.reshape(k, N1)
    worst = float(max(np.abs(Phi).max(initial=0.0), np.abs(g).max(initial=0.0)))
    if worst > constraint_tol:
        i = int(np.argmax(np.abs(Phi).max(0) + np.abs(g).max(0)))
        raise InitialDataError(
            f"the path is off the constraint at t={tn[i]:.6g} (|Φ| or |g| = {worst:.3g} > {constraint_tol:g}); "
            "(23) compares paths on the constraint: project the data or raise constraint_tol"
        )
    A = A.reshape(n, -1, n).transpose(1, 0, 2) if n > 1 else A.reshape(-1, 1, 1)
    G = _metric(metric, A, n)
    return Discretized(
        t=tn,
        R=R.reshape(n, N1).T,
        G=G,
        E1=E1.reshape(r, N1, n).transpose(1, 0, 2),
        E0=E0.reshape(r, N1, n).transpose(1, 0, 2),
        pointwise=fn.pointwise,  # type: ignore[attr-defined]
        f=f.reshape(n, N1).T,
    )


def _metric(metric: str | np.ndarray, A: np.ndarray, n: int) -> np.ndarray:
    if isinstance(metric, str):
        if metric == "A":
            return A
        if metric == "identity":
            return np.broadcast_to(np.eye(n), A.shape).copy()
        raise UnknownNameError(f"metric={metric!r} is unknown; use 'A', 'identity' or an SPD (n, n) array")
    G = np.asarray(metric, float)
    if G.shape != (n, n) or not np.allclose(G, G.T) or np.linalg.eigvalsh(0.5 * (G + G.T)).min() <= 0:
        raise InputError(f"metric must be a symmetric positive definite ({n}, {n}) array")
    return np.broadcast_to(G, A.shape).copy()


# -- the discrete problem ---------------------------------------------------------------------
def _weights(t: np.ndarray) -> np.ndarray:
    h = np.diff(t)
    w = np.zeros(t.size)
    w[:-1] += h / 2
    w[1:] += h / 2
    return w


def _mean_square(t: np.ndarray, G: np.ndarray, X: np.ndarray) -> float:
    """``(1/T) ∫ (G⁻¹X, X) dt`` by the trapezoid rule."""
    quad = np.einsum("ni,ni->n", X, np.linalg.solve(G, X[..., None])[..., 0])
    return float(_weights(t) @ quad / (t[-1] - t[0]))


def value_at_zero(d: Discretized) -> float:
    """``(1/T) ∫ (G⁻¹R, R) dt`` by the trapezoid rule."""
    return _mean_square(d.t, d.G, d.R)


def normalizer(d: Discretized) -> float:
    """What the gap is measured against: ``value_at_zero``, or for a path with no relation rows the forces' size.

    With relation rows the relative gap is the share of ``(G⁻¹R, R)`` that does work on admissible
    variations. Without any (a free piece: a body in flight between contacts, a saturated servo
    whose force is known) every variation is admissible, the gap is all of ``value_at_zero`` and
    the relative gap would be 1 for any path; there ``R = A ẍ − f`` must vanish, and the gap is
    measured against ``(1/T) ∫ (G⁻¹Aẍ, Aẍ) + (G⁻¹f, f) dt``, the size of the terms it balances.
    """
    if d.E0.shape[1] or d.f is None:
        return value_at_zero(d)
    return _mean_square(d.t, d.G, d.R + d.f) + _mean_square(d.t, d.G, d.f)


def solve_qp(d: Discretized) -> tuple[float, np.ndarray, np.ndarray]:
    """Minimize the left side of (23) over admissible ``η``: ``(minimum − value_at_zero, η, λ)``."""
    N1, n = d.t.size, d.R.shape[1]
    k = d.E0.shape[1]
    m = N1 - 2  # interior nodes
    w, h = _weights(d.t), np.diff(d.t)
    H = sp.block_diag([w[i] * d.G[i] for i in range(1, N1 - 1)], format="csc")
    g = np.concatenate([w[i] * d.R[i] for i in range(1, N1 - 1)])
    row_kind: list[tuple[str, int, int]] = []  # ("interval", j, r) per differential constraint row
    blocks: list[sp.spmatrix] = []
    point = np.flatnonzero(d.pointwise)
    diff = np.flatnonzero(~d.pointwise)
    back: list[tuple[int, np.ndarray]] = []  # per node with pointwise rows: (i, P) with μ = P y
    if point.size:
        for i in range(1, N1 - 1):
            rows, P = _independent_rows(d.E0[i][point])
            B = sp.lil_matrix((rows.shape[0], m * n))
            B[:, (i - 1) * n : i * n] = rows
            blocks.append(B)
            back.append((i, P))
    if diff.size:
        for j in range(N1 - 1):
            E1 = 0.5 * (d.E1[j][diff] + d.E1[j + 1][diff])
            E0 = 0.5 * (d.E0[j][diff] + d.E0[j + 1][diff])
            B = sp.lil_matrix((diff.size, m * n))
            if j >= 1:
                B[:, (j - 1) * n : j * n] = -E1 / h[j] + E0 / 2
            if j + 1 <= N1 - 2:
                B[:, j * n : (j + 1) * n] = E1 / h[j] + E0 / 2
            blocks.append(B)
            row_kind += [("interval", j, int(r)) for r in diff]
    B = sp.vstack(blocks, format="csc") if blocks else sp.csc_matrix((0, m * n))
    x, y = _conic(H, g, B)
    eta = np.zeros((N1, n))
    eta[1:-1] = x.reshape(m, n)
    value = float(g @ x + 0.5 * x @ (H @ x))  # Σ w (Rη + ½ηGη)
    lam = np.full((N1, k), np.nan)
    mids = np.full((N1 - 1, k), np.nan)
    at = 0
    for i, P in back:
        lam[i, point] = -(P @ y[at : at + P.shape[1]]) / w[i]
        at += P.shape[1]
    for (_kind, j, r), yj in zip(row_kind, y[at:], strict=True):
        mids[j, r] = -yj / h[j]
    if diff.size:  # midpoints → nodes: average inside, extrapolate at the ends
        lam[1:-1, diff] = 0.5 * (mids[:-1, diff] + mids[1:, diff])
        lam[0, diff] = 1.5 * mids[0, diff] - 0.5 * mids[1, diff]
        lam[-1, diff] = 1.5 * mids[-1, diff] - 0.5 * mids[-2, diff]
    return 2.0 * value / (d.t[-1] - d.t[0]), eta, lam


def _independent_rows(E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal rows ``Vᵣᵀ`` spanning the rows of ``E = U S Vᵀ`` and the map ``P = Uᵣ Sᵣ⁻¹`` back.

    Dependent rows (redundant constraints: the rows of ``J`` of a closed loop given twice) make
    the QP's equality matrix rank-deficient, and the sparse QR then returns no solution at all
    (``η = 0``: a vacuous verdict). ``Vᵣᵀ η = 0`` has the same solutions as ``E η = 0``; a
    multiplier ``y`` of the former is ``μ = P y`` of the latter, the one of least norm.
    """
    if E.shape[0] == 0:
        return E, np.zeros((0, 0))
    U, S, Vt = np.linalg.svd(E, full_matrices=False)
    r = int(np.sum(S > RANK_TOL * max(S[0], np.finfo(float).tiny)))
    return Vt[:r], U[:, :r] / S[:r]


def _conic(H: sp.spmatrix, g: np.ndarray, B: sp.spmatrix) -> tuple[np.ndarray, np.ndarray]:
    """The equality-constrained convex QP through casadi's conic interface (sparse QR, qrqp)."""
    Hd, Bd = ca.DM(H), ca.DM(B)
    solver = ca.conic(
        "integral_qp",
        "qrqp",
        {"h": Hd.sparsity(), "a": Bd.sparsity()},
        {"print_iter": False, "print_header": False, "print_info": False, "error_on_fail": False},
    )
    zero = np.zeros(B.shape[0])
    sol = solver(h=Hd, g=g, a=Bd, lba=zero, uba=zero)
    x, y = np.array(sol["x"]).ravel(), np.array(sol["lam_a"]).ravel()
    residual = float(np.abs(B @ x).max(initial=0.0)) if np.all(np.isfinite(x)) else float("nan")
    if not residual <= 1e-8 * (1 + np.abs(x).max(initial=0.0)):
        raise QPSolveError(
            f"the discretized (23) was not solved accurately: the relation (20) is violated by {residual:.3g} "
            f"(qrqp status {solver.stats().get('return_status')!r}); the nodes may be too coarse or nearly repeated"
        )
    return x, y


def solve_closed_form(d: Discretized) -> tuple[float, np.ndarray, np.ndarray]:
    """Pointwise relations only: at each interior node minimize over ``ker E0``: ``η = −G⁻¹(R − E0ᵀμ)``."""
    if not d.pointwise.all():
        raise InputError("the closed form needs pointwise relations (N = 0); use method='qp'")
    N1, n = d.R.shape
    w = _weights(d.t)
    eta = np.zeros((N1, n))
    lam = np.full((N1, d.E0.shape[1]), np.nan)
    total = 0.0
    for i in range(1, N1 - 1):
        G, R, E = d.G[i], d.R[i], d.E0[i]
        GiE = np.linalg.solve(G, E.T)
        mu = np.linalg.lstsq(E @ GiE, E @ np.linalg.solve(G, R), rcond=None)[0]
        perp = R - E.T @ mu
        eta[i] = -np.linalg.solve(G, perp)
        lam[i] = mu
        total -= w[i] * perp @ np.linalg.solve(G, perp)
    return total / (d.t[-1] - d.t[0]), eta, lam


def verdict(ver: Verification) -> str:
    """The verdict in words, with the figures it rests on."""
    word = "a motion" if ver.is_motion else "NOT a motion"
    return f"{word} (relative gap {ver.relative_gap:.2e}, tolerance {ver.tolerance:.2e}, {ver.t.size} nodes)"


def judge(d: Discretized, method: str = "qp") -> Verification:
    """Solve the discretized (23) on ``d`` and on every other node, and give the verdict."""
    solve = solve_qp if method == "qp" else solve_closed_form
    difference, eta, lam = solve(d)
    zero, scale = value_at_zero(d), normalizer(d)
    gap = max(0.0, -difference)  # (never −0.0)
    coarse = d.every_other()
    coarse_gap = max(-solve(coarse)[0], 0.0) if coarse.t.size >= 5 else np.nan
    rel = gap / scale if scale > 0 else 0.0
    coarse_scale = normalizer(coarse)
    coarse_rel = coarse_gap / coarse_scale if coarse_scale > 0 else 0.0
    tol = max(GAP_FLOOR, coarse_rel / 8) if np.isfinite(coarse_rel) else GAP_FLOOR
    return Verification(
        t=d.t,
        value_at_zero=zero,
        minimum=zero - gap,
        gap=gap,
        relative_gap=rel,
        coarse_relative_gap=coarse_rel,
        tolerance=tol,
        is_motion=rel <= tol,
        delta_x=eta,
        multipliers=lam,
        method=method,
    )
