"""Plain text of the studies: the helpers every table shares, and the demo's three tables.

Each ``*_lines`` function takes the rows of :mod:`gausspp.studies.demo` (an iterable: a row is
formatted as soon as it is computed) and yields the lines of one table — its title, header, rows
and the notes that explain the columns.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np

from ..model.model import Model
from .demo import GENERAL_RTOL, Backends, GeneralRow, SceneRow, StepRow


def one_line(text: object) -> str:
    """``text`` with every run of whitespace (newlines included) as one space."""
    return " ".join(str(text).split())


def label(name: str, params: dict[str, Any]) -> str:
    """A scene and the parameters it was built with: ``two-masses (realization='servo')``."""
    return name + (" (" + ", ".join(f"{k}={v!r}" for k, v in params.items()) + ")" if params else "")


def scalar_parameters(params: dict[str, Any]) -> str:
    """A scene's numeric parameters for a figure's title, in the scenes' SI units:
    ``"m = 1, L = 1, g = 9.81, t_end = 1 (SI units)"`` (vectors, tensors and names left out)."""
    numbers = {k: v for k, v in params.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    return ", ".join(f"{k} = {v:g}" for k, v in numbers.items()) + " (SI units)" if numbers else ""


def realizations(model: Model) -> str:
    """How each constraint is realized, and each contact's restitution, on one line."""
    parts = [f"{n}: {c.realization.label}" for n, c in zip(model.names, model.constraints, strict=True)]
    parts += [
        f"{n}: unilateral, e = {c.restitution:g}" for n, c in zip(model.contact_names, model.contacts, strict=True)
    ]
    return ", ".join(parts)


def vector(x: np.ndarray) -> str:
    """A state vector with 8 decimals, on one line."""
    return np.array2string(np.asarray(x), precision=8, separator=", ", max_line_width=200, suppress_small=False)


def _header(text: str) -> Iterator[str]:
    yield text
    yield "-" * len(text)


def step_lines(rows: Iterable[StepRow], default_backend: str) -> Iterator[str]:
    """The one-step table: each solver's raw answer, their gap, the distance from the reference, µs per step."""
    yield f"gausspp demo — one step at t = 0 by the direct formula and by the Gauss QP ({default_backend})\n"
    rows = list(rows)
    width = max([22, *(len(r.label) for r in rows)])
    yield from _header(
        f"{'scene':18s} {'realization':{width}s} {'solver':8s} {'acceleration (SI)':>30s} "
        f"{'multiplier':>11s} {'QP vs direct':>12s} {'vs reference':>12s} {'µs/step':>8s}"
    )
    for r in rows:
        acc = np.array2string(r.acceleration, precision=5, suppress_small=True, separator=", ")
        gap = "" if r.gap is None else f"{r.gap:.1e}"
        yield (
            f"{r.scene:18s} {r.label:{width}s} {r.solver:8s} {acc:>30s} {r.multiplier:>11.6f} {gap:>12s} "
            f"{r.versus_reference:>12.1e} {r.us_per_step:>8.2f}"
        )
    m1, m2, F = 1.0, 3.0, 2.0
    yield (
        f"\nExpected (m1={m1}, m2={m2}, F={F}): rod → both accelerate at F/(m1+m2) = {F / (m1 + m2):.5f}; "
        f"servo → F/m2 = {F / m2:.5f} with servo force m1·F/m2 = {m1 * F / m2:.5f}."
    )
    yield (
        "acceleration (SI): q̈ at t = 0 in the coordinates' units per s² (m/s², rad/s²); multiplier: the reaction's\n"
        "multiplier λ (N for the rod and the servo force); QP vs direct: largest difference of the two solvers' raw\n"
        "answers (no refinement step), blank for the direct row itself; vs reference: distance from the independent\n"
        "acceleration-space QP (gp.crosscheck: built from A, a0, J, phi, D alone, solved by a qpsolvers backend).\n"
        "µs/step: one compiled casadi call per step (Function.buffer), minimum over repeats."
    )
    yield ""


