"""Error against run time: which integrator and step solver buys accuracy cheapest.
================================================================================

The pendulum made by two holonomic constraints (a planar body pinned at a point) is run over a
sweep of step sizes (fixed-step methods) or tolerances (adaptive ones), with each step solved
by the direct multiplier formula and by Gauss's QP. Each run's final-state error against a
reference is plotted against its wall time: lower left is better. (`gausspp report` runs the
full study on every scene.)
Run: python examples/error_vs_runtime.py [output.png]
"""

import sys

import gausspp as gp
from gausspp import plot, report

rows = report.work_precision(["pendulum"], ["rk4", "DOP853", "Radau"], ["direct", gp.qp.DEFAULT], repeats=2)
print(report.table(rows))
best = report.best_per_scene(rows, target=1e-10)["pendulum"]
if best is not None:
    print(
        f"\ncheapest run reaching 1e-10: {best.method} with {best.solver} at {best.setting}, "
        f"{best.wall_time * 1e3:.1f} ms"
    )

p = gp.scenes.get("pendulum").params  # the parameters the study ran with, for the title
units = f"m = {p['m']:g} kg, Ic = {p['Ic']:g} kg·m², L = {p['L']:g} m, g = {p['g']:g} m/s², t_end = {p['t_end']:g} s"
fig = plot.work_precision(rows, "pendulum", title=units)
out = sys.argv[1] if len(sys.argv) > 1 else "error_vs_runtime.png"
fig.savefig(out, dpi=110, bbox_inches="tight")
print(f"work-precision diagram written to {out}")
