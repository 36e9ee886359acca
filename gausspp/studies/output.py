"""A trajectory written to files: ``<scene>.npz`` (:meth:`gausspp.Trajectory.save`'s format: every array, the
model's names, the run's settings, the scene and its parameters), ``<scene>.csv`` (named columns) and, with
matplotlib, ``<scene>.png`` (q(t) and v(t)); or one file ``.npz`` / ``.nc`` (netCDF) in that format."""

from __future__ import annotations

import inspect
import json
from pathlib import Path
from typing import Any

import numpy as np

from .. import plot, scenes
from ..errors import GaussppError
from ..simulation.labelled import energy_balance, is_trajectory_file
from ..simulation.trajectory import Trajectory
from .tables import label


def columns(traj: Trajectory) -> tuple[list[str], np.ndarray]:
    """The trajectory as named columns (for CSV): ``t``, ``q1…``, ``v1…``, ``lam1…``, …, ``energy_balance``."""
    names, blocks = ["t"], [traj.t[:, None]]
    for key in ("q", "v", "lam", "a", "u", "residual", "g"):
        arr = getattr(traj, key)
        names += [f"{key}{i + 1}" for i in range(arr.shape[1])]
        blocks.append(arr)
    for key in ("margin", "compulsion", "energy", "work_reaction", "work_forces"):
        arr = getattr(traj, key)
        if arr.size == traj.t.size:
            names.append(key)
            blocks.append(arr[:, None])
    names.append("energy_balance")
    blocks.append(energy_balance(traj)[:, None])
    return names, np.hstack(blocks) if traj.t.size else np.zeros((0, len(names)))


#: The suffixes that make ``--out`` one trajectory file rather than a directory.
FILE_SUFFIXES = (".npz", ".nc")
#: The suffixes that make ``--out`` the figure of ``q(t)`` and ``v(t)`` alone.
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")


def check_out(out: Path, scene_name: str) -> None:
    """Refuse, before the run, an ``out`` the trajectory cannot be written to without changing a file that is not
    gausspp's output: a file where a directory is meant, a directory where a file is meant, an existing
    ``.npz``/``.nc`` that is not a saved trajectory, an existing CSV that is not one written here."""
    suffix = out.suffix.lower()
    if suffix in FIGURE_SUFFIXES or suffix in FILE_SUFFIXES:
        check_file_target(out, "--out")
        if suffix in FIGURE_SUFFIXES:
            return
        targets = [out]
    elif out.exists() and not out.is_dir():
        raise GaussppError(f"--out {str(out)!r} is a file: give a directory (or a .npz, .nc or figure file name)")
    else:
        check_file_target(out, "--out", directory=True)
        targets = [out / f"{scene_name}.npz", out / f"{scene_name}.csv"]
    for target in targets:
        if target.is_dir():
            raise GaussppError(f"--out {str(out)!r}: {str(target)!r} is a directory")
        ours = _is_our_csv(target) if target.suffix == ".csv" else is_trajectory_file(target)
        if target.exists() and not ours:
            raise GaussppError(
                f"--out {str(out)!r}: {str(target)!r} exists and is not gausspp's output; choose another --out, or "
                "move that file"
            )


def check_file_target(path: Path, option: str, directory: bool = False) -> None:
    """Refuse, before the run, a path whose folders cannot hold it (a regular file on the way), or a file name that
    names a directory (``option``: the command-line option, for the message; ``directory``: ``path`` is one)."""
    if path.is_dir() and not directory:
        raise GaussppError(f"{option} {str(path)!r} is a directory, not a file name")
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise GaussppError(f"{option} {str(path)!r}: {str(parent)!r} is a file, not a directory")
            break


def _is_our_csv(path: Path) -> bool:
    """A CSV written by :func:`write_trajectory` (its header starts with the time and the coordinates)."""
    try:
        with path.open(encoding="utf-8") as fh:
            return fh.readline().startswith("t,q1")
    except (OSError, UnicodeDecodeError):
        return False


