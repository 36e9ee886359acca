"""A trajectory as labelled data, and on disk: ``xarray.Dataset``, ``pandas.DataFrame``, ``.npz`` and ``.nc``.

Every recorded array becomes a variable over ``time`` and the axes of :data:`~gausspp.simulation.labels.DIMS`,
named by the trajectory's :class:`~gausspp.simulation.labels.Labels`; the run's settings (method, solver,
lane, route, status, message, steps …) are attributes. xarray and pandas are the optional extra
``gausspp[data]``, imported only when a labelled view or a netCDF file is asked for; ``.npz`` needs numpy only.

A file written by :func:`save` reads back (:func:`read`) into the same arrays, so that a run can be verified
later (:func:`gausspp.verify`) or by another tool.
"""

from __future__ import annotations

import importlib
import json
import os
from collections.abc import Collection
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import GaussppError, InputError
from .labels import DIMS, MEANING, UNITS, Labels

#: Marks a file written by :func:`save` (and the version of its layout).
FORMAT = "gausspp-trajectory 1"
#: The run's settings, kept as attributes.
SETTINGS = ("status", "message", "method", "solver", "lane", "route", "steps", "rhs_evaluations")
_LABEL_KEY = "label_"


def require(module: str) -> Any:
    """Import ``module`` of the ``data`` extra, or say how to install it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise GaussppError(f"labelled results need {module}: pip install 'gausspp[data]' (xarray and pandas)") from None


def arrays(traj: Any) -> dict[str, np.ndarray]:
    """The recorded arrays of ``traj``, each ``(N,)`` or ``(N, n)`` (an empty default becomes ``(N, 0)``);
    a scalar series that was not recorded (wrong length) is left out."""
    n, out = len(traj.t), {}
    for key, dims in DIMS.items():
        arr = np.asarray(getattr(traj, key))
        if dims and arr.size == 0:
            arr = arr.reshape(n, 0)
        if arr.shape[:1] == (n,):
            out[key] = arr
    return out


def settings(traj: Any) -> dict[str, Any]:
    """The run's settings and events as attributes (numbers and strings only)."""
    out: dict[str, Any] = {"format": FORMAT}
    for key in SETTINGS:
        value = getattr(traj, key, "")
        out[key] = int(value) if isinstance(value, (int, np.integer)) else str(value)
    out["events"] = json.dumps(list(getattr(traj, "events", ())), default=_plain)
    return out


def _plain(x: Any) -> Any:
    """A JSON-able form of a number or array in an event."""
    return x.tolist() if isinstance(x, (np.ndarray, np.generic)) else repr(x)


def energy_balance(traj: Any) -> np.ndarray:
    """``ΔE − ΔW_reaction − ΔW_forces`` at every sample (empty for an empty trajectory)."""
    return traj.energy_balance() if len(traj.t) else np.zeros(0)


def to_xarray(traj: Any, attrs: dict[str, Any] | None = None) -> Any:
    """``traj`` as an ``xarray.Dataset``: dims ``time`` × ``coordinate``/``velocity``/``lam_state``/``unknown``/``row``/
    ``contact_row`` with the names as coordinates, one variable per recorded array (and ``energy_balance``),
    the run's settings and ``attrs`` as attributes."""
    xr = require("xarray")
    labels = traj.labels.complete(traj)
    data = {key: (("time", *DIMS[key]), arr, _var_attrs(key)) for key, arr in arrays(traj).items()}
    data["energy_balance"] = (("time",), energy_balance(traj), _var_attrs("energy_balance"))
    coords = {"time": ("time", np.asarray(traj.t), _var_attrs("t"))}
    coords.update({axis: (axis, np.asarray(names, dtype=str)) for axis, names in labels.as_dict().items()})
    unnamed = " ".join(axis for axis, names in traj.labels.as_dict().items() if names != getattr(labels, axis))
    return xr.Dataset(data, coords=coords, attrs={**settings(traj), "unnamed_axes": unnamed, **(attrs or {})})


def _var_attrs(key: str) -> dict[str, str]:
    return {"long_name": MEANING[key], **({"units": UNITS[key]} if key in UNITS else {})}


