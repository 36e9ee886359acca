"""Coulomb friction: a block sticks or slides, a ball rolls, a rod meets Painlevé's paradox
========================================================================================

Each contact is a gap ``g(q) ≥ 0`` and a slip ``s = J_t v`` (the contact point's velocity along the surface). While
it slides, the surface's reaction leans back by the friction angle: ``N J_nᵀ − μN sign(s) J_tᵀ``, a *non-ideal*
realization of the contact; while it sticks, the slip is a constraint and the friction force any value in the
cone ``|F| ≤ μ_s N``. ``gp.simulate_friction`` integrates event by event (stick, slip, lift-off, impact) and every
number below is compared with its closed form.
Run: python examples/friction.py [output.png [ball.gif]]  (the stick/slip map is written beside the figure)
"""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

import gausspp as gp
from gausspp import plot
from gausspp.friction import scenes

G = scenes.G
out = Path(sys.argv[1] if len(sys.argv) > 1 else "friction.png")
map_out = out.with_name(f"{out.stem}_stick_slip_map.png")  # beside the first figure
gif = sys.argv[2] if len(sys.argv) > 2 else None  # the ball sliding, then rolling

# -- a block on a slope: sticks for μ ≥ tan α, else slides with g(sin α − μ cos α)
mu = 0.5
print(f"block on a slope, μ = {mu} (friction angle {np.degrees(np.arctan(mu)):.2f}°)")
for alpha in (np.radians(20), np.radians(30)):
    mech, contacts = scenes.incline(alpha, mu)
    run = gp.simulate_friction(mech, contacts, [0.0, 0.0], [0.0, 0.0], 1.0)
    a = run.v[-1, 0] / run.t[-1]
    closed = max(0.0, G * (np.sin(alpha) - mu * np.cos(alpha)))
    print(f"  α = {np.degrees(alpha):4.1f}°: {run.modes[-1][0]:7s} a = {a:.12f}  closed form {closed:.12f}")

# -- a box pushed to v0 and released: both corners slide, the front one carries more of the weight
v0, mu = 3.0, 0.4
grid = np.linspace(0.0, 1.0, 201)
mech, contacts = scenes.box(mu)
box = gp.simulate_friction(mech, contacts, [0.0, 0.1, 0.0], [v0, 0.0, 0.0], 1.0, record=grid)
(stop,) = box.events
print(
    f"\nbox released at {v0} m/s, μ = {mu}: stops at t = {stop['t']:.12f} (v0/μg = {v0 / (mu * G):.12f}) after "
    f"{box.q[-1, 0]:.12f} m (v0²/2μg = {v0**2 / (2 * mu * G):.12f}); while sliding N = {box.N[1]} (back, front)"
)

# -- a ball and a hoop thrown without spin: they slide, then roll
runs, slips = {"box": box}, {"box": np.column_stack([box.v[:, 0], box.v[:, 0]])}
for name, k, t_roll, speed in (("ball", 0.4, 2 / 7, 5 / 7), ("hoop", 1.0, 2 / 4, 1 / 2)):
    mech, contacts = scenes.round_body(0.3, k, r=0.1)
    run = gp.simulate_friction(mech, contacts, [0.0, 0.1, 0.0], [2.0, 0.0, 0.0], 1.0, record=grid)
    (roll,) = run.events
    print(
        f"{name} thrown at 2 m/s, μ = 0.3: rolls from t = {roll['t']:.12f} (closed form {t_roll * 2 / (0.3 * G):.12f}) "
        f"at {run.v[-1, 0]:.12f} m/s ({speed * 2:.12f}); energy lost {run.energy[0] - run.energy[-1]:.6f} J"
    )
    runs[name], slips[name] = run, (run.v[:, 0] + 0.1 * run.v[:, 2])[:, None]

# -- Painlevé's rod: sliding backwards on its end with μ beyond 1/(…) the normal problem has no solution or two
theta = np.arctan(2.0)
critical = (1 + 3 * np.cos(theta) ** 2) / (3 * np.sin(theta) * np.cos(theta))
print(f"\nrod at θ = {np.degrees(theta):.2f}° sliding backwards: critical μ = {critical:.6f} (4/3 at tan θ = 2)")
for factor in (0.99, 1.01):
    mech, contacts = scenes.rod(critical * factor)
    try:
        rod = gp.simulate_friction(mech, contacts, [0.0, 0.5 * np.sin(theta), theta], [-1.0, 0.0, 0.0], 0.2)
        print(f"  μ = {critical * factor:.4f}: runs — {', '.join(e['kind'] for e in rod.events) or 'no event'}")
    except gp.PainleveError as exc:
        print(f"  μ = {critical * factor:.4f}: PainleveError (critical μ {exc.mu_critical:.6f})")

# -- the stick/slip map of the block: simulated verdicts against μ = tan α
alphas, mus = np.radians(np.linspace(5, 60, 16)), np.linspace(0.05, 1.5, 13)
slides = np.zeros((mus.size, alphas.size), bool)
for i, m in enumerate(mus):
    for j, a in enumerate(alphas):
        mech, contacts = scenes.incline(a, m)
        slides[i, j] = gp.simulate_friction(mech, contacts, [0.0, 0.0], [0.0, 0.0], 0.01).modes[-1] != ("stick",)
wrong = int(np.sum(slides != (mus[:, None] < np.tan(alphas)[None, :])))
print(f"\nstick/slip map: {slides.size} blocks, {wrong} verdicts off the closed form μ = tan α")

plot.friction(runs, slips).savefig(out, dpi=110)
plot.stick_slip_map(alphas, mus, slides).savefig(map_out, dpi=110)
print(f"figures written: {out}, {map_out}")

# -- the ball, animated: the spoke turns slower than it rolls while it slides; the rim point traces a cycloid after
ball = SimpleNamespace(name="ball thrown without spin: slides, then rolls", drawing=scenes.round_body_drawing(0.1))
if gif is not None:
    plot.animate(ball, runs["ball"], out=gif, frames=90)
    print(f"animation written: {gif}")
