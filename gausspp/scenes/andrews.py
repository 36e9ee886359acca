"""Andrews' squeezing mechanism: the classic multibody benchmark, against its published reference.

Seven planar rigid bodies with seven angles ``q = (β, Θ, γ, Φ, δ, Ω, ε)`` (the test set's
``y1..y7``), closed into three loops that meet at one joint point ``E``: six holonomic
constraints ``g(q) = 0``. A constant torque ``mom`` drives body 1 (angle ``β``); a linear spring
(stiffness ``c0``, rest length ``l0``) joins the fixed point ``C`` to the point ``D`` of body 3.
Hairer & Wanner, *Solving ODEs II*, §VII.7; the Bari/CWI *Test Set for IVP Solvers*, problem
``andrews``. Every number here is taken from the test set's model and reference routines
(``andrews.f``: ``andfunc``, ``andsoln``; as distributed in ``cran/deTestSet``).

Equations (test-set convention)::

    M(q) q̈ = f(q, q̇) − G(q)ᵀ λ,    g(q) = 0 ∈ R⁶,    G = ∂g/∂q.

``f`` holds everything but the constraint reaction: the driving torque, the spring and the
velocity-squared (Coriolis and centrifugal) terms of the ``q``-dependent ``M``. gausspp writes the
same step as ``A q̈ = f + D u`` with an ideal reaction ``D = Jᵀ = Gᵀ`` (the constraints enter as
``Φ = ġ = G q̇``, so ``J = G``): its multipliers are therefore **u = −λ** (test-set ``λ``), its
reaction ``Gᵀu = −Gᵀλ``. ``REFERENCE_LAMBDA`` and ``LAMBDA0`` are in the test-set sign.

The six constraints are three holonomic groups (two rows each), one per loop, all stating where
the joint point ``E(β, Θ) = (rr cos β − d cos(β+Θ), rr sin β − d sin(β+Θ))`` is:

* ``loop-B`` (rows g1, g2): ``E = B + ss (sin γ, −cos γ)``;
* ``loop-A-delta`` (g3, g4): ``E = A + (e sin(Φ+δ) + zt cos δ, −e cos(Φ+δ) + zt sin δ)``;
* ``loop-A-eps`` (g5, g6): ``E = A + (zf cos(Ω+ε) + u sin ε, zf sin(Ω+ε) − u cos ε)``.

The Jacobian ``J = G`` and the acceleration-level right-hand side ``φ = −γ(q, q̇)`` are derived
from ``g`` by casadi.

Reference. There is no closed form (``Scene.exact`` is ``None``). The published reference at
``t = 0.03`` is the test set's ``andsoln`` (PSIDE, ``rtol = atol = 1e-14``, Cray C90 double
precision): :data:`REFERENCE_Q` (angles ``y1..y7``), :data:`REFERENCE_V`, :data:`REFERENCE_A`
and :data:`REFERENCE_LAMBDA`. Its angles are good to about :data:`PUBLISHED_ACCURACY` ``= 1.4e-9``
(absolute), its accelerations and multipliers to 6–7 digits only; :data:`CONVERGED_Q`,
:data:`CONVERGED_V`, :data:`CONVERGED_A`, :data:`CONVERGED_LAMBDA` are an independent
extended-precision (long double) solution, derived again apart from gausspp by
``python benchmarks/andrews_converged.py`` (the published formulas, mpmath's Taylor-series integrator at 30
digits), which reproduces them to 14–16 digits. The initial values ``q0, v0 = 0`` and the consistent
``q̈(0)`` (:data:`ACCELERATION0`) and ``λ(0)`` (:data:`LAMBDA0`) are the test set's 30-digit values.
:func:`significant_digits` scores a result as the test set does (``scd``).

Units. Every number above is SI, as published. The scene's parameters ``metre``, ``kilogram`` and ``second`` write
the same mechanism in other units (``metre=1e3``: millimetres): each constant is multiplied by its unit's number
(:data:`DIMENSIONS`, :func:`parameters_in`), the angles and the initial state stay as they are, and
:func:`reference` gives the published states in the scene's units (times as seconds, velocities as 1/s, …).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import InputError, UnknownNameError
from ..model.constraints import Holonomic
from ..model.mechanism import MassMatrix
from ..model.model import Model
from .scene import Scene

# -- parameters (SI units, as published), test-set names ----------------------------------------
m1, m2, m3, m4, m5, m6, m7 = 0.04325, 0.00365, 0.02373, 0.00706, 0.07050, 0.00706, 0.05498
i1, i2, i3, i4, i5, i6, i7 = 2.194e-6, 4.410e-7, 5.255e-6, 5.667e-7, 1.169e-5, 5.667e-7, 1.912e-5
xa, ya = -0.06934, -0.00227
xb, yb = -0.03635, 0.03273
xc, yc = 0.014, 0.072
c0, l0, mom = 4530.0, 0.07785, 0.033
d, da, e, ea = 0.028, 0.0115, 0.02, 0.01421
rr, ra, ss = 0.007, 0.00092, 0.035
sa, sb, sc, sd = 0.01874, 0.01043, 0.018, 0.02
ta, tb = 0.02308, 0.00916
u, ua, ub = 0.04, 0.01228, 0.00449
zf, zt, fa = 0.02, 0.04, 0.01421

#: Parameters by name, as in the test set.
PARAMETERS: dict[str, float] = dict(
    m1=m1, m2=m2, m3=m3, m4=m4, m5=m5, m6=m6, m7=m7,
    i1=i1, i2=i2, i3=i3, i4=i4, i5=i5, i6=i6, i7=i7,
    xa=xa, ya=ya, xb=xb, yb=yb, xc=xc, yc=yc, c0=c0, l0=l0, mom=mom,
    d=d, da=da, e=e, ea=ea, rr=rr, ra=ra, ss=ss, sa=sa, sb=sb, sc=sc, sd=sd,
    ta=ta, tb=tb, u=u, ua=ua, ub=ub, zf=zf, zt=zt, fa=fa,
)  # fmt: skip

#: Each parameter's dimension as powers of (kg, m, s): masses, moments of inertia, lengths, the spring's stiffness
#: (N/m) and the driving torque (N·m).
DIMENSIONS: dict[str, tuple[int, int, int]] = {
    **{f"m{i}": (1, 0, 0) for i in range(1, 8)},
    **{f"i{i}": (1, 2, 0) for i in range(1, 8)},
    **{k: (0, 1, 0) for k in PARAMETERS if k[0] not in "mi" and k not in ("c0", "mom")},
    "c0": (1, 0, -2),
    "mom": (1, 2, -2),
}


def _factor(dimension: tuple[int, int, int], metre: float, kilogram: float, second: float) -> float:
    """The number a quantity of ``dimension`` (powers of kg, m, s) is multiplied by in units where one metre, one
    kilogram and one second are the numbers ``metre``, ``kilogram`` and ``second``."""
    kg, m, s = dimension
    return float(kilogram**kg * metre**m * second**s)


def parameters_in(metre: float = 1.0, kilogram: float = 1.0, second: float = 1.0) -> dict[str, float]:
    """:data:`PARAMETERS` (SI) in units where one metre, one kilogram and one second are the numbers ``metre``,
    ``kilogram`` and ``second`` (millimetres: ``metre=1e3``)."""
    return {k: value * _factor(DIMENSIONS[k], metre, kilogram, second) for k, value in PARAMETERS.items()}


#: Coordinate names in test-set order (y1..y7).
COORDINATES = ("beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon")

# -- consistent initial values (t = 0), published with 30 digits ------------------------------------
Q0 = np.array(
    [
        float("-0.0617138900142764496358948458001"),
        0.0,
        float("0.455279819163070380255912382449"),
        float("0.222668390165885884674473185609"),
        float("0.487364979543842550225598953530"),
        float("-0.222668390165885884674473185609"),
        float("1.23054744454982119249735015568"),
    ]
)
V0 = np.zeros(7)
#: q̈(0), published.
ACCELERATION0 = np.array(
    [float("14222.4439199541138705911625887"), float("-10666.8329399655854029433719415"), 0.0, 0.0, 0.0, 0.0, 0.0]
)
#: λ(0) in the test-set sign (M q̈ = f − Gᵀλ); gausspp's multipliers are u = −λ.
LAMBDA0 = np.array([float("98.5668703962410896057654982170"), float("-6.12268834425566265503114393122"), 0, 0, 0, 0])

# -- published reference at t = 0.03 (andsoln: PSIDE, rtol = atol = 1e-14) ------------------------
REFERENCE_T = 0.03
#: Published angles y1..y7 at t = 0.03.
REFERENCE_Q = np.array(
    [
        0.1581077119629904e2,
        -0.1575637105984298e2,
        0.4082224013073101e-1,
        -0.5347301163226948e0,
        0.5244099658805304e0,
        0.5347301163226948e0,
        0.1048080741042263e1,
    ]
)
#: Published velocities y8..y14 at t = 0.03.
REFERENCE_V = np.array(
    [
        0.1139920302151208e4,
        -0.1424379294994111e4,
        0.1103291221937134e2,
        0.1929337464421385e2,
        0.5735699284790808e0,
        -0.1929337464421385e2,
        0.3231791658026955e0,
    ]
)
#: Published accelerations y15..y21 at t = 0.03 (good to 6–7 digits).
REFERENCE_A = np.array(
    [
        -0.2463176316945196e5,
        0.5185037701610329e5,
        0.3241025686413781e6,
        0.5667493645176213e6,
        0.1674362929479361e5,
        -0.5667493645176222e6,
        0.9826520791458422e4,
    ]
)
#: Published multipliers y22..y27 at t = 0.03, test-set sign (good to 6–7 digits).
REFERENCE_LAMBDA = np.array(
    [
        0.1991753333731910e3,
        -0.2975531228015052e2,
        0.2306654119098399e2,
        0.3145271365475927e2,
        0.2264249232082739e2,
        0.1161740700019673e2,
    ]
)
#: Absolute accuracy of the published angles (their distance from an extended-precision solution).
PUBLISHED_ACCURACY = 1.4e-9

# -- converged values at t = 0.03 (long double) -----------------------------------------------------
CONVERGED_Q = np.array(
    [
        1.5810771195153708e01,
        -1.5756371058411840e01,
        4.0822240119645819e-02,
        -5.3473011634207957e-01,
        5.2440996587995407e-01,
        5.3473011634207956e-01,
        1.0480807410419379e00,
    ]
)
CONVERGED_V = np.array(
    [
        1.1399203022591061e03,
        -1.4243792951775401e03,
        1.1032911910618654e01,
        1.9293374105032145e01,
        5.7356991482950591e-01,
        -1.9293374105032145e01,
        3.2317914924913426e-01,
    ]
)
CONVERGED_A = np.array(
    [
        -2.4631763122874821e04,
        5.1850319636464616e04,
        3.2410260070757859e05,
        5.6674942200099530e05,
        1.6743635418345437e04,
        -5.6674942200099530e05,
        9.8265078015441792e03,
    ]
)
#: Converged multipliers, test-set sign.
CONVERGED_LAMBDA = np.array(
    [
        1.9917534810453862e02,
        -2.9755309974971717e01,
        2.3066543611622149e01,
        3.1452725275771124e01,
        2.2642494786394378e01,
        1.1617392352611274e01,
    ]
)

_UROUND = 1e-16  # the test-set driver's stand-in for a zero error
_MIN_VALUE = 1e-200  # reference components at least this large are scored


def significant_digits(q: np.ndarray, reference: np.ndarray = REFERENCE_Q) -> float:
    """The test set's ``scd`` score of the angles ``q`` (y1..y7) at ``t = 0.03``.

    Computes ``−log10(max_i |reference_i − q_i| / |reference_i|)``: the maximum over the
    components of the *relative* error, taken over the components with ``|reference_i| ≥ 1e-200``;
    a maximum of exactly 0 counts as ``1e-16`` (16 digits). This is what the Bari test-set driver
    (``report.f``, subroutine ``getscd``) reports as ``scd`` for ``andrews``, where only components
    1..7 (the angles) are scored. It is not the driver's *mixed* ``mescd``
    (``|ref − y| / (atol/rtol + |ref|)``, which depends on the tolerances and is taken over all 27
    components). Both ``q`` and ``reference`` must have 7 entries.
    """
    q = np.asarray(q, dtype=float).ravel()
    ref = np.asarray(reference, dtype=float).ravel()
    if q.shape != (7,) or ref.shape != (7,):
        raise InputError(f"significant_digits: need 7 angles and 7 reference values, got {q.size} and {ref.size}")
    scored = np.abs(ref) >= _MIN_VALUE
    worst = float(np.max(np.abs((ref[scored] - q[scored]) / ref[scored]), initial=0.0))
    return float(-np.log10(worst if worst > 0 else _UROUND))


# -- the model ------------------------------------------------------------------------------------
def mass_matrix(q: ca.SX, t: ca.SX | None = None, p: Mapping[str, float] = PARAMETERS) -> ca.SX:
    """The test set's 7×7 mass matrix ``M(q)`` (depends on Θ, Φ, Ω), of the parameters ``p`` (SI by default)."""
    m1, m2, m3, m4, m5, m6, m7 = (p[f"m{i}"] for i in range(1, 8))
    i1, i2, i3, i4, i5, i6, i7 = (p[f"i{i}"] for i in range(1, 8))
    e, ea, zf, fa, zt, u = p["e"], p["ea"], p["zf"], p["fa"], p["zt"], p["u"]
    ra, rr, da, sa, sb, ta, tb, ua, ub = (p[k] for k in ("ra", "rr", "da", "sa", "sb", "ta", "tb", "ua", "ub"))
    th, ph, om = q[1], q[3], q[5]
    ep, zp = e - ea, zf - fa
    M = ca.SX.zeros(7, 7)
    M[0, 0] = m1 * ra**2 + m2 * (rr**2 - 2 * da * rr * ca.cos(th) + da**2) + i1 + i2
    M[1, 0] = M[0, 1] = m2 * (da**2 - da * rr * ca.cos(th)) + i2
    M[1, 1] = m2 * da**2 + i2
    M[2, 2] = m3 * (sa**2 + sb**2) + i3
    M[3, 3] = m4 * ep**2 + i4
    M[4, 3] = M[3, 4] = m4 * (ep**2 + zt * ep * ca.sin(ph)) + i4
    M[4, 4] = m4 * (zt**2 + 2 * zt * ep * ca.sin(ph) + ep**2) + m5 * (ta**2 + tb**2) + i4 + i5
    M[5, 5] = m6 * zp**2 + i6
    M[6, 5] = M[5, 6] = m6 * (zp**2 - u * zp * ca.sin(om)) + i6
    M[6, 6] = m6 * (zp**2 - 2 * u * zp * ca.sin(om) + u**2) + m7 * (ua**2 + ub**2) + i6 + i7
    return M


