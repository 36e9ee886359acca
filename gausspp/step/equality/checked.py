"""The checked step: the compiled kernel of the chosen solver, its outcome judged, and the fallbacks.

:func:`checked_step` is what :meth:`gausspp.Model.step` does. A compiled step is one casadi call
(:func:`kernel_for`, kept in the model's workspace); its outputs are judged by
:func:`~gausspp.step.outcome.to_result` (realizability margin, QP residuals). The general Gauss QP
(:mod:`gausspp.step.general.general_step`) answers instead when the model has inequalities (contacts,
bounded actuators), and when the compiled QP meets rows that are redundant on the constraint manifold.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from ...disk_cache import cached_function
from ...errors import GaussppError, InputError, QPSolveError, RealizabilityError
from ...workspace import workspace
from .. import qp
from ..data import NO_STAB, StepProblem, evaluate
from ..general import general_step
from ..general.general_step import solve_at
from ..outcome import Where, evaluation_failed, to_result, warn_small_margin
from ..protocol import StepModel
from ..results import StepResult
from ..solvers import SOLVERS, check_solver  # noqa: F401  (SOLVERS: the names model.py reads from here)
from .checked_call import CheckedCall
from .kernel import CompiledKernel, Kernel, build_kernel

DIRECT_NEEDS_INDEPENDENT_ROWS = (
    " (solver='direct' needs independent rows; solver='qp' returns the unique acceleration "
    "and the least-norm multiplier when the rows are redundant)"
)


def backend_name(backend: str | qp.QPBackend | None) -> str | None:
    """The registry name of ``backend`` (a name, a backend object, or ``None`` for the default)."""
    return backend.name if isinstance(backend, qp.QPBackend) else backend


def kernel_for(model: StepModel, solver: str, backend: str | qp.QPBackend | None, refine: bool) -> Kernel:
    """The compiled step of ``model`` for ``solver`` (and QP ``backend``), built on first use and kept."""
    check_solver(solver, backend)
    if model.contacts or model.bounded:
        raise InputError(
            "this model has unilateral contacts or bounded actuators: its step is the general Gauss QP, "
            "solved from Python (model.step(..., solver='qp')), not a compiled kernel"
        )
    if model.k == 0:  # the free mechanism: no row, no QP — the step is the free acceleration, by either solver
        solver, backend = "direct", None
    chosen = qp.get(backend) if solver == "qp" else None
    key = ("kernel", solver, chosen.name if chosen else None, refine)
    ws = workspace(model)

    def build() -> Kernel:
        def compile_step() -> Kernel:
            return build_kernel("step", model.inputs, model.expressions, solver, chosen, refine, model.route)

        if solver == "direct":  # one function, kept on disk between processes (a QP's is rebuilt with its parts)
            return CompiledKernel(cached_function(model, ("direct kernel", refine), lambda: _function(compile_step())))
        return compile_step()

    kernel = ws.get(key, build)
    if chosen is not None and getattr(kernel, "backend", chosen) is not chosen:  # a backend object given anew
        kernel = ws.put(key, build())
    return kernel


def checked_call(model: StepModel, solver: str, backend: object, refine: bool) -> CheckedCall | None:
    """The hot path of ``model.step`` for ``solver`` (:mod:`gausspp.step.equality.checked_call`), built on first use and
    kept; ``None`` where only the full step applies (contacts, bounds, a QP solved from Python, an unknown
    solver or a backend given as an object — the full step then also reports any error)."""
    if model.contacts or model.bounded or solver not in SOLVERS or not (backend is None or type(backend) is str):
        return None
    if solver == "direct" and backend is not None:
        return None

    def build() -> CheckedCall | None:
        kernel = kernel_for(model, solver, backend, refine)
        if not isinstance(kernel, CompiledKernel):
            return None
        name = "direct" if solver == "direct" else qp.get(backend).name
        return CheckedCall(kernel, model.k, model.m, model.lam0, name, model.margin_warn)

    return workspace(model).get(("checked call", solver, backend, refine), build)


def _prefer_general(model: StepModel, backend: object) -> None:
    """The general QP answered a step of redundant rows: from now on ``model.step`` (qp) asks its compiled general
    step first (:func:`general_hot`), not the equality kernel that cannot solve such a step."""
    if backend is None or type(backend) is str:
        ws = workspace(model)
        for refine in (True, False):
            ws.put(("checked call", "qp", backend, refine), None)


def general_hot(model: StepModel, t: Any, q: Any, v: Any, lam: Any, solver: str, backend: object) -> StepResult | None:
    """``model.step``'s hot path through the compiled general step (:mod:`gausspp.step.general.compiled`) of the
    pattern last decided, or ``None`` when the full step must answer (inputs not plain float arrays of the right
    shapes, no pattern decided yet, or its all-clear flag down)."""
    if solver != "qp" or not (backend is None or type(backend) is str):
        return None
    if not (type(q) is np.ndarray and type(v) is np.ndarray) or q.shape != (model.nq,) or v.shape != (model.nv,):
        return None
    if q.dtype.kind != "f" or v.dtype.kind != "f":
        return None
    if lam is None:
        lam = model.lam0
    if type(lam) is not np.ndarray or lam.shape != (model.n_lam,) or lam.dtype.kind != "f":
        return None
    try:
        t = float(t)
    except (TypeError, ValueError):
        return None
    fast = general_step.compiled_outputs(model, t, q, v, lam, backend, stab=NO_STAB)  # type: ignore[arg-type]
    return None if fast is None else general_step.result_of(model, t, *fast)


def _function(kernel: Kernel) -> ca.Function:
    assert isinstance(kernel, CompiledKernel)  # the direct step is always one compiled function
    return kernel.function


def step_problem(model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> StepProblem:
    """The step's ``A, f = F − h, r₀, J, φ, D, Φ`` and what else :class:`StepProblem` carries at the state, as
    numbers (no checks on their values); the energy NaN where the mechanism has none (the compiled graphs carry 0
    there, a number their finiteness checks pass)."""
    d = evaluate(model, t, q, v, lam)
    return d if model.mechanism.energy is not None else replace(d, energy=float("nan"))


def _general(model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, backend: object):
    """The general QP's result and solution (for the fallbacks below)."""
    result, solution, _ = solve_at(model, t, q, v, lam, backend_name(backend))  # type: ignore[arg-type]
    return result, solution


