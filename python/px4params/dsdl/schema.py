"""The Python API over compiled types: load a schema, then encode, decode and access leaves."""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Mapping, MutableMapping, Sequence

from px4params import _native
from px4params._records import TYPE_CHECKING
from px4params.dsdl import signature as _signature
from px4params.dsdl.cache import load_model, newest_versions, type_refs
from px4params.dsdl.model import Field, TypeDef, TypeDoc, type_def

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, NamedTuple

    # (In Schema's body, the name _native is its property.)
    from px4params._native import DataType as CompiledType
else:
    from px4params._records import NamedTuple

__all__ = [
    "DSDL_PATH_ENV",
    "DataType",
    "Leaf",
    "Schema",
    "StructValue",
    "core_version",
    "load_schema",
    "to_json_value",
]

#: Colon-separated extra DSDL root namespace folders, added to every schema loaded by default.
DSDL_PATH_ENV = "PX4PARAMS_DSDL_PATH"


def core_version() -> tuple[str, int]:
    """The compiled core's version and the store file format version it writes (for
    ``px4params --version``: a wheel pairs core and package; a stale build would not)."""
    return _native.CORE_VERSION, _native.STORE_FORMAT_VERSION


class Leaf(NamedTuple):
    """One leaf of a value: its number ``[k]``, path, DSDL type and value.

    Union tags have paths ending in ``._tag`` and dynamic array lengths in ``._len`` (type
    ``tail`` when the length is implied by tail array optimization).
    """

    index: int  # type: ignore[assignment]  # a field named index hides tuple.index, as Leaf's must
    path: str
    type: str
    value: int | float | bool


#: A decoded struct whose fields are attributes (``DataType.decode_struct``), as pydronecan's
#: decoded objects read: ``status.uptime_sec``. Frozen; like a named tuple, its own names start
#: with an underscore: ``_asdict()`` (what ``decode`` gives), ``_fields``, ``_type`` (the key).
#: Nested structs are struct values too, arrays lists, unions one-key dicts.
StructValue = _native.StructValue


