"""MuJoCo's kinematic tree in its own joint coordinates, as casadi expressions: :class:`JointTree`.

The configuration is MuJoCo's ``qpos`` and the velocity its ``qvel``, so a state passes between MuJoCo and gausspp
unchanged. Each body's frame follows ``mj_kinematics`` (engine_core_smooth.c) step by step: from its parent's frame
``(x_p, R_p)`` through its fixed offset ``(body_pos, body_quat)``, then through its joints in order —

* ``slide``: ``x ← x + (R a)(q − q₀)``, ``a`` the joint's axis in the body frame;
* ``hinge``: ``R ← R·Rot(a, q − q₀)`` about the anchor ``x_a = x + R p_j`` (which stays put): ``x ← x_a − R p_j``;
* ``ball``: the same with the unit quaternion ``qpos[i:i+4]`` as the local rotation;
* ``free`` (alone on its body): ``x = qpos[i:i+3]``, ``R = R(qpos[i+3:i+7])``;

and its centre of mass and principal axes ``x_c = x + R·body_ipos``, ``R_c = R·R(body_iquat)``.

Velocities are MuJoCo's ``qvel``: a hinge's or slide's rate, a ball's angular velocity in the frame its rotation
carries, a free joint's origin velocity in world axes and angular velocity in body axes. The kinematics ``q̇ = K(q) v``
is the identity on hinges and slides and ``ṗ = ½ p ⊗ (0, ω)`` on quaternions. Each body's angular velocity (world
axes) accumulates down the tree — a hinge adds ``(R a) q̇``, a ball ``R ω``, a free joint sets ``R ω`` — and its
centre's velocity is ``ẋ_c = ∂x_c/∂q · K v``; both are linear in ``v``: ``ẋ_c = J_v v``, ``ω_c = J_ω v`` with ``ω_c``
in the principal axes. Then (Kane's equations, the projection of Newton–Euler onto the joint space)

.. math::

    M = Σ_b (m_b J_vᵀ J_v + J_ωᵀ I_b J_ω) + \\operatorname{diag}(\\text{armature}),

    f = Σ_b \\big(J_vᵀ (m_b g − m_b \\dot J_v v) − J_ωᵀ (I_b \\dot J_ω v + ω_c × I_b ω_c)\\big) + Q(q, v, t),

``J̇ v = ∂(J v)/∂q · K v`` and ``Q`` the generalized forces of springs, dampers, fluid, actuators … (passed in). ``M``
is MuJoCo's ``mj_fullM`` (rotor inertia ``armature`` on the diagonal), and ``M v̇ = f`` is MuJoCo's smooth dynamics
``M v̇ = qfrc_passive + qfrc_actuator − qfrc_bias``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ...errors import ShapeError
from ...model.mechanism import (
    Mechanism,
    QuaternionCoordinates,
    quaternion_rate,
    quaternion_to_matrix,
)

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3  # mjtJoint


@dataclass
class TreeJoint:
    """One MuJoCo joint: its type, axis and anchor in its body's frame, and where it sits in ``qpos``/``qvel``."""

    name: str
    kind: int
    axis: np.ndarray
    pos: np.ndarray
    qadr: int
    dadr: int
    q0: np.ndarray


@dataclass
class TreeBody:
    """One MuJoCo body (the world excluded): its parent, fixed offset, joints and inertia."""

    name: str
    parent: int  # index into the tree's bodies, −1 for the world
    pos: np.ndarray
    quat: np.ndarray
    mass: float
    inertia: np.ndarray  # principal moments
    ipos: np.ndarray
    iquat: np.ndarray
    joints: list[TreeJoint] = field(default_factory=list)


@dataclass
class Frames:
    """Every body's frame and centre of mass as expressions of ``q`` (and their velocities of ``v``)."""

    x: list[Any]  # body frame origin (world)
    R: list[Any]  # body frame → world
    xc: list[Any]  # centre of mass (world)
    Rc: list[Any]  # principal axes → world
    omega: list[Any]  # angular velocity, world axes


