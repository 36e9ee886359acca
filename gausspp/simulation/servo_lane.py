"""The servo lane: ``gp.simulate`` of a servo-constraint the actuators reach only through higher derivatives.

A servo-constraint whose actuators do not act on its second derivative (``J A⁻¹ D`` singular: the overhead crane's
payload path, the far mass of a spring chain) cannot be kept step by step — the one-step Gauss QP has no answer —
but the actuators still reach it through the constraint's higher derivatives (docs/theory.md §7). Where
:func:`gausspp.step.servo_reach.higher_reach` finds such a reach, :func:`gausspp.simulate` hands the run to the
index reduction (:func:`gausspp.simulate_servo`) and returns its motion as a :class:`~gausspp.Trajectory`
like any other: ``u`` the actuator forces, ``a = A⁻¹(f + r₀ + D u)``, the reaction ``D u`` and its compulsion, the
constraint's values, the energy, and the reaction's work ``W_R = ∫ v·D u dt`` integrated with the motion
(``Trajectory.lane == "servo"``). Index reduction integrates with DOP853 at the run's
``rtol``/``atol`` (a fixed-step method, ``dt``, a stabilization or another solver are refused: index reduction has
its own feedback, :func:`gausspp.servo.index_reduction.feedback`). There is no one-step realizability margin:
``margin`` is NaN.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..errors import GaussppError, InputError, IntegrationError, RealizabilityError, RealizabilityWarning
from ..model.model import Model
from ..model.reach_sizes import reach_sizes
from ..model.run_scales import run_scales
from ..servo.index_reduction import simulate_servo
from ..step.servo_reach import actuators_only, higher_reach
from .inputs import Options
from .labels import model_labels
from .recording import failed
from .tolerance import within_tolerance
from .trajectory import Trajectory

#: The lane's name on the trajectory.
LANE = "servo"


def wanted(model: Model, t0: float, q0: Any, v0: Any, horizon: float) -> bool:
    """Whether the run is index reduction's: the one-step solution refuses the start for want of reach, and the
    actuators reach the constraint through higher derivatives (:func:`~gausspp.step.servo_reach.higher_reach`,
    weighing sensitivities by the sizes of the run over ``horizon``: :mod:`gausspp.model.reach_sizes`)."""
    if not actuators_only(model):  # the cheap part of higher_reach's conditions: most models stop here
        return False
    try:
        _t, q, v, _lam = model.checked_state(t0, q0, v0, None)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RealizabilityWarning)
            model.step(t0, q, v)
    except RealizabilityError:
        return higher_reach(model, t0, q, v, reach_sizes(model, t0, q, v, horizon)) is not None
    except GaussppError:
        return False  # the one-step solution reports it
    return False


def check_options(opts: Options, stabilize: Any, lam0: Any) -> None:
    """Refuse what index reduction does not do, saying why."""
    if opts.method.name != "DOP853" or opts.dt is not None:
        raise InputError(
            f"index reduction integrates adaptively with DOP853 (its own feedback keeps the constraint): method "
            f"{opts.method.name!r}{' and dt' if opts.dt is not None else ''} cannot run it; pass neither method "
            "nor dt, or call gp.simulate_servo"
        )
    if stabilize is not None:
        raise InputError("index reduction has its own feedback on the constraint: pass no stabilize")
    if lam0 is not None:
        raise InputError("index reduction's actuators carry no λ state: pass no lam0")


def run_servo(model: Model, q0: Any, v0: Any, opts: Options) -> Trajectory:
    """Index reduction's motion as a :class:`~gausspp.Trajectory` (module docstring); raised per ``opts.throw``."""
    record = None if np.isscalar(opts.record) else np.asarray(opts.record, float)
    _t, q, v, lam = model.checked_state(opts.t0, q0, v0, None)
    scales = run_scales(model, opts.t0, q, v, lam, opts.t_end - opts.t0)  # read once: the tolerances and the verdict
    atol = opts.atol if opts.atol is not None else scales.atol(opts.rtol)[: model.nq + model.nv]
    sizes = reach_sizes(model, opts.t0, q, v, opts.t_end - opts.t0, scales)
    servo = simulate_servo(model, q0, v0, opts.t_end, t0=opts.t0, record=record, rtol=opts.rtol, atol=atol, sizes=sizes)
    traj = _trajectory(model, servo)
    if servo.status == "success":
        return within_tolerance(model, traj, opts.constraint_tol, scales)
    failure = IntegrationError(f"index reduction stopped: {servo.message}")
    traj = failed(traj, failure)
    if opts.throw:
        failure.trajectory = traj  # type: ignore[attr-defined]
        raise failure
    return traj


def _trajectory(model: Model, servo: Any) -> Trajectory:
    """The samples of ``servo`` with the step's quantities evaluated from the model's data at each of them."""
    n, nv, k = servo.t.size, model.nv, model.k
    a, reaction = np.zeros((n, nv)), np.zeros((n, nv))
    compulsion, energy = np.zeros(n), np.full(n, np.nan)
    residual, g = np.zeros((n, k)), np.zeros((n, k))
    no_lam = np.zeros(0)
    for i in range(n):
        d = model.evaluate_data(float(servo.t[i]), servo.q[i], servo.v[i], no_lam)
        reaction[i] = d.D @ servo.forces[i]
        a[i] = np.linalg.solve(d.A, d.f + d.r0 + reaction[i])
        compulsion[i] = float(reaction[i] @ np.linalg.solve(d.A, reaction[i]))
        residual[i], g[i] = d.Phi, d.g
        if model.has_energy:
            energy[i] = d.energy

    return Trajectory(
        t=servo.t.copy(),
        q=servo.q.copy(),
        v=servo.v.copy(),
        lam=np.zeros((n, 0)),
        a=a,
        u=servo.forces.copy(),
        reaction=reaction,
        compulsion=compulsion,
        residual=residual,
        g=g,
        margin=np.full(n, np.nan),
        energy=energy,
        work_reaction=servo.work_reaction.copy(),
        work_forces=servo.work_forces.copy() if model.has_force_power else np.full(n, np.nan),
        status="success",
        message="",
        method="DOP853",
        solver=f"index reduction (index {servo.index})",
        steps=max(n - 1, 0),
        rhs_evaluations=servo.rhs_evaluations,
        contact_force=np.zeros((n, 0)),
        tracking_error=np.zeros(n),
        saturated=np.zeros((n, model.m), dtype=bool),
        gap=np.zeros((n, 0)),
        lane=LANE,
        route=model.route,
        labels=model_labels(model),
    )
