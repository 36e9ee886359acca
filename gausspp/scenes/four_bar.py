"""A planar four-bar linkage with a redundant loop equation: one acceleration, the least-norm multiplier.

Ground pivots ``O = (0, 0)`` and ``P = (l0, 0)``; a crank ``l1`` from ``O`` to ``B``, a coupler
``l2`` from ``B`` to ``C``, a rocker ``l3`` from ``C`` back to ``P``. Coordinates are relative
angles ``q = (θ1, θ2, θ3)``: the crank's angle from the ground, the coupler's relative to the
crank, the rocker's relative to the coupler, so the absolute angles are ``φ1 = θ1``,
``φ2 = θ1 + θ2``, ``φ3 = θ1 + θ2 + θ3``. Uniform bars of mass ``ρ lᵢ`` and central moment of
inertia ``ρ lᵢ³/12`` under gravity ``g`` (``−y``); ``T`` and ``V`` are built from the bars'
centres of mass by automatic differentiation (:class:`~gausspp.Lagrangian`).

The loop closes by the ideal holonomic constraint

    closure:  l1 e(φ1) + l2 e(φ2) + l3 e(φ3) − (l0, 0) = 0,      e(φ) = (cos φ, sin φ)

(two rows: the minimal model, one degree of freedom). ``redundant=True`` adds a third row that
the first two imply, so the constraint Jacobian ``J`` (3×3) has rank 2 and the direct formula has
no answer (``S = J A⁻¹ Jᵀ`` is singular). ``third_row`` picks it:

* ``"oblique"`` — the closure projected on the fixed direction ``(cos α, sin α)``: a linear
  combination of the two rows *everywhere* (consistent at every state);
* ``"distance"`` — ``|C − P|² − l3² = 0`` with ``C = l1 e(φ1) + l2 e(φ2)``: the rocker's length,
  implied by the closure *on* the constraint manifold (dependent there only). Off it — e.g. at the
  stages of a Runge–Kutta step — the three rows are independent but nearly dependent and
  contradict each other by the drift; the step decides the redundancy at the nearest state on the
  manifold (:mod:`gausspp.step.general.redundancy`) and returns the minimal model's acceleration.

Gauss's principle still fixes the acceleration uniquely; ``solver="qp"`` returns it with the
least-norm multiplier (:mod:`gausspp.step.general`), ``solver="direct"`` refuses with a
:class:`~gausspp.RealizabilityError` that says the rows are redundant.

With the defaults (``l0, l1, l2, l3 = 1, 0.3, 1, 0.8``: a Grashof crank-rocker, the crank turns
fully and no configuration is singular) the crank starts at ``θ1 = π/2`` turning at ``ω0`` and the
linkage moves under gravity alone. There is no closed form (``exact`` is ``None``): the minimal
model (``redundant=False``) is the reference.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError, UnknownNameError
from ..model.constraints import Holonomic
from ..model.mechanism import Lagrangian
from ..model.model import Model
from .scene import Scene, numbered

THIRD_ROWS = ("oblique", "distance")


def _e(phi: Any) -> Any:
    return ca.vertcat(ca.cos(phi), ca.sin(phi))


def absolute_angles(q: Any) -> tuple[Any, Any, Any]:
    """``(φ1, φ2, φ3)`` of crank, coupler and rocker from the relative angles ``q``."""
    return q[0], q[0] + q[1], q[0] + q[1] + q[2]


def assemble(
    theta1: float, omega1: float, l0: float, l1: float, l2: float, l3: float, elbow: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """The configuration and velocity on the loop for crank angle ``theta1`` and crank rate ``omega1``.

    ``elbow = ±1`` picks one of the two assembly modes. Raises :class:`InputError` if the loop
    cannot close at that crank angle.
    """
    B = l1 * np.array([np.cos(theta1), np.sin(theta1)])
    w = np.array([l0, 0.0]) - B
    d = float(np.hypot(*w))
    cos_gamma = (l2**2 + d**2 - l3**2) / (2 * l2 * d) if d > 0 else np.inf
    if not abs(cos_gamma) <= 1.0:
        raise InputError(
            f"four-bar: the loop cannot close at theta1={theta1} with l0, l1, l2, l3 = {l0}, {l1}, {l2}, {l3}"
        )
    phi2 = np.arctan2(w[1], w[0]) + elbow * np.arccos(cos_gamma)
    C = B + l2 * np.array([np.cos(phi2), np.sin(phi2)])
    phi3 = float(np.arctan2(-C[1], l0 - C[0]))
    q = np.array([theta1, phi2 - theta1, phi3 - phi2])
    # velocities: J(q) q̇ = 0 with q̇1 = omega1; the columns of J are ∂closure/∂θi
    e_perp = [np.array([-np.sin(a), np.cos(a)]) for a in (theta1, phi2, phi3)]
    cols = [l1 * e_perp[0] + l2 * e_perp[1] + l3 * e_perp[2], l2 * e_perp[1] + l3 * e_perp[2], l3 * e_perp[2]]
    rates = np.linalg.solve(np.column_stack(cols[1:]), -cols[0] * omega1)
    return q, np.array([omega1, rates[0], rates[1]])


def build(
    redundant: bool = True,
    third_row: str = "oblique",
    alpha: float = 0.7,
    l0: float = 1.0,
    l1: float = 0.3,
    l2: float = 1.0,
    l3: float = 0.8,
    rho: float = 1.0,
    g: float = 9.81,
    theta0: float = np.pi / 2,
    omega0: float = 6.0,
    t_end: float = 2.0,
) -> Scene:
    """Four-bar linkage closed by a redundant third loop row (rank-deficient J): the QP's least-norm multiplier.

    Parameters
    ----------
    redundant : bool
        Whether to add the third loop row, which the closure's x and y rows imply (rank-deficient ``J``); False:
        the minimal model (-). Allowed: True or False.
    third_row : str
        The redundant row: the closure along ``(cos alpha, sin alpha)`` (``'oblique'``, dependent everywhere) or
        the rocker's length ``|C − P| = l3`` (``'distance'``, dependent on the constraint manifold only) (-).
        Allowed: one of 'oblique', 'distance'.
    alpha : float
        Direction of the oblique row from the x axis, used with ``third_row='oblique'`` (rad). Allowed: any
        finite number.
    l0 : float
        Distance between the ground pivots O and P (m). Allowed: > 0; the loop must close at ``theta0``.
    l1 : float
        Length of the crank OB (m). Allowed: > 0; the loop must close at ``theta0``.
    l2 : float
        Length of the coupler BC (m). Allowed: > 0; the loop must close at ``theta0``.
    l3 : float
        Length of the rocker CP (m). Allowed: > 0; the loop must close at ``theta0``.
    rho : float
        Mass per unit length of the uniform bars (kg/m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−y`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    theta0 : float
        Initial angle ``θ1`` of the crank from the ground line (rad). Allowed: any finite number at which the loop
        closes.
    omega0 : float
        Initial rate ``θ̇1`` of the crank (rad/s). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    _check(redundant, third_row, alpha, l0, l1, l2, l3, rho, g, theta0, omega0, t_end)
    lengths = (float(l1), float(l2), float(l3))
    model = Model(_bars(lengths, rho, g), _loop(redundant, third_row, alpha, l0, lengths))
    q0, v0 = assemble(float(theta0), float(omega0), float(l0), *lengths)
    name = "four-bar-redundant"
    return Scene(
        name=name,
        model=model,
        q0=q0,
        v0=v0,
        coordinates=numbered(["θ (rad)"], 3),
        lam0=None,
        t_end=float(t_end),
        exact=None,
        drawing=drawing(float(l0), lengths),
        description=(
            "four-bar linkage with a redundant loop row (rank-deficient J): the QP gives the unique acceleration "
            "and the least-norm multiplier, the direct formula refuses"
        ),
        params=dict(
            redundant=bool(redundant),
            third_row=third_row,
            alpha=alpha,
            l0=l0,
            l1=l1,
            l2=l2,
            l3=l3,
            rho=rho,
            g=g,
            theta0=theta0,
            omega0=omega0,
            t_end=t_end,
        ),
    )


def _check(
    redundant: Any,
    third_row: str,
    alpha: float,
    l0: float,
    l1: float,
    l2: float,
    l3: float,
    rho: float,
    g: float,
    theta0: float,
    omega0: float,
    t_end: float,
) -> None:
    """The parameters checked: a boolean, a known third row, positive lengths, finite numbers."""
    if not isinstance(redundant, (bool, np.bool_)):
        raise InputError(f"four-bar-redundant: redundant must be True or False, got {redundant!r}")
    if third_row not in THIRD_ROWS:
        raise UnknownNameError(f"four-bar-redundant: third_row={third_row!r} is unknown; use one of {list(THIRD_ROWS)}")
    for name, value in (("l0", l0), ("l1", l1), ("l2", l2), ("l3", l3), ("rho", rho), ("t_end", t_end)):
        if not (isinstance(value, (int, float, np.floating, np.integer)) and np.isfinite(value) and value > 0):
            raise InputError(f"four-bar-redundant: {name} must be positive and finite, got {value!r}")
    for name, value in (("alpha", alpha), ("g", g), ("theta0", theta0), ("omega0", omega0)):
        if not (isinstance(value, (int, float, np.floating, np.integer)) and np.isfinite(value)):
            raise InputError(f"four-bar-redundant: {name} must be a finite number, got {value!r}")


def _bars(lengths: tuple[float, float, float], rho: float, g: float) -> Lagrangian:
    """Crank, coupler and rocker: uniform bars of mass ``ρ lᵢ``, moment ``ρ lᵢ³/12``, under gravity."""
    l1, l2, l3 = lengths
    masses = tuple(rho * li for li in lengths)
    inertias = tuple(mi * li**2 / 12.0 for mi, li in zip(masses, lengths, strict=True))

    def centres(q: Any) -> list[Any]:
        p1, p2, p3 = absolute_angles(q)
        B = l1 * _e(p1)
        C = B + l2 * _e(p2)
        return [0.5 * l1 * _e(p1), B + 0.5 * l2 * _e(p2), C + 0.5 * l3 * _e(p3)]

    def kinetic(q: Any, v: Any, t: Any) -> Any:
        T = 0
        rates = (v[0], v[0] + v[1], v[0] + v[1] + v[2])
        for c, mi, Ii, w in zip(centres(q), masses, inertias, rates, strict=True):
            vc = ca.jacobian(c, q) @ v
            T = T + 0.5 * mi * ca.dot(vc, vc) + 0.5 * Ii * w**2
        return T

    def potential(q: Any, t: Any) -> Any:
        return g * sum(mi * c[1] for c, mi in zip(centres(q), masses, strict=True))

    return Lagrangian(n=3, T=kinetic, V=potential)


def _loop(
    redundant: bool, third_row: str, alpha: float, l0: float, lengths: tuple[float, float, float]
) -> list[Holonomic]:
    """The closure's two rows and, if ``redundant``, the third row that they imply."""
    l1, l2, l3 = lengths

    def closure(q: Any, t: Any) -> Any:
        p1, p2, p3 = absolute_angles(q)
        return l1 * _e(p1) + l2 * _e(p2) + l3 * _e(p3) - ca.vertcat(l0, 0)

    def third(q: Any, t: Any) -> Any:
        if third_row == "oblique":
            return ca.dot(ca.vertcat(np.cos(alpha), np.sin(alpha)), closure(q, t))
        p1, p2, _ = absolute_angles(q)
        CP = l1 * _e(p1) + l2 * _e(p2) - ca.vertcat(l0, 0)
        return ca.dot(CP, CP) - l3**2

    constraints = [Holonomic(closure, name="closure")]
    if redundant:
        constraints.append(Holonomic(third, name=f"closure ({third_row})"))
    return constraints


def drawing(l0: float, lengths: tuple[float, float, float]) -> Callable[[np.ndarray], dict[str, Any]]:
    """What to draw at ``q = (θ1, θ2, θ3)`` (:attr:`Scene.drawing`): the crank ``OB``, coupler ``BC`` and
    rocker ``CP``, the ground pivots ``O``, ``P``, the ground ``OP``, and the coupler curve traced by the
    coupler's midpoint. (The reaction is a set of joint torques: no arrow.)"""
    l1, l2, _ = lengths

    def draw(q: np.ndarray) -> dict[str, Any]:
        phi1, phi2, _ = absolute_angles(np.asarray(q, float))
        B = l1 * np.array([np.cos(phi1), np.sin(phi1)])
        C = B + l2 * np.array([np.cos(phi2), np.sin(phi2)])
        O, P = np.zeros(2), np.array([l0, 0.0])
        return {"segments": [(O, B), (B, C), (C, P)], "points": [B, C], "fixed": [O, P], "ground": [(O, P)],
                "trace": [0.5 * (B + C)]}  # fmt: skip

    return draw
