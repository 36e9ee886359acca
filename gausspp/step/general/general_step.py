"""The step by the general Gauss QP: contacts, bounded actuators, redundant rows.

:func:`solve_at` evaluates the model's :class:`~gausspp.step.data.StepProblem`, poses the step as one
:class:`~gausspp.step.general.GaussProblem` (:mod:`gausspp.step.gauss_problem`), lets
:func:`~gausspp.step.general.solve_general` solve it — deciding redundancy at the nearest state on
the manifold (:mod:`gausspp.step.manifold`) — and packages the answer as a :class:`StepResult`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import InputError, NonFiniteError, RealizabilityError
from ...workspace import workspace
from .. import dense
from ..data import NO_STAB, StepProblem, evaluate
from ..protocol import StepModel
from ..qp.casadi_conic import CasadiConic
from ..realizability import margin_of, normalized_cosines
from ..results import StepResult
from .compiled import HOLD_FLOOR, GeneralCall, Pattern
from .manifold import on_manifold, reference_problem
from .model_qp import closed_rows, gauss_problem
from .redundancy import CLEARLY_INDEPENDENT
from .solve import CONSISTENCY_TOL, GaussProblem, GaussSolution, check_backend, resolve_backend, solve_general


def _check_contacts(model: StepModel, t: float, d: StepProblem, closed: np.ndarray) -> None:
    approaching = closed[d.gdotc[closed] < -model.contact_tol]
    if approaching.size:
        i = int(approaching[0])
        raise InputError(
            f"contact {model.contact_row_names[i]!r} is closed and approaching (ġ = {d.gdotc[i]:.3g}) at t={t:.6g}: "
            "the velocities must jump first — apply model.impact(...) or simulate, which does"
        )
    if not np.isfinite(d.A).all() or not np.isfinite(d.f + d.r0).all():
        raise NonFiniteError(f"the mass matrix or the forces are not finite at t={t:.6g}; check the model there")


def _problem(model: StepModel, t: float, d: StepProblem, closed: np.ndarray) -> tuple[GaussProblem, np.ndarray]:
    """The problem, and the free acceleration ``A⁻¹ f`` (both solves on one factorization of ``A``)."""
    try:
        a0, free = dense.solve(d.A, np.column_stack([d.f + d.r0, d.f])).T
    except np.linalg.LinAlgError:
        a0 = free = np.zeros(model.nv)  # the QP's Cholesky reports the singular A
    return gauss_problem(model, t, d.A, a0, d.J, d.phi, d.D, d.Jc, d.phic[closed], closed), free


def _result(
    model: StepModel,
    t: float,
    d: StepProblem,
    problem: GaussProblem,
    free: np.ndarray,
    sol: GaussSolution,
    closed: np.ndarray,
    backend: str | None,
) -> StepResult:
    m, k = model.m, model.k
    contact_force = np.zeros(len(model.contact_row_names))
    contact_force[closed] = sol.u[m:]
    cos, margin = normalized_cosines(sol.S_norm[:k, :m], d.D)
    return StepResult(
        t=t,
        a=sol.a,
        u=sol.u[:m],
        reaction=d.r0 + problem.D @ sol.u,  # the realizations' reactions and the contact forces
        compulsion=sol.compulsion,
        margin=margin,
        cosines=cos,
        residual=sol.residual[:k],
        constraint_value=d.Phi,
        free_acceleration=free,
        solver=f"gauss-qp:{check_backend(backend)}",
        contact_force=contact_force,
        tracking_error=sol.tracking_error,
        saturated=sol.at_bound[:m],
    )


def _backend(model: StepModel, backend: str | None) -> Any:
    """The registry's backend for ``backend`` (kept per model: the hot path resolves no name)."""
    return workspace(model).get(("general backend", backend), lambda: resolve_backend(backend))


def _current(model: StepModel, backend: str | None, closed: Any, tol: float) -> list[GeneralCall | None]:
    """The holder of the compiled call of the pattern last decided, for these arguments."""
    key = None if closed is None else tuple(int(i) for i in np.atleast_1d(closed))
    return workspace(model).get(("general pattern", backend, key, tol), lambda: [None])


