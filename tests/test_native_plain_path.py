"""Encoding takes a type's compiled program for plain values (dicts, lists, tuples, ints, floats
of the exact built-in types); the general path takes anything else. Whichever is taken, the
bytes and errors are the same: here the general path is forced with dict and list subclasses.
Decoding is the program's alone (pydronecan is its reference, in test_pydronecan_diff.py);
here the same bytes are decoded whole and in pieces, which are joined first."""

from __future__ import annotations

from typing import Any

import px4params
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import budget, value_strategy

SCHEMA = px4params.load_schema(use_env=False)
TYPES = SCHEMA.model["types"]
KEYS = sorted(k for k, d in TYPES.items() if d["kind"] in ("struct", "union"))


class Record(dict):  # type: ignore[type-arg]
    """Not an exact dict: the encoder reads it the general way."""


class Items(list):  # type: ignore[type-arg]
    """Not an exact list: the encoder reads it the general way."""


def general(value: Any) -> Any:
    """``value`` with every dict and list replaced by a subclass."""
    if isinstance(value, dict):
        return Record({k: general(v) for k, v in value.items()})
    if isinstance(value, list):
        return Items(general(v) for v in value)
    return value


def outcome(t: px4params.DataType, value: Any, **options: Any) -> tuple[str, str]:
    try:
        return ("bytes", t.encode(value, **options).hex())
    except Exception as e:  # the class and the message must agree
        # Messages name the type given: the subclasses stand for dict and list.
        text = str(e).replace("got Record", "got dict").replace("got Items", "got list")
        return (type(e).__name__, text)


def spoiled(value: Any, how: int, key_index: int) -> Any:
    """``value`` broken in one of several ways a user breaks values."""
    if not isinstance(value, dict) or not value:
        return {"unknown": 1} if how % 2 else 3
    keys = list(value)
    key = keys[key_index % len(keys)]
    broken = dict(value)
    if how == 0:
        del broken[key]
    elif how == 1:
        broken["no_such_field"] = 0
    elif how == 2:
        broken[key] = 1 << 70  # beyond 64 bits
    elif how == 3:
        broken[key] = "text"
    elif how == 4:
        broken[key] = True
    elif how == 5:
        broken[key] = -1
    elif how == 6:
        broken[key] = [1, 2, 3]
    elif how == 7:
        broken[key] = 2.5
    elif how == 8:
        broken[key] = "nan"
    else:
        broken[key] = {"x": 1}
    return broken


@pytest.mark.parametrize("key", KEYS)
@settings(max_examples=budget(8), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data(), tao=st.booleans(), saturate=st.booleans())
def test_fast_and_general_paths_agree(
    key: str, data: st.DataObject, tao: bool, saturate: bool
) -> None:
    t = SCHEMA[key]
    value = data.draw(value_strategy(TYPES, key, infinities=False))
    options = {"tao": tao, "saturate": saturate}
    fast = outcome(t, value, **options)
    assert fast == outcome(t, general(value), **options)
    assert fast[0] == "bytes"
    broken = spoiled(value, data.draw(st.integers(0, 9)), data.draw(st.integers(0, 50)))
    assert outcome(t, broken, **options) == outcome(t, general(broken), **options)


def test_byte_strings_tuples_and_interned_keys_take_the_fast_path_to_the_same_bytes() -> None:
    t = SCHEMA["uavcan.equipment.power.BatteryInfo"]
    value = {
        "temperature": 300.5,
        "voltage": 16,  # an int for a float field
        "current": -12.25,
        "average_power_10sec": 201.0,
        "remaining_capacity_wh": 55.5,
        "full_charge_capacity_wh": 99.0,
        "hours_to_full_charge": 0.0,
        "status_flags": 3,
        "state_of_health_pct": 97,
        "state_of_charge_pct": 80,
        "state_of_charge_pct_stdev": 2,
        "battery_id": 1,
        "model_instance_id": 123456,
        "model_name": "PX4 battery",
    }
    expected = t.encode(general(value))
    assert t.encode(value) == expected
    assert t.encode({**value, "model_name": b"PX4 battery"}) == expected
    assert t.encode({**value, "model_name": tuple(b"PX4 battery")}) == expected
    # Keys in another order, and keys that are equal strings but not the interned names.
    reordered = {"".join(list(k)): value[k] for k in reversed(list(value))}
    assert t.encode(reordered) == expected
    assert t.decode(expected)["model_name"] == list(b"PX4 battery")


