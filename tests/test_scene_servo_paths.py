"""The servo scenes of issue 19 (``overhead-crane``, ``spring-chain-servo``): their exact flat solutions are
motions of their models under their exact forces, on the prescribed paths, from rest to rest, and the one-step
solution cannot step them (the servo is realized tangentially)."""

from __future__ import annotations

from math import comb

import numpy as np
import pytest
from numpy.polynomial import Polynomial

import gausspp as gp
from gausspp.scenes import smooth_paths, spring_chain_servo

#: Relative residual of ``A q̈ = f + r₀ + D λ`` accepted (q̈ from a 5-point difference of the exact v).
EOM_TOL = 1e-8


def acceleration(scene: gp.scenes.Scene, t: float, h: float = 1e-3) -> np.ndarray:
    """``q̈(t)`` by the 5-point central difference of the exact velocity (error O(h⁴))."""
    assert scene.exact is not None
    v = [scene.exact(t + k * h)[1] for k in (-2, -1, 1, 2)]
    return (v[0] - 8 * v[1] + 8 * v[2] - v[3]) / (12 * h)


def chain_acceleration(scene: gp.scenes.Scene, t: float) -> np.ndarray:
    """The chain's ``q̈(t)`` from its flat polynomials (a difference of v loses ~1e-9 to round-off for n = 6)."""
    p = scene.params
    x, _ = spring_chain_servo.flat_chain(smooth_paths.rest_to_rest(2 * p["n"] + 1, p["T"]), p["n"], p["m"], p["k"])
    return np.array([xi.deriv(2)(t) for xi in x])


def eom_residual(scene: gp.scenes.Scene, t: float, forces: np.ndarray) -> float:
    """``|A q̈ − f − r₀ − D λ|∞`` at the exact state, relative to the largest of its terms (and 1); ``q̈`` by
    differences of the exact velocity (the crane) or from the flat polynomials (the chain)."""
    assert scene.exact is not None
    q, v = scene.exact(t)
    d = scene.model.step_data(t, q, v)
    a = chain_acceleration(scene, t) if scene.name == "spring-chain-servo" else acceleration(scene, t)
    terms = (d.A @ a, d.f + d.r0, d.D @ forces)
    scale = max(1.0, *(float(np.abs(x).max()) for x in terms))
    return float(np.abs(terms[0] - terms[1] - terms[2]).max()) / scale


def inner_times(scene: gp.scenes.Scene, count: int = 23) -> np.ndarray:
    return np.linspace(0.0, scene.t_end, count)[1:-1]


# -- the paths ------------------------------------------------------------------------------------------
def test_septic_smoothstep_and_lift_are_the_crane_profiles() -> None:
    sigma = smooth_paths.rest_to_rest(4, 1.0).convert()
    np.testing.assert_allclose(sigma.coef, [0, 0, 0, 0, 0, 126, -420, 540, -315, 70], atol=1e-10)
    beta = smooth_paths.bump(4, 1.0).convert()
    expected = 2**10 * Polynomial([0, 1]) ** 5 * Polynomial([1, -1]) ** 5
    np.testing.assert_allclose(beta.coef, expected.coef, atol=1e-9)


@pytest.mark.parametrize("p", [4, *(2 * n + 1 for n in range(1, 7))])
def test_smoothstep_meets_its_hermite_conditions(p: int) -> None:
    sigma = smooth_paths.rest_to_rest(p, 1.0)
    assert sigma.degree() == 2 * p + 1
    assert sigma(0.0) == pytest.approx(0.0, abs=1e-13) and sigma(1.0) == pytest.approx(1.0, abs=1e-13)
    grid = np.linspace(0.0, 1.0, 201)
    for j in range(1, p + 1):
        dj = sigma.deriv(j)
        scale = np.abs(dj(grid)).max()
        assert abs(dj(0.0)) <= 1e-10 * scale and abs(dj(1.0)) <= 1e-10 * scale, (p, j)
    closed = sum(comb(p + j, j) * (1 - grid) ** j for j in range(p + 1)) * grid ** (p + 1)  # the textbook form
    np.testing.assert_allclose(sigma(grid), closed, atol=1e-12)


