"""Success means within tolerance: a run that left its constraints is failed, never a success
(:mod:`gausspp.simulation.residual_audit`)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes import parallelogram


def test_a_step_too_long_for_the_motion_is_a_failed_run_not_a_success() -> None:
    """rk4 with dt = 10 on the pendulum answers every step, yet |g| reaches tens of metres: the run fails, naming
    the row, the time and the fix; the fine-step run of the same motion is a success (the control)."""
    scene = gp.scenes.get("pendulum")
    with pytest.raises(gp.DriftError, match=r"left the constraint 'pin-.*' at t=.*drift_tol") as caught:
        gp.simulate(scene.model, scene.q0, scene.v0, 20.0, method="rk4", dt=10.0)
    error = caught.value
    assert isinstance(error, gp.IntegrationError) and error.constraint.startswith("pin-")
    kept = error.trajectory  # type: ignore[attr-defined]
    assert kept.status == "failed" and kept.t[-1] == error.t and abs(error.residual) > 1.0
    assert np.abs(kept.g[-1]).max() == pytest.approx(abs(error.residual))  # the departing sample is kept
    returned = gp.simulate(scene.model, scene.q0, scene.v0, 20.0, method="rk4", dt=10.0, throw=False)
    assert returned.status == "failed" and returned.message.startswith("DriftError")
    fine = gp.simulate(scene.model, scene.q0, scene.v0, 2.0, method="rk4", dt=1e-3)
    assert fine.success and fine.max_residual() < 1e-8


def test_a_step_across_a_singular_position_stops_instead_of_jumping_branch() -> None:
    """The double parallelogram (rows redundant everywhere, rank dropping again at each collinear position) by rk4:
    the run either follows the one-degree-of-freedom reference as fourth order allows or stops with an error.
    Measured: at dt = 0.01 it passes four collinear positions (error 1e-6 m before the third, 16 times less at
    dt = 0.005) and stops at t = 4.58 with a DriftError, every earlier sample within 4e-4 m of the reference; with
    the audit switched off (drift_tol = 1) the same run goes off the branch unnoticed (3 m) before it ends."""
    scene = gp.scenes.get("parallelogram", third_bar=True)
    crossings = parallelogram.collinear_times(**{**scene.params, "t_end": 5.0})

    def run(dt: float, t_end: float, drift_tol: float = 1e-3) -> tuple[gp.Trajectory, np.ndarray]:
        options = dict(method="rk4", dt=dt, throw=False, drift_tol=drift_tol, constraint_tol=1e-6)  # rk4's drift: 1e-7
        traj = gp.simulate(scene.model, scene.q0, scene.v0, t_end, **options)
        theta, omega = parallelogram.one_dof_reference(traj.t, **scene.params)
        ref = np.array([parallelogram.maximal_state(a, b, 0.0, 1, True)[0] for a, b in zip(theta, omega, strict=True)])
        return traj, np.abs(traj.q - ref).max(axis=1)

    coarse, err = run(1e-2, 5.0)
    assert coarse.t[-1] > crossings[1]  # it passed collinear positions
    if coarse.status == "failed":
        assert isinstance(coarse.failure, gp.GaussppError)
    assert err[:-1].max() < 1e-3  # on the branch up to the last sample (a branch jump is of the bars' length)
    fine, err_fine = run(5e-3, crossings[2] - 0.05)
    assert fine.success
    before_third = np.searchsorted(coarse.t, fine.t[-1])
    assert err_fine[-1] * 8 < err[before_third]  # fourth order through two collinear positions (measured 16)
    _, err_off = run(1e-2, 5.0, drift_tol=1.0)
    assert err_off.max() > 1e-2  # the control: without the audit the run leaves the branch unnoticed


def test_drift_error_travels_to_a_worker_and_back() -> None:
    """Sweeps run in other processes: the error and its attributes survive pickling."""
    error = gp.DriftError("left", t=1.5, constraint="pin-x", residual=0.25)
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is gp.DriftError and str(back) == "left"
    assert (back.t, back.constraint, back.residual) == (1.5, "pin-x", 0.25)
    realizability = pickle.loads(pickle.dumps(gp.RealizabilityError("lost", t=2.0, constraint="c", margin=0.0)))
    assert (realizability.t, realizability.constraint, realizability.margin) == (2.0, "c", 0.0)


@pytest.mark.parametrize("bad", [-1.0, 0.0, float("nan"), "small"])
def test_drift_tol_is_checked(bad: object) -> None:
    scene = gp.scenes.get("pendulum")
    with pytest.raises(gp.InputError, match="drift_tol"):
        gp.simulate(scene.model, scene.q0, scene.v0, 1.0, drift_tol=bad)  # type: ignore[arg-type]


def test_a_failed_run_with_record_times_keeps_the_last_state_it_reached() -> None:
    """The crane through its vertical rope (the margin vanishes at t ≈ 0.0954): DOP853 stops there. With record
    times every 0.05 s the failed run keeps the times it passed and the last state it reached, not t = 0 alone."""
    f = gp.scenes.get("crane", theta0=-0.3, accel=0.0, distance=0.0)
    with pytest.warns(gp.RealizabilityWarning, match="margin .* is small"):  # the last state is near the loss
        traj = gp.simulate(f.model, f.q0, f.v0, 0.2, throw=False, record=np.linspace(0.0, 0.2, 5))
    assert traj.status == "failed" and isinstance(traj.failure, gp.IntegrationError)
    assert "try a stiff method (Radau" in traj.message  # DOP853 failed: a stiff method is advice
    stopped = float(traj.message.split("stopped at t=")[1].split(":")[0])
    np.testing.assert_allclose(traj.t[:2], [0.0, 0.05])
    assert traj.t.size == 3 and abs(traj.t[-1] - stopped) < 1e-6 * max(1.0, stopped)
