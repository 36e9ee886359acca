"""The Scene record (a model with its initial data, horizon and exact solution if known), and the check of
every scene's parameters."""

from __future__ import annotations

import ast
import inspect
import sys
import textwrap
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError, UnknownNameError
from ..model.model import Model
from ..naming import numbered, velocity_name, velocity_names  # noqa: F401  (the scenes name their results with them)
from ..validation import number


@dataclass(frozen=True)
class Scene:
    """A reference problem ready to step or simulate.

    Attributes
    ----------
    name : str
    model : Model
    q0, v0 : arrays
        Initial configuration and velocity (on the constraint).
    lam0 : array or None
        Initial ``λ`` for realizations that carry it.
    t_end : float
        Suggested horizon.
    exact : callable ``t -> (q, v)`` or None
        The exact motion where one is known.
    description : str
        One line for listings.
    params : dict
        The parameters the scene was built with.
    forces : callable ``t -> (m,) array`` or None
        The exact actuator forces ``λ(t)`` along :attr:`exact` where they are known (the servo scenes).
    drawing : callable ``q -> dict`` or None
        What to draw of the mechanism at ``q`` in the plane (:func:`gausspp.plot.animate`): ``"segments"`` (pairs
        of points), ``"points"`` (bodies), ``"fixed"`` (pins), ``"path"`` (a prescribed path, ``(K, 2)``),
        ``"reaction"`` (``(point, (i, j))``: the arrow ``(R[i], R[j])`` of the generalized reaction at ``point``).
    coordinates : tuple of str or None
        The name and unit of each coordinate ``q_i``, e.g. ``("x (m)", "z (m)", "θ (rad)")``: the labels of the
        figures (``gausspp run SCENE --out DIR`` draws ``q(t)`` with them). ``len(coordinates) == nq``.
    velocities : tuple of str or None
        The name and unit of each velocity ``v_i``, given only where ``v`` is not ``q̇`` (a rigid body's
        quaternion and ``ω``); otherwise :attr:`velocity_names` derives them from :attr:`coordinates`.
    singular_positions : bool
        The motion passes positions where the constraint rows become dependent (a parallelogram's collinear
        bars): a fact of the motion, not of the initial state, so the scene says it; only the general Gauss
        step runs it through them (:func:`gausspp.scenes.category`).
    """

    name: str
    model: Model
    q0: np.ndarray
    v0: np.ndarray
    lam0: np.ndarray | None
    t_end: float
    exact: Callable[[float], tuple[np.ndarray, np.ndarray]] | None
    description: str
    params: dict[str, Any] = field(default_factory=dict)
    forces: Callable[[float], np.ndarray] | None = None
    drawing: Callable[[np.ndarray], dict[str, Any]] | None = None
    coordinates: tuple[str, ...] | None = None
    velocities: tuple[str, ...] | None = None
    singular_positions: bool = False

    @property
    def velocity_names(self) -> tuple[str, ...] | None:
        """The velocities' names and units: :attr:`velocities` if given, else those of :attr:`coordinates` dotted
        (:func:`velocity_names`), else None."""
        if self.velocities is not None:
            return self.velocities
        return velocity_names(self.coordinates) if self.coordinates is not None else None


# -- parameters: every scene's, checked by type in one place ---------------------------------------
#: Annotations checked here; a parameter annotated otherwise (``Any``: vectors, tensors) is checked by its scene.
_SIMPLE = {"float", "int", "str", "bool", "None"}


def parameters(builder: Callable[..., Scene]) -> dict[str, inspect.Parameter]:
    """The keyword parameters of a scene builder (those of its module's ``build`` behind a ``**params`` wrapper,
    without the keywords the wrapper passes itself, as ``build(law="rate", **params)`` does)."""
    sig, fixed = inspect.signature(builder), set()
    if any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values()):
        base = getattr(sys.modules[builder.__module__], "build", None)
        if base is not None and base is not builder:
            sig = inspect.signature(base)
            try:
                tree = ast.parse(textwrap.dedent(inspect.getsource(builder)))
                fixed = {kw.arg for kw in ast.walk(tree) if isinstance(kw, ast.keyword) and kw.arg}
            except (OSError, TypeError, SyntaxError):
                pass
    return {
        k: p
        for k, p in sig.parameters.items()
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and k not in fixed
    }


def kinds(param: inspect.Parameter) -> set[str]:
    """The parameter's type as a set of names (``"float | None"`` → {"float", "None"}); from the default if bare."""
    ann = param.annotation
    if ann is inspect.Parameter.empty:
        default = param.default
        return {type(default).__name__} if isinstance(default, (bool, int, float, str)) else set()
    text = ann if isinstance(ann, str) else getattr(ann, "__name__", str(ann))
    return {part.strip() for part in text.split("|")}


def check_parameters(
    scene: str, known: dict[str, inspect.Parameter], params: dict[str, Any], infinite_ok: Collection[str] = ()
) -> dict[str, Any]:
    """``params`` checked against the builder's parameters ``known``: names, and the types of those annotated
    ``float``, ``int``, ``str``, ``bool`` (or ``… | None``); numbers come back as ``float``/``int``, finite
    unless named in ``infinite_ok`` (a bound that may be absent), never NaN.

    Raises
    ------
    UnknownNameError
        A parameter the scene does not have (the message lists those it has).
    InputError, ShapeError, NonFiniteError
        A value of the wrong type (a string for a number, a vector for a scalar), or NaN/inf.
    """
    checked = {}
    for key, value in params.items():
        if key not in known:
            raise UnknownNameError(f"scene {scene!r} has no parameter {key!r}; its parameters: {', '.join(known)}")
        checked[key] = _typed(scene, key, value, kinds(known[key]), key in infinite_ok)
    if checked.get("t_end") is not None and not checked["t_end"] > 0:
        raise InputError(f"scene {scene!r}: t_end must be positive, got {params['t_end']!r}")
    return checked


def _typed(scene: str, key: str, value: Any, kind: set[str], infinite_ok: bool) -> Any:
    if not kind or not kind <= _SIMPLE or (value is None and "None" in kind):
        return value
    words = {"float": "a finite number", "int": "an integer", "str": "a string", "bool": "True or False"}
    words["None"] = "None"
    if infinite_ok:
        words["float"] = "a number"
    wanted = " or ".join(words[k] for k in words if k in kind and not (k == "int" and "float" in kind))
    where = f"scene {scene!r}: {key} must be {wanted}, got {value!r}"
    if "float" in kind or "int" in kind:
        return number(where, value, integer="float" not in kind, infinite_ok=infinite_ok)
    if "str" in kind and isinstance(value, str):
        return value
    if "bool" in kind and isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise InputError(where)
