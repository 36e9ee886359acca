"""The direct solution of a frictional step: each closed contact sticks or slides, and the rows say how.

With the contact modes fixed, the reaction is ``C u``: a sticking contact contributes the ideal columns
``J_nᵀ`` (normal force ``N``) and ``J_tᵀ`` (friction ``F``, one or two components) and the rows ``J_n q̈ = φ_n``,
``J_t q̈ = φ_t``; a sliding contact (slip direction ``ŝ``, a unit vector: ``±1`` for a one-component slip) the one
column ``D = J_nᵀ − μ J_tᵀ ŝ`` (``F = −μ N ŝ``: Coulomb's force against the slip, a *non-ideal* realization of
the contact in the sense of docs/theory.md) and the row ``J_n q̈ = φ_n``. Then ``q̈ = A⁻¹(f + C u)`` with
``(R A⁻¹ C) u = φ − R A⁻¹ f`` — the same linear system as an impact's velocity jump with ``f`` replaced by ``0``,
``q̈`` by ``v⁺ − v⁻`` and ``φ`` by the targets.

A mode set is *consistent* when the forces and the motion it gives obey the laws: ``N ≥ 0`` on closed
contacts, ``g̈ ≥ 0`` on open ones, ``‖F‖ ≤ μ_s N`` on sticking ones, the slip accelerating along ``ŝ`` on a
contact that starts to slide. :func:`choose` enumerates the modes (a handful of contacts) and takes the first
consistent set, sticking preferred (static friction holds where it can). A two-component contact that starts
to slide does so against the friction its sticking would need (``ŝ = −F/‖F‖``: exact where ``J_t A⁻¹ J_tᵀ`` is
isotropic, as for a ball or a block).

**Painlevé.** A sliding contact whose own compliance ``m = J_n A⁻¹ D`` is not positive has a normal problem
with no solution (``N = b/m < 0`` and ``g̈ < 0`` open) or two (``N = 0`` and ``N = b/m > 0``):
:class:`~gausspp.PainleveError`, with the critical ``μ = J_n A⁻¹ J_nᵀ / (J_n A⁻¹ J_tᵀ ŝ)``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..errors import IntegrationError, PainleveError
from ..model.friction_contact import FrictionContact, dry
from .kinds import HELD, OPEN, SLIDE, STICK
from .kinematics import ContactState

__all__ = ["HELD", "OPEN", "SLIDE", "STICK", "Modes", "Solution", "choose", "solve", "check_painleve"]


def held(contact: FrictionContact) -> bool:
    """Whether ``contact`` is a bilateral row (a holonomic constraint of the model), not a contact."""
    return bool(getattr(contact, "held", False))


@dataclass(frozen=True)
class Modes:
    """Each contact's mode (``open``, ``stick``, ``slide``) and, where it slides, the unit slip direction."""

    kinds: tuple[str, ...]
    dirs: tuple[np.ndarray | None, ...]

    def names(self) -> tuple[str, ...]:
        """``open``, ``stick``, ``slide+``/``slide-`` (one-component slips) or ``slide`` — for records."""
        out = []
        for kind, d in zip(self.kinds, self.dirs, strict=True):
            if kind == SLIDE and d is not None and d.size == 1:
                kind = "slide+" if d[0] > 0 else "slide-"
            out.append(kind)
        return tuple(out)


@dataclass(frozen=True)
class Solution:
    """The step under fixed modes: ``x = x0 + A⁻¹ C u`` (an acceleration, or a velocity after an impact) and per
    contact the normal force ``N`` and friction ``F`` (impulses for an impact; ``F[i]`` of the contact's slip
    dimension)."""

    x: np.ndarray
    N: np.ndarray
    F: list[np.ndarray]
    #: the reaction's columns and which force each carries (``(contact, -1)`` its ``N``, ``(contact, j)`` its
    #: ``F[j]``): for moving the forces of redundant contacts within their cones (:mod:`.redistribute`)
    C: np.ndarray | None = None
    where: tuple[tuple[int, int], ...] = ()


