"""The contract of a QP backend, and the QP forms the project solves.

Two forms (docs/theory.md §3):

* the **equality** form of the compiled step, in reaction space::

      minimize   ½ uᵀ H u          (H = Dᵀ A⁻¹ D, so this is ½ Z)
      subject to S u = rhs         (S = J A⁻¹ D, rhs = φ − J a₀)

  solved by :meth:`QPBackend.solve` (numbers) or :meth:`QPBackend.graph` (inside a casadi graph),
  returning ``u`` and the multipliers ``y`` of the rows, sign convention ``H u + Sᵀ y = 0``;
* the **general** form of :mod:`gausspp.step.general`'s stages, a :class:`QP`::

      minimize ½ xᵀ P x + qᵀ x   subject to   E x = e,   G x ≤ h,   lo ≤ x ≤ hi

  solved by :meth:`QPBackend.solve_qp`. Its *features* (:data:`FORMS`) are what a stage uses
  beyond the equality form: ``"bounds"`` (finite ``lo``/``hi``), ``"inequalities"`` (rows of
  ``G``), ``"least-squares"`` (a linear term ``q``, the tracking stage). A backend declares the
  features it solves in :attr:`QPBackend.forms`; the registry (:mod:`gausspp.step.qp`) refuses a
  backend for a problem it cannot solve, naming those that can.

A backend fulfils:

1. ``name`` — ``"family:solver"``, e.g. ``"casadi:qrqp"`` or ``"qpsolvers:daqp"``;
2. ``compiled`` — ``True`` if :meth:`graph` poses the QP inside a casadi graph, so that a
   whole step is one C call; otherwise :meth:`solve` is called from Python each step;
3. ``forms`` — the features of the general form it solves (:data:`FORMS`; ``"equality"`` alone: none);
4. :meth:`solve` — numeric solve of the equality form (every backend);
5. :meth:`graph` — symbolic solve on MX (compiled backends only);
6. :meth:`solve_qp` — numeric solve of the general form (backends whose ``forms`` say so).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import casadi as ca
import numpy as np

#: The QP forms: the equality form every backend solves, and the general form's features.
FORMS = ("equality", "bounds", "inequalities", "least-squares")
#: Every form: what a backend that solves the general form declares.
ALL_FORMS = frozenset(FORMS)


@dataclass
class QP:
    """``min ½xᵀPx + qᵀx`` s.t. ``E x = e``, ``G x ≤ h``, ``lo ≤ x ≤ hi`` (``name``: for messages)."""

    P: np.ndarray
    q: np.ndarray
    E: np.ndarray
    e: np.ndarray
    G: np.ndarray
    h: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    name: str = "QP"

    @property
    def features(self) -> frozenset[str]:
        """The forms this problem needs (:data:`FORMS`): always ``"equality"``, and what else it uses."""
        used = {"equality"}
        if np.any(np.isfinite(self.lo)) or np.any(np.isfinite(self.hi)):
            used.add("bounds")
        if self.G.size:
            used.add("inequalities")
        if np.any(self.q):
            used.add("least-squares")
        return frozenset(used)


@dataclass(frozen=True)
class QPAnswer:
    """A backend's answer to a :class:`QP`.

    Attributes
    ----------
    x : (m,) array or None   the point (``None``: the backend found none)
    dual : float             ``max |P x + q + Eᵀ y + Gᵀ z + z_box|`` from the backend's multipliers
                             (NaN when it reports none)
    found : bool             the backend calls the point a solution (not merely its last iterate)
    """

    x: np.ndarray | None
    dual: float = float("nan")
    found: bool = True


class QPBackend(ABC):
    """A QP solver behind the common contract (see the module docstring)."""

    name: str = ""
    compiled: bool = False
    description: str = ""
    forms: frozenset[str] = frozenset({"equality"})

    @abstractmethod
    def solve(self, H: np.ndarray, S: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(u, y)``; raise :class:`~gausspp.errors.QPSolveError` if no solution was found."""

    def graph(self, H: ca.MX, S: ca.MX, rhs: ca.MX) -> tuple[ca.MX, ca.MX]:
        """Return symbolic ``(u, y)`` (compiled backends)."""
        raise NotImplementedError(f"{self.name} is not a compiled backend")

    def solve_qp(self, problem: QP) -> QPAnswer:
        """Solve the general form (backends whose :attr:`forms` include its features)."""
        raise NotImplementedError(f"{self.name} solves the equality form only")

    def __repr__(self) -> str:
        return f"<QP backend {self.name}>"
