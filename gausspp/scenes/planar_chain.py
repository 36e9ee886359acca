"""A planar chain of ``N`` links in maximal coordinates: the scaling problem.

Link ``i`` (``i = 1 … N``) is a rigid bar with coordinates ``(xᵢ, zᵢ, θᵢ)``: its centre of mass and
its angle from the ``x`` axis; mass ``m``, length ``L``, central moment of inertia ``m L²/12``,
gravity ``g`` along ``−z``. So ``q ∈ ℝ³ᴺ``, the mass matrix is the constant diagonal
``A = diag(m, m, m L²/12, …)`` and

    ``T = Σ ½ m (ẋᵢ² + żᵢ²) + ½ (m L²/12) θ̇ᵢ²``,   ``V = Σ m g zᵢ``.

The link's ends are ``pᵢ∓ = (xᵢ, zᵢ) ∓ (L/2)(cos θᵢ, sin θᵢ)`` (top ``−``, bottom ``+``). Pin joints,
ideal holonomic constraints of two rows each (``2N`` rows in all):

    ``pin-1:  p₁⁻ = 0``   (the top of link 1 at the origin),
    ``pin-i:  pᵢ⁻ − pᵢ₋₁⁺ = 0``   (``i ≥ 2``).

The chain is written as bodies and joints (``gp.Multibody``: a planar body per link, a revolute per pin,
:func:`chain`); its model is, row for row, the one of the end-point expressions above (the test
``tests/test_scenes_on_multibody.py`` keeps that hand-written model as the reference: the same motion to the
last bit).
Each pin's rows are written on the six coordinates of the two links it joins only, so the
constraint Jacobian ``J`` (``2N × 3N``) is block bidiagonal in casadi's sparsity pattern and
``J A⁻¹ Jᵀ`` is banded: the structure a sparse step route can exploit.

Initial data: the chain straight, at ``theta0`` from the horizontal (default ``−0.3``: 0.3 rad below
it), hanging from the pin at rest — on the constraint manifold. The chain has ``N`` degrees of
freedom; for ``N = 1`` it is the ``pendulum`` scene with ``L/2`` from the pin to the centre of mass
and ``Ic = m L²/12``, whose ``exact`` (the 1-DOF equation about the pin, solved to ~1e-12) is this
scene's reference; for ``N ≥ 2`` there is no closed form (``exact`` is ``None``): the energy is
conserved and the pins hold, which the tests check.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from ..multibody import Multibody
from . import pendulum
from .scene import Scene, numbered

#: One bar's coordinates: its centre of mass and its angle from the x axis.
BAR = ("x (m)", "z (m)", "θ (rad)")


def end(q: Any, link: int, sign: int, L: float) -> Any:
    """The top (``sign = −1``) or bottom (``sign = +1``) end of ``link`` (0-based): ``(x, z) ± (L/2)(cos θ, sin θ)``."""
    x, z, theta = q[3 * link], q[3 * link + 1], q[3 * link + 2]
    return ca.vertcat(x + sign * 0.5 * L * ca.cos(theta), z + sign * 0.5 * L * ca.sin(theta))


def chain(N: int, m: float, L: float, g: float) -> Multibody:
    """The chain as bodies and joints: link ``i`` a bar of ``m`` and ``m L²/12`` along its body ``x``, pinned at its top
    (``−L/2``) to the bottom (``+L/2``) of the link above, the first to the origin (``pin-1``, ``pin-2``, …)."""
    mb = Multibody(gravity=(0.0, -g))  # the plane's second axis is the scene's z
    for i in range(N):
        mb.body(f"link{i + 1}", mass=m, inertia=m * L * L / 12.0, at=(0.0, 0.0), angle=0.0)
    mb.revolute("pin-1", "link1", (-L / 2, 0.0), None, (0.0, 0.0))
    for i in range(1, N):
        mb.revolute(f"pin-{i + 1}", f"link{i + 1}", (-L / 2, 0.0), f"link{i}", (L / 2, 0.0))
    return mb


def straight(N: int, L: float, theta0: float) -> np.ndarray:
    """The chain straight at angle ``theta0``, its first link's top at the origin: ``q`` (3N,)."""
    e = np.array([np.cos(theta0), np.sin(theta0)])
    q = np.empty(3 * N)
    for i in range(N):
        q[3 * i : 3 * i + 2] = (i + 0.5) * L * e
        q[3 * i + 2] = theta0
    return q


