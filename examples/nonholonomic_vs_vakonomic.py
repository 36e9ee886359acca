"""Nonholonomic vs vakonomic: one constraint, two laws of motion (Kozlov 1989, (17)–(18)).
=======================================================================================

A skate (knife edge) slides in the plane and cannot move sideways: −sin θ ẋ + cos θ ẏ = 0.
The classical (d'Alembert–Lagrange, nonholonomic) law: the blade's reaction is a sideways
force, the skate turns uniformly and runs along a circle. The vakonomic law — the same
constraint imposed in the variational principle, as a controlled flywheel would (the inertial
realization with N = Φ) — gives another motion: the heading swings like a pendulum and the
skate drifts away in a zigzag of cusps.
Run: python examples/nonholonomic_vs_vakonomic.py [output.png [animation.gif]]
"""

import sys

import numpy as np

import gausspp as gp
from gausspp import plot
from gausspp.studies.figures import skate_runs, skate_title

v0, omega0, lam0 = 1.0, 1.0, 0.5  # speed along the blade, turning rate, vakonomic λ(0)
runs = skate_runs(v0=v0, omega0=omega0, lam0=lam0, t_end=10.0)

for law, traj in runs.items():
    x, y, theta = traj.q[-1]
    radius = np.hypot(traj.q[:, 0], traj.q[:, 1] - v0 / omega0)
    print(
        f"{law:12s}: at t = {traj.t[-1]:g} the skate is at ({x:.3f}, {y:.3f}), heading {theta:.3f} rad; "
        f"no sideways slip to {traj.max_residual():.0e}; distance from the circle's centre "
        f"{radius.min():.3f}…{radius.max():.3f}"
    )
print("nonholonomic: a circle of radius v0/ω0 = 1; vakonomic: the heading oscillates and the skate drifts")

fig = plot.skate(runs=runs, title=skate_title(v0=v0, omega0=omega0, lam0=lam0, t_end=10.0))
out = sys.argv[1] if len(sys.argv) > 1 else "nonholonomic_vs_vakonomic.png"
fig.savefig(out, dpi=110, bbox_inches="tight")
print(f"figure (paths in the plane, heading over time) written to {out}")

# %%
# The two skates moving: the blade, the way its contact point has gone, and the reaction on the blade
# (the sideways force of the ideal constraint; for the vakonomic law ``−λ̇ N_v − λ [N]``).
anim = plot.animate(
    gp.scenes.get("skate", v0=v0, omega0=omega0, lam0=lam0),
    runs,
    frames=50,
    fps=10,
    out=sys.argv[2] if len(sys.argv) > 2 else None,
    title=f"skate, v0 = {v0:g} m/s, ω0 = {omega0:g} rad/s, λ0 = {lam0:g}: the same start, two laws",
)
