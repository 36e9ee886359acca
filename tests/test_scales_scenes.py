"""Every scene in other units and at rest (issue 42): the same status, the same events and the same relative accuracy
when its parameters are rewritten with lengths ×1e3, masses ×1e-3, times ×1e-2 (and the inverse), and a success
at rest at an equilibrium where it has one, and released 1e-9 … 1e-1 from it.

A scene is rewritten through its parameters, read with their documented units (``gausspp scenes NAME``,
:mod:`tests.units`); its coordinates' labels give the units to read the motion back in. The negative control: the
same comparison with the old absolute tolerance (``atol=1e-10`` in whatever units) fails."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes import parameter_docs

from . import units

#: Lengths ×1e3, masses ×1e-3, times ×1e-2, and the inverse.
CHANGES = {"mm-tonne-hs": (1e-3, 1e3, 1e-2), "km-g-cs": (1e3, 1e-3, 1e2)}
#: The horizon of each comparison (s, in the scene's own units): long enough to move, short enough for the suite.
HORIZON = 0.5
#: A unit the docs give in words: the mixed realizations' M is 1/s for λ′ = λ and a pure number for λ′ = λ̇.
UNIT_OVERRIDES = {("mixed-proportional", "M"): "1/s", ("mixed-rate", "M"): "-"}
#: Not yet the same in other units: index reduction decides which derivative an actuator reaches by comparing
#: sensitivities with an absolute threshold (gausspp.step.servo_reach.REACH_TOL·(1 + …)), so in kilometres it
#: finds no reach and the one-step solution refuses the start. Left open (the closing note of issue 42).
UNIT_LIMITS = {
    "spring-chain-servo": "index reduction's reach test (servo_reach) compares sensitivities of different units",
}
#: Scenes whose physical constants are not all parameters: they cannot be rewritten in other units here.
FIXED_UNITS = {
    "ur5-tool-path": "the UR5's masses and lengths come from its URDF, in SI",
    "underactuated-arm": "the arm's masses and lengths come from its URDF, in SI",
}


def documented_units(name: str) -> dict[str, str]:
    docs = parameter_docs.describe(name)
    return {key: UNIT_OVERRIDES.get((name, key), doc.unit) for key, doc in docs.items()}


def horizon_params(scene: gp.scenes.Scene, name: str) -> dict[str, Any]:
    """The scene's parameters (those its builder documents) with its horizon cut to :data:`HORIZON` where it has
    one."""
    documented = parameter_docs.describe(name)
    params = {key: scene.params.get(key, doc.default) for key, doc in documented.items()}
    if "t_end" in params:
        params["t_end"] = min(float(params["t_end"]), HORIZON)
    return params


@dataclass
class Run:
    traj: gp.Trajectory
    q_back: np.ndarray  # the motion read back in the scene's own units
    t_back: np.ndarray
    events: list[tuple[str, float]]


def run_in_units(name: str, params: dict[str, Any], change: tuple[float, float, float] | None, **options: Any) -> Run:
    """The scene built from ``params`` rewritten by ``change`` (mass, length, time factors), run at the defaults to
    its horizon, recorded at 41 instants; its motion and events read back in the original units."""
    mass, length, time = change or (1.0, 1.0, 1.0)
    scene0 = gp.scenes.get(name, **params)
    scaled = units.rescaled(params, documented_units(name), mass, length, time) if change else params
    scene = gp.scenes.get(name, **scaled)
    t_end = scene.t_end
    grid = np.linspace(0.0, t_end, 41)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.DriftWarning)
        traj = gp.simulate(scene.model, scene.q0, scene.v0, t_end, lam0=scene.lam0, record=grid, throw=False, **options)
    factors = units.coordinate_factors(scene0.coordinates, mass, length, time)
    events = [(str(e.get("kind", "")), float(e["t"]) / time) for e in traj.events if "t" in e]
    return Run(traj, traj.q / factors[None, :], traj.t / time, events)


def relative_error(q: np.ndarray, reference: np.ndarray, labels: tuple[str, ...]) -> float:
    """The largest error of a coordinate over the run, relative to the largest value of the coordinates of its unit
    (lengths against lengths, angles against angles): the same number in any units."""
    unit = np.array([label[label.rfind("(") :] for label in labels])
    error = 0.0
    for u in set(unit):
        cols = unit == u
        size = np.abs(reference[:, cols]).max(initial=0.0)
        if size > 0:
            error = max(error, float(np.abs(q[:, cols] - reference[:, cols]).max(initial=0.0) / size))
    return error


def reference_motion(name: str, params: dict[str, Any], t: np.ndarray) -> np.ndarray:
    """The scene's exact motion where it is known, else a run at rtol 1e-13 on the same instants."""
    scene = gp.scenes.get(name, **params)
    if scene.exact is not None:
        return np.array([scene.exact(ti)[0] for ti in t])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.DriftWarning)
        tight = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, lam0=scene.lam0, rtol=1e-13, record=t,
                            throw=False)  # fmt: skip
    assert tight.t.size == t.size, tight.message
    return tight.q


