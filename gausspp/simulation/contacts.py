"""Event-driven simulation with unilateral contacts: flight, impacts, resting contact, lift-off.

A run is a sequence of smooth *phases*. In each phase the set of active contacts is fixed and
those contacts are kept as ideal bilateral constraints ``g = 0`` — a compiled model per active
set, built on first use and kept — so the phase is integrated as accurately as any
equality-constrained motion. Which contacts are active is decided by Gauss's principle with
inequalities at the phase's start (:meth:`Model.general_step`: a closed, non-separating contact
is active iff its force is positive). A phase ends at the first event, located by the
integrator's root finder on its dense output:

* an open contact's gap ``g`` reaches zero from above → the contact closes; if it approaches,
  the velocities jump by the velocity-level Gauss QP with Newton's restitution law
  (:meth:`Model.impact`), and the impulse's work is added to the reaction's work so that
  the energy balance still closes;
* an active contact's force reaches zero from above → the contact lets go (lift-off).

Active contacts are kept like any holonomic constraint, to the integration tolerance: a body
rolling on a contact drifts into it by about ``rtol`` (2e-11 at ``rtol = 1e-10`` for a turning block).

**Rest.** A ball with ``0 < e < 1`` bounces infinitely often in finite time (Zeno). When a
contact would leave the impact slower than ``rest_speed`` the impact is taken as plastic
(``e = 0``) and the contact rests from then on. Each impact is recorded twice (before and
after the jump, same time) and listed in ``Trajectory.events``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaussppError, InitialDataError, InputError, IntegrationError
from ..model.constraints import Holonomic
from ..model.model import Model
from ..model.symbolic import evaluate
from . import methods as _methods
from .drift import as_stabilization
from .rhs import RightHandSide
from .trajectory import Trajectory

#: Largest number of events (impacts, lift-offs) in one run before it is stopped as Zeno-like.
MAX_EVENTS = 10_000


def _phase_model(model: Model, active: tuple[int, ...]) -> Model:
    """The model with the active contact rows as ideal bilateral constraints (cached per active set)."""
    cache: dict[tuple[int, ...], Model] = model.__dict__.setdefault("_phase_models", {})
    if active not in cache:
        rows: list[tuple[Any, int, str]] = []
        for c, name, k in zip(model.contacts, model.contact_names, model.contact_rows, strict=True):
            rows += [(c, j, name if k == 1 else f"{name}[{j}]") for j in range(k)]
        extra = []
        for i in active:
            c, j, name = rows[i]

            def gap(q: Any, t: Any, c: Any = c, j: int = j, name: str = name) -> Any:
                return evaluate(c._g, (q, t), (None, 1), f"contact {name!r}: g(q, t)")[j]

            extra.append(Holonomic(gap, name=f"contact {name}"))
        cache[active] = Model(
            model.mechanism,
            [*model.constraints, *extra],
            margin_warn=model.margin_warn,
            margin_error=model.margin_error,
            refine=model.refine,
            _allow_free=True,
        )
    return cache[active]


def _gap_function(model: Model) -> ca.Function:
    if "_gap_fn" not in model.__dict__:
        mech = model.mechanism
        gc, _Jc, _phic, gdotc = model.contact_expressions
        model.__dict__["_gap_fn"] = ca.Function("contact_gaps", [mech.t, mech.q, mech.v], [gc, gdotc])
    fn: ca.Function = model.__dict__["_gap_fn"]
    return fn


def _gaps(model: Model, t: float, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    g, gdot = _gap_function(model)(t, q, v)
    return np.array(g).ravel(), np.array(gdot).ravel()


def _active_set(
    model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, backend: str | None, closed: set[int]
) -> tuple[int, ...]:
    """Closed, non-separating contacts whose force by the inequality Gauss QP is positive."""
    _g, gdot = _gaps(model, t, q, v)
    candidates = [i for i in sorted(closed) if gdot[i] <= model.contact_tol]
    if not candidates:
        return ()
    force = model.general_step(t, q, v, lam, backend=backend, closed=candidates)[0].contact_force
    threshold = 1e-10 * max(1.0, float(np.max(np.abs(force), initial=0.0)))
    return tuple(i for i in candidates if force[i] > threshold)


def _off_the_start(value: float, t: float, t_start: float) -> float:
    """An event function's value, made positive at the phase's start: a phase begins *on* the boundaries it
    watches (g = 0 after a touch, ġ = 0 after a release), and the root finder would otherwise return the
    start itself as the event — no progress, the same event again (chattering at one instant)."""
    return max(value, 1e-300) if t == t_start else value


def simulate_contacts(
    model: Model,
    q0: Any,
    v0: Any,
    t_end: float,
    *,
    t0: float = 0.0,
    lam0: Any = None,
    dt: float | None = None,
    method: str | _methods.Method = "DOP853",
    solver: str = "direct",
    backend: str | None = None,
    stabilize: Any = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    constraint_tol: float = 1e-8,
    throw: bool = True,
    rest_speed: float = 1e-6,
    max_events: int = MAX_EVENTS,
    record: Any = 1,
) -> Trajectory:
    """Integrate a model with unilateral contacts (see the module docstring); ``gp.simulate`` calls this.

    Only adaptive scipy methods (RK45, DOP853, Radau, BDF) can locate events; ``dt`` caps their step.
    ``record``: every accepted step (a number), or an array of times (from the dense output); the
    states just before and after each impact are always recorded.
    Phases with active contacts are solved by ``solver``; the decisions (active set, impacts) by the
    general Gauss QP with ``backend`` when it names a qpsolvers solver.
    """
    import scipy.integrate as si

    meth = _methods.get(method)
    if meth.lane != "scipy":
        raise InputError(
            f"method {meth.name!r} cannot locate contact events; a model with unilateral contacts needs an adaptive "
            "scipy method: 'DOP853' (default), 'RK45', 'Radau' or 'BDF'"
        )
    if not (rest_speed >= 0 and np.isfinite(rest_speed)):
        raise InputError(f"rest_speed must be a finite number ≥ 0, got {rest_speed}")
    if model.bounded:
        raise InputError("unilateral contacts together with bounded actuators are not supported")
    stab = as_stabilization(stabilize, dt)
    if stab.project:
        raise InputError("stabilize='project' is not supported with contacts; use 'baumgarte' or None")
    t, q, v, lam = model.checked_state(t0, q0, v0, lam0)
    t_end = float(t_end)
    if not (np.isfinite(t_end) and t_end > t):
        raise InputError(f"need finite t0 < t_end, got t0={t}, t_end={t_end}")
    from .simulate import _check_on_constraint

    _check_on_constraint(model, t, q, v, lam, constraint_tol, hint="correct q0/v0")
    g, gdot = _gaps(model, t, q, v)
    if np.any(g < -model.contact_tol):
        i = int(np.argmin(g))
        raise InitialDataError(
            f"initial data penetrate the contact {model.contact_row_names[i]!r} at t={t:.6g}: g = {g[i]:.3g} < 0; "
            "start with every gap g ≥ 0"
        )
    gb = backend if backend is None or not backend.startswith("casadi:") else None
    qb = None if backend is None or backend.startswith("qpsolvers:") else backend
    nq, nv, nl, m = model.nq, model.nv, model.n_lam, model.m
    times = None if np.isscalar(record) else np.sort(np.asarray(record, float))
    if times is not None and (times.size == 0 or times[0] < t or times[-1] > t_end):
        raise InputError(f"record times must lie within [t0, t_end] = [{t:g}, {t_end:g}]")
    y = np.concatenate([q, v, lam, [0.0, 0.0]])
    ts: list[float] = [t]
    ys: list[np.ndarray] = [y.copy()]
    phases: list[tuple[int, ...]] = []
    events: list[dict[str, Any]] = []
    failure: Exception | None = None
    evaluations = steps = 0
    closed: set[int] = {int(i) for i in np.flatnonzero(g <= model.contact_tol)}
    departing: set[int] = set()  # at g ≈ 0 and separating: watched on ġ until they turn round
    jumps: list[float] = []  # times of the velocity jumps (numbered from 1 in the events)
    sample_phase: list[int] = [0]

    def impact(t_e: float, y_e: np.ndarray) -> np.ndarray:
        qe, ve, le = y_e[:nq], y_e[nq : nq + nv], y_e[nq + nv : nq + nv + nl]
        _g, gd = _gaps(model, t_e, qe, ve)
        slow = np.flatnonzero(model.restitution * np.maximum(-gd, 0.0) < rest_speed)
        res = model.impact(t_e, qe, ve, le, backend=gb, plastic=slow, closed=sorted(closed))
        after = _gaps(model, t_e, qe, res.v_after)[1]
        for i in res.closed:  # contacts that leave the impact separating are open again
            if after[i] > model.contact_tol:
                closed.discard(int(i))
                departing.add(int(i))
        y_new = y_e.copy()
        y_new[nq : nq + nv] = res.v_after
        y_new[nq + nv : nq + nv + nl] = res.lam_after
        y_new[-2] += res.kinetic_energy_after - res.kinetic_energy_before  # the impulse's work
        jumps.append(t_e)  # one velocity jump may close several contacts at once: they share its number
        jump = len(jumps)
        for i in res.closed:
            if gd[i] < -model.contact_tol:  # an approaching contact (a resting one only takes part)
                events.append(
                    {
                        "t": t_e,
                        "kind": "impact",
                        "jump": jump,
                        "contact": model.contact_row_names[i],
                        "speed_before": float(gd[i]),
                        "speed_after": float(after[i]),
                        "impulse": float(res.impulse[i]),
                        "kinetic_energy_before": res.kinetic_energy_before,
                        "kinetic_energy_after": res.kinetic_energy_after,
                        "plastic": bool(i in slow),
                    }
                )
        return y_new

    try:
        if np.any((g <= model.contact_tol) & (gdot < -model.contact_tol)):
            y = impact(t, y)
            ts.append(t)
            ys.append(y.copy())
            sample_phase.append(0)
        while t < t_end:
            qc, vc, lc = y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl]
            active = _active_set(model, t, qc, vc, lc, gb, closed)
            released = closed - set(active)  # closed but pushing nothing: it separates (g̈ > 0) — watch it leave
            closed -= released
            gdot_start = _gaps(model, t, qc, vc)[1]
            # departing contacts that turned round (ġ ≤ 0, e.g. at the same instant as another's apex) watch g
            departing = {i for i in departing if gdot_start[i] > 0} | released
            sub = _phase_model(model, active)
            sub_solver = "direct" if sub.k == 0 else solver
            rhs = RightHandSide(sub, sub_solver, qb if sub_solver == "qp" else None, stab)
            phases.append(active)
            inactive = [i for i in range(len(model.contact_row_names)) if i not in active]
            # a closed contact that separates is watched on ġ: it must turn round (ġ crosses zero) before it
            # can close again, and one long step from g ≈ 0 to g < 0 would show no sign change of g
            event_fns: list[Callable[..., float]] = []
            for i in inactive:
                which = 1 if i in departing or i in closed else 0

                def closes(t_: float, y_: np.ndarray, i: int = i, which: int = which, t0_: float = t) -> float:
                    value = float(_gaps(model, t_, y_[:nq], y_[nq : nq + nv])[which][i])
                    return _off_the_start(value, t_, t0_)

                closes.terminal, closes.direction = True, -1  # type: ignore[attr-defined]
                event_fns.append(closes)
            for pos, _i in enumerate(active):

                def lets_go(
                    t_: float, y_: np.ndarray, col: int = m + pos, rhs: RightHandSide = rhs, t0_: float = t
                ) -> float:
                    return _off_the_start(float(rhs.evaluate(t_, y_)["u"][col]), t_, t0_)

                lets_go.terminal, lets_go.direction = True, -1  # type: ignore[attr-defined]
                event_fns.append(lets_go)
            options: dict[str, Any] = {"rtol": rtol, "atol": atol}
            if times is not None:
                options["t_eval"] = times[(times > t) & (times <= t_end)]
            if dt is not None:
                options["max_step"] = dt
            try:
                sol = si.solve_ivp(rhs, (t, t_end), y, method=meth.name, events=event_fns or None, **options)
            finally:
                evaluations += rhs.evaluations
            sol_t = np.asarray(sol.t, float)
            sol_y = np.asarray(sol.y, float).reshape(y.size, sol_t.size)
            steps += max(sol_t.size - 1, 0)
            first = 0 if times is not None else 1  # t_eval excludes the phase's start
            for tk, yk in zip(sol_t[first:], sol_y.T[first:], strict=True):
                ts.append(float(tk))
                ys.append(yk.copy())
                sample_phase.append(len(phases) - 1)
            if sol.status == -1:
                raise IntegrationError(f"{meth.name} stopped after t={t:.6g}: {sol.message}")
            if sol.status == 0:
                break
            fired = [(float(te[0]), j) for j, te in enumerate(sol.t_events) if te.size]
            t_e, j = min(fired)
            y_e = sol.y_events[j][0].copy()
            if not ts or ts[-1] != t_e:
                ts.append(t_e)
                ys.append(y_e.copy())
                sample_phase.append(len(phases) - 1)
            t, y = t_e, y_e
            if j < len(inactive) and (inactive[j] in departing or inactive[j] in closed):
                departing.discard(inactive[j])  # a separating contact turned round (its apex): watch its gap now
                closed.discard(inactive[j])
            elif j < len(inactive):  # a contact closes (with any other that closes at the same instant)
                i = inactive[j]
                g_now, gd_now = _gaps(model, t, y[:nq], y[nq : nq + nv])
                closed.add(i)
                closed.update(
                    int(c) for c in np.flatnonzero((g_now <= model.contact_tol) & (gd_now <= model.contact_tol))
                )
                departing -= closed
                gd = _gaps(model, t, y[:nq], y[nq : nq + nv])[1][i]
                if gd < -model.contact_tol:
                    y = impact(t, y)
                    ts.append(t)
                    ys.append(y.copy())
                    sample_phase.append(len(phases))  # belongs to the next phase
                else:
                    events.append({"t": t, "kind": "touch", "contact": model.contact_row_names[i]})
            else:  # an active contact's force reaches zero
                i = active[j - len(inactive)]
                closed.discard(i)
                departing.add(i)
                events.append({"t": t, "kind": "lift-off", "contact": model.contact_row_names[i]})
            if len(events) > max_events:
                raise IntegrationError(
                    f"more than {max_events} contact events by t={t:.6g} (Zeno-like chattering): raise rest_speed so "
                    "that slow impacts end in rest, or max_events (both arguments of gp.simulate)"
                )
    except GaussppError as exc:
        failure = exc
    active_of = [phases[p] if p < len(phases) else () for p in sample_phase[: len(ts)]]
    traj = _record(
        model, np.array(ts), np.array(ys), active_of, meth.name, solver, steps, evaluations, tuple(events), qb
    )
    if failure is not None:
        traj = replace(traj, status="failed", message=f"{type(failure).__name__}: {failure}")
        if throw:
            failure.trajectory = traj  # type: ignore[attr-defined]
            raise failure
    return traj


def _record(
    model: Model,
    ts: np.ndarray,
    ys: np.ndarray,
    active_of: list[tuple[int, ...]],
    method: str,
    solver: str,
    steps: int,
    evaluations: int,
    events: tuple[dict[str, Any], ...],
    qb: str | None,
) -> Trajectory:
    """Outputs at every sample, with the active set of the phase it belongs to."""
    nq, nv, nl, m, k = model.nq, model.nv, model.n_lam, model.m, model.k
    n_rows = len(model.contact_row_names)
    N = ts.size
    cols = {
        "a": np.zeros((N, nv)),
        "u": np.zeros((N, m)),
        "reaction": np.zeros((N, nv)),
        "compulsion": np.zeros(N),
        "residual": np.zeros((N, k)),
        "g": np.zeros((N, k)),
        "margin": np.ones(N),
        "energy": np.full(N, np.nan),
        "contact_force": np.zeros((N, n_rows)),
    }
    for n in range(N):
        q, v, lam = ys[n, :nq], ys[n, nq : nq + nv], ys[n, nq + nv : nq + nv + nl]
        active = active_of[n]
        sub = _phase_model(model, active)
        out = sub.kernel("direct" if sub.k == 0 or solver == "direct" else "qp", qb if solver == "qp" else None)(
            ts[n], q, v, lam, np.zeros(2)
        )
        cols["a"][n] = out["a"].ravel()
        u = out["u"].ravel()
        cols["u"][n] = u[:m]
        cols["contact_force"][n, list(active)] = u[m:]
        cols["reaction"][n] = out["reaction"].ravel()
        cols["compulsion"][n] = float(out["compulsion"][0])
        cols["residual"][n] = out["Phi"].ravel()[:k]
        cols["g"][n] = out["g"].ravel()[:k]
        if k:
            S = np.asarray(out["S_norm"]).reshape(sub.k, sub.m)[:k, :m]
            cols["margin"][n] = float(np.linalg.svd(S, compute_uv=False).min()) if m >= k else 0.0
        if model.has_energy:
            cols["energy"][n] = float(out["energy"][0])
    return Trajectory(
        t=ts,
        q=ys[:, :nq].copy(),
        v=ys[:, nq : nq + nv].copy(),
        lam=ys[:, nq + nv : nq + nv + nl].copy(),
        a=cols["a"],
        u=cols["u"],
        reaction=cols["reaction"],
        compulsion=cols["compulsion"],
        residual=cols["residual"],
        g=cols["g"],
        margin=cols["margin"],
        energy=cols["energy"],
        work_reaction=ys[:, -2].copy(),
        work_forces=ys[:, -1].copy() if model.has_force_power else np.full(N, np.nan),
        status="success",
        message="",
        method=method,
        solver=solver,
        steps=steps,
        rhs_evaluations=evaluations,
        contact_force=cols["contact_force"],
        tracking_error=np.zeros(N),
        saturated=np.zeros((N, m), bool),
        events=events,
    )
