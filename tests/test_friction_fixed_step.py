"""Frictional runs in compiled fixed steps (``simulate_friction(step=h)``): the closed forms of the adaptive lane
hold (their motions are polynomial within a phase and each event is located inside its step), a smooth phase
converges at RK4's fourth order to the adaptive reference, the laws and the refusals are the same, and a failure
midway keeps the steps computed."""

from __future__ import annotations

import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.c_code import compiler
from gausspp.friction.scenes import G, box, incline, rod, spatial_ball, spatial_box
from gausspp.friction.scenes import round_body as disc

sys.path.insert(0, str(Path(__file__).parent))
from test_friction import ENERGY_RUNS, _critical_mu  # noqa: E402

BOX_Q0 = [0.0, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0]


# -- closed forms --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("h", [1e-3, 3.7e-3], ids=["h=1e-3", "h=3.7e-3"])
@pytest.mark.parametrize("scene", ["block", "box on two corners", "box on four corners"])
def test_a_sliding_box_stops_after_v0_squared_over_2_mu_g_in_fixed_steps(scene: str, h: float) -> None:
    """The stop is an event inside a step: its time and place are the closed form's to 1e-8, not the grid's."""
    mu, v0 = 0.4, 3.0
    mech, contacts = {"block": lambda: incline(0.0, mu), "box on two corners": lambda: box(mu)}.get(
        scene, lambda: spatial_box(mu)
    )()
    q0 = {"block": [0.0, 0.0], "box on two corners": [0.0, 0.1, 0.0]}.get(scene, BOX_Q0)
    v = np.zeros(len(q0) if scene != "box on four corners" else 6)
    v[0] = v0
    run = gp.simulate_friction(mech, contacts, q0, v, 1.0, step=h)
    time, distance = v0 / (mu * G), v0**2 / (2 * mu * G)
    stops = [ev for ev in run.events if ev["kind"] == "stops slipping"]
    assert len(stops) == len(contacts) and {ev["t"] for ev in stops} == {stops[0]["t"]}
    assert abs(stops[0]["t"] - time) <= 1e-8 * time
    assert abs(stops[0]["t"] - round(time / h) * h) > 1e-8 * time  # control: not a grid time
    assert abs(run.q[-1, 0] - distance) <= 1e-8 * distance
    assert abs(run.q[-1, 0] - 1.001 * distance) > 1e-8 * distance  # control
    assert all(m == ("stick",) * len(contacts) for m in run.modes[-3:])
    assert run.t[-1] == 1.0 and run.success


