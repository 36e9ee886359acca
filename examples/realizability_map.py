"""Where can a servo torque along n keep the constraint (ω, l) = 0?  (Kozlov 1989, §2)
===================================================================================

A rigid body (principal moments 1, 2, 3) must keep (ω, l) = 0 by a torque λn along a body axis
n. The step is solvable iff (I⁻¹n, l) ≠ 0. The paper calls the bad set "n orthogonal to l",
which is right only when l is a principal axis. For a non-principal l the true zero set is the
great circle n ⟂ I⁻¹l, not n ⟂ l. The map shows the realizability margin of every direction n.
Run: python examples/realizability_map.py [output.png]
"""

import sys

import numpy as np

from gausspp import plot
from gausspp.studies.realizability_map import realizability_grid

inertia = (1.0, 2.0, 3.0)
l = (1.0, 1.0, 1.0)  # not a principal axis

grid = realizability_grid(inertia, l, resolution=1.0)
print(f"I = diag{inertia}, l = {np.round(grid.l, 3)}; I⁻¹l points along {np.round(grid.pole, 3)}")
print(
    f"on the naive circle n ⟂ l the margin runs from {grid.naive_margin.min():.3f} to "
    f"{grid.naive_margin.max():.3f} (median {np.median(grid.naive_margin):.3f}): most of these axes work"
)
print(f"on the true zero set (I⁻¹n, l) = 0 it is at most {grid.true_margin.max():.1e}: these axes cannot act")

principal = realizability_grid(inertia, (0.0, 0.0, 1.0))
print(
    f"for the principal axis l = (0, 0, 1) the two circles coincide: margin on n ⟂ l at most "
    f"{principal.naive_margin.max():.1e}"
)

fig = plot.realizability_map(grid=grid, scene="rigid-body-servo")
out = sys.argv[1] if len(sys.argv) > 1 else "realizability_map.png"
fig.savefig(out, dpi=110, bbox_inches="tight")
print(f"map of the margin over the sphere of axes n written to {out}")
