"""The map of the realizability margin of a servo torque over the sphere of torque axes ``n``."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from .base import given, palette, pyplot, vec

#: What :func:`realizability_map` reads from its grid (a :class:`gausspp.studies.realizability_map.RealizabilityGrid`).
GRID_FIELDS = ("inertia", "l", "lon", "lat", "n", "margin", "pole", "naive_margin", "principal")
#: Where the grid comes from, for the messages.
GRID_STUDY = "gausspp.studies.realizability_map.realizability_grid(inertia, l, resolution)"


def lonlat(v: np.ndarray) -> tuple[float, float]:
    """Longitude and latitude, degrees, of a unit vector."""
    return float(np.degrees(np.arctan2(v[1], v[0]))), float(np.degrees(np.arcsin(np.clip(v[2], -1, 1))))


def _title(g: Any, scene: str) -> str:
    """The scene, its parameters with units, and what the map shows."""
    moments = np.diag(g.inertia) if np.allclose(g.inertia, np.diag(np.diag(g.inertia))) else None
    inertia_text = f"I = diag{vec(moments)} kg·m²" if moments is not None else "I = full tensor (kg·m²)"
    verdict = (
        "l is a principal axis: the true zero set is the circle $n \\perp l$"
        if g.principal
        else f"median margin on the naive circle $n \\perp l$: {np.median(g.naive_margin):.2f} — not zero"
    )
    head = f"scene {scene}: servo torque along the body axis n keeping (ω, l) = 0" if scene else "Servo torque along n"
    return f"{head}; l = {vec(g.l)} (unit axis), {inertia_text}\n{verdict}"


def _circles(ax: Any, g: Any) -> None:
    """The true zero set and the naive circle with their poles, and the legend."""
    true, naive = palette(3), "white"  # Okabe–Ito vermillion on viridis; white dashed
    ax.contour(g.lon, g.lat, g.n @ g.pole, [0.0], colors=true, linewidths=2.2)
    ax.contour(g.lon, g.lat, g.n @ g.l, [0.0], colors=naive, linestyles="--", linewidths=1.6)
    for sign in (1, -1):
        ax.plot(*lonlat(sign * g.pole), "+", color=true, ms=12, mew=2.5, clip_on=False, zorder=5)
        ax.plot(*lonlat(sign * g.l), "x", color=naive, ms=9, mew=2, clip_on=False, zorder=5)
    ax.plot([], [], "-", color=true, lw=2.2, label=r"true zero set $(I^{-1}n, l) = 0$")
    ax.plot([], [], "--", color=naive, lw=1.6, label=r"naive circle $n \perp l$")
    ax.plot([], [], "+", color=true, ms=10, mew=2, label=r"$\pm I^{-1}l$ (pole of the true set)")
    ax.plot([], [], "x", color=naive, ms=8, mew=2, label=r"$\pm l$ (pole of the naive circle)")
    ax.legend(loc="lower left", fontsize=8, facecolor="0.25", labelcolor="white", framealpha=0.85)


def realizability_map(grid: Any = None, *, floor: float = 1e-3, scene: str = "rigid-body-servo") -> Any:
    """Map of where a servo torque along ``n`` can keep ``(ω, l) = 0`` (paper §2, condition (12)).

    The colour is the realizability margin (log scale, clipped at ``floor``) of the torque axis
    ``n`` at each longitude/latitude. Overlaid: the true zero set ``(I⁻¹n, l) = 0`` (solid red;
    the great circle with pole ``I⁻¹l``, marked ``+``) and the naive circle ``n ⟂ l`` (dashed
    white; pole ``l``, marked ``×``). For a non-principal ``l`` they differ: most axes with
    ``n ⟂ l`` are realizable, and some axes not orthogonal to ``l`` are not.

    Parameters
    ----------
    grid : RealizabilityGrid
        The numbers, from :func:`gausspp.studies.realizability_map.realizability_grid`.
    floor : float
        Smallest margin shown (the colour scale's lower end).
    scene : str
        The scene the map is of, named in the title with ``l`` and ``I`` (kg·m²) (``""``: no scene named).

    Returns
    -------
    matplotlib.figure.Figure
        One map axes and its colour bar.
    """
    g = given(grid, "grid", "realizability_map", GRID_STUDY)
    missing = [name for name in GRID_FIELDS if not hasattr(g, name)]
    if missing:
        raise InputError(f"plot.realizability_map: grid must be the result of {GRID_STUDY}; got {type(g).__name__}")
    plt = pyplot()
    from matplotlib.colors import LogNorm

    fig, ax = plt.subplots(figsize=(10, 5), layout="constrained")
    im = ax.pcolormesh(
        g.lon, g.lat, np.clip(g.margin, floor, 1.0), norm=LogNorm(vmin=floor, vmax=1.0), cmap="viridis", shading="auto"
    )
    fig.colorbar(im, ax=ax, label=r"realizability margin (1): cosine of $n$, $l$ in the metric $I^{-1}$")
    _circles(ax, g)
    ax.set(
        xlabel="longitude of the torque axis n (°, body axes)",
        ylabel="latitude of n (°)",
        xlim=(-180, 180),
        ylim=(-90, 90),
        xticks=np.arange(-180, 181, 45),
        yticks=np.arange(-90, 91, 30),
        title=_title(g, scene),
    )
    return fig
