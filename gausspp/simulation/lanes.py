"""Which integrator lane takes which method, step solver, QP backend and kind of model — declared once, as data.

A *lane* is a way of running the step over time (:data:`LANES`): fixed steps from Python, scipy's
``OdeSolver`` classes, the whole run as one casadi graph (compiled RK4, CVODES), or the event-driven
runs of models with unilateral contacts. A *kind* of model (:data:`KINDS`) says which step it has:
the compiled equality step, the general Gauss QP (bounded actuators, redundant rows), or contact
phases. :func:`gausspp.simulate` consults these tables and nothing else; every refusal is built from
them, so a rule is changed in one place. Front ends (the command line, the studies) ask
:func:`accepts` and :func:`default_solver` instead of repeating a rule.

A method name says which integrator; the lane is gausspp's choice. Where several lanes run a method
(``rk4``: compiled and Python), :data:`LANES` lists them fastest first and a run takes the first that
can take the model and the options (:func:`candidates`, then :func:`check_kind`): ``rk4`` runs as one
casadi graph unless something needs Python (bounded actuators or redundant rows, a QP backend outside
casadi, more states than the compiled run may keep). ``simulate(lane=...)`` names a lane instead; the
trajectory says which lane ran (``Trajectory.lane``).

To add a lane: add a :class:`Lane` row here (its methods, kinds, solvers and abilities, its runner and, if the
samples are not recorded as a smooth run's, its recorder).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

from ..errors import GaussppError, InputError, UnknownNameError
from ..model.model import Model
from ..step import qp, solvers
from ..step.solvers import SOLVERS
from .methods import Method


@dataclass(frozen=True)
class Kind:
    """A kind of model, by the step it has."""

    name: str
    #: What the kind is, as a message names it ("a model with ...").
    description: str
    #: The step solvers that can step it.
    solvers: tuple[str, ...]
    #: The method when ``dt`` is given and no method.
    default_method: str
    #: What an integrator must do for it (used when a method cannot): a verb phrase and what it needs.
    task: str = ""
    needs: str = ""


@dataclass(frozen=True)
class Job:
    """What a lane runs: the step ``rhs`` of ``model`` with the drift control ``stab``, the checked options
    ``opts``, the initial state ``y0 = (q, v, λ, W_R, W_F)`` and whether the rows are ``redundant`` there."""

    rhs: Any
    model: Any
    stab: Any
    opts: Any
    y0: Any
    redundant: bool = False


@dataclass(frozen=True)
class Lane:
    """An integrator lane, what it can take, and its runner.

    A new lane is one row of :data:`LANES` and one function ``runner(job: Job) -> Samples``: the runner is that
    function, or ``"module:function"`` of :mod:`gausspp.simulation` (imported when the lane first runs: the
    runners import this table)."""

    name: str
    #: How it runs, as a message names it ("method 'x' runs ...").
    description: str
    methods: tuple[str, ...]
    kinds: tuple[str, ...]
    solvers: tuple[str, ...]
    #: Why it takes only these solvers (when it does not take them all).
    solver_reason: str = ""
    #: A QP step must run inside the casadi graph (a casadi conic backend).
    qp_in_graph: bool = False
    #: It can project onto the constraint (``stabilize="project"``); otherwise why not.
    project: bool = True
    no_project_reason: str = ""
    #: It calls Python at every step, so a long run reports its progress on standard error.
    progress: bool = False
    #: It keeps the state of every step (not only the recorded ones).
    keeps_every_step: bool = False
    #: ``runner(job) -> Samples``, or its ``"module:function"`` in :mod:`gausspp.simulation`.
    runner: Any = ""
    #: ``recorder(job, samples) -> Recorded``, the samples made a trajectory (the same forms as ``runner``).
    recorder: Any = "recording:record_job"

    def run(self, job: Job) -> Any:
        """The lane's samples of ``job`` (:class:`~gausspp.simulation.samples.Samples`)."""
        return _function(self.runner)(job)

    def record(self, job: Job, samples: Any) -> Any:
        """The lane's recording of ``samples`` (:data:`~gausspp.simulation.recording.Recorded`)."""
        return _function(self.recorder)(job, samples)


def _function(where: Any) -> Any:
    """A function, or the one ``"module:function"`` of :mod:`gausspp.simulation` names (imported on first use: the
    runners and recorders import this table)."""
    if isinstance(where, str):
        module, _, name = where.partition(":")
        return getattr(importlib.import_module(f"{__package__}.{module}"), name)
    return where


SMOOTH, GENERAL, CONTACTS = "smooth", "general", "contacts"

