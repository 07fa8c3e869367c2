"""Decoding from metadata alone (px4params.gcs.codec): the same bytes as the DSDL path for every
type, with nothing but the parameters.json entry, and every error it reports."""

from __future__ import annotations

import ast
import json
import math
import struct
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import px4params
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from metadata_support import wide_value_strategy, write_tst
from px4params.dsdl.schema import to_json_value
from px4params.gcs import codec as gcs_codec
from px4params.gcs.codec import (
    GcsDecodeError,
    GcsEncodeError,
    MetadataFormatError,
    ParamCodec,
    f16_from_float,
    float_from_f16,
)
from px4params.gcs.metadata import build_parameters_json, describe_value
from px4params.store.spec import parameter_specs
from strategies import budget, value_strategy

CODEC_FILE = Path(gcs_codec.__file__)
SCHEMA = px4params.load_schema(use_env=False)
TYPES = SCHEMA.model["types"]
PARAMS = [s.name for s in parameter_specs(SCHEMA)]
STRUCTS = sorted(k for k, d in TYPES.items() if d["kind"] == "struct")
INA = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}


def slow(examples: int) -> settings:
    return settings(
        max_examples=budget(examples),
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )


@pytest.fixture(scope="module")
def tst_schema(tmp_path_factory: pytest.TempPathFactory) -> px4params.Schema:
    return px4params.load_schema([write_tst(tmp_path_factory.mktemp("tst"))], use_env=False)


@pytest.fixture(scope="module")
def codecs(tst_schema: px4params.Schema) -> dict[str, ParamCodec]:
    """Every structured parameter's codec, from the parameters.json the CLI would write
    (bundled types plus the every-field-kind test type), after a round trip through JSON."""
    document = json.loads(json.dumps(build_parameters_json(tst_schema)))
    return gcs_codec.load(document)


def type_codec(key: str) -> ParamCodec:
    """A codec for any struct type, from the description of its zero value."""
    data_type = SCHEMA[key]
    zero = data_type.decode(data_type.default(tao=False), tao=False)
    return ParamCodec({"name": key, "fields": describe_value(SCHEMA, key, zero)})


def same(a: Any, b: Any) -> bool:
    return to_json_value(a) == to_json_value(b)


def schema_of(name: str, tst_schema: px4params.Schema) -> px4params.DataType:
    spec = next(s for s in parameter_specs(tst_schema) if s.name == name)
    return spec.data_type


# --- agreement with the DSDL path ---------------------------------------------------------------


def test_every_parameter_has_a_codec(codecs: dict[str, ParamCodec]) -> None:
    assert set(codecs) == {*PARAMS, "EVERYTHING_SH"}
    assert codecs["INA238"].max_instances == 4 and codecs["EVERYTHING_SH"].max_instances is None


@pytest.mark.parametrize("name", [*PARAMS, "EVERYTHING_SH"])
@slow(60)
@given(data=st.data())
def test_parameters_encode_like_the_dsdl_path(
    name: str, data: st.DataObject, codecs: dict[str, ParamCodec], tst_schema: px4params.Schema
) -> None:
    data_type = schema_of(name, tst_schema)
    value = data.draw(value_strategy(tst_schema.model["types"], data_type.key))
    expected = data_type.encode(value, tao=False)
    codec = codecs[name]
    assert codec.encode(value) == expected
    assert same(codec.decode(expected), data_type.decode(expected, tao=False))
    # Classic CAN transfers use tail array optimization; the codec does it too.
    assert codec.encode(value, tao=True) == data_type.encode(value, tao=True)


@pytest.mark.parametrize("name", [*PARAMS, "EVERYTHING_SH"])
@slow(40)
@given(data=st.data())
def test_out_of_range_values_like_the_dsdl_path(
    name: str, data: st.DataObject, codecs: dict[str, ParamCodec], tst_schema: px4params.Schema
) -> None:
    data_type = schema_of(name, tst_schema)
    value = data.draw(wide_value_strategy(tst_schema.model["types"], data_type.key))
    codec = codecs[name]
    assert codec.encode(value, saturate=True) == data_type.encode(value, tao=False, saturate=True)
    try:
        expected = data_type.encode(value, tao=False)
    except px4params.EncodeError:
        with pytest.raises(GcsEncodeError, match="out of range"):
            codec.encode(value)
    else:
        assert codec.encode(value) == expected


