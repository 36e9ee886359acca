"""docs/theory.md §6.4 (skate: one constraint, two laws) and §6.5 (crane: a servo-constraint whose margin ∝ sin²θ)."""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes.crane import free_fall, margin_closed_form

TIGHT = dict(method="DOP853", rtol=1e-12, atol=1e-14)


def max_state_error(scene: gp.scenes.Scene, traj: gp.Trajectory) -> float:
    assert scene.exact is not None
    worst = 0.0
    for t, q, v in zip(traj.t, traj.q, traj.v, strict=True):
        qe, ve = scene.exact(float(t))
        worst = max(worst, float(np.max(np.abs(q - qe))), float(np.max(np.abs(v - ve))))
    return worst


# -- skate --------------------------------------------------------------------------------------
def skate(realization: str, **params: float) -> gp.scenes.Scene:
    return gp.scenes.get("skate", realization=realization, **params)


def run_skate(s: gp.scenes.Scene, **options) -> gp.Trajectory:
    return gp.simulate(s.model, s.q0, s.v0, s.t_end, lam0=s.lam0, **{**TIGHT, **options})


def blade_speed(traj: gp.Trajectory) -> np.ndarray:
    """Speed along the blade ``u = cos θ ẋ + sin θ ẏ``."""
    th = traj.q[:, 2]
    return np.cos(th) * traj.v[:, 0] + np.sin(th) * traj.v[:, 1]


def test_skate_unknown_realization_lists_the_valid_ones() -> None:
    with pytest.raises(gp.UnknownNameError, match="nonholonomic.*vakonomic"):
        skate("servo")


@pytest.mark.parametrize("realization", ["nonholonomic", "vakonomic"])
def test_skate_initial_data_lie_on_the_constraint(realization: str) -> None:
    s = skate(realization, theta0=0.7, v0=2.0)
    res = s.model.step(0.0, s.q0, s.v0, s.lam0, solver="direct")
    assert abs(res.constraint_value[0]) < 1e-15
    assert blade_speed(gp.simulate(s.model, s.q0, s.v0, 0.1, lam0=s.lam0, method="rk4", dt=0.1))[0] == (
        pytest.approx(2.0, rel=1e-15)
    )