KINDS: dict[str, Kind] = {
    k.name: k
    for k in (
        Kind(SMOOTH, "a model with equality constraints", SOLVERS, "rk4"),
        Kind(
            GENERAL,
            "a model with bounded actuators (inequalities) or redundant constraint rows",
            ("qp",),
            "rk4",
            task="solve the general Gauss QP",
            needs="the general Gauss QP at every step (compiled, or from Python where its pattern changes)",
        ),
        Kind(
            CONTACTS,
            "a model with unilateral contacts",
            SOLVERS,
            "DOP853",
            task="locate contact events",
            needs="an adaptive scipy method, whose dense output locates them",
        ),
    )
}

_SCIPY = ("RK45", "DOP853", "Radau", "BDF")

LANES: dict[str, Lane] = {
    lane.name: lane
    for lane in (
        Lane(
            "compiled",
            "the compiled step (the whole run as one casadi graph)",
            ("rk4",),
            (SMOOTH,),
            SOLVERS,
            qp_in_graph=True,
            keeps_every_step=True,
            runner="compiled:run_compiled",
        ),
        Lane(
            "cvodes",
            "the compiled step through SUNDIALS CVODES",
            ("cvodes", "cvodes-adams"),
            (SMOOTH,),
            ("direct",),
            solver_reason="CVODES differentiates the right-hand side",
            qp_in_graph=True,
            project=False,
            no_project_reason="it cannot project between its internal steps",
            runner="compiled:run_compiled",
        ),
        Lane(
            "cvodes-general",
            "the compiled general step (the pattern decided, :mod:`gausspp.step.general.compiled`) through SUNDIALS "
            "CVODES, continued by scipy's DOP853 where the pattern changes",
            ("cvodes", "cvodes-adams"),
            (GENERAL,),
            ("qp",),
            solver_reason="the general step is the Gauss QP",
            qp_in_graph=True,
            project=False,
            no_project_reason="it cannot project between its internal steps",
            runner="general_cvodes:run_general_cvodes",
        ),
        Lane(
            "python",
            "fixed steps from Python",
            ("rk4", "symplectic-euler"),
            (SMOOTH, GENERAL),
            SOLVERS,
            progress=True,
            runner="integrate:run_python",
        ),
        Lane("scipy", "scipy's OdeSolver", _SCIPY, (SMOOTH, GENERAL), SOLVERS, runner="integrate:run_scipy"),
        Lane(
            "events",
            "event-driven phases",
            _SCIPY,
            (CONTACTS,),
            SOLVERS,
            project=False,
            no_project_reason="contact phases are not projected",
            runner="events:run_events",
            recorder="events:record_events",
        ),
    )
}

#: The method when neither a method nor ``dt`` is given: adaptive, error-controlled to ``rtol`` and ``atol``.
ADAPTIVE_DEFAULT = "DOP853"

#: The general QP's pair of refusals that is no lane's business: contacts and bounds in one model.
CONTACTS_WITH_BOUNDS = "unilateral contacts together with bounded actuators are not supported"


def kind_of(model: Model, redundant: bool = False) -> Kind:
    """The kind of ``model`` (``redundant``: its rows are dependent at the start)."""
    if model.contacts:
        if model.bounded:
            raise InputError(CONTACTS_WITH_BOUNDS)
        return KINDS[CONTACTS]
    return KINDS[GENERAL] if model.bounded or redundant else KINDS[SMOOTH]


def default_method(model: Model, dt: float | None = None) -> str:
    """The method :func:`gausspp.simulate` uses when none is given: without ``dt`` the adaptive
    :data:`ADAPTIVE_DEFAULT`, with ``dt`` the default of the model's kind."""
    if dt is None:
        return ADAPTIVE_DEFAULT
    return KINDS[CONTACTS if model.contacts else SMOOTH].default_method


def lane_of(method: Method, kind: Kind) -> Lane:
    """The lane that runs ``method`` on ``kind``; the refusal names the methods that can."""
    for lane in LANES.values():
        if method.name in lane.methods and kind.name in lane.kinds:
            return lane
    runs = next(lane for lane in LANES.values() if method.name in lane.methods)
    choices = [m for lane in LANES.values() if kind.name in lane.kinds for m in lane.methods]
    named = ", ".join(f"{m!r}" + (" (default)" if m == kind.default_method else "") for m in dict.fromkeys(choices))
    raise InputError(
        f"method {method.name!r} runs {runs.description}, which cannot {kind.task}: {kind.description} needs "
        f"{kind.needs}; use {named}"
    )


def _lanes_running(method: Method) -> list[Lane]:
    return [lane for lane in LANES.values() if method.name in lane.methods]