@pytest.mark.parametrize("name", [*PARAMS, "EVERYTHING_SH"])
@slow(60)
@given(raw=st.binary(max_size=48), tao=st.booleans())
def test_any_bytes_decode_like_the_dsdl_path(
    name: str, raw: bytes, tao: bool, codecs: dict[str, ParamCodec], tst_schema: px4params.Schema
) -> None:
    data_type = schema_of(name, tst_schema)
    try:
        expected = data_type.decode(raw, tao=tao)
    except px4params.DecodeError:
        with pytest.raises(GcsDecodeError):
            codecs[name].decode(raw, tao=tao)
    else:
        assert same(codecs[name].decode(raw, tao=tao), expected)


@pytest.mark.parametrize("key", STRUCTS)
@slow(8)
@given(data=st.data(), tao=st.booleans())
def test_every_bundled_struct_type_from_its_description(
    key: str, data: st.DataObject, tao: bool
) -> None:
    # Beyond parameters: DroneCAN's own types exercise arrays, padding and TAO corners.
    value = data.draw(value_strategy(TYPES, key))
    expected = SCHEMA[key].encode(value, tao=tao)
    codec = type_codec(key)
    assert codec.encode(value, tao=tao) == expected
    assert same(codec.decode(expected, tao=tao), SCHEMA[key].decode(expected, tao=tao))


def test_the_talks_value(codecs: dict[str, ParamCodec]) -> None:
    data = codecs["INA238"].encode(INA)
    assert data == SCHEMA["px.Ina238"].encode(INA, tao=False)
    decoded = codecs["INA238"].decode(data)
    assert decoded["bus"] == {"i2c": {"p_version": 0, "bus_id": 1, "address": 0x45}}
    assert decoded["current"] == 200 and decoded["shunt"] == pytest.approx(0.0003, rel=1e-3)
    assert decoded["p_version"] == SCHEMA["px.Ina238"].version[1]  # type: ignore[index]


def test_uint8_arrays_take_bytes_and_text(codecs: dict[str, ParamCodec]) -> None:
    codec = codecs["EVERYTHING_SH"]
    base: dict[str, Any] = {
        "wrap": 1,
        "signed_value": 0,
        "flag": False,
        "triple": [1, 2, 3],
        "items": [],
        "choice": {"text": [104, 105]},
        "pair": [0.0, 0.0],
        "loose": 0.0,
        "tail": [0xC3, 0xA9],
    }
    expected = codec.encode(base)
    assert codec.encode({**base, "tail": "é", "triple": b"\x01\x02\x03"}) == expected
    assert codec.encode({**base, "choice": {"text": "hi"}, "tail": bytearray(b"\xc3\xa9")}) == (
        expected
    )


# --- float16 ------------------------------------------------------------------------------------


def test_float16_round_trips_every_value() -> None:
    for half in range(0x10000):
        value = float_from_f16(half)
        if math.isnan(value):
            assert f16_from_float(value) == (half & 0x8000) | 0x7FFF
        else:
            assert f16_from_float(value) == half, hex(half)


@pytest.mark.parametrize(
    ("value", "half"),
    [
        (1.0, 0x3C00),
        (-2.0, 0xC000),
        (65504.0, 0x7BFF),
        (65519.0, 0x7BFF),
        (65520.0, 0x7C00),
        (1.0 + 2.0**-11, 0x3C01),  # a tie: away from zero, not to even
        (-(1.0 + 2.0**-11), 0xBC01),
        (1.0 + 3 * 2.0**-11, 0x3C02),
        (2.0**-25, 0x0001),  # half the smallest subnormal rounds up
        (2.0**-26, 0x0000),
        (2.5 * 2.0**-24, 0x0003),
        (2.0**-14 - 2.0**-25, 0x0400),  # rounds up into the normals
        (math.inf, 0x7C00),
        (-math.inf, 0xFC00),
        (math.nan, 0x7FFF),
        (1e-45, 0x0000),  # a float32 subnormal
    ],
)
def test_float16_rounding(value: float, half: int) -> None:
    assert f16_from_float(value) == half
    if math.isfinite(value) and abs(value) > 65504:
        return  # the codecs' range check turns these into 65504 or infinity first
    # The same as the DSDL path's truncated float16 field (no range check in the way).
    model = {
        "types": {
            "t.H": {
                "name": "t.H",
                "version": None,
                "kind": "struct",
                "dialect": "uavcan",
                "fields": [
                    {"name": "x", "type": {"kind": "float", "bits": 16, "cast": "truncated"}}
                ],
            }
        }
    }
    assert px4params.Schema(model)["t.H"].encode({"x": value}) == struct.pack("<H", half)


