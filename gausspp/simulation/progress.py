"""Progress of a long run on standard error: how far it is, and how long it still needs (a tqdm bar).

A run of more than :data:`gausspp.simulate.LONG_RUN_STEPS` fixed steps is announced up front
(:class:`~gausspp.LongRunWarning`); while the Python lane steps it, a bar like
``gausspp.simulate (rk4): 37% (3700000 of 1e+07 steps), about 00:52 left |███▋      |`` is redrawn in
place every few seconds on a terminal, and cleared at the end. Not on a terminal (a log, a pipe), or
with ``enabled=False``, nothing is drawn.
"""

from __future__ import annotations

import sys
from typing import TextIO

from tqdm import tqdm

#: The bar's text: the fraction done, the steps, the time left, then the bar.
FORMAT = "{desc}: {percentage:.0f}% ({n:.3g} of {total:.3g} steps), about {remaining} left |{bar}|"


def is_terminal(stream: TextIO) -> bool:
    """Whether ``stream`` is a terminal (the bar is drawn there only)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class Progress:
    """Report ``done`` out of ``total`` steps at most every ``every`` seconds, on ``stream`` (standard error) when
    it is a terminal; ``enabled=False``: silent.

    :meth:`update` costs one clock read; call it every few hundred steps.
    """

    def __init__(self, total: int, label: str, *, enabled: bool, every: float = 2.0, stream: TextIO | None = None):
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled and is_terminal(self.stream)
        self.bar = tqdm(
            total=total,
            desc=label,
            file=self.stream,
            mininterval=every,
            miniters=1,
            disable=not self.enabled,
            bar_format=FORMAT,
            leave=True,
        )

    def update(self, done: int) -> None:
        """``done`` steps of ``total`` are taken."""
        if self.enabled and done > self.bar.n:
            self.bar.update(done - self.bar.n)

    def close(self) -> None:
        """End the bar (a newline, so that what follows starts clean)."""
        self.bar.close()
