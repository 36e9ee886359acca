"""docs/theory.md §6.3 (gyrostat, flywheel realization) and §6.2 with n = l (Suslov's problem).

* the gyrostat obeys d/dt(Iω + λn) + ω × (Iω + λn) = 0 with (ω, l) = 0 kept by λ̇;
* it is the same motion as the body with the rotor angle as a coordinate and the motor torque
  as a Béghin servo (scene "gyrostat-extended"): ω, λ = J_r(n·ω + θ̇) and τ = λ̇ agree;
* with n = l it is the vakonomic motion;
* Suslov's motion conserves energy and tends to the steady rotation of ``steady_rotation``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes.gyrostat_extended import rotor_momentum
from gausspp.scenes.suslov import approach_rate, steady_rotation

TIGHT: dict[str, Any] = dict(method="DOP853", rtol=1e-12, atol=1e-14)
INERTIA = np.diag([1.0, 2.0, 3.0])
L_DIAG = np.ones(3) / np.sqrt(3.0)

# (inertia, rotor axis n, constraint axis l, omega0, lam0): a principal-axis rotor with a skew
# constraint (the default scene), n = l (vakonomic), and a full tensor with skew n and l.
FULL = np.array([[2.0, 0.3, -0.2], [0.3, 1.5, 0.1], [-0.2, 0.1, 1.0]])
CASES = {
    "default": ((1.0, 2.0, 3.0), (0.0, 0.0, 1.0), (1.0, 1.0, 1.0), (1.0, -0.5, 0.2), 0.5),
    "n=l": ((1.0, 2.0, 3.0), None, (1.0, 1.0, 1.0), (1.0, -0.5, 0.2), -0.8),
    "full-tensor": (FULL, (1.0, -2.0, 0.5), (0.2, 1.0, -0.7), (0.3, 0.9, -1.1), 1.3),
}


def gyrostat(case: str) -> gp.scenes.Scene:
    inertia, n, l, omega0, lam0 = CASES[case]
    return gp.scenes.get("gyrostat", inertia=inertia, n=n, l=l, omega0=omega0, lam0=lam0)


def extended(case: str, rotor_inertia: float = 0.1) -> gp.scenes.Scene:
    inertia, n, l, omega0, lam0 = CASES[case]
    return gp.scenes.get(
        "gyrostat-extended", inertia=inertia, rotor_inertia=rotor_inertia, n=n, l=l, omega0=omega0, lam0=lam0
    )


# -- the gyrostat's step -----------------------------------------------------------------------
@pytest.mark.parametrize("solver", ["direct", "qp"])
@pytest.mark.parametrize("case", list(CASES))
def test_gyrostat_step_is_eulers_equation_with_rotor(case: str, solver: str, rng: np.random.Generator) -> None:
    s = gyrostat(case)
    I, n, l = (np.array(s.params[k]) for k in ("inertia", "n", "l"))
    for _ in range(5):
        w = rng.standard_normal(3)
        w -= (w @ l) * l
        lam = rng.standard_normal(1)
        res = s.model.step(0.3, s.q0, w, lam, solver=solver)
        lam_dot = res.u[0]
        K = I @ w + lam[0] * n  # total angular momentum of carrier and rotor
        np.testing.assert_allclose(I @ res.a + lam_dot * n + np.cross(w, K), 0.0, atol=1e-13)
        assert abs(res.a @ l) < 1e-14
        # the reaction of the flywheel realization, eq. (15): R = −λ̇ n − λ ω × n
        np.testing.assert_allclose(res.reaction, -lam_dot * n - lam[0] * np.cross(w, n), atol=1e-13)
        # λ̇ from (ω̇, l) = 0 in closed form: (I⁻¹(λ̇n + ω × K), l) = 0
        Iinv = np.linalg.inv(I)
        expected = -(l @ Iinv @ np.cross(w, K)) / (l @ Iinv @ n)
        assert lam_dot == pytest.approx(expected, rel=1e-12, abs=1e-14)


def test_gyrostat_unrealizable_when_I_inverse_n_is_perpendicular_to_l() -> None:
    n = INERTIA @ np.array([1.0, -1.0, 0.0])  # I⁻¹n = (1, −1, 0) ⟂ l although n is not ⟂ l
    assert abs(n @ L_DIAG) > 0.5
    for name, condition in (("gyrostat", "(16)"), ("gyrostat-extended", "(12)")):
        s = gp.scenes.get(name, inertia=(1.0, 2.0, 3.0), n=n, l=L_DIAG)
        for solver in ("direct", "qp"):
            with pytest.raises(gp.RealizabilityError) as info:
                s.model.step(0.5, s.q0, s.v0, s.lam0, solver=solver)
            err = info.value
            assert err.t == 0.5 and err.constraint == "(ω, l) = 0" and err.margin < 1e-12
            assert condition in str(err)
        with pytest.raises(gp.RealizabilityError):
            gp.simulate(s.model, s.q0, s.v0, 1.0, dt=0.1)


def test_scene_parameters_are_checked() -> None:
    with pytest.raises(gp.ShapeError, match="n must have 3"):
        gp.scenes.get("gyrostat", n=(1.0, 0.0))
    with pytest.raises(gp.InputError, match="l must be a finite nonzero"):
        gp.scenes.get("gyrostat", l=(0.0, 0.0, 0.0))
    with pytest.raises(gp.ShapeError, match="lam0"):
        gp.scenes.get("gyrostat", lam0=(1.0, 2.0))
    with pytest.raises(gp.InputError, match="rotor_inertia"):
        gp.scenes.get("gyrostat-extended", rotor_inertia=0.0)
    s = gp.scenes.get("gyrostat", omega0=(1.0, 2.0, 3.0))
    assert abs(s.v0 @ np.array(s.params["l"])) < 1e-15  # omega0 projected onto the constraint


# -- the extended model ------------------------------------------------------------------------
def test_extended_mass_matrix_is_the_hessian_of_T(rng: np.random.Generator) -> None:
    """A = ∂²T/∂v² and f = (−ω × ∂T/∂ω, 0) for T = ½ωᵀI′ω + ½J_r(n·ω + θ̇)² (checked in numbers)."""
    Jr = 0.3
    s = extended("full-tensor", rotor_inertia=Jr)
    I, n = FULL, np.array(s.params["n"])
    q = np.array([0.6, 0.0, 0.8, 0.0, 1.2])
    for _ in range(5):
        v = rng.standard_normal(4)
        data = s.model.step_data(0.0, q, v)
        T = 0.5 * v[:3] @ I @ v[:3] + 0.5 * Jr * (n @ v[:3] + v[3]) ** 2
        assert 0.5 * v @ data.A @ v == pytest.approx(T, rel=1e-14)
        dT_dw = I @ v[:3] + Jr * (n @ v[:3] + v[3]) * n
        np.testing.assert_allclose(data.A[:3] @ v, dT_dw, rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(data.f, np.append(-np.cross(v[:3], dT_dw), 0.0), rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(data.D.ravel(), [0.0, 0.0, 0.0, 1.0])


@pytest.mark.parametrize("case", list(CASES))
def test_extended_model_is_the_gyrostat(case: str) -> None:
    """Same ω(t), λ(t) = J_r(n·ω + θ̇), motor torque τ = λ̇, over t = 10 (acceptance: ω to 1e-9)."""
    Jr = 0.1
    g, e = gyrostat(case), extended(case, Jr)
    assert e.v0[:3] == pytest.approx(g.v0, abs=1e-15)
    assert g.lam0 is not None and e.lam0 is None  # λ is a state of the gyrostat only
    assert rotor_momentum(e.v0, e.params["n"], Jr)[0] == pytest.approx(g.lam0[0], rel=1e-14)
    times = np.linspace(0.0, 10.0, 201)[1:]
    tg = gp.simulate(g.model, g.q0, g.v0, 10.0, record=times, **TIGHT)
    te = gp.simulate(e.model, e.q0, e.v0, 10.0, record=times, **TIGHT)
    np.testing.assert_allclose(tg.t, times, rtol=0, atol=1e-12)
    np.testing.assert_allclose(te.t, times, rtol=0, atol=1e-12)
    scale = np.abs(tg.v).max()
    dw = np.abs(tg.v - te.v[:, :3]).max()
    assert dw <= 1e-9 * scale, f"ω differs by {dw:.3g}"
    lam_e = rotor_momentum(te.v, e.params["n"], Jr)
    np.testing.assert_allclose(lam_e, tg.lam[:, 0], rtol=0, atol=1e-9 * np.abs(tg.lam).max())
    # the Béghin multiplier of the extended model is the motor torque τ = λ̇ of the gyrostat
    np.testing.assert_allclose(te.u[:, 0], tg.u[:, 0], rtol=0, atol=1e-9 * np.abs(tg.u).max())
    # and the orientation of the carrier is the same
    np.testing.assert_allclose(te.q[:, :4], tg.q, rtol=0, atol=1e-9)
    # the motion is not trivial: the rotor is driven (λ changes by O(1))
    assert np.ptp(tg.lam[:, 0]) > 0.1


@pytest.mark.parametrize("case", list(CASES))
def test_energies_of_the_two_models(case: str) -> None:
    """Gyrostat: ½ωᵀIω changes by the work of −λ̇n − λω×n; extended: T by the motor's work θ̇τ.

    Their difference is the rotor's own energy λ²/(2J_r).
    """
    Jr = 0.1
    g, e = gyrostat(case), extended(case, Jr)
    tg = gp.simulate(g.model, g.q0, g.v0, 10.0, **TIGHT)
    te = gp.simulate(e.model, e.q0, e.v0, 10.0, **TIGHT)
    Eg, Ee = tg.energy[0], te.energy[0]
    assert np.abs(tg.energy_balance()).max() <= 1e-10 * Eg
    if not g.params["vakonomic"]:  # the rotor exchanges energy with the carrier: power −λ̇(n, ω)
        assert np.ptp(tg.energy) > 1e-3 * Eg
    else:  # n = l: the power −λ̇(l, ω) vanishes on the constraint
        assert np.ptp(tg.energy) <= 1e-10 * Eg
    # MassMatrix does not know its applied forces' power, so energy_balance() is NaN there; the
    # balance without applied forces is E − E₀ − W_R
    assert np.abs(te.energy - Ee - te.work_reaction).max() <= 1e-10 * Ee
    times = np.linspace(0.0, 10.0, 101)[1:]
    tg = gp.simulate(g.model, g.q0, g.v0, 10.0, record=times, **TIGHT)
    te = gp.simulate(e.model, e.q0, e.v0, 10.0, record=times, **TIGHT)
    scale = np.abs(te.energy).max()  # the rotor pumps energy in: up to 80 times the initial (the run's scale)
    np.testing.assert_allclose(te.energy - tg.energy, tg.lam[:, 0] ** 2 / (2 * Jr), rtol=0, atol=1e-11 * scale)


@pytest.mark.parametrize("name", ["gyrostat", "gyrostat-extended"])
def test_qp_and_direct_agree_along_a_trajectory(name: str) -> None:
    s = gp.scenes.get(name)
    qp = gp.simulate(s.model, s.q0, s.v0, 10.0, dt=0.01, solver="qp")
    direct = gp.simulate(s.model, s.q0, s.v0, 10.0, dt=0.01, solver="direct")
    for field in ("q", "v", "lam", "u", "reaction"):
        a, b = getattr(qp, field), getattr(direct, field)
        assert np.abs(a - b).max(initial=0.0) <= 1e-10 * max(1.0, np.abs(b).max(initial=0.0)), field
    assert qp.max_residual() < 1e-12 and direct.max_residual() < 1e-12


def test_n_equal_l_is_the_vakonomic_motion() -> None:
    """Paper §4: with the rotor on the constraint's axis, N = (l, ω) = Φ — eqs. (17)–(18)."""
    s = gyrostat("n=l")
    l = np.array(s.params["l"])
    assert s.params["vakonomic"]
    vak = gp.Model(
        gp.RigidBody(inertia=INERTIA),
        gp.Constraint(lambda q, w, t: ca.dot(w, ca.DM(l)), realization=gp.Vakonomic(lam0=s.lam0)),
    )
    times = np.linspace(0.0, 10.0, 101)[1:]
    a = gp.simulate(s.model, s.q0, s.v0, 10.0, record=times, **TIGHT)
    b = gp.simulate(vak, s.q0, s.v0, 10.0, record=times, **TIGHT)
    for field in ("q", "v", "lam", "u", "reaction"):
        assert np.abs(getattr(a, field) - getattr(b, field)).max() <= 1e-10, field
    # vakonomic, not nonholonomic: the Suslov motion (ideal (ω, l) = 0) from the same ω₀ differs
    suslov = gp.scenes.get("rigid-body-servo", inertia=(1.0, 2.0, 3.0), l=l, omega0=s.v0)
    c = gp.simulate(suslov.model, suslov.q0, suslov.v0, 10.0, record=times, **TIGHT)
    assert np.abs(a.v - c.v).max() > 0.1


