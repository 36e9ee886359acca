"""Two masses, one constraint, two realizations (Kozlov 1989, §1).

A force F pulls mass m2; the constraint ẋ₂ = ẋ₁ keeps the masses moving together. Kept by a
rigid rod (ideal), both accelerate at F/(m1+m2). Kept by a follower force acting on m1 only
(a Béghin servo-constraint), m2 feels nothing but F and both accelerate at F/m2 — the same
constraint, a different motion. Run: python examples/two_masses.py
"""

import gausspp as gp

m1, m2, F = 1.0, 3.0, 2.0
print(f"m1 = {m1}, m2 = {m2}, force F = {F} on m2; constraint: v2 − v1 = 0\n")
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
    f"servo F/m2 = {F / m2:.4f}, servo force m1·F/m2 = {m1 * F / m2:.4f}"
)