def test_decode_takes_any_bytes_like_data() -> None:
    t = SCHEMA["uavcan.protocol.NodeStatus"]
    data = bytes.fromhex("39300000000700")
    value = t.decode(data)
    assert value == {
        "uptime_sec": 12345,
        "health": 0,
        "mode": 0,
        "sub_mode": 0,
        "vendor_specific_status_code": 7,
    }
    assert t.decode(bytearray(data)) == value
    assert t.decode(memoryview(data)) == value
    with pytest.raises(TypeError):
        t.decode(12345)  # type: ignore[arg-type]


def test_decoded_dicts_are_new_each_time() -> None:
    # Decoding copies a dict of the field names per struct: the copies must not share values.
    t = SCHEMA["uavcan.protocol.NodeStatus"]
    first = t.decode(bytes.fromhex("39300000000700"))
    first["uptime_sec"] = 0
    assert t.decode(bytes.fromhex("39300000000700"))["uptime_sec"] == 12345


def decoded(t: px4params.DataType, data: bytes, pieces: int, **options: Any) -> tuple[str, str]:
    try:
        if pieces == 1:
            return ("value", repr(t.decode(data, **options)))
        cut = len(data) // pieces
        fragments = [data[:cut], data[cut:]] if pieces == 2 else [data[:cut], b"", data[cut:]]
        return ("value", repr(t.decode_fragments(fragments, **options)))
    except Exception as e:  # the class and the message must agree
        return (type(e).__name__, str(e))


@pytest.mark.parametrize("key", KEYS)
@settings(max_examples=budget(8), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data(), tao=st.booleans(), allow_trailing=st.booleans())
def test_whole_and_fragmented_decoding_agree(
    key: str, data: st.DataObject, tao: bool, allow_trailing: bool
) -> None:
    t = SCHEMA[key]
    value = data.draw(value_strategy(TYPES, key, infinities=True))
    encoded = t.encode(value, tao=tao)
    # The value's bytes, cut short, with bytes after them, or changed at random.
    how = data.draw(st.integers(0, 3))
    if how == 1 and encoded:
        encoded = encoded[: data.draw(st.integers(0, len(encoded) - 1))]
    elif how == 2:
        encoded += data.draw(st.binary(min_size=1, max_size=4))
    elif how == 3:
        encoded = data.draw(st.binary(max_size=len(encoded) + 2))
    options = {"tao": tao, "allow_trailing": allow_trailing}
    whole = decoded(t, encoded, 1, **options)
    assert whole == decoded(t, encoded, data.draw(st.integers(2, 3)), **options)
    if how == 0:
        assert whole[0] == "value"


class Sneaky:
    """A key with a field name's hash, so that looking that field up compares it, and the
    comparison runs ``action`` once armed."""

    def __init__(self, name: str, action: Any) -> None:
        self.name, self.action, self.armed = name, action, False

    def __hash__(self) -> int:
        return hash(self.name)

    def __eq__(self, other: object) -> bool:
        if self.armed:
            self.action()
        return False


def test_python_code_run_by_a_field_look_up_is_survived() -> None:
    t = SCHEMA["uavcan.protocol.NodeStatus"]
    fields = {"uptime_sec": 1, "health": 0, "mode": 0, "sub_mode": 0}
    fields["vendor_specific_status_code"] = 7

    def compared() -> None:
        raise RuntimeError("compared")

    # Its exception comes out unchanged, whichever path met it first.
    value: dict[Any, Any] = {}
    sneaky = Sneaky("mode", compared)
    value[sneaky] = 1
    value.update(fields)
    sneaky.armed = True
    with pytest.raises(RuntimeError, match="compared"):
        t.encode(value)
    # A look-up that empties the dict: read as it then is, with nothing freed under the reader.
    value = {}
    sneaky = Sneaky("mode", value.clear)
    value[sneaky] = 1
    value.update(fields)
    sneaky.armed = True
    with pytest.raises(px4params.ValueShapeError, match="uptime_sec: missing field"):
        t.encode(value)