def _spring(q: ca.SX, p: Mapping[str, float]) -> tuple[ca.SX, ca.SX, ca.SX]:
    """Spring point ``D − C`` on body 3, its length ``L`` and ``∂D/∂γ``."""
    sc, sd, xb, yb, xc, yc = (p[k] for k in ("sc", "sd", "xb", "yb", "xc", "yc"))
    ga = q[2]
    Dx = sd * ca.cos(ga) + sc * ca.sin(ga) + xb
    Dy = sd * ca.sin(ga) - sc * ca.cos(ga) + yb
    rel = ca.vertcat(Dx - xc, Dy - yc)
    dD = ca.vertcat(sc * ca.cos(ga) - sd * ca.sin(ga), sd * ca.cos(ga) + sc * ca.sin(ga))
    return rel, ca.norm_2(rel), dD


def force(q: ca.SX, v: ca.SX, t: ca.SX | None = None, p: Mapping[str, float] = PARAMETERS) -> ca.SX:
    """The test set's force vector ``f(q, q̇)``: torque, spring and velocity-squared terms (parameters ``p``)."""
    m2, m4, m6, mom, c0, l0 = p["m2"], p["m4"], p["m6"], p["mom"], p["c0"], p["l0"]
    e, ea, zf, fa, zt, u, da, rr = (p[k] for k in ("e", "ea", "zf", "fa", "zt", "u", "da", "rr"))
    th, ph, om = q[1], q[3], q[5]
    bep, thp, php, dep, omp, epp = v[0], v[1], v[3], v[4], v[5], v[6]
    ep, zp = e - ea, zf - fa
    rel, L, dD = _spring(q, p)
    F = -c0 * (L - l0) / L * rel
    return ca.vertcat(
        mom - m2 * da * rr * thp * (thp + 2 * bep) * ca.sin(th),
        m2 * da * rr * bep**2 * ca.sin(th),
        ca.dot(F, dD),
        m4 * zt * ep * dep**2 * ca.cos(ph),
        -m4 * zt * ep * php * (php + 2 * dep) * ca.cos(ph),
        -m6 * u * zp * epp**2 * ca.cos(om),
        m6 * u * zp * omp * (omp + 2 * epp) * ca.cos(om),
    )


