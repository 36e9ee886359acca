"""Unilateral contacts (issue 7): Gauss's principle with inequalities, impacts, rest, lift-off."""

from __future__ import annotations

import itertools

import casadi as ca
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import gausspp as gp
from gausspp.scenes.block_on_floor import bounce_times
from gausspp.scenes.bouncing_pendulum import impact_times
from gausspp.simulation.contacts import gaps as contact_gaps
from gausspp.step.general import GaussProblem, solve_general

from .factories import random_spd

BACKENDS = ["daqp", "osqp"]
G = 9.81


@pytest.fixture(scope="module")
def block_run() -> tuple[gp.scenes.Scene, gp.Trajectory]:
    scene = gp.scenes.get("block-on-floor", e=0.5, drop=1.0, t_end=2.0)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, rtol=1e-12, atol=1e-14, dt=0.05)
    return scene, traj


def _impact_times(traj: gp.Trajectory) -> np.ndarray:
    return np.array(sorted({ev["t"] for ev in traj.events if ev["kind"] == "impact"}))


# -- a block dropped flat on a floor: the point-mass bounce in closed form ---------------------------
def test_block_impact_times_follow_the_closed_form(block_run) -> None:
    scene, traj = block_run
    times = _impact_times(traj)
    assert times.size >= 10
    ref = bounce_times(1.0, 0.5, G, times.size)
    assert np.max(np.abs(times[:10] - ref[:10])) <= 1e-9
    assert np.max(np.abs(times - ref)) <= 1e-9  # every bounce down to rest_speed


def test_block_bounce_heights_follow_the_closed_form(block_run) -> None:
    """Recorded at the closed-form apex times (from the dense output): the height is ``e^{2k}`` of the drop and
    the vertical velocity zero there — both off by far more than 1e-9 if the apex came at another time."""
    scene, _traj = block_run
    times = bounce_times(1.0, 0.5, G, 11)
    v1 = np.sqrt(2 * G)
    apexes = times[:10] + 0.5 ** np.arange(1, 11) * v1 / G
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, rtol=1e-12, atol=1e-14, dt=0.05, record=apexes)
    at = np.isin(traj.t, apexes)  # the impacts' states are recorded too
    heights = traj.q[at, 1] - 0.5 * scene.params["h"]
    expected = 1.0 * 0.5 ** (2 * np.arange(1, 11))
    assert at.sum() == 10
    assert np.max(np.abs(heights - expected)) <= 1e-9
    assert np.max(np.abs(traj.v[at, 1])) <= 1e-9 * v1


def test_block_comes_to_rest_with_contact_force_equal_to_its_weight(block_run) -> None:
    scene, traj = block_run
    v1 = np.sqrt(2 * G)
    t_rest = np.sqrt(2 / G) + 2 * 0.5 * v1 / (G * 0.5)
    resting = traj.t > t_rest + 1e-3
    assert resting.sum() >= 3
    weight = scene.params["m"] * G
    total = traj.contact_force[resting].sum(axis=1)
    assert np.max(np.abs(total - weight)) <= 1e-12 * weight
    bottom = traj.contact_force[resting][:, :2]  # corner+ and corner- (the top corners carry nothing)
    assert np.max(np.abs(bottom - weight / 2)) <= 1e-12 * weight  # symmetric: half each
    assert np.max(np.abs(traj.v[resting])) <= 1e-12


def test_block_never_penetrates_and_its_energy_balance_closes(block_run) -> None:
    scene, traj = block_run
    gaps = np.array([contact_gaps(scene.model, t, q, v)[0] for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)])
    assert gaps.min() >= -1e-12
    # the impulses' work is booked as the reaction's work: ΔE − W_R = 0 through every impact
    assert np.max(np.abs(traj.energy_balance())) <= 1e-10
    assert traj.energy[-1] < 0.5 * traj.energy[0] + 1e-9  # and energy was lost, all of it at impacts


