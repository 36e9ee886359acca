"""Coulomb friction on unilateral contacts, by Gauss's principle (docs/friction.md).

:class:`FrictionContact` declares a contact (gap, slip, ``μ``, ``μ_s``, restitution), :class:`JointFriction` a
joint's dry friction (a force along its velocity with a fixed bound);
:func:`simulate_friction` integrates a mechanism with such contacts event by event (stick, slide, lift-off,
impact); :func:`gauss_qp_step` solves one step as Gauss's QP over the conceivable accelerations with the
friction cone, the independent check of the direct solution (:mod:`.modes`).
"""

from ..model.friction_contact import FrictionContact, JointFriction
from .gauss_qp import gauss_qp_step
from .integrate import simulate_friction
from .run import FrictionRun

__all__ = ["FrictionContact", "FrictionRun", "JointFriction", "gauss_qp_step", "simulate_friction"]
