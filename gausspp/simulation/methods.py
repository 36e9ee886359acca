"""Integration methods: a registry of names with their declared order.

Which lane runs a method is decided by :mod:`gausspp.simulation.lanes` (the one table of lanes); the lanes
run the same right-hand side (the step of docs/theory.md §2–3 plus kinematics):

* ``python`` — fixed-step schemes stepped from Python, one compiled step call per stage;
* ``scipy`` — scipy's adaptive and stiff ``OdeSolver`` classes (RK45, DOP853, Radau, BDF), the
  step as right-hand side;
* ``compiled`` — the whole right-hand side is one casadi graph: RK4 over the whole run in a
  single ``mapaccum`` call, or CVODES (BDF) on the direct-path right-hand side.

Runge–Kutta methods are coefficient data (:class:`Tableau`), used by the Python and the
compiled lanes alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import UnknownNameError


@dataclass(frozen=True)
class Tableau:
    """An explicit Runge–Kutta method: ``c``, ``A`` (strictly lower triangular), ``b``."""

    c: tuple[float, ...]
    A: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]


RK4 = Tableau(
    c=(0.0, 0.5, 0.5, 1.0),
    A=((), (0.5,), (0.0, 0.5), (0.0, 0.0, 1.0)),
    b=(1 / 6, 1 / 3, 1 / 3, 1 / 6),
)


@dataclass(frozen=True)
class Method:
    """An integration method.

    Attributes
    ----------
    name : str
    order : int
        Declared order of convergence in the step size, measured with the step imposed (``dt``
        with loose tolerances for adaptive methods) — the test suite fits it for every method.
        Variable-order BDF codes (scipy's BDF, CVODES) do not raise their order when the step is
        imposed, so they declare 1; with their own step control they behave as tolerance-
        proportional methods.
    adaptive : bool
        True if the step size is chosen by an error estimate (``rtol``, ``atol``).
    description : str
    tableau : Tableau or None
        For explicit Runge–Kutta methods.
    iterates : bool
        True if each step solves its stages by iteration (Newton or functional): the iteration cannot converge
        below the round-off of the right-hand side times its conditioning, so its absolute tolerance keeps a floor
        of ``rtol`` times the machine's size (:meth:`gausspp.model.run_scales.RunScales.atol`).
    """

    name: str
    order: int
    adaptive: bool
    description: str
    tableau: Tableau | None = None
    iterates: bool = False


METHODS: dict[str, Method] = {
    m.name: m
    for m in (
        Method("rk4", 4, False, "classical Runge–Kutta, fixed step", RK4),
        Method(
            "symplectic-euler",
            1,
            False,
            "semi-implicit Euler: v first, then q with the new v; symplectic for ideal holonomic systems",
        ),
        Method("RK45", 5, True, "scipy Dormand–Prince 5(4), adaptive"),
        Method("DOP853", 8, True, "scipy Dormand–Prince 8(5,3), adaptive"),
        Method("Radau", 5, True, "scipy Radau IIA, implicit, stiff", iterates=True),
        Method(
            "BDF", 1, True, "scipy variable-order BDF, stiff; stays at order 1 when the step is imposed", iterates=True
        ),
        Method(
            "cvodes",
            1,
            True,
            "SUNDIALS CVODES variable-order BDF via casadi (direct path); stays at order 1 when the step is imposed",
            iterates=True,
        ),
        Method(
            "cvodes-adams",
            1,
            True,
            "SUNDIALS CVODES variable-order (1–12) Adams–Moulton via casadi, functional iteration (non-stiff; no "
            "Jacobian); stays at order 1 when the step is imposed",
            iterates=True,
        ),
    )
}


#: Names that were methods and are not: what to write instead. ``"rk4-compiled"`` named a lane, not an integrator
#: (RK4 run as one casadi graph): ``method="rk4"`` runs there wherever it can, and ``lane="compiled"`` insists.
RETIRED = {"rk4-compiled": "write method='rk4' (it runs compiled wherever it can), with lane='compiled' to insist"}


def get(name: str | Method) -> Method:
    """The method for ``name`` (or an instance unchanged); unknown names list the valid ones."""
    if isinstance(name, Method):
        return name
    if name in RETIRED:
        raise UnknownNameError(f"method={name!r} is gone: {RETIRED[name]}")
    if name not in METHODS:
        raise UnknownNameError(f"method={name!r} is unknown; valid methods: {list(METHODS)}")
    return METHODS[name]


def names() -> list[str]:
    """Every method name."""
    return list(METHODS)


def rk_step(tableau: Tableau, f, t: float, y: np.ndarray, h: float) -> np.ndarray:  # type: ignore[no-untyped-def]
    """One explicit Runge–Kutta step ``y(t) → y(t + h)`` of ``y' = f(t, y)`` (numpy)."""
    stages: list[np.ndarray] = []
    for c, row in zip(tableau.c, tableau.A, strict=True):
        yi = y + h * sum((a * k for a, k in zip(row, stages, strict=False) if a), np.zeros_like(y))
        stages.append(f(t + c * h, yi))
    return y + h * sum((b * k for b, k in zip(tableau.b, stages, strict=True) if b), np.zeros_like(y))