def test_block_follows_the_exact_motion(block_run) -> None:
    scene, traj = block_run
    err = max(np.max(np.abs(scene.exact(t)[0] - q)) for t, q in zip(traj.t, traj.q, strict=True))
    assert err <= 1e-9


def test_impacts_lose_energy_by_e_squared_for_the_normal_motion(block_run) -> None:
    _, traj = block_run
    impacts = [ev for ev in traj.events if ev["kind"] == "impact" and not ev["plastic"]]
    ratios = np.array([ev["speed_after"] / -ev["speed_before"] for ev in impacts])
    assert np.max(np.abs(ratios - 0.5)) <= 1e-12
    last = [ev for ev in traj.events if ev["kind"] == "impact"][-1]
    assert last["plastic"] and abs(last["speed_after"]) <= 1e-15  # the slow last impact ends in rest


def test_a_tilted_block_rocks_and_settles_on_both_corners() -> None:
    scene = gp.scenes.get("block-on-floor", tilt=0.3, e=0.3, drop=0.2, t_end=2.5)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, rtol=1e-11, atol=1e-13)
    gaps = np.array([contact_gaps(scene.model, t, q, v)[0] for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)])
    assert gaps.min() >= -1e-12
    assert np.max(np.abs(traj.energy_balance())) <= 1e-8
    kinds = {ev["kind"] for ev in traj.events}
    assert "impact" in kinds
    assert {ev["contact"] for ev in traj.events if ev["kind"] == "impact"} == {"corner+", "corner-"}
    weight = scene.params["m"] * G
    assert abs(traj.contact_force[-1].sum() - weight) <= 1e-9 * weight
    assert abs(traj.q[-1, 2]) <= 1e-9  # flat on the floor


# -- a pendulum hitting a wall -------------------------------------------------------------------
@pytest.fixture(scope="module")
def pendulum_run() -> tuple[gp.scenes.Scene, gp.Trajectory]:
    scene = gp.scenes.get("bouncing-pendulum", e=0.8, theta0=1.0, t_end=3.5)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, rtol=1e-12, atol=1e-14)
    return scene, traj


def test_pendulum_impact_times_are_located_to_1e_10(pendulum_run) -> None:
    scene, traj = pendulum_run
    times = _impact_times(traj)
    assert times.size >= 3
    ref = impact_times(1.0, G, 1.0, 0.8, times.size)
    assert abs(times[0] - ref[0]) <= 1e-10
    assert np.max(np.abs(times - ref)) <= 1e-9


def test_pendulum_kinetic_energy_after_impact_is_e_squared_before(pendulum_run) -> None:
    _, traj = pendulum_run
    impacts = [ev for ev in traj.events if ev["kind"] == "impact"]
    ratios = np.array([ev["kinetic_energy_after"] / ev["kinetic_energy_before"] for ev in impacts])
    assert np.max(np.abs(ratios - 0.8**2)) <= 1e-12


def test_pendulum_keeps_its_rod_and_never_enters_the_wall(pendulum_run) -> None:
    _, traj = pendulum_run
    assert traj.max_residual() <= 1e-11
    assert traj.q[:, 0].min() >= -1e-12
    assert np.max(np.abs(traj.energy_balance())) <= 1e-10


@pytest.mark.parametrize("backend", BACKENDS)
def test_pendulum_runs_the_same_on_both_qp_backends(pendulum_run, backend: str) -> None:
    scene, reference = pendulum_run
    traj = gp.simulate(
        scene.model, scene.q0, scene.v0, scene.t_end, rtol=1e-12, atol=1e-14, backend=f"qpsolvers:{backend}"
    )
    assert np.max(np.abs(_impact_times(traj) - _impact_times(reference))) <= 1e-10


# -- the step and the impact as QPs ----------------------------------------------------------------
def _ball(e: float = 0.5) -> gp.Model:
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), V=lambda q, t: G * q[1])
    return gp.Model(body, [gp.Unilateral(lambda q, t: q[1], name="floor", restitution=e)])


