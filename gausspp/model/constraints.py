"""Constraints: velocity-level ``Φ(q, v, t) = 0`` and holonomic ``g(q, t) = 0``.

Along a motion a constraint is differentiated once more (paper eq. (11)):
``J q̈ = φ`` with ``J = ∂Φ/∂v`` and ``φ = −(∂Φ/∂q · q̇ + ∂Φ/∂t)``. A holonomic constraint
enters as ``Φ = ġ = ∂g/∂q · q̇ + ∂g/∂t`` and keeps ``g`` for drift correction.
How the constraint is *realized* — which reaction keeps it — is its ``realization``
(:mod:`gausspp.model.realizations`); the default is ideal.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca

from ..errors import InputError
from .constraint_expressions import ConstraintExpressions
from .mechanism import Mechanism
from .realizations import Realization, as_realization
from .symbolic import evaluate, require_affine_in


class Constraint:
    """A velocity-level constraint ``Φ(q, v, t) = 0`` with ``k`` components.

    Parameters
    ----------
    phi : callable ``(q, v, t) -> (k,)``
        The constraint function, written with casadi operations.
    name : str, optional
        Used in messages and reports.
    realization : Realization or str, optional
        How the constraint is kept (default: :class:`~gausspp.Ideal`).
    """

    def __init__(
        self,
        phi: Callable[..., Any],
        name: str | None = None,
        realization: Realization | str | None = None,
    ) -> None:
        if name is not None and not isinstance(name, str):
            raise InputError(f"{type(self).__name__}: name must be a string, got {name!r}")
        self._phi = _function(self, "phi", phi)
        self.name = name
        self.realization = as_realization(realization)

    def expressions(self, mech: Mechanism) -> ConstraintExpressions:
        """Build ``Φ``, ``J`` and ``φ`` on a mechanism's symbols.

        ``Φ`` must be affine in the velocities, ``∂²Φ/∂v² ≡ 0`` (checked symbolically): then
        ``J = ∂Φ/∂v`` does not depend on ``v``, the virtual displacements ``J δx = 0`` are those of
        the paper, and the projection onto ``Φ = 0`` is one linear solve.
        """
        what = f"{self._title}: Φ(q, v, t)"
        Phi = evaluate(self._phi, (mech.q, mech.v, mech.t), (None, 1), what)
        require_affine_in(Phi, mech.v, what)
        return _differentiate(Phi, mech, g=None)

    @property
    def _title(self) -> str:
        """How messages name the constraint: ``constraint 'rod'`` (or ``unnamed Constraint``)."""
        return (
            f"constraint {self.name!r}" if self.name is not None else f"unnamed {type(self).__name__} (give name=...)"
        )

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, realization={self.realization!r})"


class Holonomic(Constraint):
    """A position-level constraint ``g(q, t) = 0``, entering as ``Φ = ġ``.

    Parameters
    ----------
    g : callable ``(q, t) -> (k,)``
        The constraint function.
    name, realization :
        As for :class:`Constraint`.
    """

    def __init__(
        self,
        g: Callable[..., Any],
        name: str | None = None,
        realization: Realization | str | None = None,
    ) -> None:
        super().__init__(lambda q, v, t: None, name=name, realization=realization)
        self._g = _function(self, "g", g)  # ġ is affine in the velocities by construction

    def value(self, q: Any, t: Any) -> ca.SX:
        """``g(q, t)`` on casadi symbols (or numbers), checked to be a column."""
        return evaluate(self._g, (q, t), (None, 1), f"{self._title}: g(q, t)")

    def expressions(self, mech: Mechanism) -> ConstraintExpressions:
        g = self.value(mech.q, mech.t)
        Phi = ca.jacobian(g, mech.q) @ mech.qdot + ca.jacobian(g, mech.t)
        return _differentiate(Phi, mech, g=g)


class Unilateral(Holonomic):
    """A one-sided contact ``g(q, t) ≥ 0`` (non-penetration), kept ideally (paper §1, eq. (4)).

    While the contact is open (``g > 0``) it exerts nothing. When it is closed (``g = 0``)
    Gauss's principle with inequalities decides: the acceleration minimizes the compulsion
    subject to ``g̈ ≥ 0`` for every closed contact, so a contact pushes (``λ ≥ 0`` along
    ``∂g/∂q``) only while it would otherwise be penetrated, and lets go when the force would
    have to pull — complementarity from the QP's KKT conditions.

    When a contact closes with approaching speed the velocities jump (an impact): the
    post-impact velocities minimize the kinetic-energy distance ``½(v⁺ − v⁻)ᵀA(v⁺ − v⁻)``
    (Gauss's principle at the velocity level) subject to Newton's law ``ġ⁺ ≥ −e ġ⁻`` on the
    closed contacts, ``e`` the coefficient of restitution. For one degree of freedom the
    kinetic energy after the impact is ``e²`` times that before.

    Parameters
    ----------
    g : callable ``(q, t) -> (k,)``
        The gap function(s), positive when open.
    name : str, optional
    restitution : float in [0, 1]
        Newton's coefficient ``e`` (0 plastic, 1 elastic).
    """

    def __init__(self, g: Callable[..., Any], name: str | None = None, restitution: float = 0.0) -> None:
        super().__init__(g, name=name, realization=None)
        try:
            e = float(restitution)
        except (TypeError, ValueError):
            raise InputError(f"{self._title}: restitution must be a number, got {restitution!r}") from None
        if not 0.0 <= e <= 1.0:
            raise InputError(f"{self._title}: restitution must lie in [0, 1], got {restitution!r}")
        self.restitution = e

    def __repr__(self) -> str:
        return f"Unilateral(name={self.name!r}, restitution={self.restitution})"


def _function(owner: Constraint, what: str, fn: Any) -> Callable[..., Any]:
    """``fn`` if it can be called, else an error naming the constraint and the argument."""
    if not callable(fn):
        raise InputError(
            f"{type(owner).__name__}: {what} must be a function of the symbols (e.g. lambda q, v, t: v[1] - v[0]), "
            f"got {fn!r}"
        )
    return fn  # type: ignore[no-any-return]


def _differentiate(Phi: ca.SX, mech: Mechanism, g: ca.SX | None) -> ConstraintExpressions:
    J = ca.jacobian(Phi, mech.v)
    phi = -(ca.jacobian(Phi, mech.q) @ mech.qdot + ca.jacobian(Phi, mech.t))
    return ConstraintExpressions(Phi=Phi, J=J, phi=phi, g=g)
