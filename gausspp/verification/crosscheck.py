"""An independent reference for the step: Gauss's principle posed in acceleration space.

The model's two solvers (the direct multiplier formula and the compiled QP) share one reduction to
reaction space (``Ŝ``, the whitened reaction, :mod:`gausspp.step`) and, by default, one refinement
step; comparing them checks little. The reference here shares nothing with them. It is the QP of
the paper (§3) and docs/theory.md §3, assembled from the step's data ``A, a₀, J, φ, D`` alone::

    minimize   ½ (a − a₀)ᵀ A (a − a₀)                 over the accelerations a ∈ Rⁿ
    subject to J a = φ                                 (the constraint, eq. (11))
               Pᵀ A (a − a₀) = 0                       (the reaction A(a − a₀) lies in range(D))

with ``P`` an orthonormal basis of ``ker Dᵀ`` (from an SVD of ``D``), posed with numpy's data — no
casadi graph, no Cholesky factor, no reaction-space unknowns — and solved by a backend of the QP
registry chosen by name (default: the first installed of
:data:`gausspp.step.qp.REFERENCE_DEFAULTS`, exact qpsolvers codes, none of them the compiled
step's default). Its KKT residuals (primal and dual) are reported with it.

:func:`crosscheck` compares the model's *raw* answers (``refine=False``: what each solver itself
returned) with this reference, and the refined ones apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError, NonFiniteError, NotPositiveDefiniteError, QPSolveError
from ..model.model import model_argument
from ..step import qp
from ..validation import positive

#: Backends tried in this order for the reference (declared in the registry): exact dense active-set codes first.
REFERENCE_BACKENDS = qp.REFERENCE_DEFAULTS
#: Relative distance from the reference (and KKT residual of the reference) above which a check fails.
TOLERANCE = 1e-9


@dataclass(frozen=True)
class AccelerationQP:
    """The reference answer and how well it satisfies its own optimality conditions.

    Attributes
    ----------
    a : (n,)        the acceleration
    backend : str   the backend that found it (its short name, :func:`gausspp.step.qp.short_name`)
    primal : float  ``max |E a − e|`` over the (unit) equality rows, relative to ``1 + max |a|``
    dual : float    ``max |A a − A a₀ + Eᵀ y|``, relative to ``max |A| · (1 + max |a|)``
    """

    a: np.ndarray
    backend: str
    primal: float
    dual: float


def reference_backend(name: str | None = None) -> qp.QPBackend:
    """The registry's backend for ``name`` (``None``: :func:`gausspp.step.qp.default` ``("reference")``)."""
    return qp.get(qp.default("reference") if name is None else name)


def acceleration_qp(
    A: np.ndarray, a0: np.ndarray, J: np.ndarray, phi: np.ndarray, D: np.ndarray, backend: str | None = None
) -> AccelerationQP:
    """Solve the step as the acceleration-space QP of the module docstring.

    Parameters
    ----------
    A : (n, n) array   kinetic-energy matrix (symmetric positive definite)
    a0 : (n,) array    the acceleration with no reaction unknowns, ``A⁻¹(F − h + r₀)``
    J : (k, n) array   constraint rows;  phi : (k,) array  their right-hand sides
    D : (n, m) array   the realization's reaction directions
    backend : str, optional   a name of :func:`gausspp.step.qp.names` (default: :func:`reference_backend`)
    """
    A, a0, J, phi, D = (np.asarray(x, dtype=float) for x in (A, a0, J, phi, D))
    n = A.shape[0]
    if not (A.shape == (n, n) and a0.shape == (n,) and J.ndim == 2 and J.shape[1] == n and phi.shape == (J.shape[0],)):
        raise InputError(f"acceleration_qp: shapes A {A.shape}, a0 {a0.shape}, J {J.shape}, phi {phi.shape} do not fit")
    if D.ndim != 2 or D.shape[0] != n:
        raise InputError(f"acceleration_qp: D has shape {D.shape}, expected ({n}, m)")
    for name, x in (("A", A), ("a0", a0), ("J", J), ("phi", phi), ("D", D)):
        if not np.all(np.isfinite(x)):
            raise NonFiniteError(f"acceleration_qp: {name} contains NaN or inf; check the step's data")
    # symmetric to round-off of the matrix as a whole (entries that vanish carry round-off of either sign)
    asymmetry = float(np.max(np.abs(A - A.T))) if n else 0.0
    if asymmetry > 1e-12 * max(float(np.max(np.abs(A))) if n else 0.0, 1e-300):
        raise NotPositiveDefiniteError(
            f"acceleration_qp: A is not symmetric (largest |A - Aᵀ| = {asymmetry:.3g}); pass the kinetic-energy matrix"
        )
    if n and np.min(np.linalg.eigvalsh(0.5 * (A + A.T))) <= 0:
        raise NotPositiveDefiniteError("acceleration_qp: A is not positive definite; pass the kinetic-energy matrix")
    solver = reference_backend(backend)
    U, s, _ = np.linalg.svd(D, full_matrices=True)
    rank = int(np.sum(s > 1e-12 * max(float(s[0]) if s.size else 0.0, 1e-300)))
    P = U[:, rank:]  # orthonormal basis of ker Dᵀ
    E = np.vstack([J, P.T @ A])
    e = np.concatenate([phi, P.T @ A @ a0])
    size = np.linalg.norm(E, axis=1)
    size[size == 0] = 1.0
    E, e = E / size[:, None], e / size
    weight = float(np.max(np.abs(A)))
    problem = qp.QP(
        A / weight,
        -(A @ a0) / weight,
        E,
        e,
        np.zeros((0, n)),
        np.zeros(0),
        np.full(n, -np.inf),
        np.full(n, np.inf),
        "reference",
    )
    answer = _solve(problem, solver)
    a = np.asarray(answer.x, dtype=float)
    primal = float(np.max(np.abs(E @ a - e))) / (1.0 + float(np.max(np.abs(a))))
    # the backend's stationarity residual max|A(a − a₀)/w + Eᵀy| from its own multipliers (inf when it gave none)
    dual = (answer.dual if np.isfinite(answer.dual) else np.inf) / (1.0 + float(np.max(np.abs(a))))
    return AccelerationQP(a=a, backend=qp.short_name(solver), primal=primal, dual=dual)


