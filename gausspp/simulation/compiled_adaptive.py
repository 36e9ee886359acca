"""The adaptive default compiled: every stage of an embedded Runge–Kutta step in one casadi call.

scipy's ``DOP853`` (and ``RK45``) call the right-hand side once per stage from Python — twelve calls of the
compiled step per DOP853 step, each with its buffers, its checks and, for the realizability margin, an SVD in
numpy. Here the whole step is one flat SX function of ``(t, y, f, h, stab)``: every stage's step (the direct
formula), the new state, its derivative ``f_new`` (the first stage of the next step), the stages ``K`` the
dense output needs, and the checks of every stage — ``A`` positive definite, everything finite, the margin
certainly above ``margin_error`` (:func:`~gausspp.step.realizability.margin_bound`: ``b ≤ σ_min``) — as one
flag. The step-size control, the error norm and the dense output stay scipy's own: :class:`CompiledRungeKutta`
is scipy's solver with only the stages computed elsewhere, so a run takes the same steps as scipy's to
round-off.

A step whose flag is down (a stage failed, or the margin's bound cannot vouch for it) is taken again by scipy's
own stages through the Python right-hand side, which raises the project error that explains the failure or, when
the bound was merely too coarse, passes. After each step the exact margin at the new state (the last stage's, in
closed form for up to two rows) is left with the right-hand side, as its own evaluation would leave it, for the
singular-position watch (:mod:`gausspp.simulation.crossing`).

Where it applies (:func:`applies`): scipy's ``DOP853`` and ``RK45`` with the direct step on a compiled kernel,
up to :data:`~gausspp.step.realizability.MARGIN_BOUND_ROWS` rows.
"""

from __future__ import annotations

import functools
from typing import Any

import casadi as ca
import numpy as np
import scipy.integrate as si
from scipy.integrate._ivp import rk as scipy_rk

from ..disk_cache import cached_function
from ..model.model import Model
from ..step import realizability
from ..step.bound import Bound
from ..step.equality.expressions import OUTPUTS
from ..step.equality.kernel import CompiledKernel
from ..step.outcome import QP_TOLERANCE
from ..workspace import workspace
from .rhs import RightHandSide

#: The embedded methods of scipy this lane compiles.
METHODS = ("DOP853", "RK45")


def applies(method: str, rhs: Any) -> bool:
    """Whether a scipy-lane run of ``method`` with ``rhs`` takes the compiled stages (module docstring)."""
    return (
        method in METHODS
        and isinstance(rhs, RightHandSide)
        and isinstance(rhs.kernel, CompiledKernel)
        and rhs.model.k <= realizability.MARGIN_BOUND_ROWS
    )


def solver_class(method: str, rhs: Any) -> Any:
    """The ``OdeSolver`` class a scipy-lane run of ``method`` with ``rhs`` takes: scipy's with compiled stages where
    :func:`applies`, else scipy's own — each able to :meth:`~Retargetable.retarget`."""
    if applies(method, rhs):
        return {"DOP853": CompiledDOP853, "RK45": CompiledRK45}[method]
    return _retargetable(getattr(si, method))


class Retargetable:
    """Mixed into a scipy ``OdeSolver``: :meth:`retarget`."""

    t: float
    t_bound: float
    direction: float
    status: str

    def retarget(self, t_bound: float) -> None:
        """Go on to ``t_bound`` from where the solver stands, with its step size, its last derivative and (implicit
        methods) its Jacobian and history: where the motion is smooth a fresh solver would only guess a first
        step again (two more evaluations and a few short steps per approach of a singular position)."""
        self.t_bound = t_bound
        self.status = "running" if self.direction * (t_bound - self.t) > 0 else "finished"

    def moved_to(self, y: Any) -> None:
        """Go on from the state ``y`` at the same time (a projection onto the constraints after an accepted step),
        with the derivative there: the first stage of the next step (explicit Runge–Kutta's first-same-as-last,
        Radau's)."""
        self.y = y
        if hasattr(self, "f"):
            self.f = self.fun(self.t, y)


@functools.cache
def _retargetable(cls: type) -> type:
    return type(cls.__name__, (Retargetable, cls), {"__doc__": f"scipy's {cls.__name__}, :class:`Retargetable`."})


def stages_function(model: Model, method: str, kernel: CompiledKernel, solver: str) -> ca.Function:
    """``(t, y, f, h, stab, rtol, atol) ↦ (y_new, f_new, K, ok, margin at the new state, error norm)`` of one step
    of scipy's ``method``
    (its tableau ``A, B, C``; ``K``: the ``n_stages + 1`` stages as rows, the last ``f_new``) by the step ``kernel``
    (of step solver ``solver``); built once per model, method and solver, kept in the model's workspace and on
    disk."""
    key = ("adaptive-stages", method, solver)
    return workspace(model).get(key, lambda: cached_function(model, key, lambda: _build(model, method, kernel)))


def _build(model: Model, method: str, kernel: CompiledKernel) -> ca.Function:
    return build_stages(model, method, _stage_function(model, kernel))


