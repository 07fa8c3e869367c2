"""Data type signatures (python/px4params/signature.py) against pydronecan, for every bundled type.

The normalized definition texts need no native code; signatures and CRC seeds use the native
CRC functions.
"""

from __future__ import annotations

import copy
import struct
import textwrap
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from dronecan.dsdl.signature import Signature
from dronecan_oracle import BUNDLED
from px4params.dsdl import cache as model_cache
from px4params.dsdl.cache import load_model
from px4params.dsdl.signature import data_type_signature, normalized_definition, transfer_crc_seed
from px4params.errors import DsdlError

NAMES = sorted(BUNDLED)
OVERRIDDEN = sorted(n for n, t in BUNDLED.items() if t.override_signature is not None)
SERVICES = sorted(n for n, t in BUNDLED.items() if t.kind == t.KIND_SERVICE)

#: Pinned: a changed normalization or CRC changes these (and every px signature on the wire).
INA238_TEXT = """\
px.Ina238
saturated uint4 p_version
px.Bus bus
saturated uint10 current
saturated float16 shunt"""
BUS_TEXT = """\
px.Bus
@union
px.I2c i2c
px.Spi spi
px.Serial serial
px.Dronecan dronecan
px.Simulation sim
px.Mavlink mavlink"""
INA238_SIGNATURE = 0xE931820F070F961B


def model_keys(name: str) -> list[str]:
    """The model keys of a bundled type: a service's two halves, or the message itself."""
    t = BUNDLED[name]
    return [f"{name}.Request", f"{name}.Response"] if t.kind == t.KIND_SERVICE else [name]


def seed_of(signature: int) -> int:
    """pydronecan's ``base_crc`` formula, for types it gives none (no data type ID)."""
    return dronecan.dsdl.crc16_from_bytes(struct.pack("<Q", signature))


@pytest.fixture(scope="module")
def types(schema: px4params.Schema) -> dict[str, Any]:
    return dict(schema.model["types"])


@pytest.fixture(scope="module")
def px_keys(types: dict[str, Any]) -> list[str]:
    keys = sorted(k for k in types if k.startswith("px."))
    assert len(keys) >= 16
    return keys


def independent_signature(types: dict[str, Any], key: str) -> int:
    """A px type's signature through pydronecan's CRC-64 class instead of the native code."""
    sig = Signature()
    sig.add(normalized_definition(types, key).encode())
    value = sig.get_value()
    sig = Signature(value)
    for f in types[key]["fields"]:
        inner = f["type"]
        while inner["kind"] in ("array", "dynarray"):
            inner = inner["elem"]
        if inner["kind"] == "ref":
            so_far = sig.get_value()
            sig.add(struct.pack("<Q", independent_signature(types, inner["name"])))
            sig.add(struct.pack("<Q", so_far))
    return sig.get_value()


# --------------------------------------------------------------------------------------------------
# Every bundled DroneCAN type


def test_bundled_set_is_all_there(types: dict[str, Any]) -> None:
    assert len(NAMES) == 147
    assert SERVICES and OVERRIDDEN
    for name in NAMES:
        for key in model_keys(name):
            assert key in types, key


@pytest.mark.parametrize("name", NAMES)
def test_normalized_definition_equals_pydronecan(types: dict[str, Any], name: str) -> None:
    expected = BUNDLED[name].get_dsdl_signature_source_definition()
    for key in model_keys(name):
        assert normalized_definition(types, key) == expected, key


@pytest.mark.parametrize("name", NAMES)
def test_data_type_signature_equals_pydronecan(types: dict[str, Any], name: str) -> None:
    expected = BUNDLED[name].get_data_type_signature()
    for key in model_keys(name):
        assert data_type_signature(types, key) == expected, key
        assert transfer_crc_seed(types, key) == seed_of(expected), key


def test_transfer_crc_seed_equals_base_crc(types: dict[str, Any]) -> None:
    # dronecan.TYPENAMES (the types pydronecan can send) carry the seed it really uses.
    checked = 0
    memo: dict[str, int] = {}
    for name, t in dronecan.TYPENAMES.items():
        if not hasattr(t, "base_crc"):
            continue
        for key in model_keys(name):
            assert transfer_crc_seed(types, key, memo=memo) == t.base_crc, key
        checked += 1
    assert checked > 100


def test_all_signatures_with_one_memo(types: dict[str, Any]) -> None:
    memo: dict[str, int] = {}
    for name in NAMES:
        for key in model_keys(name):
            assert (
                data_type_signature(types, key, memo=memo)
                == BUNDLED[name].get_data_type_signature()
            )
    # Nested types were entered on the way, and both halves of every service.
    assert set(memo) == {key for name in NAMES for key in model_keys(name)}


