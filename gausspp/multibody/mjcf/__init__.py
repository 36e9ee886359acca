"""``gp.from_mjcf``: a MuJoCo MJCF model read by MuJoCo's own parser and built in MuJoCo's joint coordinates.

.. code-block:: python

    hopper = gp.from_mjcf("hopper.xml")                # a path, an XML string or a mujoco.MjModel
    traj = gp.simulate(hopper.model, qpos, qvel, 2.0)  # gausspp's state is MuJoCo's (qpos, qvel)

MuJoCo (``pip install mujoco``, the ``peers`` extra) compiles the file — defaults, ``childclass``, inertias from
geoms, ``ref`` angles, ``autolimits`` … are all its own — and the loader reads the compiled ``mujoco.MjModel``.

**Coordinates.** The model's coordinates are MuJoCo's ``qpos`` and its velocities MuJoCo's ``qvel``, one per degree
of freedom, whatever the joints of a body (:mod:`.tree`): ``M`` is ``mj_fullM``'s, armature included, and a state
passes between the two unchanged. Why joint coordinates and not one rigid body per MuJoCo body: docs/architecture.md.

**Forces** (:mod:`.passive`, :mod:`.actuators`): gravity, joint and tendon springs and dampers, gravity
compensation, MuJoCo's inertia-box fluid forces, and the actuators driven by ``ctrl(q, v, t)``.

**Rows** (:mod:`.rows`): ``connect``, ``weld``, ``joint`` and ``tendon`` equalities as holonomic rows, joint and
tendon ``range`` limits as unilateral rows — kept exactly where MuJoCo keeps them softly.

**Contacts** (:mod:`.contacts`): the geom pairs MuJoCo would let collide, as hard frictional contacts
(``machine.contacts``, :class:`gausspp.FrictionContact`), which ``gp.simulate`` takes from ``machine.model``; and
each degree of freedom's ``frictionloss`` as dry friction with that bound (:mod:`.dry_friction`,
:class:`gausspp.JointFriction`: sticking and slipping, where MuJoCo keeps it softly).

**What is refused.** Everything that puts a force MuJoCo computes into the motion is mapped or refused; nothing is
dropped silently, and every problem is listed at once with the MuJoCo element's name: a tendon's ``frictionloss``,
activation dynamics and other actuators than the affine ones, transmissions other than a hinge, a slide
or a fixed tendon, spatial tendons with forces or limits, MuJoCo's ellipsoid fluid model, flexes, mocap bodies,
plugins, inactive and ``distance``/``flex`` equalities, geom pairs other than those :mod:`.contacts` lists. The
caller may leave out ``actuators``, ``tendons`` (their forces and limits), ``contacts`` or ``limits`` with
``"ignore"`` — the motion is then MuJoCo's with that part switched off.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ...errors import InputError, ShapeError
from ...model.model import Model
from .actuators import actuator_forces
from .contacts import ContactBuilder
from .context import Loading
from .dry_friction import joint_friction
from .passive import passive_forces
from .reader import EXTRA, compile_source, coordinate_names, import_mujoco, tree_bodies
from .rows import equality_rows, limit_rows
from .tree import JointTree

__all__ = ["EXTRA", "CHOICES", "MJCFMachine", "from_mjcf"]

#: What the caller may say about actuators, tendons, contacts and joint limits.
CHOICES = ("map", "ignore")


class MJCFMachine:
    """What :func:`from_mjcf` returns.

    Attributes
    ----------
    model : Model
        The tree with its equality rows and limits (``gp.Model``); its frictional contacts ride with it
        (``model.friction``).
    tree : JointTree
        The mechanism in ``(qpos, qvel)``.
    contacts : list of FrictionContact
        The hard frictional contacts of the geom pairs that may collide (empty with ``contacts="ignore"``).
    joint_names, coordinate_names, velocity_names : tuple of str
    mujoco_model : mujoco.MjModel
        The compiled MuJoCo model.
    """

    def __init__(self, model: Model, tree: JointTree, contacts: list[Any], m: Any, joints: tuple[str, ...]) -> None:
        self.model, self.tree, self.contacts, self.mujoco_model = model, tree, contacts, m
        self.joint_names = joints
        self.coordinate_names, self.velocity_names = tree.coordinate_names, tree.velocity_names

    def state_from_mujoco(self, qpos: Any, qvel: Any) -> tuple[np.ndarray, np.ndarray]:
        """gausspp's ``(q, v)`` from MuJoCo's ``(qpos, qvel)``: the same numbers (copied, quaternions normalized),
        checked for size and finiteness; one state, or one per row."""
        m = self.mujoco_model
        q, v = np.array(qpos, float), np.array(qvel, float)
        if q.shape[-1:] != (m.nq,) or v.shape[-1:] != (m.nv,) or q.shape[:-1] != v.shape[:-1] or q.ndim > 2:
            raise ShapeError(
                f"state_from_mujoco: qpos must have {m.nq} numbers and qvel {m.nv} (or one state per row), got shapes "
                f"{q.shape} and {v.shape}"
            )
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            raise InputError("state_from_mujoco: qpos and qvel must be finite")
        return self.tree.normalize_array(q), v

    def initial_state(self) -> tuple[np.ndarray, np.ndarray]:
        """MuJoCo's reference state, ``qpos0`` and zero velocities, with each limited hinge or slide moved to the
        nearest end of its range where ``qpos0`` lies outside it (MuJoCo's soft limit would push it there; gausspp's
        one-sided rows refuse a start outside them)."""
        m = self.mujoco_model
        q = np.array(m.qpos0, float)
        for j in np.flatnonzero(np.asarray(m.jnt_limited)):
            if int(m.jnt_type[j]) in (2, 3):
                a = int(m.jnt_qposadr[j])
                q[a] = min(max(q[a], float(m.jnt_range[j][0])), float(m.jnt_range[j][1]))
        return q, np.zeros(m.nv)


def from_mjcf(
    source: Any,
    *,
    ctrl: Callable[..., Any] | Any = None,
    actuators: str = "map",
    tendons: str = "map",
    contacts: str = "map",
    limits: str = "map",
    **options: Any,
) -> MJCFMachine:
    """A MuJoCo MJCF model in MuJoCo's joint coordinates (module docstring).

    Parameters
    ----------
    source : str, path or mujoco.MjModel
        A file (``str`` without ``<``, or a path object), the XML itself (a ``str`` holding ``<``), or a compiled
        ``mujoco.MjModel``.
    ctrl : callable ``(q, v, t) -> (nu,)`` or array, optional
        The actuators' controls (casadi operations), MuJoCo's ``data.ctrl``; zero by default.
    actuators, tendons, contacts, limits : {"map", "ignore"}
        Map MuJoCo's actuators, tendons' forces and limits, colliding geoms, joint and tendon limits (the default),
        or build the machine without them.
    **options
        Passed to :class:`gausspp.Model`.

    Raises
    ------
    BackendUnavailableError
        MuJoCo is not installed.
    InputError
        No such file; MuJoCo cannot read the model (its message is given); or the model has what gausspp cannot map
        — every problem found is listed, each with the MuJoCo element's name.
    """
    mujoco = import_mujoco()
    choices = {"actuators": actuators, "tendons": tendons, "contacts": contacts, "limits": limits}
    for key, value in choices.items():
        if value not in CHOICES:
            raise InputError(f"from_mjcf: {key} must be one of {CHOICES}, got {value!r}")
    if ctrl is not None and not callable(ctrl):
        ctrl = np.asarray(ctrl, float)
    m = compile_source(mujoco, source)
    load = Loading(mujoco, m, choices)
    _check_unmapped(load)
    bodies = tree_bodies(m, load.names)
    gravity = np.zeros(3) if load.disabled("GRAVITY") else np.array(m.opt.gravity, float)
    armature = np.array(m.dof_armature, float)
    if ctrl is not None and not callable(ctrl) and ctrl.shape not in ((m.nu,), (m.nu, 1)):
        raise ShapeError(f"from_mjcf: ctrl must have one number per actuator ({m.nu}), got shape {ctrl.shape}")

    def forces(tree: JointTree) -> tuple[Any, Any, Any]:
        Q, Q_nc, V = passive_forces(load, tree) if tendons == "map" else _no_tendon_forces(load, tree)
        if actuators == "map":
            act = actuator_forces(load, tree, ctrl)
            Q, Q_nc = Q + act, Q_nc + act
        return Q, Q_nc, V

    tree = JointTree(bodies, m.nq, m.nv, gravity, armature, forces, coordinate_names(m, load.names))
    rows = equality_rows(load, tree)
    if limits == "map":
        rows += limit_rows(load, tree)
    friction = ContactBuilder(load, tree).contacts() if contacts == "map" else []
    friction += joint_friction(load, tree)
    if load.problems:
        listed = "\n".join(f"  - {p}" for p in load.problems)
        raise InputError(f"from_mjcf: the model has what gausspp cannot map:\n{listed}")
    if not any(b.mass > 0 for b in bodies) or m.nv == 0:
        raise InputError("from_mjcf: the model has no moving body with mass: nothing for gausspp to move")
    model = Model(tree, rows, friction=friction, **options)
    joints = tuple(load.names.of("joint", j) for j in range(m.njnt))
    return MJCFMachine(model, tree, friction, m, joints)


def _no_tendon_forces(load: Loading, tree: JointTree) -> tuple[Any, Any, Any]:
    """The passive forces with the tendons' springs and dampers left out (``tendons="ignore"``)."""
    saved = (load.m.tendon_stiffness.copy(), load.m.tendon_damping.copy())
    load.m.tendon_stiffness[:] = 0
    load.m.tendon_damping[:] = 0
    try:
        return passive_forces(load, tree)
    finally:
        load.m.tendon_stiffness[:], load.m.tendon_damping[:] = saved


