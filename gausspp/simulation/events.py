"""The event-driven lane: runs with unilateral contacts — flight, impacts, resting contact, lift-off.

A run is a sequence of smooth *phases* (:mod:`gausspp.simulation.contacts`: in each, the active
contacts are ideal bilateral constraints). A phase ends at the first event, located by the
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

from typing import Any

import numpy as np

from ..errors import GaussppError, InitialDataError, IntegrationError
from ..model.model import Model
from . import general_stages, lanes, recording
from .contacts import active_set, gaps, phase_step
from .drift import Stabilization
from .event_watch import PhaseWatch, StepDense
from .first_step import initial_step
from .inputs import Options
from .rhs import RightHandSide, step_control_atol
from .samples import Samples


def check_gaps(model: Model, t0: float, q: np.ndarray, v: np.ndarray) -> None:
    """Refuse initial data inside a contact (a gap below ``−contact_tol``) with an :class:`InitialDataError`."""
    g, _gdot = gaps(model, t0, q, v)
    if np.any(g < -model.contact_tol):
        i = int(np.argmin(g))
        raise InitialDataError(
            f"initial data penetrate the contact {model.contact_row_names[i]!r} at t={t0:.6g}: g = {g[i]:.3g} "
            "< 0; start with every gap g ≥ 0"
        )


def run_events(job: lanes.Job) -> Samples:
    """The events lane's runner: the phases from the checked start ``job.y0`` (:class:`EventRun`)."""
    return EventRun(job.model, job.opts, job.stab, job.y0).samples()


def record_events(job: lanes.Job, samples: Samples) -> recording.Recorded:
    """The events lane's recording: each sample by the model of its phase (:func:`recording.record_contacts`)."""
    return recording.record_contacts(job.model, samples, job.opts.drift_tol, job.opts.scales)


