"""Verifying a trajectory, and catching a wrong one, by the integral principle (Kozlov 1989, §6).
==============================================================================================

A path x(t) on the constraint is a motion of a model iff no admissible variation δx (vanishing
at the ends, obeying the realization's virtual displacements) lowers the integral compulsion
(23). gp.verify finds the best δx; the relative gap it achieves is ≈ 0 for a motion and of
order one for a path of another realization.

Here: two masses on a spring, kept together by a rod. The rod's motion is checked against the
rod model (a motion) and against the servo model, whose virtual displacements are δx₁ = 0 —
the same constraint, another realization, so the path is caught.
Run: python examples/verify_a_trajectory.py [output.png]
"""

import sys

import numpy as np

import gausspp as gp
from gausspp import plot

rod = gp.scenes.get("two-masses", realization="ideal", k=3.0, v=0.5)
servo = gp.scenes.get("two-masses", realization="servo", k=3.0, v=0.5)
t_end = 2.0
path = gp.simulate(
    rod.model, rod.q0, rod.v0, t_end, method="DOP853", rtol=1e-12, atol=1e-14, record=np.linspace(0, t_end, 201)
)

checks = {
    "rod's motion vs the rod model": gp.verify(rod.model, path),
    "rod's motion vs the servo model": gp.verify(servo.model, path),
}
for name, check in checks.items():
    verdict = "a motion" if check.is_motion else "NOT a motion"
    print(f"{name}: relative gap {check.relative_gap:.2e} (tolerance {check.tolerance:.1e}) → {verdict}")
ok = checks["rod's motion vs the rod model"]
inside = slice(1, -1)
print(
    "rod tension recovered from (23) vs the simulation's: max difference "
    f"{np.nanmax(np.abs(ok.multipliers[inside, 0] - path.u[inside, 0])):.1e}"
)

p = rod.params
title = (
    f"scene two-masses: m1 = {p['m1']:g} kg, m2 = {p['m2']:g} kg, F = {p['F']:g} N, spring k = {p['k']:g} N/m, "
    f"v0 = {p['v']:g} m/s, t = 0 … {t_end:g} s"
)
fig = plot.verification(checks, path, title=title)
out = sys.argv[1] if len(sys.argv) > 1 else "verify_a_trajectory.png"
fig.savefig(out, dpi=110, bbox_inches="tight")
print(f"figure (minimizing variation δx(t) and the gap, passing and failing) written to {out}")
