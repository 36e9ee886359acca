"""Front ends (docs/theory.md §1): A and h by autodiff, the Lagrange derivative [N], Euler–Poincaré."""

from __future__ import annotations

import casadi as ca
import numpy as np

import gausspp as gp

from .factories import double_pendulum

M1, M2, L1, L2 = 1.3, 0.7, 0.9, 1.4


def hand_A_h(q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Double pendulum in absolute angles, derived by hand."""
    c, s = np.cos(q[0] - q[1]), np.sin(q[0] - q[1])
    A = np.array([[(M1 + M2) * L1**2, M2 * L1 * L2 * c], [M2 * L1 * L2 * c, M2 * L2**2]])
    h = np.array([M2 * L1 * L2 * s * v[1] ** 2, -M2 * L1 * L2 * s * v[0] ** 2])
    return A, h


def test_double_pendulum_A_and_h(rng: np.random.Generator) -> None:
    mech = double_pendulum(M1, M2, L1, L2)
    fn = ca.Function("Af", [mech.q, mech.v, mech.t], [mech.A, mech.f])
    for _ in range(25):
        q, v = rng.uniform(-np.pi, np.pi, 2), rng.standard_normal(2) * 3
        A, f = (np.array(x) for x in fn(q, v, 0.0))
        A_hand, h_hand = hand_A_h(q, v)
        np.testing.assert_allclose(A, A_hand, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(-f.ravel(), h_hand, rtol=1e-13, atol=1e-14)  # no forces: f = −h


def test_potential_enters_forces_and_energy() -> None:
    g = 9.81
    mech = gp.Lagrangian(n=1, T=lambda q, v, t: 0.5 * v[0] ** 2, V=lambda q, t: g * q[0])
    fn = ca.Function("fE", [mech.q, mech.v, mech.t], [mech.f, mech.energy])
    f, E = fn(2.0, 3.0, 0.0)
    assert float(f) == -g and float(E) == 0.5 * 9 + g * 2


def path(t: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([np.sin(t), np.cos(2 * t)]), np.array([np.cos(t), -2 * np.sin(2 * t)])


def N_affine(q, v, t):  # noqa: ANN001, ANN201 - user-style callable
    return ca.vertcat(ca.sin(q[0]) * q[1] * v[0] + q[0] ** 2 * v[1] + t * q[1], ca.exp(q[1]) * v[1] + v[0] * t**2)


def test_lagrange_derivative_matches_finite_differences_along_a_path() -> None:
    """[N] = d/dt ∂N/∂v − ∂N/∂q, the time derivative taken along a path by central differences."""
    mech = double_pendulum()
    bracket = mech.lagrange_derivative(N_affine)
    N = N_affine(mech.q, mech.v, mech.t)
    parts = ca.Function("parts", [mech.q, mech.v, mech.t], [ca.jacobian(N, mech.v), ca.jacobian(N, mech.q)])
    for t in (0.3, 1.1, 2.7):
        h = 1e-5
        p_plus = np.array(parts(*path(t + h), t + h)[0])
        p_minus = np.array(parts(*path(t - h), t - h)[0])
        dq_N = np.array(parts(*path(t), t)[1])
        fd = (p_plus - p_minus) / (2 * h) - dq_N
        np.testing.assert_allclose(bracket(*path(t), t), fd, rtol=1e-8, atol=1e-9)


def test_rigid_body_bracket_is_euler_poincare(rng: np.random.Generator) -> None:
    """For N = (n, ω): [N] = ω × n — the gyroscopic term of a rotor of fixed axis (paper §4)."""
    body = gp.RigidBody(inertia=np.diag([1.0, 2.0, 3.0]))
    n = rng.standard_normal(3)
    bracket = body.lagrange_derivative(lambda q, w, t: ca.dot(ca.DM(n), w))
    w = rng.standard_normal(3)
    np.testing.assert_allclose(bracket([1, 0, 0, 0], w, 0.0).ravel(), np.cross(w, n), rtol=1e-14)


def test_rigid_body_euler_equations(rng: np.random.Generator) -> None:
    I = np.array([[2.0, 0.1, 0.0], [0.1, 3.0, 0.2], [0.0, 0.2, 4.0]])
    body = gp.RigidBody(inertia=I, torque=lambda R, w, t: [0.1, 0.0, -0.3])
    fn = ca.Function("f", [body.q, body.v, body.t], [body.f, body.qdot])
    w = rng.standard_normal(3)
    f, qdot = fn([1, 0, 0, 0], w, 0.0)
    np.testing.assert_allclose(np.array(f).ravel(), [0.1, 0.0, -0.3] - np.cross(w, I @ w), rtol=1e-14)
    np.testing.assert_allclose(np.array(qdot).ravel(), 0.5 * np.r_[0.0, w], rtol=1e-15)  # q̇ = ½ q ⊗ (0, ω) at q = 1


def test_mass_matrix_front_end_takes_f_as_given() -> None:
    mech = gp.MassMatrix(n=2, A=lambda q, t: [[2.0, 0.0], [0.0, 1.0 + q[0] ** 2]], f=lambda q, v, t: [v[1] ** 2, -q[1]])
    model = gp.Model(mech, gp.Holonomic(lambda q, t: q[0] - q[1], name="equal"))
    data = model.step_data(0.0, [1.0, 1.0], [0.5, 0.5])
    np.testing.assert_allclose(data.A, [[2.0, 0.0], [0.0, 2.0]])
    np.testing.assert_allclose(data.f, [0.25, -1.0])
    res = model.step(0.0, [1.0, 1.0], [0.5, 0.5], solver="direct")
    assert res.a[0] == res.a[1] or abs(res.a[0] - res.a[1]) < 1e-15
    np.testing.assert_allclose(res.a, [(0.25 - 1.0) / 4.0] * 2, rtol=1e-14)
