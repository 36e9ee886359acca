"""Event-driven simulation of a mechanism with frictional contacts (docs/friction.md).

Between events the contact modes are fixed (:mod:`.modes`) and scipy's DOP853 (Radau while a two-component slip
slides: :meth:`.runner.Runner.method`) integrates ``q̇ = K(q, v)``, ``v̇ = q̈`` — or, with ``step=h``, compiled RK4 steps
(:mod:`.fixed_step`). Its events end a phase where a mode stops holding:

* an open contact's gap closes;
* a closed one's normal force ``N`` falls to zero (lift-off);
* a sliding one's slip ``s`` reaches zero (it stops: it sticks or slides back) — or, with two components, turns
  90° from the phase's first direction (``"turns"``: the next phase takes the new one);
* a sticking one's friction reaches the cone ``|F| = μ_s N`` (it starts to slide).

At each event the modes are chosen anew; a gap closing with approaching speed is an impact first (Newton's
restitution on the normal velocity, Coulomb's law on the impulses: :func:`impact`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import GaussppError, InputError, IntegrationError, ShapeError
from ..model.friction_contact import FrictionContact, as_contacts
from ..model.mechanism import Mechanism
from ..model.model import Model
from ..validation import array, flag, positive, record_times
from ..workspace import workspace
from .fixed_step import run_phase
from .modes import Modes, check_painleve
from .run import FrictionRun, Record
from .runner import CONTACT_TOL, Runner


def simulate_friction(
    system: Mechanism | Model,
    contacts: FrictionContact | list[FrictionContact],
    q0: Any,
    v0: Any,
    t_end: float,
    *,
    step: float | None = None,
    codegen: bool = False,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_events: int = 1000,
    throw: bool = True,
    record: Any = None,
) -> FrictionRun:
    """Simulate ``system`` (a mechanism, or a model without constraints) with frictional ``contacts`` (a
    :class:`FrictionContact` or a list of them) from ``(q0, v0)`` to ``t_end`` (module docstring). Raises
    :class:`~gausspp.PainleveError` where sliding makes the contact problem inconsistent; a failure midway keeps
    what was computed (``.run``, or the returned run marked failed with ``throw=False``).

    ``step``: ``None`` (default) integrates each phase adaptively (DOP853, Radau; ``rtol``, ``atol``); a number
    ``h`` takes RK4 steps of ``h`` compiled into one casadi graph per phase, each event located exactly inside its
    step (:mod:`.fixed_step`: a time-stepping cost per step, the events kept); with ``codegen=True`` each phase's
    steps run as C where a compiler is (:mod:`gausspp.c_code`: built once per phase, kept on disk).
    ``record``: increasing times to sample at (besides the events); default every step the integrator takes."""
    runner = _runner(system, contacts)
    q = array("simulate_friction", "q0", q0).ravel()
    v = array("simulate_friction", "v0", v0).ravel()
    if q.size != runner.nq or v.size != runner.nv:
        raise ShapeError(f"simulate_friction: q0 needs {runner.nq} entries and v0 {runner.nv}, got {q.size}, {v.size}")
    opts = FrictionOptions.checked(t_end, step, codegen, rtol, atol, max_events, record)
    rec = Record(runner.nq, runner.nv, len(runner.contacts), int(sum(runner.kin.dims)))
    events: list[dict[str, Any]] = []
    failure: Exception | None = None
    if opts.codegen:  # the state's function as C too (the adaptive lane calls it at every stage and event)
        runner.kin.compile_c()
    try:
        runner.check_start(q, v)
        (_adaptive if opts.step is None else _fixed_step)(runner, q, v, opts=opts, rec=rec, events=events)
    except GaussppError as exc:
        failure = exc
    run = rec.run(tuple(runner.names), events)
    if failure is not None:
        run.status, run.message, run.failure = "failed", f"{type(failure).__name__}: {failure}", failure
        if throw:
            failure.run = run  # type: ignore[attr-defined]
            raise failure
    return run


@dataclass(frozen=True)
class FrictionOptions:
    """The checked options of :func:`simulate_friction` (see there), as they flow to the phases."""

    t_end: float
    step: float | None
    codegen: bool
    rtol: float
    atol: float
    max_events: int
    times: np.ndarray | None

    @classmethod
    def checked(
        cls, t_end: Any, step: Any, codegen: Any, rtol: Any, atol: Any, max_events: Any, record: Any
    ) -> FrictionOptions:
        t_end = float(positive("t_end", t_end))
        times = None if record is None else record_times("simulate_friction", record, 0.0, t_end)
        return cls(
            t_end=float(positive("t_end", t_end)),
            step=None if step is None else float(positive("step", step)),
            codegen=flag("simulate_friction", "codegen", codegen),
            rtol=float(positive("rtol", rtol)),
            atol=float(positive("atol", atol)),
            max_events=int(positive("max_events", max_events)),
            times=times,
        )


def _runner(system: Mechanism | Model, contacts: FrictionContact | list[FrictionContact]) -> Runner:
    """The runner of ``system``'s mechanism and ``contacts`` (checked), kept in the mechanism's workspace with its
    compiled phases for the next run."""
    mech = system.mechanism if isinstance(system, Model) else system
    if isinstance(system, Model) and system.k:
        raise InputError("simulate_friction takes a mechanism (or a model without constraint rows)")
    if not isinstance(mech, Mechanism):
        raise InputError(f"simulate_friction takes a gausspp mechanism or model, got {type(system).__name__}")
    contacts = as_contacts("simulate_friction", contacts)
    key = ("friction-runner", *((c, c.gap, c.slip, c.mu, c.mu_static, c.restitution) for c in contacts))
    return workspace(mech).get(key, lambda: Runner(mech, contacts))


def _next_modes(
    runner: Runner, t: float, y: np.ndarray, fired: list[tuple[str, int]], max_events: int, events: list
) -> tuple[Modes, np.ndarray]:
    """The modes after the events ``fired`` at ``(t, y)`` (and the velocity after an impact), the events logged. A
    two-component slip whose ``d·s`` fell through zero while it still slips has turned by 90°, not stopped: its
    event is logged as ``"turns"`` (the next phase slides along its new direction)."""
    if len(events) >= max_events:
        raise IntegrationError(f"more than max_events={max_events} contact events by t={t:.6g}")
    q, v = runner.split(y)
    s, speed = runner.kin(q, v).s, 1.0 + np.abs(v).max(initial=0.0)
    modes, v, _ = runner.modes_at(t, q, v, tuple(fired))
    for kind, i in fired:
        if kind == "stops slipping" and s[i].size > 1 and np.linalg.norm(s[i]) > CONTACT_TOL * speed:
            kind = "turns"
        events.append({"t": t, "kind": kind, "contact": runner.names[i], "modes": modes.names()})
    return modes, np.concatenate([q, v])


def _fixed_step(
    runner: Runner, q: np.ndarray, v: np.ndarray, *, opts: FrictionOptions, rec: Record, events: list
) -> None:
    """Phases of compiled RK4 steps of ``h`` (:func:`.fixed_step.run_phase`), event to event."""
    phases = runner.phases
    modes, v, _ = runner.modes_at(0.0, q, v)
    t, y = 0.0, np.concatenate([q, v])
    while True:
        t, y, fired = run_phase(
            phases, modes, t, y, t_end=opts.t_end, h=opts.step, times=opts.times, record=rec, codegen=opts.codegen
        )
        if not fired:
            return
        modes, y = _next_modes(runner, t, y, fired, opts.max_events, events)
        if t >= opts.t_end:  # an event at t_end ends the run (no phase of length zero after it)
            return


def _adaptive(
    runner: Runner, q: np.ndarray, v: np.ndarray, *, opts: FrictionOptions, rec: Record, events: list
) -> None:
    """Phases integrated by scipy (DOP853, or Radau where a two-component slip slides), event to event."""
    from scipy.integrate import solve_ivp  # imported here: ``import gausspp`` does not load scipy's integrators

    t, times = 0.0, opts.times
    modes, v, _ = runner.modes_at(t, q, v)
    y = np.concatenate([q, v])
    while t < opts.t_end:
        check_painleve(runner.kin(*runner.split(y)), runner.contacts, modes, t)
        _keep(runner, rec, modes, [t], [y])  # the phase's start, kept if the phase fails
        watched = runner.events(modes, y)
        sol = solve_ivp(
            runner.compiled_rhs(modes, y, opts.codegen) or runner.rhs(modes),
            (t, opts.t_end),
            y,
            method=runner.method(modes),
            rtol=opts.rtol,
            atol=opts.atol,
            events=watched,
            **({"jac": runner.jacobian(modes)} if runner.method(modes) == "Radau" else {}),
            t_eval=None if times is None else np.append(times[(times > t) & (times < opts.t_end)], opts.t_end),
        )
        failed = sol.status == -1
        sol.t, sol.y = np.atleast_1d(np.asarray(sol.t, float)), np.asarray(sol.y, float).reshape(y.size, -1)
        ends = [(te[0], ye[0]) for te, ye in zip(sol.t_events, sol.y_events, strict=True) if te.size]
        if times is not None:  # the phase's start, the sampled times, then the event's state
            seg_t, seg_y = [t, *sol.t], [y, *sol.y.T]
            if ends:
                seg_t.append(ends[0][0]), seg_y.append(ends[0][1])
        else:
            seg_t, seg_y = list(sol.t), list(sol.y.T)
        _keep(runner, rec, modes, seg_t[1:], seg_y[1:])
        t, y = float(seg_t[-1]), np.asarray(seg_y[-1])
        if failed:  # what it computed is recorded above
            raise IntegrationError(f"the integrator failed at t={sol.t[-1]:.6g}: {sol.message}")
        if sol.status == 0:
            return
        fired = [
            ("closes", ev.closing(y)) if ev.what == ("closes", -1) else ev.what
            for ev, te in zip(watched, sol.t_events, strict=True)
            if te.size
        ]
        modes, y = _next_modes(runner, t, y, fired, opts.max_events, events)


def _keep(runner: Runner, rec: Record, modes: Modes, ts: list, ys: list) -> None:
    """Record the states ``ys`` at ``ts`` of a phase under ``modes``, with their forces and energy."""
    names = modes.names()
    for ti, yi in zip(ts, ys, strict=True):
        st = runner.kin.checked(*runner.split(yi), ti, runner.names)
        acc = runner.accel(st, modes, runner.split(yi)[1])
        rec.add(ti, yi, names, acc.N, np.concatenate(acc.F), st.energy)
