"""From declarations to the step's structure: stacking the constraints and their realizations.

:func:`assemble` turns a mechanism and its bilateral constraints into docs/theory.md §2's step
``A q̈ = F − h + r₀ + D u``, ``J q̈ = φ − αΦ − βg`` (the rows of ``J`` stacked, the columns of
``D`` side by side, one :class:`~gausspp.step.outcome.Group` per constraint); :func:`assemble_contacts`
stacks the unilateral contacts' gaps. Both return frozen records the :class:`~gausspp.Model` keeps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import ShapeError
from ..step.equality.expressions import StepExpressions
from ..step.protocol import ContactExpressions, Group
from .constraint_expressions import ConstraintExpressions
from .constraints import Constraint, Unilateral
from .mechanism import Mechanism


@dataclass(frozen=True)
class Assembly:
    """The bilateral constraints stacked: the step's expressions and the bookkeeping of rows and columns."""

    expressions: StepExpressions
    inputs: list[ca.SX]  # (t, q, v, λ, stab)
    k: int  # constraint rows
    m: int  # reaction unknowns
    n_lam: int
    row_names: list[str]
    lam_columns: list[int]  # the columns of u that are λ̇
    groups: tuple[Group, ...]
    group_bounds: tuple[tuple[np.ndarray, np.ndarray] | None, ...]
    holonomic_rows: list[int]
    lam0: np.ndarray | None


@dataclass(frozen=True)
class ContactAssembly:
    """The unilateral contacts stacked."""

    expressions: ContactExpressions
    rows: list[int]  # rows per contact
    row_names: list[str]
    restitution: np.ndarray  # per row


def _lam0_of(lam0: np.ndarray | None, k: int, name: str) -> np.ndarray | None:
    if lam0 is not None and lam0.shape != (k,):
        raise ShapeError(f"constraint {name!r}: lam0 has {lam0.size} entries, expected {k}")
    return lam0


def _row_names(name: str, k: int) -> list[str]:
    return [name] if k == 1 else [f"{name}[{i}]" for i in range(k)]


def assemble(mech: Mechanism, constraints: Sequence[Constraint], names: Sequence[str]) -> Assembly:
    """Stack the bilateral constraints of ``mech`` with their realizations' reactions."""
    exprs = [c.expressions(mech) for c in constraints]
    sizes = [int(e.Phi.numel()) for e in exprs]
    n_lam = sum(k for k, c in zip(sizes, constraints, strict=True) if c.realization.has_state)
    lam, stab = ca.SX.sym("lam", n_lam), ca.SX.sym("stab", 2)
    Ds, r0, groups, bounds, lam0_parts, row_names, lam_cols = [], ca.SX.zeros(mech.nv), [], [], [], [], []
    row = col = lam_at = 0
    for c, e, k, name in zip(constraints, exprs, sizes, names, strict=True):
        real = c.realization
        lam_c = lam[lam_at : lam_at + k] if real.has_state else ca.SX(0, 1)
        if real.has_state:
            lam_at += k
            lam0_parts.append(_lam0_of(real.lam0, k, name))
            lam_cols += list(range(col, col + k))  # u = λ̇ for these
        D, r0_c, group = _reaction_block(mech, c, e, lam_c, name, slice(row, row + k), col)
        Ds.append(D)
        bounds.append(real.bounds_for(D.size2()))
        r0 = r0 + r0_c
        groups.append(group)
        row_names += _row_names(name, k)
        row, col = row + k, col + D.size2()
    known = [p for p in lam0_parts if p is not None]
    starts = np.cumsum([0, *sizes])
    return Assembly(
        expressions=_stacked(mech, exprs, sizes, r0, Ds, stab),
        inputs=[mech.t, mech.q, mech.v, lam, stab],
        k=row,
        m=col,
        n_lam=n_lam,
        row_names=row_names,
        lam_columns=lam_cols,
        groups=tuple(groups),
        group_bounds=tuple(bounds),
        holonomic_rows=[
            i for e, k, at in zip(exprs, sizes, starts, strict=False) if e.g is not None for i in range(at, at + k)
        ],
        lam0=None if len(known) < len(lam0_parts) else np.concatenate([np.zeros(0), *known]),
    )


def _reaction_block(
    mech: Mechanism, c: Constraint, e: ConstraintExpressions, lam_c: ca.SX, name: str, rows: slice, col: int
) -> tuple[ca.SX, ca.SX, Group]:
    """One constraint's reaction ``r₀ + D u`` from its realization and its :class:`Group` (columns from ``col``)."""
    real = c.realization
    reaction = real.reaction(mech, e, lam_c)
    if reaction.D.size1() != mech.nv:
        raise ShapeError(
            f"constraint {name!r}: reaction directions D have shape {reaction.D.shape}, expected ({mech.nv}, m)"
        )
    group = Group(name, rows, slice(col, col + reaction.D.size2()), real.hint, real.label)
    return reaction.D, reaction.r0, group


def _stacked(
    mech: Mechanism, exprs: list[ConstraintExpressions], sizes: list[int], r0: ca.SX, Ds: list[ca.SX], stab: ca.SX
) -> StepExpressions:
    """The step's expressions: the rows of ``J``, ``φ``, ``Φ``, ``g`` stacked, the columns of ``D`` side by side.

    Baumgarte terms (docs/theory.md §5): ``J q̈ = φ − α Φ − β g``, with ``(α, β) = stab`` an input (zero: the
    exact step).
    """
    Phi = ca.vertcat(ca.SX(0, 1), *[e.Phi for e in exprs])
    g = ca.vertcat(
        ca.SX(0, 1), *[e.g if e.g is not None else ca.SX.zeros(k) for e, k in zip(exprs, sizes, strict=True)]
    )
    return StepExpressions(
        A=mech.A,
        f=mech.f,
        r0=r0,
        J=ca.vertcat(ca.SX(0, mech.nv), *[e.J for e in exprs]),
        phi=ca.vertcat(ca.SX(0, 1), *[e.phi for e in exprs]) - stab[0] * Phi - stab[1] * g,
        D=ca.horzcat(ca.SX(mech.nv, 0), *Ds),
        Phi=Phi,
        v=mech.v,
        qdot=mech.qdot,
        energy=mech.energy,
        F_nc=mech.F_nc,
        g=g,
    )


def assemble_contacts(mech: Mechanism, contacts: Sequence[Unilateral], names: Sequence[str]) -> ContactAssembly:
    """Stack the unilateral contacts' gaps ``g_c ≥ 0`` with their Jacobians and right-hand sides."""
    exprs = [c.expressions(mech) for c in contacts]
    rows = [int(e.Phi.numel()) for e in exprs]
    return ContactAssembly(
        expressions=ContactExpressions(
            g=ca.vertcat(ca.SX(0, 1), *[e.g for e in exprs if e.g is not None]),
            J=ca.vertcat(ca.SX(0, mech.nv), *[e.J for e in exprs]),
            phi=ca.vertcat(ca.SX(0, 1), *[e.phi for e in exprs]),
            gdot=ca.vertcat(ca.SX(0, 1), *[e.Phi for e in exprs]),
        ),
        rows=rows,
        row_names=[r for name, k in zip(names, rows, strict=True) for r in _row_names(name, k)],
        restitution=np.repeat([c.restitution for c in contacts], rows) if contacts else np.zeros(0),
    )
