"""The step's numbers at one state, as one typed structure: :class:`StepData`.

One compiled function (kept in the model's workspace) evaluates everything the general step,
the projection onto the constraints and the impact law read at a state ``(t, q, v, λ)`` with
Baumgarte terms ``stab = (α, β)``: the step ``A q̈ = f + r₀ + D u``, ``J q̈ = φ`` (docs/theory.md §2),
the constraint values ``Φ`` and ``g``, the kinematics ``q̇``, the energy and the power of the
non-conservative forces, and the unilateral contacts' ``g_c, J_c, φ_c, ġ_c``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..model.workspace import workspace
from .kernel import Bound, dense_outputs, load_inputs
from .protocol import StepModel

NO_STAB = np.zeros(2)


@dataclass(frozen=True)
class StepData:
    """The step at one state, as arrays in their natural shapes.

    Attributes
    ----------
    A : (nv, nv)
        Mass matrix.
    f : (nv,)
        ``F − h``: applied minus gyroscopic/Coriolis forces.
    r0 : (nv,)
        The realizations' known reaction part.
    J : (k, nv), phi : (k,)
        The bilateral rows ``J q̈ = φ`` (with the Baumgarte terms of ``stab``).
    D : (nv, m)
        The realizations' reaction directions.
    Phi, g : (k,)
        The constraints' values ``Φ(q, v, t)`` and holonomic residuals ``g(q, t)`` (0 on other rows).
    qdot : (nq,)
        ``q̇`` from the kinematics.
    energy, power : float
        Mechanical energy (0 if the mechanism has none) and power of the non-conservative forces.
    gc, Jc, phic, gdotc : (nc,), (nc, nv), (nc,), (nc,)
        The unilateral contacts' gaps, Jacobian, right-hand side and gap rates.
    """

    A: np.ndarray
    f: np.ndarray
    r0: np.ndarray
    J: np.ndarray
    phi: np.ndarray
    D: np.ndarray
    Phi: np.ndarray
    g: np.ndarray
    qdot: np.ndarray
    energy: float
    power: float
    gc: np.ndarray
    Jc: np.ndarray
    phic: np.ndarray
    gdotc: np.ndarray


_FIELDS = tuple(StepData.__dataclass_fields__)


def _build(model: StepModel) -> Bound:
    p, mech, c = model.expressions, model.mechanism, model.contact_expressions
    outputs = [
        p.A,
        p.f,
        p.r0,
        p.J,
        p.phi,
        p.D,
        p.Phi,
        p.g if p.g is not None else ca.SX.zeros(model.k),
        mech.qdot,
        mech.energy if mech.energy is not None else ca.SX(0),
        ca.dot(mech.v, mech.F_nc) if mech.F_nc is not None else ca.SX(0),
        c.g,
        c.J,
        c.phi,
        c.gdot,
    ]
    fn = ca.Function("step_data", model.inputs, outputs)
    return Bound(ca.Function("step_data", model.inputs, dense_outputs(fn.call(model.inputs))))


def evaluate(
    model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, stab: Any = NO_STAB
) -> StepData:
    """:class:`StepData` at ``(t, q, v, λ)`` (inputs already checked; no checks on the values)."""
    bound = workspace(model).get(("step-data",), lambda: _build(model))
    load_inputs(bound.args, (t, q, v, lam, stab))
    bound.eval()
    values: dict[str, Any] = {}
    for i, (name, raw) in enumerate(zip(_FIELDS, bound.res, strict=True)):
        rows, cols = bound.fn.size_out(i)
        if name in ("energy", "power"):
            values[name] = float(raw[0])
        elif name in ("A", "J", "D", "Jc"):
            values[name] = raw.reshape((rows, cols), order="F").copy()
        else:
            values[name] = raw.copy()
    return StepData(**values)
