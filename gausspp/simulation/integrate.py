"""The Python and scipy lanes: the step as a right-hand side, stepped from Python or by scipy's ``OdeSolver``.

Both hand back the accepted states (:class:`~gausspp.simulation.samples.Samples`); recording them is
:mod:`gausspp.simulation.recording`'s job.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate._ivp.rk import RungeKutta

from ..errors import GaussppError, InputError, IntegrationError, NonFiniteError
from ..model.model import Model
from ..workspace import workspace
from . import crossing, general_stages, inputs
from . import methods as _methods
from .compiled import rhs_function
from .first_step import initial_step
from .initial import Projection, projection
from .lanes import Job
from .progress import Progress
from .rhs import AnyRightHandSide, step_control_atol
from .samples import Samples, fixed_grid, kept_steps


def run_python(job: Job) -> Samples:
    """The python lane's runner: fixed steps (RK tableau or symplectic Euler) from Python; keeps the recorded
    steps."""
    rhs, model, stab, opts, y0, redundant = job.rhs, job.model, job.stab, job.opts, job.y0, job.redundant
    meth, t0, t_end, dt = opts.method, opts.t0, opts.t_end, opts.dt
    assert dt is not None  # checked for fixed-step methods
    grid = fixed_grid(t0, t_end, dt)
    n_steps = grid.size - 1
    keep = kept_steps(grid, opts.record)
    ts, ys = np.empty(keep.size), np.empty((keep.size, y0.size))
    project = projection(model, redundant) if stab.project else None
    y, slot, t = y0.copy(), 0, t0
    failure = None
    progress = Progress(n_steps, f"gausspp.simulate ({meth.name})", enabled=n_steps > inputs.LONG_RUN_STEPS)
    for i in range(n_steps + 1):
        if i % inputs.PROGRESS_EVERY == 0:
            progress.update(i)
        if slot < keep.size and keep[slot] == i:
            ts[slot], ys[slot] = t, y
            slot += 1
        if i == n_steps:
            break
        t_next = t0 + (i + 1) * dt if i + 1 < n_steps else t_end
        try:
            y = _one_step(meth, rhs, model, project, t, y, min(dt, t_end - t), t_next)
            t = t_next
        except GaussppError as exc:
            failure = exc
            break
    progress.close()
    return Samples(ts[:slot], ys[:slot], i, rhs.evaluations, failure, meth.name, rhs.solver)


def _step_projection(job: Job, method: str, redundant: bool) -> Callable[[Any], None] | None:
    """With ``stabilize="project"``: after each accepted step, ``q`` and ``v`` moved back onto the constraints along
    ``A⁻¹D`` (:func:`gausspp.simulation.initial.projection`) — by ``gp.simulate``'s default drift control only where the
    state's relative drift exceeds ``stab.project_above`` — and the solver's derivative at the step's end taken
    anew at the projected state (the first stage of its next step). A record time inside a step is read from the
    step's own interpolant, off the constraints by what the step drifted. BDF keeps a history of past states that a
    projection would contradict: refused by name."""
    if not job.stab.project:
        return None
    if method == "BDF":
        raise InputError(
            "stabilize='project' with method='BDF': BDF's history of past states cannot follow a projection; use "
            "Radau or DOP853, or stabilize='baumgarte'"
        )
    model = job.model
    nq, nv, nl = model.nq, model.nv, model.n_lam
    onto = projection(model, redundant)
    above = job.stab.project_above
    drift = _drift_function(model) if above > 0 else None

    def project(solver: Any) -> None:
        y = solver.y
        q, v, lam = y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl]
        if drift is not None and not float(drift(solver.t, q, v, lam, np.zeros(2))) > above:
            return  # on its constraints to the accuracy asked: nothing to do
        q, v = onto(solver.t, q, v, lam)
        if np.array_equal(q, y[:nq]) and np.array_equal(v, y[nq : nq + nv]):
            return
        y = y.copy()
        y[:nq], y[nq : nq + nv] = q, v
        solver.moved_to(y)

    return project


def _drift_function(model: Model) -> ca.Function:
    """``(t, q, v, λ, stab) ↦`` the state's relative drift (:func:`gausspp.step.general.drift.relative_drift`), kept
    in the model's workspace."""
    from ..step.general.drift import relative_drift

    return workspace(model).get(
        ("relative drift",), lambda: ca.Function("drift", model.inputs, [relative_drift(model)])
    )


