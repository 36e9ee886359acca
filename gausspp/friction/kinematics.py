"""The numbers a frictional step reads at a state, from one compiled casadi function.

For contacts ``i = 1..c`` with gaps ``g_i(q)`` and slips ``s_i = J_t,i(q) v``:

* ``ġ_i = J_n,i v`` with ``J_n,i = ∂g_i/∂q · ∂q̇/∂v``; ``g̈_i = J_n,i q̈ − φ_n,i`` with ``φ_n,i = −∂(J_n,i v)/∂q · q̇``;
* ``ṡ_i = J_t,i q̈ − φ_t,i`` with ``φ_t,i = −∂s_i/∂q · q̇``;

so that a closed contact keeps ``g̈ = 0`` by ``J_n q̈ = φ_n`` and a sticking one ``ṡ = 0`` by ``J_t q̈ = φ_t``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import InputError, NonFiniteError
from ..model.friction_contact import FrictionContact
from ..model.mechanism import Mechanism
from ..model.symbolic import evaluate
from ..step.bound import Bound, dense_outputs
from ..step.outcome import not_positive_definite


class Called:
    """A compiled function of numpy arrays called through its bound buffers (:class:`~gausspp.step.bound.Bound`):
    a plain casadi call from Python and its conversion of the result cost tens of microseconds, this about one.
    Returns a copy of the one dense output."""

    def __init__(self, fn: ca.Function) -> None:
        self.fn = fn
        self.bound = Bound(fn)

    def __call__(self, *args: np.ndarray) -> np.ndarray:
        bound = self.bound
        for target, value in zip(bound.args, args, strict=True):
            target[:] = value
        bound.eval()
        return bound.res[0].copy()


@dataclass(frozen=True)
class ContactState:
    """The mechanism and its contacts at ``(q, v)``: ``A, f`` and, per contact, ``g, ġ, J_n, φ_n`` (rows of
    arrays) and ``s (d,), J_t (d, nv), φ_t (d,)`` (lists: a contact's slip has ``d = 1`` or ``2`` components);
    ``energy`` (NaN where the mechanism does not know it)."""

    A: np.ndarray
    f: np.ndarray
    g: np.ndarray
    gdot: np.ndarray
    Jn: np.ndarray
    phin: np.ndarray
    s: list[np.ndarray]
    Jt: list[np.ndarray]
    phit: list[np.ndarray]
    energy: float


class ContactKinematics:
    """One compiled function ``(q, v) ↦`` :class:`ContactState` for a mechanism and its frictional contacts."""

    def __init__(self, mechanism: Mechanism, contacts: list[FrictionContact]) -> None:
        mech = mechanism
        q, v = mech.q, mech.v
        if ca.depends_on(ca.vertcat(ca.vec(ca.SX(mech.A)), ca.SX(mech.f)), mech.t):
            raise InputError("frictional contacts take a mechanism without explicit time (A and f of q and v)")
        gaps, slips = [], []
        for c in contacts:
            gaps.append(evaluate(lambda q_, c=c: c.gap(q_), (q,), (1, 1), f"gap of contact {c.name!r}"))
            slip = evaluate(lambda q_, v_, c=c: c.slip(q_, v_), (q, v), (None, 1), f"slip of contact {c.name!r}")
            if slip.numel() not in (1, 2):
                raise InputError(f"the slip of contact {c.name!r} has {slip.numel()} components; give 1 or 2")
            slips.append(slip)
        g, s = ca.vertcat(*gaps), ca.vertcat(*slips)
        qdot = mech.qdot
        gdot = ca.jtimes(g, q, qdot)  # directional derivatives (forward mode): a fraction of the full Jacobians' size
        Jn, Jt = ca.jacobian(gdot, v), ca.jacobian(s, v)
        if ca.depends_on(Jt, v) or ca.depends_on(Jn, v):
            raise InputError("a contact's slip must be linear in the velocities v")
        phin = -ca.jtimes(gdot, q, qdot)  # ġ = J_n v and s = J_t v: ∂(J v)/∂q · q̇ with v held
        phit = -ca.jtimes(s, q, qdot)
        energy = mech.energy if mech.energy is not None else ca.SX(np.nan)
        self.c, self.nq, self.nv = len(contacts), mech.q.numel(), mech.v.numel()
        self.dims = tuple(int(x.numel()) for x in slips)
        self.offsets = np.concatenate([[0], np.cumsum(self.dims)]).astype(int)
        parts = [mech.A, mech.f, g, gdot, Jn, phin, s, Jt, phit, energy]
        #: the same quantities as casadi expressions of ``(q, v)`` (for the compiled phases, :mod:`.phase_graph`)
        self.symbols = dict(zip(("A", "f", "g", "gdot", "Jn", "phin", "s", "Jt", "phit", "energy"), parts, strict=True))
        self.symbols.update(q=q, v=v, qdot=qdot)
        self.sizes = [(int(x.size1()), int(x.size2())) for x in map(ca.SX, parts)]
        # one flat output, called through bound buffers (Called): each casadi call from Python, and each output's
        # conversion, costs tens of microseconds
        self.fn = Called(_dense("contact_state", [q, v], ca.vertcat(*[ca.vec(ca.SX(x)) for x in parts])))
        #: ``(q, v) ↦ (vec A, f, q̇)``: the machine alone (a phase with every contact open asks nothing else)
        self.free = Called(_dense("free", [q, v], ca.vertcat(ca.vec(ca.SX(mech.A)), ca.SX(mech.f), qdot)))
        #: ``q ↦ g``: the gaps alone (a closing contact's event asks nothing else)
        self.gaps = Called(_dense("gaps", [q], g))
        #: ``(q, v) ↦ q̇``
        self.qdot = Called(_dense("qdot", [q, v], qdot))
        #: ``q ↦ Σ_j |∂g_i/∂q_j| |q_j|``: the size of the terms each gap adds up (its own scale, :meth:`gap_scales`)
        self._gap_terms = ca.Function("gap_terms", [q], [ca.mtimes(ca.fabs(ca.jacobian(g, q)), ca.fabs(q))])

    def compile_c(self) -> None:
        """Evaluate the state (and the gaps) as C where a compiler is (:mod:`gausspp.c_code`), once."""
        from ..c_code import c_function

        if not getattr(self, "_c", False):
            for name in ("fn", "gaps", "free", "qdot"):
                called = getattr(self, name)
                compiled = c_function(called.fn)
                if compiled is not None:
                    setattr(self, name, Called(compiled))
            self._c = True

    def gap_scales(self, q: np.ndarray) -> np.ndarray:
        """Each gap's own scale at ``q``: ``Σ_j |∂g_i/∂q_j| |q_j|``, the coordinates it depends on and no other."""
        return np.asarray(self._gap_terms(q), float).ravel()

    def __call__(self, q: np.ndarray, v: np.ndarray) -> ContactState:
        flat = self.fn(q, v)
        out, k = [], 0
        for rows, cols in self.sizes:  # casadi's vec is column-major
            out.append(flat[k : k + rows * cols].reshape((rows, cols), order="F"))
            k += rows * cols
        c, nv, o = self.c, self.nv, self.offsets
        s, Jt, phit = out[6].ravel(), out[7].reshape(-1, nv), out[8].ravel()
        return ContactState(
            A=out[0],
            f=out[1].ravel(),
            g=out[2].ravel(),
            gdot=out[3].ravel(),
            Jn=out[4].reshape(c, nv),
            phin=out[5].ravel(),
            s=[s[o[i] : o[i + 1]] for i in range(c)],
            Jt=[Jt[o[i] : o[i + 1]] for i in range(c)],
            phit=[phit[o[i] : o[i + 1]] for i in range(c)],
            energy=float(out[9][0, 0]),
        )

    def checked(self, q: np.ndarray, v: np.ndarray, t: float, names: list[str]) -> ContactState:
        """The state at ``(q, v)``, refused with a project error where it cannot be stepped: a quantity that is not
        finite (naming the contact ``names[i]`` and the time) or a mass matrix not symmetric positive definite."""
        st = self(q, v)
        for what, value in (("the mass matrix A", st.A), ("the forces f", st.f)):
            if not np.all(np.isfinite(value)):
                raise NonFiniteError(f"{what} is not finite at t={t:.6g}; check the mechanism's formulas there")
        if np.isfinite(self.fn.bound.res[0]).all():  # the usual case: the call's whole output, checked at once
            names = []
        for i, name in enumerate(names):
            parts = (st.g[i], st.gdot[i], st.Jn[i], st.phin[i], st.s[i], st.Jt[i], st.phit[i])
            if not all(np.all(np.isfinite(x)) for x in parts):
                raise NonFiniteError(
                    f"contact {name!r}: its gap or slip (or their derivatives) is not finite at t={t:.6g}; check "
                    "its formulas there"
                )
        try:
            np.linalg.cholesky(st.A)
        except np.linalg.LinAlgError:
            raise not_positive_definite(st, t) from None
        if np.abs(st.A - st.A.T).max() > 1e-12 * np.abs(st.A).max():
            raise not_positive_definite(st, t)
        return st


def _dense(name: str, inputs: list[ca.SX], output: ca.SX) -> ca.Function:
    """A function with one output, every entry stored (the bound buffer is read as the dense vector)."""
    return ca.Function(name, inputs, dense_outputs([ca.vec(ca.SX(output))]))