@pytest.mark.parametrize("backend", BACKENDS)
def test_step_resting_open_and_pulling_contacts(backend: str) -> None:
    model = _ball()
    rest = model.step(0.0, [0.0, 0.0], [1.0, 0.0], backend=backend)
    assert rest.contact_force == pytest.approx([G], abs=1e-9) and np.max(np.abs(rest.a)) <= 1e-9
    flying = model.step(0.0, [0.0, 0.3], [1.0, 0.0], backend=backend)
    assert flying.contact_force == pytest.approx([0.0]) and flying.a == pytest.approx([0.0, -G])
    # on the floor but pulled up harder than gravity: the contact lets go (no pulling force)
    up = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), V=lambda q, t: -3.0 * q[1])
    lifted = gp.Model(up, [gp.Unilateral(lambda q, t: q[1], name="floor")]).step(0.0, [0, 0], [0, 0], backend=backend)
    assert lifted.contact_force == pytest.approx([0.0], abs=1e-9) and lifted.a == pytest.approx([0.0, 3.0])


def test_step_refuses_an_approaching_contact_and_the_direct_solver() -> None:
    model = _ball()
    with pytest.raises(gp.InputError, match=r"'floor' is closed and approaching.*impact"):
        model.step(0.0, [0.0, 0.0], [0.0, -1.0])
    with pytest.raises(gp.InputError, match="solver='qp'"):
        model.step(0.0, [0.0, 0.0], [0.0, 0.0], solver="direct")
    with pytest.raises(gp.InputError, match="general Gauss QP"):
        model.kernel("direct")


@pytest.mark.parametrize("backend", BACKENDS)
def test_impact_with_restitution_and_friction_free_tangent(backend: str) -> None:
    res = _ball(0.5).impact(0.0, [0.0, 0.0], [1.0, -2.0], backend=backend)
    assert res.v_after == pytest.approx([1.0, 1.0], abs=1e-9)  # normal speed reversed × e, tangent kept
    assert res.impulse == pytest.approx([3.0], abs=1e-9)
    assert res.kinetic_energy_after == pytest.approx(1.0, abs=1e-9)


def test_unilateral_and_contact_simulation_input_errors() -> None:
    with pytest.raises(gp.InputError, match=r"restitution must lie in \[0, 1\]"):
        gp.Unilateral(lambda q, t: q[0], restitution=1.5)
    model = _ball()
    with pytest.raises(gp.InitialDataError, match="penetrate the contact 'floor'"):
        gp.simulate(model, [0.0, -0.1], [0.0, 0.0], 1.0)
    with pytest.raises(gp.InputError, match="cannot locate contact events"):
        gp.simulate(model, [0.0, 1.0], [0.0, 0.0], 1.0, method="rk4", dt=0.01)


def test_a_contact_run_that_fails_keeps_what_it_computed() -> None:
    model = _ball(1.0)  # elastic: never comes to rest, events pile up
    with pytest.raises(gp.IntegrationError, match="contact events") as info:
        gp.simulate(model, [0.0, 1.0], [0.0, 0.0], 10.0, max_events=3)
    traj = info.value.trajectory  # type: ignore[attr-defined]
    assert traj.status == "failed" and traj.t[-1] > 0.4 and len(traj.events) == 4


