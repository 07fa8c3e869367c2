"""parameters.json for ground stations (px4params.gcs.metadata): the talk's INA238 entry, fields
that are the leaves of the default value, every union variant, and QGC's rules for the file."""

from __future__ import annotations

import copy
import json
import struct
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import px4params
import pytest
from metadata_support import TST_KEY, real_parameters_json, write_tst
from px4params.gcs import codec as gcs_codec
from px4params.gcs.metadata import (
    QGC_TYPE,
    MetadataError,
    build_parameters_json,
    classic_source,
    describe_value,
    structured_entry,
)
from px4params.store.classic import CLASSIC_ENV, ClassicParamsError
from px4params.store.spec import metadata_default, parameter_specs

#: FactMetaData::createFromJsonObject (QGroundControl, src/FactSystem/FactMetaData.cc) checks
#: these keys' JSON types; one of another type makes QGC drop the entry's metadata.
QGC_KEY_TYPES = {
    "name": "string",
    "type": "string",
    "shortDesc": "string",
    "longDesc": "string",
    "units": "string",
    "decimalPlaces": "number",
    "min": "number",
    "max": "number",
    "control": "bool",
    "qgcRebootRequired": "bool",
    "rebootRequired": "bool",
    "category": "string",
    "group": "string",
    "volatile": "bool",
    "bitmask": "array",
    "values": "array",
    "enumValues": "string",
    "enumStrings": "string",
}
#: FactMetaData::stringToType's names (compared case-insensitively); others are "Unknown type".
QGC_TYPES = [
    *("Uint8", "Int8", "Uint16", "Int16", "Uint32", "Int32", "Uint64", "Int64"),
    *("Float", "Double", "String", "Bool", "ElapsedSeconds", "Custom"),
]

#: The talk's slide: INA238's seven fields, in [k] order.
TALK_FIELDS = [
    (0, "p_version", "p_version", "uint4", "version"),
    (1, "bus", "bus._tag", "uint3", "union_tag"),
    (2, "p_version", "bus.i2c.p_version", "uint4", "version"),
    (3, "bus_id", "bus.i2c.bus_id", "uint4", "value"),
    (4, "address", "bus.i2c.address", "uint7", "value"),
    (5, "current", "current", "uint10", "value"),
    (6, "shunt", "shunt", "float16", "value"),
]


@pytest.fixture(scope="module")
def tst_schema(tmp_path_factory: pytest.TempPathFactory) -> px4params.Schema:
    root = write_tst(tmp_path_factory.mktemp("tst-dsdl"))
    return px4params.load_schema([root], use_env=False)


@pytest.fixture(scope="module")
def document(schema: px4params.Schema) -> dict[str, Any]:
    return build_parameters_json(schema)


def by_name(document: Mapping[str, Any], name: str) -> dict[str, Any]:
    return next(e for e in document["parameters"] if e["name"] == name)


def json_kind(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int | float):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    return "null" if value is None else "object"


def stored(kind_type: str, value: Any) -> Any:
    """A declared default as the field stores it (floats rounded to their width)."""
    if kind_type == "float16":
        return gcs_codec.float_from_f16(gcs_codec.f16_from_float(value))
    if kind_type == "float32":
        return struct.unpack("<f", struct.pack("<f", value))[0]
    return value


def tag_entries(fields: list[dict[str, Any]]) -> Iterator[dict[str, Any]]:
    for f in fields:
        if f["role"] == "union_tag":
            yield f
            for v in f["variants"]:
                yield from tag_entries(v["fields"])
        elif f["role"] == "length":
            yield from tag_entries(f["element"])


# --- the talk's entry ---------------------------------------------------------------------------