def check_same_in_units(name: str, params: dict[str, Any], **options: Any) -> None:
    """The comparison the tests make: the same status and events in every set of units, and an error within 10× of
    the error in the scene's own units (both against the same reference, read back)."""
    base = run_in_units(name, params, None, **options)
    reference = reference_motion(name, params, base.t_back)
    labels = gp.scenes.get(name, **params).coordinates
    error = relative_error(base.q_back, reference, labels)
    for label, change in CHANGES.items():
        other = run_in_units(name, params, change, **options)
        assert other.traj.status == base.traj.status, f"{label}: {other.traj.message}"
        assert [k for k, _ in other.events] == [k for k, _ in base.events], label
        np.testing.assert_allclose([t for _, t in other.events], [t for _, t in base.events], rtol=1e-6, atol=1e-9)
        if base.traj.status == "failed":
            continue
        assert other.t_back.size == base.t_back.size
        other_error = relative_error(other.q_back, reference, labels)
        assert other_error <= 10 * max(error, 1e-13), f"{label}: relative error {other_error:.3g} against {error:.3g}"


NAMES = [name for name in gp.scenes.names()]


@pytest.mark.parametrize("name", NAMES)
def test_a_scene_in_other_units_runs_the_same(name: str) -> None:
    if name in FIXED_UNITS:
        pytest.skip(FIXED_UNITS[name])
    if name in UNIT_LIMITS:
        pytest.xfail(UNIT_LIMITS[name])
    scene = gp.scenes.get(name)
    check_same_in_units(name, horizon_params(scene, name))


def test_a_unit_dependent_tolerance_fails_the_comparison() -> None:
    """The negative control: an absolute tolerance of 1e-10 in whatever units — the old default — follows the
    pendulum in kilometres (its coordinates ~1e-3) to far less of its motion than in metres."""
    scene = gp.scenes.get("pendulum")
    with pytest.raises(AssertionError):
        check_same_in_units("pendulum", horizon_params(scene, "pendulum"), atol=1e-10)


# --- at rest ----------------------------------------------------------------------------------------------------

HANG = -np.pi / 2
#: For each scene with an equilibrium: the parameters that put it at rest there, and the parameter that releases it
#: from there (None: the scene has no parameter that moves it off that rest alone).
REST: dict[str, tuple[dict[str, Any], str | None]] = {
    "two-masses": ({"F": 0.0, "v": 0.0}, "v"),
    "rigid-body-servo": ({"omega0": (0.0, 0.0, 0.0)}, None),
    "gyrostat": ({"omega0": (0.0, 0.0, 0.0), "lam0": 0.0}, "lam0"),
    "gyrostat-extended": ({"omega0": (0.0, 0.0, 0.0), "lam0": 0.0}, "lam0"),
    "skate": ({"v0": 0.0, "omega0": 0.0, "lam0": 0.0}, "omega0"),
    "mixed-proportional": ({"x0": 0.0, "lam0": 0.0}, "x0"),
    "mixed-rate": ({"x0": 0.0, "lam0": 0.0}, "x0"),
    "stiff-chain": ({"amplitude": 0.0}, "amplitude"),
    "pendulum": ({"phi0": HANG, "omega0": 0.0}, "phi0"),
    "block-on-floor": ({"drop": 0.0, "tilt": 0.0, "vx": 0.0}, "vx"),
    "two-actuator-servo": ({"theta0": 0.0, "climb": 0.0}, None),
    "four-bar-redundant": ({"theta0": "hanging", "omega0": 0.0}, "theta0"),
    "planar-chain": ({"theta0": HANG}, "theta0"),
    "planar-ladder": ({"theta0": HANG}, "theta0"),
    "parallelogram": ({"theta0": HANG, "omega0": 0.0}, "theta0"),
    "spatial-parallelogram": ({"theta0": HANG, "omega0": 0.0}, "theta0"),
    "overhead-crane": ({"D": 0.0, "h": 0.0}, None),
    "spring-chain-servo": ({"distance": 0.0}, None),
    "underactuated-arm": ({"d": (0.0, 0.0)}, None),
}
#: Scenes without an equilibrium, and why.
NO_REST = {
    "andrews": "its motor turns it with a constant torque: no state of rest",
    "crane": "its rope hangs vertical only at rest, where the trolley's force cannot reach the payload (margin 0)",
    "saturated-crane": "as the crane: at rest its force realization cannot reach the payload",
    "ur5-tool-path": "its tool held still, the arm's three other degrees of freedom fall under gravity",
    "bouncing-pendulum": "it rests hanging against its wall, at θ = 0, which the scene refuses (it is released on the "
    "wall's side, 0 < θ₀ < π)",
}


