"""A UR5's tool follows a prescribed path, realized by its six joint torques: servo inverse dynamics.
==================================================================================================

The UR5 of example-robot-data (``gp.from_urdf``): six revolute joints, ``A(q) q̈ = τ − h(q, v)``. The tool frame's
position ``p(q)`` must follow ``p₀ + (1 − cos 2t) d`` — three coordinates — and the constraint is realized by a
Béghin servo force ``gp.Force`` whose directions are the six joint torques (the identity). Six actuators for three
path coordinates: the arm is redundant, and Gauss's principle picks, among the torques that keep the tool on its
path, the motion of least compulsion (the QP solver) — the motion the arm would have if the tool were guided by an
ideal constraint. The model is the scene ``ur5-tool-path`` (gausspp/scenes/ur5_tool_path.py).
Nothing holds the three-dimensional self-motion: the wrists swing freely (the printed joint
speeds), which is why the move is kept short. The computed torques are then compared with Pinocchio's
inverse dynamics (RNEA) of the computed motion, and the integral principle checks the motion.
Needs the robot extras: pip install 'gausspp[robots]' example-robot-data pin
Run: python examples/robot_arm_servo.py [output.png]
"""

import sys
import time
from importlib import metadata, util

import casadi as ca
import numpy as np

import gausspp as gp
from gausspp import plot

missing = [name for name in ("adam", "pinocchio") if util.find_spec(name) is None]
try:
    metadata.distribution("example-robot-data")
except metadata.PackageNotFoundError:
    missing = [*missing, "example-robot-data"]
if missing:
    print(f"robot_arm_servo needs {', '.join(missing)}: pip install 'gausspp[robots]' example-robot-data pin")
    sys.exit(0)
import pinocchio as pin  # noqa: E402  (optional: imported once known present)

from gausspp.scenes.ur5_tool_path import ur5_urdf  # noqa: E402

scene = gp.scenes.get("ur5-tool-path")  # the tool path p0 + (1 - cos 2t) d, every joint a motor
model, q0, T = scene.model, scene.q0, scene.t_end  # T = 1.2 s; longer, the free self-motion (below) grows
mech, d = model.mechanism, np.array(scene.params["d"])  # the tool moves 2|d| ≈ 21 cm out and back in π s
path = ur5_urdf()
p0 = np.array(ca.Function("p", [mech.q], [gp.frame_position(mech, "tool0")])(q0)).ravel()
start = time.perf_counter()
samples = np.linspace(0.0, T, 1001)  # dense enough for the integral principle's quintic splines
traj = gp.simulate(model, q0, scene.v0, T, solver="qp", stabilize="baumgarte", record=samples)
wall = time.perf_counter() - start

pm = pin.buildModelFromUrdf(path)
data = pm.createData()
rnea = np.array([pin.rnea(pm, data, q, v, a) for q, v, a in zip(traj.q, traj.v, traj.a, strict=True)])
relative = np.linalg.norm(traj.reaction - rnea, axis=1) / np.linalg.norm(rnea, axis=1)
verdict = gp.verify(model, traj)
print(f"UR5 ({', '.join(mech.joint_names)}): tool path of 3 coordinates by 6 joint torques (least compulsion)")
print(f"  simulate (QP solver)          {wall:.2f} s, status {traj.status}")
print(f"  tool off its path            {np.abs(traj.g).max():.1e} m")
print(f"  torques vs Pinocchio RNEA    {relative.max():.1e} (largest relative difference)")
print(f"  largest joint speed          {np.abs(traj.v).max():.1f} rad/s (the free self-motion)")
print(f"  largest torque               {np.abs(traj.reaction).max():.1f} N m")
print(f"  gp.verify                    {verdict.message}")

plt = plot.pyplot()
fig = plt.figure(figsize=(11, 4.2), layout="constrained")
ax_path = fig.add_subplot(1, 2, 1, projection="3d")
ax_torque = fig.add_subplot(1, 2, 2)
tool = ca.Function("p", [mech.q], [gp.frame_position(mech, "tool0")])
xyz = np.array([np.array(tool(q)).ravel() for q in traj.q])
ax_path.plot(*xyz.T, color="#0072B2", lw=2.5, label="tool (computed motion)")
ax_path.plot(*(p0 + np.outer(1 - np.cos(2 * traj.t[::40]), d)).T, "o", ms=3, color="#D55E00", label="p(t) prescribed")
ax_path.set(xlabel="x (m)", ylabel="y (m)", zlabel="z (m)", title=f"tool path, t = 0 … {T:g} s")
ax_path.legend(fontsize=8)
for i, (name, tau) in enumerate(zip(traj.labels.coordinate, traj.reaction.T, strict=True)):
    ax_torque.plot(traj.t, tau, color=plot.base.palette(i), label=name)
ax_torque.plot(traj.t[::40], rnea[::40], "k.", ms=2)
ax_torque.set(xlabel="time t (s)", ylabel="joint torque (N·m)", title="joint torques (dots: Pinocchio RNEA)")
fig.suptitle(
    f"scene ur5-tool-path: UR5 tool follows p₀ + (1 − cos 2t) d, d = {plot.base.vec(d)} m, by its 6 joint torques"
)
ax_torque.legend(fontsize=7, ncol=2)
out = sys.argv[1] if len(sys.argv) > 1 else "robot_arm_servo.png"
fig.savefig(out, dpi=100)
print(f"\nfigure written to {out}")
