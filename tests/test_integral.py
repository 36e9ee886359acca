"""Verification by the integral principle (23): motions pass, other realizations' motions fail."""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp
from gausspp.verification.integral import Discretized, solve_closed_form, solve_qp

from .factories import random_spd


def motion(scene: gp.scenes.Scene, horizon: float, samples: int) -> gp.Trajectory:
    """A tight reference motion recorded at uniform times."""
    return gp.simulate(
        scene.model,
        scene.q0,
        scene.v0,
        horizon,
        lam0=scene.lam0,
        method="DOP853",
        rtol=1e-13,
        atol=1e-14,
        solver="direct",
        record=np.linspace(0.0, horizon, samples),
    )


@pytest.mark.parametrize("name", gp.scenes.names("equality"))
def test_every_scene_motion_passes_and_the_gap_falls(name: str) -> None:
    scene = gp.scenes.get(name)
    horizon = min(scene.t_end, 1.0)
    traj = motion(scene, horizon, 401)
    fine = gp.verify(scene.model, traj)
    coarse = gp.verify(scene.model, traj, nodes=101)
    with np.errstate(divide="ignore", invalid="ignore"):
        order = np.log(np.float64(coarse.relative_gap) / fine.relative_gap) / np.log(4.0)
    print(
        f"{name}: relative gap {coarse.relative_gap:.2e} (101 nodes) → {fine.relative_gap:.2e} (401), order {order:.1f}"
    )
    assert fine.is_motion and coarse.is_motion
    if any(not c.realization.has_state for c in scene.model.constraints):
        # pointwise (20): the gap is the squared error of the path's acceleration — below 1e-11
        # it is rounding and unresolved fast modes (stiff chain), not the discretization of (23)
        assert fine.relative_gap <= coarse.relative_gap or fine.relative_gap < 1e-11
    else:  # differential (20), midpoint rule: the gap falls like h⁴
        assert order > 3.5


def discriminate(model: gp.Model, traj: gp.Trajectory) -> gp.Verification:
    return gp.verify(model, traj)


@pytest.mark.parametrize(("ran", "checked"), [("ideal", "servo"), ("servo", "ideal")])
def test_two_masses_discrimination(ran: str, checked: str) -> None:
    traj = motion(gp.scenes.get("two-masses", realization=ran, k=3.0, v=0.5), 2.0, 201)
    own = gp.verify(gp.scenes.get("two-masses", realization=ran, k=3.0).model, traj)
    other = gp.verify(gp.scenes.get("two-masses", realization=checked, k=3.0).model, traj)
    assert own.is_motion and not other.is_motion and other.relative_gap >= 1e-2


def test_suslov_vs_gyrostat_discrimination() -> None:
    gyro = gp.scenes.get("gyrostat")
    suslov = gp.scenes.get("rigid-body-servo", inertia=(1, 2, 3), l=(1, 1, 1), omega0=gyro.v0)
    gyro_motion, suslov_motion = motion(gyro, 3.0, 301), motion(suslov, 3.0, 301)
    assert gp.verify(gyro.model, gyro_motion).is_motion and gp.verify(suslov.model, suslov_motion).is_motion
    a, b = gp.verify(suslov.model, gyro_motion), gp.verify(gyro.model, suslov_motion)
    assert not a.is_motion and not b.is_motion and min(a.relative_gap, b.relative_gap) >= 1e-2


def test_skate_nonholonomic_vs_vakonomic() -> None:
    non, vak = gp.scenes.get("skate", realization="nonholonomic"), gp.scenes.get("skate", realization="vakonomic")
    non_motion, vak_motion = motion(non, 3.0, 301), motion(vak, 3.0, 301)
    assert gp.verify(non.model, non_motion).is_motion and gp.verify(vak.model, vak_motion).is_motion
    a, b = gp.verify(vak.model, non_motion), gp.verify(non.model, vak_motion)
    assert not a.is_motion and not b.is_motion and min(a.relative_gap, b.relative_gap) >= 1e-2


