"""The model side of (23): the data ``R = A ẍ − f``, ``A``, (20), ``Φ``, ``g`` along a path, on nodes.

:func:`data_function` compiles them for a model; :func:`path_samples` and :func:`check_samples` read and
check a trajectory's samples; :func:`discretize` fits the path's splines (the acceleration ``ẍ`` from a
quintic spline of ``v(t)``, or the recorded one), checks that the path is on the constraint and returns
the :class:`~gausspp.verification.discrete.Discretized` problem that :mod:`gausspp.verification.discrete`
solves.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np
from scipy.interpolate import make_interp_spline

from ..errors import InitialDataError, InputError, NonFiniteError, ShapeError, UnknownNameError
from ..model.model import Model
from ..validation import array, positive, short
from ..workspace import workspace
from .discrete import Discretized

#: A path's samples: times, positions, velocities and (if recorded) accelerations.
Samples = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]


def data_function(model: Model) -> ca.Function:
    """``(t, q, v, a) -> (R, A, E1, E0, Φ, g, f)`` along a path (kept in the model's workspace)."""
    return workspace(model).get(("integral-data",), lambda: _build_data_function(model))


def _build_data_function(model: Model) -> ca.Function:
    mech = model.mechanism
    a = ca.SX.sym("a", mech.nv)
    E1s, E0s, pointwise = [], [], []
    for c in model.constraints:
        rel = c.realization.virtual_displacements(mech, c.expressions(mech), a)
        k = rel.E0.shape[0]
        E1s.append(rel.E1 if rel.E1 is not None else ca.SX.zeros(k, mech.nv))
        E0s.append(rel.E0)
        pointwise += [rel.E1 is None] * k
    p = model.expressions
    assert p.g is not None  # a model's step always carries its holonomic residuals
    R = p.A @ a - p.f
    E1, E0 = (ca.vertcat(ca.SX(0, mech.nv), *E) for E in (E1s, E0s))  # no rows: a free model (contact flight)
    fn = ca.Function("integral_data", [mech.t, mech.q, mech.v, a], [R, p.A, E1, E0, p.Phi, p.g, p.f])
    fn.pointwise = np.array(pointwise, dtype=bool)  # type: ignore[attr-defined]
    return fn


def _window(window: Any) -> tuple[float, float]:
    """``window`` as two finite times ``(t1, t2)``."""
    ends = array("verify", "window", window)
    if ends.shape != (2,):
        raise ShapeError(f"window must be two times (t1, t2), got {short(window)}")
    return float(ends[0]), float(ends[1])


def path_samples(trajectory: Any) -> Samples:
    """The trajectory's ``t``, ``q``, ``v`` and (if recorded) ``a``, one row per sample; not yet checked."""
    get = trajectory.get if isinstance(trajectory, Mapping) else lambda k, d=None: getattr(trajectory, k, d)
    missing = [k for k in ("t", "q", "v") if get(k, None) is None]
    if missing:
        raise InputError(
            f"trajectory must be a gp.Trajectory (from gp.simulate) or a mapping with t, q and v; got "
            f"{type(trajectory).__name__} {short(trajectory)} without {', '.join(missing)}"
        )
    t, q, v = (array("trajectory", k, get(k), finite=False) for k in ("t", "q", "v"))  # located below if not
    a = get("a", None)
    a = None if a is None else array("trajectory", "a", a, finite=False)
    return t, np.atleast_2d(q.T).T, np.atleast_2d(v.T).T, None if a is None else np.atleast_2d(a.T).T


def check_samples(t: np.ndarray, q: np.ndarray, v: np.ndarray, *, monotone: bool = True) -> None:
    """Finite samples, at least 2, with ``t`` strictly increasing (or, ``monotone=False``, non-decreasing:
    a trajectory with velocity jumps records two samples at each jump's time)."""
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
        bad = int(np.flatnonzero(~(np.isfinite(q).all(1) & np.isfinite(v).all(1) & np.isfinite(t)))[0])
        raise NonFiniteError(f"trajectory: sample {bad} (t={t[bad]:.6g}) is not finite; cut the window before it")
    step = np.diff(t)
    if t.size < 2 or np.any(step <= 0 if monotone else step < 0):
        order = "strictly increasing" if monotone else "non-decreasing"
        raise InputError(f"trajectory: t must be {order} with at least 2 samples")


def check_model(model: Any) -> None:
    """``model`` is a :class:`~gausspp.Model`."""
    if not isinstance(model, Model):
        raise InputError(f"model must be a gp.Model, got {short(model)}")


def discretize(
    model: Model,
    trajectory: Any,
    *,
    window: tuple[float, float] | None = None,
    nodes: int | None = None,
    metric: str | np.ndarray = "A",
    acceleration: str = "path",
    constraint_tol: float = 1e-6,
) -> Discretized:
    """Evaluate ``R``, the metric and (20) on the nodes of a path (checked).

    The steps: the path's samples (:func:`checked_samples`), the window and the choice of
    acceleration, the nodes and the path's values there (:func:`node_values`), the model's data
    on them (:func:`evaluate`).
    """
    check_model(model)
    constraint_tol = positive(
        "constraint_tol", constraint_tol, zero_ok=True, hint=" (how far the path may be off the constraint)"
    )
    if nodes is not None:
        nodes = positive("nodes", nodes, integer=True, hint=" (uniform nodes in the window, at least 5)")
    t, q, v, a = checked_samples(model, trajectory)
    t1, t2 = (t[0], t[-1]) if window is None else _window(window)
    if not (t[0] <= t1 < t2 <= t[-1]):
        raise InputError(f"window ({t1:g}, {t2:g}) is outside the data [{t[0]:g}, {t[-1]:g}] or empty")
    if acceleration not in ("path", "recorded"):
        raise UnknownNameError(f"acceleration={acceleration!r} is unknown; use 'path' (from v(t)) or 'recorded'")
    if acceleration == "recorded" and a is None:
        raise InputError("acceleration='recorded' needs the trajectory's accelerations a")
    tn, qn, vn, an = node_values(model, (t, q, v, a), (t1, t2), nodes, acceleration)
    return evaluate(model, tn, qn, vn, an, metric, constraint_tol)


def checked_samples(model: Model, trajectory: Any) -> Samples:
    """The trajectory's samples, of the model's shapes, finite and increasing, near-repeated times dropped."""
    t, q, v, a = path_samples(trajectory)
    N = t.size
    if q.shape != (N, model.nq) or v.shape != (N, model.nv):
        raise ShapeError(
            f"trajectory: q and v must be ({N}, {model.nq}) and ({N}, {model.nv}), got {q.shape}, {v.shape}"
        )
    check_samples(t, q, v)
    # samples closer than 1e-9 of the span (an adaptive integrator's last sliver of a step) carry no
    # information and would spoil the splines: keep the later of each such pair
    keep = np.append(np.diff(t) > 1e-9 * (t[-1] - t[0]), True)
    keep[0] = True
    return t[keep], q[keep], v[keep], a[keep] if a is not None else None


def node_values(
    model: Model, samples: Samples, window: tuple[float, float], nodes: int | None, acceleration: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(t, q, v, ẍ)`` on the nodes: the samples inside the window, or ``nodes`` uniform ones on quintic splines.

    ``ẍ`` is the derivative of the quintic spline of ``v(t)`` (error ``O(h⁵)``) or, with
    ``acceleration='recorded'``, the recorded one.
    """
    t, q, v, a = samples
    t1, t2 = window
    N = t.size
    recorded = a if a is not None else v  # (only read when acceleration == "recorded")
    if N < 6:
        raise InputError(f"trajectory: {N} samples; the path's acceleration needs at least 6")
    v_spline = make_interp_spline(t, v, k=5, axis=0)  # quintic: ẍ from v(t) with O(h⁵) error
    path_a = v_spline.derivative()
    if nodes is None:
        inside = (t >= t1 - 1e-12) & (t <= t2 + 1e-12)
        tn, qn, vn = t[inside], q[inside], v[inside]
        an = recorded[inside] if acceleration == "recorded" else path_a(tn)
    else:
        tn = np.linspace(t1, t2, int(nodes))
        qn = np.array([model.mechanism.normalize_array(x) for x in make_interp_spline(t, q, k=5, axis=0)(tn)])
        vn = v_spline(tn)
        an = make_interp_spline(t, recorded, k=5, axis=0)(tn) if acceleration == "recorded" else path_a(tn)
    if tn.size < 5:
        raise InputError(
            f"too few nodes in the window: {tn.size}; the discretization needs at least 5 (pass nodes=...)"
        )
    return tn, qn, vn, an


def evaluate(
    model: Model,
    tn: np.ndarray,
    qn: np.ndarray,
    vn: np.ndarray,
    an: np.ndarray,
    metric: str | np.ndarray,
    constraint_tol: float,
) -> Discretized:
    """The model's data of (23) on the nodes, the path checked to be on the constraint (``|Φ|, |g| ≤ tol``)."""
    fn = data_function(model)
    out = fn.map(tn.size)(tn[None, :], qn.T, vn.T, an.T)
    R, A, E1, E0, Phi, g, f = (np.array(x) for x in out)
    n, k, N1 = model.nv, model.k, tn.size
    r = fn.pointwise.size  # type: ignore[attr-defined]  # rows of the relations (20): k unless a realization has more
    Phi, g = Phi.reshape(k, N1), g.reshape(k, N1)
    worst = float(max(np.abs(Phi).max(initial=0.0), np.abs(g).max(initial=0.0)))
    if worst > constraint_tol:
        i = int(np.argmax(np.abs(Phi).max(0) + np.abs(g).max(0)))
        raise InitialDataError(
            f"the path is off the constraint at t={tn[i]:.6g} (|Φ| or |g| = {worst:.3g} > {constraint_tol:g}); "
            "(23) compares paths on the constraint: project the data or raise constraint_tol"
        )
    A = A.reshape(n, -1, n).transpose(1, 0, 2) if n > 1 else A.reshape(-1, 1, 1)
    G = _metric(metric, A, n)
    return Discretized(
        t=tn,
        R=R.reshape(n, N1).T,
        G=G,
        E1=E1.reshape(r, N1, n).transpose(1, 0, 2),
        E0=E0.reshape(r, N1, n).transpose(1, 0, 2),
        pointwise=fn.pointwise,  # type: ignore[attr-defined]
        f=f.reshape(n, N1).T,
        momentum=np.einsum("nij,nj->ni", A, vn),
    )


def _metric(metric: str | np.ndarray, A: np.ndarray, n: int) -> np.ndarray:
    if isinstance(metric, str):
        if metric == "A":
            return A
        if metric == "identity":
            return np.broadcast_to(np.eye(n), A.shape).copy()
        raise UnknownNameError(f"metric={metric!r} is unknown; use 'A', 'identity' or an SPD (n, n) array")
    G = np.asarray(metric, float)
    if G.shape != (n, n) or not np.allclose(G, G.T) or np.linalg.eigvalsh(0.5 * (G + G.T)).min() <= 0:
        raise InputError(f"metric must be a symmetric positive definite ({n}, {n}) array")
    return np.broadcast_to(G, A.shape).copy()
