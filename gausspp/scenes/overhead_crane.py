"""A planar overhead crane whose payload follows a prescribed path: a servo-constraint realized tangentially.

A trolley of mass ``m1`` at ``s`` on a horizontal rail carries, on a massless rope of length ``l`` at angle
``θ`` from the downward vertical, a payload of mass ``m2`` at

    X = s + l sin θ,   Y = −l cos θ   (y up);   q = (s, l, θ),
    T = ½ m1 ṡ² + ½ m2 (Ẋ² + Ẏ²),   V = m2 g Y.

Two actuators: a horizontal force ``F1`` on the trolley (generalized force on ``s``) and the winch's rope
tension ``F2`` (generalized force ``−F2`` on ``l``): ``gp.Force(M = [[1, 0, 0], [0, −1, 0]])``, ``λ = (F1, F2)``.
The servo-constraint ``(X − Xd(t), Y − Yd(t)) = 0`` prescribes the payload's path: a rest-to-rest transfer of
``D`` over ``T`` that lifts the load by ``h`` mid-way,

    Xd = D σ(t/T),   σ(τ) = 126τ⁵ − 420τ⁶ + 540τ⁷ − 315τ⁸ + 70τ⁹,
    Yd = −L0 + h β(t/T),   β(τ) = 2¹⁰ τ⁵ (1 − τ)⁵,

both with zero derivatives up to order 4 at the ends (:mod:`.smooth_paths`). ``F1`` reaches the payload only
through ``θ̈``, i.e. in the path's 4th derivative: the one-step matrix ``J A⁻¹ Mᵀ`` is singular at every state
(Blajer's tangential realization; the servo DAE has index 5).

**Exact solution (flatness).** The payload is a flat output. Newton for the payload, pulled towards the
trolley along ``(−sin θ, cos θ)`` by ``F2``: ``m2 Ẍ = −F2 sin θ``, ``m2 (Ÿ + g) = F2 cos θ``. With ``a = Ẍ``,
``b = Ÿ + g`` (``b > 0`` along this path):

    θ = atan2(−a, b),   F2 = m2 √(a² + b²),   s = X − Y a / b = N / b  with  N = X b − Y a,
    l = √P / b  with  P = Y² (a² + b²),   F1 = m1 s̈ + m2 Ẍ

(the trolley: ``m1 s̈ = F1 + F2 sin θ``). ``a``, ``b``, ``N``, ``P`` are polynomials in ``t`` (numpy); the
velocities and ``s̈`` come from the quotient rule on them with their polynomial derivatives,
``ṡ = (N′b − Nb′)/b²``, ``s̈ = (N″b − Nb″)/b² − 2b′ṡ/b``, ``θ̇ = (a b′ − b a′)/(a² + b²)``,
``l̇ = P′/(2√P b) − √P b′/b²`` (:func:`flat_motion`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from numpy.polynomial import Polynomial

from ..errors import InputError
from ..model.constraints import Holonomic
from ..model.mechanism import Lagrangian
from ..model.model import Model
from ..model.realizations import Force
from . import smooth_paths
from .scene import Scene

#: Order of the path's derivatives that vanish at both ends (the relative degree of the servo is 4).
SMOOTHNESS = 4


@dataclass(frozen=True)
class Path:
    """The prescribed payload path ``(Xd(t), Yd(t))`` as polynomials in ``t`` on ``[0, duration]``."""

    X: Polynomial
    Y: Polynomial
    duration: float

    @classmethod
    def transfer(cls, D: float, L0: float, h: float, duration: float) -> Path:
        """The rest-to-rest transfer of ``D`` over ``duration`` from depth ``L0``, lifted by ``h`` mid-way."""
        X = smooth_paths.rest_to_rest(SMOOTHNESS, duration, D)
        Y = smooth_paths.bump(SMOOTHNESS, duration, h) - L0
        return cls(X, Y, float(duration))

    def at(self, t: Any) -> tuple[Any, Any]:
        """``(Xd(t), Yd(t))`` for a number or a casadi symbol (clamped to the move: at rest outside)."""
        return smooth_paths.evaluate(self.X, t, self.duration), smooth_paths.evaluate(self.Y, t, self.duration)


def flat_motion(path: Path, m1: float, m2: float, g: float, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The exact motion and forces at ``t`` from the flat output (module docstring): ``(q, v, (F1, F2))``."""
    tc = float(np.clip(t, 0.0, path.duration))  # at rest outside the move: the end states are equilibria
    X, Y = path.X, path.Y
    a, b = X.deriv(2), Y.deriv(2) + g
    N, P, R = X * b - Y * a, Y**2 * (a**2 + b**2), a**2 + b**2
    av, bv, b1, b2, a1 = a(tc), b(tc), b.deriv()(tc), b.deriv(2)(tc), a.deriv()(tc)
    Nv, N1, N2, Pv, P1 = N(tc), N.deriv()(tc), N.deriv(2)(tc), P(tc), P.deriv()(tc)
    s, sdot = Nv / bv, (N1 * bv - Nv * b1) / bv**2
    sddot = (N2 * bv - Nv * b2) / bv**2 - 2 * b1 * sdot / bv
    l, ldot = np.sqrt(Pv) / bv, P1 / (2 * np.sqrt(Pv) * bv) - np.sqrt(Pv) * b1 / bv**2
    theta, thetadot = np.arctan2(-av, bv), (av * b1 - bv * a1) / R(tc)
    forces = np.array([m1 * sddot + m2 * av, m2 * np.sqrt(R(tc))])
    return np.array([s, l, theta]), np.array([sdot, ldot, thetadot]), forces


