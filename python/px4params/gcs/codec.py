"""Structured parameters for ground stations: encode and decode from ``parameters.json`` alone.

A ground station has no DSDL: it has the vehicle's ``parameters.json``. A structured entry's
``fields`` (see :mod:`px4params.gcs.metadata`) say everything the DroneCAN serialization needs: each
leaf's type and cast mode, every union's variants, every dynamic array's element. This module
reads that description and nothing else (the standard library only: no pydsdl, no native code),
so it can be copied into a ground station as it is.

>>> codecs = load("parameters.json")                                    # doctest: +SKIP
>>> ina = codecs["INA238"]                                               # doctest: +SKIP
>>> data = ina.encode({"bus": {"i2c": {"bus_id": 1, "address": 0x45}},  # doctest: +SKIP
...                    "current": 200, "shunt": 0.0003})
>>> ina.decode(data)["bus"]["i2c"]["address"]                            # doctest: +SKIP
69

Values have the shape the rest of px4params uses: a struct is a dict (``p_version`` may be left
out and is filled in), a union a dict with one key, arrays lists (``uint8`` arrays also take
``bytes`` or ``str``), floats may be ``"nan"``, ``"inf"``, ``"-inf"``. Stored parameters use no
tail array optimization, hence ``tao=False`` by default.
"""

from __future__ import annotations

import json
import math
import os
import re
import struct
from collections.abc import Mapping, Sequence
from typing import Any

__all__ = [
    "GcsCodecError",
    "GcsDecodeError",
    "GcsEncodeError",
    "MetadataFormatError",
    "ParamCodec",
    "f16_from_float",
    "float_from_f16",
    "load",
    "structured_entries",
]


class GcsCodecError(ValueError):
    """Base class of this module's errors."""


class MetadataFormatError(GcsCodecError):
    """A ``parameters.json`` or an entry that does not describe a structured parameter."""


class GcsEncodeError(GcsCodecError):
    """A value that does not fit the parameter (wrong shape, out of range)."""


class GcsDecodeError(GcsCodecError):
    """Bytes that are no value of the parameter (truncated, bad union tag, too long)."""


def structured_entries(document: Mapping[str, Any]) -> dict[str, Mapping[str, Any]]:
    """The structured entries (those with ``fields``) of a parameters.json document, by name."""
    if not isinstance(document, Mapping) or not isinstance(document.get("parameters"), list):
        raise MetadataFormatError(
            "not a parameters.json (expected an object with a 'parameters' list)"
        )
    if document.get("version") != 1:
        raise MetadataFormatError(
            f"parameters.json version {document.get('version')!r} (expected 1)"
        )
    return {
        str(e.get("name")): e
        for e in document["parameters"]
        if isinstance(e, Mapping) and "fields" in e
    }


def load(source: str | os.PathLike[str] | Mapping[str, Any]) -> dict[str, ParamCodec]:
    """A codec for every structured parameter of a parameters.json (a path or the document)."""
    if isinstance(source, Mapping):
        document: Any = source
    else:
        where = os.fspath(source)
        try:
            with open(where, encoding="utf-8") as f:
                document = json.load(f)
        except OSError as e:
            raise MetadataFormatError(f"{where}: cannot read: {e.strerror}") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise MetadataFormatError(f"{where}: not JSON: {e}") from None
    return {name: ParamCodec(entry) for name, entry in structured_entries(document).items()}


