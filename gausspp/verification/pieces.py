"""Verification in smooth pieces: contacts between their events, bounded servos by saturation.

Inequality (23) speaks of one smooth path and one law of motion. A trajectory of a model with
unilateral contacts or bounded actuators follows different laws on different intervals, so
:func:`gausspp.verify` splits it and verifies each piece by the law that held there:

* **contacts** (event-driven runs, :mod:`gausspp.simulation.contacts`): the path is cut at every event — an
  impact (two samples at one time, before and after the velocity jump), a touch, a lift-off. On
  a piece the contacts that stay closed (``|g|`` and ``|ġ|`` within ``constraint_tol`` at every
  sample) act as ideal bilateral constraints ``g = 0`` and the others are absent: the piece must
  be a motion of that model, the multipliers (23) recovers for the closed contacts must be
  pushing forces (``λ ≥ 0``), and no open contact may be penetrated. No piece is integrated
  across a velocity jump; each jump is checked instead against the model's impact law
  (:meth:`Model.impact`: Gauss's principle at the velocity level with Newton's restitution).
* **bounded servos** (:class:`~gausspp.Force` with ``bounds``): the path is cut where the set of
  saturated actuators changes (``Trajectory.saturated``). Unsaturated pieces follow the servo law
  itself. On a saturated piece the actuators push at their bounds, so their reaction
  ``D u_bound`` is a known force: the piece must be the motion of the model *without* the
  bounded constraints under that extra force (every admissible variation is free for them).
  After a saturation the servo is off its constraint and returns to it by drift feedback (the
  scene's Baumgarte terms): that is not a law (23) states — those samples are skipped with the
  reason until the path is back on the constraint to ``constraint_tol``. A piece where only some
  actuators of bounded servos saturate (the allocation is then decided by the tracking stage of
  :mod:`gausspp.step.general`) is skipped too, with its reason.

Pieces with fewer than :data:`MIN_SAMPLES` samples are skipped (the path's acceleration comes from
a quintic spline, and the verdict compares the gap with that on every other node). The result is
one :class:`~gausspp.verification.integral.Verification`: ``is_motion`` holds iff at least one piece was verified
and every verified piece, every contact force and every jump passed; its ``relative_gap`` and
``tolerance`` are those of the worst piece (largest ratio), its ``gap`` and ``value_at_zero`` the
time averages over the verified pieces; ``pieces``, ``skipped`` and ``message`` say the rest.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from ..model.derived import gaps as contact_gaps
from ..model.derived import phase_model, sub_model
from ..model.model import Model
from . import integral
from .integral import Verification

#: Fewest samples a piece needs to be verified (a quintic spline, and ≥ 5 nodes on every other one).
MIN_SAMPLES = 9
#: A closed contact's recovered multiplier below −this × the piece's largest multiplier is a pull.
PULL_TOL = 1e-4
#: Largest relative difference between a recorded velocity jump and the model's impact law.
JUMP_TOL = 1e-6


@dataclass(frozen=True)
class Piece:
    """Samples ``start:stop`` of the path and the law that held there.

    ``model`` is the model of the piece, ``columns`` the columns of the combined multiplier table
    its constraint rows fill, ``known`` (N, nv) a known reaction along the samples (saturated
    actuators), ``contacts`` the columns that are unilateral (must push), ``skip`` the reason the
    piece is not verified (empty if it is).
    """

    start: int
    stop: int
    model: Model
    label: str
    columns: tuple[int, ...] = ()
    known: np.ndarray | None = None
    contacts: tuple[int, ...] = ()
    skip: str = ""


@dataclass(frozen=True)
class Path:
    """The samples of a trajectory (checked by :func:`~gausspp.verification.integral.path_samples`), its records."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray | None
    lam: np.ndarray | None
    u: np.ndarray | None
    saturated: np.ndarray | None
    events: tuple[dict[str, Any], ...]


