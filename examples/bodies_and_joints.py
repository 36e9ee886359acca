"""Bodies and joints: a four-bar, a slider-crank and an overconstrained spatial loop in a few lines each.
======================================================================================================

``gp.Multibody`` takes a machine as its bodies (mass, inertia, where they are) and its joints (which points of
which bodies are pinned, slide, or are welded) and makes the ``gp.Model``: every body in maximal coordinates — a
planar body's ``(x, y, θ)``, a spatial body's centre and unit quaternion — and every joint as named constraint rows,
``"revolute crank1-coupler [x]"``. ``mb.assemble`` puts the bodies on their joints from what is held (a crank's
angle and rate).

* The **parallelogram four-bar** (IFToMM A02): its bars line up twice a turn, where one row becomes dependent on
  the others; gausspp steps over those instants on the parallelogram's branch.
* The **slider-crank**: a crank, a connecting rod, a slider on a guide (a prismatic joint).
* The **spatial double parallelogram**: four spatial bars, six hinges — 30 rows of which only 23 are independent
  (Grübler counts −6 degrees of freedom; it moves with one).
* **Bricard's mechanism** (IFToMM A04): five rods along the edges of a cube and six hinges — Grübler counts no
  freedom, the hinges' special directions leave one; released from rest, it falls through it.
* **Watt's flyball governor**: a spindle turned at a prescribed speed (a servo-constraint, kept by the drive's
  torque), arms, links and a sleeve — 41 rows of rank 35; the arms rise and fall about the angle where the
  effective potential ``V − ½ Ω² I_zz(α)`` is stationary.

The first three are checked against a one-degree-of-freedom model of the same machine (the tests); Bricard's
against MuJoCo's simulation of the same machine in joint coordinates. The figure: the three machines' energy
(constant: no friction) and the crank angle of the four-bar beside its reference.
Run: python examples/bodies_and_joints.py [output.png [animation.gif]]
"""

import sys

import numpy as np
from scipy.integrate import solve_ivp

import gausspp as gp
from gausspp.scenes import parallelogram

G = 9.81


def four_bar() -> gp.Multibody:
    """IFToMM A02: three bars of 1 m and 1 kg on ground pins 1 m apart; cranks vertical, coupler level."""
    mb = gp.Multibody(gravity=(0.0, -G))
    bar = dict(mass=1.0, inertia=1.0 / 12)
    mb.body("crank1", **bar, at=(0.0, 0.5), angle=np.pi / 2)
    mb.body("coupler", **bar, at=(0.5, 1.0), angle=0.0)
    mb.body("crank2", **bar, at=(1.0, 0.5), angle=np.pi / 2)
    mb.revolute("ground-crank1", "crank1", (-0.5, 0.0), None, (0.0, 0.0))
    mb.revolute("crank1-coupler", "crank1", (0.5, 0.0), "coupler", (-0.5, 0.0))
    mb.revolute("coupler-crank2", "coupler", (0.5, 0.0), "crank2", (0.5, 0.0))
    mb.revolute("ground-crank2", "crank2", (-0.5, 0.0), None, (1.0, 0.0))
    return mb


def slider_crank(r: float = 0.5, L: float = 1.2, masses: tuple = (1.0, 2.0, 0.5)) -> gp.Multibody:
    """A crank of ``r`` on a ground pin, a rod of ``L``, a slider on a horizontal guide through the pin (uniform bars
    of the given masses, kg)."""
    mc, mr, ms = masses
    mb = gp.Multibody(gravity=(0.0, -G))
    mb.body("crank", mass=mc, inertia=mc * r**2 / 12, at=(0.0, r / 2), angle=np.pi / 2)
    mb.body("rod", mass=mr, inertia=mr * L**2 / 12, at=(0.3, 0.25), angle=-0.4)  # guesses: assemble fixes them
    mb.body("slider", mass=ms, inertia=1e-3, at=(1.1, 0.0))
    mb.revolute("ground-crank", "crank", (-r / 2, 0.0), None, (0.0, 0.0))
    mb.revolute("crank-rod", "crank", (r / 2, 0.0), "rod", (-L / 2, 0.0))
    mb.revolute("rod-slider", "rod", (L / 2, 0.0), "slider", (0.0, 0.0))
    mb.prismatic("guide", "slider", (0.0, 0.0), None, (0.0, 0.0), axis=(1.0, 0.0))
    return mb


