"""What a contact phase watches along its accepted steps, and where the first event lies.

A phase of the event-driven lane (:mod:`gausspp.simulation.events`) ends at the first of:

* an open contact's gap ``g`` reaching zero from above (it closes);
* an active contact's force reaching zero from above (it lets go).

A contact that has just separated starts *on* ``g = 0``: one long step could carry it up and back
below the floor with no sign change of ``g`` between the step's ends. Such a *departing* contact is
watched on its rate ``ġ`` until it turns round (its apex) and on ``g`` from then on — inside the
same phase: the apex is no event, only the moment the watch changes (it is located only in the rare
step that also brings the contact back below the floor).

Each accepted step is judged from its end values (one gap evaluation for all contacts; the forces
from the step's own last stage). A sign change is located on the solver's dense output: a gap by
Newton's method with the gap rate as its slope, safeguarded by the bracket (three or four
evaluations to round-off where bisection-type root finders take eight), a force or a rate by
Brent's method (:func:`scipy.optimize.brentq`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.optimize import brentq

from .contacts import off_the_start

#: Root-finding tolerance on the time, relative (as scipy's own event location).
EPS = 4 * np.finfo(float).eps

#: ``(t, y) → (gaps, gap rates)``, ``(t, y) → forces of the active contacts``.
Gaps = Callable[[float, np.ndarray], tuple[np.ndarray, np.ndarray]]
Forces = Callable[[float, np.ndarray], np.ndarray]


class StepDense:
    """The last accepted step's dense output, built on first use (DOP853's costs three more evaluations)."""

    def __init__(self, solver: Any) -> None:
        self.solver, self._dense = solver, None

    def __call__(self, s: float) -> np.ndarray:
        if self._dense is None:
            self._dense = self.solver.dense_output()
        return np.asarray(self._dense(s))


class PhaseWatch:
    """The event functions of one phase: gaps of the open contacts (rates of the departing ones), forces of the
    active ones; :meth:`first_event` judges each accepted step."""

    def __init__(
        self,
        t0: float,
        y0: np.ndarray,
        inactive: list[int],
        departing: set[int],
        n_active: int,
        gaps: Gaps,
        forces: Forces,
    ) -> None:
        self.t0, self.inactive, self.n_active = t0, inactive, n_active
        self.departing = set(departing) & set(inactive)
        self.gaps, self.forces = gaps, forces
        #: ``(t, g, ġ)`` at the last two step ends (the Hermite start of :meth:`_newton`)
        self.ends: list[tuple[float, np.ndarray, np.ndarray]] = []
        self.prev = self.values(t0, y0)

    def values(self, t: float, y: np.ndarray) -> np.ndarray:
        """Every event function at ``(t, y)`` (positive at the phase's start: :func:`off_the_start`)."""
        out = np.empty(len(self.inactive) + self.n_active)
        if self.inactive:
            g, gdot = self.gaps(t, y)
            self.ends.append((t, g, gdot))
            del self.ends[:-2]
            for j, i in enumerate(self.inactive):
                out[j] = off_the_start(float((gdot if i in self.departing else g)[i]), t, self.t0)
        if self.n_active:
            u = self.forces(t, y)
            for pos in range(self.n_active):
                out[len(self.inactive) + pos] = off_the_start(float(u[pos]), t, self.t0)
        return out

    def first_event(
        self, t_old: float, t_new: float, y_new: np.ndarray, dense: Callable[[float], np.ndarray]
    ) -> tuple[float, int] | None:
        """The first event in ``(t_old, t_new]`` as ``(time, index into inactive + active)``, or ``None``; departing
        contacts that turned round in the step are watched on their gaps from now on."""
        new = self.values(t_new, y_new)
        crossed = np.flatnonzero((self.prev >= 0) & (new <= 0))
        turned = [j for j in crossed if j < len(self.inactive) and self.inactive[j] in self.departing]
        found = [(self.locate(j, t_old, t_new, dense), int(j)) for j in crossed if j not in turned]
        first = min(found) if found else None
        for j in turned:  # its apex: from there the gap is what closes it
            i = self.inactive[j]
            g_new = float(self.gaps(t_new, y_new)[0][i])
            if g_new > 0 and first is None:
                self.departing.discard(i)
                new[j] = g_new
                continue
            t_apex = brentq(lambda s, i=i: self._value(s, dense, i, rate=True), t_old, t_new, xtol=EPS, rtol=EPS)
            if first is not None and t_apex >= first[0]:
                continue  # the phase ends before the apex: still departing at the next phase's start
            self.departing.discard(i)
            new[j] = g_new
            if g_new <= 0:  # up and back below the floor in one step
                t_hit = self._newton(i, t_apex, t_new, dense)
                first = min(first, (t_hit, int(j))) if first is not None else (t_hit, int(j))
        self.prev = new
        return first

    def locate(self, j: int, a: float, b: float, dense: Callable[[float], np.ndarray]) -> float:
        """The root of event function ``j`` in ``(a, b]``, where it falls from ≥ 0 to ≤ 0."""
        if j < len(self.inactive):
            return self._newton(self.inactive[j], a, b, dense)
        pos = j - len(self.inactive)

        def force(s: float) -> float:
            return off_the_start(float(self.forces(s, dense(s))[pos]), s, self.t0)

        return float(brentq(force, a, b, xtol=EPS, rtol=EPS))

    def _value(self, s: float, dense: Callable[[float], np.ndarray], i: int, rate: bool = False) -> float:
        g, gdot = self.gaps(s, dense(s))
        return off_the_start(float((gdot if rate else g)[i]), s, self.t0)

    def _newton(self, i: int, a: float, b: float, dense: Callable[[float], np.ndarray]) -> float:
        """Where contact ``i``'s gap reaches zero in ``(a, b]`` (``g(a) ≥ 0 ≥ g(b)``): Newton with the gap rate as the
        slope, from the root of the step's cubic Hermite interpolant of ``g`` (exact for a free flight), kept inside
        the shrinking bracket (a step that leaves it bisects)."""
        s = self._start(i, a, b)
        for _ in range(100):
            g, gdot = self.gaps(s, dense(s))
            f = off_the_start(float(g[i]), s, self.t0)
            if f > 0:
                a = s
            else:
                b = s
            if f == 0 or b - a <= EPS * max(abs(a), abs(b), 1.0):
                return b
            slope = float(gdot[i])
            s_next = s - f / slope if slope != 0 else np.inf
            if abs(s_next - s) <= EPS * max(abs(s), 1.0):  # converged (to round-off of the time)
                return min(max(s_next, a), b)
            s = s_next if a < s_next < b else 0.5 * (a + b)
        return b

    def _start(self, i: int, a: float, b: float) -> float:
        """The root in ``(a, b)`` of the cubic through ``g`` and ``ġ`` at the step's ends, if they bound this
        interval and the cubic has one there; else the middle."""
        if len(self.ends) == 2 and (self.ends[0][0], self.ends[1][0]) == (a, b):
            (_, ga, da), (_, gb, db) = self.ends
            h = b - a
            c2 = 3 * (gb[i] - ga[i]) - h * (2 * da[i] + db[i])
            c3 = 2 * (ga[i] - gb[i]) + h * (da[i] + db[i])
            hermite = np.polynomial.Polynomial([ga[i], h * da[i], c2, c3])  # in x = (s − a)/h on [0, 1]
            x = [r.real for r in hermite.roots() if abs(r.imag) <= 1e-12 and 0 < r.real < 1]
            if x:
                return a + h * min(x)
        return 0.5 * (a + b)
