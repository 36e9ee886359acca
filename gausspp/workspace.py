"""Compiled artefacts of a model, kept beside it — never inside it.

A :class:`~gausspp.Model` is what the user declared and does not change. Everything built from it on
demand — step kernels, bound casadi functions, projections, the models of a contact phase, compiled
integration runs — lives in the model's :class:`Workspace`, found by :func:`workspace`. Each layer
stores its artefacts under its own keys (a tuple whose first item names the artefact), so the step,
the simulation lanes and the verification never touch one another's entries, and no module writes
into another object's attributes.

The workspaces are held by a weak-keyed table: a model that is no longer referenced takes its
workspace with it.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Hashable
from typing import Any, TypeVar

T = TypeVar("T")


class Workspace:
    """The cache of one model: ``get(key, build)`` builds an artefact on first use and keeps it."""

    def __init__(self) -> None:
        self._items: dict[Hashable, Any] = {}

    def get(self, key: Hashable, build: Callable[[], T]) -> T:
        """The artefact stored under ``key``, built by ``build()`` (and kept) the first time."""
        try:
            return self._items[key]  # type: ignore[no-any-return]
        except KeyError:
            value = self._items[key] = build()
            return value

    def put(self, key: Hashable, value: T) -> T:
        """Store ``value`` under ``key`` (replacing an older one), and return it."""
        self._items[key] = value
        return value

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items

    def keys(self) -> list[Hashable]:
        """The keys stored so far, in the order they were built."""
        return list(self._items)

    def __len__(self) -> int:
        return len(self._items)


_WORKSPACES: weakref.WeakKeyDictionary[Any, Workspace] = weakref.WeakKeyDictionary()


def workspace(owner: Any) -> Workspace:
    """The workspace of ``owner`` (a model), created empty on first use."""
    try:
        return _WORKSPACES[owner]
    except KeyError:
        ws = _WORKSPACES[owner] = Workspace()
        return ws