@pytest.mark.parametrize("name", OVERRIDDEN)
def test_override_signature(types: dict[str, Any], name: str) -> None:
    t = BUNDLED[name]
    for key in model_keys(name):
        assert types[key]["signature_override"] == t.override_signature
    # The override replaces the DSDL signature: the text's CRC would give another value.
    without = copy.deepcopy(types)
    for key in model_keys(name):
        without[key]["signature_override"] = None
    assert data_type_signature(without, model_keys(name)[0]) != t.get_data_type_signature()
    assert data_type_signature(types, model_keys(name)[0]) == t.get_data_type_signature()


def test_no_override_elsewhere(types: dict[str, Any]) -> None:
    for name in set(NAMES) - set(OVERRIDDEN):
        for key in model_keys(name):
            assert types[key]["signature_override"] is None, key


@pytest.mark.parametrize("name", SERVICES)
def test_service_halves_share_the_service(types: dict[str, Any], name: str) -> None:
    request, response = model_keys(name)
    assert types[request]["service"] == types[response]["service"] == name
    memo: dict[str, int] = {}
    value = data_type_signature(types, response, memo=memo)
    assert memo[request] == memo[response] == value
    assert normalized_definition(types, name) == normalized_definition(types, request)
    assert data_type_signature(types, name) == value


def test_messages_are_not_services(types: dict[str, Any]) -> None:
    for name in set(NAMES) - set(SERVICES):
        assert types[name]["service"] is None


def test_memo_is_used(types: dict[str, Any]) -> None:
    key = "uavcan.equipment.power.BatteryInfo"
    assert data_type_signature(types, key, memo={key: 1234}) == 1234


def test_datatype_signature_property(schema: px4params.Schema) -> None:
    for name in ("uavcan.protocol.NodeStatus", "uavcan.equipment.power.BatteryInfo"):
        assert schema[name].signature == BUNDLED[name].get_data_type_signature()
    expected = BUNDLED["uavcan.protocol.GetNodeInfo"].get_data_type_signature()
    assert schema["uavcan.protocol.GetNodeInfo.Request"].signature == expected
    assert schema["uavcan.protocol.GetNodeInfo.Response"].signature == expected
    assert schema["px.Ina238"].signature == INA238_SIGNATURE
    assert schema["px.Ina238"].dtid is None
    assert schema["uavcan.protocol.NodeStatus"].dtid == 341


# --------------------------------------------------------------------------------------------------
# Our px types


def test_px_normalized_text(types: dict[str, Any]) -> None:
    assert normalized_definition(types, "px.Ina238.1.1") == INA238_TEXT
    assert normalized_definition(types, "px.Bus.1.0") == BUS_TEXT


def test_px_signatures_pinned_and_independent(types: dict[str, Any], px_keys: list[str]) -> None:
    assert data_type_signature(types, "px.Ina238.1.1") == INA238_SIGNATURE
    for key in px_keys:
        assert data_type_signature(types, key) == independent_signature(types, key), key


def test_px_signatures_distinct(types: dict[str, Any], px_keys: list[str]) -> None:
    signatures = {key: data_type_signature(types, key) for key in px_keys}
    assert len(set(signatures.values())) == len(px_keys), signatures
    assert all(0 <= s < 1 << 64 for s in signatures.values())
    again = {key: data_type_signature(types, key) for key in px_keys}
    assert again == signatures


def test_px_layout_change_changes_signature(types: dict[str, Any]) -> None:
    changed = copy.deepcopy(types)
    address = next(f for f in changed["px.I2c.1.0"]["fields"] if f["name"] == "address")
    address["type"]["bits"] = 8
    assert data_type_signature(changed, "px.I2c.1.0") != data_type_signature(types, "px.I2c.1.0")
    # ... and, through the nested signature, every type holding an I2c.
    assert data_type_signature(changed, "px.Ina238.1.1") != INA238_SIGNATURE
    assert normalized_definition(changed, "px.Ina238.1.1") == INA238_TEXT


def test_px_types_have_no_service_or_override(types: dict[str, Any], px_keys: list[str]) -> None:
    for key in px_keys:
        assert types[key]["service"] is None
        assert types[key]["signature_override"] is None


# --------------------------------------------------------------------------------------------------
# Extra roots, loader fields, errors


def write(root: Path, relative: str, text: str) -> None:
    path = root / relative
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text), encoding="utf-8")


def test_model_format_bumped(tmp_path: Path) -> None:
    assert model_cache.MODEL_FORMAT >= 2
    model = load_model(include_dronecan=False, cache_dir=tmp_path)
    assert model["format"] == model_cache.MODEL_FORMAT
    assert all("service" in t and "signature_override" in t for t in model["types"].values())


