"""A crane whose trolley force makes the payload follow a prescribed horizontal motion (docs/theory.md §6.5).

A trolley of mass ``M0`` at horizontal position ``x`` carries a payload ``m`` on a rope of length
``L`` at angle ``θ`` from the vertical: the payload is at ``(x + L sin θ, −L cos θ)``. Gravity
``g``; ``q = (x, θ)``,

    T = ½ (M0 + m) ẋ² + m L cos θ ẋ θ̇ + ½ m L² θ̇²,      V = −m g L cos θ.

Servo-constraint: the payload's horizontal position follows ``s(t)``,
``x + L sin θ − s(t) = 0``, realized by a horizontal force on the trolley (Béghin, ``M = (1, 0)``).
The trolley moves the payload only through the rope, so the realizability margin (the cosine
of the ``A⁻¹``-angle between ``J = (1, L cos θ)`` and ``D = (1, 0)``) is

    margin(θ) = sin²θ · sqrt(m / (m sin²θ + M0 cos²θ))          (:func:`margin_closed_form`)

and vanishes with the rope vertical: condition (12) fails there.

The payload's vertical motion is not prescribed: the rope tension is ``−m s̈ / sin θ`` and the
rope angle obeys ``L (sin θ θ̈ + cos θ θ̇²) = −s̈ cot θ − g``. Wherever ``s̈ = 0`` the payload
falls freely and the rope reaches the vertical in finite time (a rest-to-rest move of a
hanging payload must end at the singularity). The default motion therefore carries the payload
with the steady acceleration ``accel = −g tan θ0`` that holds the rope at ``θ0``, plus a smooth
rest-to-rest move of ``distance`` over ``duration``:

    s(t) = ½ accel t² + distance · σ(t / duration),   σ(τ) = 35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷ on [0, 1]

(``σ`` clamped to 0 and 1 outside; ``s`` is C³). With ``distance = 0`` the motion is exact:
``θ ≡ θ0``, ``x = s(t) − L sin θ0`` (:attr:`Scene.exact`). ``accel=0`` gives a pure
rest-to-rest move, which drives the rope to the vertical (a :class:`RealizabilityError`);
with ``accel=0, distance=0`` the payload falls freely and the exact motion is
:func:`free_fall`, reaching the vertical rope at ``t* = sqrt(2 L (1 − cos θ0) / g)``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.constraints import Holonomic
from ..model.mechanism import Lagrangian
from ..model.model import Model
from ..model.realizations import Force
from .scene import Scene


def margin_closed_form(theta: Any, M0: float, m: float) -> Any:
    """Realizability margin of the crane's servo-constraint at rope angle ``theta``.

    ``|J A⁻¹ D| / sqrt((J A⁻¹ Jᵀ)(Dᵀ A⁻¹ D))`` with ``J = (1, L cos θ)``, ``D = (1, 0)ᵀ`` and
    ``A = [[M0 + m, m L cos θ], [m L cos θ, m L²]]``: ``det A = m L² (M0 + m sin²θ)`` and

    * ``J A⁻¹ D = sin²θ / (M0 + m sin²θ)``,
    * ``Dᵀ A⁻¹ D = 1 / (M0 + m sin²θ)``,
    * ``J A⁻¹ Jᵀ = (m sin²θ + M0 cos²θ) / (m (M0 + m sin²θ))``,

    so the margin is ``sin²θ · sqrt(m / (m sin²θ + M0 cos²θ))``, independent of ``L``.
    """
    s2 = np.sin(theta) ** 2
    return s2 * np.sqrt(m / (m * s2 + M0 * np.cos(theta) ** 2))


def free_fall(t: float, L: float, g: float, theta0: float) -> tuple[np.ndarray, np.ndarray]:
    """The crane's motion for ``s ≡ 0`` from rest at ``theta0``: the payload falls freely.

    With ``s̈ = 0`` the rope carries no tension, so the payload drops vertically from rest,
    ``L cos θ(t) = L cos θ0 + ½ g t²``, and the trolley keeps it at horizontal position 0:
    ``x = −L sin θ``. The rope is vertical at ``t* = sqrt(2 L (1 − cos θ0) / g)``, where ``θ̇``
    blows up (``θ̇ = −g t / (L sin θ)``) and the constraint stops being realizable; for
    ``t ≥ t*`` there is no motion and NaNs are returned.
    """
    c = np.cos(theta0) + 0.5 * g * t * t / L
    if not c < 1.0:
        return np.full(2, np.nan), np.full(2, np.nan)
    th = np.copysign(np.arccos(c), theta0)
    thdot = -g * t / (L * np.sin(th))
    return np.array([-L * np.sin(th), th]), np.array([-L * np.cos(th) * thdot, thdot])


def rest_to_rest(tau: Any) -> Any:
    """Septic rest-to-rest profile from 0 to 1 on ``[0, 1]`` (zero velocity, acceleration and jerk at both ends)."""
    return tau**4 * (35 - 84 * tau + 70 * tau**2 - 20 * tau**3)


def motion(accel: float, distance: float, duration: float) -> Callable[[Any], Any]:
    """``s(t) = ½ accel t² + distance σ(t/duration)``, for casadi symbols or numbers."""

    def s(t: Any) -> Any:
        tau: Any
        if isinstance(t, (ca.SX, ca.MX, ca.DM)):
            tau = ca.fmin(ca.fmax(t / duration, 0), 1)
        else:
            tau = np.clip(np.asarray(t, float) / duration, 0.0, 1.0)
        return 0.5 * accel * t**2 + distance * rest_to_rest(tau)

    return s


def build(
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
    """Crane: a trolley force makes the payload's horizontal position follow s(t); margin ∝ sin²θ.

    The payload starts at horizontal position 0 with the trolley at rest relative to it (``θ̇ = 0``,
    ``ẋ = ṡ(0) = 0``).

    Parameters
    ----------
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
    _check(M0, m, L, g, theta0, distance, duration, t_end)
    if accel is None:
        accel = -g * float(np.tan(theta0))
    model = _crane(M0, m, L, g, motion(float(accel), float(distance), float(duration)))
    q0 = np.array([-L * np.sin(theta0), float(theta0)])
    v0 = np.array([0.0, 0.0])  # ṡ(0) = 0 for every accel, distance
    exact = _exact(accel, distance, L, g, theta0)
    return Scene(
        name="crane",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=("x (m)", "θ (rad)"),
        lam0=None,
        t_end=float(t_end),
        exact=exact,
        description="crane: trolley force makes the payload follow s(t); margin ∝ sin²θ, zero with the rope vertical",
        params=dict(
            M0=M0, m=m, L=L, g=g, theta0=theta0, accel=accel, distance=distance, duration=duration, t_end=t_end
        ),
    )