def _redundant_step(
    model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, exc: Exception, backend: object
) -> StepResult:
    """The compiled QP refused a singular step: if the rows are merely redundant, the general QP answers."""
    try:
        result, solution = _general(model, t, q, v, lam, backend)
    except (RealizabilityError, QPSolveError) as general:  # the compiled step's message names the cause
        exc.args = (f"{exc} [the general QP: {general}]",)
        raise exc from None
    if solution.redundant_rows == 0:
        raise exc
    _prefer_general(model, backend)
    return result


def _small_margin(
    model: StepModel,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    result: StepResult,
    solver: str,
    backend: object,
) -> StepResult:
    """A small margin: nearly dependent rows.

    If they are dependent on the constraint manifold (and independent here only by round-off or drift),
    solving them exactly would amplify the drift by 1/margin — the general QP keeps the independent rows
    instead (:mod:`gausspp.step.general.redundancy`); ``solver='direct'`` refuses.
    """
    if model.k > 1:
        try:
            general, solution = _general(model, t, q, v, lam, backend)
        except GaussppError:
            general, solution = None, None
        if general is not None and solution is not None and solution.redundant_rows > 0:
            if solver == "direct":
                raise RealizabilityError(
                    f"the constraint rows of {', '.join(map(repr, model.names))} are redundant on the constraint "
                    f"manifold at t={t:.6g} (margin here {result.margin:.3g}, by the state's distance from the "
                    f"manifold){DIRECT_NEEDS_INDEPENDENT_ROWS}",
                    t=t,
                    constraint=", ".join(model.names),
                    margin=result.margin,
                )
            _prefer_general(model, backend)
            return general
    warn_small_margin(result.margin, t, model.groups, model.margin_warn, stacklevel=6)
    return result


def checked_step(
    model: StepModel,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    solver: str,
    backend: str | qp.QPBackend | None,
    refine: bool,
) -> StepResult:
    """The step on checked inputs (see :meth:`gausspp.Model.step` for the parameters and errors)."""
    if model.contacts or model.bounded:
        if solver != "qp":
            raise InputError(
                f"solver={solver!r}: a model with unilateral contacts or bounded actuators has no closed-form "
                "step (inequalities); use solver='qp'"
            )
        return _general(model, t, q, v, lam, backend)[0]
    kernel = kernel_for(model, solver, backend, refine)
    name = "direct" if solver == "direct" else qp.get(backend).name
    where = Where(t, name, model.groups, lambda: step_problem(model, t, q, v, lam))
    try:
        out = kernel(t, q, v, lam, NO_STAB)
    except RuntimeError as exc:  # casadi refused to evaluate (e.g. a QP plugin given NaN data)
        raise evaluation_failed(exc, where, margin_error=model.margin_error) from None
    except QPSolveError as exc:  # a nearly singular step the backend could not solve: redundant rows?
        if solver == "direct" or model.k < 2:
            raise
        return _redundant_step(model, t, q, v, lam, exc, backend)
    try:
        result = to_result(out, where, margin_warn=0.0, margin_error=model.margin_error)
    except (RealizabilityError, QPSolveError) as exc:
        if isinstance(exc, QPSolveError) and (solver == "direct" or model.k < 2):
            raise
        if solver == "direct":
            exc.args = (f"{exc}{DIRECT_NEEDS_INDEPENDENT_ROWS}",)
            raise
        return _redundant_step(model, t, q, v, lam, exc, backend)
    if result.margin >= model.margin_warn:
        return result
    return _small_margin(model, t, q, v, lam, result, solver, backend)
