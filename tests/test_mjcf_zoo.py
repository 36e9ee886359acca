"""MuJoCo's two most used model collections through ``gp.from_mjcf`` (issue 43): dm_control's suite and Gymnasium's
MuJoCo assets, 26 files no one here wrote.

Each loads with the defaults within 2 s, or names exactly what it lacks (24 load). For each one loaded, with contacts
and limits off and zero control, at random states its kinetic energy is ``½ q̇ᵀ M q̇`` with MuJoCo's ``mj_fullM``
(armature included) to 1e-12, and 1 s of its passive motion — damping, springs, armature, fluid forces — ends where
MuJoCo's (RK4, dt = 1e-4, contacts and limits disabled, frictionloss zeroed) does, to 1e-7 relative in ``qpos``."""

from __future__ import annotations

import importlib.util
import time
import warnings

import casadi as ca
import numpy as np
import pytest

import gausspp as gp

from .mjcf_zoo import models, zoo

pytestmark = [
    pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="needs MuJoCo: pip install mujoco"),
    pytest.mark.skipif(zoo() is None, reason="MuJoCo's model collections are not on this machine"),
]

#: What the two refused files lack (the loader names it; the test checks the names): the stacker's boxes against
#: boxes, capsules and spheres; the pusher's gripper against the side *and* the top of its puck (a cylinder).
REFUSED = {
    "dm_control/stacker.xml": ("capsule–box", "box–box", "sphere–box"),
    "gymnasium/pusher.xml": ("cylinder–capsule", "end or rim"),
}


def test_at_least_24_of_the_26_load() -> None:
    assert len(models()) - len(REFUSED) >= 24


def test_the_zoo_is_all_there() -> None:
    assert len(models()) == 26


@pytest.mark.parametrize("name", models())
def test_each_model_loads_within_two_seconds_or_names_what_it_lacks(name: str) -> None:
    start = time.perf_counter()
    if name in REFUSED:
        with pytest.raises(gp.InputError) as caught:
            gp.from_mjcf(str(zoo() / name))
        for what in REFUSED[name]:
            assert what in str(caught.value)
        return
    machine = gp.from_mjcf(str(zoo() / name))
    seconds = time.perf_counter() - start
    print(f"\n{name}: {seconds:.2f} s, nq {machine.model.nq}, {len(machine.contacts)} contact points")
    assert seconds <= 2.0


def _mujoco_passive(path: str):  # noqa: ANN202
    import mujoco

    m = mujoco.MjModel.from_xml_path(path)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    m.dof_frictionloss[:] = 0
    m.opt.integrator, m.opt.timestep = int(mujoco.mjtIntegrator.mjINT_RK4), 1e-4
    return mujoco, m


@pytest.mark.parametrize("name", [n for n in models() if n not in REFUSED])
def test_energy_and_one_second_of_passive_motion_are_mujocos(name: str) -> None:
    mujoco, m = _mujoco_passive(str(zoo() / name))
    # frictionloss zeroed as in MuJoCo's run (MuJoCo keeps it softly, gausspp exactly: test_mjcf_contacts.py)
    machine = gp.from_mjcf(_mujoco_passive(str(zoo() / name))[1], contacts="ignore", limits="ignore")
    kinetic = ca.Function("T", [machine.tree.q, machine.tree.v], [machine.tree.kinetic])
    d = mujoco.MjData(m)
    rng = np.random.default_rng(1)
    worst_energy = 0.0
    for _ in range(5):
        d.qpos[:] = m.qpos0 + 0.3 * rng.standard_normal(m.nq)
        mujoco.mj_normalizeQuat(m, d.qpos)
        d.qvel[:] = rng.standard_normal(m.nv)
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        T_mj = 0.5 * d.qvel @ M @ d.qvel
        worst_energy = max(worst_energy, abs(float(kinetic(d.qpos, d.qvel)) - T_mj) / T_mj)
    d.qpos[:] = m.qpos0 + 0.1 * rng.standard_normal(m.nq)
    mujoco.mj_normalizeQuat(m, d.qpos)
    d.qvel[:] = 0.5 * rng.standard_normal(m.nv)
    q0, v0 = d.qpos.copy(), d.qvel.copy()
    for _ in range(10_000):
        mujoco.mj_step(m, d)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.DriftWarning)
        traj = gp.simulate(machine.model, q0, v0, 1.0, rtol=1e-11)
    error = float(np.abs(traj.q[-1] - d.qpos).max() / max(1.0, np.abs(d.qpos).max()))
    moved = float(np.abs(d.qpos - q0).max())
    print(f"\n{name}: kinetic energy {worst_energy:.1e}, qpos after 1 s {error:.1e} relative (moved {moved:.2g})")
    assert worst_energy <= 1e-12 and error <= 1e-7 and moved > 1e-3


def test_a_damping_ten_percent_off_is_seen() -> None:
    """Negative control: the cheetah loaded from a copy whose joint damping is 10 % larger ends 1 s of passive motion
    far from MuJoCo's run of the original file (by more than 1e-5, a hundred times the test's tolerance)."""
    name = "dm_control/cheetah.xml"
    mujoco, m = _mujoco_passive(str(zoo() / name))
    changed = mujoco.MjModel.from_xml_path(str(zoo() / name))
    changed.dof_damping[:] *= 1.1
    machine = gp.from_mjcf(changed, contacts="ignore", limits="ignore")
    d = mujoco.MjData(m)
    d.qvel[:] = np.linspace(-1.0, 1.0, m.nv)
    q0, v0 = d.qpos.copy(), d.qvel.copy()
    for _ in range(10_000):
        mujoco.mj_step(m, d)
    traj = gp.simulate(machine.model, q0, v0, 1.0, rtol=1e-11)
    assert float(np.abs(traj.q[-1] - d.qpos).max()) > 1e-5
