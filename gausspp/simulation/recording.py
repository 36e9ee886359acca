"""The one recording path: every :class:`~gausspp.Trajectory` is built here, from a lane's samples.

A lane hands over the states it accepted (:class:`~gausspp.simulation.samples.Samples`); the
recording evaluates the step at each sample (unstabilized: the outputs of the motion itself),
fills the trajectory's columns, audits the realizability margin between samples
(:mod:`gausspp.simulation.margins`, smooth runs) and, when the run failed, marks the trajectory
failed with what was computed (:func:`finish`).

Smooth runs (Python, scipy, compiled lanes) evaluate the run's own right-hand side; event-driven
contact runs evaluate, at each sample, the model of the phase it belongs to, and also record the
contact gaps (``Trajectory.gap``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import (
    DriftError,
    GaussppError,
    IntegrationError,
    NonFiniteError,
    RealizabilityError,
    RealizabilityWarning,
)
from ..model.model import Model
from ..model.run_scales import RunScales
from ..step.realizability import stacked_margins
from .contacts import gaps, phase_step
from .energy_audit import energy_audit
from .labels import model_labels
from .margins import SMALL_MARGIN, audit
from .residual_audit import residual_audit
from .rhs import AnyRightHandSide, GeneralRightHandSide, RightHandSide
from .samples import Samples
from .trajectory import Trajectory

#: A recorded trajectory, the failure the recording found (or ``None``), the warnings it has to give.
Recorded = tuple[Trajectory, Exception | None, list[str]]

#: ``(sample index) ↦ (step outputs, active contact rows, bilateral rows of the stepped model, its columns)``.
Evaluate = Callable[[int], tuple[dict[str, np.ndarray], tuple[int, ...], int, int]]


class Columns:
    """The per-sample outputs of a run, filled row by row."""

    def __init__(self, model: Model, n: int, general: bool, keep_S: bool = True) -> None:
        nv, m, k = model.nv, model.m, model.k
        #: whether ``S`` is kept (its margin audited): not for redundant rows, whose margin is 0 by design
        self.model, self.general, self.kept, self.keep_S = model, general, 0, keep_S
        self.a, self.u, self.reaction = np.zeros((n, nv)), np.zeros((n, m)), np.zeros((n, nv))
        self.compulsion, self.energy = np.zeros(n), np.full(n, np.nan)
        self.residual, self.g = np.zeros((n, k)), np.zeros((n, k))
        self.S = np.zeros((n, k, m) if keep_S else (n, 0, 0))
        self.contact_force = np.zeros((n, len(model.contact_row_names)))
        self.tracking_error, self.saturated = np.zeros(n), np.zeros((n, m), bool)

    def fill(self, i: int, out: dict[str, np.ndarray], active: tuple[int, ...], sub_k: int, sub_m: int) -> None:
        """Row ``i`` from the step outputs ``out`` of a model with ``sub_k`` rows and ``sub_m`` columns whose
        extra rows are the ``active`` contacts."""
        row = {name: np.asarray(out[name])[None] for name in self.names if name != "S_norm" or self.keep_S}
        if self.keep_S:
            row["S_norm"] = np.asarray(out["S_norm"]).reshape(1, sub_k, sub_m)
        self.fill_rows(i, row, active)

    @property
    def names(self) -> list[str]:
        """The step outputs the columns are filled from."""
        extra = (["energy"] if self.model.has_energy else []) + (
            ["tracking_error", "saturated"] if self.general else []
        )
        return ["a", "u", "reaction", "compulsion", "Phi", "g", "S_norm", *extra]

    def fill_rows(self, start: int, out: dict[str, np.ndarray], active: tuple[int, ...] = ()) -> None:
        """Rows ``start, start + 1, …`` from step outputs stacked along a first axis, one entry per sample
        (``S_norm``: ``(n, sub_k, sub_m)``, the extra rows and columns being the ``active`` contacts)."""
        model, n = self.model, out["a"].shape[0]
        m, k, rows = model.m, model.k, slice(start, start + n)

        def flat(name: str) -> np.ndarray:
            return out[name].reshape(n, -1)

        self.a[rows], self.reaction[rows] = flat("a"), flat("reaction")
        u = flat("u")
        self.u[rows] = u[:, :m]
        if active:
            self.contact_force[rows, list(active)] = u[:, m:]
        self.compulsion[rows] = flat("compulsion")[:, 0]
        self.residual[rows], self.g[rows] = flat("Phi")[:, :k], flat("g")[:, :k]
        if not self.keep_S:
            pass
        elif k and start == 0 and n == self.S.shape[0] and out["S_norm"].shape[1:] == (k, m):
            self.S = out["S_norm"]  # every sample at once (the smooth runs): taken as it is, not copied
        elif k:
            self.S[rows] = out["S_norm"][:, :k, :m]
        if model.has_energy:
            self.energy[rows] = flat("energy")[:, 0]
        if self.general:
            self.tracking_error[rows] = flat("tracking_error")[:, 0]
            self.saturated[rows] = flat("saturated").astype(bool)
        self.kept = start + n

    def margin(self, known: np.ndarray | None = None) -> np.ndarray:
        """The margin ``σ_min`` of each kept sample's normalized ``S``; the first ones may be ``known`` already."""
        known = np.zeros(0) if known is None else known
        if not self.keep_S:
            return np.zeros(self.kept)
        model = self.model
        rest = stacked_margins(self.S[known.size : self.kept], model.k, model.m, symmetric=model.symmetric_S or None)
        return np.concatenate([known, rest])


