"""The first step of an adaptive run, chosen the same way in any units.

scipy's ``select_initial_step`` (Hairer, Nørsett and Wanner, *Solving ODEs I*, II.4) takes
``h₁ = (0.01 / max(d₁, d₂))^{1/(p+1)}`` with ``d₁ = ‖f₀‖`` and ``d₂ = ‖f₁ − f₀‖/h₀`` in the weighted norm: ``d₁`` is
a rate (1/s) and ``d₂`` a rate squared, so ``h₁`` changes with the unit of time — the pendulum rewritten in
hectoseconds took a first step 10× longer relative to its motion than in seconds, and so other steps all along.
:func:`first_step` keeps Hairer's two estimates in the units of time: the step that moves the state by 1 % of its
tolerance scale, ``h₀ = 0.01 d₀/d₁``, and the step whose local error ``h^{p+1} ‖y^{(p+1)}‖`` is 1 % of the
tolerance, with ``‖y^{(p+1)}‖ ≈ d₁ λᵖ`` and the rate ``λ = d₂/d₁`` at which ``f`` turns.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import Radau
from scipy.integrate._ivp.rk import RungeKutta

from ..errors import GaussppError


def first_step(
    f: Callable[[float, np.ndarray], np.ndarray],
    t0: float,
    y0: np.ndarray,
    f0: np.ndarray,
    scale: np.ndarray,
    order: int,
    horizon: float,
) -> float:
    """The first step of a method of error order ``order`` from ``(t0, y0)`` with ``f0 = f(t0, y0)``, the error
    weighted by ``scale`` (``atol + rtol·|y|``; ``inf`` leaves a component out), at most ``horizon``."""
    weight = np.where(np.isfinite(scale) & (scale > 0), 1.0 / np.where(scale > 0, scale, 1.0), 0.0)
    d0, d1 = _norm(y0 * weight), _norm(f0 * weight)
    if not (d1 > 0 and np.isfinite(d1)):
        return float(horizon)  # nothing moves at the start: the step control takes it from there
    h0 = min(0.01 * d0 / d1, horizon) if d0 > 0 else 1e-6 * horizon
    f1 = f(t0 + h0, y0 + h0 * f0)
    d2 = _norm((f1 - f0) * weight) / h0
    if not (np.isfinite(d2) and d2 > 0):
        return float(min(100 * h0, horizon))
    rate = d2 / d1
    h1 = (0.01 / (d1 * rate**order)) ** (1.0 / (order + 1))
    return float(min(100 * h0, h1, horizon))


def _norm(x: np.ndarray) -> float:
    return float(np.linalg.norm(x) / np.sqrt(x.size)) if x.size else 0.0


def initial_step(
    rhs: Any, solver: type, t0: float, y0: np.ndarray, options: dict[str, Any], horizon: float
) -> float | None:
    """The first step of a scipy ``solver`` class from ``(t0, y0)``, chosen the same way in any units
    (:mod:`.first_step`; the error order scipy's own choice uses: Radau 3, BDF 1, a Runge–Kutta pair its lower
    order); ``None`` where the right-hand side fails there (the solver then names the failure)."""
    if issubclass(solver, Radau):
        order = 3
    elif issubclass(solver, RungeKutta):
        order = int(solver.error_estimator_order)
    else:
        order = 1
    scale = options["atol"] + np.abs(y0) * options["rtol"]
    try:
        f0 = np.asarray(rhs(t0, y0), float)
        if not np.all(np.isfinite(f0)):
            return None
        step = first_step(rhs, t0, y0, f0, scale, order, horizon)
    except GaussppError:
        return None
    return step if np.isfinite(step) and step > 0 else None
