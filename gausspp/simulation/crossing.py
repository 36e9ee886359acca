"""Crossing a singular position of a linkage: the adaptive lane steps over the instant where its rows' rank drops.

A parallelogram four-bar written in maximal coordinates has independent rows except where its bars lie in line:
there ``J`` loses a rank and a second assembly branch (the anti-parallelogram) crosses the motion's. The motion
itself is smooth through that instant — ideal reactions are orthogonal to the branch the linkage moves on, the
velocity is continuous — but the step's formula ``q̈ = q̈₀ + A⁻¹Jᵀ(JA⁻¹Jᵀ)⁻¹(φ − Jq̈₀)`` amplifies any drift by
``1/σ``, ``σ`` the smallest kept singular value of the (normalized) rows, which vanishes linearly in time there.
An error-controlled integrator sees that amplification as stiffness and shrinks its step towards the instant
without reaching it (Zeno).

Continuity of the motion is what carries it across. :class:`SingularityWatch` follows ``σ_r`` (``r``: the rank of
the rows on the open pieces of the motion) at every accepted state; when its linear trend reaches zero within
the next step, the instant ``t*`` is estimated and :func:`bridge` takes **one** step of DOP853 (8th order) from
the last accepted state ``t_a`` to ``t_b = t_a + (t* − t_a)/FRACTION``. Its stages sit at fixed fractions of the
step, none nearer ``t*`` than 13 % of it (the gap of DOP853's nodes between 1/3 and 3/5), so the ill-conditioned
neighbourhood is never evaluated; the step's error is the method's, ``O(h⁹)``, as on any step of that size. The
state reached is projected back onto the constraints (position, then velocity), which keeps the branch the
velocity points along: the other branch is ``O(h)`` away, the step's error ``O(h⁹)``. A correction larger than
:data:`BRANCH_SHARE` of the distance travelled would mean a jump to the other branch: the run stops with an
:class:`~gausspp.IntegrationError` instead.

It applies where the argument holds: every row holonomic and ideal (reactions along the rows, ``D = J``), no
bounded actuators or contacts, up to :data:`MAX_COORDINATES` coordinates (one SVD per accepted step). A realization
that is not ideal losing its margin is a different matter — the realization cannot keep the constraint there
(:mod:`gausspp.simulation.margins`) — and is not crossed.

Each crossing is an event of the trajectory: ``{"t": t*, "kind": "singular position", "from": t_a, "to": t_b,
"correction": |Δq|∞ of the projection}``. A singular position that one of the run's own steps went over (loose
tolerances, long steps) is an event too, without ``"correction"``: ``σ_r`` fell and rose again and changed sign in
between, which the singular vectors at the samples tell (:func:`sign_changed`); a dip of ``σ_r`` that stays above
zero (the pendulum's pin) changes no sign, and the watch makes no approach where ``σ_r``'s trend flattens out
(:data:`CONVEX`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
import scipy.integrate as si

from ..errors import GaussppError, IntegrationError
from ..model.model import Model
from ..step.bound import Bound, load_inputs
from ..workspace import workspace
from .initial import Projection

#: Where ``t*`` lies in the bridging step, as a fraction of it: midway in the widest gap of DOP853's nodes
#: (``1/3`` and ``3/5``), so that no stage is nearer the singular instant than 13 % of the step.
FRACTION = 0.466
#: Rows of the normalized ``J`` whose singular value is below this (relative to the largest) at the start are
#: dependent there: the watched one is the smallest above it.
RANK_TOL = 1e-8
#: The watch plans a crossing when ``σ_r = 0`` is estimated within this many steps ahead (the longest of the last
#: :data:`REMEMBER`: the integrator shortens its steps before a singular position, its step of a moment ago is the
#: motion's).
LOOKAHEAD = 2.0
REMEMBER = 8
#: … unless Newton's zero lies beyond this times the secant's: ``σ_r`` flattening out, the bottom of a dip above zero
#: (the pendulum's pin, 2.7) — where it does reach zero it is linear or steepening (the parallelogram, ≤ 1.0
#: measured at every approach): the next samples, nearer, tell again.
CONVEX = 1.5
#: The bridge is at most this share of the run's recent longest step: a step that evaluates the motion near a
#: singular position is less accurate than an ordinary step of its length (measured on the parallelogram at
#: rtol = 1e-12: a 1e-10 J energy error per bridge at the full step, none seen at 0.6 of it).
BRIDGE_SHARE = 0.6
#: The bridge starts where ``t*`` is estimated within this times ``FRACTION`` of the recent longest step.
CLOSE_ENOUGH = 1.2
#: … and when two successive estimates agree within this share of the distance to it: ``σ_r`` vanishes there,
#: where a dip of ``σ_r`` that stays above zero (two singular values changing places) moves the estimate away.
AGREE = 0.1
#: A minimum of ``σ_r`` below this between two samples is checked for a singular position a step went over (loose
#: tolerances step over one in steps across which ``σ_r`` changes by ~0.4).
WENT_OVER_BELOW = 0.5
#: … by the change of sign of ``σ_r``, told where the singular vectors turned less than this (``|cos|``).
ALIGNED = 0.5
#: … and only once ``σ_r`` has fallen below this (unit-free, ``σ ≤ 1``): far from a singular position a falling
#: trend is no reason to step over anything.
WATCH_BELOW = 0.2
#: A projection after the bridge that moves ``q`` by more than this share of the distance travelled would be a jump
#: to another branch (they part linearly from ``t*``): refused.
BRANCH_SHARE = 1e-2
#: A row shorter than this share of its length at the start is scaled by that share of it, not to unit length: in
#: joint coordinates a row can vanish whole at a singular position (:func:`_normalized_rows`), while a row's length
#: in maximal coordinates varies by tens of percent along a motion with no singular position at all.
FLOOR_SHARE = 0.1
#: The watch computes an SVD of the rows at every accepted state: models up to this many coordinates.
MAX_COORDINATES = 120


def applies(model: Model) -> bool:
    """Whether a run of ``model`` may cross singular positions (module docstring): ideal holonomic rows only."""
    return (
        model.k > 0
        and len(model.holonomic_rows) == model.k
        and model.symmetric_S
        and not model.bounded
        and not model.contacts
        and model.nv <= MAX_COORDINATES
    )


def smallest_kept(
    model: Model, t: float, y: np.ndarray, rank: int | None = None, floor: np.ndarray | None = None
) -> tuple[float, int]:
    """``(σ_r, r)``: the ``r``-th singular value of the rows ``J`` normalized in the kinetic metric (``J L⁻ᵀ``,
    ``A = L Lᵀ``, each row scaled to unit length — or by ``floor`` where its length falls below it), and ``r``
    (counted at this state unless given)."""
    rows = _normalized_rows(model, t, y, floor)
    sigma = np.linalg.svd(rows, compute_uv=False) if rows.size else np.zeros(0)
    if rank is None:
        rank = int(np.count_nonzero(sigma > RANK_TOL * sigma[0])) if sigma.size else 0
    return (float(sigma[rank - 1]) if 0 < rank <= sigma.size else 0.0), rank


def smallest_pair(
    model: Model, t: float, y: np.ndarray, rank: int, floor: np.ndarray | None = None
) -> tuple[float, np.ndarray, np.ndarray]:
    """``(σ_r, u, v)``: :func:`smallest_kept`'s singular value with its left and right singular vectors."""
    U, sigma, Vt = np.linalg.svd(_normalized_rows(model, t, y, floor), full_matrices=False)
    return float(sigma[rank - 1]), U[:, rank - 1], Vt[rank - 1]


