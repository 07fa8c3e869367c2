"""``DataType.decode_struct``: the decoded value as a ``StructValue`` whose fields are
attributes. It holds what ``decode`` gives (checked against pydronecan's own decoded objects
too), raises what ``decode`` raises, and ``encode`` takes it back."""

from __future__ import annotations

import gc
import inspect
import sys
import weakref
from typing import Any

import px4params
import pytest
from dronecan_oracle import fill, new_value, pack, same, to_plain, unpack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from px4params import StructValue, _native
from strategies import budget, value_strategy
from test_fastcall import outcome

SCHEMA = px4params.load_schema(use_env=False)
TYPES = SCHEMA.model["types"]
STRUCTS = sorted(k for k, d in TYPES.items() if d["kind"] == "struct")
STANDARD = [k for k in STRUCTS if TYPES[k].get("dialect") == "uavcan"]
NODE_STATUS = SCHEMA["uavcan.protocol.NodeStatus"]
STATUS = {
    "uptime_sec": 12345,
    "health": 1,
    "mode": 2,
    "sub_mode": 0,
    "vendor_specific_status_code": 7,
}


def plain(value: Any) -> Any:
    """``value`` with struct values made dicts by reading their attributes (not ``_asdict``)."""
    if isinstance(value, StructValue):
        return {name: plain(getattr(value, name)) for name in value._fields}
    if isinstance(value, list):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    return value


@pytest.mark.parametrize("key", STRUCTS)
@settings(max_examples=budget(6), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_a_struct_value_holds_what_decode_gives(key: str, data: st.DataObject) -> None:
    t = SCHEMA[key]
    raw = t.encode(data.draw(value_strategy(TYPES, key, infinities=False)))
    value = t.decode_struct(raw)
    # repr: NaNs compare equal.
    assert repr(plain(value)) == repr(value._asdict()) == repr(t.decode(raw))
    assert value._type == t.key
    assert t.encode(value) == raw
    # Nested in a dict, as the value of its own field, a struct value is taken as its dict.
    for name in value._fields:
        field = getattr(value, name)
        if isinstance(field, StructValue):
            assert t.encode({**t.decode(raw), name: field}) == raw
    # Cut, lengthened or not bytes: the same result or error as decode, on either path.
    for item in (raw[:-1], raw + b"\x00", bytearray(raw), memoryview(raw)):
        got = outcome(t.decode_struct, item)
        assert got == outcome(t.decode_struct, item, tao=True, allow_trailing=False)
        if got[0] == "result":
            assert repr(plain(t.decode_struct(item))) == repr(t.decode(item))
        else:
            assert got == outcome(t.decode, item)


@pytest.mark.parametrize("key", STANDARD)
@settings(max_examples=budget(4), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data(), tao=st.booleans())
def test_attributes_are_what_pydronecan_decodes(key: str, data: st.DataObject, tao: bool) -> None:
    value = data.draw(value_strategy(TYPES, key, infinities=False))
    theirs_bytes = pack(fill(new_value(key), value), tao=tao)
    ours = SCHEMA[key].decode_struct(theirs_bytes, tao=tao)
    theirs = unpack(key, theirs_bytes, tao=tao)
    for name in ours._fields:
        assert same(plain(getattr(ours, name)), to_plain(getattr(theirs, name))), name


def test_a_node_status_from_pydronecan_reads_field_by_field() -> None:
    data = pack(fill(new_value("uavcan.protocol.NodeStatus"), STATUS), tao=True)
    # uptime 12345 little-endian; health 01, mode 010, sub_mode 000 from the top bit; 7.
    assert data.hex() == "39300000" + "50" + "0700"
    value = NODE_STATUS.decode_struct(data)
    assert (value.uptime_sec, value.health, value.mode, value.sub_mode) == (12345, 1, 2, 0)
    assert value.vendor_specific_status_code == 7
    assert value._fields == tuple(STATUS)
    assert repr(value) == (
        "uavcan.protocol.NodeStatus(uptime_sec=12345, health=1, mode=2, sub_mode=0, "
        "vendor_specific_status_code=7)"
    )


def test_nested_structs_are_struct_values_and_unions_one_key_dicts() -> None:
    t = SCHEMA["px.Ina238"]
    value = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}
    decoded = t.decode_struct(t.encode(value))
    i2c = decoded.bus["i2c"]
    assert isinstance(i2c, StructValue)
    assert (i2c._type, i2c.bus_id, i2c.address) == ("px.I2c.1.0", 1, 0x45)
    assert decoded._asdict()["bus"] == {"i2c": {"p_version": 0, "bus_id": 1, "address": 0x45}}


