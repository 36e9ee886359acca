"""Where MuJoCo's model collections are: ``$GAUSSPP_MJCF_ZOO``, else ``../shared/mjcf-zoo`` beside the repository,
else ``/work/shared/mjcf-zoo`` (this machine's copy, which a fresh clone elsewhere also finds)."""

from __future__ import annotations

import os
from pathlib import Path


def zoo() -> Path | None:
    here = Path(__file__).resolve().parents[1]
    for candidate in (os.environ.get("GAUSSPP_MJCF_ZOO"), here.parent / "shared" / "mjcf-zoo", "/work/shared/mjcf-zoo"):
        if candidate and Path(candidate).is_dir():
            return Path(candidate)
    return None


def models() -> list[str]:
    """The zoo's model files, as ``collection/name.xml`` (empty where the zoo is not on disk)."""
    root = zoo()
    if root is None:
        return []
    return sorted(str(p.relative_to(root)) for p in root.glob("*/*.xml"))
