"""Where the schema model comes from on every call but the first: a cache of the model that
:mod:`px4params.dsdl.loader` builds, so that a command parses no DSDL and imports no parser.

The cache file's name is a key over what the model is built from: the model format, the
loader's own modules, the installed pydsdl and pydronecan, and every DSDL file of every root
(its path, size and modification time). A file modified less than two seconds before the key is
taken is keyed by its contents too: two writes within the file system's timestamp resolution
keep the same time (git's "racy" files). A cache hit costs a directory walk, a ``stat`` per
file and one read of a :mod:`px4params.cache_file`.

Each type's definition is cached packed (marshalled on its own) and unpacked on first use
(:class:`LazyTypes`), with the newest version of every name and the types each type refers to
beside them: a command that works on one DroneCAN message does not unpack the other two
hundred, and :class:`px4params.dsdl.schema.Schema` compiles only what it is asked for.
"""

from __future__ import annotations

import binascii
import marshal
import os
import time
from collections.abc import Iterator, Mapping, Sequence

from px4params._records import TYPE_CHECKING
from px4params.cache_file import (
    INTERPRETER,
    RACY_SECONDS,
    cache_path,
    default_cache_dir,
    read_cached,
    write_cached,
)
from px4params.data import VALUE_SETS_TOML
from px4params.dsdl.roots import Root, collect_roots, package_init
from px4params.errors import DsdlError
from px4params.reading import DSDL, read_bytes

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any

    Model = dict[str, Any]

#: Bumped whenever the model's shape changes, so that older caches are rebuilt.
#: 2: type entries carry ``service`` and ``signature_override`` (data type signatures).
#: 3: a marshal cache file instead of JSON, each type packed on its own.
MODEL_FORMAT = 3


_HERE = os.path.dirname(os.path.abspath(__file__))
#: The modules whose code decides what the model holds.
_LOADER_MODULES = ("loader.py", "cache.py")


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
    cache_file = cache_path(directory, "model", key_text)
    cached = _read_cache(cache_file, key_text)
    if cached is not None:
        return _unpacked(cached, key_text)
    from px4params.dsdl.loader import build_model  # a miss: now the parsers are needed

    types = build_model(roots)["types"]
    packed = {
        "format": MODEL_FORMAT,
        "types": {key: marshal.dumps(definition) for key, definition in types.items()},
        "newest": newest_versions(types),
        "refs": {key: sorted(type_refs(definition)) for key, definition in types.items()},
    }
    write_cached(cache_file, key_text, packed)
    return _unpacked(packed, key_text, types)


class LazyTypes(Mapping[str, "Model"]):
    """A model's ``types``: key -> definition, each unpacked on first use."""

    def __init__(self, packed: dict[str, bytes], unpacked: Model | None = None) -> None:
        self._packed = packed
        self._unpacked: dict[str, Model] = dict(unpacked or {})

    def __getitem__(self, key: str) -> Model:
        definition = self._unpacked.get(key)
        if definition is None:
            definition = marshal.loads(self._packed[key])
            self._unpacked[key] = definition
        return definition

    def __contains__(self, key: object) -> bool:
        return key in self._packed

    def __iter__(self) -> Iterator[str]:
        return iter(self._packed)

    def __len__(self) -> int:
        return len(self._packed)

    def __repr__(self) -> str:
        return f"<LazyTypes: {len(self._packed)} types, {len(self._unpacked)} unpacked>"


def _unpacked(packed: Model, key_text: str, types: Model | None = None) -> Model:
    return {
        "format": packed["format"],
        "types": LazyTypes(packed["types"], types),
        "newest": packed["newest"],
        "refs": packed["refs"],
        # What the model was built from: what depends on it alone can be cached under it.
        "key": key_text,
    }


def newest_versions(types: Mapping[str, Model]) -> dict[str, str]:
    """Name without version -> key of its newest version, for the versioned (DSDL) types."""
    newest: dict[str, tuple[tuple[int, int], str]] = {}
    for key, definition in types.items():
        version = definition.get("version")
        if version:
            rank = (int(version[0]), int(version[1]))
            name = definition["name"]
            if name not in newest or newest[name][0] < rank:
                newest[name] = (rank, key)
    return {name: key for name, (_, key) in newest.items()}


def type_refs(definition: Model) -> set[str]:
    """The keys of the types ``definition``'s fields refer to (directly)."""
    found: set[str] = set()
    pending: list[object] = [definition.get("fields")]
    while pending:
        item = pending.pop()
        if isinstance(item, dict):
            if item.get("kind") == "ref":
                found.add(item["name"])
            pending.extend(item.values())
        elif isinstance(item, list):
            pending.extend(item)
    return found


def _installed(name: str) -> str:
    """Identifies an installed package by its module file's path, size and time: a new install
    changes them (cheaper than importlib.metadata, which costs a command ~30 ms)."""
    origin = package_init(name)
    if origin is None:
        return "not-installed"
    try:
        st = os.stat(origin)
    except OSError:
        return "not-installed"
    return f"{origin}:{st.st_size}:{st.st_mtime_ns}"


def cache_key_text(roots: Sequence[Root], include_dronecan: bool) -> str:
    """What the model is built from, as text (see the module documentation)."""
    racy_after = (time.time() - RACY_SECONDS) * 1e9
    parts = [
        "px4params-dsdl-model",
        str(MODEL_FORMAT),
        INTERPRETER,
        f"pydsdl={_installed('pydsdl')}",
        f"dronecan={_installed('dronecan')}",
        f"include_dronecan={include_dronecan}",
    ]
    files = [os.path.join(_HERE, m) for m in _LOADER_MODULES] + [VALUE_SETS_TOML]
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
        return binascii.crc32(read_bytes(path, DSDL))
    except OSError as ex:
        raise DsdlError(f"cannot read DSDL file: {ex.strerror or ex}", path) from ex


def _read_cache(path: str, key_text: str) -> Model | None:
    model = read_cached(path, key_text)
    if (
        isinstance(model, dict)
        and model.get("format") == MODEL_FORMAT
        and isinstance(model.get("types"), dict)
    ):
        return model
    return None