# -- overhead crane -------------------------------------------------------------------------------------
def crane_path(t: float, D: float = 2.0, L0: float = 1.5, h: float = 0.5, T: float = 4.0) -> tuple[float, float]:
    """The payload path of issue 19, written out from its formulas."""
    tau = t / T
    sigma = 126 * tau**5 - 420 * tau**6 + 540 * tau**7 - 315 * tau**8 + 70 * tau**9
    return D * sigma, -L0 + h * 2**10 * tau**5 * (1 - tau) ** 5


def test_crane_flat_solution_is_a_motion_under_its_forces() -> None:
    scene = gp.scenes.get("overhead-crane")
    assert scene.forces is not None
    worst = max(eom_residual(scene, t, scene.forces(t)) for t in inner_times(scene))
    assert worst < EOM_TOL


def test_crane_payload_is_on_its_path_and_the_rope_taut() -> None:
    scene = gp.scenes.get("overhead-crane")
    assert scene.exact is not None and scene.forces is not None
    for t in np.linspace(0.0, scene.t_end, 41):
        (s, l, theta), v = scene.exact(t)
        X, Y = crane_path(t)
        assert abs(s + l * np.sin(theta) - X) < 1e-12 and abs(-l * np.cos(theta) - Y) < 1e-12
        assert np.abs(scene.model.step_data(t, *scene.exact(t)).Phi).max() < 1e-11  # ġ = 0: along the path
        F1, F2 = scene.forces(t)
        assert l > 0 and F2 > 0


def test_crane_starts_and_ends_at_rest() -> None:
    scene = gp.scenes.get("overhead-crane")
    assert scene.exact is not None and scene.forces is not None
    m2, g, D, L0 = (scene.params[k] for k in ("m2", "g", "D", "L0"))
    for t, q_end in ((0.0, [0.0, L0, 0.0]), (scene.t_end, [D, L0, 0.0])):
        q, v = scene.exact(t)
        np.testing.assert_allclose(q, q_end, atol=1e-12)
        np.testing.assert_allclose(v, 0.0, atol=1e-12)
        np.testing.assert_allclose(scene.forces(t), [0.0, m2 * g], atol=1e-12)  # the winch holds the load
    np.testing.assert_allclose(scene.exact(0.0)[0], scene.q0, atol=1e-12)
    path = smooth_paths.rest_to_rest(4, scene.t_end), smooth_paths.bump(4, scene.t_end)
    for poly in path:
        for j in range(1, 5):
            scale = np.abs(poly.deriv(j)(np.linspace(0.0, scene.t_end, 201))).max()
            assert abs(poly.deriv(j)(0.0)) < 1e-10 * scale and abs(poly.deriv(j)(scene.t_end)) < 1e-10 * scale


def test_crane_signs_trolley_leads_then_trails_and_tension_carries_the_lift() -> None:
    """The trolley accelerates first (θ < 0: the rope trails), and the winch pulls more than the weight while
    the payload is lifted from rest."""
    scene = gp.scenes.get("overhead-crane")
    assert scene.exact is not None and scene.forces is not None
    q, _ = scene.exact(0.4)
    F1, F2 = scene.forces(0.4)
    assert q[0] > crane_path(0.4)[0] and q[2] < 0 and F1 > 0
    assert F2 > scene.params["m2"] * scene.params["g"]


@pytest.mark.parametrize("factor", [(1.01, 1.0), (1.0, 1.001)])
def test_crane_check_refuses_a_wrong_force(factor: tuple[float, float]) -> None:
    scene = gp.scenes.get("overhead-crane")
    assert scene.forces is not None
    forces = scene.forces
    worst = max(eom_residual(scene, t, np.multiply(factor, forces(t))) for t in inner_times(scene))
    assert worst > 100 * EOM_TOL


def test_crane_one_step_matrix_is_singular_along_the_path() -> None:
    scene = gp.scenes.get("overhead-crane")
    assert scene.exact is not None
    for t in (0.0, 1.3, 2.0, 3.1):
        with pytest.raises(gp.RealizabilityError):
            scene.model.step(t, *scene.exact(t))


def test_crane_refuses_a_path_that_slackens_the_rope() -> None:
    with pytest.raises(gp.InputError, match="taut"):
        gp.scenes.get("overhead-crane", h=5.0, T=1.0)