def solve(
    state: ContactState,
    contacts: list[FrictionContact],
    modes: Modes,
    x0: np.ndarray,
    target_n: np.ndarray,
    target_t: list[np.ndarray],
) -> Solution | None:
    """The solution under ``modes`` with rows ``J_n x = target_n`` (closed), ``J_t x = target_t`` (sticking);
    ``None`` where the rows cannot be met."""
    cols, rows, rhs, where = [], [], [], []
    known = np.zeros(state.A.shape[0])  # the slipping joints' dry friction: a force known in advance
    for i, kind in enumerate(modes.kinds):
        if kind == OPEN:
            continue
        if dry(contacts[i]):  # no normal row; sticking: the joint's velocity held, its force an unknown
            if kind == STICK:
                cols += list(state.Jt[i])
                rows += list(state.Jt[i])
                rhs += list(target_t[i])
                where += [(i, j) for j in range(state.Jt[i].shape[0])]
            else:
                known -= contacts[i].bound * (modes.dirs[i] @ state.Jt[i])  # type: ignore[attr-defined]
            continue
        rows.append(state.Jn[i])
        rhs.append(target_n[i])
        if kind == STICK:
            cols += [state.Jn[i], *state.Jt[i]]
            rows += list(state.Jt[i])
            rhs += list(target_t[i])
            where += [(i, -1)] + [(i, j) for j in range(state.Jt[i].shape[0])]
        elif kind == HELD or contacts[i].mu == 0.0:  # no force along the slip: the normal column alone
            cols.append(state.Jn[i])
            where.append((i, -1))
        else:
            cols.append(state.Jn[i] - contacts[i].mu * modes.dirs[i] @ state.Jt[i])
            where.append((i, -1))
    N = np.array([c.bound if dry(c) and k != OPEN else 0.0 for c, k in zip(contacts, modes.kinds, strict=True)])
    F = [np.zeros(len(si)) for si in state.s]
    if np.any(known):
        x0 = x0 + np.linalg.solve(state.A, known)
    if not cols:
        for i, kind in enumerate(modes.kinds):
            if kind == SLIDE and dry(contacts[i]):
                F[i] = -contacts[i].mu * N[i] * modes.dirs[i]
        return Solution(x0.copy(), N, F)
    C, R = np.array(cols).T, np.array(rows)
    AinvC = np.linalg.solve(state.A, C)
    M = R @ AinvC
    b = np.array(rhs) - R @ x0
    # redundant rows (a box flat on two corners: their slips are one): the least forces that meet them, Gauss's
    # acceleration being unique where the forces are not
    u = np.linalg.lstsq(M, b, rcond=1e-12)[0]
    if not np.all(np.isfinite(u)) or np.abs(M @ u - b).max(initial=0.0) > 1e-9 * (1.0 + np.abs(b).max(initial=0.0)):
        return None
    for (i, j), value in zip(where, u, strict=True):
        if j < 0:
            N[i] = value
        else:
            F[i][j] = value
    for i, kind in enumerate(modes.kinds):
        if kind == SLIDE:
            F[i] = -contacts[i].mu * N[i] * modes.dirs[i]
    return Solution(x0 + AinvC @ u, N, F, C, tuple(where))


def compliance(state: ContactState, contact: FrictionContact, i: int, direction: np.ndarray) -> tuple[float, float]:
    """``m = J_n A⁻¹ D`` of contact ``i`` sliding along ``direction``, and the critical ``μ`` where it vanishes
    (``inf`` if friction cannot make it vanish)."""
    Jn, Jt = state.Jn[i], state.Jt[i]
    nn = float(Jn @ np.linalg.solve(state.A, Jn))
    nt = float(Jn @ np.linalg.solve(state.A, Jt.T @ direction))
    m = nn - contact.mu * nt
    critical = nn / nt if nt > 0 else np.inf
    return m, critical


def check_painleve(state: ContactState, contacts: list[FrictionContact], modes: Modes, t: float) -> None:
    """Raise :class:`~gausspp.PainleveError` for a sliding contact whose compliance ``m`` is not positive."""
    for i, kind in enumerate(modes.kinds):
        if kind != SLIDE or dry(contacts[i]):  # a joint's dry friction has no normal problem
            continue
        m, critical = compliance(state, contacts[i], i, modes.dirs[i])
        scale = float(state.Jn[i] @ np.linalg.solve(state.A, state.Jn[i]))
        if m <= 1e-9 * scale:
            raise PainleveError(
                f"Painlevé's paradox at contact {contacts[i].name!r}, t={t:.6g}: sliding ({modes.names()[i]}) with "
                f"mu={contacts[i].mu:g} beyond the critical {critical:.6g}, the normal problem J_n A⁻¹ D N = b has "
                f"J_n A⁻¹ D = {m:.3g} ≤ 0 — no solution or two (N = 0 and N = b/m); Coulomb's rigid contact cannot "
                "continue: lower mu below the critical value, or model the contact's compliance",
                t=t,
                contact=contacts[i].name,
                mu_critical=critical,
            )


def consistent(
    contacts: list[FrictionContact],
    modes: Modes,
    sol: Solution,
    residual_n: np.ndarray,
    residual_t: list[np.ndarray],
    tol: float,
) -> bool:
    """Whether ``sol`` obeys the laws under ``modes``: ``residual_n = J_n x − target_n`` (≥ 0 on open candidates),
    ``residual_t = J_t x − target_t`` (along ``ŝ`` on contacts that start to slide)."""
    for i, kind in enumerate(modes.kinds):
        if kind == OPEN and residual_n[i] < -tol:
            return False
        if kind not in (OPEN, HELD) and sol.N[i] < -tol:
            return False
        if kind == STICK and np.linalg.norm(sol.F[i]) > contacts[i].mu_static * sol.N[i] + tol:
            return False
        if kind == SLIDE and float(modes.dirs[i] @ residual_t[i]) < -tol:
            return False
    return True