class ParamCodec:
    """Encodes and decodes the values of one structured parameter."""

    def __init__(self, entry: Mapping[str, Any]) -> None:
        self.name = str(entry.get("name", "?"))
        fields = entry.get("fields")
        if not isinstance(fields, list):
            raise MetadataFormatError(f"{self.name}: no 'fields' list: not a structured parameter")
        self.entry = entry
        #: Instance slots, or None for a shared parameter.
        self.max_instances: int | None = entry.get("max_instances")
        try:
            self._root = _Parser(self.name).node("", fields)
        except (KeyError, TypeError, ValueError, IndexError) as e:
            if isinstance(e, MetadataFormatError):
                raise
            raise MetadataFormatError(f"{self.name}: malformed 'fields': {e!r}") from None

    def encode(self, value: Any, *, tao: bool = False, saturate: bool = False) -> bytes:
        """The DroneCAN encoding of ``value``. Out-of-range numbers are refused unless
        ``saturate`` is set, which applies the fields' cast modes."""
        out = _Writer()
        self._root.encode(_Encoding(self.name, saturate), out, value, "", tao)
        return out.to_bytes()

    def decode(self, data: bytes, *, tao: bool = False, allow_trailing: bool = False) -> Any:
        """The value encoded in ``data``; whole bytes after it are refused unless
        ``allow_trailing``."""
        reader = _Reader(self.name, bytes(data))
        value = self._root.decode(reader, "", tao)
        used = (reader.pos + 7) // 8
        if not allow_trailing and used < len(data):
            raise GcsDecodeError(
                f"{self.name}: data is too long: the value ends after {used} bytes, "
                f"the data has {len(data)} (at bit {reader.pos})"
            )
        return value

    def __repr__(self) -> str:
        return f"<ParamCodec {self.name}>"


# --- bits -------------------------------------------------------------------------------------