# --- no DSDL involved ---------------------------------------------------------------------------


def test_the_module_imports_only_the_standard_library() -> None:
    tree = ast.parse(CODEC_FILE.read_text(encoding="utf-8"))
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, "no relative imports: the module stands alone"
            imported.add((node.module or "").split(".")[0])
    assert imported - {"__future__"} <= set(sys.stdlib_module_names), imported


def test_it_works_without_pydsdl_dronecan_or_px4params(
    tmp_path: Path, codecs: dict[str, ParamCodec], schema: px4params.Schema
) -> None:
    document = tmp_path / "parameters.json"
    document.write_text(json.dumps(build_parameters_json(schema)), encoding="utf-8")
    script = """
import importlib.util, json, sys
for blocked in ("pydsdl", "dronecan", "px4params"):
    sys.modules[blocked] = None  # any import of these fails
spec = importlib.util.spec_from_file_location("gcs_codec", sys.argv[1])
module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
codec = module.load(sys.argv[2])["INA238"]
data = codec.encode(json.loads(sys.argv[3]))
print(data.hex(), json.dumps(codec.decode(data)["bus"]))
"""
    proc = subprocess.run(
        [sys.executable, "-c", script, str(CODEC_FILE), str(document), json.dumps(INA)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    hex_bytes, bus = proc.stdout.split(" ", 1)
    assert hex_bytes == SCHEMA["px.Ina238"].encode(INA, tao=False).hex()
    assert json.loads(bus) == {"i2c": {"p_version": 0, "bus_id": 1, "address": 69}}


# --- loading and its errors ---------------------------------------------------------------------


def test_load_reads_a_file(tmp_path: Path, schema: px4params.Schema) -> None:
    path = tmp_path / "parameters.json"
    classic = {"name": "X_ONE", "type": "Float", "default": 1.0}
    document = build_parameters_json(schema)
    document["parameters"].insert(0, classic)
    path.write_text(json.dumps(document), encoding="utf-8")
    codecs = gcs_codec.load(path)
    assert sorted(codecs) == PARAMS  # the classic entry has no fields: not structured
    assert repr(codecs["INA238"]) == "<ParamCodec INA238>"


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ([], "not a parameters.json (expected an object with a 'parameters' list)"),
        ({"version": 1}, "not a parameters.json (expected an object with a 'parameters' list)"),
        ({"version": 2, "parameters": []}, "parameters.json version 2 (expected 1)"),
    ],
)
def test_documents_that_are_not_parameters_json(document: Any, message: str) -> None:
    with pytest.raises(MetadataFormatError) as info:
        gcs_codec.load(document) if isinstance(document, Mapping) else (
            gcs_codec.structured_entries(document)
        )
    assert str(info.value) == message


def test_unreadable_and_non_json_files(tmp_path: Path) -> None:
    with pytest.raises(MetadataFormatError, match=r"nope\.json: cannot read: No such file"):
        gcs_codec.load(tmp_path / "nope.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{", encoding="utf-8")
    with pytest.raises(MetadataFormatError, match=r"bad\.json: not JSON: Expecting"):
        gcs_codec.load(bad)


def leaf(path: str, type_: str, role: str = "value", **extra: Any) -> dict[str, Any]:
    return {"name": path, "path": path, "type": type_, "role": role, **extra}


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        (None, "X: no 'fields' list: not a structured parameter"),
        ([leaf("a", "uint99")], "X: fields: a: unknown type 'uint99'"),
        ([leaf("a", "float8")], "X: fields: a: unknown type 'float8'"),
        ([leaf("a", "string")], "X: fields: a: unknown type 'string'"),
        ([leaf("a", "void3")], "X: fields: a: void3 is not a value type"),
        ([leaf("a", "uint3", cast="wrapped")], "X: fields: a: unknown cast mode 'wrapped'"),
        (
            [{"path": "_pad", "type": "uint3", "role": "padding"}],
            "X: fields: _pad: padding must be voidN, got 'uint3'",
        ),
        (
            [leaf("a", "uint3"), leaf("b", "uint1"), leaf("a", "uint3")],
            "X: fields: the value: a field appears twice",
        ),
        ([leaf("9a", "uint3")], "X: fields: '9a': expected a field name after ''"),
        (
            [leaf("u._tag", "int3", "union_tag", variants=[{"tag": 0, "name": "a", "fields": []}])],
            "X: fields: u._tag: expected a uintN type, got 'int3'",
        ),
        (
            [
                leaf(
                    "u._tag", "uint1", "union_tag", variants=[{"tag": 1, "name": "a", "fields": []}]
                )
            ],
            "X: fields: u: union variants must be numbered 0..n-1",
        ),
        (
            [
                leaf(
                    "u._tag",
                    "uint1",
                    "union_tag",
                    variants=[{"tag": 0, "name": "a", "fields": [leaf("v.a", "uint2")]}],
                )
            ],
            "X: fields: 'v.a' is not inside 'u.a'",
        ),
        ([leaf("a[1]", "uint3")], "X: fields: a: array elements must be numbered 0..n-1"),
        (
            [leaf("a[0]", "uint3"), leaf("a[x]", "uint3")],
            "X: fields: a[x]: expected an element of a",
        ),
        ([leaf("a._len", "uint3", "length")], "X: malformed 'fields': KeyError('element')"),
    ],
)
def test_malformed_descriptions(fields: Any, message: str) -> None:
    with pytest.raises(MetadataFormatError) as info:
        ParamCodec({"name": "X", "fields": fields})
    assert str(info.value) == message


