"""Progress of a long run on standard error: how far it is, and how long it still needs.

A run of more than :data:`gausspp.simulate.LONG_RUN_STEPS` fixed steps is announced up front
(:class:`~gausspp.LongRunWarning`); while the Python lane steps it, a line like
``gausspp.simulate: 37% (3.7e+06 of 1e+07 steps), about 52 s left`` is rewritten in place every
few seconds, and cleared at the end.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """Report ``done`` out of ``total`` steps at most every ``every`` seconds (``enabled=False``: silent).

    :meth:`update` costs one clock read; call it every few hundred steps.
    """

    def __init__(self, total: int, label: str, *, enabled: bool, every: float = 2.0, stream: TextIO | None = None):
        self.total, self.label, self.enabled, self.every = total, label, enabled, every
        self.stream = stream if stream is not None else sys.stderr
        self.start = self.last = time.perf_counter()
        self.shown = False

    def update(self, done: int) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self.last < self.every or done <= 0:
            return
        self.last = now
        left = (now - self.start) / done * (self.total - done)
        self.stream.write(
            f"\r{self.label}: {100 * done / self.total:.0f}% ({done:.3g} of {self.total:.3g} steps), "
            f"about {_duration(left)} left "
        )
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        """End the progress line (a newline, so that what follows starts clean)."""
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()
            self.shown = False


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
