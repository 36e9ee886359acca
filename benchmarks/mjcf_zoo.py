"""MuJoCo's model collections through ``gp.from_mjcf``, beside MuJoCo, in one run: ``python benchmarks/mjcf_zoo.py``.

Needs MuJoCo (``pip install gausspp[peers]``) and the collections (``$GAUSSPP_MJCF_ZOO``, or ``../shared/mjcf-zoo``
beside the repository, as the tests find them).

1. **Load time** of each of the 26 files (``gp.from_mjcf`` whole: MuJoCo's compiler, the tree's expressions, the
   rows and contacts; best of 3), or what the file lacks.
2. **Coordinates**: Bricard's mechanism (IFToMM A04) as ``gp.Multibody`` writes it — one rigid body per link in
   maximal coordinates, six hinges as rows — and as ``gp.from_mjcf`` reads the same machine from MJCF — MuJoCo's
   joint coordinates, a tree of five hinges closed by two ``connect`` rows: the sizes, ``model.step``'s cost and the
   wall of a 10 s ``gp.simulate`` at ``rtol`` 1e-10 (the default), 1e-6 and 1e-3 (warm; best of 3), its status,
   steps and largest constraint residual.
3. **Contacts**: hopper, walker2d, half_cheetah and ant dropped on the floor from their reference pose for 2 s,
   zero control: gausspp's whole ``gp.simulate`` (hard frictional contacts, the friction lane; warm, best of 3; in
   casadi's virtual machine and as C, ``codegen=True``) against MuJoCo's ``mj_step`` at the file's own timestep for
   the same 2 s (best of 3), and the ratio of the walls — gausspp's cost per MuJoCo step of the same motion.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))

import gausspp as gp  # noqa: E402
from benchmarks._optional import peer  # noqa: E402
from benchmarks._timing import best_ms, best_us  # noqa: E402
from tests.mjcf_zoo import models, zoo  # noqa: E402

DROPPED = ["gymnasium/hopper.xml", "gymnasium/walker2d.xml", "gymnasium/half_cheetah.xml", "gymnasium/ant.xml"]


def load_times() -> None:
    print("\n1. Load time of each file (gp.from_mjcf, best of 3)")
    loaded = 0
    for name in models():
        path = str(zoo() / name)
        try:
            ms = min(_timed(lambda: gp.from_mjcf(path)) for _ in range(3)) * 1e3
        except gp.InputError as exc:
            lacks = "; ".join(line.strip("- ").split(":")[0] for line in str(exc).splitlines()[1:4])
            print(f"  {name:40s} refused: {lacks} …")
            continue
        loaded += 1
        print(f"  {name:40s} {ms:7.1f} ms")
    print(f"  {loaded} of {len(models())} load")


def _timed(fn) -> float:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def coordinates() -> None:
    import bodies_and_joints as example

    print("\n2. Bricard's mechanism: maximal coordinates (gp.Multibody) and MuJoCo's joint coordinates (from_mjcf)")
    mb = example.bricard()
    q0, v0 = mb.assemble()
    machine = gp.from_mjcf(example.bricard_mjcf(1e-3))
    rows = [("maximal (gp.Multibody)", mb.model(), q0, v0)]
    qj, vj = machine.initial_state()
    rows.append(("joint (gp.from_mjcf)", machine.model, qj, vj))
    for label, model, q, v in rows:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gp.DriftWarning)
            step = best_us(lambda model=model, q=q, v=v: model.step(0.0, q, v), 0.3, 3)
            line = f"  {label:24s} nq {model.nq:3d}, {model.k:2d} rows: model.step {step:7.1f} µs; 10 s gp.simulate"
            for rtol in (1e-10, 1e-6, 1e-3):  # the defaults, then loosened (the default drift control projects)
                wall = best_ms(
                    lambda model=model, q=q, v=v, r=rtol: gp.simulate(model, q, v, 10.0, rtol=r, throw=False)
                )
                traj = gp.simulate(model, q, v, 10.0, rtol=rtol, throw=False)
                line += f"\n      rtol {rtol:.0e}: {wall:7.1f} ms ({traj.status}, {traj.steps} steps, "
                line += f"residual {traj.max_residual():.1e})"
        print(line)


def contacts(mujoco) -> None:  # type: ignore[no-untyped-def]
    print("\n3. Dropped on the floor, 2 s, zero control: gausspp (hard contacts) against mj_step (its own timestep)")
    for name in DROPPED:
        path = str(zoo() / name)
        m = mujoco.MjModel.from_xml_path(path)
        d = mujoco.MjData(m)
        steps = round(2.0 / m.opt.timestep)
        vm = gp.from_mjcf(path)
        q0, v0 = vm.initial_state()

        def mujoco_run() -> None:
            mujoco.mj_resetData(m, d)
            d.qpos[:] = q0
            mujoco.mj_step(m, d, steps)

        mj = best_ms(mujoco_run)
        line = f"  {name:28s} mj_step ×{steps}: {mj:6.1f} ms ({mj / steps * 1e3:5.1f} µs/step)"
        for label, codegen in (("VM", False), ("C", True)):
            machine = vm if not codegen else gp.from_mjcf(path, codegen=True)
            ms = best_ms(lambda machine=machine: gp.simulate(machine.model, q0, v0, 2.0))
            line += f"; gausspp {label} {ms:7.1f} ms = {ms / mj:6.1f}×"
        print(line)


def main() -> None:
    if zoo() is None:
        print("MuJoCo's model collections are not on this machine (set GAUSSPP_MJCF_ZOO)")
        return
    load_times()
    coordinates()
    mujoco = peer("mujoco")
    if mujoco is not None:
        contacts(mujoco)


if __name__ == "__main__":
    main()
