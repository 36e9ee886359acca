"""The symbolic pieces of one constraint on one mechanism: what a constraint hands to its realization."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca


@dataclass(frozen=True)
class ConstraintExpressions:
    """Symbolic pieces of one constraint on one mechanism.

    Attributes
    ----------
    Phi : (k,) SX
        The velocity-level constraint ``Φ(q, v, t)``.
    J : (k, nv) SX
        ``∂Φ/∂v``.
    phi : (k,) SX
        Right-hand side of ``J q̈ = φ``: ``−(∂Φ/∂q · q̇ + ∂Φ/∂t)``.
    g : (k,) SX or None
        The holonomic constraint ``g(q, t)``, if any.
    """

    Phi: ca.SX
    J: ca.SX
    phi: ca.SX
    g: ca.SX | None
