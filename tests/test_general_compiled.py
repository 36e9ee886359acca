"""The compiled general step (gausspp.step.general.compiled): one call, an all-clear flag, the Python step behind it.

Each answer of the compiled call is checked two ways:

* against the Gauss QP's optimality conditions assembled from the problem's data alone (``A, f, r₀, J, φ, D`` and
  the contacts' ``J_c, φ_c``, by numpy, sharing no reduction, factorization or solver with the step): the motion
  equation with the reaction ``D u + J_cᵀ λ_c``, the rows kept, the contacts not penetrating with ``λ_c ≥ 0`` and
  complementary, the bounds, and stationarity ``Dᵀ(a − a₀)`` in the span of the active rows' ``(J A⁻¹ D)ᵀ`` —
  shown to fail on a deliberately wrong answer;
* against the Python step of the same step (the lexicographic stages of :mod:`gausspp.step.general.solve`).

States come from runs of the general scenes (saturated, resting, bouncing, redundant) and are perturbed off the
constraint manifold by hypothesis.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gausspp as gp
from gausspp import scenes
from gausspp.step.data import NO_STAB
from gausspp.step.general import general_step
from gausspp.step.general.solve import CONSISTENCY_TOL

CASES = {
    "four-bar-oblique": ("four-bar-redundant", {}),
    "four-bar-distance": ("four-bar-redundant", {"third_row": "distance"}),
    "block-resting": ("block-on-floor", {}),
    "saturated-crane": ("saturated-crane", {}),
    "bouncing-pendulum": ("bouncing-pendulum", {}),
    "two-actuator-bounded": ("two-actuator-servo", {"f_max": 6.0}),
}


@functools.cache
def case(name: str) -> tuple[gp.Model, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The model, and the states ``(t, q, v, λ)`` of a run through its general steps."""
    scene_name, params = CASES[name]
    try:
        sc = scenes.get(scene_name, **params)
    except TypeError:
        pytest.skip(f"{scene_name} takes no {params}")
    traj = gp.simulate(sc.model, sc.q0, sc.v0, sc.t_end, record=np.linspace(0.0, sc.t_end, 101))
    n_lam = sc.model.n_lam
    lam = traj.lam if n_lam else np.zeros((traj.t.size, 0))
    return sc.model, traj.t, traj.q, traj.v, lam


def python_step(model, t, q, v, lam):
    return general_step.solve_at(model, t, q, v, lam, None, compiled=False)


def compiled(model, t, q, v, lam):
    """The compiled call's answer at the state (after the Python step decided the pattern), or None."""
    general_step.solve_at(model, t, q, v, lam, None)  # decides and compiles the pattern (Python step if needed)
    fast = general_step.compiled_outputs(model, t, q, v, lam, None, stab=NO_STAB, consistency_tol=CONSISTENCY_TOL)
    return None if fast is None else general_step._from_packed(model, t, *fast)


