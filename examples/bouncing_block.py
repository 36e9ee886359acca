"""A tilted block dropped on a floor: it rocks on its corners, loses energy at each impact, and settles.
=====================================================================================================

The scene ``block-on-floor``: a planar block (width 0.4, height 0.2, mass 1) whose two bottom corners
are unilateral contacts with restitution e. Tilted, it lands on one corner, rocks from corner to
corner, and each corner ends a Zeno sequence of ever smaller bounces with a plastic impact (slower
than ``rest_speed``): then it rests, the floor carrying its weight, half under each corner. A corner
already resting when the other one lands takes part in that impact: it is listed as a plastic impact
at speed ≈ 0 (the squares of one colour while the other corner bounces).
Dropped flat, it bounces like a point mass at closed-form times.
The figure shows the gaps, the contact forces and the energy (``gausspp.plot.contacts``).
Run: python examples/bouncing_block.py [output.png [animation.gif]]
"""

import sys
import time
from collections import Counter

import numpy as np

import gausspp as gp
from gausspp import plot
from gausspp.scenes.block_on_floor import bounce_times

TOL = dict(method="DOP853", rtol=1e-11, atol=1e-13)


def run(**params: float) -> tuple[gp.scenes.Scene, gp.Trajectory, float]:
    scene = gp.scenes.get("block-on-floor", **params)
    start = time.perf_counter()
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, record=np.linspace(0.0, scene.t_end, 1001), **TOL)
    return scene, traj, time.perf_counter() - start


# -- the tilted block ------------------------------------------------------------------------------------
scene, traj, wall = run(tilt=0.3, e=0.5, drop=0.3, t_end=1.0)
p = scene.params
print(
    f"block {p['w']} × {p['h']}, m = {p['m']}, tilted {p['tilt']} rad, lower corner {p['drop']} above the floor, "
    f"e = {p['e']}: {len(traj.events)} events in {wall:.2f} s ({traj.method}, rtol {TOL['rtol']:g})\n"
)
print(f"{'t':>9}  {'event':<15} {'contact':<8} {'ġ before → after':>22}")
shown = 12
for ev in traj.events[:shown]:
    kind = "plastic impact" if ev.get("plastic") else ev["kind"]
    speeds = f"{ev['speed_before']:+.4f} → {ev['speed_after']:+.4f}" if ev["kind"] == "impact" else ""
    print(f"{ev['t']:9.5f}  {kind:<15} {ev['contact']:<8} {speeds:>22}")
if len(traj.events) > shown:
    print(f"{'…':>9}  {len(traj.events) - shown} more: Zeno sequences, each bounce e = {p['e']} times slower")
counts = Counter(("plastic impact" if ev.get("plastic") else ev["kind"], ev["contact"]) for ev in traj.events)
print("all events:", ", ".join(f"{n} × {kind} {contact}" for (kind, contact), n in sorted(counts.items())))
last = traj.events[-1]["t"]
print(f"last event at t = {last:.6f}: from then on the block rests")

weight = p["m"] * p["g"]
force = traj.contact_force[-1]
per_corner = ", ".join(f"{name} {f:.9f}" for name, f in zip(scene.model.contact_row_names, force, strict=True))
print(
    f"\nfinal contact forces {per_corner}: "
    f"sum {force.sum():.9f} vs the weight m g = {weight:.9f}; "
    f"each corner {weight / 2:.9f} (the centre of mass is midway between them)"
)
jumps = {
    (ev["t"], ev["kinetic_energy_before"], ev["kinetic_energy_after"]) for ev in traj.events if ev["kind"] == "impact"
}
lost = sum(before - after for _, before, after in jumps)
print(
    f"energy: E(0) = {traj.energy[0]:.6f}, E(end) = {traj.energy[-1]:.6f} (= m g h/2 = {weight * p['h'] / 2:.6f}); "
    f"lost at {len(jumps)} velocity jumps {lost:.6f}; balance E(0) − E(end) − lost = "
    f"{traj.energy[0] - traj.energy[-1] - lost:.1e}"
)

# -- the flat drop: closed-form impact times ------------------------------------------------------------------
flat, flat_traj, flat_wall = run(tilt=0.0, e=0.5, drop=0.3, t_end=1.0)
impacts = sorted({ev["t"] for ev in flat_traj.events if ev["kind"] == "impact"})  # both corners at once
count = 6
exact = bounce_times(flat.params["drop"], flat.params["e"], flat.params["g"], count)
print(f"\nflat drop ({flat_wall:.2f} s): both corners hit together, like a point mass")
print(f"{'k':>3} {'impact time':>14} {'closed form':>14} {'error':>9}")
for k, (t_sim, t_exact) in enumerate(zip(impacts[:count], exact, strict=False), start=1):
    print(f"{k:3d} {t_sim:14.10f} {t_exact:14.10f} {abs(t_sim - t_exact):9.1e}")
v1 = np.sqrt(2 * flat.params["g"] * flat.params["drop"])
t_inf = exact[0] + 2 * flat.params["e"] * v1 / (flat.params["g"] * (1 - flat.params["e"]))
print(
    f"rest at t = {impacts[-1]:.6f} (the bounces accumulate at t∞ = {t_inf:.6f}); "
    f"final forces {np.round(flat_traj.contact_force[-1], 9)}"
)

fig = plot.contacts(
    scene.model,
    traj,
    title=(
        f"scene block-on-floor: block {p['w']} m × {p['h']} m, m = {p['m']} kg, tilted {p['tilt']} rad, "
        f"dropped from {p['drop']} m, restitution e = {p['e']}: rocks on its corners, then rests"
    ),
)
out = sys.argv[1] if len(sys.argv) > 1 else "bouncing_block.png"
fig.savefig(out, dpi=100)
print(f"\nfigure (gaps, contact forces, energy over time) written to {out}")

# %%
# The tilted block rocking to rest: its outline, the way its centre of mass goes, and the sum of the
# contact forces at the centre of mass (zero in flight, ``m g`` at rest).
anim = plot.animate(
    scene,
    traj,
    frames=50,
    fps=10,
    out=sys.argv[2] if len(sys.argv) > 2 else None,
    title=f"block {p['w']} m × {p['h']} m tilted {p['tilt']} rad, e = {p['e']}: rocking to rest",
)