def spatial_double_parallelogram(l: float = 1.0, m: float = 1.0) -> gp.Multibody:
    """Three cranks of ``l`` on ground hinges ``l`` apart and a coupler of ``2 l`` hinged to their tips — spatial
    bars (thin rods along their body ``x``) and hinges about ``z``: the scene ``spatial-parallelogram``."""
    mb = gp.Multibody(gravity=(0.0, -G, 0.0))
    z = (0.0, 0.0, 1.0)

    def bar(name: str, length: float, mass: float, at: tuple, psi: float) -> None:
        eps = mass * (0.01 * length) ** 2 / 2  # about its own axis: a rod of radius 1 % of its length
        inertia = (eps, mass * length**2 / 12, mass * length**2 / 12)
        mb.body(name, mass=mass, inertia=inertia, at=at, orientation=(np.cos(psi / 2), 0.0, 0.0, np.sin(psi / 2)))

    for j in range(3):
        bar(f"crank{j + 1}", l, m, (j * l, l / 2, 0.0), np.pi / 2)
        mb.revolute(f"ground-crank{j + 1}", f"crank{j + 1}", (-l / 2, 0, 0), None, (j * l, 0, 0), axis=z)
    bar("coupler", 2 * l, 2 * m, (l, l, 0.0), 0.0)
    for j in range(3):
        mb.revolute(f"crank{j + 1}-coupler", f"crank{j + 1}", (l / 2, 0, 0), "coupler", ((j - 1) * l, 0, 0), axis=z)
    return mb


def flyball_governor(alpha: float, omega: float, l: float = 1.0, h: float = 1.0) -> gp.Multibody:
    """Watt's flyball governor: a spindle turned at ``omega`` (a servo-constraint on its spin, realized by the
    drive's torque), two arms of ``l`` (1 kg) hinged at its top, ``alpha`` from the vertical, and two links of
    ``l/2`` (0.5 kg) from the arms' middles to a sleeve (0.5 kg) sliding on the spindle: 41 rows of rank 35."""
    mb = gp.Multibody(gravity=(0.0, 0.0, -G))
    mb.body("spindle", mass=1.0, inertia=(1 / 12, 1 / 12, 1e-2), at=(0, 0, h / 2))
    mb.revolute("ground-spindle", "spindle", (0, 0, -h / 2), None, (0, 0, 0), axis=(0, 0, 1))
    zs = h - l * np.cos(alpha)
    mb.body("sleeve", mass=0.5, inertia=(1e-2, 1e-2, 1e-2), at=(0, 0, zs))
    mb.prismatic("sleeve-spindle", "sleeve", (0, 0, 0), "spindle", (0, 0, zs - h / 2), axis=(0, 0, 1))
    for side, s in (("1", 1.0), ("2", -1.0)):  # rods along their body x, turned about y into the plane x-z
        for name, m, length, centre, turn in (
            ("arm", 1.0, l, (s * l / 2 * np.sin(alpha), 0, h - l / 2 * np.cos(alpha)), s * np.sin(alpha)),
            ("link", 0.5, l / 2, (s * l / 4 * np.sin(alpha), 0, h - 0.75 * l * np.cos(alpha)), -s * np.sin(alpha)),
        ):
            psi = np.arctan2(np.cos(alpha), turn)  # body x → (cos ψ, 0, −sin ψ): down the rod
            rod = (m * 1e-4, m * length**2 / 12, m * length**2 / 12)
            mb.body(name + side, mass=m, inertia=rod, at=centre, orientation=(np.cos(psi / 2), 0, np.sin(psi / 2), 0))
        mb.revolute("spindle-arm" + side, "arm" + side, (-l / 2, 0, 0), "spindle", (0, 0, h / 2), axis=(0, 1, 0))
        mb.revolute("arm-link" + side, "arm" + side, (0, 0, 0), "link" + side, (-l / 4, 0, 0), axis=(0, 1, 0))
        mb.revolute("link-sleeve" + side, "link" + side, (l / 4, 0, 0), "sleeve", (0, 0, 0), axis=(0, 1, 0))
    mb.spin("drive", "spindle", (0, 0, 1), lambda t: omega, realization=gp.Ideal())  # a torque about the axis
    return mb


#: Bricard's mechanism (IFToMM A04): the loop's corners (m) and the hinge axis at each (space axes).
BRICARD_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1], [0, 0, 1]], float)
BRICARD_AXES = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]], float)


