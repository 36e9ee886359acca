"""The right-hand side ``y' = F(t, y)`` of a simulation, ``y = (q, v, λ, W_R, W_F)``.

One compiled step call per evaluation (a buffer-bound kernel); cheap checks on the hot path,
the full diagnosis of :mod:`gausspp.step.outcome` only when something is wrong.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..disk_cache import cached_function
from ..errors import NonFiniteError
from ..model.model import Model
from ..step import qp
from ..step.bound import sparse_output
from ..step.equality.expressions import OUTPUTS
from ..step.equality.kernel import Bound, CompiledKernel
from ..step.general import check_backend, general_step
from ..step.outcome import QP_TOLERANCE, Where, evaluation_failed, step_margin, to_result
from ..step.realizability import stacked_margins
from ..workspace import workspace
from .drift import Stabilization

#: How many work integrals close the state ``y``: ``W_R`` and ``W_F``, the energy audit's quadratures.
AUDIT_CHANNELS = 2


def step_control_atol(atol: float | np.ndarray, n: int) -> np.ndarray:
    """The absolute tolerance of an adaptive run over the state ``y`` of size ``n``: ``atol`` on ``(q, v, λ)``,
    ``inf`` on the work integrals ``W_R, W_F``.

    The work integrals are quadratures: they feed nothing back into the motion, so their error estimate must not
    choose the step (as SUNDIALS' CVODES leaves quadratures out of its error test by default, ``errconQ``). An
    ideal constraint's power is round-off, and its integral's "error" at ``atol = 1e-12`` set the step size of
    every ideal run — 116 DOP853 steps on the pendulum where the motion needs 33. They are integrated by the same
    steps, with the method's order, and the energy audit checks them."""
    tol = np.full(n, np.inf)
    tol[: n - AUDIT_CHANNELS] = np.broadcast_to(np.asarray(atol, float), (n - AUDIT_CHANNELS,))
    return tol


class _StateDerivative:
    """``F(t, y) = (q̇, q̈, λ̇, power of the reaction, power of the forces)`` from a step's outputs."""

    _lam_cols: np.ndarray

    def evaluate(self, t: float, y: np.ndarray, stabilized: bool = True) -> dict[str, np.ndarray]:
        raise NotImplementedError

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        out = self.evaluate(t, y)
        u = out["u"]
        return np.concatenate([out["qdot"], out["a"], u[self._lam_cols], out["power_reaction"], out["power_forces"]])

    def qdot(self, t: float, y: np.ndarray) -> np.ndarray:
        """The kinematics ``q̇ = K(q, v, t)`` at ``y`` (one step evaluation)."""
        return np.array(self.evaluate(t, y)["qdot"])


class RightHandSide(_StateDerivative):
    """``F(t, y)`` for a model, a step solver and a stabilization; counts its evaluations."""

    #: Whether the realizability margin of its steps means something (see :class:`GeneralRightHandSide`).
    margin_checked = True

    def __init__(self, model: Model, solver: str, backend: str | None, stab: Stabilization) -> None:
        self.model = model
        self.kernel = model.kernel(solver, backend)
        self.solver = "direct" if solver == "direct" else qp.get(backend).name
        self.stab = np.array(stab.stab, float)
        self.evaluations = 0
        m = model
        self._slices = (slice(0, m.nq), slice(m.nq, m.nq + m.nv), slice(m.nq + m.nv, m.nq + m.nv + m.n_lam))
        self._lam_cols = np.array(model.lam_columns, dtype=int)
        #: ``(t, y, margin)`` of the last evaluation that passed (``y`` the caller's array, not a copy)
        self.last_margin: tuple[float, np.ndarray, float] | None = None

    def margin_at(self, t: float, y: np.ndarray) -> float | None:
        """The realizability margin of the last evaluation if it was at ``(t, y)`` (an integrator's accepted state
        is its last stage), else ``None``."""
        last = self.last_margin
        if last is None or last[0] != t:
            return None
        return last[2] if last[1] is y or np.array_equal(last[1], y) else None

    def _load(self, t: float, y: np.ndarray, stabilized: bool) -> None:
        """The kernel's inputs from the state ``y = (q, v, λ, W_R, W_F)``."""
        sq, sv, sl = self._slices
        inputs = self.kernel.inputs
        inputs[0][0] = t
        inputs[1][:], inputs[2][:], inputs[3][:] = y[sq], y[sv], y[sl]
        inputs[4][:] = self.stab if stabilized else 0.0

    def margin(self, t: float, y: np.ndarray) -> float:
        """The realizability margin at ``(t, y)`` by one compiled step call, unchecked (NaN where the step fails):
        for a watch that probes states the integrator does not keep."""
        if not isinstance(self.kernel, CompiledKernel):
            return float("nan")
        self._load(t, y, stabilized=False)
        try:
            self.kernel.evaluate()
        except RuntimeError:
            return float("nan")
        out = self.kernel.result()
        return step_margin(out["S_norm"], self.model.k, self.model.m) if out["pivot"][0] > 0 else float("nan")

    def evaluate(self, t: float, y: np.ndarray, stabilized: bool = True) -> dict[str, np.ndarray]:
        """Evaluate the step at ``(t, y)``; raise a project error if it fails."""
        sq, sv, sl = self._slices
        self._load(t, y, stabilized)
        self.evaluations += 1
        try:
            self.kernel.evaluate()
        except RuntimeError as exc:  # casadi refused to evaluate: explain it from the step's data
            m = self.model
            q, v, lam = y[sq].copy(), y[sv].copy(), y[sl].copy()
            where = Where(float(t), self.solver, m.groups, lambda: m.step_data(t, q, v, lam))
            raise evaluation_failed(exc, where, margin_error=m.margin_error) from None
        out = self.kernel.result()
        ok = out["pivot"][0] > 0 and np.isfinite(out["checksum"][0]) and out["qp_primal"][0] <= QP_TOLERANCE
        if ok:  # the realizability margin, at every evaluation (docs/theory.md §2): σ_min of the normalized S
            margin = step_margin(out["S_norm"], self.model.k, self.model.m)
            self.last_margin = (t, y, margin)
            ok = margin >= self.model.margin_error
        if not ok:  # diagnose: raises the project error that explains the failure
            size = float(np.max(np.abs(y)))
            if not size < 1e100:
                raise NonFiniteError(
                    f"the state diverged at t={t:.6g} (largest component {size:.3g}): the integration is unstable; "
                    "reduce dt or use a stiff method (Radau, BDF, cvodes)"
                )
            m = self.model
            q, v, lam = y[sq].copy(), y[sv].copy(), y[sl].copy()
            where = Where(float(t), self.solver, m.groups, lambda: m.step_data(t, q, v, lam))
            to_result(dict(out), where, margin_warn=0.0, margin_error=m.margin_error)
        return out

    def evaluate_all(
        self, t: np.ndarray, y: np.ndarray, solutions: np.ndarray | None = None
    ) -> tuple[dict[str, np.ndarray], np.ndarray, int]:
        """The unstabilized step at every sample ``(t_i, y_i)`` at once: the compiled step mapped over
        :data:`CHUNK` samples (``Function.map``), one call per chunk of the ``(nq + nv + nλ) × n`` matrix of states.

        ``solutions`` (a compiled QP run's, :class:`~gausspp.simulation.samples.Samples`): where a sample's row
        is finite, the QP's solution there — the step is replayed from it (build and finish, no QP solved again).

        Returns each output stacked along a first axis (``(n, rows, cols)``), each sample's margin
        (:func:`~gausspp.step.realizability.stacked_margins`) and how many leading samples pass the checks of
        :meth:`evaluate`; the first that does not (and the rest) are left to :meth:`evaluate`, which raises the
        error that explains. ``0`` samples for a QP solved from Python.
        """
        kernel = self.kernel
        if not isinstance(kernel, CompiledKernel) or t.size == 0:
            return {}, np.zeros(0), 0
        replay = None if solutions is None or kernel.qp_parts is None else np.isfinite(solutions).all(axis=1)
        if replay is None or not replay.any():
            out, n = _mapped(_mapped_step(self.model, kernel, self.solver), t, y, self._slices)
        else:
            out, n = _replayed(self.model, kernel, t, y, self._slices, solutions, replay)  # type: ignore[arg-type]
        self.evaluations += n
        m = self.model
        margin = stacked_margins(out["S_norm"][:n], m.k, m.m, symmetric=m.symmetric_S or None)
        ok = (out["pivot"][:n, 0, 0] > 0) & np.isfinite(out["checksum"][:n, 0, 0])  # as evaluate, sample by sample
        ok &= (out["qp_primal"][:n, 0, 0] <= QP_TOLERANCE) & (margin >= m.margin_error)
        good = n if ok.all() else int(np.argmin(ok))
        return out, margin, good


#: Samples per call of the mapped step, and per call for a run's last samples (fewer than :data:`CHUNK`): a run of
#: 41 samples evaluates 48, not 128 — padding a short run to a whole chunk tripled its recording's QP solves.
CHUNK = 128
TAIL_CHUNK = 16


#: Where the normalized ``S`` is among the step's outputs: the recording's mapped steps store it by its nonzeros.
S_OUTPUT = OUTPUTS.index("S_norm")

#: A mapped step by its number of samples per call (:data:`CHUNK` or :data:`TAIL_CHUNK`).
Mapped = Callable[[int], Bound]


def _mapped_step(model: Model, kernel: CompiledKernel, solver: str) -> Mapped:
    """The step mapped over ``chunk`` samples (kept beside the kernel, and on disk for a direct step), its
    ``S_norm`` stored by its nonzeros (:func:`~gausspp.step.bound.sparse_output`)."""

    def mapped(chunk: int) -> Bound:
        def build() -> Bound:
            if kernel.qp_parts is not None:
                return Bound(kernel.function.map(chunk))
            fn = kernel.function
            what = ("mapped step", chunk, solver, fn.name(), fn.n_instructions(), "sparse S")
            return Bound(cached_function(model, what, lambda: sparse_output(fn, S_OUTPUT).map(chunk)))

        return workspace(kernel).get(("mapped step", chunk), build)

    return mapped


def _replayed(
    model: Model,
    kernel: CompiledKernel,
    t: np.ndarray,
    y: np.ndarray,
    slices: tuple[slice, slice, slice],
    solutions: np.ndarray,
    replay: np.ndarray,
) -> tuple[dict[str, np.ndarray], int]:
    """:func:`_mapped` with the samples where ``replay`` holds replayed from their QP ``solutions``."""
    assert kernel.qp_parts is not None
    parts = kernel.qp_parts

    def replayed(chunk: int) -> Bound:
        return workspace(kernel).get(
            ("replayed step", chunk), lambda: Bound(sparse_output(parts.replay(), S_OUTPUT).map(chunk))
        )

    again = np.flatnonzero(~replay)
    out = _mapped(replayed, t[replay], y[replay], slices, solutions[replay])[0]  # SX: never refuses
    if again.size == 0:
        return out, t.size
    solved, n_solved = _mapped(_mapped_step(model, kernel, "qp"), t[again], y[again], slices)
    merged = {name: np.empty((t.size, *value.shape[1:])) for name, value in out.items()}
    for name, value in merged.items():
        value[replay], value[again] = out[name], solved[name]
    return merged, t.size if n_solved == again.size else int(again[n_solved])


def _mapped(
    mapped_over: Mapped,
    t: np.ndarray,
    y: np.ndarray,
    slices: tuple[slice, slice, slice],
    extra: np.ndarray | None = None,
) -> tuple[dict[str, np.ndarray], int]:
    """A mapped step's outputs at the samples, :data:`CHUNK` at a time and the rest :data:`TAIL_CHUNK` at a time
    (the last call padded with the last sample); how many were evaluated (fewer if casadi refused a call: the
    samples from it on are left out). ``extra``: one more input per sample (a row each)."""
    n = t.size
    first = mapped_over(CHUNK if n >= CHUNK else TAIL_CHUNK)
    chunk = _chunk(first)
    out = {name: np.zeros((n, rows, cols // chunk)) for name, (rows, cols) in zip(OUTPUTS, first.shapes, strict=True)}
    start = 0
    while start < n:
        mapped = mapped_over(CHUNK if n - start >= CHUNK else TAIL_CHUNK)
        chunk = _chunk(mapped)
        places = _places_of(mapped)
        args, (sq, sv, sl) = mapped.args, slices  # the inputs column-major: sample after sample
        args[4][:] = 0.0
        stop, rows = min(start + chunk, n), np.minimum(np.arange(start, start + chunk), n - 1)
        args[0][:], args[1][:], args[2][:], args[3][:] = (
            t[rows],
            y[rows, sq].ravel(),
            y[rows, sv].ravel(),
            y[rows, sl].ravel(),
        )
        if extra is not None:
            args[5][:] = extra[rows].ravel()
        try:
            mapped.eval()
        except RuntimeError:
            return out, start
        for name, res, shape, place in zip(OUTPUTS, mapped.res, mapped.shapes, places, strict=True):
            if place is None:
                out[name][start:stop] = _stacked(res, shape, chunk)[: stop - start]
            else:  # stored by its nonzeros: each sample's into its (row, column)
                sample, row, col = place
                keep = sample < stop - start
                out[name][start + sample[keep], row[keep], col[keep]] = res[keep]
        start = stop
    return out, n


def _chunk(mapped: Bound) -> int:
    """How many samples one call of ``mapped`` evaluates (its time input holds one per sample)."""
    return int(mapped.fn.size1_in(0) * mapped.fn.size2_in(0))


def _places_of(mapped: Bound) -> list[tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
    """:func:`_places` of each output of ``mapped`` (computed once per mapped function)."""
    return workspace(mapped).get(
        ("places",), lambda: [_places(mapped.fn.sparsity_out(i), _chunk(mapped)) for i in range(len(OUTPUTS))]
    )


def _places(sparsity: Any, chunk: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Where each stored entry of a mapped output goes: ``(sample, row, column)`` of its nonzeros (the samples'
    blocks side by side, as :func:`_stacked`); ``None`` for a dense output."""
    if sparsity.is_dense():
        return None
    rows, cols = (np.asarray(x, int) for x in sparsity.get_triplet())
    width = sparsity.size2() // chunk
    return cols // width, rows, cols % width


def _stacked(res: np.ndarray, shape: tuple[int, int], n: int) -> np.ndarray:
    """A mapped output's buffer (``shape = (rows, n·cols)``: the samples side by side, column-major) as a view
    ``(n, rows, cols)``."""
    rows, all_cols = shape
    return res.reshape(n, all_cols // n, rows).transpose(0, 2, 1)


_NO_STAB = np.zeros(2)


class GeneralRightHandSide(_StateDerivative):
    """``F(t, y)`` through the general Gauss QP (:meth:`Model.general_step`): bounded actuators and
    redundant constraint rows. Each evaluation is the compiled general step of the pattern decided (one C call,
    :mod:`gausspp.step.general.compiled`) when its all-clear flag is up, else the Python step, which decides the
    pattern again."""

    kernel = None

    def __init__(self, model: Model, backend: str | None, stab: Stabilization, *, margin_checked: bool = True) -> None:
        self.model = model
        self.backend = check_backend(backend)
        self.solver = f"gauss-qp:{self.backend}"
        self.stab = np.array(stab.stab, float)
        self.evaluations = 0
        m = model
        self._slices = (slice(0, m.nq), slice(m.nq, m.nq + m.nv), slice(m.nq + m.nv, m.nq + m.nv + m.n_lam))
        self._lam_cols = np.array(model.lam_columns, dtype=int)
        #: Whether the realizability margin says anything (not for redundant rows, where it is 0 by design).
        self.margin_checked = margin_checked

    def evaluate(self, t: float, y: np.ndarray, stabilized: bool = True) -> dict[str, np.ndarray]:
        """Evaluate the step at ``(t, y)``; raise a project error if it fails."""
        sq, sv, sl = self._slices
        self.evaluations += 1
        size = float(np.max(np.abs(y)))
        if not size < 1e100:
            raise NonFiniteError(
                f"the state diverged at t={t:.6g} (largest component {size:.3g}): the integration is unstable; "
                "reduce dt or use a stiff method"
            )
        m = self.model
        stab = self.stab if stabilized else _NO_STAB
        call = general_step.current_call(m, self.backend, None, general_step.CONSISTENCY_TOL)
        if call is not None:  # the pattern decided, its decision held as an integrator's states need (loose_call)
            loose = loose_call(m, call)
            out = loose(float(t), y[sq], y[sv], y[sl], stab)
            if out is not None:
                return general_step.rhs_outputs(m, loose, out)
        res, _, extras = m.general_step_full(
            float(t),
            y[sq],
            y[sv],
            y[sl],
            self.backend,
            self.stab if stabilized else np.zeros(2),
        )
        return {
            "a": res.a,
            "u": res.u,
            "reaction": res.reaction,
            "compulsion": np.array([res.compulsion]),
            "Phi": res.constraint_value,
            "tracking_error": np.array([res.tracking_error]),
            "saturated": np.asarray(res.saturated, bool),
            **extras,
        }


def loose_call(model: Model, call: Any) -> Any:
    """``call``'s pattern compiled with its decision held to :data:`~gausspp.step.general.drift.STAGE_SLACK_CAP` off
    the manifold (kept in the model's workspace): a run's states — an integrator's stages, a record time inside a
    step — lie as far off as its tolerance lets them, and at ``model.step``'s cap every such state of Bricard's
    mechanism at rtol 1e-4 went to the Python step, which decides at the nearest state on the manifold (315 ms for
    10 s where this takes 38 ms, the same motion to three digits)."""
    from ..step.general.compiled import GeneralCall
    from ..step.general.drift import STAGE_SLACK_CAP

    key = ("general call, loose", call.solver, call.pattern, call.consistency_tol)
    return workspace(model).get(
        key, lambda: GeneralCall(model, call.pattern, call.backend, call.consistency_tol, STAGE_SLACK_CAP)
    )


#: Either right-hand side (the compiled step, or the general QP's).
AnyRightHandSide = RightHandSide | GeneralRightHandSide
