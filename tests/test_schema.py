"""The Python codec API: golden vector, round trips, leaf access and every error message."""

from __future__ import annotations

import contextlib
import gc
import inspect
import itertools
import math
import os
import sys
import weakref
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from dronecan import transport
from dronecan_oracle import fill, new_value, pack, same, to_plain, unpack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from px4params import StructValue, _native
from px4params.cli.commands.codec import TALK_INA238, schema_golden_vector
from px4params.errors import LeafError
from strategies import budget, expected_decoded, same_decoded, value_strategy
from test_native_fastcall import outcome
from test_native_plain_path import Sneaky, spoiled

BUNDLED = sorted(
    k
    for k, d in px4params.load_schema(use_env=False).model["types"].items()
    if d["name"].startswith("px.")
)


def test_golden_vector() -> None:
    assert schema_golden_vector() == bytes([0xDA, 0xEF, 0x7C, 0x00])


def test_talk_ina238(schema: px4params.Schema) -> None:
    t = schema["px.Ina238"]
    data = t.encode(TALK_INA238)
    assert data.hex() == "10031720ea0c"
    leaves = t.leaves(data)
    assert [(leaf.index, leaf.path, leaf.type) for leaf in leaves] == [
        (0, "p_version", "uint4"),
        (1, "bus._tag", "uint3"),
        (2, "bus.i2c.p_version", "uint4"),
        (3, "bus.i2c.bus_id", "uint4"),
        (4, "bus.i2c.address", "uint7"),
        (5, "current", "uint10"),
        (6, "shunt", "float16"),
    ]
    assert [leaf.value for leaf in leaves[:6]] == [1, 0, 0, 1, 0x45, 200]
    assert leaves[6].value == pytest.approx(0.0003, rel=1e-3)
    assert t.get_leaf(data, "bus.i2c.address").value == 69
    assert t.get_leaf(data, 4) == leaves[4]


def test_set_leaf(schema: px4params.Schema) -> None:
    t = schema["px.Ina238"]
    data = t.encode(TALK_INA238)
    assert t.decode(t.set_leaf(data, 4, 0x46))["bus"]["i2c"]["address"] == 0x46
    assert t.decode(t.set_leaf(data, "current", 10))["current"] == 10
    spi = t.decode(t.set_leaf(data, "bus._tag", 1))
    assert list(spi["bus"]) == ["spi"] and spi["current"] == 200
    with pytest.raises(
        px4params.EncodeError,
        match=r"^px\.Ina238\.1\.1: bus\.i2c\.address: value 128 is out of range "
        r"\(expected 0 to 127\)$",
    ):
        t.set_leaf(data, 4, 128)
    with pytest.raises(
        px4params.LeafError, match=r"no leaf \[9\] \(the value has 7 leaves: \[0\]\.\.\[6\]\)"
    ):
        t.get_leaf(data, 9)
    with pytest.raises(
        px4params.LeafError, match=r"bus\.spi: this union variant is not the selected one"
    ):
        t.get_leaf(data, "bus.spi.bus_id")
    with pytest.raises(TypeError, match=r"index \[k\] \(int >= 0\) or a path \(str\), got float"):
        t.get_leaf(data, 1.5)


@pytest.mark.parametrize("key", BUNDLED)
@settings(max_examples=budget(40), deadline=None)
@given(data=st.data(), tao=st.booleans())
def test_round_trip_every_bundled_type(
    schema: px4params.Schema, key: str, data: st.DataObject, tao: bool
) -> None:
    t = schema[key]
    value = data.draw(value_strategy(schema.model["types"], key))
    encoded = t.encode(value, tao=tao)
    decoded = t.decode(encoded, tao=tao)
    # decode(encode(v)) is v, floats rounded to their fields' widths (worked out by Python's
    # struct, not by the codec) and p_version filled in; re-encoding reproduces the bytes.
    assert same_decoded(expected_decoded(schema.model["types"], t.key, value), decoded)
    assert t.encode(decoded, tao=tao) == encoded
    assert same(t.decode(t.encode(decoded, tao=tao), tao=tao), decoded)
    for leaf in t.leaves(encoded, tao=tao):
        assert t.get_leaf(encoded, leaf.index, tao=tao).path == leaf.path