def _normalized_rows(model: Model, t: float, y: np.ndarray, floor: np.ndarray | None = None) -> np.ndarray:
    """The rows ``J L⁻ᵀ``, each divided by its length — or by ``floor`` where the length falls below it: in joint
    coordinates a row can vanish whole at a singular position (a planar loop's ``x`` row when its bars lie along
    ``x``), and scaled to unit length it would hide the rank it loses."""
    rows, norms = _unit_rows(model, t, y)
    if floor is not None:
        scaled = rows * (norms / np.maximum(np.maximum(norms, floor), np.finfo(float).tiny))[:, None]
        return scaled[(norms > 0) | (floor > 0)]
    kept = norms > 0
    return rows[kept] if kept.all() else rows[kept].copy()


def row_lengths(model: Model, t: float, y: np.ndarray) -> np.ndarray:
    """Each row's length in the kinetic metric, ``‖J_i L⁻ᵀ‖``, at ``(t, y)``."""
    return _unit_rows(model, t, y)[1].copy()


def _unit_rows(model: Model, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``J L⁻ᵀ`` with unit rows and the rows' lengths (views into the bound buffers of :func:`_mass_and_rows`)."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    bound = workspace(model).get(("crossing: A and J",), lambda: _mass_and_rows(model))
    load_inputs(bound.args, (t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], np.zeros(2)))
    bound.eval()
    rows, norms = bound.output(0), bound.res[1]
    if not (np.all(np.isfinite(rows)) and np.all(np.isfinite(norms))):  # A not positive definite here: numpy says
        np.linalg.cholesky(bound.output(2))
    return rows, norms


