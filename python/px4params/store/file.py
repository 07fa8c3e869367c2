"""The store file: what differs from the defaults, one CRC-checked record per parameter.

The format is described in ``docs/store-format.md``. In short (integers little-endian)::

    header   "PX4P"  u8 format version (3)  u8 flags (0)  u32 fingerprint of the table
    table    the structured parameters the records refer to by index (NAME=TYPE.MAJOR)
    records  u8 kind, key, payloads, u16 CRC-16-CCITT-FALSE of the record's bytes
    trailer  u32 CRC-32 (zlib's) of every byte before it

A file names its own parameters, so a schema with more types (a newer px4params, another DSDL
folder) reads it. Format 1 files had no table: they are read by a schema with the same
parameters, or with the first bundled set plus the same extra types.

The bytes are read and written by the core (``px4params_core::file``), the implementation
firmware uses through the C ABI; this module maps the file's parameters to the store's,
translates values stored by older minor versions, and does the file system's part.

A file is checked completely (trailer, then every record) before anything is applied, and it
is applied to a copy of the store that replaces the store only when all of it went in.
Saving writes a temporary file, fsyncs it, keeps the old file as ``FILE.bak`` and renames the
new one over ``FILE``: a crash at any moment leaves the old or the new file intact.
"""

from __future__ import annotations

import binascii
import math
import os
import struct
from collections.abc import Mapping

from px4params import writing
from px4params._native import check_store_file
from px4params._records import TYPE_CHECKING
from px4params.dsdl.schema import DataType, value_at
from px4params.errors import (
    OutputFileError,
    Px4ParamsError,
    StoreError,
    StoreFileError,
    ValueRangeError,
)
from px4params.reading import STORE, read_bytes
from px4params.store.classic import exact_in_type
from px4params.store.spec import ParamSpec, check_leaves, leaf_ranges, shown_number

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, NamedTuple

    from px4params.store.classic import ClassicParam
    from px4params.store.store import Store, _Param
else:
    from px4params._records import NamedTuple

#: Record kinds, as the core's checked records carry them.
KIND_STRUCTURED = 1
KIND_CLASSIC = 2
#: A classic parameter's type, as the core and the C ABI number it (``px4p_param.classic``);
#: a classic record of format 2 says none (0).
CLASSIC_INT32 = 1
CLASSIC_FLOAT = 2


#: Structured parameters bundled after format 1 was replaced: a format 1 file was written by
#: a schema without them (the first nine bundled types, plus any extra DSDL folder's).
ADDED_AFTER_FORMAT_1 = frozenset(
    {
        "ASP5033", "AUAV", "BATMON", "BATT_SMBUS", "ETS3", "HMC5883", "ICM20948", "IIS2MDC",
        "IRLOCK", "IST8308", "LL40LS", "MB12XX", "MCP9808", "MS4515", "MS4525DO", "MS5525DSO",
        "PCF8583", "QMC5883P", "SDP3X", "SF1XX", "SHT3X", "SPA06", "SPL06", "TERARANGER",
        "TF02PRO", "TMP102", "VL53L0X", "VL53L1X",
    }
)  # fmt: skip


def table_lines(specs: list[ParamSpec]) -> list[str]:
    """``NAME=TYPE.MAJOR`` of each structured parameter, in order: what records refer to by
    index."""
    return [f"{s.name}={s.data_type.name}.{(s.data_type.version or (0, 0))[0]}" for s in specs]


def fingerprint(specs: list[ParamSpec]) -> int:
    """CRC-32 over the structured parameters' names, types and major versions."""
    return _lines_crc(table_lines(specs))


def _lines_crc(lines: list[str]) -> int:
    return binascii.crc32("\n".join(lines).encode())


# -- writing ------------------------------------------------------------------------------------


def encode_file(store: Store) -> bytes:
    """The store's file content, written by the core (the bytes firmware writes too)."""
    params = sorted(store._params.values(), key=lambda p: p.index)
    # (a parameter has a spec where it is not classic)
    names = [
        (p.name, CLASSIC_FLOAT if p.classic.is_float else CLASSIC_INT32)
        if p.classic is not None
        else (table_lines([p.spec])[0], 0)  # type: ignore[list-item]
        for p in params
    ]
    order = [p.index for p in store._order]
    # A kept record of a parameter this store now writes itself (one of another type, set
    # here since) gives way: two records of one parameter would make the file unreadable.
    written = {p.name for p in params if p.classic is not None and _has_record(store, p)}
    foreign = [raw for name, raw in store._foreign.items() if name not in written]
    return bytes(store._native.file_bytes(names, order, foreign))


