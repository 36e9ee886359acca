"""Models derived from a model: a contact phase, a subset of the constraints; and the contact gaps.

An event-driven simulation needs, between two events, the model with the closed contacts as ideal
bilateral constraints (:func:`phase_model`); the verification of a saturated interval needs the model
without the saturated actuators (:func:`sub_model`). Both are built once per model and key, and kept in
the model's workspace (:mod:`gausspp.workspace`).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..step.equality.kernel import Bound, dense_outputs, load_inputs
from ..workspace import workspace
from .constraints import Holonomic
from .model import Model


def _like(model: Model, constraints: list[Any]) -> Model:
    """A model on the same mechanism with the same options and these constraints (possibly none)."""
    return Model(
        model.mechanism,
        constraints,
        margin_warn=model.margin_warn,
        margin_error=model.margin_error,
        refine=model.refine,
        route=model.route_requested,
        codegen=model.codegen,
    )


def _contact_rows(model: Model) -> list[Holonomic]:
    """One ideal holonomic constraint per contact row, named ``contact NAME``."""
    rows = []
    for c, name, k in zip(model.contacts, model.contact_names, model.contact_rows, strict=True):
        for j in range(k):
            row_name = name if k == 1 else f"{name}[{j}]"

            def gap(q: Any, t: Any, c: Holonomic = c, j: int = j) -> Any:
                return c.value(q, t)[j]

            rows.append(Holonomic(gap, name=f"contact {row_name}"))
    return rows


def phase_model(model: Model, active: tuple[int, ...]) -> Model:
    """The model with the contact rows ``active`` closed: ideal bilateral constraints after the model's own."""

    def build() -> Model:
        rows = _contact_rows(model)
        return _like(model, [*model.constraints, *(rows[i] for i in active)])

    return workspace(model).get(("phase-model", tuple(active)), build)


def sub_model(model: Model, keep: tuple[int, ...]) -> Model:
    """The model with only the bilateral constraints ``keep`` (indices into ``model.constraints``)."""
    return workspace(model).get(("sub-model", tuple(keep)), lambda: _like(model, [model.constraints[i] for i in keep]))


def gaps(model: Model, t: float, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The contact rows' gaps ``g_c(q, t)`` and gap rates ``ġ_c`` at a state (one buffer-bound C call)."""

    def build() -> Bound:
        mech, c = model.mechanism, model.contact_expressions
        fn = ca.Function("contact_gaps", [mech.t, mech.q, mech.v], [c.g, c.gdot])
        return Bound(
            ca.Function("contact_gaps", [mech.t, mech.q, mech.v], dense_outputs(fn.call([mech.t, mech.q, mech.v])))
        )

    bound = workspace(model).get(("contact-gaps",), build)
    load_inputs(bound.args, (t, q, v))
    bound.eval()
    return bound.res[0].copy(), bound.res[1].copy()