def test_the_box_on_four_corners_shares_its_weight_and_friction_evenly_front_and_back_by_the_moments() -> None:
    """Sliding along x, the floor's friction ``μ N`` at the corners tips the box forward: the front corners carry
    ``m g (1 + μ c/a)/4`` each and the back ones ``m g (1 − μ c/a)/4`` (moments about the centre: ``a (N_f − N_b)
    = c μ m g``, half-extents ``a = 0.2``, ``c = 0.1``); left and right are equal (the least forces on four rows of
    rank three)."""
    mu = 0.4
    mech, contacts = spatial_box(mu)
    run = gp.simulate_friction(mech, contacts, BOX_Q0, [3.0, 0, 0, 0, 0, 0], 0.5, step=1e-3)
    front = G * (1 + mu * 0.1 / 0.2) / 4
    back = G * (1 - mu * 0.1 / 0.2) / 4
    names = list(run.contact_names)
    N = run.N[len(run.t) // 2]
    for name, expected in (("front-left", front), ("front-right", front), ("back-left", back), ("back-right", back)):
        assert abs(N[names.index(name)] - expected) <= 1e-9 * expected
    assert abs(N[names.index("front-left")] - back) > 0.1  # control
    assert np.abs(run.F[len(run.t) // 2, 0::2] + mu * N).max() <= 1e-9  # F = −μ N along x at each corner


@pytest.mark.parametrize(("k", "t_factor", "speed"), [(0.4, 2 / 7, 5 / 7), (1.0, 2 / 4, 1 / 2)], ids=["ball", "hoop"])
def test_a_round_body_slides_then_rolls_in_fixed_steps(k: float, t_factor: float, speed: float) -> None:
    mu, v0, r = 0.3, 2.0, 0.1
    mech, contacts = disc(mu, k, r)
    run = gp.simulate_friction(mech, contacts, [0.0, r, 0.0], [v0, 0.0, 0.0], 1.0, step=1e-3)
    (roll,) = run.events
    assert roll["kind"] == "stops slipping" and roll["modes"] == ("stick",)
    assert abs(roll["t"] - t_factor * v0 / (mu * G)) <= 1e-8 * roll["t"]
    assert abs(run.v[-1, 0] - speed * v0) <= 1e-8 * v0
    assert abs(run.v[-1, 0] - 1.001 * speed * v0) > 1e-8 * v0  # control


def test_a_spinning_ball_rolls_from_two_u0_over_seven_mu_g_in_fixed_steps() -> None:
    """Two slip components: the direction law continued past the stop (not flipped) keeps the step that holds
    the event on the smooth phase, so the stop is exact."""
    mu, r = 0.3, 0.1
    mech, contacts = spatial_ball(mu, r)
    v0 = np.array([2.0, 0.0, 0.5, 10.0, 0.0, -5.0])
    u0 = np.array([v0[0] + r * v0[5], v0[2] - r * v0[3]])
    run = gp.simulate_friction(mech, contacts, np.zeros(6) + [0, r, 0, 0, 0, 0], v0, 0.5, step=1e-3)
    (stop,) = run.events
    expected = 2 * np.linalg.norm(u0) / (7 * mu * G)
    assert abs(stop["t"] - expected) <= 1e-8 * expected
    assert np.abs(run.v[-1, [0, 2]] - (v0[[0, 2]] - 2 / 7 * u0)).max() <= 1e-8 * np.linalg.norm(u0)


def test_the_incline_sticks_or_slides_with_g_sin_minus_mu_cos_in_fixed_steps() -> None:
    for alpha, mu in ((0.3, 0.5), (0.6, 0.5)):
        mech, contacts = incline(alpha, mu)
        run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [0.0, 0.0], 1.0, step=1e-3)
        a = run.v[-1, 0] / run.t[-1]
        expected = max(G * (np.sin(alpha) - mu * np.cos(alpha)), 0.0)
        assert abs(a - expected) <= 1e-10 * max(expected, 1e-2)
        assert run.modes[-1] == (("stick",) if expected == 0 else ("slide+",))


def test_a_dropped_ball_lands_at_the_closed_form_time_and_bounces_by_newton() -> None:
    e, r, drop = 0.6, 0.1, 0.2
    mech, contacts = disc(0.2, 0.4, r, e=e)
    run = gp.simulate_friction(mech, contacts, [0.0, r + drop, 0.0], [0.0, 0.0, 0.0], 0.5, step=1e-3)
    closes = [ev["t"] for ev in run.events if ev["kind"] == "closes"]
    first = np.sqrt(2 * drop / G)
    second = first + 2 * e * np.sqrt(2 * G * drop) / G
    assert abs(closes[0] - first) <= 1e-10 and abs(closes[1] - second) <= 1e-10
    assert abs(closes[1] - (first + 2 * 0.61 * np.sqrt(2 * G * drop) / G)) > 1e-3  # control


# -- a smooth phase: RK4's order -----------------------------------------------------------------------------------
def test_a_rod_sliding_on_its_end_converges_at_fourth_order_to_the_adaptive_reference() -> None:
    """The rod's phase is not polynomial: halving ``h`` divides the error by ~16 (measured 15.8–15.9)."""
    mech, contacts = rod(0.5)
    q0, v0 = [0.0, 0.5 * np.sin(1.0), 1.0], [-1.0, 0.0, 0.0]
    ref = gp.simulate_friction(mech, contacts, q0, v0, 0.3, rtol=1e-13, atol=1e-15)
    errors = []
    for h in (4e-3, 2e-3, 1e-3):
        run = gp.simulate_friction(mech, contacts, q0, v0, 0.3, step=h)
        errors.append(np.abs(run.v[-1] - ref.v[-1]).max())
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(12 < x < 20 for x in ratios), ratios
    assert errors[-1] <= 1e-9


# -- laws, events, refusals ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(ENERGY_RUNS))
def test_the_energy_never_rises_and_the_events_agree_with_the_adaptive_lane(name: str) -> None:
    build, q0, v0 = ENERGY_RUNS[name]
    mech, contacts = build()
    run = gp.simulate_friction(mech, contacts, q0, v0, 0.6, step=1e-3)
    ref = gp.simulate_friction(mech, contacts, q0, v0, 0.6)
    assert run.success and run.t[-1] == 0.6
    scale = np.abs(run.energy).max() + 1.0
    assert np.diff(run.energy).max() <= 1e-12 * scale
    assert [(ev["kind"], ev["contact"]) for ev in run.events] == [(ev["kind"], ev["contact"]) for ev in ref.events]
    assert all(abs(a["t"] - b["t"]) <= 1e-9 for a, b in zip(run.events, ref.events, strict=True))
    assert np.abs(run.q[-1] - ref.q[-1]).max() <= 1e-9 * (1.0 + np.abs(ref.q[-1]).max())


@pytest.mark.parametrize("theta", [0.9, 1.1071487177940904, 1.3], ids=["0.9", "atan 2", "1.3"])
def test_painleve_is_refused_in_fixed_steps_just_inside_and_resolved_by_short_steps_just_outside(theta: float) -> None:
    """Just inside the region: the named error, whatever the step. Just outside, the normal force is ~1e7 N and the
    slip stops within ~1e-7 s: steps of 1e-9 s find the adaptive lane's stop (to 1e-8); a step of 1e-3 s cannot
    resolve that phase and says so (at 1.3 rad the rate changes by ~1e40 of the state within it)."""
    mu_star = _critical_mu(theta)
    q0, v0 = [0.0, 0.5 * np.sin(theta), theta], [-1.0, 0.0, 0.0]
    mech, contacts = rod(mu_star * (1 + 1e-6))
    with pytest.raises(gp.PainleveError) as err:
        gp.simulate_friction(mech, contacts, q0, v0, 0.01, step=1e-3)
    assert abs(err.value.mu_critical - mu_star) <= 1e-9 * mu_star
    mech, contacts = rod(mu_star * (1 - 1e-6))
    ref = gp.simulate_friction(mech, contacts, q0, v0, 2e-7, rtol=1e-12, atol=1e-14)
    run = gp.simulate_friction(mech, contacts, q0, v0, 2e-7, step=1e-9)
    assert run.success and abs(run.events[0]["t"] - ref.events[0]["t"]) <= 1e-8 * ref.events[0]["t"]
    if theta == 1.3:
        # where within the first step the guard names the failure (its end, or the slip's stop an event search
        # found inside it, ~2.5e-8 s) depends on round-off at a rate of ~1e40: the message and the kept start do not
        with pytest.raises(gp.IntegrationError, match="step h=0.001 is too long for the phase at t=") as too_long:
            gp.simulate_friction(mech, contacts, q0, v0, 0.01, step=1e-3)
        assert too_long.value.run.t.tolist() == [0.0]  # the start is kept


def test_recorded_times_lie_on_the_closed_form_and_the_stop_is_kept() -> None:
    mu, v0 = 0.4, 3.0
    mech, contacts = incline(0.0, mu)
    grid = np.linspace(0.0, 1.0, 101)
    run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [v0, 0.0], 1.0, step=3.3e-3, record=grid)
    stop = v0 / (mu * G)
    assert np.isin(grid, run.t).all() and any(abs(t - stop) <= 1e-8 * stop for t in run.t)
    sliding = run.t < stop
    assert np.abs(run.q[sliding, 0] - (v0 * run.t - 0.5 * mu * G * run.t**2)[sliding]).max() <= 1e-9
    assert len(run.t) < 110  # the grid, the stop and the phases' ends: not every step


@pytest.mark.skipif(compiler() is None, reason="no C compiler on the PATH")
def test_the_phases_as_c_give_the_virtual_machines_numbers() -> None:
    mech, contacts = box(0.4)
    vm = gp.simulate_friction(mech, contacts, [0.0, 0.1, 0.0], [3.0, 0.0, 0.0], 1.0, step=1e-3)
    c = gp.simulate_friction(mech, contacts, [0.0, 0.1, 0.0], [3.0, 0.0, 0.0], 1.0, step=1e-3, codegen=True)
    assert np.array_equal(vm.t.shape, c.t.shape)
    assert np.abs(vm.q - c.q).max() <= 1e-12 and abs(vm.events[0]["t"] - c.events[0]["t"]) <= 1e-12


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"step": 0.0}, "step"), ({"step": float("nan")}, "step"), ({"step": 1e-3, "codegen": "yes"}, "codegen")],
)
def test_bad_steps_are_refused(kwargs: dict, match: str) -> None:
    mech, contacts = incline(0.3, 0.5)
    with pytest.raises(gp.InputError, match=match):
        gp.simulate_friction(mech, contacts, [0.0, 0.0], [0.0, 0.0], 1.0, **kwargs)


