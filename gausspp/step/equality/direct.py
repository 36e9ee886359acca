"""The direct multiplier solution (docs/theory.md §2): ``u = S⁻¹(φ − J a₀)``, ``q̈ = a₀ + A⁻¹ D u``.

The cross-check for every QP answer. It exists only when ``S = J A⁻¹ D`` is square and
nonsingular, i.e. as many reaction directions as constraint components and the
realizability conditions (12)/(16) hold.
"""

from __future__ import annotations

import casadi as ca

from ...errors import InputError
from .expressions import Reduced


def direct_reaction(red: Reduced) -> ca.SX:
    """The whitened reaction ``z = R_D u`` solving ``Ŝ z = L_J⁻¹(φ − J a₀)`` (symbolic).

    ``Ŝ`` is ``S`` with the scales of ``J`` and ``D`` in the kinetic metric divided out; its
    condition number is ``1/margin``, whereas ``S`` inherits the condition number of ``A``.
    """
    require_square(*red.S_hat.shape)
    return ca.solve(red.S_hat, red.rhs_hat)


def require_square(k: int, m: int) -> None:
    """The direct solution needs ``S`` square: as many reaction directions ``m`` as constraint rows ``k``."""
    if k != m:
        raise InputError(
            f"solver='direct' needs as many reaction directions as constraint components, got {m} for {k}; "
            "use solver='qp', which finds the least-compulsion reaction"
        )
