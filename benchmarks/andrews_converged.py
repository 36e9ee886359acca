"""Andrews' squeezing mechanism at t = 0.03 in extended precision: ``python benchmarks/andrews_converged.py``.

What it computes. The state ``q, q̇, q̈, λ`` of the IVP test-set problem ``andrews`` (Hairer & Wanner,
*Solving ODEs II*, §VII.7; Bari/CWI *Test Set for IVP Solvers*) at ``t = 0.03``, independently of gausspp's
model and integrators, to check the golden numbers ``CONVERGED_Q/V/A/LAMBDA`` in ``gausspp/scenes/andrews.py``
(and the published ``REFERENCE_*``, whose angles are good to about 1.4e-9).

How. The problem is implemented here from the published formulas (the write-up of the test set's
``andfunc``/``andsoln`` in ``/work/shared/benchmarks/andrews.md``: ``M(y)``, ``f(y, y')``, ``g(y)``,
``G = ∂g/∂y``, the parameters and the 30-digit consistent initial values), with every parameter read
from its decimal string. The index-3 DAE ``M y'' = f − Gᵀλ, g(y) = 0`` is integrated in its index-1 form::

    [[M, Gᵀ], [G, 0]] [y''; λ] = [f; −g_yy(y', y')],     g_yy(y', y') = d²/ds² g(y + s y') at s = 0,

as a first-order ODE in ``(y, y')`` (14 components). ``g_yy`` is written out analytically (each term
``c·cos x`` / ``c·sin x`` of ``g`` with ``x`` linear in the angles gives ``−c·cos x·ẋ²`` / ``−c·sin x·ẋ²``);
before integrating, the script checks it, and ``G``, against ``mpmath.diff`` of ``g``; checks that the
velocity-squared terms of the published ``f`` are the Coriolis/centrifugal terms of ``M`` and that its
spring term is ``−∂V/∂γ`` (Lagrange's equations, again with ``mpmath.diff``); and checks that the KKT solve
at ``t = 0`` reproduces the published 30-digit ``y''(0)`` and ``λ(0)``. The integrator is mpmath's
``odefun`` (a Taylor-series method of degree ``3 + 1.5·dps``; the Taylor coefficients come from
finite differences of Euler steps at about ``(degree+1)×`` the working precision; local tolerance about
``2^-(prec+10)``), with ``mp.dps = 30`` (about 100 bits) by default, ``--dps`` to change it; no
stabilization. At ``t = 0.03`` the constraints ``g(y)`` and ``G y'`` are reported, then the state is
projected onto them (Gauss–Newton with ``Gᵀ(GGᵀ)⁻¹``; the corrections are reported, they are at the
working precision), and ``y''``, ``λ`` are the KKT solution at the projected state.

Output: ``q, v, a, λ`` at ``t = 0.03`` with 17 significant digits, the constraint residuals, the run time,
and the largest differences against ``CONVERGED_*`` (absolute for ``q`` and ``v``; relative for ``a`` and
``λ``, both componentwise and, as ``tests/test_scene_andrews.py`` measures, relative to the largest
component) and against the published ``REFERENCE_*``. gausspp is imported only to read those constants.
The KKT system is solved by Gaussian elimination with partial pivoting on mpf lists, and the sines and
cosines of the ten angle combinations are evaluated once per right-hand side (mpmath's pure-Python
``lu_solve`` and repeated trig calls made each evaluation roughly ten times slower).

Run time (measured on a busy 2-core machine, pure-Python mpmath backend): about 470 s wall with the default
``--dps 30`` and about 120 s with ``--dps 20``. Both runs print the same 17 digits, except the last digit of
one component of ``a``, so the default run has converged well past 16 digits. mpmath is not a direct
gausspp dependency (sympy, in the ``test`` extra, installs it).
"""

from __future__ import annotations

import argparse
import time

import mpmath
import numpy as np

mp = mpmath.mp

