"""What the command line shows on stderr besides errors: exit codes, usage errors, progress, warnings."""

from __future__ import annotations

import sys
import threading
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import IO

from tqdm import tqdm

from ..errors import LongRunWarning
from ..studies.tables import one_line

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


class UsageError(Exception):
    """A command line that parses but cannot be meant (unknown parameter, value of the wrong type): exit 2."""


class Progress:
    """Elapsed time on stderr while a long call runs: a spinner line on a terminal, sparse lines otherwise.

    Nothing is shown for calls shorter than ``delay`` seconds. Calls into compiled code that hold
    the GIL pause the spinner; the elapsed time is right again when they return.
    """

    _FRAMES = "|/-\\"
    _LOG_AT = (2.0, 10.0, 30.0, 60.0)  # non-terminal: one line at these elapsed times, then every minute

    def __init__(self, label: str, enabled: bool = True, delay: float = 1.0) -> None:
        self.label, self.enabled, self.delay = label, enabled, delay
        self.shown = False
        self._done = threading.Event()
        self._thread: threading.Thread | None = None
        self._stream: IO[str] = sys.stderr

    def __enter__(self) -> Progress:
        if self.enabled:
            self._stream = sys.stderr
            self._start = time.perf_counter()
            self._thread = threading.Thread(target=self._loop, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        if self._thread is not None:
            self._thread.join()
        if self.shown:
            if self._tty():
                self._stream.write("\r\033[K")
            else:
                self._stream.write(f"gausspp: {self.label}: done in {time.perf_counter() - self._start:.1f} s\n")
            self._stream.flush()

    def _tty(self) -> bool:
        return is_terminal(self._stream)

    def _loop(self) -> None:
        if self._done.wait(self.delay):
            return
        tty, frame, marks = self._tty(), 0, list(self._LOG_AT)
        while not self._done.is_set():
            elapsed = time.perf_counter() - self._start
            if tty:
                self._stream.write(f"\r{self._FRAMES[frame % 4]} {self.label} … {elapsed:.1f} s")
                self._stream.flush()
                self.shown, frame = True, frame + 1
            elif elapsed >= marks[0]:
                self._stream.write(f"gausspp: {self.label} … {elapsed:.0f} s\n")
                self._stream.flush()
                self.shown = True
                marks = marks[1:] or [marks[0] + 60.0]
            self._done.wait(0.2)


def is_terminal(stream: IO[str]) -> bool:
    """Whether ``stream`` is a terminal (a bar is drawn there only)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class RowProgress:
    """Rows of a study as they finish: a line each on stderr, and a bar with the time left (tqdm) on a terminal.

    ``enabled=False`` (``--quiet``): neither. :meth:`emit` prints a line of the study's own output
    on stdout around the bar.
    """

    def __init__(self, total: int, label: str, enabled: bool = True) -> None:
        self.total, self.label, self.enabled, self.count = total, label, enabled, 0
        self.bar = tqdm(
            total=total,
            desc=label,
            unit="row",
            file=sys.stderr,
            leave=False,
            disable=not (enabled and is_terminal(sys.stderr)),
            bar_format="{desc}: {n}/{total} rows |{bar}| {elapsed} elapsed, about {remaining} left",
        )

    def done(self, what: str, seconds: float) -> None:
        """One more row finished: ``what`` it was and how long it took."""
        self.count += 1
        if self.enabled:
            self.bar.write(f"{self.label}: {self.count}/{self.total} {what} ({seconds:.1f} s)", file=sys.stderr)
        self.bar.update(1)

    def emit(self, line: str) -> None:
        """Print ``line`` on stdout (the bar, if any, is redrawn below it)."""
        self.bar.write(line, file=sys.stdout)

    def close(self) -> None:
        self.bar.close()


@contextmanager
def warnings_as_lines() -> Iterator[None]:
    """Show warnings raised inside as one line each on stderr (``gausspp: warning: ...``), once per message:
    a :class:`~gausspp.LongRunWarning` at once (it announces the wait), the others when the block ends."""
    caught: list[tuple[type[Warning], str]] = []
    seen: set[str] = set()

    def show(category: type[Warning], message: object) -> None:
        line = one_line(message)
        if line not in seen:
            seen.add(line)
            print(f"gausspp: warning: {category.__name__}: {line}", file=sys.stderr, flush=True)

    def collect(message: Warning | str, category: type[Warning], *_: object, **__: object) -> None:
        if issubclass(category, LongRunWarning):
            show(category, message)
        else:
            caught.append((category, str(message)))

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = collect
        try:
            yield
        finally:
            for category, message in caught:
                show(category, message)
