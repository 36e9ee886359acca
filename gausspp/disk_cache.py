"""Compiled casadi functions kept on disk between processes, keyed by everything they are built from.

Building a large model's compiled run (its step, the whole-run ``mapaccum``, the recording's mapped step) takes a
good part of a second per hundred bodies; loading the same functions from disk takes milliseconds. A function
is stored under a key made of

* the model's *fingerprint*: the serialized graph of its step data (``A, f, r₀, J, φ, D, Φ`` … of
  ``model.inputs``) and its options (``refine``, ``route``) — two models with the same equations share it,
  a changed equation or option gives another;
* the gausspp source and the casadi version (a new gausspp builds its graphs anew);
* what the function is (``("compiled-step", solver, backend, …)``).

The directory is ``$GAUSSPP_CACHE_DIR`` (default ``~/.cache/gausspp``); ``GAUSSPP_CACHE_DIR=off`` turns the cache off.
A file that cannot be read, or that is not the one stored for its key (its signature beside it, ``.key``, names the
key and the file's bytes: a valid function of another key copied over it is caught), is rebuilt and rewritten; a
function casadi cannot serialize is simply not stored;
files are written to a temporary name and renamed, so a process never loads a half-written one.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from collections.abc import Callable, Hashable
from pathlib import Path
from typing import Any

import casadi as ca

from .workspace import workspace

ENV = "GAUSSPP_CACHE_DIR"

#: How many functions this process loaded from disk, built and stored, built but could not store (diagnostics).
counts = {"loaded": 0, "built": 0, "not stored": 0}


def directory() -> Path | None:
    """Where the functions are kept (``None``: the cache is off)."""
    value = os.environ.get(ENV, "")
    if value.lower() in ("off", "0", "none", "false"):
        return None
    return Path(value).expanduser() if value else Path.home() / ".cache" / "gausspp"


@functools.cache
def source_hash() -> str:
    """A hash of gausspp's own source (every module) and casadi's version: a new gausspp builds anew."""
    digest = hashlib.sha256(str(ca.CasadiMeta.version()).encode())
    for path in sorted(Path(__file__).parent.rglob("*.py")):
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def fingerprint(model: Any) -> str:
    """The model's step data as a graph, serialized and hashed with its options (kept in its workspace)."""

    def compute() -> str:
        p = model.expressions
        fields = [getattr(p, name) for name in p.__dataclass_fields__]
        graph = ca.Function("model", model.inputs, [f for f in fields if isinstance(f, ca.SX)])
        digest = hashlib.sha256(graph.serialize().encode())
        digest.update(repr((model.refine, model.route, model.k, model.m, model.n_lam)).encode())
        return digest.hexdigest()[:24]

    return workspace(model).get(("disk fingerprint",), compute)


def cached_function(model: Any, what: Hashable, build: Callable[[], ca.Function]) -> ca.Function:
    """The function ``what`` of ``model`` from the disk cache, or ``build()`` and stored there."""
    folder = directory()
    if folder is None:
        return build()
    key = hashlib.sha256(repr((source_hash(), fingerprint(model), what)).encode()).hexdigest()
    path = folder / f"{key[:32]}.casadi"
    if path.exists() and _signed(path, key):
        try:
            fn = ca.Function.load(str(path))
        except RuntimeError:  # unreadable (another casadi, a damaged file): build it again below
            pass
        else:
            counts["loaded"] += 1
            return fn
    fn = build()
    counts["built" if _store(fn, path, key) else "not stored"] += 1
    return fn


def _signature(path: Path) -> Path:
    return path.with_suffix(".key")


def _signed(path: Path, key: str) -> bool:
    """Whether the file at ``path`` is the one stored for ``key``: its signature beside it names the key and the
    file's own bytes, so a file of another function copied or renamed over it (valid, but not this one) is
    rebuilt, never used."""
    try:
        stored = _signature(path).read_text().split()
        content = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return False
    return stored == [key, content]


def _store(fn: ca.Function, path: Path, key: str) -> bool:
    """Write ``fn`` to ``path`` (through a temporary file) and its signature beside it; whether it could."""
    partial: Path | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, suffix=".part", delete=False) as tmp:
            partial = Path(tmp.name)
        fn.save(str(partial))
        content = hashlib.sha256(partial.read_bytes()).hexdigest()
        os.replace(partial, path)
        partial = None
        with tempfile.NamedTemporaryFile("w", dir=path.parent, suffix=".part", delete=False) as tmp:
            tmp.write(f"{key} {content}\n")
            partial = Path(tmp.name)
        os.replace(partial, _signature(path))
    except (OSError, RuntimeError):  # read-only home, a plugin casadi cannot serialize: run without the cache
        if partial is not None:
            partial.unlink(missing_ok=True)
        return False
    return True
