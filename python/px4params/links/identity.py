"""Who a node is: the version it reports and a unique ID that stays with its store file.

MAVLink's ``AUTOPILOT_VERSION`` and DroneCAN's ``GetNodeInfo`` both carry them; ground stations
key their parameter caches by the unique ID, so the same store file must be the same vehicle.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable

__all__ = ["store_digest", "version_parts"]


def version_parts() -> tuple[int, int, int, bool]:
    """``(major, minor, patch, development)`` of this package's version."""
    from px4params import __version__

    parts = [int(p) for p in __version__.split("+")[0].split(".")[:3] if p.isdigit()]
    major, minor, patch = [*parts, 0, 0, 0][:3]
    return major, minor, patch, "dev" in __version__


def store_digest(store_path: str | os.PathLike[str] | None, parameters: Iterable[str]) -> bytes:
    """32 bytes that name a store: from its file's real path (a symlink or a relative path to
    the same file gives the same bytes), else from its parameter names."""
    if store_path is not None:
        source = "file:" + os.path.realpath(os.fspath(store_path))
    else:
        source = "memory:" + ",".join(parameters)
    return hashlib.sha256(source.encode("utf-8", "surrogateescape")).digest()
