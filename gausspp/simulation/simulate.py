"""``simulate``: integrate a model from initial data (docs/theory.md §5) — the dispatcher.

What is integrated (the model's step as ``y' = F(t, y)`` with ``y = (q, v, λ, W_R, W_F)``),
how (a :mod:`~gausspp.methods` method, run by the lane :mod:`~gausspp.simulation.lanes` assigns)
and what is recorded (a :class:`~gausspp.Trajectory` built by :mod:`~gausspp.simulation.recording`
from the accepted states afterwards) are kept apart. ``simulate`` checks the arguments, sets up the
initial state, chooses the lane, runs it and records. A run that fails midway keeps what it
computed: the exception carries ``.trajectory`` (``throw=True``, the default), or the trajectory is
returned with ``status="failed"`` and the message (``throw=False``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import GaussppError, RealizabilityError
from ..model.model import Model
from ..model.run_scales import run_scales
from ..step import servo_reach
from ..step.outcome import QP_TOLERANCE
from . import lanes, recording, servo_lane
from . import methods as _methods
from .drift import Baumgarte, Stabilization, as_stabilization
from .events import check_gaps
from .initial import check_on_constraint, initial_state, project_initial, redundant_rows
from .inputs import DEFAULT_RTOL, Options, check_options, with_scales
from .rhs import AnyRightHandSide, GeneralRightHandSide, RightHandSide
from .samples import Samples
from .tolerance import within_tolerance
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
    rtol: float = DEFAULT_RTOL,
    atol: float | None = None,
    record: int | Any = 1,
    constraint_tol: float | None = None,
    throw: bool = True,
    rest_speed: float = 1e-6,
    max_events: int = 10_000,
    lane: str | None = None,
    drift_tol: float = 1e-3,
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
        The integrator. Default: without ``dt``, ``"DOP853"`` (adaptive, to ``rtol`` and ``atol``); with ``dt``,
        ``"rk4"`` (``"DOP853"`` for a model with unilateral contacts, whose events only adaptive methods
        locate). See :func:`gausspp.methods.names`: ``"rk4"``, ``"symplectic-euler"``, ``"RK45"``,
        ``"DOP853"``, ``"Radau"``, ``"BDF"``, ``"cvodes"``, ``"cvodes-adams"``. Where the method runs is
        gausspp's choice (:mod:`gausspp.simulation.lanes`): ``"rk4"`` runs as one compiled casadi graph
        unless something needs Python — bounded actuators or redundant rows, a QP backend outside casadi — and
        from Python then; ``Trajectory.lane`` says which, and ``lane`` chooses.
    solver : {"qp", "direct"}
        How each step is solved; ``backend`` picks the QP backend.
    stabilize : None, False, "baumgarte", "project", Baumgarte, or a list of these
        Drift control. ``"project"`` moves ``q`` and ``v`` back onto the constraints along ``A⁻¹D`` after every step
        (and the initial data first). By default (``None``) an adaptive run at ``rtol`` above 1e-8 of a model with
        bilateral rows (no contacts) projects after a step whose state drifted by more than 1e-10 relative
        (:data:`PROJECT_BELOW_DRIFT`): a loosened tolerance gives a faster run that stays on its constraints; at
        tighter tolerances, and with ``False``, there is no drift control.
    rtol, atol : float
        Tolerances of adaptive methods: a step's error estimate on each component of ``q``, ``v``, ``λ`` within
        ``atol + rtol·|y|``; the works ``W_R``, ``W_F`` are integrated by the same steps and do not choose them.
        ``rtol`` defaults to 1e-10. ``atol`` defaults to ``rtol`` times each component's own size, read from the
        initial state and the machine (:mod:`gausspp.model.run_scales`): the same relative accuracy in any
        units, for a small motion about an equilibrium as for a large one. A number is an absolute tolerance in
        the state's units, the same for every component.
    record : int or array
        Record every ``record``-th step (fixed-step methods; every accepted step for adaptive
        ones), or at the given times (must lie on the grid for fixed-step methods).
    throw : bool
        Raise on failure (the exception's ``.trajectory`` holds what was computed), or return
        the partial trajectory with ``status="failed"``.
    rest_speed, max_events :
        Unilateral contacts only (:mod:`gausspp.simulation.contacts`): an impact that would leave a contact
        slower than ``rest_speed`` ends in rest; a run with more than ``max_events`` events stops.
    constraint_tol : float
        The accuracy the run promises (default ``max(1e-8, 10·rtol)``: the accuracy asked for): the initial data
        must keep it, and a run that reached ``t_end`` is a success only if every sample keeps
        ``|g_i| ≤ constraint_tol·s_g,i`` and ``|Φ_i| ≤ constraint_tol·s_Φ,i`` — each row against its own scale,
        the size of the terms it adds up
        (:func:`gausspp.model.run_scales.row_scales`) — and, where the energy balance closes, the balance within
        ``100·constraint_tol`` of the run's energy scale (:func:`gausspp.model.run_scales.energy_scale`);
        otherwise its status is ``"drifted"`` (the trajectory whole, a :class:`~gausspp.DriftWarning`; not raised:
        :mod:`gausspp.simulation.tolerance`). Every scale is read from the machine (docs/guide.md, "The scales of a
        run"): the same at rest and in motion, in any units.
    drift_tol : float
        How far the motion may leave its constraints before the run counts as failed: a sample with
        ``|g_i| > drift_tol·s_g,i`` or ``|Φ_i| > drift_tol·s_Φ,i`` (the rows' own scales) ends the run with a
        :class:`~gausspp.DriftError` (a step too long for the motion, a step across a singular position off the
        branch). Rows of a model with bounded actuators are not checked (a saturated actuator falls short of its
        constraint: ``Trajectory.tracking_error``). Where the model's energy balance closes, a sample with
        ``|E − E₀ − W_R − W_F|`` above ``100·drift_tol`` of the run's energy scale ends it the same way
        (:mod:`gausspp.simulation.energy_audit`).
    lane : str, optional
        Run in this lane of :data:`gausspp.simulation.lanes.LANES` (``"python"``, ``"compiled"``,
        ``"scipy"``, ``"cvodes"``, ``"events"``) instead of the fastest that can; e.g. ``method="rk4",
        lane="python"`` steps from Python (progress on standard error, the step's checks at every stage).

    Returns
    -------
    Trajectory
    """
    if getattr(model, "friction", ()):  # frictional contacts: the friction lane (simulate_friction), a Trajectory
        from . import friction_lane

        friction_lane.check_friction_options(
            model, method=method, stabilize=stabilize, lam0=lam0, backend=backend, lane=lane
        )
        return friction_lane.run_friction(
            model, q0, v0, t_end, dt=dt, rtol=rtol, atol=atol, record=record, throw=throw, max_events=max_events
        )
    constraint_tol = _promised(constraint_tol, rtol)
    opts = check_options(
        model,
        method=method,
        t0=t0,
        t_end=t_end,
        dt=dt,
        solver=solver,
        backend=backend,
        rtol=rtol,
        atol=atol,
        record=record,
        constraint_tol=constraint_tol,
        throw=throw,
        rest_speed=rest_speed,
        max_events=max_events,
        lane=lane,
        drift_tol=drift_tol,
    )
    # a servo reached only through higher derivatives: index reduction
    if not model.contacts and servo_lane.wanted(model, opts.t0, q0, v0, opts.t_end - opts.t0):
        servo_lane.check_options(opts, stabilize, lam0)
        return servo_lane.run_servo(model, q0, v0, opts)
    stab = as_stabilization(_drift_control(model, stabilize, method, dt, rtol, lane), opts.dt)
    try:
        y0, redundant, chosen, opts = _start(model, q0, v0, lam0, stab, opts)
    except RealizabilityError as exc:  # a servo reached only through higher derivatives: point to index reduction
        raise servo_reach.explain(model, exc, opts.t0, q0, v0) from None
    rhs = None if model.contacts else _right_hand_side(model, opts, stab, redundant)  # the events lane: per phase
    job = lanes.Job(rhs, model, stab, opts, y0, redundant)
    samples = _run(chosen, job)
    return _servo_advice(
        model,
        opts.t0,
        y0,
        lambda: _labelled(
            chosen.name,
            model.route,
            lambda: within_tolerance(
                model,
                recording.finish(chosen.record(job, samples), samples.failure, opts.throw),
                opts.constraint_tol,
                opts.scales,
            ),
        ),
    )


