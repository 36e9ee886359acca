"""The general Gauss QP (gausspp.step.general) and the model features built on it: errors and edge cases."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.errors import BackendUnavailableError
from gausspp.step.general import GaussProblem, check_backend, default_backend, solve_general

BACKENDS = ["daqp", "osqp", "casadi:qrqp"]


def _problem(**changes: object) -> GaussProblem:
    A = np.diag([1.0, 2.0, 3.0])
    J = np.array([[1.0, 1.0, 0.0]])
    data = dict(
        A=A,
        a0=np.array([0.0, -1.0, 0.5]),
        D=J.T,
        J=J,
        phi=np.array([0.3]),
        role=["eq"],
        lower=np.array([-np.inf]),
        upper=np.array([np.inf]),
    )
    data.update(changes)
    return GaussProblem(**data)  # type: ignore[arg-type]


def test_problem_shapes_and_values_are_checked() -> None:
    with pytest.raises(gp.ShapeError, match="phi has shape"):
        _problem(phi=np.zeros(2))
    with pytest.raises(gp.ShapeError, match="role needs one of"):
        _problem(role=["equal"])
    with pytest.raises(gp.NonFiniteError, match="a0 is not finite"):
        _problem(a0=np.array([0.0, np.nan, 0.0]))
    with pytest.raises(gp.ShapeError, match="lower bound exceeds"):
        _problem(lower=np.array([1.0]), upper=np.array([0.0]))


@pytest.mark.parametrize("backend", BACKENDS)
def test_mass_matrix_that_is_not_positive_definite(backend: str) -> None:
    with pytest.raises(gp.NotPositiveDefiniteError, match="not positive definite at t=0.5"):
        solve_general(_problem(A=np.diag([1.0, -2.0, 3.0]), t=0.5), backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_realization_that_cannot_keep_its_constraint(backend: str) -> None:
    # force along the third axis, constraint on the first two: J A⁻¹ D = 0 (condition (12) fails)
    with pytest.raises(gp.RealizabilityError, match=r"cannot keep the constraint.*rank 0 < rank J = 1") as info:
        solve_general(_problem(D=np.array([[0.0], [0.0], [1.0]]), rows=["servo"], t=2.0), backend)
    assert info.value.t == 2.0 and info.value.constraint == "servo"


@pytest.mark.parametrize("backend", BACKENDS)
def test_dependent_rows_that_contradict_each_other(backend: str) -> None:
    J = np.array([[1.0, 1.0, 0.0], [2.0, 2.0, 0.0]])
    p = _problem(
        J=J, D=J.T, phi=np.array([0.3, 0.7]), role=["eq", "eq"], lower=np.full(2, -np.inf), upper=np.full(2, np.inf)
    )
    with pytest.raises(gp.RealizabilityError, match="dependent and contradict each other"):
        solve_general(p, backend)
    consistent = solve_general(
        _problem(
            J=J, D=J.T, phi=np.array([0.3, 0.6]), role=["eq", "eq"], lower=np.full(2, -np.inf), upper=np.full(2, np.inf)
        ),
        backend,
    )
    single = solve_general(_problem(), backend)
    assert consistent.redundant_rows == 1 and np.allclose(consistent.a, single.a, atol=1e-14)
    assert consistent.u == pytest.approx(single.u[0] * np.array([1.0, 2.0]) / 5.0, abs=1e-12)  # least norm


@pytest.mark.parametrize("backend", BACKENDS)
def test_contacts_that_cannot_all_hold_are_a_clear_qp_error(backend: str) -> None:
    # an equality a₁ + a₂ = 0.3 with both accelerations pushed ≥ 1 by "contacts" with no force: infeasible
    J = np.array([[1.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    D = np.array([[1.0, 1.0, 0.0]]).T
    p = _problem(J=J, D=D, phi=np.array([0.3, 1.0, 1.0]), role=["eq", "ge", "ge"])
    with pytest.raises(gp.QPSolveError, match=r"contradict each other|violates"):
        solve_general(p, backend)


def test_backend_names() -> None:
    """A name means one backend on every path (the registry's): no swap, a bare name by the registry's rule."""
    assert check_backend(None) == default_backend() == "qrqp"  # casadi's, compiled into the general step
    assert check_backend("qpsolvers:osqp") == "osqp" and check_backend("casadi:osqp") == "casadi:osqp"
    # the compiled default is not swapped for another solver; its short name is the bare one (qpsolvers has no qrqp)
    assert check_backend("casadi:qrqp") == check_backend("qrqp") == "qrqp"
    with pytest.raises(
        gp.UnknownNameError, match=r"QP backend 'gurobix' is unknown; valid names here: \[.*casadi:qrqp"
    ):
        check_backend("gurobix")


def _point() -> gp.Lagrangian:
    return gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), V=lambda q, t: 9.81 * q[1])


def _servo(**force: object) -> gp.Model:
    realization = gp.Force(lambda q, v, t: [0, 1], **force)  # type: ignore[arg-type]
    return gp.Model(_point(), [gp.Holonomic(lambda q, t: q[1] - ca.sin(t), name="track", realization=realization)])


def test_force_bounds_are_checked() -> None:
    with pytest.raises(gp.InputError, match=r"bounds must be a pair"):
        gp.Force(lambda q, v, t: [0, 1], bounds=5.0)
    with pytest.raises(gp.NonFiniteError, match="bounds contain NaN"):
        gp.Force(lambda q, v, t: [0, 1], bounds=(np.nan, 1.0))
    with pytest.raises(gp.InputError, match="lower bound exceeds"):
        _servo(bounds=(2.0, 1.0))
    with pytest.raises(gp.ShapeError, match="1 or 1 entries"):
        _servo(bounds=([-1.0, -2.0], 1.0))
    with pytest.raises(gp.ShapeError, match="fewer actuators than constraint rows"):
        gp.Model(_point(), [gp.Holonomic(lambda q, t: q, name="both", realization=gp.Force(lambda q, v, t: [0, 1]))])


@pytest.mark.parametrize("backend", BACKENDS)
def test_bounded_servo_saturates_exactly_when_its_force_would_exceed_the_bound(backend: str) -> None:
    model = _servo(bounds=(-9.5, 9.5))
    for t in np.linspace(0.0, 6.0, 25):
        q, v = [0.0, np.sin(t)], [0.0, np.cos(t)]
        needed = 9.81 - np.sin(t)  # ÿ = −sin t = −g + λ
        res = model.step(t, q, v, backend=backend)
        if needed > 9.5 + 1e-9:
            assert res.saturated[0] and res.u[0] == pytest.approx(9.5, abs=1e-9)
            assert res.tracking_error == pytest.approx(needed - 9.5, rel=1e-8)  # one row: |J a − φ| / |J|_A⁻¹
        elif needed < 9.5 - 1e-9:
            assert not res.saturated[0] and res.tracking_error == 0.0
            assert res.u[0] == pytest.approx(needed, abs=1e-9) and np.max(np.abs(res.residual)) <= 1e-12


def test_bounded_models_refuse_the_direct_and_compiled_routes() -> None:
    model = _servo(bounds=(-9.5, 9.5))
    with pytest.raises(gp.InputError, match="solver='qp'"):
        model.step(0.0, [0, 0], [0, 1], solver="direct")
    with pytest.raises(gp.InputError, match="solver='qp'"):
        gp.simulate(model, [0, 0], [0, 1], 1.0, dt=0.01, solver="direct")
    with pytest.raises(gp.InputError, match="the compiled lane cannot run .* bounded actuators.*lane='python'"):
        gp.simulate(model, [0, 0], [0, 1], 1.0, dt=0.01, method="rk4", lane="compiled")


def test_bounded_simulation_records_saturation_and_keeps_the_bound() -> None:
    model = _servo(bounds=(-9.5, 9.5))
    traj = gp.simulate(model, [0, 0], [0, 1], 6.0, dt=0.01, stabilize="baumgarte")
    assert traj.success and np.all(np.abs(traj.u) <= 9.5 + 1e-12)
    assert traj.saturated.any() and not traj.saturated.all()
    assert np.all((traj.tracking_error > 0) == traj.saturated[:, 0])
    assert traj.solver == f"gauss-qp:{default_backend()}"


@pytest.mark.parametrize("backend", BACKENDS)
def test_over_actuated_step_is_the_least_compulsion_allocation(backend: str) -> None:
    rows = [[0.0, 1.0], [1.0, 1.0]]
    realization = gp.Force(lambda q, v, t: rows)
    model = gp.Model(_point(), [gp.Holonomic(lambda q, t: q[1] - ca.sin(t), name="track", realization=realization)])
    res = model.step(1.0, [0.0, np.sin(1.0)], [0.0, np.cos(1.0)], backend=backend)
    # the pure vertical thruster does it alone: the slanted one would push x too, adding compulsion
    assert res.u == pytest.approx([9.81 - np.sin(1.0), 0.0], abs=1e-9)
    with pytest.raises(gp.InputError, match="solver='qp'"):
        model.step(1.0, [0.0, np.sin(1.0)], [0.0, np.cos(1.0)], solver="direct")


def test_verify_tells_the_least_compulsion_allocation_from_another_one() -> None:
    """(23) for an over-actuated servo uses the k relations S H⁻¹ M δx = 0 of the least-compulsion reaction:
    the drone's own motion passes; a motion where a capped rotor forces another allocation does not."""
    free = gp.scenes.get("two-actuator-servo")
    capped = gp.scenes.get("two-actuator-servo", f_max=(5.5, 100.0))  # the lever rule asks rotor 1 for ≈ 5.9
    record = np.linspace(0.0, 0.4, 401)
    own = gp.simulate(free.model, free.q0, free.v0, 0.4, method="DOP853", rtol=1e-12, atol=1e-14, record=record)
    other = gp.simulate(capped.model, capped.q0, capped.v0, 0.4, method="DOP853", rtol=1e-12, atol=1e-14, record=record)
    assert other.saturated[:, 0].any() and other.tracking_error.max() == 0.0  # reallocated, constraint kept
    assert other.max_residual() <= 1e-12
    assert gp.verify(free.model, own).is_motion
    check = gp.verify(free.model, other)
    assert not check.is_motion and check.relative_gap > 5 * check.tolerance


# -- one registry: casadi:qrqp on inequalities, unknown / uninstalled / unable backends -----------------------------


def _scene_state(name: str, **params: object) -> tuple[gp.Model, float, np.ndarray, np.ndarray]:
    scene = gp.scenes.get(name, **params)
    return scene.model, 0.0, np.asarray(scene.q0, float), np.asarray(scene.v0, float)


@pytest.mark.parametrize(
    "name, params",
    [("saturated-crane", {}), ("two-actuator-servo", {"f_max": 5.0}), ("block-on-floor", {"drop": 0.0})],
)
def test_casadi_qrqp_solves_the_general_step_as_daqp_does(name: str, params: dict[str, object]) -> None:
    """``backend="casadi:qrqp"`` on a model with bounds or contacts: casadi's conic with lba/uba/lbx/ubx, through
    the same feasibility and dual-residual checks; the answer is daqp's (the backend really is qrqp: no swap)."""
    model, t, q, v = _scene_state(name, **params)
    ours = model.step(t, q, v, backend="casadi:qrqp")
    reference = model.step(t, q, v, backend="qpsolvers:daqp")
    assert ours.solver == "gauss-qp:qrqp" and reference.solver == "gauss-qp:daqp"
    scale = 1.0 + np.max(np.abs(reference.a))
    assert np.max(np.abs(ours.a - reference.a)) <= 1e-9 * scale
    for force in ("u", "contact_force"):
        mine, theirs = getattr(ours, force), getattr(reference, force)
        assert np.max(np.abs(mine - theirs), initial=0.0) <= 1e-9 * (1.0 + np.max(np.abs(theirs), initial=0.0))


def test_casadi_qrqp_on_a_saturated_step() -> None:
    """The bounded servo of this module past its bound: qrqp tracks, saturates and agrees with daqp."""
    model = _servo(bounds=(-9.5, 9.5))
    t = 3 * np.pi / 2  # needed force 9.81 + 1 > 9.5
    q, v = [0.0, np.sin(t)], [0.0, np.cos(t)]
    ours, (ref, _) = model.step(t, q, v, backend="casadi:qrqp"), model.general_step(t, q, v, backend="daqp")
    assert ours.saturated[0] and ours.u[0] == 9.5
    assert ours.tracking_error == pytest.approx(ref.tracking_error, rel=1e-9)


def test_contacts_with_casadi_qrqp_in_the_general_problem() -> None:
    """A point on a floor pushed down (contact row ``ge``), solved by every casadi plugin that loads here: the
    active-set ones and polished OSQP to 1e-9, the interior-point and proximal ones to their own accuracy."""
    A, D = np.eye(2), np.array([[0.0], [1.0]])
    p = GaussProblem(
        A=A,
        a0=np.array([1.0, -9.81]),
        D=D,
        J=D.T,
        phi=np.zeros(1),
        role=["ge"],
        lower=np.zeros(1),
        upper=np.full(1, np.inf),
    )
    exact = solve_general(p, "daqp")
    for name in (n for n in gp.qp.names() if n.startswith("casadi:")):
        sol = solve_general(p, name)
        tol = 1e-9 if name in ("casadi:qrqp", "casadi:daqp", "casadi:qpoases", "casadi:osqp") else 1e-6
        assert sol.u == pytest.approx([9.81], rel=tol) and sol.a == pytest.approx(exact.a, abs=tol * 9.81), name


def test_casadi_answers_face_the_dual_residual_check(monkeypatch: pytest.MonkeyPatch) -> None:
    """A casadi answer that is feasible but not optimal is refused, as a qpsolvers one is (DUAL_TOL)."""
    from gausspp.step.qp import CasadiConic, QPAnswer

    real = CasadiConic.solve_qp

    def off_optimum(self: CasadiConic, problem):  # type: ignore[no-untyped-def]
        answer = real(self, problem)
        return QPAnswer(answer.x, dual=1e-3, found=True)

    monkeypatch.setattr(CasadiConic, "solve_qp", off_optimum)
    p = _problem(D=np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]), lower=np.full(2, -5.0), upper=np.full(2, 5.0))
    with pytest.raises(gp.QPSolveError, match=r"qrqp returned a point that is not optimal.*dual residual"):
        solve_general(p, "casadi:qrqp")


