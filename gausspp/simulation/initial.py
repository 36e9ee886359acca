"""The initial state of a run: checked, projected onto the constraint if asked, and on it.

Shared by the smooth lanes and the event-driven contact lane (:mod:`gausspp.simulation.events`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import GaussppError, InitialDataError, RealizabilityWarning
from ..model.model import Model
from ..model.run_scales import RunScales, row_scales, within
from ..step.bound import Bound, load_inputs
from ..workspace import workspace
from .drift import least_squares_projection_function, projection_function

#: ``(t, q, v, λ) ↦ (q', v')``: a projection onto the constraint.
Projection = Callable[[float, np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]

#: What to do about initial data off the constraint (contact runs cannot project: they say only the first part).
PROJECT_HINT = (
    "correct q0/v0, or pass stabilize='project' to project them onto the constraint along the realization's directions"
)


def initial_state(model: Model, t0: float, q0: Any, v0: Any, lam0: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, v, λ)`` checked for shape and finiteness (``λ`` defaults to the realizations' ``lam0``)."""
    _t, q, v, lam = model.checked_state(t0, q0, v0, lam0)
    return q, v, lam


def redundant_rows(
    model: Model, solver: str, backend: str | None, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray
) -> bool:
    """Whether the bilateral rows are dependent at the start, so that the run needs the general QP (which
    returns the least-norm multiplier) and the realizability margin, 0 by design, says nothing."""
    try:
        if model.bounded:  # the general QP's own rank test
            return model.k > 0 and model.general_step(t, q, v, lam)[1].redundant_rows > 0
        if solver != "qp":
            return False
        with warnings.catch_warnings():  # the compiled QP hands exactly redundant rows to the general QP
            warnings.simplefilter("ignore", RealizabilityWarning)
            return model.step(t, q, v, lam, solver=solver, backend=backend).solver.startswith("gauss-qp:")
    except GaussppError:
        return False  # the run itself reports the error, with its trajectory


def projection(model: Model, redundant: bool = False) -> Projection:
    """The projection onto the constraints along ``A⁻¹D``: compiled (kept in the model's workspace); for redundant
    rows, where its square solves are singular, the compiled least-norm Newton
    (:func:`~gausspp.simulation.drift.least_squares_projection_function`), and the model's careful one
    (:meth:`Model.nearest_on_manifold`: the clearly independent rows first) where that one does not bring the
    residuals down by :data:`LS_CONVERGED`."""
    if redundant:
        return _least_squares_projection(model)
    fn = workspace(model).get(("projection",), lambda: projection_function(model))

    def project(t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q1, v1 = fn(t, q, v, lam)
        return np.array(q1).ravel(), np.array(v1).ravel()

    return project


#: A least-norm projection whose residuals end below this fraction of where they started has converged (Newton's
#: steps from a drift the default control acts on reach round-off: many orders below).
LS_CONVERGED = 1e-3


def _least_squares_projection(model: Model) -> Projection:
    build = lambda: Bound(least_squares_projection_function(model))  # noqa: E731
    bound = workspace(model).get(("projection", "least squares"), build)
    nq, nv = model.nq, model.nv

    def project(t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        load_inputs(bound.args, (t, q, v, lam))
        bound.eval()
        q1, v1, g1, phi1 = (r.copy() for r in bound.res)
        before = residuals(model, t, q, v, lam)
        start = max(float(np.abs(before[0]).max(initial=0.0)), float(np.abs(before[1]).max(initial=0.0)))
        end = max(float(np.abs(g1[model.holonomic_rows]).max(initial=0.0)), float(np.abs(phi1).max(initial=0.0)))
        if np.all(np.isfinite(q1)) and np.all(np.isfinite(v1)) and end <= LS_CONVERGED * start:
            return q1[:nq], v1[:nv]
        return model.nearest_on_manifold(t, q, v, lam)

    return project


def residuals(model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(g(q, t), Φ(q, v, t))`` of the bilateral rows."""
    data = model.evaluate_data(t, q, v, lam)
    return data.g, data.Phi


def project_initial(
    model: Model,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    tol: float,
    redundant: bool = False,
    max_steps: int = 50,
) -> tuple[np.ndarray, np.ndarray]:
    """Newton steps of the projection until ``g`` and ``Φ`` are within ``tol/1000`` (or fail clearly)."""
    project = projection(model, redundant)
    start, first_move = q.copy(), None
    for _ in range(max_steps):
        g, Phi = residuals(model, t, q, v, lam)
        size = float(np.max(np.abs(np.concatenate([g, Phi]))))
        if size <= tol * 1e-3:
            moved = float(np.max(np.abs(q - start)))
            if first_move is not None and moved > 10 * first_move + 1e-12:
                raise InitialDataError(
                    f"projecting the initial data onto the constraints ended far from them at t={t:.6g} (q moved by "
                    f"{moved:.3g}, the first Newton step by {first_move:.3g}): Newton found a distant root; start "
                    "closer to the constraint"
                )
            return q, v
        q_prev = q
        q, v = project(t, q, v, lam)
        if first_move is None:
            first_move = float(np.max(np.abs(q - q_prev))) if np.all(np.isfinite(q)) else np.inf
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            raise InitialDataError(
                f"projecting the initial data onto the constraints failed at t={t:.6g} (NaN): the constraint rows are "
                "dependent (redundant constraints) or the realization cannot move the state there; give q0/v0 on "
                "the constraint"
            )
    raise InitialDataError(
        f"projecting the initial data onto the constraints did not converge in {max_steps} Newton steps "
        f"(|g|, |Φ| still {size:.3g} at t={t:.6g}); start closer to the constraint"
    )


def check_on_constraint(
    model: Model,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    tol: float,
    hint: str = PROJECT_HINT,
    scales: RunScales | None = None,
) -> None:
    """Refuse initial data off a bilateral row by more than ``tol`` of the row's own scale
    (:func:`~gausspp.model.run_scales.row_scales`; of 1 without ``scales``), naming the row."""
    g, Phi = residuals(model, t, q, v, lam)
    if scales is None or model.k == 0:
        s_g, s_Phi, f_g, f_Phi = np.ones_like(g), np.ones_like(Phi), np.zeros_like(g), np.zeros_like(Phi)
    else:
        y = np.concatenate([q, v, lam])[None, :]
        s_g, s_Phi, f_g, f_Phi = (s[0] for s in row_scales(model, scales, np.array([t]), y, 1))
    for values, size, floor, what in ((g, s_g, f_g, "g(q, t)"), (Phi, s_Phi, f_Phi, "Φ(q, v, t)")):
        off = within(values, size, floor, tol)
        bad = np.flatnonzero(~(off <= 1.0))  # NaN counts as off
        if bad.size:
            worst = int(bad[np.argmax(np.nan_to_num(off[bad], nan=np.inf))])
            scale = "" if scales is None else f" of the row's scale {size[worst]:.3g}"
            raise InitialDataError(
                f"initial data are off the constraint {model.row_names[worst]!r} at t={t:.6g}: {what} = "
                f"{values[worst]:.3g} (tolerance {tol:g}{scale}); {hint}"
            )
