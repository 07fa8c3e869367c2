"""DroneCAN data type signatures of the types in a schema model.

The DSDL signature is the CRC-64-WE of a type's *normalized definition*: its full name, then one
line per field (``<cast mode> <type> <name>``, array sizes as ``[N]`` or ``[<=N]``, nested types
by full name, padding as ``voidN``), ``@union`` before the fields of a union, and for a service
the request fields, ``---``, the response fields. Constants, comments and directives other than
``@union`` are left out. This is the text pydronecan's ``get_dsdl_signature_source_definition()``
gives, byte for byte.

The *data type signature* extends that CRC with the data type signature of each nested type, in
field order (a service's request fields first). It is what a multi-frame transfer's CRC is seeded
with (:func:`transfer_crc_seed`). An ``OVERRIDE_SIGNATURE`` directive replaces the DSDL signature
(the nested types still extend it). Both halves of a service (``.Request``, ``.Response``) have
the service's signature.

Our own ``px.*`` types (pydsdl syntax) get signatures by the same rules, with versionless names
(``px.Ina238``, ``px.Bus bus``) and ``saturated bool``; they have no DroneCAN standard to match,
but a changed layout changes the signature, as it does for DroneCAN types.
"""

from __future__ import annotations

from collections.abc import Mapping, MutableMapping

from px4params import _native
from px4params._records import TYPE_CHECKING
from px4params.errors import DsdlError

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any

__all__ = ["data_type_signature", "normalized_definition", "transfer_crc_seed"]


def normalized_definition(types: Mapping[str, Any], key: str) -> str:
    """The normalized definition text of type ``key`` of the model's ``types``.

    For a service half (``...Request`` / ``...Response``), or the service's own name when its
    halves are DroneCAN keys, the whole service's text.

    Raises:
        KeyError: no type ``key``.
        DsdlError: a service half without its other half, or a reference to an unknown type.
    """
    header, parts = _parts(types, key)
    lines = [header]
    for index, part in enumerate(parts):
        if index:
            lines.append("---")
        spec = types[part]
        if spec["kind"] == "union":
            lines.append("@union")
        lines += [_field_line(types, part, f) for f in spec["fields"]]
    return "\n".join(lines)


def data_type_signature(
    types: Mapping[str, Any], key: str, *, memo: MutableMapping[str, int] | None = None
) -> int:
    """The data type signature (64 bits) of type ``key`` of the model's ``types``.

    ``memo`` (key -> signature) keeps results between calls; pass the same mapping for the same
    ``types``. Both halves of a service are entered.

    Raises:
        KeyError: no type ``key``.
        DsdlError: a service half without its other half, a reference to an unknown type, or a
            type that contains itself.
    """
    memo = {} if memo is None else memo
    return _signature(types, key, memo, ())


def transfer_crc_seed(
    types: Mapping[str, Any], key: str, *, memo: MutableMapping[str, int] | None = None
) -> int:
    """The CRC-16-CCITT-FALSE seed of a multi-frame transfer of type ``key`` (pydronecan's
    ``base_crc``): the CRC of the data type signature's 8 little-endian bytes."""
    return int(_native.transfer_crc_seed(data_type_signature(types, key, memo=memo)))


# --------------------------------------------------------------------------------------------------


def _signature(
    types: Mapping[str, Any], key: str, memo: MutableMapping[str, int], active: tuple[str, ...]
) -> int:
    cached = memo.get(key)
    if cached is not None:
        return cached
    _, parts = _parts(types, key)
    if any(part in active for part in parts):
        chain = " -> ".join((*active, parts[0]))
        raise DsdlError(f"type {parts[0]} contains itself ({chain})", types[parts[0]].get("file"))
    override = types[parts[0]].get("signature_override")
    if override is not None:
        dsdl = int(override)
    else:
        dsdl = int(_native.dsdl_signature(normalized_definition(types, key).encode("utf-8")))
    nested = []
    for part in parts:
        for f in types[part]["fields"]:
            ref = _innermost(f["type"])
            if ref["kind"] == "ref":
                _check_ref(types, part, f, ref)
                nested.append(_signature(types, ref["name"], memo, (*active, *parts)))
    value = int(_native.data_type_signature(dsdl, nested))
    for part in parts:
        memo[part] = value
    if key not in memo:  # a service given by its own name
        memo[key] = value
    return value


def _parts(types: Mapping[str, Any], key: str) -> tuple[str, list[str]]:
    """The name a type's normalized text starts with, and the model keys of its parts: the
    type itself, or a service's request and response."""
    if key not in types and f"{key}.Request" in types and f"{key}.Response" in types:
        key = f"{key}.Request"  # a DroneCAN service by its own name
    spec = types[key]
    service = spec.get("service")
    if not service:
        return str(spec["name"]), [key]
    name = str(spec["name"])
    half = name.rpartition(".")[2]
    if half not in ("Request", "Response") or not key.startswith(name):
        raise DsdlError(
            f"type {key} is marked as part of service {service} but is not its Request or Response",
            spec.get("file"),
        )
    suffix = key[len(name) :]  # "" for DroneCAN keys, ".1.0" for pydsdl keys
    parts = [f"{service}.Request{suffix}", f"{service}.Response{suffix}"]
    for part in parts:
        if part not in types:
            raise DsdlError(f"service {service} has no {part} in the model", spec.get("file"))
    return service, parts


def _field_line(types: Mapping[str, Any], owner: str, f: Mapping[str, Any]) -> str:
    ftype = f["type"]
    if ftype["kind"] == "void":
        return f"void{ftype['bits']}"
    return f"{_type_text(types, owner, f, ftype)} {f['name']}"


def _type_text(
    types: Mapping[str, Any], owner: str, f: Mapping[str, Any], t: Mapping[str, Any]
) -> str:
    kind = t["kind"]
    if kind in ("uint", "int", "float"):
        return f"{t.get('cast', 'saturated')} {kind}{t['bits']}"
    if kind == "bool":
        return f"{t.get('cast', 'saturated')} bool"
    if kind == "void":
        return f"void{t['bits']}"
    if kind == "array":
        return f"{_type_text(types, owner, f, t['elem'])}[{t['len']}]"
    if kind == "dynarray":
        return f"{_type_text(types, owner, f, t['elem'])}[<={t['max']}]"
    if kind == "ref":
        _check_ref(types, owner, f, t)
        return str(types[t["name"]]["name"])  # versionless for pydsdl types
    raise DsdlError(f"{owner}.{f['name']}: unknown type kind {kind!r}", types[owner].get("file"))


def _check_ref(
    types: Mapping[str, Any], owner: str, f: Mapping[str, Any], ref: Mapping[str, Any]
) -> None:
    if ref["name"] not in types:
        spec = types[owner]
        raise DsdlError(
            f"{owner}.{f['name']} refers to unknown type {ref['name']}",
            spec.get("file"),
            f.get("line"),
        )


def _innermost(t: Mapping[str, Any]) -> Mapping[str, Any]:
    while t["kind"] in ("array", "dynarray"):
        t = t["elem"]
    return t
