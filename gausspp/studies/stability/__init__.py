"""The stability study (docs/theory.md §6.6): each hard case, what the library does, and a verdict.

Every case runs the library as a user would, measures what it does (with numbers) and compares
it with what is *right*. A verdict ✗ means the library does something wrong there; the case's
``problems`` say what, with a minimal reproduction. Nothing here changes the library.

One module per case, each with ``NAME``, ``WHAT`` (the situation), ``EXPECTED`` (what is right)
and ``case(quick=True) -> Case`` (``quick=True`` for the test suite and ``gausspp report
--stability``, ``quick=False`` for the full sizes):

* **stiff chain** (:mod:`.stiff_chain`) — scene ``stiff-chain`` with stiffness ratio 1e8. Explicit
  RK4 at the largest step reaching a final error ≤ 1e-6 (found by bisection; its stability bound
  is ``dt·ω ≤ 2√2``) against Radau; judged on right-hand-side evaluations (≥ 10× fewer for Radau),
  wall times reported only.
* **mass ratios** (:mod:`.mass_ratios`) — ``two-masses`` and ``stiff-chain`` over mass ratios
  1e-6…1e6, both realizations: direct and QP steps against an exact rational solve; error
  ≤ 10·eps·cond(A) and QP ≡ direct.
* **realizability margins** (:mod:`.margins`) — the crane at margins 1e-3…1e-9: a
  RealizabilityWarning exactly below ``margin_warn``, a RealizabilityError naming constraint, time
  and margin below ``margin_error``, and an acceleration error growing like eps/margin against a
  closed form free of cancellation.
* **long horizon** (:mod:`.long_horizon`) — the pendulum, 1e5 (1e6) RK4 steps raw, projected and
  with Baumgarte terms: drift and energy.
* **redundant constraints** (:mod:`.redundant`) — a circle written twice, and pins plus the
  distance they imply: exact redundancy must raise a RealizabilityError naming the constraints and
  the redundancy with every solver, near-redundancy (drift off the manifold) must warn or raise,
  and any answer without a warning must be the minimal model's.
* **initial data off the constraint** (:mod:`.off_constraint`) — InitialDataError naming the
  constraint, time and value; ``stabilize="project"`` starts on the constraint near the data, or
  says clearly that it cannot.
* **crane near the vertical rope** (:mod:`.crane`) — the margin ∝ sin²θ at the step level, and a
  payload in free fall through the singular instant t* with every integration lane: each must
  stop at t* with a project error, point at the margin, and keep no sample beyond t*.

:func:`run` runs all cases (a case that raises becomes a failed case, never a dropped one),
:func:`table` prints them, :func:`to_records` flattens them for CSV/JSON.
"""

from __future__ import annotations

import textwrap
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from . import crane, long_horizon, margins, mass_ratios, off_constraint, redundant, stiff_chain
from .common import Case

_MODULES = (stiff_chain, mass_ratios, margins, long_horizon, redundant, off_constraint, crane)

#: case name → its function ``case(quick) -> Case``, in the order of the report
CASES: dict[str, Callable[[bool], Case]] = {m.NAME: m.case for m in _MODULES}

#: case name → (what, expected): what a crashed case still reports
_ABOUT: dict[str, tuple[str, str]] = {m.NAME: (m.WHAT, m.EXPECTED) for m in _MODULES}


def run(quick: bool = True) -> list[Case]:
    """Run every case (quick sizes by default); a case that raises becomes a failed case.

    Each case's figures gain ``seconds``, its wall time.
    """
    cases = []
    for name, fn in CASES.items():
        start = time.perf_counter()
        try:
            case = fn(quick)
        except Exception as exc:  # noqa: BLE001 - never drop a case
            what, expected = _ABOUT.get(name, ("", ""))
            failure = f"{type(exc).__name__}: {exc}"
            case = Case(
                name,
                what,
                expected,
                f"the case raised {failure}",
                False,
                {"crashed": 1.0},
                (f"the study itself failed: {failure}",),
            )
        cases.append(replace(case, figures={**case.figures, "seconds": time.perf_counter() - start}))
    return cases


def table(cases: list[Case], width: int = 100) -> str:
    """A plain-text table: case, verdict (✓/✗), observed summary; then the library problems found."""
    name_w = max([len("case"), *(len(c.name) for c in cases)])
    indent = " " * (name_w + 2 + 7 + 2)
    rule = "-" * (len(indent) + width)
    lines = [f"{'case':{name_w}s}  verdict  observed", rule]
    for c in cases:
        wrapped = textwrap.wrap(c.observed, width) or [""]
        lines.append(f"{c.name:{name_w}s}  {'✓' if c.verdict else '✗':^7s}  {wrapped[0]}")
        lines += [indent + w for w in wrapped[1:]]
    lines += [rule, f"{sum(c.verdict for c in cases)}/{len(cases)} cases as they should be"]
    found = [(c.name, p) for c in cases for p in c.problems]
    if found:
        lines += ["", "Library problems found:"]
        for case_name, p in found:
            wrapped = textwrap.wrap(f"[{case_name}] {p}", len(rule) - 2)
            lines.append("- " + wrapped[0])
            lines += ["  " + w for w in wrapped[1:]]
    return "\n".join(lines)


def to_records(cases: list[Case]) -> list[dict[str, Any]]:
    """One flat dict per case (``figure:<name>`` columns), ready for csv.DictWriter or json."""
    records = []
    for c in cases:
        record: dict[str, Any] = {
            "name": c.name,
            "verdict": bool(c.verdict),
            "what": c.what,
            "expected": c.expected,
            "observed": c.observed,
            "problems": " | ".join(c.problems),
        }
        record.update({f"figure:{k}": float(v) for k, v in c.figures.items()})
        records.append(record)
    return records


__all__ = [
    "CASES",
    "Case",
    "crane",
    "long_horizon",
    "margins",
    "mass_ratios",
    "off_constraint",
    "redundant",
    "run",
    "stiff_chain",
    "table",
    "to_records",
]
