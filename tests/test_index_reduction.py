"""Servo-constraints beyond the one-step formula (issue 19): the diagnosis, index reduction, the replay.

The references are the scenes' flat solutions (gausspp/scenes/overhead_crane.py, spring_chain_servo.py), derived
with numpy polynomials from the path alone — nothing of index reduction (no Lie derivative, no extension, no feedback).
"""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp
from gausspp.servo.index_reduction import ServoTrajectory


@pytest.fixture(scope="module")
def crane() -> tuple[gp.scenes.Scene, ServoTrajectory]:
    scene = gp.scenes.get("overhead-crane")
    return scene, gp.simulate_servo(scene.model, scene.q0, scene.v0, scene.t_end)


def exact(scene: gp.scenes.Scene, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.array([scene.exact(ti)[0] for ti in t])
    forces = np.array([np.atleast_1d(scene.forces(ti)) for ti in t])
    return q, forces


def force_error(got: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Each actuator's largest error relative to its largest force."""
    return np.abs(got - reference).max(axis=0) / np.abs(reference).max(axis=0)


def test_the_crane_follows_its_flat_solution(crane) -> None:
    scene, traj = crane
    assert traj.status == "success" and traj.t[0] == 0.0 and traj.t[-1] == pytest.approx(scene.t_end)
    q, forces = exact(scene, traj.t)
    # tolerances ~100 times the achieved figures (an unstable feedback grows from round-off well past them)
    assert np.abs(traj.constraint).max() <= 1e-9  # the payload on its path, m (measured 4.0e-12)
    assert np.abs(traj.q[:, 0] - q[:, 0]).max() <= 1e-9  # the trolley, m
    assert np.abs(traj.q - q).max() <= 1e-9  # measured 5.3e-12
    assert np.all(force_error(traj.forces, forces) <= 5e-9)  # F1, F2 (measured 4.5e-11, 1.5e-12)
    assert not np.all(force_error(traj.forces * (1 + 1e-7), forces) <= 5e-9)  # a wrong force would show


def test_the_crane_is_diagnosed_mixed_of_index_five(crane) -> None:
    scene, traj = crane
    d = gp.servo_diagnosis(scene.model, 0.0, scene.q0, scene.v0)
    assert (d.geometry, d.index, d.unextended, d.degrees, d.chains) == ("mixed", 5, (2, 2), (4, 4), (0, 2))
    assert (traj.index, traj.degrees, traj.chains) == (5, (4, 4), (0, 2)) and not d.one_step
    assert "mixed realization" in d.describe() and "DAE index 5" in d.describe()


def test_the_crane_forces_alone_keep_the_payload_on_its_path(crane) -> None:
    """Open loop: the free crane under the returned forces (interpolated), no constraint, no feedback."""
    scene, traj = crane
    assert np.abs(gp.replay(scene.model, traj).constraint).max() <= 1e-7  # measured 1.3e-9
    wrong = ServoTrajectory(**{**vars(traj), "forces": traj.forces * (1 + 1e-5)})
    assert np.abs(gp.replay(scene.model, wrong).constraint).max() > 1e-7


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6])
def test_the_spring_chain_has_index_2n_plus_1_and_its_flat_force(n: int) -> None:
    scene = gp.scenes.get("spring-chain-servo", n=n)
    traj = gp.simulate_servo(scene.model, scene.q0, scene.v0, scene.t_end)
    assert traj.status == "success" and traj.index == 2 * n + 1 and traj.degrees == (2 * n,)
    _, forces = exact(scene, traj.t)
    assert force_error(traj.forces, forces)[0] <= 5e-9  # measured 2.3e-11 … 9.1e-11 over n = 1 … 6
    assert force_error(traj.forces + 1e-7 * np.abs(forces).max(), forces)[0] > 5e-9
    kind = gp.servo_diagnosis(scene.model, 0.0, scene.q0, scene.v0).geometry
    assert kind == ("orthogonal" if n == 1 else "tangential")  # one mass: the force acts on it directly


@pytest.mark.parametrize(
    ("name", "params", "kind"),
    [
        ("two-masses", {"realization": "ideal"}, "orthogonal"),
        ("two-masses", {"realization": "servo"}, "oblique"),
        ("rigid-body-servo", {}, "orthogonal"),  # the torque along the normal (in the metric I⁻¹)
        ("rigid-body-servo", {"n": (1.0, 0.2, 0.0)}, "oblique"),
        ("pendulum", {}, "orthogonal"),
        ("andrews", {}, "orthogonal"),
    ],
)
def test_todays_scenes_are_orthogonal_or_oblique_and_one_step(name: str, params: dict, kind: str) -> None:
    scene = gp.scenes.get(name, **params)
    d = gp.servo_diagnosis(scene.model, 0.0, scene.q0, scene.v0)
    assert d.geometry == kind and d.one_step and not any(d.chains)
    assert max(d.degrees) <= 2  # the forces appear in the constraint's first (velocity rows) or second derivative