# -- the published problem (andrews.md), every number from its decimal string --------------------------------------
_PARAMETERS = dict(
    m1="0.04325", m2="0.00365", m3="0.02373", m4="0.00706", m5="0.07050", m6="0.00706", m7="0.05498",
    i1="2.194e-6", i2="4.410e-7", i3="5.255e-6", i4="5.667e-7", i5="1.169e-5", i6="5.667e-7", i7="1.912e-5",
    xa="-0.06934", ya="-0.00227", xb="-0.03635", yb="0.03273", xc="0.014", yc="0.072",
    c0="4530", l0="0.07785", mom="0.033",
    d="0.028", da="0.0115", e="0.02", ea="0.01421", rr="0.007", ra="0.00092", ss="0.035",
    sa="0.01874", sb="0.01043", sc="0.018", sd="0.02", ta="0.02308", tb="0.00916",
    u="0.04", ua="0.01228", ub="0.00449", zf="0.02", zt="0.04", fa="0.01421",
)  # fmt: skip
Q0 = (
    "-0.0617138900142764496358948458001",
    "0",
    "0.455279819163070380255912382449",
    "0.222668390165885884674473185609",
    "0.487364979543842550225598953530",
    "-0.222668390165885884674473185609",
    "1.23054744454982119249735015568",
)
A0 = ("14222.4439199541138705911625887", "-10666.8329399655854029433719415", "0", "0", "0", "0", "0")
LAMBDA0 = ("98.5668703962410896057654982170", "-6.12268834425566265503114393122", "0", "0", "0", "0")
T_END = "0.03"

P: dict[str, mpmath.mpf] = {}


def set_parameters() -> None:
    """Read the parameters at 40 digits beyond the working precision (exact enough for any run here)."""
    with mp.extradps(40):
        P.update({k: mp.mpf(s) for k, s in _PARAMETERS.items()})
        P["ep"], P["zp"] = P["e"] - P["ea"], P["zf"] - P["fa"]  # e' = e − ea, z' = zf − fa


Trig = dict[str, tuple[mpmath.mpf, mpmath.mpf]]


def trig(q: list) -> Trig:
    """(cos, sin) of the ten angles the formulas use, each evaluated once."""
    be, th, ga, ph, de, om, ep = q
    angles = dict(be=be, th=th, ga=ga, ph=ph, de=de, om=om, ep=ep, bt=be + th, pd=ph + de, oe=om + ep)
    return {k: mp.cos_sin(x) for k, x in angles.items()}


def mass(q: list, cs: Trig | None = None) -> list:
    """M(q), andrews.md "Mass matrix" (a list of rows)."""
    p, cs = P, cs or trig(q)
    cth, sph, som = cs["th"][0], cs["ph"][1], cs["om"][1]
    ep, zp = p["ep"], p["zp"]
    M = [[mp.zero] * 7 for _ in range(7)]
    M[0][0] = p["m1"] * p["ra"] ** 2 + p["m2"] * (p["rr"] ** 2 - 2 * p["da"] * p["rr"] * cth + p["da"] ** 2)
    M[0][0] += p["i1"] + p["i2"]
    M[0][1] = M[1][0] = p["m2"] * (p["da"] ** 2 - p["da"] * p["rr"] * cth) + p["i2"]
    M[1][1] = p["m2"] * p["da"] ** 2 + p["i2"]
    M[2][2] = p["m3"] * (p["sa"] ** 2 + p["sb"] ** 2) + p["i3"]
    M[3][3] = p["m4"] * ep**2 + p["i4"]
    M[3][4] = M[4][3] = p["m4"] * (ep**2 + p["zt"] * ep * sph) + p["i4"]
    M[4][4] = p["m4"] * (p["zt"] ** 2 + 2 * p["zt"] * ep * sph + ep**2) + p["m5"] * (p["ta"] ** 2 + p["tb"] ** 2)
    M[4][4] += p["i4"] + p["i5"]
    M[5][5] = p["m6"] * zp**2 + p["i6"]
    M[5][6] = M[6][5] = p["m6"] * (zp**2 - p["u"] * zp * som) + p["i6"]
    M[6][6] = p["m6"] * (zp**2 - 2 * p["u"] * zp * som + p["u"] ** 2) + p["m7"] * (p["ua"] ** 2 + p["ub"] ** 2)
    M[6][6] += p["i6"] + p["i7"]
    return M


