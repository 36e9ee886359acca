"""MuJoCo's passive forces on the joint tree (``mj_passive``, engine_passive.c), as generalized forces.

* **Joint springs** (hinge, slide): ``Q = −x·(k + Σ pᵢ xⁱ⁺¹)``, ``x = q − springref``, with the potential
  ``k x²/2 + Σ pᵢ xⁱ⁺³/(i+3)`` in the energy. A ball's or free joint's spring is refused by name.
* **Joint dampers**: ``Q = −v·(b + Σ pᵢ |v|ⁱ⁺¹)`` on each degree of freedom (non-conservative).
* **Tendon springs and dampers** (fixed tendons ``L = Σ cₖ qₖ``): ``F = −k x − b L̇`` along the tendon, ``x`` the
  length's distance outside the dead band ``[lo, up]`` of ``springlength``, as ``Q = cᵀ F``.
* **Gravity compensation**: ``−gravcomp·m g`` at each centre of mass (its potential in the energy).
* **Fluid forces**, MuJoCo's inertia-box model (``mj_inertiaBoxFluidModel``): each body with mass is a box of sides
  ``bᵢ = √(6 (I_j + I_k − I_i)/m)``; in its principal axes, with ``ω`` and ``u = v_c − wind`` there, the force is
  ``−3π d μ u − ½ ρ (b_j b_k) |uᵢ| uᵢ`` and the torque ``−π d³ μ ω − ρ bᵢ (b_j⁴ + b_k⁴) |ωᵢ| ωᵢ / 64``, ``d`` the
  boxes' mean side, ``ρ`` the medium's density and ``μ`` its viscosity (non-conservative). MuJoCo's ellipsoid model
  (``fluidshape="ellipsoid"``: added mass, Kutta lift, Magnus force) is refused by name.

Each is switched off by MuJoCo's flags as MuJoCo switches it (``spring``, ``damper``, ``gravity``; with both
``spring`` and ``damper`` off, MuJoCo skips every passive force, gravity compensation and fluid included).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from .context import Loading
from .tree import FREE, JointTree

NPOLY = 3  # MuJoCo's mjNPOLY (the polynomial terms after the linear one)


def _poly(row: Any) -> np.ndarray:
    return np.zeros(NPOLY) if row is None else np.asarray(row, float).ravel()


def _poly_force(linear: float, poly: np.ndarray, x: Any, odd: bool) -> Any:
    """``mju_polyForce``: ``linear + Σ pᵢ xⁱ⁺¹`` (``|x|`` for a damper)."""
    a = ca.fabs(x) if odd else x
    out, power = linear, 1
    for p in poly:
        power = power * a
        out = out + float(p) * power
    return out


def _poly_potential(linear: float, poly: np.ndarray, x: Any) -> Any:
    out = 0.5 * linear * x**2
    for i, p in enumerate(poly):
        out = out + float(p) * x ** (i + 3) / (i + 3)
    return out


def tendon_lengths(load: Loading, q: Any) -> list[Any]:
    """Each fixed tendon's length ``Σ cₖ qₖ`` (a spatial tendon's is ``None``: refused where it is used)."""
    m = load.m
    out = []
    for t in range(m.ntendon):
        adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
        if any(int(m.wrap_type[w]) != int(load.mj.mjtWrap.mjWRAP_JOINT) for w in range(adr, adr + num)):
            out.append(None)
            continue
        L = ca.SX(0)
        for w in range(adr, adr + num):
            L = L + float(m.wrap_prm[w]) * q[int(m.jnt_qposadr[int(m.wrap_objid[w])])]
        out.append(L)
    return out


def passive_forces(load: Loading, tree: JointTree) -> tuple[Any, Any, Any]:
    """``(Q, Q_nc, V)``: the passive generalized force, its non-conservative part, the springs' potential."""
    m, q, v = load.m, tree.q, tree.v
    Q, Q_nc, V = ca.SX.zeros(tree.nv), ca.SX.zeros(tree.nv), ca.SX(0)
    spring, damper = not load.disabled("SPRING"), not load.disabled("DAMPER")
    if not spring and not damper:  # MuJoCo skips every passive force then (gravcomp and fluid too)
        return Q, Q_nc, V
    if spring:
        spoly = getattr(m, "jnt_stiffnesspoly", None)
        for j in range(m.njnt):
            poly = _poly(None if spoly is None else spoly[j])
            k = float(m.jnt_stiffness[j])
            if k == 0 and not poly.any():
                continue
            if int(m.jnt_type[j]) in (FREE, 1):
                load.problem(f"joint {load.names.of('joint', j)!r} is a free or ball joint with stiffness: not mapped")
                continue
            a, d = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            x = q[a] - float(m.qpos_spring[a])
            Q[d] -= x * _poly_force(k, poly, x, odd=False)
            V += _poly_potential(k, poly, x)
    if damper:
        dpoly = getattr(m, "dof_dampingpoly", None)
        for d in range(m.nv):
            poly = _poly(None if dpoly is None else dpoly[d])
            b = float(m.dof_damping[d])
            if b == 0 and not poly.any():
                continue
            force = -v[d] * _poly_force(b, poly, v[d], odd=True)
            Q[d] += force
            Q_nc[d] += force
    lengths = tendon_lengths(load, q)
    for t, L in enumerate(lengths):
        k = float(m.tendon_stiffness[t]) if spring else 0.0
        b = float(m.tendon_damping[t]) if damper else 0.0
        polys = [
            _poly(getattr(m, f, None)[t]) if getattr(m, f, None) is not None else np.zeros(NPOLY)
            for f in ("tendon_stiffnesspoly", "tendon_dampingpoly")
        ]
        if k == 0 and b == 0 and not any(p.any() for p in polys):
            continue
        name = load.names.of("tendon", t)
        if L is None:
            load.problem(f"tendon {name!r} is a spatial tendon with stiffness or damping: not mapped")
            continue
        if any(p.any() for p in polys):
            load.problem(f"tendon {name!r} has a polynomial stiffness or damping: not mapped")
            continue
        c = ca.jacobian(L, q)  # the tendon's moment arms over qpos (hinges and slides: the same over qvel)
        cv = _over_velocities(load, c)
        rate = cv @ v
        lo, up = (float(x) for x in m.tendon_lengthspring[t])
        x = ca.if_else(L > up, L - up, ca.if_else(L < lo, L - lo, 0))
        Q += cv.T * (-k * x - b * rate)
        Q_nc += cv.T * (-b * rate)
        V += 0.5 * k * x**2
    if not load.disabled("GRAVITY") and np.any(np.asarray(m.body_gravcomp) != 0):
        g = ca.DM(np.asarray(m.opt.gravity, float))
        for k_, bdy in enumerate(tree.bodies):
            gc = float(m.body_gravcomp[k_ + 1])
            if gc != 0 and k_ in tree.velocities:
                if getattr(m, "jnt_actgravcomp", None) is not None and np.any(np.asarray(m.jnt_actgravcomp)):
                    load.problem("gravity compensation through actuators (actuatorgravcomp): not mapped")
                    break
                Q += tree.generalized(k_, -gc * bdy.mass * g, ca.SX.zeros(3))
                V += gc * bdy.mass * ca.dot(g, tree.frames.xc[k_])
    fluid = _fluid(load, tree) if (m.opt.density > 0 or m.opt.viscosity > 0) else None
    if fluid is not None:
        Q += fluid
        Q_nc += fluid
    return Q, Q_nc, V