class DataType(_native.DataType):
    """One type, compiled: DroneCAN (UAVCAN v0) serialization and leaf access.

    Values are plain data: a struct is a dict of field name to value (``p_version`` and padding
    may be left out), a union a dict with exactly one key, arrays lists (``uint8`` arrays also
    take ``bytes`` or ``str``), floats may be given as ``"nan"``, ``"inf"``, ``"-inf"``.

    ``decode_struct`` decodes a struct type into a :class:`StructValue` instead, its fields
    attributes; ``encode`` takes one as its ``_asdict()``, in a dict too.

    ``encode``, ``decode``, ``decode_struct``, the batch forms ``encode_many`` and
    ``decode_many``, ``min_bits``, ``max_bits`` and ``key`` are the compiled type's own
    (``px4params._native.DataType``): called straight, with no Python in between.
    """

    def __new__(
        cls,
        key: str,
        definition: Mapping[str, Any],
        native: _native.DataType,
        types: Mapping[str, Mapping[str, Any]] | None = None,
        signatures: MutableMapping[str, int] | None = None,
        type_defs: MutableMapping[str, TypeDef] | None = None,
    ) -> DataType:
        return super().__new__(cls, native)

    def __init__(
        self,
        key: str,
        definition: Mapping[str, Any],
        native: _native.DataType,
        types: Mapping[str, Mapping[str, Any]] | None = None,
        signatures: MutableMapping[str, int] | None = None,
        type_defs: MutableMapping[str, TypeDef] | None = None,
    ) -> None:
        self.definition = definition
        # Every type of the schema (for nested types' signatures) and the schema's memo of them.
        self._types = types if types is not None else {key: definition}
        self._signatures = signatures if signatures is not None else {}
        self._type_defs = type_defs if type_defs is not None else {}
        #: What other layers derive from the type once and keep with it (its destructured
        #: letters, ``px4params.store.flat.layout``).
        self.derived: dict[str, Any] = {}

    @property
    def name(self) -> str:
        """Full name without version, e.g. ``px.Ina238``."""
        return str(self.definition["name"])

    @property
    def version(self) -> tuple[int, int] | None:
        """``(major, minor)``, or None for DroneCAN types without a version."""
        v = self.definition.get("version")
        return (int(v[0]), int(v[1])) if v else None

    @property
    def type_def(self) -> TypeDef:
        """The type's declaration, typed: its doc, tags and fields
        (:mod:`px4params.dsdl.model`), read once per schema."""
        return type_def(self.key, self.definition, self._type_defs)

    def nested_type_def(self, key: str) -> TypeDef:
        """The declaration of ``key``, a type this one uses (or this one)."""
        return type_def(key, self._types[key], self._type_defs)

    def field_at(self, path: str) -> Field | None:
        """The field a leaf path ends at (``bus.i2c.address``; ``cells[3].volts`` is field
        ``volts`` of an element), or None: no such field, a union tag or an array length."""
        declared: TypeDef | None = self.type_def
        found = None
        for step in path.split("."):
            if declared is None:
                return None
            found = declared.field(step.partition("[")[0])
            if found is None:
                return None
            spec = found.type
            while spec["kind"] in ("array", "dynarray"):
                spec = spec["elem"]
            declared = self.nested_type_def(spec["name"]) if spec["kind"] == "ref" else None
        return found

    @property
    def doc(self) -> TypeDoc:
        """The type's doc comment: ``short``, ``long`` and its tags (``max_instances`` ...)."""
        return self.type_def.doc

    @property
    def signature(self) -> int:
        """The DroneCAN data type signature (64 bits): CRC-64-WE of the normalized definition,
        extended with the nested types' signatures; a service's for both of its halves. It seeds
        the CRC of multi-frame transfers (see :mod:`px4params.dsdl.signature`)."""
        return _signature.data_type_signature(self._types, self.key, memo=self._signatures)

    @property
    def dtid(self) -> int | None:
        """Default data type ID (DroneCAN) or fixed port ID (pydsdl), or None."""
        dtid = self.definition.get("dtid")
        return int(dtid) if dtid is not None else None

    @property
    def max_bytes(self) -> int:
        """Largest encoded length in bytes."""
        return (self.max_bits + 7) // 8

    def decode_fragments(
        self, fragments: Sequence[bytes], *, tao: bool = True, allow_trailing: bool = False
    ) -> dict[str, Any]:
        """Decodes a value whose bytes arrive in pieces (e.g. CAN frame payloads)."""
        value: dict[str, Any] = super().decode_fragments(
            [bytes(f) for f in fragments], tao=tao, allow_trailing=allow_trailing
        )
        return value

    def default(self, *, tao: bool = True) -> bytes:
        """The encoding of the zero value (``p_version`` filled, first variants, empty arrays)."""
        return super().default(tao=tao)

    # The core's rows as Leaf records: a list of a subtype, which mypy's invariant list refuses.
    def leaves(self, data: bytes | None = None, *, tao: bool = True) -> list[Leaf]:  # type: ignore[override]
        """Every leaf of ``data`` (of the default value when None) in ``[k]`` order."""
        raw = self.default(tao=tao) if data is None else bytes(data)
        return [Leaf(*row) for row in super().leaves(raw, tao=tao)]

    def get_leaf(self, data: bytes, target: int | str, *, tao: bool = True) -> Leaf:
        """Reads leaf ``[k]`` (an int) or a path such as ``"bus.i2c.address"``, without
        decoding the rest."""
        return Leaf(*super().get_leaf(bytes(data), target, tao=tao))

    def set_leaf(
        self,
        data: bytes,
        target: int | str,
        value: Any,
        *,
        tao: bool = True,
        saturate: bool = False,
    ) -> bytes:
        """Returns ``data`` with one leaf replaced. Setting a union tag selects that variant
        with its default value; setting an array length truncates or appends defaults."""
        return super().set_leaf(bytes(data), target, value, tao=tao, saturate=saturate)


