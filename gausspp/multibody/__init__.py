"""Multibody systems as bodies and joints in maximal coordinates (:class:`Multibody`)."""

from .system import Multibody

__all__ = ["Multibody"]
