"""The geom pairs MuJoCo would let collide, as hard frictional contacts (:class:`gausspp.FrictionContact`).

**Which pairs.** MuJoCo's own filters (``engine_collision_driver.c``): explicit ``<pair>`` elements, then every two
geoms on bodies that are not welded together and not both without degrees of freedom, whose
``contype``/``conaffinity`` bits match, past the parent filter (unless disabled) and ``<exclude>``.

**Which contacts.** Each pair gives one or more contact points, each a gap ``g(q) ≥ 0`` (the distance between the
two surfaces along the normal ``n``) and a two-component slip: the relative velocity of the two material points at
the contact, on two unit tangents ``t₁, t₂ ⟂ n``.

==========================  ===========================================================================================
pair                        contact points
==========================  ===========================================================================================
plane – sphere              the centre: ``g = n·(c − p) − r``
plane – capsule             the two end spheres of its segment (a capsule lying flat rests on both)
plane – box                 the eight corners
plane – ellipsoid           the support point: ``g = n·(c − p) − ‖diag(a) Rᵀ n‖``
sphere/capsule – sphere/    the closest points of the two segments (a sphere's is one point):
capsule                     ``g = ‖c₂ − c₁‖ − r₁ − r₂``, ``n = (c₂ − c₁)/‖c₂ − c₁‖``, tangents from a reference axis
                            chosen at ``qpos0`` far from ``n`` (they turn with ``n``; undefined only where ``n``
                            reaches that axis)
==========================  ===========================================================================================

Other pairs (a cylinder, a box against anything but a plane, meshes, height fields) are refused by name.

**Friction.** Coulomb's coefficient is MuJoCo's ``friction[0]`` of the pair: an explicit pair's own, else the geom of
higher ``priority``'s, else the larger of the two; ``condim = 1`` (the larger of the two geoms') is frictionless
(``μ = 0``). MuJoCo's torsional and rolling friction (``condim`` 4, 6) are refused by name. MuJoCo's contacts are soft
(``solref``, ``solimp``) and act from ``margin`` on; gausspp's are hard: the gap never goes below zero, and
``margin``/``gap`` are not used.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ...model.friction_contact import FrictionContact
from .context import Loading
from .cylinders import cylinder_pair
from .segments import closest_points
from .tree import JointTree, constant_rotation, frames

PLANE, HFIELD, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX = 0, 1, 2, 3, 4, 5, 6
ROUND = (SPHERE, CAPSULE)


def colliding_pairs(load: Loading) -> list[tuple[int, int, int]]:
    """``(geom1, geom2, pair)`` for every pair MuJoCo's filters let through (``pair`` the explicit pair's index, or
    −1), whatever their distance."""
    m = load.m
    if load.disabled("CONTACT", "CONSTRAINT"):
        return []
    pairs = [(int(a), int(b), p) for p, (a, b) in enumerate(zip(m.pair_geom1, m.pair_geom2, strict=True))]
    g1, g2 = np.triu_indices(m.ngeom, 1)
    weld, parent, dofs = np.asarray(m.body_weldid), np.asarray(m.body_parentid), np.asarray(m.body_dofnum)
    b1, b2 = np.asarray(m.geom_bodyid)[g1], np.asarray(m.geom_bodyid)[g2]
    w1, w2 = weld[b1], weld[b2]
    keep = (w1 != w2) & ((dofs[w1] > 0) | (dofs[w2] > 0))
    if not load.disabled("FILTERPARENT"):
        keep &= ~((w1 != 0) & (w2 != 0) & ((w1 == weld[parent[w2]]) | (w2 == weld[parent[w1]])))
    contype, conaffinity = np.asarray(m.geom_contype), np.asarray(m.geom_conaffinity)
    keep &= ((contype[g1] & conaffinity[g2]) | (contype[g2] & conaffinity[g1])) != 0
    signature = (np.minimum(b1, b2).astype(np.int64) << 16) + np.maximum(b1, b2)
    keep &= ~np.isin(signature, np.asarray(m.exclude_signature, np.int64))
    explicit = {(min(a, b), max(a, b)) for a, b, _ in pairs}
    pairs += [(int(a), int(b), -1) for a, b in zip(g1[keep], g2[keep], strict=True) if (int(a), int(b)) not in explicit]
    return pairs


@dataclass
class Geom:
    """A geom's centre and axes (world) as expressions of ``q``, and the velocity of a point fixed in it."""

    kind: int
    size: np.ndarray
    x: Any
    R: Any
    body_x: Any
    body_v: Any
    omega: Any

    def velocity(self, point: Any) -> Any:
        """The velocity of the material point of the geom's body now at ``point``."""
        return self.body_v + ca.cross(self.omega, point - self.body_x)