def test_multipliers_reproduce_lambda_and_converge() -> None:
    """Differential (20) on the gyrostat: λ from the QP's multipliers, error falling like h²."""
    gyro = gp.scenes.get("gyrostat")
    errors = []
    for samples in (101, 201, 401):
        traj = motion(gyro, 3.0, samples)
        ver = gp.verify(gyro.model, traj)
        errors.append(np.abs(ver.multipliers[:, 0] - traj.lam[:, 0]).max())
    order = np.polyfit(np.log([101, 201, 401]), np.log(errors), 1)[0]
    print(f"gyrostat λ errors {[f'{e:.1e}' for e in errors]}, order in 1/h {-order:.2f}")
    assert errors[-1] < 1e-3 and -order > 1.5
    servo = gp.scenes.get("two-masses", realization="servo", k=3.0, v=0.5)
    traj = motion(servo, 2.0, 201)
    lam = gp.verify(servo.model, traj).multipliers[1:-1, 0]  # pointwise rows: at interior nodes
    np.testing.assert_allclose(lam, traj.u[1:-1, 0], atol=1e-6)


def random_pointwise(rng: np.random.Generator, n: int, k: int, nodes: int) -> Discretized:
    t = np.sort(rng.uniform(0, 1, nodes))
    return Discretized(
        t=t,
        R=rng.standard_normal((nodes, n)),
        G=np.array([random_spd(rng, n, rng.uniform(0, 3)) for _ in range(nodes)]),
        E1=np.zeros((nodes, k, n)),
        E0=rng.standard_normal((nodes, k, n)),
        pointwise=np.ones(k, dtype=bool),
    )


def test_qp_equals_closed_form_on_random_systems(rng: np.random.Generator) -> None:
    for _ in range(30):
        n = int(rng.integers(1, 7))
        d = random_pointwise(rng, n, int(rng.integers(1, n + 1)), int(rng.integers(5, 40)))
        v_qp, eta_qp, lam_qp = solve_qp(d)
        v_cf, eta_cf, lam_cf = solve_closed_form(d)
        assert v_qp == pytest.approx(v_cf, rel=1e-9)
        np.testing.assert_allclose(eta_qp, eta_cf, atol=1e-9 * max(1.0, np.abs(eta_cf).max()))
        np.testing.assert_allclose(lam_qp[1:-1], lam_cf[1:-1], atol=1e-8 * np.abs(lam_cf[1:-1]).max())


@pytest.mark.parametrize("metric", ["A", "identity", "random"])
def test_any_spd_metric_gives_the_verdict(metric: str, rng: np.random.Generator) -> None:
    G = random_spd(rng, 2, 2.0) if metric == "random" else metric
    ideal = motion(gp.scenes.get("two-masses", realization="ideal", k=3.0, v=0.5), 2.0, 201)
    servo_model = gp.scenes.get("two-masses", realization="servo", k=3.0).model
    ideal_model = gp.scenes.get("two-masses", realization="ideal", k=3.0).model
    assert gp.verify(ideal_model, ideal, metric=G).is_motion
    assert not gp.verify(servo_model, ideal, metric=G).is_motion
    gyro = gp.scenes.get("gyrostat")
    G3 = random_spd(rng, 3, 1.0) if metric == "random" else metric
    assert gp.verify(gyro.model, motion(gyro, 2.0, 201), metric=G3).is_motion


def test_gap_grows_like_epsilon_squared() -> None:
    """A pendulum motion bent by ε·bump (still on the constraint): gap ∝ ε²."""
    scene = gp.scenes.get("pendulum")
    traj = motion(scene, 1.0, 801)
    phi, omega, t = traj.q[:, 2], traj.v[:, 2], traj.t
    bump, dbump = np.sin(np.pi * t) ** 3, 3 * np.pi * np.sin(np.pi * t) ** 2 * np.cos(np.pi * t)
    L = scene.params.get("L", 1.0)
    eps = np.array([1e-4, 1e-3, 1e-2])
    gaps = []
    for e in eps:
        p, w = phi + e * bump, omega + e * dbump
        path = {
            "t": t,
            "q": np.c_[L * np.cos(p), L * np.sin(p), p],
            "v": np.c_[-L * np.sin(p) * w, L * np.cos(p) * w, w],
        }
        gaps.append(gp.verify(scene.model, path).gap)
    slope = np.polyfit(np.log(eps), np.log(gaps), 1)[0]
    print(f"gaps {[f'{g:.2e}' for g in gaps]}, slope {slope:.3f}")
    assert abs(slope - 2.0) <= 0.2


