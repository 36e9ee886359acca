"""A rigid body about a fixed point kept by a servo torque (paper §2, docs/theory.md §6.2).

Constraint ``(ω, l) = 0`` (body axes), kept by a torque ``λ n`` along the body axis ``n``
(Béghin realization, ``M = nᵀ``). Realizable iff ``(I⁻¹ n, l) ≠ 0`` — this is ``n ⟂̸ l`` only
when ``l`` is a principal axis; the paper's "orthogonal" is that special case.
``n = l`` is Suslov's nonholonomic problem (the ideal realization).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..model.constraints import Constraint
from ..model.mechanism import RigidBody
from ..model.model import Model
from ..model.realizations import Force
from .rigid import OMEGA, QUATERNION, body_axes_drawing, inertia_matrix, on_plane, unit_vector
from .scene import Scene


def build(
    inertia: Any = (1.0, 2.0, 3.0),
    l: Any = (1.0, 1.0, 1.0),
    n: Any = None,
    omega0: Any = (1.0, -0.5, 0.2),
    t_end: float = 10.0,
) -> Scene:
    """Rigid body with a servo torque along ``n`` keeping ``(ω, l) = 0``; ``n=None`` means ``n = l`` (Suslov).

    Parameters
    ----------
    inertia : (3,) or (3, 3) array_like
        Inertia about the fixed point in body axes: the principal moments or the tensor (kg·m²).
        Allowed: symmetric positive definite, its largest principal moment at most the sum of the other two.
    l : (3,) array_like
        Body axis of the constraint ``(ω, l) = 0``, normalized here (-). Allowed: a finite nonzero 3-vector.
    n : (3,) array_like or None
        Body axis of the servo torque ``λ n``, normalized here; None: ``n = l``, Suslov's problem (-).
        Allowed: a finite nonzero 3-vector, or None; realizable only if ``(I⁻¹n, l) ≠ 0`` (not checked here: the
        step raises a RealizabilityError).
    omega0 : (3,) array_like
        Initial angular velocity in body axes, projected onto the plane ``(ω, l) = 0`` so that the initial data
        lie on the constraint (rad/s). Allowed: a finite 3-vector.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    I = inertia_matrix("rigid-body-servo", inertia)
    l_ = unit_vector("rigid-body-servo", "l", l)
    n_ = l_ if n is None else unit_vector("rigid-body-servo", "n", n)
    body = RigidBody(inertia=I)
    servo = Force(M=lambda q, w, t: ca.DM(n_).T)
    model = Model(body, [Constraint(lambda q, w, t: ca.dot(w, ca.DM(l_)), name="(ω, l) = 0", realization=servo)])
    w0 = on_plane("rigid-body-servo", omega0, l_)
    suslov = n is None or np.allclose(n_, l_)
    return Scene(
        name="rigid-body-servo",
        model=model,
        q0=np.array([1.0, 0.0, 0.0, 0.0]),
        v0=w0,
        coordinates=QUATERNION,
        velocities=OMEGA,
        lam0=None,
        t_end=t_end,
        exact=None,
        drawing=body_axes_drawing,
        description="rigid body, servo torque along n keeping (ω, l) = 0; n = l is Suslov's problem; paper §2",
        params=dict(inertia=I.tolist(), l=l_.tolist(), n=n_.tolist(), suslov=suslov, t_end=t_end),
    )
