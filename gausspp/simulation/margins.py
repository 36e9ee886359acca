"""The realizability margin along a recorded run: where the realization lost the constraint between samples.

Every step checks the margin where it is evaluated (:mod:`gausspp.simulation.rhs`), but a step can
go past a state where it vanishes. :func:`audit` looks at the sampled margin afterwards: a sign
change of ``det S`` (it passed through zero), a small minimum whose parabola dips to zero (it
touched zero), a sample below ``margin_error`` — each cuts the run there with a
:class:`~gausspp.RealizabilityError` — and a sample below ``margin_warn`` (a warning).
"""

from __future__ import annotations

import numpy as np

from ..errors import GaussppError, IntegrationError, NonFiniteError, RealizabilityError
from ..model.model import Model
from ..step.outcome import Where, to_result
from ..step.realizability import is_symmetric
from .rhs import AnyRightHandSide, GeneralRightHandSide

#: A sampled margin below this is "small": worth a look between samples, and worth naming in a failure.
SMALL_MARGIN = 1e-2

#: What :func:`audit` found: the samples to keep, the failure, the warnings to give.
Audit = tuple[int, Exception | None, list[str]]


def replaceable(failure: Exception | None) -> bool:
    """No failure yet, or one that a margin lost at earlier samples explains (a realizability failure, or the
    divergence that follows a step across a singular state)."""
    return failure is None or isinstance(failure, (RealizabilityError, NonFiniteError, IntegrationError))


def audit(
    model: Model,
    rhs: AnyRightHandSide,
    t: np.ndarray,
    y: np.ndarray,
    S: np.ndarray,
    margin: np.ndarray,
    failure: Exception | None,
    crossed: tuple[float, ...] = (),
) -> Audit:
    """Check the sampled margin (``S``: the normalized ``S`` of each sample); ``failure``: the recording's own;
    ``crossed``: the singular positions the run stepped over (:mod:`gausspp.simulation.crossing`), where the margin
    of ideal rows touches zero and the motion goes on."""
    n, notes = t.size, list[str]()
    if not rhs.margin_checked:  # redundant rows: the margin is 0 by design and says nothing
        return n, failure, notes
    if replaceable(failure) and n > 1 and model.m == model.k and not (model.symmetric_S or is_symmetric(S)):
        # (a symmetric S is J A⁻¹ Jᵀ: positive semidefinite, det S ≥ 0 — a lost margin shows as a dip to zero)
        found = _sign_change(model, t, S)
        if found is not None:
            n, failure = found
    touch = touches_zero(t[:n], margin[:n], model.margin_error, crossed) if replaceable(failure) else None
    if touch is not None:  # a minimum of the margin between samples reaches zero: the step went past it
        i, t_min = touch
        notes.append(
            f"the realizability margin falls below {model.margin_warn:g} between the samples at t={t[i - 1]:.6g} and "
            f"t={t[i + 1]:.6g} (smallest sampled {margin[i]:.3g}; its parabola reaches zero near t={t_min:.6g})"
        )
        n, failure = i + 1, _touched(model, t, i, t_min)
    bad = np.flatnonzero(margin[:n] < model.margin_error)
    if bad.size and failure is None:
        n = int(bad[0])
        failure = _vanished(model, rhs, t, y, margin, n)
    low = np.flatnonzero(margin[:n] < model.margin_warn)
    if low.size:
        notes.append(
            f"realizability margin {margin[low[0]]:.3g} at t={t[low[0]]:.6g} (smallest {margin[:n].min():.3g}) is "
            "small: the reaction is large and sensitive to errors"
        )
    return n, failure, notes


def _lost(model: Model, when: str, t: float, then: str, margin: float = 0.0) -> RealizabilityError:
    names = ", ".join(repr(n) for n in model.names)
    return RealizabilityError(
        f"the realizability margin {when}constraints {names}): the realization cannot keep the constraint there{then}",
        t=float(t),
        constraint=", ".join(model.names),
        margin=margin,
    )


def _touched(model: Model, t: np.ndarray, i: int, t_min: float) -> RealizabilityError:
    when = f"reaches zero between t={t[i - 1]:.6g} and t={t[i + 1]:.6g} (near t={t_min:.6g}; "
    return _lost(model, when, t_min, " and the step went past it; samples after it are dropped")


def _sign_change(model: Model, t: np.ndarray, S: np.ndarray) -> tuple[int, Exception] | None:
    """``det S`` is continuous along a motion: a sign change between samples means ``S`` was singular."""
    flips = np.flatnonzero(np.sign(np.linalg.det(S[1:])) * np.sign(np.linalg.det(S[:-1])) < 0)
    if not flips.size:
        return None
    i = int(flips[0])
    return i + 1, _lost(
        model,
        f"passed through zero between t={t[i]:.6g} and t={t[i + 1]:.6g} (",
        t[i + 1],
        " and the step went past it; samples after it are dropped",
    )


def _vanished(
    model: Model, rhs: AnyRightHandSide, t: np.ndarray, y: np.ndarray, margin: np.ndarray, i: int
) -> Exception:
    """The error for the first sample ``i`` whose margin is below ``margin_error``: the step's own diagnosis (the
    compiled step), or — the general QP answered although the margin vanished — a realizability error."""
    if not isinstance(rhs, GeneralRightHandSide):
        nq, nv, nl = model.nq, model.nv, model.n_lam
        q, v, lam = y[i, :nq], y[i, nq : nq + nv], y[i, nq + nv : nq + nv + nl]
        where = Where(float(t[i]), rhs.solver, model.groups, lambda: model.step_data(t[i], q, v, lam))
        try:
            out = rhs.evaluate(t[i], y[i], stabilized=False)
            to_result(out, where, margin_warn=model.margin_warn, margin_error=model.margin_error)
        except GaussppError as exc:
            return exc
    return _lost(
        model, f"vanished at t={t[i]:.6g} (", t[i], "; samples from it on are dropped", margin=float(margin[i])
    )


def touches_zero(
    ts: np.ndarray, margin: np.ndarray, floor: float, crossed: tuple[float, ...] = ()
) -> tuple[int, float] | None:
    """First strict local minimum of the sampled margin whose parabola through it and its neighbours dips
    below ``floor``: a margin that touches zero between samples without changing the sign of det S (the
    crane's ``sin²θ``). Returns the sample index and the estimated time, or ``None``. Minima whose neighbours
    enclose a ``crossed`` instant (a singular position stepped over) are not suspect."""
    inner = margin[1:-1]  # only an already small strict minimum is suspect
    suspects = np.flatnonzero((inner < SMALL_MARGIN) & (inner < margin[:-2]) & (inner < margin[2:])) + 1
    for i in suspects:
        if any(ts[i - 1] < c < ts[i + 1] for c in crossed):
            continue
        m0, m1, m2 = margin[i - 1 : i + 2]
        t0, t1, t2 = ts[i - 1 : i + 2]
        a, b, c = np.polyfit([t0 - t1, 0.0, t2 - t1], [m0, m1, m2], 2)
        if a <= 0:
            continue
        vertex = -b / (2 * a)
        if c - b * b / (4 * a) < floor and t0 - t1 <= vertex <= t2 - t1:
            return int(i), float(t1 + vertex)
    return None