def test_pydsdl_service(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    write(root, "Pair.1.0.dsdl", "@union\nuint8 x\nint3[<=4] y\n@sealed\n")
    write(
        root,
        "Ask.1.0.dsdl",
        """\
        uint8 a
        uint8 LIMIT = 4
        @sealed
        ---
        bool b
        void3
        Pair.1.0[2] pairs
        @sealed
        """,
    )
    types = load_model([root], include_dronecan=False, cache_dir=tmp_path / "cache")["types"]
    request, response = types["ext.Ask.Request.1.0"], types["ext.Ask.Response.1.0"]
    assert request["service"] == response["service"] == "ext.Ask"
    text = "ext.Ask\nsaturated uint8 a\n---\nsaturated bool b\nvoid3\next.Pair[2] pairs"
    assert normalized_definition(types, "ext.Ask.Request.1.0") == text
    assert normalized_definition(types, "ext.Ask.Response.1.0") == text
    assert normalized_definition(types, "ext.Pair.1.0") == (
        "ext.Pair\n@union\nsaturated uint8 x\nsaturated int3[<=4] y"
    )
    memo: dict[str, int] = {}
    value = data_type_signature(types, "ext.Ask.Request.1.0", memo=memo)
    assert memo["ext.Ask.Response.1.0"] == value
    pair = memo["ext.Pair.1.0"]
    dsdl = Signature()
    dsdl.add(text.encode())
    expected = Signature(dsdl.get_value())
    expected.add(struct.pack("<Q", pair) + struct.pack("<Q", dsdl.get_value()))
    assert value == expected.get_value()


def test_uavcan_root_like_pydronecan(tmp_path: Path) -> None:
    """Truncated bool, OVERRIDE_SIGNATURE with nested types, [<N], unions and constants."""
    root = tmp_path / "vendor"
    write(
        root,
        "Inner.uavcan",
        """\
        @union
        truncated bool flag   # a truncated bool only changes the signature
        uint8[<4] small
        """,
    )
    write(
        root,
        "20001.Outer.uavcan",
        """\
        OVERRIDE_SIGNATURE 0x0123456789ABCDEF
        uint8 CONSTANT = 7
        Inner inner
        truncated int9[3] values
        void2
        Inner[<=2] more
        """,
    )
    write(
        root,
        "201.Call.uavcan",
        """\
        Inner request_inner
        ---
        @union
        float16 x
        truncated uint64 y
        """,
    )
    parsed = {t.full_name: t for t in dronecan.dsdl.parse_namespaces([str(root)])}
    types = load_model([root], include_dronecan=False, cache_dir=tmp_path / "cache")["types"]
    assert types["vendor.Inner"]["fields"][0]["type"] == {"kind": "bool", "cast": "truncated"}
    assert types["vendor.Outer"]["signature_override"] == 0x0123456789ABCDEF
    for name, t in parsed.items():
        keys = [f"{name}.Request", f"{name}.Response"] if t.kind == t.KIND_SERVICE else [name]
        for key in keys:
            assert normalized_definition(types, key) == t.get_dsdl_signature_source_definition()
            assert data_type_signature(types, key) == t.get_data_type_signature()


def test_unknown_key(types: dict[str, Any]) -> None:
    with pytest.raises(KeyError):
        normalized_definition(types, "uavcan.NoSuchType")
    with pytest.raises(KeyError):
        data_type_signature(types, "px.NoSuchType.1.0")


def tiny(fields: list[tuple[str, dict[str, Any]]], **extra: Any) -> dict[str, Any]:
    return {
        "kind": "struct",
        "dialect": "uavcan",
        "file": "/x.uavcan",
        "fields": [{"name": n, "type": t, "line": 1} for n, t in fields],
        **extra,
    }


def test_dangling_reference() -> None:
    types = {"a.A": tiny([("b", {"kind": "ref", "name": "a.Missing"})], name="a.A")}
    with pytest.raises(DsdlError, match=r"refers to unknown type a\.Missing"):
        normalized_definition(types, "a.A")
    with pytest.raises(DsdlError, match=r"refers to unknown type a\.Missing"):
        data_type_signature(types, "a.A")


def test_cycle_is_an_error() -> None:
    types = {
        "a.A": tiny([("b", {"kind": "ref", "name": "a.B"})], name="a.A"),
        "a.B": tiny(
            [("a", {"kind": "dynarray", "elem": {"kind": "ref", "name": "a.A"}, "max": 2})],
            name="a.B",
        ),
    }
    with pytest.raises(DsdlError, match="contains itself"):
        data_type_signature(types, "a.A")


def test_service_half_without_partner() -> None:
    types = {"a.S.Request": tiny([], name="a.S.Request", service="a.S")}
    with pytest.raises(DsdlError, match=r"no a\.S\.Response"):
        data_type_signature(types, "a.S.Request")
