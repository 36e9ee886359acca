"""The stability study (docs/theory.md §6.6, issue 5 item 3): each case's verdict and its key figures.

The study runs once per module (``run(quick=True)``, about ten seconds). Cases whose verdict is ✗
(the library does something wrong there) have a test of what is *right*, marked
``xfail(strict=True)`` with the library problem as reason: it turns into a failure as soon as
the library is fixed, so the mark (and the study's verdict) must then be revisited.
"""

from __future__ import annotations

import csv
import io
import json
import math
import warnings

import numpy as np
import pytest

import gausspp as gp
from gausspp.studies import stability
from gausspp.studies.stability import Case, crane, margins, redundant

EPS = float(np.finfo(float).eps)


@pytest.fixture(scope="module")
def cases() -> dict[str, Case]:
    return {c.name: c for c in stability.run(quick=True)}


def _realizability_warned(caught: list[warnings.WarningMessage]) -> bool:
    return any(issubclass(w.category, gp.RealizabilityWarning) for w in caught)


# -- the study as a whole ------------------------------------------------------------------------
def test_run_returns_all_seven_cases_with_verdicts(cases: dict[str, Case]) -> None:
    assert list(cases) == list(stability.CASES) and len(cases) == 7
    for c in cases.values():
        assert isinstance(c.verdict, bool)
        assert c.what and c.expected and c.observed
        assert "crashed" not in c.figures, c.observed  # no case raised
        assert all(isinstance(v, float) for v in c.figures.values())
        assert c.figures["seconds"] > 0
        if not c.verdict:  # a ✗ says what is wrong
            assert c.problems
    print()
    print(stability.table(list(cases.values())))
    print("seconds per case:", {n: round(c.figures["seconds"], 2) for n, c in cases.items()})


def test_table_mentions_every_case_and_its_verdict(cases: dict[str, Case]) -> None:
    text = stability.table(list(cases.values()))
    lines = text.splitlines()
    for c in cases.values():
        row = next(line for line in lines if line.startswith(c.name))
        assert ("✓" if c.verdict else "✗") in row
        assert c.observed.split()[0] in row
    assert f"{sum(c.verdict for c in cases.values())}/7 cases" in text
    if any(c.problems for c in cases.values()):
        assert "Library problems found:" in text


def test_records_are_flat_and_serializable(cases: dict[str, Case]) -> None:
    records = stability.to_records(list(cases.values()))
    assert [r["name"] for r in records] == list(cases)
    assert json.loads(json.dumps(records))[0]["verdict"] in (True, False)
    keys = sorted({k for r in records for k in r})
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=keys)
    writer.writeheader()
    writer.writerows(records)
    assert out.getvalue().count("\n") >= 8  # header and seven rows (texts may hold no newlines)
    assert records[0]["figure:seconds"] > 0


