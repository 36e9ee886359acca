"""The adaptive default compiled (gausspp.simulation.compiled_adaptive) against scipy's own solver at the same
tolerances: the same steps to round-off, the same states at the record times, the same failures."""

from __future__ import annotations

import re
import warnings
from typing import Any

import casadi as ca
import numpy as np
import pytest
import scipy.integrate as si

import gausspp as gp
from gausspp.simulation import compiled_adaptive
from gausspp.simulation.drift import Stabilization
from gausspp.simulation.initial import initial_state
from gausspp.simulation.rhs import RightHandSide, step_control_atol
from gausspp.step.bound import Bound

#: (scene, parameters, step solver): equality rows (direct and the QP in the graph), λ-states of an inertial
#: realization, a mixed realization, Andrews' squeezing mechanism (six rows).
CASES = [
    ("pendulum", {}, "direct"),
    ("pendulum", {}, "qp"),
    ("gyrostat", {}, "direct"),
    ("mixed-rate", {}, "qp"),
    ("andrews", {}, "direct"),
]


def _start(name: str, params: dict, solver: str) -> tuple[RightHandSide, np.ndarray, float]:
    scene = gp.scenes.get(name, **params)
    m = scene.model
    q, v, lam = initial_state(m, 0.0, scene.q0, scene.v0, None)
    return RightHandSide(m, solver, None, Stabilization()), np.concatenate([q, v, lam, [0.0, 0.0]]), scene.t_end


def _run(
    cls: type, rhs: RightHandSide, y0: np.ndarray, t_end: float, times: np.ndarray, atol: Any = 1e-10
) -> tuple[int, np.ndarray]:
    """Steps to ``t_end``; the states at ``times`` from each step's dense output."""
    solver = cls(rhs, 0.0, y0, t_end, rtol=1e-10, atol=atol)
    out, steps = np.empty((times.size, y0.size)), 0
    while solver.status == "running":
        t_old = solver.t
        solver.step()
        assert solver.status != "failed"
        steps += 1
        inside = (times > t_old) & (times <= solver.t)
        if inside.any():
            out[inside] = np.asarray(solver.dense_output()(times[inside])).T
    return steps, out


@pytest.mark.parametrize(("name", "params", "solver"), CASES)
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_each_compiled_step_is_scipys_step(name: str, params: dict, solver: str, method: str) -> None:
    """Along scipy's own run, every accepted step taken again by the compiled stages from the same ``(t, y, f, h)``:
    the new state and every stage to round-off of their size, the error norm to the round-off it carries (its
    estimate is a difference of nearly equal stages divided by ``atol + rtol|y|``)."""
    rhs, y0, t_end = _start(name, params, solver)
    assert compiled_adaptive.applies(method, rhs)
    ref = getattr(si, method)(rhs, 0.0, y0, min(t_end, 2.0), rtol=1e-10, atol=1e-10)
    new = compiled_adaptive.solver_class(method, rhs)(rhs, 0.0, y0, min(t_end, 2.0), rtol=1e-10, atol=1e-10)
    steps = 0
    while ref.status == "running":
        t, y, f = ref.t, ref.y.copy(), ref.f.copy()
        ref.step()
        h = ref.t - t
        y_new, f_new, error = new.stages(t, y, f, h)
        scale = ref.atol + np.maximum(np.abs(y), np.abs(ref.y)) * ref.rtol
        error_ref = ref._estimate_error_norm(ref.K, h, scale)
        assert np.abs(y_new - ref.y).max() <= 1e-13 * (1 + np.abs(ref.y).max())
        assert np.abs(new.K - ref.K).max() <= 1e-12 * (1 + np.abs(ref.K).max())
        assert abs(error - error_ref) <= 1e-3 * max(error_ref, 1e-2)
        steps += 1
    assert steps >= 5