def _mass_and_rows(model: Model) -> Bound:
    """``(t, q, v, λ, stab) ↦ (J L⁻ᵀ with unit rows, the rows' lengths, A)`` bound, ``A = L Lᵀ`` (the Cholesky factor
    in the graph: the watch runs at every accepted step)."""
    p = model.expressions
    A, J = ca.SX(p.A), ca.SX(p.J)
    U = ca.chol(A)  # A = UᵀU: J L⁻ᵀ = J U⁻¹
    rows = ca.solve(U.T, J.T).T
    norms = ca.sqrt(ca.sum2(rows * rows))
    unit = rows / ca.if_else(norms > 0, norms, 1)
    return Bound(ca.Function("mass_and_rows", model.inputs, [ca.densify(unit), ca.densify(norms), ca.densify(A)]))


def sign_changed(a: tuple[float, np.ndarray, np.ndarray], b: tuple[float, np.ndarray, np.ndarray]) -> bool | None:
    """Whether ``σ_r`` changed sign between two states, from its singular pairs ``(σ, u, v)`` there: ``True``,
    ``False``, or ``None`` when the vectors turned too far to tell (:data:`ALIGNED`).

    Followed continuously, ``σ_r = uᵀ M v`` is a smooth function of time that passes through zero at a singular
    position; an SVD reports ``|σ_r|`` and makes it positive by flipping ``u`` or ``v``. The SVD's own freedom
    flips both at once, which leaves ``(u_a·u_b)(v_a·v_b)`` unchanged: its sign says whether ``σ_r`` did."""
    uu, vv = float(a[1] @ b[1]), float(a[2] @ b[2])
    if min(abs(uu), abs(vv)) < ALIGNED:
        return None
    return uu * vv < 0


@dataclass(frozen=True)
class Approach:
    """Step (error-controlled, as the run does) to ``t``, from where the bridge will be placed."""

    t: float


@dataclass(frozen=True)
class Cross:
    """Bridge now, over the singular instant estimated at ``t``."""

    t: float