def test_external_data_and_recorded_accelerations() -> None:
    scene = gp.scenes.get("two-masses", realization="servo", k=3.0, v=0.5)
    t = np.linspace(0, 2, 201)
    q, v = np.array([scene.exact(x)[0] for x in t]), np.array([scene.exact(x)[1] for x in t])
    assert gp.verify(scene.model, {"t": t, "q": q, "v": v}).is_motion
    a = np.gradient(v, t, axis=0, edge_order=2)
    assert gp.verify(scene.model, {"t": t, "q": q, "v": v, "a": a}, acceleration="recorded").is_motion


def test_bad_input() -> None:
    scene = gp.scenes.get("two-masses", realization="servo")
    traj = motion(scene, 1.0, 51)
    with pytest.raises(gp.InitialDataError, match="off the constraint at t="):
        gp.verify(scene.model, {"t": traj.t, "q": traj.q, "v": traj.v + np.array([0.0, 1e-3])})
    with pytest.raises(gp.InputError, match="too few nodes"):
        gp.verify(scene.model, traj, window=(0.0, 0.05))
    with pytest.raises(gp.InputError, match=r"window \(0.5, 2\) is outside the data"):
        gp.verify(scene.model, traj, window=(0.5, 2.0))
    bad = traj.q.copy()
    bad[10, 0] = np.nan
    with pytest.raises(gp.NonFiniteError, match="sample 10"):
        gp.verify(scene.model, {"t": traj.t, "q": bad, "v": traj.v})
    with pytest.raises(gp.ShapeError):
        gp.verify(scene.model, {"t": traj.t, "q": traj.q[:, :1], "v": traj.v})
    with pytest.raises(gp.InputError, match="closed form needs pointwise"):
        gyro = gp.scenes.get("gyrostat")
        gp.verify(gyro.model, motion(gyro, 0.5, 51), method="closed-form")
    with pytest.raises(gp.InputError, match="metric must be a symmetric positive definite"):
        gp.verify(scene.model, traj, metric=-np.eye(2))


def _two_masses_path(F: float, realization: str) -> tuple[gp.scenes.Scene, gp.Trajectory]:
    scene = gp.scenes.get("two-masses", F=F, v=0.5, k=0.0, realization=realization)
    times = np.linspace(0.0, 1.0, 41)
    return scene, gp.simulate(scene.model, scene.q0, scene.v0, 1.0, record=times, method="DOP853", rtol=1e-12)


def test_a_path_with_no_reaction_is_a_motion_of_every_realization() -> None:
    """Without forces the two masses glide together: R is round-off (1e-29) for the rod and the servo alike,
    and the relative gap must not be round-off over round-off."""
    rod, path = _two_masses_path(0.0, "ideal")
    servo, _ = _two_masses_path(0.0, "servo")
    assert np.abs(path.reaction).max() <= 1e-12
    for model in (rod.model, servo.model):
        assert gp.verify(model, path).is_motion


@pytest.mark.parametrize("F", [1e-3, 1.0])
def test_a_small_reaction_that_does_work_is_still_caught(F: float) -> None:
    """Negative control of the round-off floor: with a force on m2 the rod's reaction works on the servo's
    variations, and the rod's path is no motion of the servo model, even when the force is small."""
    _, path = _two_masses_path(F, "ideal")
    servo, _ = _two_masses_path(F, "servo")
    result = gp.verify(servo.model, path)
    assert not result.is_motion
    assert result.relative_gap > 0.1  # a share of order one of the reaction does work, whatever the force's size


@pytest.mark.parametrize("method", ["qp", "closed-form"])
def test_the_verdict_reports_the_solved_gap(method: str, rng: np.random.Generator) -> None:
    """``judge``'s gap is the solved minimum's distance below the value at zero — from the closed form solved
    apart (not through ``judge``): a verdict that scaled the gap (halved it: the mutation check) would accept
    paths up to twice as far from a motion, which no is-motion test sees."""
    from gausspp.verification.integral import judge, value_at_zero

    for _ in range(20):
        n = int(rng.integers(1, 7))
        d = random_pointwise(rng, n, int(rng.integers(1, n + 1)), int(rng.integers(5, 40)))
        ver = judge(d, method)
        expected = max(0.0, -solve_closed_form(d)[0])
        assert ver.gap == pytest.approx(expected, rel=1e-9, abs=1e-14 * value_at_zero(d))
        assert ver.minimum == pytest.approx(value_at_zero(d) - expected, rel=1e-9, abs=1e-14 * value_at_zero(d))