# -- spring chain ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("n", range(1, 7))
def test_chain_flat_solution_is_a_motion_on_its_path(n: int) -> None:
    scene = gp.scenes.get("spring-chain-servo", n=n)
    assert scene.exact is not None and scene.forces is not None
    assert scene.params["index"] == 2 * n + 1
    worst = max(eom_residual(scene, t, scene.forces(t)) for t in inner_times(scene))
    assert worst < EOM_TOL
    p = 2 * n + 1
    for t in np.linspace(0.0, scene.t_end, 21):
        tau = t / scene.t_end
        yd = tau ** (p + 1) * sum(comb(p + j, j) * (1 - tau) ** j for j in range(p + 1))
        assert abs(scene.exact(t)[0][-1] - yd) < 1e-12


@pytest.mark.parametrize("n", range(1, 7))
def test_chain_starts_and_ends_at_rest(n: int) -> None:
    scene = gp.scenes.get("spring-chain-servo", n=n)
    assert scene.exact is not None and scene.forces is not None
    scale = max(np.abs(scene.exact(t)[0]).max() for t in inner_times(scene)) + max(
        abs(scene.forces(t)[0]) for t in inner_times(scene)
    )
    for t, q_end in ((0.0, 0.0), (scene.t_end, 1.0)):
        q, v = scene.exact(t)
        np.testing.assert_allclose(q, q_end, atol=1e-9 * scale)
        np.testing.assert_allclose(v, 0.0, atol=1e-9 * scale)
        assert abs(scene.forces(t)[0]) < 1e-9 * scale


def test_chain_one_step_solution_only_for_a_single_mass() -> None:
    """n ≥ 2: the force reaches the last mass through springs, ``J A⁻¹ Mᵀ = 0``; n = 1 is an ordinary servo
    (index 3), whose one-step force is the exact one."""
    for n in range(2, 7):
        scene = gp.scenes.get("spring-chain-servo", n=n)
        assert scene.exact is not None
        with pytest.raises(gp.RealizabilityError):
            scene.model.step(1.3, *scene.exact(1.3))
    single = gp.scenes.get("spring-chain-servo", n=1)
    assert single.exact is not None and single.forces is not None
    step = single.model.step(1.3, *single.exact(1.3))
    np.testing.assert_allclose(step.u, single.forces(1.3), rtol=1e-9)


@pytest.mark.parametrize("n", [1, 3, 6])
def test_chain_check_refuses_a_wrong_force(n: int) -> None:
    scene = gp.scenes.get("spring-chain-servo", n=n)
    assert scene.forces is not None
    forces = scene.forces
    worst = max(eom_residual(scene, t, 1.01 * forces(t)) for t in inner_times(scene))
    assert worst > 100 * EOM_TOL


def test_chain_refuses_more_than_six_masses() -> None:
    with pytest.raises(gp.InputError, match="between 1 and 6"):
        gp.scenes.get("spring-chain-servo", n=7)


@pytest.mark.parametrize(
    ("name", "params"), [("overhead-crane", {}), *(("spring-chain-servo", {"n": n}) for n in (1, 3, 6))]
)
def test_exact_velocity_is_the_derivative_of_the_exact_position(name: str, params: dict[str, int]) -> None:
    scene = gp.scenes.get(name, **params)
    assert scene.exact is not None
    exact, h = scene.exact, 1e-3
    for t in inner_times(scene, 11):
        q = [exact(t + k * h)[0] for k in (-2, -1, 1, 2)]
        difference = (q[0] - 8 * q[1] + 8 * q[2] - q[3]) / (12 * h)
        v = exact(t)[1]
        assert np.abs(difference - v).max() <= 1e-8 * max(1.0, np.abs(v).max()), (t, difference, v)


# -- the servo kind -------------------------------------------------------------------------------------
def test_servo_scenes_are_their_own_kind() -> None:
    servo = gp.scenes.names("servo")
    assert servo == ["overhead-crane", "spring-chain-servo"]
    assert set(servo) <= set(gp.scenes.names())
    assert not set(servo) & (set(gp.scenes.names("equality")) | set(gp.scenes.names("general")))