class Schema(Mapping[str, DataType]):
    """Every loaded type, compiled once into one layout.

    Look types up by key (``"px.Ina238.1.1"``, ``"uavcan.protocol.GetNodeInfo.Request"``) or by
    name without version (``"px.Ina238"``: the newest version).
    """

    def __init__(self, model: Mapping[str, Any]) -> None:
        self.model = model
        types: Mapping[str, Any] = model["types"]
        self._definitions = types
        # A cached model carries these; a model built by hand has them worked out here.
        self._newest: Mapping[str, str] = model.get("newest") or newest_versions(types)
        self._refs: Mapping[str, Sequence[str]] = model.get("refs") or {}
        self._all: _native.Schema | None = None
        self._cache: dict[str, DataType] = {}
        self._signatures: dict[str, int] = {}
        self._type_defs: dict[str, TypeDef] = {}

    @property
    def _native(self) -> _native.Schema:
        """Every type compiled into one layout (a store's types must share one)."""
        if self._all is None:
            self._all = _native.Schema(dict(self._definitions.items()))
        return self._all

    def _compiled(self, key: str) -> CompiledType:
        """``key`` compiled: from the whole layout once there is one, else with only the types
        it uses (a command on one message does not compile two hundred)."""
        if self._all is not None:
            return self._all.get(key)
        return _native.Schema(self._closure([key])).get(key)

    def _closure(self, keys: list[str]) -> dict[str, Any]:
        """The definitions of ``keys`` and of every type they use."""
        closure: dict[str, Any] = {}
        pending = list(keys)
        while pending:
            name = pending.pop()
            if name not in closure:
                definition = self._definitions[name]
                closure[name] = definition
                refs = self._refs.get(name)
                pending.extend(refs if refs is not None else type_refs(definition))
        return closure

    def resolve(self, name: str) -> str:
        """The key of ``name`` (a key, or a versionless name meaning its newest version)."""
        if name in self._definitions:
            return name
        if name in self._newest:
            return self._newest[name]
        raise KeyError(name)

    def __getitem__(self, name: str) -> DataType:
        key = self.resolve(name)
        cached = self._cache.get(key)
        if cached is None:
            cached = DataType(
                key,
                self._definitions[key],
                self._compiled(key),
                self._definitions,
                self._signatures,
                self._type_defs,
            )
            self._cache[key] = cached
        return cached

    def type_def(self, name: str) -> TypeDef:
        """The declaration of type ``name`` (a key or a versionless name), typed
        (:mod:`px4params.dsdl.model`): read on first use, without compiling the type."""
        found = self._type_defs.get(name)  # (a key, read before: the common case)
        if found is not None:
            return found
        key = self.resolve(name)
        return type_def(key, self._definitions[key], self._type_defs)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and (name in self._definitions or name in self._newest)

    def __iter__(self) -> Iterator[str]:
        return iter(sorted(self._definitions))

    def __len__(self) -> int:
        return len(self._definitions)

    def suggest(self, name: str, limit: int = 3) -> list[str]:
        """Keys that look like ``name`` (for "did you mean" in error messages)."""
        import difflib

        candidates = list(self._definitions) + list(self._newest)
        return difflib.get_close_matches(name, candidates, n=limit, cutoff=0.6)


def load_schema(
    dsdl: Sequence[str | os.PathLike[str]] = (),
    *,
    include_dronecan: bool = True,
    use_env: bool = True,
    cache_dir: str | os.PathLike[str] | None = None,
) -> Schema:
    """Loads the bundled ``px`` types, the DroneCAN standard types and the extra root namespace
    folders ``dsdl`` (plus those in ``$PX4PARAMS_DSDL_PATH`` when ``use_env``).

    Parsing happens once per set of DSDL files; later calls read a cached model.
    """
    roots = [os.fspath(d) for d in dsdl]
    if use_env:
        roots += [p for p in os.environ.get(DSDL_PATH_ENV, "").split(os.pathsep) if p]
    return Schema(load_model(roots, include_dronecan=include_dronecan, cache_dir=cache_dir))


def to_json_value(value: Any) -> Any:
    """``value`` with non-finite floats spelled ``"nan"``, ``"inf"``, ``"-inf"`` (JSON has none)."""
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, dict):
        return {k: to_json_value(v) for k, v in value.items()}
    if isinstance(value, list):
        return [to_json_value(v) for v in value]
    return value


# -- parts of decoded values, by the leaf paths DataType.leaves writes --------------------------


def path_steps(path: str) -> list[str | int]:
    """``cells[3].volts`` -> ``["cells", 3, "volts"]``: a leaf path's field names and indices."""
    steps: list[str | int] = []
    for part in path.split(".") if path else []:
        name, *indices = part.replace("]", "").split("[")
        steps += [name, *map(int, indices)] if name else list(map(int, indices))
    return steps


def value_at(value: Any, path: str) -> Any:
    """The part of a decoded value at ``path`` (the whole value for ``""``); None where the value
    has no such part (a union variant not selected, an index past an array's end)."""
    for step in path_steps(path):
        if isinstance(step, int):
            value = value[step] if isinstance(value, list) and step < len(value) else None
        else:
            value = value.get(step) if isinstance(value, dict) else None
    return value


def put_at(value: Any, path: str, part: Any) -> None:
    """Replaces the part of a decoded value at ``path``, which it has (not ``""``: the root is
    no part)."""
    *above, last = path_steps(path)
    for step in above:
        value = value[step]
    value[last] = part
