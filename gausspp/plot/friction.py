"""Figures of frictional runs: each contact's slip, normal and friction force and the energy; the stick/slip map."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .base import STYLES, palette, pyplot


def friction(runs: Mapping[str, Any], slips: Mapping[str, np.ndarray]) -> Any:
    """Three panels for the runs ``label → FrictionRun``: the slip ``slips[label]`` (one column per contact, from
    the caller), the normal force ``N`` and the friction ``F`` (dashed) of each contact, and the energy; the
    events (stick, slip, lift-off, impact) as dots on the slip."""
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 7.5), sharex=True)
    for k, (label, run) in enumerate(runs.items()):
        color = palette(k)
        slip = np.asarray(slips[label])
        for j, name in enumerate(run.contact_names):
            tag = f"{label} · {name}" if len(run.contact_names) > 1 else label
            axes[0].plot(run.t, slip[:, j], color=color, ls=STYLES[j % len(STYLES)], label=tag)
            axes[1].plot(run.t, run.N[:, j], color=color, ls="-", label=f"N {tag}")
            axes[1].plot(run.t, run.F[:, j], color=color, ls="--", label=f"F {tag}")
        for ev in run.events:
            i = min(int(np.searchsorted(run.t, ev["t"])), run.t.size - 1)
            j = run.contact_names.index(ev["contact"])
            axes[0].plot(ev["t"], slip[i, j], "o", color=color, ms=5)
        axes[2].plot(run.t, run.energy - run.energy[0], color=color, label=label)
    axes[0].set_ylabel("slip s (m/s)")
    axes[0].axhline(0.0, color="0.6", lw=0.8)
    axes[1].set_ylabel("N (—), F (- -)  (N)")
    axes[2].set_ylabel("E − E₀ (J)")
    axes[2].set_xlabel("t (s)")
    for ax in axes:
        ax.legend(fontsize=7, loc="best")
        ax.grid(alpha=0.3)
    axes[0].set_title("Coulomb friction: slip, contact forces and energy (dots: events)")
    fig.tight_layout()
    return fig


def stick_slip_map(alpha: np.ndarray, mu: np.ndarray, slides: np.ndarray) -> Any:
    """The simulated verdict of a block at rest on a slope (``slides[i, j]`` for ``mu[i]``, ``alpha[j]``) with the
    friction angle ``μ = tan α`` over it."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    ax.pcolormesh(np.degrees(alpha), mu, slides.astype(float), cmap="coolwarm", shading="nearest", vmin=0, vmax=1)
    fine = np.linspace(alpha.min(), alpha.max(), 400)
    ax.plot(np.degrees(fine), np.tan(fine), color="k", lw=2, label="μ = tan α (closed form)")
    ax.set_xlabel("slope α (degrees)")
    ax.set_ylabel("friction coefficient μ")
    ax.set_ylim(mu.min(), mu.max())
    ax.set_title("A block released at rest: sticks (blue) or slides (red)")
    ax.legend(loc="upper left")
    fig.tight_layout()
    return fig
