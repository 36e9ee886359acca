"""The general Gauss step: equality rows of any rank, unilateral contacts and bounded actuators.

The second kind of step, beside the compiled equality step of :mod:`gausspp.step`: the Gauss QP
where no closed form exists (docs/theory.md §3, §6, §7). Its modules, following the data flow:

* :mod:`.model_qp` — the model's step at one state as one :class:`GaussProblem` (:mod:`.gauss_problem`);
* :mod:`.scaling` — the problem in unit-free form; :mod:`.redundancy`, :mod:`.kept_rows` — which
  bilateral rows are kept, decided on the constraint manifold (:mod:`.manifold`: the nearest state on it);
* :mod:`.solve` — the stages (track, compulsion, least norm), each a QP by a backend (:mod:`.stage`);
* :mod:`.general_step` — the model's general step at a state: the compiled call when its all-clear
  flag is up, the Python step above otherwise.
"""

from .solve import (
    CONSISTENCY_TOL,
    DUAL_TOL,
    FEASIBILITY_TOL,
    RANK_TOL,
    TRACK_REGULARIZATION,
    GaussProblem,
    GaussSolution,
    check_backend,
    default_backend,
    features,
    resolve_backend,
    solve_general,
)

__all__ = [
    "CONSISTENCY_TOL",
    "DUAL_TOL",
    "FEASIBILITY_TOL",
    "RANK_TOL",
    "TRACK_REGULARIZATION",
    "GaussProblem",
    "GaussSolution",
    "check_backend",
    "default_backend",
    "features",
    "resolve_backend",
    "solve_general",
]
