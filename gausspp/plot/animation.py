"""The mechanism moving: each frame drawn from what the scene says to draw at ``q`` (``scene.drawing``).

A scene's drawing is a function ``q -> dict`` in the plane ``(x, y)``; the keys, all optional:

``"segments"``  links and ropes: a list of pairs of points ``((x₁, y₁), (x₂, y₂))``;
``"points"``    bodies: a list of points, drawn as dots;
``"fixed"``     fixed points (pins, anchors): drawn as small black squares;
``"path"``      a prescribed path: a ``(K, 2)`` array, drawn once, dashed;
``"reaction"``  where the constraint's reaction acts: a list of ``(point, (i, j))``, the arrow at ``point`` with
                components ``(R[i], R[j])`` of the run's generalized reaction ``R = [T] − F`` (``None`` for a zero
                component); drawn only for a run that carries ``reaction`` (a :class:`~gausspp.Trajectory`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import GaussppError, InputError, ShapeError
from .base import pyplot

#: The keys a drawing may hold.
KEYS = ("segments", "points", "fixed", "path", "reaction")
#: The longest reaction arrow as a fraction of the picture's size.
ARROW = 0.25


def drawing_of(scene: Any) -> Any:
    """``scene.drawing``, or a clear error for a model or a scene that has none."""
    draw = getattr(scene, "drawing", None)
    if draw is None:
        name = getattr(scene, "name", type(scene).__name__)
        raise InputError(
            f"plot.animate: {name!r} has no drawing — animate needs a Scene whose `drawing` maps q to the points "
            "and segments to draw (a Model carries none); give the scene, or build one with drawing=..."
        )
    return draw


def frame_indices(n: int, frames: int | None, fps: int) -> np.ndarray:
    """``frames`` sample indices spread evenly over ``n`` samples, first and last included (all if fewer)."""
    if frames is not None and (int(frames) != frames or frames < 1):
        raise InputError(f"plot.animate: frames must be a positive integer, got {frames!r}")
    k = min(n, int(frames) if frames is not None else 4 * fps)
    return np.linspace(0, n - 1, k).round().astype(int)


def _picture(draw: Any, q: np.ndarray) -> dict[str, Any]:
    """The drawing at ``q``, its keys checked."""
    pic = dict(draw(np.asarray(q, float)))
    unknown = set(pic) - set(KEYS)
    if unknown:
        raise InputError(f"plot.animate: the drawing returned unknown keys {sorted(unknown)}; allowed: {list(KEYS)}")
    return pic


def _points(pic: dict[str, Any]) -> np.ndarray:
    """Every point of a picture as ``(K, 2)`` (the limits of the axes)."""
    parts = [np.reshape(np.asarray(pic.get(k, []), float), (-1, 2)) for k in ("segments", "points", "fixed", "path")]
    return np.concatenate(parts, axis=0)


def _limits(pictures: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray, float]:
    """Lower and upper corners of the box holding every frame (with a margin) and its size."""
    pts = np.concatenate([_points(p) for p in pictures], axis=0)
    if not pts.size or not np.all(np.isfinite(pts)):
        raise ShapeError("plot.animate: the drawing gives no finite point to draw; check the scene's drawing")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = float(max(np.max(hi - lo), 1e-9))
    pad = 0.1 * size + 0.05 * (size == 1e-9)
    return lo - pad, hi + pad, size


def _arrows(pic: dict[str, Any], reaction: np.ndarray | None) -> list[tuple[np.ndarray, np.ndarray]]:
    """The reaction arrows of one frame: ``(foot, vector)`` pairs (none if the run carries no reaction)."""
    if reaction is None:
        return []
    out = []
    for point, (i, j) in pic.get("reaction", []):
        vec = np.array([0.0 if i is None else reaction[i], 0.0 if j is None else reaction[j]])
        out.append((np.asarray(point, float), vec))
    return out


class _Frames:
    """The artists of the animation and how one frame updates them."""

    def __init__(self, ax: Any, pictures: list[dict[str, Any]], arrows: list[list[Any]], times: np.ndarray) -> None:
        self.ax, self.pictures, self.arrows, self.times = ax, pictures, arrows, times
        lo, hi, size = _limits(pictures)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]))
        longest = max((float(np.linalg.norm(v)) for frame in arrows for _, v in frame), default=0.0)
        #: quiver's scale: data units of force per unit of length, so the longest arrow is ARROW of the picture.
        self.scale = longest / (ARROW * size) if longest > 0 else 0.0
        self.links = ax.plot([], [], "-", color="0.3", lw=2.5, solid_capstyle="round")[0]
        self.bodies = ax.plot([], [], "o", color="tab:blue", ms=10, zorder=3)[0]
        self.fixed = ax.plot([], [], "s", color="k", ms=6, zorder=3)[0]
        self.quiver: Any = None

    def update(self, k: int) -> list[Any]:
        pic = self.pictures[k]
        segs = np.reshape(np.asarray(pic.get("segments", []), float), (-1, 2, 2))
        gaps = np.full((len(segs), 1, 2), np.nan)  # one polyline, the segments split by NaN
        xy = np.concatenate([segs, gaps], axis=1).reshape(-1, 2)
        xs, ys = xy[:, 0], xy[:, 1]
        self.links.set_data(xs, ys)
        for line, key in ((self.bodies, "points"), (self.fixed, "fixed")):
            pts = np.reshape(np.asarray(pic.get(key, []), float), (-1, 2))
            line.set_data(pts[:, 0], pts[:, 1])
        artists = [self.links, self.bodies, self.fixed]
        if self.scale > 0:
            self._draw_arrows(self.arrows[k])
            artists.append(self.quiver)
        self.ax.set_title(f"t = {self.times[k]:.3f} s", fontsize=10)
        return artists

    def _draw_arrows(self, frame: list[tuple[np.ndarray, np.ndarray]]) -> None:
        """Replace the reaction arrows (the longest of the run is :data:`ARROW` of the picture)."""
        if self.quiver is not None:
            self.quiver.remove()
        feet = np.array([f for f, _ in frame]).reshape(-1, 2)
        vecs = np.array([v for _, v in frame]).reshape(-1, 2)
        self.quiver = self.ax.quiver(
            feet[:, 0], feet[:, 1], vecs[:, 0], vecs[:, 1], color="tab:red", angles="xy", scale_units="xy",
            scale=self.scale, zorder=4, width=0.006,
        )  # fmt: skip


def animate(
    scene: Any,
    traj: Any,
    *,
    out: str | Path | None = None,
    fps: int = 30,
    frames: int | None = None,
    dpi: int = 100,
    title: str | None = None,
) -> Any:
    """The mechanism moving along a run, drawn from ``scene.drawing(q)`` at evenly spread samples.

    Each frame draws the scene's links, bodies, fixed points, its prescribed path (if any) and, for a run
    that carries the generalized reaction ``R = [T] − F`` (a :class:`~gausspp.Trajectory`; not a
    :class:`~gausspp.servo.route.ServoTrajectory`), the reaction as an arrow where the drawing says it acts;
    the time is in the title. The animation plays at ``fps`` frames per second (not in real time).

    Parameters
    ----------
    scene : Scene
        A scene with a ``drawing`` (``q -> dict``, see the module docstring); a model has none.
    traj : Trajectory or ServoTrajectory
        Anything with samples ``t`` (N,) and ``q`` (N, nq).
    out : str or Path, optional
        Save to this file: ``.gif`` (pillow) or ``.mp4`` (needs ffmpeg). The figure is closed after saving.
    fps : int
        Frames per second of the saved file.
    frames : int, optional
        Number of frames (default ``4 fps``, at most the number of samples), first and last sample included.
    dpi : int
        Resolution of the saved file.
    title : str, optional
        The figure's title (default: the scene's name).

    Returns
    -------
    matplotlib.animation.FuncAnimation

    Raises
    ------
    InputError
        The scene has no drawing, ``frames``/``fps`` are not positive integers, ``out`` has another suffix.
    GaussppError
        matplotlib missing, or ``.mp4`` asked without ffmpeg.
    """
    plt = pyplot()
    from matplotlib.animation import FuncAnimation, writers

    draw = drawing_of(scene)
    t, q = np.asarray(traj.t, float), np.asarray(traj.q, float)
    if t.ndim != 1 or q.ndim != 2 or len(t) != len(q) or not len(t):
        raise ShapeError(f"plot.animate: traj needs t (N,) and q (N, nq) with N ≥ 1; got {t.shape}, {q.shape}")
    if int(fps) != fps or fps < 1:
        raise InputError(f"plot.animate: fps must be a positive integer, got {fps!r}")
    writer = _writer(out, writers)
    idx = frame_indices(len(t), frames, int(fps))
    pictures = [_picture(draw, q[i]) for i in idx]
    reaction = getattr(traj, "reaction", None)
    arrows = [
        _arrows(p, None if reaction is None else np.asarray(reaction)[i]) for p, i in zip(pictures, idx, strict=True)
    ]
    fig, ax = plt.subplots(figsize=(5.0, 4.0), layout="constrained")
    ax.set(aspect="equal", xlabel="x (m)", ylabel="y (m)")
    ax.grid(True, alpha=0.3)
    for pic in pictures[:1]:
        if "path" in pic:
            path = np.reshape(np.asarray(pic["path"], float), (-1, 2))
            ax.plot(path[:, 0], path[:, 1], "--", color="tab:orange", lw=1, label="prescribed path")
            ax.legend(fontsize=8, loc="upper right")
    fig.suptitle(title if title is not None else str(getattr(scene, "name", "")))
    state = _Frames(ax, pictures, arrows, t[idx])
    anim = FuncAnimation(fig, state.update, frames=len(idx), interval=1000.0 / fps, blit=False)
    if out is not None:
        anim.save(str(out), writer=writer, fps=int(fps), dpi=dpi)
        plt.close(fig)
    return anim


def _writer(out: str | Path | None, writers: Any) -> str | None:
    """The matplotlib writer for ``out``'s suffix: pillow for ``.gif``, ffmpeg for ``.mp4``."""
    if out is None:
        return None
    suffix = Path(out).suffix.lower()
    if suffix == ".gif":
        return "pillow"
    if suffix == ".mp4":
        if not writers.is_available("ffmpeg"):
            raise GaussppError(f"plot.animate: out={str(out)!r} needs ffmpeg, which is not installed; save a .gif")
        return "ffmpeg"
    raise InputError(f"plot.animate: out={str(out)!r} must end in .gif or .mp4")