@pytest.mark.parametrize(
    "key", [*BUNDLED, "uavcan.equipment.power.BatteryInfo", "uavcan.protocol.GetNodeInfo.Response"]
)
@settings(max_examples=budget(200), deadline=None)
@given(data=st.binary(max_size=80), tao=st.booleans())
def test_random_bytes_never_crash(
    schema: px4params.Schema, key: str, data: bytes, tao: bool
) -> None:
    t = schema[key]
    try:
        value = t.decode(data, tao=tao, allow_trailing=True)
    except px4params.DecodeError as e:
        assert str(e).startswith(f"{t.key}: ") and "(at bit " in str(e)
        assert isinstance(e.bit_offset, int)
        return
    assert isinstance(value, dict)
    for k in range(3):
        with contextlib.suppress(px4params.DecodeError, px4params.LeafError):
            t.get_leaf(data, k, tao=tao)


# ---- every error path, with its message -------------------------------------------------------

INA_ERRORS = [
    (
        "not a dict",
        [1, 2],
        px4params.ValueShapeError,
        r"^px\.Ina238\.1\.1: expected a dict \(struct\), got list$",
    ),
    (
        "unknown field",
        {**TALK_INA238, "volts": 1},
        px4params.ValueShapeError,
        r"^px\.Ina238\.1\.1: unknown field 'volts' \(expected: p_version, bus, current, shunt\)$",
    ),
    (
        "missing field",
        {"bus": TALK_INA238["bus"], "current": 1},
        px4params.ValueShapeError,
        r"^px\.Ina238\.1\.1: shunt: missing field$",
    ),
    (
        "union two keys",
        {**TALK_INA238, "bus": {"i2c": {}, "spi": {}}},
        px4params.ValueShapeError,
        r"^px\.Ina238\.1\.1: bus: a union takes exactly one variant "
        r"\(i2c, spi, serial, dronecan, sim, mavlink\), got 2 keys$",
    ),
    (
        "union unknown variant",
        {**TALK_INA238, "bus": {"usb": {}}},
        px4params.ValueShapeError,
        r"^px\.Ina238\.1\.1: bus: unknown union variant 'usb' "
        r"\(expected one of: i2c, spi, serial, dronecan, sim, mavlink\)$",
    ),
    (
        "union not a dict",
        {**TALK_INA238, "bus": "i2c"},
        px4params.ValueShapeError,
        r"bus: expected a dict with one key, the union variant \(i2c, .*\), got str$",
    ),
    (
        "string for int",
        {**TALK_INA238, "current": "200"},
        px4params.ValueShapeError,
        r"^px\.Ina238\.1\.1: current: expected an integer, got str$",
    ),
    (
        "bool for int",
        {**TALK_INA238, "current": True},
        px4params.ValueShapeError,
        r"current: expected an integer, got bool$",
    ),
    (
        "float for int",
        {**TALK_INA238, "current": 2.5},
        px4params.ValueShapeError,
        r"current: expected an integer, got float$",
    ),
    (
        "int out of range",
        {**TALK_INA238, "current": 1024},
        px4params.EncodeError,
        r"^px\.Ina238\.1\.1: current: value 1024 is out of range \(expected 0 to 1023\)$",
    ),
    (
        "negative uint",
        {**TALK_INA238, "current": -1},
        px4params.EncodeError,
        r"current: value -1 is out of range \(expected 0 to 1023\)$",
    ),
    (
        "huge int",
        {**TALK_INA238, "current": 1 << 70},
        px4params.EncodeError,
        r"current: value 1180591620717411303424 is out of range \(expected 0 to 1023\)$",
    ),
    (
        "float16 overflow",
        {**TALK_INA238, "shunt": 1e6},
        px4params.EncodeError,
        r"shunt: value 1000000 is out of range \(expected -65504 to 65504\)$",
    ),
    (
        "bad float string",
        {**TALK_INA238, "shunt": "small"},
        px4params.ValueShapeError,
        r"shunt: expected a number \(or \"nan\", \"inf\", \"-inf\"\), got 'small'$",
    ),
    (
        "wrong p_version",
        {**TALK_INA238, "p_version": 3},
        px4params.EncodeError,
        r"p_version: p_version is set automatically; got 3, the type's version is 1$",
    ),
    (
        "nested missing",
        {**TALK_INA238, "bus": {"i2c": {"bus_id": 1}}},
        px4params.ValueShapeError,
        r"bus\.i2c\.address: missing field$",
    ),
]


