"""Machines built from bodies and joints beside the hand-written models and MuJoCo, in one run.

    .venv/bin/python benchmarks/multibody.py

For the parallelogram four-bar (IFToMM A02) and the spatial double parallelogram (an overconstrained spatial loop
the size of Bricard's: 30 rows, rank 23), both as ``gp.Multibody`` (examples/bodies_and_joints.py) and as the
hand-written scenes ``parallelogram`` and ``spatial-parallelogram``: one ``model.step`` (µs, best of repeats), the
whole default ``gp.simulate`` over 10 s (ms) and its error against the one-degree-of-freedom model; Bricard's
mechanism (IFToMM A04) from bodies and joints; beside them MuJoCo's A02 (one parallelogram cell, hinges and a
``connect``) and Bricard (a hinge chain closed by two ``connect``) at RK4, dt = 1e-3, per step and over 10 s.
"""

from __future__ import annotations

import importlib.util
import sys
import warnings
from pathlib import Path

import numpy as np
from _timing import best_ms, best_us

import gausspp as gp
from gausspp.scenes import parallelogram as P

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("bodies_and_joints", ROOT / "examples" / "bodies_and_joints.py")
assert _spec is not None and _spec.loader is not None
example = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(example)


def _row(label: str, model: gp.Model, q0: np.ndarray, v0: np.ndarray, error) -> dict[str, float | str]:  # type: ignore[no-untyped-def]
    model.step(0.0, q0, v0)
    step = best_us(lambda: model.step(0.0, q0, v0), 0.2, 5)
    grid = np.linspace(0.0, 10.0, 101)
    traj = gp.simulate(model, q0, v0, 10.0, record=grid)
    wall = best_ms(lambda: gp.simulate(model, q0, v0, 10.0, record=grid))
    return dict(what=label, step_us=step, wall_ms=wall, error=error(traj), rows=model.k, nv=model.nv)


def rows() -> list[dict[str, float | str]]:
    out = []
    mb = example.four_bar()
    q0, v0 = mb.assemble(fix={"crank1.θ": np.pi / 2}, rates={"crank1.θ̇": -1.0})
    scene = gp.scenes.get("parallelogram")

    def planar_error(traj: gp.Trajectory) -> float:
        theta, _ = P.one_dof_reference(traj.t)
        return float(np.abs(traj.q[:, 2] - theta).max())

    out.append(_row("A02 four-bar, bodies and joints", mb.model(), q0, v0, planar_error))
    out.append(_row("A02 four-bar, hand-written scene", scene.model, scene.q0, scene.v0, planar_error))
    sp = example.spatial_double_parallelogram()
    q0, v0 = sp.assemble(rates={"crank1.ωz": -1.0})
    spatial = gp.scenes.get("spatial-parallelogram")

    def spatial_error(traj: gp.Trajectory) -> float:
        theta, _ = P.one_dof_reference(traj.t, third_bar=True)
        return float(np.abs(traj.q[:, :2] - 0.5 * np.column_stack([np.cos(theta), np.sin(theta)])).max())

    out.append(_row("spatial double parallelogram, bodies and joints", sp.model(), q0, v0, spatial_error))
    out.append(_row("spatial double parallelogram, hand-written", spatial.model, spatial.q0, spatial.v0, spatial_error))
    br = example.bricard()
    q0, v0 = br.assemble()
    out.append(_row("Bricard (IFToMM A04), bodies and joints", br.model(), q0, v0, lambda traj: float("nan")))
    return out


def mujoco_rows() -> list[dict[str, float | str]]:
    """MuJoCo's A02 (``benchmarks/_mujoco_peers.py``) and Bricard (the gallery's MJCF: a hinge chain closed by two
    soft connects, RK4 at dt = 1e-3) over 10 s."""
    try:
        import _mujoco_peers as mj
        import mujoco

        ten = mj.parallelogram_ladder(1, t_end=10.0)
    except Exception as exc:  # mujoco is an optional extra
        print(f"(MuJoCo not run: {type(exc).__name__}: {exc})", file=sys.stderr)
        return []
    a02 = dict(what="A02 four-bar, MuJoCo (hinges + connect, RK4 dt 1e-3)", step_us=ten["step_us"],
               wall_ms=ten["wall_ms"], error=abs(ten["angle_error"]), rows=ten["rows"], nv=ten["nv"])  # fmt: skip
    model = mujoco.MjModel.from_xml_string(example.bricard_mjcf(1e-3))
    data = mujoco.MjData(model)

    def run() -> None:
        mujoco.mj_resetData(model, data)
        mujoco.mj_step(model, data, 10_000)

    wall = best_ms(run)
    bricard = dict(what="Bricard, MuJoCo (hinge chain + 2 connects, RK4 dt 1e-3)", step_us=wall * 1e3 / 10_000,
                   wall_ms=wall, error=float("nan"), rows=6, nv=int(model.nv))  # fmt: skip
    return [a02, bricard]


def main() -> None:
    warnings.simplefilter("ignore")
    table = rows()
    peers = mujoco_rows()
    table += peers
    mj = peers[0] if peers else None
    print(f"{'what':56s} {'rows':>5s} {'nv':>4s} {'step µs':>9s} {'10 s, ms':>9s} {'error':>9s}")
    print("-" * 97)
    for r in table:
        print(f"{r['what']:56s} {r['rows']:5d} {r['nv']:4d} {r['step_us']:9.1f} {r['wall_ms']:9.1f} {r['error']:9.1e}")
    by = {str(r["what"]): r for r in table}
    bodies, hand = by["A02 four-bar, bodies and joints"], by["A02 four-bar, hand-written scene"]
    print(f"\nA02 step, bodies / hand-written: {float(bodies['step_us']) / float(hand['step_us']):.2f}")
    if mj is not None:
        print(f"A02 step, bodies / MuJoCo's mj_step: {float(bodies['step_us']) / float(mj['step_us']):.2f}")
        print(f"A02 10 s, bodies / MuJoCo: {float(bodies['wall_ms']) / float(mj['wall_ms']):.2f}")
    if peers:
        b, m = by["Bricard (IFToMM A04), bodies and joints"], peers[1]
        print(f"Bricard step, bodies / MuJoCo's mj_step: {float(b['step_us']) / float(m['step_us']):.2f}")
    sb, sh = by["spatial double parallelogram, bodies and joints"], by["spatial double parallelogram, hand-written"]
    print(f"spatial loop step, bodies / hand-written: {float(sb['step_us']) / float(sh['step_us']):.2f}")
    print("errors: against the one-degree-of-freedom model (crank angle, rad, or crank centre, m); MuJoCo's: its "
          "crank angle at 10 s")  # fmt: skip


if __name__ == "__main__":
    main()
