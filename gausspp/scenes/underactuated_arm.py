"""A three-link planar arm with a passive elbow whose tip follows a path: an underactuated servo.

Three revolute joints about ``z`` (shoulder, elbow, wrist; links 0.5, 0.5 and 0.4 m to the tip), in the
horizontal plane, written here as a URDF (:func:`three_link_urdf`) and read by :func:`~gausspp.from_urdf`.
The tip's ``x`` and ``y`` follow ``p₀ + (1 − cos ωt) d`` (two coordinates), realized by a Béghin servo
:class:`~gausspp.Force` with two motors, the shoulder and the wrist (``M`` the rows ``e₁``, ``e₃``); the elbow
is passive. ``J A⁻¹ Mᵀ`` is 2 × 2: the direct formula (``solver="direct"``). On ``[0, 0.5]`` s the realizability
margin stays near 0.4; continued, the passive elbow is dragged towards a configuration where ``J A⁻¹ Mᵀ`` is
singular (t ≈ 0.87 s). Needs ``pip install 'gausspp[robots]'``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ..model.model import Model
from ..model.urdf import from_urdf
from ..validation import positive
from .scene import Scene
from .ur5_tool_path import path_offset, tool_path

#: The motors: shoulder and wrist (the rows of ``M``, reaction ``Mᵀλ``); the elbow is passive.
MOTORS = ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0))
#: The initial joint angles (rad).
Q0 = (0.3, 0.8, -0.5)


def link(name: str, x: float = 0.25) -> str:
    """A URDF link of mass 1.3 kg, its centre of mass at ``(x, 0.02, 0.01)``, a full (non-diagonal) inertia."""
    return (
        f'<link name="{name}"><inertial><origin xyz="{x} 0.02 0.01" rpy="0.1 0.2 0.3"/><mass value="1.3"/>'
        '<inertia ixx="0.02" ixy="0.001" ixz="0.002" iyy="0.03" iyz="0.003" izz="0.04"/></inertial></link>'
    )


def three_link_urdf() -> str:
    """A planar arm in the horizontal plane (three joints about ``z``, links 0.5, 0.5 and 0.4 m to the tip)."""
    joints = ""
    for name, parent, child, x in (
        ("shoulder", "base", "l1", 0),
        ("elbow", "l1", "l2", 0.5),
        ("wrist", "l2", "l3", 0.5),
    ):
        joints += (
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{x} 0 0"/><axis xyz="0 0 1"/>'
            '<limit effort="100" velocity="10" lower="-3" upper="3"/></joint>'
        )
    tip = '<joint name="tip_fixed" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0.4 0 0"/></joint>'
    body = link("l1") + link("l2") + link("l3") + joints + tip
    return f'<robot name="three"><link name="base"/>{body}<link name="tip"/></robot>'


def arm_model(mech: Any, d: Any = (0.05, 0.04), q0: Any = Q0, omega: float = 2.0) -> Model:
    """The arm ``mech`` (from :func:`three_link_urdf`) with its tip's ``x, y`` on the path, by the two motors."""
    path = tool_path(mech, "tip", np.asarray(q0, float), np.asarray(d, float), MOTORS, coords=(0, 1), omega=omega)
    return Model(mech, path)


def build(
    d: Any = (0.05, 0.04), t_end: float = 0.5, omega: float = 2.0, g: float = 9.81, urdf: str | None = None
) -> Scene:
    """Three-link planar arm, passive elbow: the tip's x, y follow a path by shoulder and wrist (direct formula).

    Needs ``pip install 'gausspp[robots]'``.

    Parameters
    ----------
    d : (2,) array_like
        Amplitude of the tip's path ``p₀ + (1 − cos ωt) d`` in x and y: the tip moves to ``p₀ + 2d`` and back in
        2π/ω (m). Allowed: 2 finite numbers.
    t_end : float
        Suggested horizon of a simulation: the margin stays above 0.3 on the default 0.5 s, near 0.87 s the arm
        meets a singular ``J A⁻¹ Mᵀ`` (s). Allowed: > 0.
    omega : float
        Angular frequency ω of the path (1/s). Allowed: > 0.
    g : float
        Gravity's magnitude, along the base's −z, normal to the arm's plane (m/s²). Allowed: finite.
    urdf : str or None
        Path of the arm's URDF: three joints ``shoulder``, ``elbow``, ``wrist`` and a frame ``tip``, in any units
        (-). Allowed: None for :func:`three_link_urdf`, or a readable file.
    """
    offset = path_offset("underactuated-arm", d, 2)
    t_end, omega = positive("t_end", t_end), positive("omega", omega)
    if urdf is not None:
        mech = from_urdf(urdf, g=g)
    else:
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "three_link.urdf"
            path.write_text(three_link_urdf())
            mech = from_urdf(str(path), g=g)
    return Scene(
        name="underactuated-arm",
        model=arm_model(mech, offset, omega=omega),
        q0=np.array(Q0),
        v0=np.zeros(3),
        coordinates=tuple(f"{joint} (rad)" for joint in mech.joint_names),
        lam0=None,
        t_end=float(t_end),
        exact=None,
        description="three-link arm, passive elbow: tip path by 2 motors (direct formula)",
        params={
            "d": tuple(offset),
            "t_end": float(t_end),
            "omega": omega,
            "g": float(g),
            "urdf": urdf,
            "solver": "direct",
        },
    )
