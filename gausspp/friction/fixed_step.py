"""Fixed-step frictional phases: compiled RK4 chunks, and each event located exactly inside its step.

Each phase runs its compiled graph (:class:`.phase_graph.PhaseGraph`) :data:`.phase_graph.CHUNK` steps of
length ``h`` per call, no Python between the steps. After a chunk the events' values are read at every step's
end; the first step where one falls through zero is taken again from its start with the length ``h* ∈ [0, h]``
at which that value is zero (Brent's method on the compiled step), so the event's time and state are those of
an RK4 step, not of the grid. The modes are then chosen anew (:meth:`.runner.Runner.modes_at`) and the next phase
starts there. A motion that is polynomial of degree ≤ 4 within its phases (a box sliding to rest, a ball
sliding until it rolls) is integrated exactly, events included.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import brentq

from ..errors import IntegrationError, NonFiniteError
from .modes import SLIDE, Modes, check_painleve
from .phase_graph import CHUNK, PhaseGraph, kept_rows, rows_function
from .run import Record

#: A step whose rate changes by more than this (relative to the state's size, ``PhaseGraph.step``'s ``jump``) is too
#: long for its phase: the run stops with an IntegrationError instead of stepping past what it cannot resolve.
MAX_JUMP = 0.1


class Phases:
    """The compiled phases of one mechanism and its contacts, built on first use and kept (by modes and rows)."""

    def __init__(self, runner: Any) -> None:
        self.runner = runner
        self.rows: dict[tuple[str, ...], Any] = {}
        self.graphs: dict[tuple[tuple[str, ...], tuple[int, ...]], PhaseGraph] = {}

    def at(self, modes: Modes, q: np.ndarray, v: np.ndarray) -> tuple[PhaseGraph, np.ndarray]:
        """The graph of ``modes`` at ``(q, v)`` (its kept rows chosen there) and its directions' vector ``d``."""
        r = self.runner
        kinds = modes.kinds
        d = np.zeros(int(sum(r.kin.dims)))
        for i, kind in enumerate(kinds):
            if kind == SLIDE:
                d[r.kin.offsets[i] : r.kin.offsets[i + 1]] = modes.dirs[i]
        if kinds not in self.rows:
            self.rows[kinds] = rows_function(r.kin, r.contacts, kinds)
        kept = kept_rows(self.rows[kinds](q, v, d).full())
        key = (kinds, kept)
        if key not in self.graphs:
            self.graphs[key] = PhaseGraph(r.kin, r.contacts, kinds, kept, normalize=r.mech.normalize)
        return self.graphs[key], d


