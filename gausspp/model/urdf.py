"""URDF robots as mechanisms: ``gp.from_urdf`` and the frame kinematics to write constraints with.

A fixed-base robot with joint coordinates ``q`` (revolute angles, prismatic displacements) moves by

.. math:: A(q)\\,\\ddot q = \\tau(q, v, t) - h(q, v), \\qquad h = C(q, v)\\,v + g(q),

``A`` the composite-rigid-body mass matrix and ``h`` the bias forces (recursive Newton–Euler at zero
acceleration), with gravity ``g`` along ``−z`` of the base frame. Both come from adam-robotics 0.5.0
(:mod:`gausspp.model.adam_robot`, an optional extra: ``pip install 'gausspp[robots]'``) as casadi
expressions; the robot becomes a :class:`~gausspp.MassMatrix` whose energy is
``½ vᵀ A v + m g z_c(q)`` (``m`` the total mass, ``z_c`` the height of the centre of mass).

A frame's position ``p(q)`` (:func:`frame_position`), translational Jacobian ``J = ∂p/∂q``
(:func:`frame_jacobian`) and acceleration bias ``J̇ v = ∂(J v)/∂q · v`` (:func:`frame_acceleration_bias`,
so that ``p̈ = J q̈ + J̇ v``) are casadi expressions of whatever ``q`` (and ``v``) they are given — the
symbols a constraint's function receives.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from importlib import metadata
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaussppError, InputError, UnknownNameError
from ..validation import number
from .mechanism import (
    MassMatrix,
    normalize_quaternion_array,
    normalize_quaternions,
    quaternion_rate,
    quaternion_to_matrix,
)
from .symbolic import evaluate

#: What to install for :func:`from_urdf`.
EXTRA = "pip install 'gausspp[robots]'"
#: Joint types that are one coordinate each.
ONE_DOF = ("revolute", "continuous", "prismatic")
#: Joint types :func:`from_urdf` reads: the one-coordinate ones, and ``fixed``.
READ = (*ONE_DOF, "fixed")
#: URDF's other joint types (adam-robotics does not model them).
UNREAD = ("planar", "floating")


class URDFMechanism(MassMatrix):
    """A URDF robot, ``A(q) v̇ = τ − h(q, v)`` (built by :func:`from_urdf`).

    Attributes
    ----------
    joint_names : tuple of str
        The joints, in the order of their coordinates (after the base's seven for a floating base).
    floating : bool
        Whether the base floats (``q = (p, ρ, s)``, ``v = (u, ω, ṡ)``: :func:`from_urdf`).
    robot : AdamRobot
        The kinematics and dynamics as casadi expressions (:mod:`gausspp.model.adam_robot`).
    """

    def __init__(
        self,
        robot: Any,
        joint_names: Sequence[str],
        g: float,
        torque: Callable[..., Any] | None,
        floating: bool = False,
    ) -> None:
        joints = len(joint_names)
        n = joints + (6 if floating else 0)
        self.robot = robot
        self.joint_names = tuple(joint_names)
        self.floating = bool(floating)
        base_q = ("base.x", "base.y", "base.z", "base.qw", "base.qx", "base.qy", "base.qz") if floating else ()
        base_v = ("base.u", "base.v", "base.w", "base.ωx", "base.ωy", "base.ωz") if floating else ()
        self.coordinate_names = (*base_q, *self.joint_names)  # names in results and plots
        self.velocity_names = (*base_v, *self.joint_names)
        self.g = float(g)

        def applied(q: Any, v: Any, t: Any) -> Any:
            if torque is None:
                return ca.SX.zeros(n)
            tau = evaluate(torque, (q, v, t), (joints, 1), "torque(q, v, t)")
            return ca.vertcat(ca.SX.zeros(n - joints), tau)

        def energy(q: Any, v: Any, t: Any) -> Any:
            return 0.5 * ca.dot(v, robot.mass_matrix(q) @ v) + robot.mass * self.g * robot.com(q)[2]

        def kinematics(q: Any, v: Any, t: Any) -> Any:  # ṗ = R u, ρ̇ = ½ ρ ⊗ (0, ω), ṡ = ṡ
            rho = q[3:7]
            R = quaternion_to_matrix(rho / ca.norm_2(rho))
            return ca.vertcat(R @ v[0:3], quaternion_rate(rho, v[3:6]), v[6:])

        super().__init__(
            n,
            A=lambda q, t: robot.mass_matrix(q),
            f=lambda q, v, t: applied(q, v, t) - robot.bias(q, v),
            energy=energy,
            kinematics=kinematics if floating else None,
            nq=n + 1 if floating else None,
            nonconservative=applied,
        )

    def normalize(self, q: ca.SX) -> ca.SX:
        """The floating base's quaternion of unit length (a fixed base: ``q`` itself)."""
        return normalize_quaternions(q, [slice(3, 7)] if self.floating else [])

    def normalize_array(self, q: np.ndarray) -> np.ndarray:
        """:meth:`normalize` on numbers (one configuration, or one per row)."""
        return normalize_quaternion_array(q, [slice(3, 7)] if self.floating else [])

    def variation_matrix(self) -> ca.SX:
        """The floating base's body velocity ``(u, ω)`` is a quasi-velocity: ``δ(u, ω) = η̇ + ad₍ᵤ,ω₎ η`` with
        ``ad = [[ω×, u×], [0, ω×]]`` (zero for a fixed base)."""
        C = ca.SX.zeros(self.nv, self.nv)
        if self.floating:
            w, u = self.v[3:6], self.v[0:3]
            C[0:3, 0:3] = ca.skew(w)
            C[0:3, 3:6] = ca.skew(u)
            C[3:6, 3:6] = ca.skew(w)
        return C


def _robot_class() -> Any:
    """adam's adapter class, or a project error naming the extra to install (or the version to pin)."""
    try:
        found = metadata.version("adam-robotics")
    except metadata.PackageNotFoundError:
        raise GaussppError(f"from_urdf needs adam-robotics with casadi: {EXTRA}") from None
    from . import adam_robot

    if found != adam_robot.ADAM_VERSION:
        raise GaussppError(
            f"from_urdf is written for adam-robotics {adam_robot.ADAM_VERSION} (its workarounds depend on it), "
            f"found {found!r}; {EXTRA}"
        )
    return adam_robot


def from_urdf(
    path: str,
    joints: Sequence[str] | None = None,
    g: float = 9.81,
    torque: Callable[..., Any] | None = None,
    floating: bool = False,
) -> URDFMechanism:
    """A robot from a URDF file: ``A(q)``, bias forces, gravity, joint names.

    Parameters
    ----------
    path : str
        The URDF file (``package://`` mesh addresses do not matter: only the inertias and joints are read). What
        URDF allows and adam-robotics trips on is written out first (:mod:`gausspp.model.urdf_clean`: a joint or an
        inertial without ``<origin>``, materials with textures, transmissions), and the parser's warnings about
        tags the dynamics do not read are kept quiet.
    joints : sequence of str, optional
        The joints that move, in the order of ``q``; default every revolute, continuous and prismatic
        joint in the file's order. Other joints are held at zero. A ``planar`` or ``floating`` joint (or a
        type URDF does not have) is refused, naming the joint.
    g : float
        Gravity's magnitude along ``−z`` of the world frame (gausspp's convention, 9.81).
    torque : callable ``(q, v, t) -> (n,)``, optional
        Applied joint torques (friction, springs, a known actuation), one per joint; none by default.
    floating : bool
        A floating base (a legged robot, a humanoid): the root link moves freely, ``q = (p, ρ, s)`` — the root
        frame's origin ``p`` in the world, its unit quaternion ``ρ = (w, x, y, z)`` (root → world), the joints ``s``
        — and ``v = (u, ω, ṡ)`` with the root's velocity ``u`` and angular velocity ``ω`` in the **root's axes**
        (Pinocchio's free-flyer's convention), so ``ṗ = R(ρ) u`` and ``ρ̇ = ½ ρ ⊗ (0, ω)``: ``nq = 7 + n``,
        ``nv = 6 + n``. Default: the root is bolted to the world.

    Returns
    -------
    URDFMechanism
        A :class:`~gausspp.MassMatrix` with ``joint_names``.
    """
    path = _checked_file(path)
    adam_robot = _robot_class()
    g = number(f"from_urdf: g must be a finite number (gravity's magnitude, m/s²), got {g!r}", g)
    if not isinstance(floating, bool):
        raise InputError(f"from_urdf: floating must be True or False, got {floating!r}")
    if joints is not None and (isinstance(joints, str) or not all(isinstance(j, str) for j in joints)):
        raise InputError(f"from_urdf: joints must be a list of joint names, got {joints!r}")
    from .urdf_clean import clean_urdf

    xml = clean_urdf(path)
    movable = [name for name, _ in adam_robot.movable_joints(xml)]  # one coordinate each (_checked_file)
    names = movable if joints is None else list(joints)
    for name in names:
        if name not in movable:
            raise UnknownNameError(
                f"from_urdf: joint {name!r} is not a movable joint of {path}; known: {sorted(movable)}"
            )
    if not names:
        raise InputError(
            f"from_urdf: {path} has no revolute, continuous or prismatic joint: one rigid body, nothing moves with a "
            "fixed base; write a floating one as a gp.Multibody body (its mass and inertia from the file's link)"
            if floating
            else f"from_urdf: {path} has no revolute, continuous or prismatic joint: nothing moves with a fixed base"
        )
    robot = adam_robot.AdamRobot(xml, names, float(g), floating)
    return URDFMechanism(robot, names, g, torque, floating)


def _checked_file(path: Any) -> str:
    """The URDF file, readable and well-formed XML, or an error naming it and what is wrong."""
    import xml.etree.ElementTree as ET

    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"from_urdf: path must be the name of a URDF file, got {path!r}")
    if not os.path.isfile(path):
        raise InputError(f"from_urdf: {str(path)!r}: no such file")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise InputError(f"from_urdf: {str(path)!r} is not well-formed XML ({exc})") from None
    except OSError as exc:
        raise InputError(f"from_urdf: cannot read {str(path)!r}: {exc.strerror or exc}") from None
    if root.tag != "robot":
        raise InputError(f"from_urdf: {str(path)!r} is not a URDF file (its root element is <{root.tag}>, not <robot>)")
    _check_masses(root, str(path))
    _check_joints(root, str(path))
    return str(path)


