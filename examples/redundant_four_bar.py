"""A four-bar linkage with a redundant loop equation: one motion, the least-norm multipliers.
==========================================================================================

The scene ``four-bar-redundant``: a crank (0.3 m), a coupler (1 m) and a rocker (0.8 m) on a 1 m ground, uniform
bars under gravity, the crank started at 6 rad/s. The loop closes by two equations; a third one, the closure
projected on a fixed direction, adds nothing — the three rows of ``J`` have rank 2. The direct multiplier
formula needs ``S = J A⁻¹ Jᵀ`` invertible and refuses; Gauss's principle does not care: the compulsion has one
minimizer, so the acceleration is unique, and the QP returns it with the least-norm multipliers. The script
compares that motion with the minimal model's (two rows), step by step and over 1.2 s (about one turn of the
crank), and plays the linkage with its coupler curve (the way the coupler's midpoint goes).
Run: python examples/redundant_four_bar.py [output.png [animation.gif]]
"""

import sys

import numpy as np

import gausspp as gp
from gausspp import plot

redundant = gp.scenes.get("four-bar-redundant")
minimal = gp.scenes.get("four-bar-redundant", redundant=False)
t0, q0, v0 = 0.0, redundant.q0, redundant.v0

# One step: the direct formula refuses, the QP answers, and the answer is the minimal model's.
try:
    redundant.model.step(t0, q0, v0, solver="direct")
except gp.GaussppError as exc:
    print(f"direct formula on the redundant model refuses: {str(exc)[:110]}…")
step = redundant.model.step(t0, q0, v0, solver="qp")
reference = minimal.model.step(t0, q0, v0, solver="direct")
print(f"QP on the redundant model: q̈ = {np.round(step.a, 6)}, margin {step.margin:.1e} (0: rows dependent)")
print(f"minimal model, direct:     q̈ = {np.round(reference.a, 6)}")
print(f"relative difference {np.linalg.norm(step.a - reference.a) / np.linalg.norm(reference.a):.1e}")
print(f"least-norm multipliers u = {np.round(step.u, 4)} (three rows), minimal u = {np.round(reference.u, 4)}")
print(f"the same reaction: ‖R − R_min‖ / ‖R_min‖ = "
      f"{np.linalg.norm(step.reaction - reference.reaction) / np.linalg.norm(reference.reaction):.1e}")  # fmt: skip

# The whole motion: both models, the same integrator.
T = 1.2  # about one turn of the crank
times = np.linspace(0.0, T, 201)
runs = {
    name: gp.simulate(scene.model, q0, v0, T, solver=solver, method="DOP853", rtol=1e-10, atol=1e-12, record=times)
    for name, scene, solver in (("redundant, QP", redundant, "qp"), ("minimal, direct", minimal, "direct"))
}
a, b = runs["redundant, QP"], runs["minimal, direct"]
print(f"\nover {T:g} s: max |q − q_min| = {np.abs(a.q - b.q).max():.1e} rad, "
      f"loop closure off by at most {a.max_residual():.1e} m")  # fmt: skip
print(f"energy drift (redundant run) {np.ptp(a.energy) / np.abs(a.energy).max():.1e} (relative)")

plt = plot.pyplot()
fig, (ax_q, ax_u) = plt.subplots(1, 2, figsize=(11, 4), layout="constrained")
for i, name in enumerate(("crank θ1", "coupler θ2", "rocker θ3")):
    ax_q.plot(a.t, a.q[:, i], color=plot.palette(i), label=f"{name} (rad)")
    ax_q.plot(b.t[::10], b.q[::10, i], "o", ms=3, color=plot.palette(i))
ax_q.set(xlabel="time t (s)", ylabel="relative angle (rad)", title="angles: lines redundant QP, dots minimal model")
ax_q.legend(fontsize=8)
for i in range(a.u.shape[1]):
    ax_u.plot(a.t, a.u[:, i], color=plot.palette(i), label=f"row {i + 1} of three (least norm)")
for i in range(b.u.shape[1]):
    ax_u.plot(b.t, b.u[:, i], "--", color=plot.palette(i + 4), label=f"row {i + 1} of two (minimal)")
ax_u.set(xlabel="time t (s)", ylabel="multiplier λ (N)", title="multipliers: least-norm split vs minimal rows")
ax_u.legend(fontsize=7)
p = redundant.params
fig.suptitle(
    f"scene four-bar-redundant: l0 = {p['l0']} m, l1 = {p['l1']} m, l2 = {p['l2']} m, l3 = {p['l3']} m, "
    f"ρ = {p['rho']} kg/m, g = {p['g']} m/s², crank at {p['omega0']} rad/s; third row {p['third_row']!r}"
)
out = sys.argv[1] if len(sys.argv) > 1 else "redundant_four_bar.png"
fig.savefig(out, dpi=100)
print(f"\nfigure (angles and multipliers over time, both models) written to {out}")

# %%
# The linkage moving (the redundant model's run), with the coupler curve traced by the coupler's midpoint.
anim = plot.animate(
    redundant,
    a,
    frames=50,
    fps=10,
    out=sys.argv[2] if len(sys.argv) > 2 else None,
    title="four-bar with a redundant loop row: crank 0.3 m, coupler 1 m, rocker 0.8 m, ground 1 m",
)
