"""One servo-constraint, two actuators: Gauss's principle allocates the force (over-actuation).

A planar rigid body (a two-rotor drone seen from the side) with centre of mass ``(x, y)``, tilt
``θ``, mass ``m`` and moment of inertia ``I`` about the centre of mass, under gravity ``g``:
``q = (x, y, θ)``, ``T = ½ m (ẋ² + ẏ²) + ½ I θ̇²``, ``V = m g y``. Two rotors at arms ``d1``
(left) and ``d2`` (right) of the centre of mass push along the body's up axis
``(−sin θ, cos θ)`` with thrusts ``f1, f2``: the actuator rows

    M = [[−sin θ, cos θ, −d1],
         [−sin θ, cos θ, +d2]]      (force and torque of each rotor; reaction ``R = Mᵀ (f1, f2)``)

keep one servo-constraint, the altitude ``y − h(t) = 0`` with a smooth rest-to-rest climb
``h(t) = climb · σ(t/duration)`` (:func:`gausspp.scenes.crane.rest_to_rest`, zero velocity,
acceleration and jerk at both ends). One constraint row, two actuators (``m = 2 > k = 1``):
infinitely many thrust pairs keep it. Gauss's principle picks the one of least compulsion

    Z = uᵀ(M A⁻¹ Mᵀ)u = (f1 + f2)²/m + (d2 f2 − d1 f1)²/I      subject to (f1 + f2) cos θ = m (ḧ + g)

— zero torque, the lever rule ``f1 d1 = f2 d2``:
``f1 = T d2/(d1 + d2)``, ``f2 = T d1/(d1 + d2)`` with ``T = m (ḧ + g)/cos θ`` (the closed form
``u = H⁻¹Sᵀ(SH⁻¹Sᵀ)⁻¹(φ − J a₀)``, ``H = M A⁻¹ Mᵀ``, ``S = J A⁻¹ Mᵀ``, for this system). So the
body keeps its tilt ``θ ≡ θ0`` and drifts sideways: the exact motion (``θ̇0 = 0``, from rest) is

    y = h(t),   θ = θ0,   x = −tan θ0 · (h(t) + ½ g t²).

**Bounds.** ``f_max`` (a number or a pair, one per rotor) bounds the thrusts to ``0 ≤ fᵢ ≤ f_maxᵢ``
(rotors push only; :class:`~gausspp.Force` with ``bounds``). When the lever rule asks a rotor for
more than it has, the QP *reallocates*: that rotor runs at its bound and the other supplies the rest,
so the altitude is still kept exactly (``tracking_error = 0``) — at the price of a torque that turns
the body. Only when the two together cannot supply the thrust does the servo saturate and track.
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
from .crane import rest_to_rest
from .scene import Scene


def altitude(climb: float, duration: float) -> Callable[[Any], Any]:
    """``h(t) = climb · σ(t / duration)`` (``σ`` clamped to 0 and 1 outside), for casadi symbols or numbers."""

    def h(t: Any) -> Any:
        tau: Any
        if isinstance(t, (ca.SX, ca.MX, ca.DM)):
            tau = ca.fmin(ca.fmax(t / duration, 0), 1)
        else:
            tau = np.clip(np.asarray(t, float) / duration, 0.0, 1.0)
        return climb * rest_to_rest(tau)

    return h


def altitude_derivatives(t: float, climb: float, duration: float) -> tuple[float, float, float]:
    """``(h, ḣ, ḧ)`` at ``t`` (numbers)."""
    tau = float(np.clip(t / duration, 0.0, 1.0))
    inside = 0.0 < t / duration < 1.0
    h = climb * tau**4 * (35 - 84 * tau + 70 * tau**2 - 20 * tau**3)
    dh = climb * 140 * tau**3 * (1 - tau) ** 3 / duration if inside else 0.0
    ddh = climb * 420 * tau**2 * (1 - tau) ** 2 * (1 - 2 * tau) / duration**2 if inside else 0.0
    return h, dh, ddh


def lever_rule(T: float, d1: float, d2: float) -> np.ndarray:
    """The torque-free split of a total thrust ``T`` between rotors at arms ``d1``, ``d2``."""
    return np.array([T * d2 / (d1 + d2), T * d1 / (d1 + d2)])


def _positive(name: str, value: Any) -> float:
    if not (isinstance(value, (int, float, np.floating, np.integer)) and np.isfinite(value) and value > 0):
        raise InputError(f"two-actuator-servo: {name} must be positive and finite, got {value!r}")
    return float(value)


def build(
    m: float = 1.0,
    I: float = 0.05,
    d1: float = 0.2,
    d2: float = 0.3,
    g: float = 9.81,
    theta0: float = 0.1,
    climb: float = 1.0,
    duration: float = 2.0,
    f_max: float | tuple[float, float] | None = None,
    t_end: float = 2.0,
) -> Scene:
    """Two rotors keep one altitude constraint: the least-compulsion split is the torque-free lever rule.

    A rotor at its bound ``f_max`` hands the rest to the other (reallocation): the altitude is kept while the
    pair can supply the thrust.

    Parameters
    ----------
    m : float
        Mass of the body (kg). Allowed: > 0.
    I : float
        Moment of inertia of the body about its centre of mass (kg·m²). Allowed: > 0.
    d1 : float
        Arm of the left rotor from the centre of mass (m). Allowed: > 0.
    d2 : float
        Arm of the right rotor from the centre of mass (m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−y`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    theta0 : float
        Initial tilt of the body, which the torque-free thrust split keeps while no rotor is at its bound; the
        body starts at rest at the origin (rad).
        Allowed: |theta0| < π/2 (the rotors push upwards).
    climb : float
        Altitude gained by the smooth rest-to-rest climb ``h(t)`` (m). Allowed: any finite number.
    duration : float
        Duration of the climb (s). Allowed: > 0.
    f_max : float, pair or None
        Bound on the thrusts, ``0 ≤ fᵢ ≤ f_max``: one number for both rotors or one per rotor; None: unbounded
        (N). Allowed: > 0 each (inf allowed), or None.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    m, I, d1, d2, duration, t_end = (
        _positive(n, x)
        for n, x in (("m", m), ("I", I), ("d1", d1), ("d2", d2), ("duration", duration), ("t_end", t_end))
    )
    _check_numbers(g, theta0, climb)
    bounds = _thrust_bounds(f_max)
    theta0, g, climb = float(theta0), float(g), float(climb)
    model = _model(m, I, d1, d2, g, altitude(climb, duration), bounds)
    q0, v0 = np.array([0.0, 0.0, theta0]), np.zeros(3)
    exact = _exact(theta0, g, climb, duration) if f_max is None else None
    return Scene(
        name="two-actuator-servo",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=("x (m)", "y (m)", "θ (rad)"),
        lam0=None,
        t_end=t_end,
        exact=exact,
        description=(
            "two rotors keep one altitude constraint: the least-compulsion allocation is the torque-free lever "
            "rule; bounded rotors reallocate"
        ),
        params=dict(
            m=m, I=I, d1=d1, d2=d2, g=g, theta0=theta0, climb=climb, duration=duration, f_max=f_max, t_end=t_end
        ),
    )


def _check_numbers(g: Any, theta0: Any, climb: Any) -> None:
    """``g``, ``theta0``, ``climb`` finite numbers; the rotors push upwards (``|theta0| < π/2``)."""
    for name, value in (("g", g), ("theta0", theta0), ("climb", climb)):
        if not (isinstance(value, (int, float, np.floating, np.integer)) and np.isfinite(value)):
            raise InputError(f"two-actuator-servo: {name} must be a finite number, got {value!r}")
    if not abs(theta0) < np.pi / 2:
        raise InputError(f"two-actuator-servo: |theta0| must be below π/2 (the rotors must push upwards), got {theta0}")


def _thrust_bounds(f_max: Any) -> tuple[float, np.ndarray] | None:
    """The thrusts' bounds ``[0, f_max]`` (one per rotor), or ``None`` for unbounded rotors."""
    if f_max is None:
        return None
    caps = np.broadcast_to(np.asarray(f_max, dtype=float), (2,)) if np.size(f_max) in (1, 2) else None
    if caps is None or not np.all(caps > 0):  # NaN fails too
        raise InputError(
            f"two-actuator-servo: f_max must be a positive number or a pair of them (inf allowed), got {f_max!r}"
        )
    return (0.0, caps.copy())


def _model(
    m: float, I: float, d1: float, d2: float, g: float, h: Callable[[Any], Any], bounds: tuple[float, np.ndarray] | None
) -> Model:
    """The planar body ``q = (x, y, θ)`` under gravity, its altitude ``y = h(t)`` kept by the two rotors."""
    body = Lagrangian(
        n=3,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * I * v[2] ** 2,
        V=lambda q, t: m * g * q[1],
    )

    def rotors(q: Any, v: Any, t: Any) -> Any:
        s, c = ca.sin(q[2]), ca.cos(q[2])
        return ca.vertcat(ca.horzcat(-s, c, -d1), ca.horzcat(-s, c, d2))

    servo = Holonomic(
        lambda q, t: q[1] - h(t), name="altitude follows h(t)", realization=Force(M=rotors, bounds=bounds)
    )
    return Model(body, [servo])


def _exact(theta0: float, g: float, climb: float, duration: float) -> Callable[[float], tuple[np.ndarray, np.ndarray]]:
    """The unbounded motion: ``y = h(t)``, ``θ = θ0``, ``x = −tan θ0 (h + g t²/2)`` (thrust along the body's axis)."""

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        y, dy, _ = altitude_derivatives(t, climb, duration)
        tan = np.tan(theta0)
        return np.array([-tan * (y + 0.5 * g * t * t), y, theta0]), np.array([-tan * (dy + g * t), dy, 0.0])

    return exact