def test_skate_nonholonomic_step_is_the_sideways_reaction() -> None:
    """Ideal constraint: R = λ(−sin θ, cos θ, 0) and a = (−uω sin θ, uω cos θ, 0) (turning at ω, speed u)."""
    s = skate("nonholonomic", theta0=0.4, v0=1.5, omega0=0.8)
    res = s.model.step(0.0, s.q0, s.v0, solver="direct")
    u, w, th = 1.5, 0.8, 0.4
    np.testing.assert_allclose(res.a, [-u * w * np.sin(th), u * w * np.cos(th), 0.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(res.reaction, res.u[0] * np.array([-np.sin(th), np.cos(th), 0.0]), rtol=0, atol=1e-15)
    assert res.u[0] == pytest.approx(1.0 * u * w, rel=1e-14)  # centripetal force m u ω


def test_skate_vakonomic_step_matches_its_equations() -> None:
    """Vakonomic (N = Φ): λ̇ = −m θ̇ u, m u̇ = λ θ̇, J θ̈ = −λ u (derived by hand from R = −λ̇ N_v − λ[N])."""
    m, J, lam, u, w, th = 1.3, 0.2, 0.7, 1.5, 0.8, 0.4
    s = skate("vakonomic", m=m, J=J, lam0=lam, theta0=th, v0=u, omega0=w)
    res = s.model.step(0.0, s.q0, s.v0, s.lam0, solver="direct")
    assert res.u[0] == pytest.approx(-m * w * u, rel=1e-14)  # u = λ̇ for realizations with λ as state
    assert res.a[2] == pytest.approx(-lam * u / J, rel=1e-14)
    u_dot = np.cos(th) * res.a[0] + np.sin(th) * res.a[1] + w * (-np.sin(th) * s.v0[0] + np.cos(th) * s.v0[1])
    assert u_dot == pytest.approx(lam * w / m, rel=1e-14)


def test_skate_nonholonomic_runs_along_its_circle() -> None:
    s = skate("nonholonomic")
    traj = run_skate(s)
    assert traj.success and traj.t[-1] == s.t_end
    assert np.max(np.abs(traj.residual)) < 1e-10
    assert max_state_error(s, traj) < 1e-10
    assert np.max(np.abs(traj.energy_balance())) < 1e-12  # the ideal reaction does no work


def linear_momentum(traj: gp.Trajectory, m: float) -> np.ndarray:
    """``m (ẋ, ẏ) + λ ∂Φ/∂(ẋ, ẏ)`` — for the vakonomic law ``∂L/∂v`` of ``L = T + λΦ``."""
    th, lam = traj.q[:, 2], traj.lam[:, 0] if traj.lam.shape[1] else np.zeros(len(traj))
    return m * traj.v[:, :2] + lam[:, None] * np.stack([-np.sin(th), np.cos(th)], axis=1)


def test_skate_vakonomic_keeps_its_constraint_and_invariants() -> None:
    m = 1.7
    s = skate("vakonomic", m=m)
    traj = run_skate(s)
    assert traj.success and traj.t[-1] == s.t_end
    assert np.max(np.abs(traj.residual)) < 1e-10
    # T is conserved (the vakonomic reaction's power λ̇Φ + λ v·[N] vanishes on the constraint) ...
    assert np.max(np.abs(traj.energy_balance())) < 1e-11
    assert np.max(np.abs(traj.work_reaction)) < 1e-11
    # ... and so is the momentum m v + λ ∂Φ/∂v (Noether: L = T + λΦ is invariant under translations),
    p = linear_momentum(traj, m)
    assert np.max(np.abs(p - p[0])) < 1e-11
    # while the heading no longer turns uniformly
    assert np.ptp(traj.v[:, 2]) > 1.0


def test_skate_the_two_laws_give_two_motions() -> None:
    nonholonomic = run_skate(skate("nonholonomic"))
    vakonomic = run_skate(skate("vakonomic"))
    assert skate("vakonomic").lam0[0] != 0.0
    assert np.linalg.norm(nonholonomic.q[-1, :2] - vakonomic.q[-1, :2]) > 1e-2
    # the nonholonomic skate turns uniformly with its momentum m v rotating (not conserved)
    assert np.ptp(nonholonomic.v[:, 2]) < 1e-12
    assert np.max(np.abs(linear_momentum(nonholonomic, 1.0) - linear_momentum(nonholonomic, 1.0)[0])) > 1.0
    # even λ(0) = 0 does not make them agree (λ̇ = −m θ̇ u) ...
    zero = run_skate(skate("vakonomic", lam0=0.0))
    assert np.linalg.norm(nonholonomic.q[-1, :2] - zero.q[-1, :2]) > 1e-2
    # ... except on a straight line, where λ stays 0
    straight = [run_skate(skate(r, omega0=0.0, lam0=0.0)) for r in ("nonholonomic", "vakonomic")]
    assert np.max(np.abs(straight[1].lam)) == 0.0
    np.testing.assert_allclose(straight[1].q[-1], straight[0].q[-1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("realization", ["nonholonomic", "vakonomic"])
def test_skate_qp_and_direct_give_the_same_run(realization: str) -> None:
    s = skate(realization)
    times = np.linspace(0.0, s.t_end, 26)
    qp, direct = (run_skate(s, solver=solver, record=times) for solver in ("qp", "direct"))
    np.testing.assert_array_equal(qp.t, times)
    np.testing.assert_array_equal(direct.t, times)
    np.testing.assert_allclose(qp.q, direct.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(qp.v, direct.v, rtol=0, atol=1e-10)
    np.testing.assert_allclose(qp.lam, direct.lam, rtol=0, atol=1e-10)


# -- crane --------------------------------------------------------------------------------------
M0, M, L = 1.0, 0.5, 1.0
NAME = "payload follows s(t)"


def crane_scene(**params: float) -> gp.scenes.Scene:
    return gp.scenes.get("crane", M0=M0, m=M, L=L, **params)


def test_crane_closed_form_margin_is_the_defined_cosine() -> None:
    """The derivation in margin_closed_form, checked by hand-built A, J, D with numpy."""
    for theta in (0.1, 0.3, -0.7, 1.2, 2.5):
        c = np.cos(theta)
        A = np.array([[M0 + M, M * L * c], [M * L * c, M * L * L]])
        J, D = np.array([1.0, L * c]), np.array([1.0, 0.0])
        Ai = np.linalg.inv(A)
        by_definition = abs(J @ Ai @ D) / np.sqrt((J @ Ai @ J) * (D @ Ai @ D))
        assert margin_closed_form(theta, M0, M) == pytest.approx(by_definition, rel=1e-13)


@pytest.mark.parametrize("solver", ["qp", "direct"])
@pytest.mark.parametrize("theta", [0.1, 0.3, -0.7, 1.2, np.pi / 2, 2.5])
def test_crane_step_margin_matches_closed_form(theta: float, solver: str) -> None:
    s = crane_scene()
    # the step does not need the state to be on the constraint
    res = s.model.step(0.7, [0.3, theta], [0.1, -0.2], solver=solver)
    assert res.margin == pytest.approx(margin_closed_form(theta, M0, M), rel=1e-12)


def test_crane_margin_vanishes_like_sin_squared_as_the_rope_turns_vertical() -> None:
    s = crane_scene()
    thetas = np.array([0.3, 0.1, 0.03, 0.01, 0.003])
    margins = np.array([s.model.step(0.0, [0.0, th], [0.0, 0.0], solver="direct").margin for th in thetas])
    assert np.all(np.diff(margins) < 0) and margins[-1] < 1e-5
    np.testing.assert_allclose(
        margins / np.sin(thetas) ** 2, np.sqrt(M / (M * np.sin(thetas) ** 2 + M0 * np.cos(thetas) ** 2)), rtol=1e-10
    )


def test_crane_nearly_vertical_rope_warns_with_the_time() -> None:
    s = crane_scene()
    with pytest.warns(gp.RealizabilityWarning, match=r"t=1\.25"):
        res = s.model.step(1.25, [0.0, 1e-4], [0.0, 0.0], solver="direct")
    # 1e-8·sqrt(m/M0); computed as J A⁻¹ D = (mL² − mL² cos²θ)/det A, a cancellation that costs
    # eps/θ² ≈ 2e-8 of relative accuracy at θ = 1e-4
    assert res.margin == pytest.approx(margin_closed_form(1e-4, M0, M), rel=1e-6)
    assert res.margin == pytest.approx(1e-8 * np.sqrt(M / M0), rel=1e-6)


@pytest.mark.parametrize("solver", ["qp", "direct"])
def test_crane_vertical_rope_is_not_realizable(solver: str) -> None:
    s = crane_scene()
    with pytest.raises(gp.RealizabilityError, match=r"payload follows s\(t\).*t=0\.5") as info:
        s.model.step(0.5, [0.0, 0.0], [0.0, 0.0], solver=solver)
    assert info.value.t == 0.5 and info.value.constraint == NAME and info.value.margin < 1e-12


def test_crane_qp_solves_a_warned_but_realizable_step() -> None:
    s = crane_scene()
    with pytest.warns(gp.RealizabilityWarning):
        direct = s.model.step(0.0, [0.0, 1e-3], [0.0, 0.0], solver="direct")
    with pytest.warns(gp.RealizabilityWarning):
        qp = s.model.step(0.0, [0.0, 1e-3], [0.0, 0.0], solver="qp")
    assert qp.disagreement(direct) < 1e-9


def test_crane_realizability_error_reports_the_actual_margin() -> None:
    s = crane_scene()
    model = gp.Model(s.model.mechanism, s.model.constraints, margin_error=1e-9)
    with pytest.raises(gp.RealizabilityError) as info:
        model.step(0.0, [0.0, 3e-5], [0.0, 0.0], solver="direct")
    # 6.4e-10, below margin_error but not zero (rel 1e-4: the cancellation costs eps/θ² ≈ 2.5e-7)
    assert info.value.margin == pytest.approx(margin_closed_form(3e-5, M0, M), rel=1e-4)


def test_crane_initial_data_lie_on_the_constraint() -> None:
    s = crane_scene(theta0=0.4, distance=0.8)
    data = s.model.kernel("direct")(0.0, s.q0, s.v0, np.zeros(0), np.zeros(2))
    assert abs(data["g"][0]) < 1e-15 and abs(data["Phi"][0]) < 1e-15


def test_crane_payload_follows_the_prescribed_motion() -> None:
    s = crane_scene()
    traj = gp.simulate(s.model, s.q0, s.v0, s.t_end, method="DOP853", rtol=1e-11, atol=1e-13)
    assert traj.success and traj.t[-1] == s.t_end
    p = s.params
    assert p["accel"] == pytest.approx(9.81 * np.tan(0.3), rel=1e-15)  # default: −g tan θ0 with θ0 = −0.3
    tau = np.clip(traj.t / p["duration"], 0, 1)
    prescribed = 0.5 * p["accel"] * traj.t**2 + p["distance"] * (35 * tau**4 - 84 * tau**5 + 70 * tau**6 - 20 * tau**7)
    payload = traj.q[:, 0] + L * np.sin(traj.q[:, 1])
    assert np.max(np.abs(payload - prescribed)) < 1e-10
    assert np.max(np.abs(traj.residual)) < 1e-10
    # the trolley force does work; the energy balance closes with it
    assert abs(traj.work_reaction[-1]) > 10.0
    assert np.max(np.abs(traj.energy_balance())) < 1e-9
    # the rope swings (θ is not prescribed) but stays away from the vertical
    assert np.ptp(traj.q[:, 1]) > 0.1 and traj.margin.min() > 0.01
    np.testing.assert_allclose(traj.margin, margin_closed_form(traj.q[:, 1], M0, M), rtol=1e-12)


def test_crane_steady_acceleration_holds_the_rope_angle() -> None:
    s = crane_scene(theta0=-0.3, distance=0.0)
    assert s.exact is not None
    traj = gp.simulate(s.model, s.q0, s.v0, s.t_end, method="DOP853", rtol=1e-11, atol=1e-13)
    assert traj.success
    assert max_state_error(s, traj) < 1e-10
    np.testing.assert_allclose(traj.u[:, 0], (M0 + M) * 9.81 * np.tan(0.3), rtol=1e-10)  # F = (M0 + m)·a


def test_crane_qp_and_direct_give_the_same_run() -> None:
    s = crane_scene()
    times = np.linspace(0.0, s.t_end, 31)
    qp, direct = (
        gp.simulate(s.model, s.q0, s.v0, s.t_end, method="DOP853", rtol=1e-11, atol=1e-13, solver=solver, record=times)
        for solver in ("qp", "direct")
    )
    np.testing.assert_allclose(qp.q, direct.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(qp.v, direct.v, rtol=0, atol=1e-10)
    np.testing.assert_allclose(qp.u, direct.u, rtol=1e-9)


def free_fall_model(theta0: float) -> tuple[gp.scenes.Scene, gp.Model, float]:
    """s ≡ 0: the payload falls freely and the rope turns vertical at t* = sqrt(2L(1 − cos θ0)/g).

    The model declares margins below 1e-9 unrealizable: as the margin → 0 like (t* − t), adaptive
    steps approach t* geometrically and, with the default 1e-12, usually stall on the step-size
    limit (θ ≈ 1e-6, θ̇ ≈ 1e5) before the margin reaches it.
    """
    s = crane_scene(theta0=theta0, accel=0.0, distance=0.0, t_end=1.0)
    model = gp.Model(s.model.mechanism, s.model.constraints, margin_error=1e-9)
    return s, model, float(np.sqrt(2 * L * (1 - np.cos(theta0)) / 9.81))


def test_crane_free_fall_exact_motion_until_the_rope_is_vertical() -> None:
    s, model, t_star = free_fall_model(-0.3)
    traj = gp.simulate(model, s.q0, s.v0, 0.9 * t_star, method="DOP853", rtol=1e-12, atol=1e-14)
    assert traj.success
    assert max_state_error(s, traj) < 1e-9
    np.testing.assert_allclose(traj.reaction[:, 1], 0.0, atol=1e-12)  # the trolley only: M = (1, 0)
    assert np.all(np.isnan(np.concatenate(free_fall(1.01 * t_star, L, 9.81, -0.3))))


def test_crane_driven_to_the_vertical_rope_fails_with_realizability_error() -> None:
    s, model, t_star = free_fall_model(-0.3)
    options = dict(method="DOP853", rtol=1e-9, atol=1e-12, solver="direct")
    with pytest.warns(gp.RealizabilityWarning), pytest.raises(gp.RealizabilityError) as info:
        gp.simulate(model, s.q0, s.v0, s.t_end, **options)
    err = info.value
    assert err.constraint == NAME and 0.0 <= err.margin < 1e-9
    assert err.t == pytest.approx(t_star, abs=1e-8)
    assert len(err.trajectory) > 1

    with pytest.warns(gp.RealizabilityWarning):
        traj = gp.simulate(model, s.q0, s.v0, s.t_end, throw=False, **options)
    assert traj.status == "failed" and not traj.success
    assert traj.message.startswith("RealizabilityError") and NAME in traj.message
    assert f"t={t_star:.6g}" in traj.message
    assert len(traj) > 1 and traj.t[-1] < t_star
    assert traj.margin[-1] >= 1e-9 and abs(traj.q[-1, 1]) < 1e-3  # the prefix reaches the nearly vertical rope
    assert np.max(np.abs(traj.g)) < 1e-8
    np.testing.assert_array_equal(traj.t, err.trajectory.t)
