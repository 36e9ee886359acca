"""``gp.simulate`` runs a servo-constraint reached only through higher derivatives (issue 30, item 1).

References: the scenes' flat solutions (numpy polynomials of the path alone, gausspp/scenes/overhead_crane.py and
spring_chain_servo.py), as in tests/test_index_reduction.py.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

import gausspp as gp


def _flat(scene: gp.scenes.Scene, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    q = np.array([scene.exact(ti)[0] for ti in t])
    forces = np.array([np.atleast_1d(scene.forces(ti)) for ti in t])
    return q, forces


@pytest.mark.parametrize(("name", "params"), [("overhead-crane", {}), ("spring-chain-servo", {"n": 2})])
def test_simulate_follows_the_path_and_returns_a_trajectory(name: str, params: dict, tmp_path: Path) -> None:
    """No extra argument: index reduction runs (lane "servo"), the motion is the flat solution (≤ 1e-8 m; measured
    8.2e-10 for the crane at the default rtol), the forces are its (u, ≤ 1e-6 relative; measured 6.4e-9), and the
    result is a Trajectory that gp.verify, save/load and to_xarray take."""
    scene = gp.scenes.get(name, **params)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end)
    assert isinstance(traj, gp.Trajectory) and traj.success and traj.lane == "servo"
    q, forces = _flat(scene, traj.t)
    assert np.abs(traj.q - q).max() <= 1e-8
    assert np.abs(traj.u - forces).max() <= 1e-6 * np.abs(forces).max()
    assert np.abs(traj.u * (1 + 1e-5) - forces).max() > 1e-6 * np.abs(forces).max()  # a wrong force would show
    assert np.abs(traj.g).max() <= 1e-8  # the constraint's values along the run
    assert gp.verify(scene.model, traj).is_motion
    path = tmp_path / "servo.npz"
    traj.save(path)
    back = gp.load_trajectory(path)
    np.testing.assert_array_equal(back.q, traj.q)
    np.testing.assert_array_equal(back.u, traj.u)
    assert traj.to_xarray().sizes["unknown"] == scene.model.m
    # the energy balance closes up to the quadrature of the reaction's work over the samples (measured 7.6e-9
    # relative for the crane)
    assert np.isfinite(traj.energy).all()
    assert np.abs(traj.energy_balance()).max() <= 1e-5 * (np.abs(traj.energy).max() + np.abs(traj.work_reaction).max())


def test_record_times_are_the_samples() -> None:
    scene = gp.scenes.get("spring-chain-servo", n=2)
    grid = np.linspace(0.0, 1.0, 11)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.0, record=grid)
    np.testing.assert_array_equal(traj.t, grid)


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"method": "rk4", "dt": 0.01}, "index reduction integrates adaptively"),
        ({"dt": 0.01}, "index reduction integrates adaptively"),
        ({"stabilize": "baumgarte"}, "own feedback"),
    ],
)
def test_what_index_reduction_does_not_do_is_refused(options: dict, match: str) -> None:
    scene = gp.scenes.get("overhead-crane")
    with pytest.raises(gp.InputError, match=match):
        gp.simulate(scene.model, scene.q0, scene.v0, 1.0, **options)


def test_one_step_servos_keep_their_lane() -> None:
    """A servo the actuators reach at the second derivative (the crane of scene "crane") is stepped as before."""
    scene = gp.scenes.get("crane")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.0)
    assert traj.success and traj.lane != "servo"


def test_the_actuators_work_is_integrated_with_the_motion() -> None:
    """The spring chain driven to its flat path, recorded at only 41 samples: the actuator's work ``W_R`` equals the
    exact ``∫ u ẋ₁ dt`` of the flat solution (not a quadrature of the samples, which missed it by 1e-3 J and made
    the run "drifted"), and the run is a success."""
    scene = gp.scenes.get("spring-chain-servo")
    record = np.linspace(0.0, scene.t_end, 41)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, record=record)
    assert traj.lane == "servo" and traj.status == "success", traj.message
    fine = np.linspace(0.0, scene.t_end, 4001)
    power = [float(scene.forces(t)[0] * scene.exact(t)[1][0]) for t in fine]
    exact = np.interp(record, fine, cumulative_simpson(power, x=fine, initial=0.0))
    size = np.abs(exact).max()
    assert np.abs(traj.work_reaction - exact).max() <= 1e-7 * size
    # the control: the old quadrature of the 41 samples misses by far more
    sampled = cumulative_simpson(np.einsum("ij,ij->i", traj.v, traj.reaction), x=traj.t, initial=0.0)
    assert np.abs(sampled - exact).max() > 1e3 * np.abs(traj.work_reaction - exact).max()
