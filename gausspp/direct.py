"""The direct multiplier solution (DESIGN §2): ``u = S⁻¹(φ − J a₀)``, ``q̈ = a₀ + A⁻¹ D u``.

The cross-check for every QP answer. It exists only when ``S = J A⁻¹ D`` is square and
nonsingular, i.e. as many reaction directions as constraint components and the
realizability conditions (12)/(16) hold.
"""

from __future__ import annotations

import casadi as ca

from .errors import InputError
from .step import Reduced


def direct_reaction(red: Reduced) -> ca.SX:
    """``u`` solving ``S u = φ − J a₀`` (symbolic)."""
    k, m = red.S.shape
    if k != m:
        raise InputError(
            f"solver='direct' needs as many reaction directions as constraint components, got {m} for {k}; "
            "use solver='qp', which finds the least-compulsion reaction"
        )
    return ca.solve(red.S, red.rhs)