def test_a_failure_midway_keeps_the_steps_computed() -> None:
    """A potential ``√(1 − x)`` pulls a frictionless block to ``x = 1``, where its force is infinite and beyond which
    it is not defined: the run stops there with a NonFiniteError naming the time; the steps before it are kept,
    marked failed."""
    mech = gp.Lagrangian(
        2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2), V=lambda q, t: G * q[1] + ca.sqrt(1 - q[0])
    )
    contacts = [gp.FrictionContact(lambda q: q[1], lambda q, v: v[0], 0.0, name="floor")]
    with pytest.raises(gp.NonFiniteError, match=r"non-finite at t=0\.\d+ \(modes \('slide\+',\)\)") as err:
        gp.simulate_friction(mech, contacts, [0.0, 0.0], [1.0, 0.0], 2.0, step=1e-3)
    run = err.value.run
    assert run.status == "failed" and 0.9 < run.q[-1, 0] < 1.0 and len(run.t) > 100
    assert np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.energy))
    kept = gp.simulate_friction(mech, contacts, [0.0, 0.0], [1.0, 0.0], 2.0, step=1e-3, throw=False)
    assert kept.status == "failed" and np.array_equal(kept.t, run.t)


# -- found by review: a slip that turns, events at t_end, recording after a failure ------------------------------------
def test_a_slip_that_turns_by_ninety_degrees_is_a_new_phase_not_a_stop_and_stays_fourth_order() -> None:
    """A box sliding and spinning on four corners: a corner's slip turns past 90° from its phase's first direction
    while it still slips. Both lanes log it as ``"turns"`` (not a stop) and slide on along the new direction, and the
    fixed steps converge at fourth order to the adaptive run through it (the direction is the slip's own within 120°
    of the phase's first: a flipped one made the state after the turn first-order, 2.2e-3 off at h = 1e-3)."""
    mech, contacts = spatial_box(0.4)
    v0 = [1.0, 0.0, 0.0, 0.0, 0.0, 12.0]
    ref = gp.simulate_friction(mech, contacts, BOX_Q0, v0, 0.3, rtol=1e-12, atol=1e-14)
    turns = [ev for ev in ref.events if ev["kind"] == "turns"]
    assert turns and all(m == "slide" for m in turns[0]["modes"])
    from gausspp.friction.kinematics import ContactKinematics

    i = int(np.flatnonzero(ref.t == turns[0]["t"])[0])
    slip = ContactKinematics(mech, contacts)(ref.q[i], ref.v[i]).s[list(ref.contact_names).index(turns[0]["contact"])]
    assert np.linalg.norm(slip) > 0.1  # control: it turned, it did not stop (measured 0.47 m/s)
    errors = []
    for h in (1e-3, 5e-4):
        run = gp.simulate_friction(mech, contacts, BOX_Q0, v0, 0.3, step=h)
        assert [ev["kind"] for ev in run.events] == [ev["kind"] for ev in ref.events]
        errors.append(np.abs(run.v[-1] - ref.v[-1]).max())
    assert errors[0] <= 1e-8 and 10 < errors[0] / errors[1] < 25, errors  # measured 6.9e-10, ratio 16


