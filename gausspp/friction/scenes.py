"""Frictional test bodies. Planar: a block on a slope, a round body on a table, a rod on its end, a box on two
corners. Spatial (a two-component slip): a block on a slope, a ball on a table, a box on its four corners. Each
returns ``(mechanism, contacts)`` for :func:`~gausspp.friction.simulate_friction`; gravity ``G = 9.81`` along ``−y``."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from ..model.friction_contact import FrictionContact
from ..model.mechanism import Lagrangian
from ..multibody.bodies import spatial_body
from ..multibody.front_end import Bodies

G = 9.81


def incline(alpha: float, mu: float, mu_static: float | None = None, m: float = 1.0) -> tuple:
    """A block on a slope of angle ``alpha``: ``q = (x, y)``, ``x`` down the slope, ``y`` off it."""
    mech = Lagrangian(
        2,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2),
        V=lambda q, t: m * G * (-np.sin(alpha) * q[0] + np.cos(alpha) * q[1]),
    )
    return mech, [FrictionContact(lambda q: q[1], lambda q, v: v[0], mu, mu_static=mu_static, name="base")]


def round_body(mu: float, k: float, r: float = 0.1, m: float = 1.0, slope: float = 0.0, e: float = 0.0) -> tuple:
    """A ball (``k = 2/5``), disc (1/2) or hoop (1) of radius ``r``, inertia ``k m r²``: ``q = (x, y, θ)``, the
    contact point's slip ``ẋ + r θ̇``; on a slope of angle ``slope`` (``x`` down it)."""
    mech = Lagrangian(
        3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * k * m * r * r * v[2] ** 2,
        V=lambda q, t: m * G * (-np.sin(slope) * q[0] + np.cos(slope) * q[1]),
    )
    return mech, [FrictionContact(lambda q: q[1] - r, lambda q, v: v[0] + r * v[2], mu, restitution=e, name="table")]


def rod(mu: float, half: float = 0.5, m: float = 1.0) -> tuple:
    """A uniform rod of length ``2·half``: ``q = (x, y, θ)`` of its centre and its angle to the floor, touching it
    with its lower end ``(x − half cos θ, y − half sin θ)``."""
    mech = Lagrangian(
        3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * (m * half**2 / 3) * v[2] ** 2,
        V=lambda q, t: m * G * q[1],
    )
    contact = FrictionContact(
        lambda q: q[1] - half * ca.sin(q[2]), lambda q, v: v[0] + half * ca.sin(q[2]) * v[2], mu, name="end"
    )
    return mech, [contact]


def box(mu: float, w: float = 0.4, h: float = 0.2, m: float = 1.0, mu_static: float | None = None) -> tuple:
    """A box ``w × h`` on its two bottom corners: ``q = (x, y, θ)`` of its centre."""
    inertia = m * (w * w + h * h) / 12
    mech = Lagrangian(
        3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * inertia * v[2] ** 2,
        V=lambda q, t: m * G * q[1],
    )
    contacts = []
    for side, name in ((-1.0, "back"), (1.0, "front")):
        dx, dy = side * w / 2, -h / 2

        def gap(q, dx=dx, dy=dy):  # the corner's height
            return q[1] + dx * ca.sin(q[2]) + dy * ca.cos(q[2])

        def slip(q, v, dx=dx, dy=dy):  # the corner's horizontal velocity
            return v[0] - (dx * ca.sin(q[2]) + dy * ca.cos(q[2])) * v[2]

        contacts.append(FrictionContact(gap, slip, mu, mu_static=mu_static, name=name))
    return mech, contacts


