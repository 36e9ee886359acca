"""The result of a sweep: parameters, results and errors in task order, as columns and as NPZ.

Parameters and results are stored and compared as canonical JSON text (:func:`canonical_json`), so a
resumed sweep equals an uninterrupted one; :class:`SweepResult` reads columns from them and writes NPZ.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import GaussppError, InputError

__all__ = ["SweepError", "SweepResult", "canonical_json"]


class SweepError(GaussppError):
    """A sweep cannot run as asked (e.g. its ``out`` file holds another sweep)."""


def canonical_json(obj: Any, what: str) -> str:
    """The JSON text of ``obj`` with sorted keys: how parameters and results are stored and compared."""
    try:
        return json.dumps(obj, sort_keys=True, default=_plain)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be JSON-serializable (numbers, strings, lists, dicts): {exc}") from None


def _plain(obj: Any) -> Any:
    """numpy scalars and arrays as Python numbers and lists (json's ``default`` hook)."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} {obj!r} is not JSON-serializable")


# -- columns --------------------------------------------------------------------------------------------
_MISSING = object()


def _numeric(values: list[Any]) -> np.ndarray | None:
    """Values (``_MISSING`` where absent) as one float array ``(N, *shape)``, NaN where absent; None if
    the present values are not numbers or arrays of one shape."""
    present = [v for v in values if v is not _MISSING]
    if any(isinstance(v, (str, bytes, Mapping)) for v in present):
        return None
    try:
        arrays = [np.asarray(v, dtype=float) for v in present]
    except (TypeError, ValueError):
        return None
    shapes = {a.shape for a in arrays}
    if len(shapes) > 1:
        return None
    shape = shapes.pop() if shapes else ()
    out = np.full((len(values), *shape), np.nan)
    it = iter(arrays)
    for i, v in enumerate(values):
        if v is not _MISSING:
            out[i] = next(it)
    return out


def _column_array(values: list[Any]) -> np.ndarray:
    """The best NPZ array for one column: int or bool if complete, float (NaN where absent), str, or JSON text."""
    present = [v for v in values if v is not _MISSING]
    complete = len(present) == len(values) and len(values) > 0
    if complete and all(isinstance(v, bool) for v in present):
        return np.array(present, dtype=bool)
    if complete and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        try:
            return np.array(present, dtype=np.int64)
        except OverflowError:
            pass
    if present and all(isinstance(v, str) for v in present):
        return np.array(["" if v is _MISSING else v for v in values], dtype=str)
    numeric = _numeric(values)
    if numeric is not None:
        return numeric
    return np.array(["" if v is _MISSING else canonical_json(v, "a value") for v in values], dtype=str)


def _keys(dicts: Iterable[Mapping[str, Any] | None]) -> list[str]:
    return list(dict.fromkeys(k for d in dicts if d is not None for k in d))


# -- the result ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepResult:
    """A finished sweep, in task order.

    Attributes
    ----------
    params : list of dict
        The parameters of every task.
    results : list of (dict or None)
        Each task's result (after a JSON round trip, so a resumed sweep equals an uninterrupted one),
        ``None`` where the task failed.
    errors : dict int → str
        Task index → the error text (exception type, message and the last traceback line) of failed tasks.
    wall_time : float
        Seconds for this call (tasks taken from ``out`` cost nothing).
    computed : int
        Tasks computed by this call; the others were read back from ``out``.
    """

    params: list[dict[str, Any]]
    results: list[dict[str, Any] | None]
    errors: dict[int, str]
    wall_time: float
    computed: int

    @property
    def tasks_per_second(self) -> float:
        """Throughput of this call: tasks computed per second of wall time."""
        return self.computed / self.wall_time if self.wall_time > 0 else math.inf

    @property
    def ok(self) -> bool:
        """True if no task failed."""
        return not self.errors

    def column(self, key: str) -> np.ndarray:
        """``result[key]`` of every task as a float array, NaN where the task failed or lacks ``key``.

        Scalars give shape ``(N,)``; lists of one shape ``s`` (e.g. a final state) give ``(N, *s)``.
        """
        values = [_MISSING if r is None else r.get(key, _MISSING) for r in self.results]
        known = _keys(self.results)
        if known and key not in known:  # a typo (if every task failed, the column is all NaN)
            raise SweepError(f"no task's result has {key!r}; the results have {known}")
        out = _numeric(values)
        if out is None:
            raise SweepError(f"result {key!r} is not a number (or an array of one shape) in every task")
        return out

    def param(self, key: str) -> np.ndarray:
        """``params[key]`` of every task as an array (float, NaN where absent; or str)."""
        if not any(key in p for p in self.params):
            raise SweepError(f"no task has the parameter {key!r}; the parameters are {_keys(self.params)}")
        return _column_array([p.get(key, _MISSING) for p in self.params])

    def __len__(self) -> int:
        return len(self.params)

    # -- NPZ --------------------------------------------------------------------------------------------
    def to_npz(self, path: str | os.PathLike[str], overwrite: bool = False) -> Path:
        """Write the sweep as NPZ columns, one array per parameter and per result key.

        Arrays: ``index``; ``ok`` (bool) and ``error`` (the error text, ``""`` where the task succeeded);
        ``params.<key>`` and ``results.<key>`` for every key — int or bool where complete, float with NaN
        where a task lacks the value or failed, ``(N, *shape)`` for lists of one shape, str for strings, the
        JSON text otherwise; ``record`` (the whole sweep as JSON, for :meth:`from_npz`). Loads with
        ``numpy.load(path)`` (no pickle). Written whole or not at all (a temporary name, then renamed); a file at
        ``path`` that is not a sweep written here is replaced only with ``overwrite=True``.
        """
        target = Path(path)
        if target.exists() and not overwrite and not is_sweep_npz(target):
            raise SweepError(
                f"{str(target)!r} exists and is not a sweep written by SweepResult.to_npz: choose another name, or "
                "pass overwrite=True to replace it"
            )
        arrays: dict[str, np.ndarray] = {
            "index": np.arange(len(self), dtype=np.int64),
            "ok": np.array([i not in self.errors for i in range(len(self))], dtype=bool),
            "error": np.array([self.errors.get(i, "") for i in range(len(self))], dtype=str),
        }
        for key in _keys(self.params):
            arrays[f"params.{key}"] = _column_array([p.get(key, _MISSING) for p in self.params])
        for key in _keys(self.results):
            arrays[f"results.{key}"] = _column_array(
                [_MISSING if r is None else r.get(key, _MISSING) for r in self.results]
            )
        record = {
            "params": self.params,
            "results": self.results,
            "errors": {str(i): e for i, e in self.errors.items()},
            "wall_time": self.wall_time,
            "computed": self.computed,
        }
        arrays["record"] = np.array(canonical_json(record, "the sweep"))
        partial = target.with_name(f".{target.name}.{os.getpid()}.part")  # whole or not at all
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            with partial.open("wb") as fh:
                np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]
            os.replace(partial, target)
        except OSError as exc:
            raise SweepError(f"cannot write {str(target)!r}: {exc}") from None
        finally:
            partial.unlink(missing_ok=True)
        return target

    @classmethod
    def from_npz(cls, path: str | os.PathLike[str]) -> SweepResult:
        """The sweep written by :meth:`to_npz`, exactly (params, results, errors)."""
        try:
            with np.load(Path(path), allow_pickle=False) as data:
                text = str(data["record"][()])
        except (OSError, ValueError) as exc:
            raise SweepError(f"cannot read {str(path)!r} as an NPZ file: {exc}") from None
        except KeyError:
            raise SweepError(f"{str(path)!r} is not a sweep written by SweepResult.to_npz (no 'record')") from None
        rec = json.loads(text)
        return cls(
            params=rec["params"],
            results=rec["results"],
            errors={int(i): e for i, e in rec["errors"].items()},
            wall_time=float(rec["wall_time"]),
            computed=int(rec["computed"]),
        )


def is_sweep_npz(path: Path) -> bool:
    """Whether ``path`` holds a sweep written by :meth:`SweepResult.to_npz` (its ``record`` and ``index``)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            return "record" in data.files and "index" in data.files
    except Exception:  # noqa: BLE001 — anything numpy cannot read as an archive is not one
        return False
