"""A stiff spring chain with a constraint (docs/theory.md §6.6): a test for stiff integrators.

``n`` masses on a line, ``q`` their displacements. Spring 0 joins mass 0 to a wall, spring ``i``
(``1 ≤ i < n``) joins masses ``i − 1`` and ``i``; soft springs have stiffness ``k``, the springs
listed in ``stiff`` have ``stiffness_ratio · k``. The masses grow geometrically from ``m`` to
``mass_ratio · m``. A lever ties the last two masses: ``Φ = v[n−1] + v[n−2] = 0``, kept ideally
(``realization="ideal"``, a lever with a fixed pivot) or by a follower force on the last mass
(``realization="servo"``, Béghin, ``M = e_{n−1}``).

Both realizations keep ``J`` and ``D`` constant, so the motion is linear:
``q̈ = −L q`` with ``L = (I − A⁻¹D S⁻¹J) A⁻¹K`` and ``S = J A⁻¹D``. ``exact`` is the modal
solution of that ODE (eigenvectors of ``L``, computed once per build): an independent
reference by a different method, accurate to about ``1e-10`` (the eigenvalues of ``L`` carry
round-off relative to its largest one).

Initial data: at rest (so on the constraint), the last two masses displaced to ``∓amplitude``
and each stiff spring pre-stretched so that its extension starts with zero acceleration — the
slow manifold. The stiff oscillation (frequency ≈ ``√(stiffness_ratio · k)``) is then hardly
excited, and a stiff method may step over it while an explicit one must resolve it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..errors import InputError, UnknownNameError
from ..model.constraints import Constraint
from ..model.mechanism import Lagrangian
from ..model.model import Model
from ..model.realizations import Force, Ideal, Realization
from .scene import Scene, numbered

REALIZATIONS = ("ideal", "servo")


def _extension_rows(n: int, springs: Sequence[int]) -> np.ndarray:
    """Rows ``E`` with ``E q`` the extensions of ``springs``."""
    E = np.zeros((len(springs), n))
    for r, s in enumerate(springs):
        E[r, s] = 1.0
        if s > 0:
            E[r, s - 1] = -1.0
    return E


def build(
    n: int = 4,
    stiffness_ratio: float = 1e6,
    mass_ratio: float = 1.0,
    stiff: Sequence[int] = (1,),
    realization: str = "ideal",
    k: float = 1.0,
    amplitude: float = 0.5,
    m: float = 1.0,
    t_end: float = 10.0,
) -> Scene:
    """Chain of masses on soft and stiff springs (stiffness ratio 1e6 by default), lever constraint (ideal or servo).

    Parameters
    ----------
    n : int
        Number of masses (-). Allowed: integer ≥ 3.
    stiffness_ratio : float
        Stiffness of the stiff springs over ``k`` (-). Allowed: > 0.
    mass_ratio : float
        Last mass over the first: the masses grow geometrically from ``m`` to ``mass_ratio · m`` (-). Allowed: > 0.
    stiff : sequence of int
        Indices of the stiff springs: spring 0 joins mass 0 to the wall, spring ``i`` masses ``i − 1`` and ``i``
        (-). Allowed: integers from 0 to n − 1 (repeats ignored; empty: no stiff spring).
    realization : str
        How the lever ``v[n−1] + v[n−2] = 0`` is kept: by a lever with a fixed pivot (``'ideal'``) or by a
        follower force on the last mass (``'servo'``) (-). Allowed: one of 'ideal', 'servo'.
    k : float
        Stiffness of the soft springs (N/m). Allowed: > 0.
    amplitude : float
        Initial displacements ``∓amplitude`` of the last two masses (m). Allowed: any finite number.
    m : float
        Mass of the first body (kg). Allowed: > 0.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    stiff = _checked(n, stiffness_ratio, mass_ratio, stiff, realization, k, m)
    n = int(n)
    masses = float(m) * float(mass_ratio) ** (np.arange(n) / (n - 1))
    springs = np.full(n, float(k))
    springs[stiff] *= stiffness_ratio
    E_all = _extension_rows(n, range(n))
    K = E_all.T @ (springs[:, None] * E_all)
    constraint, J, D = _lever(n, realization)
    model = Model(_chain(masses, springs), [constraint])

    # the linear motion q̈ = −L q of both realizations (D and J constant)
    Ainv = np.diag(1.0 / masses)
    S = J @ Ainv @ D
    L = (np.eye(n) - Ainv @ D @ np.linalg.solve(S, J)) @ Ainv @ K
    q0 = _slow_start(masses, stiff, L, amplitude)
    v0 = np.zeros(n)
    return Scene(
        name="stiff-chain",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=numbered(["x (m)"], n, start=0),
        lam0=None,
        t_end=t_end,
        exact=_modal_solution(L, q0, v0),
        description=(
            f"{n} masses on springs, stiffness ratio {stiffness_ratio:g}, mass ratio {mass_ratio:g}, "
            f"lever constraint ({realization}); docs/theory.md §6.6"
        ),
        params=dict(
            n=n,
            stiffness_ratio=stiffness_ratio,
            mass_ratio=mass_ratio,
            stiff=stiff,
            realization=realization,
            k=k,
            amplitude=amplitude,
            m=m,
            t_end=t_end,
        ),
    )


