"""Static indeterminacy: the forces of redundant contacts moved within their cones.

A body resting on more contacts than its freedom needs (a table on four legs, a quadruped on four feet) has many
force distributions that give the same acceleration: with the contact columns ``C`` (``q̈ = A⁻¹(f + C u)``), any
``u + Z w`` with ``C Z = 0`` (``Z`` a basis of ``C``'s null space) moves nothing. The direct solution
(:func:`.modes.solve`) takes the least-squares one, which may put one foot's friction outside its cone
``‖F‖ ≤ μ_s N`` (or pull, ``N < 0``) where another distribution keeps every cone: the modes are consistent, and
Coulomb's law holds them. :func:`within_cones` looks for such a ``w`` — the nearest to the least-squares forces,
``min ‖w‖²`` over the cones of the sticking contacts and ``N ≥ 0`` on the closed ones — a second-order cone program
solved by Clarabel (exact), or, without it, scipy's linear program over each cone's inscribed polygon of
:data:`FACETS` facets (a feasible answer is then feasible for the circular cone too; one within ``1 − cos(π/16)``,
2 %, of the cone's edge may be missed and the contact take the next modes: it slides).
"""

from __future__ import annotations

import numpy as np

from ..model.friction_contact import FrictionContact, dry
from .kinds import HELD, OPEN, SLIDE, STICK

#: The inscribed polygon of a two-component cone without Clarabel.
FACETS = 16


def within_cones(
    contacts: list[FrictionContact],
    kinds: tuple[str, ...],
    dirs: tuple[np.ndarray | None, ...],
    N0: np.ndarray,
    F0: list[np.ndarray],
    C: np.ndarray,
    where: list[tuple[int, int]],
    tol: float,
) -> tuple[np.ndarray, list[np.ndarray]] | None:
    """The normal and friction forces ``(N, F)`` of the contacts in modes ``kinds`` (slip directions ``dirs``) moved
    along ``C``'s null space from ``(N0, F0)`` into the cones (module docstring), or ``None`` where there is no
    freedom or no such forces."""
    from scipy.linalg import null_space

    Z = null_space(C, rcond=1e-10)
    if Z.shape[1] == 0:
        return None
    u0 = np.zeros(len(where))
    for k, (i, j) in enumerate(where):
        u0[k] = N0[i] if j < 0 else F0[i][j]
    cones, signs = [], []
    for i, kind in enumerate(kinds):
        if kind in (OPEN, HELD):
            continue
        if dry(contacts[i]):  # a joint's dry friction: its force within the fixed bound, no normal column
            if kind == STICK:
                cones.append((None, [k for k, (c, j) in enumerate(where) if c == i], contacts[i].bound))  # type: ignore[attr-defined]
            continue
        n = [k for k, (c, j) in enumerate(where) if c == i and j < 0][0]
        signs.append(n)
        if kind == STICK:
            cones.append((n, [k for k, (c, j) in enumerate(where) if c == i and j >= 0], contacts[i].mu_static))
    w = _solve(u0, Z, cones, signs, tol)
    if w is None:
        return None
    u = u0 + Z @ w
    N, F = N0.copy(), [f.copy() for f in F0]
    for k, (i, j) in enumerate(where):
        if j < 0:
            N[i] = u[k]
        else:
            F[i][j] = u[k]
    for i, kind in enumerate(kinds):
        if kind == SLIDE and dirs[i] is not None:
            F[i] = -contacts[i].mu * N[i] * dirs[i]
    return N, F


def _solve(u0: np.ndarray, Z: np.ndarray, cones: list, signs: list[int], tol: float) -> np.ndarray | None:
    try:
        import clarabel
    except ImportError:
        return _polygon(u0, Z, cones, signs, tol)
    import scipy.sparse as sp

    p = Z.shape[1]
    blocks, b, kinds = [], [], []
    # N ≥ −tol: s = N0 + tol + Zn w ≥ 0, Clarabel's A x + s = b form: A = −Zn, b = N0 + tol
    blocks.append(-Z[signs])
    b += list(u0[signs] + tol)
    kinds.append(clarabel.NonnegativeConeT(len(signs)))
    for n, f, mu in cones:  # (μ N + tol, F) in the second-order cone (N fixed at 1 for a joint's bound μ)
        rows = np.vstack([-mu * Z[n] if n is not None else np.zeros((1, p)), -Z[f]])
        blocks.append(rows)
        b += [mu * (u0[n] if n is not None else 1.0) + tol, *u0[f]]
        kinds.append(clarabel.SecondOrderConeT(1 + len(f)))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solver = clarabel.DefaultSolver(
        sp.csc_matrix(np.eye(p)), np.zeros(p), sp.csc_matrix(np.vstack(blocks)), np.array(b), kinds, settings
    )
    result = solver.solve()
    return np.array(result.x) if str(result.status) == "Solved" else None


def _polygon(u0: np.ndarray, Z: np.ndarray, cones: list, signs: list[int], tol: float) -> np.ndarray | None:
    from scipy.optimize import linprog

    rows, rhs = [-Z[signs]], list(u0[signs] + tol)  # −Zn w ≤ N0 + tol
    for n, f, mu in cones:
        if len(f) == 1:
            normals, reach = [np.array([1.0]), np.array([-1.0])], mu
        else:
            angles = (2 * np.arange(FACETS) + 1) * np.pi / FACETS
            normals, reach = [np.array([np.cos(a), np.sin(a)]) for a in angles], mu * np.cos(np.pi / FACETS)
        for normal in normals:  # normal·F − reach·N ≤ tol (N fixed at 1 for a joint's bound)
            fixed = n is None
            rows.append((normal @ Z[f] - (0.0 if fixed else reach * Z[n]))[None, :])
            rhs.append(tol - normal @ u0[f] + reach * (1.0 if fixed else u0[n]))
    found = linprog(np.zeros(Z.shape[1]), A_ub=np.vstack(rows), b_ub=np.array(rhs), bounds=(None, None))
    return np.asarray(found.x) if found.status == 0 else None
