"""docs/theory.md §6.2: rigid body with a servo torque; realizability is (I⁻¹n, l) ≠ 0, not n ⟂̸ l."""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp

INERTIA = (1.0, 2.0, 3.0)
L_NONPRINCIPAL = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)


def scene(n: object, l: object = L_NONPRINCIPAL) -> gp.scenes.Scene:
    return gp.scenes.get("rigid-body-servo", inertia=INERTIA, l=l, n=n)


def test_n_perpendicular_to_l_is_realizable_for_non_principal_l() -> None:
    n = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
    assert abs(n @ L_NONPRINCIPAL) < 1e-15  # the paper's "orthogonal" would call this unrealizable
    assert abs((n / INERTIA) @ L_NONPRINCIPAL) > 0.1  # but (I⁻¹n, l) ≠ 0
    s = scene(n)
    for solver in ("direct", "qp"):
        res = s.model.step(0.0, s.q0, s.v0, solver=solver)
        assert res.margin > 0.1
        # the constraint (ω, l) = 0 is kept: (ω̇, l) = 0
        assert abs(res.a @ L_NONPRINCIPAL) < 1e-14
        # Euler with the servo torque λn: I ω̇ + ω × Iω = λ n
        Iw = np.array(INERTIA) * s.v0
        np.testing.assert_allclose(np.array(INERTIA) * res.a + np.cross(s.v0, Iw), res.u[0] * n, atol=1e-14)


def test_I_inverse_n_perpendicular_to_l_raises_with_time_and_constraint() -> None:
    n = np.array(INERTIA) * np.array([1.0, -1.0, 0.0])  # I⁻¹n = (1, −1, 0) ⟂ l although n is not ⟂ l
    assert abs(n @ L_NONPRINCIPAL) > 0.1
    s = scene(n)
    for solver in ("direct", "qp"):
        with pytest.raises(gp.RealizabilityError) as info:
            s.model.step(0.25, s.q0, s.v0, solver=solver)
        err = info.value
        assert err.t == 0.25 and err.constraint == "(ω, l) = 0" and err.margin < 1e-12
        assert "t=0.25" in str(err) and "(ω, l) = 0" in str(err) and "(12)" in str(err)


def test_suslov_reaction_does_no_work(rng: np.random.Generator) -> None:
    s = scene(None)  # n = l
    for _ in range(20):
        w = rng.standard_normal(3)
        w -= (w @ L_NONPRINCIPAL) * L_NONPRINCIPAL
        for solver in ("direct", "qp"):
            res = s.model.step(0.0, s.q0, w, solver=solver)
            assert res.margin == pytest.approx(1.0, abs=1e-12)  # ideal: D = Jᵀ
            assert abs(w @ res.reaction) <= 1e-14 * np.linalg.norm(w) * np.linalg.norm(res.reaction)


def test_margin_follows_the_cosine_formula(rng: np.random.Generator) -> None:
    """For one constraint the margin is |(I⁻¹n, l)| / sqrt((I⁻¹n, n)(I⁻¹l, l))."""
    Iinv = 1.0 / np.array(INERTIA)
    for _ in range(10):
        n, l = rng.standard_normal(3), rng.standard_normal(3)
        expected = abs((Iinv * n) @ l) / np.sqrt(((Iinv * n) @ n) * ((Iinv * l) @ l))
        s = scene(n, l)
        assert s.model.step(0.0, s.q0, s.v0).margin == pytest.approx(expected, rel=1e-12)


def test_small_margin_warns() -> None:
    n0 = np.array(INERTIA) * np.array([1.0, -1.0, 0.0])
    n = n0 + 1e-8 * np.array([0.0, 0.0, 1.0]) + 1e-8 * np.array(INERTIA) * L_NONPRINCIPAL
    s = scene(n)
    with pytest.warns(gp.RealizabilityWarning, match="realizability margin"):
        res = s.model.step(0.0, s.q0, s.v0, solver="direct")
    assert 1e-12 < res.margin < 1e-6