def _check(
    M0: float, m: float, L: float, g: float, theta0: float, distance: float, duration: float, t_end: float
) -> None:
    """Positive finite masses, length and duration; finite ``g``, ``theta0``, ``distance``, ``t_end``."""
    for name, value in (("M0", M0), ("m", m), ("L", L), ("duration", duration)):
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"crane: {name} must be positive and finite, got {value}")
    for name, value in (("g", g), ("theta0", theta0), ("distance", distance), ("t_end", t_end)):
        if not np.isfinite(value):
            raise InputError(f"crane: {name} must be finite, got {value}")


def _crane(M0: float, m: float, L: float, g: float, s: Callable[[Any], Any]) -> Model:
    """Trolley ``x``, rope angle ``θ``; the trolley force makes the payload's position ``x + L sin θ`` follow ``s``."""
    body = Lagrangian(
        n=2,
        T=lambda q, v, t: 0.5 * (M0 + m) * v[0] ** 2 + m * L * ca.cos(q[1]) * v[0] * v[1] + 0.5 * m * L**2 * v[1] ** 2,
        V=lambda q, t: -m * g * L * ca.cos(q[1]),
    )
    servo = Holonomic(
        lambda q, t: q[0] + L * ca.sin(q[1]) - s(t),
        name="payload follows s(t)",
        realization=Force(M=lambda q, v, t: [1, 0]),
    )
    return Model(body, [servo])


def _exact(
    accel: float, distance: float, L: float, g: float, theta0: float
) -> Callable[[float], tuple[np.ndarray, np.ndarray]] | None:
    """The closed-form motion where there is one: steady at ``θ0``, or a free fall for ``s ≡ 0``; else ``None``."""
    exact: Callable[[float], tuple[np.ndarray, np.ndarray]] | None = None
    if distance == 0.0 and accel == -g * np.tan(theta0):  # steady: the rope stays at θ0

        def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
            return np.array([0.5 * accel * t**2 - L * np.sin(theta0), theta0]), np.array([accel * t, 0.0])

    elif distance == 0.0 and accel == 0.0:  # s ≡ 0: no tension, the payload falls freely

        def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
            return free_fall(t, L, g, theta0)

    return exact
