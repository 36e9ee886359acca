"""Figures (matplotlib, an optional extra: ``pip install gausspp[plots]``).

Every function returns a matplotlib :class:`~matplotlib.figure.Figure`; saving and showing it
are the caller's choice. A non-interactive backend (Agg) is used when no display is available.
matplotlib is imported only when a figure is drawn; the number crunching behind the figures
(:func:`realizability_grid`, :func:`three_realizations_runs`, :func:`skate_runs`) needs only numpy.

Figures
-------
trajectory          ``q(t)``, ``v(t)`` and optionally the phase portrait ``(qᵢ, vᵢ)``
reaction_over_time  ``u(t)`` (``λ`` or ``λ̇``), compulsion ``Z(t)`` and the realizability margin
contacts            gaps ``g(t)``, contact forces and energy of a run with unilateral contacts
realizability_map   the margin of a servo torque along ``n`` over the sphere of directions ``n``
three_realizations  one constraint ``(ω, l) = 0`` kept ideally, by a servo torque, by a flywheel
skate               the nonholonomic and the vakonomic skate in the plane
verification        the minimizing variation ``δx(t)`` of the integral principle (23)
work_precision      error against run time (the study of :mod:`gausspp.report`)
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import GaussppError, InputError, ShapeError
from .scenes._rigid import inertia_matrix, unit_vector

if TYPE_CHECKING:
    from .model.model import Model
    from .simulation.trajectory import Trajectory
    from .studies.report import Row
    from .verification.integral import Verification

#: Line styles that tell runs apart when several are drawn on one axes (colours tell components).
_STYLES = ("-", "--", ":", "-.")
#: The models' default warning level of the realizability margin (``Model(margin_warn=...)``).
_MARGIN_WARN = 1e-6


def _pyplot() -> Any:
    try:
        import matplotlib
    except ImportError:
        raise GaussppError("plots need matplotlib: pip install 'gausspp[plots]'") from None
    if not os.environ.get("DISPLAY") and "MPLBACKEND" not in os.environ:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _runs(obj: Any, what: str) -> dict[str, Any]:
    """One object or a mapping ``label → object`` as a dict (label ``""`` for a lone object)."""
    if isinstance(obj, Mapping):
        if not obj:
            raise InputError(f"nothing to plot: the mapping of {what} is empty")
        return {str(k): v for k, v in obj.items()}
    return {"": obj}


def _labels(given: Sequence[str] | None, n: int, symbol: str) -> list[str]:
    if given is None:
        return [f"${symbol}_{{{i + 1}}}$" for i in range(n)]
    labels = [str(s) for s in given]
    if len(labels) != n:
        raise ShapeError(f"{symbol}_labels: {n} labels needed, got {len(labels)}")
    return labels


def _suffix(name: str, traj: Any = None) -> str:
    failed = traj is not None and getattr(traj, "status", "success") != "success"
    tail = f"failed at t={traj.t[-1]:.3g}" if failed else ""
    inner = ", ".join(s for s in (name, tail) if s)
    return f" ({inner})" if inner else ""


def _legend(ax: Any) -> None:
    """A legend sized to the number of labelled artists (none if there are none)."""
    n = len(ax.get_legend_handles_labels()[1])
    if n:
        ax.legend(fontsize=8 if n <= 8 else 6, ncol=1 if n <= 6 else 2, loc="best")


# -- trajectories --------------------------------------------------------------------------------
def trajectory(
    traj: Trajectory | Mapping[str, Trajectory],
    *,
    phase: bool = False,
    q_labels: Sequence[str] | None = None,
    v_labels: Sequence[str] | None = None,
    title: str | None = None,
) -> Any:
    """Coordinates and velocities over time, and optionally the phase portrait.

    Draws ``q_i(t)`` and ``v_i(t)`` (``v = q̇``, or the quasi-velocities ``ω`` of a rigid body) in
    two panels; with ``phase=True`` a third panel draws each pair ``(q_i(t), v_i(t))``, the
    projection of the motion onto the phase plane of coordinate ``i``, with its start marked.

    Parameters
    ----------
    traj : Trajectory or mapping of str to Trajectory
        One run, or several (e.g. ``{"rod": a, "servo": b}``) drawn with one line style each;
        components keep their colour across runs. All runs must have the same ``nq`` and ``nv``.
    phase : bool
        Add the phase portrait; needs ``nq == nv`` (not a rigid body's quaternion and ``ω``).
    q_labels, v_labels : sequence of str, optional
        Names of the components (default ``q₁…``, ``v₁…``).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Two axes (``q``, ``v``), three with ``phase``.
    """
    plt = _pyplot()
    runs = _runs(traj, "trajectories")
    first = next(iter(runs.values()))
    nq, nv = first.q.shape[1], first.v.shape[1]
    for name, tr in runs.items():
        if tr.q.shape[1] != nq or tr.v.shape[1] != nv:
            raise ShapeError(f"trajectory {name!r}: nq, nv = {tr.q.shape[1]}, {tr.v.shape[1]}; expected {nq}, {nv}")
    if phase and nq != nv:
        raise InputError(
            f"phase=True draws v_i against q_i and needs nq == nv; these runs have nq={nq}, nv={nv} "
            "(a rigid body: quaternion and ω) — draw them over time instead"
        )
    ql, vl = _labels(q_labels, nq, "q"), _labels(v_labels, nv, "v")
    ncols = 3 if phase else 2
    fig, axes = plt.subplots(1, ncols, figsize=(4.8 * ncols, 4.0), layout="constrained")
    colors = plt.get_cmap("tab10")
    for r, (name, tr) in enumerate(runs.items()):
        ls, sfx = _STYLES[r % len(_STYLES)], _suffix(name, tr)
        for i in range(nq):
            axes[0].plot(tr.t, tr.q[:, i], ls, color=colors(i % 10), label=ql[i] + sfx)
        for i in range(nv):
            axes[1].plot(tr.t, tr.v[:, i], ls, color=colors(i % 10), label=vl[i] + sfx)
        if phase:
            for i in range(nq):
                axes[2].plot(tr.q[:, i], tr.v[:, i], ls, color=colors(i % 10), label=f"({ql[i]}, {vl[i]}){sfx}")
                axes[2].plot(tr.q[0, i], tr.v[0, i], "o", color=colors(i % 10), ms=4)
    axes[0].set(xlabel="time t", ylabel="coordinates q", title="coordinates over time")
    axes[1].set(xlabel="time t", ylabel="velocities v", title="velocities over time")
    if phase:
        axes[2].set(xlabel="coordinate $q_i$", ylabel="velocity $v_i$", title="phase portrait (start: dot)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        _legend(ax)
    if title:
        fig.suptitle(title)
    return fig


def reaction_over_time(traj: Trajectory | Mapping[str, Trajectory], *, title: str | None = None) -> Any:
    """The reaction's unknowns, Gauss's compulsion and the realizability margin over time.

    Three panels sharing the time axis:

    1. ``u(t)``, the step's unknowns in ``A ẍ + h = F + r₀ + D u``: ``λ`` for ideal and force
       realizations (the reaction is ``Jᵀλ``, resp. ``Mᵀλ``, eqs. (4), (10)), ``λ̇`` for flywheel
       realizations (eq. (15)), whose state ``λ(t)`` is drawn too (thin, translucent);
    2. the compulsion ``Z = (A(ẍ − a₀), ẍ − a₀)``, ``a₀ = A⁻¹(F − h + r₀)`` the released
       acceleration — what the reaction costs in Gauss's measure;
    3. the realizability margin (log scale): the smallest singular value of ``S = J A⁻¹ D``
       normalized in the metric ``A⁻¹``, 1 for ideal constraints, 0 where the realization cannot
       keep the constraint (conditions (12), (16)); the dotted line is the default warning level.

    Parameters
    ----------
    traj : Trajectory or mapping of str to Trajectory
        One run or several, told apart by line style.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Three axes: ``u``, ``Z``, margin.
    """
    plt = _pyplot()
    runs = _runs(traj, "trajectories")
    fig, axes = plt.subplots(3, 1, figsize=(8.0, 7.5), sharex=True, layout="constrained")
    colors = plt.get_cmap("tab10")
    lowest = 1.0
    for r, (name, tr) in enumerate(runs.items()):
        ls, sfx = _STYLES[r % len(_STYLES)], _suffix(name, tr)
        for j in range(tr.u.shape[1]):
            axes[0].plot(tr.t, tr.u[:, j], ls, color=colors(j % 10), label=f"$u_{{{j + 1}}}${sfx}")
        for j in range(tr.lam.shape[1]):
            axes[0].plot(
                tr.t,
                tr.lam[:, j],
                ls,
                color=colors(j % 10),
                lw=0.8,
                alpha=0.5,
                label=f"state $\\lambda_{{{j + 1}}}${sfx}",
            )
        axes[1].plot(tr.t, tr.compulsion, ls, color="k" if len(runs) == 1 else colors(r % 10), label=f"Z{sfx}")
        margin = np.asarray(tr.margin, float)
        shown = np.maximum(margin, 1e-17)
        lowest = min(lowest, float(np.nanmin(shown)) if shown.size else 1.0)
        axes[2].semilogy(tr.t, shown, ls, color="k" if len(runs) == 1 else colors(r % 10), label=f"margin{sfx}")
    axes[2].axhline(_MARGIN_WARN, color="tab:red", ls=":", lw=1, label=f"default warning level {_MARGIN_WARN:g}")
    axes[2].set_ylim(min(lowest / 3, _MARGIN_WARN / 10), 2.0)
    axes[0].set(ylabel="u", title=r"reaction unknowns $u$: $\lambda$ (ideal, force) or $\dot\lambda$ (flywheel)")
    axes[1].set(ylabel="Z", title=r"compulsion $Z = (A(\ddot x - a_0), \ddot x - a_0)$")
    axes[2].set(xlabel="time t", ylabel="margin", title="realizability margin (0: the realization cannot act)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        _legend(ax)
    if title:
        fig.suptitle(title)
    return fig


# -- contacts ----------------------------------------------------------------------------------------
def contacts(model: Model, traj: Trajectory, *, title: str | None = None) -> Any:
    """Gaps, contact forces and energy of a run with unilateral contacts (``gp.Unilateral``).

    Three panels sharing the time axis:

    1. every contact row's gap ``g(t)`` (linear scale; the floor ``g = 0`` dotted), with the
       contact events marked on it at ``g = 0`` in the row's colour: impacts ``▼``, plastic
       impacts ``■`` (``e = 0``: slower than ``rest_speed``, the last impact of a Zeno sequence
       that ends in rest, or a resting contact that takes part in another contact's impact),
       lift-offs ``▲``, touches without impact ``○``;
    2. the contact forces ``traj.contact_force`` (``≥ 0``; zero in flight — the impulses of the
       impacts are not drawn);
    3. the total energy ``E(t)`` and, as a step line, the kinetic energy lost at impacts, summed
       over the velocity jumps (simultaneous impacts of several rows are one jump, counted once);
       their sum ``E + lost`` (dotted) is constant when nothing else does work.

    The markers of panel 1 are ``Line2D`` artists with ``gid`` ``"impact"``,
    ``"plastic impact"``, ``"lift-off"`` or ``"touch"``: one per row and kind, one point per event.

    Parameters
    ----------
    model : Model
        The model that was simulated (it knows the gaps and the rows' names).
    traj : Trajectory
        Its run by :func:`gausspp.simulate` (event by event).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Three axes: gaps, forces, energy.
    """
    from .simulation.contacts import _gaps

    names = [str(s) for s in getattr(model, "contact_row_names", [])]
    if not names:
        raise InputError(
            "the model has no unilateral contacts (gp.Unilateral): no gaps or contact forces to draw; "
            "use plot.trajectory or plot.reaction_over_time"
        )
    N, n = int(np.size(traj.t)), len(names)
    if N == 0:
        raise InputError("the trajectory has no samples")
    for attr, want in {"t": (N,), "q": (N, model.nq), "v": (N, model.nv), "contact_force": (N, n)}.items():
        got = tuple(np.shape(getattr(traj, attr)))
        if got != want:
            raise ShapeError(
                f"traj.{attr} has shape {got}, expected {want} ({N} samples, contact rows {names}): "
                "is this a run of this model?"
            )
    unknown = sorted({str(ev.get("contact")) for ev in traj.events if ev.get("contact") not in names})
    if unknown:
        raise InputError(f"traj.events name contacts {unknown} that the model does not have ({names})")
    plt = _pyplot()
    from matplotlib.lines import Line2D

    t = np.asarray(traj.t, float)
    gaps = np.array([_gaps(model, t[k], traj.q[k], traj.v[k])[0] for k in range(N)]).reshape(N, n)
    fig, (gap_ax, force_ax, energy_ax) = plt.subplots(3, 1, figsize=(8.0, 8.0), sharex=True, layout="constrained")
    colors = plt.get_cmap("tab10")
    for i, name in enumerate(names):
        gap_ax.plot(t, gaps[:, i], color=colors(i % 10), lw=1.2, label=f"gap of {name}")
        force_ax.plot(t, traj.contact_force[:, i], color=colors(i % 10), lw=1.2, label=f"force on {name}")
    gap_ax.axhline(0.0, color="k", ls=":", lw=0.8)

    kinds = {  # gid: marker, filled, legend text
        "impact": ("v", True, "impact"),
        "plastic impact": ("s", True, "plastic impact (e = 0: ends in rest)"),
        "lift-off": ("^", True, "lift-off"),
        "touch": ("o", False, "touch (no impact)"),
    }

    def kind(ev: Mapping[str, Any]) -> str:
        return "plastic impact" if ev.get("kind") == "impact" and ev.get("plastic") else str(ev.get("kind"))

    handles = gap_ax.get_legend_handles_labels()[0]
    for gid, (marker, filled, text) in kinds.items():
        for i, name in enumerate(names):
            times = [float(ev["t"]) for ev in traj.events if ev.get("contact") == name and kind(ev) == gid]
            if times:
                c = colors(i % 10)
                mfc = c if filled else "none"
                style = dict(marker=marker, ls="none", ms=6, mec="k", mew=0.6, mfc=mfc, color=c)
                gap_ax.plot(times, np.zeros(len(times)), gid=gid, zorder=3, **style)
        if any(kind(ev) == gid for ev in traj.events):
            handles.append(
                Line2D([], [], marker=marker, ls="none", mec="k", mfc="0.6" if filled else "none", label=text)
            )
    gap_ax.legend(handles=handles, fontsize=8, loc="upper right")
    gap_ax.set(ylabel="gap g", title="gaps g(t) of the contacts (g ≥ 0; events marked at g = 0)")
    force_ax.set(ylabel="contact force", title="contact forces (multipliers ≥ 0; zero in flight)")

    # the energy the velocity jumps took: the events of one jump share t and the kinetic energies
    jumps: dict[tuple[float, float, float], float] = {}
    for ev in traj.events:
        if ev.get("kind") == "impact":
            before, after = float(ev["kinetic_energy_before"]), float(ev["kinetic_energy_after"])
            jumps[(float(ev["t"]), before, after)] = before - after
    energy = np.asarray(traj.energy, float)
    if energy.shape == (N,) and np.all(np.isfinite(energy)):
        energy_ax.plot(t, energy, color="k", lw=1.2, label="total energy E")
        lost_by_sample = np.zeros(N)
        repeated = np.flatnonzero(np.diff(t) == 0.0) + 1  # a sample after a jump shares the time of the one before
        start = 0
        for (tj, _before, _after), loss in jumps.items():
            after_jump = repeated[(repeated >= start) & (t[repeated] == tj)]
            start = int(after_jump[0]) if after_jump.size else int(np.searchsorted(t, tj, side="right"))
            lost_by_sample[start:] += loss
            start += 1
        energy_ax.plot(t, energy + lost_by_sample, color="0.45", ls=":", lw=1.2, label="E + lost at impacts")
    losses = list(jumps.values())
    energy_ax.step(
        [t[0], *(key[0] for key in jumps), t[-1]],
        [0.0, *np.cumsum(losses), float(np.sum(losses))],
        where="post",
        color="tab:red",
        lw=1.2,
        label=f"kinetic energy lost at impacts ({len(jumps)} jumps)",
    )
    energy_ax.set(xlabel="time t", ylabel="energy", title="energy, and the kinetic energy lost at impacts")
    for ax in (gap_ax, force_ax, energy_ax):
        ax.grid(True, alpha=0.3)
    _legend(force_ax)
    _legend(energy_ax)
    fig.suptitle((title or "Unilateral contacts") + _suffix("", traj))
    return fig


# -- the realizability map ------------------------------------------------------------------------
@dataclass(frozen=True)
class RealizabilityGrid:
    """The numbers behind :func:`realizability_map`.

    Attributes
    ----------
    inertia : (3, 3) array
        The body's inertia tensor ``I`` (body axes).
    l : (3,) array
        Unit normal of the constraint ``(ω, l) = 0``.
    lon, lat : (n_lon,), (n_lat,) arrays
        Longitudes in ``[−180°, 180°]`` and latitudes in ``[−90°, 90°]`` of the grid, degrees.
    n : (n_lat, n_lon, 3) array
        The unit torque axes ``n = (cos φ cos ψ, cos φ sin ψ, sin φ)`` (``φ`` latitude, ``ψ`` longitude).
    margin : (n_lat, n_lon) array
        The realizability margin of the servo torque along ``n``.
    pole : (3,) array
        ``I⁻¹l / |I⁻¹l|``: the true zero set is the great circle ``(n, pole) = 0``.
    true_circle, naive_circle : (m, 3) arrays
        Unit vectors on the true zero set ``(I⁻¹n, l) = 0`` and on the naive circle ``n ⟂ l``.
    true_margin, naive_margin : (m,) arrays
        The margin along them.
    """

    inertia: np.ndarray
    l: np.ndarray
    lon: np.ndarray
    lat: np.ndarray
    n: np.ndarray
    margin: np.ndarray
    pole: np.ndarray
    true_circle: np.ndarray
    naive_circle: np.ndarray
    true_margin: np.ndarray
    naive_margin: np.ndarray

    @property
    def principal(self) -> bool:
        """True if ``l`` is a principal axis (``I⁻¹l ∥ l``): then both circles coincide."""
        return bool(np.linalg.norm(np.cross(self.pole, self.l)) < 1e-12)


def _inertia(inertia: Any) -> np.ndarray:
    arr = inertia_matrix("plot", inertia)
    if not (np.all(np.isfinite(arr)) and np.allclose(arr, arr.T)) or np.linalg.eigvalsh(arr).min() <= 0:
        raise InputError(f"inertia must be symmetric positive definite, got {arr.tolist()}")
    return arr


def _unit(name: str, value: Any) -> np.ndarray:
    return unit_vector("plot", name, value)


def servo_margin(inertia: Any, l: Any, n: Any) -> np.ndarray:
    """Realizability margin of a servo torque along ``n`` keeping ``(ω, l) = 0``, for many ``n`` at once.

    With ``A = I``, ``J = lᵀ`` and ``D = n`` (paper §2, condition (12)) the margin of
    :func:`gausspp.realizability.margin` is the cosine of the angle between ``l`` and ``n`` in
    the metric ``I⁻¹``:

        margin(n) = |(I⁻¹n, l)| / √((I⁻¹l, l) (I⁻¹n, n)),

    zero exactly on the great circle ``(n, I⁻¹l) = 0``.

    Parameters
    ----------
    inertia : (3,) or (3, 3) array
    l : (3,) array
    n : (..., 3) array
        Torque axes (need not be unit vectors).

    Returns
    -------
    (...) array
    """
    I = _inertia(inertia)
    lv = _unit("l", l)
    nv = np.asarray(n, dtype=float)
    if nv.shape[-1:] != (3,):
        raise ShapeError(f"n must have 3 components in its last axis, got shape {nv.shape}")
    Il = np.linalg.solve(I, lv)
    In = np.linalg.solve(I, nv.reshape(-1, 3).T).T.reshape(nv.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.abs(nv @ Il) / np.sqrt((lv @ Il) * np.einsum("...i,...i->...", nv, In))
    return np.nan_to_num(out, nan=0.0)


def _great_circle(normal: np.ndarray, m: int) -> np.ndarray:
    """``m`` unit vectors on the great circle ``(n, normal) = 0``."""
    e1 = np.cross(normal, np.eye(3)[int(np.argmin(np.abs(normal)))])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    s = np.linspace(0.0, 2 * np.pi, m, endpoint=False)
    return np.outer(np.cos(s), e1) + np.outer(np.sin(s), e2)


def realizability_grid(
    inertia: Any = (1.0, 2.0, 3.0), l: Any = (1.0, 1.0, 1.0), resolution: float = 1.0, circle_points: int = 720
) -> RealizabilityGrid:
    """The realizability margin of a servo torque along ``n`` over the sphere of directions ``n``.

    A rigid body about a fixed point must keep ``(ω, l) = 0`` by a torque ``λn`` along a body
    axis ``n`` (Béghin realization, paper §2). The step is solvable iff ``(I⁻¹n, l) ≠ 0``
    (condition (12)): the bad axes form the great circle ``n ⟂ I⁻¹l``. The paper calls them
    "``n`` orthogonal to ``l``", which is the same circle only when ``l`` is a principal axis
    (``I⁻¹l ∥ l``). See :func:`servo_margin` for the margin.

    Parameters
    ----------
    inertia : (3,) or (3, 3) array
        Principal moments or an inertia tensor (symmetric positive definite).
    l : (3,) array
        The constraint's normal (normalized here).
    resolution : float
        Grid step in degrees of longitude and latitude.
    circle_points : int
        Points on each of the two circles.

    Returns
    -------
    RealizabilityGrid
    """
    I, lv = _inertia(inertia), _unit("l", l)
    if not (np.isfinite(resolution) and 0 < resolution <= 30):
        raise InputError(f"resolution is a grid step in degrees, 0 < resolution ≤ 30; got {resolution}")
    lon = np.linspace(-180.0, 180.0, int(round(360 / resolution)) + 1)
    lat = np.linspace(-90.0, 90.0, int(round(180 / resolution)) + 1)
    LON, LAT = np.meshgrid(np.radians(lon), np.radians(lat))
    n = np.stack([np.cos(LAT) * np.cos(LON), np.cos(LAT) * np.sin(LON), np.sin(LAT)], axis=-1)
    pole = _unit("I⁻¹l", np.linalg.solve(I, lv))
    true_circle, naive_circle = _great_circle(pole, circle_points), _great_circle(lv, circle_points)
    return RealizabilityGrid(
        inertia=I,
        l=lv,
        lon=lon,
        lat=lat,
        n=n,
        margin=servo_margin(I, lv, n),
        pole=pole,
        true_circle=true_circle,
        naive_circle=naive_circle,
        true_margin=servo_margin(I, lv, true_circle),
        naive_margin=servo_margin(I, lv, naive_circle),
    )


def _lonlat(v: np.ndarray) -> tuple[float, float]:
    return float(np.degrees(np.arctan2(v[1], v[0]))), float(np.degrees(np.arcsin(np.clip(v[2], -1, 1))))


def _vec(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.3g}" for x in v) + ")"


def realizability_map(
    inertia: Any = (1.0, 2.0, 3.0),
    l: Any = (1.0, 1.0, 1.0),
    resolution: float = 1.0,
    *,
    floor: float = 1e-3,
    grid: RealizabilityGrid | None = None,
) -> Any:
    """Map of where a servo torque along ``n`` can keep ``(ω, l) = 0`` (paper §2, condition (12)).

    The colour is the realizability margin (log scale, clipped at ``floor``) of the torque axis
    ``n`` at each longitude/latitude, from :func:`realizability_grid`. Overlaid: the true zero set
    ``(I⁻¹n, l) = 0`` (solid red; the great circle with pole ``I⁻¹l``, marked ``+``) and the naive
    circle ``n ⟂ l`` (dashed white; pole ``l``, marked ``×``). For a non-principal ``l`` they
    differ: most axes with ``n ⟂ l`` are realizable, and some axes not orthogonal to ``l`` are not.

    Parameters
    ----------
    inertia : (3,) or (3, 3) array
    l : (3,) array
    resolution : float
        Grid step in degrees.
    floor : float
        Smallest margin shown (the colour scale's lower end).
    grid : RealizabilityGrid, optional
        Precomputed numbers (``inertia``, ``l`` and ``resolution`` are then ignored).

    Returns
    -------
    matplotlib.figure.Figure
        One map axes and its colour bar.
    """
    plt = _pyplot()
    from matplotlib.colors import LogNorm

    g = grid if grid is not None else realizability_grid(inertia, l, resolution)
    fig, ax = plt.subplots(figsize=(10, 5), layout="constrained")
    im = ax.pcolormesh(
        g.lon, g.lat, np.clip(g.margin, floor, 1.0), norm=LogNorm(vmin=floor, vmax=1.0), cmap="viridis", shading="auto"
    )
    fig.colorbar(im, ax=ax, label=r"realizability margin (cosine of $n$, $l$ in the metric $I^{-1}$)")
    ax.contour(g.lon, g.lat, g.n @ g.pole, [0.0], colors="red", linewidths=2.2)
    ax.contour(g.lon, g.lat, g.n @ g.l, [0.0], colors="white", linestyles="--", linewidths=1.6)
    for sign in (1, -1):
        ax.plot(*_lonlat(sign * g.pole), "+", color="red", ms=12, mew=2.5, clip_on=False, zorder=5)
        ax.plot(*_lonlat(sign * g.l), "x", color="white", ms=9, mew=2, clip_on=False, zorder=5)
    ax.plot([], [], "r-", lw=2.2, label=r"true zero set $(I^{-1}n, l) = 0$")
    ax.plot([], [], "w--", lw=1.6, label=r"naive circle $n \perp l$")
    ax.plot([], [], "r+", ms=10, mew=2, label=r"$\pm I^{-1}l$ (pole of the true set)")
    ax.plot([], [], "wx", ms=8, mew=2, label=r"$\pm l$ (pole of the naive circle)")
    ax.legend(loc="lower left", fontsize=8, facecolor="0.25", labelcolor="white", framealpha=0.85)
    moments = np.diag(g.inertia) if np.allclose(g.inertia, np.diag(np.diag(g.inertia))) else None
    inertia_text = f"I = diag{_vec(moments)}" if moments is not None else "I = full tensor"
    ax.set(
        xlabel="longitude of the torque axis n [°]",
        ylabel="latitude of n [°]",
        xlim=(-180, 180),
        ylim=(-90, 90),
        xticks=np.arange(-180, 181, 45),
        yticks=np.arange(-90, 91, 30),
        title=(
            f"Servo torque along n keeping (ω, l) = 0: l = {_vec(g.l)}, {inertia_text}\n"
            + (
                "l is a principal axis: the true zero set is the circle $n \\perp l$"
                if g.principal
                else f"median margin on the naive circle $n \\perp l$: {np.median(g.naive_margin):.2f} — not zero"
            )
        ),
    )
    return fig


# -- one constraint, three realizations -----------------------------------------------------------
#: Keys and legend labels of :func:`three_realizations_runs`.
THREE_LABELS = {
    "ideal": "Ideal: Suslov's constraint (reaction along l)",
    "force": "Force: servo torque along n",
    "inertial": "Inertial: flywheel on axis n",
}


def three_realizations_runs(
    inertia: Any = (1.0, 2.0, 3.0),
    l: Any = (1.0, 1.0, 1.0),
    n: Any = (0.0, 0.0, 1.0),
    omega0: Any = (0.0, 1.0, -1.0),
    lam0: float = 0.0,
    t_end: float = 10.0,
    samples: int = 401,
) -> dict[str, Trajectory]:
    """Simulate one rigid body and one constraint ``(ω, l) = 0`` kept in three ways, from one ``ω₀``.

    * ``"ideal"``: the scene ``rigid-body-servo`` with ``n = l`` — Suslov's nonholonomic problem,
      ``Iω̇ + ω × Iω = μ l`` (paper §2 with the reaction normal to the constraint);
    * ``"force"``: ``rigid-body-servo`` with the torque ``λn`` along ``n`` (Béghin servo, eq. (10));
    * ``"inertial"``: the scene ``gyrostat``, a rotor on axis ``n`` with angular momentum ``λ``,
      ``d/dt(Iω + λn) + ω × (Iω + λn) = 0`` (eqs. (14)–(15)), ``λ(0) = lam0``.

    The force and flywheel realizations need ``(I⁻¹n, l) ≠ 0`` (conditions (12), (16)).
    Integrated by DOP853 (``rtol = 1e-10``), recorded at ``samples`` uniform times.

    Returns
    -------
    dict of str to Trajectory
        Keys ``"ideal"``, ``"force"``, ``"inertial"``.
    """
    from . import scenes
    from .simulation.simulate import simulate

    common = dict(inertia=inertia, l=l, omega0=omega0, t_end=t_end)
    built = {
        "ideal": scenes.get("rigid-body-servo", n=None, **common),
        "force": scenes.get("rigid-body-servo", n=n, **common),
        "inertial": scenes.get("gyrostat", n=n, lam0=lam0, **common),
    }
    times = np.linspace(0.0, float(t_end), int(samples))
    return {
        key: simulate(s.model, s.q0, s.v0, s.t_end, lam0=s.lam0, method="DOP853", rtol=1e-10, atol=1e-12, record=times)
        for key, s in built.items()
    }


def _plane_basis(I: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An orthonormal basis ``(e₁, e₂)`` of ``(ω, l) = 0``, ``e₁ ∥ l × Il`` where that is nonzero."""
    d = np.cross(l, I @ l)
    if np.linalg.norm(d) < 1e-12 * np.linalg.norm(I):
        d = np.cross(l, np.eye(3)[int(np.argmin(np.abs(l)))])
    e1 = d / np.linalg.norm(d)
    return e1, np.cross(l, e1)


def three_realizations(
    inertia: Any = (1.0, 2.0, 3.0),
    l: Any = (1.0, 1.0, 1.0),
    n: Any = (0.0, 0.0, 1.0),
    omega0: Any = (0.0, 1.0, -1.0),
    lam0: float = 0.0,
    t_end: float = 10.0,
    *,
    runs: Mapping[str, Trajectory] | None = None,
) -> Any:
    """ "One constraint, three realizations": the same body and ``(ω, l) = 0``, three motions.

    Top row, one panel per realization: the body angular velocity ``ω(t)``. Bottom left: the
    three paths of ``ω`` in the constraint plane ``(ω, l) = 0`` (coordinates on ``e₁ ∥ l × Il``,
    ``e₂ = l × e₁``), with Suslov's attracting steady rotation ``ω∞ ∥ l × Il`` (see
    :mod:`gausspp.scenes.suslov`). Bottom right: the kinetic energy of the carrier
    ``½ (Iω, ω)``, conserved by the ideal constraint (its reaction does no work on motions that
    keep it) and changed by the servo torque and by the flywheel.

    Parameters
    ----------
    inertia, l, n, omega0, lam0, t_end
        As in :func:`three_realizations_runs`.
    runs : mapping, optional
        The result of :func:`three_realizations_runs` with the same parameters (else computed).

    Returns
    -------
    matplotlib.figure.Figure
        Five axes: three ``ω(t)`` panels, the constraint plane, the energy.
    """
    plt = _pyplot()
    from .scenes.suslov import steady_rotation

    I, lv = _inertia(inertia), _unit("l", l)
    nv = _unit("n", n)
    runs = dict(runs) if runs is not None else three_realizations_runs(inertia, l, n, omega0, lam0, t_end)
    missing = set(THREE_LABELS) - set(runs)
    if missing:
        raise InputError(f"runs must have the keys {list(THREE_LABELS)}; missing {sorted(missing)}")
    fig = plt.figure(figsize=(13, 8), layout="constrained")
    grid = fig.add_gridspec(2, 3)
    top = [fig.add_subplot(grid[0, 0])]
    top += [fig.add_subplot(grid[0, j], sharey=top[0]) for j in (1, 2)]
    plane, energy = fig.add_subplot(grid[1, :2]), fig.add_subplot(grid[1, 2])
    colors = plt.get_cmap("tab10")
    run_colors = {"ideal": "tab:blue", "force": "tab:orange", "inertial": "tab:green"}
    comp = [r"$\omega_1$", r"$\omega_2$", r"$\omega_3$"]
    e1, e2 = _plane_basis(I, lv)
    for ax, key in zip(top, THREE_LABELS, strict=True):
        tr = runs[key]
        for i in range(3):
            ax.plot(tr.t, tr.v[:, i], color=colors(i), label=comp[i])
        ax.set(xlabel="time t", title=THREE_LABELS[key] + _suffix("", tr))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
        w = tr.v
        c = run_colors[key]
        plane.plot(w @ e1, w @ e2, color=c, label=THREE_LABELS[key])
        plane.plot(w[-1] @ e1, w[-1] @ e2, "s", color=c, ms=6)
        energy.plot(tr.t, 0.5 * np.einsum("ti,ij,tj->t", w, I, w), color=c, label=key)
    top[0].set_ylabel("body angular velocity ω")
    w0 = runs["ideal"].v[0]
    plane.plot(w0 @ e1, w0 @ e2, "ko", ms=6, label="common start ω₀ (end: squares)")
    w_inf = steady_rotation(I, lv, w0)
    plane.plot(w_inf @ e1, w_inf @ e2, "*", color="tab:blue", ms=14, mec="k", label="Suslov's steady rotation ω∞")
    plane.set(
        xlabel=r"$(\omega, e_1)$,  $e_1 \parallel l \times Il$",
        ylabel=r"$(\omega, e_2)$,  $e_2 = l \times e_1$",
        title=f"ω in the constraint plane (ω, l) = 0: three motions (n = {_vec(nv)})",
    )
    plane.set_aspect("equal", adjustable="datalim")
    plane.grid(True, alpha=0.3)
    plane.legend(fontsize=8, loc="best")
    energy.set(xlabel="time t", ylabel=r"$\frac{1}{2}(I\omega, \omega)$", title="kinetic energy of the body")
    energy.grid(True, alpha=0.3)
    energy.legend(fontsize=8)
    fig.suptitle(f"The constraint (ω, l) = 0, l = {_vec(lv)}, kept three ways from the same ω₀ = {_vec(w0)}")
    return fig


# -- the skate ----------------------------------------------------------------------------------------
def skate_runs(
    m: float = 1.0,
    J: float = 0.1,
    v0: float = 1.0,
    omega0: float = 1.0,
    theta0: float = 0.0,
    lam0: float = 0.5,
    t_end: float = 10.0,
    samples: int = 501,
) -> dict[str, Trajectory]:
    """The skate (scene ``skate``) from the same initial data under both laws of motion.

    ``"nonholonomic"``: the ideal constraint ``−sin θ ẋ + cos θ ẏ = 0`` (reaction ``λ(−sin θ, cos θ, 0)``);
    ``"vakonomic"``: the same constraint, vakonomic (eqs. (17)–(18), ``λ(0) = lam0``).
    Integrated by DOP853 (``rtol = 1e-10``), recorded at ``samples`` uniform times.
    """
    from . import scenes
    from .simulation.simulate import simulate

    times = np.linspace(0.0, float(t_end), int(samples))
    out = {}
    for law in ("nonholonomic", "vakonomic"):
        s = scenes.get("skate", m=m, J=J, realization=law, v0=v0, omega0=omega0, theta0=theta0, lam0=lam0, t_end=t_end)
        out[law] = simulate(
            s.model, s.q0, s.v0, s.t_end, lam0=s.lam0, method="DOP853", rtol=1e-10, atol=1e-12, record=times
        )
    return out


def skate(
    m: float = 1.0,
    J: float = 0.1,
    v0: float = 1.0,
    omega0: float = 1.0,
    theta0: float = 0.0,
    lam0: float = 0.5,
    t_end: float = 10.0,
    *,
    runs: Mapping[str, Trajectory] | None = None,
) -> Any:
    """The nonholonomic and the vakonomic skate: one constraint, two laws of motion.

    Left: the contact point's paths ``(x(t), y(t))`` with the blade's heading ``θ`` drawn as
    arrows along them. The nonholonomic skate (d'Alembert–Lagrange) turns uniformly,
    ``θ̇ = ω₀``, and runs along a circle of radius ``v₀/ω₀``; the vakonomic one obeys
    ``J θ̈ = −(|p|²/2m) sin 2(α − θ)`` (a pendulum in ``θ``, see :mod:`gausspp.scenes.skate`).
    Right: the heading ``θ(t)``.

    Parameters
    ----------
    m, J, v0, omega0, theta0, lam0, t_end
        As in :func:`skate_runs` (the scene ``skate``).
    runs : mapping, optional
        The result of :func:`skate_runs` (else computed).

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the plane, the heading.
    """
    plt = _pyplot()
    runs = dict(runs) if runs is not None else skate_runs(m, J, v0, omega0, theta0, lam0, t_end)
    if set(runs) != {"nonholonomic", "vakonomic"}:
        raise InputError(f"runs must have the keys 'nonholonomic' and 'vakonomic', got {sorted(runs)}")
    fig, (ax, axt) = plt.subplots(1, 2, figsize=(12, 5), width_ratios=(1.3, 1), layout="constrained")
    style = {"nonholonomic": ("tab:blue", "nonholonomic (ideal)"), "vakonomic": ("tab:red", "vakonomic")}
    for law, tr in runs.items():
        color, label = style[law]
        x, y, th = tr.q[:, 0], tr.q[:, 1], tr.q[:, 2]
        ax.plot(x, y, color=color, label=label + _suffix("", tr))
        k = np.linspace(0, tr.t.size - 1, 16).astype(int)
        ax.quiver(x[k], y[k], np.cos(th[k]), np.sin(th[k]), color=color, angles="xy", scale=22, width=0.004)
        axt.plot(tr.t, th, color=color, label=label)
    ax.plot(runs["nonholonomic"].q[0, 0], runs["nonholonomic"].q[0, 1], "ko", label="start")
    ax.set(xlabel="x", ylabel="y", title="contact point in the plane (arrows: the blade's heading)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    axt.set(xlabel="time t", ylabel="heading θ [rad]", title="heading of the blade")
    axt.grid(True, alpha=0.3)
    axt.legend(fontsize=8)
    fig.suptitle("Skate: no sideways slip (−sin θ ẋ + cos θ ẏ = 0), two laws of motion from the same start")
    return fig


# -- the integral principle --------------------------------------------------------------------------
def verification(
    check: Verification | Mapping[str, Verification],
    traj: Trajectory | Mapping[str, Trajectory] | None = None,
) -> Any:
    """The minimizing variation of the integral principle (23) and the verdict.

    For a path ``x(t)`` on the constraint, with ``R = [T] − F`` along it, :func:`gausspp.verify`
    minimizes ``(1/T) ∫ (G⁻¹(R + Gδx), R + Gδx) dt`` over variations ``δx`` that vanish at the
    ends and obey the realization's relation (20). The relative gap
    ``(value at δx = 0 − minimum) / value at δx = 0`` is zero (to discretization error) iff the
    path is a motion; the minimizing ``δx(t)`` shows where and how a path fails (it is
    ``−G⁻¹`` times the part of ``R`` that does work on admissible variations).

    One column per check: ``δx(t)`` with the relative gap, the tolerance and the verdict in the
    title (green: a motion; red: not). With ``traj`` a second row compares the multipliers of
    (20) recovered by the check with the trajectory's own ``λ`` (its state ``λ`` for flywheel
    realizations, else ``u``).

    Parameters
    ----------
    check : Verification or mapping of str to Verification
    traj : Trajectory or mapping of str to Trajectory, optional
        The path(s) checked: one for all checks, or one per check key.

    Returns
    -------
    matplotlib.figure.Figure
        ``len(check)`` axes, twice as many with ``traj``.
    """
    plt = _pyplot()
    checks = _runs(check, "verifications")
    trajs: dict[str, Any] | None = None
    if traj is not None:
        if isinstance(traj, Mapping):
            missing = set(checks) - {str(k) for k in traj}
            if missing:
                raise InputError(f"traj has no trajectory for the checks {sorted(missing)}")
            trajs = {k: traj[k] for k in checks}
        else:
            trajs = dict.fromkeys(checks, traj)
    ncols, nrows = len(checks), 1 if trajs is None else 2
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(5.5 * ncols, 3.6 * nrows), squeeze=False, sharex="col", layout="constrained"
    )
    colors = plt.get_cmap("tab10")
    for j, (name, c) in enumerate(checks.items()):
        ax = axes[0, j]
        for i in range(c.delta_x.shape[1]):
            ax.plot(c.t, c.delta_x[:, i], ".-", ms=3, color=colors(i % 10), label=f"$\\delta x_{{{i + 1}}}$")
        verdict = "a motion" if c.is_motion else "NOT a motion"
        ax.set_title(
            (f"{name}\n" if name else "")
            + f"relative gap {c.relative_gap:.2e} (tolerance {c.tolerance:.1e}): {verdict}",
            color="tab:green" if c.is_motion else "tab:red",
            fontsize=10,
        )
        ax.set(ylabel="minimizing variation δx")
        biggest = float(np.max(np.abs(c.delta_x), initial=0.0))
        ax.text(0.98, 0.03, f"max |δx| = {biggest:.1e}", transform=ax.transAxes, ha="right", va="bottom", fontsize=8)
        ax.grid(True, alpha=0.3)
        _legend(ax)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
        if trajs is None:
            ax.set_xlabel("time t")
            continue
        tr, bx = trajs[name], axes[1, j]
        k = c.multipliers.shape[1]
        own = tr.lam if tr.lam.shape[1] == k else (tr.u if tr.lam.shape[1] == 0 and tr.u.shape[1] == k else None)
        for r in range(k):
            lam_r = f"$\\lambda_{{{r + 1}}}$"
            bx.plot(c.t, c.multipliers[:, r], "o", ms=3, color=colors(r % 10), label=f"{lam_r} from (20)")
            if own is not None:
                bx.plot(tr.t, own[:, r], "-", color=colors(r % 10), lw=1, label=f"{lam_r} of the path")
        bx.set(xlabel="time t", ylabel="multiplier λ", title="multipliers of (20) vs the path's λ")
        bx.grid(True, alpha=0.3)
        _legend(bx)
    fig.suptitle("Integral principle (23): the variation δx that lowers the compulsion most")
    return fig


# -- work-precision -------------------------------------------------------------------------------------
def work_precision(rows: Sequence[Row], scene: str, ax: Any = None) -> Any:
    """Final-state error against wall time, log–log, one line per method and step solver.

    Each point is one run of :func:`gausspp.report.work_precision` (a step size or a tolerance
    of the sweep), its error ``max |x − x_ref| / max(1, |x_ref|)`` over ``q`` and ``v`` at the
    final time against the wall time (minimum of repeats): lower left is better.
    """
    plt = _pyplot()
    fig = ax.figure if ax is not None else plt.figure(figsize=(7, 4.5))
    ax = ax or fig.add_subplot()
    mine = [r for r in rows if r.scene == scene and r.status == "success" and r.final_error > 0]
    methods = list(dict.fromkeys(r.method for r in mine))
    solvers = list(dict.fromkeys(r.solver for r in mine))
    colors = plt.get_cmap("tab10")
    styles = ["-", "--", ":", "-."]
    markers = ["o", "s", "^", "D"]
    for key in dict.fromkeys((r.method, r.solver) for r in mine):
        pts = [(r.wall_time, r.final_error) for r in mine if (r.method, r.solver) == key]  # in sweep order
        m, s_ = methods.index(key[0]), solvers.index(key[1]) % len(styles)
        ax.loglog(
            *zip(*pts, strict=True),
            linestyle=styles[s_],
            marker=markers[s_],
            color=colors(m % 10),
            label=f"{key[0]} · {key[1]}",
            ms=4,
        )
    failed = sum(1 for r in rows if r.scene == scene and r.status != "success")
    ax.set(
        xlabel="wall time [s] (minimum of repeats)",
        ylabel="final-state error (mixed abs/rel)",
        title=f"{scene}: error against run time" + (f" ({failed} failed runs in the table)" if failed else ""),
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), title="method · step solver")
    return fig


def save_work_precision(rows: Sequence[Row], out: Path) -> list[Path]:
    """One PNG per scene in ``out``."""
    plt = _pyplot()
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for scene in dict.fromkeys(r.scene for r in rows):
        fig = work_precision(rows, scene)
        path = out / f"work_precision_{scene}.png"
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        paths.append(path)
    return paths
