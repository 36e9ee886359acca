"""One constraint, three realizations: three motions (Kozlov 1989, §§2, 4).
========================================================================

A rigid body (principal moments 1, 2, 3) turns about a fixed point and must keep the body
angular velocity ω in the plane (ω, l) = 0, l = (1, 1, 1)/√3. The constraint is kept

* ideally: the reaction torque is along l, as for a knife edge — Suslov's problem; the reaction
  does no work, the energy is conserved and ω tends to a steady rotation ω∞ ∥ l × Il;
* by a servo torque along the body axis n = (0, 0, 1) (a Béghin servo-constraint): a motor
  pushes along n as hard as needed; it does work;
* by a flywheel on the axis n, whose spin the motor controls (the inertial realization).

Same body, same constraint, same initial ω — three different motions.
Run: python examples/one_constraint_three_realizations.py [output.png [animation.gif]]
"""

import sys

import numpy as np

import gausspp as gp
from gausspp import plot
from gausspp.studies.figures import suslov_steady, three_realizations_runs

inertia, l, n = (1.0, 2.0, 3.0), (1.0, 1.0, 1.0), (0.0, 0.0, 1.0)
omega0, lam0, t_end = (0.0, 1.0, -1.0), 0.0, 10.0  # the flywheel starts with no spin of its own
runs = three_realizations_runs(inertia, l, n, omega0, lam0, t_end)

I = np.diag(inertia)
for key, traj in runs.items():
    w = traj.v
    energy = 0.5 * np.einsum("ti,ij,tj->t", w, I, w)
    print(
        f"{plot.THREE_LABELS[key]:45s} ω(10) = {np.round(w[-1], 3)}, energy {energy[0]:.3f} → {energy[-1]:.3f}, "
        f"|(ω, l)| ≤ {traj.max_residual():.0e}, margin ≥ {traj.margin.min():.3f}"
    )

fig = plot.three_realizations(inertia, l, n, omega0, lam0, t_end, runs=runs, steady=suslov_steady(inertia, l, omega0))
out = sys.argv[1] if len(sys.argv) > 1 else "one_constraint_three_realizations.png"
fig.savefig(out, dpi=110, bbox_inches="tight")
print(f"figure (ω over time for each realization, ω in the constraint plane, energy) written to {out}")

# %%
# The body turning in each realization: its axes e₁, e₂, e₃ (blue, orange, green) about the fixed point,
# seen from one fixed view, with the way their tips go. Same start, three different turns.
anim = plot.animate(
    gp.scenes.get("gyrostat", inertia=inertia, l=l, n=n, omega0=omega0, lam0=lam0, t_end=t_end),
    {plot.THREE_LABELS[key].split(":")[0]: traj for key, traj in runs.items()},
    frames=50,
    fps=10,
    out=sys.argv[2] if len(sys.argv) > 2 else None,
    title=f"rigid body I = {inertia} kg·m², (ω, l) = 0 with l = {l}, n = {n}: body axes",
)