def test_a_case_that_raises_becomes_a_failed_case(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(quick: bool) -> Case:
        raise ZeroDivisionError("boom")

    quick_ok = Case("x", "w", "e", "o", True, {})
    monkeypatch.setattr(
        stability,
        "CASES",
        {name: (broken if name == "long horizon" else (lambda quick: quick_ok)) for name in stability.CASES},
    )
    result = stability.run(quick=True)
    assert len(result) == 7
    failed = result[3]
    assert failed.name == "long horizon" and failed.verdict is False
    assert failed.what and failed.expected  # a crashed case still says what it is about
    assert "ZeroDivisionError: boom" in failed.observed and failed.figures["crashed"] == 1.0


# -- 1. stiff chain --------------------------------------------------------------------------------
def test_stiff_chain_stiff_method_needs_ten_times_fewer_evaluations(cases: dict[str, Case]) -> None:
    c = cases["stiff chain"]
    f = c.figures
    assert c.verdict, c.observed
    assert f["stiffness_ratio"] >= 1e6
    assert f["radau_error"] <= 1e-6 and f["rk4_error"] <= 1e-6
    assert f["evaluation_ratio"] >= 10.0
    assert f["rk4_evaluations"] == 4 * f["rk4_steps"]  # RK4: four right-hand sides per step
    # RK4 is at its stability limit |dt·ω| ≤ 2√2, and one step larger it does not reach 1e-6
    assert 2.5 <= f["rk4_dt_times_omega"] <= 2 * math.sqrt(2) + 0.02
    assert f["rk4_next_larger_dt_error"] > 1e-6
    # wall times are reported, never asserted (shared, noisy machines)
    assert f["rk4_wall_s"] > 0 and f["radau_wall_s"] > 0


@pytest.mark.slow
def test_stiff_chain_full() -> None:
    c = stability.stiff_chain.case(quick=False)
    assert c.verdict, c.observed
    assert c.figures["t_end"] == 10.0
    assert c.figures["evaluation_ratio@1e10"] >= 10.0 and c.figures["radau_error@1e10"] <= 1e-6


# -- 2. mass ratios --------------------------------------------------------------------------------
def test_mass_ratios_agree_within_eps_times_condition_number(cases: dict[str, Case]) -> None:
    c = cases["mass ratios"]
    f = c.figures
    assert c.verdict, c.observed
    assert f["steps_checked"] == 28 and f["failures"] == 0
    assert f["max_cond"] >= 1e6 * (1 - 1e-9)
    assert f["worst_error_over_eps_cond"] <= 10.0
    assert f["worst_qp_direct_difference_over_eps_cond"] <= 10.0
    assert f["reference_vs_closed_form"] < 1e-14  # the exact rational solve is the closed form
    for key in ("worst_error_direct", f"worst_error_{gp.qp.DEFAULT}", "worst_error_casadi:osqp"):
        assert f[key] <= 10 * EPS * f["max_cond"]


@pytest.mark.slow
def test_mass_ratios_full() -> None:
    c = stability.mass_ratios.case(quick=False)
    assert c.verdict, c.observed
    assert c.figures["steps_checked"] == 13 * 4 * 4


# -- 3. realizability margins ------------------------------------------------------------------------
def test_margins_warn_raise_and_error_grows_like_eps_over_margin(cases: dict[str, Case]) -> None:
    c = cases["realizability margins"]
    f = c.figures
    assert c.verdict, c.observed
    assert f["warning_mismatches"] == 0 and f["failures"] == 0
    assert f["errors_below_margin_error"] == 3  # direct, default QP, casadi:osqp
    assert -1.5 <= f["error_slope_vs_margin"] <= -0.5
    assert f["worst_error_times_margin_over_eps"] <= 10.0
    assert f["error_direct@1e-09"] <= 10 * EPS / 1e-9
    assert f["error_direct@1e-03"] <= 10 * EPS / 1e-3


def test_margin_1e9_warns_and_below_margin_error_raises() -> None:
    s = gp.scenes.get("crane", M0=1.0, m=0.5, L=1.0, theta0=-0.3, distance=0.0)
    for solver in ("direct", "qp"):
        with pytest.warns(gp.RealizabilityWarning, match=r"realizability margin 1e-09 at t=0\.5"):
            res = s.model.step(0.5, [0.1, margins.theta_for_margin(1e-9)], [0.3, 0.2], solver=solver)
        assert res.margin == pytest.approx(1e-9, rel=1e-6)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # margin 1e-5: no warning at all
            s.model.step(0.5, [0.1, margins.theta_for_margin(1e-5)], [0.3, 0.2], solver=solver)
        with pytest.raises(gp.RealizabilityError, match=r"'payload follows s\(t\)'.*t=0\.5") as info:
            s.model.step(0.5, [0.1, margins.theta_for_margin(1e-13)], [0.3, 0.2], solver=solver)
        assert info.value.margin < 1e-12


# -- 4. long horizon --------------------------------------------------------------------------------
def test_long_horizon_projection_holds_and_raw_drift_grows(cases: dict[str, Case]) -> None:
    """1e5 RK4 steps of dt = 0.01 on the pendulum; measured: Baumgarte τ = 0.1 keeps |g| ≤ 3e-7 and |Φ| ≤ 3.6e-6.

    Those two levels are RK4's truncation error fed back through the Baumgarte terms (not round-off), so
    the bounds below leave a factor of about three.
    """
    c = cases["long horizon"]
    f = c.figures
    assert c.verdict, c.observed
    assert f["steps"] == 1e5
    assert f["project_max_residual"] <= 1e-12
    assert f["raw_max_g"] > 1e-3 and f["raw_g_growth"] >= 10.0  # Φ drifts linearly, g like t²
    assert f["baumgarte_max_g"] <= 1e-3 * f["raw_max_g"]
    assert f["baumgarte_max_g"] <= 1e-6 and f["baumgarte_max_Phi"] <= 1e-5
    assert f["project_energy_drift"] <= 1e-4 * 9.81


@pytest.mark.slow
def test_long_horizon_full_million_steps() -> None:
    c = stability.long_horizon.case(quick=False)
    assert c.verdict, c.observed
    assert c.figures["steps"] == 1e6 and c.figures["project_max_residual"] <= 1e-12


# -- 5. redundant constraints -------------------------------------------------------------------------
# Issue 7: solver='direct' stops with a clear RealizabilityError; solver='qp' hands exactly dependent,
# consistent rows to the general Gauss QP: the unique acceleration and the least-norm multiplier.
_QUADPROG = "qpsolvers:quadprog"
_REDUNDANT_EXACT = 1e-10  # acceleration and multiplier, exactly dependent consistent rows (relative)


def _qp_backend_params() -> list[object]:
    return [None, *gp.qp.names()]


def test_redundant_case_figures(cases: dict[str, Case]) -> None:
    c = cases["redundant constraints"]
    f = c.figures
    # A. circle twice: direct names both constraints, redundancy and solver='qp'; every QP backend answers
    assert f["duplicate_solvers"] >= 3 and f["duplicate_qp_backends"] == f["duplicate_solvers"] - 1
    assert f["duplicate_direct_clear_error"] == 1
    assert f["duplicate_qp_right_answers"] == f["duplicate_qp_backends"]
    assert f["duplicate_max_acceleration_error"] <= _REDUNDANT_EXACT
    assert f["duplicate_max_multiplier_error"] <= _REDUNDANT_EXACT
    assert f["duplicate_least_norm_vs_pinv"] <= 1e-14  # λ_min·(1, 2)/5 is numpy's least-norm solution
    assert f["duplicate_cosine_min"] <= 1e-15  # the margin of a rank-deficient J is 0
    # B. on the manifold: direct always the clear error, every QP step the minimal model's answer
    assert f["manifold_direct_clear_errors"] == f["manifold_states"]
    assert f["manifold_default_qp_answers"] == f["manifold_states"]
    assert f["manifold_qp_backend_steps"] >= 4 * f["duplicate_qp_backends"]
    assert f["manifold_qp_answers"] == f["manifold_qp_steps"] and f["unclear_manifold_outcomes"] == 0
    assert f["manifold_max_error"] <= _REDUNDANT_EXACT and f["manifold_max_multiplier_error"] <= _REDUNDANT_EXACT
    # C. off the manifold by δ: every answer is the minimal model's at the same state, within 1e-12 + 2δ (measured
    # ≤ 0.88·δ), and direct always refuses; no wrong answer anywhere
    assert f["wrong_answers"] == 0 and f["non_project_exceptions"] == 0
    assert f["off_manifold_qp_steps"] == f["off_manifold_states"] * f["duplicate_qp_backends"]
    answered_or_refused = f["off_manifold_qp_answers"] + f["off_manifold_approximate_refusals"]
    assert answered_or_refused + f["off_manifold_qp_errors"] == f["off_manifold_qp_steps"]
    assert f["off_manifold_error_over_drift"] <= redundant.OFF_PER_DRIFT
    assert f["off_manifold_direct_refusals"] == f["off_manifold_states"]
    # D. contradicting rows: the speeds (same row, different right-hand sides) always raise
    assert f["contradiction_realizability_errors"] >= f["contradiction_steps"] / 2
    # E. simulate: solver='direct' fails naming the redundancy; solver='qp' follows the minimal model (the compiled
    # integrator refuses, naming the redundancy)
    assert f["simulate_redundancy_named"] == f["simulate_runs"]
    assert f["simulate_compiled_qp_refusals"] == 1 and f["simulate_qp_runs"] == f["simulate_runs"] - 1
    assert f["simulate_qp_followed_minimal"] == f["simulate_qp_runs"]
    # the verdict is the absence of problems; each problem quotes a reproduction
    assert c.verdict == (not c.problems) and all("Repro" in p or "simulate" in p for p in c.problems)


def test_redundant_case_has_no_problems(cases: dict[str, Case]) -> None:
    c = cases["redundant constraints"]
    assert c.figures["off_manifold_qp_errors"] == 0, c.problems
    assert c.figures["off_manifold_direct_errors_naming_constraints"] == c.figures["off_manifold_states"]
    assert c.figures["contradiction_realizability_errors"] == c.figures["contradiction_steps"]
    assert c.verdict and not c.problems


def test_only_an_approximate_backend_may_refuse_redundant_rows_and_it_names_the_exact_ones() -> None:
    """No backend is swapped for another (issue 16): HiGHS (declared ~1e-7 accurate) may refuse a nearly singular
    redundant step — clearly, naming the exact backends — where the accurate ones return the minimal model's answer."""
    scene, m = redundant.pendulum_with_distance()
    q, v = redundant.pendulum_state(0.7, 1.3, 1e-6)
    ref = scene.model.step(0.0, q, v, solver="direct").a
    for backend in ("qpsolvers:daqp", "casadi:qrqp"):
        if backend in gp.qp.names():
            assert np.max(np.abs(m.step(0.0, q, v, backend=backend).a - ref)) <= redundant.off_tol(1e-6) * np.max(
                np.abs(ref)
            )
    if "casadi:highs" in gp.qp.names():
        try:
            a = m.step(0.0, q, v, backend="casadi:highs").a
        except (gp.QPSolveError, gp.RealizabilityError) as exc:
            assert "try another backend" in str(exc) and "daqp" in str(exc)
        else:
            assert np.max(np.abs(a - ref)) <= redundant.off_tol(1e-6) * np.max(np.abs(ref))


def test_redundant_exact_duplicates_direct_raises_a_clear_realizability_error() -> None:
    _, doubled = redundant.circle_twice()
    q, v = redundant.circle_state()
    with pytest.raises(
        gp.RealizabilityError,
        match=r"'circle', 'circle again'.*margin.*redundant.*solver='qp' returns the unique acceleration and "
        r"the least-norm multiplier",
    ) as info:
        doubled.step(0.0, q, v, solver="direct")
    assert info.value.t == 0.0 and info.value.margin < 1e-15


def test_redundant_circle_twice_least_norm_multiplier_is_lambda_min_times_1_2_over_5() -> None:
    # D = [d, 2d] with d the minimal model's column: D u = d (u₁ + 2u₂) = d λ_min, least norm at u ∥ (1, 2)
    minimal, doubled = redundant.circle_twice()
    q, v = redundant.circle_state()
    d_min, d_two = minimal.step_data(0.0, q, v).D, doubled.step_data(0.0, q, v).D
    np.testing.assert_allclose(d_two, np.hstack([d_min, 2.0 * d_min]), rtol=1e-15, atol=0.0)
    ref = minimal.step(0.0, q, v, solver="direct")
    derived = ref.u[0] * np.array([1.0, 2.0]) / 5.0
    pinv = redundant.least_norm_multiplier(doubled, q, v, ref.a)
    np.testing.assert_allclose(pinv, derived, rtol=1e-14, atol=0.0)
    lstsq = np.linalg.lstsq(d_two, d_min[:, 0] * ref.u[0], rcond=None)[0]
    np.testing.assert_allclose(lstsq, derived, rtol=1e-14, atol=0.0)


@pytest.mark.parametrize("backend", _qp_backend_params())
def test_redundant_exact_duplicates_qp_answers_the_minimal_acceleration_and_least_norm_multiplier(
    backend: str | None,
) -> None:
    minimal, doubled = redundant.circle_twice()
    q, v = redundant.circle_state()
    ref = minimal.step(0.0, q, v, solver="direct")
    with warnings.catch_warnings(), stability.common.quiet_c_output():
        warnings.simplefilter("ignore")  # Clarabel warns about its own numerical error
        res = doubled.step(0.0, q, v, solver="qp", backend=backend)
    assert res.solver.startswith("gauss-qp:"), res.solver
    assert np.max(np.abs(res.a - ref.a)) <= _REDUNDANT_EXACT * np.max(np.abs(ref.a))
    least_norm = ref.u[0] * np.array([1.0, 2.0]) / 5.0
    assert np.max(np.abs(res.u - least_norm)) <= _REDUNDANT_EXACT * np.max(np.abs(least_norm)), res.u
    np.testing.assert_allclose(res.reaction, ref.reaction, rtol=_REDUNDANT_EXACT, atol=1e-12)
    assert res.margin <= 1e-15  # the step is singular and says so


def test_redundant_verdict_fails_on_a_wrong_qp_answer(monkeypatch: pytest.MonkeyPatch) -> None:
    """Negative control of the case's ✓ (test_redundant_case_has_no_problems): with the QP step's acceleration
    off by 1e-6 (relative) the case finds answers different from the minimal model's and says ✗, naming them."""
    from dataclasses import replace as _replace

    original = gp.Model.step

    def off(self: gp.Model, *args: object, **kwargs: object) -> object:
        res = original(self, *args, **kwargs)  # type: ignore[arg-type]
        if kwargs.get("solver", "qp") != "direct":
            res = _replace(res, a=res.a * (1 + 1e-6))
        return res

    monkeypatch.setattr(gp.Model, "step", off)
    c = redundant.case(quick=True)
    assert not c.verdict and any("different from the minimal model's" in p for p in c.problems), c.problems


def _off_manifold_tolerance(drift: float) -> float:
    return redundant.OFF_FLOOR + redundant.OFF_PER_DRIFT * drift


def test_redundant_constraints_off_the_manifold_qp_gives_the_minimal_acceleration() -> None:
    """Default QP: the minimal model's acceleration at the same state, within 1e-12 + 2δ (measured ≤ 0.88·δ, round-off
    where the rows are exactly dependent); direct refuses, pointing to solver='qp'."""
    scene, model = redundant.pendulum_with_distance()
    for phi in (0.7, 0.0, -2.0):  # φ = 0: the rows stay dependent off the manifold
        for stretch in (0.0, 1e-10, 1e-8, 2e-8, 3e-8, 1e-6, 1e-4, 1e-2):  # on the manifold, and drifts off it
            q, v = redundant.pendulum_state(phi, 1.3, stretch=stretch)
            ref = scene.model.step(0.0, q, v, solver="direct").a
            with pytest.raises(gp.RealizabilityError, match=r"redundant.*solver='qp'"):
                model.step(0.0, q, v, solver="direct")
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                res = model.step(0.0, q, v, solver="qp")
            assert not _realizability_warned(caught), (phi, stretch)
            err = np.max(np.abs(res.a - ref)) / np.max(np.abs(ref))
            assert err <= (_REDUNDANT_EXACT if stretch == 0.0 else _off_manifold_tolerance(stretch)), (phi, stretch)


def test_redundant_constraints_on_the_manifold_direct_raises_and_qp_answers() -> None:
    scene, model = redundant.pendulum_with_distance()
    for phi in (0.0, 0.3, 0.7, 2.5):  # formerly decided by round-off: errors at some angles, answers at others
        q, v = redundant.pendulum_state(phi, 1.3)
        with pytest.raises(gp.RealizabilityError, match=r"'pin-x', 'pin-z', 'distance'.*redundant.*solver='qp'"):
            model.step(0.0, q, v, solver="direct")
        ref = scene.model.step(0.0, q, v, solver="direct")
        res = model.step(0.0, q, v, solver="qp")
        assert res.solver.startswith("gauss-qp:")
        assert np.max(np.abs(res.a - ref.a)) <= _REDUNDANT_EXACT * np.max(np.abs(ref.a)), phi
        least_norm = redundant.least_norm_multiplier(model, q, v, ref.a)
        assert np.max(np.abs(res.u - least_norm)) <= _REDUNDANT_EXACT * np.max(np.abs(least_norm)), phi


@pytest.mark.parametrize("backend", _qp_backend_params())
def test_redundant_rows_that_contradict_each_other_raise(backend: str | None) -> None:
    """``v₁ − v₀ = 0`` and ``v₁ − v₀ − t = 0``: the same row, acceleration-level right-hand sides 0 and 1."""
    models = redundant.contradicting_models()
    for name in ("speeds at t = 0", "speeds at t = 0.5"):
        model, q, v, t = models[name]
        with pytest.raises(gp.RealizabilityError, match=r"'equal speeds', 'speeds apart'.*redundant.*solver='qp'"):
            model.step(t, q, v, solver="direct")
        with warnings.catch_warnings(), stability.common.quiet_c_output():
            warnings.simplefilter("ignore")  # Clarabel warns about its own numerical error
            with pytest.raises(gp.RealizabilityError, match=r"dependent and contradict each other") as info:
                model.step(t, q, v, solver="qp", backend=backend)
        assert info.value.t == t and "equal speeds" in info.value.constraint + str(info.value)


def test_redundant_positions_that_contradict_each_other_raise() -> None:
    model, q, v, t = redundant.contradicting_models()["positions at x = 0.25"]
    with pytest.raises(gp.RealizabilityError, match=r"'x at 0', 'x at 0.5'.*redundant"):
        model.step(t, q, v, solver="direct")
    try:
        res = model.step(t, q, v, solver="qp")
    except gp.RealizabilityError as exc:
        assert "contradict" in str(exc)
    else:
        raise AssertionError(f"x = 0 and x = 0.5 at x = 0.25: answered a = {res.a}")


def test_redundant_nearly_dependent_rows_qp_answers_the_minimal_model() -> None:
    """φ = 0.7, 1e-6 off the manifold: the three rows are independent there (margin ∝ δ²) — the QP keeps the pins
    (decided on the manifold) and answers the minimal model's acceleration; direct refuses the redundant rows."""
    scene, model = redundant.pendulum_with_distance()
    q, v = redundant.pendulum_state(0.7, 1.3, stretch=1e-6)
    with pytest.raises(gp.RealizabilityError, match=r"redundant.*solver='qp'") as info:
        model.step(0.0, q, v, solver="direct")
    assert all(name in info.value.constraint for name in ("pin-x", "pin-z", "distance"))
    ref = scene.model.step(0.0, q, v, solver="direct").a
    res = model.step(0.0, q, v, solver="qp")
    assert res.solver.startswith("gauss-qp:")
    assert np.max(np.abs(res.a - ref)) <= _off_manifold_tolerance(1e-6) * np.max(np.abs(ref))


def test_redundant_constraints_simulate_direct_refuses_and_qp_follows_the_minimal_model() -> None:
    scene, model = redundant.pendulum_with_distance()
    for method, lane in (("rk4", "python"), ("rk4", "compiled"), ("DOP853", None)):
        with pytest.raises(gp.RealizabilityError, match=r"redundant"):
            options = dict(dt=0.01, method=method, lane=lane, solver="direct", stabilize="project")
            gp.simulate(model, scene.q0, scene.v0, 1.0, **options)
    q, v = redundant.pendulum_state(0.0, 0.0, stretch=1e-3)  # off the manifold: the projection needs the QP's rows
    with pytest.raises(gp.InitialDataError, match=r"projecting .* failed .*redundant"):
        gp.simulate(model, q, v, 1.0, dt=0.01, solver="direct", stabilize="project")
    traj = gp.simulate(model, q, v, 0.5, dt=0.01, stabilize="project")
    ref = gp.simulate(scene.model, q, v, 0.5, dt=0.01, stabilize="project")
    assert traj.success and traj.q.shape == ref.q.shape
    assert np.max(np.abs(traj.q - ref.q)) <= 1e-8  # measured 1e-10 (relative, over 1 s)
    with pytest.raises(gp.InputError, match=r"redundant"):  # the compiled integrator has no general QP
        gp.simulate(model, scene.q0, scene.v0, 1.0, dt=0.01, method="rk4", lane="compiled", stabilize="project")


# -- 6. initial data off the constraint -------------------------------------------------------------
def test_off_constraint_errors_name_the_constraint(cases: dict[str, Case]) -> None:
    f = cases["initial data off the constraint"].figures
    assert f["setups"] == 8
    assert f["named_errors"] == f["setups"]
    assert f["projected_near"] == 5  # all but the far and the singular crane
    # the vertical rope (NaN), g = 5 (no convergence) and g = 0.3 (Newton's distant root, refused)
    assert f["projection_refused_clearly"] == 3 and f["projected_far"] == 0
    assert f["projected_near"] + f["projection_refused_clearly"] + f["projected_far"] == f["setups"]


def test_off_constraint_pendulum_error_and_projection() -> None:
    s = gp.scenes.get("pendulum")
    q0 = s.q0 + np.array([1e-3, 0.0, 0.0])
    with pytest.raises(gp.InitialDataError, match=r"off the constraint 'pin-x' at t=0: g\(q, t\) = 0\.001"):
        gp.simulate(s.model, q0, s.v0, 0.05, dt=0.01)
    traj = gp.simulate(s.model, q0, s.v0, 0.05, dt=0.01, stabilize="project")
    assert max(np.abs(traj.g[0]).max(), np.abs(traj.residual[0]).max()) <= 1e-12


def test_off_constraint_projection_reaches_the_crane_constraint() -> None:
    c = gp.scenes.get("crane", M0=1.0, m=0.5, L=1.0)
    for offset in (1e-3, 1e-2):  # was: 3 Newton steps without a convergence check left g ≠ 0 at 1e-2
        traj = gp.simulate(c.model, c.q0 + np.array([offset, 0.0]), c.v0, 0.05, dt=0.01, stabilize="project")
        assert max(np.abs(traj.g[0]).max(), np.abs(traj.residual[0]).max()) <= 1e-12
        assert np.max(np.abs(traj.q[0] - c.q0)) < 1.0


def test_off_constraint_projection_fails_clearly_where_it_cannot_converge() -> None:
    c = gp.scenes.get("crane", M0=1.0, m=0.5, L=1.0)
    with pytest.raises(gp.InitialDataError, match=r"projecting .* failed at t=0 \(NaN\)") as info:
        gp.simulate(c.model, [1e-3, 0.0], [0.0, 0.0], 0.05, dt=0.01, stabilize="project")  # the vertical rope
    assert "stabilize='project'" not in str(info.value)  # it does not advise what the caller did
    with pytest.raises(gp.InitialDataError, match=r"did not converge in 50 Newton steps"):
        gp.simulate(c.model, c.q0 + np.array([5.0, 0.0]), c.v0, 0.05, dt=0.01, stabilize="project")


def test_off_constraint_verdict(cases: dict[str, Case]) -> None:
    assert cases["initial data off the constraint"].verdict, cases["initial data off the constraint"].observed


def test_off_constraint_projection_stays_near_the_data_or_fails() -> None:
    c = gp.scenes.get("crane", M0=1.0, m=0.5, L=1.0)
    q0 = c.q0 + np.array([0.3, 0.0])
    try:
        traj = gp.simulate(c.model, q0, c.v0, 0.05, dt=0.01, stabilize="project")
    except gp.InitialDataError:
        return  # failing clearly is right too
    # the first Newton step is 3.4 long; a backtracking Newton lands at (−0.96, 1.31), 1.6 away
    assert np.max(np.abs(traj.q[0] - q0)) <= 10 * 3.4, traj.q[0]


# -- 7. crane near the vertical rope --------------------------------------------------------------
def test_crane_vertical_step_level_and_adaptive_methods(cases: dict[str, Case]) -> None:
    f = cases["crane near the vertical rope"].figures
    assert f["step_margin_vs_closed_form"] <= 1e-6
    assert f["step_warnings_correct"] == 7 and f["vertical_errors"] == 2
    # the adaptive lanes warn and stop at t* without keeping a sample beyond it
    for run in ("rk45", "dop853_margin_error_1e_9", "radau"):
        assert f[f"{run}_ok"] == 1.0 and f[f"{run}_warned"] == 1.0, run
        assert abs(f[f"{run}_error_time"] - f["t_star"]) <= 1e-4
    # cvodes (was: a 100 s stall, then a bare GaussppError and nothing kept) stops within the recorded sample
    # before t*, keeps that prefix, and names the small margin
    assert f["cvodes_ok"] == 1.0 and f["cvodes_samples_beyond_t_star"] == 0
    assert 0 <= f["t_star"] - f["cvodes_error_time"] <= 2e-3


def test_crane_cvodes_fails_quickly_with_an_integration_error() -> None:
    f = crane.free_fall()
    traj = gp.simulate(
        f.model, f.q0, f.v0, f.t_end, method="cvodes", solver="direct", record=[0.05, 0.09, 0.1, 0.2], throw=False
    )
    assert traj.status == "failed" and traj.message.startswith(
        "IntegrationError: CVODES stopped between t=0.09 and t=0.1"
    )
    assert "margin" in traj.message
    assert list(traj.t) == [0.0, 0.05, 0.09]  # the prefix is kept


def test_crane_vertical_verdict(cases: dict[str, Case]) -> None:
    assert cases["crane near the vertical rope"].verdict, cases["crane near the vertical rope"].observed


def test_crane_fixed_step_rk4_warns_and_stops_at_the_vertical_rope() -> None:
    """The sampled margin stays above 1e-6 until the step past t*; the dip of its parabola between samples
    both warns (the margin falls below margin_warn there) and stops the run."""
    s = gp.scenes.get("crane", M0=1.0, m=0.5, L=1.0, theta0=-0.3, accel=0.0, distance=0.0, t_end=0.2)
    t_star = math.sqrt(2 * (1 - math.cos(0.3)) / 9.81)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        traj = gp.simulate(s.model, s.q0, s.v0, 0.2, dt=1e-3, method="rk4", solver="direct", throw=False)
    assert traj.status == "failed"
    assert _realizability_warned(caught), "no warning"
    assert np.all(traj.t <= t_star), "samples beyond the vertical rope"


def test_crane_failure_hint_reaches_the_raised_exception() -> None:
    f = crane.free_fall()
    with warnings.catch_warnings(), pytest.raises(gp.RealizabilityError) as info:
        warnings.simplefilter("ignore")
        gp.simulate(f.model, f.q0, f.v0, f.t_end, dt=1e-3, method="rk4", solver="direct")
    # the raised exception and the kept trajectory both name the margin as the cause
    assert "margin reaches zero between" in str(info.value)
    assert "margin reaches zero between" in info.value.trajectory.message  # type: ignore[attr-defined]


@pytest.mark.slow
def test_full_study() -> None:
    """The whole study at full size (1e6 steps, every lane through the vertical rope): every case runs, is judged."""
    result = stability.run(quick=False)
    print()
    print(stability.table(result))
    print("seconds per case:", {c.name: round(c.figures["seconds"], 1) for c in result})
    assert len(result) == 7 and all("crashed" not in c.figures for c in result)