def _servo_advice(model: Model, t0: float, y0: np.ndarray, run: Callable[[], Trajectory]) -> Trajectory:
    """``run()``; a realizability failure at the very start reworded by :func:`~gausspp.step.servo_reach.explain`
    when the actuators reach the constraint through higher derivatives (raised, or in the trajectory's message)."""
    q0, v0 = y0[: model.nq], y0[model.nq : model.nq + model.nv]
    try:
        traj = run()
    except RealizabilityError as exc:
        better = servo_reach.explain(model, exc, t0, q0, v0) if exc.t == t0 else exc
        if better is exc:
            raise
        better.trajectory = getattr(exc, "trajectory", None)  # type: ignore[attr-defined]
        raise better from None
    failure = traj.failure
    if isinstance(failure, RealizabilityError) and failure.t == t0 and traj.t.size <= 1:
        better = servo_reach.explain(model, failure, t0, q0, v0)
        if better is not failure:
            traj = recording.failed(traj, better)
    return traj


def _labelled(lane: str, route: str, run: Callable[[], Trajectory]) -> Trajectory:
    """The trajectory ``run`` returns, or carries on the error it raises, with ``lane`` (the lane that ran it)
    and ``route`` (the step's, :mod:`gausspp.step.equality.sparse`)."""
    try:
        return replace(run(), lane=lane, route=route)
    except GaussppError as exc:
        if isinstance(getattr(exc, "trajectory", None), Trajectory):
            exc.trajectory = replace(exc.trajectory, lane=lane, route=route)  # type: ignore[attr-defined]
        raise


