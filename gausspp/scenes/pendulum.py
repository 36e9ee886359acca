"""A pendulum made by constraints (docs/theory.md §6.7), for comparison with other simulators.

A planar rigid body with coordinates ``q = (x, z, φ)``: its centre of mass ``(x, z)`` and its
angle ``φ``; mass ``m``, central moment of inertia ``Ic``, gravity ``g`` along ``−z``:
``T = ½ m (ẋ² + ż²) + ½ Ic φ̇²``, ``V = m g z``. The body point ``(−L, 0)`` in body axes —
at distance ``L`` from the centre of mass, at ``(x, z) − L (cos φ, sin φ)`` — is pinned to the
origin by two ideal holonomic constraints

    ``pin-x: x − L cos φ = 0``,   ``pin-z: z − L sin φ = 0``,

so the centre of mass is at ``L (cos φ, sin φ)`` and ``φ`` is also its polar angle. Released at
rest from ``φ = 0`` (centre of mass at ``(L, 0)``, level with the pin), the body swings down.

Reference: the 1-DOF equation about the pin, ``(Ic + m L²) φ̈ = −m g L cos φ``. ``exact`` is a
high-accuracy numerical solution of that ODE (scipy ``solve_ivp``, DOP853, ``rtol = atol = 1e-13``,
dense output on ``[0, t_end]``), computed once per build: a reference by a different method,
not a closed form; it is accurate to about ``1e-12``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.constraints import Holonomic
from ..model.mechanism import Lagrangian
from ..model.model import Model
from .scene import Scene


def build(
    m: float = 1.0,
    Ic: float = 0.01,
    L: float = 1.0,
    g: float = 9.81,
    phi0: float = 0.0,
    omega0: float = 0.0,
    t_end: float = 2.0,
) -> Scene:
    """Planar rigid body pinned at distance L from its centre of mass by two holonomic constraints.

    Parameters
    ----------
    m : float
        Mass of the body (kg). Allowed: > 0.
    Ic : float
        Moment of inertia of the body about its centre of mass (kg·m²). Allowed: > 0.
    L : float
        Distance from the pin to the centre of mass (m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−z`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    phi0 : float
        Initial angle ``φ`` of the body: the polar angle of its centre of mass about the pin, from the x axis; 0:
        level with the pin (rad). Allowed: any finite number.
    omega0 : float
        Initial angular velocity ``φ̇`` (rad/s). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation, also the span of the reference solution (s). Allowed: > 0.
    """
    from scipy.integrate import solve_ivp

    if not (m > 0 and Ic > 0 and L > 0):
        raise InputError(f"pendulum: m, Ic and L must be positive, got m={m}, Ic={Ic}, L={L}")
    if not t_end > 0:
        raise InputError(f"pendulum: t_end must be positive, got {t_end}")
    body = Lagrangian(
        n=3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * Ic * v[2] ** 2,
        V=lambda q, t: m * g * q[1],
    )
    pins = [
        Holonomic(lambda q, t: q[0] - L * ca.cos(q[2]), name="pin-x"),
        Holonomic(lambda q, t: q[1] - L * ca.sin(q[2]), name="pin-z"),
    ]
    model = Model(body, pins)

    inertia_about_pin = Ic + m * L * L
    reference = solve_ivp(
        lambda t, y: [y[1], -m * g * L * np.cos(y[0]) / inertia_about_pin],
        (0.0, t_end),
        [phi0, omega0],
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        dense_output=True,
    )
    if not reference.success:  # pragma: no cover - a smooth 1-DOF ODE on a finite interval
        raise InputError(f"pendulum: the reference solution failed: {reference.message}")

    def state(phi: float, omega: float) -> tuple[np.ndarray, np.ndarray]:
        c, s = np.cos(phi), np.sin(phi)
        return np.array([L * c, L * s, phi]), np.array([-L * s * omega, L * c * omega, omega])

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        phi, omega = reference.sol(float(t))
        return state(phi, omega)

    q0, v0 = state(phi0, omega0)
    return Scene(
        name="pendulum",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=("x (m)", "z (m)", "φ (rad)"),
        lam0=None,
        t_end=t_end,
        exact=exact,
        description="planar rigid body pinned by two holonomic constraints; reference (Ic + mL²)φ̈ = −mgL cos φ",
        params=dict(m=m, Ic=Ic, L=L, g=g, phi0=phi0, omega0=omega0, t_end=t_end),
        drawing=drawing,
    )


def drawing(q: np.ndarray) -> dict[str, Any]:
    """The rod from the pin (the origin) to the centre of mass ``(x, z)``; the reaction ``(R_x, R_z)`` on the
    body drawn at its centre of mass (:attr:`Scene.drawing`)."""
    body = (q[0], q[1])
    return {"segments": [((0.0, 0.0), body)], "points": [body], "fixed": [(0.0, 0.0)], "reaction": [(body, (0, 1))]}
