"""The double parallelogram with spatial bars and revolute joints: an overconstrained closed loop (Bricard-size).

The mechanism of :func:`gausspp.scenes.parallelogram.build` with ``third_bar=True`` (cranks of length ``l`` on
ground pins at ``(j l, 0, 0)``, couplers of length ``2 l`` pinned at their ends and centre to three crank tips;
``cells=N`` chains ``N`` cells along ``x``), every bar now a rigid body in space and every pin a revolute joint
with its axis along ``z``.

Coordinates, 6 per bar in the planar scene's bar order: the centre of mass ``c = (x, y, z)`` and yaw–pitch–roll
angles ``(ψ, θ, φ)`` (ZYX), ``R = R_z(ψ) R_y(θ) R_x(φ)``; the bar lies along its body ``x`` axis. With
``v = q̇`` the body angular velocity ``ω = Rᵀ Ṙ`` is

    ``ω = (φ̇ − ψ̇ sin θ,  θ̇ cos φ + ψ̇ cos θ sin φ,  ψ̇ cos θ cos φ − θ̇ sin φ)``,

so a planar motion is pure yaw (``θ = φ = 0``, ``ω = (0, 0, ψ̇)``), far from gimbal lock (``θ = ±π/2``). A bar of
mass ``mᵢ`` (``m`` per length ``l``) and length ``Lᵢ`` has

    ``T = Σ ½ mᵢ |ċᵢ|² + ½ ωᵢᵀ diag(εᵢ, mᵢ Lᵢ²/12, mᵢ Lᵢ²/12) ωᵢ``,   ``V = Σ mᵢ g yᵢ``,

``εᵢ = mᵢ (ρ Lᵢ)²/2`` (a solid rod of radius ``ρ Lᵢ``, ``ρ = 1 %``): the mass matrix is positive definite and the
moment about ``z`` is the planar scene's, so the one-DOF reference is the same.

Joints. The point of bar ``i`` at offset ``s`` along its axis is ``pᵢ(s) = cᵢ + s Rᵢ e_x``. A revolute joint between
``(i, sᵢ)`` and ``(j, sⱼ)`` with axis ``z`` is 5 rows (``pin NAME[0…4]``)

    ``pᵢ(sᵢ) − pⱼ(sⱼ) = 0`` (3),   ``(Rᵢ e_z)·(Rⱼ e_x) = 0``,   ``(Rᵢ e_z)·(Rⱼ e_y) = 0`` (2);

a ground joint puts ``pᵢ(sᵢ)`` on the ground pin and ``Rᵢ e_z`` along the world ``z``: ``(Rᵢ e_z)·e_x =
(Rᵢ e_z)·e_y = 0``.

Sizes. ``3N + 1`` bars and ``5N + 1`` joints: ``18N + 6`` coordinates, ``25N + 5`` rows. On the manifold ``J`` has
rank ``18N + 5`` (one degree of freedom): the planar part has the planar scene's rank ``9N + 2``, the out-of-plane
part (``z``, ``θ``, ``φ`` of every bar, ``9N + 3`` coordinates, ``15N + 3`` rows) full rank. ``cells=1``: 24
coordinates, 30 rows, rank 23 — seven redundant rows, like Bricard's mechanism (IFToMM A04: 35 coordinates,
rank 34). At the collinear positions (``sin ψ = 0`` for the cranks) the planar part loses one rank more.

Reference. The motion is the planar scene's: ``z = θ = φ = 0``, ``ψ`` the planar angle, so
:func:`one_dof_reference` is :func:`gausspp.scenes.parallelogram.one_dof_reference` with ``third_bar=True`` and
:func:`maximal_state` places :func:`gausspp.scenes.parallelogram.maximal_state` in these coordinates. Initially the
cranks stand vertical (``ψ = π/2``) with ``ψ̇ = −1`` rad/s: the tips move at 1 m/s along ``+x``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model.constraints import Holonomic
from ..model.mechanism import Lagrangian
from ..model.model import Model
from . import parallelogram as planar
from .scene import Scene, numbered

#: One bar's coordinates: its centre of mass and its yaw, pitch and roll (ZYX).
BAR = ("x (m)", "y (m)", "z (m)", "ψ (rad)", "θ (rad)", "φ (rad)")
#: A bar's radius as a fraction of its length: the moment ``ε = m (ρ L)²/2`` about its own axis.
RADIUS = 0.01
#: Where the planar coordinates ``(x, y, θ)`` of a bar sit among its six.
PLANAR = [0, 1, 3]


def rotation(psi: Any, theta: Any, phi: Any) -> Any:
    """``R = R_z(ψ) R_y(θ) R_x(φ)`` (casadi symbols or numbers) as a 3×3 casadi matrix."""
    cz, sz, cy, sy, cx, sx = ca.cos(psi), ca.sin(psi), ca.cos(theta), ca.sin(theta), ca.cos(phi), ca.sin(phi)
    return ca.vertcat(
        ca.horzcat(cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx),
        ca.horzcat(sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx),
        ca.horzcat(-sy, cy * sx, cy * cx),
    )


def body_rate(angles: Any, rates: Any) -> Any:
    """The body angular velocity ``ω = Rᵀ Ṙ`` from the ZYX angles ``(ψ, θ, φ)`` and their rates."""
    _, theta, phi = angles[0], angles[1], angles[2]
    dpsi, dtheta, dphi = rates[0], rates[1], rates[2]
    return ca.vertcat(
        dphi - dpsi * ca.sin(theta),
        dtheta * ca.cos(phi) + dpsi * ca.cos(theta) * ca.sin(phi),
        dpsi * ca.cos(theta) * ca.cos(phi) - dtheta * ca.sin(phi),
    )


def frame(q: Any, bar: int) -> tuple[Any, Any]:
    """The centre ``c`` and rotation ``R`` of ``bar`` (its index in ``q``)."""
    c = ca.vertcat(q[6 * bar], q[6 * bar + 1], q[6 * bar + 2])
    return c, rotation(q[6 * bar + 3], q[6 * bar + 4], q[6 * bar + 5])


def point(q: Any, bar: int, s: float) -> Any:
    """The point of ``bar`` at offset ``s`` from its centre along its axis: ``c + s R e_x``."""
    c, R = frame(q, bar)
    return c + s * R[:, 0]


def _joint(name: str, first: tuple[int, float], to: tuple[int, float] | None, ground: float = 0.0) -> Holonomic:
    """Five rows: a revolute joint with axis ``z`` between ``first = (bar, s)`` and ``to`` (another bar's point), or
    the ground pin ``(ground, 0, 0)``: the points coincide, ``first``'s ``z`` axis is normal to the other's ``x``
    and ``y`` axes (the world's with ``to=None``)."""

    def rows(q: Any, t: Any) -> Any:
        axis = frame(q, first[0])[1][:, 2]
        if to is None:
            return ca.vertcat(point(q, *first) - ca.vertcat(ground, 0.0, 0.0), axis[0], axis[1])
        other = frame(q, to[0])[1]
        return ca.vertcat(point(q, *first) - point(q, *to), ca.dot(axis, other[:, 0]), ca.dot(axis, other[:, 1]))

    return Holonomic(rows, name=name)


def _joints(cells: int, l: float) -> list[Holonomic]:
    """The planar scene's pins (:func:`gausspp.scenes.parallelogram._pins`, ``third_bar=True``) as revolute joints."""
    index = {bar: i for i, bar in enumerate(planar.bars(cells, True))}
    joints = [_joint("pin ground-crank1", (0, -l / 2), None, 0.0)]
    for k in range(cells):
        coupler = index["coupler", k]
        for i in range(3):
            j = 2 * k + i
            crank = index["crank", j]
            joints.append(_joint(f"pin crank{j + 1}-coupler{k + 1}", (coupler, (i - 1) * l), (crank, l / 2)))
            if i:
                joints.append(_joint(f"pin ground-crank{j + 1}", (crank, -l / 2), None, j * l))
    return joints


def _bodies(lengths: list[float], masses: list[float], g: float) -> Lagrangian:
    """Free spatial bars: ``T = Σ ½ mᵢ |ċᵢ|² + ½ ωᵢᵀ Iᵢ ωᵢ``, ``Iᵢ = diag(εᵢ, mᵢ Lᵢ²/12, mᵢ Lᵢ²/12)``,
    ``V = Σ mᵢ g yᵢ``."""

    def kinetic(q: Any, v: Any, t: Any) -> Any:
        total = 0
        for i, (li, mi) in enumerate(zip(lengths, masses, strict=True)):
            w = body_rate(q[6 * i + 3 : 6 * i + 6], v[6 * i + 3 : 6 * i + 6])
            moments = ca.vertcat(mi * (RADIUS * li) ** 2 / 2, mi * li**2 / 12, mi * li**2 / 12)
            total += 0.5 * mi * ca.sumsqr(v[6 * i : 6 * i + 3]) + 0.5 * ca.dot(moments, w * w)
        return total

    def potential(q: Any, t: Any) -> Any:
        return sum(mi * g * q[6 * i + 1] for i, mi in enumerate(masses))

    return Lagrangian(n=6 * len(lengths), T=kinetic, V=potential)


def maximal_state(
    theta: float, omega: float, alpha: float = 0.0, cells: int = 1, l: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, v, a)`` for cranks at the planar angle ``θ`` (the yaw ``ψ``), ``θ̇ = omega``, ``θ̈ = alpha``: the planar
    scene's (:func:`gausspp.scenes.parallelogram.maximal_state`) with ``z``, pitch, roll and their rates zero."""
    out = []
    for planar_part in planar.maximal_state(theta, omega, alpha, cells, True, l):
        full = np.zeros((planar_part.size // 3, 6))
        full[:, PLANAR] = planar_part.reshape(-1, 3)
        out.append(full.ravel())
    return out[0], out[1], out[2]


def one_dof_reference(
    t: Any,
    cells: int = 1,
    l: float = 1.0,
    m: float = 1.0,
    g: float = 9.81,
    theta0: float = np.pi / 2,
    omega0: float = -1.0,
    t_end: float | None = None,
) -> tuple[Any, Any]:
    """The cranks' yaw ``ψ(t)`` and rate (the planar one-DOF reference of the double parallelogram ladder):
    ``one_dof_reference(t, **scene.params)``."""
    return planar.one_dof_reference(t, cells, True, l, m, g, theta0, omega0)


def build(
    cells: int = 1,
    l: float = 1.0,
    m: float = 1.0,
    g: float = 9.81,
    theta0: float = np.pi / 2,
    omega0: float = -1.0,
    t_end: float = 10.0,
) -> Scene:
    """Spatial double parallelogram, revolute joints, in maximal coordinates: overconstrained like Bricard's.

    Parameters
    ----------
    cells : int
        Number of double parallelogram cells chained along x (-). Allowed: integer ≥ 1.
    l : float
        Length of a crank; the couplers are ``2 l`` long (m). Allowed: > 0.
    m : float
        Mass of a crank: every bar has mass ``m`` per length ``l`` (kg). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−y`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    theta0 : float
        Initial yaw ``ψ`` of the cranks from the ground line; π/2: vertical (rad). Allowed: any finite number.
    omega0 : float
        Initial yaw rate ``ψ̇`` of the cranks (rad/s). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    try:
        planar._check(cells, True, l, m, g, theta0, omega0, t_end)
    except InputError as exc:
        raise InputError(f"spatial-{exc}") from None
    order = planar.bars(cells, True)
    lengths = [l if kind == "crank" else 2 * l for kind, _ in order]
    model = Model(_bodies(lengths, [m * length / l for length in lengths], g), _joints(cells, l))
    q0, v0, _ = maximal_state(theta0, omega0, 0.0, cells, l)
    flat = planar.drawing(lengths, [j * l for j in range(2 * cells + 1)])
    what = "double parallelogram" if cells == 1 else f"ladder of {cells} double parallelogram cells"
    return Scene(
        name="spatial-parallelogram",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=numbered(BAR, len(order)),
        lam0=None,
        t_end=float(t_end),
        exact=None,
        drawing=lambda q: flat(np.reshape(np.asarray(q, float), (-1, 6))[:, PLANAR].ravel()),
        description=(
            f"{what} of spatial bars and revolute joints ({model.nq} coordinates, {model.k} joint rows, rank "
            f"{model.nq - 1}); reference: the planar one-DOF crank equation"
        ),
        params=dict(cells=cells, l=l, m=m, g=g, theta0=theta0, omega0=omega0, t_end=t_end),
    )