def record_smooth(
    model: Model, rhs: AnyRightHandSide, samples: Samples, tol: float, scales: RunScales | None = None
) -> Recorded:
    """The trajectory of a smooth run, its margin and its residuals (to ``tol``) audited; samples past a lost
    margin or the first beyond ``tol`` are dropped."""
    y = samples.y.copy()
    # adaptive lanes integrate q freely: bring the samples back onto the manifold (unit quaternions)
    y[:, : model.nq] = model.mechanism.normalize_array(y[:, : model.nq])
    solutions = samples.qp_solutions if np.array_equal(y, samples.y) else None  # replayed at the very same states
    samples = replace(samples, y=y)
    general = isinstance(rhs, GeneralRightHandSide)

    def evaluate(i: int) -> tuple[dict[str, np.ndarray], tuple[int, ...], int, int]:
        return rhs.evaluate(samples.t[i], y[i], stabilized=False), (), model.k, model.m

    cols, known = Columns(model, samples.t.size, general, keep_S=not general or rhs.margin_checked), None
    if isinstance(rhs, RightHandSide):  # the samples that pass all at once, the rest (if any) one by one
        out, margin, good = rhs.evaluate_all(samples.t, y, solutions)
        if good:
            cols.fill_rows(0, {name: out[name][:good] for name in cols.names})
            known = margin[:good]
    failure = _fill(cols, evaluate, cols.kept)
    margin = cols.margin(known)
    crossed = tuple(e["t"] for e in samples.events if e.get("kind") == "singular position")
    kept, failure, notes = audit(model, rhs, samples.t[: cols.kept], y, cols.S[: cols.kept], margin, failure, crossed)
    kept, failure = _within(model, samples.t, y, cols, tol, kept, failure, scales)
    return _trajectory(model, samples, cols, margin, kept), failure, notes


def record_job(job: Any, samples: Samples) -> Recorded:
    """The default recorder of a lane (:attr:`~gausspp.simulation.lanes.Lane.recorder`): a smooth run's samples
    (:func:`record_smooth`) with the job's step and drift tolerance."""
    return record_smooth(job.model, job.rhs, samples, job.opts.drift_tol, job.opts.scales)


def record_contacts(model: Model, samples: Samples, tol: float, scales: RunScales | None = None) -> Recorded:
    """The trajectory of an event-driven run: each sample by the model of its phase, with the contact gaps; its
    residuals audited to ``tol``."""
    assert samples.active is not None  # an event-driven run names each sample's phase
    active_of = samples.active
    nq, nv, nl = model.nq, model.nv, model.n_lam

    def evaluate(i: int) -> tuple[dict[str, np.ndarray], tuple[int, ...], int, int]:
        sub, solver, backend = phase_step(model, active_of[i], samples.solver, samples.backend)
        y = samples.y[i]
        out = sub.kernel(solver, backend)(samples.t[i], y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], np.zeros(2))
        return out, active_of[i], sub.k, sub.m

    cols = Columns(model, samples.t.size, False)
    failure = _fill(cols, evaluate, 0)
    kept, failure = _within(model, samples.t, samples.y, cols, tol, cols.kept, failure, scales)
    return _trajectory(model, samples, cols, cols.margin(), kept), failure, []


