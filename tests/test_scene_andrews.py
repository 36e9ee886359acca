"""Andrews' squeezing mechanism against the published Bari/CWI test-set reference.

Acceptance: the angles at t = 0.03 agree with the published reference to ≤ 3e-9 (≥ 9 significant
digits) with a stated method; the constraint residual at the end is reported. The tighter comparisons use the
converged values ``an.CONVERGED_*``, derived apart from gausspp by ``python benchmarks/andrews_converged.py``
(the published formulas, mpmath's Taylor-series integrator at 30 digits: they agree to 14–16 digits).
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes import andrews as an

# The methods that reach the published accuracy, with their settings (measured: 0.1–0.3 s and 0.6–1.7 s).
METHODS = {
    "DOP853": dict(method="DOP853", rtol=1e-12, atol=1e-14),
    "rk4 compiled": dict(method="rk4", lane="compiled", dt=1e-6),
}


@pytest.fixture(scope="module")
def scene() -> gp.scenes.Scene:
    return gp.scenes.get("andrews")


def run(scene: gp.scenes.Scene, solver: str, **kw: object) -> tuple[gp.Trajectory, float]:
    start = time.perf_counter()
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, solver=solver, **kw)  # type: ignore[arg-type]
    return traj, time.perf_counter() - start


def relative(x: np.ndarray, ref: np.ndarray) -> float:
    """Largest difference, relative to the reference's largest component."""
    return float(np.max(np.abs(x - ref)) / np.max(np.abs(ref)))


# -- the scene record ------------------------------------------------------------------------------
def test_registry_builds_the_scene(scene: gp.scenes.Scene) -> None:
    assert scene.name == "andrews" and scene.t_end == 0.03 and scene.exact is None and scene.lam0 is None
    assert (scene.model.nq, scene.model.nv, scene.model.k, scene.model.m) == (7, 7, 6, 6)
    assert scene.model.holonomic_rows == list(range(6))
    assert all(isinstance(c.realization, gp.Ideal) for c in scene.model.constraints)
    assert gp.scenes.describe()["andrews"] == (
        "Andrews' squeezing mechanism: 7 bodies, 6 holonomic loop-closure constraints (Hairer–Wanner / Bari test set)"
    )
    # the 30-digit initial values as floats, and the initial state is on the constraint (andrews.md: 1.4e-17)
    assert scene.q0[0] == float("-0.0617138900142764496358948458001") and scene.q0[3] == -scene.q0[5]
    np.testing.assert_array_equal(scene.v0, 0.0)
    data = scene.model.kernel("direct")(0.0, scene.q0, scene.v0, np.zeros(0), np.zeros(2))
    assert np.max(np.abs(data["g"])) <= 1e-16


def test_significant_digits_is_the_test_sets_relative_scd() -> None:
    ref = an.REFERENCE_Q
    assert an.significant_digits(ref) == 16.0  # zero error counts as 1e-16
    bumped = ref.copy()
    bumped[2] += 1e-9 * abs(ref[2])  # γ ≈ 0.04: relative error 1e-9 although the absolute one is 4e-11
    bumped[0] += 1e-10  # β ≈ 15.8: a larger absolute error, a smaller relative one
    assert an.significant_digits(bumped) == pytest.approx(9.0, abs=1e-6)
    # the published angles against the converged ones: 1.43e-9 absolute (Θ), 9.57 digits (γ dominates)
    assert np.max(np.abs(an.REFERENCE_Q - an.CONVERGED_Q)) == pytest.approx(an.PUBLISHED_ACCURACY, rel=0.05)
    assert an.significant_digits(an.CONVERGED_Q) == pytest.approx(9.566, abs=1e-3)


