"""What the command line shows on stderr besides errors: exit codes, usage errors, progress, warnings."""

from __future__ import annotations

import sys
import threading
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import IO

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
        try:
            return bool(self._stream.isatty())
        except (AttributeError, ValueError):
            return False

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