def test_ina238_entry_shows_the_talks_seven_fields(
    schema: px4params.Schema, document: dict[str, Any]
) -> None:
    ina = by_name(document, "INA238")
    rows = [(f["index"], f["name"], f["path"], f["type"], f["role"]) for f in ina["fields"]]
    assert rows == TALK_FIELDS
    assert ina["type"] == QGC_TYPE == "Custom"
    assert ina["max_instances"] == 4
    assert (ina["group"], ina["category"], ina["rebootRequired"]) == ("Sensors", "Standard", True)
    assert ina["shortDesc"] == "INA238 power monitor"
    data_type = schema["px.Ina238"]
    assert ina["dsdl_type"] == data_type.key and ina["max_bytes"] == data_type.max_bytes
    assert ina["default_value"] == metadata_default(schema, data_type.key)
    # QGC holds a Custom default as bytes: the DroneCAN encoding, in hex (the talk's bytes)
    assert ina["default"] == "1001151dea0c"
    assert data_type.decode(bytes.fromhex(ina["default"]), tao=False) == {
        "p_version": 1,
        "bus": {"i2c": {"p_version": 0, "bus_id": 0, "address": 0x45}},
        "current": 327,
        "shunt": data_type.decode(bytes.fromhex(ina["default"]), tao=False)["shunt"],
    }
    f = {row["path"]: row for row in ina["fields"]}
    assert f["p_version"]["default"] == data_type.version[1]  # type: ignore[index]
    assert f["bus.i2c.address"]["default"] == 0x45
    assert (f["current"]["unit"], f["current"]["default"], f["current"]["max"]) == ("A", 327, 327)
    assert (f["shunt"]["unit"], f["shunt"]["default"], f["shunt"]["decimalPlaces"]) == (
        "Ohm",
        0.0003,
        6,
    )
    assert f["shunt"]["shortDesc"] == "Shunt resistance"
    tag = f["bus._tag"]
    assert [v["name"] for v in tag["variants"]] == [
        "i2c",
        "spi",
        "serial",
        "dronecan",
        "sim",
        "mavlink",
    ]
    assert tag["values"][:2] == [
        {"value": 0, "description": "I2C"},
        {"value": 1, "description": "SPI"},
    ]
    assert (tag["default"], tag["min"], tag["max"]) == (0, 0, 5)
    spi = tag["variants"][1]["fields"]
    assert [(x["path"], x["type"]) for x in spi] == [
        ("bus.spi.p_version", "uint4"),
        ("bus.spi.bus_id", "uint4"),
        ("bus.spi.chip_select", "uint5"),
        ("bus.spi.max_frequency", "uint16"),
        ("bus.spi.mode", "uint2"),
    ]
    assert spi[4]["default"] == 3  # Spi's own @default for an unselected variant
    assert all("index" not in x for x in spi)


def test_the_document_is_qgcs_version_1(document: dict[str, Any]) -> None:
    assert document["version"] == 1
    names = [e["name"] for e in document["parameters"]]
    structured_names = [e["name"] for e in document["parameters"] if e["type"] == "Custom"]
    flat_names = names[len(structured_names) :]
    # no classic parameters: structured ones by name, then their destructured names
    assert names[: len(structured_names)] == sorted(structured_names)
    assert flat_names[:3] == ["AK09916_INST", "AK09916_0A", "AK09916_0B"]
    assert {"INA238", "INA226", "INA228", "AK09916", "RM3100"} <= set(names)
    json.dumps(document, allow_nan=False)  # plain JSON: no NaN or infinities


# --- fields are the leaves ----------------------------------------------------------------------


def all_specs(schema: px4params.Schema, tst_schema: px4params.Schema) -> Iterator[tuple[Any, Any]]:
    for spec in parameter_specs(schema):
        yield schema, spec
    yield tst_schema, next(s for s in parameter_specs(tst_schema) if s.name == "EVERYTHING_SH")


def test_fields_are_the_leaves_of_the_default_value(
    schema: px4params.Schema, tst_schema: px4params.Schema
) -> None:
    checked = 0
    for sch, spec in all_specs(schema, tst_schema):
        entry = structured_entry(sch, spec)
        data = bytes.fromhex(entry["default"])
        leaves = spec.data_type.leaves(data, tao=False)
        fields = [f for f in entry["fields"] if f["role"] != "padding"]
        assert [(f["index"], f["path"], f["type"]) for f in fields] == [
            (leaf.index, leaf.path, leaf.type) for leaf in leaves
        ], spec.name
        for f, leaf in zip(fields, leaves, strict=True):
            assert stored(f["type"], f["default"]) == leaf.value, (spec.name, f["path"])
            assert f["min"] <= f["default"] <= f["max"], (spec.name, f["path"])
        checked += 1
    assert checked == len(parameter_specs(schema)) + 1


def test_every_variant_is_described_as_its_selection_would_be(schema: px4params.Schema) -> None:
    for spec in parameter_specs(schema):
        entry = structured_entry(schema, spec)
        default = metadata_default(schema, spec.data_type.key)
        for tag in (f for f in entry["fields"] if f["role"] == "union_tag"):
            union = tag["path"].removesuffix("._tag")
            field = next(f for f in spec.data_type.definition["fields"] if f["name"] == union)
            variants = schema.model["types"][field["type"]["name"]]["fields"]
            for variant, described in zip(variants, tag["variants"], strict=True):
                value = copy.deepcopy(default)
                if variant["name"] not in value[union]:  # the selected one keeps its defaults
                    variant_default = metadata_default(schema, variant["type"]["name"])
                    value[union] = {variant["name"]: variant_default}
                fields = describe_value(schema, spec.data_type.key, value)
                at = next(i for i, f in enumerate(fields) if f["path"] == tag["path"])
                inline = fields[at + 1 : at + 1 + len(described["fields"])]
                assert [{k: v for k, v in f.items() if k != "index"} for f in inline] == (
                    described["fields"]
                )
                assert fields[at]["default"] == described["tag"]
                # And these are the leaves the codec sees for that selection.
                leaves = spec.data_type.leaves(spec.data_type.encode(value, tao=False), tao=False)
                assert [(f["path"], f["type"]) for f in fields] == [
                    (leaf.path, leaf.type) for leaf in leaves
                ]


