"""gp.verify on every scene's own simulated run: a motion (issues 15, 29).

Contacts are verified between their events, a saturating servo by the law it followed on each
interval (gausspp.verification.pieces). Negative controls: the same paths checked against a model with another
parameter (gravity, the motor's bound) or bent, still on the constraint, are not motions.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import gausspp as gp

#: Horizons long enough for each scene's events (impacts, rest, the saturation at t ≈ 1.42), short otherwise.
HORIZON = {"block-on-floor": 1.5, "bouncing-pendulum": 1.2, "saturated-crane": 1.7, "four-bar-redundant": 0.5}


def run(scene: gp.scenes.Scene, horizon: float) -> gp.Trajectory:
    """The scene's default run (its own drift control), coarse: every accepted DOP853 step of at most T/150."""
    return gp.simulate(
        scene.model,
        scene.q0,
        scene.v0,
        horizon,
        lam0=scene.lam0,
        method="DOP853",
        rtol=1e-9,
        dt=horizon / 150,
        stabilize=scene.params.get("stabilize"),
    )


def horizon(name: str, scene: gp.scenes.Scene) -> float:
    return HORIZON.get(name, min(scene.t_end, 0.6))


@pytest.mark.parametrize(
    "name", gp.scenes.names("equality") + gp.scenes.names("general")
)  # servo: no one-step solution
def test_every_scene_is_a_motion(name: str) -> None:
    """Every scene's run passes the integral principle (no scene is refused: a refusal fails here)."""
    scene = gp.scenes.get(name)
    traj = run(scene, horizon(name, scene))
    check = gp.verify(scene.model, traj)
    print(f"{name}: {check.message}")
    assert check.is_motion, check.message
    assert check.relative_gap <= check.tolerance
    assert check.message


@pytest.mark.parametrize(
    "name", ["pendulum", "andrews", "four-bar-redundant", "planar-chain", "two-masses", "mixed-rate"]
)
def test_the_same_path_traversed_slower_is_not_a_motion(name: str) -> None:
    """Negative control of the test above: each run's path traversed 1 % slower (``t → 1.01 t``, ``v → v/1.01``)
    stays on the constraint but breaks the dynamics of a system under forces: NOT a motion (measured relative gaps
    8 to 10 times the tolerance). (A force-free body — the gyrostat, the skate — has no such control: its motion
    slowed down is a motion.)"""
    scene = gp.scenes.get(name)
    traj = run(scene, horizon(name, scene))
    check = gp.verify(scene.model, replace(traj, t=traj.t * 1.01, v=traj.v / 1.01))
    assert not check.is_motion and check.relative_gap > 2 * check.tolerance


def test_contacts_are_verified_between_events() -> None:
    scene = gp.scenes.get("bouncing-pendulum")
    traj = run(scene, 1.2)
    check = gp.verify(scene.model, traj)
    impacts = [e["t"] for e in traj.events if e["kind"] == "impact"]
    assert impacts and len(check.pieces) == len(impacts) + 1
    for piece in check.pieces:  # no piece runs across a velocity jump
        assert not any(piece.t[0] < t < piece.t[-1] for t in impacts)
    assert "velocity jump(s) checked against the impact law" in check.message


def test_a_velocity_jump_off_the_impact_law_is_caught() -> None:
    """Negative control of the jump check: the bouncing pendulum's first v⁺ altered by 1e-3 (relative) is named;
    the recorded one passes."""
    scene = gp.scenes.get("bouncing-pendulum")
    traj = run(scene, 1.2)
    assert "impact law by" not in gp.verify(scene.model, traj).message
    after = int(np.flatnonzero(traj.t[1:] <= traj.t[:-1])[0]) + 1
    v = traj.v.copy()
    v[after] *= 1 + 1e-3
    check = gp.verify(scene.model, replace(traj, v=v))
    assert not check.is_motion and "differs from the model's impact law" in check.message


def test_resting_contact_force_is_recovered() -> None:
    scene = gp.scenes.get("block-on-floor")
    traj = run(scene, 1.5)
    check = gp.verify(scene.model, traj)
    rest = check.pieces[-1]
    assert check.is_motion and "corner+" in check.message
    weight = scene.params["m"] * scene.params["g"]
    corners = rest.multipliers[1:-1, -2:]  # the two bottom corners carry the block at rest
    np.testing.assert_allclose(corners.sum(axis=1), weight, rtol=1e-6)


