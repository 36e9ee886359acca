"""``simulate``: integrate a model from initial data (docs/theory.md §5).

What is integrated (the model's step as ``y' = F(t, y)`` with ``y = (q, v, λ, W_R, W_F)``),
how (a :mod:`~gausspp.methods` method) and what is recorded (a :class:`~gausspp.Trajectory`
built from the accepted states afterwards) are kept apart. A run that fails midway keeps
what it computed: the exception carries ``.trajectory`` (``throw=True``, the default), or the
trajectory is returned with ``status="failed"`` and the message (``throw=False``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from ..errors import (
    GaussppError,
    InitialDataError,
    InputError,
    IntegrationError,
    LongRunWarning,
    NonFiniteError,
    RealizabilityError,
    RealizabilityWarning,
    ShapeError,
    UnknownNameError,
)
from ..model.model import Model
from ..model.workspace import workspace
from ..step import qp
from ..step.outcome import QP_TOLERANCE, Where, to_result
from ..validation import array, number, positive
from . import methods as _methods
from .drift import Baumgarte, Stabilization, as_stabilization, projection_function
from .progress import Progress
from .rhs import AnyRightHandSide, GeneralRightHandSide, RightHandSide
from .trajectory import Trajectory


def simulate(
    model: Model,
    q0: Any,
    v0: Any,
    t_end: float,
    *,
    t0: float = 0.0,
    lam0: Any = None,
    dt: float | None = None,
    method: str | _methods.Method | None = None,
    solver: str = "qp",
    backend: str | None = None,
    stabilize: str | Baumgarte | list[Any] | None = None,
    rtol: float = 1e-9,
    atol: float = 1e-12,
    record: int | Any = 1,
    constraint_tol: float = 1e-8,
    throw: bool = True,
    rest_speed: float = 1e-6,
    max_events: int = 10_000,
) -> Trajectory:
    """Integrate ``model`` from ``(q0, v0)`` at ``t0`` to ``t_end``.

    Parameters
    ----------
    model : Model
    q0, v0 : arrays
        Initial configuration and velocity; they must satisfy the constraints (to
        ``constraint_tol``) unless ``stabilize`` includes ``"project"``, which projects them first.
    t_end : float
    lam0 : array, optional
        Initial ``λ`` for realizations that carry it (default: their ``lam0``).
    dt : float
        Step for fixed-step methods (and, if given, the first and largest step of adaptive ones).
    method : str
        Default ``"rk4"`` (``"DOP853"`` for a model with unilateral contacts, whose events only
        adaptive methods locate). See :func:`gausspp.methods.names`: ``"rk4"``, ``"symplectic-euler"``, ``"RK45"``,
        ``"DOP853"``, ``"Radau"``, ``"BDF"``, ``"rk4-compiled"``, ``"cvodes"``.
    solver : {"qp", "direct"}
        How each step is solved; ``backend`` picks the QP backend.
    stabilize : None, "baumgarte", "project", Baumgarte, or a list of these
        Drift control (off by default).
    rtol, atol : float
        Tolerances of adaptive methods.
    record : int or array
        Record every ``record``-th step (fixed-step methods; every accepted step for adaptive
        ones), or at the given times (must lie on the grid for fixed-step methods).
    throw : bool
        Raise on failure (the exception's ``.trajectory`` holds what was computed), or return
        the partial trajectory with ``status="failed"``.
    rest_speed, max_events :
        Unilateral contacts only (:mod:`gausspp.simulation.contacts`): an impact that would leave a contact
        slower than ``rest_speed`` ends in rest; a run with more than ``max_events`` events stops.

    Returns
    -------
    Trajectory
    """
    if not isinstance(model, Model):
        raise InputError(f"model must be a gp.Model (scenes carry one: gp.scenes.get(name).model), got {model!r}")
    if method is None:  # fixed-step RK4, or DOP853 where contact events must be located
        method = "DOP853" if model.contacts else "rk4"
    meth = _methods.get(method)
    t0 = number(f"t0 must be a finite number, got {t0!r}", t0)
    t_end = number(f"t_end must be a finite number, got {t_end!r}", t_end)
    if not t_end > t0:
        raise InputError(f"need t0 < t_end, got t0={t0}, t_end={t_end}")
    if dt is None and not meth.adaptive:
        raise InputError(f"method {meth.name!r} has a fixed step: give dt > 0, e.g. dt={(t_end - t0) / 1000:.3g}")
    if dt is not None:
        dt = positive("dt", dt, hint=" (the step; for adaptive methods the first and largest)")
    rtol = positive("rtol", rtol, hint=" (the relative tolerance of adaptive methods, e.g. rtol=1e-9)")
    atol = positive("atol", atol, zero_ok=True, hint=" (the absolute tolerance of adaptive methods, e.g. atol=1e-12)")
    constraint_tol = positive("constraint_tol", constraint_tol, zero_ok=True)
    rest_speed = positive("rest_speed", rest_speed, zero_ok=True)
    max_events = positive("max_events", max_events, integer=True)
    if not isinstance(throw, (bool, np.bool_)):
        raise InputError(f"throw must be True or False, got {throw!r}")
    record = _check_record(record, t0, t_end)
    if dt is not None:
        _check_step_count(meth, model, t0, t_end, dt, record)
    if solver not in ("qp", "direct"):
        raise UnknownNameError(f"solver={solver!r} is unknown; use 'qp' or 'direct'")
    if solver == "direct" and backend is not None:
        raise InputError(f"backend={backend!r} applies to solver='qp' only")
    if meth.name == "cvodes" and solver != "direct":
        raise InputError("method='cvodes' needs solver='direct': CVODES differentiates the right-hand side")
    if meth.lane == "compiled" and solver == "qp" and not qp.get(backend).compiled:
        raise InputError(
            f"the compiled lane needs the step inside the casadi graph: use solver='direct' or a casadi QP "
            f"backend (casadi:qrqp, casadi:daqp, casadi:osqp, ...), not {backend!r}"
        )
    if model.contacts:
        from .contacts import simulate_contacts

        return simulate_contacts(
            model,
            q0,
            v0,
            t_end,
            t0=t0,
            lam0=lam0,
            dt=dt,
            method=meth,
            solver=solver,
            backend=backend,
            stabilize=stabilize,
            rtol=rtol,
            atol=atol,
            constraint_tol=constraint_tol,
            throw=throw,
            record=record,
            rest_speed=rest_speed,
            max_events=max_events,
        )
    stab = as_stabilization(stabilize, dt)
    q, v, lam = _initial_state(model, t0, q0, v0, lam0)
    redundant = _redundant_rows(model, solver, backend, t0, q, v, lam)
    if stab.project:
        q, v = _project_initial(model, t0, q, v, lam, constraint_tol, redundant)
    _check_on_constraint(model, t0, q, v, lam, constraint_tol)

    general = model.bounded or redundant
    rhs: AnyRightHandSide
    if general:
        if solver == "direct":
            raise InputError(
                "solver='direct' cannot step a model with bounded actuators (inequalities); use solver='qp'"
            )
        if meth.lane == "compiled":
            raise InputError(
                f"method {meth.name!r} runs the compiled step, which a model with bounded actuators or redundant "
                "constraint rows does not have: use a Python or scipy method (rk4, RK45, DOP853, Radau, ...)"
            )
        rhs = GeneralRightHandSide(model, backend, stab, margin_checked=not redundant)
    else:
        rhs = RightHandSide(model, solver, backend, stab)
    y0 = np.concatenate([q, v, lam, [0.0, 0.0]])
    label = rhs.solver if general else ("direct" if solver == "direct" else qp.get(backend).name)
    failure: Exception | None = None
    compiled_evaluations = None
    try:
        if meth.lane == "python":
            assert dt is not None  # checked above for fixed-step methods
            ts, ys, steps, failure = _fixed_step(meth, rhs, model, stab, t0, t_end, dt, y0, record)
        elif meth.lane == "scipy":
            ts, ys, steps, failure = _scipy(meth, rhs, t0, t_end, y0, dt, rtol, atol, record)
        else:
            from .compiled import integrate_compiled

            ts, ys, steps, failure, compiled_evaluations = integrate_compiled(
                meth, model, solver, backend, stab, t0, t_end, dt, y0, rtol, atol, record
            )
    except GaussppError as exc:  # failed before the first step could be kept
        failure, ts, ys, steps = exc, np.array([t0]), y0[None, :], 0
    evaluations = rhs.evaluations if compiled_evaluations is None else compiled_evaluations
    traj, record_failure = _record(model, rhs, ts, ys, meth, label, steps, failure)
    traj = replace(traj, rhs_evaluations=evaluations)
    if isinstance(record_failure, RealizabilityError):  # the cause, seen before the integration broke down
        failure = record_failure
    failure = failure or record_failure
    if failure is None:
        return traj
    traj = _failed(traj, failure)
    if throw:
        hint = traj.message.partition(" [smallest realizability margin")[2]
        if hint:  # the same pointer at a small margin as in the returned trajectory
            failure.args = (f"{failure} [smallest realizability margin{hint}",)
        failure.trajectory = traj  # type: ignore[attr-defined]
        raise failure
    return traj


# -- set-up ----------------------------------------------------------------------------------
#: A run with more fixed steps than this warns up front (:class:`~gausspp.LongRunWarning`) with the count.
LONG_RUN_STEPS = 1_000_000
#: A long fixed-step run looks at the clock every this many steps (and reports at most every 2 s).
PROGRESS_EVERY = 500
#: A run with more steps than this is refused: it would run for days and its samples would not fit in memory.
MAX_STEPS = 10**10
#: The states a run keeps (every step on the compiled lane, the recorded ones elsewhere) may take this many bytes.
MAX_KEPT_BYTES = 2**31


def _check_record(record: Any, t0: float, t_end: float) -> Any:
    """``record``: a positive integer (every ``record``-th step) or a 1-D array of times in ``[t0, t_end]``."""
    if np.isscalar(record) or record is None:
        return positive("record", record, integer=True, hint=" (record every k-th step) or an array of times")
    times = array("simulate", "record", record)
    if times.ndim != 1 or times.size == 0:
        raise ShapeError(f"record must be a positive integer or a 1-D array of times, got shape {times.shape}")
    if times.min() < t0 or times.max() > t_end:
        raise InputError(
            f"record times must lie within [t0, t_end] = [{t0:g}, {t_end:g}], got {times.min():g} … {times.max():g}"
        )
    return times


def _check_step_count(meth: _methods.Method, model: Model, t0: float, t_end: float, dt: float, record: Any) -> None:
    """Refuse a run of more than :data:`MAX_STEPS` steps or whose kept states exceed :data:`MAX_KEPT_BYTES`; warn
    (:class:`~gausspp.LongRunWarning`) above :data:`LONG_RUN_STEPS` steps, before the wait. For an adaptive method
    ``dt`` is the largest step, so the count is a lower bound."""
    steps = (t_end - t0) / dt  # a float: t_end=1e300 must not overflow an integer
    bound = "at least " if meth.adaptive else ""
    what = f"t_end - t0 = {t_end - t0:.6g} with dt={dt:.3g} is {bound}{steps:.3g} steps"
    if steps > MAX_STEPS:
        raise InputError(
            f"{what}, more than the {MAX_STEPS:.0e} a run may take (days of computing): enlarge dt or shorten t_end"
        )
    width = 8 * (model.nq + model.nv + model.n_lam + 2)
    if meth.lane == "compiled" and not meth.adaptive:  # the compiled RK keeps every step's state
        kept = steps + 1
    elif np.isscalar(record):  # every record-th fixed step; every accepted step of an adaptive method
        kept = steps + 1 if meth.adaptive else steps / float(record) + 2  # type: ignore[arg-type]
    else:
        kept = len(record)
    if kept * width > MAX_KEPT_BYTES:
        keep_less = "" if meth.lane == "compiled" else ", or record fewer steps (record=k keeps every k-th)"
        raise InputError(
            f"{what}; method {meth.name!r} would keep {kept:.3g} states ({kept * width / 2**30:.3g} GiB, more than "
            f"{MAX_KEPT_BYTES / 2**30:g} GiB): enlarge dt or shorten t_end{keep_less}"
        )
    if steps > LONG_RUN_STEPS:
        warnings.warn(
            f"{what} (method {meth.name!r}): this run will take long"
            + (" (its progress and the time left are shown on standard error)" if meth.lane == "python" else "")
            + "; enlarge dt or shorten t_end"
            + (", or use an adaptive or compiled method (DOP853, rk4-compiled)" if meth.lane == "python" else ""),
            LongRunWarning,
            stacklevel=3,
        )


def _redundant_rows(
    model: Model, solver: str, backend: str | None, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray
) -> bool:
    """Whether the bilateral rows are dependent at the start, so that the run needs the general QP (which
    returns the least-norm multiplier) and the realizability margin, 0 by design, says nothing."""
    try:
        if model.bounded:  # the general QP's own rank test
            return model.k > 0 and model.general_step(t, q, v, lam)[1].redundant_rows > 0
        if solver != "qp":
            return False
        with warnings.catch_warnings():  # the compiled QP hands exactly redundant rows to the general QP
            warnings.simplefilter("ignore", RealizabilityWarning)
            return model.step(t, q, v, lam, solver=solver, backend=backend).solver.startswith("gauss-qp:")
    except GaussppError:
        return False  # the run itself reports the error, with its trajectory


def _initial_state(model: Model, t0: float, q0: Any, v0: Any, lam0: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t, q, v, lam = model.checked_state(t0, q0, v0, lam0)
    return q, v, lam


def _project(
    model: Model, redundant: bool = False
) -> Callable[[float, np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The projection onto the constraints along ``A⁻¹D``: compiled, or (redundant rows, where the compiled one's
    square solves are singular) the model's least-squares Newton."""
    if redundant:
        return model.nearest_on_manifold
    fn = workspace(model).get(("projection",), lambda: projection_function(model))

    def project(t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q1, v1 = fn(t, q, v, lam)
        return np.array(q1).ravel(), np.array(v1).ravel()

    return project


def _residuals(model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    data = model.evaluate_data(t, q, v, lam)
    return data.g, data.Phi


def _project_initial(
    model: Model,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    tol: float,
    redundant: bool = False,
    max_steps: int = 50,
) -> tuple[np.ndarray, np.ndarray]:
    """Newton steps of the projection until ``g`` and ``Φ`` are within ``tol/1000`` (or fail clearly)."""
    project = _project(model, redundant)
    start, first_move = q.copy(), None
    for _ in range(max_steps):
        g, Phi = _residuals(model, t, q, v, lam)
        size = float(np.max(np.abs(np.concatenate([g, Phi]))))
        if size <= tol * 1e-3:
            moved = float(np.max(np.abs(q - start)))
            if first_move is not None and moved > 10 * first_move + 1e-12:
                raise InitialDataError(
                    f"projecting the initial data onto the constraints ended far from them at t={t:.6g} (q moved by "
                    f"{moved:.3g}, the first Newton step by {first_move:.3g}): Newton found a distant root; start "
                    "closer to the constraint"
                )
            return q, v
        q_prev = q
        q, v = project(t, q, v, lam)
        if first_move is None:
            first_move = float(np.max(np.abs(q - q_prev))) if np.all(np.isfinite(q)) else np.inf
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            raise InitialDataError(
                f"projecting the initial data onto the constraints failed at t={t:.6g} (NaN): the constraint rows are "
                "dependent (redundant constraints) or the realization cannot move the state there; give q0/v0 on "
                "the constraint"
            )
    raise InitialDataError(
        f"projecting the initial data onto the constraints did not converge in {max_steps} Newton steps "
        f"(|g|, |Φ| still {size:.3g} at t={t:.6g}); start closer to the constraint"
    )


#: What to do about initial data off the constraint (contact runs cannot project: they say only the first part).
PROJECT_HINT = (
    "correct q0/v0, or pass stabilize='project' to project them onto the constraint along the realization's directions"
)


def _check_on_constraint(
    model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, tol: float, hint: str = PROJECT_HINT
) -> None:
    g, Phi = _residuals(model, t, q, v, lam)
    for values, what in ((g, "g(q, t)"), (Phi, "Φ(q, v, t)")):
        bad = np.flatnonzero(~(np.abs(values) <= tol))  # NaN counts as off
        if bad.size:
            worst = int(bad[np.argmax(np.nan_to_num(np.abs(values[bad]), nan=np.inf))])
            raise InitialDataError(
                f"initial data are off the constraint {model.row_names[worst]!r} at t={t:.6g}: {what} = "
                f"{values[worst]:.3g} (tolerance {tol:g}); {hint}"
            )


# -- lanes -----------------------------------------------------------------------------------
def _fixed_step(
    meth: _methods.Method,
    rhs: AnyRightHandSide,
    model: Model,
    stab: Stabilization,
    t0: float,
    t_end: float,
    dt: float,
    y0: np.ndarray,
    record: Any,
) -> tuple[np.ndarray, np.ndarray, int, Exception | None]:
    n_steps = int(np.ceil((t_end - t0) / dt - 1e-9))
    keep = _keep_indices(n_steps, t0, dt, record)
    ts, ys = np.empty(keep.size), np.empty((keep.size, y0.size))
    redundant = isinstance(rhs, GeneralRightHandSide) and not rhs.margin_checked
    project = _project(model, redundant) if stab.project else None
    nq, nv, nl = model.nq, model.nv, model.n_lam
    y, slot, t = y0.copy(), 0, t0
    failure = None
    progress = Progress(n_steps, f"gausspp.simulate ({meth.name})", enabled=n_steps > LONG_RUN_STEPS)
    for i in range(n_steps + 1):
        if i % PROGRESS_EVERY == 0:
            progress.update(i)
        if slot < keep.size and keep[slot] == i:
            ts[slot], ys[slot] = t, y
            slot += 1
        if i == n_steps:
            break
        h = min(dt, t_end - t)
        try:
            if meth.tableau is not None:
                y = _methods.rk_step(meth.tableau, rhs, t, y, h)
            else:  # symplectic Euler: v, λ and the works first, then q with the new v
                y_new = y + h * rhs(t, y)
                y_new[:nq] = y[:nq]
                y_new[:nq] = y[:nq] + h * rhs.qdot(t, y_new)
                y = y_new
            t = t0 + (i + 1) * dt if i + 1 < n_steps else t_end
            y[:nq] = model.mechanism.normalize_array(y[:nq])
            if project is not None:
                y[:nq], y[nq : nq + nv] = project(t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl])
            if not np.isfinite(y.sum()):
                raise NonFiniteError(f"the state became NaN or inf at t={t:.6g}; reduce dt or use a stiff method")
        except GaussppError as exc:
            failure = exc
            break
    progress.close()
    return ts[:slot], ys[:slot], i, failure


def _keep_indices(n_steps: int, t0: float, dt: float, record: Any) -> np.ndarray:
    if np.isscalar(record):
        every = int(record)  # type: ignore[arg-type]  # checked by _check_record
        idx = np.arange(0, n_steps + 1, every)
        return idx if idx[-1] == n_steps else np.append(idx, n_steps)
    times = np.asarray(record, float)
    idx = np.rint((times - t0) / dt).astype(int)
    if (
        np.any(np.abs(t0 + idx * dt - times) > 1e-9 * max(1.0, abs(times).max()))
        or np.any(idx < 0)
        or np.any(idx > n_steps)
    ):
        raise InputError("record times must lie on the fixed-step grid t0 + i·dt within [t0, t_end]")
    return np.unique(idx)


def _scipy(
    meth: _methods.Method,
    rhs: AnyRightHandSide,
    t0: float,
    t_end: float,
    y0: np.ndarray,
    dt: float | None,
    rtol: float,
    atol: float,
    record: Any,
) -> tuple[np.ndarray, np.ndarray, int, Exception | None]:
    import scipy.integrate as si

    options: dict[str, Any] = {"rtol": rtol, "atol": atol}
    if dt is not None:
        options.update(first_step=dt, max_step=dt)
    if meth.name in ("Radau", "BDF"):  # implicit methods: the exact Jacobian from casadi where it exists
        options["jac"] = _jacobian(rhs)
    solver_cls = getattr(si, meth.name)
    solver = solver_cls(rhs, t0, y0, t_end, **options)
    times = None if np.isscalar(record) else np.sort(np.asarray(record, float))  # checked by _check_record
    keep_start = times is None or times[0] == t0
    ts, ys = ([t0], [y0.copy()]) if keep_start else ([], [])
    failure, steps, t_prev = None, 0, t0
    while solver.status == "running":
        try:
            message = solver.step()
        except GaussppError as exc:
            failure = exc
            break
        if solver.status == "failed":
            failure = IntegrationError(
                f"{meth.name} stopped at t={solver.t:.6g}: {message}; near a singular or very stiff state — "
                "check the realizability margin there, loosen rtol/atol, or try a stiff method"
            )
            break
        steps += 1
        if times is None:
            ts.append(solver.t)
            ys.append(solver.y.copy())
        else:
            dense = solver.dense_output()
            for tk in times[(times > t_prev) & (times <= solver.t)]:
                ts.append(float(tk))
                ys.append(np.asarray(dense(tk)))
        t_prev = solver.t
    return np.array(ts), np.array(ys).reshape(len(ts), y0.size), steps, failure


def _jacobian(rhs: AnyRightHandSide) -> Any:
    """``∂F/∂y`` by casadi on the direct path; for a QP step, the structure only (the works feed nothing back)."""
    from .compiled import rhs_function

    n = rhs.model.nq + rhs.model.nv + rhs.model.n_lam + 2
    if rhs.solver == "direct":
        cache = rhs.model.__dict__
        if "_rhs_jacobian" not in cache:  # built once per model
            F = rhs_function(rhs.model, "direct", None)
            t, y, s = ca.SX.sym("t"), ca.SX.sym("y", n), ca.SX.sym("stab", 2)
            cache["_rhs_jacobian"] = ca.Function("rhs_jacobian", [t, y, s], [ca.jacobian(F(t, y, s), y)])
        jac = cache["_rhs_jacobian"]
        stab = rhs.stab

        def exact(t_: float, y_: np.ndarray) -> np.ndarray:
            return np.array(jac(t_, y_, stab))

        return exact
    return None


# -- recording -------------------------------------------------------------------------------
def _replaceable(failure: Exception | None) -> bool:
    """No failure yet, or one that a margin lost at earlier samples explains (a realizability failure, or the
    divergence that follows a step across a singular state)."""
    return failure is None or isinstance(failure, (RealizabilityError, NonFiniteError, IntegrationError))


def _record(
    model: Model,
    rhs: AnyRightHandSide,
    ts: np.ndarray,
    ys: np.ndarray,
    meth: _methods.Method,
    label: str,
    steps: int,
    failure: Exception | None,
) -> tuple[Trajectory, Exception | None]:
    nq, nv, nl = model.nq, model.nv, model.n_lam
    N = ts.size
    ys = ys.copy()
    for row in ys:  # adaptive lanes integrate q freely: bring samples back onto the manifold (unit quaternions)
        row[:nq] = model.mechanism.normalize_array(row[:nq])
    general = isinstance(rhs, GeneralRightHandSide)
    keys = ("a", "u", "reaction", "compulsion", "Phi", "g", "S_norm", "energy")
    cols: dict[str, list[np.ndarray]] = {k: [] for k in (*keys, *(("tracking_error", "saturated") if general else ()))}
    kernel = rhs.kernel
    record_failure: Exception | None = None
    kept = N
    for i in range(N):
        y = ys[i]
        try:
            out = rhs.evaluate(ts[i], y, stabilized=False)
        except GaussppError as exc:
            record_failure, kept = exc, i
            break
        for k in cols:
            cols[k].append(np.array(out[k], copy=True))
    del kernel
    ts, ys = ts[:kept], ys[:kept]
    S = np.array(cols["S_norm"]).reshape(kept, model.k, model.m) if kept else np.zeros((0, model.k, model.m))
    margin = np.linalg.svd(S, compute_uv=False).min(axis=1) if kept and model.m >= model.k else np.zeros(kept)
    checked = rhs.margin_checked
    if (
        kept > 1 and model.m == model.k and checked
    ):  # det S is continuous along a motion: a sign change means S was singular
        flips = np.flatnonzero(np.sign(np.linalg.det(S[1:])) * np.sign(np.linalg.det(S[:-1])) < 0)
        if flips.size and _replaceable(record_failure):  # a margin lost earlier explains a later failure
            i = int(flips[0])
            record_failure = RealizabilityError(
                f"the realizability margin passed through zero between t={ts[i]:.6g} and t={ts[i + 1]:.6g} "
                f"(constraints {', '.join(repr(n) for n in model.names)}): the realization cannot keep the "
                "constraint there and the step went past it; samples after it are dropped",
                t=float(ts[i + 1]),
                constraint=", ".join(model.names),
                margin=0.0,
            )
            margin = margin[: i + 1]
            ts, ys, kept = ts[: i + 1], ys[: i + 1], i + 1
            cols = {k: v[: i + 1] for k, v in cols.items()}
    touch = _margin_touches_zero(ts, margin, model.margin_error) if _replaceable(record_failure) and checked else None
    if touch is not None:  # a minimum of the margin between samples reaches zero: the step went past it
        i, t_min = touch
        warnings.warn(
            f"the realizability margin falls below {model.margin_warn:g} between the samples at t={ts[i - 1]:.6g} and "
            f"t={ts[i + 1]:.6g} (smallest sampled {margin[i]:.3g}; its parabola reaches zero near t={t_min:.6g})",
            RealizabilityWarning,
            stacklevel=3,
        )
        record_failure = RealizabilityError(
            f"the realizability margin reaches zero between t={ts[i - 1]:.6g} and t={ts[i + 1]:.6g} (near "
            f"t={t_min:.6g}; constraints {', '.join(repr(n) for n in model.names)}): the realization cannot keep the "
            "constraint there and the step went past it; samples after it are dropped",
            t=float(t_min),
            constraint=", ".join(model.names),
            margin=0.0,
        )
        margin, ts, ys, kept = margin[: i + 1], ts[: i + 1], ys[: i + 1], i + 1
        cols = {k: v[: i + 1] for k, v in cols.items()}
    bad = np.flatnonzero(margin < model.margin_error) if checked else np.zeros(0, int)
    if bad.size and record_failure is None and not general:
        i = int(bad[0])
        where = Where(
            float(ts[i]),
            label,
            model.groups,
            lambda: model.step_data(ts[i], ys[i, :nq], ys[i, nq : nq + nv], ys[i, nq + nv : nq + nv + nl]),
        )
        try:
            to_result(
                rhs.evaluate(ts[i], ys[i], stabilized=False),
                where,
                margin_warn=model.margin_warn,
                margin_error=model.margin_error,
            )
        except GaussppError as exc:
            record_failure = exc
        ts, ys, margin, kept = ts[:i], ys[:i], margin[:i], i
        cols = {k: v[:i] for k, v in cols.items()}
    if bad.size and record_failure is None:  # the general QP answered although the margin vanished
        i = int(bad[0])
        record_failure = RealizabilityError(
            f"the realizability margin vanished at t={ts[i]:.6g} (constraints {', '.join(map(repr, model.names))}): "
            "the realization cannot keep the constraint there; samples from it on are dropped",
            t=float(ts[i]),
            constraint=", ".join(model.names),
            margin=float(margin[i]),
        )
        ts, ys, margin, kept = ts[:i], ys[:i], margin[:i], i
        cols = {k: v[:i] for k, v in cols.items()}
    low = np.flatnonzero(margin < model.margin_warn) if checked else np.zeros(0, int)
    if low.size:
        warnings.warn(
            f"realizability margin {margin[low[0]]:.3g} at t={ts[low[0]]:.6g} (smallest {margin.min():.3g}) is small: "
            "the reaction is large and sensitive to errors",
            RealizabilityWarning,
            stacklevel=3,
        )

    def stack(key: str, width: int) -> np.ndarray:
        return np.array(cols[key]).reshape(kept, width) if kept else np.zeros((0, width))

    energy = stack("energy", 1).ravel() if model.has_energy else np.full(kept, np.nan)
    traj = Trajectory(
        t=ts.copy(),
        q=ys[:, :nq].copy(),
        v=ys[:, nq : nq + nv].copy(),
        lam=ys[:, nq + nv : nq + nv + nl].copy(),
        a=stack("a", nv),
        u=stack("u", model.m),
        reaction=stack("reaction", nv),
        compulsion=stack("compulsion", 1).ravel(),
        residual=stack("Phi", model.k),
        g=stack("g", model.k),
        margin=margin,
        energy=energy,
        work_reaction=ys[:, -2].copy(),
        work_forces=ys[:, -1].copy() if model.has_force_power else np.full(kept, np.nan),
        status="success",
        message="",
        method=meth.name,
        solver=label,
        steps=steps,
        rhs_evaluations=rhs.evaluations,
        contact_force=np.zeros((kept, 0)),
        tracking_error=stack("tracking_error", 1).ravel() if general else np.zeros(kept),
        saturated=stack("saturated", model.m).astype(bool) if general else np.zeros((kept, model.m), bool),
    )
    return traj, record_failure


#: A sampled margin below this is "small": worth a look between samples, and worth naming in a failure.
SMALL_MARGIN = 1e-2


def _margin_touches_zero(ts: np.ndarray, margin: np.ndarray, floor: float) -> tuple[int, float] | None:
    """First strict local minimum of the sampled margin whose parabola through it and its neighbours dips
    below ``floor``: a margin that touches zero between samples without changing the sign of det S (the
    crane's ``sin²θ``). Returns the sample index and the estimated time, or ``None``."""
    for i in range(1, margin.size - 1):
        m0, m1, m2 = margin[i - 1 : i + 2]
        if not (m1 < SMALL_MARGIN and m1 < m0 and m1 < m2):  # only an already small minimum is suspect
            continue
        t0, t1, t2 = ts[i - 1 : i + 2]
        a, b, c = np.polyfit([t0 - t1, 0.0, t2 - t1], [m0, m1, m2], 2)
        if a <= 0:
            continue
        vertex = -b / (2 * a)
        if c - b * b / (4 * a) < floor and t0 - t1 <= vertex <= t2 - t1:
            return i, float(t1 + vertex)
    return None


def _failed(traj: Trajectory, failure: Exception) -> Trajectory:
    message = f"{type(failure).__name__}: {failure}"
    if isinstance(failure, (NonFiniteError, IntegrationError)) and traj.margin.size:
        i = int(np.argmin(traj.margin))
        if traj.margin[i] < SMALL_MARGIN:  # a failing integration near a singular step: say so
            message += (
                f" [smallest realizability margin on the way: {traj.margin[i]:.3g} at t={traj.t[i]:.6g} — the "
                "realization may have lost the constraint there]"
            )
    return replace(traj, status="failed", message=message)


__all__ = ["QP_TOLERANCE", "simulate"]