@pytest.mark.parametrize(("name", "params", "solver"), CASES)
def test_whole_runs_agree_with_scipys_within_their_tolerance(name: str, params: dict, solver: str) -> None:
    """Whole DOP853 runs, compiled and scipy's, at 25 times: within ten times ``rtol`` of the state's size — the
    same method at the same tolerances (``benchmarks/peers.py`` prints the measured agreement, ~1e-13)."""
    rhs, y0, t_end = _start(name, params, solver)
    t_end = min(t_end, 2.0)
    times = np.linspace(0.0, t_end, 26)[1:]
    n_ref, ref = _run(si.DOP853, rhs, y0, t_end, times)
    n_new, new = _run(compiled_adaptive.solver_class("DOP853", rhs), rhs, y0, t_end, times)
    assert abs(n_new - n_ref) <= max(2, n_ref // 20)
    assert np.abs(new - ref).max() <= 10 * 1e-10 * (1 + np.abs(ref).max())


def test_a_wrong_tableau_is_told_apart(monkeypatch: pytest.MonkeyPatch) -> None:
    """The whole-run comparison catches compiled stages with one weight off by 1e-3 (a hundredfold beyond its
    tolerance): the negative control; the step comparison's tolerance is tighter still."""
    rhs, y0, _ = _start("pendulum", {}, "direct")
    times = np.linspace(0.0, 1.0, 11)[1:]
    _, ref = _run(si.DOP853, rhs, y0, 1.0, times)
    monkeypatch.setattr(si.DOP853, "B", si.DOP853.B * (1 + 1e-3 * (np.arange(12) == 5)))
    wrong_stages = compiled_adaptive._build(rhs.model, "DOP853", rhs.kernel)
    monkeypatch.undo()

    class Wrong(compiled_adaptive.CompiledDOP853):
        def setup(self, rhs: RightHandSide, method: str) -> None:
            super().setup(rhs, method)
            rtol, atol = self._bound.args[5][0], self._bound.args[6].copy()
            self._bound = Bound(wrong_stages)
            self._bound.args[5][0], self._bound.args[6][:] = rtol, atol

    _, wrong = _run(Wrong, rhs, y0, 1.0, times)
    assert np.abs(wrong - ref).max() > 100 * 10 * 1e-10 * (1 + np.abs(ref).max())


def test_simulate_takes_the_compiled_stages_and_gives_scipys_trajectory() -> None:
    """``gp.simulate``'s default lane at the record times, against scipy's DOP853 stepped from the same right-hand
    side; the evaluations are counted as scipy counts them (12 per DOP853 step)."""
    scene = gp.scenes.get("pendulum")
    times = np.linspace(0.0, 2.0, 21)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 2.0, record=times, rtol=1e-10, atol=1e-10, solver="direct")
    rhs, y0, _ = _start("pendulum", {}, "direct")
    _, ref = _run(si.DOP853, rhs, y0, 2.0, times[1:], step_control_atol(1e-10, y0.size))
    nq, nv = scene.model.nq, scene.model.nv
    assert np.abs(traj.q[1:] - ref[:, :nq]).max() <= 1e-12 * (1 + np.abs(ref).max())
    assert np.abs(traj.v[1:] - ref[:, nq : nq + nv]).max() <= 1e-12 * (1 + np.abs(ref).max())
    assert traj.rhs_evaluations >= 12 * traj.steps


def _failure_time(traj: gp.Trajectory) -> float:
    return float(re.search(r"at t=([0-9.]+)", traj.message).group(1))  # type: ignore[union-attr]


def test_a_stage_that_fails_hands_the_step_to_python_which_names_the_failure(monkeypatch: pytest.MonkeyPatch) -> None:
    """A mass matrix that stops being positive definite at t = 1: the compiled flag goes down, scipy's stages in
    Python raise the project error — the same error, at the same stage, as the scipy lane without compiled stages
    (a swinging coordinate, so that the error estimate is the motion's and not round-off: the same steps)."""
    body = gp.Lagrangian(
        n=2, T=lambda q, v, t: 0.5 * (1.0 - t) * v[0] ** 2 + 0.5 * v[1] ** 2, V=lambda q, t: 1 - ca.cos(q[1])
    )
    model = gp.Model(body, [gp.Holonomic(lambda q, t: q[0] - q[1], name="line")])
    traj = gp.simulate(model, [0.0, 0.0], [1.0, 1.0], 2.0, throw=False)
    assert traj.status == "failed"
    assert isinstance(traj.failure, gp.NotPositiveDefiniteError)
    assert _failure_time(traj) > 1.0 > traj.t[-1]
    monkeypatch.setattr(compiled_adaptive, "applies", lambda method, rhs: False)
    plain = gp.simulate(gp.Model(body, list(model.constraints)), [0.0, 0.0], [1.0, 1.0], 2.0, throw=False)
    assert type(plain.failure) is type(traj.failure)
    assert plain.t.size == traj.t.size  # the steps' times agree to the error norm's round-off, not bitwise
    # the same stage of the same step: the failure times agree as the steps do — the error estimate is a difference
    # of stages, its relative round-off ~1e-4 here (measured: the second step's lengths differ by 5e-5), far below
    # the 1e-2 of the failing step's length that another stage or another step would make
    failing_step = _failure_time(traj) - traj.t[-1]
    assert abs(_failure_time(plain) - _failure_time(traj)) <= 1e-2 * failing_step