def _checked(
    n: int, stiffness_ratio: float, mass_ratio: float, stiff: Sequence[int], realization: str, k: float, m: float
) -> list[int]:
    """The parameters checked; the stiff springs' indices sorted, without repeats."""
    if realization not in REALIZATIONS:
        raise UnknownNameError(f"stiff-chain: realization={realization!r} is unknown; use one of {list(REALIZATIONS)}")
    if not isinstance(n, (int, np.integer)) or n < 3:
        raise InputError(f"stiff-chain: need n ≥ 3 masses (a spring to the wall, the lever on the last two), got {n!r}")
    if not (stiffness_ratio > 0 and mass_ratio > 0 and k > 0 and m > 0):
        raise InputError(
            "stiff-chain: stiffness_ratio, mass_ratio, k and m must be positive, "
            f"got {stiffness_ratio}, {mass_ratio}, {k}, {m}"
        )
    stiff = sorted({int(s) for s in stiff})
    if any(not 0 <= s < n for s in stiff):
        raise InputError(f"stiff-chain: stiff springs must be indices in 0…{n - 1}, got {stiff}")
    return stiff


def _chain(masses: np.ndarray, springs: np.ndarray) -> Lagrangian:
    """The masses on a line, spring 0 to the wall, spring ``i`` between masses ``i − 1`` and ``i``."""
    n = masses.size

    def V(q, t):  # noqa: ANN001, ANN202
        extensions = [q[0]] + [q[i] - q[i - 1] for i in range(1, n)]
        return sum(0.5 * springs[i] * extensions[i] ** 2 for i in range(n))

    return Lagrangian(n=n, T=lambda q, v, t: 0.5 * sum(masses[i] * v[i] ** 2 for i in range(n)), V=V)


def _lever(n: int, realization: str) -> tuple[Constraint, np.ndarray, np.ndarray]:
    """The lever ``v[n−1] + v[n−2] = 0`` with its realization, and its constant ``J`` and ``D``."""
    J = np.zeros((1, n))
    J[0, n - 2 :] = 1.0
    real: Realization
    if realization == "ideal":
        real, D = Ideal(), J.T
    else:
        e_last = np.zeros(n)
        e_last[-1] = 1.0
        real, D = Force(M=lambda q, v, t: [e_last.tolist()]), e_last[:, None]
    return Constraint(lambda q, v, t: v[n - 1] + v[n - 2], name="lever", realization=real), J, D


def _slow_start(masses: np.ndarray, stiff: list[int], L: np.ndarray, amplitude: float) -> np.ndarray:
    """At rest, lever tilted, stiff springs on the slow manifold (their extensions' accelerations
    ``−E L q`` vanish); each stiff spring is stretched about its pair's centre of mass."""
    n = masses.size
    q0 = np.zeros(n)
    q0[n - 2], q0[n - 1] = -amplitude, amplitude
    if stiff:
        P = np.zeros((n, len(stiff)))
        for r, s in enumerate(stiff):
            if s == 0:
                P[0, r] = 1.0
            else:
                a, b = masses[s - 1], masses[s]
                P[s, r], P[s - 1, r] = a / (a + b), -b / (a + b)
        E = _extension_rows(n, stiff)
        q0 = q0 + P @ np.linalg.solve(E @ L @ P, -(E @ L @ q0))
    return q0


def _modal_solution(L: np.ndarray, q0: np.ndarray, v0: np.ndarray) -> Callable[[float], tuple[np.ndarray, np.ndarray]]:
    """The exact motion of ``q̈ = −L q`` from ``(q0, v0)`` by the eigenvectors of ``L``."""
    mu, modes = np.linalg.eig(L)
    mu[np.argmin(np.abs(mu))] = 0.0  # J L = 0 exactly: the lever's mode does not oscillate
    omega = np.emath.sqrt(mu.astype(complex))
    c0, d0 = np.linalg.solve(modes, q0.astype(complex)), np.linalg.solve(modes, v0.astype(complex))

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        wt = omega * t
        sin_over_omega = t * np.sinc(wt / np.pi)  # sin(ωt)/ω, → t for the lever's zero mode
        q = modes @ (c0 * np.cos(wt) + d0 * sin_over_omega)
        v = modes @ (-c0 * omega * np.sin(wt) + d0 * np.cos(wt))
        return q.real, v.real

    return exact