def spatial_block(alpha: float, mu: float, heading: float = 0.0, m: float = 1.0) -> tuple:
    """A block on a slope of angle ``alpha`` whose downhill direction lies at ``heading`` in the surface's
    ``(x, z)`` axes: ``q = (x, y, z)``, ``y`` off the slope, the slip ``(ẋ, ż)``."""
    down = (np.cos(heading), np.sin(heading))
    mech = Lagrangian(
        3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2 + v[2] ** 2),
        V=lambda q, t: m * G * (-np.sin(alpha) * (down[0] * q[0] + down[1] * q[2]) + np.cos(alpha) * q[1]),
    )
    return mech, [FrictionContact(lambda q: q[1], lambda q, v: ca.vertcat(v[0], v[2]), mu, name="base")]


def spatial_ball(mu: float, r: float = 0.1, m: float = 1.0) -> tuple:
    """A uniform ball on a table: ``v = (ẋ, ẏ, ż, ω)`` (``y`` up; ``q``'s last three entries integrate ``ω``, which
    a ball's isotropic inertia allows: nothing depends on its orientation); the contact point's slip
    ``(ẋ + r ω_z, ż − r ω_x)``."""
    inertia = 0.4 * m * r * r
    mech = Lagrangian(
        6,
        T=lambda q, v, t: (
            0.5 * m * (v[0] ** 2 + v[1] ** 2 + v[2] ** 2) + 0.5 * inertia * (v[3] ** 2 + v[4] ** 2 + v[5] ** 2)
        ),
        V=lambda q, t: m * G * q[1],
    )
    slip = lambda q, v: ca.vertcat(v[0] + r * v[5], v[2] - r * v[3])  # noqa: E731
    return mech, [FrictionContact(lambda q: q[1] - r, slip, mu, name="table")]


def spatial_box(mu: float, half: tuple = (0.2, 0.1, 0.1), m: float = 1.0, mu_static: float | None = None) -> tuple:
    """A box of half-extents ``half`` on its four bottom corners, a free rigid body in space (``z`` up):
    ``q = (x, y, z, quaternion w, x, y, z)``, ``v = (ẋ, ẏ, ż, ω in body axes)``; each corner's gap is its height
    and its slip its horizontal velocity ``ṙ + R(ω × ℓ)``. At rest at ``q = (0, 0, half[2], 1, 0, 0, 0)``."""
    a, b, c = (float(x) for x in half)
    inertia = m / 3 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    body = replace(spatial_body("box", m, inertia, (0.0, 0.0, c), (1.0, 0.0, 0.0, 0.0), None), q_start=0, v_start=0)
    mech = Bodies([body], np.array([0.0, 0.0, -G]))
    contacts = []
    for sx, sy, name in ((1, 1, "front-left"), (-1, 1, "back-left"), (-1, -1, "back-right"), (1, -1, "front-right")):
        local = ca.DM([sx * a, sy * b, -c])

        def gap(q, local=local):
            return body.point(q, local)[2]

        def slip(q, v, local=local):
            _, R = body.parts(q)
            velocity = v[0:3] + R @ ca.cross(v[3:6], local)
            return velocity[0:2]

        contacts.append(FrictionContact(gap, slip, mu, mu_static=mu_static, name=name))
    return mech, contacts


def round_body_drawing(r: float = 0.1, floor: tuple[float, float] = (-0.2, 1.8)) -> Any:
    """What :func:`gausspp.plot.animate` draws of :func:`round_body` at ``q = (x, y, θ)``: the rim, a spoke at
    ``θ`` (sliding shows as the spoke lagging the roll), the floor, and the way of the centre and of a rim point
    (a cycloid once it rolls)."""
    angles = np.linspace(0.0, 2 * np.pi, 25)

    def draw(q: np.ndarray) -> dict[str, Any]:
        x, y, th = (float(c) for c in q[:3])
        rim = np.c_[x + r * np.cos(angles), y + r * np.sin(angles)]
        mark = np.array([x + r * np.cos(th), y + r * np.sin(th)])
        return {
            "segments": [(rim[i], rim[i + 1]) for i in range(len(angles) - 1)] + [((x, y), tuple(mark))],
            "points": [(x, y)],
            "trace": [(x, y), tuple(mark)],
            "ground": [((floor[0], 0.0), (floor[1], 0.0))],
        }

    return draw