def choose(
    state: ContactState,
    contacts: list[FrictionContact],
    candidates: list[int],
    slipping: dict[int, np.ndarray],
    *,
    x0: np.ndarray,
    target_n: np.ndarray,
    target_t: list[np.ndarray],
    t: float,
    tol: float,
    forced: dict[int, tuple[str, ...]] | None = None,
) -> tuple[Modes, Solution]:
    """The first consistent modes (sticking preferred) for the contacts in ``candidates`` (closed or closing; the
    others open); ``slipping`` maps a contact that slips to its unit slip direction (it slides along it or opens);
    ``forced`` limits a contact's options (at the event that ended its mode: it may not take it again)."""
    options = []
    forced = forced or {}
    for i in range(len(contacts)):
        if held(contacts[i]):
            options.append((HELD,))
        elif dry(contacts[i]):  # always engaged (outside an impact, which passes it as no candidate)
            engaged = (SLIDE,) if i in slipping else tuple(k for k in forced.get(i, (STICK, SLIDE)) if k != OPEN)
            options.append(engaged if i in candidates else (OPEN,))
        elif i not in candidates:
            options.append((OPEN,))
        elif contacts[i].mu_static == 0.0:  # frictionless: pushes along its normal (sliding) or lets go
            options.append((OPEN,) if forced.get(i) == (OPEN,) else (SLIDE, OPEN))
        elif i in slipping:
            options.append((SLIDE, OPEN))
        else:
            options.append(forced.get(i, (STICK, SLIDE, OPEN)))
    for kinds in itertools.product(*options):
        dirs = _directions(state, contacts, kinds, slipping, x0, target_n, target_t)
        if dirs is None:
            continue
        modes = Modes(kinds, dirs)
        sliding = Modes(tuple(k if i in slipping else (OPEN if k == SLIDE else k) for i, k in enumerate(kinds)), dirs)
        check_painleve(state, contacts, sliding, t)  # a contact that slips cannot avoid its paradox by opening
        sol = solve(state, contacts, modes, x0, target_n, target_t)
        if sol is None:
            continue
        res_n = state.Jn @ sol.x - target_n
        res_n[[i for i in range(len(contacts)) if i not in candidates]] = 0.0  # g̈ ≥ 0 binds touching contacts
        res_t = [
            np.zeros_like(target_t[i]) if i in slipping else state.Jt[i] @ sol.x - target_t[i]  # the direction law
            for i in range(len(contacts))  # binds a contact that starts to slide, not one that slips
        ]
        if consistent(contacts, modes, sol, res_n, res_t, tol):
            return modes, sol
        if sol.C is not None and any(k in (STICK, SLIDE) for k in kinds):  # redundant contacts: other forces?
            from .redistribute import within_cones

            forces = within_cones(contacts, modes.kinds, modes.dirs, sol.N, sol.F, sol.C, list(sol.where), tol)
            if forces is not None:
                moved = Solution(sol.x, forces[0], forces[1], sol.C, sol.where)
                if consistent(contacts, modes, moved, res_n, res_t, tol):
                    return modes, moved
    raise IntegrationError(
        f"no consistent contact modes at t={t:.6g} for contacts {[contacts[i].name for i in candidates]}: the "
        "frictional contact problem has no solution here (a wedged configuration); check the contacts' geometry"
    )


def _directions(
    state: ContactState,
    contacts: list[FrictionContact],
    kinds: tuple[str, ...],
    slipping: dict[int, np.ndarray],
    x0: np.ndarray,
    target_n: np.ndarray,
    target_t: list[np.ndarray],
) -> tuple[np.ndarray | None, ...] | None:
    """The slip direction of each sliding contact: its slip's where it slips; where it starts to slide, ``±1``
    per :func:`choose`'s order for a one-component slip (``None`` = try the other one: both are enumerated by
    the caller through the sign options), against the sticking friction for two components (``None`` if there
    is none)."""
    dirs: list[np.ndarray | None] = [None] * len(contacts)
    for i, k in enumerate(kinds):  # frictionless: no force along the slip, whatever its direction
        if k == SLIDE and contacts[i].mu_static == 0.0:
            n = state.Jt[i].shape[0]
            dirs[i] = slipping[i] if i in slipping else np.ones(n) / np.sqrt(n)
    starting = [i for i, k in enumerate(kinds) if k == SLIDE and i not in slipping and dirs[i] is None]
    for i, k in enumerate(kinds):
        if k == SLIDE and i in slipping:
            dirs[i] = slipping[i]
    if not starting:
        return tuple(dirs)
    trial_kinds = tuple(STICK if i in starting else k for i, k in enumerate(kinds))
    trial = solve(state, contacts, Modes(trial_kinds, tuple(dirs)), x0, target_n, target_t)
    if trial is None:
        return None
    for i in starting:
        F = trial.F[i]
        size = np.linalg.norm(F)
        if size == 0.0:
            return None
        dirs[i] = -F / size
    return tuple(dirs)