def spring_point(c: mpmath.mpf, s: mpmath.mpf) -> tuple[mpmath.mpf, mpmath.mpf]:
    """D = B + (sd cos γ + sc sin γ, sd sin γ − sc cos γ), from c = cos γ, s = sin γ."""
    p = P
    return p["xb"] + p["sd"] * c + p["sc"] * s, p["yb"] + p["sd"] * s - p["sc"] * c


def spring_energy(gamma: mpmath.mpf) -> mpmath.mpf:
    """½ c0 (L − l0)², L = |D − C| (used only to check f3)."""
    Dx, Dy = spring_point(*mp.cos_sin(gamma))
    L = mp.sqrt((Dx - P["xc"]) ** 2 + (Dy - P["yc"]) ** 2)
    return P["c0"] * (L - P["l0"]) ** 2 / 2


def force(q: list, v: list, cs: Trig | None = None) -> list:
    """f(q, q'), andrews.md "Force vector"."""
    p, cs = P, cs or trig(q)
    bep, thp, php, dep, omp, epp = v[0], v[1], v[3], v[4], v[5], v[6]
    ep, zp = p["ep"], p["zp"]
    c, s = cs["ga"]
    Dx, Dy = spring_point(c, s)
    rx, ry = Dx - p["xc"], Dy - p["yc"]
    L = mp.sqrt(rx**2 + ry**2)
    scale = -p["c0"] * (L - p["l0"]) / L
    Fx, Fy = scale * rx, scale * ry
    sth, cph, com = cs["th"][1], cs["ph"][0], cs["om"][0]
    return [
        p["mom"] - p["m2"] * p["da"] * p["rr"] * thp * (thp + 2 * bep) * sth,
        p["m2"] * p["da"] * p["rr"] * bep**2 * sth,
        Fx * (p["sc"] * c - p["sd"] * s) + Fy * (p["sd"] * c + p["sc"] * s),
        p["m4"] * p["zt"] * ep * dep**2 * cph,
        -p["m4"] * p["zt"] * ep * php * (php + 2 * dep) * cph,
        -p["m6"] * p["u"] * zp * epp**2 * com,
        p["m6"] * p["u"] * zp * omp * (omp + 2 * epp) * com,
    ]


def constraints(q: list) -> list:
    """g(q), andrews.md "The six constraints" (E = end of body 2 from O). Direct transcription (own sin/cos)."""
    p = P
    be, th, ga, ph, de, om, ep = q
    Ex = p["rr"] * mp.cos(be) - p["d"] * mp.cos(be + th)
    Ey = p["rr"] * mp.sin(be) - p["d"] * mp.sin(be + th)
    return [
        Ex - p["ss"] * mp.sin(ga) - p["xb"],
        Ey + p["ss"] * mp.cos(ga) - p["yb"],
        Ex - p["e"] * mp.sin(ph + de) - p["zt"] * mp.cos(de) - p["xa"],
        Ey + p["e"] * mp.cos(ph + de) - p["zt"] * mp.sin(de) - p["ya"],
        Ex - p["zf"] * mp.cos(om + ep) - p["u"] * mp.sin(ep) - p["xa"],
        Ey - p["zf"] * mp.sin(om + ep) + p["u"] * mp.cos(ep) - p["ya"],
    ]


