"""The run log of a sweep: a JSON-lines file, appended as tasks finish, read back to resume.

Its first line names the task; every other line is one task's record (index, parameters, and result or
error text). :func:`resume` reads what is recorded, :func:`open_log` opens the file for appending and
:class:`Collector` takes each finished chunk into the results, the log and the progress bar.
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from ..errors import SweepLogWarning
from .sweep_engine import Progress
from .sweep_result import SweepError, canonical_json, is_sweep_npz

__all__ = ["Collector", "log_paths", "open_log", "resume"]


def log_paths(out: str | os.PathLike[str] | None) -> tuple[Path | None, Path | None]:
    """(JSON-lines log, NPZ file or None) for ``out``."""
    if out is None:
        return None, None
    path = Path(out)
    if path.suffix.lower() in (".parquet", ".pq"):
        raise SweepError(f"out={str(path)!r}: Parquet is not supported (it needs pyarrow); use a .npz or .jsonl file")
    if path.suffix.lower() == ".npz":
        log, npz = path.with_suffix(".jsonl"), path
    else:
        log, npz = path, None
    for target, is_ours in ((log, _is_sweep_log), (npz, is_sweep_npz)):
        if target is not None and target.is_dir():
            raise SweepError(f"out={str(out)!r}: {str(target)!r} is a directory; give a file name (.jsonl or .npz)")
        if target is not None and target.exists() and not is_ours(target):
            raise SweepError(
                f"out={str(out)!r}: {str(target)!r} exists and is not a sweep's output; a sweep never writes over "
                "another file — choose another out, or move that file"
            )
    return log, npz


def _is_sweep_log(path: Path) -> bool:
    """An empty file, or one whose first line names a sweep's task (what :func:`open_log` writes)."""
    if path.is_dir():
        return False
    try:
        with path.open(encoding="utf-8") as fh:
            first = fh.readline()
    except (OSError, UnicodeDecodeError):
        return False
    if not first.strip():
        return path.stat().st_size == 0
    try:
        head = json.loads(first)
    except ValueError:
        return False
    return isinstance(head, dict) and "task" in head and "index" not in head


def resume(
    path: Path | None, keys: list[str], name: str, retry_failed: bool
) -> tuple[list[dict[str, Any] | None], dict[int, str], list[int]]:
    """The results and errors already recorded in ``path`` (in task order), and the tasks still to run."""
    results: list[dict[str, Any] | None] = [None] * len(keys)
    errors: dict[int, str] = {}
    recorded = read_log(path, keys, name) if path is not None else {}
    for index, (result, error) in recorded.items():
        if error is not None and retry_failed:
            continue
        results[index] = result
        if error is not None:
            errors[index] = error
    todo = [i for i in range(len(keys)) if i not in recorded or (retry_failed and recorded[i][1] is not None)]
    return results, errors, todo


def open_log(path: Path | None, name: str) -> TextIO | None:
    """The JSON-lines log opened for appending (its first line names the task), a partial last line cut off."""
    if path is None:
        return None
    blocking = next((p for p in path.parents if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise SweepError(
            f"cannot write out={str(path)!r}: {str(blocking)!r} is a file, not a folder; choose a path in a folder"
        )
    if path.is_dir():
        raise SweepError(
            f"cannot write out={str(path)!r}: it is a folder; give a file name (JSON lines, e.g. sweep.jsonl)"
        )
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        _cut_partial_line(path)  # a kill's partial last record must not swallow the next one
        sink = path.open("a", encoding="utf-8")
    except OSError as exc:
        raise SweepError(f"cannot write out={str(path)!r}: {exc}") from None
    if sink.tell() == 0:
        sink.write(canonical_json({"task": name}, "the task's name") + "\n")
    sink.flush()
    return sink


@dataclass
class Collector:
    """Takes each finished chunk: into ``results`` and ``errors``, appended to the log, counted by the bar."""

    plist: list[dict[str, Any]]
    results: list[dict[str, Any] | None]
    errors: dict[int, str]
    sink: TextIO | None
    bar: Progress

    def __call__(self, batch: list[tuple[int, str | None, str | None]]) -> None:
        for index, result_json, error in batch:
            result = json.loads(result_json) if result_json is not None else None
            self.results[index] = result
            if error is not None:
                self.errors[index] = error
            else:
                self.errors.pop(index, None)
            if self.sink is not None:
                record = {"index": index, "params": self.plist[index]}
                record.update({"error": error} if error is not None else {"result": result})
                self.sink.write(canonical_json(record, "record") + "\n")
        if self.sink is not None:
            self.sink.flush()  # in the OS's hands: survives a kill of this process
        self.bar.update(len(batch), sum(e is not None for _, _, e in batch))


def read_log(path: Path, keys: list[str], task: str) -> dict[int, tuple[dict[str, Any] | None, str | None]]:
    """Records already in ``path``.

    An unterminated last line is the record a kill cut short: it is ignored (and cut off before the sweep
    appends, :func:`open_log`). Any other line that is not a record (not JSON, no ``index``) is skipped
    with a :class:`~gausspp.SweepLogWarning` naming the file and the line: its task, if it had one, runs
    again, and the rest of the log is kept — resuming should not throw away good results because one line
    was damaged. Blank lines are skipped silently.
    """
    done: dict[int, tuple[dict[str, Any] | None, str | None]] = {}
    if not path.exists():
        return done
    try:
        fh = path.open(encoding="utf-8")
    except OSError as exc:
        raise SweepError(f"cannot read out={str(path)!r}: {exc}") from None
    with fh:
        for lineno, line in enumerate(fh, 1):
            if not line.strip() or not line.endswith("\n"):
                continue  # blank, or the partial last record of a killed sweep
            try:
                rec = json.loads(line)
                if isinstance(rec, dict) and "task" in rec and "index" not in rec:
                    if rec["task"] != task:
                        raise SweepError(
                            f"out={str(path)!r} holds a sweep of task {rec['task']!r}, not {task!r}: "
                            "use another out file or delete it"
                        )
                    continue
                index = int(rec["index"])
            except (ValueError, KeyError, TypeError, IndexError, OverflowError):
                warnings.warn(
                    f"out={str(path)!r} line {lineno} is not a record of this sweep ({line.strip()[:60]!r}); it is "
                    "skipped and its task, if it had one, runs again — delete the line to silence this",
                    SweepLogWarning,
                    stacklevel=3,
                )
                continue
            if not 0 <= index < len(keys) or canonical_json(rec.get("params"), "params") != keys[index]:
                raise SweepError(
                    f"out={str(path)!r} line {lineno} records task {index} with other parameters than this sweep "
                    f"({rec.get('params')!r}); it holds another sweep: use another out file or delete it"
                )
            done[index] = (rec.get("result"), rec.get("error"))
    return done


def _cut_partial_line(path: Path) -> None:
    """Cut off an unterminated last line (a record a kill cut short; :func:`read_log` ignored it)."""
    if not path.exists():
        return
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with path.open("rb+") as fh:
            fh.truncate(data.rfind(b"\n") + 1)
