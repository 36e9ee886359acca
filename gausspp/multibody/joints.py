"""Joints as position-level constraint rows ``g(q) = 0`` between two bodies (or a body and the ground).

Every joint names the point it joins on each body (``local``: from the centre of mass, in body axes); ``b = None``
is the ground, whose "local" coordinates are space coordinates. Each row is one :class:`gausspp.Holonomic` named
``"<kind> <name> [<row>]"`` — e.g. ``"revolute crank-coupler [x]"`` — so that reactions, residuals and
realizations read by joint.

Planar (bodies ``(x, y, θ)``):

* **revolute** — the two points coincide: ``P_a − P_b = 0`` (rows ``x``, ``y``);
* **prismatic** — the relative angle is kept, ``θ_a − θ_b − θ₀ = 0``, and ``P_b`` stays on the line through ``P_a``
  along ``R_a e`` (``e`` the axis in ``a``'s axes): ``(R_a n)·(P_b − P_a) = 0`` with ``n ⊥ e`` (rows ``angle``,
  ``normal``);
* **on a curve** — the point ``P_a`` on ``f(x, y) = 0`` (one row).

Spatial (bodies with a quaternion):

* **spherical** — ``P_a − P_b = 0`` (``x``, ``y``, ``z``);
* **revolute** — spherical, and the axis ``R_b e_b`` perpendicular to two directions ``R_a u₁``, ``R_a u₂`` normal
  to ``R_a e_a`` (``axis·u1``, ``axis·u2``): five rows;
* **universal** — spherical, and the two axes perpendicular, ``(R_a e_a)·(R_b e_b) = 0``: four rows;
* **cylindrical** — ``P_b`` on the line through ``P_a`` along ``R_a e_a`` (``normal u1``, ``normal u2``) and the
  axes parallel as for the revolute: four rows;
* **prismatic** — cylindrical, and the turn about the axis kept: ``(R_a u₁)·(R_b R₀ᵀ u₂) = 0`` with ``R₀`` the
  relative rotation at the guess (``twist``): five rows;
* **fixed** (weld) — spherical, and the relative rotation ``R_aᵀ R_b = R₀`` kept through three rows
  ``(R_a e_i)·(R_b R₀ᵀ e_j) = 0``, ``(i, j) = (2, 3), (3, 1), (1, 2)``: six rows;
* **on a surface** — ``f(P_a) = 0`` (one row).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError
from .bodies import Body

#: A row function of the whole configuration (and time).
Row = Callable[[Any, Any], Any]


def place(body: Body | None, q: Any, local: np.ndarray) -> Any:
    """The point ``local`` of ``body`` in space (of the ground: ``local`` itself)."""
    return ca.DM(local) if body is None else body.point(q, local)


def rotation(body: Body | None, q: Any, dim: int) -> Any:
    """The body's rotation (body → space); the ground's is the identity."""
    return ca.DM.eye(dim) if body is None else body.parts(q)[1]


def angle(body: Body | None, q: Any) -> Any:
    """A planar body's angle (the ground's: 0)."""
    return 0.0 if body is None else q[body.q_start + 2]


def normals(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors normal to ``axis`` and to each other (a fixed, well-conditioned choice)."""
    e = axis / np.linalg.norm(axis)
    helper = np.eye(3)[int(np.argmin(np.abs(e)))]
    u1 = np.cross(e, helper)
    u1 /= np.linalg.norm(u1)
    return u1, np.cross(e, u1)


def unit(owner: str, axis: Any, dim: int) -> np.ndarray:
    e = np.asarray(axis, float)
    if e.shape != (dim,) or not np.all(np.isfinite(e)) or not np.linalg.norm(e) > 0:
        raise InputError(f"{owner}: axis must be a nonzero vector of {dim} numbers, got {axis!r}")
    return e / np.linalg.norm(e)


def coincide(a: Body, pa: np.ndarray, b: Body | None, pb: np.ndarray, dim: int) -> list[tuple[str, Row]]:
    """The rows ``P_a − P_b = 0``."""
    axes = "xyz"[:dim]
    return [(axes[i], lambda q, t, i=i: (place(a, q, pa) - place(b, q, pb))[i]) for i in range(dim)]


def planar_prismatic(
    a: Body, pa: np.ndarray, b: Body | None, pb: np.ndarray, axis: np.ndarray, theta0: float
) -> list[tuple[str, Row]]:
    n = ca.DM([-axis[1], axis[0]])

    def normal(q: Any, t: Any) -> Any:
        return ca.dot(rotation(a, q, 2) @ n, place(b, q, pb) - place(a, q, pa))

    return [("angle", lambda q, t: angle(a, q) - angle(b, q) - theta0), ("normal", normal)]


def aligned(a: Body, ea: np.ndarray, b: Body | None, eb: np.ndarray) -> list[tuple[str, Row]]:
    """``R_b e_b`` parallel to ``R_a e_a``: perpendicular to ``R_a u₁`` and ``R_a u₂``."""
    u1, u2 = normals(ea)
    return [
        (f"axis·u{k}", lambda q, t, u=u: ca.dot(rotation(a, q, 3) @ ca.DM(u), rotation(b, q, 3) @ ca.DM(eb)))
        for k, u in ((1, u1), (2, u2))
    ]


def on_line(a: Body, pa: np.ndarray, b: Body | None, pb: np.ndarray, ea: np.ndarray) -> list[tuple[str, Row]]:
    """``P_b`` on the line through ``P_a`` along ``R_a e_a``."""
    u1, u2 = normals(ea)

    def row(u: np.ndarray) -> Row:
        return lambda q, t: ca.dot(rotation(a, q, 3) @ ca.DM(u), place(b, q, pb) - place(a, q, pa))

    return [("normal u1", row(u1)), ("normal u2", row(u2))]


def kept_rotation(a: Body, b: Body | None, R0: np.ndarray, pairs: list[tuple[int, int]]) -> list[tuple[str, Row]]:
    """Rows ``(R_a e_i)·(R_b R₀ᵀ e_j) = 0``: the relative rotation ``R_aᵀ R_b`` held at ``R₀`` (to first order)."""
    E = np.eye(3)

    def row(i: int, j: int) -> Row:
        target = ca.DM(R0.T @ E[j])
        return lambda q, t: ca.dot(rotation(a, q, 3) @ ca.DM(E[i]), rotation(b, q, 3) @ target)

    return [(f"turn {'xyz'[i]}{'xyz'[j]}", row(i, j)) for i, j in pairs]


def relative_rotation(a: Body, b: Body | None) -> np.ndarray:
    """``R_aᵀ R_b`` at the bodies' guesses."""
    Ra = np.array(ca.DM(a.parts(ca.DM(_guess_vector(a)))[1]))
    Rb = np.eye(3) if b is None else np.array(ca.DM(b.parts(ca.DM(_guess_vector(b)))[1]))
    return Ra.T @ Rb


def _guess_vector(body: Body) -> np.ndarray:
    """A state vector holding ``body``'s guess at its place (zeros elsewhere)."""
    q = np.zeros(body.q_start + body.nq)
    q[body.q_start :] = body.guess
    return q
