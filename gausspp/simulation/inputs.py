"""The arguments of a run, checked once: :func:`check_options` returns them as :class:`Options`.

Also the limits of a run's size (:data:`MAX_STEPS`, :data:`MAX_KEPT_BYTES`) and when a long run is
announced (:data:`LONG_RUN_STEPS`) and reports its progress (:data:`PROGRESS_EVERY`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import InputError, IntegrationError, LongRunWarning
from ..model.model import Model
from ..model.run_scales import RunScales
from ..validation import number, positive, record_times
from . import lanes
from . import methods as _methods

#: A run with more fixed steps than this warns up front (:class:`~gausspp.LongRunWarning`) with the count.
LONG_RUN_STEPS = 1_000_000
#: A long fixed-step run looks at the clock every this many steps (and reports at most every 2 s).
PROGRESS_EVERY = 500
#: A run with more steps than this is refused: it would run for days and its samples would not fit in memory.
MAX_STEPS = 10**10
#: The states a run keeps (every step on the compiled lane, the recorded ones elsewhere) may take this many bytes.
MAX_KEPT_BYTES = 2**31


#: The default relative tolerance of adaptive runs (``gp.simulate``, ``gausspp run``): the error each step admits on
#: ``(q, v, λ)`` is ``atol + rtol·|y|``, with ``atol`` by default ``rtol`` times each component's own size
#: (:func:`gausspp.model.run_scales.RunScales.atol`), so that the tolerance means the same in any units.
DEFAULT_RTOL = 1e-10
#: ``atol=None``: derived from the run's scales.
DEFAULT_ATOL = None


@dataclass(frozen=True)
class Options:
    """The checked arguments of :func:`gausspp.simulate` (see there)."""

    method: _methods.Method
    t0: float
    t_end: float
    dt: float | None
    solver: str
    backend: str | None
    rtol: float
    #: ``None`` until the run's scales are read (:func:`with_scales`), then one tolerance per component
    atol: Any
    record: Any
    constraint_tol: float
    throw: bool
    rest_speed: float
    max_events: int
    #: The run's residuals ``|g|, |Φ|`` may not exceed this relative to ``1 + ‖q‖∞``, ``1 + ‖v‖∞``
    #: (:mod:`gausspp.simulation.residual_audit`).
    drift_tol: float = 1e-3
    #: The lanes that can run the method with these options, fastest first (:func:`lanes.check_solver`).
    lanes: tuple[lanes.Lane, ...] = ()
    #: The scales every tolerance of the run is measured against, read at its initial state (:func:`with_scales`).
    scales: RunScales | None = None


def with_scales(opts: Options, scales: RunScales) -> Options:
    """``opts`` with the run's scales, and its ``atol`` derived from them where the user gave none."""
    atol = scales.atol(opts.rtol, opts.method.iterates) if opts.atol is None else opts.atol
    return replace(opts, atol=atol, scales=scales)


def check_options(  # the arguments of gp.simulate, by name
    model: Model,
    *,
    method: str | _methods.Method | None,
    t0: Any,
    t_end: Any,
    dt: Any,
    solver: str,
    backend: str | None,
    rtol: Any,
    atol: Any,
    record: Any,
    constraint_tol: Any,
    throw: Any,
    rest_speed: Any,
    max_events: Any,
    lane: str | None = None,
    drift_tol: Any = 1e-3,
) -> Options:
    """Every argument of a run that does not need the state, checked; the errors name the argument and the fix."""
    if not isinstance(model, Model):
        raise InputError(f"model must be a gp.Model (scenes carry one: gp.scenes.get(name).model), got {model!r}")
    meth = _methods.get(lanes.default_method(model, dt) if method is None else method)
    t0 = number(f"t0 must be a finite number, got {t0!r}", t0)
    t_end = number(f"t_end must be a finite number, got {t_end!r}", t_end)
    if not t_end > t0:
        raise InputError(f"need t0 < t_end, got t0={t0}, t_end={t_end}")
    if dt is None and not meth.adaptive:
        raise InputError(f"method {meth.name!r} has a fixed step: give dt > 0, e.g. dt={(t_end - t0) / 1000:.3g}")
    if dt is not None:
        dt = positive("dt", dt, hint=" (the step; for adaptive methods the first and largest)")
        if dt > t_end - t0:
            raise InputError(
                f"dt={dt:g} is longer than the run (t_end - t0 = {t_end - t0:g}): give dt ≤ {t_end - t0:g}, e.g. "
                f"dt={(t_end - t0) / 1000:.3g}"
            )
    rtol = positive("rtol", rtol, hint=" (the relative tolerance of adaptive methods, e.g. rtol=1e-9)")
    if atol is not None:
        atol = positive(
            "atol", atol, zero_ok=True, hint=" (the absolute tolerance of adaptive methods, e.g. atol=1e-12)"
        )
    constraint_tol = positive("constraint_tol", constraint_tol, zero_ok=True)
    drift_tol = positive("drift_tol", drift_tol, hint=" (the drift a run may take, relative: e.g. drift_tol=1e-3)")
    rest_speed = positive("rest_speed", rest_speed, zero_ok=True)
    max_events = positive("max_events", max_events, integer=True)
    if not isinstance(throw, (bool, np.bool_)):
        raise InputError(f"throw must be True or False, got {throw!r}")
    record = check_record(record, t0, t_end)
    if model.k == 0 and not model.contacts and solver in lanes.SOLVERS:  # the free mechanism: no QP to solve
        solver, backend = "direct", None
    among = lanes.check_solver(meth, solver, backend, lane)
    if dt is not None:
        among = check_step_count(meth, model, t0, t_end, dt, record, among)
    return Options(
        meth,
        t0,
        t_end,
        dt,
        solver,
        backend,
        rtol,
        atol,
        record,
        constraint_tol,
        bool(throw),
        rest_speed,
        max_events,
        drift_tol,
        among,
    )


