"""The figure of the integral principle (23): the minimizing variation ``δx(t)`` and the verdict."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import InputError
from .base import as_runs, legend, palette, pyplot


def _paths_per_check(checks: Mapping[str, Any], traj: Any) -> dict[str, Any] | None:
    """The path of each check: one for all, one per check key, or None."""
    if traj is None:
        return None
    if isinstance(traj, Mapping):
        missing = set(checks) - {str(k) for k in traj}
        if missing:
            raise InputError(f"traj has no trajectory for the checks {sorted(missing)}")
        return {k: traj[k] for k in checks}
    return dict.fromkeys(checks, traj)


def _variation_panel(ax: Any, name: str, c: Any, colors: Any) -> None:
    """``δx(t)`` of one check, the verdict in the title (green: a motion; red: not)."""
    for i in range(c.delta_x.shape[1]):
        ax.plot(c.t, c.delta_x[:, i], ".-", ms=3, color=colors(i), label=f"$\\delta x_{{{i + 1}}}$")
    verdict = "a motion" if c.is_motion else "NOT a motion"
    ax.set_title(
        (f"{name}\n" if name else "") + f"relative gap {c.relative_gap:.2e} (tolerance {c.tolerance:.1e}): {verdict}",
        color=palette(2) if c.is_motion else palette(3),
        fontsize=10,
    )
    ax.set(ylabel="minimizing variation δx (units of q)")
    biggest = float(np.max(np.abs(c.delta_x), initial=0.0))
    ax.text(0.98, 0.03, f"max |δx| = {biggest:.1e}", transform=ax.transAxes, ha="right", va="bottom", fontsize=8)
    ax.grid(True, alpha=0.3)
    legend(ax)
    ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))


def _multiplier_panel(ax: Any, c: Any, tr: Any, colors: Any) -> None:
    """The multipliers of (20) recovered by the check against the path's own ``λ`` (or ``u``)."""
    k = c.multipliers.shape[1]
    own = tr.lam if tr.lam.shape[1] == k else (tr.u if tr.lam.shape[1] == 0 and tr.u.shape[1] == k else None)
    for r in range(k):
        lam_r = f"$\\lambda_{{{r + 1}}}$"
        ax.plot(c.t, c.multipliers[:, r], "o", ms=3, color=colors(r), label=f"{lam_r} from (20)")
        if own is not None:
            ax.plot(tr.t, own[:, r], "-", color=colors(r), lw=1, label=f"{lam_r} of the path")
    ax.set(xlabel="time t (s)", ylabel="multiplier λ (N, N·m: per row)", title="multipliers of (20) vs the path's λ")
    ax.grid(True, alpha=0.3)
    legend(ax)


def verification(check: Any, traj: Any = None, *, title: str | None = None) -> Any:
    """The minimizing variation of the integral principle (23) and the verdict.

    For a path ``x(t)`` on the constraint, with ``R = [T] − F`` along it, :func:`gausspp.verify`
    minimizes ``(1/T) ∫ (G⁻¹(R + Gδx), R + Gδx) dt`` over variations ``δx`` that vanish at the
    ends and obey the realization's relation (20). The relative gap
    ``(value at δx = 0 − minimum) / value at δx = 0`` is zero (to discretization error) iff the
    path is a motion; the minimizing ``δx(t)`` shows where and how a path fails (it is
    ``−G⁻¹`` times the part of ``R`` that does work on admissible variations).

    One column per check: ``δx(t)`` with the relative gap, the tolerance and the verdict in the
    title (green: a motion; red: not). With ``traj`` a second row compares the multipliers of
    (20) recovered by the check with the trajectory's own ``λ`` (its state ``λ`` for flywheel
    realizations, else ``u``).

    Parameters
    ----------
    check : Verification or mapping of str to Verification
    traj : Trajectory or mapping of str to Trajectory, optional
        The path(s) checked: one for all checks, or one per check key.
    title : str, optional
        The scene and its parameters with units (``"two-masses: m1 = 1 kg, …"``), a second line of the title.

    Returns
    -------
    matplotlib.figure.Figure
        ``len(check)`` axes, twice as many with ``traj``.
    """
    plt = pyplot()
    checks = as_runs(check, "verifications")
    trajs = _paths_per_check(checks, traj)
    ncols, nrows = len(checks), 1 if trajs is None else 2
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(5.5 * ncols, 3.6 * nrows), squeeze=False, sharex="col", layout="constrained"
    )
    colors = palette
    for j, (name, c) in enumerate(checks.items()):
        _variation_panel(axes[0, j], name, c, colors)
        if trajs is None:
            axes[0, j].set_xlabel("time t (s)")
        else:
            _multiplier_panel(axes[1, j], c, trajs[name], colors)
    head = "Integral principle (23): the variation δx that lowers the compulsion most"
    fig.suptitle(f"{head}\n{title}" if title else head)
    return fig
