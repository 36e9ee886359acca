"""The realizability margin is checked at every right-hand-side evaluation, for any number of rows."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp


def _turning_actuators() -> gp.Model:
    """A point in the plane, both velocities prescribed (``J = I``), two force directions ``(1, 0)`` and
    ``(cos θ, sin θ)`` with ``θ = 0.03 + (1 − t)²``: the margin (``≈ θ/√2``) dips to about 0.02 at ``t = 1``
    without crossing zero (so ``det S`` keeps its sign)."""
    body = gp.MassMatrix(n=2, A=lambda q, t: ca.DM.eye(2), f=lambda q, v, t: ca.vertcat(0.0, -1.0))

    def M(q, v, t):
        theta = 0.03 + (1.0 - t) ** 2
        return ca.vertcat(ca.horzcat(1.0, 0.0), ca.horzcat(ca.cos(theta), ca.sin(theta)))

    servo = gp.Constraint(lambda q, v, t: v - ca.vertcat(1.0, 0.5), name="servo", realization=gp.Force(M=M))
    # a demanding margin_error: S is far from singular in round-off terms, but the user refuses margins < 0.05
    return gp.Model(body, [servo], margin_warn=0.1, margin_error=0.05)


@pytest.mark.parametrize("method", ["rk4", "RK45"])
def test_a_two_row_margin_that_vanishes_between_recorded_samples_stops_the_run(method: str) -> None:
    """Only t = 0 and t = 2 are recorded, so no recorded sample sees the margin fall below margin_error = 0.05
    (for |t − 1| < 0.05); the run must still stop there — before, only one-row models were checked during
    integration, and this run ended 'successfully' at t = 2."""
    model = _turning_actuators()
    options = dict(dt=0.08) if method == "rk4" else dict(rtol=1e-8, atol=1e-10)
    traj = gp.simulate(
        model,
        [0.0, 0.0],
        [1.0, 0.5],
        2.0,
        method=method,
        solver="direct",
        record=np.array([0.0, 2.0]),
        throw=False,
        **options,
    )
    assert not traj.success
    assert traj.message.startswith("RealizabilityError")
    assert "servo" in traj.message
    assert traj.t[-1] < 1.0  # nothing kept past the unrealizable interval


def test_the_same_model_runs_where_the_actuators_stay_independent() -> None:
    """Control: over [0, 0.5] the margin stays above margin_warn: the run succeeds and keeps the servo exactly."""
    model = _turning_actuators()
    traj = gp.simulate(model, [0.0, 0.0], [1.0, 0.5], 0.5, method="rk4", dt=0.1, solver="direct")
    assert traj.success and np.min(traj.margin) > 0.1
    np.testing.assert_allclose(traj.v, np.tile([1.0, 0.5], (len(traj), 1)), atol=1e-12)


def test_the_compiled_lane_checks_the_margin_at_every_step() -> None:
    """rk4 in the compiled lane records only t = 0 and t = 2 too: the in-graph bound (within √k of σ_min) stops the
    run."""
    model = _turning_actuators()
    traj = gp.simulate(
        model,
        [0.0, 0.0],
        [1.0, 0.5],
        2.0,
        method="rk4",
        lane="compiled",
        dt=0.01,
        solver="direct",
        record=np.array([0.0, 2.0]),
        throw=False,
    )
    assert not traj.success and traj.message.startswith("RealizabilityError")
    assert "margin_error=0.05" in traj.message and "servo" in traj.message


def test_the_margin_bound_brackets_the_margin() -> None:
    """b ≤ σ_min ≤ √k·b along the model's states (k = 2)."""
    from gausspp.simulation.compiled import margin_bound

    model = _turning_actuators()
    bound = margin_bound(model)
    for t in np.linspace(0.0, 2.0, 21):
        y = np.array([0.0, 0.0, 1.0, 0.5, 0.0, 0.0])
        b = float(bound(t, y))
        sigma = np.linalg.svd(model.kernel("direct")(t, y[:2], y[2:4], np.zeros(0), np.zeros(2))["S_norm"])[1][-1]
        assert b <= sigma * (1 + 1e-12) and sigma <= np.sqrt(2) * b * (1 + 1e-12)
