"""The mechanism moving: each frame drawn from what the scene says to draw at ``q`` (``scene.drawing``).

The drawing's keys are listed in :mod:`gausspp.plot.frames`. Several runs of one scene (a mapping
``label → run``) play side by side, one panel each, on the same time grid, limits and arrow scale.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import GaussppError, InputError, ShapeError
from .base import as_runs, pyplot
from .frames import Panel, arrow_scale, arrows, dense_way, limits, picture
from .gif import save_gif


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


def _samples(label: str, traj: Any) -> tuple[np.ndarray, np.ndarray]:
    """A run's ``t`` (N,) and ``q`` (N, nq), checked."""
    t, q = np.asarray(traj.t, float), np.asarray(traj.q, float)
    if t.ndim != 1 or q.ndim != 2 or len(t) != len(q) or not len(t):
        where = f"run {label!r}" if label else "traj"
        raise ShapeError(f"plot.animate: {where} needs t (N,) and q (N, nq) with N ≥ 1; got {t.shape}, {q.shape}")
    return t, q


def frame_samples(times: list[np.ndarray], frames: int | None, fps: int) -> list[np.ndarray]:
    """The sample index of each frame in each run: frames evenly spread in time over the span every run
    covers (as many as :func:`frame_indices` gives for the shortest run), each run's sample nearest to each
    frame's time. (Spread in time, not in samples: a run with events has extra samples at its impacts.)"""
    count = len(frame_indices(min(len(t) for t in times), frames, fps))
    start, stop = max(t[0] for t in times), min(t[-1] for t in times)
    grid = np.linspace(start, stop, count)
    return [nearest(t, grid) for t in times]


def nearest(t: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """The index of the sample of ``t`` (increasing) nearest to each time of ``grid``."""
    right = np.searchsorted(t, grid).clip(0, len(t) - 1)
    left = (right - 1).clip(0)
    return np.where(np.abs(grid - t[left]) <= np.abs(t[right] - grid), left, right)


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
    """The mechanism moving along a run (or several side by side), drawn from ``scene.drawing(q)``.

    Each frame draws the scene's links, body axes, bodies, fixed points and ground, its prescribed path (if
    any), the way traced so far by the points the drawing marks, and, for a run that carries the generalized
    reaction ``R = [T] − F`` (a :class:`~gausspp.Trajectory`; not a
    :class:`~gausspp.servo.index_reduction.ServoTrajectory`), the reaction as an arrow where the drawing says it acts
    (one scale for all panels and frames: the longest arrow is a quarter of the picture). The time is in
    each panel's title. The animation plays at ``fps`` frames per second (not in real time).

    Parameters
    ----------
    scene : Scene
        A scene with a ``drawing`` (``q -> dict``, keys in :mod:`gausspp.plot.frames`); a model has none.
    traj : Trajectory, ServoTrajectory, or mapping of str to them
        Anything with samples ``t`` (N,) and ``q`` (N, nq); a mapping ``label → run`` (runs of the same
        mechanism, e.g. two realizations of one constraint) plays them side by side, one panel each, at
        the same times (over the span all runs cover).
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
    ShapeError
        A run without samples ``t`` (N,) and ``q`` (N, nq).
    GaussppError
        matplotlib missing, or ``.mp4`` asked without ffmpeg.
    """
    plt = pyplot()
    from matplotlib.animation import FuncAnimation, writers

    draw = drawing_of(scene)
    runs = as_runs(traj, "runs") if isinstance(traj, Mapping) else {"": traj}
    samples = {label: _samples(label, run) for label, run in runs.items()}
    if int(fps) != fps or fps < 1:
        raise InputError(f"plot.animate: fps must be a positive integer, got {fps!r}")
    writer = _writer(out, writers)
    chosen = frame_samples([t for t, _ in samples.values()], frames, int(fps))
    fig, panels = _panels(plt, draw, runs, samples, chosen)
    heading = title if title is not None else str(getattr(scene, "name", ""))
    fig.suptitle(textwrap.fill(heading, width=int(13 * fig.get_figwidth())), fontsize=11)
    for panel in panels:  # lay the figure out on the last frame (its title is the widest), then keep it fixed
        panel.update(len(chosen[0]) - 1)

    def update(k: int) -> list[Any]:
        return [artist for panel in panels for artist in panel.update(k)]

    anim = FuncAnimation(fig, update, frames=len(chosen[0]), interval=1000.0 / fps, blit=False)
    fig.canvas.draw()  # the layout, once; the animation counts as drawn (no warning if it is never saved)
    fig.set_layout_engine("none")
    if writer == "pillow" and out is not None:
        save_gif(fig, update, len(chosen[0]), out, int(fps), dpi)
    elif writer is not None:
        anim.save(str(out), writer=writer, fps=int(fps), dpi=dpi)
    if out is not None:
        plt.close(fig)
    return anim


def _panels(
    plt: Any, draw: Any, runs: dict[str, Any], samples: dict[str, tuple[np.ndarray, np.ndarray]], chosen: list[Any]
) -> tuple[Any, list[Panel]]:
    """The figure, one panel per run side by side: its pictures at the ``chosen`` samples, its reaction arrows
    on one scale for all, the limits of every frame of every run, a size from the picture's aspect."""
    pictures = [[picture(draw, q[i]) for i in idx] for (_, q), idx in zip(samples.values(), chosen, strict=True)]
    all_arrows = [
        [arrows(p, None if getattr(run, "reaction", None) is None else np.asarray(run.reaction)[i])
         for p, i in zip(pics, idx, strict=True)]
        for run, pics, idx in zip(runs.values(), pictures, chosen, strict=True)
    ]  # fmt: skip
    box = limits([p for pics in pictures for p in pics])
    scale = arrow_scale(all_arrows, box[2])
    n = len(runs)
    (lo, hi, _), width = box, max(4.2, 6.4 / n)
    height = float(np.clip(width * (hi[1] - lo[1]) / (hi[0] - lo[0]) + 1.3, 2.6, 5.0))
    fig, axs = plt.subplots(1, n, figsize=(width * n + 0.4, height), layout="constrained", squeeze=False)
    panels = [
        Panel(ax, pics, arr, t[idx], box, scale, label, dense_way(draw, t, q, t[idx]))
        for ax, pics, arr, (t, q), idx, label in zip(
            axs[0], pictures, all_arrows, samples.values(), chosen, runs, strict=True
        )
    ]
    return fig, panels


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