def _check_masses(root: Any, path: str) -> None:
    """Every link's mass a non-negative number, or an error naming the link."""
    for link in root.iter("link"):
        for mass in link.iter("mass"):
            text = mass.get("value")
            try:
                value = float(text) if text is not None else float("nan")
            except ValueError:
                value = float("nan")
            if not value >= 0 or value == float("inf"):  # 0 is a frame's massless link
                raise InputError(
                    f"from_urdf: link {link.get('name')!r} of {path!r} has mass {text!r}; a link's mass must be "
                    "a non-negative number (kg)"
                )


def _check_joints(root: Any, path: str) -> None:
    """Every joint of a type :func:`from_urdf` reads (:data:`READ`), or an error naming the joint, its type and
    what to write instead (``<robot>``'s own joints: a ``<transmission>``'s joint references have no type)."""
    fixes = {
        "planar": "write it as two prismatic joints and a revolute one through massless links, or make it 'fixed'",
        "floating": "from_urdf builds fixed-base robots: make it 'fixed'",
    }
    for joint in root.findall("joint"):
        kind = joint.get("type")
        if kind in READ:
            continue
        what = "which adam-robotics does not model" if kind in UNREAD else "which is not a URDF joint type"
        fix = fixes.get(str(kind), "give it one of these types")
        raise InputError(
            f"from_urdf: joint {joint.get('name')!r} of {path!r} has type {kind!r}, {what}; from_urdf reads "
            f"{', '.join(READ)} joints: {fix}"
        )


