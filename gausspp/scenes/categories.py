"""What kind of problem a scene is, computed from the scene it builds (not listed by hand).

At the scene's initial state, in this order:

* ``robot`` — a robot read from URDF (:class:`~gausspp.model.urdf.URDFMechanism`): built only with the robots
  extra, and stepped by the solver its parameters name;
* ``general`` — the direct formula does not apply, only the general Gauss QP steps it: the lane kind
  (:func:`gausspp.simulation.lanes.kind_of`) is contacts, or general (bounded actuators, rows dependent at the
  start, by the rank of ``J``); or the step's unknowns do not match its rows (over-actuated: more reaction
  columns than constraints); or the scene says its motion passes singular positions
  (:attr:`~gausspp.scenes.scene.Scene.singular_positions`);
* ``servo`` — ``J A⁻¹ D`` is singular with ``J`` of full rank: the actuators reach the constraint only through
  higher derivatives (index > 3), no one-step solution steps it; index reduction does;
* ``equality`` — the rest: a square equality system, the direct formula steps it (the lane kind ``smooth``).

A scene that cannot be built here (a missing optional extra) is ``unavailable``. The categories are computed once
per process, on first use.
"""

from __future__ import annotations

import functools

import numpy as np

from ..errors import GaussppError
from .scene import Scene

#: The categories, in the order the rules above try them.
CATEGORIES = ("robot", "general", "servo", "equality", "unavailable")
#: Relative rank tolerance of ``J`` and ``J A⁻¹ D`` at the initial state.
RANK_TOL = 1e-9


def category_of(scene: Scene) -> str:
    """The category of a built scene (module docstring)."""
    from ..model.urdf import URDFMechanism  # imported here: listing the scenes loads no lane table
    from ..simulation import lanes

    model = scene.model
    if isinstance(model.mechanism, URDFMechanism):
        return "robot"
    if lanes.kind_of(model).name != lanes.SMOOTH or scene.singular_positions:
        return "general"
    data = model.step_data(0.0, scene.q0, scene.v0, scene.lam0)
    k, columns = data.J.shape[0], data.D.shape[1]
    if _rank(data.J) < k or columns != k:
        return "general"
    if _rank(data.J @ np.linalg.solve(data.A, data.D)) < k:
        return "servo"
    return "equality"


def _rank(M: np.ndarray) -> int:
    return int(np.linalg.matrix_rank(M, tol=RANK_TOL * max(1.0, float(np.abs(M).max(initial=0.0)))))


@functools.cache
def category(name: str) -> str:
    """The category of the registered scene ``name``, built with its defaults (cached)."""
    from . import get  # the registry: this module sits below it

    try:
        scene = get(name)
    except GaussppError:
        return "unavailable"
    return category_of(scene)
