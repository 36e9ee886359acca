"""A phase of a frictional run as one compiled casadi graph: fixed modes, RK4 steps, and the events' values.

While the modes are fixed (:mod:`.modes`) the acceleration is a smooth function of ``(q, v)``:
``q̈ = A⁻¹(f + C u)`` with ``(R A⁻¹ C) u = φ − R A⁻¹ f`` — the assembly of :func:`.modes.solve`, written here in
casadi. Rows that depend on the others (a box flat on its four corners: four normal rows of rank three) are
dropped once, at the phase's start, by a pivoted QR of ``M = R A⁻¹ C`` there (:func:`kept_rows`); the forces are
then the least that meet the kept rows, ``u = M_rᵀ (M_r M_rᵀ)⁻¹ b_r`` — the least-squares solution of the
adaptive integrator, the motion being Gauss's unique one. A two-component slip slides against its current
direction, or against the phase's first direction ``d`` while it is below ``SLIP_FLOOR``; past the phase's end
(``d·s < 0``, where an RK4 stage may reach) the direction is continued, ``−s/‖s‖``, not flipped, so the step that
holds the event is the smooth phase's own.

:class:`PhaseGraph` holds ``step(y, d, h) -> (y⁺, out⁺, jump)`` — one classical RK4 step; at its end the normal
forces, friction forces, energy and events' values (``out``); and ``jump = max |h (k₄ − k₁)| / (1 + |y|)``, how much
the rate changes within the step relative to the state (a step too long for the phase shows there) — and
``chunk``, :data:`CHUNK` such steps in one call (``mapaccum``: no Python between the steps).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from scipy.linalg import qr

from ..c_code import c_function
from ..model.friction_contact import FrictionContact, dry
from .kinematics import ContactKinematics
from .modes import HELD, OPEN, SLIDE, STICK

#: Steps taken in one call of a phase's ``chunk``.
CHUNK = 256
#: A two-component slip below this (relative to the velocities' size) slides along the phase's first direction.
SLIP_FLOOR = 1e-7
#: A two-component slip opposite its phase's first direction ``d`` (``d·s < −TURN ‖s‖``: more than 120° from it)
#: has passed through zero, and its direction is continued (``−s/‖s‖``); within 120° it is the slip's own. A phase
#: ends where ``d·s`` falls through zero: the slip stops (and its direction is continued in the stages past the
#: stop), or it has turned by 90° (and the next phase takes its new direction), so no stage of a step meets the
#: 120° line except one past a stop.
TURN = 0.5
#: Relative rank tolerance of the pivoted QR that keeps the independent rows.
RANK_TOL = 1e-10


def _forces(
    kin: ContactKinematics, contacts: list[FrictionContact], kinds: tuple[str, ...], d: ca.SX
) -> dict[str, Any]:
    """The phase's rows ``R x = φ``, columns ``C`` and slip directions, as expressions of ``(q, v, d)``."""
    S, o = kin.symbols, kin.offsets
    q, v = S["q"], S["v"]
    Jn, Jt, s = ca.SX(S["Jn"]), ca.SX(S["Jt"]), ca.SX(S["s"])
    speed = 1.0 + ca.mmax(ca.fabs(v))
    cols, rows, rhs, where, dirs = [], [], [], [], []
    known = ca.SX.zeros(v.numel())  # the slipping joints' dry friction, a known force

    def held_slip(i: int, part: slice) -> None:
        """A sticking contact's (or joint's) slip components: each a row ``J_t q̈ = φ_t`` and its force's column."""
        for j in range(part.start, part.stop):
            cols.append(Jt[j, :].T)
            rows.append(Jt[j, :])
            rhs.append(S["phit"][j])
            where.append((i, j - part.start))

    for i, kind in enumerate(kinds):
        part = slice(int(o[i]), int(o[i + 1]))
        di = d[part]
        if kind == SLIDE and kin.dims[i] > 1:  # against the slip's current direction, once it has one
            size = ca.norm_2(s[part])
            along = ca.if_else(ca.dot(di, s[part]) >= -TURN * size, 1, -1) * s[part] / ca.fmax(size, 1e-300)
            di = ca.if_else(size > SLIP_FLOOR * speed, along, di)
        dirs.append(di)
        if kind == OPEN:
            continue
        if dry(contacts[i]):  # no normal row: sticking holds the joint's velocity, slipping is a known force
            if kind == STICK:
                held_slip(i, part)
            else:
                known -= contacts[i].bound * (Jt[part, :].T @ di)  # type: ignore[attr-defined]
            continue
        rows.append(Jn[i, :])
        rhs.append(S["phin"][i])
        where.append((i, -1))
        if kind == STICK:
            cols.append(Jn[i, :].T)
            held_slip(i, part)
        else:
            cols.append(Jn[i, :].T - contacts[i].mu * Jt[part, :].T @ di)
    A, f = ca.SX(S["A"]), ca.SX(S["f"]) + known
    D, LT, perm = ca.ldl(A)  # A = L D Lᵀ (permuted): half the operations of a QR, and no square root — an A that
    # stops being positive definite still gives numbers, and the report's least pivot names it

    def solve_A(X: ca.SX) -> ca.SX:
        return ca.ldl_solve(X, D, LT, perm)

    x0 = solve_A(f)
    out: dict[str, Any] = {"q": q, "v": v, "x0": x0, "dirs": dirs, "where": where}
    if cols:
        C, R = ca.horzcat(*cols), ca.vertcat(*rows)
        out["AinvC"] = solve_A(C)
        out["M"] = R @ out["AinvC"]
        out["b"] = ca.vertcat(*rhs) - R @ x0
    return out