def jacobian(q: list, cs: Trig | None = None) -> list:
    """G = ∂g/∂q (6 rows), differentiated by hand from g (checked against mpmath.diff in check_formulas)."""
    p, cs = P, cs or trig(q)
    G = [[mp.zero] * 7 for _ in range(6)]
    (cbe, sbe), (cbt, sbt) = cs["be"], cs["bt"]
    for row in (0, 2, 4):  # ∂Ex/∂β, ∂Ex/∂Θ
        G[row][0], G[row][1] = -p["rr"] * sbe + p["d"] * sbt, p["d"] * sbt
    for row in (1, 3, 5):  # ∂Ey/∂β, ∂Ey/∂Θ
        G[row][0], G[row][1] = p["rr"] * cbe - p["d"] * cbt, -p["d"] * cbt
    cga, sga = cs["ga"]
    G[0][2], G[1][2] = -p["ss"] * cga, -p["ss"] * sga
    (cpd, spd), (cde, sde) = cs["pd"], cs["de"]
    G[2][3], G[2][4] = -p["e"] * cpd, -p["e"] * cpd + p["zt"] * sde
    G[3][3], G[3][4] = -p["e"] * spd, -p["e"] * spd - p["zt"] * cde
    (coe, soe), (cep, sep) = cs["oe"], cs["ep"]
    G[4][5], G[4][6] = p["zf"] * soe, p["zf"] * soe - p["u"] * cep
    G[5][5], G[5][6] = -p["zf"] * coe, -p["zf"] * coe - p["u"] * sep
    return G


def g_yy(q: list, v: list, cs: Trig | None = None) -> list:
    """g_yy(q', q') = (∂(G q')/∂q) q' = d²/ds² g(q + s q')|_{s=0}, by hand (checked in check_formulas)."""
    p, cs = P, cs or trig(q)
    bd, thd, gad, phd, ded, omd, epd = v
    (cbe, sbe), (cbt, sbt), (cga, sga) = cs["be"], cs["bt"], cs["ga"]
    (cpd, spd), (cde, sde), (coe, soe), (cep, sep) = cs["pd"], cs["de"], cs["oe"], cs["ep"]
    gx = -p["rr"] * cbe * bd**2 + p["d"] * cbt * (bd + thd) ** 2
    gy = -p["rr"] * sbe * bd**2 + p["d"] * sbt * (bd + thd) ** 2
    return [
        gx + p["ss"] * sga * gad**2,
        gy - p["ss"] * cga * gad**2,
        gx + p["e"] * spd * (phd + ded) ** 2 + p["zt"] * cde * ded**2,
        gy - p["e"] * cpd * (phd + ded) ** 2 + p["zt"] * sde * ded**2,
        gx + p["zf"] * coe * (omd + epd) ** 2 + p["u"] * sep * epd**2,
        gy + p["zf"] * soe * (omd + epd) ** 2 - p["u"] * cep * epd**2,
    ]


def solve(A: list, b: list) -> list:
    """A x = b by Gaussian elimination with partial pivoting (plain lists of mpf; A, b are not modified)."""
    n = len(b)
    A = [list(row) + [bi] for row, bi in zip(A, b, strict=True)]
    for k in range(n):
        pivot = max(range(k, n), key=lambda i: abs(A[i][k]))
        A[k], A[pivot] = A[pivot], A[k]
        for i in range(k + 1, n):
            if A[i][k]:
                factor = A[i][k] / A[k][k]
                row, pivot_row = A[i], A[k]
                A[i] = [row[j] - factor * pivot_row[j] if j >= k and pivot_row[j] else row[j] for j in range(n + 1)]
    x = [mp.zero] * n
    for k in reversed(range(n)):
        x[k] = (A[k][n] - sum(A[k][j] * x[j] for j in range(k + 1, n))) / A[k][k]
    return x


def kkt(q: list, v: list) -> tuple[list, list]:
    """Solve [[M, Gᵀ], [G, 0]] [a; λ] = [f; −g_yy(v, v)]: the test-set λ (M a = f − Gᵀλ)."""
    cs = trig(q)
    M, G, f, gam = mass(q, cs), jacobian(q, cs), force(q, v, cs), g_yy(q, v, cs)
    K = [M[i] + [G[r][i] for r in range(6)] for i in range(7)] + [G[r] + [mp.zero] * 6 for r in range(6)]
    x = solve(K, f + [-gi for gi in gam])
    return x[:7], x[7:]


def rhs(t: mpmath.mpf, y: list) -> list:
    """The index-1 ODE in (q, q')."""
    q, v = y[:7], y[7:]
    a, _ = kkt(q, v)
    return v + a