# -- Suslov's problem (scene "rigid-body-servo" with n = l) ------------------------------------
def test_suslov_conserves_energy() -> None:
    s = gp.scenes.get("rigid-body-servo")  # I = diag(1, 2, 3), l = (1, 1, 1)/√3: non-principal
    assert s.params["suslov"]
    tr = gp.simulate(s.model, s.q0, s.v0, 100.0, **TIGHT)
    assert tr.success and tr.t[-1] == 100.0
    E0 = tr.energy[0]
    assert np.abs(tr.energy / E0 - 1.0).max() <= 1e-10
    assert np.abs(tr.energy_balance()).max() <= 1e-10 * E0
    assert tr.max_residual() <= 1e-12


def test_steady_rotation_is_steady_on_the_energy_level() -> None:
    for inertia, l in ((INERTIA, L_DIAG), (FULL, np.array([0.2, 1.0, -0.7]) / np.linalg.norm([0.2, 1.0, -0.7]))):
        w0 = np.array([0.3, 0.9, -1.1])
        w0 -= (w0 @ l) * l
        w = steady_rotation(inertia, l, w0)
        assert abs(w @ l) < 1e-15
        assert 0.5 * w @ inertia @ w == pytest.approx(0.5 * w0 @ inertia @ w0, rel=1e-14)
        # Euler: ω × Iω must be along l (absorbed by the reaction μl), so ω̇ = 0
        assert np.linalg.norm(np.cross(np.cross(w, inertia @ w), l)) < 1e-14
        assert np.cross(l, inertia @ l) @ w > 0  # the attracting one of ±ω∞
        assert approach_rate(inertia, l, w0) > 0
        assert np.allclose(steady_rotation(inertia, -l, w0), w, rtol=1e-14, atol=0)  # l's sign is irrelevant
    # a principal l: every rotation in the plane is steady
    w0 = np.array([0.7, -0.4, 0.0])
    assert np.array_equal(steady_rotation(INERTIA, (0.0, 0.0, 2.0), w0), w0)
    assert approach_rate(INERTIA, (0.0, 0.0, 1.0), w0) == 0.0


