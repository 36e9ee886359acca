"""One constraint, several motions: a rigid body's ``(ω, l) = 0`` kept three ways; the skate under two laws."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import inertia_matrix, unit_vector
from .base import given, palette, pyplot, suffix, vec

#: Keys and legend labels of the runs of :func:`gausspp.studies.figures.three_realizations_runs`.
THREE_LABELS = {
    "ideal": "Ideal: Suslov's constraint (reaction along l)",
    "force": "Force: servo torque along n",
    "inertial": "Inertial: flywheel on axis n",
}
#: Colour (Okabe–Ito) and line style of each realization of :data:`THREE_LABELS`.
THREE_STYLE = {"ideal": (palette(0), "-"), "force": (palette(1), "--"), "inertial": (palette(2), "-.")}
#: Colour and legend label of each law of :func:`gausspp.studies.figures.skate_runs`.
SKATE_STYLE = {"nonholonomic": (palette(0), "nonholonomic (ideal)"), "vakonomic": (palette(3), "vakonomic")}


def plane_basis(I: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An orthonormal basis ``(e₁, e₂)`` of ``(ω, l) = 0``, ``e₁ ∥ l × Il`` where that is nonzero."""
    d = np.cross(l, I @ l)
    if np.linalg.norm(d) < 1e-12 * np.linalg.norm(I):
        d = np.cross(l, np.eye(3)[int(np.argmin(np.abs(l)))])
    e1 = d / np.linalg.norm(d)
    return e1, np.cross(l, e1)


def _given_runs(runs: Any, figure: str, study: str, keys: Any) -> dict[str, Any]:
    """``runs`` as a dict with exactly the ``keys`` of the study's result, or a clear error."""
    runs = given(runs, "runs", figure, study)
    if not isinstance(runs, Mapping):
        raise InputError(f"plot.{figure}: runs must be the mapping returned by {study}, got {type(runs).__name__}")
    missing = set(keys) - {str(k) for k in runs}
    if missing:
        raise InputError(f"plot.{figure}: runs must have the keys {list(keys)}; missing {sorted(missing)}")
    return {str(k): v for k, v in runs.items()}


def _plane_panel(plane: Any, runs: Mapping[str, Any], I: np.ndarray, l: np.ndarray, n: np.ndarray, steady: Any) -> None:
    """The paths of ``ω`` in the plane ``(ω, l) = 0``, the common start and Suslov's steady rotation (if given)."""
    e1, e2 = plane_basis(I, l)
    for key, (color, ls) in THREE_STYLE.items():
        w = runs[key].v
        plane.plot(w @ e1, w @ e2, ls, color=color, label=THREE_LABELS[key])
        plane.plot(w[-1] @ e1, w[-1] @ e2, "s", color=color, ms=6)
    w0 = runs["ideal"].v[0]
    plane.plot(w0 @ e1, w0 @ e2, "ko", ms=6, label="common start ω₀ (end: squares)")
    if steady is not None:
        w_inf = np.asarray(steady, dtype=float)
        plane.plot(w_inf @ e1, w_inf @ e2, "*", color=palette(0), ms=14, mec="k", label="Suslov's steady rotation ω∞")
    plane.set(
        xlabel=r"$(\omega, e_1)$,  $e_1 \parallel l \times Il$",
        ylabel=r"$(\omega, e_2)$,  $e_2 = l \times e_1$",
        title=f"ω in the constraint plane (ω, l) = 0 (rad/s): three motions (n = {vec(n)})",
    )
    plane.set_aspect("equal", adjustable="box")  # limits fit the paths: nothing but the motions fills the panel
    plane.grid(True, alpha=0.3)
    plane.legend(fontsize=8, loc="best")


def _omega_panels(top: Any, runs: Mapping[str, Any], colors: Any) -> None:
    """One panel per realization: ``ω₁, ω₂, ω₃`` over time."""
    comp = [r"$\omega_1$", r"$\omega_2$", r"$\omega_3$"]
    for ax, key in zip(top, THREE_LABELS, strict=True):
        tr = runs[key]
        for i in range(3):
            ax.plot(tr.t, tr.v[:, i], color=colors(i), label=comp[i])
        ax.set(xlabel="time t (s)", title=THREE_LABELS[key] + suffix("", tr))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    top[0].set_ylabel("body angular velocity ω (rad/s)")


def _inertia_text(I: np.ndarray) -> str:
    """``diag(1, 2, 3)`` for a diagonal inertia, else its rows."""
    if np.allclose(I, np.diag(np.diag(I))):
        return "diag" + vec(np.diag(I))
    return "(" + ", ".join(vec(row) for row in I) + ")"