def read(model: Model, trajectory: Any) -> Path:
    """The path's arrays, checked for shape and finiteness as :func:`integral.discretize` does."""
    t, q, v, a = integral.path_samples(trajectory)
    if q.shape != (t.size, model.nq) or v.shape != (t.size, model.nv):
        raise ShapeError(
            f"trajectory: q and v must be ({t.size}, {model.nq}) and ({t.size}, {model.nv}), got {q.shape}, {v.shape}"
        )

    def field(name: str, cols: int) -> np.ndarray | None:
        x = trajectory.get(name) if isinstance(trajectory, dict) else getattr(trajectory, name, None)
        x = None if x is None else np.asarray(x)
        return x if x is not None and x.shape == (t.size, cols) else None

    events = trajectory.get("events", ()) if isinstance(trajectory, dict) else getattr(trajectory, "events", ())
    return Path(t, q, v, a, field("lam", model.n_lam), field("u", model.m), field("saturated", model.m), tuple(events))


# -- cutting ----------------------------------------------------------------------------------------
def cuts(path: Path) -> list[tuple[int, int]]:
    """Where pieces end and the next begin: ``(last sample of one, first of the next)``.

    A velocity jump is two samples at one time (no overlap); a touch or lift-off one sample shared
    by both pieces; a change of the saturated actuators lies between two samples.
    """
    t = path.t
    out = {(i - 1, i) for i in range(1, t.size) if t[i] <= t[i - 1]}
    tol = 1e-12 * max(1.0, float(np.abs(t).max(initial=0.0)))
    for event in path.events:
        at = np.flatnonzero(np.abs(t - float(event.get("t", np.nan))) <= tol)
        if at.size == 1 and 0 < at[0] < t.size - 1:
            out.add((int(at[0]), int(at[0])))
    if path.saturated is not None:
        changes = np.flatnonzero(np.any(path.saturated[1:] != path.saturated[:-1], axis=1)) + 1
        out |= {(int(i) - 1, int(i)) for i in changes}
    return sorted(out)