def rows_function(kin: ContactKinematics, contacts: list[FrictionContact], kinds: tuple[str, ...]) -> ca.Function:
    """``(q, v, d) -> M``, the phase's matrix ``R A⁻¹ C`` (empty where every contact is open)."""
    d = ca.SX.sym("d", int(sum(kin.dims)))
    parts = _forces(kin, contacts, kinds, d)
    return ca.Function("rows", [parts["q"], parts["v"], d], [parts.get("M", ca.SX(0, 0))])


def kept_rows(M: np.ndarray) -> tuple[int, ...]:
    """The rows of ``M`` a pivoted QR finds independent (relative tolerance :data:`RANK_TOL`), in order."""
    if M.size == 0:
        return ()
    _, r, perm = qr(M.T, mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > RANK_TOL * max(diag[0], 1e-300)))
    return tuple(sorted(int(p) for p in perm[:rank]))


def _least_norm(M: ca.SX, b: ca.SX) -> ca.SX:
    """The least-norm solution of ``M u = b`` (``M`` of full row rank): ``Mᵀ = Q R`` by casadi's Gram–Schmidt QR,
    orthogonalized twice ("twice is enough": ``Q`` orthonormal to round-off), ``u = Q R⁻ᵀ b`` — the condition of
    ``M``, not its square as in the normal equations ``Mᵀ(MMᵀ)⁻¹b``."""
    Q1, R1 = ca.qr(M.T)
    Q, R2 = ca.qr(Q1)
    return Q @ ca.solve((R2 @ R1).T, b)


def _least_pivot(A: ca.SX) -> ca.SX:
    """The least pivot of ``A``'s elimination without pivoting, relative to its largest diagonal entry: positive
    exactly where the symmetric ``A`` is positive definite (Sylvester's criterion)."""
    n, scale = A.size1(), ca.mmax(ca.fabs(ca.diag(A)))
    pivots, rest = [], A
    for k in range(n):
        pivots.append(rest[0, 0])
        if k + 1 < n:
            rest = rest[1:, 1:] - rest[1:, 0] @ rest[0, 1:] / rest[0, 0]
    return ca.mmin(ca.vertcat(*pivots)) / scale if n else ca.SX(1)


def _rk4(rate: ca.Function, d: ca.SX, nq: int, nv: int, normalize: Any) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """One classical RK4 step of ``ẏ = rate(q, v, d)`` from the symbol ``y`` by the symbol ``h``: ``(y, h, y⁺, jump)``
    with ``q`` renormalized (unit quaternions) and ``jump`` how much the rate changes across the step, relative to
    the state's size (a guard, not an error estimate)."""
    y, h = ca.SX.sym("y", nq + nv), ca.SX.sym("h")

    def f(z: ca.SX) -> ca.SX:
        return rate(z[:nq], z[nq:], d)

    k1 = f(y)
    k2 = f(y + 0.5 * h * k1)
    k3 = f(y + 0.5 * h * k2)
    k4 = f(y + h * k3)
    y1 = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    if normalize is not None:
        y1 = ca.vertcat(normalize(y1[:nq]), y1[nq:])
    return y, h, y1, ca.mmax(ca.fabs(h * (k4 - k1)) / (1.0 + ca.fabs(y)))


