"""From a kernel's raw outputs to a checked :class:`StepResult`, or a project error.

The hot path only reads a few numbers (pivot, ``Ŝ``, residuals); the slower diagnosis —
which piece is not finite, which constraint is not realizable — runs only on failure.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import NonFiniteError, NotPositiveDefiniteError, QPSolveError, RealizabilityError, RealizabilityWarning
from .data import StepProblem
from .protocol import Group
from .realizability import group_margins, margin_of, singular_values, step_margin
from .realizability import margin as realizability_margin
from .results import StepResult

__all__ = ["QP_TOLERANCE", "Group", "Where", "evaluation_failed", "singular_values", "step_margin", "to_result"]


#: Relative primal residual of the step QP above which the backend is deemed to have failed.
QP_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Where:
    """Where a step happens, for messages: its time, solver, constraints and (lazily) its data."""

    t: float
    solver: str
    groups: Sequence[Group]
    data: Callable[[], StepProblem]


def _where(t: float) -> str:
    return f"at t={t:.6g}"


def _check_data(data: StepProblem, t: float, groups: Sequence[Group]) -> None:
    for field in ("A", "f", "r0"):
        if not np.all(np.isfinite(getattr(data, field))):
            what = {"A": "the mass matrix A", "f": "the forces F − h", "r0": "the known reaction r₀ (from λ)"}[field]
            raise NonFiniteError(f"{what} is not finite {_where(t)}; check the state and the model's formulas there")
    for g in groups:
        for field, what in (("J", "∂Φ/∂v"), ("phi", "φ = −(∂Φ/∂q q̇ + ∂Φ/∂t)"), ("Phi", "Φ")):
            if not np.all(np.isfinite(getattr(data, field)[g.rows])):
                raise NonFiniteError(
                    f"constraint {g.name!r}: {what} is not finite {_where(t)}; check its formula there"
                )
        if not np.all(np.isfinite(data.D[:, g.cols])):
            raise NonFiniteError(f"constraint {g.name!r}: the reaction directions D are not finite {_where(t)}")


def not_positive_definite(data: Any, t: float) -> NotPositiveDefiniteError:
    """The error for ``data.A`` (any object with the mass matrix ``A``) not symmetric positive definite at ``t``."""
    A = data.A
    asym = np.max(np.abs(A - A.T)) / max(np.max(np.abs(A)), 1e-300)
    if asym > 1e-12:
        return NotPositiveDefiniteError(
            f"the mass matrix A is not symmetric {_where(t)} (relative asymmetry {asym:.3g}); "
            "A = ∂²T/∂v² must be symmetric: check the MassMatrix formula"
        )
    eig = np.linalg.eigvalsh(A)
    return NotPositiveDefiniteError(
        f"the mass matrix A is not positive definite {_where(t)}: eigenvalues {np.array2string(eig, precision=4)}; "
        "check masses and inertias (sign, units) or whether the coordinates are singular at this configuration"
    )


def _unrealizable(
    data: StepProblem, t: float, margin: float, groups: Sequence[Group], margin_error: float
) -> RealizabilityError:
    margins = group_margins(data.A, data.J, data.D, [(g.rows, g.cols) for g in groups])  # one factorization of A
    solo = list(zip(margins, groups, strict=True))
    worst_margin, worst = min(solo, key=lambda s: s[0])
    if worst_margin < margin_error or len(groups) == 1:
        realization = f" by its {worst.label} realization" if worst.label else ""
        return RealizabilityError(
            f"constraint {worst.name!r} is not realizable{realization} {_where(t)}: realizability margin "
            f"{worst_margin:.3g} (J A⁻¹ D is singular); {worst.hint or 'choose other reaction directions'}",
            t=t,
            constraint=worst.name,
            margin=worst_margin,
        )
    names = ", ".join(repr(g.name) for g in groups)
    ideal = data.D.shape == data.J.T.shape and np.allclose(data.D, data.J.T, rtol=1e-12, atol=0.0)
    why = (
        "their constraint rows are dependent here (the reactions are along them): either redundant rows, dependent "
        "everywhere — solver='qp' steps them, as gp.simulate does when it finds them at the start — or a singular "
        "position of the mechanism (a linkage's bars in line), which a run cannot yet step through"
        if ideal
        else "their constraint rows or their reaction directions are dependent — remove a redundant constraint, or "
        "change one of the realizations"
    )
    return RealizabilityError(
        f"constraints {names} are each realizable but not together {_where(t)}: margin {margin:.3g} "
        f"(J A⁻¹ D is singular): {why}",
        t=t,
        constraint=names,
        margin=margin,
    )


def evaluation_failed(exc: RuntimeError, where: Where, *, margin_error: float) -> Exception:
    """The compiled step raised (a QP plugin refuses NaN data, say): find the cause in the data."""
    t, solver, groups = where.t, where.solver, where.groups
    d = where.data()
    _check_data(d, t, groups)
    if not np.all(np.linalg.eigvalsh(0.5 * (d.A + d.A.T)) > 0) or not np.allclose(d.A, d.A.T, rtol=1e-12, atol=0):
        return not_positive_definite(d, t)
    whole = realizability_margin(d.A, d.J, d.D)
    if whole < margin_error:
        return _unrealizable(d, t, whole, groups, margin_error)
    return QPSolveError(f"the step failed {_where(t)} in {solver}: {str(exc).strip().splitlines()[-1]}")


def to_result(out: dict[str, np.ndarray], where: Where, *, margin_warn: float, margin_error: float) -> StepResult:
    """Check a kernel's outputs and package them; raise a project error on failure."""
    t, solver, groups, data = where.t, where.solver, where.groups, where.data
    pivot = float(out["pivot"][0])
    finite = bool(np.isfinite(out["checksum"][0]))
    if not (pivot > 0) or not finite:
        d = data()
        _check_data(d, t, groups)
        if not (pivot > 0):
            raise not_positive_definite(d, t)
    S_norm = out["S_norm"]
    k, m = S_norm.shape if S_norm.ndim == 2 else (S_norm.size, 1)
    cos = np.zeros(min(k, m)) if not finite and not np.isfinite(S_norm.sum()) else singular_values(S_norm, k, m)
    margin = margin_of(cos, k, m)
    if margin < margin_error:
        raise _unrealizable(data(), t, margin, groups, margin_error)
    if not finite and not all(np.all(np.isfinite(v)) for name, v in out.items() if name not in ("S_norm", "checksum")):
        raise NonFiniteError(
            f"the step produced NaN or inf {_where(t)} although its data are finite; margin {margin:.3g}"
        )
    warn_small_margin(margin, t, groups, margin_warn, stacklevel=4)
    qp_res = None
    if solver != "direct":
        primal, dual = float(out["qp_primal"][0]), float(out["qp_dual"][0])
        if not (primal <= QP_TOLERANCE and dual <= QP_TOLERANCE):
            raise QPSolveError(
                f"QP backend {solver} did not solve the step {_where(t)}: relative primal residual {primal:.3g}, "
                f"dual residual {dual:.3g} (realizability margin {margin:.3g}); try another backend "
                "(gausspp.qp.names()) or solver='direct'"
            )
        qp_res = (primal, dual)
    return StepResult(
        t=t,
        a=out["a"].copy(),
        u=out["u"].copy(),
        reaction=out["reaction"].copy(),
        compulsion=float(out["compulsion"][0]),
        margin=margin,
        cosines=cos,
        residual=out["residual"].copy(),
        constraint_value=out["Phi"].copy(),
        free_acceleration=out["a_free"].copy(),
        solver=solver,
        qp_residuals=qp_res,
    )


def warn_small_margin(
    margin: float, t: float, groups: Sequence[Group], margin_warn: float, stacklevel: int = 4
) -> None:
    """Warn (:class:`RealizabilityWarning`) when ``margin < margin_warn``: the reaction is large and sensitive."""
    if margin < margin_warn:
        names = ", ".join(repr(g.name) for g in groups)
        warnings.warn(
            f"realizability margin {margin:.3g} {_where(t)} (constraints {names}) is small: the reaction is large "
            "and sensitive to errors",
            RealizabilityWarning,
            stacklevel=stacklevel,
        )
