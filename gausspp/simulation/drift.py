"""Drift control (docs/theory.md §5): Baumgarte terms and projection onto the constraint.

The step keeps only the differentiated constraint ``J q̈ = φ``, so ``Φ`` (and ``g``) drift
by the integration error. Two remedies, off by default so that exact comparisons see the
raw method:

* :class:`Baumgarte` — ``J q̈ = φ − α Φ − β g``: the drift obeys ``Φ̇ = −αΦ − βg`` and decays;
  it changes the right-hand side off the constraint only.
* projection (``"project"``) — after each step, ``q`` (holonomic rows, a few Newton steps) and
  then ``v`` are moved back onto the constraint *along the realization's directions* ``A⁻¹D``,
  so the correction is one the realization could have made:
  ``v ← v − A⁻¹D (J A⁻¹D)⁻¹ Φ``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import casadi as ca

from ..errors import InputError
from ..validation import number

if TYPE_CHECKING:
    from ..model.model import Model


@dataclass(frozen=True)
class Baumgarte:
    """Baumgarte stabilization ``J q̈ = φ − α Φ − β g``.

    ``Baumgarte.critical(tau)`` gives critically damped decay with time constant ``tau``
    (``α = 2/τ``, ``β = 1/τ²``).
    """

    alpha: float
    beta: float = 0.0

    def __post_init__(self) -> None:
        for name in ("alpha", "beta"):
            value = getattr(self, name)
            object.__setattr__(
                self, name, number(f"Baumgarte: {name} must be a finite number ≥ 0, got {value!r}", value)
            )
        if not (self.alpha >= 0 and self.beta >= 0):
            raise InputError(f"Baumgarte: alpha and beta must be ≥ 0, got {self.alpha}, {self.beta}")

    @classmethod
    def critical(cls, tau: float) -> Baumgarte:
        """Critically damped drift with time constant ``tau``."""
        tau = number(f"Baumgarte.critical: tau must be a positive number, got {tau!r}", tau)
        if not tau > 0:
            raise InputError(f"Baumgarte.critical: tau must be positive, got {tau}")
        return cls(alpha=2.0 / tau, beta=1.0 / tau**2)


@dataclass(frozen=True)
class Stabilization:
    """What a simulation does about drift: Baumgarte terms and/or projection."""

    baumgarte: Baumgarte | None = None
    project: bool = False
    #: project only where the state's relative drift (:func:`gausspp.step.general.drift.relative_drift`) exceeds
    #: this (0: after every step, as ``stabilize="project"`` asks); ``gp.simulate``'s default drift control
    project_above: float = 0.0

    @property
    def stab(self) -> tuple[float, float]:
        b = self.baumgarte
        return (b.alpha, b.beta) if b else (0.0, 0.0)


def as_stabilization(value: object, dt: float | None) -> Stabilization:
    """Accept ``None``, ``"baumgarte"``, ``"project"``, a :class:`Baumgarte`, or a list of these."""
    if value is None or value is False:
        return Stabilization()
    if isinstance(value, Stabilization):
        return value
    items = value if isinstance(value, (list, tuple)) else [value]
    baumgarte, project = None, False
    for item in items:
        if item == "project":
            project = True
        elif item == "baumgarte":
            baumgarte = Baumgarte.critical(20.0 * dt if dt else 0.05)
        elif isinstance(item, Baumgarte):
            baumgarte = item
        else:
            raise InputError(
                f"stabilize={value!r} is not understood; use None, 'baumgarte', 'project', "
                "gp.Baumgarte(alpha, beta) or a list of these"
            )
    return Stabilization(baumgarte, project)


def projection_function(model: Model, newton_steps: int = 3) -> ca.Function:
    """Compile ``(t, q, v, lam) -> (q', v')`` onto ``g = 0`` and ``Φ = 0`` along ``A⁻¹D``."""
    mech, p = model.mechanism, model.expressions
    t, q, v, lam = mech.t, mech.q, mech.v, model.lam
    zero = ca.SX.zeros(2)
    assert p.g is not None  # a model's step always carries its holonomic residuals
    pieces = ca.Function("pieces", [t, q, v, lam, model.stab], [p.A, p.J, p.D, p.Phi, p.g, mech.qdot])
    K = ca.Function("K", [q, v, t], [ca.jacobian(mech.qdot, v)])  # q̇ = K v for the affine kinematics used here
    rows = model.holonomic_rows
    cols = [c for grp in model.groups if grp.rows.start in rows for c in range(grp.cols.start, grp.cols.stop)]
    q_new = q
    if rows:
        for _ in range(newton_steps):
            A, J, D, _, g, _ = pieces(t, q_new, v, lam, zero)
            Jh, Dh = J[rows, :], D[:, cols]
            AinvD = ca.solve(A, Dh)
            dq = K(q_new, v, t) @ (AinvD @ ca.solve(Jh @ AinvD, g[rows]))
            q_new = mech.normalize(q_new - dq)
    A, J, D, Phi, _, _ = pieces(t, q_new, v, lam, zero)
    AinvD = ca.solve(A, D)
    v_new = v - AinvD @ ca.solve(J @ AinvD, Phi)
    return ca.Function("project", [t, q, v, lam], [q_new, v_new])