def optimality_gap(model: gp.Model, t, q, v, lam, result, solution) -> float:
    """How far ``(a, u, λ_c)`` is from satisfying the Gauss QP's optimality conditions (relative; data alone)."""
    d = model.evaluate_data(t, q, v, lam)
    m, k = model.m, model.k
    closed = np.flatnonzero(result.contact_force != 0) if model.contacts else np.zeros(0, int)
    closed = np.flatnonzero(d.gc <= model.contact_tol) if model.contacts else closed
    Jc, phic = d.Jc[closed], d.phic[closed]
    lam_c = result.contact_force[closed]
    a, u = result.a, result.u
    force = np.abs(d.f).max() + np.abs(d.A @ a).max() + 1.0
    gaps = [np.abs(d.A @ a - (d.f + d.r0 + d.D @ u + Jc.T @ lam_c)).max() / force]
    accel = np.abs(a).max() + np.abs(result.free_acceleration).max() + 1.0
    rows_scale = (np.abs(d.J).max() if k else 1.0) * accel + (np.abs(d.phi).max() if k else 0.0)
    tracked = np.zeros(k, bool)
    lower, upper = np.full(m, -np.inf), np.full(m, np.inf)
    for grp, bounds in zip(model.groups, model.group_bounds, strict=True):
        if bounds is not None:
            tracked[grp.rows] = True
            lower[grp.cols], upper[grp.cols] = bounds
    keep = ~tracked | (result.tracking_error == 0)
    if keep.any():
        gaps.append(np.abs(d.J[keep] @ a - d.phi[keep]).max() / rows_scale)
    if closed.size:
        cscale = np.abs(Jc).max() * accel + np.abs(phic).max() + 1.0
        slack = Jc @ a - phic
        gaps += [max(0.0, -slack.min()) / cscale, max(0.0, -lam_c.min()) / force]
        gaps.append(np.abs(lam_c * slack).max() / (force * cscale))
    if np.isfinite(lower).any() or np.isfinite(upper).any():
        gaps.append(max(0.0, (lower - u).max(), (u - upper).max()) / (np.abs(u).max() + 1.0))
    # stationarity over the reaction unknowns: H u ∈ span of the active rows' (J A⁻¹ D)ᵀ, with H = Dᵀ A⁻¹ D
    Dall = np.hstack([d.D, Jc.T])
    uall = np.concatenate([u, lam_c])
    lo_all, hi_all = (
        np.concatenate([lower, np.zeros(closed.size)]),
        np.concatenate([upper, np.full(closed.size, np.inf)]),
    )
    free = ~(np.isclose(uall, lo_all, rtol=1e-9, atol=1e-12) | np.isclose(uall, hi_all, rtol=1e-9, atol=1e-12))
    active = np.concatenate([keep, np.abs(Jc @ a - phic) <= 1e-8 * (np.abs(phic) + 1)]) if closed.size else keep
    Jall = np.vstack([d.J, Jc])[active]
    AinvD = np.linalg.solve(d.A, Dall)
    Hu = (Dall.T @ AinvD @ uall)[free]
    if Hu.size:
        span = (Jall @ AinvD).T[free]
        y = np.linalg.lstsq(span, Hu, rcond=None)[0] if span.size else np.zeros(0)
        resid = Hu - (span @ y if span.size else 0.0)
        gaps.append(np.abs(resid).max() / (np.abs(Hu).max() + np.abs(Dall.T @ AinvD).max() * 1e-300 + 1e-30))
    return float(max(gaps))


