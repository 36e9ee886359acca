"""What the rigid-body scenes share: unit axes, inertia tensors, initial ω on (ω, l) = 0, and their drawing."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import ShapeError
from ..validation import array, inertia_matrix, unit_vector  # noqa: F401  (the rigid-body scenes take them from here)

#: A rigid body's coordinates (the unit quaternion body → space, dimensionless) and velocities (ω, body axes).
QUATERNION = ("q_w (1)", "q_x (1)", "q_y (1)", "q_z (1)")
OMEGA = ("ω₁ (rad/s)", "ω₂ (rad/s)", "ω₃ (rad/s)")


def on_plane(scene: str, omega0: Any, l: np.ndarray) -> np.ndarray:
    """``omega0`` projected onto the plane ``(ω, l) = 0`` (``l`` a unit vector)."""
    w0 = array(scene, "omega0", omega0).ravel()
    if w0.shape != (3,):
        raise ShapeError(f"{scene}: omega0 must have 3 components, got {w0.size}")
    return w0 - np.dot(w0, l) * l


#: Where the camera of :func:`body_axes_drawing` looks from (space axes, z up).
VIEW_FROM = (1.0, -1.6, 0.8)


def screen(view_from: Any = VIEW_FROM) -> np.ndarray:
    """The rows ``(right, up)`` of an axonometric view looking at the origin from ``view_from``, z up:
    a space point ``p`` is seen at ``screen @ p``."""
    back = np.asarray(view_from, float) / np.linalg.norm(view_from)
    right = np.cross(-back, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    return np.vstack([right, np.cross(right, -back)])


_SCREEN = screen()


def body_axes_drawing(q: np.ndarray) -> dict[str, Any]:
    """The body axes ``e₁, e₂, e₃`` (unit length) about the fixed point, in space, seen from :data:`VIEW_FROM`,
    with the way their tips have gone and the space axes (thin) for reference (:attr:`Scene.drawing`).

    ``q`` starts with the unit quaternion ``(w, x, y, z)``, body → space; its columns ``R eᵢ`` are drawn.
    """
    rotation = Rotation.from_quat(np.asarray(q[:4], float), scalar_first=True).as_matrix()
    tips = (_SCREEN @ rotation).T
    space = (_SCREEN * 1.2).T
    origin = np.zeros(2)
    return {
        "axes": [(origin, tip) for tip in tips],
        "trace": tips,
        "fixed": [origin],
        "ground": [(origin, tip) for tip in space],
        "labels": (f"view from {VIEW_FROM}: right", "up (space z up; thin lines: space axes)"),
    }
