"""``gp.simulate`` of a model with frictional contacts (``gp.Model(..., friction=[...])``, ``gp.from_mjcf``): the
friction lane, :func:`gausspp.simulate_friction` event by event, its run returned as a :class:`Trajectory`.

The model's one-sided rows (``gp.Unilateral``: a joint's range, …) join the frictional contacts as frictionless ones
(``μ = 0``, no slip), and its bilateral holonomic rows as rows always closed whose force may take either sign
(:class:`HeldRow`), so that one event loop keeps them all. Bilateral rows are taken where every reaction is along
its row's normal (``D = Jᵀ``: ideal rows, and a servo-constraint realized along its own normal, as a joint's torque
holding its angle) and nothing depends on time explicitly; others are refused by name.
The trajectory holds the state, the energy, each contact's gap, normal force (``contact_force``), friction force
and slip (one column per slip component) and mode, and the events (impacts, stick, slip, lift-off); the step's
quantities of the other lanes (accelerations, reactions, compulsion, margin, works) are not computed here: NaN. The
options the lane does not take are refused by name.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaussppError, InputError
from ..model.friction_contact import FrictionContact
from ..model.model import Model
from .trajectory import Trajectory


class HeldRow(FrictionContact):
    """A bilateral holonomic row of the model among the frictional contacts: always closed, its force of either
    sign along ``∂g/∂q`` (:data:`gausspp.friction.modes.HELD`)."""

    held = True


def check_friction_options(model: Model, **given: Any) -> None:
    """Refuse, by name, what the friction lane does not do."""
    from ..model.constraints import Holonomic

    not_holonomic = [n for c, n in zip(model.constraints, model.names, strict=True) if not isinstance(c, Holonomic)]
    if not_holonomic:
        raise InputError(
            f"gp.simulate: frictional contacts with the velocity-level rows {not_holonomic}: the friction lane keeps "
            "holonomic rows only (g(q) = 0)"
        )
    if model.k and not (model.symmetric_S and model.n_lam == 0):
        raise InputError(
            f"gp.simulate: frictional contacts with rows ({', '.join(model.names)}) whose reactions are not along "
            "their normals (D ≠ Jᵀ) or carry a λ state: the friction lane keeps ideal rows, and servo-constraints "
            "realized along their own normals (a joint's torque holding its angle)"
        )
    for name, value in given.items():
        if value is not None:
            raise InputError(f"gp.simulate: {name}={value!r} is not taken by the friction lane (frictional contacts)")


def _held_rows(model: Model) -> list[FrictionContact]:
    """Each bilateral holonomic row of the model as a :class:`HeldRow`."""
    return _rows_as_contacts(model, model.constraints, model.names, HeldRow, "row")


def _limit_contacts(model: Model) -> list[FrictionContact]:
    """Each one-sided row of the model as a frictionless contact with no slip (its restitution kept)."""
    return _rows_as_contacts(model, model.contacts, model.contact_names, FrictionContact, "one-sided row")


def _rows_as_contacts(model: Model, constraints: Any, names: list[str], kind: type, what: str) -> list[FrictionContact]:
    """Each row ``g_i(q)`` of ``constraints`` as a contact of ``kind`` with that gap, no slip and no friction."""
    mech = model.mechanism
    out: list[FrictionContact] = []
    for c, name in zip(constraints, names, strict=True):
        rows = ca.SX(c.value(mech.q, mech.t))
        if ca.depends_on(rows, mech.t):
            raise InputError(f"gp.simulate: the {what} {name!r} depends on time: not taken with frictional contacts")
        for i in range(rows.numel()):
            fn = ca.Function("g", [mech.q], [rows[i]])
            label = name if rows.numel() == 1 else f"{name}[{i}]"
            e = getattr(c, "restitution", 0.0)
            out.append(kind(gap=lambda q, fn=fn: fn(q), slip=lambda q, v: 0 * v[0], mu=0.0, name=label, restitution=e))
    return out


def run_friction(
    model: Model, q0: Any, v0: Any, t_end: float, *, dt: float | None, rtol: float, atol: float | None, record: Any,
    throw: bool, max_events: int,
) -> Trajectory:  # fmt: skip
    from ..friction.integrate import simulate_friction
    from ..workspace import workspace

    contacts = workspace(model).get(
        "friction-lane contacts", lambda: [*model.friction, *_limit_contacts(model), *_held_rows(model)]
    )
    times = None if isinstance(record, (int, np.integer)) else record
    options: dict[str, Any] = {
        "rtol": rtol, "max_events": max_events, "record": times, "step": dt, "throw": False, "codegen": model.codegen
    }  # fmt: skip
    if atol is not None:
        options["atol"] = atol
    if model.k:  # the bilateral rows must hold at the start, each against its own scale (as gp.simulate's)
        from ..model.run_scales import run_scales
        from ..validation import array
        from .initial import check_on_constraint

        q, v = array("simulate", "q0", q0).ravel(), array("simulate", "v0", v0).ravel()
        if q.size == model.nq and v.size == model.nv:
            lam = np.zeros(0)
            scales = run_scales(model, 0.0, q, v, lam, t_end)
            check_on_constraint(model, 0.0, q, v, lam, 1e-8, scales=scales)
    run = simulate_friction(model.mechanism, contacts, q0, v0, t_end, **options)
    traj = _trajectory(model, contacts, run, dt)
    if run.failure is not None and throw:
        exc = run.failure
        if isinstance(exc, GaussppError):
            exc.trajectory = traj  # type: ignore[attr-defined]
        raise exc
    return traj


def _measure(model: Model, contacts: list[FrictionContact]) -> ca.Function:
    """``(q, v) ↦ (gaps, slips)`` of the contacts."""
    mech = model.mechanism
    gaps = ca.vertcat(*[ca.SX(c.gap(mech.q)) for c in contacts])
    slips = ca.vertcat(*[ca.SX(c.slip(mech.q, mech.v)) for c in contacts])
    return ca.Function("measure", [mech.q, mech.v], [gaps, slips])


def _trajectory(model: Model, contacts: list[FrictionContact], run: Any, dt: float | None) -> Trajectory:
    from ..workspace import workspace

    n = run.t.size
    measure = workspace(model).get("friction-lane measure", lambda: _measure(model, contacts))
    slips = measure.sparsity_out(1)
    if n:
        g, s = measure.map(n)(run.q.T, run.v.T)
        g, s = np.array(g).T, np.array(s).T
    else:
        g, s = np.zeros((0, len(contacts))), np.zeros((0, int(slips.numel())))
    nan = np.full(n, np.nan)
    return Trajectory(
        t=run.t, q=run.q, v=run.v, lam=np.zeros((n, 0)), a=np.full((n, model.nv), np.nan), u=np.zeros((n, 0)),
        reaction=np.full((n, model.nv), np.nan), compulsion=nan, residual=np.zeros((n, 0)), g=np.zeros((n, 0)),
        margin=nan, energy=run.energy, work_reaction=nan.copy(), work_forces=nan.copy(), status=run.status,
        message=run.message, method="DOP853" if dt is None else "rk4", solver="friction", steps=n, rhs_evaluations=0,
        contact_force=run.N, events=tuple(run.events), gap=g, friction_force=run.F, slip=s,
        modes=tuple(tuple(m) for m in run.modes), lane="friction", failure=run.failure,
    )  # fmt: skip
