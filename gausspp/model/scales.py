"""The scales a model declares where its numbers cannot tell them (docs/guide.md, "The scales of a run").

A run reads every scale it judges by from the machine itself (:mod:`gausspp.model.run_scales`); a model may name
the size of some of its components instead, e.g. a coordinate that starts at zero but will move far.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, ShapeError


@dataclass(frozen=True)
class Scales:
    """The scales a model declares where its numbers cannot tell them (docs/guide.md, "The scales of a run").

    Parameters
    ----------
    q : sequence of nq floats, optional
        The size of each coordinate's motion, in its own units (a length for a position, radians for an angle):
        an adaptive run follows each coordinate to ``rtol`` of it, and the constraint rows' residuals are judged
        against ``|∂g/∂q|`` times it. ``None`` (an entry, or the whole): derived from the initial state.
    v : sequence of nv floats, optional
        The size of each velocity component, the same way.
    """

    q: Sequence[float | None] | None = None
    v: Sequence[float | None] | None = None

    def checked(self, nq: int, nv: int) -> Scales:
        """The declaration with each given entry a positive finite number, of the model's sizes."""
        return Scales(_declared("q", self.q, nq), _declared("v", self.v, nv))


def _declared(name: str, values: Any, size: int) -> tuple[float | None, ...] | None:
    if values is None:
        return None
    try:
        items = list(values)
    except TypeError:
        raise InputError(
            f"Scales({name}=...): give a sequence of {size} sizes (None to derive one), got {values!r}"
        ) from None
    if len(items) != size:
        raise ShapeError(f"Scales({name}=...): the model has {size} components, got {len(items)} sizes")
    out: list[float | None] = []
    for i, item in enumerate(items):
        if item is None:
            out.append(None)
            continue
        try:
            value = float(item)
        except (TypeError, ValueError):
            raise InputError(f"Scales({name}=...): entry {i} must be a number or None, got {item!r}") from None
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"Scales({name}=...): entry {i} must be a positive finite size, got {item!r}")
        out.append(value)
    return tuple(out)


def check_scales(scales: Any, nq: int, nv: int) -> Scales | None:
    """``gp.Model(..., scales=)``: ``None``, a :class:`Scales` or a dict of its fields, checked against the sizes."""
    if scales is None:
        return None
    if isinstance(scales, dict):
        unknown = set(scales) - {"q", "v"}
        if unknown:
            raise InputError(f"scales: unknown keys {sorted(unknown)}; give q= and/or v= (sizes of the components)")
        scales = Scales(**scales)
    if not isinstance(scales, Scales):
        raise InputError(f"scales must be gp.Scales(q=..., v=...) or a dict of them, got {scales!r}")
    return scales.checked(nq, nv)