def scene_lines(rows: Iterable[SceneRow], default_backend: str) -> Iterator[str]:
    """Every scene by both step solvers: their gap along the run, residual, energy balance, the verdict of (23)."""
    yield (
        f"Every scene, compiled RK4 with the direct step and with the Gauss QP ({default_backend}), "
        "then verified by (23):\n"
    )
    rows = list(rows)
    width = max([19, *(len(r.scene) for r in rows)])
    yield from _header(
        f"{'scene':{width}s} {'realizations':26s} {'T (s)':>6s} {'steps':>6s} {'QP vs direct':>12s} "
        f"{'|Φ|,|g| max':>11s} {'energy bal.':>11s} {'(23) gap':>9s} {'motion':>6s} {'run ms':>7s}"
    )
    for r in rows:
        energy = "—" if r.energy_balance is None else f"{r.energy_balance:.1e}"
        yield (
            f"{r.scene:{width}s} {r.realizations:26s} {r.t_end:6.3g} {r.steps:6d} {r.gap:12.1e} {r.residual:11.1e} "
            f"{energy:>11s} {r.relative_gap:9.1e} {'yes' if r.is_motion else 'NO':>6s} {r.run_ms:7.1f}"
        )
    yield (
        "\nT: the run's length; steps: RK4 steps; QP vs direct: largest state difference (relative) along the whole\n"
        "run; |Φ|,|g| max: largest constraint residual along the run (in the rows' own units); energy bal.:\n"
        "largest |E − E₀ − W_reaction − W_forces| (J; — where the scene's energy is not known); (23) gap: relative\n"
        "gap of the integral principle for the direct run's path — zero up to discretization iff the path is a\n"
        "motion (motion: yes); run ms: wall time of the two runs and the verification."
    )


def general_lines(backends: Backends, rows: Iterable[GeneralRow]) -> Iterator[str]:
    """The scenes only the general Gauss QP solves: events, saturation, the two backends' gap, the exact error."""
    first, second = backends.first, backends.second
    versus = f"{first} vs {second}" if second else "backends"
    compared = (
        f"{first}, compared with {second}" if second else f"{first} only; daqp not installed — `pip install daqp`"
    )
    yield f"\nBeyond closed forms — the general Gauss QP ({compared}), DOP853 rtol {GENERAL_RTOL:g}:\n"
    rows = list(rows)
    width, vs_width = max([19, *(len(r.scene) for r in rows)]), max(12, len(versus))
    yield from _header(
        f"{'scene':{width}s} {'what':28s} {'T (s)':>5s} {'events':>6s} {'saturated':>9s} {versus:>{vs_width}s} "
        f"{'|Φ|,|g| max':>11s} {'energy bal.':>11s} {'vs exact':>9s} {'run ms':>7s}"
    )
    for r in rows:
        diff = "—" if r.backend_gap is None else f"{r.backend_gap:.1e}"
        saturated = "—" if r.saturated is None else f"{r.saturated:.0%}"
        energy = "—" if r.energy_balance is None else f"{r.energy_balance:.1e}"
        exact = "—" if r.exact_error is None else f"{r.exact_error:.1e}"
        yield (
            f"{r.scene:{width}s} {r.what:28s} {r.t_end:5.3g} {r.events:6d} {saturated:>9s} {diff:>{vs_width}s} "
            f"{r.residual:11.1e} {energy:>11s} {exact:>9s} {r.run_ms:7.0f}"
        )
    yield (
        "\nevents: impacts, lift-offs and touch-downs located by the integrator; saturated: share of samples with an "
        "actuator at its bound;\n|Φ|,|g| max: largest constraint residual (the rows' units) — where an actuator "
        "saturates (saturated-crane) it is\nthe path the bounded force cannot follow, by design, not an error; "
        "energy bal.: as above (J); vs exact: largest\nerror against the scene's closed form (m or rad); — : no "
        "such quantity for the scene (no closed form, no bound, one backend)."
    )
    if second:
        yield f"{versus}: largest difference of q on a common grid of 201 times (the two QP backends run here)."
    else:
        yield f"only {first} was run: daqp not installed — `pip install daqp` to compare two QP backends."
