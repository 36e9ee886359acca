"""simulate (docs/theory.md §5): convergence orders, exact motions, λ state, drift control, failures."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp

SPRING = {"realization": "servo", "k": 3.0, "v": 0.5}


def final_error(method: str, dt: float) -> float:
    s = gp.scenes.get("two-masses", **SPRING)
    meth = gp.methods.get(method)
    loose = {"rtol": 1e2, "atol": 1e2} if meth.adaptive else {}  # impose the step: accept every step
    traj = gp.simulate(s.model, s.q0, s.v0, 2.0, dt=dt, method=method, solver="direct", **loose)
    q, v = s.exact(traj.t[-1])
    return max(np.abs(traj.q[-1] - q).max(), np.abs(traj.v[-1] - v).max())


@pytest.mark.parametrize("method", gp.methods.names())
def test_convergence_order(method: str) -> None:
    order = gp.methods.get(method).order
    steps = [0.8, 0.4, 0.2] if order > 6 else [0.2, 0.1, 0.05, 0.025] if order > 1 else [0.02, 0.01, 0.005, 0.0025]
    errors = [final_error(method, h) for h in steps]
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    shown = ", ".join(f"{e:.1e}" for e in errors)
    print(f"{method}: errors [{shown}], observed order {slope:.2f}, declared {order}")
    assert abs(slope - order) <= 0.5


@pytest.mark.parametrize(("method", "lane"), [("rk4", "python"), ("rk4", "compiled"), ("DOP853", None)])
@pytest.mark.parametrize("realization", ["ideal", "servo"])
def test_two_masses_exact_quadratic_motion(realization: str, method: str, lane: str | None) -> None:
    s = gp.scenes.get("two-masses", realization=realization, v=0.3)
    for solver in ("direct", "qp"):
        traj = gp.simulate(
            s.model, s.q0, s.v0, 1.0, dt=0.05, method=method, lane=lane, solver=solver, rtol=1e-12, atol=1e-14
        )
        for t, q, v in zip(traj.t, traj.q, traj.v, strict=True):
            qe, ve = s.exact(t)
            np.testing.assert_allclose(q, qe, rtol=0, atol=1e-12)
            np.testing.assert_allclose(v, ve, rtol=0, atol=1e-12)
        assert traj.success and np.abs(traj.energy_balance()).max() < 1e-12


def test_lam_state_is_integrated_and_lam0_required() -> None:
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), F=lambda q, v, t: [0.0, 1.0])
    model = gp.Model(body, gp.Constraint(lambda q, v, t: v[1] - v[0], realization=gp.Inertial(N=lambda q, v, t: v[0])))
    with pytest.raises(gp.MissingMultiplierError, match="lam0"):
        gp.simulate(model, [0, 0], [0, 0], 1.0, dt=0.1)
    traj = gp.simulate(model, [0, 0], [0, 0], 1.0, dt=0.1, lam0=[0.2], solver="direct")
    # N = v₀: R = −λ̇ (1, 0) acts on mass 1 only, so both accelerate at F/m₂ = 1 and λ̇ = −1
    np.testing.assert_allclose(traj.lam[:, 0], 0.2 - traj.t, atol=1e-13)
    np.testing.assert_allclose(traj.u[:, 0], -1.0, atol=1e-13)


def collapsing_model() -> gp.Model:
    """A mass matrix that stops being positive definite when q₀ reaches 1."""
    mech = gp.MassMatrix(n=2, A=lambda q, t: [[1.0, 0.0], [0.0, 1.0 - q[0]]], f=lambda q, v, t: [0.0, 0.0])
    return gp.Model(mech, gp.Constraint(lambda q, v, t: v[1], name="hold"))


@pytest.mark.parametrize(("method", "lane"), [("rk4", "python"), ("RK45", None), ("rk4", "compiled")])
def test_failure_midway_keeps_the_prefix(method: str, lane: str | None) -> None:
    model = collapsing_model()
    options = dict(dt=0.01, method=method, lane=lane, solver="direct")
    traj = gp.simulate(model, [0.0, 0.0], [1.0, 0.0], 2.0, throw=False, **options)
    assert traj.status == "failed" and not traj.success
    assert len(traj) > 10 and 0.9 < traj.t[-1] < 1.0  # everything before the collapse at t = 1
    assert "t=" in traj.message
    with pytest.raises(gp.GaussppError) as info:
        gp.simulate(model, [0.0, 0.0], [1.0, 0.0], 2.0, **options)
    kept = info.value.trajectory  # type: ignore[attr-defined]
    assert kept.status == "failed" and len(kept) == len(traj)


def test_initial_data_off_the_constraint() -> None:
    s = gp.scenes.get("two-masses", realization="servo")
    with pytest.raises(gp.InitialDataError, match=r"off the constraint 'rod' at t=0: Φ\(q, v, t\) = 0.5"):
        gp.simulate(s.model, s.q0, [0.0, 0.5], 1.0, dt=0.1)
    traj = gp.simulate(s.model, s.q0, [0.0, 0.5], 1.0, dt=0.1, stabilize="project")
    assert abs(traj.residual[0, 0]) < 1e-15
    # projected along the servo's direction A⁻¹D = (1/m1, 0): only mass 1 was moved
    np.testing.assert_allclose(traj.v[0], [0.5, 0.5])


def circle_particle() -> gp.Model:
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), V=lambda q, t: 9.81 * q[1])
    return gp.Model(body, gp.Holonomic(lambda q, t: ca.sumsqr(q) - 1.0, name="circle"))


def test_baumgarte_and_projection_control_drift() -> None:
    model = circle_particle()
    # a first-order method at a coarse step: the drift is the figure compared (1e-3 in Φ even with Baumgarte)
    kwargs = dict(dt=0.01, method="symplectic-euler", solver="direct", drift_tol=1.0)
    raw = gp.simulate(model, [1.0, 0.0], [0.0, 0.0], 5.0, **kwargs)
    baum = gp.simulate(model, [1.0, 0.0], [0.0, 0.0], 5.0, stabilize=gp.Baumgarte.critical(0.05), **kwargs)
    proj = gp.simulate(model, [1.0, 0.0], [0.0, 0.0], 5.0, stabilize="project", **kwargs)
    drift = [np.abs(x.g).max() for x in (raw, baum, proj)]
    print("max |g|: raw {:.2e}, Baumgarte {:.2e}, projection {:.2e}".format(*drift))
    assert np.abs(raw.g).max() > 1e-2
    assert np.abs(baum.g).max() < 0.1 * np.abs(raw.g).max()
    assert proj.max_residual() < 1e-12


def test_suslov_drift_over_1e5_rk4_steps() -> None:
    s = gp.scenes.get("rigid-body-servo")
    kwargs = dict(dt=1e-3, method="rk4", lane="compiled", solver="direct", record=1000)
    raw = gp.simulate(s.model, s.q0, s.v0, 100.0, **kwargs)
    stab = gp.simulate(s.model, s.q0, s.v0, 100.0, stabilize="project", **kwargs)
    assert raw.steps == stab.steps == 100_000
    growth = np.abs(raw.residual[:, 0])
    print(f"|Φ| without stabilization: {growth[1]:.1e} at t={raw.t[1]:g} → {growth.max():.1e} max over t ≤ 100")
    assert np.abs(stab.residual).max() <= 1e-10
    assert np.all(np.abs(np.linalg.norm(stab.q, axis=1) - 1.0) < 1e-14)  # the quaternion stays unit


def test_record_options() -> None:
    s = gp.scenes.get("two-masses")
    traj = gp.simulate(s.model, s.q0, s.v0, 1.0, dt=0.1, record=[0.0, 0.5, 1.0], solver="direct")
    np.testing.assert_allclose(traj.t, [0.0, 0.5, 1.0])
    with pytest.raises(gp.InputError, match="grid"):
        gp.simulate(s.model, s.q0, s.v0, 1.0, dt=0.1, record=[0.55], solver="direct")
    dense = gp.simulate(s.model, s.q0, s.v0, 1.0, method="DOP853", record=np.linspace(0, 1, 11), solver="direct")
    np.testing.assert_allclose(dense.t, np.linspace(0, 1, 11))
    np.testing.assert_allclose(dense.q[5], s.exact(0.5)[0], atol=1e-12)


def test_bad_arguments() -> None:
    s = gp.scenes.get("two-masses")
    with pytest.raises(gp.UnknownNameError, match="method='rk5' is unknown; valid methods"):
        gp.simulate(s.model, s.q0, s.v0, 1.0, dt=0.1, method="rk5")
    with pytest.raises(gp.InputError, match="fixed step: give dt"):
        gp.simulate(s.model, s.q0, s.v0, 1.0, method="rk4")  # without a method, no dt means adaptive
    with pytest.raises(gp.InputError, match="t0 < t_end"):
        gp.simulate(s.model, s.q0, s.v0, -1.0, dt=0.1)
    with pytest.raises(gp.InputError, match="needs solver='direct'"):
        gp.simulate(s.model, s.q0, s.v0, 1.0, method="cvodes", solver="qp")
    with pytest.raises(gp.InputError, match="compiled lane needs"):
        gp.simulate(s.model, s.q0, s.v0, 1.0, dt=0.1, method="rk4", lane="compiled", backend="qpsolvers:osqp")


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_compiled_lane_failure_keeps_prefix(solver: str) -> None:
    traj = gp.simulate(
        collapsing_model(),
        [0.0, 0.0],
        [1.0, 0.0],
        2.0,
        dt=0.01,
        method="rk4",
        lane="compiled",
        solver=solver,
        throw=False,
    )
    assert traj.status == "failed" and 0.9 < traj.t[-1] < 1.0 and len(traj) > 10


# -- the capability rules, declared once (gausspp.simulation.lanes) --------------------------------
def test_lane_rules_answer_front_ends_as_simulate_does() -> None:
    from gausspp.simulation import lanes

    cvodes, rk4 = (gp.methods.get(m) for m in ("cvodes", "rk4"))
    assert not lanes.accepts(cvodes, "qp") and lanes.accepts(cvodes, "direct")
    assert lanes.default_solver(cvodes) == "direct" and lanes.default_solver(rk4) == "qp"
    assert lanes.accepts(rk4, "qp", "casadi:qrqp", lane="compiled")
    assert not lanes.accepts(rk4, "qp", "qpsolvers:osqp", lane="compiled") and lanes.accepts(
        rk4, "qp", "qpsolvers:osqp"
    )
    assert not lanes.accepts(rk4, "qp", kind="contacts") and lanes.accepts(
        gp.methods.get("DOP853"), "qp", kind="contacts"
    )
    assert not lanes.accepts(rk4, "qp", kind="general", lane="compiled") and not lanes.accepts(
        rk4, "direct", kind="general"
    )
    s = gp.scenes.get("two-masses")
    with pytest.raises(gp.InputError, match=r"stabilize='project' is not supported by method='cvodes'"):
        gp.simulate(s.model, s.q0, s.v0, 0.1, method="cvodes", solver="direct", stabilize="project")


def test_simulation_writes_no_attribute_into_the_model() -> None:
    """Compiled runs, projections, Jacobians, phase models and gap functions live in the model's workspace."""
    s = gp.scenes.get("pendulum")
    before = set(vars(s.model))
    gp.simulate(s.model, s.q0, s.v0, 0.05, dt=0.01, method="rk4", lane="compiled", stabilize="project")
    gp.simulate(s.model, s.q0, s.v0, 0.05, method="Radau", solver="direct")
    gp.simulate(s.model, s.q0, s.v0, 0.05, dt=0.01, stabilize="project")
    assert set(vars(s.model)) == before and vars(s.model).get("_projection") is None
    block = gp.scenes.get("block-on-floor")
    before = set(vars(block.model))
    gp.simulate(block.model, block.q0, block.v0, 0.5)
    assert set(vars(block.model)) == before