def test_every_field_kind_is_described(tst_schema: px4params.Schema) -> None:
    spec = next(s for s in parameter_specs(tst_schema) if s.name == "EVERYTHING_SH")
    entry = structured_entry(tst_schema, spec)
    assert entry["dsdl_type"] == TST_KEY
    assert entry["max_instances"] is None  # shared
    assert entry["group"] == "Test" and "rebootRequired" not in entry
    f = {x["path"]: x for x in entry["fields"] if x["role"] != "padding"}
    assert [x["path"] for x in entry["fields"] if x["role"] == "padding"] == [
        "choice.item._pad",
        "_pad",
    ]
    assert all("index" not in x for x in entry["fields"] if x["role"] == "padding")
    assert (f["wrap"]["cast"], f["wrap"]["default"]) == ("truncated", 5)
    assert (f["signed_value"]["type"], f["signed_value"]["min"], f["signed_value"]["max"]) == (
        "int7",
        -64,
        63,
    )
    assert (f["flag"]["type"], f["flag"]["default"], "cast" in f["flag"]) == ("bool", True, False)
    assert [f[f"triple[{i}]"]["type"] for i in range(3)] == ["uint8"] * 3
    items = f["items._len"]
    assert (items["type"], items["max"], items["default"], items["element_min_bits"]) == (
        "uint2",
        3,
        0,
        45,
    )
    assert [(x["path"], x["role"]) for x in items["element"]] == [
        ("items[].p_version", "version"),
        ("items[].offset", "value"),
        ("items[].enabled", "value"),
        ("items[]._pad", "padding"),
        ("items[].gain", "value"),
    ]
    assert items["element"][1]["unit"] == "mm" and items["element"][1]["min"] == -10
    choice = f["choice._tag"]
    assert choice["default"] == 3  # @default item.offset 2 selects the item variant
    assert f["choice.item.offset"]["default"] == 2
    text = choice["variants"][2]["fields"]
    assert [(x["path"], x["type"], x["max"]) for x in text] == [("choice.text._len", "uint3", 5)]
    assert text[0]["element"] == [
        {
            "name": "text",
            "path": "choice.text[]",
            "type": "uint8",
            "role": "value",
            "shortDesc": "Some text",
            "default": 0,
            "min": 0,
            "max": 255,
            "cast": "saturated",
        }
    ]
    assert choice["variants"][1]["fields"][0]["type"] == "float64"
    assert (f["loose"]["cast"], f["tail._len"]["element_min_bits"]) == ("truncated", 8)
    tags = list(tag_entries(entry["fields"]))
    assert [t["path"] for t in tags] == ["choice._tag"]


# --- QGC ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def real() -> dict[str, Any]:
    with open(real_parameters_json(), encoding="utf-8") as f:
        return json.load(f)


def structured(schema: px4params.Schema, tst_schema: px4params.Schema) -> list[dict[str, Any]]:
    return [structured_entry(sch, spec) for sch, spec in all_specs(schema, tst_schema)]


def test_no_key_that_every_real_entry_has_is_missing(
    real: dict[str, Any], schema: px4params.Schema, tst_schema: px4params.Schema
) -> None:
    always = set.intersection(*(set(e) for e in real["parameters"]))
    assert {"name", "type", "default", "group", "category", "shortDesc"} <= always
    for entry in structured(schema, tst_schema):
        assert always <= set(entry), entry["name"]


def test_value_types_match_the_real_file(
    real: dict[str, Any], schema: px4params.Schema, tst_schema: px4params.Schema
) -> None:
    kinds: dict[str, set[str]] = {}
    for e in real["parameters"]:
        for key, value in e.items():
            kinds.setdefault(key, set()).add(json_kind(value))
    assert kinds["default"] == {"number"} and kinds["rebootRequired"] == {"bool"}
    for entry in structured(schema, tst_schema):
        for key, value in entry.items():
            if key == "default":
                # QGC converts a Custom value to a byte array (FactMetaData::convertAndValidateRaw):
                # the encoding, as a hex string.
                assert entry["type"] == "Custom" and json_kind(value) == "string"
            elif key in kinds:
                assert json_kind(value) in kinds[key], (entry["name"], key)
            else:
                assert key in (
                    "max_instances",
                    "dsdl_type",
                    "max_bytes",
                    "default_value",
                    "fields",
                    "flat",
                )


