"""The planar chain of N links in maximal coordinates (issue 18's scaling problem): on the manifold at the start,
the chain's sparsity in the constraint graph, energy conserved and pins held after a run, N = 1 the pendulum."""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes.planar_chain import end


def run(scene: gp.scenes.Scene, t_end: float, solver: str = "direct") -> gp.Trajectory:
    return gp.simulate(scene.model, scene.q0, scene.v0, t_end, dt=1e-3, method="rk4", lane="compiled", solver=solver)


@pytest.mark.parametrize("N", [1, 2, 5, 8])
def test_starts_on_the_manifold_at_rest(N: int) -> None:
    scene = gp.scenes.get("planar-chain", N=N)
    assert scene.q0.shape == (3 * N,) and scene.model.n_lam == 0
    q = scene.q0
    np.testing.assert_allclose(np.asarray(end(q, 0, -1, 1.0)).ravel(), 0.0, atol=1e-15)
    for i in range(1, N):  # each link's top on the previous link's bottom
        top, bottom = np.asarray(end(q, i, -1, 1.0)).ravel(), np.asarray(end(q, i - 1, +1, 1.0)).ravel()
        np.testing.assert_allclose(top, bottom, atol=1e-14)
    traj = run(scene, 0.002)
    assert np.abs(traj.g[0]).max() < 1e-14 and np.abs(traj.residual[0]).max() < 1e-14
    assert traj.g.shape[1] == 2 * N


def test_each_pin_row_depends_on_the_two_links_it_joins() -> None:
    N = 6
    J = gp.scenes.get("planar-chain", N=N).model.expressions.J
    sparsity = J.sparsity()
    for row in range(2 * N):
        link = row // 2
        allowed = set(range(3 * max(link - 1, 0), 3 * link + 3))
        used = {c for c in range(3 * N) if sparsity.has_nz(row, c)}
        assert used and used <= allowed, (row, used)


@pytest.mark.parametrize("N", [2, 4, 8])
def test_energy_is_conserved_and_the_pins_hold(N: int) -> None:
    traj = run(gp.scenes.get("planar-chain", N=N), 0.3)
    assert traj.success
    drift = np.abs(traj.energy - traj.energy[0]).max()
    assert drift < 1e-6 * max(1.0, abs(traj.energy[0])), drift
    assert np.abs(traj.g[-1]).max() < 1e-8
    assert np.abs(traj.residual[-1]).max() < 1e-8
    assert np.abs(traj.q[-1] - traj.q[0]).max() > 1e-2  # it moved


def test_qp_and_direct_agree() -> None:
    scene = gp.scenes.get("planar-chain", N=3)
    direct, qp = run(scene, 0.1), run(scene, 0.1, solver="qp")
    np.testing.assert_allclose(qp.q[-1], direct.q[-1], atol=1e-9)
    np.testing.assert_allclose(qp.v[-1], direct.v[-1], atol=1e-8)


def test_one_link_is_the_pendulum() -> None:
    scene = gp.scenes.get("planar-chain", N=1, t_end=0.5)
    assert scene.exact is not None
    traj = run(scene, 0.5)
    q, v = scene.exact(traj.t[-1])
    np.testing.assert_allclose(traj.q[-1], q, atol=1e-9)
    np.testing.assert_allclose(traj.v[-1], v, atol=1e-8)
    # the reference itself: the centre of mass at L/2 from the pin, at the polar angle θ
    q0, _ = scene.exact(0.0)
    np.testing.assert_allclose(q0, scene.q0, atol=1e-14)


def test_bad_size_is_refused() -> None:
    with pytest.raises(gp.InputError, match="N must be a positive integer"):
        gp.scenes.get("planar-chain", N=0)


@pytest.mark.parametrize("N", [1, 2])
def test_ladder_of_four_bars_keeps_its_loops_and_its_energy(N: int) -> None:
    scene = gp.scenes.get("planar-ladder", N=N)
    assert scene.q0.shape == (9 * N,)
    traj = run(scene, 0.3)
    assert traj.success and traj.g.shape[1] == 8 * N
    assert np.abs(traj.g[0]).max() < 1e-14 and np.abs(traj.residual[0]).max() < 1e-14
    assert np.abs(traj.g[-1]).max() < 1e-8 and np.abs(traj.residual[-1]).max() < 1e-8
    assert np.abs(traj.energy - traj.energy[0]).max() < 1e-6 * max(1.0, abs(traj.energy[0]))
    rungs = traj.q[:, 8::9]  # a parallelogram keeps each rung level
    np.testing.assert_allclose(rungs, 0.0, atol=1e-8)
    assert np.abs(traj.q[-1] - traj.q[0]).max() > 1e-2


def test_ladder_refuses_rails_level_with_the_rungs() -> None:
    with pytest.raises(gp.InputError, match="theta0"):
        gp.scenes.get("planar-ladder", theta0=0.0)