def axis_rotation(axis: np.ndarray, angle: Any) -> Any:
    """Rodrigues' rotation by ``angle`` about the unit ``axis`` (a constant)."""
    a = np.asarray(axis, float)
    K = ca.DM(np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]))
    return ca.DM.eye(3) + ca.sin(angle) * K + (1 - ca.cos(angle)) * (K @ K)


def constant_rotation(quat: np.ndarray) -> ca.DM:
    """The rotation matrix of a constant quaternion ``(w, x, y, z)`` (normalized first, as MuJoCo does)."""
    p = np.asarray(quat, float)
    return ca.DM(ca.evalf(quaternion_to_matrix(ca.SX(ca.DM(p / np.linalg.norm(p))))))


def frames(bodies: list[TreeBody], q: Any, v: Any) -> Frames:
    """``mj_kinematics`` on symbols (module docstring), with each body's angular velocity."""
    out = Frames([], [], [], [], [])
    for b in bodies:
        if b.joints and b.joints[0].kind == FREE:
            j = b.joints[0]
            x, R = q[j.qadr : j.qadr + 3], quaternion_to_matrix(q[j.qadr + 3 : j.qadr + 7])
            omega = R @ v[j.dadr + 3 : j.dadr + 6]
        else:
            if b.parent < 0:
                x, R, omega = ca.SX(ca.DM(b.pos)), ca.SX(constant_rotation(b.quat)), ca.SX.zeros(3)
            else:
                Rp = out.R[b.parent]
                x = out.x[b.parent] + Rp @ ca.DM(b.pos)
                R = Rp @ constant_rotation(b.quat)
                omega = out.omega[b.parent]
            for j in b.joints:
                if j.kind == SLIDE:
                    x = x + (R @ ca.DM(j.axis)) * (q[j.qadr] - j.q0[0])
                    continue
                anchor = x + R @ ca.DM(j.pos)
                if j.kind == HINGE:
                    omega = omega + (R @ ca.DM(j.axis)) * v[j.dadr]
                    R = R @ axis_rotation(j.axis, q[j.qadr] - j.q0[0])
                else:  # BALL
                    R = R @ quaternion_to_matrix(q[j.qadr : j.qadr + 4])
                    omega = omega + R @ v[j.dadr : j.dadr + 3]
                x = anchor - R @ ca.DM(j.pos)
        out.x.append(x)
        out.R.append(R)
        out.xc.append(x + R @ ca.DM(b.ipos))
        out.Rc.append(R @ constant_rotation(b.iquat))
        out.omega.append(omega)
    return out


