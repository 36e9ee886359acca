"""The compiled lane: the whole right-hand side as one casadi graph.

``rk4`` in the compiled lane chains RK4 steps with ``mapaccum``: the whole run is one C call. ``cvodes``
hands the (direct-path) right-hand side to SUNDIALS CVODES through ``casadi.integrator``.
Both return the states on their grid; recording is the caller's job.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..c_code import c_function
from ..disk_cache import cached_function
from ..errors import GaussppError, InputError, IntegrationError, NonFiniteError, RealizabilityError
from ..model.model import Model
from ..step import realizability
from ..step.equality.expressions import OUTPUTS, reduce
from ..step.equality.kernel import CompiledKernel, only_outputs
from ..step.qp.casadi_conic import stdout_silenced
from ..step.realizability import MARGIN_BOUND_ROWS
from ..workspace import workspace
from . import lanes
from . import methods as _methods
from .drift import Stabilization, projection_function
from .inputs import Options
from .rhs import RightHandSide, step_control_atol
from .samples import Samples, fixed_grid, kept_steps

#: CVODES gives up after this many internal steps (seconds on a small model) instead of stalling.
MAX_CVODES_STEPS = 100_000

_RHS_OUTPUTS = [OUTPUTS.index(k) for k in ("qdot", "a", "u", "power_reaction", "power_forces")]


def rhs_function(model: Model, solver: str, backend: str | None, *, with_solution: bool = False) -> ca.Function:
    """``F(t, y, stab) -> y'`` with ``y = (q, v, λ, W_R, W_F)``, the step inside the graph.

    With ``solver="direct"`` the result is a pure SX function (one flat instruction list); with
    a casadi QP backend an MX graph around the conic node, computing only what ``y'`` needs.
    ``with_solution``: a second output, the QP's solution ``(z, y)`` (empty for the direct step), so that the
    recording can replay the step without solving its QP again (:meth:`~gausspp.step.equality.kernel.QPParts.replay`).
    """
    kernel = model.kernel(solver, backend)
    if not isinstance(kernel, CompiledKernel):
        raise InputError(lanes.graph_backend_error(lanes.LANES["compiled"], backend))
    nq, nv, nl = model.nq, model.nv, model.n_lam
    t, y, stab = ca.MX.sym("t"), ca.MX.sym("y", nq + nv + nl + 2), ca.MX.sym("stab", 2)
    args = [t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], stab]
    solution = ca.MX(0, 1)
    if kernel.qp_parts is None:
        qdot, a, u, pR, pF = only_outputs(kernel.function, _RHS_OUTPUTS)(*args)
    else:
        (qdot, a, u, pR, pF), solution = kernel.qp_parts.graph_and_solution(args, only=_RHS_OUTPUTS)
    lam_dot = ca.vertcat(*[u[i] for i in model.lam_columns]) if model.lam_columns else ca.MX(0, 1)
    outputs = [ca.vertcat(qdot, a, lam_dot, pR, pF), *([solution] if with_solution else [])]
    F = ca.Function("rhs", [t, y, stab], outputs)
    return F.expand() if kernel.qp_parts is None else F


def rk_step_function(model: Model, F: ca.Function, tableau: _methods.Tableau, stab: Stabilization) -> ca.Function:
    """One explicit RK step of ``F`` (:func:`rhs_function` ``with_solution``) as a casadi function
    ``(y, t, h, stab) -> (y', margin bound at the start, the QP's solution at the start)``."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    t, h, y, s = ca.MX.sym("t"), ca.MX.sym("h"), ca.MX.sym("y", F.size1_in(1)), ca.MX.sym("stab", 2)
    stages: list[ca.MX] = []
    for c, row in zip(tableau.c, tableau.A, strict=True):
        yi = y
        for a, k in zip(row, stages, strict=False):
            if a:
                yi = yi + h * a * k
        derivative, solution = F(t + c * h, yi, s)
        stages.append(derivative)
        if not c:
            start = solution  # the first stage: the step at (t, y) itself
    y1 = y
    for b, k in zip(tableau.b, stages, strict=True):
        y1 = y1 + h * b * k
    q1 = _normalize(model, y1[:nq])
    v1, lam1 = y1[nq : nq + nv], y1[nq + nv : nq + nv + nl]
    if stab.project:
        q1, v1 = projection_function(model)(t + h, q1, v1, lam1)
    y1 = ca.vertcat(q1, v1, lam1, y1[nq + nv + nl :])
    step = ca.Function("rk_step", [y, t, h, s], [y1, margin_bound(model)(t, y), start])
    try:
        flat = step.expand()  # direct path: one flat SX instruction list for the whole step ...
    except RuntimeError:
        return step  # a conic node cannot be expanded; the QP stays a call in the MX graph
    args = flat.sx_in()
    return ca.Function("rk_step", args, ca.cse(flat.call(args)))  # ... without repeated subexpressions