def test_unknown_backend_lists_the_names() -> None:
    model = _servo(bounds=(-9.5, 9.5))
    with pytest.raises(gp.UnknownNameError, match=r"QP backend 'casadi:nosuch' is unknown; valid names here: \["):
        model.step(0.0, [0, 0], [0, 1], backend="casadi:nosuch")
    with pytest.raises(gp.UnknownNameError, match=r"QP backend 'nosuch' is unknown"):
        solve_general(_problem(), "nosuch")


def test_an_uninstalled_backend_is_an_error_not_a_swap(monkeypatch: pytest.MonkeyPatch) -> None:
    """Availability monkeypatched: a known solver that is not installed raises, naming what to install."""
    import gausspp.step.qp as registry
    from gausspp.step.qp import qpsolvers_backend

    monkeypatch.setattr(qpsolvers_backend, "available", lambda: ["osqp"])
    monkeypatch.setattr(registry, "plugin_available", lambda plugin: plugin == "proxqp")
    registry._make.cache_clear()
    try:
        with pytest.raises(BackendUnavailableError, match=r"'qpsolvers:daqp'.*no solver 'daqp' installed"):
            solve_general(_problem(), "qpsolvers:daqp")
        with pytest.raises(BackendUnavailableError, match=r"'casadi:osqp'.*cannot load the conic plugin 'osqp'"):
            _servo(bounds=(-9.5, 9.5)).step(0.0, [0, 0], [0, 1], backend="casadi:osqp")
        assert (
            check_backend(None) == "osqp"
        )  # the general default: neither qrqp nor daqp here, so OSQP (declared order)
    finally:
        registry._make.cache_clear()


def test_a_backend_that_solves_the_equality_form_only_is_refused_by_name() -> None:
    """A user backend without the general form: a clear InputError naming the backends that do solve it."""

    class EqualityOnly(gp.qp.QPBackend):
        name = "mine:equality"

        def solve(self, H: np.ndarray, S: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            raise NotImplementedError

    bounded = _problem(lower=np.array([-1.0]), upper=np.array([1.0]))
    with pytest.raises(
        gp.InputError, match=r"'mine:equality' does not solve QPs with bounds; backends that do: \[.*qrqp"
    ):
        solve_general(bounded, EqualityOnly())
