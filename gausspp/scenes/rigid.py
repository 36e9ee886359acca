"""Parameters shared by the rigid-body scenes: unit axes, inertia tensors, initial ω on (ω, l) = 0."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from ..validation import array

#: A rigid body's coordinates (the unit quaternion body → space, dimensionless) and velocities (ω, body axes).
QUATERNION = ("q_w (1)", "q_x (1)", "q_y (1)", "q_z (1)")
OMEGA = ("ω₁ (rad/s)", "ω₂ (rad/s)", "ω₃ (rad/s)")


def unit_vector(scene: str, name: str, value: Any) -> np.ndarray:
    """``value`` as a unit 3-vector, or a clear error naming the scene and the parameter."""
    vec = array(scene, name, value).ravel()
    if vec.shape != (3,):
        raise ShapeError(f"{scene}: {name} must have 3 components, got {vec.size}")
    norm = np.linalg.norm(vec)
    if norm == 0:
        raise InputError(f"{scene}: {name} must be a finite nonzero vector, got {vec.tolist()}")
    return vec / norm


def inertia_matrix(scene: str, inertia: Any) -> np.ndarray:
    """A 3-vector of principal moments or a 3×3 tensor, as a 3×3 array (checked by the front end)."""
    arr = array(scene, "inertia", inertia)
    if arr.shape == (3,):
        return np.diag(arr)
    if arr.shape != (3, 3):
        raise ShapeError(f"{scene}: inertia must be 3 principal moments or a 3×3 tensor, got shape {arr.shape}")
    return arr


def on_plane(scene: str, omega0: Any, l: np.ndarray) -> np.ndarray:
    """``omega0`` projected onto the plane ``(ω, l) = 0`` (``l`` a unit vector)."""
    w0 = array(scene, "omega0", omega0).ravel()
    if w0.shape != (3,):
        raise ShapeError(f"{scene}: omega0 must have 3 components, got {w0.size}")
    return w0 - np.dot(w0, l) * l
