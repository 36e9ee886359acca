"""The contract of a QP backend.

Every backend solves the same reaction-space Gauss QP (docs/theory.md §3)::

    minimize   ½ uᵀ H u          (H = Dᵀ A⁻¹ D, so this is ½ Z)
    subject to S u = rhs         (S = J A⁻¹ D, rhs = φ − J a₀)

and returns ``u`` with the multipliers ``y`` of the equality rows, sign convention
``H u + Sᵀ y = 0``. A backend fulfils:

1. ``name`` — ``"route:solver"``, e.g. ``"casadi:qrqp"`` or ``"qpsolvers:daqp"``;
2. ``compiled`` — ``True`` if :meth:`graph` poses the QP inside a casadi graph, so that a
   whole step is one C call; otherwise :meth:`solve` is called from Python each step;
3. :meth:`solve` — numeric solve (every backend);
4. :meth:`graph` — symbolic solve on MX (compiled backends only).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import casadi as ca
import numpy as np


class QPBackend(ABC):
    """A QP solver behind the common contract (see the module docstring)."""

    name: str = ""
    compiled: bool = False
    description: str = ""

    @abstractmethod
    def solve(self, H: np.ndarray, S: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(u, y)``; raise :class:`~gausspp.errors.QPSolveError` if no solution was found."""

    def graph(self, H: ca.MX, S: ca.MX, rhs: ca.MX) -> tuple[ca.MX, ca.MX]:
        """Return symbolic ``(u, y)`` (compiled backends)."""
        raise NotImplementedError(f"{self.name} is not a compiled backend")

    def __repr__(self) -> str:
        return f"<QP backend {self.name}>"
