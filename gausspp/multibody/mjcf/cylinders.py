"""Cylinders in contact: the pairs whose contact stays on one piece of the cylinder, as a smooth gap.

A cylinder (axis ``a`` through its centre ``c``, radius ``r``, half-height ``h``) has two flat ends, two rims and a
curved side, and the distance to it changes formula from one to the next. gausspp maps a pair whose contact stays
on one piece at every state the joints allow — checked when the model loads, at the reference pose and
:data:`SAMPLES` − 1 states around it (each quantity below constant to :data:`CONSTANT_TOL` of the geoms' size) —
and refuses the others by name:

* **plane – cylinder** whose distance to the plane the joints cannot change (its centre's height and its axis's
  angle to the plane fixed: a decoration on a hinge, a wheel's hub): left out when it is apart at the reference —
  it can never touch — or touches without friction (a row with no gradient pushes nothing). Its distance is the
  support distance ``g = n·(c − p) − h|n·a| − r√(1 − (n·a)²)``.
* **cylinder – sphere/capsule** whose core (a sphere's centre, a capsule's segment) keeps one constant coordinate
  ``z`` along the cylinder's axis, inside ``[−h, h]``: it can meet the curved side only, and the gap is the distance
  from the axis point ``c + z a`` to the core, less both radii (a finger's capsule against a spinner's hub).
* **cylinder – cylinder** with axes parallel at every state and spans along them that overlap: side against side,
  the gap is the distance between the axes less both radii.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ...model.friction_contact import FrictionContact
from .segments import closest_points

#: States at which a pair's geometry is probed (the reference pose and random ones around it).
SAMPLES = 8
#: A probed quantity varying by less than this times the geoms' size is constant.
CONSTANT_TOL = 1e-9
PLANE, SPHERE, CAPSULE, CYLINDER = 0, 2, 3, 5


def cylinder_pair(builder: Any, name: str, A: Any, B: Any, mu: float) -> list[FrictionContact]:
    """The contacts of a pair with a cylinder (``A`` the plane or the cylinder; module docstring), or none — the
    problem said to ``builder.load`` where the pair is not mapped."""
    probe = _Probe(builder)
    if A.kind == PLANE:
        return _on_plane(builder, probe, name, A, B, mu)
    if B.kind == CYLINDER:
        return _parallel(builder, probe, name, A, B, mu)
    return _side(builder, probe, name, A, B, mu)


class _Probe:
    """Values of expressions of ``q`` at the reference pose and random states around it."""

    def __init__(self, builder: Any) -> None:
        self.q = builder.tree.q
        q0 = np.array(builder.load.m.qpos0, float)
        rng = np.random.default_rng(1989)
        self.states = [q0] + [
            builder.tree.normalize_array(q0 + 0.5 * rng.standard_normal(q0.size)) for _ in range(SAMPLES - 1)
        ]

    def values(self, expr: Any) -> np.ndarray:
        fn = ca.Function("probe", [self.q], [ca.vec(ca.SX(expr))])
        return np.array([np.array(fn(q), float).ravel() for q in self.states])

    def constant(self, expr: Any, scale: float) -> tuple[bool, np.ndarray]:
        """Whether ``expr`` is constant over the states (to :data:`CONSTANT_TOL` of ``scale``), and its value at the
        reference."""
        v = self.values(expr)
        return bool(np.ptp(v, axis=0).max(initial=0.0) <= CONSTANT_TOL * scale), v[0]


KIND_NAMES = {PLANE: "plane", SPHERE: "sphere", CAPSULE: "capsule", CYLINDER: "cylinder"}


def _refuse(builder: Any, name: str, kinds: tuple[Any, Any], why: str) -> list[FrictionContact]:
    geoms = "–".join(repr(part) for part in name.split("–"))
    pair = "–".join(KIND_NAMES[g.kind] for g in kinds)
    builder.load.problem(
        f"geoms {geoms} could collide ({pair}) {why}: not mapped (gausspp keeps a cylinder's contact where it stays "
        "on its side, or where it never comes); exclude the pair (<exclude>, contype/conaffinity) or pass "
        "contacts='ignore'"
    )
    return []


def _on_plane(builder: Any, probe: _Probe, name: str, plane: Any, cyl: Any, mu: float) -> list[FrictionContact]:
    n, a = plane.R[:, 2], cyl.R[:, 2]
    r, h = float(cyl.size[0]), float(cyl.size[1])
    na = ca.dot(n, a)
    gap = ca.dot(n, cyl.x - plane.x) - h * ca.fabs(na) - r * ca.sqrt(ca.fmax(1 - na**2, 0))
    fixed, g0 = probe.constant(gap, r + h)
    if not fixed:
        return _refuse(
            builder,
            name,
            (plane, cyl),
            "with a cylinder that moves relative to the plane (its end, rim and side take turns)",
        )
    if g0[0] > CONSTANT_TOL * (r + h) or mu == 0.0:
        return []  # apart for ever, or touching without friction along a row with no gradient: no force
    return _refuse(
        builder, name, "touching the plane with friction where the joints give it no motion along the normal"
    )


def _side(builder: Any, probe: _Probe, name: str, cyl: Any, other: Any, mu: float) -> list[FrictionContact]:
    a, c, h = cyl.R[:, 2], cyl.x, float(cyl.size[1])
    half = other.R[:, 2] * (float(other.size[1]) if other.kind == CAPSULE else 0.0)
    ends = (other.x - half, other.x + half)
    along = ca.vertcat(ca.dot(a, ends[0] - c), ca.dot(a, ends[1] - c))
    scale = float(cyl.size[:2].sum() + other.size[:2].sum())
    fixed, z0 = probe.constant(along, scale)
    if not (fixed and abs(z0[0] - z0[1]) <= CONSTANT_TOL * scale and abs(z0[0]) <= h):
        return _refuse(
            builder,
            name,
            (cyl, other),
            "where the cylinder's end or rim may be reached (the other's core does not stay beside its side)",
        )
    on_axis = c + along[0] * a
    _, core = closest_points(on_axis, on_axis, ends[0], ends[1])
    return [builder.between(name, cyl, other, on_axis, core, mu)]


def _parallel(builder: Any, probe: _Probe, name: str, A: Any, B: Any, mu: float) -> list[FrictionContact]:
    a, b = A.R[:, 2], B.R[:, 2]
    hA, hB = float(A.size[1]), float(B.size[1])
    scale = float(A.size[:2].sum() + B.size[:2].sum())
    z = ca.dot(a, B.x - A.x)  # B's centre along A's axis
    fixed, values = probe.constant(ca.vertcat(ca.cross(a, b), z), scale)
    if not (fixed and np.abs(values[:3]).max() <= CONSTANT_TOL and abs(values[3]) <= hA + hB):
        return _refuse(builder, name, (A, B), "where the axes turn or the spans part (ends or rims may meet)")
    level = float(np.clip(values[3], -hA, hA))  # an axial coordinate both spans share
    on_a = A.x + level * a
    on_b = B.x + (level - z) * ca.dot(a, b) * b
    return [builder.between(name, A, B, on_a, on_b, mu)]
