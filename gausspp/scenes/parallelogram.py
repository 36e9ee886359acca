"""Parallelogram linkages in maximal coordinates (IFToMM benchmark A02), the double parallelogram and a ladder.

Geometry. ``n = w N + 1`` parallel cranks of length ``l`` stand on ground pins at ``(j l, 0)``, ``j = 0 … n − 1``;
``N = cells`` couplers, each a bar of length ``w l`` (``w = 1``, or ``w = 2`` with ``third_bar``), lie end to end
along the cranks' tips: coupler ``k`` is pinned at its offsets ``0, l, …, w l`` from its left end to the tips of
cranks ``k w, …, k w + w``. Bars are uniform: mass ``m`` per length ``l`` (a crank ``m``, a coupler ``w m``), central
moment ``mass · length²/12``, gravity ``g`` along ``−y``.

* ``cells=1`` — A02: two cranks and a coupler of length ``l`` (9 coordinates, 8 rows). Grübler mobility 1, the
  rows independent except at the collinear positions ``sin θ = 0``: all bars lie on the ground line, another
  assembly branch crosses the parallelogram's there (crank 1 along the ground, the coupler folded onto crank 2)
  and ``J`` drops to rank 7.
* ``third_bar=True`` — the double parallelogram: a coupler of length ``2 l`` pinned at its left end, centre and right
  end to three cranks on ground pins at ``x = 0, l, 2 l`` (12 coordinates, 12 rows). Grübler counts
  ``3·4 − 2·6 = 0``, yet it moves with one degree of freedom: one row is redundant at *every* state on the manifold
  (``J`` has rank 11), two at the collinear positions (rank 10).
* ``cells=N`` — a ladder of ``N`` such cells chained along ``x``, adjacent cells sharing the crank between them:
  ``3(n + N)`` coordinates and ``2(n + 2 N)`` rows without ``third_bar`` (``6N + 3`` and ``6N + 2``: still A02's
  mobility), ``9N + 3`` coordinates and ``10N + 2`` rows with it (``N`` rows redundant on the manifold).

Coordinates: each bar's centre of mass and angle ``(x, y, θ)``, bars in chain order: crank 1, then for each cell its
coupler and its ``w`` further cranks (A02: crank 1, coupler 1, crank 2). A point of a bar at the signed offset ``s``
from its centre along its axis is ``(x, y) + s (cos θ, sin θ)``; each pin is two rows (``pin NAME[0]``, ``[1]``)
equating two such points, or a point and a ground pin.

One-DOF reference. On the manifold every crank has the same angle ``θ`` and every coupler translates (angle 0) with
the crank tips' velocity ``l θ̇ (−sin θ, cos θ)``. With cranks rotating about their ground pins (moment ``m l²/3``)

    ``T = ½ I θ̇²,  I = n m l²/3 + N w m l²``,      ``V = G sin θ,  G = g (n m l/2 + N w m l)``,

so ``I θ̈ = −G cos θ``, solved by DOP853 at ``rtol = atol = 1e-13`` (:func:`one_dof_reference`). Initially
``θ = π/2`` (cranks vertical, couplers at height ``l``) and ``θ̇ = −1`` rad/s: the tips move at 1 m/s along ``+x``.
The crank turns over and over and first lies on the ground line (``θ = 0``) at ``t ≈ 0.7085`` s for A02.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from ..errors import InputError
from ..model.constraints import Holonomic
from ..model.mechanism import Lagrangian
from ..model.model import Model
from .scene import Scene, numbered

#: One bar's coordinates: its centre of mass and its angle from the x axis.
BAR = ("x (m)", "y (m)", "θ (rad)")


def bars(cells: int, third_bar: bool) -> list[tuple[str, int]]:
    """The bars in ``q`` order, as ``("crank", j)`` or ``("coupler", k)`` (0-based): crank 0, then each cell's
    coupler and its ``w`` further cranks."""
    w = 2 if third_bar else 1
    order = [("crank", 0)]
    for k in range(cells):
        order += [("coupler", k)] + [("crank", k * w + i) for i in range(1, w + 1)]
    return order


def one_dof(
    cells: int = 1, third_bar: bool = False, l: float = 1.0, m: float = 1.0, g: float = 9.81
) -> tuple[float, float]:
    """``(I, G)`` of the one-DOF model ``I θ̈ = −G cos θ`` (module docstring)."""
    w = 2 if third_bar else 1
    n = w * cells + 1
    return n * m * l**2 / 3 + cells * w * m * l**2, g * (n * m * l / 2 + cells * w * m * l)


def maximal_state(
    theta: float, omega: float, alpha: float = 0.0, cells: int = 1, third_bar: bool = False, l: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, v, a)`` in maximal coordinates for cranks at ``θ``, ``θ̇ = omega``, ``θ̈ = alpha`` (couplers translating).

    A crank's centre is ``(j l, 0) + (l/2) e(θ)``, a coupler's ``(k w l + w l/2, 0) + l e(θ)``; a centre at
    ``b + r e(θ)`` moves at ``r θ̇ e⊥(θ)`` and accelerates at ``r (θ̈ e⊥(θ) − θ̇² e(θ))``, ``e⊥ = (−sin θ, cos θ)``.
    """
    w = 2 if third_bar else 1
    e, ep = np.array([np.cos(theta), np.sin(theta)]), np.array([-np.sin(theta), np.cos(theta)])
    q, v, a = [], [], []
    for kind, j in bars(cells, third_bar):
        base, r, turns = (j * l, l / 2, 1.0) if kind == "crank" else ((j * w + w / 2) * l, l, 0.0)
        q += [base + r * e[0], r * e[1], turns * theta]
        v += [*(r * omega * ep), turns * omega]
        a += [*(r * (alpha * ep - omega**2 * e)), turns * alpha]
    return np.array(q), np.array(v), np.array(a)


