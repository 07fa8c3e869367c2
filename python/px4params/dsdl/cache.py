"""Where the schema model comes from on every call but the first: a cache of the model that
:mod:`px4params.dsdl.loader` builds, so that a command parses no DSDL and imports no parser.

The cache file's name is a key over what the model is built from: the model format, the
loader's own modules, the installed pydsdl and pydronecan, and every DSDL file of every root
(its path, inode, size, modification and change times: an edit whose modification time was put
back, as ``cp -p`` or ``rsync -t`` do, still changes the change time). A file changed less than
two seconds before the key is taken is keyed by its contents too: two writes within the file
system's timestamp resolution keep the same time (git's "racy" files). A cache hit costs a
directory walk, a ``stat`` per file and one read of a :mod:`px4params.cache_file`.

A cached model whose CRC matches but whose shape is wrong (written by something else, or
edited) is discarded with a note on stderr and parsed again: its outer tables are checked when
it is read, each type when it is first unpacked.

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
    cache_path,
    default_cache_dir,
    discard,
    file_stamp,
    is_racy,
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
    cached = read_cached(cache_file, key_text)
    if cached is not None:
        problem = _container_problem(cached)
        if problem is None:
            return _unpacked(cached, key_text, rebuild=_Rebuild(cache_file, key_text, roots))
        discard(cache_file, problem)
    packed, types = _build(cache_file, key_text, roots)
    return _unpacked(packed, key_text, types)


def _build(cache_file: str, key_text: str, roots: Sequence[Root]) -> tuple[Model, Model]:
    """The model parsed from ``roots`` (packed, and its types), written to ``cache_file``."""
    from px4params.dsdl.loader import build_model  # a miss: now the parsers are needed

    types = build_model(roots)["types"]
    packed = {
        "format": MODEL_FORMAT,
        "types": {key: marshal.dumps(definition) for key, definition in types.items()},
        "newest": newest_versions(types),
        "refs": {key: sorted(type_refs(definition)) for key, definition in types.items()},
    }
    write_cached(cache_file, key_text, packed)
    return packed, types


class _Rebuild:
    """How a cached model is replaced when one of its types turns out to be of the wrong shape
    (its CRC matched: written by something else, or edited): discard the file, say so, parse."""

    def __init__(self, cache_file: str, key_text: str, roots: Sequence[Root]) -> None:
        self.cache_file = cache_file
        self.key_text = key_text
        self.roots = roots

    def __call__(self, why: str) -> tuple[Model, Model]:
        discard(self.cache_file, why)
        return _build(self.cache_file, self.key_text, self.roots)


class LazyTypes(Mapping[str, "Model"]):
    """A model's ``types``: key -> definition, each unpacked on first use.

    A cached type is checked when it is unpacked (its shape, the types it refers to); one of
    the wrong shape makes the whole model be parsed again (``rebuild``), and the model's
    ``newest`` and ``refs`` (shared with whoever holds them) are replaced in place."""

    def __init__(
        self,
        packed: dict[str, bytes],
        unpacked: Model | None = None,
        *,
        newest: dict[str, str] | None = None,
        refs: dict[str, list[str]] | None = None,
        rebuild: _Rebuild | None = None,
    ) -> None:
        self._packed = packed
        self._unpacked: dict[str, Model] = dict(unpacked or {})
        self._newest = newest if newest is not None else {}
        self._refs = refs if refs is not None else {}
        self._rebuild = rebuild

    def __getitem__(self, key: str) -> Model:
        cached = self._unpacked.get(key)
        if cached is not None:
            return cached
        packed = self._packed[key]
        definition: Model
        if self._rebuild is None:  # built in this process: nothing to doubt
            definition = marshal.loads(packed)
        else:
            try:
                definition = marshal.loads(packed)
                problem = _definition_problem(key, definition, self._refs, self._newest)
            except (ValueError, EOFError, TypeError) as e:
                problem = f"cannot unpack it ({e})"
            if problem is not None:
                self._replace(self._rebuild(f"type {key}: {problem}"))
                return self[key]
        self._unpacked[key] = definition
        return definition

    def _replace(self, built: tuple[Model, Model]) -> None:
        packed, types = built
        self._rebuild = None
        self._packed = packed["types"]
        self._unpacked = dict(types)
        self._newest.clear()
        self._newest.update(packed["newest"])
        self._refs.clear()
        self._refs.update(packed["refs"])

    def __contains__(self, key: object) -> bool:
        return key in self._packed

    def __iter__(self) -> Iterator[str]:
        return iter(self._packed)

    def __len__(self) -> int:
        return len(self._packed)

    def __repr__(self) -> str:
        return f"<LazyTypes: {len(self._packed)} types, {len(self._unpacked)} unpacked>"


def _unpacked(
    packed: Model, key_text: str, types: Model | None = None, rebuild: _Rebuild | None = None
) -> Model:
    newest, refs = packed["newest"], packed["refs"]
    return {
        "format": packed["format"],
        "types": LazyTypes(packed["types"], types, newest=newest, refs=refs, rebuild=rebuild),
        "newest": newest,
        "refs": refs,
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
    return f"{origin} {file_stamp(st)}"


def cache_key_text(roots: Sequence[Root], include_dronecan: bool) -> str:
    """What the model is built from, as text (see the module documentation)."""
    now = time.time()
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
        parts.append(f"{file} {file_stamp(st)}")
        if is_racy(st, now):
            parts.append(f"crc32={_file_crc(file):08x}")
    return "\n".join(parts)


def _file_crc(path: str) -> int:
    try:
        return binascii.crc32(read_bytes(path, DSDL))
    except OSError as ex:
        raise DsdlError(f"cannot read DSDL file: {ex.strerror or ex}", path) from ex


def _container_problem(model: Any) -> str | None:
    """What is wrong with a cached model's outer shape (each type is checked when unpacked:
    :func:`_definition_problem`); None when nothing is."""
    if not isinstance(model, dict) or model.get("format") != MODEL_FORMAT:
        return f"not a schema model of format {MODEL_FORMAT}"
    types, newest, refs = model.get("types"), model.get("newest"), model.get("refs")
    if not isinstance(types, dict) or not all(
        isinstance(k, str) and isinstance(v, bytes) for k, v in types.items()
    ):
        return "'types' is not a table of packed types"
    if newest != _newest_by_key(types):
        return "'newest' does not name the newest version of each type"
    if not isinstance(refs, dict) or refs.keys() != types.keys():
        return "'refs' does not list the model's types"
    return None


def _newest_by_key(types: Mapping[str, object]) -> dict[str, str]:
    """:func:`newest_versions` worked out from the keys alone (``NAME.MAJOR.MINOR``), without
    unpacking a type."""
    newest: dict[str, tuple[tuple[int, int], str]] = {}
    for key in types:
        head, _, minor = key.rpartition(".")
        name, _, major = head.rpartition(".")
        if major.isdigit() and minor.isdigit():
            rank = (int(major), int(minor))
            if name not in newest or newest[name][0] < rank:
                newest[name] = (rank, key)
    return {name: key for name, (_, key) in newest.items()}


#: The keys each kind of field type needs (what the compiler reads).
_TYPE_KEYS = {
    "uint": ("bits",),
    "int": ("bits",),
    "float": ("bits",),
    "bool": (),
    "void": ("bits",),
    "array": ("elem", "len"),
    "dynarray": ("elem", "max"),
    "ref": ("name",),
}


def _definition_problem(
    key: str, definition: Any, refs: Mapping[str, Any], newest: Mapping[str, str]
) -> str | None:
    """What is wrong with a cached type's shape, as the compiler and the layers above read it;
    None when nothing is."""
    if not isinstance(definition, dict):
        return "not a table"
    name, kind, fields = definition.get("name"), definition.get("kind"), definition.get("fields")
    if not isinstance(name, str) or not key.startswith(name):
        return f"its name {name!r} is not the type's"
    if kind not in ("struct", "union") or not isinstance(fields, list):
        return "no 'kind' of struct or union, or no 'fields' list"
    if not isinstance(definition.get("doc", {}), dict):
        return "'doc' is not a table"
    version = definition.get("version")
    if version is not None and (
        not isinstance(version, list | tuple) or len(version) != 2 or newest.get(name) is None
    ):
        return f"version {version!r} is not (major, minor) of a known name"
    pending: list[Any] = []
    for field in fields:
        if not isinstance(field, dict) or not isinstance(field.get("name"), str):
            return "a field without a name"
        pending.append(field.get("type"))
    while pending:
        item = pending.pop()
        needed = _TYPE_KEYS.get(item.get("kind", "")) if isinstance(item, dict) else None
        if needed is None or not all(
            isinstance(item.get(k), dict if k == "elem" else str if k == "name" else int)
            for k in needed
        ):
            return f"a field type of the wrong shape: {item!r}"[:200]
        if "elem" in needed:
            pending.append(item["elem"])
    if refs.get(key) != sorted(type_refs(definition)):
        return "its list of referenced types is not the one its fields make"
    return None