def test_every_scene_is_listed_at_rest_or_says_why_not() -> None:
    assert set(REST) | set(NO_REST) == set(gp.scenes.names())


def at_rest(name: str) -> dict[str, Any]:
    """The scene's parameters at rest at its equilibrium (:data:`REST`)."""
    scene = gp.scenes.get(name)
    params = {**horizon_params(scene, name), **REST[name][0]}
    if params.get("theta0") == "hanging":
        params["theta0"] = hanging_angle(name, params)
    return params


def hanging_angle(name: str, params: dict[str, Any]) -> float:
    """The crank angle where a one-degree-of-freedom linkage hangs at rest: the root of its acceleration at rest,
    between the angles where gravity turns it one way and the other (scanned over a turn, then Brent's method)."""
    from scipy.optimize import brentq

    def acceleration(theta: float) -> float:
        scene = gp.scenes.get(name, **{**params, "theta0": theta})
        return float(scene.model.step(0.0, scene.q0, scene.v0, scene.lam0).a[0])

    grid = np.linspace(-np.pi, np.pi, 25)
    values = [acceleration(theta) for theta in grid]
    for a, b, fa, fb in zip(grid, grid[1:], values, values[1:], strict=False):
        if fa > 0 > fb:  # restoring: the stable equilibrium
            return float(brentq(acceleration, a, b, xtol=1e-15))
    raise AssertionError(f"{name}: no stable equilibrium found over a turn")


@pytest.mark.parametrize("name", sorted(REST))
def test_a_scene_at_rest_stays_there(name: str) -> None:
    """At rest at its equilibrium, at the defaults: a success, and it stays (its acceleration there is round-off)."""
    params = at_rest(name)
    scene = gp.scenes.get(name, **params)
    try:
        step = scene.model.step(0.0, scene.q0, scene.v0, scene.lam0)
        assert np.abs(step.a).max() < 1e-9  # the precondition: an equilibrium
    except gp.RealizabilityError:  # a servo reached through higher derivatives: index reduction holds it
        pass
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, lam0=scene.lam0)
    assert traj.status == "success", traj.message
    assert np.abs(traj.q - scene.q0).max() < 1e-8
    if name not in FIXED_UNITS and name not in UNIT_LIMITS:
        check_same_in_units(name, params)


RELEASES = [(name, p) for name, (_, p) in sorted(REST.items()) if p is not None]


@pytest.mark.parametrize("amplitude", [1e-9, 1e-6, 1e-3, 1e-1])
@pytest.mark.parametrize(("name", "param"), RELEASES)
def test_a_scene_released_near_rest_is_a_success(name: str, param: str, amplitude: float) -> None:
    """Released ``amplitude`` from rest (a parameter of its own units moved by that much: an angle in radians, a
    velocity in m/s, …), at the defaults: a success, and the motion is of the size it was released with."""
    params = at_rest(name)
    params[param] = params[param] + amplitude if np.ndim(params[param]) == 0 else params[param]
    scene = gp.scenes.get(name, **params)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, lam0=scene.lam0)
    assert traj.status == "success", traj.message
    rest = gp.scenes.get(name, **at_rest(name))
    moved = np.abs(traj.q - rest.q0).max()
    assert moved < 1e3 * amplitude + 1e-12  # a small release makes a small motion