# -- checks of the hand-written formulas ----------------------------------------------------------------------------
def check_formulas() -> float:
    """Largest relative mismatch of G, g_yy and f's velocity and spring terms against mpmath.diff, at a generic
    state with velocities of the size the motion reaches."""
    q = [mp.mpf(s) for s in Q0]
    q = [qi + mp.mpf(k + 1) / 7 for k, qi in enumerate(q)]  # off the initial state, all angles nonzero
    v = [mp.mpf(x) for x in ("1100", "-1400", "11", "19", "0.6", "-19", "0.3")]
    worst = mp.zero

    def rel(x: mpmath.mpf, ref: mpmath.mpf, scale: mpmath.mpf) -> mpmath.mpf:
        return abs(x - ref) / scale

    G, gam = jacobian(q), g_yy(q, v)
    for i in range(6):
        gi = lambda *x, i=i: constraints(list(x))[i]  # noqa: E731
        for j in range(7):
            dj = mp.diff(gi, q, tuple(int(k == j) for k in range(7)))
            worst = max(worst, rel(G[i][j], dj, P["d"]))
        d2 = mp.diff(lambda s, i=i: constraints([qk + s * vk for qk, vk in zip(q, v, strict=True)])[i], 0, 2)
        worst = max(worst, rel(gam[i], d2, max(abs(x) for x in gam)))
    # Lagrange: M a = −(dM/dt) q' + ½ ∂(q'ᵀ M q')/∂q + mom e1 − ∂V/∂γ e3 (+ reaction); f must equal the right side
    f = force(q, v)

    def kinetic(*x: mpmath.mpf) -> mpmath.mpf:
        M = mass(list(x))
        return sum(v[i] * M[i][j] * v[j] for i in range(7) for j in range(7)) / 2

    def mass_along(s: mpmath.mpf, i: int, j: int) -> mpmath.mpf:
        return mass([qk + s * vk for qk, vk in zip(q, v, strict=True)])[i][j]

    dMdt = [[mp.diff(lambda s, i=i, j=j: mass_along(s, i, j), 0) for j in range(7)] for i in range(7)]
    lagrange = []
    for i in range(7):
        dT = mp.diff(kinetic, q, tuple(int(k == i) for k in range(7)))
        lagrange.append(-sum(dMdt[i][j] * v[j] for j in range(7)) + dT)
    lagrange[0] += P["mom"]
    lagrange[2] -= mp.diff(spring_energy, q[2])
    scale = max(abs(x) for x in f)
    for i in range(7):
        worst = max(worst, rel(f[i], lagrange[i], scale))
    return float(worst)


def check_initial() -> tuple[float, float, float]:
    """|g(q0)| and the relative errors of the KKT y''(0), λ(0) against the published 30-digit values."""
    q0, v0 = [mp.mpf(s) for s in Q0], [mp.zero] * 7
    a, lam = kkt(q0, v0)
    ea = max(abs(x - mp.mpf(s)) for x, s in zip(a, A0, strict=True)) / max(abs(mp.mpf(s)) for s in A0)
    el = max(abs(x - mp.mpf(s)) for x, s in zip(lam, LAMBDA0, strict=True)) / max(abs(mp.mpf(s)) for s in LAMBDA0)
    return float(max(abs(x) for x in constraints(q0))), float(ea), float(el)