def _robot(mech: Any, frame: str) -> Any:
    robot = getattr(mech, "robot", None)
    if not isinstance(mech, URDFMechanism) or robot is None:
        raise InputError(f"mech must be a mechanism from gp.from_urdf, got {type(mech).__name__}")
    if frame not in robot.frames:
        raise UnknownNameError(f"frame {frame!r} is not a link or frame of the robot; known: {sorted(robot.frames)}")
    return robot


def frame_position(mech: URDFMechanism, frame: str, q: Any = None) -> ca.SX:
    """Position ``p(q)`` of a link or frame's origin in the base frame, a ``(3, 1)`` casadi expression.

    ``q`` defaults to ``mech.q``; inside a constraint pass the ``q`` the constraint receives.
    """
    robot = _robot(mech, frame)
    return robot.pose(frame, mech.q if q is None else q)[:3, 3]


def frame_rotation(mech: URDFMechanism, frame: str, q: Any = None) -> ca.SX:
    """Rotation matrix (frame → base) of a link or frame, a ``(3, 3)`` casadi expression."""
    robot = _robot(mech, frame)
    return robot.pose(frame, mech.q if q is None else q)[:3, :3]


def frame_jacobian(mech: URDFMechanism, frame: str, q: Any = None) -> ca.SX:
    """Translational Jacobian ``J(q) = ∂p/∂q`` of a frame's origin, ``(3, n)``: ``ṗ = J v``."""
    qs = mech.q
    J = ca.jacobian(frame_position(mech, frame, qs), qs)
    return J if q is None else ca.substitute(J, qs, q)


def frame_acceleration_bias(mech: URDFMechanism, frame: str, q: Any = None, v: Any = None) -> ca.SX:
    """``J̇ v = ∂(J v)/∂q · v``, ``(3, 1)``: the frame origin's acceleration is ``p̈ = J q̈ + J̇ v``."""
    qs, vs = mech.q, mech.v
    Jv = frame_jacobian(mech, frame) @ vs
    bias = ca.jacobian(Jv, qs) @ vs
    if q is None and v is None:
        return bias
    return ca.substitute(bias, ca.vertcat(qs, vs), ca.vertcat(mech.q if q is None else q, vs if v is None else v))
