"""The general step through CVODES: the compiled call of the pattern decided, as SUNDIALS' right-hand side.

A model of the general kind whose step is an equality pattern — redundant rows, kept rows decided once
(:mod:`gausspp.step.general.compiled`) — has a right-hand side that is one flat SX function. CVODES (BDF, or
Adams–Moulton with functional iteration: ``method="cvodes-adams"``) integrates it in C, without a Python call
per evaluation. The function returns NaN where the pattern's all-clear flag is down, so that CVODES stops
there; the run then goes on from the last output time reached with scipy's DOP853 at the same tolerances,
whose right-hand side takes the Python step and decides the pattern again. A pattern with inequalities
(bounded actuators: a QP node in the graph) runs in CVODES with Adams' functional iteration, which needs no
Jacobian; BDF, which differentiates the right-hand side, hands it to DOP853 from the start.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from ..model.model import Model
from ..step.general import general_step
from ..step.general.solve import CONSISTENCY_TOL
from . import methods as _methods
from .compiled import CVODES, cvodes_run
from .integrate import run_scipy
from .lanes import Job
from .rhs import GeneralRightHandSide
from .samples import Samples

#: The method that goes on where CVODES stops (the pattern changed).
CONTINUATION = "DOP853"


def _rhs_function(
    model: Model, rhs: GeneralRightHandSide, t0: float, y0: np.ndarray, differentiated: bool
) -> ca.Function | None:
    """``F(t, y, stab) → y'`` of the pattern decided at ``(t0, y0)``, NaN where its flag is down; ``None`` when
    there is none, or when the method ``differentiated`` it (BDF's Newton iteration) and it holds a QP node."""
    rhs.evaluate(t0, y0)  # the Python step decides the pattern at the start (or its compiled call answers)
    call = general_step.current_call(model, rhs.backend, None, CONSISTENCY_TOL)
    flat = call is not None and call.function.is_a("SXFunction")
    if call is None or (differentiated and not flat):
        return None
    nq, nv, nl = model.nq, model.nv, model.n_lam
    sym = ca.SX.sym if flat else ca.MX.sym
    t, y, s = sym("t"), sym("y", nq + nv + nl + 2), sym("stab", 2)
    out = call.function(t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], s)
    sl = call.slices
    u = out[sl["u"].start : sl["u"].start + model.m]
    ydot = ca.vertcat(
        out[sl["qdot"]],
        out[sl["a"]],
        *(u[i] for i in model.lam_columns),
        out[sl["power_reaction"]],
        out[sl["power"]],
    )
    flag = out[out.shape[0] - 2]
    return ca.Function("general_rhs", [t, y, s], [ca.if_else(flag > 0.5, ydot, np.nan)])


def run_general_cvodes(job: Job) -> Samples:
    """The cvodes-general lane's runner: CVODES on the compiled general step, then DOP853 from where it stopped
    (module docstring)."""
    rhs, model, stab, opts, y0 = job.rhs, job.model, job.stab, job.opts, job.y0
    o = opts
    F = _rhs_function(model, rhs, o.t0, y0, differentiated=CVODES[o.method.name] == "bdf")
    continuation = replace(o, method=_methods.get(CONTINUATION), dt=None)
    if F is None:
        return run_scipy(replace(job, opts=continuation))
    t, Y, steps, failure, evaluations, _ = cvodes_run(F, o, stab=stab, y0=y0)
    if failure is None:
        return Samples(t, Y, steps, evaluations + rhs.evaluations, None, o.method.name, rhs.solver)
    later = replace(continuation, t0=float(t[-1]), record=_later(o.record, float(t[-1])))
    rest = run_scipy(replace(job, opts=later, y0=Y[-1]))
    keep = rest.t > t[-1]
    return Samples(
        np.concatenate([t, rest.t[keep]]),
        np.vstack([Y, rest.y[keep]]),
        steps + rest.steps,
        evaluations + rest.evaluations,
        rest.failure,
        o.method.name,
        rhs.solver,
        events=rest.events,
    )


def _later(record: object, t: float) -> object:
    """The record times after ``t`` (and ``t`` itself, where the continuation starts); a count as it is."""
    if np.isscalar(record):
        return record
    times = np.asarray(record, float)
    return np.concatenate([[t], times[times > t]])