@pytest.mark.parametrize(
    ("case", "value", "exc", "message"), INA_ERRORS, ids=[c[0] for c in INA_ERRORS]
)
def test_encode_errors(schema: px4params.Schema, case: str, value, exc, message: str) -> None:
    with pytest.raises(exc, match=message) as info:
        schema["px.Ina238"].encode(value)
    assert "\n" not in str(info.value)


def test_array_errors(schema: px4params.Schema) -> None:
    t = schema["uavcan.equipment.power.BatteryInfo"]
    base = {
        f: 0.0
        for f in (
            "temperature",
            "voltage",
            "current",
            "average_power_10sec",
            "remaining_capacity_wh",
            "full_charge_capacity_wh",
            "hours_to_full_charge",
        )
    }
    base |= {
        "status_flags": 0,
        "state_of_health_pct": 0,
        "state_of_charge_pct": 0,
        "state_of_charge_pct_stdev": 0,
        "battery_id": 0,
        "model_instance_id": 0,
    }
    assert t.decode(t.encode({**base, "model_name": "abc"}))["model_name"] == list(b"abc")
    assert t.decode(t.encode({**base, "model_name": b"abc"}))["model_name"] == list(b"abc")
    with pytest.raises(
        px4params.EncodeError, match=r"model_name: array has 40 elements, at most 31 allowed$"
    ):
        t.encode({**base, "model_name": "x" * 40})
    with pytest.raises(
        px4params.ValueShapeError, match=r"model_name: expected a list \(array\), got int$"
    ):
        t.encode({**base, "model_name": 5})
    with pytest.raises(px4params.EncodeError, match=r"model_name\[1\]: value 300 is out of range"):
        t.encode({**base, "model_name": [1, 300]})
    cov = schema["uavcan.equipment.ahrs.Solution"]
    fields = {f["name"] for f in cov.definition["fields"]}
    assert "orientation_xyzw" in fields


def test_decode_errors(schema: px4params.Schema) -> None:
    t = schema["px.Ina238"]
    with pytest.raises(
        px4params.DecodeError,
        match=r"^px\.Ina238\.1\.1: shunt: data is truncated: needs at least 48 bits, "
        r"has 40 \(at bit 32\)$",
    ) as info:
        t.decode(bytes(5))
    assert info.value.bit_offset == 32 and info.value.path == "shunt"
    with pytest.raises(
        px4params.DecodeError,
        match=r"data is too long: the value ends after 6 bytes, the data has 7 \(at bit 48\)$",
    ):
        t.decode(bytes(7))
    assert t.decode(bytes(7), allow_trailing=True)["current"] == 0
    with pytest.raises(
        px4params.DecodeError,
        match=r"bus: union tag 7 selects no variant \(expected 0\.\.5\) \(at bit 4\)$",
    ):
        t.decode(bytes([0x0E, 0, 0, 0, 0, 0]))
    b = schema["uavcan.equipment.power.BatteryInfo"]
    with pytest.raises(
        px4params.DecodeError, match=r"model_name: array has 32 elements, at most 31 allowed"
    ):
        b.decode(bytes(23) + b"x" * 32)


def test_non_finite_floats(schema: px4params.Schema) -> None:
    t = schema["px.Ina238"]
    for text, check in (
        ("nan", math.isnan),
        ("inf", lambda v: v == math.inf),
        ("-inf", lambda v: v == -math.inf),
    ):
        assert check(t.decode(t.encode({**TALK_INA238, "shunt": text}))["shunt"])
    assert px4params.to_json_value({"a": [math.nan, -math.inf, 1.5]}) == {"a": ["nan", "-inf", 1.5]}


def test_saturate_is_explicit(schema: px4params.Schema) -> None:
    t = schema["px.Ina238"]
    assert t.decode(t.encode({**TALK_INA238, "current": 5000}, saturate=True))["current"] == 1023
    assert t.decode(t.encode({**TALK_INA238, "shunt": 1e9}, saturate=True))["shunt"] == 65504.0


def test_lookup(schema: px4params.Schema) -> None:
    assert schema.resolve("px.Ina238") == "px.Ina238.1.1"
    assert "uavcan.protocol.NodeStatus" in schema
    with pytest.raises(KeyError):
        schema["px.Nope"]
    assert schema.suggest("px.Ina23") == ["px.Ina238", "px.Ina228", "px.Ina226"] or schema.suggest(
        "px.Ina23"
    )


