"""pydronecan as the oracle: our plain values to its value objects and back, and its bytes."""

from __future__ import annotations

import math
import os
from typing import Any

import dronecan
from dronecan import transport


def _parse_bundled() -> dict[str, Any]:
    # dronecan.TYPENAMES lacks namespaces without data type IDs (mppt): parse them all.
    specs = os.path.join(os.path.dirname(dronecan.__file__), "dsdl_specs")
    roots = [os.path.join(specs, d) for d in sorted(os.listdir(specs))]
    return {t.full_name: t for t in dronecan.dsdl.parse_namespaces(roots)}


BUNDLED = _parse_bundled()


def bundled_keys() -> set[str]:
    """Every bundled type as a model key (services as ``<name>.Request/.Response``)."""
    keys = set()
    for name, t in BUNDLED.items():
        if t.kind == t.KIND_SERVICE:
            keys |= {f"{name}.Request", f"{name}.Response"}
        else:
            keys.add(name)
    return keys


def new_value(key: str) -> Any:
    """A pydronecan value object for a model key."""
    for suffix, mode in ((".Request", "request"), (".Response", "response")):
        if key.endswith(suffix):
            return transport.CompoundValue(BUNDLED[key.removesuffix(suffix)], _mode=mode)
    return transport.CompoundValue(BUNDLED[key])


def _fill_array(array: Any, items: list[Any]) -> None:
    static = array._type.mode == dronecan.dsdl.ArrayType.MODE_STATIC
    primitive = isinstance(array._type.value_type, dronecan.dsdl.PrimitiveType)
    for i, item in enumerate(items):
        if primitive:
            if static:
                array[i] = item
            else:
                array.append(item)
        else:
            element = array[i] if static else array.new_item()
            fill(element, item)
            if not static:
                array.append(element)


def fill(obj: Any, value: dict[str, Any]) -> Any:
    """Sets ``obj`` (a pydronecan CompoundValue) from our plain ``value``."""
    fields = transport.get_fields(obj)
    if obj._is_union:
        ((name, inner),) = value.items()
        transport.switch_union_field(obj, name)
        items = [(name, inner)]
    else:
        items = list(value.items())
    for name, inner in items:
        field = fields[name]
        if isinstance(field, transport.PrimitiveValue):
            field.value = inner
        elif isinstance(field, transport.ArrayValue):
            _fill_array(field, inner)
        else:
            fill(field, inner)
    return obj


def to_plain(obj: Any) -> Any:
    """Our plain value of a pydronecan value object."""
    if isinstance(obj, transport.CompoundValue):
        fields = transport.get_fields(obj)
        if obj._is_union:
            name = obj._union_field or next(iter(fields))
            return {name: to_plain(fields[name])}
        return {n: to_plain(f) for n, f in fields.items() if not n.startswith("_void_")}
    if isinstance(obj, transport.ArrayValue):
        return [to_plain(x) if isinstance(x, transport.CompoundValue) else x for x in obj]
    if isinstance(obj, transport.PrimitiveValue):
        return obj.value
    return obj


def pack(obj: Any, *, tao: bool) -> bytes:
    return bytes(transport.bytes_from_bits(obj._pack(tao)))


def unpack(key: str, data: bytes, *, tao: bool) -> Any:
    obj = new_value(key)
    obj._unpack(transport.bits_from_bytes(data), tao)
    return obj


def same(a: Any, b: Any) -> bool:
    """Structural equality with NaN equal to NaN and bools equal to 0/1."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b