def _within(
    model: Model,
    t: np.ndarray,
    y: np.ndarray,
    cols: Columns,
    tol: float,
    kept: int,
    failure: Exception | None,
    scales: RunScales | None = None,
) -> tuple[int, Exception | None]:
    """The samples to keep and the failure once the residuals and the energy balance are audited
    (:mod:`.residual_audit`, :mod:`.energy_audit`): a departure from either explains any failure found after it."""
    n, drift = residual_audit(model, t, y, cols.g, cols.residual, tol, kept, scales)
    n_energy, energy_drift = energy_audit(model, t, y, cols.energy, tol, kept, scales)
    if energy_drift is not None and (drift is None or n_energy < n):  # the earlier departure (a row at a tie)
        n, drift = n_energy, energy_drift
    if drift is None or (failure is not None and n >= kept):
        return kept, failure
    return n, drift


def _fill(cols: Columns, evaluate: Evaluate, start: int) -> Exception | None:
    """Evaluate the samples from ``start`` on, one by one; stop at the first that fails (its error is the
    recording's failure)."""
    for i in range(start, cols.a.shape[0]):
        try:
            out, active, sub_k, sub_m = evaluate(i)
        except GaussppError as exc:
            return exc
        cols.fill(i, out, active, sub_k, sub_m)
    return None


def _trajectory(model: Model, samples: Samples, cols: Columns, margin: np.ndarray, n: int) -> Trajectory:
    """The first ``n`` samples as a trajectory (status ``"success"``: :func:`finish` marks a failure)."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    y = samples.y[:n]
    return Trajectory(
        t=samples.t[:n].copy(),
        q=y[:, :nq].copy(),
        v=y[:, nq : nq + nv].copy(),
        lam=y[:, nq + nv : nq + nv + nl].copy(),
        a=cols.a[:n],
        u=cols.u[:n],
        reaction=cols.reaction[:n],
        compulsion=cols.compulsion[:n],
        residual=cols.residual[:n],
        g=cols.g[:n],
        margin=margin[:n],
        energy=cols.energy[:n],
        work_reaction=y[:, -2].copy(),
        work_forces=y[:, -1].copy() if model.has_force_power else np.full(n, np.nan),
        status="success",
        message="",
        method=samples.method,
        solver=samples.solver,
        steps=samples.steps,
        rhs_evaluations=samples.evaluations,
        contact_force=cols.contact_force[:n],
        tracking_error=cols.tracking_error[:n],
        saturated=cols.saturated[:n],
        events=samples.events,
        gap=contact_gaps(model, samples.t[:n], y),
        labels=model_labels(model),
    )


def contact_gaps(model: Model, t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The gap ``g`` of every contact row at every sample, ``(N, n_contact_rows)``."""
    n_rows, nq, nv = len(model.contact_row_names), model.nq, model.nv
    out = np.zeros((t.size, n_rows))
    if n_rows:
        for i in range(t.size):
            out[i] = gaps(model, t[i], y[i, :nq], y[i, nq : nq + nv])[0]
    return out


def finish(recorded: Recorded, run_failure: Exception | None, throw: bool) -> Trajectory:
    """The trajectory, marked failed if the run (``run_failure``) or its recording failed; raised with the
    trajectory as ``.trajectory`` if ``throw``. A lost margin found by the recording is the cause of a later
    breakdown of the run, and is reported instead."""
    traj, record_failure, notes = recorded
    for note in notes:
        warnings.warn(note, RealizabilityWarning, stacklevel=3)
    explains = isinstance(record_failure, (RealizabilityError, DriftError))  # found at a sample before the run's
    failure = record_failure if explains else run_failure or record_failure
    if failure is None:
        return traj
    traj = failed(traj, failure)
    if throw:
        hint = traj.message.partition(" [smallest realizability margin")[2]
        if hint:  # the same pointer at a small margin as in the returned trajectory
            failure.args = (f"{failure} [smallest realizability margin{hint}",)
        failure.trajectory = traj  # type: ignore[attr-defined]
        raise failure
    return traj


def failed(traj: Trajectory, failure: Exception) -> Trajectory:
    """``traj`` marked failed with the error's type and message (and, where the run broke down near a small
    margin, where that was)."""
    message = f"{type(failure).__name__}: {failure}"
    if isinstance(failure, (NonFiniteError, IntegrationError)) and traj.margin.size:
        i = int(np.argmin(traj.margin))
        if traj.margin[i] < SMALL_MARGIN:  # a failing integration near a singular step: say so
            message += (
                f" [smallest realizability margin on the way: {traj.margin[i]:.3g} at t={traj.t[i]:.6g} — the "
                "realization may have lost the constraint there]"
            )
    return replace(traj, status="failed", message=message, failure=failure)
