"""Scenes built once per process: what a sweep's task uses so that a worker compiles each model once."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import numpy as np

from .. import scenes


def _freeze(value: Any) -> Any:
    if isinstance(value, Mapping):
        return tuple(sorted((k, _freeze(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple, np.ndarray)):
        return tuple(_freeze(v) for v in value)
    return value


def _thaw(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


@functools.lru_cache(maxsize=32)
def scene(name: str, frozen: tuple[tuple[str, Any], ...]) -> Any:
    return scenes.get(name, **{k: _thaw(v) for k, v in frozen})


def cached_scene(name: str, **params: Any) -> Any:
    """``gausspp.scenes.get(name, **params)``, built once per process and reused (an LRU cache of 32).

    Task functions call this instead of building the model themselves: a worker then compiles each
    distinct model once, however many tasks it runs. Parameter lists are frozen into tuples for the cache.
    """
    return scene(name, _freeze(params))
