"""MuJoCo's equality constraints and limits on the joint tree, as gausspp constraint rows (kept exactly, where MuJoCo
keeps them softly with ``solref``/``solimp``).

* ``connect``: the two anchors coincide, ``x₁ + R₁ a₁ − (x₂ + R₂ a₂) = 0`` (three rows; site semantic: the two
  sites' positions); a row identically zero — the out-of-plane row of a planar machine's connect — restricts
  nothing and is left out (MuJoCo keeps it, softly, at zero);
* ``weld``: the anchors coincide and the relative orientation is ``relpose``: the axial part of
  ``R₂ᵀ R₁ R_rel`` vanishes (six rows; ``torquescale = 0`` keeps the three translational ones);
* ``joint``: ``q₁ − q₁₀ = c₀ + c₁ d + c₂ d² + c₃ d³ + c₄ d⁴`` with ``d = q₂ − q₂₀`` (or ``q₁ − q₁₀ = c₀`` alone);
  ``tendon``: the same with fixed tendons' lengths and their lengths at ``qpos0``;
* a joint's ``range`` (``limited``): two unilateral rows ``q − lo ≥ 0``, ``hi − q ≥ 0``, restitution-free like
  MuJoCo's limits (an impact on a limit is plastic); a fixed tendon's ``range`` the same on its length.

Equalities inactive at the start (``active="false"``: switched by the user at run time), ``distance`` and ``flex``
equalities, limits on ball joints and on spatial tendons are refused by name. Each row set is named after MuJoCo's
element: ``"equality <name>"``, ``"limit <joint>"``, ``"tendon limit <tendon>"``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ...model.constraints import Constraint, Holonomic, Unilateral
from .context import Loading
from .passive import tendon_lengths
from .tree import JointTree, constant_rotation


def _vee_skew(Rm: Any) -> Any:
    """The axial vector of ``(R − Rᵀ)/2``: zero at ``R = I`` and, near it, the rotation vector."""
    return 0.5 * ca.vertcat(Rm[2, 1] - Rm[1, 2], Rm[0, 2] - Rm[2, 0], Rm[1, 0] - Rm[0, 1])


def _frame(tree: JointTree, body: int, q: Any) -> tuple[Any, Any]:
    """MuJoCo body ``body``'s frame ``(x, R)`` as expressions of ``q`` (the world's: constants)."""
    if body == 0:
        return ca.SX.zeros(3), ca.SX.eye(3)
    fr = _frames_of(tree, q)
    return fr.x[body - 1], fr.R[body - 1]


def _frames_of(tree: JointTree, q: Any) -> Any:
    from .tree import frames

    return frames(tree.bodies, q, ca.SX.zeros(tree.nv))


def equality_rows(load: Loading, tree: JointTree) -> list[Constraint]:
    m, mj = load.m, load.mj
    E = mj.mjtEq
    out: list[Constraint] = []
    if m.neq and load.disabled("EQUALITY", "CONSTRAINT"):
        return out
    lengths0 = np.asarray(getattr(m, "tendon_length0", np.zeros(m.ntendon)), float)
    for e in range(m.neq):
        name = load.names.of("equality", e)
        kind = int(m.eq_type[e])
        if not m.eq_active0[e]:
            load.problem(f"equality {name!r} is inactive at the start (MuJoCo switches it at run time): not mapped")
            continue
        data = np.array(m.eq_data[e], float)
        o1, o2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        key = f"equality {name}"
        if kind in (int(E.mjEQ_CONNECT), int(E.mjEQ_WELD)):
            out.append(_pose_rows(load, tree, e, kind == int(E.mjEQ_WELD), key, o1, o2, data))
        elif kind in (int(E.mjEQ_JOINT), int(E.mjEQ_TENDON)):
            joint = kind == int(E.mjEQ_JOINT)

            def scalar(i: int, q: Any, joint: bool = joint) -> tuple[Any, float]:
                if joint:
                    a = int(m.jnt_qposadr[i])
                    return q[a], float(m.qpos0[a])
                L = tendon_lengths(load, q)[i]
                return L, float(lengths0[i])

            bad = [
                i
                for i in (o1, o2)
                if i >= 0 and (int(m.jnt_type[i]) not in (2, 3) if joint else tendon_lengths(load, tree.q)[i] is None)
            ]
            if bad:
                load.problem(f"equality {name!r} couples a ball/free joint or a spatial tendon: not mapped")
                continue

            def g(q: Any, t: Any, o1: int = o1, o2: int = o2, data: np.ndarray = data, scalar: Any = scalar) -> Any:
                s1, r1 = scalar(o1, q)
                if o2 < 0:
                    return s1 - r1 - data[0]
                s2, r2 = scalar(o2, q)
                d = s2 - r2
                return s1 - r1 - (data[0] + data[1] * d + data[2] * d**2 + data[3] * d**3 + data[4] * d**4)

            out.append(Holonomic(g, name=key))
        else:
            load.problem(f"equality {name!r} is a {E(kind).name[5:].lower()} equality: not mapped")
    return out


def _pose_rows(load: Loading, tree: JointTree, e: int, weld: bool, key: str, o1: int, o2: int, data: np.ndarray) -> Any:
    m, mj = load.m, load.mj
    sites = int(m.eq_objtype[e]) == int(mj.mjtObj.mjOBJ_SITE)
    if sites:
        b1, b2 = int(m.site_bodyid[o1]), int(m.site_bodyid[o2])
        p1, p2 = np.array(m.site_pos[o1]), np.array(m.site_pos[o2])
        Rl1, Rl2 = constant_rotation(np.array(m.site_quat[o1])), constant_rotation(np.array(m.site_quat[o2]))
        Rrel = ca.DM.eye(3)
    else:
        b1, b2 = o1, o2
        p1, p2 = (data[0:3], data[3:6]) if not weld else (data[3:6], data[0:3])
        Rl1 = Rl2 = ca.DM.eye(3)
        Rrel = constant_rotation(data[6:10]) if weld else ca.DM.eye(3)
    rotate = weld and float(data[10]) != 0

    def g(q: Any, t: Any) -> Any:
        x1, R1 = _frame(tree, b1, q)
        x2, R2 = _frame(tree, b2, q)
        rows = [x1 + R1 @ ca.DM(p1) - (x2 + R2 @ ca.DM(p2))]
        if rotate:
            rows.append(_vee_skew((R2 @ Rl2).T @ (R1 @ Rl1) @ Rrel))
        return ca.vertcat(*rows)

    # a row identically zero restricts nothing (a connect's out-of-plane row in a planar machine): left out
    full = ca.SX(g(tree.q, tree.t))
    kept = [i for i in range(full.numel()) if not full[i].is_zero()]
    if not kept:
        load.problem(f"{key!r} holds nothing: its rows are identically zero (the two anchors move as one)")
        kept = list(range(full.numel()))
    if len(kept) == full.numel():
        return Holonomic(g, name=key)
    return Holonomic(lambda q, t: ca.vertcat(*[g(q, t)[i] for i in kept]), name=key)


def limit_rows(load: Loading, tree: JointTree) -> list[Constraint]:
    m = load.m
    out: list[Constraint] = []
    if load.disabled("LIMIT", "CONSTRAINT"):
        return out
    for j in np.flatnonzero(np.asarray(m.jnt_limited)):
        name = load.names.of("joint", int(j))
        if int(m.jnt_type[j]) not in (2, 3):
            load.problem(f"joint {name!r}: a limit on a ball or free joint is not mapped")
            continue
        a = int(m.jnt_qposadr[j])
        lo, hi = (float(x) for x in m.jnt_range[j])
        out.append(Unilateral(lambda q, t, a=a, lo=lo, hi=hi: ca.vertcat(q[a] - lo, hi - q[a]), name=f"limit {name}"))
    limited = np.asarray(getattr(m, "tendon_limited", np.zeros(m.ntendon)))
    for t_ in np.flatnonzero(limited):
        name = load.names.of("tendon", int(t_))
        if tendon_lengths(load, tree.q)[int(t_)] is None:
            load.problem(f"tendon {name!r}: a limit on a spatial tendon is not mapped")
            continue
        lo, hi = (float(x) for x in m.tendon_range[t_])
        out.append(
            Unilateral(
                lambda q, t, i=int(t_), lo=lo, hi=hi: ca.vertcat(
                    tendon_lengths(load, q)[i] - lo, hi - tendon_lengths(load, q)[i]
                ),
                name=f"tendon limit {name}",
            )
        )
    return out