def bricard(masses: tuple = (1.0,) * 5) -> gp.Multibody:
    """Five rods of 1 m and 1 kg (square section 0.1 m) around the edges of a unit cube, joined to each other and to
    the ground by six hinges: 30 rows of rank 29, one degree of freedom where Grübler counts none. Gravity −y."""
    mb = gp.Multibody(gravity=(0.0, -G, 0.0))
    side = (0.1**2 + 0.1**2) / 12, (1.0 + 0.1**2) / 12  # per kg: about the rod's axis, across it
    frames = []
    for i, (a, b) in enumerate(zip(BRICARD_CORNERS[:-1], BRICARD_CORNERS[1:], strict=True)):
        ex = b - a  # body x along the rod; z across it, normal to the first hinge's axis
        ez = np.cross(ex, BRICARD_AXES[i] if abs(BRICARD_AXES[i] @ ex) < 0.5 else [0, 0, 1.0])
        R = np.column_stack([ex, np.cross(ez, ex) / np.linalg.norm(ez), ez / np.linalg.norm(ez)])
        frames.append(R)
        inertia = masses[i] * np.array([side[0], side[1], side[1]])
        mb.body(f"link{i + 1}", mass=masses[i], inertia=inertia, at=(a + b) / 2, orientation=quaternion(R))
    mb.revolute("P0", "link1", (-0.5, 0, 0), None, BRICARD_CORNERS[0], axis=frames[0].T @ BRICARD_AXES[0])
    for i in range(1, 5):
        axis = frames[i - 1].T @ BRICARD_AXES[i]
        mb.revolute(f"P{i}", f"link{i}", (0.5, 0, 0), f"link{i + 1}", (-0.5, 0, 0), axis=axis)
    mb.revolute("P5", "link5", (0.5, 0, 0), None, BRICARD_CORNERS[5], axis=frames[4].T @ BRICARD_AXES[5])
    return mb


def bricard_mjcf(dt: float) -> str:
    """The same Bricard mechanism for MuJoCo: a chain of five hinged links from the ground (body frames at the
    corners, axes along the rods in the inertial frames), closed by two ``connect`` equalities on the last hinge's
    axis at the stiffest softness (time constant 2 dt)."""
    corners, axes = BRICARD_CORNERS, BRICARD_AXES
    bodies = ""
    for i in range(5):
        d, rel = corners[i + 1] - corners[i], corners[i] - (corners[i - 1] if i else 0.0)
        x = np.array([1.0, 0.0, 0.0])
        c, axis = float(x @ d), np.cross(x, d)
        w = np.sqrt(2 * (1 + c)) / 2 if c > -1 + 1e-12 else 0.0
        q = (w, *(axis / (2 * w))) if w > 0 else (0.0, 0.0, 0.0, 1.0)
        bodies += (
            f'<body name="link{i + 1}" pos="{rel[0]} {rel[1]} {rel[2]}"><joint type="hinge" axis="{axes[i][0]} '
            f'{axes[i][1]} {axes[i][2]}"/><inertial pos="{d[0] / 2} {d[1] / 2} {d[2] / 2}" quat="{q[0]} {q[1]} '
            f'{q[2]} {q[3]}" mass="1" diaginertia="{0.02 / 12} {1.01 / 12} {1.01 / 12}"/>'
        )
    a = corners[5] - corners[4]
    soft = f'solref="{2 * dt} 1" solimp="0.9999 0.9999 0.001 0.5 2"'
    return (
        f'<mujoco><option gravity="0 -{G} 0" timestep="{dt}" integrator="RK4"><flag contact="disable"/></option>'
        f"<worldbody>{bodies}{'</body>' * 5}</worldbody><equality>"
        f'<connect body1="link5" anchor="{a[0]} {a[1]} {a[2]}" {soft}/>'
        f'<connect body1="link5" anchor="{a[0] + 0.5} {a[1]} {a[2]}" {soft}/></equality></mujoco>'
    )