def _has_record(store: Store, p: _Param) -> bool:
    """Whether the core writes a record of classic parameter ``p``: its value or default
    differs from the type's."""
    default = store._native.get(p.index, 0, default=True)
    value = store._native.get(p.index, 0, default=False)
    return value != default or default != store._type_default(p)


def save(store: Store, path: str | os.PathLike[str]) -> int:
    """Writes the store to ``path`` atomically, keeping the previous file as ``path.bak``
    (:func:`write_file`)."""
    return write_file(path, encode_file(store), keep_backup=True)


def write_file(path: str | os.PathLike[str], data: bytes, *, keep_backup: bool) -> int:
    """:func:`px4params.writing.write_file`, a refusal reported as a
    :class:`~px4params.errors.StoreFileError` (the store's files are saved through it)."""
    try:
        return writing.write_file(path, data, keep_backup=keep_backup)
    except OutputFileError as e:
        raise StoreFileError(e.strerror or str(e), e.filename) from None


# -- reading ------------------------------------------------------------------------------------


class Record(NamedTuple):
    """One checked record."""

    offset: int
    kind: int
    #: Parameter index (structured) or name (classic).
    key: int | str
    instance: int
    default: bytes | None
    value: bytes | None
    #: The record's bytes without its CRC.
    raw: bytes = b""
    #: A classic record's type: :data:`CLASSIC_INT32` or :data:`CLASSIC_FLOAT`; 0 when the
    #: file (format 2) does not say, and for a structured record.
    classic_type: int = 0


class FileContent(NamedTuple):
    """A checked file."""

    version: int
    fingerprint: int
    #: The parameter table (``NAME=TYPE.MAJOR`` per index); None in a format 1 file.
    table: list[str] | None
    records: list[Record]


def read_file(path: str | os.PathLike[str]) -> FileContent:
    """The whole file, after checking all of it."""
    where = os.fspath(path)
    try:
        data = read_bytes(where, STORE)
    except OSError as e:
        raise StoreFileError(f"cannot read: {e.strerror}", where) from None
    return parse(data, where)


def parse(data: bytes, where: str) -> FileContent:
    """Checks ``data`` completely (in the core) and returns its table and records."""
    version, file_fp, table, records = check_store_file(data, where)
    checked = [Record(*r) for r in records]
    # A second record of one instance (or classic parameter): which would hold? (The core
    # keeps no set; a file this package writes has one record of each.)
    seen = set[tuple[int, int | str, int]]()
    for record in checked:
        key = (record.kind, record.key, record.instance)
        if key in seen:
            raise StoreFileError(
                "record is malformed: a second record of the same parameter instance",
                where,
                record.offset,
            )
        seen.add(key)
    return FileContent(version, file_fp, table, checked)


# -- applying -----------------------------------------------------------------------------------


def apply_file(store: Store, path: str | os.PathLike[str], *, merge: bool) -> list[str]:
    """Applies a checked file to a copy of the store (reset first unless ``merge``); the copy
    replaces the store only when every record went in. Returns the report's lines."""
    where = os.fspath(path)
    content = read_file(where)
    work = store._native.copy() if merge else store._initial.copy()
    report: list[str] = []
    foreign = dict(store._foreign) if merge else {}
    by_index = _file_parameters(store, content, where)
    untyped = content.version == 2 and any(r.kind == KIND_CLASSIC for r in content.records)
    if untyped:
        report.append(
            f"{where}: store file format 2, whose classic records do not say their type: read "
            "as this parameter set types them (if it was saved with another, load it with that "
            "one first)"
        )
    for record in content.records:
        try:
            _apply(store, work, record, by_index, report, foreign)
        except Px4ParamsError as e:
            cause = (
                " (a format 2 file: saved with a parameter set where it is the other type?)"
                if untyped and record.kind == KIND_CLASSIC
                else ""
            )
            raise StoreFileError(
                f"record cannot be applied: {e}{cause}", where, record.offset
            ) from None
    work.mark_saved()
    # A value converted from the other type is not what the file holds: unsaved ("*") until a
    # save writes it in this set's type (firmware built with this set would skip the record).
    for record in content.records:
        param = store._params.get(record.key) if record.kind == KIND_CLASSIC else None  # type: ignore[arg-type]
        if (
            param
            and param.classic
            and record.key not in foreign
            and _retyped(record, param.classic)
        ):
            for default in (True, False):
                data = work.get(param.index, 0, default=default)
                work.set_encoded(param.index, 0, data, default=default)
    store._native.restore(work)
    store._foreign = foreign
    return report