def _distance(tr: gp.Trajectory, target: np.ndarray) -> np.ndarray:
    return np.linalg.norm(tr.v - target, axis=1) / np.linalg.norm(target)


CASES_SUSLOV = {
    "scene default": (INERTIA, L_DIAG, None),
    "full tensor": (FULL, np.array([0.2, 1.0, -0.7]), np.array([0.3, 0.9, -1.1])),
}


@pytest.mark.parametrize("case", list(CASES_SUSLOV))
def test_suslov_tends_to_the_predicted_steady_rotation(case: str) -> None:
    inertia, l, omega0 = CASES_SUSLOV[case]
    kw = {} if omega0 is None else dict(omega0=omega0)
    s = gp.scenes.get("rigid-body-servo", inertia=inertia, l=l, **kw)
    target = steady_rotation(inertia, l, s.v0)
    rate = approach_rate(inertia, l, s.v0)
    # by t_end the exponential part exp(−rate t) is below 1e-30 (rate·t_end ≥ 70): only the
    # integration error (≈ rtol) is left of the distance
    t_end = max(200.0, 70.0 / rate)
    tr = gp.simulate(s.model, s.q0, s.v0, t_end, **TIGHT)
    d = _distance(tr, target)
    assert d[0] > 0.1  # starts far from it
    assert d[-1] <= 1e-11, f"distance to the steady rotation at t={t_end:g}: {d[-1]:.3g}"
    # and approaches it at the predicted exponential rate (fit over the linear regime)
    window = (d < 1e-4) & (d > 1e-9)
    assert window.sum() > 10
    slope = np.polyfit(tr.t[window], np.log(d[window]), 1)[0]
    assert -slope == pytest.approx(rate, rel=1e-2)


def test_suslov_leaves_the_unstable_steady_rotation() -> None:
    """Started next to −ω∞ (the steady rotation with s > 0) the motion goes to +ω∞."""
    target = steady_rotation(INERTIA, L_DIAG, np.array([1.0, -0.5, 0.2]))
    e = np.cross(L_DIAG, target) / np.linalg.norm(target)  # in the plane, across the rotation
    start = -target + 1e-6 * e
    s = gp.scenes.get("rigid-body-servo", inertia=(1.0, 2.0, 3.0), l=L_DIAG, omega0=start)
    # ω∞ is the same for the start's slightly different energy up to 1e-12
    target = steady_rotation(INERTIA, L_DIAG, s.v0)
    tr = gp.simulate(s.model, s.q0, s.v0, 300.0, **TIGHT)
    d = _distance(tr, target)
    assert d[0] == pytest.approx(2.0, abs=1e-5)
    assert d[-1] <= 1e-11
