"""The Python codec API: golden vector, round trips, leaf access and every error message."""

from __future__ import annotations

import contextlib
import math

import px4params
import pytest
from dronecan_oracle import same
from hypothesis import given, settings
from hypothesis import strategies as st
from px4params.cli.commands.codec import TALK_INA238, schema_golden_vector
from strategies import budget, expected_decoded, same_decoded, value_strategy

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
