"""Singular positions of linkages crossed on the motion's branch (:mod:`gausspp.simulation.crossing`).

The reference is the one-degree-of-freedom crank equation of :mod:`gausspp.scenes.parallelogram` (solved by
scipy at 1e-13, no gausspp code), its collinear instants found by scipy's event location; the other assembly
branch (crank 2 folded back, ``θ₂ = −θ``) is the wrong answer each check must tell apart.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes import parallelogram as P
from gausspp.simulation import crossing
from gausspp.simulation.drift import as_stabilization
from gausspp.simulation.initial import projection
from gausspp.simulation.rhs import RightHandSide


def _against_reference(scene: gp.scenes.Scene, traj: gp.Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample position error against the reference, and against the folded branch (the wrong answer)."""
    p = scene.params
    theta, omega = P.one_dof_reference(traj.t, **p)
    pairs = zip(theta, omega, strict=True)
    ref = np.array([P.maximal_state(a, b, 0.0, p["cells"], p["third_bar"])[0] for a, b in pairs])
    folded = ref.copy()
    crank2 = 3 * P.bars(p["cells"], p["third_bar"]).index(("crank", 1))
    folded[:, crank2 + 2] = -ref[:, crank2 + 2]  # the second crank's angle mirrored: the anti-parallelogram
    return np.abs(traj.q - ref).max(axis=1), np.abs(traj.q - folded).max(axis=1)


@pytest.mark.parametrize("third_bar", [False, True], ids=["A02", "double"])
def test_the_default_run_passes_every_collinear_position_on_its_branch(third_bar: bool) -> None:
    """10 s at the defaults (DOP853, rtol 1e-9): ten collinear positions, each stepped over where the reference
    puts it, the motion on the parallelogram branch throughout. Measured: error ≤ 7e-11 m, each instant within
    2e-4 s of the reference's; the folded branch is metres away after the first."""
    scene = gp.scenes.get("parallelogram", third_bar=third_bar)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no realizability warning: ideal rows losing rank are no lost realization
        traj = gp.simulate(scene.model, scene.q0, scene.v0, 10.0)
    assert traj.success and traj.t[-1] == 10.0
    expected = P.collinear_times(**scene.params)
    crossed = np.array([e["t"] for e in traj.events if e["kind"] == "singular position"])
    assert crossed.size == expected.size == 10
    assert np.abs(crossed - expected).max() < 2e-3  # the half-gap between collinear positions is > 0.25 s
    err, off = _against_reference(scene, traj)
    assert err.max() < 1e-7
    after = traj.t > expected[0] + 0.1
    assert off[after].max() > 0.1  # negative control: the check tells the other branch apart


@pytest.mark.parametrize("third_bar", [False, True], ids=["A02", "double"])
def test_at_tight_tolerances_the_run_matches_the_one_dof_reference(third_bar: bool) -> None:
    """Acceptance of issue 27: rtol = atol = 1e-12, 10 s, ≤ 1e-8 m against the reference and energy drift
    ≤ 1e-9 relative. Measured 1.1e-11 m (A02), 5.6e-12 m (double); energy 2.8e-13 and 3.3e-13."""
    scene = gp.scenes.get("parallelogram", third_bar=third_bar)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 10.0, rtol=1e-12, atol=1e-12)
    assert traj.success and len(traj.events) == 10
    err, off = _against_reference(scene, traj)
    assert err.max() < 1e-8
    energy = traj.energy
    assert np.abs(energy - energy[0]).max() < 1e-9 * np.abs(energy).max()
    assert off[traj.t > 1.0].max() > 0.1  # negative control, as above


