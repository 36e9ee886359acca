"""The gyrostat with its rotor angle as a coordinate and a motor torque as Béghin servo (docs/theory.md §6.3).

The same body as the scene ``"gyrostat"``, modelled without the flywheel realization: the
rotor's angle ``θ`` relative to the carrier is an extra coordinate, and the motor torque ``τ``
between carrier and rotor is a controlled force on ``θ`` (Béghin, ``M = (0, 0, 0, 1)``) that
keeps ``(ω, l) = 0``. Velocities ``v = (ω₁, ω₂, ω₃, θ̇)``, configuration
``q = (w, x, y, z, θ)`` (unit quaternion body → space, rotor angle), kinematics
``q̇ = (½ q ⊗ (0, ω), θ̇)``. Kinetic energy

    T = ½ ωᵀI′ω + ½ J_r (n·ω + θ̇)²,

``I′`` the carrier's inertia with the rotor's transverse inertia, ``J_r`` the rotor's axial
inertia. ``θ`` is cyclic, and the Euler–Poincaré equations are

    d/dt (I′ω + λn) + ω × (I′ω + λn) = 0,     d/dt λ = τ,      λ = J_r (n·ω + θ̇),

so ``A = [[I′ + J_r nnᵀ, J_r n], [J_r nᵀ, J_r]]`` and ``f = (−ω × (I′ω + λn), 0)``. These are the
gyrostat's equations with ``I = I′``: the two models give the same ``ω(t)`` and ``λ(t)``, and the
motor torque ``τ`` here is ``λ̇`` there. Realizable iff ``(I′⁻¹n, l) ≠ 0``, as for the gyrostat.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.constraints import Constraint
from ..model.mechanism import MassMatrix
from ..model.model import Model
from ..model.realizations import Force
from .rigid import OMEGA, QUATERNION, body_axes_drawing, inertia_matrix, on_plane, unit_vector
from .scene import Scene


def rotor_momentum(v: Any, n: Any, rotor_inertia: float) -> np.ndarray:
    """The rotor's axial angular momentum ``λ = J_r (n·ω + θ̇)`` for velocities ``v = (ω, θ̇)`` (rows)."""
    v = np.atleast_2d(np.asarray(v, dtype=float))
    return rotor_inertia * (v[:, :3] @ np.asarray(n, dtype=float) + v[:, 3])


