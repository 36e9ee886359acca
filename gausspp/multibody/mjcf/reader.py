"""Read the compiled ``mujoco.MjModel`` into plain numbers: the tree's bodies and joints, names, flags."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ...errors import BackendUnavailableError, InputError
from .tree import TreeBody, TreeJoint

#: What to install for :func:`gausspp.from_mjcf`.
EXTRA = "pip install mujoco (or pip install 'gausspp[peers]')"


def import_mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        raise BackendUnavailableError(
            f"gp.from_mjcf reads MJCF with MuJoCo's parser, which is missing: {EXTRA}"
        ) from None
    return mujoco


def compile_source(mujoco: Any, source: Any) -> Any:
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


class Names:
    """MuJoCo's names of a compiled model's elements (``"<kind>#<id>"`` for an unnamed one)."""

    def __init__(self, mujoco: Any, m: Any) -> None:
        self.mj, self.m = mujoco, m

    def of(self, kind: str, i: int) -> str:
        obj = getattr(self.mj.mjtObj, f"mjOBJ_{kind.upper()}")
        found = self.mj.mj_id2name(self.m, obj, int(i))
        return found if found else f"{kind}#{int(i)}"

    def listed(self, kind: str, ids: Any) -> str:
        return ", ".join(repr(self.of(kind, int(i))) for i in ids)


def disabled(mujoco: Any, m: Any, *flags: str) -> bool:
    """Whether one of MuJoCo's disable flags ``mjDSBL_<flag>`` is set (flags this MuJoCo lacks: not set)."""
    bits = int(m.opt.disableflags)
    found = [getattr(mujoco.mjtDisableBit, f"mjDSBL_{f}", None) for f in flags]
    return any(bits & int(bit) for bit in found if bit is not None)


def tree_bodies(m: Any, names: Names) -> list[TreeBody]:
    """Every body but the world, parents first, with its joints (index ``i − 1`` for MuJoCo's body ``i``)."""
    bodies = []
    for i in range(1, m.nbody):
        b = TreeBody(
            name=names.of("body", i),
            parent=int(m.body_parentid[i]) - 1,
            pos=np.array(m.body_pos[i], float),
            quat=np.array(m.body_quat[i], float),
            mass=float(m.body_mass[i]),
            inertia=np.array(m.body_inertia[i], float),
            ipos=np.array(m.body_ipos[i], float),
            iquat=np.array(m.body_iquat[i], float),
        )
        for j in range(int(m.body_jntadr[i]), int(m.body_jntadr[i] + m.body_jntnum[i])):
            qadr = int(m.jnt_qposadr[j])
            width = {0: 7, 1: 4, 2: 1, 3: 1}[int(m.jnt_type[j])]
            b.joints.append(
                TreeJoint(
                    name=names.of("joint", j),
                    kind=int(m.jnt_type[j]),
                    axis=np.array(m.jnt_axis[j], float),
                    pos=np.array(m.jnt_pos[j], float),
                    qadr=qadr,
                    dadr=int(m.jnt_dofadr[j]),
                    q0=np.array(m.qpos0[qadr : qadr + width], float),
                )
            )
        bodies.append(b)
    return bodies


def coordinate_names(m: Any, names: Names) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """``qpos`` and ``qvel`` names: a hinge's or slide's name; ``<j>.x … <j>.qz`` for a free joint's seven and
    ``<j>.vx … <j>.wz`` for its six; ``<j>.qw … <j>.qz`` and ``<j>.wx … <j>.wz`` for a ball."""
    qn: list[str] = []
    vn: list[str] = []
    for j in range(m.njnt):
        n, kind = names.of("joint", j), int(m.jnt_type[j])
        if kind == 0:
            qn += [f"{n}.{c}" for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]
            vn += [f"{n}.{c}" for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
        elif kind == 1:
            qn += [f"{n}.{c}" for c in ("qw", "qx", "qy", "qz")]
            vn += [f"{n}.{c}" for c in ("wx", "wy", "wz")]
        else:
            qn.append(n)
            vn.append(n)
    return tuple(qn), tuple(vn)
