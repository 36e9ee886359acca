"""The velocity jump when contacts close: Gauss's principle one level down (docs/theory.md §6).

The post-impact velocities minimize ``½(v⁺ − v⁻)ᵀA(v⁺ − v⁻)`` — the same QP as the step with ``v⁻``
in the place of ``a₀`` and impulses in the place of forces.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from . import impact_qp
from .data import evaluate
from .general import solve_general
from .general.model_qp import closed_rows, gauss_problem
from .protocol import StepModel
from .results import ImpactResult


def impact(
    model: StepModel,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    backend: str | None = None,
    plastic: Any = (),
    closed: Any = None,
) -> ImpactResult:
    """The impact on checked inputs (see :meth:`gausspp.Model.impact`)."""
    if model.bounded:
        raise InputError("impacts with bounded actuators are not supported: a bounded force cannot deliver an impulse")
    d = evaluate(model, t, q, v, lam)
    closed = closed_rows(model, d.gc, closed)
    e = model.restitution[closed].copy()
    e[np.isin(closed, np.asarray(plastic, dtype=int))] = 0.0
    Jcc = d.Jc[closed].reshape(closed.size, model.nv)
    target = -e * np.minimum(d.gdotc[closed], 0.0)  # ġ⁺ ≥ target
    # the same problem one level down: v⁻ plays a₀, impulses play forces, the rows act on v⁺
    phi = d.J @ v - d.Phi
    impulse = np.zeros(len(model.contact_row_names))
    fast = impact_qp.ideal_impact(model, backend, d.A, v, d.J, phi, Jcc, Jcc @ v - d.gdotc[closed] + target)
    if fast is not None:  # ideal rows: one QP in v⁺, verified (else the general step below)
        v_after, lam_after = fast[0], lam
        impulse[closed] = fast[2]
    else:
        problem = gauss_problem(model, t, d.A, v, d.J, phi, d.D, d.Jc, Jcc @ v - d.gdotc[closed] + target, closed)
        sol = solve_general(problem, backend)
        impulse[closed] = sol.u[model.m :]
        v_after = sol.a
        lam_after = lam + sol.u[: model.m][model.lam_columns] if model.n_lam else lam
    return ImpactResult(
        t=t,
        v_before=v,
        v_after=v_after,
        lam_after=lam_after,
        impulse=impulse,
        closed=closed,
        kinetic_energy_before=0.5 * float(v @ d.A @ v),
        kinetic_energy_after=0.5 * float(v_after @ d.A @ v_after),
    )
