"""The recording of smooth runs: all samples at once (the step mapped over them) gives what sample by sample gives."""

import numpy as np
import pytest

import gausspp as gp
from gausspp.simulation import recording
from gausspp.simulation.drift import Stabilization
from gausspp.simulation.rhs import RightHandSide
from gausspp.simulation.samples import Samples

COLUMNS = ("a", "u", "reaction", "compulsion", "residual", "g", "margin", "energy", "q", "v", "lam")


class OneByOne(RightHandSide):
    """The same right-hand side, recorded sample by sample (nothing evaluated at once)."""

    def evaluate_all(self, t, y):
        return {}, np.zeros(0), 0


def samples_of(model, traj):
    work_forces = np.nan_to_num(traj.work_forces)
    y = np.column_stack([traj.q, traj.v, traj.lam, traj.work_reaction, work_forces])
    return Samples(traj.t, y, traj.steps, traj.rhs_evaluations, None, traj.method, traj.solver)


def both(model, samples, solver):
    at_once = recording.record_smooth(model, RightHandSide(model, solver, None, Stabilization()), samples)
    one_by_one = recording.record_smooth(model, OneByOne(model, solver, None, Stabilization()), samples)
    return at_once, one_by_one


@pytest.mark.parametrize("scene", ["pendulum", "gyrostat"])
@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_at_once_equals_sample_by_sample(scene, solver):
    sc = gp.scenes.get(scene)
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.5, dt=1e-3, method="rk4-compiled", solver=solver, record=5)
    assert traj.status == "success" and traj.t.size > 50
    (fast, fast_failure, notes), (slow, slow_failure, slow_notes) = both(sc.model, samples_of(sc.model, traj), solver)
    assert fast_failure is None and slow_failure is None and notes == slow_notes
    for name in COLUMNS:
        np.testing.assert_allclose(getattr(fast, name), getattr(slow, name), rtol=1e-12, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(getattr(fast, name), getattr(traj, name), rtol=1e-12, atol=1e-12, err_msg=name)


def test_a_failing_sample_fails_as_sample_by_sample():
    sc = gp.scenes.get("gyrostat")
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.2, dt=1e-2, method="rk4-compiled", solver="direct")
    samples = samples_of(sc.model, traj)
    samples.y[7, 0] = np.nan  # a sample the step cannot evaluate: the recording stops there, as before
    (fast, fast_failure, _), (slow, slow_failure, _) = both(sc.model, samples, "direct")
    assert type(fast_failure) is type(slow_failure) and str(fast_failure) == str(slow_failure)
    assert fast.t.size == slow.t.size == 7
    np.testing.assert_allclose(fast.a, slow.a, rtol=1e-12, atol=1e-12)
