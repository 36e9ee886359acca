"""``from_mjcf``: a MuJoCo MJCF model read by MuJoCo's own parser and made into a spatial :class:`gp.Multibody`.

.. code-block:: python

    from gausspp.multibody.mjcf import from_mjcf

    arm = from_mjcf("arm.xml")                       # a path, an XML string or a mujoco.MjModel
    q0, v0 = arm.state_from_mujoco(qpos, qvel)       # MuJoCo's joint-space state → gausspp's maximal coordinates
    traj = gp.simulate(arm.model, q0, v0, 2.0)

MuJoCo (``pip install mujoco``, the ``peers`` extra) compiles the file — defaults, ``childclass``, inertias from
geoms, ``ref`` angles, ``autolimits`` … are all its own — and :func:`from_mjcf` reads the compiled
``mujoco.MjModel`` and the kinematics ``mj_kinematics`` gives at the reference configuration ``qpos0``.

**Bodies.** Every moving MuJoCo body with mass ``m > 0`` becomes a spatial body of the :class:`~gausspp.Multibody`
placed at its centre of mass with its **principal inertia frame** as body axes: MuJoCo's inertial frame
(``body_ipos``, ``body_iquat`` from the body frame), in which the inertia tensor is ``diag(body_inertia)``. At
``qpos0`` the body is at ``r₀ = xipos`` with rotation ``R₀ = ximat`` (body → space), the quaternion
``p₀ = xquat ⊗ body_iquat`` (MuJoCo's and gausspp's quaternions are both ``(w, x, y, z)``). Its coordinates are
``(r, p)`` and its velocities ``(ṙ, ω)``: ``ṙ`` the centre's velocity in space axes, ``ω`` the angular velocity in
the principal axes, so that the kinetic energy is ``½ m |ṙ|² + ½ ωᵀ diag(I₁, I₂, I₃) ω``.

* A **static** body (``body_weldid = 0``: no joint between it and the world, whatever its mass) is part of the
  ground (``None``): it never moves, and its mass does not enter the dynamics in MuJoCo either.
* A moving body of **zero mass without joints** is welded to its parent: its points, sites and children's joints
  are carried by the gausspp body that carries the parent. It adds nothing to the kinetic energy in MuJoCo either,
  so nothing is lost.
* A moving body of **zero mass with joints** (MuJoCo compiles it only if a body with mass is welded to it, through
  bodies without joints) is carried by the first such body (in MuJoCo's order): its joints join that body to the
  parent's, at the same points and axes, since the two move as one rigid body. The others of its weld group are
  welded to that body as above. Without such a body (a model edited after compiling) it is refused.
* A body with mass whose principal moments are not positive (a point mass) is refused: gausspp's spatial body needs
  a positive-definite inertia.

**Joints** (MuJoCo's joints of a body are between it and its parent: below, ``child`` is the gausspp body carrying
the body and ``parent`` the one carrying its parent, ``None`` for the ground; ``p_a`` is the joint's anchor
``xanchor`` at ``qpos0`` in the child's principal axes from its centre, ``p_b`` the same point in the parent's, and
the axis ``e`` is ``xaxis`` at ``qpos0`` in the child's principal axes):

==========================  ====================================================================================
MuJoCo                      gausspp row set (:class:`~gausspp.Multibody`), named by the joint
==========================  ====================================================================================
``hinge``                   ``revolute(name, child, p_a, parent, p_b, axis=e)`` — five rows
``slide``                   ``prismatic(name, child, p_a, parent, p_b, axis=e)`` — five rows
``ball``                    ``spherical(name, child, p_a, parent, p_b)`` — three rows
``free``                    none: the body is free
(no joint)                  ``fixed("<body> (no joint)", child, 0, parent, r₀ in the parent)`` — six rows
                            (none if the parent is carried by the body itself: a massless jointed parent)
two ``hinge`` s, one        ``universal("<j1>+<j2>", child, p_a, parent, p_b, e₂ in the child, e₁ in the
anchor, axes ⊥              parent)``: MuJoCo turns about ``e₁`` (fixed in the parent) then ``e₂`` (fixed in the
                            child) — a Hooke joint
three ``hinge`` s, one      ``spherical("<j1>+<j2>+<j3>", …)``: three independent axes through one point turn
anchor, independent axes    the body about that point (Euler-like angles; singular where MuJoCo's are)
==========================  ====================================================================================

Any other set of joints on one body (two hinges at different points or not perpendicular, a slide with a hinge,
…) is refused, naming the body and its joints.

**Equality constraints** (between the gausspp bodies carrying MuJoCo's ``body1`` and ``body2``, or their sites):
``connect`` → ``spherical("equality <name>", …)`` at MuJoCo's two anchors (``mj_equalityAnchors``) — body
semantic, ``xpos + xmat·data[0:3]`` on ``body1`` and ``xpos + xmat·data[3:6]`` on ``body2`` (MuJoCo computes the
second at ``qpos0`` from the first), or site semantic, ``site_xpos``; they need not coincide at ``qpos0`` (then
:meth:`gausspp.Multibody.assemble` closes the loop). ``weld`` → ``fixed("equality <name>", …)``, which holds the
relative pose of ``qpos0``: a weld whose ``relpose`` is not met at ``qpos0`` (MuJoCo's own weld error there above
``WELD_TOL``) is refused; ``torquescale = 0`` leaves only MuJoCo's translational rows: ``spherical``. MuJoCo keeps
these softly (``solref``, ``solimp``); gausspp keeps them exactly. ``joint``, ``tendon``, ``distance`` and ``flex``
equalities are refused with their names, as are equalities inactive at the start (``active="false"``: MuJoCo
switches them at run time).

**What is refused, and what may be ignored.** Everything that puts a force MuJoCo computes into the motion is
either mapped or refused; nothing is dropped silently. Refused always: joint ``armature`` (rotor inertia in joint
space: no rigid body), joint ``stiffness`` and ``damping`` (unless the ``spring`` / ``damper`` flags are off),
``frictionloss``, ``gravcomp``, fluid forces (``density`` or ``viscosity`` > 0), flexes, mocap bodies (moved by
the user at run time), plugins. Refused unless the caller says ``"ignore"``:

* ``actuators`` — gausspp's :meth:`~gausspp.Multibody.motor` is planar only; ignored, the motion is MuJoCo's with
  the actuation flag off (no actuator force, including position servos' and bias forces);
* ``tendons`` — their stiffness, damping, limits (a tendon equality is refused all the same);
* ``contacts`` — a pair of geoms that MuJoCo could make collide (explicit ``<pair>``, or geoms on bodies not welded
  together whose ``contype``/``conaffinity`` match, past the parent filter and ``<exclude>``); gausspp's
  multibody has no contact: switch contacts off (``<flag contact="disable"/>``, ``contype="0"``) or ignore them;
* ``limits`` — joint ranges with ``limited``: unilateral, and gausspp's joints are bilateral.

Sensors, cameras, lights, keyframes and visual elements do not move anything and are not read.

**State map.** :meth:`MJCFMachine.state_from_mujoco` maps MuJoCo's ``(qpos, qvel)`` to gausspp's ``(q, v)`` on a
scratch ``MjData``: ``mj_kinematics``, ``mj_comPos``, ``mj_comVel``, then per body ``r = xipos``,
``p = xquat ⊗ body_iquat`` (normalized), and ``mj_objectVelocity(mjOBJ_BODY, flg_local=0)``, which gives
``(ω, ṙ)`` in space axes at the centre of mass ``xipos``; ``ω`` is then turned into the principal axes,
``ω_body = ximatᵀ ω``. ``v`` is linear in ``qvel`` at a fixed ``qpos``: ``v = J(qpos) qvel``, and the joint-space
mass matrix is ``M(qpos) = Jᵀ A J`` with ``A = diag(m, m, m, I₁, I₂, I₃, …)`` — MuJoCo's ``mj_fullM``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import BackendUnavailableError, InputError, ShapeError
from ..model.model import Model
from .system import Multibody

#: What to install for :func:`from_mjcf`.
EXTRA = "pip install mujoco (or pip install 'gausspp[peers]')"
#: What the caller may say about actuators, tendons, contacts and joint limits.
CHOICES = ("refuse", "ignore")
#: A weld is accepted when MuJoCo's own weld error at ``qpos0`` (m, and the quaternion's axis part) is below this.
WELD_TOL = 1e-10
#: Two hinges share an anchor when their anchors are this close (relative to the model's size) ...
ANCHOR_TOL = 1e-12
#: ... and are perpendicular when ``|e₁·e₂|`` is below this; three axes are independent when ``|det| ≥`` this.
AXIS_TOL = 1e-12


class MJCFMachine:
    """What :func:`from_mjcf` returns: the :class:`~gausspp.Multibody`, its :class:`~gausspp.Model`, the name maps
    and the state map from MuJoCo's joint space (module docstring).

    Attributes
    ----------
    multibody : Multibody
        The bodies and joints (spatial; gravity ``model.opt.gravity``, zero if MuJoCo's gravity flag is off).
    model : Model
        ``multibody.model()``.
    bodies : dict
        Every MuJoCo body's name (``"body#<id>"`` for an unnamed one; ``"world"`` too) → the gausspp body that
        carries it: its own, its parent's carrier (a massless body without joints), a massive body welded to it (a
        massless body with joints), or ``None`` (the ground: the world and static bodies).
    rows : dict
        Each mapped MuJoCo element — a joint's name (``"<j1>+<j2>"`` for a universal, ``"<j1>+<j2>+<j3>"`` for
        three hinges through one point; a free joint has no row), ``"<body> (no joint)"`` for a weld by absence of
        joints, ``"equality <name>"`` — → the names of its rows in ``model``.
    mujoco_model : mujoco.MjModel
        The compiled MuJoCo model.
    """

    def __init__(
        self,
        multibody: Multibody,
        model: Model,
        bodies: Mapping[str, str | None],
        rows: Mapping[str, tuple[str, ...]],
        mujoco_model: Any,
        body_ids: tuple[int, ...],
    ) -> None:
        import mujoco

        self.multibody, self.model = multibody, model
        self.bodies, self.rows = dict(bodies), dict(rows)
        self.mujoco_model = mujoco_model
        #: the MuJoCo body id of each gausspp body, in the order of the state
        self.body_ids = body_ids
        self._mujoco = mujoco
        self._data = mujoco.MjData(mujoco_model)

    def state_from_mujoco(self, qpos: Any, qvel: Any) -> tuple[np.ndarray, np.ndarray]:
        """gausspp's ``(q, v)`` from MuJoCo's ``(qpos, qvel)`` (module docstring, *State map*).

        ``q`` holds per body ``(r, p)``: the centre of mass in space and the unit quaternion ``(w, x, y, z)`` of
        the principal axes (body → space); ``v`` per body ``(ṙ, ω)``: the centre's velocity in space axes and the
        angular velocity in the principal axes. ``qpos`` and ``qvel`` may be one state or one per row (then ``q``
        and ``v`` have one row per state). Quaternions in ``qpos`` are used as MuJoCo uses them (normalized)."""
        m = self.mujoco_model
        qpos_, qvel_ = np.asarray(qpos, float), np.asarray(qvel, float)
        if qpos_.ndim == 2 and qvel_.ndim == 2 and qpos_.shape[0] == qvel_.shape[0]:
            pairs = [self.state_from_mujoco(a, b) for a, b in zip(qpos_, qvel_, strict=True)]
            return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
        if qpos_.shape != (m.nq,) or qvel_.shape != (m.nv,):
            raise ShapeError(
                f"state_from_mujoco: qpos must have {m.nq} numbers and qvel {m.nv} (or one state per row), got shapes "
                f"{qpos_.shape} and {qvel_.shape}"
            )
        if not (np.all(np.isfinite(qpos_)) and np.all(np.isfinite(qvel_))):
            raise InputError("state_from_mujoco: qpos and qvel must be finite")
        mj, d = self._mujoco, self._data
        d.qpos[:], d.qvel[:] = qpos_, qvel_
        mj.mj_kinematics(m, d)
        mj.mj_comPos(m, d)
        mj.mj_comVel(m, d)
        q, v = [], []
        res = np.zeros(6)
        for i in self.body_ids:
            q += [np.array(d.xipos[i]), _inertial_quaternion(mj, m, d, i)]
            mj.mj_objectVelocity(m, d, mj.mjtObj.mjOBJ_BODY, i, res, 0)  # (ω, ṙ) at xipos, space axes
            v += [res[3:6].copy(), d.ximat[i].reshape(3, 3).T @ res[0:3]]
        return np.concatenate(q), np.concatenate(v)


def from_mjcf(
    source: Any,
    *,
    actuators: str = "refuse",
    tendons: str = "refuse",
    contacts: str = "refuse",
    limits: str = "refuse",
    **options: Any,
) -> MJCFMachine:
    """A MuJoCo MJCF model as a spatial :class:`~gausspp.Multibody` (module docstring).

    Parameters
    ----------
    source : str, path or mujoco.MjModel
        A file (``str`` without ``<``, or a path object), the XML itself (a ``str`` holding ``<``), or a compiled
        ``mujoco.MjModel``.
    actuators, tendons, contacts, limits : {"refuse", "ignore"}
        What to do with MuJoCo's actuators, tendons, geoms that could collide and limited joints: refuse the model
        (the default), or build the machine without them (module docstring).
    **options
        Passed to :meth:`gausspp.Multibody.model` (as for ``gp.Model``).

    Returns
    -------
    MJCFMachine
        ``.multibody``, ``.model``, ``.bodies``, ``.rows``, ``.mujoco_model``, ``.state_from_mujoco(qpos, qvel)``.

    Raises
    ------
    BackendUnavailableError
        MuJoCo is not installed.
    InputError
        No such file; MuJoCo cannot read the model (its message is given); or the model has what gausspp cannot map
        — every problem found is listed, each with the MuJoCo element's name.
    """
    try:
        import mujoco
    except ImportError:
        raise BackendUnavailableError(
            f"gp.from_mjcf reads MJCF with MuJoCo's parser, which is missing: {EXTRA}"
        ) from None
    choices = {"actuators": actuators, "tendons": tendons, "contacts": contacts, "limits": limits}
    for key, value in choices.items():
        if value not in CHOICES:
            raise InputError(f"from_mjcf: {key} must be one of {CHOICES}, got {value!r}")
    m = _compile(mujoco, source)
    return _Builder(mujoco, m, choices).build(options)


def _compile(mujoco: Any, source: Any) -> Any:
    """The compiled ``MjModel`` of ``source``, or an :class:`InputError` with MuJoCo's message."""
    if isinstance(source, mujoco.MjModel):
        return source
    if isinstance(source, os.PathLike) or (isinstance(source, str) and "<" not in source):
        path = os.fspath(source)
        if not os.path.isfile(path):
            raise InputError(f"from_mjcf: no MJCF file {path!r} (give a path to an .xml file, or the XML as a string)")
        reader, what = (lambda: mujoco.MjModel.from_xml_path(path)), f"file {path!r}"
    elif isinstance(source, str):
        reader, what = (lambda: mujoco.MjModel.from_xml_string(source)), "XML string"
    else:
        raise InputError(
            f"from_mjcf: source must be a path, an XML string or a mujoco.MjModel, got {type(source).__name__}"
        )
    try:
        return reader()
    except Exception as exc:  # MuJoCo's parser and compiler raise ValueError with their message; keep it
        message = " ".join(str(exc).split())
        raise InputError(f"from_mjcf: MuJoCo cannot read the {what}: {message}") from None