def _energy(q: ca.SX, v: ca.SX, t: ca.SX, p: Mapping[str, float] = PARAMETERS) -> ca.SX:
    """``½ q̇ᵀ M q̇ + ½ c0 (L − l0)²`` (the torque ``mom`` is the non-conservative force)."""
    _, L, _ = _spring(q, p)
    return 0.5 * ca.dot(v, mass_matrix(q, t, p) @ v) + 0.5 * p["c0"] * (L - p["l0"]) ** 2


def joint_point(q: ca.SX, p: Mapping[str, float] = PARAMETERS) -> tuple[ca.SX, ca.SX]:
    """``E(β, Θ)``: the end of body 2, reached from the crank pivot O."""
    rr, d = p["rr"], p["d"]
    be, th = q[0], q[1]
    return rr * ca.cos(be) - d * ca.cos(be + th), rr * ca.sin(be) - d * ca.sin(be + th)


def loop_b(q: ca.SX, t: ca.SX | None = None, p: Mapping[str, float] = PARAMETERS) -> ca.SX:
    """Rows g1, g2: ``E = B + ss (sin γ, −cos γ)``."""
    ss, xb, yb = p["ss"], p["xb"], p["yb"]
    Ex, Ey = joint_point(q, p)
    ga = q[2]
    return ca.vertcat(Ex - ss * ca.sin(ga) - xb, Ey + ss * ca.cos(ga) - yb)