def quaternion(R: np.ndarray) -> tuple[float, float, float, float]:
    """The unit quaternion ``(w, x, y, z)`` of a rotation matrix (scipy's, reordered)."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return float(w), float(x), float(y), float(z)


def slider_crank_reference(
    t: np.ndarray, r: float = 0.5, L: float = 1.2, rate: float = 2.0, masses: tuple = (1.0, 2.0, 0.5)
) -> np.ndarray:
    """The crank angle by Lagrange's equation in it alone, ``M(θ) θ̈ + ½ M′(θ) θ̇² + V′(θ) = 0``, written by sympy
    from the geometry (the rod's angle ``φ = asin(−r sin θ / L)``, the slider at ``r cos θ + L cos φ``) and solved
    by scipy — a computation that shares nothing with gausspp's."""
    import sympy as sp

    mc, mr, ms = masses
    th, w = sp.symbols("th w")
    phi = sp.asin(-r * sp.sin(th) / L)
    tip = sp.Matrix([r * sp.cos(th), r * sp.sin(th)])
    rod = tip + L / 2 * sp.Matrix([sp.cos(phi), sp.sin(phi)])
    slider = r * sp.cos(th) + L * sp.cos(phi)
    speed = lambda p: p.diff(th) * w  # noqa: E731
    T = sp.Rational(1, 2) * (
        mc * speed(tip / 2).dot(speed(tip / 2)) + mc * r**2 / 12 * w**2
        + mr * speed(rod).dot(speed(rod)) + mr * L**2 / 12 * (phi.diff(th) * w) ** 2 + ms * speed(slider) ** 2
    )  # fmt: skip
    V = G * (mc * tip[1] / 2 + mr * rod[1])
    M = sp.diff(T, w, 2)
    acc = sp.lambdify((th, w), -(sp.diff(M, th) * w**2 - sp.diff(T, th) + sp.diff(V, th)) / M)
    sol = solve_ivp(lambda _t, s: [s[1], acc(s[0], s[1])], (0.0, t[-1]), [np.pi / 2, rate], t_eval=t,
                    method="DOP853", rtol=1e-13, atol=1e-13)  # fmt: skip
    return sol.y[0]


def main() -> None:
    runs = {}
    mb = four_bar()
    q0, v0 = mb.assemble(fix={"crank1.θ": np.pi / 2}, rates={"crank1.θ̇": -1.0})
    runs["four-bar"] = four = gp.simulate(mb.model(), q0, v0, 5.0, rtol=1e-12, atol=1e-12)
    theta, _ = parallelogram.one_dof_reference(four.t)
    print(f"four-bar: {len(four.events)} collinear positions, crank angle {np.abs(four.q[:, 2] - theta).max():.1e} "
          "rad from the one-DOF model")  # fmt: skip
    sc = slider_crank()
    q0, v0 = sc.assemble(fix={"crank.θ": np.pi / 2}, rates={"crank.θ̇": 2.0})
    runs["slider-crank"] = slide = gp.simulate(sc.model(), q0, v0, 3.0, rtol=1e-12, atol=1e-12)
    print(f"slider-crank: crank angle {np.abs(slide.q[:, 2] - slider_crank_reference(slide.t)).max():.1e} rad from "
          "the one-DOF Lagrange equation")  # fmt: skip
    sp = spatial_double_parallelogram()
    model = sp.model()
    q0, v0 = sp.assemble(rates={"crank1.ωz": -1.0})
    runs["spatial double parallelogram"] = loop = gp.simulate(model, q0, v0, 5.0, record=np.linspace(0, 5, 201))
    theta, _ = parallelogram.one_dof_reference(loop.t, third_bar=True)
    centre = 0.5 * np.column_stack([np.cos(theta), np.sin(theta)])
    print(f"spatial double parallelogram: {model.k} rows on {model.nv} velocities, crank centre "
          f"{np.abs(loop.q[:, :2] - centre).max():.1e} m from the one-DOF model")  # fmt: skip
    br = bricard()
    model = br.model()
    q0, v0 = br.assemble()
    runs["Bricard"] = cube = gp.simulate(model, q0, v0, 5.0, record=np.linspace(0, 5, 201))
    print(f"Bricard: {model.k} rows on {model.nv} velocities; link 1 swings {np.ptp(cube.q[:, 2]):.2f} m in z")
    gov = flyball_governor(0.98, 7.0)  # 0.05 rad above the steady angle at 7 rad/s
    q0, v0 = gov.assemble(rates={"spindle.ωz": 7.0, "arm1.ωy": 0.0})
    turn = gp.simulate(gov.model(), q0, v0, 2.0, record=np.linspace(0, 2, 81))
    i = gov.coordinate_names.index("arm1.x")
    alpha = np.arctan2(np.hypot(turn.q[:, i], turn.q[:, i + 1]), 1.0 - turn.q[:, i + 2])
    print(f"flyball governor: {gov.model().k} rows on {gov.model().nv} velocities; the arms swing between "
          f"{alpha.min():.3f} and {alpha.max():.3f} rad about the steady 0.926")  # fmt: skip
    for name, run in runs.items():
        print(f"  {name}: energy constant to {np.ptp(run.energy) / np.abs(run.energy).max():.1e} (relative)")
    if len(sys.argv) > 1:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
        for name, run in runs.items():
            ax1.plot(run.t, (run.energy - run.energy[0]) / np.abs(run.energy).max(), label=name)
        ax1.set(xlabel="time t (s)", ylabel="(E − E₀)/max|E|", title="energy: constant to round-off")
        ax1.legend(fontsize=8)
        theta, _ = parallelogram.one_dof_reference(four.t)
        ax2.plot(four.t, four.q[:, 2], label="crank angle (bodies and joints)")
        ax2.plot(four.t, theta, "k--", lw=1, label="one-DOF model")
        for ev in four.events:
            ax2.axvline(ev["t"], color="0.8", lw=0.8)
        ax2.set(xlabel="time t (s)", ylabel="θ (rad)", title="four-bar: through its collinear positions (grey)")
        ax2.legend(fontsize=8)
        fig.savefig(sys.argv[1], dpi=120)
    if len(sys.argv) > 2:
        from gausspp import plot

        class Machine:  # what plot.animate draws: the bodies as segments to their joints
            drawing = staticmethod(mb.drawing)

        plot.animate(Machine(), four, out=sys.argv[2], frames=60)


if __name__ == "__main__":
    main()
