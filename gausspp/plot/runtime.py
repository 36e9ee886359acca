"""Work-precision figures: final-state error against run time (the rows of :mod:`gausspp.report`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .base import STYLES, palette, pyplot

#: Markers telling the step solvers apart (with the line styles).
MARKERS = ("o", "s", "^", "D")


def work_precision(rows: Sequence[Any], scene: str, ax: Any = None, *, title: str | None = None) -> Any:
    """Final-state error against wall time, log–log, one line per method and step solver.

    Each point is one run of :func:`gausspp.report.work_precision` (a step size or a tolerance
    of the sweep), its error ``max |x − x_ref| / max(1, |x_ref|)`` over ``q`` and ``v`` at the
    final time against the wall time (minimum of repeats): lower left is better.

    Parameters
    ----------
    rows : sequence of gausspp.report.Row
    scene : str
        The scene whose rows are drawn.
    ax : matplotlib axes, optional
        Where to draw (else a new figure).
    title : str, optional
        The scene's parameters with units (``"m = 1 kg, L = 1 m, t_end = 1 s"``), put after the scene's name in
        the title.
    """
    plt = pyplot()
    fig = ax.figure if ax is not None else plt.figure(figsize=(7, 4.5))
    ax = ax or fig.add_subplot()
    mine = [r for r in rows if r.scene == scene and r.status != "failed" and r.final_error > 0]
    methods = list(dict.fromkeys(r.method for r in mine))
    solvers = list(dict.fromkeys(r.solver for r in mine))
    for key in dict.fromkeys((r.method, r.solver) for r in mine):
        pts = [(r.wall_time, r.final_error) for r in mine if (r.method, r.solver) == key]  # in sweep order
        m, s_ = methods.index(key[0]), solvers.index(key[1]) % len(STYLES)
        ax.loglog(
            *zip(*pts, strict=True),
            linestyle=STYLES[s_],
            marker=MARKERS[s_],
            color=palette(m),
            label=f"{key[0]} · {key[1]}",
            ms=4,
        )
    failed = sum(1 for r in rows if r.scene == scene and r.status == "failed")
    head = f"scene {scene}" + (f" ({title})" if title else "")
    ax.set(
        xlabel="wall time (s), minimum of repeats",
        ylabel="final-state error (1): max |x − x_ref| / max(1, |x_ref|)",
        title=f"{head}: error against run time" + (f" ({failed} failed runs in the table)" if failed else ""),
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), title="method · step solver")
    return fig


def save_work_precision(rows: Sequence[Any], out: Path, titles: Mapping[str, str] | None = None) -> list[Path]:
    """One PNG per scene in ``out``; ``titles`` maps a scene to its parameters for the title (see
    :func:`work_precision`)."""
    plt = pyplot()
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for scene in dict.fromkeys(r.scene for r in rows):
        fig = work_precision(rows, scene, title=(titles or {}).get(scene))
        path = out / f"work_precision_{scene}.png"
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        paths.append(path)
    return paths
