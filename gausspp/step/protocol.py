"""What the step needs from a model: the :class:`StepModel` protocol.

The step layer never imports :mod:`gausspp.model`; it works on any object with these attributes.
:class:`gausspp.Model` is the one that provides them (assembled in :mod:`gausspp.model.assembly`),
so the import arrows point one way: ``model → step``.
"""

from __future__ import annotations

from typing import Any, NamedTuple, Protocol

import casadi as ca
import numpy as np

from .equality.expressions import StepExpressions


class Group(NamedTuple):
    """One constraint's block of the step: its rows of ``J``, columns of ``D``, and how to name it in messages."""

    name: str
    rows: slice
    cols: slice
    hint: str  # how to fix an unrealizable constraint (from its realization)
    label: str = ""  # the realization's name


class ContactExpressions(NamedTuple):
    """The unilateral contacts' gap ``g_c``, its Jacobian ``J_c``, the right-hand side ``φ_c`` and ``ġ_c``."""

    g: ca.SX
    J: ca.SX
    phi: ca.SX
    gdot: ca.SX


class StepModel(Protocol):
    """The assembled model as the step layer reads it (attributes documented on :class:`gausspp.Model`)."""

    mechanism: Any
    names: list[str]
    row_names: list[str]
    contact_row_names: list[str]
    groups: tuple[Group, ...]
    group_bounds: tuple[tuple[np.ndarray, np.ndarray] | None, ...]
    holonomic_rows: list[int]
    lam_columns: list[int]
    restitution: np.ndarray
    expressions: StepExpressions
    contact_expressions: ContactExpressions
    inputs: list[ca.SX]
    k: int
    m: int
    n_lam: int
    contacts: tuple[Any, ...]
    bounded: bool
    margin_warn: float
    margin_error: float
    refine: bool
    contact_tol: float
    nq: int
    nv: int
    route: str

    @property
    def lam0(self) -> np.ndarray | None:
        """``λ`` when the caller gives none (``None``: it must be given)."""