class _Writer:
    """Bits most significant first, into one growing integer."""

    def __init__(self) -> None:
        self.acc = 0
        self.bits = 0

    def write(self, stream: int, bits: int) -> None:
        self.acc = (self.acc << bits) | stream
        self.bits += bits

    def to_bytes(self) -> bytes:
        pad = -self.bits % 8  # the value is zero-padded to a byte boundary
        return (self.acc << pad).to_bytes((self.bits + pad) // 8, "big")


class _Reader:
    def __init__(self, name: str, data: bytes) -> None:
        self.name = name
        self.value = int.from_bytes(data, "big")
        self.total = len(data) * 8
        self.pos = 0

    def read(self, bits: int, path: str) -> int:
        if self.pos + bits > self.total:
            raise GcsDecodeError(
                f"{_where(self.name, path)}data is truncated: needs at least "
                f"{self.pos + bits} bits, has {self.total} (at bit {self.pos})"
            )
        shift = self.total - self.pos - bits
        self.pos += bits
        return (self.value >> shift) & ((1 << bits) - 1)

    def remaining(self) -> int:
        return self.total - self.pos


def _to_stream(value: int, bits: int) -> int:
    """DroneCAN byte order: the whole low bytes first, then the top ``bits % 8`` bits."""
    whole, rest = divmod(bits, 8)
    out = 0
    for i in range(whole):
        out = (out << 8) | ((value >> (8 * i)) & 0xFF)
    if rest:
        out = (out << rest) | ((value >> (8 * whole)) & ((1 << rest) - 1))
    return out


def _from_stream(stream: int, bits: int) -> int:
    whole, rest = divmod(bits, 8)
    value = (stream & ((1 << rest) - 1)) << (8 * whole)
    stream >>= rest
    for i in range(whole):
        value |= ((stream >> (8 * (whole - 1 - i))) & 0xFF) << (8 * i)
    return value


def f16_from_float(value: float) -> int:
    """IEEE binary16 bits as libuavcan/libcanard make them: the float is first rounded to
    float32, then to the nearest float16 with ties away from zero; overflow gives infinity, NaN
    0x7FFF (with its sign)."""
    bits: int = struct.unpack("<I", struct.pack("<f", value))[0]
    sign = (bits >> 16) & 0x8000
    bits &= 0x7FFF_FFFF
    if bits > 0x7F80_0000:
        return sign | 0x7FFF
    if bits == 0x7F80_0000:
        return sign | 0x7C00
    exp = (bits >> 23) - 127
    if exp < -25:  # below half the smallest subnormal (float32 subnormals included)
        return sign
    mant = (bits & 0x7F_FFFF) | 0x80_0000  # 24 significant bits: value = mant * 2**(exp-23)
    if exp < -14:
        shift = -1 - exp  # to units of 2**-24, the float16 subnormal step
        return sign | ((mant + (1 << (shift - 1))) >> shift)
    rounded = (mant + 0x1000) >> 13  # adding half a float16 ulp first: ties away from zero
    exp16 = exp + 15
    if rounded == 0x800:
        rounded, exp16 = 0x400, exp16 + 1
    if exp16 >= 31:
        return sign | 0x7C00
    return sign | (exp16 << 10) | (rounded - 0x400)


def float_from_f16(half: int) -> float:
    """The exact value of IEEE binary16 bits."""
    sign = -1.0 if half & 0x8000 else 1.0
    exp, mant = (half >> 10) & 0x1F, half & 0x3FF
    if exp == 0:
        return sign * mant * 2.0**-24
    if exp == 31:
        # NaN keeps its sign, so that decoding and encoding again gives the same bits.
        return sign * math.inf if mant == 0 else math.copysign(math.nan, sign)
    return sign * (0x400 | mant) * 2.0 ** (exp - 25)


# --- the tree rebuilt from the flat field list -------------------------------------------------

_HEAD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_SCALAR = re.compile(r"(bool)|(uint|int|float|void)([1-9][0-9]*)")
_INDEX = re.compile(r"\[([0-9]+)\]")
_FLOAT_LIMIT = {16: 65504.0, 32: 3.4028234663852886e38, 64: 1.7976931348623157e308}
_NONFINITE = {"nan": math.nan, "inf": math.inf, "+inf": math.inf, "-inf": -math.inf}


def _where(name: str, path: str) -> str:
    return f"{name}: {path}: " if path else f"{name}: "


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _type_name(value: Any) -> str:
    return type(value).__name__


class _Encoding:
    """What an encode call carries through the tree."""

    def __init__(self, name: str, saturate: bool) -> None:
        self.name = name
        self.saturate = saturate

    def fail(self, path: str, message: str) -> GcsEncodeError:
        return GcsEncodeError(f"{_where(self.name, path)}{message}")


class _Node:
    def encode(self, ctx: _Encoding, out: _Writer, value: Any, path: str, tao: bool) -> None:
        raise NotImplementedError

    def decode(self, reader: _Reader, path: str, tao: bool) -> Any:
        raise NotImplementedError


class _Parser:
    """Turns a flat field list (leaves in ``[k]`` order, grouped by path) back into a tree."""

    def __init__(self, name: str) -> None:
        self.name = name

    def fail(self, message: str) -> MetadataFormatError:
        return MetadataFormatError(f"{self.name}: fields: {message}")

    def node(self, path: str, entries: Sequence[Mapping[str, Any]]) -> _Node:
        """The node at ``path`` from the entries that describe it."""
        if not entries:
            return _Struct([])  # a struct without fields, e.g. an empty union variant
        first = entries[0]
        where = str(first.get("path", ""))
        role = first.get("role")
        if where == path and role in ("value", "version"):
            return self.scalar(first)
        if role == "union_tag" and where == f"{path}._tag":
            return self.union(path, first)
        if role == "length" and where == f"{path}._len":
            return self.dynarray(path, first)
        if path and where.startswith(f"{path}["):
            return self.array(path, entries)
        return self.struct(path, entries)

    def scalar(self, entry: Mapping[str, Any]) -> _Scalar:
        kind, bits = self.scalar_type(entry)
        if kind == "void":
            raise self.fail(f"{entry.get('path')}: {entry['type']} is not a value type")
        version = int(entry["default"]) if entry.get("role") == "version" else None
        cast = str(entry.get("cast", "saturated"))
        if cast not in ("saturated", "truncated"):
            raise self.fail(f"{entry.get('path')}: unknown cast mode {cast!r}")
        return _Scalar(kind, bits, cast, version)

    def scalar_type(self, entry: Mapping[str, Any]) -> tuple[str, int]:
        match = _SCALAR.fullmatch(str(entry.get("type")))
        if not match:
            raise self.fail(f"{entry.get('path')}: unknown type {entry.get('type')!r}")
        if match.group(1):
            return "bool", 1
        kind, bits = match.group(2), int(match.group(3))
        if (kind == "float" and bits not in _FLOAT_LIMIT) or bits > 64:
            raise self.fail(f"{entry.get('path')}: unknown type {entry.get('type')!r}")
        return kind, bits

    def uint_width(self, entry: Mapping[str, Any]) -> int:
        kind, bits = self.scalar_type(entry)
        if kind != "uint":
            raise self.fail(f"{entry.get('path')}: expected a uintN type, got {entry['type']!r}")
        return bits

    def union(self, path: str, entry: Mapping[str, Any]) -> _Union:
        variants = sorted(entry["variants"], key=lambda v: int(v["tag"]))
        if [int(v["tag"]) for v in variants] != list(range(len(variants))) or not variants:
            raise self.fail(f"{path}: union variants must be numbered 0..n-1")
        nodes = [(str(v["name"]), self.node(_join(path, v["name"]), v["fields"])) for v in variants]
        return _Union(self.uint_width(entry), nodes)

    def dynarray(self, path: str, entry: Mapping[str, Any]) -> _DynArray:
        elem = self.node(f"{path}[]", entry["element"])
        return _DynArray(
            elem, int(entry["max"]), self.uint_width(entry), int(entry["element_min_bits"])
        )

    def array(self, path: str, entries: Sequence[Mapping[str, Any]]) -> _Array:
        first_index: list[Mapping[str, Any]] = []
        indices: list[int] = []
        for e in entries:
            match = _INDEX.match(str(e.get("path", "")), len(path))
            if not match:
                raise self.fail(f"{e.get('path')}: expected an element of {path}")
            i = int(match.group(1))
            if not indices or indices[-1] != i:
                indices.append(i)
            if i == 0:
                first_index.append(e)
        if indices != list(range(len(indices))):
            raise self.fail(f"{path}: array elements must be numbered 0..n-1")
        return _Array(self.node(f"{path}[0]", first_index), len(indices))

    def struct(self, path: str, entries: Sequence[Mapping[str, Any]]) -> _Struct:
        prefix = f"{path}." if path else ""
        fields: list[tuple[str | None, _Node]] = []
        group: list[Mapping[str, Any]] = []
        head = ""
        for e in entries:
            where = str(e.get("path", ""))
            if not where.startswith(prefix):
                raise self.fail(f"{where!r} is not inside {path!r}")
            rest = where[len(prefix) :]
            if e.get("role") == "padding" and rest == "_pad":
                if group:
                    fields.append((head, self.node(prefix + head, group)))
                    group = []
                kind, bits = self.scalar_type(e)
                if kind != "void":
                    raise self.fail(f"{where}: padding must be voidN, got {e['type']!r}")
                fields.append((None, _Pad(bits)))
                continue
            match = _HEAD.match(rest)
            if not match:
                raise self.fail(f"{where!r}: expected a field name after {prefix!r}")
            if group and match.group(0) != head:
                fields.append((head, self.node(prefix + head, group)))
                group = []
            head = match.group(0)
            group.append(e)
        if group:
            fields.append((head, self.node(prefix + head, group)))
        names = [n for n, _ in fields if n is not None]
        if len(set(names)) != len(names):
            raise self.fail(f"{path or 'the value'}: a field appears twice")
        return _Struct(fields)


class _Pad(_Node):
    def __init__(self, bits: int) -> None:
        self.bits = bits

    def encode(self, ctx: _Encoding, out: _Writer, value: Any, path: str, tao: bool) -> None:
        out.write(0, self.bits)

    def decode(self, reader: _Reader, path: str, tao: bool) -> Any:
        reader.read(self.bits, path)


class _Scalar(_Node):
    def __init__(self, kind: str, bits: int, cast: str, version: int | None) -> None:
        self.kind, self.bits, self.cast, self.version = kind, bits, cast, version

    def encode(self, ctx: _Encoding, out: _Writer, value: Any, path: str, tao: bool) -> None:
        out.write(_to_stream(self.raw(ctx, value, path), self.bits), self.bits)

    def raw(self, ctx: _Encoding, value: Any, path: str) -> int:
        if self.kind == "bool":
            if isinstance(value, bool):
                return int(value)
            if not isinstance(value, int):
                raise ctx.fail(path, f"expected a boolean, got {_type_name(value)}")
            if value not in (0, 1):
                raise ctx.fail(
                    path, f"value {value} is out of range (expected a boolean: true, false, 0 or 1)"
                )
            return value
        if self.kind == "float":
            return self.float_raw(ctx, value, path)
        if isinstance(value, bool) and not (self.kind == "uint" and self.bits == 1):
            raise ctx.fail(path, f"expected an integer, got {_type_name(value)}")
        if not isinstance(value, int):
            raise ctx.fail(path, f"expected an integer, got {_type_name(value)}")
        mask = (1 << self.bits) - 1
        low, high = (0, mask) if self.kind == "uint" else (-(mask >> 1) - 1, mask >> 1)
        if not low <= value <= high:
            if self.cast == "truncated":
                return value & mask  # two's complement for negative values
            if not ctx.saturate:
                raise ctx.fail(path, f"value {value} is out of range (expected {low} to {high})")
            return min(max(value, low), high) & mask
        return value & mask

    def float_raw(self, ctx: _Encoding, value: Any, path: str) -> int:
        if isinstance(value, str) and value.lower() in _NONFINITE:
            number = _NONFINITE[value.lower()]
        elif isinstance(value, int | float) and not isinstance(value, bool):
            number = float(value)
        else:
            raise ctx.fail(
                path, f'expected a number (or "nan", "inf", "-inf"), got {_type_name(value)}'
            )
        limit = _FLOAT_LIMIT[self.bits]
        if math.isfinite(number) and abs(number) > limit:
            if self.cast == "truncated":
                number = math.copysign(math.inf, number)
            elif ctx.saturate:
                number = math.copysign(limit, number)
            else:
                raise ctx.fail(
                    path, f"value {value:g} is out of range (expected {-limit:g} to {limit:g})"
                )
        if self.bits == 16:
            return f16_from_float(number)
        single, double = ("<f", "<I") if self.bits == 32 else ("<d", "<Q")
        raw: int = struct.unpack(double, struct.pack(single, number))[0]
        return raw

    def decode(self, reader: _Reader, path: str, tao: bool) -> Any:
        raw = _from_stream(reader.read(self.bits, path), self.bits)
        if self.kind == "bool":
            return bool(raw)
        if self.kind == "uint":
            return raw
        if self.kind == "int":
            return raw - (1 << self.bits) if raw >> (self.bits - 1) else raw
        if self.bits == 16:
            return float_from_f16(raw)
        if self.bits == 32:
            return struct.unpack("<f", raw.to_bytes(4, "little"))[0]
        return struct.unpack("<d", raw.to_bytes(8, "little"))[0]


class _Struct(_Node):
    def __init__(self, fields: list[tuple[str | None, _Node]]) -> None:
        self.fields = fields
        self.names = [n for n, _ in fields if n is not None]

    def encode(self, ctx: _Encoding, out: _Writer, value: Any, path: str, tao: bool) -> None:
        if not isinstance(value, Mapping):
            raise ctx.fail(path, f"expected a dict (struct), got {_type_name(value)}")
        unknown = [k for k in value if k not in self.names]
        if unknown:
            raise ctx.fail(
                path, f"unknown field {unknown[0]!r} (expected: {', '.join(self.names)})"
            )
        last = len(self.fields) - 1
        for i, (name, node) in enumerate(self.fields):
            # Tail array optimization reaches only the last field (padding counts).
            tail = tao and i == last
            if name is None:
                node.encode(ctx, out, None, path, tail)
                continue
            fpath = _join(path, name)
            if name in value:
                if isinstance(node, _Scalar) and node.version is not None:
                    given = value[name]
                    if isinstance(given, bool) or given != node.version:
                        raise ctx.fail(
                            fpath,
                            f"p_version is set automatically; got {given!r}, "
                            f"the type's version is {node.version}",
                        )
                node.encode(ctx, out, value[name], fpath, tail)
            elif isinstance(node, _Scalar) and node.version is not None:
                node.encode(ctx, out, node.version, fpath, tail)
            else:
                raise ctx.fail(fpath, "missing field")

    def decode(self, reader: _Reader, path: str, tao: bool) -> Any:
        value: dict[str, Any] = {}
        last = len(self.fields) - 1
        for i, (name, node) in enumerate(self.fields):
            if name is None:
                node.decode(reader, path, tao and i == last)
            else:
                value[name] = node.decode(reader, _join(path, name), tao and i == last)
        return value


class _Union(_Node):
    def __init__(self, tag_bits: int, variants: list[tuple[str, _Node]]) -> None:
        self.tag_bits = tag_bits
        self.variants = variants
        self.names = [n for n, _ in variants]

    def encode(self, ctx: _Encoding, out: _Writer, value: Any, path: str, tao: bool) -> None:
        choices = ", ".join(self.names)
        if not isinstance(value, Mapping):
            raise ctx.fail(
                path,
                f"expected a dict with one key, the union variant ({choices}), "
                f"got {_type_name(value)}",
            )
        if len(value) != 1:
            raise ctx.fail(
                path, f"a union takes exactly one variant ({choices}), got {len(value)} keys"
            )
        ((name, inner),) = value.items()
        if name not in self.names:
            raise ctx.fail(path, f"unknown union variant {name!r} (expected one of: {choices})")
        tag = self.names.index(name)
        out.write(_to_stream(tag, self.tag_bits), self.tag_bits)
        self.variants[tag][1].encode(ctx, out, inner, _join(path, name), tao)

    def decode(self, reader: _Reader, path: str, tao: bool) -> Any:
        at = reader.pos
        tag = _from_stream(reader.read(self.tag_bits, path), self.tag_bits)
        if tag >= len(self.variants):
            raise GcsDecodeError(
                f"{_where(reader.name, path)}union tag {tag} selects no variant "
                f"(expected 0..{len(self.variants) - 1}) (at bit {at})"
            )
        name, node = self.variants[tag]
        return {name: node.decode(reader, _join(path, name), tao)}


def _elements(ctx: _Encoding, elem: _Node, value: Any, path: str) -> list[Any]:
    if isinstance(value, bytes | bytearray | str) and (
        isinstance(elem, _Scalar) and elem.kind == "uint" and elem.bits == 8
    ):
        return list(value.encode("utf-8") if isinstance(value, str) else value)
    if not isinstance(value, list | tuple):
        raise ctx.fail(path, f"expected a list (array), got {_type_name(value)}")
    return list(value)


class _Array(_Node):
    def __init__(self, elem: _Node, length: int) -> None:
        self.elem, self.length = elem, length

    def encode(self, ctx: _Encoding, out: _Writer, value: Any, path: str, tao: bool) -> None:
        items = _elements(ctx, self.elem, value, path)
        if len(items) != self.length:
            raise ctx.fail(path, f"array has {len(items)} elements, expected exactly {self.length}")
        for i, item in enumerate(items):
            self.elem.encode(ctx, out, item, f"{path}[{i}]", tao and i == self.length - 1)

    def decode(self, reader: _Reader, path: str, tao: bool) -> Any:
        return [
            self.elem.decode(reader, f"{path}[{i}]", tao and i == self.length - 1)
            for i in range(self.length)
        ]


class _DynArray(_Node):
    def __init__(self, elem: _Node, max_len: int, len_bits: int, elem_min_bits: int) -> None:
        self.elem, self.max, self.len_bits = elem, max_len, len_bits
        # Elements of 8 bits or more make the array's length implied when it is last.
        self.tail_capable = elem_min_bits >= 8

    def encode(self, ctx: _Encoding, out: _Writer, value: Any, path: str, tao: bool) -> None:
        items = _elements(ctx, self.elem, value, path)
        if len(items) > self.max:
            raise ctx.fail(path, f"array has {len(items)} elements, at most {self.max} allowed")
        tail = tao and self.tail_capable
        if not tail:
            out.write(_to_stream(len(items), self.len_bits), self.len_bits)
        for i, item in enumerate(items):
            # Under TAO the elements are not last (the array has no end marker); otherwise the
            # flag passes on to the last element.
            self.elem.encode(
                ctx, out, item, f"{path}[{i}]", tao and not tail and i == len(items) - 1
            )

    def decode(self, reader: _Reader, path: str, tao: bool) -> Any:
        items: list[Any] = []
        if tao and self.tail_capable:
            while reader.remaining() >= 8:
                if len(items) == self.max:
                    raise GcsDecodeError(
                        f"{_where(reader.name, path)}array has more than {self.max} elements "
                        f"(at bit {reader.pos})"
                    )
                items.append(self.elem.decode(reader, f"{path}[{len(items)}]", False))
            return items
        at = reader.pos
        n = _from_stream(reader.read(self.len_bits, path), self.len_bits)
        if n > self.max:
            raise GcsDecodeError(
                f"{_where(reader.name, path)}array length {n} exceeds the maximum of {self.max} "
                f"(at bit {at})"
            )
        return [self.elem.decode(reader, f"{path}[{i}]", tao and i == n - 1) for i in range(n)]