def test_trajectories_record_the_contact_gaps() -> None:
    from gausspp.simulation.contacts import gaps

    block = gp.scenes.get("block-on-floor")
    traj = gp.simulate(block.model, block.q0, block.v0, 0.8)
    assert traj.gap.shape == traj.contact_force.shape == (len(traj), len(block.model.contact_row_names))
    expected = [gaps(block.model, t, q, v)[0] for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)]
    np.testing.assert_array_equal(traj.gap, expected)
    assert traj.gap.min() >= -1e-9 and np.any(traj.gap.min(axis=1) <= 1e-9)  # it lands
    s = gp.scenes.get("two-masses")
    assert gp.simulate(s.model, s.q0, s.v0, 0.1, dt=0.01).gap.shape == (11, 0)


# -- the lane is gausspp's choice: a method names the integrator ------------------------------------
@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_rk4_runs_compiled_with_the_numbers_of_the_lanes_it_replaces(solver: str) -> None:
    """``method="rk4"`` runs in the compiled lane (where ``lane="compiled"`` insists on running it); the Python lane,
    asked for by name, steps the same RK4: the three trajectories agree to round-off (scaled by the size of the
    state)."""
    s = gp.scenes.get("pendulum")
    runs = {
        name: gp.simulate(s.model, s.q0, s.v0, 0.5, dt=1e-3, solver=solver, **options)
        for name, options in {
            "rk4": dict(method="rk4"),
            "compiled": dict(method="rk4", lane="compiled"),
            "python": dict(method="rk4", lane="python"),
        }.items()
    }
    assert [r.lane for r in runs.values()] == ["compiled", "compiled", "python"]
    assert runs["rk4"].method == "rk4" and runs["python"].method == "rk4"
    reference = runs["python"]
    for traj in runs.values():
        assert traj.success and len(traj) == len(reference)
        for field in ("q", "v", "a", "reaction"):
            want, got = getattr(reference, field), getattr(traj, field)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * (1.0 + np.max(np.abs(want))))