def test_entries_pass_qgcs_key_checks(
    schema: px4params.Schema, tst_schema: px4params.Schema
) -> None:
    for entry in structured(schema, tst_schema):
        for key, kind in QGC_KEY_TYPES.items():
            if key in entry:
                assert json_kind(entry[key]) == kind, (entry["name"], key)
        assert entry["type"].lower() in {t.lower() for t in QGC_TYPES}
        assert 1 <= len(entry["name"]) <= 16


def test_classic_parameters_are_copied_unchanged(
    real: dict[str, Any], schema: px4params.Schema
) -> None:
    document = build_parameters_json(schema, real_parameters_json())
    params = document["parameters"]
    assert params[: len(real["parameters"])] == real["parameters"]
    specs = parameter_specs(schema)
    after = params[len(real["parameters"]) :]
    assert [e["name"] for e in after[: len(specs)]] == [s.name for s in specs]
    assert all(e["type"] in ("Int32", "Float") for e in after[len(specs) :])
    assert document["translation"] == real["translation"]
    assert document["version"] == 1
    names = [e["name"] for e in params]
    assert len(set(names)) == len(names)
    # What QGC reads back: the same document, in plain JSON.
    assert json.loads(json.dumps(document, allow_nan=False)) == document


# --- sources and errors -------------------------------------------------------------------------


def test_classic_source_prefers_the_explicit_file(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(CLASSIC_ENV, "/from/env.json")
    assert classic_source("given.json") == "given.json"
    assert classic_source(Path("p.json")) == "p.json"
    assert classic_source(None) == "/from/env.json"
    monkeypatch.setenv(CLASSIC_ENV, "")
    assert classic_source(None) is None
    monkeypatch.delenv(CLASSIC_ENV)
    assert classic_source(None) is None


def test_a_classic_parameter_with_a_structured_name_is_refused(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    classic = tmp_path / "parameters.json"
    classic.write_text(
        json.dumps(
            {"version": 1, "parameters": [{"name": "INA238", "type": "Int32", "default": 0}]}
        ),
        encoding="utf-8",
    )
    with pytest.raises(MetadataError) as info:
        build_parameters_json(schema, classic)
    assert str(info.value) == (
        f"parameter INA238 is both structured ({schema['px.Ina238'].key}) and classic "
        f"(in {classic})"
    )


@pytest.mark.parametrize(
    ("name", "described"), [("INA238_0A", "INA238 #0: bus._tag"), ("INA238_INST", "INA238")]
)
def test_a_classic_parameter_with_a_destructured_name_is_refused(
    schema: px4params.Schema, tmp_path: Path, name: str, described: str
) -> None:
    # Written with the name twice (exit 0): the store refuses the same pair.
    classic = tmp_path / "parameters.json"
    classic.write_text(
        json.dumps({"version": 1, "parameters": [{"name": name, "type": "Int32", "default": 0}]}),
        encoding="utf-8",
    )
    with pytest.raises(MetadataError) as info:
        build_parameters_json(schema, classic)
    assert str(info.value).startswith(f"{name} is both a destructured name ({described}") and str(
        info.value
    ).endswith(f") and a classic parameter (in {classic})")


def test_a_bad_classic_file_fails_with_its_message(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    with pytest.raises(ClassicParamsError, match=r"missing\.json: cannot read: No such file"):
        build_parameters_json(schema, tmp_path / "missing.json")


def test_a_classic_file_without_translation_gets_none(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    classic = tmp_path / "parameters.json"
    entry = {"name": "X_ONE", "type": "Float", "default": 1.5, "units": "m"}
    classic.write_text(json.dumps({"version": 1, "parameters": [entry]}), encoding="utf-8")
    document = build_parameters_json(schema, classic)
    assert "translation" not in document
    assert document["parameters"][0] == entry


def test_describe_value_refuses_what_does_not_encode(schema: px4params.Schema) -> None:
    value = metadata_default(schema, schema["px.Ina238"].key)
    value["bus"] = {"i2c": {"bus_id": 1, "address": 200}}
    with pytest.raises(
        px4params.EncodeError, match=r"bus\.i2c\.address: value 200 is out of range"
    ):
        describe_value(schema, schema["px.Ina238"].key, value)


def test_describe_value_wants_a_struct(schema: px4params.Schema) -> None:
    key = schema["px.Bus"].key
    with pytest.raises(MetadataError) as info:
        describe_value(schema, key, {"i2c": {"bus_id": 1, "address": 2}})
    assert str(info.value) == f"{key}: a parameter's type must be a struct, not a union"
