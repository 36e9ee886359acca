"""Suslov's problem: the stability of its steady rotations by gp.linearize.
========================================================================

A rigid body turns about a fixed point with its angular velocity kept perpendicular to a body axis ``l``:
``(ω, l) = 0`` (Suslov's constraint, ideal). Euler's equations with the constraint's reaction ``μ l`` keep the
energy ``E = ½ ωᵀIω``, and ``ω`` is steady exactly when it lies along ``d = l × Il``: on each energy level there
are two steady rotations, ``ω± = ±κ d``. Writing ``ω`` in an orthonormal body basis ``(e₁, e₂, l)`` with ``e₁``
along ``d``, ``I₂`` the 2×2 block of ``I`` on the plane and ``b`` the plane components of ``Il``, the combination
``c = b·ω`` obeys ``ċ = s (bᵀ I₂⁻¹ b) c`` near ``ω = s b₂ e₁``: the small motions about a steady rotation have the
eigenvalues ``0`` (along the family of steady rotations) and ``s bᵀI₂⁻¹b`` — one of the two rotations attracts
every motion of its energy, the other repels.

``gp.linearize`` differentiates gausspp's step about each steady rotation (casadi's exact derivative, the
orientation held: torque-free, nothing depends on it) in two components of ``ω`` (the constraint fixes the
third) and gives those eigenvalues. A motion started near the repelling rotation runs to the attracting one at the
predicted rate (the figure: the distance on a log scale, beside the line of slope ``s bᵀI₂⁻¹b``).
Run: python examples/suslov_stability.py [output.png]
"""

import sys

import numpy as np

import gausspp as gp
from gausspp.scenes import suslov

scene = gp.scenes.get("rigid-body-servo", t_end=60.0)  # I = diag(1, 2, 3), l = n = (1, 1, 1)/√3: Suslov
I, l = np.array(scene.params["inertia"]), np.array(scene.params["l"])
model, energy = scene.model, 0.5


def closed_form(omega: np.ndarray) -> float:
    """``s bᵀI₂⁻¹b`` at the steady rotation ``omega = s b₂ e₁``."""
    d = np.cross(l, I @ l)
    e1 = d / np.linalg.norm(d)
    basis = np.column_stack([e1, np.cross(l, e1)])
    I2, b = basis.T @ I @ basis, basis.T @ I @ l
    s = (omega @ e1) / b[1]
    return float(s * b @ np.linalg.solve(I2, b))


def steady_rotations() -> dict[str, np.ndarray]:
    d = np.cross(l, I @ l)
    kappa = np.sqrt(2 * energy / (d @ I @ d))
    return {"ω+": kappa * d, "ω−": -kappa * d}


def linearized(omega: np.ndarray) -> gp.Linearization:
    """About the steady rotation (identity orientation) in ``ω₁, ω₂`` (state indices 4, 5)."""
    return gp.linearize(model, 0.0, [1.0, 0.0, 0.0, 0.0], omega, independent=[4, 5])


def main() -> None:
    rates = {}
    for name, omega in steady_rotations().items():
        lin = linearized(omega)
        rates[name] = closed_form(omega)
        verdict = "attracts" if rates[name] < 0 else "repels"
        values = np.array2string(lin.eigenvalues.real, precision=6)
        print(f"{name} = {np.array2string(omega, precision=4)}: eigenvalues {values}")
        print(f"    closed form 0 and {rates[name]:+.6f} — {verdict}")
    repelling = next(name for name, mu in rates.items() if mu > 0)
    attracting = next(name for name, mu in rates.items() if mu < 0)
    start = steady_rotations()[repelling] + 1e-4 * np.cross(l, steady_rotations()[repelling])  # a small push
    traj = gp.simulate(model, [1.0, 0.0, 0.0, 0.0], start, scene.t_end, record=np.linspace(0, scene.t_end, 601))
    final = suslov.steady_rotation(I, l, start)  # the attracting rotation of the pushed motion's own energy
    distance = np.linalg.norm(traj.v - final, axis=1)
    print(f"from near {repelling}: |ω − {attracting}| = {distance[-1]:.2e} after {scene.t_end:g} s")
    if len(sys.argv) > 1:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
        ax.semilogy(traj.t, distance, label=f"|ω(t) − {attracting}| (gausspp)")
        away = np.linalg.norm(traj.v - steady_rotations()[repelling], axis=1)
        ax.semilogy(traj.t, away, label=f"|ω(t) − {repelling}|")
        late = traj.t > 0.6 * scene.t_end
        t1 = traj.t[late][0]
        ax.semilogy(
            traj.t[late], distance[late][0] * np.exp(rates[attracting] * (traj.t[late] - t1)), "k--",
            label=f"slope {rates[attracting]:.4f}/s (linearization)",
        )  # fmt: skip
        title = "Suslov's rigid body: one steady rotation attracts"
        ax.set(xlabel="time t (s)", ylabel="distance in ω (rad/s)", title=title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.savefig(sys.argv[1], dpi=120)


if __name__ == "__main__":
    main()
