"""Event-driven simulation of a mechanism with frictional contacts (docs/friction.md).

Between events the contact modes are fixed (:mod:`.modes`) and scipy's DOP853 (Radau while a two-component slip
slides: :meth:`_Runner.method`) integrates ``q̇ = K(q, v)``, ``v̇ = q̈`` — or, with ``step=h``, compiled RK4 steps
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

import casadi as ca
import numpy as np

from ..errors import GaussppError, InitialDataError, InputError, IntegrationError, NonFiniteError, ShapeError
from ..model.friction_contact import FrictionContact, as_contacts
from ..model.mechanism import Mechanism
from ..model.model import Model
from ..step.outcome import not_positive_definite
from ..validation import array, flag, positive, record_times
from ..workspace import workspace
from .fixed_step import Phases, run_phase
from .kinematics import ContactKinematics, ContactState
from .modes import HELD, OPEN, SLIDE, STICK, Modes, Solution, check_painleve, choose, solve
from .phase_graph import SLIP_FLOOR, TURN
from .run import FrictionRun, Record

#: Relative tolerance of "on the contact" and "not slipping" at an event, and of the laws' inequalities.
CONTACT_TOL = 1e-8
#: A phase that starts with a contact on its event's boundary to round-off watches it from this far below zero,
#: relative to the gap's own terms (a gap) or the forces' scale (a normal force): :meth:`_Runner.events`.
TIE = 1e-11
#: The laws' inequalities (``N ≥ 0``, ``|F| ≤ μ_s N``, ``g̈ ≥ 0``) hold to this, relative to the forces' scale.
LAW_TOL = 1e-12


class _Runner:
    def __init__(self, mechanism: Mechanism, contacts: list[FrictionContact]) -> None:
        self.mech, self.contacts = mechanism, contacts
        self.kin = ContactKinematics(mechanism, contacts)
        self.nq, self.nv = self.kin.nq, self.kin.nv
        self.qdot = ca.Function("qdot", [mechanism.q, mechanism.v], [mechanism.qdot])
        self.names = [c.name for c in contacts]
        self.phases = Phases(self)
        self._last: tuple[Modes, bytes, ContactState, Solution] | None = None
        self.jac_sparsity = _state_dependence(self.kin, mechanism)
        self._gaps: tuple[bytes, np.ndarray] | None = None

    # -- one state --------------------------------------------------------------------------------------------
    def split(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return y[: self.nq], y[self.nq :]

    def accel(self, st: ContactState, modes: Modes, v: np.ndarray) -> Solution:
        """The acceleration under ``modes`` at velocity ``v``; a two-component slip slides against its current
        direction (the phase's first direction while the slip is below :data:`SLIP_FLOOR`: a slip that starts from
        zero grows along it, and round-off has no direction)."""
        dirs = list(modes.dirs)
        for i, kind in enumerate(modes.kinds):
            if kind == SLIDE and st.s[i].size > 1:
                size = np.linalg.norm(st.s[i])
                if size > SLIP_FLOOR * (1.0 + np.abs(v).max()):  # continued past a stop (phase_graph.TURN)
                    dirs[i] = (1.0 if modes.dirs[i] @ st.s[i] >= -TURN * size else -1.0) * st.s[i] / size
        try:
            x0 = np.linalg.solve(st.A, st.f)
        except np.linalg.LinAlgError:  # a configuration where the mass matrix is singular, between samples
            raise not_positive_definite(st, float("nan")) from None
        sol = solve(st, self.contacts, Modes(modes.kinds, tuple(dirs)), x0, st.phin, st.phit)
        if sol is None:
            raise IntegrationError("the contact rows became dependent: the modes cannot be kept")
        return sol

    def rhs(self, modes: Modes) -> Any:
        def f(t: float, y: np.ndarray) -> np.ndarray:
            q, v = self.split(y)
            st = self.kin(q, v)
            if not (np.isfinite(y).all() and np.isfinite(st.A).all() and np.isfinite(st.f).all()):
                raise NonFiniteError(
                    f"the state or the forces became non-finite at t={t:.6g} (modes {modes.names()}); check the "
                    "mechanism's formulas there"
                )
            return np.concatenate([np.array(self.qdot(q, v)).ravel(), self.accel(st, modes, v).x])

        return f

    def jacobian(self, modes: Modes) -> Any:
        """The right-hand side's Jacobian for Radau by forward differences of bounded step: ``h_k = √ε·max(|y_k|,
        10⁻³ ‖y‖_block)`` on each component the state's functions depend on (:func:`_state_dependence`), zero
        columns elsewhere. scipy's own differences grow the step of a column that is zero at the state (a
        quaternion's radial direction, a position along the ground) tenfold per call, without bound, until it
        overflows."""
        f = self.rhs(modes)
        used = np.flatnonzero(self.jac_sparsity[0])
        root = np.sqrt(np.finfo(float).eps)

        def jac(t: float, y: np.ndarray) -> np.ndarray:
            f0 = f(t, y)
            J = np.zeros((y.size, y.size))
            q_size, v_size = np.abs(y[: self.nq]).max(initial=0.0), np.abs(y[self.nq :]).max(initial=0.0)
            for k in used:
                block = q_size if k < self.nq else v_size
                h = root * max(abs(y[k]), 1e-3 * block, np.finfo(float).tiny ** 0.5)
                shifted = y.copy()
                shifted[k] += h
                J[:, k] = (f(t, shifted) - f0) / (shifted[k] - y[k])
            return J

        return jac

    def method(self, modes: Modes) -> str:
        """DOP853, or Radau where a two-component slip slides: its direction follows the slip with a rate
        ``μN/(m|s|)`` that grows without bound as the slip starts from or returns to zero — stiff (an explicit
        method takes ~1e5 steps to leave a slip of 1e-7 m/s where Radau takes a few dozen)."""
        stiff = any(k == SLIDE and self.kin.dims[i] > 1 for i, k in enumerate(modes.kinds))
        return "Radau" if stiff else "DOP853"

    def events(self, modes: Modes, y: np.ndarray | None = None) -> list[Any]:
        """The phase's events. A contact that starts the phase on its event's boundary — open with its gap at zero
        to round-off, closed with its normal force at zero to round-off (a tie: the same motion whether it is
        closed or open, as a free-falling machine's joint at its limit) — is watched from a band below zero
        (:data:`TIE`, against the gap's own terms or the forces' scale), so that round-off does not end the phase
        where it starts; a real approach or pull crosses the band at once (a penetration below ``TIE`` of the
        gap's scale)."""
        gap_band = np.zeros(len(self.contacts))
        force_band = np.zeros(len(self.contacts))
        if y is not None:
            q, v = self.split(y)
            st = self.kin(q, v)
            sol = self.accel(st, modes, v)
            size = 1.0 + self.kin.gap_scales(q)
            force = 1.0 + float(np.abs(st.f).max(initial=0.0)) + float(np.abs(sol.N).max(initial=0.0))
            for i, kind in enumerate(modes.kinds):
                if kind == OPEN and abs(st.g[i]) <= TIE * size[i]:
                    gap_band[i] = TIE * size[i]
                elif kind not in (OPEN, HELD) and abs(sol.N[i]) <= TIE * force:
                    force_band[i] = TIE * force
        opened = [i for i, kind in enumerate(modes.kinds) if kind == OPEN]
        out = [self._gap_event(opened, gap_band[opened])] if opened else []
        for i, kind in enumerate(modes.kinds):
            if kind in (OPEN, HELD):  # a bilateral row neither lifts off nor slips
                continue
            else:
                out.append(self._event(modes, lambda st, sol, i=i, b=force_band[i]: sol.N[i] + b, ("lifts off", i)))
            if self.contacts[i].mu_static == 0.0:  # frictionless: its slip changes nothing
                continue
            if kind == SLIDE:  # the slip along the phase's first direction reaches zero
                d = modes.dirs[i]
                out.append(self._event(modes, lambda st, sol, i=i, d=d: float(d @ st.s[i]), ("stops slipping", i)))
            if kind == STICK:
                mu_s = self.contacts[i].mu_static
                cone = lambda st, sol, i=i, m=mu_s: m * sol.N[i] - np.linalg.norm(sol.F[i])  # noqa: E731
                out.append(self._event(modes, cone, ("starts to slip", i)))
        return out

    def _gap_event(self, opened: list[int], band: np.ndarray) -> Any:
        """The first of the open contacts ``opened`` closes: the least of their gaps (each plus the phase's start
        band) falls through zero — one event for them all, from the gaps alone (one root to locate, not one per
        contact); :meth:`closing` names the contact at the event's state."""

        def event(_t: float, y: np.ndarray) -> float:
            return float(np.min(self._gap_values(y)[opened] + band))

        event.terminal, event.direction = True, -1  # type: ignore[attr-defined]
        event.what = ("closes", -1)  # type: ignore[attr-defined]
        event.closing = lambda y: opened[int(np.argmin(self._gap_values(y)[opened] + band))]  # type: ignore[attr-defined]
        return event

    def _gap_values(self, y: np.ndarray) -> np.ndarray:
        key = y.tobytes()
        if self._gaps is None or self._gaps[0] != key:
            self._gaps = (key, np.asarray(self.kin.gaps(y[: self.nq]), float).ravel())
        return self._gaps[1]

    def _event(self, modes: Modes, value: Any, what: tuple[str, int]) -> Any:
        def event(_t: float, y: np.ndarray) -> float:
            return float(value(*self._state(modes, y)))

        event.terminal, event.direction, event.what = True, -1, what  # type: ignore[attr-defined]
        return event

    def _state(self, modes: Modes, y: np.ndarray) -> tuple[ContactState, Solution]:
        """The contact state and the solution under ``modes`` at ``y``, kept for the next call at the same ``y``
        (scipy asks every event of a step at the step's end: one evaluation serves them all)."""
        key = y.tobytes()
        last = self._last
        if last is None or last[0] is not modes or last[1] != key:
            q, v = self.split(y)
            st = self.kin(q, v)
            last = self._last = (modes, key, st, self.accel(st, modes, v))
        return last[2], last[3]

    def check_start(self, q: np.ndarray, v: np.ndarray) -> None:
        """Refuse initial data that cannot be stepped (:meth:`ContactKinematics.checked`) or penetrate a contact."""
        gaps = self.kin.checked(q, v, 0.0, self.names).g
        scales = self.kin.gap_scales(q)  # each gap against its own terms: a far coordinate does not excuse it
        off = gaps < -CONTACT_TOL * scales
        if np.any(off):
            i = int(np.flatnonzero(off)[np.argmin(gaps[off])])
            raise InitialDataError(
                f"initial data penetrate the contact {self.names[i]!r} at t=0: g = {gaps[i]:.3g} < 0 (the gap's own "
                f"scale {scales[i]:.3g}); start with every gap g ≥ 0"
            )

    # -- modes at an event --------------------------------------------------------------------------------------
    def modes_at(
        self, t: float, q: np.ndarray, v: np.ndarray, fired: tuple[tuple[str, int], ...] = ()
    ) -> tuple[Modes, np.ndarray, Solution]:
        """The modes from the state ``(q, v)`` (after an impact if a contact closes approaching); a contact whose
        event ``fired`` may not keep the mode that event ended (it sits on that mode's boundary)."""
        st = self.kin.checked(q, v, t, self.names)
        size = 1.0 + self.kin.gap_scales(q)  # each gap against its own terms, not the largest coordinate
        speed = contact_speeds(st, v)  # each contact's own: 1 + the terms of its ġ and slip
        touching = [i for i in range(len(self.contacts)) if st.g[i] <= CONTACT_TOL * size[i]]
        approaching = [i for i in touching if st.gdot[i] < -CONTACT_TOL * speed[i]]
        if approaching:
            v = self.impact(t, st, touching, v)
            st = self.kin(q, v)
            speed = contact_speeds(st, v)
        candidates = [i for i in touching if abs(st.gdot[i]) <= CONTACT_TOL * speed[i] * 10]
        slipping = {
            i: st.s[i] / np.linalg.norm(st.s[i]) for i in candidates if np.linalg.norm(st.s[i]) > CONTACT_TOL * speed[i]
        }
        x0 = np.linalg.solve(st.A, st.f)
        tol = LAW_TOL * (1.0 + np.abs(st.f).max(initial=0.0) + np.abs(x0).max(initial=0.0))
        forced = {}
        for kind, i in fired:
            if kind == "starts to slip":
                forced[i] = (SLIDE, OPEN)
            elif kind == "lifts off":
                forced[i] = (OPEN,)
        modes, sol = choose(
            st,
            self.contacts,
            candidates,
            slipping,
            x0=x0,
            target_n=st.phin,
            target_t=st.phit,
            t=t,
            tol=tol,
            forced=forced,
        )
        return modes, v, sol

    def impact(self, t: float, st: ContactState, touching: list[int], v: np.ndarray) -> np.ndarray:
        """The velocity after an impact: Newton's ``ġ⁺ = −e ġ⁻`` (or opening) and Coulomb on the impulses."""
        e = np.array([c.restitution for c in self.contacts])
        target_n = np.where(st.gdot < 0, -e * st.gdot, 0.0)
        target_t = [np.zeros_like(si) for si in st.s]
        # every contact may stick, slide or open in an impact: Coulomb's law on the impulses, the tangential one
        # against the slip it would otherwise have to stop
        _, sol = choose(
            st, self.contacts, touching, {}, x0=v, target_n=target_n, target_t=target_t, t=t, tol=CONTACT_TOL
        )
        return sol.x


def _state_dependence(kin: ContactKinematics, mechanism: Mechanism) -> np.ndarray:
    """The right-hand side's Jacobian pattern for Radau: every row may depend on each component of the state that
    the contact state or the kinematics depend on, on no other. A machine's position along the ground (a robot's
    base ``x``, ``y``) enters nothing; scipy's finite differences would grow their step there without bound (a
    column of zeros) until it overflows, so those columns are declared empty."""
    S = kin.symbols
    y = ca.vertcat(S["q"], S["v"])
    out = ca.vertcat(*[ca.vec(ca.SX(S[k])) for k in ("A", "f", "g", "Jn", "phin", "Jt", "phit")], mechanism.qdot)
    pattern = ca.jacobian(out, y).sparsity()
    columns = np.diff(np.array(pattern.colind())) > 0
    return np.ones((y.numel(), 1)) * columns[None, :]


def contact_speeds(st: Any, v: np.ndarray) -> np.ndarray:
    """``1 +`` the size of the terms each contact's gap rate and slip add up (``|J_n,i||v|``, ``|J_t,i||v|``): the
    speed its rate is judged against, not the largest velocity of the whole state."""
    normal = np.abs(st.Jn) @ np.abs(v) if st.Jn.size else np.zeros(len(st.s))
    tangent = np.array([float((np.abs(Jt) @ np.abs(v)).max(initial=0.0)) for Jt in st.Jt])
    return 1.0 + np.maximum(normal, tangent)


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


def _runner(system: Mechanism | Model, contacts: FrictionContact | list[FrictionContact]) -> _Runner:
    """The runner of ``system``'s mechanism and ``contacts`` (checked), kept in the mechanism's workspace with its
    compiled phases for the next run."""
    mech = system.mechanism if isinstance(system, Model) else system
    if isinstance(system, Model) and system.k:
        raise InputError("simulate_friction takes a mechanism (or a model without constraint rows)")
    if not isinstance(mech, Mechanism):
        raise InputError(f"simulate_friction takes a gausspp mechanism or model, got {type(system).__name__}")
    contacts = as_contacts("simulate_friction", contacts)
    key = ("friction-runner", *((c, c.gap, c.slip, c.mu, c.mu_static, c.restitution) for c in contacts))
    return workspace(mech).get(key, lambda: _Runner(mech, contacts))


def _next_modes(
    runner: _Runner, t: float, y: np.ndarray, fired: list[tuple[str, int]], max_events: int, events: list
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
    runner: _Runner, q: np.ndarray, v: np.ndarray, *, opts: FrictionOptions, rec: Record, events: list
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
    runner: _Runner, q: np.ndarray, v: np.ndarray, *, opts: FrictionOptions, rec: Record, events: list
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
            runner.rhs(modes),
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


def _keep(runner: _Runner, rec: Record, modes: Modes, ts: list, ys: list) -> None:
    """Record the states ``ys`` at ``ts`` of a phase under ``modes``, with their forces and energy."""
    names = modes.names()
    for ti, yi in zip(ts, ys, strict=True):
        st = runner.kin.checked(*runner.split(yi), ti, runner.names)
        acc = runner.accel(st, modes, runner.split(yi)[1])
        rec.add(ti, yi, names, acc.N, np.concatenate(acc.F), st.energy)
