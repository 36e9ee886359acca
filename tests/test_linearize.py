"""``gp.linearize`` (issue 30, item 3): the linear dynamics about a state on the constraints, by exact derivatives.

References: closed forms (the pendulum's ``ω² = m g L/(I_c + m L²)``, the free pendulum's ``ω² = g``) and central
differences of ``model.step``.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp

G = 9.81


def _pendulum_state(phi: float) -> np.ndarray:
    return np.array([np.cos(phi), np.sin(phi), phi])  # the scene's defaults: L = 1, the pin at the origin


@pytest.mark.parametrize("independent", [None, ["q3", "q3′"], [2, 5]])
def test_the_pinned_body_hanging_oscillates_and_standing_falls(independent) -> None:
    """The scene `pendulum` (three coordinates, two pin rows): hanging, ±iω with ω² = m g L/(I_c + m L²) (measured
    to 1e-15); standing on its pin, ±ω — an instability. Chosen automatically or named, the same."""
    model = gp.scenes.get("pendulum").model
    omega = np.sqrt(1.0 * G * 1.0 / (0.01 + 1.0))
    down = gp.linearize(model, 0.0, _pendulum_state(-np.pi / 2), np.zeros(3), independent=independent)
    assert down.A.shape == (2, 2) and down.drift < 1e-12  # an equilibrium
    np.testing.assert_allclose(down.eigenvalues, [-1j * omega, 1j * omega], atol=1e-12)
    up = gp.linearize(model, 0.0, _pendulum_state(np.pi / 2), np.zeros(3), independent=independent)
    np.testing.assert_allclose(up.eigenvalues, [-omega, omega], atol=1e-12)
    assert not np.allclose(up.eigenvalues, down.eigenvalues)  # negative control: the two equilibria told apart
    # the basis spans the constraints' tangent space: the pin's rows hold for every δy = T z
    assert np.abs(down.basis[:3, 0] - [1.0, 0.0, 1.0]).max() < 1e-12  # δφ moves the centre along x at φ = −π/2


def test_the_free_pendulum() -> None:
    """No constraint: every component is independent, ±i√g."""
    free = gp.Model(gp.Lagrangian(n=1, T=lambda q, v, t: 0.5 * v[0] ** 2, V=lambda q, t: -G * ca.cos(q[0])), [])
    lin = gp.linearize(free, 0.0, [0.0], [0.0])
    assert lin.names == ("q1", "q1′")
    np.testing.assert_allclose(lin.eigenvalues, [-1j * np.sqrt(G), 1j * np.sqrt(G)], atol=1e-12)


@pytest.mark.parametrize("name", ["crane", "gyrostat", "andrews"])
def test_the_derivatives_are_model_steps_central_differences(name: str) -> None:
    """∂F/∂y against central differences of ``model.step``'s acceleration at random states near the scene's start
    (off the constraint too), in random directions: agreement to 1e-6 of the step's scale (measured ≤ 4.4e-10)."""
    scene = gp.scenes.get(name)
    model = scene.model
    nq, nv = model.nq, model.nv
    rng = np.random.default_rng(30)
    lam0 = np.zeros(model.n_lam) if scene.lam0 is None else np.asarray(scene.lam0, float)
    for _ in range(3):
        q = scene.q0 + 1e-3 * rng.standard_normal(nq)
        v = scene.v0 + 1e-3 * rng.standard_normal(nv)
        lin = gp.linearize(model, 0.3, q, v, lam0)
        direction = rng.standard_normal(nq + nv)
        h = 1e-6 * (1 + np.abs(np.concatenate([q, v])).max())

        def accel(y: np.ndarray) -> np.ndarray:
            return model.step(0.3, y[:nq], y[nq:], lam0, solver="direct").a

        y = np.concatenate([q, v])
        central = (accel(y + h * direction) - accel(y - h * direction)) / (2 * h)
        exact = lin.jacobian[nq : nq + nv, : nq + nv] @ direction
        scale = np.abs(exact).max() + np.abs(model.step(0.3, q, v, lam0, solver="direct").a).max()
        assert np.abs(central - exact).max() <= 1e-6 * scale
        assert np.abs(central - 1.01 * exact).max() > 1e-6 * scale  # negative control: 1 % off is seen


def test_bad_choices_are_refused() -> None:
    model = gp.scenes.get("pendulum").model
    state = (0.0, _pendulum_state(-np.pi / 2), np.zeros(3))
    with pytest.raises(gp.InputError, match="no component"):
        gp.linearize(model, *state, independent=["theta"])
    with pytest.raises(gp.InputError, match="do not fix"):
        gp.linearize(model, *state, independent=["q1", "q3", "q1′"])  # 3 named, 4 rows on the other 3: no
    with pytest.raises(gp.InputError, match="contacts"):
        block = gp.scenes.get("block-on-floor")
        gp.linearize(block.model, 0.0, block.q0, block.v0)


def test_a_state_where_the_step_is_not_defined_is_a_project_error() -> None:
    """No silent number where the step has none: redundant rows (the direct step refuses them), a servo at the
    state where its margin vanishes (the crane's rope vertical: the derivative would be finite but ~1e8), a mass
    matrix that is not positive definite, a NaN."""
    redundant = gp.scenes.get("four-bar-redundant")
    with pytest.raises(gp.RealizabilityError, match="linearize: the step has no derivative"):
        gp.linearize(redundant.model, 0.0, redundant.q0, redundant.v0)
    crane = gp.scenes.get("crane", theta0=0.0)
    with pytest.raises(gp.RealizabilityError, match="linearize: .*not realizable"):
        gp.linearize(crane.model, 0.0, crane.q0, crane.v0)
    indefinite = gp.Model(
        gp.MassMatrix(n=2, A=lambda q, t: ca.diag(ca.vertcat(1.0, -1.0)), f=lambda q, v, t: ca.vertcat(0, -G)),
        [gp.Holonomic(lambda q, t: q[0] - q[1], name="tie")],
    )
    with pytest.raises(gp.GaussppError, match="linearize: the step has no derivative"):
        gp.linearize(indefinite, 0.0, [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(gp.NonFiniteError):
        gp.linearize(gp.scenes.get("pendulum").model, 0.0, [np.nan, 0.0, 0.0], np.zeros(3))
