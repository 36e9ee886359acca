"""Figures (matplotlib, an optional extra: ``pip install gausspp[plots]``).

Every function draws on a given axes or a new figure and returns the figure; saving is the
caller's choice. A non-interactive backend is used when no display is available.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import GaussppError

if TYPE_CHECKING:
    from .report import Row


def _pyplot() -> Any:
    try:
        import matplotlib
    except ImportError:
        raise GaussppError("plots need matplotlib: pip install 'gausspp[plots]'") from None
    if not os.environ.get("DISPLAY") and "MPLBACKEND" not in os.environ:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def work_precision(rows: Sequence[Row], scene: str, ax: Any = None) -> Any:
    """Final-state error against wall time, log–log, one line per method and step solver."""
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
    ax.legend(fontsize=7, ncol=2)
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
