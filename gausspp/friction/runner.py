"""The machine and its frictional contacts at a state: accelerations under fixed modes, the events that end a phase,
the modes chosen at an event, impacts, and Radau's Jacobian (the state of :func:`.integrate.simulate_friction`)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import InitialDataError, IntegrationError, NonFiniteError
from ..model.friction_contact import FrictionContact, dry
from ..model.mechanism import Mechanism
from ..step.outcome import not_positive_definite
from .fixed_step import Phases
from .kinematics import Called, ContactKinematics, ContactState
from .modes import HELD, OPEN, SLIDE, STICK, Modes, Solution, choose, solve
from .phase_graph import SLIP_FLOOR, TURN

#: Relative tolerance of "on the contact" and "not slipping" at an event, and of the laws' inequalities.
CONTACT_TOL = 1e-8
#: A phase that starts with a contact on its event's boundary to round-off watches it from this far below zero,
#: relative to the gap's own terms (a gap) or the forces' scale (a normal force): :meth:`Runner.events`.
TIE = 1e-11
#: The laws' inequalities (``N ≥ 0``, ``|F| ≤ μ_s N``, ``g̈ ≥ 0``) hold to this, relative to the forces' scale.
LAW_TOL = 1e-12


class Runner:
    def __init__(self, mechanism: Mechanism, contacts: list[FrictionContact]) -> None:
        self.mech, self.contacts = mechanism, contacts
        self.kin = ContactKinematics(mechanism, contacts)
        self.nq, self.nv = self.kin.nq, self.kin.nv
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

    def compiled_rhs(self, modes: Modes, y0: np.ndarray, codegen: bool = False) -> Any:
        """The phase's right-hand side as its compiled graph's rate (:class:`.phase_graph.PhaseGraph`, called through
        bound buffers: one call); ``None`` where every contact is open (:meth:`rhs` then asks the machine alone). Its
        kept rows are solved by casadi's QR — a square system directly, redundant rows for their least-norm forces
        through the QR of ``Mᵀ`` — as accurate as :meth:`accel`'s least squares (the normal equations, with the
        squared condition, cost the walker standing 62 steps where this takes 10)."""
        if all(kind == OPEN for kind in modes.kinds):
            return None
        q0, v0 = self.split(y0)
        graph, d = self.phases.at(modes, q0, v0)
        rate = Called(graph.rate_c() if codegen else graph.rate)
        dirs = d.copy()

        def f(t: float, y: np.ndarray) -> np.ndarray:
            out = rate(y[: self.nq], y[self.nq :], dirs)
            if not (np.isfinite(out).all() and np.isfinite(y).all()):
                raise NonFiniteError(
                    f"the state or the forces became non-finite at t={t:.6g} (modes {modes.names()}); check the "
                    "mechanism's formulas there"
                )
            return out

        return f

    def rhs(self, modes: Modes) -> Any:
        """The phase's right-hand side ``(t, y) ↦ (q̇, q̈)`` by the direct solution of :meth:`accel` at each call.
        (The phase's compiled graph, :attr:`.phase_graph.PhaseGraph.rate`, solves its kept rows by the normal
        equations: round-off of the squared condition, 1e-11 where this gives 1e-14 on a walker at rest, and the
        adaptive steps shrink to it — 62 steps for 2 s of walker2d standing where this takes 9.)"""

        if all(kind == OPEN for kind in modes.kinds):  # every contact open: the machine alone, no contact data
            return self._free_rhs(modes)

        def f(t: float, y: np.ndarray) -> np.ndarray:
            q, v = self.split(y)
            st = self.kin(q, v)
            if not (np.isfinite(y).all() and np.isfinite(st.A).all() and np.isfinite(st.f).all()):
                raise NonFiniteError(
                    f"the state or the forces became non-finite at t={t:.6g} (modes {modes.names()}); check the "
                    "mechanism's formulas there"
                )
            return np.concatenate([self.kin.qdot(q, v), self.accel(st, modes, v).x])

        return f

    def _free_rhs(self, modes: Modes) -> Any:
        """``(q̇, A⁻¹f)`` from the mechanism's ``A``, ``f`` and kinematics alone (a flight phase)."""
        free = self.kin.free

        def f(t: float, y: np.ndarray) -> np.ndarray:
            flat = free(y[: self.nq], y[self.nq :])
            n = self.nv
            A, force, qdot = flat[: n * n].reshape(n, n, order="F"), flat[n * n : n * n + n], flat[n * n + n :]
            if not (np.isfinite(flat).all() and np.isfinite(y).all()):
                raise NonFiniteError(
                    f"the state or the forces became non-finite at t={t:.6g} (modes {modes.names()}); check the "
                    "mechanism's formulas there"
                )
            return np.concatenate([qdot, np.linalg.solve(A, force)])

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
            if not dry(self.contacts[i]):  # a joint's dry friction has no normal force to lose
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
            self._gaps = (key, self.kin.gaps(y[: self.nq]))
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
        touching = [i for i in touching if not dry(self.contacts[i])]  # a bounded force gives no impulse
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
