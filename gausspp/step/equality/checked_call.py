"""The checked step's hot path: :meth:`gausspp.Model.step` in one buffer-bound call and one flag.

A :class:`CheckedCall` wraps a compiled step kernel (:mod:`gausspp.step.equality.kernel`) into one casadi
function of ``(t, q, v, λ)`` whose output is a single packed vector: the step's results and one
*all-clear flag*. The flag is 1 exactly when every check :func:`~gausspp.step.outcome.to_result`
makes would pass:

* the inputs are finite: ``|t + Σq + Σv + Σλ| < ∞`` (false for NaN, for ±inf, and — harmlessly — for
  a sum that overflows);
* ``A`` is positive definite (the factorization's relative pivot ``> 0``) and every output is finite
  (the kernel's checksum);
* the realizability margin ``σ_k ≥ margin_warn`` — computed in the graph for one or two rows
  (:func:`~gausspp.step.realizability.graph_cosines`), from the numbers by an SVD otherwise;
* for a QP, its relative primal and dual residuals ``≤`` :data:`~gausspp.step.outcome.QP_TOLERANCE`.

Any other case — a list instead of an array, a wrong shape, a flag of 0 — returns ``None``, and
:meth:`~gausspp.Model.step` takes the full step (:func:`gausspp.step.equality.checked.checked_step`), which
diagnoses, raises the project error or warns, and falls back to the general QP where it should. The
hot path thus costs a few numpy assignments, one C call and one small copy, and answers exactly what
the full step answers.
"""

from __future__ import annotations

import operator
from typing import Any

import casadi as ca
import numpy as np

from ..outcome import QP_TOLERANCE
from ..realizability import graph_cosines, margin_of, singular_values
from ..results import StepResult
from .expressions import OUTPUTS
from .kernel import Bound, CompiledKernel

#: The packed outputs, in order (each flattened column-major), then the flag.
PACKED = ("a", "u", "reaction", "compulsion", "residual", "Phi", "a_free", "qp_primal", "qp_dual")


def _packing(
    fn: ca.Function, k: int, m: int, margin_warn: float, qp: bool, S_sparsity: ca.Sparsity
) -> tuple[ca.Function, bool]:
    """The SX function ``(t, q, v, λ, *OUTPUTS) ↦ [packed outputs, cosines or S_norm's nonzeros, flag]`` for the
    step ``fn``'s outputs (``S_norm`` of the given sparsity), and whether the cosines are in it."""
    ins = [ca.SX.sym(name, fn.sparsity_in(i)) for i, name in enumerate(("t", "q", "v", "lam"))]
    out = {name: ca.SX.sym(name, fn.sparsity_out(i)) for i, name in enumerate(OUTPUTS)}
    out["S_norm"] = ca.SX.sym("S_norm", S_sparsity)
    S = ca.reshape(out["S_norm"], k, m) if k else out["S_norm"]
    cos = graph_cosines(S, k, m)
    checks = [out["pivot"] > 0, ca.fabs(out["checksum"]) < ca.inf]
    checks.append(ca.fabs(sum(ca.sum1(ca.vec(x)) for x in ins)) < ca.inf)
    if cos is not None:
        checks.append(cos[-1] >= margin_warn if k <= m else ca.SX(0))
    if qp:
        checks += [out["qp_primal"] <= QP_TOLERANCE, out["qp_dual"] <= QP_TOLERANCE]
    flag = checks[0]
    for c in checks[1:]:
        flag = ca.logic_and(flag, c)
    extra = cos if cos is not None else out["S_norm"].nz[:]  # its nonzeros, column-major, as S_sparsity
    packed = ca.densify(ca.vertcat(*(ca.vec(out[name]) for name in PACKED), extra, flag))
    return ca.Function("checked_packing", [*ins, *out.values()], [packed]), cos is not None


#: Where ``S_norm`` is among the step's outputs.
S_OUTPUT = OUTPUTS.index("S_norm")


def _packed_function(
    kernel: CompiledKernel, k: int, m: int, margin_warn: float
) -> tuple[ca.Function, bool, ca.Sparsity]:
    """``(t, q, v, λ) ↦ [packed outputs, cosines or S_norm's nonzeros, flag]``, whether the cosines are in it,
    and the sparsity of the ``S_norm`` packed: one SX function for the direct step, its ``S_norm`` by its
    nonzeros (a large banded ``S`` is a small part of its entries); for a QP, one MX graph level (the QP's
    parts, then the packing), its ``S_norm`` dense."""
    fn, parts = kernel.function, kernel.qp_parts
    names = ("t", "q", "v", "lam")
    if parts is None:
        sx = [ca.SX.sym(name, fn.sparsity_in(i)) for i, name in enumerate(names)]
        out = fn.call([*sx, ca.SX.zeros(fn.sparsity_in(4))])  # no stabilization: the exact step
        out[S_OUTPUT] = ca.sparsify(out[S_OUTPUT])  # the entries that are the constant zero, dropped
        packing, in_graph = _packing(fn, k, m, margin_warn, False, out[S_OUTPUT].sparsity())
        return ca.Function("checked_step", sx, packing.call([*sx, *out])), in_graph, out[S_OUTPUT].sparsity()
    packing, in_graph = _packing(fn, k, m, margin_warn, True, fn.sparsity_out(S_OUTPUT))
    mx = [ca.MX.sym(name, fn.sparsity_in(i)) for i, name in enumerate(names)]
    out_mx = parts.graph([*mx, ca.MX.zeros(fn.sparsity_in(4))])
    return ca.Function("checked_step", mx, packing.call([*mx, *out_mx])), in_graph, fn.sparsity_out(S_OUTPUT)