def test_an_event_within_round_off_past_t_end_ends_the_run_at_t_end() -> None:
    """The last step of 1e-3 ends 1e-13 past ``t_end`` (labelled ``t_end``) and the stop falls between: the run ends at
    ``t_end`` without the event, as the adaptive lane does (it raised scipy's ValueError before)."""
    mu, h = 0.4, 1e-3
    mech, contacts = incline(0.0, mu)
    t_end, stop = 0.2 - 1e-13, 0.2 - 0.5e-13
    run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [mu * G * stop, 0.0], t_end, step=h)
    ref = gp.simulate_friction(mech, contacts, [0.0, 0.0], [mu * G * stop, 0.0], t_end)
    assert run.success and run.t[-1] == t_end and run.events == ref.events == []


def test_an_event_at_t_end_ends_the_run_with_one_sample_there() -> None:
    """The box stops at ``t_end`` itself, on the grid: whether round-off puts the stop just before or just after the
    last step's end, the run ends with one sample at ``t_end`` (no phase of length zero after an event there)."""
    mu, h = 0.4, 1e-3
    mech, contacts = incline(0.0, mu)
    t_end = 39 * h
    run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [mu * G * t_end, 0.0], t_end, step=h)
    assert run.success and (run.t == t_end).sum() == 1 and len(run.events) <= 1
    assert all(abs(ev["t"] - t_end) <= 1e-12 for ev in run.events)


