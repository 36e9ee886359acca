"""The adaptive default compiled for the general Gauss step: every stage of a DOP853 step in one casadi call.

A model with redundant rows or bounded actuators is stepped by the general Gauss QP; where its pattern (the rows
kept, the bounds active) stays, that step is one compiled casadi function (:class:`gausspp.step.general.compiled.
GeneralCall`). scipy's DOP853 still called it once per stage from Python — twelve round trips per step, about
20 µs each on the redundant four-bar, three times the step's own cost. Here, as
:mod:`.compiled_adaptive` does for the equality step, the twelve stages, the new state, its derivative and scipy's
error norm are one call of a function built around the pattern's compiled step; its all-clear flag is the stages'
flags together. Where a stage's flag is down (the pattern changes, a contact closes, a row is no longer
dependent) the step is taken again by scipy's own stages through the Python right-hand side, which decides the
pattern anew — the next step then runs compiled around the new pattern. The step-size control is scipy's own,
line by line (:class:`.compiled_adaptive.CompiledRungeKutta`).

Where it applies (:func:`applies`): scipy's ``DOP853`` and ``RK45`` on the general step, without contacts.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate._ivp import rk as scipy_rk

from ..step.bound import Bound
from ..step.general import general_step
from ..step.general.compiled import GeneralCall
from ..workspace import workspace
from . import compiled_adaptive
from .compiled_adaptive import METHODS, CompiledRungeKutta, build_stages
from .rhs import GeneralRightHandSide, loose_call


def solver_class(method: str, rhs: Any) -> Any:
    """The ``OdeSolver`` class a scipy-lane run of ``method`` with ``rhs`` takes: the general step's compiled stages
    where :func:`applies`, else :func:`.compiled_adaptive.solver_class`'s."""
    if applies(method, rhs):
        return {"DOP853": GeneralDOP853, "RK45": GeneralRK45}[method]
    return compiled_adaptive.solver_class(method, rhs)


def applies(method: str, rhs: Any) -> bool:
    """Whether a scipy-lane run of ``method`` with ``rhs`` takes the general step's compiled stages."""
    return method in METHODS and isinstance(rhs, GeneralRightHandSide) and not rhs.model.contacts


def _stage(model: Any, call: GeneralCall) -> ca.Function:
    """``(t, y, stab) ↦ (y', all-clear, NaN)``: the state's derivative by the pattern's compiled step, and its flag
    (the pattern holds there: its packed output's last two entries)."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    t, y, stab = ca.MX.sym("t"), ca.MX.sym("y", nq + nv + nl + 2), ca.MX.sym("stab", 2)
    (out,) = call.function.call([t, y[:nq], y[nq : nq + nv], y[nq + nv : nq + nv + nl], stab])
    sl, n = call.slices, out.numel()
    u = out[sl["u"]]
    lam_dot = ca.vertcat(*[u[i] for i in model.lam_columns]) if model.lam_columns else ca.MX(0, 1)
    derivative = ca.vertcat(out[sl["qdot"]], out[sl["a"]], lam_dot, out[sl["power_reaction"]], out[sl["power"]])
    ok = out[n - 2] == 1.0 if call.pattern.given else ca.logic_and(out[n - 2] == 1.0, out[n - 1] == 1.0)
    fn = ca.Function("general_stage", [t, y, stab], [ca.densify(derivative), ok, ca.MX(np.nan)])
    if not call.function.is_a("SXFunction"):  # a QP node inside: its MX graph, inlined where it is called
        return ca.Function("general_stage", [t, y, stab], [ca.densify(derivative), ok, ca.MX(np.nan)],
                           {"always_inline": True})  # fmt: skip
    flat = fn.expand()  # equality rows only: one flat SX graph
    return ca.Function("general_stage", flat.sx_in(), ca.cse(flat.call(flat.sx_in())))


class GeneralRungeKutta(CompiledRungeKutta):
    """scipy's ``DOP853``/``RK45`` whose stages are one call around the general step's current pattern (module
    docstring)."""

    def setup(self, rhs: GeneralRightHandSide, method: str) -> None:  # type: ignore[override]
        self.rhs, self._method = rhs, method
        self._stab = np.array(rhs.stab, float)
        self._last_call: GeneralCall | None = None
        self._last_bound: Any = None

    def _bound_for(self, call: GeneralCall) -> Bound:
        """The stages' function around ``call``'s pattern, built once per pattern and method (kept in the model's
        workspace), its tolerances this run's."""
        if call is self._last_call:
            return self._last_bound
        model, method = self.rhs.model, self._method
        key = ("general adaptive stages", method, call.solver, call.pattern)
        loose = loose_call(model, call)
        bound: Bound = workspace(model).get(key, lambda: Bound(build_stages(model, method, _stage(model, loose))))
        s: Any = self
        bound.args[5][0] = s.rtol
        bound.args[6][:] = np.broadcast_to(s.atol, bound.args[6].shape)
        self._last_call, self._last_bound = call, bound
        return bound

    def stages(self, t: float, y: np.ndarray, f: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, float]:
        rhs = self.rhs
        call = general_step.current_call(rhs.model, rhs.backend, None, general_step.CONSISTENCY_TOL)
        if call is not None:
            bound = self._bound_for(call)
            args = bound.args
            args[0][0], args[1][:], args[2][:], args[3][0], args[4][:] = t, y, f, h, self._stab
            bound.eval()
            res = bound.res
            if res[3][0] > 0:
                rhs.evaluations += self.n_stages
                self.K[:] = bound.output(2)
                return res[0].copy(), res[1].copy(), float(res[5][0])
        return self.scipy_stages(t, y, f, h)


class GeneralDOP853(GeneralRungeKutta, scipy_rk.DOP853):
    """scipy's DOP853 with the general step's compiled stages."""

    def __init__(self, rhs: GeneralRightHandSide, t0: float, y0: np.ndarray, t_bound: float, **options: Any) -> None:
        scipy_rk.DOP853.__init__(self, rhs, t0, y0, t_bound, **options)
        self.setup(rhs, "DOP853")


class GeneralRK45(GeneralRungeKutta, scipy_rk.RK45):
    """scipy's RK45 with the general step's compiled stages."""

    def __init__(self, rhs: GeneralRightHandSide, t0: float, y0: np.ndarray, t_bound: float, **options: Any) -> None:
        scipy_rk.RK45.__init__(self, rhs, t0, y0, t_bound, **options)
        self.setup(rhs, "RK45")
