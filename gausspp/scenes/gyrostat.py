"""A rigid body kept on ``(ω, l) = 0`` by a flywheel: the gyrostat (paper §4, docs/theory.md §6.3).

A symmetric rotor spins about the body axis ``n``; its axial angular momentum ``λ`` is a state
(initial value required). The kinetic energy of the carrier is changed to
``T* = ½ ωᵀIω + λ (n, ω)`` (eq. (14) with ``N = (n, ω)``), and the reaction is
``R = −λ̇ N_v − λ [N] = −λ̇ n − λ ω × n`` (eq. (15)): Euler's equations of a gyrostat,

    d/dt (Iω + λn) + ω × (Iω + λn) = 0,

with ``λ̇`` chosen (by the motor) so that ``(ω, l) = 0`` holds. ``I`` is the inertia of the
carrier with the rotor's transverse inertia, without the rotor's axial inertia ``J_r``; then
``λ = J_r (n·ω + θ̇)`` with ``θ`` the rotor's angle (compare the scene
``"gyrostat-extended"``, which carries ``θ`` as a coordinate). Realizable iff
``(I⁻¹n, l) ≠ 0`` (condition (16)). With ``n = l`` the motion is vakonomic (eqs. (17)–(18)).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ShapeError
from ..model.constraints import Constraint
from ..model.mechanism import RigidBody
from ..model.model import Model
from ..model.realizations import Inertial
from .rigid import OMEGA, QUATERNION, body_axes_drawing, inertia_matrix, on_plane, unit_vector
from .scene import Scene


def build(
    inertia: Any = (1.0, 2.0, 3.0),
    n: Any = (0.0, 0.0, 1.0),
    l: Any = (1.0, 1.0, 1.0),
    omega0: Any = (1.0, -0.5, 0.2),
    lam0: float = 0.5,
    t_end: float = 10.0,
) -> Scene:
    """Gyrostat: a rotor on body axis ``n`` keeps ``(ω, l) = 0`` (flywheel realization); ``n=None`` means ``n = l``.

    Realizable iff ``(I⁻¹n, l) ≠ 0`` (16).

    Parameters
    ----------
    inertia : (3,) or (3, 3) array_like
        Inertia of the carrier with the rotor's transverse inertia but not its axial one, body axes: the principal
        moments or the tensor (kg·m²). Allowed: symmetric positive definite, its largest principal moment at most
        the sum of the other two.
    n : (3,) array_like or None
        Body axis of the rotor, normalized here; None: ``n = l``, the vakonomic motion (-). Allowed: a finite
        nonzero 3-vector, or None; realizable only if ``(I⁻¹n, l) ≠ 0`` (not checked here: the step raises a
        RealizabilityError).
    l : (3,) array_like
        Body axis of the constraint ``(ω, l) = 0``, normalized here (-). Allowed: a finite nonzero 3-vector.
    omega0 : (3,) array_like
        Initial angular velocity in body axes, projected onto the plane ``(ω, l) = 0`` (rad/s).
        Allowed: a finite 3-vector.
    lam0 : float
        Initial axial angular momentum ``λ`` of the rotor (kg·m²/s). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    I = inertia_matrix("gyrostat", inertia)
    l_ = unit_vector("gyrostat", "l", l)
    n_ = l_ if n is None else unit_vector("gyrostat", "n", n)
    lam = np.atleast_1d(np.asarray(lam0, dtype=float)).ravel()
    if lam.shape != (1,):
        raise ShapeError(f"gyrostat: lam0 is the rotor's angular momentum, one number; got {lam.size} entries")
    body = RigidBody(inertia=I)
    rotor = Inertial(N=lambda q, w, t: ca.dot(ca.DM(n_), w), lam0=lam)
    model = Model(body, [Constraint(lambda q, w, t: ca.dot(w, ca.DM(l_)), name="(ω, l) = 0", realization=rotor)])
    vakonomic = bool(np.allclose(n_, l_, rtol=0.0, atol=1e-15))
    return Scene(
        name="gyrostat",
        model=model,
        q0=np.array([1.0, 0.0, 0.0, 0.0]),
        v0=on_plane("gyrostat", omega0, l_),
        coordinates=QUATERNION,
        velocities=OMEGA,
        lam0=lam,
        t_end=t_end,
        exact=None,
        drawing=body_axes_drawing,
        description="gyrostat: a rotor on axis n keeps (ω, l) = 0 (flywheel realization); n = l is vakonomic; paper §4",
        params=dict(
            inertia=I.tolist(), n=n_.tolist(), l=l_.tolist(), lam0=float(lam[0]), vakonomic=vakonomic, t_end=t_end
        ),
    )