# -- projection onto g = 0, G q' = 0 ---------------------------------------------------------------------------------
def project(q: list, v: list) -> tuple[list, list, float, float]:
    """Gauss–Newton q ← q − Gᵀ(GGᵀ)⁻¹ g(q) (a few sweeps), then v ← v − Gᵀ(GGᵀ)⁻¹ G v."""
    q0, v0 = list(q), list(v)
    for _ in range(3):
        G = mp.matrix(jacobian(q))
        dq = G.T * mp.lu_solve(G * G.T, mp.matrix(constraints(q)))
        q = [q[i] - dq[i] for i in range(7)]
    G = mp.matrix(jacobian(q))
    dv = G.T * mp.lu_solve(G * G.T, G * mp.matrix(v))
    v = [v[i] - dv[i] for i in range(7)]
    return (
        q,
        v,
        float(max(abs(a - b) for a, b in zip(q, q0, strict=True))),
        float(max(abs(a - b) for a, b in zip(v, v0, strict=True))),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dps", type=int, default=30, help="mpmath working precision in decimal digits (30)")
    parser.add_argument("--progress", type=int, default=10, help="report progress at this many times (10)")
    args = parser.parse_args()
    mp.dps = args.dps
    set_parameters()
    print(f"Andrews' squeezing mechanism, mpmath {mpmath.__version__} odefun (Taylor), mp.dps = {mp.dps}")

    start = time.perf_counter()
    mismatch = check_formulas()
    print(f"formula checks against mpmath.diff (G, g_yy, f vs Lagrange): worst relative mismatch {mismatch:.1e}")
    g0, ea0, el0 = check_initial()
    print(f"t = 0: max|g(q0)| = {g0:.1e}; KKT vs published 30-digit y''(0): {ea0:.1e}, λ(0): {el0:.1e} (relative)")

    y0 = [mp.mpf(s) for s in Q0] + [mp.zero] * 7
    t_end = mp.mpf(T_END)
    solution = mp.odefun(rhs, 0, y0)
    for k in range(1, args.progress + 1):
        t = t_end * k / args.progress
        y = solution(t)
        print(f"  t = {float(t):.4f}: β = {mp.nstr(y[0], 12):>16s}, {time.perf_counter() - start:7.1f} s", flush=True)
    q, v = y[:7], y[7:]
    G = mp.matrix(jacobian(q))
    res_g = float(max(abs(x) for x in constraints(q)))
    res_gv = float(max(abs(x) for x in G * mp.matrix(v)))
    q, v, dq, dv = project(q, v)
    a, lam = kkt(q, v)
    res_g_proj = float(max(abs(x) for x in constraints(q)))
    wall = time.perf_counter() - start

    def show(name: str, x: list) -> None:
        print(f"{name} = [" + ", ".join(mp.nstr(xi, 17, min_fixed=0, max_fixed=0) for xi in x) + "]")

    print(f"\nstate at t = {T_END} (17 significant digits):")
    show("q     ", q)
    show("v     ", v)
    show("a     ", a)
    show("lambda", lam)
    print(
        f"constraints at t = 0.03 before projection: max|g| = {res_g:.1e}, max|G q'| = {res_gv:.1e}; "
        f"projection moved q by {dq:.1e}, q' by {dv:.1e}; after: max|g| = {res_g_proj:.1e}"
    )
    print(f"symmetry: Φ + Ω = {float(q[3] + q[5]):.1e}, Φ' + Ω' = {float(v[3] + v[5]):.1e}")
    print(f"run time {wall:.1f} s")

    from gausspp.scenes import andrews as an  # only the constants, for the comparison

    def diffs(x: list, ref: np.ndarray, relative: bool) -> str:
        """Largest difference, in mpmath (the float64 constants are exact binary numbers)."""
        err = [abs(xi - mp.mpf(float(ri))) for xi, ri in zip(x, ref, strict=True)]
        if not relative:
            return f"max abs {float(max(err)):.2e}"
        comp = max(e / abs(ri) for e, ri in zip(err, ref, strict=True))
        return f"max rel {float(comp):.2e} (componentwise), {float(max(err)) / np.max(np.abs(ref)):.2e} (to max|ref|)"

    qf = np.array([float(x) for x in q])
    for label, refs in (
        ("CONVERGED_* (scenes/andrews.py)", (an.CONVERGED_Q, an.CONVERGED_V, an.CONVERGED_A, an.CONVERGED_LAMBDA)),
        ("published REFERENCE_* (andsoln)", (an.REFERENCE_Q, an.REFERENCE_V, an.REFERENCE_A, an.REFERENCE_LAMBDA)),
    ):
        print(f"\nagainst {label}:")
        print(f"  q: {diffs(q, refs[0], False)}, significant digits (scd) {an.significant_digits(qf, refs[0]):.2f}")
        print(f"  v: {diffs(v, refs[1], False)}")
        print(f"  a: {diffs(a, refs[2], True)}")
        print(f"  λ: {diffs(lam, refs[3], True)}")


if __name__ == "__main__":
    main()