def _over_velocities(load: Loading, c_q: Any) -> Any:
    """A row over ``qpos`` of hinge/slide coordinates, moved to ``qvel``'s indices."""
    m = load.m
    out = ca.SX.zeros(1, m.nv)
    for j in range(m.njnt):
        if int(m.jnt_type[j]) in (2, 3):
            out[int(m.jnt_dofadr[j])] = c_q[int(m.jnt_qposadr[j])]
    return out


def _fluid(load: Loading, tree: JointTree) -> Any:
    m = load.m
    rho, mu = float(m.opt.density), float(m.opt.viscosity)
    wind = ca.DM(np.asarray(m.opt.wind, float))
    Q = ca.SX.zeros(tree.nv)
    for k, b in enumerate(tree.bodies):
        i = k + 1
        if b.mass < 1e-15 or k not in tree.velocities:  # mjMINVAL
            continue
        geoms = range(int(m.body_geomadr[i]), int(m.body_geomadr[i] + m.body_geomnum[i]))
        if any(float(m.geom_fluid[g][0]) > 0 for g in geoms):
            load.problem(f"body {b.name!r} uses MuJoCo's ellipsoid fluid model (fluidshape): not mapped")
            continue
        I = b.inertia
        box = [np.sqrt(max(1e-15, I[(a + 1) % 3] + I[(a + 2) % 3] - I[a]) / b.mass * 6.0) for a in range(3)]
        vc, wc, _, _ = tree.velocities[k]
        Rc = tree.frames.Rc[k]
        u = Rc.T @ vc - Rc.T @ wind
        force, torque = ca.SX.zeros(3), ca.SX.zeros(3)
        if mu > 0:
            diam = sum(box) / 3.0
            torque -= np.pi * diam**3 * mu * wc
            force -= 3.0 * np.pi * diam * mu * u
        if rho > 0:
            for a in range(3):
                j_, k2 = (a + 1) % 3, (a + 2) % 3
                force[a] -= 0.5 * rho * box[j_] * box[k2] * ca.fabs(u[a]) * u[a]
                torque[a] -= rho * box[a] * (box[j_] ** 4 + box[k2] ** 4) * ca.fabs(wc[a]) * wc[a] / 64.0
        Q += tree.generalized(k, Rc @ force, torque)
    return Q