def test_small_ints_are_read_and_made_as_the_numbers_they_are() -> None:
    """Ints 0 to 255 are CPython's own objects, which the program knows by their address (a
    value read, a value made): every one of them, and the numbers around them, encode as the
    DroneCAN rules say (uint8 items are the bytes; int16 little-endian; a bool the next bit)
    and decode to themselves."""
    uint8 = {"kind": "uint", "bits": 8, "cast": "saturated"}
    fields = [
        ("items", {"kind": "dynarray", "elem": uint8, "max": 255}),
        ("wide", {"kind": "int", "bits": 16, "cast": "saturated"}),
        ("flag", {"kind": "bool"}),
    ]
    model = {"t.B": {"kind": "struct", "fields": [{"name": n, "type": t} for n, t in fields]}}
    t = px4params._native.Schema(model).get("t.B")
    items = list(range(255))
    for wide in (0, 1, 7, 255, 256, 257, -1, -5, -6, 32767, -32768):
        for flag in (0, 1, True, False):
            data = t.encode({"items": items, "wide": wide, "flag": flag})
            expected = bytes([255, *items]) + wide.to_bytes(2, "little", signed=True)
            assert data == expected + (b"\x80" if flag else b"\x00")
            value = t.decode(data)
            assert value == {"items": items, "wide": wide, "flag": bool(flag)}
            assert all(got is want for got, want in zip(value["items"], items, strict=True))
    with pytest.raises(px4params.errors.EncodeError, match=r"items\[0\]: value 256 is out"):
        t.encode({"items": [256], "wide": 0, "flag": 0})
    with pytest.raises(px4params.errors.EncodeError, match=r"flag: value 2 is out of range"):
        t.encode({"items": [], "wide": 0, "flag": 2})


def test_numpy_numbers_give_the_bytes_their_values_give() -> None:
    # numpy's int64 and float32 were refused ("expected an integer, got int64"), where the
    # docs promise the general path's same bytes. Numbers count by what they declare
    # (numbers.Integral, numbers.Real): numpy's bool declares neither, and is no number.
    import fractions

    import numpy as np

    ina = SCHEMA["px.Ina238"]
    plain = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}
    given = {
        "bus": {"i2c": {"bus_id": np.uint8(1), "address": np.int16(0x45)}},
        "current": np.int64(200),
        "shunt": np.float32(0.0003),
    }
    assert ina.encode(given) == ina.encode(plain)
    assert ina.encode({**plain, "shunt": fractions.Fraction(3, 10000)}) == ina.encode(plain)
    assert ina.encode({**plain, "shunt": np.int64(0)}) == ina.encode({**plain, "shunt": 0})
    refusals = [
        ({**plain, "current": np.True_}, "current: expected an integer, got bool"),
        ({**plain, "current": np.float64(200.0)}, "current: expected an integer, got float64"),
        ({**plain, "shunt": np.True_}, "shunt: expected a number, got bool"),
        ({**plain, "current": np.int64(2000)}, "current: value 2000 is out of range"),
    ]
    for value, message in refusals:
        with pytest.raises(px4params.CodecError) as refused:
            ina.encode(value)
        assert message in str(refused.value)
    store = px4params.Store(SCHEMA, classic=[])
    store.add("INA238#0")
    store.set("INA238#0.current", np.int32(100))
    store.set("INA238#0[4]", np.uint8(0x41))
    assert (store.get("INA238#0.current"), store.get("INA238#0[4]")) == (100, 0x41)
    with pytest.raises(px4params.ValueRangeError) as refused:
        store.set("INA238#0.current", np.int64(500))
    assert str(refused.value) == "INA238#0.current: 500 is outside 1..327 (@min/@max)"