def test_rk4_runs_from_python_where_something_needs_python() -> None:
    s = gp.scenes.get("two-masses")
    osqp = gp.simulate(s.model, s.q0, s.v0, 0.1, dt=0.01, method="rk4", backend="qpsolvers:osqp")
    assert osqp.success and osqp.lane == "python"  # a QP backend outside casadi
    crane = gp.scenes.get("saturated-crane")
    bounded = gp.simulate(crane.model, crane.q0, crane.v0, 0.05, dt=0.01, method="rk4")
    assert bounded.lane == "python"  # bounded actuators: the general Gauss QP at every step
    with pytest.raises(gp.InputError, match="compiled lane"):
        gp.simulate(crane.model, crane.q0, crane.v0, 0.05, dt=0.01, method="rk4", lane="compiled")
    with pytest.raises(gp.InputError, match=r"lane='cvodes' does not run method 'rk4'"):
        gp.simulate(s.model, s.q0, s.v0, 0.1, dt=0.01, method="rk4", lane="cvodes")
    with pytest.raises(gp.UnknownNameError, match=r"lane='fast' is unknown"):
        gp.simulate(s.model, s.q0, s.v0, 0.1, dt=0.01, lane="fast")
    assert gp.simulate(s.model, s.q0, s.v0, 0.1, method="RK45").lane == "scipy"