def to_pandas(traj: Any) -> Any:
    """``traj`` as a ``pandas.DataFrame`` indexed by time: columns ``q[name]``, ``v[name]``, ``u[name]``,
    ``residual[row]`` … for arrays along an axis, ``margin``, ``energy`` … for series; settings in ``.attrs``."""
    pd = require("pandas")
    names = traj.labels.complete(traj).as_dict()
    columns: dict[str, np.ndarray] = {}
    for key, arr in arrays(traj).items():
        if arr.ndim == 1:
            columns[key] = arr
        else:
            columns.update({f"{key}[{name}]": arr[:, j] for j, name in enumerate(names[DIMS[key][0]])})
    columns["energy_balance"] = energy_balance(traj)
    frame = pd.DataFrame(columns, index=pd.Index(np.asarray(traj.t), name="t"))
    frame.attrs.update(settings(traj))
    return frame


def save(traj: Any, path: str | os.PathLike[str], attrs: dict[str, Any] | None = None, overwrite: bool = False) -> Path:
    """Write ``traj`` to ``path``: ``.npz`` (numpy only) or ``.nc`` (netCDF through xarray), by its suffix;
    ``attrs`` (strings and numbers) are stored beside the settings. Returns the path.

    The file is written under a temporary name beside ``path`` and then renamed, so that a failure leaves no half
    file and an existing file is either replaced whole or untouched. A file already at ``path`` is replaced only if
    it is a trajectory written here, or with ``overwrite=True``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".nc"):
        raise InputError(f"path={str(path)!r}: a trajectory is saved as .npz or .nc (netCDF): use one of those")
    if not isinstance(overwrite, (bool, np.bool_)):
        raise InputError(f"overwrite must be True or False, got {overwrite!r}")
    attrs = _checked_attrs(traj, attrs)
    if suffix == ".nc" and len(traj.t) == 0:
        raise InputError(f"path={str(path)!r}: an empty trajectory cannot be written as netCDF; use a .npz file")
    if path.is_dir():
        raise InputError(f"path={str(path)!r} is a directory: give a file name ending in {suffix}")
    blocking = next((parent for parent in path.parents if parent.exists() and not parent.is_dir()), None)
    if blocking is not None:
        raise InputError(
            f"path={str(path)!r}: {str(blocking)!r} is a file, not a directory, so nothing can be written under it; "
            "choose a path in a directory"
        )
    if path.exists() and not overwrite and not is_trajectory_file(path):
        raise InputError(
            f"path={str(path)!r} exists and is not a trajectory written by Trajectory.save: choose another name, "
            "or pass overwrite=True to replace it"
        )
    partial = path.with_name(f".{path.name}.{os.getpid()}.part")
    try:
        if suffix == ".npz":
            _save_npz(traj, partial, attrs)
        else:
            _save_nc(traj, partial, attrs)
        os.replace(partial, path)
    except OSError as exc:
        raise GaussppError(f"cannot write {str(path)!r}: {exc.strerror or exc}") from exc
    finally:
        partial.unlink(missing_ok=True)
    return path


def _checked_attrs(traj: Any, attrs: Any) -> dict[str, Any]:
    """``attrs`` as stored: string keys that name none of the stored arrays and settings, values that are strings
    or finite numbers (what both formats keep and read back)."""
    if attrs is None:
        return {}
    if not isinstance(attrs, dict):
        raise InputError(f"attrs must be a dict of names to strings or numbers, got {type(attrs).__name__}")
    taken = {"t", "energy_balance", *DIMS, *settings(traj), *(_LABEL_KEY + axis for axis in Labels().as_dict())}
    for key, value in attrs.items():
        if not isinstance(key, str) or not key.isidentifier():
            raise InputError(f"attrs key {key!r} must be a name (letters, digits, underscores)")
        if key in taken:
            raise InputError(f"attrs key {key!r} is the name of a stored field or setting; choose another name")
        plain = isinstance(value, str) or (
            isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
        )
        if not plain or (not isinstance(value, str) and not np.isfinite(value)):
            raise InputError(f"attrs[{key!r}] = {value!r}: a stored attribute is a string or a finite number")
    return dict(attrs)


def is_trajectory_file(path: Path) -> bool:
    """Whether ``path`` holds a trajectory written by :func:`save` (its format mark), without raising."""
    try:
        if path.suffix.lower() == ".nc":
            xr = require("xarray")
            with xr.open_dataset(path) as ds:
                return bool(ds.attrs.get("format") == FORMAT)
        with np.load(path, allow_pickle=False) as data:
            return bool("format" in data.files and str(data["format"]) == FORMAT)
    except Exception:  # noqa: BLE001 — any file that does not read as one is not one
        return False


def _save_npz(traj: Any, path: Path, attrs: dict[str, Any]) -> None:
    """Every field array as it is, the labels as string arrays ``label_<axis>``, settings as 0-d arrays."""
    labels = {_LABEL_KEY + axis: np.asarray(names, dtype=str) for axis, names in traj.labels.as_dict().items()}
    fields = {key: np.asarray(getattr(traj, key)) for key in ("t", *DIMS)}
    stored: dict[str, Any] = {"energy_balance": energy_balance(traj), **fields, **labels, **settings(traj), **attrs}
    with open(path, "wb") as fh:  # a handle: numpy would append ".npz" to a name ending in ".NPZ"
        np.savez(fh, **stored)


def _save_nc(traj: Any, path: Path, attrs: dict[str, Any]) -> None:
    """The dataset of :func:`to_xarray` without its zero-width axes (netCDF 3 cannot hold them)."""
    ds = to_xarray(traj, attrs)
    empty = [dim for dim, size in ds.sizes.items() if size == 0]
    ds.drop_dims(empty).to_netcdf(path)


def read(path: str | os.PathLike[str], fields: Collection[str]) -> dict[str, Any]:
    """The trajectory fields (of ``fields``) stored in a file written by :func:`save`."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"path={str(path)!r}: no such file")
    if path.suffix.lower() == ".nc":
        return _read_nc(path, fields)
    try:
        loaded = np.load(path, allow_pickle=False)
        if not isinstance(loaded, np.lib.npyio.NpzFile):
            raise ValueError("it holds a single array (.npy), not an archive of arrays")
        with loaded as data:
            stored = {key: data[key] for key in data.files}
    except Exception as exc:  # noqa: BLE001 — truncated, empty, not a zip, a .npy array, pickled objects …
        raise InputError(
            f"path={str(path)!r} is not a readable trajectory file written by Trajectory.save: {_why(exc)} — "
            "expected the .npz archive (or .nc netCDF file) that Trajectory.save writes"
        ) from None
    if str(stored.get("format", "")) != FORMAT:
        raise InputError(f"path={str(path)!r} is not a trajectory written by Trajectory.save (no format {FORMAT!r})")
    axes = Labels().as_dict()
    labels = {axis: tuple(str(s) for s in stored.get(_LABEL_KEY + axis, ())) for axis in axes}
    out = {key: value for key, value in stored.items() if key in fields and key in DIMS or key == "t"}
    return {**out, **_settings_back(stored, fields), "labels": Labels(**labels)}