@pytest.mark.parametrize(("name", "changed"), [("bouncing-pendulum", {"g": 9.0}), ("block-on-floor", {"g": 9.0})])
def test_contact_path_of_another_gravity_is_not_a_motion(name: str, changed: dict[str, float]) -> None:
    scene = gp.scenes.get(name)
    traj = run(scene, HORIZON[name])
    check = gp.verify(gp.scenes.get(name, **changed).model, traj)
    assert not check.is_motion
    assert "NOT a motion" in check.message


def test_saturated_interval_follows_the_bound() -> None:
    scene = gp.scenes.get("saturated-crane")
    traj = run(scene, 1.7)
    assert traj.saturated.any()
    own = gp.verify(scene.model, traj)
    assert own.is_motion and "saturated: actuators at their bounds" in own.message
    # a motor with another bound would have pushed with another force on the saturated interval
    other = gp.verify(gp.scenes.get("saturated-crane", F_max=13.0).model, traj)
    assert not other.is_motion
    saturated = [p for p in other.pieces if "saturated" in p.message and "unsaturated" not in p.message]
    assert saturated and not saturated[0].is_motion


def test_bent_contact_flight_is_not_a_motion() -> None:
    """The pendulum's first swing bent by ε·bump along the rod (still on it, same jumps): not a motion."""
    scene = gp.scenes.get("bouncing-pendulum")
    traj = run(scene, 1.2)
    first = traj.t <= traj.events[0]["t"]
    t = traj.t[first]
    s = t / t[-1]
    bump, dbump = 0.05 * np.sin(np.pi * s) ** 3, 0.05 * 3 * np.pi * np.sin(np.pi * s) ** 2 * np.cos(np.pi * s) / t[-1]
    theta = np.arctan2(traj.q[first, 0], -traj.q[first, 1]) + bump
    L = scene.params["L"]
    omega = (traj.q[first, 0] * traj.v[first, 1] - traj.q[first, 1] * traj.v[first, 0]) / L**2 + dbump
    q, v = traj.q.copy(), traj.v.copy()
    q[first] = np.c_[L * np.sin(theta), -L * np.cos(theta)]
    v[first] = np.c_[L * np.cos(theta) * omega, L * np.sin(theta) * omega]
    bent = {"t": traj.t, "q": q, "v": v, "events": traj.events}
    check = gp.verify(scene.model, bent)
    assert not check.is_motion and not check.pieces[0].is_motion and check.pieces[1].is_motion


def test_failed_run_is_verified_on_what_it_computed() -> None:
    """A failed run returns what it computed, marked failed: that part is verified and the message says so."""
    scene = gp.scenes.get("two-masses", realization="servo")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.0, method="rk4", dt=0.01)
    failed = replace(traj, status="failed", message="IntegrationError: stopped at t=1 (a stand-in failure)")
    check = gp.verify(scene.model, failed)
    assert check.is_motion and "the run failed (IntegrationError" in check.message
    assert check.t[-1] == traj.t[-1]


def test_short_pieces_and_nodes_are_refused_clearly() -> None:
    scene = gp.scenes.get("bouncing-pendulum")
    traj = run(scene, 1.2)
    with pytest.raises(gp.InputError, match="verified piece by piece"):
        gp.verify(scene.model, traj, nodes=50)
    sparse = {"t": traj.t[::40], "q": traj.q[::40], "v": traj.v[::40]}
    with pytest.raises(gp.InputError, match="nothing to verify.*samples; a piece needs at least"):
        gp.verify(scene.model, sparse)


def test_redundant_rows_do_not_make_the_verdict_vacuous() -> None:
    """Dependent constraint rows left the sparse QP with no solution (η = 0, every path 'a motion')."""
    minimal = gp.scenes.get("four-bar-redundant", redundant=False)
    traj = gp.simulate(minimal.model, minimal.q0, minimal.v0, 0.5, method="DOP853", rtol=1e-10, solver="direct")
    assert gp.verify(gp.scenes.get("four-bar-redundant").model, traj).is_motion
    other = gp.verify(gp.scenes.get("four-bar-redundant", g=9.0).model, traj)
    assert not other.is_motion and other.relative_gap > other.tolerance
