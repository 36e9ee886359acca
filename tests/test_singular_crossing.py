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
    """10 s at the defaults (DOP853, rtol = atol = 1e-10): ten collinear positions, each stepped over where the
    reference puts it, the motion on the parallelogram branch throughout: the error is the tolerance's (measured
    1.5e-7 m in 200 steps (A02), 9.1e-8 m (double); 6e-10 m at rtol 1e-11 — the bridges' share ≤ 2e-8). What the
    bridge's accuracy rests on is that the reference's instant falls in the gap of DOP853's nodes (1/3 … 3/5 of
    the bridge) that the estimate aims at (0.466): measured 0.42–0.47 in both linkages, each estimate within
    3.3e-3 s of the reference; the folded branch is metres away after the first."""
    scene = gp.scenes.get("parallelogram", third_bar=third_bar)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no realizability warning: ideal rows losing rank are no lost realization
        traj = gp.simulate(scene.model, scene.q0, scene.v0, 10.0)
    assert traj.success and traj.t[-1] == 10.0
    expected = P.collinear_times(**scene.params)
    bridged = [e for e in traj.events if e["kind"] == "singular position"]
    assert len(bridged) == expected.size == 10 and all("correction" in e for e in bridged)
    where = np.array([(x - e["from"]) / (e["to"] - e["from"]) for e, x in zip(bridged, expected, strict=True)])
    assert np.all((1 / 3 < where) & (where < 3 / 5)), where  # no stage of the bridge near the singular instant
    err, off = _against_reference(scene, traj)
    assert err.max() < 1e-6
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
    amplify by ~1/σ: the bridge projects first, so its final correction is the step's own error, far inside the
    tolerance. Measured at rtol = atol = 1e-6 (76 steps in 10 s): corrections ≤ 1.9e-9 m; without the first
    projection 1e-4 m and more (the mutation check). The run's own long steps go over the other five positions,
    each noted by the change of sign of σ_r (:func:`~gausspp.simulation.crossing.sign_changed`)."""
    scene = gp.scenes.get("parallelogram")
    rtol = 1e-6
    traj = gp.simulate(  # as promised; the raw run (no default drift control): the bridge's own projection is tested
        scene.model, scene.q0, scene.v0, 10.0, rtol=rtol, atol=rtol, constraint_tol=rtol, stabilize=False
    )
    corrections = [e["correction"] for e in traj.events if "correction" in e]
    assert traj.success and len(traj.events) == 10
    assert len(corrections) >= 5  # bridged (measured 5)
    assert max(corrections) <= 1e-2 * rtol


def test_the_sign_of_sigma_is_told_through_the_svds_freedom() -> None:
    """``σ_r`` of ``M(t) = [[1, 0, 0], [0, t, 0]]`` passes through zero at ``t = 0``; ``[[1, 0, 0], [0, 0.1 + t², 0]]``
    dips to 0.1 and rises. Each state's pair is taken with random signs, as an SVD may return it: the first pair of
    states straddling 0 changes sign whatever the signs; the dip never does; vectors turned by 90° cannot tell."""
    rng = np.random.default_rng(0)

    def pair(sigma: float, turn: float = 0.0) -> tuple[float, np.ndarray, np.ndarray]:
        s = rng.choice([-1.0, 1.0])  # the SVD's freedom: u and v flipped together
        u = np.array([np.sin(turn), np.cos(turn)])
        v = np.array([0.0, 1.0, 0.0])
        return abs(sigma), s * np.sign(sigma or 1.0) * u, s * v

    for _ in range(20):
        assert crossing.sign_changed(pair(0.3), pair(-0.2)) is True  # through zero
        assert crossing.sign_changed(pair(0.3), pair(0.2)) is False  # a dip: both positive
        assert crossing.sign_changed(pair(0.3), pair(-0.2, turn=np.pi / 2)) is None


@pytest.mark.parametrize("rtol", [1e-9, 1e-6])
def test_a_dip_of_the_margin_is_no_singular_position(rtol: float) -> None:
    """The pendulum's pin: ``σ_r`` dips to 0.14 twice a swing, never to zero — no event at any tolerance (a
    parabola through three samples of ``σ_r²`` saw three at rtol = 1e-6, the negative control)."""
    scene = gp.scenes.get("pendulum")
    # 10 s unstabilized: the pin drifts ~2·rtol (measured 1.9e-9, 2e-6)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 10.0, rtol=rtol, atol=rtol, constraint_tol=10 * rtol)
    assert traj.success and traj.events == ()
    history = [(t, float(crossing.smallest_kept(scene.model, t, np.r_[q, v, 0, 0])[0]))
               for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)]  # fmt: skip
    sigma = np.array([s for _, s in history])
    minima = [i for i in range(1, sigma.size - 1) if sigma[i] < sigma[i - 1] and sigma[i] < sigma[i + 1]]
    assert len(minima) >= 4 and sigma[minima].min() > 0.1  # dips there are, and they stay above zero
    parabola_says = 0
    for i in minima:
        (t0, s0), (t1, s1), (t2, s2) = history[i - 1 : i + 2]
        a, b, c = crossing._parabola(t0 - t1, t2 - t1, s0**2, s1**2, s2**2)
        parabola_says += bool(s1 < 0.2 and a > 0 and c - b * b / (4 * a) < (0.05 * max(s0, s2)) ** 2)
    if rtol == 1e-6:
        assert parabola_says >= 1