# -- Gauss's principle with inequalities ≡ the KKT (complementarity) solution -----------------------
@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 5), st.integers(1, 4))
def test_inequality_qp_is_the_least_compulsion_among_active_sets(seed: int, n: int, k: int) -> None:
    """Enumerate every active set, keep the feasible complementary one: it is the QP's answer.

    Contacts with independent normals (k ≤ n, cond(J A⁻¹ Jᵀ) < 1e5 with normalized rows; dependent normals
    have non-unique forces).
    """
    k = min(k, n)
    rng = np.random.default_rng(seed)
    A = random_spd(rng, n, rng.uniform(0, 3))
    a0, J, phi = rng.standard_normal(n), rng.standard_normal((k, n)), rng.standard_normal(k)
    problem = GaussProblem(A, a0, J.T, J, phi, ["ge"] * k, np.zeros(k), np.full(k, np.inf))
    # contacts whose normals are nearly dependent in the kinetic metric have ill-determined forces: left out
    Jt = np.linalg.solve(np.linalg.cholesky(A), J.T).T
    Jt /= np.linalg.norm(Jt, axis=1)[:, None]
    cond_H = float(np.linalg.cond(Jt @ Jt.T))
    assume(cond_H < 1e5)
    answers = {"daqp": solve_general(problem, "daqp")}
    try:
        answers["osqp"] = solve_general(problem, "osqp")
    except gp.QPSolveError:
        # OSQP (first-order ADMM) may not reach its 1e-12 tolerance on ill-conditioned steps: it must then
        # say so — never answer wrongly — and it must answer on well-conditioned ones
        assert cond_H > 1e2
    best = None
    for size in range(k + 1):
        for active in itertools.combinations(range(k), size):
            Ja = J[list(active)]
            mu = np.zeros(k)
            if size:
                S = Ja @ np.linalg.solve(A, Ja.T)
                mu[list(active)] = np.linalg.solve(S, phi[list(active)] - Ja @ a0)
            a = a0 + np.linalg.solve(A, J.T @ mu)
            if np.all(mu >= -1e-12) and np.all(J @ a - phi >= -1e-10):
                Z = float((a - a0) @ A @ (a - a0))
                if best is None or Z < best[0] - 1e-12:
                    best = (Z, a, mu)
    assert best is not None
    # OSQP is a first-order method: its answer is accurate to about 1e-12·cond(H) on the unit-sized problem
    # (measured), H = J A⁻¹ Jᵀ with normalized rows; daqp (active set) to round-off
    for backend, sol in answers.items():
        floor = 1.0 if backend == "daqp" else max(1.0, 1e4 * cond_H * 1e-12 / 1e-8)
        scale = 1 + np.max(np.abs(best[1]))
        assert np.max(np.abs(sol.a - best[1])) <= 1e-8 * floor * scale, (backend, cond_H)
        assert np.max(np.abs(sol.u - best[2])) <= 1e-7 * floor * (1 + np.max(np.abs(best[2]))), (backend, cond_H)
        assert np.all(sol.u >= -1e-12) and np.all(sol.residual >= -1e-9 * scale)
        assert abs(sol.u @ sol.residual) <= 1e-8 * floor * scale * (1 + np.max(np.abs(sol.u)))  # complementarity


def test_a_point_mass_dropped_on_a_floor_bounces_and_rests_as_the_closed_form_says() -> None:
    """The issue's case itself: a point mass (not a block) from h = 1 with e = 0.5."""
    body = gp.Lagrangian(n=1, T=lambda q, v, t: 0.5 * 2.0 * v[0] ** 2, V=lambda q, t: 2.0 * G * q[0])
    model = gp.Model(body, [gp.Unilateral(lambda q, t: q[0], name="floor", restitution=0.5)])
    ref = bounce_times(1.0, 0.5, G, 11)
    apexes = ref[:10] + 0.5 ** np.arange(1, 11) * np.sqrt(2 * G) / G  # recorded there from the dense output
    record = np.concatenate([apexes, np.linspace(1.9, 2.0, 5)])
    traj = gp.simulate(model, [1.0], [0.0], 2.0, rtol=1e-12, atol=1e-14, dt=0.05, record=record)
    times = _impact_times(traj)
    assert np.max(np.abs(times[:10] - ref[:10])) <= 1e-9
    at = np.isin(traj.t, apexes)
    assert at.sum() == 10
    assert np.max(np.abs(traj.q[at, 0] - 0.25 ** np.arange(1, 11))) <= 1e-9
    assert np.max(np.abs(traj.v[at, 0])) <= 1e-9 * np.sqrt(2 * G)
    at_rest = traj.t > times[-1] + 1e-3
    assert at_rest.sum() >= 3 and np.max(np.abs(traj.contact_force[at_rest, 0] - 2.0 * G)) <= 1e-12 * 2.0 * G
    assert traj.q[:, 0].min() >= -1e-12


