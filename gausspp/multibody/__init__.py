"""Multibody systems as bodies and joints in maximal coordinates (:class:`Multibody`), and MuJoCo's MJCF read into
them (:func:`~gausspp.multibody.mjcf.from_mjcf`)."""

from .system import Multibody

__all__ = ["Multibody"]