@pytest.mark.parametrize("name", sorted(CASES))
def test_compiled_general_step_is_the_gauss_qp_at_every_sample(name: str) -> None:
    model, T, Q, V, L = case(name)
    hot = 0
    for i in range(0, T.size, max(1, T.size // 25)):
        t, q, v, lam = float(T[i]), Q[i], V[i], L[i]
        try:
            reference, ref_sol, _ = python_step(model, t, q, v, lam)
        except gp.GaussppError:
            continue  # an approaching contact at an impact sample: the Python step's error
        answer = compiled(model, t, q, v, lam)
        if answer is None:
            continue
        hot += 1
        result, sol, _ = answer
        assert optimality_gap(model, t, q, v, lam, result, sol) < 1e-8
        assert result.disagreement(reference) < 1e-8, (name, t)
        assert np.allclose(result.contact_force, reference.contact_force, rtol=1e-8, atol=1e-9 * model.nv)
        assert sol.stages[0] == "compulsion" and ("least-norm" in sol.stages) == ("least-norm" in ref_sol.stages)
    assert hot >= 5, f"the compiled call answered only {hot} samples of {name}"


def test_the_optimality_check_fails_on_a_wrong_answer() -> None:
    """Negative control: half the reaction, or the bound ignored, or a contact force of the wrong sign."""
    for name in ("four-bar-oblique", "saturated-crane", "block-resting"):
        model, T, Q, V, L = case(name)
        i = T.size - 1 if name == "block-resting" else T.size // 2
        t, q, v, lam = float(T[i]), Q[i], V[i], L[i]
        result, sol, _ = python_step(model, t, q, v, lam)
        assert optimality_gap(model, t, q, v, lam, result, sol) < 1e-8
        d = model.evaluate_data(t, q, v, lam)
        if name == "block-resting":  # the contact forces, each pushed 10 % off
            wrong = result.contact_force * 1.1
            a = np.linalg.solve(d.A, d.f + d.Jc.T @ wrong)
            bad = type(result).of_fields({**result.__dict__, "a": a, "contact_force": wrong})
        else:
            u = result.u * 0.5
            a = np.linalg.solve(d.A, d.f + d.r0 + d.D @ u)
            bad = type(result).of_fields({**result.__dict__, "a": a, "u": u})
        assert optimality_gap(model, t, q, v, lam, bad, sol) > 1e-3, name


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(sorted(CASES)),
    where=st.floats(0.0, 1.0),
    size=st.sampled_from([0.0, 1e-12, 1e-9, 1e-6, 1e-3]),
    seed=st.integers(0, 2**16),
)
def test_off_the_manifold_the_compiled_step_answers_as_the_python_step(name, where, size, seed) -> None:
    """Drifted states: where the flag is up the answers agree; where it is down the Python step answers."""
    model, T, Q, V, L = case(name)
    i = int(where * (T.size - 1))
    rng = np.random.default_rng(seed)
    t, lam = float(T[i]), L[i]
    q = Q[i] + size * rng.standard_normal(Q.shape[1])
    v = V[i] + size * rng.standard_normal(V.shape[1])
    try:
        reference = python_step(model, t, q, v, lam)[0]
    except gp.GaussppError as exc:
        with pytest.raises(type(exc)):
            general_step.solve_at(model, t, q, v, lam, None)
        return
    answer = compiled(model, t, q, v, lam)
    routed = general_step.solve_at(model, t, q, v, lam, None)[0]
    assert routed.disagreement(reference) < 1e-7
    if answer is not None:
        assert answer[0].disagreement(reference) < 1e-7


def test_redundant_model_step_takes_the_compiled_general_step() -> None:
    """After the first redundant step, model.step answers from the compiled general call (same numbers)."""
    sc = scenes.get("four-bar-redundant")
    m = sc.model
    first = m.step(0.0, sc.q0, sc.v0)
    hot = general_step.compiled_outputs(m, 0.0, sc.q0, sc.v0, np.zeros(0), None, stab=NO_STAB)
    assert hot is not None
    again = m.step(0.0, sc.q0, sc.v0)
    assert again.disagreement(first) < 1e-12
    minimal = scenes.get("four-bar-redundant", redundant=False)
    assert np.allclose(again.a, minimal.model.step(0.0, sc.q0, sc.v0).a, rtol=1e-10, atol=1e-10)


def test_flag_down_when_the_contacts_change() -> None:
    """The pattern of a resting block does not answer for the block in the air: the Python step does."""
    model, T, Q, V, L = case("block-resting")
    t, q, v, lam = float(T[-1]), Q[-1], V[-1], L[-1]
    compiled(model, t, q, v, lam)  # the resting pattern
    lifted = q.copy()
    lifted[1] += 0.5
    assert general_step.compiled_outputs(model, t, lifted, v, lam, None, stab=NO_STAB) is None
    flying = general_step.solve_at(model, t, lifted, v, lam, None)[0]
    assert np.allclose(flying.a, flying.free_acceleration) and not flying.contact_force.any()


def test_cvodes_runs_the_redundant_four_bar_as_the_minimal_model() -> None:
    """The compiled general step through CVODES (Adams): the minimal model's motion, lane cvodes-general."""
    redundant = scenes.get("four-bar-redundant")
    minimal = scenes.get("four-bar-redundant", redundant=False)
    grid = np.linspace(0.0, 2.0, 11)
    reference = gp.simulate(minimal.model, minimal.q0, minimal.v0, 2.0, rtol=1e-13, atol=1e-13, record=grid)
    run = gp.simulate(redundant.model, redundant.q0, redundant.v0, 2.0, method="cvodes-adams", rtol=1e-12,
                      atol=1e-12, record=grid)  # fmt: skip
    assert run.success and run.lane == "cvodes-general"
    assert np.abs(run.q - reference.q).max() < 1e-9
    wrong = gp.simulate(minimal.model, minimal.q0, minimal.v0 * 1.001, 2.0, rtol=1e-13, atol=1e-13, record=grid)
    assert np.abs(run.q - wrong.q).max() > 1e-4  # the comparison tells a slightly different motion apart


def test_cvodes_runs_a_bounded_model_and_bdf_hands_it_to_dop853() -> None:
    """A pattern with a QP node (saturated actuator): Adams (no Jacobian) runs it in CVODES, at its tolerance of
    the DOP853 run; BDF, which would differentiate the QP, hands it to DOP853 from the start (the same run)."""
    sc = scenes.get("saturated-crane")
    grid = np.linspace(0.0, 3.0, 31)
    plain = gp.simulate(sc.model, sc.q0, sc.v0, 3.0, method="DOP853", rtol=1e-12, atol=1e-12, record=grid)
    assert plain.saturated.any()  # the run passes through saturation
    adams = gp.simulate(sc.model, sc.q0, sc.v0, 3.0, method="cvodes-adams", rtol=1e-10, atol=1e-10, record=grid)
    assert adams.success and adams.lane == "cvodes-general"
    assert np.abs(adams.q - plain.q).max() < 1e-7  # measured 3.7e-9 (tolerance 1e-10, kinks at saturation)
    bdf = gp.simulate(sc.model, sc.q0, sc.v0, 1.0, method="cvodes", rtol=1e-12, atol=1e-12, record=grid[:11])
    np.testing.assert_allclose(bdf.q, plain.q[:11], rtol=0, atol=1e-12)


def test_double_parallelogram_passes_its_first_collinear_position_on_its_branch() -> None:
    """Rows redundant everywhere plus a rank drop at the first collinear position (t ≈ 0.714 s): the run stays on
    the parallelogram branch (the one-DOF reference), where the anti-parallelogram branch would part from it.
    (The adaptive lane's crossings over 10 s: tests/test_singular_crossing.py.)"""
    from gausspp.scenes import parallelogram as P

    sc = scenes.get("parallelogram", third_bar=True)
    grid = np.linspace(0.0, 1.0, 11)
    run = gp.simulate(sc.model, sc.q0, sc.v0, 1.0, method="cvodes-adams", rtol=1e-10, atol=1e-10, record=grid)
    assert run.success and run.t[-1] == 1.0
    theta, omega = P.one_dof_reference(run.t, **sc.params)
    reference = np.array([P.maximal_state(a, b, 0.0, 1, True)[0] for a, b in zip(theta, omega, strict=True)])
    assert np.abs(run.q - reference).max() < 1e-8
    energy = run.energy  # measured 2.9e-9 relative at rtol 1e-10 (most of it from the crossing)
    assert np.abs(energy - energy[0]).max() < 1e-8 * np.abs(energy).max()
    # negative control: past the collinear position the other branch (crank 2 folded back, θ₂ = −θ) parts from it
    after = run.t > 0.8
    folded = reference[after].copy()
    folded[:, 8] = -reference[after, 8]  # the second crank's angle mirrored
    assert np.abs(run.q[after] - folded).max() > 0.1


@pytest.mark.parametrize("name", ["saturated-crane", "bouncing-pendulum", "block-on-floor", "four-bar-redundant"])
def test_the_compiled_general_step_changes_no_trajectory(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Whole runs at rtol = atol = 1e-12 with the compiled general step and with the Python step alone (the
    compiled call switched off): the same trajectory to 1e-10 relative (measured ≤ 6e-12 against the previous
    release, whose general step was the Python step)."""
    sc = scenes.get(name)
    grid = np.linspace(0.0, 1.0, 11)

    def run() -> gp.Trajectory:
        traj = gp.simulate(sc.model, sc.q0, sc.v0, 1.0, lam0=sc.lam0, record=grid, rtol=1e-12, atol=1e-12)
        keep = np.isin(np.round(traj.t, 12), np.round(grid, 12))  # contact runs add their events' samples
        return traj.q[keep], traj.v[keep]

    q_fast, v_fast = run()
    with monkeypatch.context() as patch:
        patch.setattr(general_step, "compiled_outputs", lambda *args, **kwargs: None)
        sc = scenes.get(name)  # a new model: nothing compiled for it
        q_slow, v_slow = run()
    assert np.abs(q_fast - q_slow).max() <= 1e-10 * np.abs(q_slow).max()
    assert np.abs(v_fast - v_slow).max() <= 1e-10 * np.abs(v_slow).max()
