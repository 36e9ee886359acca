"""Which bilateral rows the general Gauss step keeps, decided where :mod:`gausspp.step.redundancy` says.

The rows are judged at a *reference* (:class:`~gausspp.step.scaling.Scaled`): the state itself, or
the same problem at the nearest state on the constraint manifold when the state cannot decide —
rows independent here but not clearly so (:data:`~gausspp.step.redundancy.CLEARLY_INDEPENDENT`),
dependent rows that disagree, or dropped rows with no witness that they hold together. There the
realizations must keep their constraints (``rank S ≥ rank J``, conditions (12)/(16)) and the dropped
rows must agree with the kept ones to the consistency tolerance; either failure is a
:class:`~gausspp.errors.RealizabilityError`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ...errors import RealizabilityError
from .. import dense
from .gauss_problem import GaussProblem, at, row_names, row_roles
from .redundancy import CLEARLY_INDEPENDENT, DEPENDENCE_TOL, chosen_rows, independent_rows, sines_of
from .scaling import Scaled, rank_of, scaled

#: A dropped row at the angle ``s`` from the kept rows' span may miss their right-hand sides by this many ``s‖y‖``.
AGREEMENT_SLACK = 10.0

#: The problem on the manifold, or a function that builds it (``None``: the state is on it already).
Reference = GaussProblem | Callable[[], GaussProblem | None] | None


@dataclass(frozen=True)
class Rows:
    """The decision: the reference it was taken at, the bilateral rows kept, and how many were dropped."""

    ref: Scaled
    kept: np.ndarray
    redundant: int
    isolated: bool = False  # rows kept on the open piece were dropped at an isolated singular position
    sine: float = 1.0  # the kept rows' smallest sine against those before them, at the reference


def kept_rows(ref: Scaled, eq: np.ndarray, keep: np.ndarray | None = None) -> tuple[np.ndarray, float, np.ndarray]:
    """The bilateral rows kept (:func:`~gausspp.step.redundancy.chosen_rows` at ``ref``, or the rows ``keep``), how
    far the dropped ones contradict the kept ones there, and each row's sine against the rows kept before it.

    The contradiction of a dropped row ``d = cᵀ K + s n`` (``s`` its sine against the kept rows ``K``) is what its
    right-hand side misses, less the ``s ‖y‖`` its own angle explains (``y`` the whitened reaction), relative to
    the right-hand side's size times ``1 + ‖c‖₁`` (round-off in the kept rows' right-hand sides multiplied by the
    combination) and over ``min(1, s_K / CLEARLY_INDEPENDENT)`` (``s_K`` the kept rows' smallest sine: nearly
    dependent kept rows amplify drift and round-off by ``1/s_K``): zero for rows dependent everywhere, and for a
    linkage passing a singular position on its branch; of order one for rows that describe different constraints.
    """
    eq_rows = np.flatnonzero(eq)
    if keep is None:
        kept_local, sines = chosen_rows(ref.Jn[eq_rows])
    else:
        kept_local = np.flatnonzero(np.isin(eq_rows, keep))
        sines = sines_of(ref.Jn[eq_rows], kept_local)
    kept = eq_rows[kept_local]
    gap = 0.0
    if kept.size < eq_rows.size:
        keep = np.zeros(eq_rows.size, bool)
        keep[kept_local] = True
        dropped = eq_rows[~keep]
        scale = max(ref.scale, 1e-300)
        if kept.size:  # each dropped row as a combination of the kept ones; its right-hand side must follow
            combo = dense.lstsq(ref.Jn[kept].T, ref.Jn[dropped].T)
            miss = np.abs(ref.r[dropped] - combo.T @ ref.r[kept]) / scale
            # what agreement can mean: a row at the angle s from the kept rows' span misses by up to s‖y‖ (y the
            # whitened reaction, here the kept rows' least-norm one), and round-off in the kept rows' right-hand
            # sides comes in multiplied by the combination's size — near a singular position both are large
            y = ref.Jn[kept].T @ dense.lstsq(ref.Jn[kept] @ ref.Jn[kept].T, ref.r[kept])
            explained = AGREEMENT_SLACK * sines[dropped] * float(np.linalg.norm(y)) / scale
            gap = float(np.max(np.maximum(miss - explained, 0.0) / (1.0 + np.abs(combo).sum(axis=0))))
            # kept rows that are themselves nearly dependent (near a singular position) amplify the drift and
            # round-off in their right-hand sides by one over their smallest sine: a gap is judged against that
            gap *= min(1.0, float(sines[kept].min()) / CLEARLY_INDEPENDENT)
        else:
            gap = float(np.abs(ref.r[dropped]).max()) / scale
    return kept, gap, sines


def check_realizable(p: GaussProblem, ref: Scaled, mask: np.ndarray) -> None:
    """Raise unless the realizations keep the rows ``mask``: ``rank S ≥ rank J`` at the reference.

    ``S = J A⁻¹ D`` is compared with the Gram matrix ``J A⁻¹ Jᵀ`` (the ideal realization's ``S``): both
    square the smallness of nearly dependent rows, so near-redundancy is not mistaken for a failing realization.
    """
    if not mask.any():
        return
    Jn = ref.Jn[mask]
    rank_J = rank_of(dense.singular_values(Jn @ Jn.T))
    rank_S = rank_of(dense.singular_values(ref.S[mask]))
    if rank_S < rank_J:
        names = row_names(p)
        raise RealizabilityError(
            f"the realization cannot keep the constraint(s) "
            f"{sorted({names[i].split('[')[0] for i in np.flatnonzero(mask)})}{at(p.t)}: "
            f"J A⁻¹ D has rank {rank_S} < rank J = {rank_J} (conditions (12)/(16)); "
            "choose reaction directions that are not A-orthogonal to the constraint's normal",
            t=p.t,
            constraint=names[int(np.flatnonzero(mask)[0])],
            margin=0.0,
        )


def _contradiction(p: GaussProblem, eq: np.ndarray, gap: float) -> RealizabilityError:
    names = row_names(p)
    involved = sorted({names[i].split("[")[0] for i in np.flatnonzero(eq)})
    return RealizabilityError(
        f"the constraint rows of {', '.join(map(repr, involved))} are dependent and contradict each other{at(p.t)} "
        f"(relative inconsistency {gap:.2e} on the constraint manifold): the redundant rows describe different "
        "constraints — remove one of them",
        t=p.t,
        constraint=names[int(np.flatnonzero(eq)[0])],
        margin=0.0,
    )


#: Whether the state is on the constraint manifold, or a function that tells (called only when rows were dropped).
NearManifold = bool | Callable[[], bool]


def decide_rows(
    p: GaussProblem,
    s: Scaled,
    consistency_tol: float,
    reference: Reference,
    near_manifold: NearManifold,
    kept_before: tuple[int, ...] | None = None,
) -> Rows:
    """The rows kept (see the module docstring); ``s`` is ``p`` scaled, the reference unless one is needed.

    ``kept_before``: the rows the decision on the open piece of the manifold the motion comes from kept (the
    compiled step's pattern). A row among them found dependent here lost its independence at an isolated
    position — a parallelogram's collinear one, where the rows' rank drops at one instant — and is dropped for
    this state without being called a contradiction: what it misses there is the drift, amplified by the rows'
    vanishing angle, not another constraint.
    """
    roles = row_roles(p)
    eq, track = roles.eq, roles.track
    ref = s
    kept, gap, sines = kept_rows(ref, eq)
    # rows that are independent here but not clearly so, or dependent rows that disagree, may be an artefact of
    # the state's distance from the manifold: decide at the nearest state on it
    ambiguous = bool(((sines > DEPENDENCE_TOL) & (sines < CLEARLY_INDEPENDENT)).any()) or gap > consistency_tol
    # dropped rows must hold together near the state: checked at the reference unless the state is a witness
    if not ambiguous and kept.size < int(eq.sum()):
        ambiguous = not (near_manifold() if callable(near_manifold) else near_manifold)
    if ambiguous and reference is not None:
        on_manifold = reference() if callable(reference) else reference
        if on_manifold is not None:
            ref = scaled(on_manifold)
            kept, gap, sines = kept_rows(ref, eq)
    kept, gap, sines = _hold(ref, eq, kept, gap, sines, kept_before)
    check_realizable(p, ref, eq | track)
    dropped = set(np.flatnonzero(eq).tolist()) - set(kept.tolist())
    # a row independent before, dropped by the declared order here (not a choice of other rows, well conditioned,
    # of the same rank: chosen_rows's pivoted choice or the rows held)
    in_order = np.flatnonzero(eq)[independent_rows(ref.Jn[eq])[0]]
    deliberate = kept.size == len(kept_before or ()) and not np.array_equal(kept, in_order)
    isolated = kept_before is not None and bool(dropped & set(kept_before)) and not deliberate
    if gap > consistency_tol and not isolated:
        raise _contradiction(p, eq, gap)
    sine = float(sines[kept].min()) if kept.size else 1.0
    return Rows(ref, kept, int(eq.sum()) - kept.size, isolated and gap > consistency_tol, sine)


def _hold(
    ref: Scaled, eq: np.ndarray, kept: np.ndarray, gap: float, sines: np.ndarray, before: tuple[int, ...] | None
) -> tuple[np.ndarray, float, np.ndarray]:
    """The rows kept before, where they are as many as a choice now and still clearly independent: a choice is
    changed only when it turns ill-conditioned (near the crossover of two choices, choosing anew at every state
    would switch back and forth)."""
    if before is None or len(before) != kept.size or set(before) == set(kept.tolist()):
        return kept, gap, sines
    held = np.array(sorted(before), dtype=int)
    if not np.all(eq[held]):
        return kept, gap, sines
    h_kept, h_gap, h_sines = kept_rows(ref, eq, keep=held)
    if h_kept.size == kept.size and h_sines[h_kept].min() >= CLEARLY_INDEPENDENT:
        return h_kept, h_gap, h_sines
    return kept, gap, sines
