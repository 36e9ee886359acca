"""What every part of the MJCF loader reads and writes: the compiled model, its names, the caller's choices, and the
problems found (all listed at once at the end)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .reader import Names, disabled


@dataclass
class Loading:
    mj: Any
    m: Any
    choices: dict[str, Any]
    problems: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.names = Names(self.mj, self.m)

    def problem(self, text: str) -> None:
        self.problems.append(text)

    def disabled(self, *flags: str) -> bool:
        return disabled(self.mj, self.m, *flags)