# --- encode errors ------------------------------------------------------------------------------


def ina(**changes: Any) -> dict[str, Any]:
    return {**INA, **changes}


def everything(**changes: Any) -> dict[str, Any]:
    value: dict[str, Any] = {
        "wrap": 1,
        "signed_value": 0,
        "flag": False,
        "triple": [1, 2, 3],
        "items": [],
        "choice": {"number": 1},
        "pair": [0.0, 0.0],
        "loose": 0.0,
        "tail": [],
    }
    return {**value, **changes}


ENCODE_ERRORS: list[tuple[str, dict[str, Any], str]] = [
    ("INA238", ina(current=200.0), "INA238: current: expected an integer, got float"),
    ("INA238", ina(current=True), "INA238: current: expected an integer, got bool"),
    ("INA238", ina(current="200"), "INA238: current: expected an integer, got str"),
    (
        "INA238",
        ina(current=1024),
        "INA238: current: value 1024 is out of range (expected 0 to 1023)",
    ),
    (
        "INA238",
        ina(shunt=70000),
        "INA238: shunt: value 70000 is out of range (expected -65504 to 65504)",
    ),
    (
        "INA238",
        ina(shunt=True),
        'INA238: shunt: expected a number (or "nan", "inf", "-inf"), got bool',
    ),
    (
        "INA238",
        ina(shunt="lots"),
        'INA238: shunt: expected a number (or "nan", "inf", "-inf"), got str',
    ),
    (
        "INA238",
        ina(bus=[]),
        "INA238: bus: expected a dict with one key, the union variant "
        "(i2c, spi, serial, dronecan, sim, mavlink), got list",
    ),
    (
        "INA238",
        ina(bus={"i2c": {}, "spi": {}}),
        "INA238: bus: a union takes exactly one variant "
        "(i2c, spi, serial, dronecan, sim, mavlink), got 2 keys",
    ),
    (
        "INA238",
        ina(bus={"usb": {}}),
        "INA238: bus: unknown union variant 'usb' "
        "(expected one of: i2c, spi, serial, dronecan, sim, mavlink)",
    ),
    ("INA238", ina(bus={"i2c": 5}), "INA238: bus.i2c: expected a dict (struct), got int"),
    (
        "INA238",
        ina(colour=1),
        "INA238: unknown field 'colour' (expected: p_version, bus, current, shunt)",
    ),
    ("INA238", {"bus": INA["bus"], "shunt": 0.1}, "INA238: current: missing field"),
    (
        "INA238",
        ina(p_version=7),
        "INA238: p_version: p_version is set automatically; got 7, the type's version is 1",
    ),
    (
        "INA238",
        ina(bus={"i2c": {"p_version": True, "bus_id": 1, "address": 2}}),
        "INA238: bus.i2c.p_version: p_version is set automatically; got True, "
        "the type's version is 0",
    ),
    ("EVERYTHING_SH", everything(flag=0.5), "EVERYTHING_SH: flag: expected a boolean, got float"),
    (
        "EVERYTHING_SH",
        everything(flag=2),
        "EVERYTHING_SH: flag: value 2 is out of range (expected a boolean: true, false, 0 or 1)",
    ),
    (
        "EVERYTHING_SH",
        everything(signed_value=-65),
        "EVERYTHING_SH: signed_value: value -65 is out of range (expected -64 to 63)",
    ),
    (
        "EVERYTHING_SH",
        everything(triple=[1, 2]),
        "EVERYTHING_SH: triple: array has 2 elements, expected exactly 3",
    ),
    (
        "EVERYTHING_SH",
        everything(triple=7),
        "EVERYTHING_SH: triple: expected a list (array), got int",
    ),
    (
        "EVERYTHING_SH",
        everything(pair="ab"),
        "EVERYTHING_SH: pair: expected a list (array), got str",
    ),
    (
        "EVERYTHING_SH",
        everything(tail=[1, 2, 3, 4, 5]),
        "EVERYTHING_SH: tail: array has 5 elements, at most 4 allowed",
    ),
    (
        "EVERYTHING_SH",
        everything(items=[{"offset": 1, "enabled": True, "gain": 1e39}]),
        "EVERYTHING_SH: items[0].gain: value 1e+39 is out of range "
        "(expected -3.40282e+38 to 3.40282e+38)",
    ),
]