def build(
    m1: float = 10.0,
    m2: float = 2.0,
    g: float = 9.81,
    D: float = 2.0,
    L0: float = 1.5,
    h: float = 0.5,
    T: float = 4.0,
) -> Scene:
    """Overhead crane (trolley force, winch tension) carrying its payload along a path: tangential servo, index 5.

    ``scene.exact(t)`` and ``scene.forces(t) = (F1, F2)`` are the flat solution.

    Parameters
    ----------
    m1 : float
        Mass of the trolley (kg). Allowed: > 0.
    m2 : float
        Mass of the payload (kg). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−y`` (m/s²). Allowed: > 0, and ``Ÿd + g > 0`` along the whole path (a
        taut rope).
    D : float
        Horizontal distance of the payload's rest-to-rest transfer (m). Allowed: any finite number.
    L0 : float
        Initial and final depth of the payload below the rail: the rope's length at rest (m). Allowed: > 0.
    h : float
        Lift of the payload mid-way (m). Allowed: any finite number with ``Ÿd + g > 0`` along the path (a taut
        rope); physically h < L0, the payload below the rail (not checked).
    T : float
        Duration of the transfer, also the scene's horizon ``t_end`` (s). Allowed: > 0.
    """
    _check(m1=m1, m2=m2, L0=L0, T=T)
    path = Path.transfer(D, L0, h, T)
    if not _hangs(path, g):
        raise InputError(
            f"overhead-crane: the path needs Ÿ + g > 0 (a taut rope) but D={D}, h={h}, T={T}, g={g} accelerate the "
            "payload downwards faster than gravity; lengthen T or lower h"
        )
    model = _model(m1, m2, g, path)

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        q, v, _ = flat_motion(path, m1, m2, g, t)
        return q, v

    def forces(t: float) -> np.ndarray:
        return flat_motion(path, m1, m2, g, t)[2]

    return Scene(
        name="overhead-crane",
        model=model,
        q0=np.array([0.0, float(L0), 0.0]),
        v0=np.zeros(3),
        coordinates=("s (m)", "l (m)", "θ (rad)"),
        lam0=None,
        t_end=float(T),
        exact=exact,
        description="overhead crane: trolley force and winch carry the payload along a path; tangential, index 5",
        params=dict(m1=m1, m2=m2, g=g, D=D, L0=L0, h=h, T=T),
        forces=forces,
        drawing=drawing(path),
    )


def drawing(path: Path) -> Callable[[np.ndarray], dict[str, Any]]:
    """What to draw at ``q = (s, l, θ)`` (:attr:`Scene.drawing`): the rail, the trolley, the rope, the payload,
    the prescribed path, and the trolley force (the reaction on ``s``) at the trolley."""
    times = np.linspace(0.0, path.duration, 101)
    curve = np.column_stack([path.X(times), path.Y(times)])
    lo, hi = float(min(curve[:, 0].min(), 0.0)) - 0.5, float(curve[:, 0].max()) + 0.5

    def draw(q: np.ndarray) -> dict[str, Any]:
        trolley = (q[0], 0.0)
        payload = (q[0] + q[1] * np.sin(q[2]), -q[1] * np.cos(q[2]))
        return {
            "segments": [((lo, 0.0), (hi, 0.0)), (trolley, payload)],
            "points": [trolley, payload],
            "path": curve,
            "reaction": [(trolley, (0, None))],
        }

    return draw


def _check(**positive: float) -> None:
    for name, value in positive.items():
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"overhead-crane: {name} must be positive and finite, got {value!r}")


def _hangs(path: Path, g: float) -> bool:
    """Whether ``Ÿ + g > 0`` on the whole move (the rope stays taut, ``b > 0`` in the flat solution)."""
    return bool(np.all(path.Y.deriv(2)(np.linspace(0.0, path.duration, 401)) + g > 0))


def _model(m1: float, m2: float, g: float, path: Path) -> Model:
    """The crane's Lagrangian and the payload-path servo with the trolley force and the winch."""

    def payload(q: Any) -> tuple[Any, Any]:
        return q[0] + q[1] * ca.sin(q[2]), -q[1] * ca.cos(q[2])

    def kinetic(q: Any, v: Any, t: Any) -> Any:
        Xdot = v[0] + v[1] * ca.sin(q[2]) + q[1] * ca.cos(q[2]) * v[2]
        Ydot = -v[1] * ca.cos(q[2]) + q[1] * ca.sin(q[2]) * v[2]
        return 0.5 * m1 * v[0] ** 2 + 0.5 * m2 * (Xdot**2 + Ydot**2)

    def on_path(q: Any, t: Any) -> list[Any]:
        (X, Y), (Xd, Yd) = payload(q), path.at(t)
        return [X - Xd, Y - Yd]

    body = Lagrangian(n=3, T=kinetic, V=lambda q, t: m2 * g * payload(q)[1])
    servo = Holonomic(on_path, name="payload path", realization=Force(lambda q, v, t: [[1, 0, 0], [0, -1, 0]]))
    return Model(body, [servo])
