"""``gp.linearize``: the linear dynamics of a constrained model about a state, in independent coordinates.

The model's state ``y = (q, v, λ)`` moves by ``ẏ = F(t, y)`` — the step as a right-hand side
(:func:`gausspp.simulation.compiled.rhs_function`, the direct step) — on the manifold of its constraints,
``g(q, t) = 0`` for the holonomic rows and ``Φ(q, v, t) = 0`` for every row. About a state ``y₀`` on it, a
perturbation ``δy`` that stays on the manifold satisfies ``C δy = 0`` with ``C = [∂g/∂q 0 0; ∂Φ/∂q ∂Φ/∂v 0]``.
Choosing independent components ``z`` of ``δy`` (the others are then fixed by ``C``: ``δy = T z``), the linear
dynamics are

    ``ż = (∂F/∂y · T)[independent rows] z``,

with ``∂F/∂y`` casadi's exact derivative of the step — not finite differences. At an equilibrium this is the
linearization proper: its eigenvalues are the small motions' (``±iω`` for an oscillation, a positive real one for
an instability). About a steady motion the named coordinates should be those the motion's stability is about
(lean and steer, not a wheel's angle): components that are neither named nor fixed by ``C`` are held at zero.

``independent`` names the components: indices into ``y`` or the model's coordinate names (``"φ"``) and their
rates (``"φ′"``, for ``q̇ = v``); by default they are chosen by a column-pivoted QR of ``C`` (the best-conditioned
dependent set).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from scipy.linalg import qr

from ..errors import GaussppError, InputError, NonFiniteError
from ..model.model import Model
from ..workspace import workspace
from .compiled import rhs_function


@dataclass(frozen=True)
class Linearization:
    """The linear dynamics ``ż = A z`` of :func:`linearize`.

    Attributes
    ----------
    t, y : float, array
        The state linearized about (``y = (q, v, λ)``).
    names : tuple of str
        The independent components ``z`` (a coordinate ``q3``/its name, a velocity ``v3``/``name′``, ``λ1``).
    A : (d, d) array
        ``ż = A z``.
    basis : (nq + nv + nλ, d) array
        ``δy = basis @ z``: the whole state's perturbation on the manifold's tangent space.
    eigenvalues : (d,) complex array
    modes : (d, d) complex array
        The eigenvectors in ``z`` (columns).
    drift : float
        ``‖F(t, y)‖`` restricted to the named components: 0 at an equilibrium.
    jacobian : (nq + nv + nλ, nq + nv + nλ) array
        ``∂F/∂y`` of the whole state, before the restriction to the manifold.
    """

    t: float
    y: np.ndarray
    names: tuple[str, ...]
    A: np.ndarray
    basis: np.ndarray
    eigenvalues: np.ndarray
    modes: np.ndarray
    drift: float
    jacobian: np.ndarray


def linearize(
    model: Model, t: float, q: Any, v: Any, lam: Any = None, independent: Sequence[int | str] | None = None
) -> Linearization:
    """The linear dynamics of ``model`` about ``(t, q, v, λ)`` in independent components (module docstring)."""
    if model.contacts or model.bounded:
        raise InputError("linearize: a model with contacts or bounded actuators has no smooth right-hand side")
    t, q, v, lam = model.checked_state(t, q, v, lam)
    nq, nv, nl = model.nq, model.nv, model.n_lam
    y0 = np.concatenate([q, v, lam])
    _step_defined(model, t, q, v, lam)  # not realizable here, A not positive definite …: the step's own error
    jac_F, F0, C = (np.array(x, float) for x in _functions(model)(t, y0))
    if not (np.all(np.isfinite(jac_F)) and np.all(np.isfinite(F0)) and np.all(np.isfinite(C))):
        raise NonFiniteError(
            f"linearize: the step's derivative is NaN or inf at t={t:g} though the step itself answers there; "
            "linearize about a nearby state"
        )
    names = _component_names(model)
    rank = np.linalg.matrix_rank(C) if C.size else 0
    chosen = _choose(C, rank, nq + nv + nl) if independent is None else _indices(independent, names)
    dependent = [i for i in range(nq + nv + nl) if i not in chosen]
    basis = _basis(C, chosen, dependent, rank, names)
    A = (jac_F @ basis)[chosen]
    eigenvalues, modes = np.linalg.eig(A)
    order = np.lexsort((eigenvalues.imag, eigenvalues.real))
    return Linearization(
        t=t,
        y=y0,
        names=tuple(names[i] for i in chosen),
        A=A,
        basis=basis,
        eigenvalues=eigenvalues[order],
        modes=modes[:, order],
        drift=float(np.max(np.abs(F0[chosen]), initial=0.0)),
        jacobian=jac_F,
    )


def _step_defined(model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> None:
    """Raise the project error that says why the step (and so its derivative) is not defined at this state."""
    try:
        model.step(t, q, v, lam, solver="direct")
    except GaussppError as exc:
        exc.args = (f"linearize: the step has no derivative at t={t:g}: {exc}",)
        raise


def _functions(model: Model) -> ca.Function:
    """``(t, y) ↦ (∂F/∂y, F, C)`` for ``y = (q, v, λ)`` (kept in the model's workspace)."""

    def build() -> ca.Function:
        nq, nv, nl = model.nq, model.nv, model.n_lam
        F = rhs_function(model, "direct", None)
        t, y = ca.SX.sym("t"), ca.SX.sym("y", nq + nv + nl)
        ydot = F(t, ca.vertcat(y, 0, 0), ca.DM.zeros(2))[: nq + nv + nl]
        mech, p = model.mechanism, model.expressions
        g = p.g if p.g is not None else ca.SX.zeros(model.k)
        rows = model.holonomic_rows
        inputs = [mech.t, mech.q, mech.v, *model.inputs[3:4]]
        values = [t, y[:nq], y[nq : nq + nv], y[nq + nv :]]
        hol = ca.vertcat(*[g[i] for i in rows]) if rows else ca.SX(0, 1)
        constraint = ca.vertcat(ca.substitute(hol, ca.vertcat(*inputs), ca.vertcat(*values)),
                                ca.substitute(p.Phi, ca.vertcat(*inputs), ca.vertcat(*values)))  # fmt: skip
        return ca.Function("linearize", [t, y], [ca.jacobian(ydot, y), ydot, ca.jacobian(constraint, y)])

    return workspace(model).get(("linearize",), build)


def _component_names(model: Model) -> list[str]:
    """``q`` by the coordinates' names (without units), ``v`` by their rates where ``q̇ = v``, ``λ`` numbered."""
    mech = model.mechanism
    coords = [n.partition(" (")[0] for n in (mech.coordinate_names or ())] or [f"q{i + 1}" for i in range(model.nq)]
    speeds = [n.partition(" (")[0] for n in (mech.velocity_names or ())]
    if not speeds:
        speeds = [f"{c}′" for c in coords] if model.nq == model.nv else [f"v{i + 1}" for i in range(model.nv)]
    return [*coords, *speeds, *(f"λ{i + 1}" for i in range(model.n_lam))]


def _indices(independent: Sequence[int | str], names: list[str]) -> list[int]:
    out = []
    for item in independent:
        if isinstance(item, str):
            if item not in names:
                raise InputError(f"linearize: {item!r} is no component of the state; the components are {names}")
            out.append(names.index(item))
        elif isinstance(item, (int, np.integer)) and 0 <= item < len(names):
            out.append(int(item))
        else:
            raise InputError(
                f"linearize: independent components are indices 0 … {len(names) - 1} or names, got {item!r}"
            )
    if len(set(out)) != len(out):
        raise InputError(f"linearize: a component is named twice in {list(independent)}")
    return out


def _choose(C: np.ndarray, rank: int, n: int) -> list[int]:
    """The independent components: all but the ``rank`` columns a column-pivoted QR of ``C`` picks first."""
    if not rank:
        return list(range(n))
    _, _, pivots = qr(C, pivoting=True, mode="economic")
    return sorted(int(i) for i in pivots[rank:])


def _basis(C: np.ndarray, chosen: list[int], dependent: list[int], rank: int, names: list[str]) -> np.ndarray:
    """``T`` with ``δy = T z``: the named components are ``z``; ``rank`` of the others solve ``C δy = 0`` (the
    best-conditioned such set), the rest are held at zero."""
    n = C.shape[1] if C.size else len(names)
    T = np.zeros((n, len(chosen)))
    T[chosen, np.arange(len(chosen))] = 1.0
    if not rank:
        return T
    held = _choose(C[:, dependent], rank, len(dependent)) if len(dependent) > rank else []  # neither named nor fixed
    fixed = [dependent[i] for i in range(len(dependent)) if i not in held]
    Cd = C[:, fixed]
    if np.linalg.matrix_rank(Cd) < rank:
        raise InputError(
            f"linearize: the constraints do not fix the components {[names[i] for i in fixed]} from the named ones "
            f"{[names[i] for i in chosen]}: name others (the constraints' rank is {rank})"
        )
    T[fixed] = -np.linalg.lstsq(Cd, C[:, chosen], rcond=None)[0]
    return T