def one_dof_reference(
    t: Any,
    cells: int = 1,
    third_bar: bool = False,
    l: float = 1.0,
    m: float = 1.0,
    g: float = 9.81,
    theta0: float = np.pi / 2,
    omega0: float = -1.0,
    t_end: float | None = None,
) -> tuple[Any, Any]:
    """The cranks' ``θ(t)`` and ``θ̇(t)`` (scalars, or arrays like ``t ≥ 0``) from ``I θ̈ = −G cos θ`` by DOP853 at
    ``rtol = atol = 1e-13``. ``t_end`` is not used: it lets ``one_dof_reference(t, **scene.params)`` be written."""
    inertia, moment = one_dof(cells, third_bar, l, m, g)
    times = np.atleast_1d(np.asarray(t, float))
    if times.size and not times.min() >= 0:
        raise InputError(f"parallelogram: the reference starts at t = 0, got t = {times.min()}")
    y = np.tile(np.array([[theta0], [omega0]], float), (1, times.size))
    later = times > 0
    if later.any():
        grid, back = np.unique(times[later], return_inverse=True)
        sol = solve_ivp(
            lambda _t, s: [s[1], -moment * np.cos(s[0]) / inertia],
            (0.0, grid[-1]),
            [theta0, omega0],
            method="DOP853",
            t_eval=grid,
            rtol=1e-13,
            atol=1e-13,
        )
        y[:, later] = sol.y[:, back]
    if np.ndim(t) == 0:
        return float(y[0, 0]), float(y[1, 0])
    return y[0].reshape(np.shape(t)), y[1].reshape(np.shape(t))


def collinear_times(
    t_end: float = 10.0,
    cells: int = 1,
    third_bar: bool = False,
    l: float = 1.0,
    m: float = 1.0,
    g: float = 9.81,
    theta0: float = np.pi / 2,
    omega0: float = -1.0,
) -> np.ndarray:
    """The instants in ``(0, t_end]`` when the cranks lie on the ground line (``sin θ = 0``), by the one-DOF model:
    ``collinear_times(**scene.params)``."""
    inertia, moment = one_dof(cells, third_bar, l, m, g)

    def event(_t: float, s: np.ndarray) -> float:
        return float(np.sin(s[0]))

    sol = solve_ivp(
        lambda _t, s: [s[1], -moment * np.cos(s[0]) / inertia],
        (0.0, t_end),
        [theta0, omega0],
        method="DOP853",
        events=event,
        rtol=1e-13,
        atol=1e-13,
    )
    return sol.t_events[0]


