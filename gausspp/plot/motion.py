"""Figures of one or several runs over time: coordinates and velocities, reactions, compulsion, margin."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from ..naming import velocity_names
from .base import (
    MARGIN_WARN,
    MARKERS,
    STYLES,
    as_runs,
    carried_names,
    component_color,
    labels,
    legend,
    palette,
    pyplot,
    suffix,
)


def _same_sizes(runs: Mapping[str, Any], phase: bool) -> tuple[int, int]:
    """``(nq, nv)`` shared by all runs; the phase portrait needs ``nq == nv``."""
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
    return nq, nv


def _difference_panels(axes: Any, runs: Mapping[str, Any], ql: Sequence[str], vl: Sequence[str]) -> None:
    """The second run minus the first, ``q_b(t) − q_a(t)`` and ``v_b(t) − v_a(t)``, on the first run's times."""
    (na, a), (nb, b) = list(runs.items())[:2]
    for ax, xa, xb, names, what in ((axes[0], a.q, b.q, ql, "coordinates"), (axes[1], a.v, b.v, vl, "velocities")):
        for i in range(xa.shape[1]):
            diff = np.interp(a.t, b.t, xb[:, i]) - xa[:, i]
            ax.plot(a.t, diff, STYLES[i % len(STYLES)], color=component_color(i, len(names)), label=f"Δ{names[i]}")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set(xlabel="time t (s)", ylabel=f"Δ {what}", title=f"difference of the {what}: {nb} − {na}")


