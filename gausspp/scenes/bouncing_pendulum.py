"""A pendulum that hits a wall: a bilateral rod and a unilateral contact together.

A point mass ``m`` at ``q = (x, z)`` on a massless rod of length ``L`` (ideal holonomic
``rod: x² + z² − L² = 0``) under gravity ``g``, and a wall through the pivot's vertical,
``wall: x ≥ 0`` (Unilateral, restitution ``e``). Released from rest at the angle ``θ₀`` from the
vertical on the wall's side, the bob swings down and hits the wall at the bottom, moving normal
to it; the impact reverses the normal speed times ``e``, so the kinetic energy after it is
``e²`` times that before (one degree of freedom).

Closed form: from rest at amplitude ``θ`` the bob reaches the bottom after a quarter period
``√(L/g) K(sin²(θ/2))`` (``K`` the complete elliptic integral of the first kind, scipy's
parameter convention); after an impact the amplitude ``θ'`` obeys ``1 − cos θ' = e²(1 − cos θ)``,
and the next impact follows a half period of that amplitude later.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.constraints import Holonomic, Unilateral
from ..model.mechanism import Lagrangian
from ..model.model import Model
from .scene import Scene


def impact_times(L: float, g: float, theta0: float, e: float, count: int) -> np.ndarray:
    """Closed-form times of the first ``count`` impacts (release from rest at ``theta0``)."""
    from scipy.special import ellipk

    quarter = np.sqrt(L / g)
    times, theta = [quarter * ellipk(np.sin(theta0 / 2) ** 2)], theta0
    for _ in range(1, count):
        theta = np.arccos(1.0 - e * e * (1.0 - np.cos(theta)))
        times.append(times[-1] + 2.0 * quarter * ellipk(np.sin(theta / 2) ** 2))
    return np.array(times)


def build(
    m: float = 1.0,
    L: float = 1.0,
    g: float = 9.81,
    e: float = 0.8,
    theta0: float = 1.0,
    t_end: float = 4.0,
) -> Scene:
    """Point pendulum on a rod swinging into a wall under its pivot: impacts with restitution e.

    Parameters
    ----------
    m : float
        Mass of the bob (kg). Allowed: > 0.
    L : float
        Length of the rod (m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−z`` (m/s²). Allowed: > 0.
    e : float
        Coefficient of restitution of the impacts on the wall (-). Allowed: 0 ≤ e ≤ 1.
    theta0 : float
        Release angle from the downward vertical, on the wall's side; the bob starts at rest (rad).
        Allowed: 0 < theta0 < π.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    if not (m > 0 and L > 0 and g > 0 and t_end > 0):
        raise InputError(f"bouncing-pendulum: m, L, g and t_end must be positive, got m={m}, L={L}, g={g}")
    if not 0 <= e <= 1:
        raise InputError(f"bouncing-pendulum: the restitution e must lie in [0, 1], got {e}")
    if not 0 < theta0 < np.pi:
        raise InputError(f"bouncing-pendulum: theta0 must lie in (0, π) (on the wall's side), got {theta0}")
    body = Lagrangian(n=2, T=lambda q, v, t: 0.5 * m * ca.sumsqr(v), V=lambda q, t: m * g * q[1])
    rod = Holonomic(lambda q, t: q[0] ** 2 + q[1] ** 2 - L * L, name="rod")
    wall = Unilateral(lambda q, t: q[0], name="wall", restitution=e)
    model = Model(body, [rod, wall])
    q0 = np.array([L * np.sin(theta0), -L * np.cos(theta0)])
    return Scene(
        name="bouncing-pendulum",
        model=model,
        q0=q0,
        v0=np.zeros(2),
        coordinates=("x (m)", "z (m)"),
        lam0=None,
        t_end=t_end,
        exact=None,
        description="pendulum on a rod hitting a wall under its pivot: bilateral rod + unilateral wall, restitution e",
        params=dict(m=m, L=L, g=g, e=e, theta0=theta0, t_end=t_end),
    )
