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

The model side (the data along a path, on nodes) is :mod:`gausspp.verification.path`, the discretized
problem and its two solvers :mod:`gausspp.verification.discrete`; this module judges: :class:`Verification`,
:func:`judge`, :func:`verdict`. Their names are re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .discrete import Discretized, normalizer, solve_closed_form, solve_qp, value_at_zero
from .path import check_model, check_samples, data_function, discretize, path_samples

__all__ = [
    "GAP_FLOOR",
    "Discretized",
    "Verification",
    "check_model",
    "check_samples",
    "data_function",
    "discretize",
    "judge",
    "normalizer",
    "path_samples",
    "solve_closed_form",
    "solve_qp",
    "value_at_zero",
    "verdict",
]

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