def build_stages(model: Model, method: str, stage: ca.Function) -> ca.Function:
    """``(t, y, f, h, stab, rtol, atol) ↦ (y_new, f_new, K, ok, margin, error norm)`` of one step of scipy's
    ``method`` by ``stage`` (``(t, y, stab) ↦ (y', all-clear, margin)``)."""
    cls = getattr(si, method)
    A, B, C, n_stages = np.asarray(cls.A), np.asarray(cls.B), np.asarray(cls.C), int(cls.n_stages)
    n = model.nq + model.nv + model.n_lam + 2
    t, h, y, f, stab = ca.MX.sym("t"), ca.MX.sym("h"), ca.MX.sym("y", n), ca.MX.sym("f", n), ca.MX.sym("stab", 2)
    stages, oks = [f], []
    for s in range(1, n_stages):
        ys = y + h * sum((float(A[s, j]) * stages[j] for j in range(s) if A[s, j]), ca.MX.zeros(n))
        ks, ok_s, _margin = stage(t + float(C[s]) * h, ys, stab)
        stages.append(ks)
        oks.append(ok_s)
    y_new = y + h * sum((float(B[j]) * stages[j] for j in range(n_stages) if B[j]), ca.MX.zeros(n))
    f_new, ok_end, margin = stage(t + h, y_new, stab)
    ok = ca.mmin(ca.vertcat(*oks, ok_end, ca.fabs(ca.sum1(y_new)) < ca.inf))
    K = ca.horzcat(*stages, f_new).T
    rtol, atol = ca.MX.sym("rtol"), ca.MX.sym("atol", n)
    scale = atol + ca.fmax(ca.fabs(y), ca.fabs(y_new)) * rtol
    error = _error_norm(cls, K, h, scale, n)
    return ca.Function("adaptive_stages", [t, y, f, h, stab, rtol, atol], [y_new, f_new, K, ok, margin, error])


def _error_norm(cls: Any, K: ca.MX, h: ca.MX, scale: ca.MX, n: int) -> ca.MX:
    """scipy's ``_estimate_error_norm`` of ``cls`` (``RK45``: the RMS of ``h Kᵀ E / scale``; ``DOP853``: its fifth-
    and third-order estimates combined), in the graph."""
    if cls is si.DOP853:
        e5 = ca.sumsqr(ca.mtimes(K.T, ca.DM(cls.E5)) / scale)
        e3 = ca.sumsqr(ca.mtimes(K.T, ca.DM(cls.E3)) / scale)
        both = e5 + 0.01 * e3
        return ca.if_else(both > 0, ca.fabs(h) * e5 / ca.sqrt(both * n), 0)
    return ca.norm_2(ca.mtimes(K.T, ca.DM(cls.E)) * h / scale) / np.sqrt(n)


def _stage_function(model: Model, kernel: CompiledKernel) -> ca.Function:
    """``(t, y, stab) ↦ (y', all-clear, margin)``: the derivative of the state at one stage by the run's own step
    kernel, whether that step passed (``A`` positive definite, finite, the QP solved, the margin's bound at least
    ``margin_error``), and the margin itself in closed form for up to two rows (NaN beyond). One flat SX function
    for the direct step; an MX graph around the QP's conic node otherwise, inlined where it is called (a nested MX
    call costs a sizeable fraction of a QP stage)."""
    nq, nv, nl, k, m = model.nq, model.nv, model.n_lam, model.k, model.m
    t, y, stab = ca.MX.sym("t"), ca.MX.sym("y", nq + nv + nl + 2), ca.MX.sym("stab", 2)
    args = [t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], stab]
    out = dict(zip(OUTPUTS, kernel.function.call(args, True, False), strict=True))  # inlined: one flat graph
    lam_cols = list(model.lam_columns)
    lam_dot = ca.vertcat(*[out["u"][i] for i in lam_cols]) if lam_cols else ca.MX(0, 1)
    bound, margin = _margins(k, m)(out["S_norm"])
    ok = ca.logic_and(out["pivot"] > 0, ca.fabs(out["checksum"]) < ca.inf)
    ok = ca.logic_and(ok, out["qp_primal"] <= QP_TOLERANCE)
    ok = ca.logic_and(ok, bound >= model.margin_error)
    derivative = ca.vertcat(out["qdot"], out["a"], lam_dot, out["power_reaction"], out["power_forces"])
    fn = ca.Function("stage", [t, y, stab], [ca.densify(derivative), ok, margin])
    if not kernel.function.is_a("SXFunction"):  # each stage's nodes inlined into the step's graph: faster
        return ca.Function("stage", [t, y, stab], [ca.densify(derivative), ok, margin], {"always_inline": True})
    flat = fn.expand()
    return ca.Function("stage", flat.sx_in(), ca.cse(flat.call(flat.sx_in())))


