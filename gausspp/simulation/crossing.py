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
"correction": |Δq|∞ of the projection}``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.integrate as si

from ..errors import GaussppError, IntegrationError
from ..model.model import Model
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
#: The bridge is at most this share of the run's recent longest step: a step that evaluates the motion near a
#: singular position is less accurate than an ordinary step of its length (measured on the parallelogram at
#: rtol = 1e-12: a 1e-10 J energy error per bridge at the full step, none seen at 0.6 of it).
BRIDGE_SHARE = 0.6
#: The bridge starts where ``t*`` is estimated within this times ``FRACTION`` of the recent longest step.
CLOSE_ENOUGH = 1.2
#: … and when two successive estimates agree within this share of the distance to it: ``σ_r`` vanishes there,
#: where a dip of ``σ_r`` that stays above zero (two singular values changing places) moves the estimate away.
AGREE = 0.1
#: A minimum of ``σ_r`` between samples below this share of its neighbours' is a singular position a step went over.
WENT_OVER = 0.05
#: … and only once ``σ_r`` has fallen below this (unit-free, ``σ ≤ 1``): far from a singular position a falling
#: trend is no reason to step over anything.
WATCH_BELOW = 0.2
#: A projection after the bridge that moves ``q`` by more than this share of the distance travelled would be a jump
#: to another branch (they part linearly from ``t*``): refused.
BRANCH_SHARE = 1e-2
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


def smallest_kept(model: Model, t: float, y: np.ndarray, rank: int | None = None) -> tuple[float, int]:
    """``(σ_r, r)``: the ``r``-th singular value of the rows ``J`` normalized in the kinetic metric (``J L⁻ᵀ``,
    ``A = L Lᵀ``, each row scaled to unit length), and ``r`` (counted at this state unless given)."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    data = model.evaluate_data(t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl])
    rows = np.linalg.solve(np.linalg.cholesky(data.A), data.J.T).T
    norms = np.linalg.norm(rows, axis=1)
    rows = rows[norms > 0] / norms[norms > 0, None]
    sigma = np.linalg.svd(rows, compute_uv=False) if rows.size else np.zeros(0)
    if rank is None:
        rank = int(np.count_nonzero(sigma > RANK_TOL * sigma[0])) if sigma.size else 0
    return (float(sigma[rank - 1]) if 0 < rank <= sigma.size else 0.0), rank


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
        sigma, self.rank = smallest_kept(model, t0, y0)
        self.history: list[tuple[float, float]] = [(t0, sigma)]
        self.target: float | None = None
        #: The singular instant estimated at the last accepted state (``None``: none was).
        self.estimate: float | None = None
        #: The run's recent longest step when that estimate was made.
        self.span = 0.0
        #: Singular positions the integrator's own error-controlled steps went over (no bridge was needed).
        self.stepped: list[dict[str, Any]] = []

    def sigma(self, t: float, y: np.ndarray) -> float:
        """``σ_r`` at ``(t, y)``: from the margin of the step's last evaluation if it was there (independent rows:
        the margin is the smallest eigenvalue of the normalized ``J A⁻¹ Jᵀ``, ``σ_r²``), else computed."""
        margin = self.rhs.margin_at(t, y) if self.rank == self.model.k and hasattr(self.rhs, "margin_at") else None
        return float(np.sqrt(margin)) if margin is not None else smallest_kept(self.model, t, y, self.rank)[0]

    def restart(self, t: float, y: np.ndarray) -> None:
        """A fresh trend after a bridge (the ``σ_r`` on the far side rises)."""
        self.history, self.target, self.estimate = [(t, self.sigma(t, y))], None, None

    def observe(self, t: float, y: np.ndarray, dense: Any) -> Approach | Cross | None:
        """Take the accepted state ``(t, y)`` (``dense()``: the last step's dense output, built only if needed); say
        what to do next."""
        if not self.rank:
            return None
        sigma = self.sigma(t, y)
        t_prev, s_prev = self.history[-1]
        self.history = [*self.history[-REMEMBER:], (t, sigma)]
        self._went_over()
        h = t - t_prev
        if self.target is not None and t < self.target:
            return None  # on the way to the approach point
        self.target = None
        previous, self.estimate = self.estimate, None
        if not (h > 0 and sigma < WATCH_BELOW and sigma < s_prev):
            return None
        longest = float(np.max(np.diff([ti for ti, _ in self.history])))
        if previous is not None:  # planning a crossing: the steps shorten on the way, the step before them counts
            longest = max(longest, self.span)
        self.span = longest
        if sigma * h / (s_prev - sigma) > 2 * LOOKAHEAD * longest:  # the secant's zero: far ahead, no need to look
            return None
        behind = 1e-2 * h  # Newton's step from the slope at t (the secant lags behind it)
        slope = (sigma - self.sigma(t - behind, np.asarray(dense()(t - behind)))) / behind
        if not slope < 0:
            return None
        ahead = sigma / -slope
        if ahead > LOOKAHEAD * longest:
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
        """Note a singular position one of the run's steps went over: ``σ_r`` fell, then rose, its parabola in
        ``σ_r²`` through the three samples dipping to (nearly) zero between them."""
        if len(self.history) < 3:
            return
        (t0, s0), (t1, s1), (t2, s2) = self.history[-3:]
        if not (s1 < s0 and s1 < s2 and s1 < WATCH_BELOW):
            return
        a, b, c = np.polyfit([t0 - t1, 0.0, t2 - t1], [s0**2, s1**2, s2**2], 2)
        if a > 0 and c - b * b / (4 * a) < (WENT_OVER * max(s0, s2)) ** 2:
            self.stepped.append({"t": float(t1 - b / (2 * a)), "kind": "singular position", "from": t0, "to": t2})


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
