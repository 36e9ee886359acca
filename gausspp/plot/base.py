"""What every figure shares: matplotlib on demand, runs given one or by label, labels, line styles, legends."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import GaussppError, InputError, ShapeError
from ..validation import short

#: Line styles that tell runs apart when several are drawn on one axes (colours tell components).
STYLES = ("-", "--", ":", "-.")
#: Markers that tell runs apart together with :data:`STYLES` (drawn every few samples).
MARKERS = ("o", "s", "^", "D")
#: The Okabe–Ito colour-blind-safe palette (Okabe & Ito 2008), black last: colours that tell series apart.
OKABE_ITO = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#F0E442", "#000000")
#: The models' default warning level of the realizability margin (``Model(margin_warn=...)``).
MARGIN_WARN = 1e-6


def pyplot() -> Any:
    """``matplotlib.pyplot``, with the Agg backend when there is no display; a clear error without matplotlib."""
    try:
        import matplotlib
    except ImportError:
        raise GaussppError("plots need matplotlib: pip install 'gausspp[plots]'") from None
    if not os.environ.get("DISPLAY") and "MPLBACKEND" not in os.environ:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def palette(i: int) -> str:
    """The ``i``-th colour of :data:`OKABE_ITO` (cycling)."""
    return OKABE_ITO[i % len(OKABE_ITO)]


#: Above this many labelled curves in one panel the legend gives way to a colour scale by component (a legend of
#: 96 entries would cover the axes).
LEGEND_MAX = 12
#: The colour scale of many components (perceptually uniform, readable in grey).
MANY = "viridis"


def component_color(i: int, n: int) -> Any:
    """Component ``i`` of ``n``: its Okabe–Ito colour while they are few, else its place on the :data:`MANY` scale
    from the first component to the last (so that neighbours in a chain are neighbours in colour)."""
    if n <= len(OKABE_ITO):
        return palette(i)
    return pyplot().get_cmap(MANY)(i / max(n - 1, 1))


def as_runs(obj: Any, what: str, needs: tuple[str, ...] = ("t",)) -> dict[str, Any]:
    """One object or a mapping ``label → object`` as a dict (label ``""`` for a lone object); each must have the
    attributes ``needs`` (a trajectory's ``t``, ``q``, ``v`` …), else an error naming what was given."""
    if isinstance(obj, Mapping):
        if not obj:
            raise InputError(f"nothing to plot: the mapping of {what} is empty")
        runs = {str(k): v for k, v in obj.items()}
    else:
        runs = {"": obj}
    for label, run in runs.items():
        if not all(hasattr(run, name) for name in needs):
            which = f" ({label!r})" if label else ""
            raise InputError(f"{what}{which}: expected a result of gausspp (with {', '.join(needs)}), got {short(run)}")
    return runs


def labels(given: Sequence[str] | None, n: int, symbol: str) -> list[str]:
    """``n`` legend labels: the ``given`` ones (checked in number) or ``symbol₁ … symbolₙ``."""
    if given is None:
        return [f"${symbol}_{{{i + 1}}}$" for i in range(n)]
    out = [str(s) for s in given]
    if len(out) != n:
        raise ShapeError(f"{symbol}_labels: {n} labels needed, got {len(out)}")
    return out


def carried_names(traj: Any, axis: str, n: int) -> list[str] | None:
    """The names ``traj`` carries from its model along ``axis`` (its ``labels``,
    :class:`gausspp.simulation.labels.Labels`), or None where it carries none (or not ``n`` of them)."""
    names = tuple(getattr(getattr(traj, "labels", None), axis, ()))
    return [str(s) for s in names] if len(names) == n and n else None


def suffix(name: str, traj: Any = None) -> str:
    """`` (name, failed at t=…)`` for a legend entry; empty for an unnamed successful run."""
    failed = traj is not None and getattr(traj, "status", "success") == "failed"
    tail = f"failed at t={traj.t[-1]:.3g}" if failed else ""
    inner = ", ".join(s for s in (name, tail) if s)
    return f" ({inner})" if inner else ""


def legend(ax: Any, components: int | None = None) -> None:
    """A legend sized to the number of labelled artists (none if there are none). Beyond :data:`LEGEND_MAX` of them,
    a colour bar from the first component to the last (``components`` of them, coloured by
    :func:`component_color`) and a note naming the first and the last instead."""
    names = ax.get_legend_handles_labels()[1]
    n = len(names)
    if not n:
        return
    if n <= LEGEND_MAX:
        ax.legend(fontsize=8 if n <= 8 else 6, ncol=1 if n <= 6 else 2, loc="best")
        return
    count = components or n
    if count > len(OKABE_ITO):
        plt = pyplot()
        scale = plt.cm.ScalarMappable(cmap=MANY, norm=plt.Normalize(1, count))
        ax.figure.colorbar(scale, ax=ax, label="component", fraction=0.05, pad=0.02)
    note = f"{n} curves: {names[0]} … {names[-1]}"
    ax.text(0.01, 0.99, note, transform=ax.transAxes, va="top", fontsize=7, bbox=dict(fc="white", alpha=0.7, lw=0))


def vec(v: np.ndarray) -> str:
    """A short vector for a title: ``(1, 0.5, 2)``."""
    return "(" + ", ".join(f"{x:.3g}" for x in v) + ")"


def given(value: Any, name: str, figure: str, study: str) -> Any:
    """``value``, or a clear error if the caller left it out: figures draw results, they do not compute them."""
    if value is None:
        raise InputError(
            f"plot.{figure}: {name} is missing — figures only draw results they are given; "
            f"compute them with {study} and pass {name}=..."
        )
    return value