def margin_bound(model: Model) -> ca.Function:
    """``(t, y) ↦ b`` with ``b ≤ σ_min(S_norm) ≤ √k · b``: :func:`gausspp.step.realizability.margin_bound`."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    t, y = ca.SX.sym("t"), ca.SX.sym("y", nq + nv + nl + 2)
    k, m = model.k, model.m
    S = ca.SX.zeros(k, m)
    if 0 < k <= min(m, MARGIN_BOUND_ROWS):
        S_of = ca.Function("S_norm", model.inputs, [reduce(model.expressions).S_norm])
        S = S_of(t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], ca.SX.zeros(2))
    return ca.Function("margin_bound", [t, y], [realizability.margin_bound(S, k, m)])


def _margin_failure(model: Model, times: np.ndarray, bounds: np.ndarray) -> tuple[int, Exception] | None:
    """The first step whose start has a margin certainly below ``margin_error`` (or not finite), as an error."""
    certain = ~(bounds * np.sqrt(max(model.k, 1)) >= model.margin_error)  # NaN counts: S singular there
    if not certain.any():
        return None
    i = int(np.argmax(certain))
    return i, RealizabilityError(
        f"the realizability margin falls below margin_error={model.margin_error:g} at t={times[i]:.6g} ("
        f"{f'at most {bounds[i] * np.sqrt(model.k):.3g}' if np.isfinite(bounds[i]) else 'not finite'}; "
        f"constraints {', '.join(repr(n) for n in model.names)}): the "
        "realization cannot keep the constraint there; the run stops",
        t=float(times[i]),
        constraint=", ".join(model.names),
        margin=float(bounds[i]),
    )


def _normalize(model: Model, q: ca.MX) -> ca.MX:
    qs = ca.SX.sym("q", model.nq)
    return ca.Function("normalize", [qs], [model.mechanism.normalize(qs)])(q)


def integrate_compiled(
    model: Model, opts: Options, *, stab: Stabilization, y0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, int, Exception | None, int, np.ndarray | None]:
    """Run a compiled-lane method (the checked options ``opts``: method, solver, backend, times, tolerances and
    record) from ``y0``; return ``(t, Y, steps, failure, rhs evaluations, QP solutions)`` on the recorded grid. The QP
    solutions (one row per kept sample, NaN where no step starts) are those of each step's first stage, the step at
    the sample itself — given only for a QP step without Baumgarte terms (``None`` otherwise)."""
    meth, solver, backend, t0, t_end, dt, record = (
        opts.method,
        opts.solver,
        opts.backend,
        opts.t0,
        opts.t_end,
        opts.dt,
        opts.record,
    )
    if meth.name in CVODES:
        return cvodes_run(rhs_function(model, solver, backend), opts, stab=stab, y0=y0)
    assert meth.tableau is not None and dt is not None
    times = fixed_grid(t0, t_end, dt)
    n_steps = times.size - 1
    step, run = _compiled_run(model, solver, backend, meth, stab, n_steps)
    h, s = np.diff(times)[None, :], np.array(stab.stab)
    try:
        Ys, bounds, starts = run(y0, times[:-1][None, :], h, s)
        Y = np.vstack([y0[None, :], np.array(Ys).T])
        bounds, solutions = np.array(bounds).ravel(), np.array(starts).T
    except RuntimeError:  # a QP plugin refused non-finite data somewhere: redo step by step to keep the prefix
        Y, bounds, solutions = _step_by_step(step, y0, times, s)
    failure: Exception | None = None
    finite = np.isfinite(Y).all(axis=1)
    if Y.shape[0] < times.size or not finite.all():
        first = int(np.argmin(finite)) if not finite.all() else Y.shape[0]
        Y, times = Y[:first], times[:first]
        failure = _diagnose(model, solver, backend, times[-1], Y[-1], times[-1] + dt)
    low = _margin_failure(model, times[: bounds.size], bounds[: times.size])
    if low is not None and low[0] > 0:  # a state whose margin vanished is not kept, nor anything after it
        Y, times, failure = Y[: low[0]], times[: low[0]], low[1]
    if failure is not None and not np.isscalar(record):  # only the requested times that were reached can be kept
        record = np.asarray(record, float)
        record = record[record <= times[-1] + 1e-12]
    keep = kept_steps(times, record)
    steps = times.size - 1
    kept_solutions = None
    if solver != "direct" and not np.any(s):  # unstabilized: the first stage is the step the recording replays
        kept_solutions = np.full((keep.size, solutions.shape[1]), np.nan)
        starts_here = keep < solutions.shape[0]
        kept_solutions[starts_here] = solutions[keep[starts_here]]
    return times[keep], Y[keep], steps, failure, steps * len(meth.tableau.c), kept_solutions


def _compiled_run(
    model: Model, solver: str, backend: str | None, meth: _methods.Method, stab: Stabilization, n_steps: int
) -> tuple[ca.Function, ca.Function]:
    """The step and the whole-run ``mapaccum`` function, built once per model and setting and kept in the model's
    workspace."""
    key = (solver, backend, meth.tableau, stab.project)  # the tableau, not the name

    def build_step() -> ca.Function:
        assert meth.tableau is not None
        return rk_step_function(model, rhs_function(model, solver, backend, with_solution=True), meth.tableau, stab)

    def cached(what: tuple[Any, ...], build: Callable[[], ca.Function]) -> ca.Function:  # memory, then disk
        return workspace(model).get(what, lambda: cached_function(model, what, build))

    step = cached(("compiled-step", *key), build_step)
    if model.codegen:  # the step as C where a compiler is (c_code), the run around it rebuilt in each process
        c_step = workspace(model).get(("compiled-step-c", *key), lambda: c_function(step) or step)
        return c_step, workspace(model).get(("compiled-run-c", *key, n_steps), lambda: c_step.mapaccum("run", n_steps))
    run = cached(("compiled-run", *key, n_steps), lambda: step.mapaccum("run", n_steps))
    return step, run


def _step_by_step(
    step: ca.Function, y0: np.ndarray, times: np.ndarray, stab: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ys, bounds, solutions = [y0], [], []
    for t, t_next in zip(times[:-1], times[1:], strict=True):
        try:
            y, bound, solution = step(ys[-1], t, t_next - t, stab)
        except RuntimeError:
            break
        ys.append(np.array(y).ravel())
        bounds.append(float(bound))
        solutions.append(np.array(solution).ravel())
        if not np.isfinite(ys[-1]).all():
            break
    return np.array(ys), np.array(bounds), np.array(solutions).reshape(len(solutions), step.nnz_out(2))


def _diagnose(model: Model, solver: str, backend: str | None, t: float, y: np.ndarray, t_next: float) -> Exception:
    """Name what failed in the step after the last good state ``y`` at ``t``."""
    rhs = RightHandSide(model, solver, backend, Stabilization())
    try:
        rhs.evaluate(t, y)
    except GaussppError as exc:
        return exc
    return NonFiniteError(
        f"the state became NaN or inf in the step from t={t:.6g} to t={t_next:.6g}: a stage of the step failed "
        "(unrealizable, mass matrix not positive definite, or unstable for this dt); reduce dt or use a stiff method"
    )


#: The CVODES methods and their linear multistep family (Adams with functional iteration needs no Jacobian).
CVODES = {"cvodes": "bdf", "cvodes-adams": "adams"}


def cvodes_run(
    F: ca.Function, opts: Options, *, stab: Stabilization, y0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, int, Exception | None, int, None]:
    """CVODES (BDF or Adams) on ``F(t, y, stab)`` from ``y0``, as :func:`integrate_compiled` (no QP solutions)."""
    method, t0, t_end, dt, rtol, atol, record = (
        opts.method.name,
        opts.t0,
        opts.t_end,
        opts.dt,
        opts.rtol,
        opts.atol,
        opts.record,
    )
    if np.isscalar(record):
        grid = np.arange(t0, t_end, dt) if dt else np.linspace(t0, t_end, 201)
        grid = np.append(grid[grid < t_end], t_end)
    else:
        grid = np.unique(np.concatenate([[t0], np.asarray(record, float)]))
    # CVODES takes one absolute tolerance: each component is integrated in units of its own (z = y / w), so the
    # error test on z with abstol 1 is the test on y with abstol w (the works: the motion's least tolerance)
    # (a user's single atol: no units to take, y itself)
    if np.ndim(atol) == 0:
        w, abstol = np.ones(y0.size), float(atol)
    else:
        w = step_control_atol(atol, y0.size)
        w[~np.isfinite(w)] = np.min(w[np.isfinite(w)], initial=1.0)
        w, abstol = np.where(w > 0, w, 1.0), 1.0
    z, t, s = ca.MX.sym("z", y0.size), ca.MX.sym("t"), ca.MX.sym("stab", 2)
    dae = {"x": z, "t": t, "p": s, "ode": F(t, z * w, s) / w if np.ndim(atol) else F(t, z, s)}
    settings: dict[str, Any] = {
        "abstol": abstol,
        "reltol": rtol,
        "max_num_steps": MAX_CVODES_STEPS,
        "disable_internal_warnings": True,
        "show_eval_warnings": False,  # a NaN from a general step's flag stops CVODES: said by the failure, not logged
    }
    if CVODES[method] == "adams":
        settings.update(linear_multistep_method="adams", nonlinear_solver_iteration="functional")
    if dt:  # as for scipy's methods: dt is the first and the largest step
        settings.update(step0=dt, max_step_size=dt)

    def run(upto: int) -> tuple[np.ndarray, ca.Function]:
        integrator = ca.integrator("cvodes", "cvodes", dae, t0, grid[1 : upto + 1], settings)
        with stdout_silenced():  # SUNDIALS prints its own failure report
            return np.array(integrator(x0=y0 / w, p=np.array(stab.stab))["xf"]).T * w, integrator

    try:
        xf, integrator = run(grid.size - 1)
    except RuntimeError as exc:
        # keep what can be kept: the longest prefix of the output grid that CVODES completes
        good, bad = 0, grid.size - 1
        while bad - good > 1:
            mid = (good + bad) // 2
            try:
                run(mid)
                good = mid
            except RuntimeError:
                bad = mid
        prefix = run(good)[0] if good else np.zeros((0, y0.size))
        failure = IntegrationError(
            f"CVODES stopped between t={grid[good]:.6g} and t={grid[bad]:.6g} ({str(exc).strip().splitlines()[-1]}); "
            "near a singular or very stiff state — check the realizability margin there"
        )
        return grid[: good + 1], np.vstack([y0[None, :], prefix]), 0, failure, 0, None
    stats = integrator.stats()
    steps = int(stats.get("nsteps", 0)) if isinstance(stats, dict) else 0
    evaluations = int(stats.get("nfevals", 0)) if isinstance(stats, dict) else 0
    Y = np.vstack([y0[None, :], xf])
    return grid, Y, steps, None, evaluations, None


def run_compiled(job: lanes.Job) -> Samples:
    """The compiled and cvodes lanes' runner: the whole run as one casadi graph (:func:`integrate_compiled`)."""
    t, y, steps, failure, evaluations, solutions = integrate_compiled(job.model, job.opts, stab=job.stab, y0=job.y0)
    return Samples(t, y, steps, evaluations, failure, job.opts.method.name, job.rhs.solver, qp_solutions=solutions)
