"""A frictional contact: a gap that must stay open or closed, and a slip velocity that Coulomb's law resists.

A contact of a planar motion is given by two functions of the generalized coordinates and velocities:

* the gap ``g(q) ≥ 0`` (open while positive), its normal Jacobian ``J_n = ∂ġ/∂v``;
* the slip ``s(q, v) = J_t(q) v``, the velocity of the contact point along the surface (one component).

While closed the surface pushes with ``N ≥ 0`` along ``J_nᵀ`` and resists slip with a tangential force ``F``
along ``J_tᵀ``: while sliding ``F = −μ N sign(s)`` (kinetic coefficient ``μ``); while sticking ``s = 0`` and
``|F| ≤ μ_s N`` (static coefficient ``μ_s ≥ μ``, default ``μ``). Restitution ``e`` is Newton's coefficient of
an impact that closes the contact (docs/friction.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from ..errors import InputError
from ..validation import number, short


def _coefficient(owner: str, name: str, value: Any, upper: float = math.inf) -> float:
    """``value`` as one finite number in ``[0, upper]``, or an error naming ``owner`` and the argument."""
    bound = "[0, 1]" if upper == 1.0 else "≥ 0"
    kind = f"in {bound}" if upper == 1.0 else bound
    x = float(number(f"{owner}: {name} must be a number, finite and {kind}, got {value!r}", value))
    if not 0.0 <= x <= upper:
        raise InputError(f"{owner}: {name} must be {bound}, got {value!r}")
    return x


class FrictionContact:
    """A unilateral contact with Coulomb friction (module docstring).

    Parameters
    ----------
    gap : callable ``q -> scalar``
        The gap, positive when open (casadi operations).
    slip : callable ``(q, v) -> scalar``
        The slip velocity of the contact point along the surface, linear in ``v``.
    mu : float
        Kinetic friction coefficient ``μ ≥ 0``, a finite number.
    mu_static : float, optional
        Static coefficient ``μ_s ≥ μ``, finite (default ``μ``).
    restitution : float in [0, 1]
        Newton's coefficient of an impact closing the contact (default 0: plastic).
    name : str, optional
    """

    def __init__(
        self,
        gap: Callable[..., Any],
        slip: Callable[..., Any],
        mu: float,
        *,
        mu_static: float | None = None,
        restitution: float = 0.0,
        name: str | None = None,
    ) -> None:
        self.name = "contact" if name is None else str(name)
        owner = f"FrictionContact {self.name!r}"
        for what, fn in (("gap", gap), ("slip", slip)):
            if not callable(fn):
                raise InputError(f"{owner}: {what} must be a function, got {fn!r}")
        self.gap, self.slip = gap, slip
        self.mu = _coefficient(owner, "mu", mu)
        self.mu_static = self.mu if mu_static is None else _coefficient(owner, "mu_static", mu_static)
        if self.mu_static < self.mu:
            raise InputError(f"{owner}: mu_static={self.mu_static:g} is below mu={self.mu:g}; static ≥ kinetic")
        self.restitution = _coefficient(owner, "restitution", restitution, upper=1.0)

    def __repr__(self) -> str:
        return f"FrictionContact(name={self.name!r}, mu={self.mu:g}, mu_static={self.mu_static:g})"


class JointFriction(FrictionContact):
    """Dry friction in a joint (MuJoCo's ``frictionloss``): a generalized force along the joint's velocity, bounded
    by a fixed ``bound`` instead of ``μ N``.

    While the joint sticks (its velocity ``s = J_t v`` held at zero) the force is whatever keeps it, within
    ``|F| ≤ bound``; while it slips ``F = −bound·sign(s)``. Among the frictional contacts it is a contact always
    closed, with no normal row, whose normal force is the constant ``bound`` and ``μ = μ_s = 1`` — so that the
    friction lane's modes, events (starts to slip, stops slipping) and records treat it as one; it takes no part in
    an impact (a bounded force gives no impulse).

    Parameters
    ----------
    slip : callable ``(q, v) -> scalar``
        The joint's velocity (linear in ``v``).
    bound : float
        The largest friction force or torque, ``> 0`` and finite.
    name : str, optional
    """

    dry = True

    def __init__(self, slip: Callable[..., Any], bound: float, *, name: str | None = None) -> None:
        label = "joint friction" if name is None else str(name)
        value = float(number(f"JointFriction {label!r}: bound must be a finite number > 0, got {bound!r}", bound))
        if not value > 0:
            raise InputError(f"JointFriction {label!r}: bound must be > 0, got {bound!r}")
        super().__init__(gap=lambda q: 0 * q[0], slip=slip, mu=1.0, name=label)
        self.bound = value

    def __repr__(self) -> str:
        return f"JointFriction(name={self.name!r}, bound={self.bound:g})"


def dry(contact: FrictionContact) -> bool:
    """Whether ``contact`` is a joint's dry friction (:class:`JointFriction`), not a contact."""
    return bool(getattr(contact, "dry", False))


def as_contacts(where: str, contacts: Any) -> list[FrictionContact]:
    """``contacts`` as a non-empty list of :class:`FrictionContact` (one contact alone: a list of one), or an error
    naming ``where`` it was passed."""
    if isinstance(contacts, FrictionContact):
        return [contacts]
    try:
        listed = list(contacts)
    except TypeError:
        listed = []
    if not listed or not all(isinstance(c, FrictionContact) for c in listed):
        raise InputError(
            f"{where}: contacts must be a gp.FrictionContact or a non-empty list of them, got {short(contacts)}"
        )
    return listed