def test_errors_carry_their_position(schema: px4params.Schema) -> None:
    t = schema["px.Ina238"]
    with pytest.raises(px4params.EncodeError) as info:
        t.encode({**TALK_INA238, "bus": {"i2c": {"bus_id": 1, "address": 300}}})
    assert (info.value.path, info.value.bit_offset) == ("bus.i2c.address", None)
    with pytest.raises(px4params.ValueShapeError) as shape:
        t.encode({**TALK_INA238, "current": "x"})
    assert shape.value.path == "current"
    with pytest.raises(px4params.EncodeError) as leaf:
        t.set_leaf(t.encode(TALK_INA238), "current", 5000)
    assert leaf.value.path == "current"


# -- tail array optimization -------------------------------------------------------------------
# Tail array optimization corner cases, decided as the spec and pydronecan decide them.
#
# The flag passes down only to the last field of a struct, the selected variant of a union and
# the last element of an array; elements of a tail-optimized array are encoded without it, and
# an array of elements shorter than 8 bits keeps its length prefix.


TAO_TYPES = {
    # Corner case 1: the tail array sits in the last field of a nested struct.
    "Inner.uavcan": "uint8 x\nuint8[<=5] tail\n",
    "NestedTail.uavcan": "uint8 a\nInner inner\n",
    # Corner case 2: the tail array is inside the selected variant of a union.
    "Choice.uavcan": "@union\nuint16 number\nuint8[<=7] bytes\n",
    "UnionTail.uavcan": "uint3 a\nChoice choice\n",
    # The last element of a static array gets the flag.
    "ArrayTail.uavcan": "Inner[2] pairs\n",
    # Elements of a tail array lose it; short elements keep the prefix.
    "ElementsLose.uavcan": "Inner[<=3] items\n",
    "ShortElements.uavcan": "uint7 a\nuint4[<=6] nibbles\n",
    "NotLast.uavcan": "uint8[<=4] first\nuint8 last\n",
}

TAO_VALUES = {
    "NestedTail": {"a": 1, "inner": {"x": 2, "tail": [3, 4, 5]}},
    "UnionTail": {"a": 5, "choice": {"bytes": [9, 8, 7]}},
    "ArrayTail": {"pairs": [{"x": 1, "tail": [2]}, {"x": 3, "tail": [4, 5]}]},
    "ElementsLose": {"items": [{"x": 1, "tail": [2, 3]}, {"x": 4, "tail": []}]},
    "ShortElements": {"a": 1, "nibbles": [1, 2, 3]},
    "NotLast": {"first": [1, 2], "last": 3},
}

# Bytes worked out by hand from the rules (TAO on), so a shared misreading cannot pass.
EXPECTED_TAO = {
    # 00000001 00000010 | 00000011 00000100 00000101: no 3-bit prefix before 3 4 5
    "NestedTail": "0102030405",
    # 101 | tag 1 | 00001001 00001000 00000111 | pad: 9 8 7 unprefixed inside the variant
    "UnionTail": "b0908070",
    # 00000001 001 00000010 | 00000011 00000100 00000101: only the last element is unprefixed
    "ArrayTail": "0120406080a0",
    # 00000001 010 00000010 00000011 | 00000100 000: the elements keep their inner prefixes
    "ElementsLose": "0140406080",
    # 0000001 | 011 0001 0010 0011: uint4 elements are too short, the prefix stays
    "ShortElements": "02c48c",
    # 010 00000001 00000010 | 00000011: not the last field, prefixed
    "NotLast": "40204060",
}


@pytest.fixture(scope="module")
def corner(tmp_path_factory: pytest.TempPathFactory) -> tuple[px4params.Schema, dict[str, object]]:
    root = tmp_path_factory.mktemp("dsdl") / "corner"
    root.mkdir()
    for name, text in TAO_TYPES.items():
        (root / name).write_text(text)
    schema = px4params.load_schema([root], use_env=False, cache_dir=root.parent / "cache")
    theirs = {t.full_name: t for t in dronecan.dsdl.parse_namespaces([os.fspath(root)])}
    return schema, theirs