def test_a_block_that_tips_over_lands_on_its_top_corners_instead_of_sinking() -> None:
    scene = gp.scenes.get("block-on-floor", tilt=0.3, e=0.7, drop=0.5, t_end=3.0)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, rtol=1e-10, atol=1e-12)
    gaps = np.array([contact_gaps(scene.model, t, q, v)[0] for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)])
    assert gaps.min() >= -1e-12  # every corner, the whole run
    assert np.max(np.abs(traj.energy_balance())) <= 1e-8
    assert traj.energy[-1] >= -1e-9  # never below the floor's potential of the lowest state


def test_simultaneous_impacts_share_one_velocity_jump_and_a_resting_corner_is_no_impact(block_run) -> None:
    _, traj = block_run
    impacts = [ev for ev in traj.events if ev["kind"] == "impact"]
    by_jump: dict[int, list[dict]] = {}
    for ev in impacts:
        by_jump.setdefault(ev["jump"], []).append(ev)
    assert all(len({ev["t"] for ev in evs}) == 1 for evs in by_jump.values())
    assert all(len(evs) == 2 for evs in by_jump.values())  # the flat block: both corners at every jump
    assert all(ev["speed_before"] < -1e-9 for ev in impacts)


def test_a_closed_contact_that_separates_by_acceleration_does_not_chatter() -> None:
    """A block spinning on one resting corner (g = ġ = 0, g̈ > 0) leaves it without events piling up at t = 0."""
    scene = gp.scenes.get("block-on-floor", tilt=0.3, drop=0.0, e=0.5, t_end=0.5)
    model, q0 = scene.model, scene.q0.copy()
    omega = -8.0
    # ż such that the lower corner's gap rate is zero: ġ = ż + (w/2) cos θ θ̇·s + (h/2) sin θ θ̇
    w, h, th = scene.params["w"], scene.params["h"], q0[2]
    lower = int(np.argmin(contact_gaps(model, 0.0, q0, np.zeros(3))[0]))
    s = 1.0 if lower == 0 else -1.0
    zdot = -(s * 0.5 * w * np.cos(th) + 0.5 * h * np.sin(th)) * omega
    v0 = np.array([0.0, zdot, omega])
    assert abs(contact_gaps(model, 0.0, q0, v0)[1][lower]) <= 1e-12
    traj = gp.simulate(model, q0, v0, 0.5, rtol=1e-12, atol=1e-14, max_events=200)
    assert traj.success and len(traj.events) < 200 and traj.events[0]["t"] > 1e-3  # leaves, comes back later
    gaps = np.array([contact_gaps(model, t, q, v)[0] for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)])
    assert gaps.min() >= -1e-12  # a corner resting while the block turns drifts by the tolerance (2e-11 at 1e-10)


def test_a_mass_matrix_that_is_not_positive_definite_stops_a_contact_run_and_a_step() -> None:
    """diag(1, −1): the compiled step's pivot check used to miss it (NaN from the failed factorization was
    dropped by casadi's fmin, and NaN·0 simplified to 0), so the free flight ran on."""
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * (v[0] ** 2 - v[1] ** 2), V=lambda q, t: G * q[1])
    contact = gp.Model(body, [gp.Unilateral(lambda q, t: q[1], name="floor")])
    traj = gp.simulate(contact, [0.0, 1.0], [0.0, 0.0], 1.0, throw=False)
    assert traj.status == "failed" and "NotPositiveDefiniteError" in traj.message
    rail = gp.Model(body, [gp.Constraint(lambda q, v, t: v[0], name="rail")])
    with pytest.raises(gp.NotPositiveDefiniteError, match=r"eigenvalues \[-1\.\s+1\.\]"):
        rail.step(0.0, [0.0, 1.0], [0.0, 0.0])
