"""A URDF file made readable for adam-robotics: what URDF allows and its parser trips on, and its chatter kept quiet.

URDF lets a ``<joint>`` or an ``<inertial>`` omit its ``<origin>`` (the identity pose) and an ``<origin>`` omit
``xyz`` or ``rpy`` (zeros); adam-robotics 0.5.0 then fails on ``None.xyz``. Materials with a ``<texture>`` without
``filename``, ``<transmission>`` and ``<gazebo>`` elements (simulator and drive descriptions, not dynamics) make
``urdf_parser_py`` raise or complain; a joint's axis a few 1e-7 from unit length (as exported by CAD tools) scales the
joint's rate in adam, where URDF means a direction. :func:`clean_urdf` writes each missing origin out, drops the
elements the dynamics do not read, makes each axis of unit length, and returns the XML text that adam is given;
:func:`quiet` keeps ``urdf_parser_py``'s "Unknown tag" lines off the user's screen (a real parse error still raises).
"""

from __future__ import annotations

import contextlib
import xml.etree.ElementTree as ET
from collections.abc import Iterator

import numpy as np

#: Elements of ``<robot>`` that the dynamics do not read (and ``urdf_parser_py`` may not parse).
DROPPED = ("transmission", "gazebo")


def clean_urdf(path: str) -> str:
    """The URDF at ``path`` as XML text with every joint's and inertial's origin written out, materials without
    textures and no ``<transmission>``/``<gazebo>`` element (module docstring)."""
    tree = ET.parse(path)
    root = tree.getroot()
    for kind in DROPPED:
        for element in root.findall(kind):
            root.remove(element)
    for material in root.iter("material"):
        for texture in material.findall("texture"):
            material.remove(texture)
    for parent in (
        *root.findall("joint"),
        *(inertial for link in root.iter("link") for inertial in link.findall("inertial")),
    ):
        origin = parent.find("origin")
        if origin is None:
            origin = ET.SubElement(parent, "origin")
        origin.set("xyz", origin.get("xyz") or "0 0 0")
        origin.set("rpy", origin.get("rpy") or "0 0 0")
    for axis in (a for joint in root.findall("joint") for a in joint.findall("axis")):
        _unit(axis)
    return ET.tostring(root, encoding="unicode")


def _unit(axis: ET.Element) -> None:
    """A joint's axis of unit length, as URDF means it (and Pinocchio reads it): adam-robotics 0.5.0 takes the
    numbers as written, and a file's ``0.0401398 -0.155542 0.987014`` (length 1 + 5e-7) scales that joint's rate."""
    try:
        e = np.array([float(x) for x in (axis.get("xyz") or "1 0 0").split()])
    except ValueError:
        return  # the parser's own error names it
    size = float(np.linalg.norm(e)) if e.shape == (3,) else 0.0
    if size > 0:
        axis.set("xyz", " ".join(repr(float(x)) for x in e / size))


@contextlib.contextmanager
def quiet() -> Iterator[list[str]]:
    """Collect ``urdf_parser_py``'s warnings (unknown tags, …) instead of printing them; yields the list."""
    from urdf_parser_py.xml_reflection import core

    said: list[str] = []
    saved = core.on_error
    core.on_error = said.append
    try:
        yield said
    finally:
        core.on_error = saved
