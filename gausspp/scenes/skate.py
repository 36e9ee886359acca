"""A skate (knife edge) in the plane (docs/theory.md §6.4): one constraint, two laws of motion.

Coordinates ``q = (x, y, θ)``: the contact point and the blade's heading. Kinetic energy
``T = ½ m (ẋ² + ẏ²) + ½ J θ̇²``; the blade cannot slide sideways:

    Φ = −sin θ · ẋ + cos θ · ẏ = 0.

* ``realization="nonholonomic"`` — the ideal (d'Alembert–Lagrange) constraint: the reaction is
  ``λ (−sin θ, cos θ, 0)``, a sideways force on the blade. The heading turns uniformly
  (``θ̇ = ω₀``) and the speed along the blade stays ``u₀``: the contact point runs along a circle
  of radius ``u₀/ω₀`` (a straight line if ``ω₀ = 0``). This is the :attr:`Scene.exact` motion.
* ``realization="vakonomic"`` — the same constraint as a vakonomic one (paper (17)–(18)):
  ``λ`` is a state with ``λ(0) = lam0``, the reaction ``−λ̇ N_v − λ [N]`` with ``N = Φ``. Along a
  motion ``m u̇ = λ θ̇``, ``λ̇ = −m θ̇ u`` and ``J θ̈ = −λ u`` (``u`` the speed along the blade), so
  the heading does not turn uniformly (even for ``lam0 = 0``: ``λ̇ = −m ω₀ u₀``); both laws agree
  only on straight lines (``omega0 = 0, lam0 = 0``) and spins in place. Conserved: ``T`` and the
  momentum ``p = m (ẋ, ẏ) + λ ∂Φ/∂(ẋ, ẏ)``, i.e. ``p_x + i p_y = (m u + iλ) e^{iθ} = |p| e^{iα}``
  (Noether, translations). Hence ``m u = |p| cos(α − θ)``, ``λ = |p| sin(α − θ)`` and
  ``J θ̈ = −(|p|²/2m) sin 2(α − θ)``, a pendulum equation; no closed form is given.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError, UnknownNameError
from ..model.constraints import Constraint
from ..model.mechanism import Lagrangian
from ..model.model import Model
from ..model.realizations import Ideal, Vakonomic
from .scene import Scene

REALIZATIONS = ("nonholonomic", "vakonomic")


def exact_nonholonomic(q0: np.ndarray, speed: float, omega: float) -> Callable[[float], tuple[np.ndarray, np.ndarray]]:
    """The nonholonomic skate's motion from ``q0`` with speed ``speed`` along the blade and ``θ̇ = omega``."""
    x0, y0, th0 = (float(c) for c in q0)

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        th = th0 + omega * t
        if omega == 0.0:
            x, y = x0 + speed * np.cos(th0) * t, y0 + speed * np.sin(th0) * t
        else:
            r = speed / omega
            x, y = x0 + r * (np.sin(th) - np.sin(th0)), y0 - r * (np.cos(th) - np.cos(th0))
        q = np.array([x, y, th])
        v = np.array([speed * np.cos(th), speed * np.sin(th), omega])
        return q, v

    return exact


def build(
    m: float = 1.0,
    J: float = 0.1,
    realization: str = "nonholonomic",
    v0: float = 1.0,
    omega0: float = 1.0,
    theta0: float = 0.0,
    lam0: float = 0.5,
    t_end: float = 5.0,
) -> Scene:
    """Skate (knife edge) in the plane, no sideways velocity; nonholonomic (ideal) or vakonomic law.

    Parameters
    ----------
    m : float
        Mass of the skate (kg). Allowed: > 0.
    J : float
        Moment of inertia about the vertical axis through the contact point (kg·m²). Allowed: > 0.
    realization : str
        The law of motion: the ideal (d'Alembert–Lagrange) constraint (``'nonholonomic'``) or the vakonomic one
        (``'vakonomic'``) (-). Allowed: one of 'nonholonomic', 'vakonomic'.
    v0 : float
        Initial speed along the blade (m/s). Allowed: any finite number.
    omega0 : float
        Initial turning rate ``θ̇`` (rad/s). Allowed: any finite number.
    theta0 : float
        Initial heading of the blade from the x axis; the skate starts at the origin (rad). Allowed: any finite
        number.
    lam0 : float
        Initial value of the vakonomic multiplier ``λ``, a momentum; ignored by the nonholonomic law, nonzero by
        default so that the two laws differ (kg·m/s). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    if realization not in REALIZATIONS:
        raise UnknownNameError(f"skate: realization={realization!r} is unknown; use one of {list(REALIZATIONS)}")
    if not (m > 0 and J > 0):
        raise InputError(f"skate: mass and moment of inertia must be positive, got m={m}, J={J}")
    for name, value in (("v0", v0), ("omega0", omega0), ("theta0", theta0), ("lam0", lam0), ("t_end", t_end)):
        if not np.isfinite(value):
            raise InputError(f"skate: {name} must be finite, got {value}")
    body = Lagrangian(
        n=3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * J * v[2] ** 2,
    )
    vakonomic = realization == "vakonomic"
    real = Vakonomic(lam0=[lam0]) if vakonomic else Ideal()
    blade = Constraint(
        lambda q, v, t: -ca.sin(q[2]) * v[0] + ca.cos(q[2]) * v[1],
        name="no sideways slip",
        realization=real,
    )
    model = Model(body, [blade])
    q0 = np.array([0.0, 0.0, float(theta0)])
    qd0 = np.array([v0 * np.cos(theta0), v0 * np.sin(theta0), float(omega0)])
    return Scene(
        name="skate",
        model=model,
        q0=q0,
        v0=qd0,
        coordinates=("x (m)", "y (m)", "θ (rad)"),
        lam0=np.array([float(lam0)]) if vakonomic else None,
        t_end=float(t_end),
        exact=None if vakonomic else exact_nonholonomic(q0, float(v0), float(omega0)),
        drawing=drawing,
        description="skate (knife edge) in the plane, no sideways slip: nonholonomic or vakonomic law",
        params=dict(m=m, J=J, realization=realization, v0=v0, omega0=omega0, theta0=theta0, lam0=lam0, t_end=t_end),
    )


#: The blade's drawn length (m).
BLADE = 0.6


def drawing(q: np.ndarray) -> dict[str, Any]:
    """The blade (length :data:`BLADE`) along the heading ``θ`` through the contact point ``(x, y)``, the way
    the contact point has gone, and the reaction's ``(x, y)`` part at the contact point (:attr:`Scene.drawing`)."""
    x, y, th = (float(c) for c in q[:3])
    half = 0.5 * BLADE * np.array([np.cos(th), np.sin(th)])
    point = np.array([x, y])
    return {"segments": [(point - half, point + half)], "trace": [point],
            "reaction": [(point, (0, 1))]}  # fmt: skip