def _check_unmapped(load: Loading) -> None:
    """What no part of the loader maps: listed with the others."""
    m, say = load.m, load.problem
    rubbing = np.flatnonzero(np.asarray(getattr(m, "tendon_frictionloss", np.zeros(0))) != 0)
    if rubbing.size and load.choices["tendons"] == "map" and not load.disabled("FRICTIONLOSS", "CONSTRAINT"):
        listed = load.names.listed("tendon", rubbing)
        say(f"tendon(s) {listed} have frictionloss (dry friction along a tendon): not mapped")
    if m.nflex:
        say(f"{m.nflex} flex(es) {load.names.listed('flex', range(m.nflex))}: deformable bodies are not mapped")
    if m.nplugin:
        say(f"{m.nplugin} plugin(s): their forces are unknown to gausspp")
    mocap = [i for i in range(m.nbody) if m.body_mocapid[i] >= 0]
    if mocap:
        say(f"mocap body(ies) {load.names.listed('body', mocap)} (moved by the user at run time): not mapped")
    for i in range(1, m.nbody):
        if m.body_dofnum[i] and m.body_mass[i] > 0 and not np.all(np.asarray(m.body_inertia[i]) > 0):
            pass  # MuJoCo's joint space takes a point mass (its rotation is carried by others or is massless)