def current_call(model: StepModel, backend: str | None, closed: Any, tol: float) -> GeneralCall | None:
    """The compiled call of the pattern last decided for these arguments (``None`` before any decision)."""
    return _current(model, backend, closed, tol)[0]


def compiled_outputs(
    model: StepModel,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    backend: str | None,
    *,
    stab: Any,
    closed: Any = None,
    consistency_tol: float = CONSISTENCY_TOL,
) -> tuple[GeneralCall, np.ndarray] | None:
    """The compiled general step of the pattern last decided, if its all-clear flag is up at this state."""
    call = _current(model, backend, closed, consistency_tol)[0]
    if call is None:
        return None
    out = call(t, q, v, lam, stab)
    return None if out is None else (call, out)


def _remember(
    model: StepModel, backend: str | None, closed: Any, tol: float, closed_rows_now: np.ndarray, sol: GaussSolution
) -> None:
    """After the Python step decided: compile (once per pattern) the step of that decision, for the next states."""
    chosen = _backend(model, backend)
    if not isinstance(chosen, CasadiConic):
        return
    floor = HOLD_FLOOR if sol.kept_sine >= CLEARLY_INDEPENDENT else 0.0
    pat = Pattern(tuple(int(i) for i in closed_rows_now), sol.kept_rows, sol.kept_cols, closed is not None, floor)
    if not pat.compilable(model):
        return
    call = workspace(model).get(("general call", chosen.name, pat, tol), lambda: GeneralCall(model, pat, chosen, tol))
    _current(model, backend, closed, tol)[0] = call


def _from_packed(
    model: StepModel, t: float, call: GeneralCall, out: np.ndarray, solution: bool = True
) -> tuple[StepResult, GaussSolution | None, dict[str, np.ndarray]]:
    """The packed outputs of a compiled call as the Python step's three results (the solution only if asked)."""
    f = {name: out[sl] for name, sl in call.slices.items()}
    m, k = model.m, model.k
    S = None if call.sparse else f["S"].reshape(call.k_all, call.m_all, order="F")
    contact_force = np.zeros(call.nc_all)
    contact_force[call.closed] = f["u"][m:]
    at_bound = f["at_bound"] > 0.5
    tracking = f["tracking_error"].item()
    compulsion = f["compulsion"].item()
    sol = None
    if solution:
        stages = ["compulsion", "track", "compulsion"] if f["saturated_branch"][0] > 0.5 else ["compulsion"]
        if call.least_norm:
            stages.append("least-norm")
        pat = call.pattern
        sol = GaussSolution.of_fields(dict(
            a=f["a"], u=f["u"], compulsion=compulsion, residual=f["residual"], tracking_error=tracking,
            at_bound=at_bound, stages=stages, redundant_rows=call.redundant, S_norm=S, kept_rows=pat.kept_rows,
            kept_cols=pat.kept_cols, isolated_rank_drop=False,
        ))  # fmt: skip
    Sk = None if S is None else S[:k, :m]
    # the sparse route computes no S (redundant rows: margin 0 by design, the cosines unknown)
    cos = np.zeros(0) if Sk is None or not k else dense.singular_values(Sk)
    result = StepResult.of_fields(dict(
        t=t, a=f["a"], u=f["u"][:m], reaction=f["reaction"], compulsion=compulsion, margin=margin_of(cos, k, m),
        cosines=cos, residual=f["residual"][:k], constraint_value=f["Phi"], free_acceleration=f["a_free"],
        solver=call.solver, qp_residuals=None, contact_force=contact_force, tracking_error=tracking,
        saturated=at_bound[:m],
    ))  # fmt: skip
    extras = {
        "qdot": f["qdot"], "energy": f["energy"], "power_forces": f["power"], "power_reaction": f["power_reaction"],
        "g": f["g"], "S_norm": Sk,
    }  # fmt: skip
    return result, sol, extras