def _inertial_quaternion(mj: Any, m: Any, d: Any, i: int) -> np.ndarray:
    """``xquat ⊗ body_iquat``, normalized: the principal axes → space, ``(w, x, y, z)``."""
    p = np.zeros(4)
    mj.mju_mulQuat(p, d.xquat[i], m.body_iquat[i])
    return p / np.linalg.norm(p)


class _Builder:
    """One pass over the compiled model: checks, bodies, joints, equalities."""

    def __init__(self, mujoco: Any, m: Any, choices: Mapping[str, str]) -> None:
        self.mj, self.m, self.choices = mujoco, m, choices
        self.d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, self.d)  # the reference configuration qpos0
        self.problems: list[str] = []
        self.carrier: dict[int, str | None] = {0: None}
        self.refused: set[int] = set()  # bodies refused with a problem listed (no gausspp body carries them)
        self.frames: dict[str, tuple[np.ndarray, np.ndarray]] = {}  # gausspp body → (r₀, R₀)
        self.rows: dict[str, tuple[str, ...]] = {}
        self.size = 1.0 + float(np.max(np.abs(self.d.xpos), initial=0.0))

    # -- names ----------------------------------------------------------------------------------------------
    def name(self, obj: Any, i: int, kind: str) -> str:
        found = self.mj.mj_id2name(self.m, obj, i)
        return found if found else f"{kind}#{i}"

    def body_name(self, i: int) -> str:
        return self.name(self.mj.mjtObj.mjOBJ_BODY, i, "body")

    def joint_name(self, j: int) -> str:
        return self.name(self.mj.mjtObj.mjOBJ_JOINT, j, "joint")

    def disabled(self, *flags: str) -> bool:
        """Whether one of MuJoCo's disable flags ``mjDSBL_<flag>`` is set (flags this MuJoCo lacks: not set)."""
        bits = int(self.m.opt.disableflags)
        found = [getattr(self.mj.mjtDisableBit, f"mjDSBL_{f}", None) for f in flags]
        return any(bits & int(bit) for bit in found if bit is not None)

    def nonzero(self, field: str, rows: int) -> np.ndarray:
        """Per row: whether MuJoCo's array ``field`` is nonzero there (an array this MuJoCo lacks: nowhere)."""
        value = getattr(self.m, field, None)
        if value is None or rows == 0:
            return np.zeros(rows, bool)
        return np.asarray(np.asarray(value).reshape(rows, -1).any(axis=1), bool)

    # -- the whole model -------------------------------------------------------------------------------------
    def build(self, options: Mapping[str, Any]) -> MJCFMachine:
        m = self.m
        gravity = np.zeros(3) if self.disabled("GRAVITY") else np.array(m.opt.gravity, float)
        self.mb = Multibody(gravity=tuple(gravity))
        self.check_forces()
        ids = self.add_bodies()
        for i in range(1, m.nbody):  # every problem at once: the bodies' joints and the equalities, whatever else
            if self.carried(i) is not None and (m.body_mass[i] > 0 or m.body_jntnum[i] > 0):
                self.add_joints(i)
        self.add_equalities()
        if self.problems:
            listed = "\n".join(f"  - {p}" for p in self.problems)
            raise InputError(f"from_mjcf: the model has what gausspp's Multibody cannot map:\n{listed}")
        if not ids:
            raise InputError("from_mjcf: the model has no moving body with mass: nothing for gausspp to move")
        bodies = {self.body_name(i): self.carrier[i] for i in range(m.nbody)}
        return MJCFMachine(self.mb, self.mb.model(**options), bodies, self.rows, m, tuple(ids))

    def check_forces(self) -> None:
        """Refuse (or, where the caller said so, leave out) what applies forces gausspp's machine would not."""
        m, mj, say = self.m, self.mj, self.problems.append

        def named(obj: Any, idx: Any, kind: str) -> str:
            return ", ".join(repr(self.name(obj, int(i), kind)) for i in idx)

        joints = np.arange(m.njnt)
        passive = {
            "armature": (self.nonzero("dof_armature", m.nv), "joint-space rotor inertia: no rigid body has it", False),
            "damping": (
                self.nonzero("dof_damping", m.nv) | self.nonzero("dof_dampingpoly", m.nv),
                "a joint damper",
                self.disabled("DAMPER", "PASSIVE"),
            ),
            "frictionloss": (
                self.nonzero("dof_frictionloss", m.nv),
                "dry friction",
                self.disabled("FRICTIONLOSS", "CONSTRAINT"),
            ),
        }
        for what, (mask, why, off) in passive.items():
            if np.any(mask) and not off:
                jnt = sorted({int(m.dof_jntid[k]) for k in np.flatnonzero(mask)})
                say(f"joint(s) {named(mj.mjtObj.mjOBJ_JOINT, jnt, 'joint')} have {what} ({why}); set it to 0")
        stiff = self.nonzero("jnt_stiffness", m.njnt) | self.nonzero("jnt_stiffnesspoly", m.njnt)
        if np.any(stiff) and not self.disabled("SPRING", "PASSIVE"):
            say(f"joint(s) {named(mj.mjtObj.mjOBJ_JOINT, joints[stiff], 'joint')} have stiffness (a joint spring)")
        if np.any(self.nonzero("body_gravcomp", m.nbody)) and not self.disabled("GRAVITY"):
            which = np.flatnonzero(self.nonzero("body_gravcomp", m.nbody))
            say(f"body(ies) {named(mj.mjtObj.mjOBJ_BODY, which, 'body')} have gravcomp (a force against gravity)")
        if m.opt.density > 0 or m.opt.viscosity > 0:
            say(f"fluid forces (density {m.opt.density:g}, viscosity {m.opt.viscosity:g}); set both to 0")
        if m.nflex:
            say(f"{m.nflex} flex(es) {named(mj.mjtObj.mjOBJ_FLEX, range(m.nflex), 'flex')}: deformable bodies")
        if m.nplugin:
            say(f"{m.nplugin} plugin(s): their forces are unknown to gausspp")
        if m.nu and not self.disabled("ACTUATION") and self.choices["actuators"] == "refuse":
            say(
                f"actuator(s) {named(mj.mjtObj.mjOBJ_ACTUATOR, range(m.nu), 'actuator')}: gausspp's spatial machine "
                "has no motor; pass actuators='ignore' to build it without them (MuJoCo's motion with actuation off)"
            )
        if m.ntendon and self.choices["tendons"] == "refuse":
            say(
                f"tendon(s) {named(mj.mjtObj.mjOBJ_TENDON, range(m.ntendon), 'tendon')}: not mapped; pass "
                "tendons='ignore' to leave out their stiffness, damping and limits"
            )
        limited = m.jnt_limited != 0
        if np.any(limited) and not self.disabled("LIMIT", "CONSTRAINT") and self.choices["limits"] == "refuse":
            say(
                f"limited joint(s) {named(mj.mjtObj.mjOBJ_JOINT, joints[limited], 'joint')}: joint limits are "
                "unilateral; pass limits='ignore' to build the joints without them"
            )
        pairs = self.collisions()
        if pairs and self.choices["contacts"] == "refuse":
            shown = ", ".join(f"{a!r}–{b!r}" for a, b in pairs[:6]) + (" …" if len(pairs) > 6 else "")
            say(
                f"{len(pairs)} pair(s) of geoms could collide ({shown}): gausspp's Multibody has no contact; disable "
                'contacts in the file (<flag contact="disable"/>, contype="0" conaffinity="0") or pass '
                "contacts='ignore'"
            )

    def collisions(self) -> list[tuple[str, str]]:
        """The geom pairs MuJoCo's collision filters let through (explicit pairs, then the bitmask, weld, parent
        and exclude filters of ``engine_collision_driver.c``), whatever their distance."""
        m, mj = self.m, self.mj
        if self.disabled("CONTACT", "CONSTRAINT"):
            return []
        geom = mj.mjtObj.mjOBJ_GEOM

        def gname(g: int) -> str:
            return self.name(geom, g, "geom")

        pairs = [(gname(int(a)), gname(int(b))) for a, b in zip(m.pair_geom1, m.pair_geom2, strict=True)]
        g1, g2 = np.triu_indices(m.ngeom, 1)
        weld, parent, dofs = np.asarray(m.body_weldid), np.asarray(m.body_parentid), np.asarray(m.body_dofnum)
        b1, b2 = np.asarray(m.geom_bodyid)[g1], np.asarray(m.geom_bodyid)[g2]
        w1, w2 = weld[b1], weld[b2]
        keep = (w1 != w2) & ((dofs[w1] > 0) | (dofs[w2] > 0))  # not one rigid body, not both dof-less
        if not self.disabled("FILTERPARENT"):
            keep &= ~((w1 != 0) & (w2 != 0) & ((w1 == weld[parent[w2]]) | (w2 == weld[parent[w1]])))
        contype, conaffinity = np.asarray(m.geom_contype), np.asarray(m.geom_conaffinity)
        keep &= ((contype[g1] & conaffinity[g2]) | (contype[g2] & conaffinity[g1])) != 0
        signature = (np.minimum(b1, b2).astype(np.int64) << 16) + np.maximum(b1, b2)
        keep &= ~np.isin(signature, np.asarray(m.exclude_signature, np.int64))
        pairs += [(gname(int(a)), gname(int(b))) for a, b in zip(g1[keep], g2[keep], strict=True)]
        return pairs

    # -- bodies ---------------------------------------------------------------------------------------------
    def add_bodies(self) -> list[int]:
        """The gausspp bodies (MuJoCo ids, parents first) and every body's carrier (module docstring)."""
        m, d, ids = self.m, self.d, []
        for i in range(1, m.nbody):
            name, parent = self.body_name(i), int(m.body_parentid[i])
            if m.body_mocapid[i] >= 0:
                self.problems.append(f"body {name!r} is a mocap body (moved by the user at run time)")
                self.refused.add(i)
            elif m.body_weldid[i] == 0:
                self.carrier[i] = None  # static: part of the ground
            elif m.body_mass[i] > 0:
                moments = np.array(m.body_inertia[i], float)
                if not np.all(moments > 0):
                    self.problems.append(
                        f"body {name!r} has mass {m.body_mass[i]:g} but principal moments {moments.tolist()}: a "
                        "spatial body needs a positive-definite inertia"
                    )
                    self.refused.add(i)
                    continue
                r0, p0 = np.array(d.xipos[i]), _inertial_quaternion(self.mj, m, d, i)
                try:
                    self.mb.body(name, mass=float(m.body_mass[i]), inertia=moments, at=r0, orientation=p0)
                except InputError as exc:
                    self.problems.append(f"body {name!r}: {exc}")
                    self.refused.add(i)
                    continue
                self.carrier[i] = name
                self.frames[name] = (r0, np.array(d.ximat[i]).reshape(3, 3))
                ids.append(i)
            elif m.body_jntnum[i] == 0:  # massless, welded: carried by its parent's body (refused with it)
                self.carrier[i] = self.carrier.get(parent)
                if parent in self.refused:
                    self.refused.add(i)
            else:  # massless with joints: carried by the first massive body rigidly attached to it
                group = [k for k in range(i + 1, m.nbody) if m.body_weldid[k] == i and m.body_mass[k] > 0]
                if group:
                    self.carrier[i] = self.body_name(group[0])
                else:  # MuJoCo's compiler refuses this too; a model edited after compiling can have it
                    joints = [self.joint_name(j) for j in self.joints_of(i)]
                    self.problems.append(
                        f"body {name!r} has zero mass but joints {joints}, and nothing with mass is welded to it: a "
                        "moving body needs mass and inertia (give it an <inertial>)"
                    )
                    self.refused.add(i)
        return ids

    def lost(self, i: int) -> bool:
        """Whether MuJoCo's body ``i`` is carried by no body gausspp built (refused: a problem listed names it)."""
        return i in self.refused or self.carrier.get(i) not in (None, *self.frames)

    def carried(self, i: int) -> str | None:
        """The gausspp body carrying MuJoCo's body ``i``; ``None`` for the ground, and for a body :meth:`lost`, so
        that the joints of its children are still read and their problems listed with the others."""
        return None if self.lost(i) else self.carrier.get(i)

    def joints_of(self, i: int) -> range:
        return range(int(self.m.body_jntadr[i]), int(self.m.body_jntadr[i] + self.m.body_jntnum[i]))

    def local(self, body: str | None, point: np.ndarray) -> np.ndarray:
        """A point in space at ``qpos0`` in ``body``'s principal axes from its centre (the ground: itself)."""
        if body is None:
            return np.array(point, float)
        r0, R0 = self.frames[body]
        return R0.T @ (np.asarray(point, float) - r0)

    def direction(self, body: str | None, axis: np.ndarray) -> np.ndarray:
        return np.array(axis, float) if body is None else self.frames[body][1].T @ np.asarray(axis, float)

    def record(self, key: str, add: Any) -> None:
        """Run ``add()`` (a Multibody joint) and remember the names of the rows it made under ``key``; a joint the
        Multibody refuses is a problem listed with the others."""
        before = len(self.mb.constraints)
        try:
            add()
        except InputError as exc:
            self.problems.append(f"{key}: {exc}")
            return
        self.rows[key] = tuple(c.name or "" for c in self.mb.constraints[before:])

    # -- joints ---------------------------------------------------------------------------------------------
    def add_joints(self, i: int) -> None:
        m, d, mb, mj = self.m, self.d, self.mb, self.mj
        child, parent = self.carried(i), self.carried(int(m.body_parentid[i]))
        assert child is not None
        joints = list(self.joints_of(i))
        kinds = [int(m.jnt_type[j]) for j in joints]
        T = mj.mjtJoint
        names = [self.joint_name(j) for j in joints]
        key = "+".join(names)
        if not joints:
            if parent == child:  # a massive body welded to the massless jointed body its joints move
                return
            r0 = self.frames[child][0]
            self.record(
                f"{child} (no joint)",
                lambda: mb.fixed(f"{child} (no joint)", child, np.zeros(3), parent, self.local(parent, r0)),
            )
            return
        anchor, axes = np.array(d.xanchor[joints[0]]), [np.array(d.xaxis[j]) for j in joints]
        pa, pb = self.local(child, anchor), self.local(parent, anchor)
        if kinds == [T.mjJNT_FREE]:
            self.rows[key] = ()
        elif kinds == [T.mjJNT_HINGE]:
            self.record(key, lambda: mb.revolute(key, child, pa, parent, pb, axis=self.direction(child, axes[0])))
        elif kinds == [T.mjJNT_SLIDE]:
            self.record(key, lambda: mb.prismatic(key, child, pa, parent, pb, axis=self.direction(child, axes[0])))
        elif kinds == [T.mjJNT_BALL]:
            self.record(key, lambda: mb.spherical(key, child, pa, parent, pb))
        elif set(kinds) == {T.mjJNT_HINGE} and len(kinds) in (2, 3) and self.one_anchor(joints):
            if len(kinds) == 2 and abs(float(axes[0] @ axes[1])) <= AXIS_TOL:
                e_child, e_parent = self.direction(child, axes[1]), self.direction(parent, axes[0])
                self.record(key, lambda: mb.universal(key, child, pa, parent, pb, e_child, e_parent))
            elif len(kinds) == 3 and abs(float(np.linalg.det(np.array(axes)))) >= AXIS_TOL:
                self.record(key, lambda: mb.spherical(key, child, pa, parent, pb))
            else:
                self.refuse_joints(i, names, "their axes are not perpendicular (two) or independent (three)")
        else:
            self.refuse_joints(i, names, "gausspp maps one hinge, slide, ball or free joint, two perpendicular "
                               "hinges through one point (a universal) or three independent ones (a ball)")  # fmt: skip

    def one_anchor(self, joints: list[int]) -> bool:
        points = np.array([self.d.xanchor[j] for j in joints])
        return bool(np.max(np.abs(points - points[0])) <= ANCHOR_TOL * self.size)

    def refuse_joints(self, i: int, names: list[str], why: str) -> None:
        kind = [self.mj.mjtJoint(int(self.m.jnt_type[j])).name[6:].lower() for j in self.joints_of(i)]
        listed = ", ".join(f"{n!r} ({k})" for n, k in zip(names, kind, strict=True))
        self.problems.append(f"body {self.body_name(i)!r} has the joints {listed}: {why}")

    # -- equalities -----------------------------------------------------------------------------------------
    def add_equalities(self) -> None:
        m, mj, mb = self.m, self.mj, self.mb
        E = mj.mjtEq
        if m.neq and self.disabled("EQUALITY", "CONSTRAINT"):
            self.problems.append("equality constraints are disabled by the option's flags: remove them or enable them")
            return
        for e in range(m.neq):
            name = self.name(mj.mjtObj.mjOBJ_EQUALITY, e, "equality")
            kind = int(m.eq_type[e])
            if kind not in (int(E.mjEQ_CONNECT), int(E.mjEQ_WELD)):
                self.problems.append(
                    f"equality {name!r} is a {E(kind).name[5:].lower()} equality: gausspp maps connect and weld only"
                )
                continue
            if not m.eq_active0[e]:
                self.problems.append(f"equality {name!r} is inactive at the start (MuJoCo switches it at run time)")
                continue
            pos1, pos2, b1, b2 = self.anchors(e)
            if self.lost(b1) or self.lost(b2):  # the body's problem is listed; this equality's would follow from it
                continue
            a, b = self.carried(b1), self.carried(b2)
            if a == b:
                self.problems.append(
                    f"equality {name!r} joins {self.body_name(b1)!r} and {self.body_name(b2)!r}, which move as one "
                    f"({'the ground' if a is None else repr(a)})"
                )
                continue
            if a is None:
                a, b, pos1, pos2 = b, a, pos2, pos1
            assert a is not None
            key = f"equality {name}"
            pa, pb = self.local(a, pos1), self.local(b, pos2)
            if kind == int(E.mjEQ_CONNECT) or m.eq_data[e][10] == 0:
                self.record(key, lambda a=a, b=b, pa=pa, pb=pb, key=key: mb.spherical(key, a, pa, b, pb))
                continue
            error = self.weld_error(e, pos1, pos2, b1, b2)
            if error > WELD_TOL:
                self.problems.append(
                    f"equality {name!r} (weld) is not met at qpos0 (error {error:.3g}): gausspp's fixed joint holds "
                    "the relative pose of qpos0; leave relpose to MuJoCo's default or place the bodies on it"
                )
                continue
            self.record(key, lambda a=a, b=b, pa=pa, pb=pb, key=key: mb.fixed(key, a, pa, b, pb))

    def anchors(self, e: int) -> tuple[np.ndarray, np.ndarray, int, int]:
        """MuJoCo's two anchor points in space at ``qpos0`` and their bodies (``mj_equalityAnchors``)."""
        m, d = self.m, self.d
        o1, o2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        if m.eq_objtype[e] == self.mj.mjtObj.mjOBJ_SITE:
            return np.array(d.site_xpos[o1]), np.array(d.site_xpos[o2]), int(m.site_bodyid[o1]), int(m.site_bodyid[o2])
        data = np.array(m.eq_data[e])
        first, second = (data[0:3], data[3:6]) if m.eq_type[e] == self.mj.mjtEq.mjEQ_CONNECT else (data[3:6], data[0:3])

        def world(body: int, local: np.ndarray) -> np.ndarray:
            return np.array(d.xpos[body]) + np.array(d.xmat[body]).reshape(3, 3) @ local

        return world(o1, first), world(o2, second), o1, o2

    def weld_error(self, e: int, pos1: np.ndarray, pos2: np.ndarray, b1: int, b2: int) -> float:
        """MuJoCo's weld error at ``qpos0``: ``|pos1 − pos2|`` and the axis part of ``q₂⁻¹ ⊗ q₁ ⊗ relpose`` (body
        semantic) or ``q_site2⁻¹ ⊗ q_site1`` (site semantic)."""
        m, d, mj = self.m, self.d, self.mj
        o1, o2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        q1, q2, neg, out = np.zeros(4), np.zeros(4), np.zeros(4), np.zeros(4)
        if m.eq_objtype[e] == mj.mjtObj.mjOBJ_SITE:
            mj.mju_mulQuat(q1, d.xquat[b1], m.site_quat[o1])
            mj.mju_mulQuat(q2, d.xquat[b2], m.site_quat[o2])
        else:
            mj.mju_mulQuat(q1, d.xquat[o1], np.array(m.eq_data[e][6:10]))
            q2[:] = d.xquat[o2]
        mj.mju_negQuat(neg, q2)
        mj.mju_mulQuat(out, neg, q1)
        return max(float(np.linalg.norm(pos1 - pos2)) / self.size, float(np.linalg.norm(out[1:])))