class SingularityWatch:
    """Follows ``σ_r`` along the accepted states of a run and plans each crossing (:meth:`observe`).

    Near ``t*``, ``σ_r ≈ c |t − t*|``. From an accepted state the instant is estimated by Newton's step on ``σ_r``
    along the motion (its slope from the step's dense output just behind). When it is within :data:`LOOKAHEAD`
    of the run's recent longest step ``H``, the run steps halfway to ``t* − FRACTION·H`` (an :class:`Approach`)
    and estimates again from there — nearer, so better (Newton's error falls as the square of the distance) —
    until ``t*`` is within :data:`CLOSE_ENOUGH` ``· FRACTION·H`` and two successive estimates agree (:data:`AGREE`);
    then it bridges (:class:`Cross`), over ``(t* − t)/FRACTION``."""

    def __init__(self, model: Model, t0: float, y0: np.ndarray, rhs: Any = None) -> None:
        self.model, self.rhs = model, rhs
        #: a share of each row's length at the start, below which a row is scaled by it (:func:`_normalized_rows`)
        self.floor = FLOOR_SHARE * row_lengths(model, t0, y0)
        sigma, self.rank = smallest_kept(model, t0, y0, floor=self.floor)
        self.history: list[tuple[float, float]] = [(t0, sigma)]
        #: ``y`` at the last three samples of :attr:`history`
        self.states: list[np.ndarray] = [np.array(y0, float)]
        self.target: float | None = None
        #: The singular instant estimated at the last accepted state (``None``: none was).
        self.estimate: float | None = None
        #: The run's recent longest step when that estimate was made.
        self.span = 0.0
        #: Singular positions the integrator's own error-controlled steps went over (no bridge was needed).
        self.stepped: list[dict[str, Any]] = []

    def sigma(self, t: float, y: np.ndarray) -> float:
        """``σ_r`` at ``(t, y)``: with independent rows the step's margin is the smallest eigenvalue of the
        normalized ``J A⁻¹ Jᵀ``, ``σ_r²`` — the last evaluation's if it was there, else one compiled step call's;
        otherwise (dependent rows, a step from Python) computed here."""
        if self.rank == self.model.k and hasattr(self.rhs, "margin_at") and not self._shrunk(t, y):
            margin = self.rhs.margin_at(t, y)
            if margin is None:
                margin = self.rhs.margin(t, y)
            if np.isfinite(margin):
                return float(np.sqrt(margin))
        return smallest_kept(self.model, t, y, self.rank, self.floor)[0]

    def _shrunk(self, t: float, y: np.ndarray) -> bool:
        """Whether a row is shorter than at the start (then the step's margin, which scales every row to unit length,
        is not ``σ_r``)."""
        return bool(np.any(row_lengths(self.model, t, y) < self.floor))

    def restart(self, t: float, y: np.ndarray) -> None:
        """A fresh trend after a bridge (the ``σ_r`` on the far side rises)."""
        self.history, self.target, self.estimate = [(t, self.sigma(t, y))], None, None
        self.states = [np.array(y, float)]

    def observe(self, t: float, y: np.ndarray, rate: Any) -> Approach | Cross | None:
        """Take the accepted state ``(t, y)`` (``rate()``: ``ẏ`` there, asked for only if needed); say what to do
        next."""
        if not self.rank:
            return None
        sigma = self.sigma(t, y)
        t_prev, s_prev = self.history[-1]
        self.history = [*self.history[-REMEMBER:], (t, sigma)]
        self.states = [*self.states[-2:], y.copy()]
        self._went_over()
        h = t - t_prev
        if self.target is not None and t < self.target:
            return None  # on the way to the approach point
        self.target = None
        previous, self.estimate = self.estimate, None
        if not (h > 0 and sigma < WATCH_BELOW and sigma < s_prev):
            return None
        times = [ti for ti, _ in self.history]
        longest = max(b - a for a, b in zip(times, times[1:], strict=False))
        if previous is not None:  # planning a crossing: the steps shorten on the way, the step before them counts
            longest = max(longest, self.span)
        self.span = longest
        secant = sigma * h / (s_prev - sigma)
        if secant > 2 * LOOKAHEAD * longest:  # the secant's zero: far ahead, no need to look
            return None
        # Newton's step from the slope at t (the secant lags behind it): σ a moment back along the tangent, whose
        # O(behind²) offset from the motion is the one-sided difference's own order of error
        behind = 1e-2 * h
        slope = (sigma - self.sigma(t - behind, y - behind * np.asarray(rate()))) / behind
        if not slope < 0:
            return None
        ahead = sigma / -slope
        if ahead > LOOKAHEAD * longest or ahead > CONVEX * secant:
            return None
        self.estimate = t + ahead
        if ahead <= CLOSE_ENOUGH * FRACTION * BRIDGE_SHARE * longest:
            if previous is not None and abs(self.estimate - previous) <= AGREE * ahead:
                return Cross(self.estimate)
            self.target = t + (1 - FRACTION) * ahead / 2  # confirm: a zero, not a dip of σ_r, keeps its place
        else:
            self.target = t + 0.5 * (ahead - FRACTION * BRIDGE_SHARE * longest)  # halfway: nearer, better estimate
        return Approach(self.target)

    def _went_over(self) -> None:
        """Note a singular position one of the run's steps went over: ``σ_r`` fell, then rose, and changed sign
        between two of the last three samples (:func:`sign_changed`) — a dip of ``σ_r`` that stays above zero
        does not. On the other side of the minimum the vectors may be another singular value's (two values of
        ``σ`` cross there): that side's verdict is "cannot tell", not "no". The instant: the zero of the parabola
        through the signed values."""
        if len(self.history) < 3 or len(self.states) < 3:
            return
        (t0, s0), (t1, s1), (t2, s2) = self.history[-3:]
        if not (s1 < s0 and s1 < s2 and s1 < WENT_OVER_BELOW):
            return
        first, last = (
            smallest_pair(self.model, t, y, self.rank, self.floor)
            for t, y in ((t0, self.states[0]), (t2, self.states[2]))
        )
        if sign_changed(first, last) is False:
            return  # the same sign at both ends, told: no zero or two (most dips end here, two SVDs)
        middle = smallest_pair(self.model, t1, self.states[1], self.rank, self.floor)
        before, after = sign_changed(first, middle), sign_changed(middle, last)
        if (before is True) == (after is True):
            return  # no change of sign that can be told, or two (σ_r back through zero: not one position)
        signed = (s0, -s1, -s2) if before else (s0, s1, -s2)
        t_star = _zero_between(t0, t1, t2, *signed, (t0, t1) if before else (t1, t2))
        self.stepped.append({"t": t_star, "kind": "singular position", "from": t0, "to": t2})