# -- t = 0: the published consistent q̈(0) and λ(0) ------------------------------------------------
@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_initial_step_reproduces_published_acceleration_and_multipliers(scene: gp.scenes.Scene, solver: str) -> None:
    """u = −λ: gausspp's ideal reaction is Gᵀu, the test set's is −Gᵀλ (M q̈ = f − Gᵀλ)."""
    r = scene.model.step(0.0, scene.q0, scene.v0, solver=solver)
    err_a, err_u = relative(r.a, an.ACCELERATION0), relative(-r.u, an.LAMBDA0)
    print(f"\n[andrews t=0 {solver}] q̈0 relative error {err_a:.2e}, λ0 relative error (u = −λ) {err_u:.2e}")
    assert err_a <= 1e-14  # measured 2.8e-15 (KKT in andrews.md: 5e-16)
    assert err_u <= 1e-14  # measured 1.0e-15
    assert relative(r.u, an.LAMBDA0) > 1.9  # the other sign is wrong by 2|λ|
    J = scene.model.step_data(0.0, scene.q0, scene.v0).J
    np.testing.assert_allclose(r.reaction, -J.T @ an.LAMBDA0, rtol=0, atol=1e-14 * np.max(np.abs(J.T @ an.LAMBDA0)))
    assert np.max(np.abs(r.residual)) <= 1e-14 * np.max(np.abs(J)) * np.max(np.abs(r.a))


# -- J and φ against andrews.md's G and γ ---------------------------------------------------------
def published_G(q: np.ndarray) -> np.ndarray:
    """G = ∂g/∂q as in andrews.md (and the test set's ``gp``)."""
    p = an.PARAMETERS
    be, th, ga, ph, de, om, ep = q
    rr, d, ss, e, zt, zf, u = (p[k] for k in ("rr", "d", "ss", "e", "zt", "zf", "u"))
    G = np.zeros((6, 7))
    G[0::2, 0] = -rr * np.sin(be) + d * np.sin(be + th)
    G[0::2, 1] = d * np.sin(be + th)
    G[1::2, 0] = rr * np.cos(be) - d * np.cos(be + th)
    G[1::2, 1] = -d * np.cos(be + th)
    G[0, 2], G[1, 2] = -ss * np.cos(ga), -ss * np.sin(ga)
    G[2, 3], G[2, 4] = -e * np.cos(ph + de), -e * np.cos(ph + de) + zt * np.sin(de)
    G[3, 3], G[3, 4] = -e * np.sin(ph + de), -e * np.sin(ph + de) - zt * np.cos(de)
    G[4, 5], G[4, 6] = zf * np.sin(om + ep), zf * np.sin(om + ep) - u * np.cos(ep)
    G[5, 5], G[5, 6] = -zf * np.cos(om + ep), -zf * np.cos(om + ep) - u * np.sin(ep)
    return G