def loop_a_delta(q: ca.SX, t: ca.SX | None = None, p: Mapping[str, float] = PARAMETERS) -> ca.SX:
    """Rows g3, g4: ``E = A + (e sin(Φ+δ) + zt cos δ, −e cos(Φ+δ) + zt sin δ)``."""
    e, zt, xa, ya = p["e"], p["zt"], p["xa"], p["ya"]
    Ex, Ey = joint_point(q, p)
    ph, de = q[3], q[4]
    return ca.vertcat(
        Ex - e * ca.sin(ph + de) - zt * ca.cos(de) - xa,
        Ey + e * ca.cos(ph + de) - zt * ca.sin(de) - ya,
    )


def loop_a_eps(q: ca.SX, t: ca.SX | None = None, p: Mapping[str, float] = PARAMETERS) -> ca.SX:
    """Rows g5, g6: ``E = A + (zf cos(Ω+ε) + u sin ε, zf sin(Ω+ε) − u cos ε)``."""
    zf, u, xa, ya = p["zf"], p["u"], p["xa"], p["ya"]
    Ex, Ey = joint_point(q, p)
    om, ep = q[5], q[6]
    return ca.vertcat(
        Ex - zf * ca.cos(om + ep) - u * ca.sin(ep) - xa,
        Ey - zf * ca.sin(om + ep) + u * ca.cos(ep) - ya,
    )


