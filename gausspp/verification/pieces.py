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

The cutting and the law of each piece are :mod:`gausspp.verification.cutting`; this module verifies the
pieces, checks the contact forces and the jumps, and combines the verdicts.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import InputError
from ..model.model import Model
from .cutting import Path, Piece, clip, cuts, laws, read, spans
from .integral import Verification, judge, verdict
from .path import check_samples, discretize

#: Fewest samples a piece needs to be verified (a quintic spline, and ≥ 5 nodes on every other one).
MIN_SAMPLES = 9
#: A closed contact's recovered multiplier below −this × the piece's largest multiplier is a pull.
PULL_TOL = 1e-4
#: Largest relative difference between a recorded velocity jump and the model's impact law.
JUMP_TOL = 1e-6


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
    check_samples(path.t, path.q, path.v, monotone=False)
    ranges = clip(path.t, spans(path.t.size, cuts(path)), window)
    pieces = laws(model, path, ranges, constraint_tol)
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
    if getattr(trajectory, "status", "success") == "failed":
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
    d = discretize(piece.model, data, metric=metric, acceleration=acceleration, constraint_tol=constraint_tol)
    if piece.known is not None:  # a known reaction is an applied force: R = A ẍ − f − D u_bound
        known = piece.known[np.searchsorted(path.t[s], d.t)]
        d = replace(d, R=d.R - known, f=None if d.f is None else d.f + known)
    ver = judge(d, method)
    return replace(ver, message=f"[{d.t[0]:.6g}, {d.t[-1]:.6g}] {piece.label}: {verdict(ver)}")


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
        # relative to the speed there, not below round-off of the motion's speed (a "jump" at an apex, v ≈ 0)
        scale = max(
            float(np.abs(path.v[i - 1 : i + 1]).max()), 1e-9 * float(np.abs(path.v).max()), np.finfo(float).tiny
        )
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
