"""Where can a servo torque along n keep the constraint (ω, l) = 0?  (Kozlov 1989, §2)

A rigid body (principal moments 1, 2, 3) must keep (ω, l) = 0 by a torque λn along a body axis
n. The step is solvable iff (I⁻¹n, l) ≠ 0. The paper calls the bad set "n orthogonal to l",
which is right only when l is a principal axis. For a non-principal l the true zero set is the
great circle n ⟂ I⁻¹l, not n ⟂ l. The map shows the realizability margin of every direction n.
Run: python examples/realizability_map.py [output.png]
"""

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import gausspp as gp

inertia = np.diag([1.0, 2.0, 3.0])
l = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)

lon = np.linspace(-np.pi, np.pi, 361)
lat = np.linspace(-np.pi / 2, np.pi / 2, 181)
LON, LAT = np.meshgrid(lon, lat)
N = np.stack([np.cos(LAT) * np.cos(LON), np.cos(LAT) * np.sin(LON), np.sin(LAT)], axis=-1)
margin = np.array([[gp.realizability.margin(inertia, l[None, :], n[:, None]) for n in row] for row in N])

fig, ax = plt.subplots(figsize=(9, 4.5))
im = ax.pcolormesh(np.degrees(LON), np.degrees(LAT), np.log10(np.maximum(margin, 1e-6)), cmap="viridis", shading="auto")
fig.colorbar(im, ax=ax, label="log₁₀ realizability margin")
ax.contour(np.degrees(LON), np.degrees(LAT), N @ np.linalg.solve(inertia, l), [0.0], colors="red", linewidths=2)
ax.contour(np.degrees(LON), np.degrees(LAT), N @ l, [0.0], colors="white", linestyles="--", linewidths=1.5)
ax.plot([], [], "r-", label="true zero set (I⁻¹n, l) = 0")
ax.plot([], [], "w--", label="naive n ⊥ l")
ax.legend(loc="lower left", facecolor="0.3", labelcolor="white")
ax.set(
    xlabel="longitude of n [°]",
    ylabel="latitude of n [°]",
    title="Servo torque along n keeping (ω, l) = 0, l = (1,1,1)/√3, I = diag(1,2,3)",
)
out = sys.argv[1] if len(sys.argv) > 1 else "realizability_map.png"
fig.savefig(out, dpi=110, bbox_inches="tight")
off = np.abs(N @ l) < 0.01
print(
    f"directions with n ⊥ l: margin between {margin[off].min():.3f} and {margin[off].max():.3f} — most are realizable"
)
print(f"smallest margin on the grid: {margin.min():.2e} (near the red circle n ⊥ I⁻¹l); figure written to {out}")