def _file_parameters(store: Store, content: FileContent, where: str) -> dict[int, _Param | str]:
    """The file's parameter indices -> this store's parameters; an entry this store has not
    (another type, or no such parameter) maps to the file's ``NAME=TYPE.MAJOR``, an error only
    if a record uses it."""
    lines = content.table
    if lines is None:  # format 1: the table is the fingerprint's list, this schema's or older
        first = [s for s in store.specs if s.name not in ADDED_AFTER_FORMAT_1]
        lines = next(
            (
                x
                for x in (table_lines(store.specs), table_lines(first))
                if _lines_crc(x) == content.fingerprint
            ),
            None,
        )
        if lines is None:
            raise StoreFileError(
                f"written for another schema (fingerprint 0x{content.fingerprint:08x}, this "
                f"schema has 0x{fingerprint(store.specs):08x}: its parameters or their types "
                "differ)",
                where,
                6,
            )
    current = dict(zip(table_lines(store.specs), store.specs, strict=True))
    found: dict[int, _Param | str] = {}
    for index, line in enumerate(lines):
        spec = current.get(line)
        found[index] = store._params[spec.name] if spec is not None else line
    return found


def _apply(
    store: Store,
    work: Any,
    record: Record,
    by_index: Mapping[int, _Param | str],
    report: list[str],
    foreign: dict[str, bytes],
) -> None:
    if record.kind == KIND_CLASSIC:
        assert isinstance(record.key, str)
        if record.classic_type == CLASSIC_FLOAT:  # (refused in every set, kept or not)
            for payload in (record.default, record.value):
                _check_float32(record.key, payload)
        param = store._params.get(record.key)
        if param is None or param.classic is None:
            # Kept as it is and written back by the next save: nothing is lost because this
            # store was opened with another set of classic parameters.
            foreign[record.key] = record.raw
            report.append(f"{record.key}: not a classic parameter of this store; kept unchanged")
            return
        payloads = _classic_payloads(param.classic, record, report)
        if payloads is None:
            foreign[record.key] = record.raw
            return
        foreign.pop(record.key, None)  # (merged over a record kept before: this one is newer)
        for payload, default in zip(payloads, (True, False), strict=True):
            if payload is not None:
                _check_finite(param, record.key, payload)
                work.set_encoded(param.index, 0, payload, default=default)
        return
    assert isinstance(record.key, int)
    p = by_index.get(record.key)
    if isinstance(p, str):
        name, _, key = p.partition("=")
        spec = store.spec(name) if name in store._params else None
        has = (
            f"this schema has {_table_key(spec)}"
            if spec is not None
            else "this schema has no such parameter"
        )
        raise StoreError(f"{name} was stored as {key}; {has}")
    if p is None or p.spec is None:
        raise StoreError(f"no parameter #{record.key}")
    if not p.shared and not work.slot(p.index, record.instance)[0]:  # import may merge
        work.add(p.index, record.instance)
    name = store._instance_name(p, record.instance)
    data_type = p.spec.data_type
    if record.default is not None:
        base = work.type_default(p.index)
        stored = _current(store, data_type, name, record.default, base, report)
        _check_finite(p, name, stored)
        work.set_encoded(p.index, record.instance, stored, default=True)
    if record.value is not None:
        base = work.get(p.index, record.instance, default=True)
        value = _current(store, data_type, name, record.value, base, report)
        _check_finite(p, name, value)
        work.set_encoded(p.index, record.instance, value)


def _classic_payloads(
    param: ClassicParam, record: Record, report: list[str]
) -> tuple[bytes | None, bytes | None] | None:
    """A classic record's default and value as ``param``'s type holds them. A record of the
    other type (its parameter's type changed between PX4 releases: RC10_REV, COM_DISARM_LAND)
    is converted where no digit is lost, and said; else None, and said: the record is kept
    unchanged. Its bytes are never read as the other type."""
    if not _retyped(record, param) or record.default is record.value is None:
        return record.default, record.value
    was = "Float" if record.classic_type == CLASSIC_FLOAT else "Int32"
    numbers = [
        None if payload is None else struct.unpack("<f" if was == "Float" else "<i", payload)[0]
        for payload in (record.default, record.value)
    ]
    exact = [None if n is None else exact_in_type(n, param.is_float) for n in numbers]
    shown = ", ".join(shown_number(n, 32) for n in numbers if n is not None)
    said = f"{record.key}: stored as {was} {shown}, {param.type} in this parameter set"
    if any(e is None for n, e in zip(numbers, exact, strict=True) if n is not None):
        report.append(f"{said}: does not fit; kept unchanged (shown here as its default)")
        return None
    taken = ", ".join(shown_number(e, 32) for e in exact if e is not None)
    report.append(f"{said} (its type changed between PX4 releases): taken as {taken}")
    pack = "<f" if param.is_float else "<i"
    return tuple(None if e is None else struct.pack(pack, e) for e in exact)  # type: ignore[return-value]


