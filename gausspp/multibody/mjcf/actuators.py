"""MuJoCo's actuators on the joint tree (``mj_fwdActuation``), driven by the caller's control ``ctrl(q, v, t)``.

For each actuator with a joint (hinge, slide) or fixed-tendon transmission of gear ``g``:

* its length and velocity ``l = g·s``, ``l̇ = g·ṡ`` (``s`` the joint coordinate or the tendon's length);
* the control, clamped to ``ctrlrange`` when ``ctrllimited`` (unless MuJoCo's ``clampctrl`` flag is off);
* the force ``F = gain·u + bias`` with ``gain = g₀ + g₁ l + g₂ l̇`` (``gaintype`` fixed or affine) and
  ``bias = b₀ + b₁ l + b₂ l̇`` (``biastype`` none or affine): ``motor``, ``position`` (``kp``, ``kv``), ``velocity``
  and ``general`` actuators are all this;
* clamped to ``forcerange`` when ``forcelimited``, then applied as ``Q = ∂l/∂qvel · F``;
* the total on a joint clamped to its ``actuatorfrcrange`` when ``actuatorfrclimited``.

Activation dynamics (``dyntype`` other than none: filters, integrators, muscles), muscle gains and biases, other
transmissions (site, body, slider-crank, a joint in parent, a ball or free joint), multi-input actuators and
actuator delays are refused by name. All the actuators' forces are non-conservative: their power enters the work.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ...model.symbolic import evaluate
from .context import Loading
from .passive import _over_velocities, tendon_lengths
from .tree import JointTree


def _control(ctrl: Any, nu: int, q: Any, v: Any, t: Any) -> Any:
    if ctrl is None:
        return ca.SX.zeros(nu)
    if callable(ctrl):
        return evaluate(ctrl, (q, v, t), (nu, 1), "from_mjcf: ctrl(q, v, t)")
    return ca.SX(ca.DM(np.asarray(ctrl, float).reshape(nu, 1)))


def actuator_forces(load: Loading, tree: JointTree, ctrl: Callable[..., Any] | None) -> Any:
    """The actuators' generalized force (nv), or zero when MuJoCo's actuation flag is off."""
    m, mj, q, v = load.m, load.mj, tree.q, tree.v
    Q = ca.SX.zeros(tree.nv)
    if m.nu == 0 or load.disabled("ACTUATION"):
        return Q
    name = lambda a: load.names.of("actuator", a)  # noqa: E731
    u = _control(ctrl, m.nu, q, v, tree.t)
    lengths = tendon_lengths(load, q) if m.ntendon else []
    T = mj.mjtTrn
    for a in range(m.nu):
        bad = []
        if int(m.actuator_dyntype[a]) != int(mj.mjtDyn.mjDYN_NONE):
            bad.append(f"activation dynamics {mj.mjtDyn(int(m.actuator_dyntype[a])).name[6:].lower()}")
        if int(m.actuator_gaintype[a]) not in (int(mj.mjtGain.mjGAIN_FIXED), int(mj.mjtGain.mjGAIN_AFFINE)):
            bad.append(f"gain {mj.mjtGain(int(m.actuator_gaintype[a])).name[7:].lower()}")
        if int(m.actuator_biastype[a]) not in (int(mj.mjtBias.mjBIAS_NONE), int(mj.mjtBias.mjBIAS_AFFINE)):
            bad.append(f"bias {mj.mjtBias(int(m.actuator_biastype[a])).name[7:].lower()}")
        for field, what in (("actuator_ctrlnum", "several controls"), ("actuator_delay", "a delay")):
            value = getattr(m, field, None)
            if value is not None and float(np.asarray(value[a]).ravel()[0]) not in (
                (1.0,) if field.endswith("num") else (0.0,)
            ):
                bad.append(what)
        for field, what in (("actuator_damping", "damping"), ("actuator_armature", "armature")):
            value = getattr(m, field, None)
            if value is not None and np.any(np.asarray(value[a]) != 0):
                bad.append(what)
        gear = np.asarray(m.actuator_gear[a], float)
        trn, target = int(m.actuator_trntype[a]), int(m.actuator_trnid[a][0])
        s = moment = None
        if trn == int(T.mjTRN_JOINT) and int(m.jnt_type[target]) in (2, 3) and not gear[1:].any():
            s, moment = q[int(m.jnt_qposadr[target])], ca.SX.zeros(1, tree.nv)
            moment[int(m.jnt_dofadr[target])] = 1.0
        elif trn == int(T.mjTRN_TENDON) and lengths[target] is not None and not gear[1:].any():
            s = lengths[target]
            moment = _over_velocities(load, ca.jacobian(s, q))
        else:
            bad.append(
                f"a {T(trn).name[6:].lower()} transmission" + (" with a 6-vector gear" if gear[1:].any() else "")
            )
        if bad:
            load.problem(f"actuator {name(a)!r} has {', '.join(bad)}: not mapped")
            continue
        length, rate = gear[0] * s, gear[0] * (moment @ v)
        gp_, bp = np.asarray(m.actuator_gainprm[a], float), np.asarray(m.actuator_biasprm[a], float)
        gain = gp_[0] + (gp_[1] * length + gp_[2] * rate if int(m.actuator_gaintype[a]) else 0)
        bias = bp[0] + bp[1] * length + bp[2] * rate if int(m.actuator_biastype[a]) else 0
        control = u[a]
        if m.actuator_ctrllimited[a] and not load.disabled("CLAMPCTRL"):
            lo, hi = (float(x) for x in m.actuator_ctrlrange[a])
            control = ca.fmin(ca.fmax(control, lo), hi)
        force = gain * control + bias
        if m.actuator_forcelimited[a]:
            lo, hi = (float(x) for x in m.actuator_forcerange[a])
            force = ca.fmin(ca.fmax(force, lo), hi)
        Q += gear[0] * moment.T * force
    limited = getattr(m, "jnt_actfrclimited", None)
    if limited is not None:
        for j in np.flatnonzero(np.asarray(limited)):
            if int(m.jnt_type[j]) in (2, 3):
                d = int(m.jnt_dofadr[j])
                lo, hi = (float(x) for x in m.jnt_actfrcrange[j])
                Q[d] = ca.fmin(ca.fmax(Q[d], lo), hi)
            else:
                load.problem(
                    f"joint {load.names.of('joint', int(j))!r}: actuatorfrcrange on a ball or free joint: not mapped"
                )
    return Q