def _zero_between(
    t0: float, t1: float, t2: float, f0: float, f1: float, f2: float, bracket: tuple[float, float]
) -> float:
    """The zero in ``bracket`` of the parabola through ``(t_i, f_i)`` (the secant's where it has none there)."""
    a, b, c = _parabola(t0 - t1, t2 - t1, f0, f1, f2)
    lo, hi = bracket
    roots = np.roots([a, b, c]) + t1 if a else np.array([t1 - c / b]) if b else np.zeros(0)
    inside = [float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and lo <= r.real <= hi]
    if inside:
        return inside[0]
    fa, fb = (f0, f1) if bracket == (t0, t1) else (f1, f2)
    return float(lo + (hi - lo) * fa / (fa - fb))


def _parabola(x0: float, x2: float, f0: float, f1: float, f2: float) -> tuple[float, float, float]:
    """``(a, b, c)`` of ``a x² + b x + c`` through ``(x0, f0)``, ``(0, f1)``, ``(x2, f2)`` (``x0 < 0 < x2``)."""
    d0, d2 = (f0 - f1) / x0, (f2 - f1) / x2  # divided differences on either side of 0
    a = (d2 - d0) / (x2 - x0)
    return a, d0 - a * x0, f1


@dataclass(frozen=True)
class Bridge:
    """One step over a singular instant: the state reached (projected) and the step's dense output."""

    t: float
    y: np.ndarray
    dense: Any
    event: dict[str, Any]


def bridge(
    rhs: Any, model: Model, project: Projection, t_a: float, y_a: np.ndarray, t_star: float, t_end: float
) -> Bridge:
    """One DOP853 step from ``(t_a, y_a)`` over ``t_star`` (module docstring), projected onto the constraints."""
    h = (t_star - t_a) / FRACTION
    t_b = min(t_a + h, t_end)
    if not t_b > t_a:
        raise IntegrationError(f"no step left to cross the singular position near t={t_star:.6g}")
    nq, nv, nl = model.nq, model.nv, model.n_lam
    y_a = np.array(y_a, float)  # on the constraints first: the step amplifies a drift off them by ~1/σ_r
    y_a[:nq], y_a[nq : nq + nv] = project(t_a, y_a[:nq], y_a[nq : nq + nv], y_a[nq + nv : nq + nv + nl])
    stepper = si.DOP853(rhs, t_a, y_a, t_b, first_step=t_b - t_a, max_step=t_b - t_a, rtol=1e10, atol=1e10)
    try:
        stepper.step()  # one step: its error estimate is within any such tolerance
    except GaussppError as exc:
        raise IntegrationError(f"the step over the singular position near t={t_star:.6g} failed: {exc}") from None
    if stepper.status == "failed" or stepper.t != t_b:
        raise IntegrationError(f"the step over the singular position near t={t_star:.6g} did not reach t={t_b:.6g}")
    y = np.array(stepper.y)
    q, v = y[:nq].copy(), y[nq : nq + nv].copy()
    for _ in range(3):  # Newton steps; the first takes the step's O(h⁹) error off, the others check it is gone
        q, v = project(t_b, q, v, y[nq + nv : nq + nv + nl])
    correction = float(np.max(np.abs(q - y[:nq])))
    travelled = float(np.max(np.abs(y[:nq] - y_a[:nq])))
    if not correction <= BRANCH_SHARE * travelled:
        raise IntegrationError(
            f"the step over the singular position near t={t_star:.6g} ended {correction:.3g} off the constraints "
            f"(it moved q by {travelled:.3g}): the motion may have left its branch there; tighten rtol/atol so the "
            "steps before it are shorter"
        )
    y[:nq], y[nq : nq + nv] = q, v
    event = {"t": float(t_star), "kind": "singular position", "from": float(t_a), "to": float(t_b)}
    return Bridge(t_b, y, stepper.dense_output(), {**event, "correction": correction})