def _solve(problem: qp.QP, backend: qp.QPBackend) -> qp.QPAnswer:
    """The reference QP by ``backend``; no answer, or one the backend does not call a solution, is an error."""
    qp.require(backend, problem.features)
    try:
        answer = backend.solve_qp(problem)
    except Exception as exc:  # the backend's own error, as ours
        raise QPSolveError(f"the reference QP failed in {backend.name}: {exc}") from exc
    if not answer.found or answer.x is None or not np.all(np.isfinite(answer.x)):
        raise QPSolveError(
            f"{backend.name} found no solution of the reference QP (the constraint may not be realizable)"
        )
    return answer


@dataclass(frozen=True)
class CrossCheck:
    """The model's answers at one state beside the independent reference.

    Attributes
    ----------
    reference : AccelerationQP   the acceleration-space QP's answer and KKT residuals
    answers : dict               solver name → acceleration, raw (each solver's own answer)
    distances : dict             solver name → ``‖a − a_ref‖ / scale``
    refined : dict               solver name → distance of the refined answer (reported apart)
    scale : float                ``max(‖a_ref‖, ‖a₀‖, ‖A⁻¹f‖)``, the size the distances are relative to
    tolerance : float
    """

    reference: AccelerationQP
    answers: dict[str, np.ndarray]
    distances: dict[str, float]
    refined: dict[str, float] = field(default_factory=dict)
    scale: float = 1.0
    tolerance: float = TOLERANCE

    @property
    def ok(self) -> bool:
        """Every raw answer within ``tolerance`` of the reference, and the reference optimal to it."""
        return (
            self.reference.primal <= self.tolerance
            and self.reference.dual <= self.tolerance
            and all(d <= self.tolerance for d in self.distances.values())
        )

    def __str__(self) -> str:
        lines = [
            f"reference ({self.reference.backend}): KKT primal {self.reference.primal:.1e}, "
            f"dual {self.reference.dual:.1e}"
        ]
        for name, d in self.distances.items():
            extra = f" (refined {self.refined[name]:.1e})" if name in self.refined else ""
            lines.append(f"{name:>20}: {d:.1e}{extra} {'ok' if d <= self.tolerance else 'DIFFERS'}")
        return "\n".join(lines)


def crosscheck(
    model: Any,
    t: float,
    q: Any,
    v: Any,
    lam: Any = None,
    *,
    solvers: tuple[str, ...] = ("direct", "qp"),
    backend: str | None = None,
    reference_backend: str | None = None,
    tolerance: float = TOLERANCE,
) -> CrossCheck:
    """Compare the model's step solvers at ``(t, q, v, λ)`` with the acceleration-space QP.

    Each solver in ``solvers`` is run raw (``refine=False``) and refined; ``backend`` is the model's
    QP backend. The direct formula is skipped where it does not exist (more reaction directions than
    constraint rows). Models with contacts or bounded actuators are not covered (their step has
    inequalities): an :class:`InputError`.
    """
    model_argument("crosscheck", model)
    tolerance = positive("tolerance", tolerance, hint=" (the relative agreement asked of the solvers, e.g. 1e-9)")
    if model.contacts or model.bounded:
        raise InputError("crosscheck covers the equality step; this model has contacts or bounded actuators")
    # the model's own answers first: they raise the clear project errors (unrealizable, not positive definite)
    answers: dict[str, np.ndarray] = {}
    polished: dict[str, np.ndarray] = {}
    for solver in solvers:
        if solver == "direct" and model.m != model.k:
            continue
        name = solver if solver == "direct" else f"qp:{backend or 'default'}"
        options = {} if solver == "direct" else {"backend": backend}
        answers[name] = model.step(t, q, v, lam, solver=solver, refine=False, **options).a
        polished[name] = model.step(t, q, v, lam, solver=solver, refine=True, **options).a
    data = model.step_data(t, q, v, lam)
    a0 = np.linalg.solve(data.A, data.f + data.r0)
    ref = acceleration_qp(data.A, a0, data.J, data.phi, data.D, reference_backend)
    sizes = (ref.a, a0, np.linalg.solve(data.A, data.f))
    scale = max(*(float(np.linalg.norm(x)) for x in sizes), 1e-300)
    distances = {name: float(np.linalg.norm(a - ref.a)) / scale for name, a in answers.items()}
    refined = {name: float(np.linalg.norm(a - ref.a)) / scale for name, a in polished.items()}
    return CrossCheck(ref, answers, distances, refined, scale, tolerance)