def test_the_one_step_refusal_points_to_index_reduction() -> None:
    """model.step cannot keep the crane's path step by step and says what can; gp.simulate takes
    index reduction by itself (tests/test_servo_lane.py)."""
    scene = gp.scenes.get("overhead-crane")
    with pytest.raises(gp.RealizabilityError) as caught:
        scene.model.step(0.0, scene.q0, scene.v0)
    message = str(caught.value)
    assert "gp.simulate_servo" in message and "index 5" in message
    assert "choose force directions" not in message  # not the advice to change the actuators
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.0)
    assert traj.success and traj.lane == "servo"
    pendulum = gp.scenes.get("pendulum", t_end=0.1)
    assert gp.simulate(pendulum.model, pendulum.q0, pendulum.v0, 0.1).failure is None


def test_an_actuator_that_never_reaches_keeps_the_old_advice() -> None:
    """Two free masses, the constraint on the second, the force on the first: no derivative ever reaches it."""
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2))
    servo = gp.Holonomic(lambda q, t: q[1] - 0.1 * t**2, name="x2", realization=gp.Force(lambda q, v, t: [[1, 0]]))
    model = gp.Model(body, servo)
    with pytest.raises(gp.RealizabilityError, match="choose force directions"):
        model.step(0.0, [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(gp.InputError, match="no actuator reaches constraint row"):
        gp.simulate_servo(model, [0.0, 0.0], [0.0, 0.0], 1.0)


def test_a_start_off_the_path_is_made_consistent_or_refused() -> None:
    scene = gp.scenes.get("spring-chain-servo", n=2)
    traj = gp.simulate_servo(scene.model, scene.q0 + 1e-3, scene.v0, 0.5)  # near the path: pulled onto it
    assert np.abs(traj.constraint).max() <= 1e-8
    with pytest.raises(gp.InputError, match="t_end must be after"):
        gp.simulate_servo(scene.model, scene.q0, scene.v0, 0.0)


def test_the_integral_principle_accepts_the_servo_motion_and_refuses_others(crane) -> None:
    """(23) with the servo's own virtual displacements: the route's motion is one; the same payload path with
    the trolley moved otherwise (other forces, the rope and angle following) is not; the replay under perturbed
    forces leaves the path and is refused."""
    from scipy.interpolate import CubicSpline

    from gausspp.servo.index_reduction import ServoTrajectory

    scene, _ = crane
    traj = gp.simulate_servo(scene.model, scene.q0, scene.v0, scene.t_end, record=np.linspace(0, scene.t_end, 801))
    assert gp.verify(scene.model, traj).is_motion
    s, l, theta = traj.q.T
    X, Y = s + l * np.sin(theta), -l * np.cos(theta)
    s2 = s + 1e-3 * np.sin(np.pi * traj.t / scene.t_end) ** 2  # the trolley off its motion by up to 1 mm
    q2 = np.column_stack([s2, np.hypot(X - s2, Y), np.arctan2(X - s2, -Y)])  # the payload still on its path
    other = dict(t=traj.t, q=q2, v=CubicSpline(traj.t, q2).derivative()(traj.t))
    assert not gp.verify(scene.model, other, constraint_tol=1e-5).is_motion
    pushed = gp.replay(scene.model, ServoTrajectory(**{**vars(traj), "forces": traj.forces * (1 + 1e-3)}))
    with pytest.raises(gp.InitialDataError, match="off the constraint"):
        gp.verify(scene.model, pushed)


def test_bad_input_to_index_reduction_is_a_project_error() -> None:
    scene = gp.scenes.get("spring-chain-servo", n=2)
    model = scene.model
    with pytest.raises(gp.ShapeError, match="q has 3 entries, expected 2"):
        gp.simulate_servo(model, [0.0, 0.0, 0.0], scene.v0, 1.0)
    with pytest.raises(gp.NonFiniteError, match="v contains NaN"):
        gp.simulate_servo(model, scene.q0, [np.nan, 0.0], 1.0)
    with pytest.raises(gp.InputError, match="pole"):
        gp.simulate_servo(model, scene.q0, scene.v0, 1.0, pole=-1.0)
    with pytest.raises(gp.NonFiniteError):
        gp.servo_diagnosis(model, np.inf, scene.q0, scene.v0)


def test_the_reach_is_found_in_any_units() -> None:
    """The spring chain in km/g/cs (masses ×1e3, lengths ×1e-3, times ×1e2): the run's sizes
    (``gausspp.model.reach_sizes``) find the force in the sixth derivative as in SI. The control: the state's own
    sizes, 1 in whatever unit (the old test), find no reach there."""
    from gausspp.model.reach_sizes import reach_sizes
    from gausspp.step.servo_reach import find_reach, state_sizes

    mass, length, time = 1e3, 1e-3, 1e2
    params = {"m": 1.0 * mass, "k": 4.0 * mass / time**2, "T": 4.0 * time, "distance": 1.0 * length}
    for scene in (gp.scenes.get("spring-chain-servo"), gp.scenes.get("spring-chain-servo", **params)):
        q, v = np.asarray(scene.q0, float), np.asarray(scene.v0, float)
        sizes = reach_sizes(scene.model, 0.0, q, v, scene.t_end)
        assert find_reach(scene.model, 0.0, q, v, sizes=sizes).degrees == (6,)
    with pytest.raises(gp.InputError):  # no actuator reaches the row within the derivatives tried
        find_reach(scene.model, 0.0, q, v, sizes=state_sizes(scene.model, q, v))
