"""How far a state is off the constraints, relative — as a symbolic expression of the model's inputs.

The compiled general steps (:mod:`.compiled`, :mod:`.sparse_pattern`) damp their equality step near a singular
position in proportion to it; :func:`.manifold.off_manifold` measures the same at a numeric state.
"""

from __future__ import annotations

import casadi as ca

from ..protocol import StepModel

#: Off the manifold by a relative drift δ (an integrator's stage), the redundancy decision's tests of the compiled
#: steps — a dropped row's sine, its right-hand side's agreement, its residuals' fit — hold to ``DRIFT_SLACK·δ``
#: beyond their tolerances (:mod:`.compiled`, :mod:`.sparse_pattern`).
DRIFT_SLACK = 100.0
#: ... and never by more than this: a state far off the manifold goes to the Python step, which decides on it.
SLACK_CAP = 1e-4
#: The cap of the adaptive stages of a run (:mod:`gausspp.simulation.general_stages`): the stages of a step taken at a
#: loose tolerance lie that far off by design (a stage's state is a low-order extrapolation). At :data:`SLACK_CAP`
#: every stage of Bricard's mechanism at rtol 1e-4 went to the Python step (315 ms for 10 s where this takes 38 ms,
#: the same motion to three digits); ``model.step`` keeps :data:`SLACK_CAP`.
STAGE_SLACK_CAP = 1e-2


def relative_drift(model: StepModel) -> ca.SX:
    """How far the state is off the constraints, relative: ``max |Φᵢ|/‖Jᵢ‖/(1 + vᵢ)`` and, on holonomic rows,
    ``|gᵢ|/‖Gᵢ‖/(1 + qᵢ)``, with ``vᵢ``, ``qᵢ`` the size of the components row ``i`` depends on (``Σ_j |J_ij||v_j| /
    Σ_j |J_ij|``, the same with ``G = ∂g/∂q``) — never the largest coordinate of the whole state (as
    :func:`.manifold.off_manifold`)."""
    p, mech = model.expressions, model.mechanism
    if not model.k:
        return ca.SX(0)
    J, Phi = p.J, p.Phi
    nrm = ca.sqrt(ca.sum2(J * J))
    nrm = ca.if_else(nrm == 0, 1, nrm)
    off = ca.mmax(ca.fabs(Phi) / nrm / (1 + row_size(J, mech.v)))
    hol = model.holonomic_rows
    if hol and p.g is not None:
        G = ca.jacobian(p.g[hol], mech.q)
        g_nrm = ca.sqrt(ca.sum2(G * G))
        g_nrm = ca.if_else(g_nrm == 0, 1, g_nrm)
        off = ca.fmax(off, ca.mmax(ca.fabs(p.g[hol]) / g_nrm / (1 + row_size(G, mech.q))))
    return off


def row_size(J: ca.SX, x: ca.SX) -> ca.SX:
    """The size of the components each row of ``J`` depends on: ``Σ_j |J_ij||x_j| / Σ_j |J_ij|`` (0 for a zero row)."""
    weight = ca.sum2(ca.fabs(J))
    return ca.mtimes(ca.fabs(J), ca.fabs(x)) / ca.if_else(weight == 0, 1, weight)
