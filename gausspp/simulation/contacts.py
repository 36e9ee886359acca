"""Unilateral contacts as a run sees them: the gaps, the model of a contact phase, the active set.

A run with contacts is a sequence of smooth *phases* (:mod:`gausspp.simulation.events`). In each
phase the set of active contacts is fixed and those contacts are kept as ideal bilateral
constraints ``g = 0`` (:func:`phase_model`: a model per active set, built on first use and kept in
the model's workspace), so the phase is integrated as accurately as any equality-constrained
motion. Which contacts are active is decided by Gauss's principle with inequalities at the phase's
start (:func:`active_set`: a closed, non-separating contact is active iff its force is positive).
"""

from __future__ import annotations

import numpy as np

from ..model.derived import gaps, phase_model
from ..model.model import Model


def phase_step(
    model: Model, active: tuple[int, ...], solver: str, backend: str | None
) -> tuple[Model, str, str | None]:
    """The phase model of ``active``, its step solver and QP backend (without bilateral rows: the direct step)."""
    sub = phase_model(model, active)
    sub_solver = "direct" if sub.k == 0 else solver
    return sub, sub_solver, (backend if sub_solver == "qp" else None)


def active_set(
    model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, backend: str | None, closed: set[int]
) -> tuple[int, ...]:
    """Closed, non-separating contacts whose force by the inequality Gauss QP is positive."""
    _g, gdot = gaps(model, t, q, v)
    candidates = [i for i in sorted(closed) if gdot[i] <= model.contact_tol]
    if not candidates:
        return ()
    force = model.general_step(t, q, v, lam, backend=backend, closed=candidates)[0].contact_force
    threshold = 1e-10 * max(1.0, float(np.max(np.abs(force), initial=0.0)))
    return tuple(i for i in candidates if force[i] > threshold)


def off_the_start(value: float, t: float, t_start: float) -> float:
    """An event function's value, made positive at the phase's start: a phase begins *on* the boundaries it
    watches (g = 0 after a touch, ġ = 0 after a release), and the root finder would otherwise return the
    start itself as the event — no progress, the same event again (chattering at one instant)."""
    return max(value, 1e-300) if t == t_start else value