def write_trajectory(traj: Trajectory, scene: scenes.Scene, params: dict[str, Any], out: Path) -> list[Path]:
    """``out`` a ``.npz`` or ``.nc`` file: the trajectory in :meth:`~gausspp.Trajectory.save`'s format (with the
    scene and its parameters), read back by :func:`gausspp.load_trajectory`. Otherwise ``out`` is a directory:
    ``<scene>.npz`` (the same format), ``<scene>.csv`` and, with matplotlib, ``<scene>.png``. ``out`` a ``.png``,
    ``.svg`` or ``.pdf`` file: that figure alone (labelled with the scene's coordinates and their units)."""
    if out.suffix.lower() in FIGURE_SUFFIXES:
        out.parent.mkdir(parents=True, exist_ok=True)
        png = plot_trajectory(traj, f"{label(scene.name, params)} · {traj.method} · {traj.status}", out, scene)
        return [png] if png is not None else []
    attrs = dict(scene=scene.name, params=json.dumps(params, default=repr))
    try:
        if out.suffix.lower() in FILE_SUFFIXES:
            out.parent.mkdir(parents=True, exist_ok=True)
            return [traj.save(out, attrs)]
        out.mkdir(parents=True, exist_ok=True)
        base = out / scene.name
        traj.save(base.with_suffix(".npz"), attrs)
        names, data = columns(traj)
        np.savetxt(base.with_suffix(".csv"), data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
        files = [base.with_suffix(".npz"), base.with_suffix(".csv")]
    except OSError as exc:
        raise GaussppError(f"cannot write to {out}: {exc.strerror or exc}") from exc
    if len(traj):
        png = plot_trajectory(traj, f"{label(scene.name, params)} · {traj.method} · {traj.status}", base, scene)
        if png is not None:
            files.append(png)
    return files


def _draw(plt: Any, traj: Trajectory, title: str, scene: scenes.Scene | None = None) -> Any:
    """q(t) and v(t): ``gausspp.plot.trajectory`` if there is one (labelled with the scene's coordinates), else
    two plain panels."""
    drawer = getattr(plot, "trajectory", None)
    if drawer is not None and "names" in inspect.signature(drawer).parameters and scene is not None:
        return drawer(traj, title=title, names=scene.coordinates, v_labels=scene.velocity_names)
    if drawer is not None and "title" in inspect.signature(drawer).parameters:
        return drawer(traj, title=title)
    if drawer is not None:
        fig = drawer(traj)
        fig.suptitle(title, fontsize=9)
        return fig
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
    for ax, key, sym in ((axes[0], "q", "q"), (axes[1], "v", "v")):
        arr = getattr(traj, key)
        for i in range(arr.shape[1]):
            ax.plot(traj.t, arr[:, i], label=f"{sym}{i}")
        ax.set_ylabel(sym)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=min(arr.shape[1], 6), loc="best")
    axes[1].set_xlabel("t")
    fig.suptitle(title, fontsize=9)
    return fig


def plot_trajectory(traj: Trajectory, title: str, base: Path, scene: scenes.Scene | None = None) -> Path | None:
    """q(t) and v(t) as ``<base>.png`` (or ``base`` itself if it names a figure file), labelled with ``scene``'s
    coordinate names and units; None (with a note on stdout) without matplotlib."""
    try:
        plt = plot.pyplot()
    except GaussppError as exc:
        print(f"(no plot: {exc})")
        return None
    fig = _draw(plt, traj, title, scene)
    path = base if base.suffix.lower() in FIGURE_SUFFIXES else base.with_suffix(".png")
    try:
        fig.savefig(path, dpi=110, bbox_inches="tight")
    except OSError as exc:
        raise GaussppError(f"cannot write {path}: {exc.strerror or exc}") from exc
    finally:
        plt.close(fig)
    return path