def _one_step(
    meth: _methods.Method,
    rhs: AnyRightHandSide,
    model: Model,
    project: Projection | None,
    t: float,
    y: np.ndarray,
    h: float,
    t_next: float,
) -> np.ndarray:
    """``y(t) → y(t + h)`` at ``t_next``, normalized (unit quaternions) and projected if asked."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    if meth.tableau is not None:
        y = _methods.rk_step(meth.tableau, rhs, t, y, h)
    else:  # symplectic Euler: v, λ and the works first, then q with the new v
        y_new = y + h * rhs(t, y)
        y_new[:nq] = y[:nq]
        y_new[:nq] = y[:nq] + h * rhs.qdot(t, y_new)
        y = y_new
    y[:nq] = model.mechanism.normalize_array(y[:nq])
    if project is not None:
        y[:nq], y[nq : nq + nv] = project(t_next, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl])
    if not np.isfinite(y.sum()):
        raise NonFiniteError(f"the state became NaN or inf at t={t_next:.6g}; reduce dt or use a stiff method")
    return y


def run_scipy(job: Job) -> Samples:
    """The scipy lane's runner: a scipy ``OdeSolver`` stepped to ``t_end``; keeps every accepted step, or the
    ``record`` times. A model whose ideal rows may lose rank is watched, and its singular positions are stepped
    over (:mod:`gausspp.simulation.crossing`): the solver starts again on the far side."""
    rhs, opts, y0 = job.rhs, job.opts, job.y0
    meth, t0, model = opts.method, opts.t0, rhs.model
    redundant = not rhs.margin_checked  # the general QP's rows dependent at the start
    options: dict[str, Any] = {"rtol": opts.rtol, "atol": step_control_atol(opts.atol, y0.size)}
    if opts.dt is not None:
        options.update(first_step=opts.dt, max_step=opts.dt)
    if meth.name in ("Radau", "BDF"):  # implicit methods: the exact Jacobian from casadi where it exists
        options["jac"] = jacobian(rhs)
    Solver = general_stages.solver_class(meth.name, rhs)  # noqa: N806  # a class
    if opts.dt is None:  # the same first step in any units (scipy's changes with the unit of time)
        options["first_step"] = initial_step(rhs, Solver, t0, y0, options, opts.t_end - t0)
        if options["first_step"] is None:
            del options["first_step"]
    project = _step_projection(job, meth.name, redundant)  # refuses BDF before its first evaluation
    solver = Solver(rhs, t0, y0, opts.t_end, **options)
    watch = crossing.SingularityWatch(model, t0, y0, rhs) if crossing.applies(model) else None
    events: list[dict[str, Any]] = []
    times = None if np.isscalar(opts.record) else np.sort(np.asarray(opts.record, float))  # checked by check_record
    keep_start = times is None or times[0] == t0
    ts, ys = ([t0], [y0.copy()]) if keep_start else ([], [])
    failure, steps, t_prev = None, 0, t0

    def keep(t_new: float, y_new: np.ndarray, dense: Any) -> None:
        if times is None:
            ts.append(t_new)
            ys.append(y_new.copy())
        else:
            for tk in times[(times > t_prev) & (times <= t_new)]:
                ts.append(float(tk))
                ys.append(y_new.copy() if tk == t_new else np.asarray(dense()(tk)))

    while solver.status == "running":
        try:
            message = solver.step()
        except GaussppError as exc:
            failure = exc
            break
        if solver.status == "failed":
            stiff = "" if meth.name in ("Radau", "BDF") else ", or try a stiff method (Radau, BDF, cvodes)"
            failure = IntegrationError(
                f"{meth.name} stopped at t={solver.t:.6g}: {message}; near a singular or very stiff state — "
                f"check the realizability margin there, loosen rtol/atol{stiff}"
            )
            break
        steps += 1
        if project is not None:
            try:
                project(solver)
            except GaussppError as exc:
                failure = exc
                break
        if steps == inputs.FORECAST_AFTER:  # a horizon of days is refused, one of hours announced
            try:
                inputs.check_forecast(meth.name, t0, opts.t_end, solver.t, steps, 8 * y0.size, len(ts))
            except GaussppError as exc:
                failure = exc
                break
        keep(solver.t, solver.y, solver.dense_output)
        t_prev = solver.t
        if watch is None or solver.t >= opts.t_end:
            continue
        try:
            plan = watch.observe(solver.t, solver.y, lambda s=solver: rate(rhs, s))
            if isinstance(plan, crossing.Approach):  # step to the point the bridge starts from
                solver.retarget(plan.t)
                continue
            if not isinstance(plan, crossing.Cross):
                if solver.status == "finished":  # an approach point was reached, the bridge not needed: go on
                    solver.retarget(opts.t_end)
                continue
            over = crossing.bridge(rhs, model, projection(model, redundant), solver.t, solver.y, plan.t, opts.t_end)
        except GaussppError as exc:
            failure = exc
            break
        steps += 1
        events.append(over.event)
        keep(over.t, over.y, lambda dense=over.dense: dense)
        t_prev = over.t
        if over.t >= opts.t_end:
            break
        watch.restart(over.t, over.y)
        solver = Solver(rhs, over.t, over.y, opts.t_end, **options)
    if failure is not None and times is not None and (not ts or solver.t > ts[-1]):
        ts.append(float(solver.t))  # a failed run keeps the last state it reached, between the record times
        ys.append(np.asarray(solver.y).copy())
    y = np.array(ys).reshape(len(ts), y0.size)
    if watch is not None:
        events = sorted([*events, *watch.stepped], key=lambda e: e["t"])
    return Samples(np.array(ts), y, steps, rhs.evaluations, failure, meth.name, rhs.solver, events=tuple(events))


def rate(rhs: AnyRightHandSide, solver: Any) -> np.ndarray:
    """``ẏ`` at the solver's state: the explicit Runge–Kutta methods keep it (``f``, their next first stage)."""
    f = getattr(solver, "f", None)
    return f if isinstance(solver, RungeKutta) and f is not None else rhs(solver.t, solver.y)


def jacobian(rhs: AnyRightHandSide) -> Any:
    """``∂F/∂y`` by casadi on the direct path (kept in the model's workspace); for a QP step, the structure only
    (``None``: the works feed nothing back)."""
    if rhs.solver != "direct":
        return None
    jac = workspace(rhs.model).get(("rhs-jacobian",), lambda: _jacobian_function(rhs.model))
    stab = rhs.stab

    def exact(t_: float, y_: np.ndarray) -> np.ndarray:
        return np.array(jac(t_, y_, stab))

    return exact


def _jacobian_function(model: Model) -> ca.Function:
    n = model.nq + model.nv + model.n_lam + 2
    F = rhs_function(model, "direct", None)
    t, y, s = ca.SX.sym("t"), ca.SX.sym("y", n), ca.SX.sym("stab", 2)
    return ca.Function("rhs_jacobian", [t, y, s], [ca.jacobian(F(t, y, s), y)])