def check_record(record: Any, t0: float, t_end: float) -> Any:
    """``record``: a positive integer (every ``record``-th step) or a 1-D array of times in ``[t0, t_end]``."""
    if np.isscalar(record) or record is None:
        return positive("record", record, integer=True, hint=" (record every k-th step) or an array of times")
    return record_times("simulate", record, t0, t_end)


def check_step_count(
    meth: _methods.Method,
    model: Model,
    t0: float,
    t_end: float,
    dt: float,
    record: Any,
    among: tuple[lanes.Lane, ...],
) -> tuple[lanes.Lane, ...]:
    """Refuse a run of more than :data:`MAX_STEPS` steps or whose kept states exceed :data:`MAX_KEPT_BYTES`; warn
    (:class:`~gausspp.LongRunWarning`) above :data:`LONG_RUN_STEPS` steps, before the wait. For an adaptive method
    ``dt`` is the largest step, so the count is a lower bound. Returns the lanes of ``among`` whose kept states fit
    (a lane that keeps every step gives way to one that thins)."""
    steps = (t_end - t0) / dt  # a float: t_end=1e300 must not overflow an integer
    bound = "at least " if meth.adaptive else ""
    what = f"t_end - t0 = {t_end - t0:.6g} with dt={dt:.3g} is {bound}{steps:.3g} steps"
    if steps > MAX_STEPS:
        raise InputError(
            f"{what}, more than the {MAX_STEPS:.0e} a run may take (days of computing): enlarge dt or shorten t_end"
        )
    width = 8 * (model.nq + model.nv + model.n_lam + 2)
    among = lanes.fitting(among, (steps + 1) * width <= MAX_KEPT_BYTES)
    every_step = bool(among) and among[0].keeps_every_step
    if every_step:  # the compiled RK keeps every step's state
        kept = steps + 1
    elif np.isscalar(record):  # every record-th fixed step; every accepted step of an adaptive method
        kept = steps + 1 if meth.adaptive else steps / float(record) + 2  # type: ignore[arg-type]
    else:
        kept = len(record)
    if kept * width > MAX_KEPT_BYTES:
        keep_less = "" if every_step else ", or record fewer steps (record=k keeps every k-th)"
        raise InputError(
            f"{what}; method {meth.name!r} would keep {kept:.3g} states ({kept * width / 2**30:.3g} GiB, more than "
            f"{MAX_KEPT_BYTES / 2**30:g} GiB): enlarge dt or shorten t_end{keep_less}"
        )
    if steps > LONG_RUN_STEPS:
        shown = bool(among) and among[0].progress
        warnings.warn(
            f"{what} (method {meth.name!r}): this run will take long"
            + (" (on a terminal, its progress and the time left are shown on standard error)" if shown else "")
            + "; enlarge dt or shorten t_end"
            + (", or use an adaptive method (DOP853) or rk4 in the compiled lane" if shown else ""),
            LongRunWarning,
            stacklevel=4,
        )
    return among


#: An adaptive run forecasts its length from this many accepted steps (:func:`check_forecast`).
FORECAST_AFTER = 200


def check_forecast(method: str, t0: float, t_end: float, t: float, steps: int, width: int, kept: int) -> None:
    """An adaptive run's length forecast from its first ``steps`` accepted steps (to ``t``): refused (an
    :class:`~gausspp.IntegrationError`, what was computed kept) above :data:`MAX_STEPS` steps or when the ``kept``
    states so far, extrapolated, would exceed :data:`MAX_KEPT_BYTES` (``width`` bytes each); announced
    (:class:`~gausspp.LongRunWarning`) above :data:`LONG_RUN_STEPS`."""
    if not t > t0:
        return
    scale = (t_end - t0) / (t - t0)
    total, states = steps * scale, kept * scale
    what = f"{method} took {steps} steps to t={t:.6g}: to t_end={t_end:.6g} that is about {total:.3g} steps"
    if total > MAX_STEPS:
        raise IntegrationError(
            f"{what}, more than the {MAX_STEPS:.0e} a run may take (days of computing): shorten t_end, loosen "
            "rtol/atol, or check the model (a very stiff or singular motion takes tiny steps)"
        )
    if states * width > MAX_KEPT_BYTES:
        raise IntegrationError(
            f"{what}, keeping {states:.3g} states ({states * width / 2**30:.3g} GiB, more than "
            f"{MAX_KEPT_BYTES / 2**30:g} GiB): record fewer (record=times) or shorten t_end"
        )
    if total > LONG_RUN_STEPS:
        warnings.warn(
            f"{what}: this run will take long; shorten t_end or loosen rtol/atol", LongRunWarning, stacklevel=5
        )