def check_solver(method: Method, solver: str, backend: str | None, lane: str | None = None) -> tuple[Lane, ...]:
    """The lanes that can run ``method`` with ``solver`` and ``backend``, fastest first (only ``lane`` if one is
    named): the rules that hold for every kind of model (checked before the state). Refused when no lane that
    runs smooth models can take them, with the fastest one's reason."""
    solvers.check_solver(solver, backend)
    running = _named(method, lane)
    refusals = {one.name: _refusal(one, method, solver, backend) for one in running}
    if all(refusals.values()):  # no kind of model could run: the reason of the fastest lane for smooth models
        smooth = [one for one in running if SMOOTH in one.kinds] or running
        raise InputError(refusals[smooth[0].name])
    return tuple(one for one in running if not refusals[one.name])


def _named(method: Method, lane: str | None) -> list[Lane]:
    """The lanes that run ``method``, fastest first; only ``lane`` if it is named (and runs it)."""
    running = _lanes_running(method)
    if lane is None:
        return running
    if lane not in LANES:
        raise UnknownNameError(f"lane={lane!r} is unknown; use one of {list(LANES)} or leave it unset")
    if lane not in [one.name for one in running]:
        raise InputError(
            f"lane={lane!r} does not run method {method.name!r}; it runs {', '.join(map(repr, LANES[lane].methods))}"
            f" — or leave lane unset (method {method.name!r} runs in {', '.join(one.name for one in running)})"
        )
    return [LANES[lane]]


def _refusal(lane: Lane, method: Method, solver: str, backend: str | None) -> str:
    """Why ``lane`` cannot run ``method`` with ``solver`` and ``backend`` (empty if it can)."""
    if solver not in lane.solvers:
        return f"method={method.name!r} needs solver={' or '.join(map(repr, lane.solvers))}: {lane.solver_reason}"
    if lane.qp_in_graph and solver == "qp":
        try:
            in_graph = qp.get(backend).compiled
        except GaussppError as exc:  # unknown or not installed: said so by the lane that runs it, or here
            return str(exc)
        if not in_graph:
            return graph_backend_error(lane, backend)
    return ""


def graph_backend_error(lane: Lane, backend: str | None) -> str:
    """Why a lane that runs the step inside the casadi graph cannot take ``backend``."""
    return (
        f"the {lane.name} lane needs the step inside the casadi graph: use solver='direct' or a casadi QP "
        f"backend (casadi:qrqp, casadi:daqp, casadi:osqp, ...), not {backend!r}"
    )


def check_kind(method: Method, kind: Kind, solver: str, project: bool, among: tuple[Lane, ...] | None = None) -> Lane:
    """The fastest lane (of ``among``, by default every lane) that runs ``method`` on ``kind`` with ``solver`` (and
    projection if ``project``), or a clear refusal."""
    if solver not in kind.solvers:
        raise InputError(
            f"solver={solver!r} cannot step {kind.description}; use solver={' or '.join(map(repr, kind.solvers))}"
        )
    among = tuple(_lanes_running(method)) if among is None else among
    fits = [lane for lane in among if kind.name in lane.kinds]
    if not fits:
        for lane in _lanes_running(method):  # a lane for this kind that refuses the solver says why
            if kind.name in lane.kinds and (reason := _refusal(lane, method, solver, None)):
                raise InputError(reason)
        other = lane_of(method, kind)  # refuses, naming the methods that can, unless another lane runs it
        raise InputError(
            f"the {' or '.join(lane.name for lane in among)} lane cannot run method {method.name!r} on "
            f"{kind.description}; the {other.name} lane can: pass lane={other.name!r} or leave lane unset"
        )
    for lane in fits:
        if lane.project or not project:
            return lane
    raise InputError(
        f"stabilize='project' is not supported by method={method.name!r} on {kind.description} "
        f"({fits[0].no_project_reason}); use stabilize='baumgarte' or None"
    )


def accepts(
    method: Method, solver: str, backend: str | None = None, kind: str = SMOOTH, lane: str | None = None
) -> bool:
    """Whether ``method`` with ``solver`` (and QP ``backend``; in ``lane`` if named) can run a model of ``kind`` —
    for front ends that list the combinations they try (the work-precision study, the command line)."""
    try:
        check_kind(method, KINDS[kind], solver, False, check_solver(method, solver, backend, lane))
    except GaussppError:  # refused, or the backend is unknown or not installed here
        return False
    return True


def default_solver(method: Method, kind: str = SMOOTH) -> str:
    """The step solver to use with ``method`` when none is given: ``"qp"`` where the lane takes it."""
    lane = lane_of(method, KINDS[kind])
    return next(s for s in SOLVERS if s in lane.solvers and s in KINDS[kind].solvers)


def fitting(lanes: tuple[Lane, ...], every_step_fits: bool) -> tuple[Lane, ...]:
    """``lanes`` without those that keep every step, when every step's state would not fit in memory (unless
    no other lane is left: the caller refuses the run then)."""
    if every_step_fits:
        return lanes
    thinning = tuple(lane for lane in lanes if not lane.keeps_every_step)
    return thinning or lanes
