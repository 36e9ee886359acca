"""``gp.verify``: decide by the integral principle (23) whether a trajectory is a motion of a model.

One smooth path is discretized and judged at once (:mod:`gausspp.verification.integral`); a path with
contacts, saturated actuators, or from a failed run is cut into smooth pieces and each is judged by the
law that held on it (:mod:`gausspp.verification.pieces`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import InputError, UnknownNameError
from ..model.model import Model
from . import integral
from .integral import Verification, check_model
from .pieces import verify_pieces


def verify(
    model: Model,
    trajectory: Any,
    *,
    window: tuple[float, float] | None = None,
    nodes: int | None = None,
    metric: str | np.ndarray = "A",
    method: str = "qp",
    acceleration: str = "path",
    constraint_tol: float = 1e-6,
) -> Verification:
    """Decide by inequality (23) whether ``trajectory`` is a motion of ``model``.

    Parameters
    ----------
    model : Model
        The model (with its realizations) to test the path against.
    trajectory : Trajectory or mapping
        Anything with ``t (N,)``, ``q (N, nq)``, ``v (N, nv)`` and optionally ``a (N, nv)``: a
        result of :func:`simulate` or data from elsewhere.
    window : (t1, t2), optional
        Part of the data to use (default: all).
    nodes : int, optional
        Resample the window at this many uniform nodes (quintic splines); default: the samples.
    metric : "A", "identity" or an SPD (nv, nv) array
        The matrix of (23); any positive definite one gives the same verdict.
    method : {"qp", "closed-form"}
        The sparse QP (any realization), or the pointwise closed form (``N = 0`` only).
    acceleration : {"path", "recorded"}
        ``ẍ`` from the path's velocities (quintic spline; the honest check) or the trajectory's
        recorded accelerations (measured data).

    Notes
    -----
    An over-actuated :class:`~gausspp.Force` enters with the relations of its least-compulsion
    reaction, ``S H⁻¹ M δx = 0``, so a path with another allocation is not a motion.

    A model with unilateral contacts or bounded actuators is verified in smooth pieces, each by
    the law that held on it (:mod:`gausspp.verification.pieces`): between impacts and lift-offs with the closed
    contacts as ideal constraints (and the jumps against the impact law), on saturated intervals
    with the actuators' force at its bound as a known force. A failed run (``success`` false)
    is verified on what was computed, and ``message`` says so. Both need the samples
    themselves (``nodes`` must be ``None``). The result's ``pieces``, ``skipped`` and ``message``
    say what was checked; a trajectory of which no piece can be checked raises
    :class:`~gausspp.InputError` with the reasons.
    """
    frictional = type(trajectory).__name__ == "FrictionRun" or getattr(trajectory, "lane", "") == "friction"
    if frictional or getattr(model, "friction", ()):  # Coulomb friction: no principle (23) for it here
        raise InputError(
            "gp.verify does not check frictional motions: (23) compares a path with the motions of ideal or "
            "prescribed realizations, and Coulomb friction is a reaction whose direction depends on the motion "
            "itself (docs/friction.md); check a frictional run by its closed forms and its energy, which friction "
            "never raises (its energy), and the gaps and slips the run records (Trajectory.gap, .slip, .modes)"
        )
    check_model(model)
    if method not in ("qp", "closed-form"):
        raise UnknownNameError(f"method={method!r} is unknown; use 'qp' or 'closed-form'")
    failed = getattr(trajectory, "status", "success") == "failed"
    if model.contacts or model.bounded or failed:
        if nodes is not None:
            raise InputError(
                f"nodes={nodes} resamples one smooth path; this trajectory (contacts, bounded actuators or a failed "
                "run) is verified piece by piece at its own samples: leave nodes=None"
            )
        return verify_pieces(
            model,
            trajectory,
            window=window,
            metric=metric,
            method=method,
            acceleration=acceleration,
            constraint_tol=constraint_tol,
        )
    d = integral.discretize(
        model,
        trajectory,
        window=window,
        nodes=nodes,
        metric=metric,
        acceleration=acceleration,
        constraint_tol=constraint_tol,
    )
    ver = integral.judge(d, method)
    return replace(ver, message=f"[{d.t[0]:.6g}, {d.t[-1]:.6g}] one smooth path: {integral.verdict(ver)}")