@pytest.mark.parametrize("name", sorted(TAO_VALUES))
@pytest.mark.parametrize("tao", [True, False])
def test_tail_array_rules_match_pydronecan(corner, name: str, tao: bool) -> None:
    schema, theirs = corner
    t = schema[f"corner.{name}"]
    ours = t.encode(TAO_VALUES[name], tao=tao)
    assert (
        ours.hex()
        == pack(
            fill(transport.CompoundValue(theirs[f"corner.{name}"]), TAO_VALUES[name]), tao=tao
        ).hex()
    )
    assert t.decode(ours, tao=tao) == TAO_VALUES[name]


def test_tail_array_rules_by_hand(corner) -> None:
    # The expected bytes above are derived by hand; check the derivations too.
    schema, _ = corner
    got = {name: schema[f"corner.{name}"].encode(v).hex() for name, v in TAO_VALUES.items()}
    assert got == EXPECTED_TAO


def test_tao_off_keeps_every_prefix(corner) -> None:
    schema, _ = corner
    t = schema["corner.NestedTail"]
    # 3-bit length prefix 011 before 03 04 05: 01 02 | 011 00000011 00000100 00000101 | pad
    assert t.encode(TAO_VALUES["NestedTail"], tao=False).hex() == "0102606080a0"
    assert len(t.encode(TAO_VALUES["NestedTail"], tao=False)) == 6


def test_model_path_is_used(corner) -> None:
    schema, _ = corner
    assert Path(schema["corner.NestedTail"].definition["file"]).name == "NestedTail.uavcan"


# -- batch calls (encode_many, decode_many) ----------------------------------------------------
# Batch calls: ``encode_many`` and ``decode_many`` give exactly what ``encode`` and ``decode``
# give item by item (bytes, values, and the first failure's class and message, told which item
# failed), over lists, tuples and any other iterable.


SCHEMA = px4params.load_schema(use_env=False)
TYPES = SCHEMA.model["types"]
KEYS = sorted(k for k, d in TYPES.items() if d["kind"] in ("struct", "union"))
NODE_STATUS = SCHEMA["uavcan.protocol.NodeStatus"]
STATUS = {"uptime_sec": 1, "health": 0, "mode": 0, "sub_mode": 0, "vendor_specific_status_code": 7}


def one_by_one(call: Any, items: list[Any], **options: Any) -> tuple[str, str]:
    """What calling ``call`` on each item gives: the results (as their ``repr``, which NaNs
    compare equal in), or the first failure as the batch words it."""
    results = []
    for i, item in enumerate(items):
        try:
            results.append(call(item, **options))
        except px4params.CodecError as e:
            return (type(e).__name__, f"item {i}: {e}")
    return ("results", repr(results))


def batched(call: Any, items: Any, **options: Any) -> tuple[str, str]:
    try:
        return ("results", repr(call(items, **options)))
    except px4params.CodecError as e:
        return (type(e).__name__, str(e))


@pytest.mark.parametrize("key", KEYS)
@settings(max_examples=budget(4), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data(), tao=st.booleans(), saturate=st.booleans())
def test_a_batch_gives_what_single_calls_give(
    key: str, data: st.DataObject, tao: bool, saturate: bool
) -> None:
    t = SCHEMA[key]
    # Values of different lengths one after another, so that the batch's one output buffer is
    # reused over a longer value's bytes; sometimes one of them broken.
    values = data.draw(st.lists(value_strategy(TYPES, key, infinities=False), max_size=5))
    if values and data.draw(st.booleans()):
        at = data.draw(st.integers(0, len(values) - 1))
        how, key_index = data.draw(st.integers(0, 9)), data.draw(st.integers(0, 50))
        values[at] = spoiled(values[at], how, key_index)
    options = {"tao": tao, "saturate": saturate}
    expected = one_by_one(t.encode, values, **options)
    assert batched(t.encode_many, values, **options) == expected
    assert batched(t.encode_many, tuple(values), **options) == expected
    assert batched(t.encode_many, iter(values), **options) == expected
    if expected[0] != "results":
        return
    # The bytes back, some of them cut short or with a byte after them.
    items = [t.encode(v, **options) for v in values]
    if items and data.draw(st.booleans()):
        at = data.draw(st.integers(0, len(items) - 1))
        items[at] = items[at][:-1] if data.draw(st.booleans()) else items[at] + b"\x00"
    decode_options = {"tao": tao, "allow_trailing": data.draw(st.booleans())}
    expected = one_by_one(t.decode, items, **decode_options)
    assert batched(t.decode_many, items, **decode_options) == expected
    assert batched(t.decode_many, (bytearray(b) for b in items), **decode_options) == expected


