"""One panel of an animation: the pictures a scene's drawing gives at each frame, and the artists that show them.

A scene's drawing is a function ``q -> dict`` in the plane ``(x, y)``; the keys, all optional:

``"segments"``  links and ropes: a list of pairs of points ``((x₁, y₁), (x₂, y₂))``, drawn grey;
``"axes"``      body axes: a list of segments drawn in the palette's colours, in order (``e₁``, ``e₂``, ``e₃``);
``"points"``    bodies: a list of points, drawn as dots;
``"fixed"``     fixed points (pins, anchors): drawn as small black squares;
``"ground"``    fixed lines (a floor, a rail): segments drawn thin and black, taken from the first frame;
``"path"``      a prescribed path: a ``(K, 2)`` array, drawn once, dashed;
``"trace"``     points whose way so far is drawn as a thin line (the ``i``-th in the ``i``-th palette colour);
``"reaction"``  where the constraint's reaction acts: a list of ``(point, (i, j))``, the arrow at ``point`` with
                components ``(R[i], R[j])`` of the run's generalized reaction ``R = [T] − F`` (``None`` for a zero
                component); drawn only for a run that carries ``reaction`` (a :class:`~gausspp.Trajectory`);
``"labels"``    the panel's axis labels ``(x label, y label)`` (default ``("x (m)", "y (m)")``), from the first
                frame: a drawing that projects a 3-D body says so here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from .base import palette

#: The keys a drawing may hold.
KEYS = ("segments", "axes", "points", "fixed", "ground", "path", "trace", "reaction", "labels")
#: The keys whose points set the panel's limits.
EXTENT = ("segments", "axes", "points", "fixed", "ground", "path", "trace")
#: The longest reaction arrow as a fraction of the picture's size.
ARROW = 0.25


def picture(draw: Any, q: np.ndarray) -> dict[str, Any]:
    """The drawing at ``q``, its keys checked."""
    pic = dict(draw(np.asarray(q, float)))
    unknown = set(pic) - set(KEYS)
    if unknown:
        raise InputError(f"plot.animate: the drawing returned unknown keys {sorted(unknown)}; allowed: {list(KEYS)}")
    return pic


def points_of(pic: dict[str, Any], keys: tuple[str, ...] = EXTENT) -> np.ndarray:
    """The points of a picture under ``keys`` as ``(K, 2)``."""
    parts = [np.reshape(np.asarray(pic.get(k, []), float), (-1, 2)) for k in keys]
    return np.concatenate(parts, axis=0)


def limits(pictures: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray, float]:
    """Lower and upper corners of the box holding every frame (with a margin) and its size."""
    pts = np.concatenate([points_of(p) for p in pictures], axis=0)
    if not pts.size or not np.all(np.isfinite(pts)):
        raise ShapeError("plot.animate: the drawing gives no finite point to draw; check the scene's drawing")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = float(max(np.max(hi - lo), 1e-9))
    pad = 0.1 * size + 0.05 * (size == 1e-9)
    return lo - pad, hi + pad, size


def arrows(pic: dict[str, Any], reaction: np.ndarray | None) -> list[tuple[np.ndarray, np.ndarray]]:
    """The reaction arrows of one frame: ``(foot, vector)`` pairs (none if the run carries no reaction)."""
    if reaction is None:
        return []
    out = []
    for point, (i, j) in pic.get("reaction", []):
        vec = np.array([0.0 if i is None else reaction[i], 0.0 if j is None else reaction[j]])
        out.append((np.asarray(point, float), vec))
    return out


def polyline(segments: Any) -> tuple[np.ndarray, np.ndarray]:
    """Segments as one polyline split by NaN (one artist for all of them)."""
    segs = np.reshape(np.asarray(segments, float), (-1, 2, 2))
    gaps = np.full((len(segs), 1, 2), np.nan)
    xy = np.concatenate([segs, gaps], axis=1).reshape(-1, 2)
    return xy[:, 0], xy[:, 1]


class Panel:
    """The artists of one run's panel and how one frame updates them.

    ``pictures`` and ``arrows`` hold one entry per frame; ``times`` the frames' times; ``box`` the limits
    ``(lo, hi, size)`` shared by every panel of the animation; ``scale`` quiver's scale (force per unit
    length, shared so that arrows compare across panels; 0 draws none).
    """

    def __init__(self, ax: Any, pictures: list[dict[str, Any]], arrows_: list[list[Any]], times: np.ndarray,
                 box: tuple[np.ndarray, np.ndarray, float], scale: float, label: str,
                 way: tuple[np.ndarray, np.ndarray] | None = None) -> None:  # fmt: skip
        self.ax, self.pictures, self.arrows, self.times = ax, pictures, arrows_, times
        self.scale, self.label = scale, label
        #: the traced points at (a dense subset of) the run's samples, (M, n_trace, 2), and per frame how many
        #: of them lie at or before the frame (the frame's own point is added last)
        self.way = way
        lo, hi, _ = box
        first = pictures[0]
        xlabel, ylabel = first.get("labels", ("x (m)", "y (m)"))
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), aspect="equal", xlabel=xlabel, ylabel=ylabel)
        ax.grid(True, alpha=0.3)
        self._static(first)
        n_axes = len(np.reshape(np.asarray(first.get("axes", []), float), (-1, 2, 2)))
        n_trace = len(points_of(first, ("trace",)))
        self.traces = [ax.plot([], [], "-", color=palette(i), lw=0.8, alpha=0.7)[0] for i in range(n_trace)]
        self.links = ax.plot([], [], "-", color="0.3", lw=2.5, solid_capstyle="round")[0]
        self.body_axes = [ax.plot([], [], "-", color=palette(i), lw=3)[0] for i in range(n_axes)]
        self.bodies = ax.plot([], [], "o", color=palette(0), ms=10, zorder=3)[0]
        self.fixed = ax.plot([], [], "s", color="k", ms=6, zorder=3)[0]
        self.quiver: Any = None

    def _static(self, first: dict[str, Any]) -> None:
        """What is drawn once: the ground and the prescribed path."""
        if "ground" in first:
            self.ax.plot(*polyline(first["ground"]), "-", color="k", lw=1.2)
        if "path" in first:
            path = np.reshape(np.asarray(first["path"], float), (-1, 2))
            self.ax.plot(path[:, 0], path[:, 1], "--", color=palette(1), lw=1, label="prescribed path")
            self.ax.legend(fontsize=8, loc="upper right")

    def update(self, k: int) -> list[Any]:
        """Draw frame ``k``; the artists that changed."""
        pic = self.pictures[k]
        self.links.set_data(*polyline(pic.get("segments", [])))
        axes = np.reshape(np.asarray(pic.get("axes", []), float), (-1, 2, 2))
        for line, seg in zip(self.body_axes, axes, strict=False):
            line.set_data(seg[:, 0], seg[:, 1])
        for line, key in ((self.bodies, "points"), (self.fixed, "fixed")):
            pts = points_of(pic, (key,))
            line.set_data(pts[:, 0], pts[:, 1])
        if self.traces:
            way = self._way(k)
            for i, line in enumerate(self.traces):
                line.set_data(way[:, i, 0], way[:, i, 1])
        artists = [self.links, self.bodies, self.fixed, *self.body_axes, *self.traces, self.ax.title]
        if self.scale > 0:
            self._draw_arrows(self.arrows[k])
            artists.append(self.quiver)
        prefix = f"{self.label}: " if self.label else ""
        self.ax.set_title(f"{prefix}t = {self.times[k]:.3f} s", fontsize=10)
        return artists

    def _way(self, k: int) -> np.ndarray:
        """The traced points' way up to frame ``k``, ``(K, n_trace, 2)``: the run's dense samples before the
        frame, then the frame's own points (only the frames' points without a dense way)."""
        now = points_of(self.pictures[k], ("trace",))[None]
        if self.way is None:
            return np.concatenate([np.stack([points_of(p, ("trace",)) for p in self.pictures[:k]] or [now[0]]), now])
        dense, counts = self.way
        return np.concatenate([dense[: counts[k]], now])

    def _draw_arrows(self, frame: list[tuple[np.ndarray, np.ndarray]]) -> None:
        """Replace the reaction arrows."""
        if self.quiver is not None:
            self.quiver.remove()
        feet = np.array([f for f, _ in frame]).reshape(-1, 2)
        vecs = np.array([v for _, v in frame]).reshape(-1, 2)
        self.quiver = self.ax.quiver(
            feet[:, 0], feet[:, 1], vecs[:, 0], vecs[:, 1], color=palette(3), angles="xy", scale_units="xy",
            scale=self.scale, zorder=4, width=0.006,
        )  # fmt: skip


def arrow_scale(all_arrows: list[list[list[Any]]], size: float) -> float:
    """quiver's scale (data units of force per unit of length) so that the longest arrow of every panel and
    frame is :data:`ARROW` of the picture's ``size``; 0 when there is no arrow."""
    longest = max((float(np.linalg.norm(v)) for panel in all_arrows for f in panel for _, v in f), default=0.0)
    return longest / (ARROW * size) if longest > 0 else 0.0


def dense_way(draw: Any, t: np.ndarray, q: np.ndarray, frame_times: np.ndarray, most: int = 2000) -> Any:
    """The drawing's traced points at up to ``most`` evenly spread samples of a run, and for each frame time
    how many of them come at or before it: ``(way (M, n_trace, 2), counts (frames,))``, or ``None`` when the
    drawing traces nothing."""
    if "trace" not in picture(draw, q[0]):
        return None
    keep = np.unique(np.linspace(0, len(t) - 1, min(len(t), most)).round().astype(int))
    way = np.stack([points_of(picture(draw, q[i]), ("trace",)) for i in keep])
    counts = np.searchsorted(t[keep], frame_times, side="right")
    return way, counts