def _run_lines(axes: Any, runs: Mapping[str, Any], ql: Sequence[str], vl: Sequence[str], phase: bool) -> None:
    """Each run in one line style and marker, each component in one colour (Okabe–Ito)."""
    for r, (name, tr) in enumerate(runs.items()):
        ls, sfx = STYLES[r % len(STYLES)], suffix(name, tr)
        mark = dict(marker=MARKERS[r % len(MARKERS)], markevery=max(1, tr.t.size // 12), ms=5) if len(runs) > 1 else {}
        nq, nv = tr.q.shape[1], tr.v.shape[1]
        for i in range(nq):
            axes[0].plot(tr.t, tr.q[:, i], ls, color=component_color(i, nq), label=ql[i] + sfx, **mark)
        for i in range(nv):
            axes[1].plot(tr.t, tr.v[:, i], ls, color=component_color(i, nv), label=vl[i] + sfx, **mark)
        if phase:
            for i in range(nq):
                color = component_color(i, nq)
                axes[2].plot(tr.q[:, i], tr.v[:, i], ls, color=color, label=f"({ql[i]}, {vl[i]}){sfx}")
                axes[2].plot(tr.q[0, i], tr.v[0, i], "o", color=color, ms=4)


def trajectory(
    traj: Any,
    *,
    phase: bool = False,
    difference: bool = False,
    q_labels: Sequence[str] | None = None,
    v_labels: Sequence[str] | None = None,
    names: Sequence[str] | None = None,
    title: str | None = None,
) -> Any:
    """Coordinates and velocities over time, and optionally the phase portrait and two runs' difference.

    Draws ``q_i(t)`` and ``v_i(t)`` (``v = q̇``, or the quasi-velocities ``ω`` of a rigid body) in
    two panels; with ``phase=True`` a third panel draws each pair ``(q_i(t), v_i(t))``, the
    projection of the motion onto the phase plane of coordinate ``i``, with its start marked.
    With ``difference=True`` (two runs ``a``, ``b``) a second row draws ``q_b(t) − q_a(t)`` and
    ``v_b(t) − v_a(t)`` (``b`` interpolated linearly on ``a``'s times): what tells the motions apart
    when their curves nearly overlap.

    Parameters
    ----------
    traj : Trajectory or mapping of str to Trajectory
        One run, or several (e.g. ``{"rod": a, "servo": b}``) drawn with one line style and marker each;
        components keep their colour (Okabe–Ito palette) across runs. All runs must have the same ``nq`` and ``nv``.
    phase : bool
        Add the phase portrait; needs ``nq == nv`` (not a rigid body's quaternion and ``ω``).
    difference : bool
        Add the row of differences; needs exactly two runs.
    q_labels, v_labels : sequence of str, optional
        Names of the components (default: from ``names``, else the names the first run carries from its model,
        else ``q₁…``, ``v₁…``).
    names : sequence of str, optional
        The coordinates' names with units (a scene's :attr:`~gausspp.scenes.Scene.coordinates`, ``"x (m)"``): the
        labels of ``q``, and, dotted (:func:`~gausspp.scenes.scene.velocity_names`, ``"ẋ (m/s)"``), of ``v`` where
        ``v = q̇`` (``nq == nv``).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Axes ``q``, ``v`` (, phase) (, ``Δq``, ``Δv`` with ``difference``).
    """
    plt = pyplot()
    runs = as_runs(traj, "trajectories")
    nq, nv = _same_sizes(runs, phase)
    if difference and len(runs) != 2:
        raise InputError(f"difference=True draws the second run minus the first; got {len(runs)} runs, give two")
    first = next(iter(runs.values()))
    if names is not None:
        q_labels = q_labels if q_labels is not None else names
        v_labels = v_labels if v_labels is not None or len(names) != nv else velocity_names(names)
    q_labels = q_labels if q_labels is not None else carried_names(first, "coordinate", nq)
    v_labels = v_labels if v_labels is not None else carried_names(first, "velocity", nv)
    ql, vl = labels(q_labels, nq, "q"), labels(v_labels, nv, "v")
    ncols, nrows = (3 if phase else 2), (2 if difference else 1)
    fig, grid = plt.subplots(nrows, ncols, figsize=(4.8 * ncols, 4.0 * nrows), layout="constrained", squeeze=False)
    axes = list(grid[0])
    _run_lines(axes, runs, ql, vl, phase)
    axes[0].set(xlabel="time t (s)", ylabel="coordinates q (units in legend)", title="coordinates over time")
    axes[1].set(xlabel="time t (s)", ylabel="velocities v (units in legend)", title="velocities over time")
    if phase:
        axes[2].set(xlabel="coordinate $q_i$", ylabel="velocity $v_i$", title="phase portrait (start: dot)")
    if difference:
        _difference_panels(grid[1], runs, ql, vl)
        axes += list(grid[1][:2])
        if phase:
            fig.delaxes(grid[1][2])
    counts = [nq, nv, *([nq] if phase else []), *([nq, nv] if difference else [])]
    for ax, count in zip(axes, counts, strict=True):
        ax.grid(True, alpha=0.3)
        legend(ax, count)
    if title:
        fig.suptitle(title)
    return fig


def _reaction_panels(axes: Any, runs: Mapping[str, Any], colors: Any) -> float:
    """Draw ``u`` (and a flywheel's state ``λ``), ``Z`` and the margin of every run; the lowest margin shown."""
    lowest = 1.0
    for r, (name, tr) in enumerate(runs.items()):
        ls, sfx = STYLES[r % len(STYLES)], suffix(name, tr)
        m, n_lam = tr.u.shape[1], tr.lam.shape[1]
        ul, ll = (
            labels(carried_names(tr, "unknown", m), m, "u"),
            labels(carried_names(tr, "lam_state", n_lam), n_lam, "\\lambda"),
        )
        for j in range(tr.u.shape[1]):
            axes[0].plot(tr.t, tr.u[:, j], ls, color=colors(j % 10), label=f"{ul[j]}{sfx}")
        for j in range(tr.lam.shape[1]):
            state = f"state {ll[j]}{sfx}"
            axes[0].plot(tr.t, tr.lam[:, j], ls, color=colors(j % 10), lw=0.8, alpha=0.5, label=state)
        color = "k" if len(runs) == 1 else colors(r % 10)
        axes[1].plot(tr.t, tr.compulsion, ls, color=color, label=f"Z{sfx}")
        shown = np.maximum(np.asarray(tr.margin, float), 1e-17)
        lowest = min(lowest, float(np.nanmin(shown)) if shown.size else 1.0)
        axes[2].semilogy(tr.t, shown, ls, color=color, label=f"margin{sfx}")
    return lowest


def reaction_over_time(traj: Any, *, title: str | None = None) -> Any:
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
    plt = pyplot()
    runs = as_runs(traj, "trajectories")
    fig, axes = plt.subplots(3, 1, figsize=(8.0, 7.5), sharex=True, layout="constrained")
    lowest = _reaction_panels(axes, runs, palette)
    axes[2].axhline(MARGIN_WARN, color=palette(3), ls=":", lw=1, label=f"default warning level {MARGIN_WARN:g}")
    axes[2].set_ylim(min(lowest / 3, MARGIN_WARN / 10), 2.0)
    axes[0].set(
        ylabel="u (N, N·m: per row)",
        title=r"reaction unknowns $u$: $\lambda$ (ideal, force) or $\dot\lambda$ (flywheel)",
    )
    axes[1].set(ylabel="Z (N²/kg)", title=r"compulsion $Z = (A(\ddot x - a_0), \ddot x - a_0)$")
    axes[2].set(xlabel="time t (s)", ylabel="margin (1)", title="realizability margin (0: the realization cannot act)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        legend(ax)
    if title:
        fig.suptitle(title)
    return fig
