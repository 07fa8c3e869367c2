"""Where the schema model comes from on every call but the first: a cache of the model that
:mod:`px4params.dsdl.loader` builds, so that a command parses no DSDL and imports no parser.

The cache file's name is a key over what the model is built from: the model format, the
loader's own modules, the installed pydsdl and pydronecan, and every DSDL file of every root
(its path, size and modification time). A file modified less than two seconds before the key is
taken is keyed by its contents too: two writes within the file system's timestamp resolution
keep the same time (git's "racy" files). A cache hit costs a directory walk, a ``stat`` per
file and one JSON read; this module imports nothing heavier than ``json`` for it.
"""

from __future__ import annotations

import contextlib
import importlib.machinery
import json
import os
import time
import zlib
from collections.abc import Sequence

from px4params._records import TYPE_CHECKING
from px4params.dsdl.roots import Root, collect_roots
from px4params.errors import DsdlError

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any

    Model = dict[str, Any]

#: Bumped whenever the model's shape changes, so that older caches are rebuilt.
#: 2: type entries carry ``service`` and ``signature_override`` (data type signatures).
MODEL_FORMAT = 2

#: Environment variable naming the cache folder.
CACHE_ENV = "PX4PARAMS_CACHE_DIR"

#: Files modified this recently (seconds) are keyed by their contents as well.
RACY_SECONDS = 2.0

_HERE = os.path.dirname(os.path.abspath(__file__))
#: The modules whose code decides what the model holds.
_LOADER_MODULES = ("loader.py", "cache.py")


def default_cache_dir() -> str:
    """``$PX4PARAMS_CACHE_DIR``, else ``$XDG_CACHE_HOME/px4params``, else ``~/.cache/px4params``."""
    explicit = os.environ.get(CACHE_ENV)
    if explicit:
        return explicit
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg:
        return os.path.join(xdg, "px4params")
    return os.path.join(os.path.expanduser("~"), ".cache", "px4params")


def load_model(
    extra_roots: Sequence[str | os.PathLike[str]] = (),
    *,
    include_dronecan: bool = True,
    cache_dir: str | os.PathLike[str] | None = None,
) -> Model:
    """Load every type of the bundled, DroneCAN-standard and extra roots into one model.

    ``extra_roots`` are root namespace folders (the folder name is the root namespace, e.g.
    ``.../px``); each is routed by its files: ``*.dsdl`` to pydsdl, ``*.uavcan`` to pydronecan.
    The model is cached in ``cache_dir`` (default :func:`default_cache_dir`).

    Raises:
        DsdlError: a definition, its metadata or a root folder is invalid.
    """
    roots = collect_roots(extra_roots, include_dronecan)
    key_text = cache_key_text(roots, include_dronecan)
    directory = os.fspath(cache_dir) if cache_dir is not None else default_cache_dir()
    name = f"model-{zlib.crc32(key_text.encode('utf-8', 'surrogateescape')):08x}.json"
    cache_file = os.path.join(directory, name)
    cached = _read_cache(cache_file, key_text)
    if cached is not None:
        return cached
    from px4params.dsdl.loader import build_model  # a miss: now the parsers are needed

    model = {"format": MODEL_FORMAT, **build_model(roots)}
    _write_cache(cache_file, key_text, model)
    return model


def _installed(name: str) -> str:
    """Identifies an installed package by its module file's path, size and time: a new install
    changes them (cheaper than importlib.metadata, which costs a command ~30 ms)."""
    spec = importlib.machinery.PathFinder.find_spec(name)
    if spec is None or spec.origin is None:
        return "not-installed"
    try:
        st = os.stat(spec.origin)
    except OSError:
        return "not-installed"
    return f"{spec.origin}:{st.st_size}:{st.st_mtime_ns}"


def cache_key_text(roots: Sequence[Root], include_dronecan: bool) -> str:
    """What the model is built from, as text (see the module documentation)."""
    racy_after = (time.time() - RACY_SECONDS) * 1e9
    parts = [
        "px4params-dsdl-model",
        str(MODEL_FORMAT),
        f"pydsdl={_installed('pydsdl')}",
        f"dronecan={_installed('dronecan')}",
        f"include_dronecan={include_dronecan}",
    ]
    files = [os.path.join(_HERE, m) for m in _LOADER_MODULES]
    for root in roots:
        parts.append(f"root {root.dialect} {root.path} {len(root.files)}")
        files += root.files
    for file in files:
        try:
            st = os.stat(file)
        except OSError as ex:
            raise DsdlError(f"cannot read DSDL file: {ex.strerror or ex}", file) from ex
        parts.append(f"{file} {st.st_size} {st.st_mtime_ns}")
        if st.st_mtime_ns > racy_after:
            parts.append(f"crc32={_file_crc(file):08x}")
    return "\n".join(parts)


def _file_crc(path: str) -> int:
    try:
        with open(path, "rb") as f:
            return zlib.crc32(f.read())
    except OSError as ex:
        raise DsdlError(f"cannot read DSDL file: {ex.strerror or ex}", path) from ex


def _read_cache(path: str, key_text: str) -> Model | None:
    try:
        with open(path, encoding="utf-8") as f:
            model = json.load(f)
    except (OSError, ValueError):  # missing, unreadable, not UTF-8 or not JSON: rebuild
        return None
    if (
        isinstance(model, dict)
        and model.get("format") == MODEL_FORMAT
        and model.get("key") == key_text  # a different key with the same CRC is a miss
        and isinstance(model.get("types"), dict)
    ):
        return model
    return None


def _write_cache(path: str, key_text: str, model: Model) -> None:
    # Best effort: a read-only or full cache folder must not break loading.
    model["key"] = key_text
    folder, name = os.path.split(path)
    tmp = os.path.join(folder, f".{name}.{os.getpid()}.tmp")
    try:
        os.makedirs(folder, exist_ok=True)
        with open(tmp, "w", encoding="utf-8") as out:
            json.dump(model, out, separators=(",", ":"))
        os.replace(tmp, path)  # atomic: readers see the old file or the whole new one
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