def test_the_shortest_call_integrates_adaptively_to_the_tolerances() -> None:
    """``gp.simulate(model, q0, v0, t_end)``: no method and no dt is DOP853 to ``rtol``/``atol``; with ``dt`` and no
    method, RK4 (in the compiled lane)."""
    s = gp.scenes.get("pendulum")
    traj = gp.simulate(s.model, s.q0, s.v0, 0.5)
    assert traj.success and traj.method == "DOP853" and traj.lane == "scipy" and traj.t[-1] == 0.5
    fine = gp.simulate(s.model, s.q0, s.v0, 0.5, dt=1e-3)
    assert fine.method == "rk4" and fine.lane == "compiled"
    assert np.max(np.abs(traj.q[-1] - fine.q[-1])) < 1e-8
    loose = gp.simulate(s.model, s.q0, s.v0, 0.5, rtol=1e-4, atol=1e-6)
    assert loose.steps < traj.steps  # the tolerances are the given ones


def test_the_retired_method_name_is_refused_with_what_to_write() -> None:
    """``rk4-compiled`` named a lane, not an integrator: refused with ``method='rk4'`` and ``lane='compiled'``."""
    s = gp.scenes.get("pendulum")
    with pytest.raises(
        gp.UnknownNameError, match=r"method='rk4-compiled' is gone: write method='rk4'.*lane='compiled'"
    ):
        gp.simulate(s.model, s.q0, s.v0, 0.1, dt=0.01, method="rk4-compiled")
    assert "rk4-compiled" not in gp.methods.names()
