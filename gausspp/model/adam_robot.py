"""adam-robotics 0.5.0 behind a thin adapter, with its two known bugs worked around (imported lazily).

Only :mod:`gausspp.model.urdf` imports this module, inside a function, so that ``import gausspp`` never
imports adam. The adapter builds adam's rigid-body algorithms (``RBDAlgorithms``) directly, with

* :class:`FixedMath` — adam's casadi ``SpatialMath`` whose ``concatenate`` joins *two* ``6 × 1`` motion
  columns side by side. adam 0.5.0's ``CasadiLike.concatenate(..., axis=-1)`` stacks any two column
  vectors vertically, so the joint Jacobian of a robot with exactly two joints comes out ``12 × 1``.
  Two ``3 × 1`` columns (the one case adam means, the linear and angular halves of an acceleration in
  its RNEA) keep adam's behaviour.
* :class:`FixedJoint` — adam's URDF joint with two prismatic fixes. (a) The motion subspace is
  ``(axis, 0, 0, 0)`` of size 6; adam 0.5.0 builds it from three ``3 × 1`` zero blocks, ``12 × 1``, and every
  algorithm fails on a tree with a prismatic joint. (b) The child frame sits at ``xyz + R(rpy) · q·axis``
  (the URDF axis is expressed in the joint frame); adam 0.5.0 places it at ``xyz + q·axis``, wrong as soon
  as the joint's origin has a rotation.

Both are pinned down by tests (tests/test_urdf.py) that reproduce the bug on adam's own classes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np
from adam.casadi.casadi_like import CasadiLike, SpatialMath
from adam.core import RBDAlgorithms
from adam.model import Model
from adam.model.std_factories.std_joint import StdJoint
from adam.model.std_factories.std_model import URDFModelFactory

from .mechanism import quaternion_to_matrix
from .urdf_clean import quiet

#: The adam-robotics version the workarounds are written for (``gausspp[robots]`` pins it).
ADAM_VERSION = "0.5.0"


class FixedMath(SpatialMath):
    """adam's casadi spatial algebra, with two ``6 × 1`` columns concatenated horizontally."""

    @staticmethod
    def concatenate(x: Sequence[CasadiLike], axis: int = 0) -> CasadiLike:
        arrs = [xi.array for xi in x]
        if axis in {-1, 1} and len(arrs) == 2 and all(a.shape == (6, 1) for a in arrs):
            return CasadiLike(ca.horzcat(*arrs))
        return SpatialMath.concatenate(x, axis=axis)


class FixedJoint(StdJoint):
    """adam's URDF joint, with the prismatic joint's motion subspace and placement corrected."""

    def homogeneous(self, q: Any) -> Any:
        if self.type == "prismatic":
            R = self.math.R_from_RPY(self.origin.rpy)
            return self.math.homogeneous(R, self.origin.xyz + self.math.mxv(R, q * self.axis))
        return super().homogeneous(q)

    def spatial_transform(self, q: Any) -> Any:
        if self.type == "prismatic":
            T = self.homogeneous(q)
            R = T[:3, :3].T
            return self.math.spatial_transform(R, -self.math.mxv(R, T[:3, 3]))
        return super().spatial_transform(q)

    def motion_subspace(self) -> Any:
        if self.type == "prismatic":
            z = self.math.zeros(1)
            return self.math.vertcat(self.axis[0], self.axis[1], self.axis[2], z, z, z)
        return super().motion_subspace()


class FixedFactory(URDFModelFactory):
    """adam's URDF factory building :class:`FixedJoint` joints."""

    def build_joint(self, joint: Any) -> StdJoint:
        return FixedJoint(joint, self.math)


def movable_joints(xml: str) -> list[tuple[str, str]]:
    """``(name, type)`` of the URDF's non-fixed joints, in the file's order (``xml``: the cleaned text,
    :func:`gausspp.model.urdf_clean.clean_urdf`)."""
    with quiet():
        factory = URDFModelFactory(path=xml, math=FixedMath())
    return [(j.name, j.joint_type) for j in factory.urdf_desc.joints if j.joint_type != "fixed"]


class AdamRobot:
    """A robot's dynamics and kinematics as casadi expressions (adam's algorithms, bugs fixed).

    Parameters
    ----------
    xml : str
        The URDF's cleaned text (:func:`gausspp.model.urdf_clean.clean_urdf`).
    joints : list of str
        The joints that move, in the order of ``q``.
    g : float
        Gravity along ``−z`` of the world frame.
    floating : bool
        A floating base: ``q = (p, ρ, s)`` — the base frame's origin ``p`` in the world, its unit quaternion ``ρ``
        ``(w, x, y, z)`` (base → world) and the joints ``s`` — and ``v = (u, ω, ṡ)`` with the base's velocity
        ``u`` and angular velocity ``ω`` both in **base axes** (adam's body-fixed representation, Pinocchio's
        free-flyer's). Otherwise the base is the world frame and ``q = s``.
    """

    def __init__(self, xml: str, joints: list[str], g: float, floating: bool = False) -> None:
        from adam.core.constants import Representations

        math = FixedMath()
        with quiet():
            model = Model.build(factory=FixedFactory(path=xml, math=math), joints_name_list=joints)
        self.algorithms = RBDAlgorithms(model=model, math=math)
        self.algorithms.set_frame_velocity_representation(Representations.BODY_FIXED_REPRESENTATION)
        self.gravity = np.array([0.0, 0.0, -g, 0.0, 0.0, 0.0])
        self.frames = set(model.links) | set(model.frames)
        self.n = len(joints)
        self.floating = bool(floating)
        self.mass = float(self.algorithms.get_total_mass())

    def base(self, q: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The base's homogeneous transform (base → world) and the joint coordinates, from ``q``."""
        if not self.floating:
            return ca.SX.eye(4), q
        p, rho = q[0:3], q[3:7]
        R = quaternion_to_matrix(rho / ca.norm_2(rho))
        H = ca.vertcat(ca.horzcat(R, p), ca.horzcat(ca.SX.zeros(1, 3), ca.SX(1)))
        return H, q[7:]

    def mass_matrix(self, q: ca.SX) -> ca.SX:
        """The CRBA mass matrix: the joints' block for a fixed base, the whole ``(6 + n)²`` for a floating one."""
        H, s = self.base(q)
        M, _ = self.algorithms.crba(H, s)
        return M.array if self.floating else M.array[6:, 6:]

    def bias(self, q: ca.SX, v: ca.SX) -> ca.SX:
        """``h(q, v) = C(q, v) v + g(q)``: the generalized forces of zero acceleration (RNEA)."""
        H, s = self.base(q)
        base_velocity, sdot = (v[0:6], v[6:]) if self.floating else (ca.SX.zeros(6), v)
        h = self.algorithms.rnea(H, s, base_velocity, sdot, self.gravity)
        return h.array if self.floating else h.array[6:]

    def pose(self, frame: str, q: ca.SX) -> ca.SX:
        """The ``4 × 4`` homogeneous transform of ``frame`` in the world frame."""
        H, s = self.base(q)
        return self.algorithms.forward_kinematics(frame, H, s).array

    def com(self, q: ca.SX) -> ca.SX:
        """The centre of mass in the world frame."""
        H, s = self.base(q)
        return self.algorithms.CoM_position(H, s).array