@pytest.mark.parametrize(("name", "value", "message"), ENCODE_ERRORS)
def test_encode_errors(name: str, value: Any, message: str, codecs: dict[str, ParamCodec]) -> None:
    with pytest.raises(GcsEncodeError) as info:
        codecs[name].encode(value)
    assert str(info.value) == message


def test_cast_modes(codecs: dict[str, ParamCodec], tst_schema: px4params.Schema) -> None:
    codec = codecs["EVERYTHING_SH"]
    data_type = schema_of("EVERYTHING_SH", tst_schema)
    # Truncated fields keep the low bits (or overflow to infinity) even without saturate.
    value = everything(wrap=13, loose=1e6, signed_value=-1)
    assert codec.encode(value) == data_type.encode(value, tao=False)
    assert codec.decode(codec.encode(value))["wrap"] == 13 & 7
    assert codec.decode(codec.encode(value))["loose"] == math.inf
    # Saturated ones clamp when asked to.
    loud = everything(signed_value=-1000, pair=[1e9, "-inf"], flag=True)
    assert codec.encode(loud, saturate=True) == data_type.encode(loud, tao=False, saturate=True)
    decoded = codec.decode(codec.encode(loud, saturate=True))
    assert decoded["signed_value"] == -64 and decoded["pair"] == [65504.0, -math.inf]
    assert math.isnan(codec.decode(codec.encode(everything(loose="NaN")))["loose"])


# --- decode errors ------------------------------------------------------------------------------


def test_decode_errors(codecs: dict[str, ParamCodec]) -> None:
    ina_codec = codecs["INA238"]
    good = ina_codec.encode(INA)
    cases: list[tuple[ParamCodec, bytes, bool, str]] = [
        (
            ina_codec,
            good[:1],
            False,
            "INA238: bus.i2c.p_version: data is truncated: needs at least 11 bits, has 8 "
            "(at bit 7)",
        ),
        (
            ina_codec,
            b"",
            False,
            "INA238: p_version: data is truncated: needs at least 4 bits, has 0 (at bit 0)",
        ),
        (
            ina_codec,
            good + b"\x00",
            False,
            "INA238: data is too long: the value ends after 6 bytes, the data has 7 (at bit 48)",
        ),
        (
            ina_codec,
            bytes([good[0] | 0x0E]) + good[1:],
            False,
            "INA238: bus: union tag 7 selects no variant (expected 0..5) (at bit 4)",
        ),
    ]
    for codec, raw, tao, message in cases:
        with pytest.raises(GcsDecodeError) as info:
            codec.decode(raw, tao=tao)
        assert str(info.value) == message
    assert ina_codec.decode(good + b"\x00", allow_trailing=True)["current"] == 200


def test_array_length_errors_when_decoding() -> None:
    codec = type_codec("uavcan.protocol.param.GetSet.Request")
    # index (13 bits) = 0, value tag (3 bits) = 0 (empty), then name: 93 bytes under TAO.
    with pytest.raises(GcsDecodeError) as info:
        codec.decode(bytes(2 + 93), tao=True)
    assert str(info.value) == (
        "uavcan.protocol.param.GetSet.Request: name: array has more than 92 elements (at bit 752)"
    )
    # Without TAO the length prefix (7 bits) says 127.
    with pytest.raises(GcsDecodeError) as info:
        codec.decode(bytes([0, 0, 0xFF]), tao=False)
    assert str(info.value) == (
        "uavcan.protocol.param.GetSet.Request: name: array length 127 exceeds the maximum of 92 "
        "(at bit 16)"
    )
