"""A body's point touching the ground, as a hard frictional contact: :meth:`gausspp.Multibody.ground_contact`.

The ground is the plane ``n·x = h`` — ``n`` the unit normal (default: against gravity), ``h`` the height — and the
point ``p`` fixed in a body (``local``, from its centre of mass in body axes) carries a sphere of ``radius`` ``ρ``
(0: the point itself). Then

* the gap ``g(q) = n·x_p(q) − h − ρ``, ``x_p = r + R p`` (positive above the ground);
* the slip: the velocity of the body's material point at the contact, ``x_c = x_p − ρ n``, along the ground:
  ``ẋ_c = ṙ + ω × (x_c − r)`` (space axes; a spatial body's ``ω = R ω_body``) on two unit tangents ``t₁, t₂ ⟂ n``
  (spatial), on ``t = (n_y, −n_x)`` (planar: one component).

Coulomb's law with ``mu`` (kinetic) and ``mu_static`` holds it (:class:`gausspp.FrictionContact`), and
``gp.simulate`` integrates the machine with its contacts event by event (its friction lane).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.friction_contact import FrictionContact
from .bodies import Body, vector


def ground_contact(
    body: Body,
    name: str,
    local: Any,
    normal: np.ndarray,
    height: float,
    radius: float,
    mu: float,
    mu_static: float | None,
    restitution: float,
) -> FrictionContact:
    dim = 2 if body.planar else 3
    p = vector(f"ground contact {name!r}", "point", local, dim)
    n = np.asarray(normal, float)
    if n.shape != (dim,) or not np.all(np.isfinite(n)) or np.linalg.norm(n) == 0:
        raise InputError(f"ground contact {name!r}: normal must be {dim} finite numbers, not all zero; got {normal!r}")
    n = n / np.linalg.norm(n)
    for what, value in (("height", height), ("radius", radius)):
        if not np.isfinite(float(value)) or (what == "radius" and float(value) < 0):
            raise InputError(
                f"ground contact {name!r}: {what} must be a finite number{' ≥ 0' if what == 'radius' else ''}"
            )
    if body.planar:
        tangents = [np.array([n[1], -n[0]])]
    else:
        helper = np.eye(3)[int(np.argmin(np.abs(n)))]
        t1 = helper - (helper @ n) * n
        t1 /= np.linalg.norm(t1)
        tangents = [t1, np.cross(n, t1)]

    def gap(q: Any) -> Any:
        return ca.dot(ca.DM(n), body.point(q, p)) - float(height) - float(radius)

    def slip(q: Any, v: Any) -> Any:
        r, R = body.parts(q)
        w = v[body.v_start : body.v_start + body.nv]
        arm = R @ ca.DM(p) - float(radius) * ca.DM(n)  # from the centre to the contact point
        if body.planar:
            velocity = w[0:2] + w[2] * ca.vertcat(-arm[1], arm[0])
        else:
            velocity = w[0:3] + ca.cross(R @ w[3:6], arm)
        return ca.vertcat(*[ca.dot(ca.DM(t), velocity) for t in tangents])

    return FrictionContact(gap, slip, mu, mu_static=mu_static, restitution=restitution, name=name)