def test_equality_is_by_type_and_fields() -> None:
    data = NODE_STATUS.encode(STATUS)
    a, b = NODE_STATUS.decode_struct(data), NODE_STATUS.decode_struct(data)
    assert a == b
    assert (a != b) is False
    assert a != NODE_STATUS.decode_struct(NODE_STATUS.encode({**STATUS, "health": 2}))
    assert a != STATUS and a._asdict() == STATUS
    other = px4params.Schema(
        {"types": {"t.T": {**TYPES["uavcan.protocol.NodeStatus"], "name": "t.T"}}}
    )["t.T"]
    assert other.decode(data) == STATUS and other.decode_struct(data) != a
    with pytest.raises(TypeError, match="unhashable type"):
        hash(a)
    with pytest.raises(TypeError, match="not supported"):
        assert a < b


def test_unknown_fields_and_unions_are_refused_by_name() -> None:
    value = NODE_STATUS.decode_struct(NODE_STATUS.encode(STATUS))
    with pytest.raises(AttributeError) as raised:
        _ = value.uptime
    assert str(raised.value) == (
        "uavcan.protocol.NodeStatus has no field 'uptime' (its fields: uptime_sec, health, "
        "mode, sub_mode, vendor_specific_status_code)"
    )
    with pytest.raises(AttributeError):
        value.health = 3  # frozen
    union = SCHEMA["px.Bus"]
    with pytest.raises(TypeError) as raised:
        union.decode_struct(union.default())
    assert str(raised.value) == (
        "px.Bus.1.0: a union has no struct value; decode() gives its one-key dict"
    )
    assert union.decode(union.default()) == {"i2c": {"p_version": 0, "bus_id": 0, "address": 0}}


def test_fields_come_first_in_dir_and_the_method_keeps_its_signature() -> None:
    value = NODE_STATUS.decode_struct(NODE_STATUS.encode(STATUS))
    assert dir(value)[:1] == ["_asdict"] and set(STATUS) <= set(dir(value))
    method = _native.DataType.decode_struct
    assert str(inspect.signature(method)) == "(self, /, data, *, tao=True, allow_trailing=False)"
    assert method.__doc__.startswith("``decode``, into a ``StructValue``")


class Probe:
    """Something a weak reference can watch."""


def test_a_cycle_through_a_list_field_is_collected() -> None:
    t = SCHEMA["uavcan.equipment.power.BatteryInfo"]
    value = t.decode_struct(t.default())
    probe = Probe()
    value.model_name.extend([probe, value])
    watch = weakref.ref(probe)
    del value, probe
    gc.collect()
    assert watch() is None


def test_no_references_are_leaked_or_lost() -> None:
    data = NODE_STATUS.encode(STATUS)
    buffer = bytearray(data)
    value = NODE_STATUS.decode_struct(data)
    before = [sys.getrefcount(x) for x in (NODE_STATUS, data, buffer, value)]
    for _ in range(1000):
        NODE_STATUS.decode_struct(data)
        NODE_STATUS.decode_struct(buffer)
        NODE_STATUS.encode(value)
        value.uptime_sec  # noqa: B018 (the read is what is tested)
        with pytest.raises(px4params.DecodeError):
            NODE_STATUS.decode_struct(data[:3])
    after = [sys.getrefcount(x) for x in (NODE_STATUS, data, buffer, value)]
    assert after == before
