"""Two masses, one constraint, two realizations (Kozlov 1989, §1).
===============================================================

A force F pulls mass m2; the constraint ẋ₂ = ẋ₁ keeps the masses moving together. Kept by a
rigid rod (ideal), both accelerate at F/(m1+m2). Kept by a follower force acting on m1 only
(a Béghin servo-constraint), m2 feels nothing but F and both accelerate at F/m2 — the same
constraint, a different motion. The figure shows both motions over time and their difference.
Run: python examples/two_masses.py [output.png [animation.gif]]
"""

import sys

import numpy as np

import gausspp as gp
from gausspp import plot

m1, m2, F = 1.0, 3.0, 2.0
print(f"m1 = {m1}, m2 = {m2}, force F = {F} on m2; constraint: v2 − v1 = 0\n")

# One step: Gauss's principle as a QP and the direct multiplier formula must agree.
for realization in ("ideal", "servo"):
    scene = gp.scenes.get("two-masses", m1=m1, m2=m2, F=F, realization=realization)
    direct = scene.model.step(0.0, scene.q0, scene.v0, solver="direct")
    gauss = scene.model.step(0.0, scene.q0, scene.v0, solver="qp")
    print(
        f"{realization:6s}: accelerations {gauss.a}, reaction {gauss.reaction}, compulsion Z = {gauss.compulsion:.4f}"
    )
    print(f"        QP vs direct: {gauss.disagreement(direct):.1e}; realizability margin {gauss.margin:.3f}")
print(
    f"\nclosed forms: rod F/(m1+m2) = {F / (m1 + m2):.4f}; "
    f"servo F/m2 = {F / m2:.4f}, servo force m1·F/m2 = {m1 * F / m2:.4f}\n"
)

# The whole motion over 2 s from rest: x(t) = x(0) + ½ a t².
t_end = 2.0
runs = {}
for realization, label in (("ideal", "rod"), ("servo", "servo")):
    scene = gp.scenes.get("two-masses", m1=m1, m2=m2, F=F, realization=realization, t_end=t_end)
    runs[label] = gp.simulate(scene.model, scene.q0, scene.v0, t_end, method="rk4", dt=0.01)
    assert scene.exact is not None  # this scene knows its exact motion
    q_exact, _ = scene.exact(t_end)
    print(
        f"{label:5s}: positions at t = {t_end:g}: {runs[label].q[-1]} (exact {q_exact}, error "
        f"{np.abs(runs[label].q[-1] - q_exact).max():.1e})"
    )

fig = plot.trajectory(
    runs,
    q_labels=["$x_1$", "$x_2$"],
    v_labels=["$v_1$", "$v_2$"],
    difference=True,
    title=(
        f"scene two-masses: m1 = {m1:g} kg, m2 = {m2:g} kg, F = {F:g} N on m2, no spring (k = 0), v0 = 0 m/s\n"
        "kept by a rod (ideal, solid, circles) or a follower force on m1 (servo, dashed, squares); t in s, x in m"
    ),
)
out = sys.argv[1] if len(sys.argv) > 1 else "two_masses.png"
fig.savefig(out, dpi=110, bbox_inches="tight")
print(f"\nfigure (positions and velocities over time, rod vs servo) written to {out}")

# %%
# The two motions side by side, on one time grid and one scale: the rod pulls m1 and holds m2 back (an arrow
# on each mass), the follower force pushes m1 alone, and the servo pair runs ahead.
anim = plot.animate(
    scene,
    runs,
    frames=40,
    fps=10,
    out=sys.argv[2] if len(sys.argv) > 2 else None,
    title=f"two masses, F = {F:g} N on m2: rod vs servo (arrows: the reaction on each mass, N)",
)