def test_the_failing_item_is_named_in_the_message_and_the_index() -> None:
    bad = dict(STATUS, health=9)
    with pytest.raises(px4params.EncodeError) as raised:
        NODE_STATUS.encode_many([STATUS, STATUS, bad, bad])
    assert str(raised.value) == (
        "item 2: uavcan.protocol.NodeStatus: health: value 9 is out of range (expected 0 to 3)"
    )
    assert (raised.value.index, raised.value.path) == (2, "health")
    missing = {k: v for k, v in STATUS.items() if k != "mode"}
    with pytest.raises(px4params.ValueShapeError, match=r"^item 1: .*: mode: missing field$"):
        NODE_STATUS.encode_many(iter([STATUS, missing]))
    good = NODE_STATUS.encode(STATUS)
    with pytest.raises(px4params.DecodeError) as raised:
        NODE_STATUS.decode_many([good, good[:3]])
    assert str(raised.value) == (
        "item 1: uavcan.protocol.NodeStatus: uptime_sec: data is truncated: needs at least 32 "
        "bits, has 24 (at bit 0)"
    )
    assert raised.value.index == 1
    # A single call's error has no index.
    with pytest.raises(px4params.DecodeError) as raised:
        NODE_STATUS.decode(good[:3])
    assert raised.value.index is None


def test_errors_not_of_the_codec_get_a_note_naming_the_item() -> None:
    with pytest.raises(TypeError, match="cannot convert 'int' object to bytes") as raised:
        NODE_STATUS.decode_many([NODE_STATUS.encode(STATUS), 5])
    assert raised.value.__notes__ == ["(item 1 of the batch)"]
    with pytest.raises(TypeError, match="'int' object is not iterable"):
        NODE_STATUS.encode_many(5)

    def broken_iterable() -> Any:
        yield STATUS
        raise RuntimeError("the source broke")

    with pytest.raises(RuntimeError, match="the source broke"):
        NODE_STATUS.encode_many(broken_iterable())


def test_empty_batches_and_batches_of_one() -> None:
    assert NODE_STATUS.encode_many([]) == []
    assert NODE_STATUS.decode_many(()) == []
    data = NODE_STATUS.encode(STATUS)
    assert NODE_STATUS.encode_many([STATUS]) == [data]
    assert NODE_STATUS.decode_many([memoryview(data)]) == [STATUS]


def test_a_list_emptied_while_its_items_are_encoded_is_survived() -> None:
    # Item 1's field look-up runs Python code that empties the batch's list.
    values: list[Any] = []
    value: dict[Any, Any] = {}
    sneaky = Sneaky("mode", values.clear)
    value[sneaky] = 1
    value.update(STATUS)
    values.extend([STATUS, value, STATUS])
    sneaky.armed = True
    with pytest.raises(px4params.ValueShapeError, match=r"^item 1: .*unknown field"):
        NODE_STATUS.encode_many(values)
    assert values == []


# -- decoding a payload in pieces --------------------------------------------------------------
# Decoding from a payload in pieces equals decoding it joined, for every bundled type.


EVERY_TYPE = sorted(SCHEMA.model["types"])


def _pieces(data: bytes, cuts: list[int]) -> list[bytes]:
    points = sorted({c % (len(data) + 1) for c in cuts})
    return [data[a:b] for a, b in itertools.pairwise([0, *points, len(data)])]


@pytest.mark.parametrize("key", EVERY_TYPE)
@settings(max_examples=budget(10), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), cuts=st.lists(st.integers(0, 10_000), max_size=12), tao=st.booleans())
def test_fragments_decode_like_flat(
    key: str, data: st.DataObject, cuts: list[int], tao: bool
) -> None:
    t = SCHEMA[key]
    value = data.draw(value_strategy(SCHEMA.model["types"], key))
    encoded = t.encode(value, tao=tao)
    pieces = _pieces(encoded, cuts)
    assert b"".join(pieces) == encoded
    assert same(t.decode_fragments(pieces, tao=tao), t.decode(encoded, tao=tao))


@given(data=st.binary(max_size=60), cuts=st.lists(st.integers(0, 100), max_size=8))
@settings(max_examples=budget(300), deadline=None)
def test_bad_fragments_fail_like_flat(data: bytes, cuts: list[int]) -> None:
    t = SCHEMA["px.Ina238"]
    try:
        flat = t.decode(data)
    except px4params.DecodeError as e:
        with pytest.raises(px4params.DecodeError) as info:
            t.decode_fragments(_pieces(data, cuts))
        assert str(info.value) == str(e)
    else:
        assert same(t.decode_fragments(_pieces(data, cuts)), flat)