def _why(exc: Exception) -> str:
    """What is wrong with a file numpy could not read, in a user's words."""
    text = str(exc)
    if "pickle" in text:
        return "it is not a numpy archive (numpy read it as pickled Python objects: a text file or another format)"
    if isinstance(exc, EOFError) or "No data left" in text:
        return "it is empty"
    if "zip" in text.lower():
        return "it is not a numpy archive (truncated, or another kind of file)"
    return text or type(exc).__name__


def _settings_back(attrs: Any, fields: Collection[str]) -> dict[str, Any]:
    """Settings and events as the trajectory's fields."""
    out: dict[str, Any] = {}
    for key in SETTINGS:
        if key in attrs and key in fields:
            value = np.asarray(attrs[key]).item()
            out[key] = int(value) if key in ("steps", "rhs_evaluations") else str(value)
    if "events" in attrs:
        out["events"] = tuple(json.loads(str(np.asarray(attrs["events"]).item())))
    return out


def _read_nc(path: Path, fields: Collection[str]) -> dict[str, Any]:
    """The fields of a netCDF file written by :func:`save`; axes dropped for being empty come back ``(N, 0)``."""
    xr = require("xarray")
    try:
        ds = xr.load_dataset(path)
    except Exception:  # noqa: BLE001 — not netCDF, truncated, no engine can read it
        raise InputError(
            f"path={str(path)!r} is not a readable netCDF trajectory written by Trajectory.save: no netCDF reader "
            "recognizes it (not netCDF, or truncated)"
        ) from None
    if ds.attrs.get("format") != FORMAT:
        raise InputError(f"path={str(path)!r} is not a trajectory written by Trajectory.save (no format {FORMAT!r})")
    n = ds.sizes["time"]
    unnamed = str(ds.attrs.get("unnamed_axes", "")).split()
    names = {
        axis: tuple(str(s) for s in ds[axis].values) if axis in ds.coords and axis not in unnamed else ()
        for axis in Labels().as_dict()
    }
    out: dict[str, Any] = {"t": ds["time"].values}
    for key, dims in DIMS.items():
        if key in ds and key in fields:
            out[key] = ds[key].values
        elif dims and key in fields:
            out[key] = np.zeros((n, 0), dtype=bool if key == "saturated" else float)
    return {**out, **_settings_back(ds.attrs, fields), "labels": Labels(**names)}
