"""Scene parameters on the command line: ``--param KEY=VALUE`` checked against the scene builder's signature."""

from __future__ import annotations

import ast
import inspect
from collections.abc import Sequence
from typing import Any

from .. import scenes
from ..errors import GaussppError
from ..scenes.scene import kinds as parameter_kinds
from ..studies.tables import label, one_line
from .console import UsageError


def _number(option: str, key: str, text: str, value: Any, kinds: set[str]) -> Any:
    """``value`` as the int or float ``kinds`` asks for (``None`` if allowed); a UsageError otherwise."""
    if value is None and "None" in kinds:
        return None
    if isinstance(value, str):
        try:
            value = float(value)  # inf, nan
        except ValueError:
            pass
    wanted = "an integer" if "float" not in kinds else "a number"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise UsageError(
            f"{option} {key}={text}: {key} must be {wanted}"
            + (" or None" if "None" in kinds else "")
            + f", got {text!r}"
        )
    if "float" not in kinds:
        if not float(value).is_integer():
            raise UsageError(f"{option} {key}={text}: {key} must be an integer, got {text!r}")
        return int(value)
    return float(value)


def parse_value(option: str, key: str, text: str, param: inspect.Parameter) -> Any:
    """``text`` as a Python literal (number, tuple, None, …), a plain string otherwise; checked against the type."""
    try:
        value: Any = ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        value = text
    kinds = parameter_kinds(param)
    if kinds == {"str"}:
        return value if isinstance(value, str) else text
    if kinds & {"float", "int"}:
        return _number(option, key, text, value, kinds)
    return value


def parse_params(scene: str, items: Sequence[str] | None, option: str = "--param") -> dict[str, Any]:
    """``["k=v", ...]`` → keyword arguments of the scene's builder (names and value types checked)."""
    known = scenes.parameters(scene)
    params: dict[str, Any] = {}
    for item in items or []:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"{option} {item!r}: expected KEY=VALUE, e.g. {option} t_end=2")
        if key not in known:
            raise UsageError(
                f"{option} {key}: scene {scene!r} has no parameter {key!r}; its parameters: {', '.join(known)}"
            )
        params[key] = parse_value(option, key, text.strip(), known[key])
    return params


def build(name: str, params: dict[str, Any]) -> scenes.Scene:
    """The scene ``name`` built with ``params``; a value its builder cannot use is a GaussppError."""
    try:
        return scenes.get(name, **params)
    except GaussppError:
        raise
    except (TypeError, ValueError) as exc:  # a value the builder could not use, not caught by the library
        raise GaussppError(f"scene {label(name, params)}: {one_line(exc)}") from exc