# -- decode_struct's StructValue ---------------------------------------------------------------
# ``DataType.decode_struct``: the decoded value as a ``StructValue`` whose fields are
# attributes. It holds what ``decode`` gives (checked against pydronecan's own decoded objects
# too), raises what ``decode`` raises, and ``encode`` takes it back.


STRUCTS = sorted(k for k, d in TYPES.items() if d["kind"] == "struct")
STANDARD = [k for k in STRUCTS if TYPES[k].get("dialect") == "uavcan"]
STRUCT_STATUS = {
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
    data = pack(fill(new_value("uavcan.protocol.NodeStatus"), STRUCT_STATUS), tao=True)
    # uptime 12345 little-endian; health 01, mode 010, sub_mode 000 from the top bit; 7.
    assert data.hex() == "39300000" + "50" + "0700"
    value = NODE_STATUS.decode_struct(data)
    assert (value.uptime_sec, value.health, value.mode, value.sub_mode) == (12345, 1, 2, 0)
    assert value.vendor_specific_status_code == 7
    assert value._fields == tuple(STRUCT_STATUS)
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
    data = NODE_STATUS.encode(STRUCT_STATUS)
    a, b = NODE_STATUS.decode_struct(data), NODE_STATUS.decode_struct(data)
    assert a == b
    assert (a != b) is False
    assert a != NODE_STATUS.decode_struct(NODE_STATUS.encode({**STRUCT_STATUS, "health": 2}))
    assert a != STRUCT_STATUS and a._asdict() == STRUCT_STATUS
    other = px4params.Schema(
        {"types": {"t.T": {**TYPES["uavcan.protocol.NodeStatus"], "name": "t.T"}}}
    )["t.T"]
    assert other.decode(data) == STRUCT_STATUS and other.decode_struct(data) != a
    with pytest.raises(TypeError, match="unhashable type"):
        hash(a)
    with pytest.raises(TypeError, match="not supported"):
        assert a < b


def test_unknown_fields_and_unions_are_refused_by_name() -> None:
    value = NODE_STATUS.decode_struct(NODE_STATUS.encode(STRUCT_STATUS))
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
    value = NODE_STATUS.decode_struct(NODE_STATUS.encode(STRUCT_STATUS))
    assert dir(value)[:1] == ["_asdict"] and set(STRUCT_STATUS) <= set(dir(value))
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
    data = NODE_STATUS.encode(STRUCT_STATUS)
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


# -- a leaf index out of every range (an outside audit's defect 10) ----------------------------


@pytest.mark.parametrize("index", [-1, 2**80, 10**100])
def test_a_leaf_index_out_of_every_range_is_a_leaf_error(
    schema: px4params.Schema, index: int
) -> None:
    ina = schema.get("px.Ina238")
    data = ina.encode({"bus": {"i2c": {"bus_id": 1, "address": 69}}, "current": 200, "shunt": 0})
    with pytest.raises(LeafError, match=r"^no leaf \[.+\] \(leaf indices are 0 and up\)$"):
        ina.get_leaf(data, index)
    with pytest.raises(LeafError):
        ina.set_leaf(data, index, 1)


def test_a_part_of_a_decoded_value_is_found_and_replaced_by_its_leaf_path() -> None:
    from px4params.dsdl.schema import path_steps, put_at, value_at

    value = {"cells": [{"volts": 3.7}, {"volts": 3.8}], "bus": {"i2c": {"address": 69}}}
    assert path_steps("cells[1].volts") == ["cells", 1, "volts"]
    assert path_steps("m[0][2]") == ["m", 0, 2] and path_steps("") == []
    assert value_at(value, "cells[1].volts") == 3.8 and value_at(value, "") is value
    # what the value has not: a variant not selected, an index past the end
    assert value_at(value, "bus.spi.bus_id") is None and value_at(value, "cells[2]") is None
    put_at(value, "bus", {"spi": {"bus_id": 1}})
    put_at(value, "cells[0].volts", 4.2)
    assert value == {"cells": [{"volts": 4.2}, {"volts": 3.8}], "bus": {"spi": {"bus_id": 1}}}
