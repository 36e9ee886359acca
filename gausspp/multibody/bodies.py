"""Rigid bodies in maximal coordinates: what each one adds to the state, and where its points are.

A **planar body** moves in the ``x``–``y`` plane: coordinates ``(x, y, θ)`` (its centre of mass and its angle),
velocities their rates, kinetic energy ``½ m (ẋ² + ẏ²) + ½ I θ̇²``.

A **spatial body** has its centre of mass ``r`` and a unit quaternion ``p = (w, x, y, z)`` (body → space) as its
seven coordinates, and six velocities: the centre's velocity ``ṙ`` in space and the angular velocity ``ω`` in
body axes — as :class:`gausspp.RigidBody` has for one body. Kinetic energy ``½ m |ṙ|² + ½ ωᵀ J ω``; kinematics
``q̇ = (ṙ, ½ p ⊗ (0, ω))``, which keeps ``|p| = 1`` by itself (no constraint row for the norm, and ``A`` stays
constant and positive definite: ``diag(m, m, m, J)``).

A point fixed in a body at ``s`` (body axes, from the centre of mass) is at ``r + R s`` in space.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError, ShapeError
from ..model.mechanism import quaternion_to_matrix
from ..validation import array, number


@dataclass(frozen=True)
class Body:
    """One rigid body: its name, inertia, place in the state and initial guess (see the module docstring)."""

    name: str
    mass: float
    #: ``(1, 1)`` about the centre of mass (planar) or ``(3, 3)`` in body axes (spatial)
    inertia: np.ndarray
    planar: bool
    #: initial guess of the coordinates: ``(x, y, θ)`` or ``(x, y, z, w, qx, qy, qz)``
    guess: np.ndarray
    #: applied force and torque (space force on the centre, torque about it: a planar scalar or body axes)
    load: Any = None
    #: first coordinate and first velocity of the body in the mechanism's state
    q_start: int = 0
    v_start: int = 0
    #: points of the body drawn by :meth:`gausspp.Multibody.drawing` (its joints' points)
    points: list[np.ndarray] = field(default_factory=list)

    @property
    def nq(self) -> int:
        return 3 if self.planar else 7

    @property
    def nv(self) -> int:
        return 3 if self.planar else 6

    def coordinate_names(self) -> list[str]:
        axes = ["x", "y", "θ"] if self.planar else ["x", "y", "z", "qw", "qx", "qy", "qz"]
        return [f"{self.name}.{a}" for a in axes]

    def velocity_names(self) -> list[str]:
        axes = ["ẋ", "ẏ", "θ̇"] if self.planar else ["ẋ", "ẏ", "ż", "ωx", "ωy", "ωz"]
        return [f"{self.name}.{a}" for a in axes]

    def parts(self, q: Any) -> tuple[Any, Any]:
        """``(r, R)``: the centre of mass and the rotation (body → space) in the coordinates ``q`` of the whole state
        (casadi symbols or numbers). Planar: ``r`` 2-vector, ``R`` 2×2."""
        c = q[self.q_start : self.q_start + self.nq]
        if self.planar:
            th = c[2]
            return c[0:2], ca.vertcat(ca.horzcat(ca.cos(th), -ca.sin(th)), ca.horzcat(ca.sin(th), ca.cos(th)))
        p = c[3:7]
        return c[0:3], quaternion_to_matrix(p / ca.norm_2(p))  # the rotation of p's direction: a joint's rows then
        # read the rotation alone, also where an integrator's stage leaves |p| ≠ 1 (its norm is no joint's business)

    def point(self, q: Any, local: Any) -> Any:
        """The point fixed in the body at ``local`` (from the centre of mass, body axes), in space."""
        r, R = self.parts(q)
        return r + R @ ca.DM(np.asarray(local, float))


def planar_body(name: str, mass: float, inertia: float, at: Any, angle: float, load: Any) -> Body:
    m, I = _positive(name, "mass", mass), _positive(name, "inertia", inertia)
    r = vector(f"body {name!r}", "at", at, 2)
    th = float(number(f"body {name!r}: angle must be one finite number (rad), got {angle!r}", angle))
    return Body(name, m, np.array([[I]]), True, np.array([r[0], r[1], th]), load)


def spatial_body(name: str, mass: float, inertia: Any, at: Any, orientation: Any, load: Any) -> Body:
    m = _positive(name, "mass", mass)
    J = np.asarray(inertia, float)
    J = np.diag(J) if J.shape == (3,) else J
    if J.shape != (3, 3) or not np.all(np.isfinite(J)):
        raise InputError(f"body {name!r}: inertia must be 3 principal moments or a 3×3 matrix, got {inertia!r}")
    if not np.allclose(J, J.T, rtol=1e-12, atol=0.0) or np.linalg.eigvalsh(J).min() <= 0:
        raise InputError(f"body {name!r}: inertia must be symmetric positive definite, got {J.tolist()}")
    moments = np.linalg.eigvalsh(J)
    if moments[2] > (moments[0] + moments[1]) * (1 + 1e-9):
        raise InputError(
            f"body {name!r}: principal moments {moments.tolist()} violate the triangle inequality (the largest "
            "exceeds the sum of the others): no body has them"
        )
    r = vector(f"body {name!r}", "at", at, 3)
    p = vector(f"body {name!r}", "orientation", orientation, 4)
    if not np.linalg.norm(p) > 0:
        raise InputError(f"body {name!r}: orientation must be a nonzero quaternion (w, x, y, z), got {p.tolist()}")
    return Body(name, m, J, False, np.concatenate([r, p / np.linalg.norm(p)]), load)


def _positive(name: str, what: str, value: Any) -> float:
    x = float(number(f"body {name!r}: {what} must be one finite number > 0, got {value!r}", value))
    if not x > 0:
        raise InputError(f"body {name!r}: {what} must be > 0, got {value!r}")
    return x


def vector(owner: str, name: str, value: Any, n: int) -> np.ndarray:
    """A finite ``n``-vector argument, or an error naming ``owner`` and the argument."""
    arr = array(owner, name, value)
    if arr.shape != (n,):
        raise ShapeError(f"{owner}: {name} must be a vector of {n} numbers, got shape {arr.shape}")
    return arr
