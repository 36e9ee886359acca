"""How far a state is off the constraints, relative — as a symbolic expression of the model's inputs.

The compiled general steps (:mod:`.compiled`, :mod:`.sparse_pattern`) damp their equality step near a singular
position in proportion to it; :func:`.manifold.off_manifold` measures the same at a numeric state.
"""

from __future__ import annotations

import casadi as ca

from ..protocol import StepModel


def relative_drift(model: StepModel) -> ca.SX:
    """How far the state is off the constraints, relative: ``max |Φᵢ|/‖Jᵢ‖/(1 + max|v|)`` and, on holonomic rows,
    ``|gᵢ|/‖Jᵢ‖/(1 + max|q|)`` (as :func:`.manifold.off_manifold`)."""
    p, mech = model.expressions, model.mechanism
    if not model.k:
        return ca.SX(0)
    J, Phi = p.J, p.Phi
    nrm = ca.sqrt(ca.sum2(J * J))
    nrm = ca.if_else(nrm == 0, 1, nrm)
    off = ca.mmax(ca.fabs(Phi) / nrm) / (1 + ca.mmax(ca.fabs(mech.v)))
    hol = model.holonomic_rows
    if hol and p.g is not None:
        off = ca.fmax(off, ca.mmax(ca.fabs(p.g[hol]) / nrm[hol]) / (1 + ca.mmax(ca.fabs(mech.q))))
    return off