class JointTree(QuaternionCoordinates, Mechanism):
    """A MuJoCo kinematic tree in ``(qpos, qvel)`` (module docstring).

    Parameters
    ----------
    bodies : list of TreeBody
        Parents before children (MuJoCo's order).
    nq, nv : int
        Sizes of ``qpos`` and ``qvel``.
    gravity : (3,) array
    armature : (nv,) array
        Rotor inertia on each degree of freedom.
    forces : callable ``(tree) -> (Q, Q_nc, V)``
        The generalized forces beyond gravity: the total ``Q`` (nv), its non-conservative part ``Q_nc`` (whose power
        closes the energy balance) and the potential ``V`` of the conservative rest (joint springs).
    names : (coordinate names, velocity names)
    """

    def __init__(
        self,
        bodies: list[TreeBody],
        nq: int,
        nv: int,
        gravity: np.ndarray,
        armature: np.ndarray,
        forces: Any,
        names: tuple[tuple[str, ...], tuple[str, ...]],
    ) -> None:
        self.bodies = bodies
        self._symbols(nq, nv)
        q, v = self.q, self.v
        self._quaternions: list[slice] = []
        self._rotations: list[slice] = []  # the velocities of quaternions (ω)
        rate = ca.SX.zeros(nq)
        for b in bodies:
            for j in b.joints:
                if j.kind in (SLIDE, HINGE):
                    rate[j.qadr] = v[j.dadr]
                    continue
                lin = 3 if j.kind == FREE else 0
                if lin:
                    rate[j.qadr : j.qadr + 3] = v[j.dadr : j.dadr + 3]
                p = slice(j.qadr + lin, j.qadr + lin + 4)
                self._quaternions.append(p)
                self._rotations.append(slice(j.dadr + lin, j.dadr + lin + 3))
                rate[p] = quaternion_rate(q[p], v[j.dadr + lin : j.dadr + lin + 3])
        self.qdot = rate
        self.frames = frames(bodies, q, v)
        g = ca.DM(np.asarray(gravity, float))
        M = ca.SX(ca.DM(np.diag(np.asarray(armature, float))))
        f = ca.SX.zeros(nv)
        kinetic, potential = 0.5 * ca.dot(v, ca.DM(np.diag(armature)) @ v), ca.SX(0)
        self.velocities: dict[int, tuple[Any, Any, Any, Any]] = {}
        for k, b in enumerate(bodies):
            if b.mass <= 0:
                continue
            xc, Rc = self.frames.xc[k], self.frames.Rc[k]
            vc = ca.jtimes(xc, q, rate)
            wc = Rc.T @ self.frames.omega[k]
            Jv, Jw = ca.jacobian(vc, v), ca.jacobian(wc, v)
            self.velocities[k] = (vc, wc, Jv, Jw)
            I = ca.DM(np.diag(b.inertia))
            M += b.mass * (Jv.T @ Jv) + Jw.T @ I @ Jw
            dvc = ca.jtimes(vc, q, rate)  # J̇_v v
            dwc = ca.jtimes(wc, q, rate)  # J̇_ω v
            f += Jv.T @ (b.mass * g - b.mass * dvc) - Jw.T @ (I @ dwc + ca.cross(wc, I @ wc))
            kinetic += 0.5 * (b.mass * ca.dot(vc, vc) + ca.dot(wc, I @ wc))
            potential -= b.mass * ca.dot(g, xc)
        Q, Q_nc, V = forces(self)
        self.A = M
        self.f = f + Q
        self.kinetic = kinetic
        self.energy = kinetic + potential + V
        self.F_nc = Q_nc
        self.coordinate_names, self.velocity_names = names

    def generalized(self, k: int, force: Any, torque: Any) -> Any:
        """The generalized force of a ``force`` (world axes) at body ``k``'s centre of mass and a ``torque`` in its
        principal axes: ``J_vᵀ F + J_ωᵀ τ``."""
        _, _, Jv, Jw = self.velocities[k]
        return Jv.T @ force + Jw.T @ torque

    # -- quaternions ------------------------------------------------------------------------------------------
    def variation_matrix(self) -> ca.SX:
        """``δω = η̇ + ω × η`` on each quaternion's angular velocity, zero elsewhere."""
        C = ca.SX.zeros(self.nv, self.nv)
        for s in self._rotations:
            C[s, s] = ca.skew(self.v[s])
        return C

    def lagrange_rows(self, N: ca.SX) -> ca.SX:
        """``[N_i]``: Lagrange's derivative in the hinge, slide and free-translation coordinates, Euler–Poincaré's
        ``d/dt ∂N/∂ω + ω × ∂N/∂ω`` in the quaternions' angular velocities (``N`` must not depend on a quaternion)."""
        for s in self._quaternions:
            if ca.depends_on(N, self.q[s]):
                raise ShapeError(
                    "MuJoCo tree: a servo-constraint's N must not depend on a free or ball joint's quaternion (the "
                    "Euler–Poincaré form used here holds for N independent of it); use an ideal realization"
                )
        q, v, t = self.q, self.v, self.t
        Nv = ca.jacobian(N, v)
        grad_all = ca.jacobian(N, q)
        position_of = {}
        for b in self.bodies:
            for j in b.joints:
                if j.kind in (SLIDE, HINGE):
                    position_of[j.dadr] = j.qadr
                elif j.kind == FREE:
                    for k in range(3):
                        position_of[j.dadr + k] = j.qadr + k
        rows = []
        for i in range(N.numel()):
            p = Nv[i, :].T
            row = ca.jacobian(p, q) @ self.qdot + ca.jacobian(p, t)
            for d, c in position_of.items():
                row[d] -= grad_all[i, c]
            for s in self._rotations:
                row[s] += ca.cross(v[s], p[s])
            rows.append(row.T)
        return ca.vertcat(*rows) if rows else ca.SX(0, self.nv)