def spans(n: int, where: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Sample ranges ``[start, stop)`` between the cuts."""
    out, start = [], 0
    for end, nxt in where:
        if end + 1 > start:
            out.append((start, end + 1))
        start = max(start, nxt)
    out.append((start, n))
    return out


# -- the law on each piece --------------------------------------------------------------------------
def contact_pieces(model: Model, path: Path, ranges: list[tuple[int, int]], tol: float) -> list[Piece]:
    """Each range with the contacts that stay closed on it as ideal bilateral constraints."""
    gaps = np.array(
        [np.concatenate(contact_gaps(model, t, q, v)) for t, q, v in zip(path.t, path.q, path.v, strict=True)]
    )
    nc = len(model.contact_row_names)
    g, gdot = gaps[:, :nc], gaps[:, nc:]
    pieces = []
    for start, stop in ranges:
        on = np.all(np.abs(g[start:stop]) <= tol, axis=0) & np.all(np.abs(gdot[start:stop]) <= tol, axis=0)
        active = tuple(int(i) for i in np.flatnonzero(on))
        deep = np.flatnonzero(np.any(g[start:stop] < -tol, axis=0))
        names = [model.contact_row_names[i] for i in active]
        label = f"contacts closed: {', '.join(names)}" if names else "no contact closed"
        skip = ""
        if deep.size:
            i = int(deep[0])
            j = start + int(np.argmin(g[start:stop, i]))
            skip = f"penetrates contact {model.contact_row_names[i]!r} at t={path.t[j]:.6g} (g = {g[j, i]:.3g})"
        pieces.append(
            Piece(
                start,
                stop,
                phase_model(model, active),
                label,
                columns=(*range(model.k), *(model.k + i for i in active)),
                contacts=tuple(model.k + i for i in active),
                skip=skip,
            )
        )
    return pieces


def servo_pieces(model: Model, path: Path, ranges: list[tuple[int, int]], tol: float) -> list[Piece]:
    """Unsaturated ranges with the model (split where the path is back on the constraint after a
    saturation); saturated ones with the bounded constraints' reaction at the bounds as a known force."""
    if path.saturated is None or path.u is None:
        raise InputError(
            "the model has bounded actuators: verifying its trajectory needs the recorded u and saturated "
            f"(arrays of shape ({path.t.size}, {model.m})), as gp.simulate returns them"
        )
    bounded = [i for i, b in enumerate(model.group_bounds) if b is not None]
    cols = np.concatenate([np.arange(model.m)[model.groups[i].cols] for i in bounded]).astype(int)
    off = _off_constraint(model, path, tol)
    pieces: list[Piece] = []
    after_saturation = False
    for start, stop in ranges:
        sat = path.saturated[start]
        if not sat.any():
            pieces += _unsaturated(model, path, start, stop, off if after_saturation else None)
        elif not sat[cols].all():
            pieces.append(Piece(start, stop, model, "partly saturated", skip=_PARTIAL))
        else:
            pieces.append(_saturated(model, path, start, stop, bounded, cols))
        after_saturation = after_saturation or bool(sat.any())
    return pieces


_PARTIAL = (
    "only some actuators of the bounded servos are at their bounds: the tracking stage then allocates the "
    "rest (gausspp.step.general), a law (23) does not state; not verified"
)


def _off_constraint(model: Model, path: Path, tol: float) -> np.ndarray:
    """Per sample: is the path off the model's constraint (``|Φ|`` or ``|g|`` above ``tol``)?"""
    fn = integral.data_function(model)
    out = fn.map(path.t.size)(path.t[None, :], path.q.T, path.v.T, np.zeros((model.nv, path.t.size)))
    Phi, g = (np.abs(np.array(x)).reshape(model.k, path.t.size) for x in out[4:6])
    worst: np.ndarray = np.maximum(Phi.max(axis=0, initial=0.0), g.max(axis=0, initial=0.0))
    return worst > tol


def _unsaturated(model: Model, path: Path, start: int, stop: int, off: np.ndarray | None) -> list[Piece]:
    """The servo law; after a saturation, the samples before the path is back on its constraint are skipped."""
    columns = tuple(range(model.k))
    if off is None or not off[start]:
        return [Piece(start, stop, model, "servo law (unsaturated)", columns=columns)]
    back = start + int(np.argmin(off[start:stop])) if not off[start:stop].all() else stop
    reason = (
        "off the constraint after a saturation: the servo returns to it by drift feedback (Baumgarte), "
        "a law (23) does not state; not verified"
    )
    out = [Piece(start, back, model, "returning to the constraint", skip=reason)]
    if back < stop:
        out.append(Piece(back, stop, model, "servo law (unsaturated, back on the constraint)", columns=columns))
    return out


def _saturated(model: Model, path: Path, start: int, stop: int, bounded: list[int], cols: np.ndarray) -> Piece:
    """The model without its bounded constraints, their actuators' reaction at the bounds a known force."""
    assert path.u is not None
    lo = np.concatenate([model.group_bounds[i][0] for i in bounded])  # type: ignore[index]
    hi = np.concatenate([model.group_bounds[i][1] for i in bounded])  # type: ignore[index]
    u = path.u[start:stop][:, cols]
    at = np.where(np.abs(u - hi) <= np.abs(u - lo), hi, lo)
    known = np.array(
        [
            model.step_data(t, q, v, None if path.lam is None else path.lam[start + j]).D[:, cols] @ at[j]
            for j, (t, q, v) in enumerate(zip(path.t[start:stop], path.q[start:stop], path.v[start:stop], strict=True))
        ]
    )
    free = [i for i in range(len(model.constraints)) if i not in bounded]
    rows = tuple(int(r) for i in free for r in range(model.k)[model.groups[i].rows])
    return Piece(start, stop, sub_model(model, tuple(free)), "saturated: actuators at their bounds", rows, known)


# -- verifying ---------------------------------------------------------------------------------------
def verify_pieces(
    model: Model,
    trajectory: Any,
    *,
    window: tuple[float, float] | None,
    metric: Any,
    method: str,
    acceleration: str,
    constraint_tol: float,
) -> Verification:
    """Cut the path, verify each piece by its law, check contact forces and jumps, and combine."""
    path = read(model, trajectory)
    integral.check_samples(path.t, path.q, path.v, monotone=False)
    ranges = _clip(path.t, spans(path.t.size, cuts(path)), window)
    if model.contacts:
        pieces = contact_pieces(model, path, ranges, constraint_tol)
    elif model.bounded:
        pieces = servo_pieces(model, path, ranges, constraint_tol)
    else:
        pieces = [Piece(a, b, model, "one smooth path", columns=tuple(range(model.k))) for a, b in ranges]
    done: list[tuple[Piece, Verification]] = []
    skipped: list[dict[str, Any]] = []
    for piece in pieces:
        reason = piece.skip or _too_short(piece)
        when = (float(path.t[piece.start]), float(path.t[piece.stop - 1]))
        if reason:
            skipped.append({"t": when, "what": piece.label, "reason": reason})
            continue
        done.append((piece, _verify_piece(piece, path, metric, method, acceleration, constraint_tol)))
    if not done:
        raise InputError(
            "nothing to verify: no piece of the trajectory could be checked by (23) — "
            + "; ".join(f"[{s['t'][0]:.6g}, {s['t'][1]:.6g}] {s['what']}: {s['reason']}" for s in skipped)
        )
    problems = [p for piece, ver in done if (p := _pull(model, piece, ver))]
    notes = []
    if getattr(trajectory, "status", "success") != "success":
        notes.append(
            f"the run failed ({getattr(trajectory, 'message', '')}): verified what it computed, up to "
            f"t={path.t[-1]:.6g}"
        )
    if model.contacts and window is None:
        checked, wrong = _jumps(model, path)
        problems += wrong
        if checked:
            notes.append(f"{checked} velocity jump(s) checked against the impact law (Model.impact)")
    return combine(model, done, skipped, problems, notes)


def _clip(t: np.ndarray, ranges: list[tuple[int, int]], window: tuple[float, float] | None) -> list[tuple[int, int]]:
    if window is None:
        return ranges
    t1, t2 = float(window[0]), float(window[1])
    if not (t[0] <= t1 < t2 <= t[-1]):
        raise InputError(f"window ({t1:g}, {t2:g}) is outside the data [{t[0]:g}, {t[-1]:g}] or empty")
    inside = [
        (a + int(np.searchsorted(t[a:b], t1)), a + int(np.searchsorted(t[a:b], t2, side="right"))) for a, b in ranges
    ]
    return [(a, b) for a, b in inside if b > a]


def _too_short(piece: Piece) -> str:
    n = piece.stop - piece.start
    if n >= MIN_SAMPLES:
        return ""
    return f"{n} samples; a piece needs at least {MIN_SAMPLES}{_SHORT}"


_SHORT = " (record more densely, e.g. a smaller dt)"


def _verify_piece(
    piece: Piece, path: Path, metric: Any, method: str, acceleration: str, constraint_tol: float
) -> Verification:
    s = slice(piece.start, piece.stop)
    data = {"t": path.t[s], "q": path.q[s], "v": path.v[s], "a": None if path.a is None else path.a[s]}
    d = integral.discretize(piece.model, data, metric=metric, acceleration=acceleration, constraint_tol=constraint_tol)
    if piece.known is not None:  # a known reaction is an applied force: R = A ẍ − f − D u_bound
        known = piece.known[np.searchsorted(path.t[s], d.t)]
        d = replace(d, R=d.R - known, f=None if d.f is None else d.f + known)
    ver = integral.judge(d, method)
    return replace(ver, message=f"[{d.t[0]:.6g}, {d.t[-1]:.6g}] {piece.label}: {integral.verdict(ver)}")


def _pull(model: Model, piece: Piece, ver: Verification) -> str:
    """A closed contact must push: its multiplier recovered by (23) may not be clearly negative."""
    if not piece.contacts:
        return ""
    lam = ver.multipliers
    scale = float(np.nanmax(np.abs(lam), initial=0.0)) if np.isfinite(lam).any() else 0.0
    contact = lam[:, -len(piece.contacts) :]
    if not np.isfinite(contact).any() or np.nanmin(contact) >= -PULL_TOL * scale:
        return ""
    node, col = np.unravel_index(np.nanargmin(contact), contact.shape)
    name = model.contact_row_names[piece.contacts[col] - model.k]
    return (
        f"contact {name!r} pulls at t={ver.t[node]:.6g}: its force by (23) is {contact[node, col]:.3g} < 0 "
        "(a unilateral contact can only push)"
    )


def _jumps(model: Model, path: Path) -> tuple[int, list[str]]:
    """Each recorded velocity jump against the model's impact law: how many, and the problems found."""
    out = []
    where = np.flatnonzero(path.t[1:] <= path.t[:-1]) + 1
    for i in where:
        t = float(path.t[i])
        plastic = [
            model.contact_row_names.index(e["contact"])
            for e in path.events
            if e.get("kind") == "impact"
            and e.get("t") == t
            and e.get("plastic")
            and e["contact"] in model.contact_row_names
        ]
        lam = None if path.lam is None else path.lam[i - 1]
        res = model.impact(t, path.q[i - 1], path.v[i - 1], lam, plastic=plastic)
        scale = max(float(np.abs(path.v[i - 1 : i + 1]).max()), np.finfo(float).tiny)
        error = float(np.abs(res.v_after - path.v[i]).max()) / scale
        if not error <= JUMP_TOL:
            out.append(
                f"the velocity jump at t={t:.6g} differs from the model's impact law by {error:.3g} (relative) "
                f"> {JUMP_TOL:g}: recorded v⁺ = {path.v[i].tolist()}, law v⁺ = {res.v_after.tolist()}"
            )
    return int(where.size), out


def _skipped_lines(skipped: list[dict[str, Any]]) -> list[str]:
    """Skipped pieces in words; the many short pieces of a Zeno-like bounce sequence in one line."""
    short = [s for s in skipped if s["reason"].endswith(_SHORT)]
    if len(short) == 1:
        short = []
    lines = [
        f"skipped [{s['t'][0]:.6g}, {s['t'][1]:.6g}] {s['what']}: {s['reason']}" for s in skipped if s not in short
    ]
    if short:
        total = sum(s["t"][1] - s["t"][0] for s in short)
        lines.append(
            f"skipped {len(short)} pieces with fewer than {MIN_SAMPLES} samples each, {total:.3g} of the time in all, "
            f"between t={short[0]['t'][0]:.6g} and t={short[-1]['t'][1]:.6g}{_SHORT}"
        )
    return lines


def combine(
    model: Model,
    done: list[tuple[Piece, Verification]],
    skipped: list[dict[str, Any]],
    problems: list[str],
    notes: list[str],
) -> Verification:
    """One verdict from the pieces (see the module docstring)."""
    vers = [v for _, v in done]
    span = np.array([v.t[-1] - v.t[0] for v in vers])
    worst = max(vers, key=lambda v: v.relative_gap / v.tolerance)
    width = model.k + len(model.contact_row_names)
    multipliers = []
    for piece, ver in done:
        table = np.full((ver.t.size, width), np.nan)
        table[:, list(piece.columns)] = ver.multipliers
        multipliers.append(table)
    is_motion = all(v.is_motion for v in vers) and not problems
    covered = float(span.sum())
    head = (
        f"{'a motion' if is_motion else 'NOT a motion'} on {len(vers)} smooth piece(s) verified by (23), "
        f"{covered:.6g} of the time"
    )
    lines = [head, *(v.message for v in vers)]
    lines += _skipped_lines(skipped)
    lines += notes + problems
    return Verification(
        t=np.concatenate([v.t for v in vers]),
        value_at_zero=float(span @ [v.value_at_zero for v in vers] / covered),
        minimum=float(span @ [v.minimum for v in vers] / covered),
        gap=float(span @ [v.gap for v in vers] / covered),
        relative_gap=worst.relative_gap,
        coarse_relative_gap=worst.coarse_relative_gap,
        tolerance=worst.tolerance,
        is_motion=is_motion,
        delta_x=np.concatenate([v.delta_x for v in vers]),
        multipliers=np.concatenate(multipliers),
        method=worst.method,
        pieces=tuple(vers),
        skipped=tuple(skipped),
        message="\n".join(lines),
    )
