"""docs/theory.md §2 table: each realization's reaction form, λ as state only where needed."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp

I = np.diag([1.0, 2.0, 3.0])
L = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)


def gyrostat(realization: gp.Realization) -> gp.Model:
    return gp.Model(
        gp.RigidBody(inertia=I), gp.Constraint(lambda q, w, t: ca.dot(w, ca.DM(L)), name="l", realization=realization)
    )


def on_constraint(w: np.ndarray) -> np.ndarray:
    return w - (w @ L) * L


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_flywheel_reaction_and_euler_equations(solver: str, rng: np.random.Generator) -> None:
    """Inertial N = (n, ω): R = −λ̇ n − λ ω × n, and I ω̇ + ω × Iω = R (eqs. (14)–(15))."""
    n = np.array([0.3, 0.9, 0.4])
    model = gyrostat(gp.Inertial(N=lambda q, w, t: ca.dot(ca.DM(n), w), lam0=0.7))
    assert model.n_lam == 1
    w, lam = on_constraint(rng.standard_normal(3)), 0.7
    res = model.step(0.0, [1, 0, 0, 0], w, solver=solver)  # λ from lam0
    lam_dot = res.u[0]
    np.testing.assert_allclose(res.reaction, -lam_dot * n - lam * np.cross(w, n), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(I @ res.a + np.cross(w, I @ w), res.reaction, rtol=1e-12, atol=1e-14)
    assert abs(res.a @ L) < 1e-14


def test_flywheel_on_l_is_vakonomic(rng: np.random.Generator) -> None:
    """With n = l the flywheel realizes the vakonomic model (17)–(18)."""
    fly = gyrostat(gp.Inertial(N=lambda q, w, t: ca.dot(ca.DM(L), w)))
    vako = gyrostat(gp.Vakonomic())
    for _ in range(5):
        w, lam = on_constraint(rng.standard_normal(3)), rng.standard_normal(1)
        a, b = fly.step(0.0, [1, 0, 0, 0], w, lam), vako.step(0.0, [1, 0, 0, 0], w, lam)
        np.testing.assert_allclose(a.a, b.a, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(a.u, b.u, rtol=1e-14, atol=1e-15)


def two_masses_mixed(law: str) -> gp.Model:
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * v[0] ** 2 + 1.5 * v[1] ** 2, F=lambda q, v, t: [0.0, 2.0])
    real = gp.Mixed(N=lambda q, v, t: q[0] * v[1], M=lambda q, v, t: [1.0, 0.5], law=law, lam0=0.4)
    return gp.Model(body, gp.Constraint(lambda q, v, t: v[1] - v[0], name="rod", realization=real))


@pytest.mark.parametrize("law", ["proportional", "rate"])
@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_mixed_reactions(law: str, solver: str) -> None:
    """N = q₀v₁: N_v = (0, q₀), [N] = (−v₁, v₀); (19): R = −λ̇N_v − λ[N] + λM, (22): … + λ̇M."""
    model = two_masses_mixed(law)
    q, v, lam = np.array([0.8, 0.1]), np.array([0.3, 0.3]), 0.4
    res = model.step(0.0, q, v, solver=solver)
    lam_dot = res.u[0]
    Nv, bracket, M = np.array([0.0, q[0]]), np.array([-v[1], v[0]]), np.array([1.0, 0.5])
    force = lam * M if law == "proportional" else lam_dot * M
    np.testing.assert_allclose(res.reaction, -lam_dot * Nv - lam * bracket + force, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(np.diag([1.0, 3.0]) @ res.a - [0.0, 2.0], res.reaction, rtol=1e-13, atol=1e-15)
    assert abs(res.a[1] - res.a[0]) < 1e-14


def test_state_only_where_needed() -> None:
    """No λ state, no [N] for ideal and force realizations."""
    calls = []

    class Spy(gp.Lagrangian):
        def lagrange_rows(self, N):  # noqa: ANN001, ANN201
            calls.append(N)
            return super().lagrange_rows(N)

    def body() -> Spy:
        return Spy(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v))

    for real in (gp.Ideal(), gp.Force(M=lambda q, v, t: [1, 0])):
        model = gp.Model(body(), gp.Constraint(lambda q, v, t: v[1] - v[0], realization=real))
        assert model.n_lam == 0 and model.kernel("direct").inputs[3].size == 0
    assert calls == []
    gp.Model(body(), gp.Constraint(lambda q, v, t: v[1] - v[0], realization=gp.Inertial(N=lambda q, v, t: v[0])))
    assert len(calls) == 1


def test_several_constraints_stack_rows_and_columns() -> None:
    body = gp.Lagrangian(
        n=3, T=lambda q, v, t: 0.5 * (v[0] ** 2 + 2 * v[1] ** 2 + 3 * v[2] ** 2), F=lambda q, v, t: [1, 0, 0]
    )
    rod = gp.Constraint(lambda q, v, t: v[1] - v[0], name="rod")
    servo = gp.Constraint(lambda q, v, t: v[2] - v[1], name="servo", realization=gp.Force(M=lambda q, v, t: [0, 0, 1]))
    model = gp.Model(body, [rod, servo])
    assert (model.k, model.m, model.row_names) == (2, 2, ["rod", "servo"])
    res = model.step(0.0, np.zeros(3), np.zeros(3), solver="direct")
    # all move together; the servo pushes m3 only, the rod carries the rest: (1 + 2) a = 1 − 0, m3 a = servo force
    np.testing.assert_allclose(res.a, [1 / 3] * 3, rtol=1e-14)
    np.testing.assert_allclose(res.reaction[2], 3 * (1 / 3), rtol=1e-14)
    np.testing.assert_allclose(model.step(0.0, np.zeros(3), np.zeros(3)).a, res.a, rtol=1e-12)