def three_realizations(
    inertia: Any = (1.0, 2.0, 3.0),
    l: Any = (1.0, 1.0, 1.0),
    n: Any = (0.0, 0.0, 1.0),
    omega0: Any = None,
    lam0: Any = None,
    t_end: Any = None,
    *,
    runs: Mapping[str, Any] | None = None,
    steady: Any = None,
) -> Any:
    """ "One constraint, three realizations": the same body and ``(ω, l) = 0``, three motions.

    Top row, one panel per realization: the body angular velocity ``ω(t)``. Bottom left: the
    three paths of ``ω`` in the constraint plane ``(ω, l) = 0`` (coordinates on ``e₁ ∥ l × Il``,
    ``e₂ = l × e₁``), with Suslov's attracting steady rotation ``ω∞ ∥ l × Il`` where ``steady`` gives it.
    Bottom right: the kinetic energy of the carrier ``½ (Iω, ω)``, conserved by the ideal constraint (its
    reaction does no work on motions that keep it) and changed by the servo torque and by the flywheel.

    Parameters
    ----------
    inertia, l, n
        The body, the constraint and the torque axis the runs were made with.
    omega0, lam0, t_end
        Accepted for calls with the study's parameters; not used (the runs carry ``ω₀`` and time).
    runs : mapping
        The runs of :func:`gausspp.studies.figures.three_realizations_runs` (keys as in :data:`THREE_LABELS`).
    steady : (3,) array, optional
        Suslov's steady rotation ``ω∞`` (:func:`gausspp.scenes.suslov.steady_rotation`), drawn as a star.

    Returns
    -------
    matplotlib.figure.Figure
        Five axes: three ``ω(t)`` panels, the constraint plane, the energy.
    """
    study = "gausspp.studies.figures.three_realizations_runs(inertia, l, n, omega0, lam0, t_end)"
    runs = _given_runs(runs, "three_realizations", study, THREE_LABELS)
    I, lv = inertia_matrix("plot.three_realizations", inertia), unit_vector("plot.three_realizations", "l", l)
    nv = unit_vector("plot.three_realizations", "n", n)
    plt = pyplot()
    fig = plt.figure(figsize=(13, 8), layout="constrained")
    grid = fig.add_gridspec(2, 3)
    top = [fig.add_subplot(grid[0, 0])]
    top += [fig.add_subplot(grid[0, j], sharey=top[0]) for j in (1, 2)]
    plane, energy = fig.add_subplot(grid[1, :2]), fig.add_subplot(grid[1, 2])
    _omega_panels(top, runs, palette)
    _plane_panel(plane, runs, I, lv, nv, steady)
    for key, (color, ls) in THREE_STYLE.items():
        w = runs[key].v
        energy.plot(runs[key].t, 0.5 * np.einsum("ti,ij,tj->t", w, I, w), ls, color=color, label=key)
    energy.set(xlabel="time t (s)", ylabel=r"$\frac{1}{2}(I\omega, \omega)$ (J)", title="kinetic energy of the body")
    energy.grid(True, alpha=0.3)
    energy.legend(fontsize=8)
    w0 = runs["ideal"].v[0]
    fig.suptitle(
        f"Suslov's body (gausspp.scenes.suslov): inertia I = {_inertia_text(I)} kg·m², "
        f"constraint (ω, l) = 0 with l = {vec(lv)}, torque axis n = {vec(nv)}\n"
        f"kept three ways from the same ω₀ = {vec(w0)} rad/s, t = 0…{runs['ideal'].t[-1]:g} s"
    )
    return fig


def skate(*parameters: Any, runs: Mapping[str, Any] | None = None, title: str | None = None) -> Any:
    """The nonholonomic and the vakonomic skate: one constraint, two laws of motion.

    Left: the contact point's paths ``(x(t), y(t))`` with the blade's heading ``θ`` drawn as
    arrows along them. The nonholonomic skate (d'Alembert–Lagrange) turns uniformly,
    ``θ̇ = ω₀``, and runs along a circle of radius ``v₀/ω₀``; the vakonomic one obeys
    ``J θ̈ = −(|p|²/2m) sin 2(α − θ)`` (a pendulum in ``θ``, see :mod:`gausspp.scenes.skate`).
    Right: the heading ``θ(t)``.

    Parameters
    ----------
    *parameters
        Accepted for calls with the study's parameters ``m, J, v0, omega0, theta0, lam0, t_end``;
        not used (the runs carry them).
    runs : mapping
        The result of :func:`gausspp.studies.figures.skate_runs` (keys ``"nonholonomic"``, ``"vakonomic"``).
    title : str, optional
        The figure's title; the default states the constraint, not the parameters (the caller knows them).

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the plane, the heading.
    """
    runs = _given_runs(runs, "skate", "gausspp.studies.figures.skate_runs(m, J, v0, omega0, ...)", SKATE_STYLE)
    plt = pyplot()
    fig, (ax, axt) = plt.subplots(1, 2, figsize=(12, 5), width_ratios=(1.3, 1), layout="constrained")
    for law, (color, label) in SKATE_STYLE.items():
        tr = runs[law]
        x, y, th = tr.q[:, 0], tr.q[:, 1], tr.q[:, 2]
        ax.plot(x, y, color=color, label=label + suffix("", tr))
        k = np.linspace(0, tr.t.size - 1, 16).astype(int)
        ax.quiver(x[k], y[k], np.cos(th[k]), np.sin(th[k]), color=color, angles="xy", scale=22, width=0.004)
        axt.plot(tr.t, th, color=color, label=label)
    ax.plot(runs["nonholonomic"].q[0, 0], runs["nonholonomic"].q[0, 1], "ko", label="start")
    ax.set(xlabel="x (m)", ylabel="y (m)", title="contact point in the plane (arrows: the blade's heading)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    axt.set(xlabel="time t (s)", ylabel="heading θ (rad)", title="heading of the blade")
    axt.grid(True, alpha=0.3)
    axt.legend(fontsize=8)
    fig.suptitle(title or "Skate: no sideways slip (−sin θ ẋ + cos θ ẏ = 0), two laws of motion from the same start")
    return fig
