"""The crane with a saturating trolley motor: a bounded servo that can only *track* its constraint.

The mechanism, the prescribed payload motion ``s(t)`` and the servo-constraint are those of the
``crane`` scene (:mod:`gausspp.scenes.crane`): a trolley ``x`` with a pendulum load at rope angle
``θ``, the payload's horizontal position ``x + L sin θ − s(t) = 0`` kept by a horizontal force
``λ`` on the trolley (Béghin, ``M = (1, 0)``). Here the motor is limited, ``|λ| ≤ F_max``
(:class:`~gausspp.Force` with ``bounds=(−F_max, F_max)``).

While the force the servo needs stays within the bound, the motion is the crane's. When it does
not, the motor saturates: the step pushes at the bound in the direction that keeps the constraint
best and reports the shortfall as ``tracking_error`` (:mod:`gausspp.step.general`, stage *track*);
the payload leaves its path. Baumgarte feedback ``J q̈ = φ − αΦ − βg`` (critically damped with
time constant ``tau``: ``α = 2/τ``, ``β = 1/τ²``) brings it back once the motor has room again.
The scene's feedback is in ``params["stabilize"]``; simulate with
``gp.simulate(..., stabilize=scene.params["stabilize"])``. On the path the feedback terms vanish,
so with a loose bound the motion is exactly the unbounded crane's.

With the defaults (the crane's defaults and ``F_max = 12``) the unbounded servo needs up to
16.65 N at ``t ≈ 1.45`` (the end of the rest-to-rest move), so the motor saturates once, for
about 0.1 s, and the payload falls behind its path by about 1 mm before the feedback pulls it
back (``|g| < 1e-7`` at ``t = 3``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.constraints import Holonomic
from ..model.model import Model
from ..model.realizations import Force
from ..simulation.drift import Baumgarte
from . import crane
from .scene import Scene

#: Parameters that may be infinite (checked by gausspp.scenes.get): no bound on the motor.
INFINITE_OK = ("F_max",)


def build(
    F_max: float = 12.0,
    tau: float = 0.1,
    M0: float = 1.0,
    m: float = 0.5,
    L: float = 1.0,
    g: float = 9.81,
    theta0: float = -0.3,
    accel: float | None = None,
    distance: float = 0.5,
    duration: float = 2.0,
    t_end: float = 3.0,
) -> Scene:
    """Crane with a bounded trolley motor |λ| ≤ F_max: the servo saturates and only tracks the payload's path.

    The parameters after ``tau`` are the ``crane`` scene's.

    Parameters
    ----------
    F_max : float
        Bound of the trolley motor, ``|λ| ≤ F_max`` (N). Allowed: > 0; inf: it never saturates, but the step is
        still the general Gauss QP.
    tau : float
        Time constant of the critically damped Baumgarte feedback that brings the payload back to its path,
        ``params["stabilize"]`` (s). Allowed: > 0.
    M0 : float
        Mass of the trolley (kg). Allowed: > 0.
    m : float
        Mass of the payload (kg). Allowed: > 0.
    L : float
        Length of the rope (m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−y`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    theta0 : float
        Initial rope angle from the vertical; the payload starts at horizontal position 0, the trolley at rest
        relative to it (rad). Allowed: any finite number ≠ 0: at 0 the servo cannot act (not checked here: the
        step raises a RealizabilityError).
    accel : float or None
        Base acceleration of the payload's prescribed horizontal motion ``s(t)``; None: ``−g tan theta0``, which
        holds the rope at ``theta0`` (m/s²). Allowed: any finite number, or None.
    distance : float
        Length of the extra smooth rest-to-rest move of the payload; 0: none (m). Allowed: any finite number.
    duration : float
        Duration of that move (s). Allowed: > 0.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    if not (isinstance(F_max, (int, float, np.floating, np.integer)) and F_max > 0):
        raise InputError(f"saturated-crane: F_max must be a positive number (the motor's bound), got {F_max!r}")
    if not (isinstance(tau, (int, float, np.floating, np.integer)) and np.isfinite(tau) and tau > 0):
        raise InputError(
            f"saturated-crane: tau must be positive and finite (the feedback's time constant), got {tau!r}"
        )
    base = crane.build(
        M0=M0, m=m, L=L, g=g, theta0=theta0, accel=accel, distance=distance, duration=duration, t_end=t_end
    )
    p = base.params
    s = crane.motion(float(p["accel"]), float(distance), float(duration))
    servo = Holonomic(
        lambda q, t: q[0] + L * ca.sin(q[1]) - s(t),
        name="payload follows s(t)",
        realization=Force(M=lambda q, v, t: [1, 0], bounds=(-float(F_max), float(F_max))),
    )
    model = Model(base.model.mechanism, [servo])
    return Scene(
        name="saturated-crane",
        model=model,
        q0=base.q0,
        v0=base.v0,
        coordinates=base.coordinates,
        lam0=None,
        t_end=float(t_end),
        exact=None,
        description=(
            "crane with a bounded trolley motor |λ| ≤ F_max: the servo saturates, tracks its constraint "
            "(tracking_error) and returns to it by Baumgarte feedback"
        ),
        params=dict(p, F_max=float(F_max), tau=float(tau), stabilize=Baumgarte.critical(float(tau))),
    )