def build(
    N: int = 4, m: float = 1.0, L: float = 1.0, g: float = 9.81, theta0: float = -0.3, t_end: float = 1.0
) -> Scene:
    """Planar chain of N pinned links in maximal coordinates (3N coordinates, 2N rows): the scaling problem.

    Parameters
    ----------
    N : int
        Number of links (-). Allowed: integer ≥ 1.
    m : float
        Mass of each link (kg). Allowed: > 0.
    L : float
        Length of each link (m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−z`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    theta0 : float
        Initial angle of the straight chain from the horizontal, negative below it; it starts at rest (rad).
        Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    if not N >= 1:
        raise InputError(f"planar-chain: N must be a positive integer, got N={N!r}; give N = 1, 2, …")
    if not (m > 0 and L > 0):
        raise InputError(f"planar-chain: m and L must be positive, got m={m}, L={L}")
    model = chain(N, m, L, g).model()
    exact = None
    if N == 1:  # the pendulum scene's reference: centre of mass at L/2 from the pin, Ic = m L²/12
        exact = pendulum.build(m=m, Ic=m * L * L / 12.0, L=0.5 * L, g=g, phi0=theta0, t_end=t_end).exact
    return Scene(
        name="planar-chain",
        model=model,
        q0=straight(N, L, theta0),
        v0=np.zeros(3 * N),
        coordinates=numbered(BAR, N),
        lam0=None,
        t_end=float(t_end),
        exact=exact,
        description=f"planar chain of {N} pinned links in maximal coordinates ({3 * N} coordinates, {2 * N} rows)",
        params=dict(N=N, m=m, L=L, g=g, theta0=theta0, t_end=t_end),
        drawing=lambda q: chain_drawing(q, L),
    )


def chain_drawing(q: np.ndarray, L: float) -> dict[str, Any]:
    """The links ``pᵢ⁻ pᵢ⁺``, their centres of mass and the top pin at the origin (:attr:`Scene.drawing`)."""
    links = np.reshape(q, (-1, 3))
    half = 0.5 * L * np.column_stack([np.cos(links[:, 2]), np.sin(links[:, 2])])
    tops, bottoms = links[:, :2] - half, links[:, :2] + half
    return {"segments": list(zip(tops, bottoms, strict=True)), "points": list(links[:, :2]), "fixed": [(0.0, 0.0)]}


def build_planar_ladder(
    N: int = 1,
    m: float = 1.0,
    L: float = 1.0,
    W: float = 1.0,
    g: float = 9.81,
    theta0: float = -1.0,
    t_end: float = 1.0,
) -> Scene:
    """Ladder of N parallelogram four-bars in maximal coordinates (closed loops: 9N coordinates, 8N rows).

    Parameters
    ----------
    N : int
        Number of levels, one parallelogram four-bar each (-). Allowed: integer ≥ 1.
    m : float
        Mass of each bar, rails and rungs alike (kg). Allowed: > 0.
    L : float
        Length of each rail bar (m). Allowed: > 0.
    W : float
        Length of each rung, the ladder's width (m). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−z`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    theta0 : float
        Initial angle of the rails from the horizontal; the ladder starts at rest (rad). Allowed: |sin theta0| >
        0.1 (rails not nearly level with the rungs).
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    if not N >= 1:
        raise InputError(f"planar-ladder: N must be a positive integer, got N={N!r}; give N = 1, 2, …")
    if not (m > 0 and L > 0 and W > 0):
        raise InputError(f"planar-ladder: m, L and W must be positive, got m={m}, L={L}, W={W}")
    if not abs(np.sin(theta0)) > 0.1:
        raise InputError(
            f"planar-ladder: theta0={theta0} leaves the rails nearly level with the rungs; use |sin θ0| > 0.1"
        )
    model = ladder(N, m, L, W, g).model()
    e = np.array([np.cos(theta0), np.sin(theta0)])
    q0 = np.empty(9 * N)
    for i in range(N):  # left rail, right rail, rung
        q0[9 * i : 9 * i + 6] = [*((i + 0.5) * L * e), theta0, *((i + 0.5) * L * e + (W, 0)), theta0]
        q0[9 * i + 6 : 9 * i + 9] = [*((i + 1) * L * e + (0.5 * W, 0)), 0.0]
    return Scene(
        name="planar-ladder",
        model=model,
        q0=q0,
        v0=np.zeros(9 * N),
        coordinates=numbered(BAR, 3 * N),
        lam0=None,
        t_end=float(t_end),
        exact=None,
        description=f"ladder of {N} parallelogram four-bars in maximal coordinates ({9 * N} coordinates, {8 * N} rows)",
        params=dict(N=N, m=m, L=L, W=W, g=g, theta0=theta0, t_end=t_end),
    )


def ladder(N: int, m: float, L: float, W: float, g: float) -> Multibody:
    """The ladder as bodies and joints. Level ``n``: a left and a right rail of ``L`` and a rung of ``W`` (bars along
    their body ``x``); each rail's top pinned to the rail above (the ground at ``(0, 0)`` and ``(W, 0)`` for the
    first), the rung's ends to the rails' bottoms (``left-n``, ``right-n``, ``rung-n left``, ``rung-n right``)."""
    mb = Multibody(gravity=(0.0, -g))
    for n in range(1, N + 1):
        for name, length in (("left", L), ("right", L), ("rung", W)):
            mb.body(f"{name}{n}", mass=m, inertia=m * length * length / 12.0, at=(0.0, 0.0), angle=0.0)
        above = [(f"left{n - 1}", (L / 2, 0.0)), (f"right{n - 1}", (L / 2, 0.0))]
        if n == 1:  # the ground
            above = [(None, (0.0, 0.0)), (None, (W, 0.0))]
        mb.revolute(f"left-{n}", f"left{n}", (-L / 2, 0.0), *above[0])
        mb.revolute(f"right-{n}", f"right{n}", (-L / 2, 0.0), *above[1])
        mb.revolute(f"rung-{n} left", f"rung{n}", (-W / 2, 0.0), f"left{n}", (L / 2, 0.0))
        mb.revolute(f"rung-{n} right", f"rung{n}", (W / 2, 0.0), f"right{n}", (L / 2, 0.0))
    return mb
