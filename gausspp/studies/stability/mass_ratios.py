"""Mass ratios 1e-6…1e6: the direct formula and the QP against an exact rational solve of the same step."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from ... import scenes
from ...errors import GaussppError
from ...model.model import Model
from ...step.data import StepProblem
from .common import EPS, Case, Solver, fmt, realizability_warnings, recorded, relative, solvers

NAME = "mass ratios"
WHAT = (
    "two-masses (m2/m1) and stiff-chain (mass_ratio) over 1e-6…1e6, ideal and servo; one step by the direct "
    "formula, the default QP and casadi:osqp, against an exact rational solve of the same step data"
)
EXPECTED = "relative acceleration error ≤ 10·eps·cond(A) for every solver, and QP ≡ direct to the same bound"

Matrix = list[list[Fraction]]


def _solve(M: Matrix, B: Matrix) -> Matrix:
    """Exact ``M⁻¹B`` by Gaussian elimination over the rationals (``M`` nonsingular, small)."""
    n = len(M)
    aug = [list(M[i]) + list(B[i]) for i in range(n)]
    for col in range(n):
        pivot = next(r for r in range(col, n) if aug[r][col] != 0)
        aug[col], aug[pivot] = aug[pivot], aug[col]
        p = aug[col][col]
        aug[col] = [x / p for x in aug[col]]
        for r in range(n):
            if r != col and aug[r][col] != 0:
                factor = aug[r][col]
                aug[r] = [x - factor * y for x, y in zip(aug[r], aug[col], strict=True)]
    return [row[n:] for row in aug]


def _exact(x: np.ndarray) -> Matrix:
    """A float array as exact rationals, vectors as columns."""
    x = np.asarray(x, float)
    return [[Fraction(float(v)) for v in row] for row in (x.reshape(-1, 1) if x.ndim == 1 else x)]


def _mul(X: Matrix, Y: Matrix) -> Matrix:
    return [
        [sum((X[i][k] * Y[k][j] for k in range(len(Y))), Fraction(0)) for j in range(len(Y[0]))] for i in range(len(X))
    ]


def exact_acceleration(p: StepProblem) -> np.ndarray:
    """The step's acceleration computed exactly (rational arithmetic) from its float data (docs/theory.md §2).

    ``a = a₀ + A⁻¹D u`` with ``a₀ = A⁻¹(f + r₀)`` and ``J A⁻¹D u = φ − J a₀``.
    """
    A, J, D = _exact(p.A), _exact(p.J), _exact(p.D)
    rhs = [[a[0] + b[0]] for a, b in zip(_exact(p.f), _exact(p.r0), strict=True)]
    a0, AinvD = _solve(A, rhs), _solve(A, D)
    r = [[phi[0] - ja[0]] for phi, ja in zip(_exact(p.phi), _mul(J, a0), strict=True)]
    u = _solve(_mul(J, AinvD), r)
    return np.array([float(x[0] + y[0]) for x, y in zip(a0, _mul(AinvD, u), strict=True)])


@dataclass
class _Tally:
    """The worst errors over the steps checked so far, and where they occurred."""

    worst: dict[str, float]
    worst_over_bound: float = 0.0
    worst_difference: float = 0.0
    worst_disagreement: float = 0.0
    reference_check: float = 0.0
    largest: float = 0.0
    worst_at: str = ""
    largest_at: str = ""
    max_cond: float = 1.0
    min_margin: float = 1.0
    checked: int = 0
    warned: int = 0
    failures: list[str] = field(default_factory=list)

    def check_step(
        self, ways: list[Solver], model: Model, q: np.ndarray, v: np.ndarray, setup: tuple[str, str, float]
    ) -> np.ndarray:
        """Step ``model`` at ``(q, v)`` with every solver and tally the errors against the exact acceleration
        (returned); ``setup`` is (scene name, realization, mass ratio), for the messages."""
        scene_name, realization, ratio = setup
        data = model.step_data(0.0, q, v)
        ref = exact_acceleration(data)
        cond = float(np.linalg.cond(data.A))
        bound = EPS * max(cond, 1.0)
        self.max_cond = max(self.max_cond, cond)
        results = {}
        with recorded() as caught:
            for label, solver, backend in ways:
                try:
                    results[label] = model.step(0.0, q, v, solver=solver, backend=backend)
                except GaussppError as exc:
                    self.failures.append(f"{scene_name} {realization} ratio {ratio:g} {label}: {exc}")
        self.warned += len(realizability_warnings(caught))
        self.checked += 1
        direct = results.get("direct")
        for label, res in results.items():
            err = relative(res.a, ref)
            self.min_margin = min(self.min_margin, res.margin)
            self.worst[label] = max(self.worst[label], err)
            where = f"{label} on {scene_name} ({realization}), mass ratio {ratio:g}, cond(A) = {cond:.1e}"
            if err > self.largest:
                self.largest, self.largest_at = err, where
            if err / bound > self.worst_over_bound:
                self.worst_over_bound, self.worst_at = err / bound, f"{where}: relative error {fmt(err)}"
            if direct is not None and label != "direct":
                self.worst_difference = max(self.worst_difference, relative(res.a, direct.a) / bound)
                self.worst_disagreement = max(self.worst_disagreement, res.disagreement(direct))
        return ref

    def check_reference(self, ref: np.ndarray, closed: float) -> None:
        """Tally the exact acceleration ``ref`` of the two-masses scene against its closed form ``(closed, closed)``."""
        self.reference_check = max(self.reference_check, relative(ref, np.array([closed, closed])))


def _setups(ratio: float) -> list[tuple[str, dict[str, float], str]]:
    """The scenes at mass ratio ``ratio``: (scene name, parameters, realization)."""
    return [
        ("two-masses", dict(m1=1.0, m2=ratio, F=2.0), "ideal"),
        ("two-masses", dict(m1=1.0, m2=ratio, F=2.0), "servo"),
        ("stiff-chain", dict(mass_ratio=ratio), "ideal"),
        ("stiff-chain", dict(mass_ratio=ratio), "servo"),
    ]


def _observed(tally: _Tally, exponents: range) -> str:
    """What the case saw, in words."""
    errors = ", ".join(f"{label} {fmt(v)}" for label, v in tally.worst.items())
    return (
        f"{tally.checked} steps over mass ratios 1e{min(exponents)}…1e{max(exponents)} (cond(A) up to "
        f"{tally.max_cond:.0e}, margins down to {tally.min_margin:.1e}): worst relative acceleration errors {errors} "
        f"(largest: {tally.largest_at}); worst error / (eps·cond A) = {tally.worst_over_bound:.2f} ({tally.worst_at}); "
        f"QP vs direct at most {tally.worst_difference:.2f}·eps·cond (the library's disagreement(), scaled by the "
        f"free acceleration as well, at most {fmt(tally.worst_disagreement)}). {len(tally.failures)} step failures, "
        f"{tally.warned} realizability warnings."
        + (
            " The loss comes from the reaction-space formulation: a = a₀ + A⁻¹Du with a₀ = A⁻¹f large when a light "
            "mass is pushed, then cancelled."
            if tally.worst_over_bound > 3.0
            else ""
        )
    )


def case(quick: bool = True) -> Case:
    """QP ≡ direct and accuracy against an exact solve over mass ratios 1e-6…1e6."""
    exponents = range(-6, 7, 2) if quick else range(-6, 7)
    ways = solvers([None, "casadi:osqp"] + ([] if quick else ["casadi:daqp", "qpsolvers:quadprog"]))
    rng = np.random.default_rng(20261121)
    tally = _Tally(worst={label: 0.0 for label, _, _ in ways})
    for e in exponents:
        ratio = 10.0**e
        for scene_name, params, realization in _setups(ratio):
            scene = scenes.get(scene_name, realization=realization, **params)
            model = scene.model
            states = [(scene.q0, scene.v0)]
            if not quick:
                states += [(rng.normal(size=model.nq), rng.normal(size=model.nv)) for _ in range(3)]
            for i, (q, v) in enumerate(states):
                ref = tally.check_step(ways, model, q, v, (scene_name, realization, ratio))
                if scene_name == "two-masses" and i == 0:  # the reference against the closed form
                    closed = 2.0 / (1.0 + ratio) if realization == "ideal" else 2.0 / ratio
                    tally.check_reference(ref, closed)
    figures: dict[str, float] = {f"worst_error_{label}": v for label, v in tally.worst.items()}
    figures.update(
        worst_error_over_eps_cond=tally.worst_over_bound,
        worst_qp_direct_difference_over_eps_cond=tally.worst_difference,
        worst_library_disagreement=tally.worst_disagreement,
        reference_vs_closed_form=tally.reference_check,
        max_cond=tally.max_cond,
        min_margin=tally.min_margin,
        steps_checked=float(tally.checked),
        failures=float(len(tally.failures)),
        realizability_warnings=float(tally.warned),
    )
    verdict = (
        not tally.failures
        and tally.worst_over_bound <= 10.0
        and tally.worst_difference <= 10.0
        and tally.reference_check < 1e-14
    )
    return Case(NAME, WHAT, EXPECTED, _observed(tally, exponents), bool(verdict), figures, tuple(tally.failures[:3]))
