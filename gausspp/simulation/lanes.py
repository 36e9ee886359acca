"""Which integrator lane takes which method, step solver, QP backend and kind of model — declared once, as data.

A *lane* is a way of running the step over time (:data:`LANES`): fixed steps from Python, scipy's
``OdeSolver`` classes, the whole run as one casadi graph (compiled RK4, CVODES), or the event-driven
runs of models with unilateral contacts. A *kind* of model (:data:`KINDS`) says which step it has:
the compiled equality step, the general Gauss QP (bounded actuators, redundant rows), or contact
phases. :func:`gausspp.simulate` consults these tables and nothing else; every refusal is built from
them, so a rule is changed in one place. Front ends (the command line, the studies) ask
:func:`accepts` and :func:`default_solver` instead of repeating a rule.

To add a lane: add a :class:`Lane` row here (its methods, kinds, solvers and abilities) and a runner
in :mod:`gausspp.simulation.simulate`'s dispatch table.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import GaussppError, InputError, UnknownNameError
from ..model.model import Model
from ..step import qp
from .methods import Method

#: The step solvers :func:`gausspp.simulate` knows.
SOLVERS = ("qp", "direct")


@dataclass(frozen=True)
class Kind:
    """A kind of model, by the step it has."""

    name: str
    #: What the kind is, as a message names it ("a model with ...").
    description: str
    #: The step solvers that can step it.
    solvers: tuple[str, ...]
    #: The method when none is given.
    default_method: str
    #: What an integrator must do for it (used when a method cannot): a verb phrase and what it needs.
    task: str = ""
    needs: str = ""


@dataclass(frozen=True)
class Lane:
    """An integrator lane and what it can take."""

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
            needs="the general Gauss QP at every step, from Python",
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
            "python",
            "fixed steps from Python",
            ("rk4", "symplectic-euler"),
            (SMOOTH, GENERAL),
            SOLVERS,
            progress=True,
        ),
        Lane("scipy", "scipy's OdeSolver", _SCIPY, (SMOOTH, GENERAL), SOLVERS),
        Lane(
            "compiled",
            "the compiled step (the whole run as one casadi graph)",
            ("rk4-compiled",),
            (SMOOTH,),
            SOLVERS,
            qp_in_graph=True,
            keeps_every_step=True,
        ),
        Lane(
            "cvodes",
            "the compiled step through SUNDIALS CVODES",
            ("cvodes",),
            (SMOOTH,),
            ("direct",),
            solver_reason="CVODES differentiates the right-hand side",
            qp_in_graph=True,
            project=False,
            no_project_reason="it cannot project between its internal steps",
        ),
        Lane(
            "events",
            "event-driven phases",
            _SCIPY,
            (CONTACTS,),
            SOLVERS,
            project=False,
            no_project_reason="contact phases are not projected",
        ),
    )
}

#: The general QP's pair of refusals that is no lane's business: contacts and bounds in one model.
CONTACTS_WITH_BOUNDS = "unilateral contacts together with bounded actuators are not supported"


def kind_of(model: Model, redundant: bool = False) -> Kind:
    """The kind of ``model`` (``redundant``: its rows are dependent at the start)."""
    if model.contacts:
        if model.bounded:
            raise InputError(CONTACTS_WITH_BOUNDS)
        return KINDS[CONTACTS]
    return KINDS[GENERAL] if model.bounded or redundant else KINDS[SMOOTH]


def default_method(model: Model) -> str:
    """The method :func:`gausspp.simulate` uses when none is given."""
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


def check_solver(method: Method, solver: str, backend: str | None) -> None:
    """The rules on ``solver`` and ``backend`` that hold for every kind of model (checked before the state)."""
    if solver not in SOLVERS:
        raise UnknownNameError(f"solver={solver!r} is unknown; use {' or '.join(map(repr, SOLVERS))}")
    if solver == "direct" and backend is not None:
        raise InputError(f"backend={backend!r} applies to solver='qp' only")
    for lane in _lanes_running(method):
        if SMOOTH not in lane.kinds:
            continue
        if solver not in lane.solvers:
            raise InputError(
                f"method={method.name!r} needs solver={' or '.join(map(repr, lane.solvers))}: {lane.solver_reason}"
            )
        if lane.qp_in_graph and solver == "qp" and not qp.get(backend).compiled:
            raise InputError(graph_backend_error(lane, backend))


def graph_backend_error(lane: Lane, backend: str | None) -> str:
    """Why a lane that runs the step inside the casadi graph cannot take ``backend``."""
    return (
        f"the {lane.name} lane needs the step inside the casadi graph: use solver='direct' or a casadi QP "
        f"backend (casadi:qrqp, casadi:daqp, casadi:osqp, ...), not {backend!r}"
    )


def check_kind(method: Method, kind: Kind, solver: str, project: bool) -> Lane:
    """The lane for ``method`` on ``kind`` with ``solver`` (and projection if ``project``), or a clear refusal."""
    if solver not in kind.solvers:
        raise InputError(
            f"solver={solver!r} cannot step {kind.description}; use solver={' or '.join(map(repr, kind.solvers))}"
        )
    lane = lane_of(method, kind)
    if project and not lane.project:
        raise InputError(
            f"stabilize='project' is not supported by method={method.name!r} on {kind.description} "
            f"({lane.no_project_reason}); use stabilize='baumgarte' or None"
        )
    return lane


def accepts(method: Method, solver: str, backend: str | None = None, kind: str = SMOOTH) -> bool:
    """Whether ``method`` with ``solver`` (and QP ``backend``) can run a model of ``kind`` — for front ends that
    list the combinations they try (the work-precision study, the command line)."""
    try:
        check_solver(method, solver, backend)
        lane = lane_of(method, KINDS[kind])
    except GaussppError:  # refused, or the backend is unknown or not installed here
        return False
    return solver in KINDS[kind].solvers and solver in lane.solvers


def default_solver(method: Method, kind: str = SMOOTH) -> str:
    """The step solver to use with ``method`` when none is given: ``"qp"`` where the lane takes it."""
    lane = lane_of(method, KINDS[kind])
    return next(s for s in SOLVERS if s in lane.solvers and s in KINDS[kind].solvers)


def progress_shown(method: Method) -> bool:
    """Whether a long run of ``method`` reports its progress on standard error."""
    return any(lane.progress for lane in _lanes_running(method))


def keeps_every_step(method: Method) -> bool:
    """Whether ``method`` keeps the state of every step (the compiled RK4 run)."""
    return any(lane.keeps_every_step for lane in _lanes_running(method))