def test_the_work_integrals_do_not_choose_the_step() -> None:
    """``W_R, W_F`` are quadratures: noise in the reaction's power (an ideal constraint's is round-off) leaves the
    steps of a run with :func:`step_control_atol` as they were; with one ``atol`` for the whole state (the negative
    control) the same noise changes them."""

    class Noisy(RightHandSide):
        def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
            out = super().__call__(t, y).copy()
            out[-2] += 1e-9 * np.sin(1e4 * t)  # a power of 1e-9 W, fast: an estimated error far above atol
            return out

    scene = gp.scenes.get("pendulum")
    q, v, lam = initial_state(scene.model, 0.0, scene.q0, scene.v0, None)
    y0 = np.concatenate([q, v, lam, [0.0, 0.0]])

    def steps(cls: type, atol: Any) -> list[float]:
        solver = si.DOP853(cls(scene.model, "direct", None, Stabilization()), 0.0, y0, 1.0, rtol=1e-9, atol=atol)
        ts = []
        while solver.status == "running":
            solver.step()
            ts.append(solver.t)
        return ts

    tol = step_control_atol(1e-12, y0.size)
    assert np.isinf(tol[-2:]).all() and (tol[:-2] == 1e-12).all()
    clean = steps(RightHandSide, tol)
    np.testing.assert_allclose(steps(Noisy, tol), clean, rtol=0, atol=1e-12)
    assert len(steps(Noisy, 1e-12)) > 2 * len(clean)


@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau"])
def test_a_solver_retargeted_stops_there_and_goes_on(method: str) -> None:
    """``retarget`` moves the end of a running solver (an approach of a singular position) and back: it stops
    exactly at the new end, goes on from there with its own step size, and ends where a plain run does
    (``y' = −y``: ``e⁻¹`` at 1 to the tolerance)."""
    assert issubclass(compiled_adaptive.CompiledDOP853, compiled_adaptive.Retargetable)  # the compiled ones too
    cls = compiled_adaptive._retargetable(getattr(si, method))
    solver = cls(lambda t, y: -y, 0.0, np.array([1.0]), 1.0, rtol=1e-10, atol=1e-12)
    solver.step()
    solver.retarget(0.5)
    while solver.status == "running":
        solver.step()
    assert solver.status == "finished" and solver.t == 0.5
    h_before = solver.step_size
    solver.retarget(1.0)
    assert solver.status == "running"
    while solver.status == "running":
        solver.step()
    assert solver.t == 1.0 and abs(solver.y[0] - np.exp(-1.0)) <= 1e-8
    assert h_before is not None and h_before > 0
    solver.retarget(0.75)  # behind it: nothing to do
    assert solver.status == "finished"


@pytest.mark.parametrize("name", ["four-bar-redundant", "saturated-crane"])
def test_the_general_steps_compiled_stages_give_scipys_trajectory(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A model of the general kind (redundant rows; a bounded actuator that saturates) takes DOP853's stages as one
    call around its compiled general step: the same steps as scipy's stages through the Python right-hand side, and
    the same motion to round-off. The control: the compiled stages with their step length halved inside (a wrong
    tableau) give another motion, which the comparison tells apart."""
    from gausspp.simulation import general_stages

    scene = gp.scenes.get(name)
    t_end, grid = 1.0, np.linspace(0.0, 1.0, 11)
    compiled = gp.simulate(scene.model, scene.q0, scene.v0, t_end, record=grid)
    assert general_stages.applies("DOP853", _general_rhs(scene.model))
    with monkeypatch.context() as patch:
        patch.setattr(general_stages, "applies", lambda method, rhs: False)
        python = gp.simulate(scene.model, scene.q0, scene.v0, t_end, record=grid)
    assert compiled.steps == python.steps and compiled.status == python.status == "success"
    size = np.abs(python.q).max()
    assert np.abs(compiled.q - python.q).max() <= 1e-9 * size
    original = general_stages.build_stages

    def halved(model: Any, method: str, stage: Any) -> Any:
        fn = original(model, method, stage)
        t, y, f, h, stab, rtol, atol = (ca.MX.sym(n, fn.size_in(i)) for i, n in enumerate(fn.name_in()))
        return ca.Function("halved", [t, y, f, h, stab, rtol, atol], fn(t, y, f, 0.5 * h, stab, rtol, atol))

    fresh = gp.scenes.get(name)  # a new model: its stages are built anew, by the wrong builder
    with monkeypatch.context() as patch, warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.DriftWarning)  # the wrong motion leaves its rows, as it should
        patch.setattr(general_stages, "build_stages", halved)
        wrong = gp.simulate(fresh.model, fresh.q0, fresh.v0, t_end, record=grid, throw=False)
    assert wrong.t.size != python.t.size or np.abs(wrong.q - python.q).max() > 1e-6 * size


def _general_rhs(model: gp.Model) -> Any:
    from gausspp.simulation.rhs import GeneralRightHandSide

    return GeneralRightHandSide(model, None, Stabilization())