def build(
    cells: int = 1,
    third_bar: bool = False,
    l: float = 1.0,
    m: float = 1.0,
    g: float = 9.81,
    theta0: float = np.pi / 2,
    omega0: float = -1.0,
    t_end: float = 10.0,
) -> Scene:
    """Parallelogram linkage in maximal coordinates: IFToMM A02, the double parallelogram (redundant), a ladder.

    Parameters
    ----------
    cells : int
        Number of cells chained along x; 1: A02, or the double parallelogram with ``third_bar`` (-).
        Allowed: integer ≥ 1.
    third_bar : bool
        Whether each cell is a double parallelogram: a third crank and a coupler of length ``2 l``, one row
        redundant at every state (-). Allowed: True or False.
    l : float
        Length of a crank, and of a coupler without ``third_bar`` (m). Allowed: > 0.
    m : float
        Mass of a crank: every bar has mass ``m`` per length ``l`` (kg). Allowed: > 0.
    g : float
        Gravitational acceleration, along ``−y`` (m/s²). Allowed: any finite number; physically > 0 (the sign
        is not checked).
    theta0 : float
        Initial angle of the cranks from the ground line; π/2: vertical (rad). Allowed: any finite number.
    omega0 : float
        Initial angular velocity of the cranks (rad/s). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    _check(cells, third_bar, l, m, g, theta0, omega0, t_end)
    w = 2 if third_bar else 1
    order = bars(cells, third_bar)
    lengths = [l if kind == "crank" else w * l for kind, _ in order]
    model = Model(_bodies(lengths, [m * length / l for length in lengths], g), _pins(cells, third_bar, l))
    q0, v0, _ = maximal_state(theta0, omega0, 0.0, cells, third_bar, l)
    what = "A02 parallelogram" if cells == 1 and not third_bar else "double parallelogram" if cells == 1 else None
    what = what or f"ladder of {cells} {'double ' if third_bar else ''}parallelogram cells"
    return Scene(
        name="parallelogram",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=numbered(BAR, len(order)),
        lam0=None,
        t_end=float(t_end),
        exact=None,
        drawing=drawing(lengths, [j * l for j in range(w * cells + 1)]),
        description=(
            f"{what} in maximal coordinates ({model.nq} coordinates, {model.k} pin rows), passing collinear "
            "positions; reference: the one-DOF crank equation"
        ),
        params=dict(cells=cells, third_bar=third_bar, l=l, m=m, g=g, theta0=theta0, omega0=omega0, t_end=t_end),
        singular_positions=True,
    )


def _check(cells: Any, third_bar: Any, l: Any, m: Any, g: Any, theta0: Any, omega0: Any, t_end: Any) -> None:
    """A positive whole number of cells, a boolean, positive lengths, mass and horizon, finite numbers."""
    if isinstance(cells, bool) or not isinstance(cells, (int, np.integer)) or cells < 1:
        raise InputError(f"parallelogram: cells must be a positive integer, got {cells!r}")
    if not isinstance(third_bar, (bool, np.bool_)):
        raise InputError(f"parallelogram: third_bar must be True or False, got {third_bar!r}")
    for name, value in (("l", l), ("m", m), ("t_end", t_end), ("g", g), ("theta0", theta0), ("omega0", omega0)):
        if not (isinstance(value, (int, float, np.floating, np.integer)) and np.isfinite(value)):
            raise InputError(f"parallelogram: {name} must be a finite number, got {value!r}")
        if name in ("l", "m", "t_end") and not value > 0:
            raise InputError(f"parallelogram: {name} must be positive, got {value!r}")


def _bodies(lengths: list[float], masses: list[float], g: float) -> Lagrangian:
    """Free bars: ``T = Σ ½ mᵢ (ẋᵢ² + ẏᵢ²) + ½ (mᵢ lᵢ²/12) θ̇ᵢ²``, ``V = Σ mᵢ g yᵢ``."""

    def kinetic(q: Any, v: Any, t: Any) -> Any:
        return sum(
            0.5 * mi * (v[3 * i] ** 2 + v[3 * i + 1] ** 2) + 0.5 * mi * li**2 / 12 * v[3 * i + 2] ** 2
            for i, (li, mi) in enumerate(zip(lengths, masses, strict=True))
        )

    def potential(q: Any, t: Any) -> Any:
        return sum(mi * g * q[3 * i + 1] for i, mi in enumerate(masses))

    return Lagrangian(n=3 * len(lengths), T=kinetic, V=potential)


def point(q: Any, bar: int, s: float) -> Any:
    """The point of ``bar`` (its index in ``q``) at offset ``s`` from its centre: ``(x, y) + s (cos θ, sin θ)``."""
    x, y, theta = q[3 * bar], q[3 * bar + 1], q[3 * bar + 2]
    return ca.vertcat(x + s * ca.cos(theta), y + s * ca.sin(theta))


def _pin(name: str, first: tuple[int, float], to: tuple[int, float] | None, ground: float = 0.0) -> Holonomic:
    """Two rows: the point ``first = (bar, s)`` (:func:`point`) on the point ``to`` of another bar, or on the ground
    pin ``(ground, 0)``."""
    if to is None:
        return Holonomic(lambda q, t: point(q, *first) - ca.vertcat(ground, 0.0), name=name)
    return Holonomic(lambda q, t: point(q, *first) - point(q, *to), name=name)


def _pins(cells: int, third_bar: bool, l: float) -> list[Holonomic]:
    """Each crank's base on its ground pin, each coupler's pins on its cranks' tips, in chain order."""
    w = 2 if third_bar else 1
    index = {bar: i for i, bar in enumerate(bars(cells, third_bar))}
    pins = [_pin("pin ground-crank1", (0, -l / 2), None, 0.0)]
    for k in range(cells):
        coupler = index["coupler", k]
        for i in range(w + 1):
            j = k * w + i
            crank = index["crank", j]
            pins.append(_pin(f"pin crank{j + 1}-coupler{k + 1}", (coupler, (i - w / 2) * l), (crank, l / 2)))
            if i:
                pins.append(_pin(f"pin ground-crank{j + 1}", (crank, -l / 2), None, j * l))
    return pins


def drawing(lengths: list[float], ground: list[float]) -> Callable[[np.ndarray], dict[str, Any]]:
    """What to draw at ``q`` (:attr:`Scene.drawing`): every bar, the cranks' tips, the ground pins and line."""
    pins = [np.array([x, 0.0]) for x in ground]

    def draw(q: np.ndarray) -> dict[str, Any]:
        b = np.reshape(np.asarray(q, float), (-1, 3))
        half = 0.5 * np.asarray(lengths)[:, None] * np.column_stack([np.cos(b[:, 2]), np.sin(b[:, 2])])
        return {"segments": list(zip(b[:, :2] - half, b[:, :2] + half, strict=True)), "points": list(b[:, :2]),
                "fixed": pins, "ground": [(pins[0], pins[-1])]}  # fmt: skip

    return draw
