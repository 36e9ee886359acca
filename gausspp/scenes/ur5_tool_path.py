"""A UR5's tool follows a prescribed path, realized by its six joint torques: servo inverse dynamics.

The UR5 of example-robot-data (:func:`~gausspp.from_urdf`): six revolute joints, ``A(q) q̈ = τ − h(q, v)``.
The tool frame's position ``p(q)`` follows

    p(t) = p₀ + (1 − cos ωt) d,   p₀ = p(q₀),

three coordinates, realized by a Béghin servo force :class:`~gausspp.Force` whose directions are the six joint
torques (``M = I₆``). Six actuators for three path coordinates: the arm is redundant, and Gauss's principle picks,
among the torques that keep the tool on its path, the motion of least compulsion — the QP solver
(``solver="qp"``, recorded in the scene's ``params`` with the drift control, ``stabilize="baumgarte"``).
Nothing holds the three-dimensional self-motion (the wrists
swing freely), which is why the move is kept short. The torques along the motion are Pinocchio's inverse dynamics
(RNEA) of that motion. Needs ``pip install 'gausspp[robots]' example-robot-data``.
"""

from __future__ import annotations

from collections.abc import Sequence
from importlib import metadata
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaussppError, ShapeError
from ..model.constraints import Holonomic
from ..model.model import Model
from ..model.realizations import Force
from ..model.urdf import EXTRA, URDFMechanism, frame_position, from_urdf
from ..validation import array, positive
from .scene import Scene

#: The UR5's initial joint angles (rad): an elbow-up pose away from singularities.
Q0 = (0.1, -1.2, 1.5, -0.8, -1.4, 0.3)


def ur5_urdf() -> str:
    """The path of example-robot-data's ``ur5_robot.urdf``, or a project error naming what to install."""
    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        raise GaussppError(f"the UR5 scene needs example-robot-data's URDF: {EXTRA} example-robot-data") from None
    found = [f for f in dist.files or [] if str(f).endswith("ur_description/urdf/ur5_robot.urdf")]
    if not found:
        raise GaussppError(f"example-robot-data has no ur_description/urdf/ur5_robot.urdf; reinstall it: {EXTRA}")
    return str(dist.locate_file(found[0]))


def tool_path(
    mech: URDFMechanism,
    frame: str,
    q0: np.ndarray,
    d: np.ndarray,
    motors: Any,
    coords: Sequence[int] | None = None,
    omega: float = 2.0,
) -> Holonomic:
    """The servo-constraint ``p(q)[coords] − (p(q₀)[coords] + (1 − cos ωt) d) = 0`` realized by ``Force(motors)``.

    ``frame`` is a link or frame of ``mech``; ``coords`` the position coordinates prescribed (all three by
    default); ``motors`` the rows of ``M`` (``R = Mᵀλ``), e.g. ``ca.DM.eye(n)`` for a torque at every joint;
    ``omega`` the path's angular frequency (1/s).
    """
    rows = list(range(3)) if coords is None else list(coords)
    p0 = ca.Function("p", [mech.q], [frame_position(mech, frame)[rows]])(q0)
    directions = ca.DM(motors)
    return Holonomic(
        lambda q, t: frame_position(mech, frame, q)[rows] - (p0 + (1 - ca.cos(omega * t)) * ca.DM(d)),
        name=f"{frame} path",
        realization=Force(lambda q, v, t: directions),
    )


def path_offset(scene: str, d: Any, n: int) -> np.ndarray:
    """``d`` as ``n`` finite numbers, or an error naming the scene."""
    vec = array(f"scene {scene!r}", "d", d).ravel()
    if vec.shape != (n,):
        raise ShapeError(f"scene {scene!r}: d must be {n} numbers (the path's amplitude, m), got {list(vec)}")
    return vec


def build(
    d: Any = (0.08, 0.05, -0.04), t_end: float = 1.2, omega: float = 2.0, g: float = 9.81, urdf: str | None = None
) -> Scene:
    """UR5 (example-robot-data): the tool follows a path by its 6 joint torques, redundant (QP, least compulsion).

    Needs ``pip install 'gausspp[robots]' example-robot-data``; step and simulate it with ``solver="qp"``.

    Parameters
    ----------
    d : (3,) array_like
        Amplitude of the tool's path ``p₀ + (1 − cos ωt) d``: the tool moves to ``p₀ + 2d`` and back in 2π/ω (m).
        Allowed: 3 finite numbers.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    omega : float
        Angular frequency ω of the path (1/s). Allowed: > 0.
    g : float
        Gravity's magnitude, along the base's −z (m/s²). Allowed: finite.
    urdf : str or None
        Path of the robot's URDF: a UR5 with a frame ``tool0`` and six joints, in any units (-). Allowed: None for
        example-robot-data's ``ur5_robot.urdf``, or a readable file.
    """
    offset = path_offset("ur5-tool-path", d, 3)
    t_end, omega = positive("t_end", t_end), positive("omega", omega)
    mech = from_urdf(ur5_urdf() if urdf is None else urdf, g=g)
    q0 = np.array(Q0)
    model = Model(mech, tool_path(mech, "tool0", q0, offset, ca.DM.eye(6), omega=omega))
    return Scene(
        name="ur5-tool-path",
        model=model,
        q0=q0,
        v0=np.zeros(6),
        coordinates=tuple(f"{joint} (rad)" for joint in mech.joint_names),
        lam0=None,
        t_end=float(t_end),
        exact=None,
        description="UR5 tool path by 6 joint torques (redundant: QP, least compulsion)",
        params={
            "d": tuple(offset),
            "t_end": float(t_end),
            "omega": omega,
            "g": float(g),
            "urdf": urdf,
            "solver": "qp",
            "stabilize": "baumgarte",
        },
    )