@dataclass(frozen=True)
class Reference:
    """The mechanism's state at one instant, in a scene's units (:func:`reference`).

    Attributes
    ----------
    t : float
        The instant.
    q, v, a : (7,) arrays
        The angles (rad, the same in every unit), the angular velocities and the accelerations.
    lam : (6,) array
        The multipliers in the test-set sign (forces, N in SI); gausspp's ``u`` is ``−lam``.
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    lam: np.ndarray


#: The published states (SI): at t = 0, the published reference at t = 0.03 and the converged values there.
_STATES = {
    "initial": (0.0, Q0, V0, ACCELERATION0, LAMBDA0),
    "published": (REFERENCE_T, REFERENCE_Q, REFERENCE_V, REFERENCE_A, REFERENCE_LAMBDA),
    "converged": (REFERENCE_T, CONVERGED_Q, CONVERGED_V, CONVERGED_A, CONVERGED_LAMBDA),
}


def reference(scene: Scene | None = None, which: str = "published") -> Reference:
    """A published state of the mechanism in the units ``scene`` was built in (its ``metre``, ``kilogram`` and
    ``second``; SI without a scene): ``"initial"`` (t = 0, :data:`ACCELERATION0`, :data:`LAMBDA0`),
    ``"published"`` (t = 0.03, :data:`REFERENCE_Q` …) or ``"converged"`` (t = 0.03, :data:`CONVERGED_Q` …).

    Times scale as seconds, angles not at all, velocities as 1/s, accelerations as 1/s², multipliers as N.
    """
    if which not in _STATES:
        raise UnknownNameError(f"andrews.reference: which={which!r} is unknown; use one of {list(_STATES)}")
    params = {} if scene is None else scene.params
    metre, kilogram, second = (float(params.get(k, 1.0)) for k in ("metre", "kilogram", "second"))
    t, q, v, a, lam = _STATES[which]
    newton = _factor((1, 1, -2), metre, kilogram, second)
    return Reference(t * second, q.copy(), v / second, a / second**2, lam * newton)


def build(t_end: float | None = None, metre: float = 1.0, kilogram: float = 1.0, second: float = 1.0) -> Scene:
    """Andrews' squeezing mechanism: 7 bodies, 6 holonomic loop-closure constraints (Hairer–Wanner / Bari test set)

    ``q = (β, Θ, γ, Φ, δ, Ω, ε)``, ``M(q) q̈ = f(q, q̇) − Gᵀλ`` with the test set's ``M`` and ``f``,
    three ideal :class:`~gausspp.Holonomic` groups ``loop-B``, ``loop-A-delta``, ``loop-A-eps``
    (rows g1..g6). gausspp's multipliers are ``u = −λ`` (test-set sign). Initial data: the
    published consistent values (``q̇(0) = 0``). No closed form (``exact = None``); the reference
    is the published solution at ``t = 0.03`` (:data:`REFERENCE_Q`, angles good to 1.4e-9) and
    the converged :data:`CONVERGED_Q`; see the module docstring.

    The published data are SI. ``metre``, ``kilogram`` and ``second`` write the same mechanism in other units: every
    published constant is multiplied by its unit's number (:func:`parameters_in`), and :func:`reference` gives the
    reference states in those units.

    Parameters
    ----------
    t_end : float or None
        Suggested horizon of a simulation; None: the published reference's instant, 0.03 s in the scene's units of
        time (s). Allowed: > 0 or None.
    metre : float
        One metre in the scene's unit of length: every published length is multiplied by it (1e3: millimetres)
        (m). Allowed: > 0.
    kilogram : float
        One kilogram in the scene's unit of mass (1e3: grams) (kg). Allowed: > 0.
    second : float
        One second in the scene's unit of time (1e3: milliseconds) (s). Allowed: > 0.
    """
    for key, value in (("metre", metre), ("kilogram", kilogram), ("second", second)):
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"andrews: {key} must be a positive number (one {key} in the scene's units), got {value}")
    t_end = REFERENCE_T * second if t_end is None else t_end
    if not (np.isfinite(t_end) and t_end > 0):
        raise InputError(f"andrews: t_end must be positive, got {t_end}")
    p = parameters_in(metre, kilogram, second)
    mom = p["mom"]
    mechanism = MassMatrix(
        n=7,
        A=lambda q, t: mass_matrix(q, t, p),
        f=lambda q, v, t: force(q, v, t, p),
        energy=lambda q, v, t: _energy(q, v, t, p),
        nonconservative=lambda q, v, t: ca.vertcat(mom, ca.SX.zeros(6)),
    )
    constraints = [
        Holonomic(lambda q, t: loop_b(q, t, p), name="loop-B"),
        Holonomic(lambda q, t: loop_a_delta(q, t, p), name="loop-A-delta"),
        Holonomic(lambda q, t: loop_a_eps(q, t, p), name="loop-A-eps"),
    ]
    return Scene(
        name="andrews",
        model=Model(mechanism, constraints),
        q0=Q0.copy(),
        v0=V0.copy(),
        coordinates=("β (rad)", "Θ (rad)", "γ (rad)", "Φ (rad)", "δ (rad)", "Ω (rad)", "ε (rad)"),
        lam0=None,
        t_end=float(t_end),
        exact=None,
        description="Andrews' squeezing mechanism: 7 bodies, 6 holonomic loop closures; published reference at t=0.03",
        params=dict(t_end=float(t_end), metre=float(metre), kilogram=float(kilogram), second=float(second)),
    )