class CheckedCall:
    """The hot path of one model's checked step for one solver (see the module's docstring).

    Parameters
    ----------
    kernel : CompiledKernel
        The compiled step ``(t, q, v, λ, stab) -> OUTPUTS``.
    k, m : int
        Constraint rows and reaction unknowns.
    lam0 : (n_lam,) array or None
        ``λ`` when the caller gives none (``None``: the caller must give it).
    solver : str
        The solver's name in results (``"direct"`` or the QP backend's).
    margin_warn : float
        Below this margin the full step answers (it warns, or hands redundant rows to the general QP).
    """

    def __init__(
        self, kernel: CompiledKernel, k: int, m: int, lam0: np.ndarray | None, solver: str, margin_warn: float
    ) -> None:
        qp = kernel.qp_parts is not None
        fn, self._cosines_in_graph, S_sparsity = _packed_function(kernel, k, m, margin_warn)
        #: where the packed nonzeros of S_norm go in the (k, m) matrix
        self._S_places = tuple(np.asarray(x, int) for x in S_sparsity.get_triplet())
        self._bound = Bound(fn)
        self._t, self._q, self._v, self._lam = self._bound.args
        self._out = self._bound.res[0]
        self._lam0 = None if lam0 is None else np.asarray(lam0, float).copy()
        self.k, self.m, self.solver, self.qp, self.margin_warn = k, m, solver, qp, margin_warn
        sizes = [kernel.function.nnz_out(OUTPUTS.index(name)) for name in PACKED]
        starts = np.concatenate([[0], np.cumsum(sizes)]).tolist()
        at = dict(zip(PACKED, starts, strict=False))
        # the vectors' slices of the packed output, and the scalars' positions
        vectors = ("a", "u", "reaction", "residual", "Phi", "a_free")
        self._vectors = operator.itemgetter(*[slice(at[n], at[n] + sizes[PACKED.index(n)]) for n in vectors])
        self._compulsion, self._primal, self._dual = at["compulsion"], at["qp_primal"], at["qp_dual"]
        self._extra = slice(starts[-1], self._out.size - 1)
        self._shapes = (self._q.shape, self._v.shape, self._lam.shape)

    def __call__(self, t: Any, q: Any, v: Any, lam: Any) -> StepResult | None:
        """The step at ``(t, q, v, λ)``, or ``None`` when the full step must answer (module docstring)."""
        if not (type(q) is np.ndarray and type(v) is np.ndarray) or (q.shape, v.shape) != self._shapes[:2]:
            return None
        if q.dtype.kind != "f" or v.dtype.kind != "f":
            return None
        if lam is None:
            if self._lam0 is None:
                return None
            lam = self._lam0
        elif type(lam) is not np.ndarray or lam.shape != self._shapes[2] or lam.dtype.kind != "f":
            return None
        try:
            t = float(t)
        except (TypeError, ValueError):
            return None
        self._t[0] = t
        self._q[:] = q
        self._v[:] = v
        self._lam[:] = lam
        self._bound.eval()
        if self._out[-1] != 1.0:
            return None
        return self._result(t, self._out.copy())

    def _result(self, t: float, out: np.ndarray) -> StepResult | None:
        """The packed output ``out`` (the caller's copy) as a result; ``None`` if the margin is small (k > 2)."""
        k, m = self.k, self.m
        cos = out[self._extra]
        if self._cosines_in_graph:  # and the flag has checked the margin
            margin = out.item(-2)
        else:
            S = np.zeros((k, m))
            S[self._S_places] = cos
            cos = singular_values(S, k, m) if k and k <= m else np.zeros(min(k, m))
            margin = margin_of(cos, k, m)
            if not margin >= self.margin_warn:
                return None
        a, u, reaction, residual, Phi, a_free = self._vectors(out)
        return StepResult.of_checked(
            {
                "t": t,
                "a": a,
                "u": u,
                "reaction": reaction,
                "compulsion": out.item(self._compulsion),
                "margin": margin,
                "cosines": cos,
                "residual": residual,
                "constraint_value": Phi,
                "free_acceleration": a_free,
                "solver": self.solver,
                "qp_residuals": (out.item(self._primal), out.item(self._dual)) if self.qp else None,
            }
        )