def test_a_failure_keeps_only_the_recorded_times() -> None:
    potential = lambda q, t: G * q[1] + ca.sqrt(1 - q[0])  # noqa: E731
    mech = gp.Lagrangian(2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2), V=potential)
    contacts = [gp.FrictionContact(lambda q: q[1], lambda q, v: v[0], 0.0, name="floor")]
    grid = np.linspace(0.0, 2.0, 201)
    run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [1.0, 0.0], 2.0, step=3.3e-3, record=grid, throw=False)
    assert run.status == "failed" and len(run.t) > 10 and np.isin(run.t, grid).all()
    assert np.array_equal(run.t, grid[: len(run.t)])  # every requested time before the failure, in order


def test_the_adaptive_lane_names_a_non_finite_force_and_keeps_the_phase_start() -> None:
    """The same scene in the adaptive lane: scipy keeps no partial phase, so the run keeps the phase's start and says
    where the forces stopped being finite (it said "the contact rows became dependent" before)."""
    potential = lambda q, t: G * q[1] + ca.sqrt(1 - q[0])  # noqa: E731
    mech = gp.Lagrangian(2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2), V=potential)
    contacts = [gp.FrictionContact(lambda q: q[1], lambda q, v: v[0], 0.0, name="floor")]
    run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [1.0, 0.0], 2.0, throw=False)
    assert isinstance(run.failure, gp.NonFiniteError) and run.t.tolist() == [0.0]
    t_fail = float(run.message.split("t=")[1].split()[0])
    fixed = gp.simulate_friction(mech, contacts, [0.0, 0.0], [1.0, 0.0], 2.0, step=1e-3, throw=False)
    assert abs(t_fail - fixed.t[-1]) <= 2e-3  # where the fixed steps stopped too


def test_a_mass_matrix_that_stops_being_positive_definite_is_refused_at_the_step_that_meets_it() -> None:
    """``A = diag(1, 1 − x)`` of a block sliding at 2 m/s (μ = 0.2, reaching x = 1 at t ≈ 0.513): the fixed steps stop
    with the step's own NotPositiveDefiniteError within a step of that time and keep the steps before; a mechanism
    that knows no energy (NaN) runs as any other until then."""
    mech = gp.MassMatrix(n=2, A=lambda q, t: [[1.0, 0.0], [0.0, 1.0 - q[0]]], f=lambda q, v, t: [0.0, -1.0])
    contacts = [gp.FrictionContact(lambda q: q[1], lambda q, v: v[0], 0.2, name="floor")]
    ok = gp.simulate_friction(mech, contacts, [0.0, 0.0], [2.0, 0.0], 0.5, step=1e-3)
    assert ok.success and np.isnan(ok.energy).all() and abs(ok.q[-1, 0] - (2 * 0.5 - 0.1 * 0.25)) <= 1e-12
    run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [2.0, 0.0], 1.0, step=1e-3, throw=False)
    assert isinstance(run.failure, gp.NotPositiveDefiniteError) and run.q[:, 0].max() < 1.0
    crossing = (2 - np.sqrt(4 - 4 * 0.1)) / 0.2  # x = 2t − 0.1t² = 1
    assert crossing - 2e-3 <= run.t[-1] < crossing
