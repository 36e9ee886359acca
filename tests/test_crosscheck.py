"""The independent cross-check: the acceleration-space QP against the model's raw answers.

The reference (:func:`gausspp.acceleration_qp`) is assembled from ``A, a₀, J, φ, D`` alone and solved by
a qpsolvers backend; the model's routes (direct formula, compiled QP) go through casadi's reduction to
reaction space. They share nothing but the data.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
import gausspp.step.equality.kernel as kernel_module

STATES_PER_MODEL = 300
MIN_MARGIN = 1e-3  # states with a smaller realizability margin are drawn again (the answers lose 1/margin)


def _random_model(n: int, k: int, m: int, seed: int) -> gp.Model:
    """``MassMatrix`` with ``A(q) = BᵀB + I`` (``B`` of sines of ``q``), forces quadratic in ``v``, and one
    constraint of ``k`` velocity rows ``C(q) v = c(t)`` realized ideally (``m = k``, ``None``) or by a force
    with ``m`` directions ``M(q)`` (``m ≥ k``: over-actuated when larger)."""
    rng = np.random.default_rng(seed)
    B0, B1 = rng.standard_normal((n, n)), rng.standard_normal((n, n))
    F0, F1 = rng.standard_normal(n), rng.standard_normal((n, n))
    C0, C1 = rng.standard_normal((k, n)), rng.standard_normal((k, n))
    M0, M1 = rng.standard_normal((m, n)), rng.standard_normal((m, n))
    c0 = rng.standard_normal(k)

    def A(q, t):
        B = ca.DM(B0) + ca.DM(B1) * ca.repmat(ca.sin(q).T, n, 1)
        return B.T @ B + ca.DM.eye(n)

    def f(q, v, t):
        return ca.DM(F0) * ca.cos(q[0]) + ca.DM(F1) @ (v * v) - 0.3 * v

    def C(q):
        return ca.DM(C0) + ca.DM(C1) * ca.repmat(ca.cos(q).T, k, 1)

    def Phi(q, v, t):
        return C(q) @ v - ca.DM(c0) * ca.sin(t)

    if m == k and seed % 2 == 0:
        realization = gp.Ideal()
    else:
        realization = gp.Force(M=lambda q, v, t: ca.DM(M0) + ca.DM(M1) * ca.repmat(ca.sin(q).T, m, 1))
    return gp.Model(gp.MassMatrix(n=n, A=A, f=f), [gp.Constraint(Phi, name="servo", realization=realization)])


SHAPES = [(3, 2, 2, 0), (4, 2, 2, 1), (3, 1, 2, 3), (5, 2, 4, 5)]  # (n, k, m, seed): square and over-actuated


@pytest.mark.parametrize("n, k, m, seed", SHAPES)
def test_acceleration_qp_agrees_with_the_raw_answers_on_random_systems(n: int, k: int, m: int, seed: int) -> None:
    """4 models × 300 states = 1200 systems with state-dependent ``A``. Measured: largest raw distance 7.1e-13
    (direct and compiled QP), reference KKT residuals below 1e-14."""
    model = _random_model(n, k, m, seed)
    rng = np.random.default_rng(100 + seed)
    checked, worst = 0, 0.0
    while checked < STATES_PER_MODEL:
        t, q, v = float(rng.uniform(0, 3)), rng.standard_normal(n), rng.standard_normal(n)
        if model.step(t, q, v, solver="qp", refine=False).margin < MIN_MARGIN:
            continue
        check = gp.crosscheck(model, t, q, v)
        assert set(check.answers) == ({"direct", "qp:default"} if m == k else {"qp:default"})
        assert check.ok, str(check)
        worst = max(worst, *check.distances.values())
        checked += 1
    assert worst <= 1e-10  # measured ≤ 7.1e-13 (n = 5, m = 4): a hundred times that, not the cross-check's 1e-9
    print(f"{n=} {k=} {m=}: largest raw distance {worst:.1e}")


def test_the_reference_is_the_paper_servo_motion() -> None:
    """Two masses, follower force on mass 1 (DESIGN §6.1): both accelerate at F/m₂ — from the data alone."""
    A, F = np.diag([1.0, 3.0]), np.array([0.0, 2.0])
    ref = gp.acceleration_qp(A, np.linalg.solve(A, F), np.array([[-1.0, 1.0]]), np.zeros(1), np.array([[1.0], [0.0]]))
    np.testing.assert_allclose(ref.a, [2.0 / 3.0, 2.0 / 3.0], rtol=1e-12)
    ideal = gp.acceleration_qp(
        A, np.linalg.solve(A, F), np.array([[-1.0, 1.0]]), np.zeros(1), np.array([[-1.0], [1.0]])
    )
    np.testing.assert_allclose(ideal.a, [0.5, 0.5], rtol=1e-12)


def test_a_wrong_direct_formula_is_caught(monkeypatch: pytest.MonkeyPatch) -> None:
    """A test double of the direct formula that solves with Ŝᵀ instead of Ŝ (a transposition slip): the
    cross-check reports it (Ŝ is not symmetric for a force realization); the true formula passes."""
    n, k, m, seed = SHAPES[1]
    rng = np.random.default_rng(7)
    t, q, v = 0.4, rng.standard_normal(n), rng.standard_normal(n)
    assert gp.crosscheck(_random_model(n, k, m, seed), t, q, v).ok

    monkeypatch.setattr(kernel_module, "direct_reaction", lambda red: ca.solve(red.S_hat.T, red.rhs_hat))
    monkeypatch.setenv("GAUSSPP_CACHE_DIR", "off")  # not the right formula from the disk cache: compile the double
    wrong = gp.crosscheck(_random_model(n, k, m, seed), t, q, v)  # a fresh model compiles the wrong formula
    assert not wrong.ok
    assert wrong.distances["direct"] > 1e-3 and wrong.distances["qp:default"] <= 1e-9


def test_a_wrong_realization_is_caught() -> None:
    """Another double: the servo's data solved as if the constraint were ideal (D = Jᵀ) — the acceleration
    differs from the reference by O(1)."""
    model = _random_model(3, 1, 1, 1)
    q, v = np.array([0.3, -0.2, 0.5]), np.array([0.1, 0.4, -0.3])
    d = model.step_data(0.2, q, v)
    a0 = np.linalg.solve(d.A, d.f + d.r0)
    ref = gp.acceleration_qp(d.A, a0, d.J, d.phi, d.D)
    ideal = gp.acceleration_qp(d.A, a0, d.J, d.phi, d.J.T)
    assert np.linalg.norm(ideal.a - ref.a) > 1e-3 * np.linalg.norm(ref.a)


def test_crosscheck_refuses_bad_input() -> None:
    scene = gp.scenes.get("block-on-floor")
    with pytest.raises(gp.InputError, match="contacts or bounded"):
        gp.crosscheck(scene.model, 0.0, scene.q0, scene.v0)
    with pytest.raises(gp.NotPositiveDefiniteError):
        gp.acceleration_qp(np.diag([1.0, -1.0]), np.zeros(2), np.eye(1, 2), np.zeros(1), np.eye(2, 1))
    with pytest.raises(gp.InputError, match="shapes"):
        gp.acceleration_qp(np.eye(2), np.zeros(3), np.eye(1, 2), np.zeros(1), np.eye(2, 1))
    with pytest.raises(gp.UnknownNameError, match=r"'nosuchsolver' is unknown; valid names here: \["):
        gp.acceleration_qp(np.eye(2), np.zeros(2), np.eye(1, 2), np.zeros(1), np.eye(2, 1), backend="nosuchsolver")


def test_the_reference_backend_is_chosen_by_registry_name() -> None:
    """The reference's backend is a registry name (default: the first installed of REFERENCE_DEFAULTS), and any
    backend of the registry that solves the general form gives the same reference."""
    args = (
        np.diag([1.0, 2.0]),
        np.array([0.5, -1.0]),
        np.array([[1.0, 1.0]]),
        np.array([0.3]),
        np.array([[1.0], [0.0]]),
    )
    default = gp.acceleration_qp(*args)
    chosen = gp.qp.default("reference")
    assert chosen in gp.qp.REFERENCE_DEFAULTS and default.backend == gp.qp.short_name(gp.qp.get(chosen))
    for name in ("casadi:qrqp", "qpsolvers:osqp"):
        other = gp.acceleration_qp(*args, backend=name)
        assert other.backend == gp.qp.short_name(gp.qp.get(name))
        assert np.allclose(other.a, default.a, rtol=0, atol=1e-10) and other.dual <= 1e-9 and other.primal <= 1e-9


def test_crosscheck_names_non_finite_data_and_an_unrealizable_state() -> None:
    with pytest.raises(gp.NonFiniteError, match="a0 contains NaN"):
        gp.acceleration_qp(np.eye(2), np.array([0.0, np.nan]), np.eye(1, 2), np.zeros(1), np.eye(2, 1))
    crane = gp.scenes.get("crane")
    q = np.array(crane.q0, float)
    q[1] = 0.0  # rope vertical: the trolley force cannot move the payload horizontally (margin 0)
    with pytest.raises(gp.RealizabilityError, match="not realizable"):
        gp.crosscheck(crane.model, 0.0, q, np.zeros_like(q))
    with pytest.raises(gp.NonFiniteError):
        gp.crosscheck(crane.model, 0.0, np.full_like(q, np.nan), np.zeros_like(q))
