"""A mechanism with no constraint simulates (issue 30, item 1): the free motion every lesson starts from."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import gausspp as gp

from .factories import kane_pendulum

G = 9.81


def _free_pendulum() -> gp.Model:
    """A pendulum in its angle alone, ``θ̈ = −g sin θ``: no constraint left to keep."""
    return gp.Model(gp.Lagrangian(n=1, T=lambda q, v, t: 0.5 * v[0] ** 2, V=lambda q, t: -G * ca.cos(q[0])), [])


def _reference(t: np.ndarray) -> np.ndarray:
    """``θ(t)`` by scipy alone (DOP853 at 1e-13)."""
    sol = solve_ivp(lambda _t, y: [y[1], -G * np.sin(y[0])], (0, t[-1]), [1.0, 0.0], t_eval=t, rtol=1e-13, atol=1e-13)
    return sol.y[0]


@pytest.mark.parametrize(
    "options",
    [{}, {"method": "rk4", "dt": 1e-3}, {"method": "cvodes"}, {"method": "Radau"}, {"solver": "direct"}],
    ids=["default", "rk4", "cvodes", "Radau", "direct"],
)
def test_a_free_pendulum_simulates_in_every_lane(options: dict) -> None:
    """Every lane runs the free model (the QP with no row is the free acceleration); the angle is the reference's
    (measured ≤ 1e-9 rad at the defaults) and the energy is kept."""
    model = _free_pendulum()
    assert model.k == 0 and "none (free)" in repr(model)
    traj = gp.simulate(model, [1.0], [0.0], 2.0, **options)
    assert traj.success
    assert np.abs(traj.q[:, 0] - _reference(traj.t)).max() < 1e-6
    assert np.abs(traj.energy_balance()).max() < 1e-6 * G
    wrong = _reference(traj.t * 1.001)  # negative control: a motion a little off the reference's clock
    assert np.abs(traj.q[:, 0] - wrong).max() > 1e-5


def test_the_free_step_is_the_free_acceleration() -> None:
    model = _free_pendulum()
    for solver in ("qp", "direct"):
        np.testing.assert_allclose(model.step(0.0, [1.0], [0.0], solver=solver).a, [-G * np.sin(1.0)], rtol=1e-14)
    traj = gp.simulate(model, [1.0], [0.0], 1.0, record=np.linspace(0.0, 1.0, 201))
    assert gp.verify(model, traj).is_motion  # (23) with no constraint: Newton's law on the nodes
    slower = gp.simulate(model, [1.0], [0.0], 1.0, record=np.linspace(0.0, 1.0, 201))
    slower = type(slower)(**{**vars(slower), "t": slower.t * 1.01, "v": slower.v / 1.01})
    assert not gp.verify(model, slower).is_motion  # negative control: the same path 1 % slower


def test_a_sympy_system_without_constraints_is_a_model() -> None:
    """from_sympy of an unconstrained pendulum (Kane) gives a Model that simulates, no longer None."""
    pytest.importorskip("sympy.physics.mechanics")
    out = kane_pendulum(G)
    assert isinstance(out.model, gp.Model) and out.model.k == 0
    traj = gp.simulate(out.model, [1.0], [0.0], 2.0)  # θ from the downward x axis: θ̈ = −g sin θ
    assert traj.success and np.abs(traj.q[:, 0] - _reference(traj.t)).max() < 1e-6
