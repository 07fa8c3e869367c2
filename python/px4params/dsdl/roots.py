"""Where DSDL comes from: the root namespace folders of a schema (bundled, pydronecan's, the
user's), each with its dialect and files."""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence

from px4params.data import DSDL_DIR
from px4params.errors import DsdlError


class Root:
    """A DSDL root namespace folder: its path (the folder name is the namespace), its dialect
    (``"dsdl"``, read with pydsdl, or ``"uavcan"``, read with pydronecan's parser) and files."""

    __slots__ = ("dialect", "files", "path")

    def __init__(self, path: str, dialect: str, files: tuple[str, ...]) -> None:
        self.path = path
        self.dialect = dialect
        self.files = files

    def __repr__(self) -> str:
        return f"Root({self.path!r}, {self.dialect!r}, {len(self.files)} files)"


def collect_roots(
    extra_roots: Sequence[str | os.PathLike[str]], include_dronecan: bool
) -> list[Root]:
    """The bundled roots, pydronecan's (when ``include_dronecan``) and ``extra_roots``, each
    once (the same folder through a symlink is read once)."""
    # (folder, whether it must hold definitions)
    candidates: list[tuple[str, bool]] = []
    if os.path.isdir(DSDL_DIR):
        bundled = os.path.realpath(DSDL_DIR)
        candidates += sorted(
            (e.path, True) for e in os.scandir(bundled) if e.is_dir() and e.name[0] != "."
        )
    if include_dronecan:
        specs = os.path.join(dronecan_package_dir(), "dsdl_specs")
        # Every namespace pydronecan ships (uavcan, dronecan, ardupilot, com, cuav, mppt, ...).
        candidates += sorted((e.path, False) for e in os.scandir(specs) if e.is_dir())
    # abspath, not realpath: a symlinked folder's own name is the namespace name.
    candidates += [(os.path.abspath(os.fspath(r)), True) for r in extra_roots]

    roots: list[Root] = []
    seen: set[str] = set()
    for path, required in candidates:
        real = os.path.realpath(path)
        if real in seen:
            continue
        seen.add(real)
        root = _classify_root(path, required=required)
        if root is not None:
            roots.append(root)
    return roots


def _classify_root(path: str, *, required: bool = True) -> Root | None:
    if not os.path.isdir(path):
        raise DsdlError("DSDL root namespace folder does not exist or is not a folder", path)
    dsdl: list[str] = []
    uavcan: list[str] = []
    for folder, _dirs, names in os.walk(path, followlinks=True):
        for name in names:
            if name.endswith(".dsdl"):
                dsdl.append(os.path.join(folder, name))
            elif name.endswith(".uavcan"):
                uavcan.append(os.path.join(folder, name))
    if dsdl and uavcan:
        raise DsdlError(
            "DSDL root mixes .dsdl (pydsdl) and .uavcan (DroneCAN) files; "
            "keep each dialect in its own root namespace folder",
            path,
        )
    if not dsdl and not uavcan:
        if not required:
            return None  # a folder of pydronecan's without definitions
        raise DsdlError("DSDL root contains no .dsdl or .uavcan files", path)
    # Sorted by the path inside the root, folder by folder (os.walk's paths start with `path`:
    # cutting it off is what os.path.relpath would do, without its cost on every command).
    files = tuple(sorted(dsdl or uavcan, key=lambda p: p[len(path) :].lstrip(os.sep).split(os.sep)))
    return Root(path, "dsdl" if dsdl else "uavcan", files)


def package_init(name: str) -> str | None:
    """The ``__init__.py`` of the installed (regular) package ``name``, found on ``sys.path`` as
    the import system would, without importing it or ``importlib`` (which costs a command
    0.3 ms)."""
    for entry in sys.path:
        candidate = os.path.join(entry or os.curdir, name, "__init__.py")
        if os.path.isfile(candidate):
            return os.path.abspath(candidate)
    return None


def dronecan_package_dir() -> str:
    """pydronecan's package folder, found without running ``dronecan/__init__.py`` (which parses
    all of its DSDL)."""
    init = package_init("dronecan")
    if init is None:
        raise DsdlError(
            "pydronecan (package 'dronecan') is not installed; use include_dronecan=False"
        )
    return os.path.dirname(init)