def rhs_outputs(model: StepModel, call: GeneralCall, out: np.ndarray) -> dict[str, np.ndarray]:
    """A compiled call's packed outputs as a simulation's right-hand side reads them (no result objects, no
    margin: the recording computes what it keeps)."""
    f = {name: out[sl] for name, sl in call.slices.items()}
    m, k = model.m, model.k
    return {
        "a": f["a"], "u": f["u"][:m], "reaction": f["reaction"], "compulsion": f["compulsion"], "Phi": f["Phi"],
        "tracking_error": f["tracking_error"], "saturated": f["at_bound"][:m] > 0.5, "qdot": f["qdot"],
        "energy": f["energy"], "power_forces": f["power"], "power_reaction": f["power_reaction"], "g": f["g"],
        "S_norm": None if call.sparse else f["S"].reshape(call.k_all, call.m_all, order="F")[:k, :m],
    }  # fmt: skip


def result_of(model: StepModel, t: float, call: GeneralCall, out: np.ndarray) -> StepResult:
    """A compiled call's packed outputs as ``model.step``'s result alone."""
    return _from_packed(model, t, call, out, solution=False)[0]


def _reference(
    model: StepModel,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    stab: Any,
    closed: np.ndarray,
    on_a_piece: bool,
) -> GaussProblem | None:
    """The problem at the nearest state on the manifold (:func:`.manifold.reference_problem`). Coming from an open
    piece of the manifold (``on_a_piece``), a nearest state not found — Gauss–Newton stalls at a singular position,
    where the rows' rank drops — means: decide at the state itself (the rows kept there are judged by
    ``kept_before``), not that the constraints contradict each other."""
    try:
        return reference_problem(model, t, q, v, lam, stab, closed)
    except RealizabilityError:
        if not on_a_piece:
            raise
        return None


def solve_at(
    model: StepModel,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    backend: str | None,
    *,
    stab: Any = NO_STAB,
    closed: Any = None,
    consistency_tol: float = CONSISTENCY_TOL,
    compiled: bool = True,
) -> tuple[StepResult, GaussSolution, dict[str, np.ndarray]]:
    """The general step on checked inputs: the result, the QP's solution, and what a simulation records.

    The third item holds ``qdot``, ``energy``, ``power_forces``, ``power_reaction``, ``g`` and ``S_norm``
    (the normalized ``J A⁻¹ D`` of the bilateral rows), named as the compiled kernels name them.
    ``compiled=False`` takes the Python step even where the compiled call of the pattern decided would answer.
    """
    fast = (
        compiled_outputs(model, t, q, v, lam, backend, stab=stab, closed=closed, consistency_tol=consistency_tol)
        if compiled
        else None
    )
    if fast is not None:
        return _from_packed(model, t, fast[0], fast[1])  # type: ignore[return-value]
    given = closed
    d = evaluate(model, t, q, v, lam, stab)
    closed = closed_rows(model, d.gc, closed)
    _check_contacts(model, t, d, closed)
    problem, free = _problem(model, t, d, closed)
    current = _current(model, backend, given, consistency_tol)[0] if compiled else None
    sol = solve_general(
        problem,
        backend,
        consistency_tol,
        kept_before=None if current is None else current.pattern.kept_rows,
        reference=lambda: _reference(model, t, q, v, lam, stab, closed, current is not None),
        # a state on the constraints is itself the witness that dependent rows hold together
        near_manifold=lambda: on_manifold(model, d.J, d.Phi, d.g, q, v),
    )
    result = _result(model, t, d, problem, free, sol, closed, backend)
    if compiled and not sol.isolated_rank_drop:  # an isolated singular position keeps the open piece's decision
        _remember(model, backend, given, consistency_tol, closed, sol)
    extras = {
        "qdot": d.qdot,
        "energy": np.array([d.energy]),
        "power_forces": np.array([d.power]),
        "power_reaction": np.array([float(v @ result.reaction)]),
        "g": d.g,
        "S_norm": sol.S_norm[: model.k, : model.m],
    }
    return result, sol, extras