def build(
    inertia: Any = (1.0, 2.0, 3.0),
    rotor_inertia: float = 0.1,
    n: Any = (0.0, 0.0, 1.0),
    l: Any = (1.0, 1.0, 1.0),
    omega0: Any = (1.0, -0.5, 0.2),
    lam0: float = 0.5,
    theta0: float = 0.0,
    t_end: float = 10.0,
) -> Scene:
    """Gyrostat with the rotor angle as a coordinate, ``(ω, l) = 0`` kept by the motor torque (Béghin servo).

    Parameters
    ----------
    inertia : (3,) or (3, 3) array_like
        ``I′``: inertia of the carrier with the rotor's transverse inertia, body axes: the principal moments or
        the tensor (kg·m²). Allowed: symmetric positive definite (not checked).
    rotor_inertia : float
        ``J_r``: the rotor's axial moment of inertia (kg·m²). Allowed: > 0.
    n : (3,) array_like or None
        Body axis of the rotor, normalized here; None: ``n = l`` (-). Allowed: a finite nonzero 3-vector, or
        None; realizable only if ``(I′⁻¹n, l) ≠ 0`` (not checked here: the step raises a RealizabilityError).
    l : (3,) array_like
        Body axis of the constraint ``(ω, l) = 0``, normalized here (-). Allowed: a finite nonzero 3-vector.
    omega0 : (3,) array_like
        Initial angular velocity of the carrier in body axes, projected onto ``(ω, l) = 0`` (rad/s).
        Allowed: a finite 3-vector.
    lam0 : float
        The rotor's initial axial angular momentum ``λ = J_r (n·ω₀ + θ̇₀)``, as in the scene ``"gyrostat"``: it
        sets the rotor's initial rate ``θ̇₀ = lam0/J_r − n·ω₀`` (kg·m²/s). Allowed: any finite number.
    theta0 : float
        Initial angle ``θ`` of the rotor relative to the carrier (rad). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    I = inertia_matrix("gyrostat-extended", inertia)
    Jr = float(rotor_inertia)
    if not (np.isfinite(Jr) and Jr > 0):
        raise InputError(f"gyrostat-extended: rotor_inertia must be positive, got {rotor_inertia!r}")
    l_ = unit_vector("gyrostat-extended", "l", l)
    n_ = l_ if n is None else unit_vector("gyrostat-extended", "n", n)
    body = _body(I, Jr, n_)
    motor = Force(M=lambda q, v, t: [0, 0, 0, 1])
    model = Model(body, [Constraint(lambda q, v, t: ca.dot(v[:3], ca.DM(l_)), name="(ω, l) = 0", realization=motor)])
    w0 = on_plane("gyrostat-extended", omega0, l_)
    theta_dot0 = float(lam0) / Jr - float(w0 @ n_)
    return Scene(
        name="gyrostat-extended",
        model=model,
        q0=np.array([1.0, 0.0, 0.0, 0.0, float(theta0)]),
        v0=np.append(w0, theta_dot0),
        coordinates=(*QUATERNION, "θ (rad)"),
        velocities=(*OMEGA, "θ̇ (rad/s)"),
        lam0=None,
        t_end=t_end,
        exact=None,
        drawing=body_axes_drawing,
        description="gyrostat with the rotor angle as a coordinate, motor torque as Béghin servo keeping (ω, l) = 0",
        params=dict(
            inertia=I.tolist(),
            rotor_inertia=Jr,
            n=n_.tolist(),
            l=l_.tolist(),
            lam0=float(lam0),
            theta0=float(theta0),
            t_end=t_end,
        ),
    )


def _body(I: np.ndarray, Jr: float, n_: np.ndarray) -> MassMatrix:
    """Carrier and rotor: ``v = (ω, θ̇)``, the rotor's momentum ``λ = J_r (n·ω + θ̇)`` along ``n``, Euler's equations."""
    Id, nd = ca.DM(I), ca.DM(n_)

    def mass_matrix(q: ca.SX, t: ca.SX) -> ca.SX:
        return ca.SX(
            ca.vertcat(
                ca.horzcat(Id + Jr * (nd @ nd.T), Jr * nd),
                ca.horzcat(Jr * nd.T, Jr),
            )
        )

    def momentum(v: ca.SX) -> tuple[ca.SX, ca.SX]:
        w = v[:3]
        lam = Jr * (ca.dot(nd, w) + v[3])
        return w, Id @ w + lam * nd

    def forces(q: ca.SX, v: ca.SX, t: ca.SX) -> ca.SX:
        w, K = momentum(v)
        return ca.vertcat(-ca.cross(w, K), 0)

    def energy(q: ca.SX, v: ca.SX, t: ca.SX) -> ca.SX:
        w = v[:3]
        return 0.5 * ca.dot(w, Id @ w) + 0.5 * Jr * (ca.dot(nd, w) + v[3]) ** 2

    return MassMatrix(n=4, A=mass_matrix, f=forces, energy=energy, kinematics=_kinematics, nq=5)


def _kinematics(q: ca.SX, v: ca.SX, t: ca.SX) -> ca.SX:
    """``q̇``: the quaternion's rate ``½ q ⊗ (0, ω)`` and the rotor angle's ``θ̇``."""
    pw, px, py, pz = q[0], q[1], q[2], q[3]
    w = v[:3]
    return ca.vertcat(  # ½ q ⊗ (0, ω), then θ̇
        0.5 * (-px * w[0] - py * w[1] - pz * w[2]),
        0.5 * (pw * w[0] + py * w[2] - pz * w[1]),
        0.5 * (pw * w[1] + pz * w[0] - px * w[2]),
        0.5 * (pw * w[2] + px * w[1] - py * w[0]),
        v[3],
    )
