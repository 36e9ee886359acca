"""What each scene's parameters mean: the "Parameters" section of its builder's docstring, read.

Every scene documents each keyword of its ``build`` in numpydoc form, one entry a parameter::

    m1 : float
        Mass of the first body (kg). Allowed: > 0.

first the meaning, then the unit in parentheses (``(-)`` for a pure number, a name or a flag), then ``Allowed:``
and the values the scene accepts. A range the scene does not enforce says "not checked". :func:`describe` reads
the entries for ``gausspp scenes NAME``; :func:`problems` lists what a builder leaves undocumented (the tests run
it on every scene).
"""

from __future__ import annotations

import inspect
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..errors import UnknownNameError
from . import _builder, names, parameters

#: A section title's underline.
_RULE = re.compile(r"-{3,}")
#: An entry's first line: ``name : type`` (numpydoc also allows ``a, b : type`` and a bare name).
_ENTRY = re.compile(r"(?P<names>\w+(?:\s*,\s*\w+)*)\s*(?::\s*(?P<kind>.*))?")
#: The unit: the last parenthesized group, at the end of the text before ``Allowed:``.
_UNIT = re.compile(r"(?P<meaning>.*?)\s*\((?P<unit>[^()]*)\)[.;,]?", re.DOTALL)
_ALLOWED = "Allowed:"


@dataclass(frozen=True)
class ParameterDoc:
    """One parameter of a scene, as its builder documents it.

    Attributes
    ----------
    kind : str
        The type as the docstring gives it (``"float"``, ``"(3,) array_like or None"``); empty if not given.
    default : Any
        The default value (from the builder's signature; ``inspect.Parameter.empty`` if none).
    meaning : str
        What the parameter is (reST markup kept).
    unit : str
        Its unit, ``"-"`` for a dimensionless parameter; empty if not given.
    allowed : str
        The values the scene accepts (``"> 0"``, ``"one of 'ideal', 'servo'"``); empty if not given.
    """

    kind: str
    default: Any
    meaning: str
    unit: str
    allowed: str


def source(name: str) -> Callable[..., Any]:
    """The function whose signature and docstring hold scene ``name``'s parameters: its builder, or the module's
    ``build`` behind a ``build(law=..., **params)`` wrapper (as :func:`gausspp.scenes.parameters` reads them)."""
    if not isinstance(name, str) or name not in names():
        raise UnknownNameError(f"scene {name!r} is unknown; available: {names()}")
    builder = _builder(name)
    if any(p.kind is p.VAR_KEYWORD for p in inspect.signature(builder).parameters.values()):
        base = getattr(sys.modules[builder.__module__], "build", None)
        if base is not None:
            return base
    return builder


def _sections(doc: str) -> list[tuple[str, int, int]]:
    """The numpydoc sections of ``doc`` (cleaned): ``(title, first line of the title, end line)``."""
    lines = doc.splitlines()
    starts = [
        i
        for i in range(len(lines) - 1)
        if lines[i].strip() and not lines[i][0].isspace() and _RULE.fullmatch(lines[i + 1].strip())
    ]
    ends = starts[1:] + [len(lines)] if starts else []
    return [(lines[i].strip(), i, end) for i, end in zip(starts, ends, strict=True)]


def entries(doc: str | None) -> dict[str, tuple[str, str]]:
    """The "Parameters" section of the docstring ``doc``: name → (type, description on one line)."""
    doc = inspect.cleandoc(doc or "")
    lines = doc.splitlines()
    found: dict[str, tuple[str, str]] = {}
    for title, start, end in _sections(doc):
        if title != "Parameters":
            continue
        current: list[str] = []
        for line in lines[start + 2 : end]:
            entry = _ENTRY.fullmatch(line.strip()) if line.strip() and not line[0].isspace() else None
            if entry:
                current = [n.strip() for n in entry["names"].split(",")]
                for key in current:
                    found[key] = ((entry["kind"] or "").strip(), "")
            elif line.strip() and current:
                for key in current:
                    kind, text = found[key]
                    found[key] = (kind, f"{text} {line.strip()}".strip())
    return found


def split(description: str) -> tuple[str, str, str]:
    """A description ``"Meaning (unit). Allowed: values."`` as ``(meaning, unit, allowed)``; a part that is
    missing comes back empty."""
    text = " ".join(description.split())
    head, found, allowed = text.rpartition(_ALLOWED)
    if not found:
        head, allowed = text, ""
    unit = _UNIT.fullmatch(head.strip())
    meaning, unit_text = (unit["meaning"], unit["unit"].strip()) if unit else (head.strip(), "")
    return meaning.strip().rstrip(",;").strip(), unit_text, allowed.strip().removesuffix(".").strip()


def _keywords(func: Callable[..., Any]) -> dict[str, inspect.Parameter]:
    kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    return {k: p for k, p in inspect.signature(func).parameters.items() if p.kind in kinds}


def documented(func: Callable[..., Any]) -> dict[str, ParameterDoc]:
    """Every parameter that ``func``'s docstring documents, with its default from ``func``'s signature."""
    signature = _keywords(func)
    docs = {}
    for key, (kind, description) in entries(func.__doc__).items():
        default = signature[key].default if key in signature else inspect.Parameter.empty
        docs[key] = ParameterDoc(kind, default, *split(description))
    return docs


def describe(name: str) -> dict[str, ParameterDoc]:
    """Scene ``name``'s parameters in its builder's order (those ``gausspp run NAME --param`` takes), each with its
    type, default, meaning, unit and allowed values. An undocumented parameter comes back with empty texts.

    Raises
    ------
    UnknownNameError
        No scene is called ``name``.
    """
    docs = documented(source(name))
    out = {}
    for key, param in parameters(name).items():
        doc = docs.get(key)
        if doc is None:
            kind = "" if param.annotation is inspect.Parameter.empty else str(param.annotation)
            doc = ParameterDoc(kind, param.default, "", "", "")
        out[key] = doc
    return out


def without_parameters(doc: str | None) -> str:
    """The docstring ``doc`` (cleaned) without its "Parameters" section: what a listing shows above the table."""
    doc = inspect.cleandoc(doc or "")
    lines = doc.splitlines()
    for title, start, end in reversed(_sections(doc)):
        if title == "Parameters":
            del lines[start:end]
    return "\n".join(lines).strip()


def problems(func: Callable[..., Any]) -> list[str]:
    """What ``func``'s docstring leaves out: a keyword not documented, an entry that is no keyword, and an entry
    without a meaning, a unit (``(-)`` if none) or allowed values. Empty if every parameter is documented."""
    signature, docs = _keywords(func), documented(func)
    where = getattr(func, "__qualname__", repr(func))
    found = [f"{where}: {key} is not documented" for key in signature if key not in docs]
    found += [f"{where}: {key} is documented but is no parameter" for key in docs if key not in signature]
    for key, doc in docs.items():
        for part in ("meaning", "unit", "allowed"):
            if not getattr(doc, part):
                found.append(f"{where}: {key} has no {part}")
    return found