class ContactBuilder:
    """The frictional contacts of a loaded tree (module docstring)."""

    def __init__(self, load: Loading, tree: JointTree) -> None:
        self.load, self.tree = load, tree
        self.fr = frames(tree.bodies, tree.q, tree.v)

    def geom(self, g: int) -> Geom:
        m, tree = self.load.m, self.tree
        b = int(m.geom_bodyid[g])
        if b == 0:
            x_b, R_b, w = ca.SX.zeros(3), ca.SX.eye(3), ca.SX.zeros(3)
        else:
            x_b, R_b, w = self.fr.x[b - 1], self.fr.R[b - 1], self.fr.omega[b - 1]
        v_b = ca.jtimes(x_b, tree.q, tree.qdot) if b else ca.SX.zeros(3)
        x = x_b + R_b @ ca.DM(np.array(m.geom_pos[g], float))
        R = R_b @ constant_rotation(np.array(m.geom_quat[g], float))
        return Geom(int(m.geom_type[g]), np.array(m.geom_size[g], float), x, R, x_b, v_b, w)

    def contacts(self) -> list[FrictionContact]:
        load, m = self.load, self.load.m
        out: list[FrictionContact] = []
        for a, b, p in colliding_pairs(load):
            ga, gb = int(m.geom_type[a]), int(m.geom_type[b])
            if gb == PLANE and ga != PLANE:
                a, b, ga, gb = b, a, gb, ga
            na, nb = load.names.of("geom", a), load.names.of("geom", b)
            mu, condim = self.friction(a, b, p)
            if condim > 3:
                load.problem(f"geoms {na!r}–{nb!r}: condim {condim} (torsional/rolling friction) is not mapped")
                continue
            if condim == 1:
                mu = 0.0
            name = f"{na}–{nb}"
            if gb == CYLINDER and ga != PLANE:  # the cylinder first
                a, b, ga, gb = b, a, gb, ga
            if ga == PLANE and gb in (SPHERE, CAPSULE, BOX, ELLIPSOID):
                out += self.on_plane(name, self.geom(a), self.geom(b), mu)
            elif ga in ROUND and gb in ROUND:
                out.append(self.round_pair(name, self.geom(a), self.geom(b), mu))
            elif CYLINDER in (ga, gb) and {ga, gb} <= {PLANE, SPHERE, CAPSULE, CYLINDER}:
                out += cylinder_pair(self, name, self.geom(a), self.geom(b), mu)
            else:
                kinds = "–".join(load.mj.mjtGeom(k).name[7:].lower() for k in (ga, gb))
                load.problem(
                    f"geoms {na!r}–{nb!r} could collide ({kinds}): gausspp's contacts are planes against spheres, "
                    "capsules, boxes and ellipsoids, and spheres/capsules against each other; exclude the pair "
                    "(<exclude>, contype/conaffinity) or pass contacts='ignore'"
                )
        return out

    def friction(self, a: int, b: int, p: int) -> tuple[float, int]:
        m = self.load.m
        if p >= 0:
            return float(m.pair_friction[p][0]), int(m.pair_dim[p])
        pa, pb = int(m.geom_priority[a]), int(m.geom_priority[b])
        if pa != pb:
            w = a if pa > pb else b
            return float(m.geom_friction[w][0]), int(m.geom_condim[w])
        return max(float(m.geom_friction[a][0]), float(m.geom_friction[b][0])), max(
            int(m.geom_condim[a]), int(m.geom_condim[b])
        )

    # -- contact points ----------------------------------------------------------------------------------------
    def _contact(self, name: str, gap: Any, slip: Any, mu: float) -> FrictionContact:
        q, v = self.tree.q, self.tree.v
        gap_fn = ca.Function("gap", [q], [gap])
        slip_fn = ca.Function("slip", [q, v], [slip])
        return FrictionContact(gap=lambda q_: gap_fn(q_), slip=lambda q_, v_: slip_fn(q_, v_), mu=mu, name=name)

    def on_plane(self, name: str, plane: Geom, other: Geom, mu: float) -> list[FrictionContact]:
        n, p0 = plane.R[:, 2], plane.x
        t1, t2 = plane.R[:, 0], plane.R[:, 1]
        a = other.size
        if other.kind == SPHERE:
            points, radius = [other.x], a[0]
        elif other.kind == CAPSULE:
            axis = other.R[:, 2] * a[1]
            points, radius = [other.x - axis, other.x + axis], a[0]
        elif other.kind == BOX:
            signs = [(sx, sy, sz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
            points, radius = [other.x + other.R @ ca.DM(np.array(s) * a) for s in signs], 0.0
        else:  # ELLIPSOID: the support point along −n
            local = other.R.T @ n
            scaled = ca.DM(a) * local
            reach = ca.norm_2(scaled)
            points, radius = [other.x - other.R @ (ca.DM(a) * scaled) / reach], 0.0
        out = []
        for k, c in enumerate(points):
            touch = c - radius * n
            rel = other.velocity(touch) - plane.velocity(touch)
            label = name if len(points) == 1 else f"{name}#{k}"
            out.append(
                self._contact(label, ca.dot(n, c - p0) - radius, ca.vertcat(ca.dot(t1, rel), ca.dot(t2, rel)), mu)
            )
        return out

    def round_pair(self, name: str, A: Geom, B: Geom, mu: float) -> FrictionContact:
        ends = []
        for G in (A, B):
            half = G.R[:, 2] * (G.size[1] if G.kind == CAPSULE else 0.0)
            ends.append((G.x - half, G.x + half))
        c1, c2 = closest_points(ends[0][0], ends[0][1], ends[1][0], ends[1][1])
        return self.between(name, A, B, c1, c2, mu)

    def between(self, name: str, A: Geom, B: Geom, c1: Any, c2: Any, mu: float) -> FrictionContact:
        """The contact of two rounded surfaces about the core points ``c1`` (of ``A``) and ``c2`` (of ``B``), each at
        its geom's radius ``size[0]`` from its core: ``g = ‖c₂ − c₁‖ − r₁ − r₂`` along ``n = (c₂ − c₁)/‖c₂ − c₁‖``."""
        d = c2 - c1
        dist = ca.norm_2(d)
        n = d / dist
        gap = dist - A.size[0] - B.size[0]
        q0 = ca.Function("n0", [self.tree.q], [n])(self.load.m.qpos0)
        ref = np.eye(3)[int(np.argmin(np.abs(np.array(q0).ravel())))]
        t1 = ca.DM(ref) - ca.dot(ca.DM(ref), n) * n
        t1 = t1 / ca.norm_2(t1)
        t2 = ca.cross(n, t1)
        pa, pb = c1 + A.size[0] * n, c2 - B.size[0] * n
        rel = B.velocity(pb) - A.velocity(pa)
        return self._contact(name, gap, ca.vertcat(ca.dot(t1, rel), ca.dot(t2, rel)), mu)