def test_record_times_inside_a_bridge_are_on_the_reference() -> None:
    """Samples asked for inside the step over a singular position come from that step's dense output."""
    scene = gp.scenes.get("parallelogram")
    grid = np.linspace(0.0, 1.3, 1301)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.3, record=grid, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(traj.t, grid)
    inside = np.zeros(grid.size, bool)
    for event in traj.events:
        inside |= (grid > event["from"]) & (grid < event["to"])
    assert inside.sum() >= 10  # the grid has samples inside each bridge
    err, _ = _against_reference(scene, traj)
    assert err[inside].max() < 1e-8


def test_a_bridge_that_would_leave_the_branch_is_refused() -> None:
    """Negative control of the bridge's own check: a projection that lands on the folded branch (a jump of the
    size the branches part by) ends the crossing with an IntegrationError, never a success."""
    scene = gp.scenes.get("parallelogram")
    model, t_star = scene.model, P.collinear_times(**scene.params)[0]
    t_a = t_star - crossing.FRACTION * 0.02
    theta, omega = P.one_dof_reference(t_a, **scene.params)
    q, v, _ = P.maximal_state(theta, omega)
    y = np.concatenate([q, v, np.zeros(model.n_lam), [0.0, 0.0]])
    rhs = RightHandSide(model, "qp", None, as_stabilization(None, None))
    honest = projection(model)
    good = crossing.bridge(rhs, model, honest, t_a, y, t_star, 10.0)
    theta_b, omega_b = P.one_dof_reference(good.t, **scene.params)
    np.testing.assert_allclose(good.y[: model.nq], P.maximal_state(theta_b, omega_b)[0], rtol=0, atol=1e-12)

    def onto_the_other_branch(t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> tuple:
        q = q.copy()
        if t > t_star:
            q[8] = -q[8]  # crank 2 folded back
        return q, v

    with pytest.raises(gp.IntegrationError, match="may have left its branch"):
        crossing.bridge(rhs, model, onto_the_other_branch, t_a, y, t_star, 10.0)


def test_a_realization_that_is_not_ideal_is_not_crossed() -> None:
    """The crane's rope kept by a servo force loses its margin through the vertical rope: that is a realization
    failing, not a linkage's singular position — the watch does not apply and the run stops there."""
    crane = gp.scenes.get("crane", theta0=-0.3, accel=0.0, distance=0.0)
    assert not crossing.applies(crane.model)
    assert crossing.applies(gp.scenes.get("parallelogram").model)
    with pytest.warns(gp.RealizabilityWarning):
        traj = gp.simulate(crane.model, crane.q0, crane.v0, 0.2, throw=False)
    assert traj.status == "failed" and not traj.events


@pytest.mark.parametrize("name", ["andrews", "pendulum", "four-bar-redundant"])
def test_the_watch_stays_out_of_motions_without_singular_positions(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Andrews' mechanism, the pendulum, the redundant four-bar: the watch applies, finds no singular position,
    and the trajectory is the very one of a run without it (it only looks)."""
    scene = gp.scenes.get(name)
    assert crossing.applies(scene.model)
    gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end)  # the general step compiles its pattern on a first run
    watched = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end)
    assert watched.success and watched.events == ()
    monkeypatch.setattr(crossing, "applies", lambda model: False)
    plain = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end)
    np.testing.assert_array_equal(watched.t, plain.t)
    np.testing.assert_array_equal(watched.q, plain.q)


def test_the_bridge_starts_on_the_constraints() -> None:
    """At loose tolerances an accepted state carries drift, which the step over a singular position would
    amplify by ~1/σ: the bridge projects first, so its final correction is the step's own error. Measured at
    rtol = atol = 1e-6: corrections ≤ 2.9e-11 m; without the first projection 4.9e-4 m (the mutation check)."""
    scene = gp.scenes.get("parallelogram")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 10.0, rtol=1e-6, atol=1e-6)
    corrections = [e["correction"] for e in traj.events if "correction" in e]
    assert traj.success and len(traj.events) == 10
    assert len(corrections) >= 5  # bridged (measured 9: one long step of the run went over its position itself)
    assert max(corrections) <= 1e-9
