"""MuJoCo's ``frictionloss``: dry friction in each degree of freedom, as :class:`gausspp.JointFriction`.

MuJoCo bounds the friction force of each degree of freedom ``d`` by its ``dof_frictionloss`` — ``|F_d| ≤ f_d``,
one box per component, a ball or free joint's components each on its own — and keeps it softly (its constraint
solver lets a sticking joint creep). gausspp keeps it as Coulomb's law with that fixed bound: the degree of freedom
sticks (its velocity ``qvel[d]`` held at zero) while the force that holds it is within the bound, and slips
against its velocity with the bound's force otherwise — the friction lane's events, exactly (docs/friction.md).
A tendon's ``frictionloss`` is refused by name (:func:`gausspp.multibody.mjcf._check_unmapped`).
"""

from __future__ import annotations

import numpy as np

from ...model.friction_contact import JointFriction
from .context import Loading
from .tree import JointTree


def joint_friction(load: Loading, tree: JointTree) -> list[JointFriction]:
    """One :class:`~gausspp.JointFriction` per degree of freedom with a nonzero ``frictionloss`` (none where MuJoCo's
    ``<flag frictionloss="disable"/>`` or ``constraint="disable"`` switches them off), named by its joint (and the
    component, for a joint of several)."""
    m = load.m
    if load.disabled("FRICTIONLOSS", "CONSTRAINT"):
        return []
    out = []
    for d in np.flatnonzero(np.asarray(m.dof_frictionloss) > 0):
        j = int(m.dof_jntid[d])
        name = load.names.of("joint", j)
        first = int(m.jnt_dofadr[j])
        count = int(np.sum(np.asarray(m.dof_jntid) == j))
        label = name if count == 1 else f"{name}[{int(d) - first}]"
        out.append(
            JointFriction(lambda q, v, d=int(d): v[d], float(m.dof_frictionloss[d]), name=f"{label} frictionloss")
        )
    return out
