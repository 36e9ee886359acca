"""The compiled lane's step as C (gausspp/c_code.py): the same trajectory as casadi's virtual machine, built once
and loaded by the next process; without a compiler, the virtual machine (never an error)."""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp
from gausspp import c_code


def runs(codegen: bool) -> gp.Trajectory:
    scene = gp.scenes.get("planar-chain", N=3)
    m = scene.model
    model = gp.Model(m.mechanism, list(m.constraints), codegen=codegen)
    return gp.simulate(model, scene.q0, scene.v0, 0.2, dt=1e-3, method="rk4", solver="direct")


@pytest.mark.skipif(c_code.compiler() is None, reason="no C compiler on this machine")
def test_the_step_in_c_gives_the_virtual_machines_trajectory(private_disk_cache) -> None:
    vm, c = runs(False), runs(True)
    assert c.status == vm.status == "success"
    scale = np.abs(vm.q).max()
    assert np.abs(c.q - vm.q).max() <= 1e-12 * scale and np.abs(c.v - vm.v).max() <= 1e-10 * max(np.abs(vm.v).max(), 1)
    assert list(private_disk_cache.glob("*.so"))  # built once, kept for the next process
    wrong = c.q + 1e-9 * scale
    assert not np.abs(wrong - vm.q).max() <= 1e-12 * scale  # the comparison sees a different trajectory


def test_without_a_compiler_the_virtual_machine_runs(monkeypatch) -> None:
    monkeypatch.setattr(c_code, "compiler", lambda: None)
    scene = gp.scenes.get("planar-chain", N=2)
    assert c_code.c_function(scene.model.kernel("direct").function) is None
    traj = runs(True)
    assert traj.status == "success" and traj.lane == "compiled"


def test_a_failing_compiler_falls_back(monkeypatch, tmp_path) -> None:
    monkeypatch.setattr(c_code, "compiler", lambda: "false")  # exits 1 and writes nothing
    monkeypatch.setenv("GAUSSPP_CACHE_DIR", str(tmp_path))
    scene = gp.scenes.get("planar-chain", N=2)
    assert c_code.c_function(scene.model.kernel("direct").function) is None
    assert not list(tmp_path.glob("*.so"))