class PhaseGraph:
    """The compiled step and chunk of one phase (module docstring): the modes ``kinds``, the kept rows ``kept``.

    ``out`` stacks the normal forces (one per contact), the friction forces (one per slip component), the energy
    and the events' values, named by :attr:`events` as ``(kind, contact index)`` in the adaptive integrator's
    order; an event fires where its value falls through zero."""

    def __init__(
        self,
        kin: ContactKinematics,
        contacts: list[FrictionContact],
        kinds: tuple[str, ...],
        kept: tuple[int, ...],
        normalize: Any = None,
    ) -> None:
        nd = int(sum(kin.dims))
        d = ca.SX.sym("d", nd)
        P = _forces(kin, contacts, kinds, d)
        q, v, S, o = P["q"], P["v"], kin.symbols, kin.offsets
        u = ca.SX(0, 1)
        qdd = P["x0"]
        #: whether the kept rows form a square system (solved by casadi's QR; else by the normal equations)
        self.square = "M" in P and len(kept) == P["M"].size2() == P["M"].size1()
        if "M" in P:
            Mr, br = P["M"][list(kept), :], P["b"][list(kept)]
            u = ca.solve(Mr, br) if Mr.size1() == Mr.size2() else _least_norm(Mr, br)
            qdd = P["x0"] + P["AinvC"] @ u
        N = [ca.SX(c.bound) if dry(c) and k != OPEN else ca.SX(0) for c, k in zip(contacts, kinds, strict=True)]
        F = [ca.SX.zeros(int(k)) for k in kin.dims]
        for (i, j), value in zip(P["where"], ca.vertsplit(u), strict=True):
            if j < 0:
                N[i] = value
            else:
                F[i][j] = value
        events: list[ca.SX] = []
        self.events: list[tuple[str, int]] = []
        for i, kind in enumerate(kinds):
            if kind == SLIDE:
                F[i] = -contacts[i].mu * N[i] * P["dirs"][i]
            if kind == HELD:  # a bilateral row neither lifts off nor slips
                continue
            if kind == OPEN:
                events.append(S["g"][i]), self.events.append(("closes", i))
            elif not dry(contacts[i]):  # a joint's dry friction has no normal force to lose
                events.append(N[i]), self.events.append(("lifts off", i))
            if contacts[i].mu_static == 0.0:  # frictionless: its slip changes nothing
                continue
            if kind == SLIDE:
                part = slice(int(o[i]), int(o[i + 1]))
                events.append(ca.dot(d[part], S["s"][part])), self.events.append(("stops slipping", i))
            if kind == STICK:
                events.append(contacts[i].mu_static * N[i] - ca.norm_2(F[i]))
                self.events.append(("starts to slip", i))
        out = ca.vertcat(*N, *F, S["energy"], _least_pivot(ca.SX(S["A"])), *events)
        self.n_contacts, self.n_friction = kin.c, nd
        #: ``(q, v, d) ↦ (q̇, q̈)``: the phase's right-hand side
        self.rate = ca.Function("rate", [q, v, d], [ca.vertcat(S["qdot"], qdd)])
        self.report = ca.Function("report", [q, v, d], [out])
        self._normalize, self._sizes = normalize, (q.numel(), v.numel(), d)
        self._steps: tuple[ca.Function, ca.Function] | None = None
        self._c: tuple[ca.Function, ca.Function] | None = None

    def rate_c(self) -> ca.Function:
        """:attr:`rate` as C where a compiler is (:mod:`gausspp.c_code`; else the virtual machine's), built once."""
        if getattr(self, "_rate_c", None) is None:
            self._rate_c = c_function(self.rate) or self.rate
        return self._rate_c

    @property
    def step(self) -> ca.Function:
        """``(y, d, h) ↦ (y⁺, out⁺, jump)``: one RK4 step (built on first use: the adaptive lane needs none)."""
        return self._stepping()[0]

    @property
    def chunk(self) -> ca.Function:
        """:data:`CHUNK` steps in one call (``mapaccum``)."""
        return self._stepping()[1]

    def _stepping(self) -> tuple[ca.Function, ca.Function]:
        if self._steps is None:
            nq, nv, d = self._sizes
            y, h, y1, jump = _rk4(self.rate, d, nq, nv, self._normalize)
            step = ca.Function("step", [y, d, h], [y1, self.report(y1[:nq], y1[nq:], d), jump], {"cse": True})
            self._steps = (step, step.mapaccum("chunk", CHUNK))
        return self._steps

    def compiled(self) -> tuple[ca.Function, ca.Function]:
        """The step and the chunk compiled to C (:func:`gausspp.c_code.c_function`, kept on disk), or themselves
        where there is no C compiler."""
        if self._c is None:
            self._c = (c_function(self.step) or self.step, c_function(self.chunk) or self.chunk)
        return self._c

    def split(self, out: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``out`` (rows, one column per sample) as normal forces, friction forces, energy, events' values."""
        c, nd = self.n_contacts, self.n_friction
        return out[:c], out[c : c + nd], out[c + nd], out[c + nd + 2 :]

    def usable(self, Y: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Per sample: the state, forces and events' values finite and the mass matrix positive definite (its least
        pivot positive); the energy may be NaN (a mechanism that does not know it)."""
        c, nd = self.n_contacts, self.n_friction
        finite = np.isfinite(Y).all(axis=0) & np.isfinite(np.delete(out, [c + nd, c + nd + 1], axis=0)).all(axis=0)
        return finite & (out[c + nd + 1] > 0)