def published_gamma(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """γ(q, q̇) = (∂(G q̇)/∂q) q̇ as derived in andrews.md."""
    p = an.PARAMETERS
    be, th, ga, ph, de, om, ep = q
    bd, thd, gad, phd, ded, omd, epd = v
    rr, d, ss, e, zt, zf, u = (p[k] for k in ("rr", "d", "ss", "e", "zt", "zf", "u"))
    gx = -rr * np.cos(be) * bd**2 + d * np.cos(be + th) * (bd + thd) ** 2
    gy = -rr * np.sin(be) * bd**2 + d * np.sin(be + th) * (bd + thd) ** 2
    return np.array(
        [
            gx + ss * np.sin(ga) * gad**2,
            gy - ss * np.cos(ga) * gad**2,
            gx + e * np.sin(ph + de) * (phd + ded) ** 2 + zt * np.cos(de) * ded**2,
            gy - e * np.cos(ph + de) * (phd + ded) ** 2 + zt * np.sin(de) * ded**2,
            gx + zf * np.cos(om + ep) * (omd + epd) ** 2 + u * np.sin(ep) * epd**2,
            gy + zf * np.sin(om + ep) * (omd + epd) ** 2 - u * np.cos(ep) * epd**2,
        ]
    )


def test_symbolic_jacobian_and_acceleration_rhs_match_published_formulas(
    scene: gp.scenes.Scene, rng: np.random.Generator
) -> None:
    """At random states with velocities of the size the motion reaches (|β̇|, |Θ̇| ~ 1e3), J = G, φ = −γ."""
    for _ in range(5):
        q = scene.q0 + rng.uniform(-1.0, 1.0, 7)
        v = rng.uniform(-1.0, 1.0, 7) * np.array([1e3, 1e3, 20, 20, 1, 20, 1])
        data = scene.model.step_data(0.0, q, v)
        G, gamma = published_G(q), published_gamma(q, v)
        assert np.all(np.abs(gamma) > 1.0)  # every row's γ is exercised
        np.testing.assert_allclose(data.J, G, rtol=0, atol=1e-16)  # measured: exact to round-off (≤ 7e-18)
        np.testing.assert_allclose(data.phi, -gamma, rtol=0, atol=1e-13 * np.max(np.abs(gamma)))
        np.testing.assert_allclose(data.Phi, G @ v, rtol=0, atol=1e-14 * np.max(np.abs(G @ v)))


def test_force_vector_is_consistent_with_the_mass_matrix(scene: gp.scenes.Scene) -> None:
    """Energy balance E − E₀ = W(mom) (ideal reactions do no work): checks f's velocity-squared terms
    against M(q) and the spring potential, independently of the test set's transcription."""
    traj, _ = run(scene, "direct", **METHODS["DOP853"])
    assert traj.success
    balance = np.max(np.abs(traj.energy_balance()))
    print(f"\n[andrews energy] |E − E0 − W| ≤ {balance:.2e}, W(mom) = {traj.work_forces[-1]:.4f}")
    assert traj.work_forces[-1] > 0.5  # the torque does work 0.52
    assert np.max(np.abs(traj.work_reaction)) <= 1e-11  # measured 6e-13
    assert balance <= 1e-11  # measured 1.2e-13


# -- acceptance: the published angles at t = 0.03 -------------------------------------------------
@pytest.mark.parametrize("name", list(METHODS))
def test_angles_at_t_003_match_published_reference(scene: gp.scenes.Scene, name: str) -> None:
    """Acceptance: max |q(0.03) − published| ≤ 3e-9 (≥ 9 significant digits), solver 'direct'."""
    traj, wall = run(scene, "direct", record=[scene.t_end], **METHODS[name])
    assert traj.success and traj.t[-1] == scene.t_end
    q, v, a, lam = traj.q[-1], traj.v[-1], traj.a[-1], -traj.u[-1]  # u = −λ (test-set sign)
    err_pub = float(np.max(np.abs(q - an.REFERENCE_Q)))
    err_conv = float(np.max(np.abs(q - an.CONVERGED_Q)))
    residual = float(np.max(np.abs(traj.g[-1])))
    scd = an.significant_digits(q)
    print(
        f"\n[andrews {name}, {METHODS[name]}] wall {wall:.2f} s, {traj.steps} steps, "
        f"{traj.rhs_evaluations} evaluations\n"
        f"  max|q − published| = {err_pub:.3e}, scd = {scd:.2f}; max|q − converged| = {err_conv:.3e} "
        f"(scd vs converged {an.significant_digits(q, an.CONVERGED_Q):.2f})\n"
        f"  max|v − converged| = {np.max(np.abs(v - an.CONVERGED_V)):.3e}, "
        f"λ vs published {np.max(np.abs(lam - an.REFERENCE_LAMBDA) / np.abs(an.REFERENCE_LAMBDA)):.2e}, "
        f"λ vs converged {relative(lam, an.CONVERGED_LAMBDA):.2e} (relative)\n"
        f"  end residual max|g| = {residual:.2e}, max|Φ| = {np.max(np.abs(traj.residual[-1])):.2e}; "
        f"Φ + Ω = {q[3] + q[5]:.1e}, Φ' + Ω' = {v[3] + v[5]:.1e}"
    )
    assert err_pub <= 3e-9  # measured 1.43e-9 with both methods: the published values' own error
    assert scd >= 9.0  # measured 9.56
    assert err_conv <= 1e-11  # measured 4.6e-13 (DOP853), 2.4e-12 (rk4 compiled)
    assert np.max(np.abs(v - an.REFERENCE_V)) <= 1e-6  # andrews.md threshold; measured 5.4e-7
    assert np.max(np.abs(v - an.CONVERGED_V)) <= 1e-8  # measured 1.6e-10, 9.7e-10
    # q̈ and λ: published to 6–7 digits only (threshold 1e-5 relative), converged much better
    assert np.max(np.abs(lam - an.REFERENCE_LAMBDA) / np.abs(an.REFERENCE_LAMBDA)) <= 1e-5  # measured 1.3e-6
    assert np.max(np.abs(a - an.REFERENCE_A) / np.abs(an.REFERENCE_A)) <= 1e-5  # measured 1.3e-6
    assert relative(lam, an.CONVERGED_LAMBDA) <= 1e-10  # measured 1.4e-12, 2.8e-13
    assert relative(a, an.CONVERGED_A) <= 1e-10
    # pitfall 6: the parameter symmetry makes Φ = −Ω, Φ' = −Ω'
    assert abs(q[3] + q[5]) <= 1e-13  # measured 3e-16, 6e-15
    assert abs(v[3] + v[5]) <= 1e-10 * abs(v[3])  # measured 4.7e-13, 1.7e-13 (|Φ'| = 19)
    assert residual <= 1e-12  # measured 9e-15, 7e-15 (no stabilization)


def test_qp_gives_the_same_end_state_as_direct(scene: gp.scenes.Scene) -> None:
    """The Gauss QP (default backend) and the direct formula, same method and tolerances."""
    (direct, t_direct), (qp, t_qp) = (
        run(scene, s, record=[scene.t_end], **METHODS["DOP853"]) for s in ("direct", "qp")
    )
    assert qp.solver == gp.qp.DEFAULT and direct.solver == "direct"
    dq = float(np.max(np.abs(qp.q[-1] - direct.q[-1])))
    dv = float(np.max(np.abs(qp.v[-1] - direct.v[-1])))
    print(
        f"\n[andrews qp ({qp.solver}) vs direct, DOP853] max|Δq| = {dq:.1e}, max|Δv| = {dv:.1e}; "
        f"wall {t_qp:.2f} s vs {t_direct:.2f} s; qp: max|q − published| = "
        f"{np.max(np.abs(qp.q[-1] - an.REFERENCE_Q)):.3e}"
    )
    assert qp.success and qp.t[-1] == scene.t_end
    assert dq <= 1e-9  # measured 8e-14
    assert dv <= 1e-9 * np.max(np.abs(direct.v[-1]))  # measured 3e-11 of |v| = 1.4e3
    assert relative(qp.u[-1], direct.u[-1]) <= 1e-9  # measured 1.3e-13
    assert np.max(np.abs(qp.q[-1] - an.REFERENCE_Q)) <= 3e-9


# -- the same mechanism in other units ------------------------------------------------------------
#: (metre, kilogram, second): millimetres, grams and milliseconds; kilometres, tonnes and hectoseconds.
OTHER_UNITS = [(1e3, 1e3, 1e3), (1e-3, 1e-3, 1e-2)]


@pytest.mark.parametrize(("metre", "kilogram", "second"), OTHER_UNITS)
def test_in_other_units_it_reaches_the_published_reference_in_those_units(
    metre: float, kilogram: float, second: float
) -> None:
    """Written in other units (every published constant multiplied by its unit's number), the scene starts where
    the test set starts and reaches its reference at 0.03 s, each read in the scene's own units (``reference``): the
    angles to the acceptance's 3e-9, the rest as closely as in SI. The control: the SI reference's velocities are
    not the scaled run's."""
    scene = gp.scenes.get("andrews", metre=metre, kilogram=kilogram, second=second)
    start = an.reference(scene, "initial")
    r = scene.model.step(0.0, scene.q0, scene.v0)
    assert relative(r.a, start.a) <= 1e-14 and relative(-r.u, start.lam) <= 1e-14  # measured ≤ 5e-16
    published, converged = an.reference(scene), an.reference(scene, "converged")
    assert scene.t_end == published.t == pytest.approx(0.03 * second, rel=1e-15)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, method="DOP853", rtol=1e-12, record=[scene.t_end])
    assert traj.success
    q, v, a, lam = traj.q[-1], traj.v[-1], traj.a[-1], -traj.u[-1]
    assert np.max(np.abs(q - published.q)) <= 3e-9  # measured 1.43e-9: the published values' own error
    assert np.max(np.abs(q - converged.q)) <= 1e-10  # measured 9e-12 (8.9e-12 in SI at the same call)
    assert relative(v, converged.v) <= 1e-10  # measured 2.3e-12, as in SI
    assert relative(lam, converged.lam) <= 1e-10  # measured 7.5e-12
    assert relative(a, converged.a) <= 1e-10  # measured 2.0e-11
    assert relative(v, an.reference(which="converged").v) > 0.5  # the SI reference is another number


def test_reference_refuses_an_unknown_state() -> None:
    with pytest.raises(gp.UnknownNameError, match="which='final'"):
        an.reference(which="final")
    with pytest.raises(gp.InputError, match="metre must be a positive number"):
        gp.scenes.get("andrews", metre=0.0)
