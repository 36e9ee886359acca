"""Cutting a path into smooth pieces, each with the law that held on it (see :mod:`gausspp.verification.pieces`).

:func:`read` takes the trajectory's arrays and records, :func:`cuts` and :func:`spans` find the sample ranges
between velocity jumps, events and changes of saturation, :func:`clip` keeps what lies in a window, and
:func:`laws` gives each range its :class:`Piece`: the model with the contacts closed there
(:func:`contact_pieces`), or the servo law, or the model without the saturated servos under their known
reaction (:func:`servo_pieces`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from ..model.derived import gaps as contact_gaps
from ..model.derived import phase_model, sub_model
from ..model.model import Model
from .path import data_function, path_samples


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
    """The path's arrays, checked for shape and finiteness as :func:`~gausspp.verification.path.discretize` does."""
    t, q, v, a = path_samples(trajectory)
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


def clip(t: np.ndarray, ranges: list[tuple[int, int]], window: tuple[float, float] | None) -> list[tuple[int, int]]:
    """The ranges cut to the samples inside ``window`` (all of them without one)."""
    if window is None:
        return ranges
    t1, t2 = float(window[0]), float(window[1])
    if not (t[0] <= t1 < t2 <= t[-1]):
        raise InputError(f"window ({t1:g}, {t2:g}) is outside the data [{t[0]:g}, {t[-1]:g}] or empty")
    inside = [
        (a + int(np.searchsorted(t[a:b], t1)), a + int(np.searchsorted(t[a:b], t2, side="right"))) for a, b in ranges
    ]
    return [(a, b) for a, b in inside if b > a]


def laws(model: Model, path: Path, ranges: list[tuple[int, int]], tol: float) -> list[Piece]:
    """Each range with its law: by the contacts closed on it, by the saturation of bounded servos, or the model."""
    if model.contacts:
        return contact_pieces(model, path, ranges, tol)
    if model.bounded:
        return servo_pieces(model, path, ranges, tol)
    return [Piece(a, b, model, "one smooth path", columns=tuple(range(model.k))) for a, b in ranges]


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
    fn = data_function(model)
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