class EventRun:
    """The state of an event-driven run: samples, phases, closed and departing contacts, events."""

    def __init__(self, model: Model, opts: Options, stab: Stabilization, y0: np.ndarray) -> None:
        self.model, self.opts, self.stab = model, opts, stab
        self.decisions_backend = opts.backend
        self.t, self.y = opts.t0, y0
        self.ts: list[float] = [opts.t0]
        self.ys: list[np.ndarray] = [y0.copy()]
        self.sample_phase: list[int] = [0]
        self.phases: list[tuple[int, ...]] = []
        self.events: list[dict[str, Any]] = []
        self.jumps: list[float] = []  # times of the velocity jumps (numbered from 1 in the events)
        self.steps = self.evaluations = 0
        self._last_gaps: tuple[float, np.ndarray, tuple[np.ndarray, np.ndarray]] | None = None
        g, _gdot = self.gaps(self.t, y0)
        self.closed: set[int] = {int(i) for i in np.flatnonzero(g <= model.contact_tol)}
        self.departing: set[int] = set()  # at g ≈ 0 and separating: watched on ġ until they turn round
        record = opts.record
        self.times = None if np.isscalar(record) else np.sort(np.asarray(record, float))

    def gaps(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The contacts' gaps and rates at ``(t, y)``; the last state's kept (scipy asks every event function, one
        contact each, at the same state)."""
        last = self._last_gaps
        if last is not None and last[0] == t and np.array_equal(last[1], y):
            return last[2]
        nq, nv = self.model.nq, self.model.nv
        out = gaps(self.model, t, y[:nq], y[nq : nq + nv])
        self._last_gaps = (t, y.copy(), out)
        return out

    def keep(self, t: float, y: np.ndarray, phase: int) -> None:
        self.ts.append(float(t))
        self.ys.append(y.copy())
        self.sample_phase.append(phase)

    def samples(self) -> Samples:
        """Run to ``t_end`` (or to a failure) and hand over what was computed."""
        failure: Exception | None = None
        try:
            self.run()
        except GaussppError as exc:
            failure = exc
        active_of = [self.phases[p] if p < len(self.phases) else () for p in self.sample_phase[: len(self.ts)]]
        o = self.opts
        y = np.array(self.ys)
        return Samples(
            np.array(self.ts),
            y,
            self.steps,
            self.evaluations,
            failure,
            o.method.name,
            o.solver,
            active_of,
            o.backend,
            tuple(self.events),
        )

    def run(self) -> None:
        model, opts = self.model, self.opts
        g, gdot = self.gaps(self.t, self.y)
        if np.any((g <= model.contact_tol) & (gdot < -model.contact_tol)):
            self.y = self.impact(self.t, self.y)
            self.keep(self.t, self.y, 0)
        while self.t < opts.t_end:
            fired = self.phase()
            if fired is None:
                break
            self.on_event(*fired)
            if len(self.events) > opts.max_events:
                raise IntegrationError(
                    f"more than {opts.max_events} contact events by t={self.t:.6g} (Zeno-like chattering): raise "
                    "rest_speed so that slow impacts end in rest, or max_events (both arguments of gp.simulate)"
                )

    def phase(self) -> tuple[int, list[int], tuple[int, ...]] | None:
        """Integrate one phase from ``(t, y)``, stepping the solver and judging each accepted step
        (:class:`~gausspp.simulation.event_watch.PhaseWatch`); return the event that ended it (``None`` at
        ``t_end``)."""
        model, opts, t, y = self.model, self.opts, self.t, self.y
        nq, nv, nl = model.nq, model.nv, model.n_lam
        active = active_set(
            model, t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], self.decisions_backend, self.closed
        )
        released = self.closed - set(active)  # closed but pushing nothing: it separates (g̈ > 0) — watch it leave
        self.closed -= released
        gdot_start = self.gaps(t, y)[1]
        # departing contacts that turned round (ġ ≤ 0, e.g. at the same instant as another's apex) watch g
        self.departing = {i for i in self.departing if gdot_start[i] > 0} | released
        sub, sub_solver, sub_backend = phase_step(model, active, opts.solver, opts.backend)
        rhs = RightHandSide(sub, sub_solver, sub_backend, self.stab)
        self.phases.append(active)
        inactive = [i for i in range(len(model.contact_row_names)) if i not in active]
        options: dict[str, Any] = {"rtol": opts.rtol, "atol": step_control_atol(opts.atol, y.size)}
        if opts.dt is not None:
            options["max_step"] = opts.dt
        cols = self.model.m + np.arange(len(active))
        watch = PhaseWatch(
            t, y, inactive, self.departing, len(active), self.gaps, lambda t_, y_: rhs.evaluate(t_, y_)["u"][cols]
        )
        phase = len(self.phases) - 1
        solver_class = general_stages.solver_class(opts.method.name, rhs)
        if opts.dt is None:  # the same first step in any units (:mod:`.first_step`)
            first = initial_step(rhs, solver_class, t, y, options, opts.t_end - t)
            if first is not None:
                options["first_step"] = first
        try:
            solver = solver_class(rhs, t, y, opts.t_end, **options)
            while solver.status == "running":
                t_old = solver.t
                message = solver.step()
                if solver.status == "failed":
                    raise IntegrationError(f"{opts.method.name} stopped after t={t_old:.6g}: {message}")
                self.steps += 1
                dense = StepDense(solver)
                hit = watch.first_event(t_old, solver.t, solver.y, dense)
                t_stop = solver.t if hit is None else hit[0]
                self.keep_step(t_old, t_stop, solver.y if hit is None else None, dense, phase)
                if hit is not None:
                    self.departing = watch.departing | (self.departing - set(inactive))
                    self.t, self.y = self.ts[-1], self.ys[-1].copy()
                    return hit[1], inactive, active
        finally:
            self.evaluations += rhs.evaluations
        self.departing = watch.departing | (self.departing - set(inactive))
        self.t, self.y = solver.t, solver.y.copy()
        return None

    def keep_step(self, t_old: float, t_stop: float, y_stop: np.ndarray | None, dense: StepDense, phase: int) -> None:
        """Keep an accepted step up to ``t_stop`` (its end, or an event inside it: always kept, from the dense
        output): every step's end, or the record times it passes."""
        if self.times is not None:
            for tk in self.times[(self.times > t_old) & (self.times <= t_stop)]:
                self.keep(float(tk), y_stop if (tk == t_stop and y_stop is not None) else dense(tk), phase)
        if y_stop is None:  # an event: its state, once
            if self.ts[-1] != t_stop:
                self.keep(t_stop, dense(t_stop), phase)
        elif self.times is None:
            self.keep(t_stop, y_stop, phase)

    def on_event(self, j: int, inactive: list[int], active: tuple[int, ...]) -> None:
        """A separating contact turned round, a contact closes (touch or impact), or an active one lets go."""
        model, t = self.model, self.t
        if j < len(inactive):  # a contact closes (with any other that closes at the same instant)
            i = inactive[j]
            g_now, gd_now = self.gaps(t, self.y)
            self.closed.add(i)
            self.closed.update(
                int(c) for c in np.flatnonzero((g_now <= model.contact_tol) & (gd_now <= model.contact_tol))
            )
            self.departing -= self.closed
            if self.gaps(t, self.y)[1][i] < -model.contact_tol:
                self.y = self.impact(t, self.y)
                self.keep(t, self.y, len(self.phases))  # belongs to the next phase
            else:
                self.events.append({"t": t, "kind": "touch", "contact": model.contact_row_names[i]})
        else:  # an active contact's force reaches zero
            i = active[j - len(inactive)]
            self.closed.discard(i)
            self.departing.add(i)
            self.events.append({"t": t, "kind": "lift-off", "contact": model.contact_row_names[i]})

    def impact(self, t_e: float, y_e: np.ndarray) -> np.ndarray:
        """The velocity jump at ``t_e`` (Newton's law, plastic below ``rest_speed``); lists the impacts."""
        model = self.model
        nq, nv, nl = model.nq, model.nv, model.n_lam
        qe, ve, le = y_e[:nq], y_e[nq : nq + nv], y_e[nq + nv : nq + nv + nl]
        _g, gd = gaps(model, t_e, qe, ve)
        slow = np.flatnonzero(model.restitution * np.maximum(-gd, 0.0) < self.opts.rest_speed)
        res = model.impact(t_e, qe, ve, le, backend=self.decisions_backend, plastic=slow, closed=sorted(self.closed))
        after = gaps(model, t_e, qe, res.v_after)[1]
        for i in res.closed:  # contacts that leave the impact separating are open again
            if after[i] > model.contact_tol:
                self.closed.discard(int(i))
                self.departing.add(int(i))
        y_new = y_e.copy()
        y_new[nq : nq + nv] = res.v_after
        y_new[nq + nv : nq + nv + nl] = res.lam_after
        y_new[-2] += res.kinetic_energy_after - res.kinetic_energy_before  # the impulse's work
        self.jumps.append(t_e)  # one velocity jump may close several contacts at once: they share its number
        for i in res.closed:
            if gd[i] < -model.contact_tol:  # an approaching contact (a resting one only takes part)
                self.events.append(
                    {
                        "t": t_e,
                        "kind": "impact",
                        "jump": len(self.jumps),
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