def _retyped(record: Record, param: ClassicParam) -> bool:
    """Whether a classic record says the other type than ``param``'s (format 2 says none)."""
    stored = record.classic_type
    return stored != 0 and (stored == CLASSIC_FLOAT) != param.is_float


def _check_float32(name: str, payload: bytes | None) -> None:
    """A float32 record's value that is NaN or an infinity is refused, as :func:`_check_finite`
    refuses one: a record this set keeps unread would otherwise be saved on, to be refused
    whole by the set that reads it."""
    if payload is not None:
        (number,) = struct.unpack("<f", payload)
        if not math.isfinite(number):
            raise ValueRangeError(
                f"{name}: {number} is not a finite number (a Float record: NaN and infinities "
                "are refused)"
            )


def _check_finite(p: _Param, name: str, payload: bytes) -> None:
    """A NaN or an infinity is refused (:class:`ValueRangeError`): nothing stores one, so a file
    holding one was damaged or written by something else. (Values outside ``@min``/``@max``
    are loaded as written: ``param set --force`` stores them.)"""
    if p.spec is not None:
        ranges = leaf_ranges(p.spec.data_type)
        if any(r.float_bits for r in ranges.values()):
            check_leaves(name, p.spec.data_type.leaves(payload, tao=False), ranges, bounds=False)
    elif p.classic is not None and p.classic.is_float and len(payload) == 4:
        (number,) = struct.unpack("<f", payload)
        if not math.isfinite(number):
            raise ValueRangeError(
                f"{name}: {number} is not a finite number (Float: NaN and infinities are refused)"
            )


def _table_key(spec: ParamSpec) -> str:
    return table_lines([spec])[0].partition("=")[2]


# -- version translation ------------------------------------------------------------------------


def stored_version(data_type: DataType, payload: bytes) -> int | None:
    """The minor version a payload was written with: its leading ``p_version`` field."""
    fields = data_type.type_def.fields
    if not fields or fields[0].name != "p_version" or fields[0].kind != "uint":
        return None
    bits = int(fields[0].type["bits"])
    return payload[0] >> (8 - bits) if payload else None


def _current(
    store: Store,
    data_type: DataType,
    name: str,
    payload: bytes,
    base: bytes,
    report: list[str],
) -> bytes:
    """``payload`` in the current version of ``data_type``, translated when it was written by
    another minor version: fields carried over by name, new ones from ``base``."""
    version = data_type.version
    written = stored_version(data_type, payload)
    if version is None or written is None or written == version[1]:
        return payload
    old_key = f"{data_type.name}.{version[0]}.{written}"
    if old_key not in store.schema:
        raise StoreError(f"{name} was stored by {old_key}, which this schema does not have")
    try:  # the core's translation, the one firmware runs
        data, changes = store.schema._native.translate(old_key, payload, data_type.key, base)
    except StoreError as e:
        raise StoreError(f"{name}: cannot translate from {old_key}: {e}") from None
    kept = [path for change, path in changes if change == "kept"]
    new = [path for change, path in changes if change == "new"]
    dropped = [path for change, path in changes if change == "dropped"]
    line = f"{name}: translated {old_key} -> {data_type.key}: kept {', '.join(kept) or 'nothing'}"
    if new:
        line += f"; new, from defaults: {', '.join(new)}"
    if dropped:
        old = store.schema[old_key].decode(payload, tao=False)
        shown = [f"{path}={_shown(value_at(old, path))}" for path in dropped]
        line += f"; dropped: {', '.join(shown)}"
    report.append(line)
    return data


def _shown(value: Any) -> str:
    """A dropped value, as the report shows it (JSON, so that it can be typed back in)."""
    import json

    return json.dumps(value, separators=(",", ":"))