def falls(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Where an event's value falls through zero between two samples (as scipy's ``direction = −1`` events)."""
    return ((before >= 0) & (after < 0)) | ((before > 0) & (after <= 0))


def run_phase(
    phases: Phases,
    modes: Modes,
    t: float,
    y: np.ndarray,
    *,
    t_end: float,
    h: float,
    times: np.ndarray | None,
    record: Record,
    codegen: bool = False,
) -> tuple[float, np.ndarray, list[tuple[str, int]]]:
    """Step the phase of ``modes`` from ``(t, y)`` until an event or ``t_end``; record its samples (every step, or
    the ``times`` inside it, and the phase's start and end); ``codegen``: the chunks as C where a compiler is.
    Returns the end's time, state and the events fired."""
    runner = phases.runner
    nq = runner.nq
    q, v = y[:nq], y[nq:]
    check_painleve(runner.kin(q, v), runner.contacts, modes, t)
    graph, d = phases.at(modes, q, v)
    step, chunk = graph.compiled() if codegen else (graph.step, graph.chunk)
    names = modes.names()
    samples = _Samples(graph, step, d, names, times, t_end, record)
    keep, sample = samples.keep, samples.sample
    out0 = graph.report(q, v, d).full()
    keep(np.array([t]), y[:, None], out0)
    before = graph.split(out0)[3].ravel()
    while True:
        ts, lengths, Y, out, jump = _advance(step, chunk, y, d, t, t_end, h)
        bad = ~graph.usable(Y, out) | ~(jump[0] <= MAX_JUMP)
        values = graph.split(out)[3]
        fire = falls(np.column_stack([before, values[:, :-1]]), values).any(axis=0)
        first = int(np.argmax(fire)) if fire.any() else ts.size
        if bad[:first].any():
            j = int(np.argmax(bad))
            samples.steps(np.concatenate([[t], ts[:-1]])[:j], ts[:j], y, Y, out)  # what the run asked to keep
            _refuse(runner, ts[j], h, names, Y[:, j], usable=bool(graph.usable(Y, out)[j]))
        starts = np.concatenate([[t], ts[:-1]])
        samples.steps(starts[:first], ts[:first], y, Y, out)
        if first == ts.size:
            t, y, before = float(ts[-1]), Y[:, -1].copy(), values[:, -1]
            if t >= t_end:
                return t, y, []
            continue
        t0, y0 = float(starts[first]), (Y[:, first - 1] if first else y).copy()
        start_values = before if first == 0 else values[:, first - 1]
        h_star, fired = _first_event(step, graph, d, y0, float(lengths[first]), start_values, values[:, first])
        if t0 + h_star > t_end + 4 * np.finfo(float).eps * abs(t_end):  # past t_end (a last step within round-off
            h_star, fired = t_end - t0, []  # of it, labelled t_end): the run ends there, no event
        sample(t0, y0, t0 + h_star)
        y1, out1, jump1 = step(y0, d, h_star)
        y_star = y1.full().ravel()
        if not (graph.usable(y_star[:, None], out1.full())[0] and float(jump1) <= MAX_JUMP):
            _refuse(runner, t0 + h_star, h, names, y_star, usable=bool(graph.usable(y_star[:, None], out1.full())[0]))
        t_star = t_end if not fired else min(t0 + h_star, t_end)
        keep(np.array([t_star]), y_star[:, None], out1.full())
        return t_star, y_star, fired


class _Samples:
    """What a phase records: every step, or only the requested ``times`` (by partial steps) and its ends."""

    def __init__(
        self, graph: PhaseGraph, step: Any, d: np.ndarray, names: tuple, times: Any, t_end: float, record: Record
    ) -> None:
        self.graph, self.step, self.d, self.names = graph, step, d, names
        self.times, self.t_end, self.record = times, t_end, record

    def keep(self, ts: np.ndarray, Y: np.ndarray, out: np.ndarray) -> None:
        """Record the states ``Y`` (one column per time) and their outputs."""
        N, F, energy, _ = self.graph.split(out)
        self.record.add(ts, Y.T, self.names, N.T, F.T, energy)

    def sample(self, t0: float, y0: np.ndarray, upto: float) -> None:
        """Record the requested times in ``(t0, upto)`` by a partial step from ``(t0, y0)``."""
        if self.times is None:
            return
        for tau in self.times[(self.times > t0) & (self.times < upto)]:
            y1, out1, _ = self.step(y0, self.d, tau - t0)
            self.keep(np.array([tau]), y1.full(), out1.full())

    def steps(self, starts: np.ndarray, ends: np.ndarray, y: np.ndarray, Y: np.ndarray, out: np.ndarray) -> None:
        """Record the steps ``starts[k] → ends[k]`` (``y`` the state at ``starts[0]``, ``Y`` at each end)."""
        if self.times is None:
            self.keep(ends, Y[:, : ends.size], out[:, : ends.size])
            return
        for k in range(ends.size):
            self.sample(starts[k], Y[:, k - 1] if k else y, ends[k])
            if ends[k] in self.times or ends[k] == self.t_end:
                self.keep(ends[k : k + 1], Y[:, k : k + 1], out[:, k : k + 1])


def _advance(
    step: Any, chunk: Any, y: np.ndarray, d: np.ndarray, t: float, t_end: float, h: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The next steps from ``(t, y)``: a chunk of steps of ``h`` (as many as fit before ``t_end``; a last one within
    round-off of ``t_end`` is labelled ``t_end``), or the last, shorter one; their end times, lengths, states,
    outputs and jumps (one column per step)."""
    n_full = int(np.floor((t_end - t) / h * (1.0 + 1e-12)))
    if n_full < 1:
        y1, out1, jump1 = step(y, d, t_end - t)
        return np.array([t_end]), np.array([t_end - t]), y1.full(), out1.full(), jump1.full()
    m = min(CHUNK, n_full)
    Y, out, jump = (x.full()[:, :m] for x in chunk(y, d, h))
    ts = t + h * np.arange(1, m + 1)
    if m == n_full and t_end - ts[-1] <= 1e-12 * (1.0 + abs(t_end)):
        ts[-1] = t_end
    return ts, np.full(m, h), Y, out, jump


def _first_event(
    step: Any, graph: PhaseGraph, d: np.ndarray, y0: np.ndarray, h_step: float, before: np.ndarray, after: np.ndarray
) -> tuple[float, list[tuple[str, int]]]:
    """Inside the step of ``h_step`` from ``y0`` where the events' values go from ``before`` to ``after``: the length
    ``h*`` at which the first of those that fall reaches zero, and every event that falls there."""

    def value(hh: float, k: int) -> float:
        return float(step(y0, d, hh)[1].full()[-len(graph.events) + k, 0])

    hit = np.flatnonzero(falls(before, after))
    roots = {int(k): _root(lambda hh, k=k: value(hh, k), h_step) for k in hit}
    h_star = min(roots.values())
    together = 1e-9 * h_step  # roots this close are one instant (symmetric corners), whatever the step's length
    return h_star, [graph.events[k] for k, r in roots.items() if r <= h_star + together]


def _refuse(runner: Any, t: float, h: float, names: tuple[str, ...], y: np.ndarray, *, usable: bool) -> None:
    """Stop the run at the step ending at ``t`` in ``y``: what the contact state's own checks refuse there (a mass
    matrix not positive definite, a quantity not finite), other non-finite numbers, or — its numbers ``usable`` — a
    step too long for its phase."""
    if np.isfinite(y).all():
        runner.kin.checked(y[: runner.nq], y[runner.nq :], t, runner.names)
    if not usable:
        raise NonFiniteError(
            f"the state or the contact forces became non-finite at t={t:.6g} (modes {names}); check the mechanism's "
            "formulas there, or take a shorter step"
        )
    raise IntegrationError(
        f"the step h={h:g} is too long for the phase at t={t:.6g} (modes {names}): its rate changes by more than "
        f"{MAX_JUMP:g} of the state's size within one step (a stiff contact force, or a fast event); take a shorter "
        "step, or step=None (adaptive)"
    )


def _root(f: Any, h: float) -> float:
    """The first zero of ``f`` on ``[0, h]`` where ``f(0) ≥ 0 > f(h)`` (or ``f(0) > 0 ≥ f(h)``)."""
    if f(0.0) <= 0.0:
        return 0.0
    if f(h) >= 0.0:  # the end value that showed the fall, evaluated again, does not: the zero is at the end
        return h
    return float(brentq(f, 0.0, h, xtol=1e-16, rtol=4 * np.finfo(float).eps, maxiter=200))
