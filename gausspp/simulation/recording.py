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

import numpy as np

from ..errors import GaussppError, IntegrationError, NonFiniteError, RealizabilityError, RealizabilityWarning
from ..model.model import Model
from .contacts import gaps, phase_step
from .margins import SMALL_MARGIN, audit
from .rhs import AnyRightHandSide, GeneralRightHandSide
from .samples import Samples
from .trajectory import Trajectory

#: A recorded trajectory, the failure the recording found (or ``None``), the warnings it has to give.
Recorded = tuple[Trajectory, Exception | None, list[str]]

#: ``(sample index) ↦ (step outputs, active contact rows, bilateral rows of the stepped model, its columns)``.
Evaluate = Callable[[int], tuple[dict[str, np.ndarray], tuple[int, ...], int, int]]


class Columns:
    """The per-sample outputs of a run, filled row by row."""

    def __init__(self, model: Model, n: int, general: bool) -> None:
        nv, m, k = model.nv, model.m, model.k
        self.model, self.general, self.kept = model, general, 0
        self.a, self.u, self.reaction = np.zeros((n, nv)), np.zeros((n, m)), np.zeros((n, nv))
        self.compulsion, self.energy = np.zeros(n), np.full(n, np.nan)
        self.residual, self.g, self.S = np.zeros((n, k)), np.zeros((n, k)), np.zeros((n, k, m))
        self.contact_force = np.zeros((n, len(model.contact_row_names)))
        self.tracking_error, self.saturated = np.zeros(n), np.zeros((n, m), bool)

    def fill(self, i: int, out: dict[str, np.ndarray], active: tuple[int, ...], sub_k: int, sub_m: int) -> None:
        """Row ``i`` from the step outputs ``out`` of a model with ``sub_k`` rows and ``sub_m`` columns whose
        extra rows are the ``active`` contacts."""
        model = self.model
        m, k = model.m, model.k
        self.a[i] = out["a"].ravel()
        u = out["u"].ravel()
        self.u[i] = u[:m]
        if active:
            self.contact_force[i, list(active)] = u[m:]
        self.reaction[i] = out["reaction"].ravel()
        self.compulsion[i] = float(out["compulsion"][0])
        self.residual[i] = out["Phi"].ravel()[:k]
        self.g[i] = out["g"].ravel()[:k]
        if k:
            self.S[i] = np.asarray(out["S_norm"]).reshape(sub_k, sub_m)[:k, :m]
        if model.has_energy:
            self.energy[i] = float(out["energy"][0])
        if self.general:
            self.tracking_error[i] = float(out["tracking_error"][0])
            self.saturated[i] = np.asarray(out["saturated"], bool).ravel()
        self.kept = i + 1

    def margin(self) -> np.ndarray:
        """``σ_min`` of each sample's normalized ``S`` (1 without bilateral rows, 0 with more rows than columns)."""
        n, k, m = self.kept, self.model.k, self.model.m
        if k == 0:
            return np.ones(n)
        if m < k or n == 0:
            return np.zeros(n)
        return np.linalg.svd(self.S[:n], compute_uv=False).min(axis=1)


def record_smooth(model: Model, rhs: AnyRightHandSide, samples: Samples) -> Recorded:
    """The trajectory of a smooth run, its margin audited; samples past a lost margin are dropped."""
    y = samples.y.copy()
    nq, normalize = model.nq, model.mechanism.normalize_array
    for row in y:  # adaptive lanes integrate q freely: bring samples back onto the manifold (unit quaternions)
        row[:nq] = normalize(row[:nq])
    samples = replace(samples, y=y)
    general = isinstance(rhs, GeneralRightHandSide)

    def evaluate(i: int) -> tuple[dict[str, np.ndarray], tuple[int, ...], int, int]:
        return rhs.evaluate(samples.t[i], y[i], stabilized=False), (), model.k, model.m

    cols, failure = _columns(model, samples, evaluate, general)
    margin = cols.margin()
    kept, failure, notes = audit(model, rhs, samples.t[: cols.kept], y, cols.S[: cols.kept], margin, failure)
    return _trajectory(model, samples, cols, margin, kept), failure, notes


def record_contacts(model: Model, samples: Samples) -> Recorded:
    """The trajectory of an event-driven run: each sample by the model of its phase, with the contact gaps."""
    assert samples.active is not None  # an event-driven run names each sample's phase
    active_of = samples.active
    nq, nv, nl = model.nq, model.nv, model.n_lam

    def evaluate(i: int) -> tuple[dict[str, np.ndarray], tuple[int, ...], int, int]:
        sub, solver, backend = phase_step(model, active_of[i], samples.solver, samples.backend)
        y = samples.y[i]
        out = sub.kernel(solver, backend)(samples.t[i], y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], np.zeros(2))
        return out, active_of[i], sub.k, sub.m

    cols, failure = _columns(model, samples, evaluate, False)
    return _trajectory(model, samples, cols, cols.margin(), cols.kept), failure, []


def _columns(model: Model, samples: Samples, evaluate: Evaluate, general: bool) -> tuple[Columns, Exception | None]:
    """Evaluate every sample; stop at the first that fails (its error is the recording's failure)."""
    cols = Columns(model, samples.t.size, general)
    for i in range(samples.t.size):
        try:
            out, active, sub_k, sub_m = evaluate(i)
        except GaussppError as exc:
            return cols, exc
        cols.fill(i, out, active, sub_k, sub_m)
    return cols, None


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
    failure = record_failure if isinstance(record_failure, RealizabilityError) else run_failure or record_failure
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
    return replace(traj, status="failed", message=message)
