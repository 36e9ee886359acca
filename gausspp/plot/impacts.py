"""The figure of a run with unilateral contacts: gaps and events, contact forces, energy and its losses."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from .base import legend, palette, pyplot, suffix

#: Event kinds marked on the gap panel: gid → (marker, filled, legend text).
EVENT_MARKERS = {
    "impact": ("v", True, "impact"),
    "plastic impact": ("s", True, "plastic impact (slower than rest_speed: ends in rest)"),
    "lift-off": ("^", True, "lift-off"),
    "touch": ("o", False, "touch (no impact)"),
}


def event_kind(ev: Mapping[str, Any]) -> str:
    """The marker's gid of a contact event: its ``kind``, with plastic impacts apart."""
    return "plastic impact" if ev.get("kind") == "impact" and ev.get("plastic") else str(ev.get("kind"))


def checked_contact_run(model: Any, traj: Any) -> list[str]:
    """The model's contact rows, after checking that ``traj`` is a run of it that recorded its gaps.

    Raises :class:`~gausspp.errors.InputError` if the model has no contacts, the trajectory no samples
    or no recorded gaps ``traj.gap``, or its events name rows the model lacks; a
    :class:`~gausspp.errors.ShapeError` if an array does not fit the model.
    """
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
    gap = getattr(traj, "gap", None)
    if gap is None:
        raise InputError(
            "plot.contacts: the trajectory carries no gaps (traj.gap, recorded by gausspp.simulate for runs with "
            "contacts); re-run the simulation with the current gausspp — plots draw what a run recorded"
        )
    if np.shape(gap) != (N, n):
        raise ShapeError(f"traj.gap has shape {np.shape(gap)}, expected {(N, n)} ({N} samples, contact rows {names})")
    unknown = sorted({str(ev.get("contact")) for ev in traj.events if ev.get("contact") not in names})
    if unknown:
        raise InputError(f"traj.events name contacts {unknown} that the model does not have ({names})")
    return names


def _mark_events(ax: Any, names: Sequence[str], events: Sequence[Mapping[str, Any]], colors: Any) -> None:
    """One marker line per row and event kind at ``g = 0``, and the gap panel's legend."""
    from matplotlib.lines import Line2D

    handles = ax.get_legend_handles_labels()[0]
    for gid, (marker, filled, text) in EVENT_MARKERS.items():
        for i, name in enumerate(names):
            times = [float(ev["t"]) for ev in events if ev.get("contact") == name and event_kind(ev) == gid]
            if times:
                c = colors(i % 10)
                style = dict(marker=marker, ls="none", ms=6, mec="k", mew=0.6, mfc=c if filled else "none", color=c)
                ax.plot(times, np.zeros(len(times)), gid=gid, zorder=3, **style)
        if any(event_kind(ev) == gid for ev in events):
            mfc = "0.6" if filled else "none"
            handles.append(Line2D([], [], marker=marker, ls="none", mec="k", mfc=mfc, label=text))
    ax.legend(handles=handles, fontsize=8, loc="upper right")


def impact_losses(events: Sequence[Mapping[str, Any]]) -> dict[tuple[float, float, float], float]:
    """Kinetic energy taken by each velocity jump, keyed by ``(t, T before, T after)``.

    The impact events of one jump (several rows hit at once) share these three numbers, so a jump
    is counted once.
    """
    jumps: dict[tuple[float, float, float], float] = {}
    for ev in events:
        if ev.get("kind") == "impact":
            before, after = float(ev["kinetic_energy_before"]), float(ev["kinetic_energy_after"])
            jumps[(float(ev["t"]), before, after)] = before - after
    return jumps


def lost_by_sample(t: np.ndarray, jumps: Mapping[tuple[float, float, float], float]) -> np.ndarray:
    """The energy lost at impacts up to each sample (a sample after a jump shares the time of the one before)."""
    lost = np.zeros(t.size)
    repeated = np.flatnonzero(np.diff(t) == 0.0) + 1
    start = 0
    for (tj, _before, _after), loss in jumps.items():
        after_jump = repeated[(repeated >= start) & (t[repeated] == tj)]
        start = int(after_jump[0]) if after_jump.size else int(np.searchsorted(t, tj, side="right"))
        lost[start:] += loss
        start += 1
    return lost


def _energy_panel(ax: Any, t: np.ndarray, traj: Any) -> None:
    """``E(t)``, ``E + lost`` (dotted) and the lost energy as a step line."""
    jumps = impact_losses(traj.events)
    energy = np.asarray(traj.energy, float)
    if energy.shape == t.shape and np.all(np.isfinite(energy)):
        ax.plot(t, energy, color="k", lw=1.2, label="total energy E")
        ax.plot(t, energy + lost_by_sample(t, jumps), color="0.45", ls=":", lw=1.2, label="E + lost at impacts")
    losses = list(jumps.values())
    ax.step(
        [t[0], *(key[0] for key in jumps), t[-1]],
        [0.0, *np.cumsum(losses), float(np.sum(losses))],
        where="post",
        color=palette(3),
        lw=1.2,
        label=f"kinetic energy lost at impacts ({len(jumps)} jumps)",
    )
    ax.set(xlabel="time t (s)", ylabel="energy (J)", title="energy, and the kinetic energy lost at impacts")


def contacts(model: Any, traj: Any, *, title: str | None = None) -> Any:
    """Gaps, contact forces and energy of a run with unilateral contacts (``gp.Unilateral``).

    Three panels sharing the time axis:

    1. every contact row's recorded gap ``traj.gap`` (linear scale; the floor ``g = 0`` dotted),
       with the contact events marked on it at ``g = 0`` in the row's colour: impacts ``▼``,
       plastic impacts ``■`` (``e = 0``: slower than ``rest_speed``, the last impact of a Zeno
       sequence that ends in rest, or a resting contact that takes part in another contact's
       impact), lift-offs ``▲``, touches without impact ``○``;
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
        The model that was simulated (it names the contact rows; it is not evaluated).
    traj : Trajectory
        Its run by :func:`gausspp.simulate` (event by event), with the recorded gaps ``traj.gap``.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Three axes: gaps, forces, energy.
    """
    names = checked_contact_run(model, traj)
    plt = pyplot()
    t, gaps = np.asarray(traj.t, float), np.asarray(traj.gap, float)
    fig, (gap_ax, force_ax, energy_ax) = plt.subplots(3, 1, figsize=(8.0, 8.0), sharex=True, layout="constrained")
    colors = palette
    for i, name in enumerate(names):
        gap_ax.plot(t, gaps[:, i], color=colors(i % 10), lw=1.2, label=f"gap of {name}")
        force_ax.plot(t, traj.contact_force[:, i], color=colors(i % 10), lw=1.2, label=f"force on {name}")
    gap_ax.axhline(0.0, color="k", ls=":", lw=0.8)
    _mark_events(gap_ax, names, traj.events, colors)
    gap_ax.set(ylabel="gap g (m)", title="gaps g(t) of the contacts (g ≥ 0; events marked at g = 0)")
    force_ax.set(ylabel="contact force (N)", title="contact forces (multipliers ≥ 0; zero in flight)")
    _energy_panel(energy_ax, t, traj)
    for ax in (gap_ax, force_ax, energy_ax):
        ax.grid(True, alpha=0.3)
    legend(force_ax)
    legend(energy_ax)
    fig.suptitle((title or "Unilateral contacts") + suffix("", traj))
    return fig