#: Below this ``rtol`` a run keeps its constraints by its accuracy alone; above it, the scipy lane projects.
PROJECT_ABOVE_RTOL = 1e-8


def _promised(constraint_tol: Any, rtol: Any) -> Any:
    """The accuracy a run promises: ``constraint_tol`` as given, else ``max(1e-8, 10·rtol)`` — the accuracy asked
    for, never tighter than the default's (a number that is not one is left to :func:`check_options`)."""
    if constraint_tol is not None:
        return constraint_tol
    try:
        r = float(rtol)
    except (TypeError, ValueError):
        return 1e-8
    return max(1e-8, 10.0 * r) if np.isfinite(r) and r > 0 else 1e-8


def _drift_control(model: Model, stabilize: Any, method: Any, dt: Any, rtol: Any, lane: Any) -> Any:
    """``stabilize`` as given; by default, an adaptive run at ``rtol`` above :data:`PROJECT_ABOVE_RTOL` of a model
    with bilateral rows and no contacts projects onto its constraints after each step (``"project"``): a loosened
    tolerance then gives a faster run that stays on its constraints. At tighter tolerances the run keeps them by
    its accuracy and nothing is added."""
    if stabilize is not None or dt is not None or lane is not None or model.contacts or not getattr(model, "k", 0):
        return stabilize
    if method not in (None, "DOP853", "RK45", "RK23", "Radau"):
        return stabilize
    try:
        loose = float(rtol) > PROJECT_ABOVE_RTOL
    except (TypeError, ValueError):
        return stabilize
    return Stabilization(project=True, project_above=PROJECT_BELOW_DRIFT) if loose else stabilize


#: The default drift control projects a state whose relative drift exceeds this (and leaves the others alone: on a
#: machine whose integration keeps its constraints, it costs one drift measure per step).
PROJECT_BELOW_DRIFT = 1e-10


def _start(
    model: Model, q0: Any, v0: Any, lam0: Any, stab: Stabilization, opts: Options
) -> tuple[np.ndarray, bool, lanes.Lane, Options]:
    """The initial state ``y0`` (projected if asked, checked on the constraint), whether the rows are redundant
    there, the lane that runs the model, and the options with the run's scales (:mod:`.scales`)."""
    q, v, lam = initial_state(model, opts.t0, q0, v0, lam0)
    if model.contacts:  # the phases decide their rows; a contact's gap must not be negative
        lane = lanes.check_kind(opts.method, lanes.kind_of(model), opts.solver, stab.project, opts.lanes)
        scales = run_scales(model, opts.t0, q, v, lam, opts.t_end - opts.t0)
        check_on_constraint(model, opts.t0, q, v, lam, opts.constraint_tol, hint="correct q0/v0", scales=scales)
        check_gaps(model, opts.t0, q, v)
        return np.concatenate([q, v, lam, [0.0, 0.0]]), False, lane, with_scales(opts, scales)
    redundant = redundant_rows(model, opts.solver, opts.backend, opts.t0, q, v, lam)
    if stab.project:
        q, v = project_initial(model, opts.t0, q, v, lam, opts.constraint_tol, redundant)
    scales = run_scales(model, opts.t0, q, v, lam, opts.t_end - opts.t0)
    check_on_constraint(model, opts.t0, q, v, lam, opts.constraint_tol, scales=scales)
    lane = lanes.check_kind(opts.method, lanes.kind_of(model, redundant), opts.solver, stab.project, opts.lanes)
    return np.concatenate([q, v, lam, [0.0, 0.0]]), redundant, lane, with_scales(opts, scales)


def _right_hand_side(model: Model, opts: Options, stab: Stabilization, redundant: bool) -> AnyRightHandSide:
    """The compiled step, or the general Gauss QP (bounded actuators, redundant rows: no margin to check)."""
    if redundant or model.bounded:
        return GeneralRightHandSide(model, opts.backend, stab, margin_checked=not redundant)
    return RightHandSide(model, opts.solver, opts.backend, stab)


def _run(lane: lanes.Lane, job: lanes.Job) -> Samples:
    """Run ``lane`` (its runner, :attr:`~gausspp.simulation.lanes.Lane.run`); a failure before the first step keeps
    the initial state."""
    try:
        return lane.run(job)
    except GaussppError as exc:  # failed before the first step could be kept
        o, rhs = job.opts, job.rhs
        evaluations, solver = (0, o.solver) if rhs is None else (rhs.evaluations, rhs.solver)
        return Samples(np.array([o.t0]), job.y0[None, :], 0, evaluations, exc, o.method.name, solver)


__all__ = ["QP_TOLERANCE", "simulate"]
