"""A robot's named frame touching the ground, as a hard frictional contact: :func:`frame_contact`.

For a URDF robot (:func:`gausspp.from_urdf`, fixed or floating base) the ground is the plane ``z = h`` of the world
(gravity along ``−z``) and the contact point is the origin ``p(q)`` of a link or frame (a foot) with a sphere of
radius ``ρ`` around it (0: the point itself). Then the gap is ``g(q) = p_z − h − ρ`` and the slip the horizontal
velocity of the material point at the contact, ``p − ρ e_z``: ``ṗ + ω × (−ρ e_z)``, its ``x`` and ``y`` components
(``ω`` the frame's angular velocity in the world, from ``Ṙ Rᵀ``). Coulomb's law with ``mu`` holds it
(:class:`gausspp.FrictionContact`); give it to ``gp.Model(..., friction=[...])`` and ``gp.simulate`` integrates it.
"""

from __future__ import annotations

import casadi as ca

from ..errors import InputError
from .friction_contact import FrictionContact
from .urdf import URDFMechanism, _robot


def frame_contact(
    mech: URDFMechanism,
    frame: str,
    mu: float,
    *,
    radius: float = 0.0,
    height: float = 0.0,
    name: str | None = None,
    mu_static: float | None = None,
    restitution: float = 0.0,
) -> FrictionContact:
    """The contact of ``frame``'s origin (with a sphere of ``radius``) with the ground ``z = height`` (module
    docstring)."""
    robot = _robot(mech, frame)
    for what, value in (("radius", radius), ("height", height)):
        if not isinstance(value, (int, float)) or value != value or abs(value) == float("inf"):
            raise InputError(f"frame_contact {frame!r}: {what} must be a finite number, got {value!r}")
    if radius < 0:
        raise InputError(f"frame_contact {frame!r}: radius must be ≥ 0, got {radius!r}")
    q, v = mech.q, mech.v
    pose = robot.pose(frame, q)
    p, R = pose[:3, 3], pose[:3, :3]
    pdot = ca.jtimes(p, q, mech.qdot)
    Rdot = ca.reshape(ca.jtimes(ca.vec(R), q, mech.qdot), 3, 3)
    W = Rdot @ R.T  # ω̂ in the world
    omega = ca.vertcat(W[2, 1], W[0, 2], W[1, 0])
    material = pdot + ca.cross(omega, ca.vertcat(0, 0, -float(radius)))
    gap_fn = ca.Function("gap", [q], [p[2] - float(height) - float(radius)])
    slip_fn = ca.Function("slip", [q, v], [material[0:2]])
    return FrictionContact(
        gap=lambda q_: gap_fn(q_), slip=lambda q_, v_: slip_fn(q_, v_), mu=mu, mu_static=mu_static,
        restitution=restitution, name=frame if name is None else name,
    )  # fmt: skip