def _margins(k: int, m: int) -> ca.Function:
    """``S_norm ↦ (b, σ_k)``: the bound ``b ≤ σ_min`` of :func:`~gausspp.step.realizability.margin_bound` and, for up
    to two rows, the margin in closed form (:func:`~gausspp.step.realizability.graph_cosines`; NaN beyond)."""
    S = ca.SX.sym("S", k, m)
    cos = realizability.graph_cosines(S, k, m)
    if k == 0:
        margin = ca.SX(1.0)
    elif k > m:
        margin = ca.SX(0.0)
    else:
        margin = ca.SX(np.nan) if cos is None else cos[-1]
    return ca.Function("margins", [S], [realizability.margin_bound(S, k, m), margin])


class CompiledRungeKutta(Retargetable):
    """Mixed into scipy's ``DOP853``/``RK45``: :meth:`_step_impl` is scipy's own (``RungeKutta._step_impl``, the
    same step-size control line by line), with the stages and the error norm (scipy's formula) from one compiled
    call (module docstring)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    K: np.ndarray
    n_stages: int

    def setup(self, rhs: RightHandSide, method: str) -> None:
        self.rhs = rhs
        fn = stages_function(rhs.model, method, rhs.kernel, rhs.solver)
        # its buffers are kept beside the function, as a kernel's are (one run at a time steps a model)
        self._bound = workspace(rhs.model).get(("adaptive-stages bound", method, rhs.solver), lambda: Bound(fn))
        self._stab = np.array(rhs.stab, float)
        s: Any = self
        self._bound.args[5][0] = s.rtol
        self._bound.args[6][:] = np.broadcast_to(s.atol, self._bound.args[6].shape)

    def stages(self, t: float, y: np.ndarray, f: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, float]:
        """``rk_step`` of scipy and the error norm: ``(y_new, f_new, error norm)``, the stages in ``self.K`` —
        compiled, or from Python when the compiled step's flag is down."""
        args = self._bound.args
        args[0][0], args[1][:], args[2][:], args[3][0], args[4][:] = t, y, f, h, self._stab
        self._bound.eval()
        res = self._bound.res
        if res[3][0] > 0:
            self.rhs.evaluations += self.n_stages
            self.K[:] = self._bound.output(2)
            y_new, f_new = res[0].copy(), res[1].copy()
            self.rhs.last_margin = (t + h, y_new, float(res[4][0])) if np.isfinite(res[4][0]) else None
            return y_new, f_new, float(res[5][0])
        return self.scipy_stages(t, y, f, h)

    def scipy_stages(self, t: float, y: np.ndarray, f: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, float]:
        """scipy's own ``rk_step`` through the Python right-hand side (which names a failure), and its error norm."""
        s: Any = self
        y_new, f_new = scipy_rk.rk_step(s.fun, t, y, f, h, s.A, s.B, s.C, s.K)
        scale = s.atol + np.maximum(np.abs(y), np.abs(y_new)) * s.rtol
        return y_new, f_new, s._estimate_error_norm(s.K, h, scale)

    def _step_impl(self) -> tuple[bool, str | None]:  # scipy's RungeKutta._step_impl, with rk_step → self.stages
        s: Any = self
        t, y = s.t, s.y
        max_step = s.max_step
        min_step = 10 * np.abs(np.nextafter(t, s.direction * np.inf) - t)
        h_abs = max_step if s.h_abs > max_step else (min_step if s.h_abs < min_step else s.h_abs)
        step_accepted = step_rejected = False
        while not step_accepted:
            if h_abs < min_step:
                return False, s.TOO_SMALL_STEP
            h = h_abs * s.direction
            t_new = t + h
            if s.direction * (t_new - s.t_bound) > 0:
                t_new = s.t_bound
            h = t_new - t
            h_abs = np.abs(h)
            y_new, f_new, error_norm = self.stages(t, y, s.f, h)
            if error_norm < 1:
                factor = (
                    scipy_rk.MAX_FACTOR
                    if error_norm == 0
                    else min(scipy_rk.MAX_FACTOR, scipy_rk.SAFETY * error_norm**s.error_exponent)
                )
                if step_rejected:
                    factor = min(1, factor)
                h_abs *= factor
                step_accepted = True
            else:
                h_abs *= max(scipy_rk.MIN_FACTOR, scipy_rk.SAFETY * error_norm**s.error_exponent)
                step_rejected = True
        s.h_previous, s.y_old = h, y
        s.t, s.y, s.h_abs, s.f = t_new, y_new, h_abs, f_new
        return True, None


class CompiledDOP853(CompiledRungeKutta, si.DOP853):
    """scipy's DOP853 with compiled stages."""

    def __init__(self, rhs: RightHandSide, t0: float, y0: np.ndarray, t_bound: float, **options: Any) -> None:
        si.DOP853.__init__(self, rhs, t0, y0, t_bound, **options)
        self.setup(rhs, "DOP853")


class CompiledRK45(CompiledRungeKutta, si.RK45):
    """scipy's RK45 with compiled stages."""

    def __init__(self, rhs: RightHandSide, t0: float, y0: np.ndarray, t_bound: float, **options: Any) -> None:
        si.RK45.__init__(self, rhs, t0, y0, t_bound, **options)
        self.setup(rhs, "RK45")
