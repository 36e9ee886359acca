"""The runs behind the teaching figures: one constraint kept three ways, the skate under two laws.

Each function simulates and returns its trajectories; :func:`gausspp.plot.three_realizations` and
:func:`gausspp.plot.skate` draw them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import scenes
from ..scenes import Scene
from ..scenes.suslov import steady_rotation
from ..simulation.simulate import simulate
from ..simulation.trajectory import Trajectory

#: The keys of :func:`three_realizations_runs`, in drawing order.
THREE_KEYS = ("ideal", "force", "inertial")
#: The keys of :func:`skate_runs`: the two laws of motion.
SKATE_LAWS = ("nonholonomic", "vakonomic")


def tight_run(scene: Scene, times: np.ndarray) -> Trajectory:
    """``scene`` integrated by DOP853 (``rtol = 1e-10``, ``atol = 1e-12``), recorded at ``times``."""
    return simulate(
        scene.model,
        scene.q0,
        scene.v0,
        scene.t_end,
        lam0=scene.lam0,
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
        record=times,
    )


def three_realizations_runs(
    inertia: Any = (1.0, 2.0, 3.0),
    l: Any = (1.0, 1.0, 1.0),
    n: Any = (0.0, 0.0, 1.0),
    omega0: Any = (0.0, 1.0, -1.0),
    lam0: float = 0.0,
    t_end: float = 10.0,
    samples: int = 401,
) -> dict[str, Trajectory]:
    """Simulate one rigid body and one constraint ``(ω, l) = 0`` kept in three ways, from one ``ω₀``.

    * ``"ideal"``: the scene ``rigid-body-servo`` with ``n = l`` — Suslov's nonholonomic problem,
      ``Iω̇ + ω × Iω = μ l`` (paper §2 with the reaction normal to the constraint);
    * ``"force"``: ``rigid-body-servo`` with the torque ``λn`` along ``n`` (Béghin servo, eq. (10));
    * ``"inertial"``: the scene ``gyrostat``, a rotor on axis ``n`` with angular momentum ``λ``,
      ``d/dt(Iω + λn) + ω × (Iω + λn) = 0`` (eqs. (14)–(15)), ``λ(0) = lam0``.

    The force and flywheel realizations need ``(I⁻¹n, l) ≠ 0`` (conditions (12), (16)).
    Integrated by DOP853 (``rtol = 1e-10``), recorded at ``samples`` uniform times.

    Returns
    -------
    dict of str to Trajectory
        Keys ``"ideal"``, ``"force"``, ``"inertial"`` (:data:`THREE_KEYS`).
    """
    common = dict(inertia=inertia, l=l, omega0=omega0, t_end=t_end)
    built = {
        "ideal": scenes.get("rigid-body-servo", n=None, **common),
        "force": scenes.get("rigid-body-servo", n=n, **common),
        "inertial": scenes.get("gyrostat", n=n, lam0=lam0, **common),
    }
    times = np.linspace(0.0, float(t_end), int(samples))
    return {key: tight_run(built[key], times) for key in THREE_KEYS}


def suslov_steady(inertia: Any = (1.0, 2.0, 3.0), l: Any = (1.0, 1.0, 1.0), omega0: Any = (0.0, 1.0, -1.0)) -> Any:
    """Suslov's steady rotation ``ω∞`` that the ideal run of :func:`three_realizations_runs` tends to (its
    figure's star: :func:`gausspp.plot.three_realizations`'s ``steady``)."""
    return steady_rotation(inertia, l, omega0)


def skate_runs(
    m: float = 1.0,
    J: float = 0.1,
    v0: float = 1.0,
    omega0: float = 1.0,
    theta0: float = 0.0,
    lam0: float = 0.5,
    t_end: float = 10.0,
    samples: int = 501,
) -> dict[str, Trajectory]:
    """The skate (scene ``skate``) from the same initial data under both laws of motion.

    ``"nonholonomic"``: the ideal constraint ``−sin θ ẋ + cos θ ẏ = 0`` (reaction ``λ(−sin θ, cos θ, 0)``);
    ``"vakonomic"``: the same constraint, vakonomic (eqs. (17)–(18), ``λ(0) = lam0``).
    Integrated by DOP853 (``rtol = 1e-10``), recorded at ``samples`` uniform times.

    Returns
    -------
    dict of str to Trajectory
        Keys ``"nonholonomic"``, ``"vakonomic"`` (:data:`SKATE_LAWS`).
    """
    times = np.linspace(0.0, float(t_end), int(samples))
    params = dict(m=m, J=J, v0=v0, omega0=omega0, theta0=theta0, lam0=lam0, t_end=t_end)
    return {law: tight_run(scenes.get("skate", realization=law, **params), times) for law in SKATE_LAWS}


def skate_title(
    m: float = 1.0,
    J: float = 0.1,
    v0: float = 1.0,
    omega0: float = 1.0,
    theta0: float = 0.0,
    lam0: float = 0.5,
    t_end: float = 10.0,
) -> str:
    """The skate figure's title: scene, parameters (with units) and the constraint, for :func:`skate_runs`'s
    parameters (the same defaults). ``λ`` multiplies the constraint ``Φ`` (a velocity) in ``T* = T + λΦ``,
    so it is a momentum (kg·m/s)."""
    return (
        f"scene skate (knife edge): m = {m:g} kg, J = {J:g} kg·m², v0 = {v0:g} m/s, ω0 = {omega0:g} rad/s, "
        f"θ0 = {theta0:g} rad, vakonomic λ(0) = {lam0:g} kg·m/s; t = 0 … {t_end:g} s\n"
        "no sideways slip −sin θ ẋ + cos θ ẏ = 0: nonholonomic vs vakonomic"
    )
