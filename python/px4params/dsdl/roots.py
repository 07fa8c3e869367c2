"""Where DSDL comes from: the root namespace folders of a schema (bundled, pydronecan's, the
user's), each with its dialect and files."""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence

from px4params.data import DSDL_DIR
from px4params.errors import DsdlError
from px4params.reading import DSDL, check_file


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


#: A root namespace folder is walked to at most this many folders below it (pydsdl's and
#: pydronecan's deepest namespaces are 3 levels deep) ...
MAX_ROOT_DEPTH = 16
#: ... and at most this many entries (files and folders; pydronecan ships 147 definitions):
#: a folder like ``/usr`` given as a root is refused at this count instead of walked for minutes.
MAX_ROOT_ENTRIES = 10_000


def _classify_root(path: str, *, required: bool = True) -> Root | None:
    if not os.path.isdir(path):
        raise DsdlError("DSDL root namespace folder does not exist or is not a folder", path)
    if not os.path.basename(os.path.normpath(path)).strip(os.sep):
        raise DsdlError(
            "the file system's root is not a DSDL root namespace folder (the folder's name is "
            "the namespace)",
            path,
        )
    dsdl, uavcan = _definition_files(path)
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
    # Sorted by the path inside the root, folder by folder (the walk's paths start with `path`:
    # cutting it off is what os.path.relpath would do, without its cost on every command).
    files = tuple(sorted(dsdl or uavcan, key=lambda p: p[len(path) :].lstrip(os.sep).split(os.sep)))
    return Root(path, "dsdl" if dsdl else "uavcan", files)


def _definition_files(path: str) -> tuple[list[str], list[str]]:
    """The ``.dsdl`` and ``.uavcan`` files under ``path``, each checked to be a regular file of
    a definition's size. Symbolic links are followed, but no folder is walked twice (by its
    real path): a link back up the tree ends the walk there instead of looping."""
    dsdl: list[str] = []
    uavcan: list[str] = []
    walked: set[str] = set()
    pending = [(path, 0)]
    entries = 0
    while pending:
        folder, depth = pending.pop()
        real = os.path.realpath(folder)
        if real in walked:
            continue
        walked.add(real)
        try:
            with os.scandir(folder) as listing:
                found = list(listing)
        except OSError as e:
            raise DsdlError(f"cannot read DSDL folder: {e.strerror or e}", folder) from None
        entries += len(found)
        if entries > MAX_ROOT_ENTRIES:
            raise DsdlError(
                f"DSDL root holds more than {MAX_ROOT_ENTRIES:,} files and folders; a root "
                "namespace folder holds only definitions (is it the right folder?)",
                path,
            )
        for entry in found:
            if _is_folder(entry):
                if depth + 1 > MAX_ROOT_DEPTH:
                    raise DsdlError(
                        f"DSDL folders nested deeper than {MAX_ROOT_DEPTH} levels", entry.path
                    )
                pending.append((entry.path, depth + 1))
            elif entry.name.endswith((".dsdl", ".uavcan")):
                try:
                    check_file(entry.path, DSDL)
                except OSError as e:
                    raise DsdlError(
                        f"cannot read DSDL file: {e.strerror or e}", entry.path
                    ) from None
                (dsdl if entry.name.endswith(".dsdl") else uavcan).append(entry.path)
    return dsdl, uavcan


def _is_folder(entry: os.DirEntry[str]) -> bool:
    """Whether ``entry`` is a folder or a link to one (not a broken link or a link loop)."""
    try:
        return entry.is_dir()
    except OSError:
        return False


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
