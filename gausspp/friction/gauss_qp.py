"""One frictional step as Gauss's principle: the compulsion minimized over the conceivable accelerations.

At a state whose closed contacts are known (``g = 0``, ``ġ = 0``), the conceivable accelerations are
``q̈ = A⁻¹(f + C u)``: a contact that slips (``s ≠ 0``, sign ``σ``) reacts along its realization's one direction
``D = J_nᵀ − μσ J_tᵀ`` with ``N ≥ 0``; one that does not slip along ``J_nᵀ`` and ``J_tᵀ`` with ``(N, F)`` in the
friction cone ``|F| ≤ μ_s N``. Gauss's principle takes, among them, those that keep the contacts
(``J_n q̈ ≥ φ_n``; ``J_t q̈ = φ_t`` for a contact that sticks) with the least compulsion
``Z = (A(q̈ − q̈₀), q̈ − q̈₀) = uᵀ Cᵀ A⁻¹ C u``: a QP in ``u``. Where no cone force can keep a contact from
slipping the QP is infeasible: the contact starts to slide (``None``, reported to the caller).

A contact that is to stick keeps its normal row as an equality. With ``J_n q̈ ≥ φ_n`` there, the cone couples the
two rows and the least compulsion may be a *lift-off*: a larger ``N`` widens the cone until it holds the slip,
and the body leaves the surface with ``g̈ = μ|ṡ|``-like normal acceleration — the relaxation convex contact
models (MuJoCo's, Anitescu's) accept, not Coulomb's law. Measured on a hoop on a slope of 1 rad at μ = 0.5, the
relaxed QP answers a normal acceleration of 2.95 m/s² where the surface holds the hoop (tests/test_friction.py).

**The cone.** A one-component slip's cone is the interval ``|F| ≤ μ_s N``: two linear inequalities. A
two-component slip's is the circular cone ``‖F‖ ≤ μ_s N`` — a second-order cone, solved exactly by Clarabel
(``cone="exact"``) — or its inscribed polygon of ``k`` facets, ``F·n_j ≤ μ_s N cos(π/k)`` with ``n_j`` at the
angles ``(2j + 1)π/k`` (``cone=k``), a QP: the polygon holds less in the directions between its vertices, by up
to the factor ``cos(π/k)`` (29 % for 4 facets, 8 % for 8, 2 % for 16).

This is assembled from ``A, f, J_n, J_t, φ_n, φ_t`` and the realization's columns alone and solved by a conic
solver (Clarabel), independent of the direct solution's enumeration of modes (:mod:`.modes`) it checks.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import BackendUnavailableError
from ..model.friction_contact import FrictionContact, as_contacts
from .kinematics import ContactState


def gauss_qp_step(
    state: ContactState,
    contacts: FrictionContact | list[FrictionContact],
    closed: list[int],
    *,
    slip_tol: float = 1e-10,
    cone: str | int = "exact",
    relaxed: bool = False,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]] | None:
    """The acceleration, normal forces and friction forces by Gauss's QP (module docstring), or ``None`` where a
    non-slipping contact cannot stick while closed (infeasible: it slides, or lifts off). ``cone``: ``"exact"`` or
    a number of facets for two-component slips. ``relaxed`` keeps every normal row an inequality (the convex
    relaxation of the module docstring)."""
    clarabel = _clarabel_module()
    contacts = as_contacts("gauss_qp_step", contacts)
    cols, unknowns = _columns(state, contacts, closed, slip_tol)
    a0 = np.linalg.solve(state.A, state.f)
    N, F = np.zeros(len(contacts)), [np.zeros(len(si)) for si in state.s]
    if not cols:
        return a0, N, F
    n = len(cols)
    C = np.array(cols).T
    AinvC = np.linalg.solve(state.A, C)
    P = C.T @ AinvC
    P = 0.5 * (P + P.T) + 1e-14 * np.trace(P) * np.eye(n)
    # Clarabel's form: A u + z = b with z in the cones (zero: equalities; nonnegative: inequalities; SOC)
    zero_rows, zero_b, nonneg_rows, nonneg_b, socs = [], [], [], [], []
    for i in closed:  # J_n q̈ ≥ φ_n where the contact slips; = φ_n where it is to stick (see the module docstring)
        row, rhs = state.Jn[i] @ AinvC, state.phin[i] - state.Jn[i] @ a0
        if relaxed or np.linalg.norm(state.s[i]) > slip_tol:
            nonneg_rows.append(-row)
            nonneg_b.append(-rhs)
        else:
            zero_rows.append(row)
            zero_b.append(rhs)
    for k, (i, what) in enumerate(unknowns):
        if what in ("N", "slide"):  # N ≥ 0
            nonneg_rows.append(-np.eye(n)[k])
            nonneg_b.append(0.0)
        if what == "N":
            d, mu_s = state.s[i].size, contacts[i].mu_static
            for j in range(d):  # no slip
                zero_rows.append(state.Jt[i][j] @ AinvC)
                zero_b.append(state.phit[i][j] - state.Jt[i][j] @ a0)
            _cone_rows(k, d, mu_s, cone, n, nonneg_rows, nonneg_b, socs)
    u = _clarabel(clarabel, P, (zero_rows, zero_b), (nonneg_rows, nonneg_b), socs)
    if u is None:
        return None
    for k, (i, what) in enumerate(unknowns):
        if what in ("N", "slide"):
            N[i] = u[k]
        if what == "slide":
            F[i] = -contacts[i].mu * u[k] * state.s[i] / np.linalg.norm(state.s[i])
        elif what != "N":
            F[i][what] = u[k]
    return a0 + AinvC @ u, N, F


def _columns(
    state: ContactState, contacts: list[FrictionContact], closed: list[int], slip_tol: float
) -> tuple[list[np.ndarray], list[tuple[int, Any]]]:
    """The reaction's columns and what each unknown is: ``(contact, "slide")`` for a slipping contact (one column
    ``J_nᵀ − μ J_tᵀ ŝ``), ``(contact, "N")`` and ``(contact, j)`` for a non-slipping one (``J_nᵀ`` and ``J_tᵀ``)."""
    cols: list[np.ndarray] = []
    unknowns: list[tuple[int, Any]] = []
    for i in closed:
        s = state.s[i]
        if np.linalg.norm(s) > slip_tol:
            cols.append(state.Jn[i] - contacts[i].mu * (s / np.linalg.norm(s)) @ state.Jt[i])
            unknowns.append((i, "slide"))
        else:
            cols += [state.Jn[i], *state.Jt[i]]
            unknowns += [(i, "N")] + [(i, j) for j in range(s.size)]
    return cols, unknowns


def _clarabel_module() -> Any:
    """Clarabel, imported here (``import gausspp`` does not load the conic solver), or the error that says so."""
    try:
        import clarabel
    except ImportError:
        raise BackendUnavailableError(
            "gauss_qp_step solves the friction cone with Clarabel, which is not installed: pip install clarabel "
            "(or gausspp[backends])"
        ) from None
    return clarabel


def _clarabel(clarabel: Any, P: np.ndarray, zero: tuple, nonneg: tuple, socs: list) -> np.ndarray | None:
    """``min ½ uᵀPu`` over ``u`` with the rows ``zero`` (``(rows, b)``: ``row·u = b``), ``nonneg`` (``row·u ≤ b``)
    and the second-order cones ``socs`` (``−rows·u`` in the cone), by Clarabel; ``None`` where it finds none."""
    import scipy.sparse as sp

    blocks, b, cones = [], [], []
    for (rows, rhs), make in ((zero, clarabel.ZeroConeT), (nonneg, clarabel.NonnegativeConeT)):
        if rows:
            blocks.append(np.array(rows))
            b += list(rhs)
            cones.append(make(len(rows)))
    for rows in socs:
        blocks.append(np.array(rows))
        b += [0.0] * len(rows)
        cones.append(clarabel.SecondOrderConeT(len(rows)))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-12
    n = P.shape[0]
    solver = clarabel.DefaultSolver(
        sp.csc_matrix(np.triu(P)), np.zeros(n), sp.csc_matrix(np.vstack(blocks)), np.array(b), cones, settings
    )
    result = solver.solve()
    return np.array(result.x) if str(result.status) in ("Solved", "AlmostSolved") else None


def _cone_rows(k: int, d: int, mu_s: float, cone: str | int, n: int, nonneg: list, nonneg_b: list, socs: list) -> None:
    """The friction cone of the contact whose ``N`` is variable ``k`` (its ``F`` the next ``d``), as rows of the
    nonnegative cone (``-row·u ≥ 0`` form: ``row·u ≤ 0``) or one second-order cone."""
    if d == 1 or cone != "exact":
        if d == 1:
            normals = [np.array([1.0]), np.array([-1.0])]
            reach = mu_s
        else:
            facets = int(cone)
            if facets < 3:
                raise ValueError(f"a polyhedral cone needs at least 3 facets, got {cone!r}")
            angles = (2 * np.arange(facets) + 1) * np.pi / facets
            normals = [np.array([np.cos(a), np.sin(a)]) for a in angles]
            reach = mu_s * np.cos(np.pi / facets)
        for normal in normals:  # normal·F − reach·N ≤ 0
            row = np.zeros(n)
            row[k + 1 : k + 1 + d] = normal
            row[k] = -reach
            nonneg.append(row)
            nonneg_b.append(0.0)
        return
    rows = [np.zeros(n) for _ in range(d + 1)]  # z = (μ_s N, F) in the second-order cone: -A u = z
    rows[0][k] = -mu_s
    for j in range(d):
        rows[j + 1][k + 1 + j] = -1.0
    socs.append(rows)
