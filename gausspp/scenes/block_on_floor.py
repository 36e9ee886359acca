"""A block dropped on a floor: impacts with restitution, then resting contact.

A planar rigid block (width ``w``, height ``h``, mass ``m``, central moment of inertia
``m(w² + h²)/12``) with coordinates ``q = (x, z, θ)`` under gravity ``g``; its corners
``(±w/2, ∓h/2)`` (body axes) must stay above the floor:

    ``corner±: z ± (w/2) sin θ − (h/2) cos θ ≥ 0``,  ``top±: z ± (w/2) sin θ + (h/2) cos θ ≥ 0``

(Unilateral, restitution ``e``; the top corners matter only for a block that tips over).

Dropped flat (``tilt = 0``) from height ``z0 − h/2`` with zero vertical speed, both corners hit
together and the block bounces like a point mass. Closed form: impact speeds ``v_k = eᵏ v₁``
with ``v₁ = √(2 g H)``, impact times ``t₁ = √(2H/g)``, ``t_{k+1} = t_k + 2 v_k/g``, apex heights
``eᵏ`` ... ``H_k = e^{2k} H``; the bounces accumulate at ``t_∞ = t₁ + 2 e v₁ / (g (1 − e))``,
after which the block rests with contact force ``m g`` (``m g / 2`` per corner). ``exact`` gives
that motion (the rest of the Zeno sequence included). With a tilt the block rocks (no closed form).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.constraints import Unilateral
from ..model.mechanism import Lagrangian
from ..model.model import Model
from .scene import Scene


def bounce_times(height: float, e: float, g: float, count: int) -> np.ndarray:
    """Closed-form times of the first ``count`` impacts of a point dropped from rest from ``height``."""
    v1 = np.sqrt(2.0 * g * height)
    times = [np.sqrt(2.0 * height / g)]
    for k in range(1, count):
        times.append(times[-1] + 2.0 * e**k * v1 / g)
    return np.array(times)


def build(
    m: float = 1.0,
    w: float = 0.4,
    h: float = 0.2,
    g: float = 9.81,
    e: float = 0.5,
    drop: float = 1.0,
    tilt: float = 0.0,
    vx: float = 0.0,
    t_end: float = 3.0,
) -> Scene:
    """Planar block dropped on a floor: its corners bounce with restitution e, then it rests.

    Parameters
    ----------
    m : float
        Mass of the block (kg). Allowed: > 0.
    w : float
        Width of the block (m). Allowed: > 0.
    h : float
        Height of the block (m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−z`` (m/s²). Allowed: > 0.
    e : float
        Coefficient of restitution of the corners' impacts on the floor (-). Allowed: 0 ≤ e ≤ 1.
    drop : float
        Initial height of the lowest corner above the floor; the block starts with zero vertical speed (m).
        Allowed: ≥ 0.
    tilt : float
        Initial angle of the block; 0: level, it bounces like a point mass (the exact motion is known) (rad).
        Allowed: |tilt| < π/2.
    vx : float
        Initial horizontal velocity (m/s). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    _check(m, w, h, g, e, drop, tilt, t_end)
    model = _block(m, w, h, g, e)
    # the lower corner starts `drop` above the floor
    z0 = drop + 0.5 * w * abs(np.sin(tilt)) + 0.5 * h * np.cos(tilt)
    q0, v0 = np.array([0.0, z0, tilt]), np.array([vx, 0.0, 0.0])
    exact = _bouncing(h, g, e, drop, vx, z0) if tilt == 0.0 else None
    return Scene(
        name="block-on-floor",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=("x (m)", "z (m)", "θ (rad)"),
        lam0=None,
        t_end=t_end,
        exact=exact,
        drawing=drawing(w, h, float(q0[0])),
        description="planar block dropped on a floor: four unilateral corner contacts, impacts with restitution e, "
        "then rest",
        params=dict(m=m, w=w, h=h, g=g, e=e, drop=drop, tilt=tilt, vx=vx, t_end=t_end),
    )


def _check(m: float, w: float, h: float, g: float, e: float, drop: float, tilt: float, t_end: float) -> None:
    """Positive sizes, mass and gravity; ``0 ≤ e ≤ 1``; ``drop ≥ 0``, ``t_end > 0``; ``|tilt| < π/2``."""
    if not (m > 0 and w > 0 and h > 0 and g > 0):
        raise InputError(f"block-on-floor: m, w, h and g must be positive, got m={m}, w={w}, h={h}, g={g}")
    if not 0 <= e <= 1:
        raise InputError(f"block-on-floor: the restitution e must lie in [0, 1], got {e}")
    if not (drop >= 0 and t_end > 0):
        raise InputError(f"block-on-floor: need drop ≥ 0 and t_end > 0, got drop={drop}, t_end={t_end}")
    if not abs(tilt) < np.pi / 2:
        raise InputError(f"block-on-floor: |tilt| must be below π/2, got {tilt}")


def _block(m: float, w: float, h: float, g: float, e: float) -> Model:
    """The block ``q = (x, z, φ)`` under gravity with a unilateral contact at each of its four corners."""
    inertia = m * (w * w + h * h) / 12.0
    body = Lagrangian(
        n=3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * inertia * v[2] ** 2,
        V=lambda q, t: m * g * q[1],
    )
    # all four corners: a block that tips over lands on its top ones (the bottom two carry it otherwise)
    corners = [
        Unilateral(
            lambda q, t, s=s, u=u: q[1] + s * 0.5 * w * ca.sin(q[2]) + u * 0.5 * h * ca.cos(q[2]),
            name=name,
            restitution=e,
        )
        for s, u, name in ((1.0, -1.0, "corner+"), (-1.0, -1.0, "corner-"), (1.0, 1.0, "top+"), (-1.0, 1.0, "top-"))
    ]
    return Model(body, corners)


def _bouncing(
    h: float, g: float, e: float, drop: float, vx: float, z0: float
) -> Callable[[float], tuple[np.ndarray, np.ndarray]]:
    """The level block's motion: a fall from ``z0``, flights of upward speed ``eᵏ v1`` after impact ``k``,
    rest at ``z = h/2`` from ``t∞`` (the sum of the flights) on."""
    v1 = np.sqrt(2.0 * g * drop)
    t_inf = np.sqrt(2.0 * drop / g) + (2.0 * e * v1 / (g * (1.0 - e)) if e < 1 else np.inf)

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        t = float(t)
        z0_ = 0.5 * h
        if t >= t_inf:
            return np.array([vx * t, z0_, 0.0]), np.array([vx, 0.0, 0.0])
        t1 = np.sqrt(2.0 * drop / g)
        if t < t1:
            return np.array([vx * t, z0 - 0.5 * g * t * t, 0.0]), np.array([vx, -g * t, 0.0])
        start, k = t1, 1
        while True:  # flight k starts at impact k with upward speed e^k v1
            up = e**k * v1
            if t < start + 2.0 * up / g or up == 0.0:
                s = t - start
                return np.array([vx * t, z0_ + up * s - 0.5 * g * s * s, 0.0]), np.array([vx, up - g * s, 0.0])
            start, k = start + 2.0 * up / g, k + 1

    return exact


def drawing(w: float, h: float, x0: float) -> Callable[[np.ndarray], dict[str, Any]]:
    """What to draw at ``q = (x, z, θ)`` (:attr:`Scene.drawing`): the block's outline, its centre of mass with
    the way it has gone, the floor (``3w`` wide about ``x0``) and the contact forces' sum (the reaction's
    ``(x, z)`` part) at the centre of mass."""
    body = 0.5 * np.array([[w, -h], [w, h], [-w, h], [-w, -h]])  # corners in body axes, in turn

    def draw(q: np.ndarray) -> dict[str, Any]:
        x, z, th = (float(c) for c in q[:3])
        turn = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        centre = np.array([x, z])
        corners = centre + body @ turn.T
        return {
            "segments": [(corners[i], corners[(i + 1) % 4]) for i in range(4)],
            "points": [centre],
            "trace": [centre],
            "ground": [((x0 - 1.5 * w, 0.0), (x0 + 1.5 * w, 0.0))],
            "labels": ("x (m)", "z (m)"),
            "reaction": [(centre, (0, 1))],
        }

    return draw
