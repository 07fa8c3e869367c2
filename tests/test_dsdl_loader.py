"""Tests for px4params.dsdl.loader: the schema model built from pydsdl and pydronecan."""

from __future__ import annotations

import json
import marshal
import math
import os
import pickle
import subprocess
import sys
import textwrap
import zlib
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from px4params.dsdl import cache as model_cache
from px4params.dsdl import loader as dsdl_loader
from px4params.dsdl import roots as model_roots
from px4params.dsdl.cache import load_model
from px4params.errors import DsdlError, Px4ParamsError

PYTHON_DIR = Path(dsdl_loader.__file__).resolve().parents[2]

PX_STRUCTS = [
    "I2c",
    "Spi",
    "Serial",
    "Dronecan",
    "Simulation",
    "Mavlink",
    "Ina226",
    "Ina228",
    "Ina238",
    "Ak09916",
    "Bmm350",
    "Ist8310",
    "Lis3mdl",
    "Qmc5883l",
    "Rm3100",
]
MAGNETOMETERS = ["Ak09916", "Bmm350", "Ist8310", "Lis3mdl", "Qmc5883l", "Rm3100"]


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Never touch the user's real cache, even when a test forgets cache_dir.
    monkeypatch.setenv("PX4PARAMS_CACHE_DIR", str(tmp_path / "default-cache"))


@pytest.fixture(scope="module")
def px_model(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return load_model(include_dronecan=False, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def full_model(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return load_model(cache_dir=tmp_path_factory.mktemp("cache"))


def write(root: Path, relative: str, text: str) -> Path:
    path = root / relative
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
    return path


def load_ext(tmp_path: Path, *roots: Path) -> dict[str, Any]:
    return load_model(list(roots), include_dronecan=False, cache_dir=tmp_path / "cache")


def leaves(model: dict[str, Any], key: str) -> list[tuple[str, str]]:
    """Flatten a type in declaration order, unions following their first variant."""
    out: list[tuple[str, str]] = []

    def visit(type_key: str, prefix: str) -> None:
        spec = model["types"][type_key]
        fields = spec["fields"]
        if spec["kind"] == "union":
            out.append((prefix + "tag", f"uint{math.ceil(math.log2(len(fields)))}"))
            fields = fields[:1]
        for f in fields:
            t = f["type"]
            if t["kind"] == "ref":
                visit(t["name"], f"{prefix}{f['name']}.")
            else:
                bits = t.get("bits", 1)
                out.append((prefix + f["name"], t["kind"] + (str(bits) if "bits" in t else "")))

    visit(key, "")
    return out


# --------------------------------------------------------------------------------------------------
# Bundled types


def test_bundled_types_present(px_model: dict[str, Any]) -> None:
    keys = set(px_model["types"])
    for name in [*PX_STRUCTS, "Bus"]:
        assert f"px.{name}.1.0" in keys
    assert all(spec["dialect"] == "dsdl" for spec in px_model["types"].values())
    assert px_model["format"] == model_cache.MODEL_FORMAT


def test_every_struct_starts_with_p_version(px_model: dict[str, Any]) -> None:
    for name in PX_STRUCTS:
        spec = px_model["types"][f"px.{name}.1.0"]
        assert spec["kind"] == "struct"
        first = spec["fields"][0]
        assert first["name"] == "p_version"
        assert first["type"] == {"kind": "uint", "bits": 4, "cast": "saturated"}


def test_leaves_fit_in_32_bits(px_model: dict[str, Any]) -> None:
    for spec in px_model["types"].values():
        for f in spec["fields"]:
            assert f["type"]["kind"] in ("uint", "int", "float", "bool", "ref"), f
            assert f["type"].get("bits", 1) <= 32, f


def test_ina238_model(px_model: dict[str, Any]) -> None:
    spec = px_model["types"]["px.Ina238.1.1"]
    assert spec["name"] == "px.Ina238"
    assert spec["version"] == [1, 1]
    assert spec["kind"] == "struct"
    assert spec["dtid"] is None
    assert spec["line"] == 1
    assert spec["file"].endswith(os.path.join("px", "Ina238.1.1.dsdl"))
    assert Path(spec["file"]).is_absolute()
    assert [(f["name"], f["type"]) for f in spec["fields"]] == [
        ("p_version", {"kind": "uint", "bits": 4, "cast": "saturated"}),
        ("bus", {"kind": "ref", "name": "px.Bus.1.0"}),
        ("current", {"kind": "uint", "bits": 10, "cast": "saturated"}),
        ("shunt", {"kind": "float", "bits": 16, "cast": "saturated"}),
    ]
    assert all(isinstance(f["line"], int) for f in spec["fields"])


def test_ina238_flattened_leaves(px_model: dict[str, Any]) -> None:
    # The talk's seven leaves: [0] p_version ... [6] shunt.
    assert leaves(px_model, "px.Ina238.1.1") == [
        ("p_version", "uint4"),
        ("bus.tag", "uint3"),
        ("bus.i2c.p_version", "uint4"),
        ("bus.i2c.bus_id", "uint4"),
        ("bus.i2c.address", "uint7"),
        ("current", "uint10"),
        ("shunt", "float16"),
    ]


def test_bus_union(px_model: dict[str, Any]) -> None:
    bus = px_model["types"]["px.Bus.1.0"]
    assert bus["kind"] == "union"
    assert [(f["name"], f["type"]["name"]) for f in bus["fields"]] == [
        ("i2c", "px.I2c.1.0"),
        ("spi", "px.Spi.1.0"),
        ("serial", "px.Serial.1.0"),
        ("dronecan", "px.Dronecan.1.0"),
        ("sim", "px.Simulation.1.0"),
        ("mavlink", "px.Mavlink.1.0"),
    ]


def test_i2c_matches_talk(px_model: dict[str, Any]) -> None:
    fields = px_model["types"]["px.I2c.1.0"]["fields"]
    assert [(f["name"], f["type"]["bits"]) for f in fields] == [
        ("p_version", 4),
        ("bus_id", 4),
        ("address", 7),
    ]
    assert fields[2]["doc"]["tags"] == {"min": 0, "max": 127, "format": "hex"}


def test_ina_metadata(px_model: dict[str, Any]) -> None:
    spec = px_model["types"]["px.Ina238.1.1"]
    assert spec["doc"]["short"] == "INA238 power monitor"
    assert "ina238" in spec["doc"]["long"]
    assert spec["doc"]["tags"] == {"group": "Sensors", "max_instances": 4, "reboot_required": True}
    bus, current, shunt = (f["doc"] for f in spec["fields"][1:])
    assert bus["tags"] == {"default": {"i2c.address": 0x45}}
    assert current["short"] == "Max current"
    assert current["tags"]["unit"] == "A"
    assert current["tags"]["default"] == 327
    assert shunt["tags"]["unit"] == "Ohm"
    assert shunt["tags"]["default"] == pytest.approx(0.0003)
    defaults = {
        name: px_model["types"][f"px.{name}.1.0"]["fields"][1]["doc"]["tags"]["default"]
        for name in ("Ina226", "Ina228", "Ina238")
    }
    assert defaults == {
        "Ina226": {"i2c.address": 0x41},
        "Ina228": {"i2c.address": 0x45},
        "Ina238": {"i2c.address": 0x45},
    }


def test_magnetometers(px_model: dict[str, Any]) -> None:
    for name in MAGNETOMETERS:
        spec = px_model["types"][f"px.{name}.1.0"]
        assert spec["doc"]["tags"]["group"] == "Sensors"
        names = [f["name"] for f in spec["fields"]]
        assert names[:3] == ["p_version", "bus", "rotation"], name
        rotation = spec["fields"][2]
        assert rotation["type"]["kind"] == "uint"
        assert rotation["doc"]["tags"]["min"] == 0
        assert rotation["doc"]["tags"]["max"] == 40
        assert [v[0] for v in rotation["doc"]["tags"]["value"]] == list(range(41))
        assert "i2c.address" in spec["fields"][1]["doc"]["tags"]["default"]
    ak = px_model["types"]["px.Ak09916.1.0"]
    assert ak["fields"][1]["doc"]["tags"]["default"] == {"i2c.address": 0x0C}


def test_model_is_json_roundtrip_stable(px_model: dict[str, Any]) -> None:
    # Every definition is plain data (the cache packs each one; nothing else may be in them).
    types = dict(px_model["types"].items())
    assert json.loads(json.dumps(types)) == types
    assert json.loads(json.dumps(px_model["newest"])) == px_model["newest"]


# --------------------------------------------------------------------------------------------------
# DroneCAN standard set


def _expected_dronecan_type(t: Any) -> dict[str, Any]:
    """The model type of a pydronecan field type, written independently of the loader."""
    if t.category == t.CATEGORY_COMPOUND:
        return {"kind": "ref", "name": t.full_name}
    if t.category == t.CATEGORY_VOID:
        return {"kind": "void", "bits": t.bitlen}
    if t.category == t.CATEGORY_ARRAY:
        elem = _expected_dronecan_type(t.value_type)
        if t.mode == t.MODE_STATIC:
            return {"kind": "array", "elem": elem, "len": t.max_size}
        return {"kind": "dynarray", "elem": elem, "max": t.max_size}
    if t.kind == t.KIND_BOOLEAN:
        return {"kind": "bool"}
    kind = {t.KIND_UNSIGNED_INT: "uint", t.KIND_SIGNED_INT: "int", t.KIND_FLOAT: "float"}[t.kind]
    cast = "truncated" if t.cast_mode == t.CAST_MODE_TRUNCATED else "saturated"
    return {"kind": kind, "bits": t.bitlen, "cast": cast}


def _expected_fields(fields: list[Any]) -> list[tuple[str, dict[str, Any]]]:
    return [(f.name or "", _expected_dronecan_type(f.type)) for f in fields]


def test_dronecan_standard_set_complete(full_model: dict[str, Any]) -> None:

    types = full_model["types"]
    for name, t in dronecan.TYPENAMES.items():
        if t.kind == t.KIND_SERVICE:
            request, response = types[f"{name}.Request"], types[f"{name}.Response"]
            assert _expected_fields(t.request_fields) == [
                (f["name"], f["type"]) for f in request["fields"]
            ]
            assert _expected_fields(t.response_fields) == [
                (f["name"], f["type"]) for f in response["fields"]
            ]
            assert request["kind"] == ("union" if t.request_union else "struct")
            assert response["kind"] == ("union" if t.response_union else "struct")
            assert request["dtid"] == response["dtid"] == t.default_dtid
        else:
            spec = types[name]
            assert _expected_fields(t.fields) == [(f["name"], f["type"]) for f in spec["fields"]]
            assert spec["kind"] == ("union" if t.union else "struct")
            assert spec["dtid"] == t.default_dtid
            assert spec["dialect"] == "uavcan"


def test_every_bundled_uavcan_file_is_loaded(full_model: dict[str, Any]) -> None:
    specs = Path(model_roots.dronecan_package_dir(), "dsdl_specs")
    files = sorted(specs.rglob("*.uavcan"))
    assert len(files) >= 147
    loaded = {spec["file"] for spec in full_model["types"].values()}
    assert {str(f.absolute()) for f in files} <= loaded
    for namespace in ("uavcan", "dronecan", "ardupilot", "com", "cuav", "mppt"):
        assert any(k.startswith(namespace + ".") for k in full_model["types"]), namespace


def test_battery_info(full_model: dict[str, Any]) -> None:

    expected = dronecan.TYPENAMES["uavcan.equipment.power.BatteryInfo"]
    spec = full_model["types"]["uavcan.equipment.power.BatteryInfo"]
    assert [f["name"] for f in spec["fields"]] == [f.name for f in expected.fields]
    assert spec["name"] == "uavcan.equipment.power.BatteryInfo"
    assert spec["version"] is None
    assert spec["dtid"] == 1092
    assert spec["doc"]["short"] == "Single battery info."
    assert spec["fields"][0]["type"] == {"kind": "float", "bits": 16, "cast": "saturated"}
    assert spec["fields"][0]["line"] is not None
    names = {f["name"]: f for f in spec["fields"]}
    assert names["model_name"]["type"]["kind"] == "dynarray"


def test_service_and_union_keys(full_model: dict[str, Any]) -> None:
    types = full_model["types"]
    assert "uavcan.protocol.param.GetSet" not in types
    response = types["uavcan.protocol.param.GetSet.Response"]
    assert response["fields"][0] == {
        "name": "",
        "type": {"kind": "void", "bits": 5},
        "line": response["fields"][0]["line"],
        "doc": {"short": "", "long": "", "tags": {}},
    }
    assert types["uavcan.protocol.param.Value"]["kind"] == "union"


# --------------------------------------------------------------------------------------------------
# Extra roots, pydsdl details


def test_extra_pydsdl_root_with_all_type_kinds(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    write(
        root,
        "Kinds.1.0.dsdl",
        """
        # All the kinds
        uint4 p_version
        truncated uint5 small  # trailing comment
        # more doc
        uint8 LIMIT = 3  # a constant, not a field
        bool flag
        void3
        float32[3] vec
        uint8[<4] short_list
        uint12[<=5] list
        byte[2] b
        utf8[<=4] s
        px.Bus.1.0 bus
        @sealed
        """,
    )
    spec = load_ext(tmp_path, root)["types"]["ext.Kinds.1.0"]
    octet = {"kind": "uint", "bits": 8, "cast": "truncated"}  # byte and utf8
    assert [(f["name"], f["type"]) for f in spec["fields"]] == [
        ("p_version", {"kind": "uint", "bits": 4, "cast": "saturated"}),
        ("small", {"kind": "uint", "bits": 5, "cast": "truncated"}),
        ("flag", {"kind": "bool"}),
        ("", {"kind": "void", "bits": 3}),
        (
            "vec",
            {"kind": "array", "elem": {"kind": "float", "bits": 32, "cast": "saturated"}, "len": 3},
        ),
        (
            "short_list",
            {
                "kind": "dynarray",
                "elem": {"kind": "uint", "bits": 8, "cast": "saturated"},
                "max": 3,
            },
        ),
        (
            "list",
            {
                "kind": "dynarray",
                "elem": {"kind": "uint", "bits": 12, "cast": "saturated"},
                "max": 5,
            },
        ),
        ("b", {"kind": "array", "elem": octet, "len": 2}),
        ("s", {"kind": "dynarray", "elem": octet, "max": 4}),
        ("bus", {"kind": "ref", "name": "px.Bus.1.0"}),
    ]
    assert [f["line"] for f in spec["fields"]] == [2, 3, 6, 7, 8, 9, 10, 11, 12, 13]
    assert spec["fields"][1]["doc"]["short"] == "trailing comment"
    assert spec["fields"][1]["doc"]["long"] == "more doc"


def test_field_tags_parsed(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    write(
        root,
        "Tags.1.0.dsdl",
        """
        int16 offset
        # Offset
        # @unit mm
        # @default -0x10
        # @min -1000
        # @max 1000
        # @decimal 0
        # @increment 5
        # @reboot_required false
        uint8 flags
        # Flags
        # @bit 0 First
        # @bit 7 Last
        # @value 1 One
        # @value 0x80 Big
        float32 gain
        # @default 1e-3
        # @min -1.5
        bool enabled
        # @default true
        @sealed
        """,
    )
    offset, flags, gain, enabled = load_ext(tmp_path, root)["types"]["ext.Tags.1.0"]["fields"]
    assert offset["doc"]["tags"] == {
        "unit": "mm",
        "default": -16,
        "min": -1000,
        "max": 1000,
        "decimal": 0,
        "increment": 5,
        "reboot_required": False,
    }
    assert flags["doc"]["tags"] == {
        "bit": [[0, "First"], [7, "Last"]],
        "value": [[1, "One"], [128, "Big"]],
    }
    assert gain["doc"] == {"short": "", "long": "", "tags": {"default": 0.001, "min": -1.5}}
    assert enabled["doc"]["tags"] == {"default": True}


def test_doc_comment_assignment(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    write(
        root,
        "Doc.1.0.dsdl",
        """
        # Short line
        # Long line one
        #
        # Long line three
        # @group Sensors

        # nobody's comment (above a field)
        uint8 a
        # Field a
        # @unit m

        # nobody's either
        uint8 b
        @sealed
        """,
    )
    spec = load_ext(tmp_path, root)["types"]["ext.Doc.1.0"]
    assert spec["doc"] == {
        "short": "Short line",
        "long": "Long line one\n\nLong line three",
        "tags": {"group": "Sensors"},
    }
    assert spec["fields"][0]["doc"] == {"short": "Field a", "long": "", "tags": {"unit": "m"}}
    assert spec["fields"][1]["doc"] == {"short": "", "long": "", "tags": {}}


def test_pydsdl_service(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    write(
        root,
        "300.Ping.1.0.dsdl",
        """
        # Ping request
        uint8 token
        @sealed
        ---
        # Ping response
        uint8 token
        uint16 rtt
        @sealed
        """,
    )
    types = load_ext(tmp_path, root)["types"]
    request, response = types["ext.Ping.Request.1.0"], types["ext.Ping.Response.1.0"]
    assert request["name"] == "ext.Ping.Request"
    assert request["dtid"] == response["dtid"] == 300
    assert request["doc"]["short"] == "Ping request"
    assert response["doc"]["short"] == "Ping response"
    assert [f["name"] for f in response["fields"]] == ["token", "rtt"]
    assert response["fields"][1]["line"] == 7


def test_all_versions_are_included(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    write(root, "Thing.1.0.dsdl", "uint4 p_version\nuint8 a\n@sealed\n")
    write(root, "Thing.1.1.dsdl", "uint4 p_version\nuint8 a\n# now documented\n@sealed\n")
    types = load_ext(tmp_path, root)["types"]
    assert types["ext.Thing.1.0"]["version"] == [1, 0]
    assert types["ext.Thing.1.1"]["fields"][1]["doc"]["short"] == "now documented"


def test_minor_versions_must_keep_their_size(tmp_path: Path) -> None:
    # pydsdl's rule for sealed types: same major version, same extent. Layout changes need 2.0.
    root = tmp_path / "ext"
    write(root, "Thing.1.0.dsdl", "uint8 a\n@sealed\n")
    write(root, "Thing.1.1.dsdl", "uint8 a\nuint8 b\n@sealed\n")
    with pytest.raises(DsdlError, match="extent"):
        load_ext(tmp_path, root)


def test_extra_uavcan_root_uses_standard_types(tmp_path: Path) -> None:
    root = tmp_path / "vendor"
    write(
        root,
        "20990.Report.uavcan",
        """
        # Vendor report
        uavcan.Timestamp timestamp
        uint8 CONSTANT = 3
        uint8[<=4] data  # payload
        """,
    )
    model = load_model([root], cache_dir=tmp_path / "cache")
    spec = model["types"]["vendor.Report"]
    assert spec["dtid"] == 20990
    assert spec["doc"]["short"] == "Vendor report"
    assert [(f["name"], f["line"]) for f in spec["fields"]] == [("timestamp", 2), ("data", 4)]
    assert spec["fields"][0]["type"] == {"kind": "ref", "name": "uavcan.Timestamp"}
    assert spec["fields"][1]["doc"]["short"] == "payload"


# --------------------------------------------------------------------------------------------------
# Cache


def test_second_load_hits_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    first = load_model(include_dronecan=False, cache_dir=tmp_path)

    def fail(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("parsed again instead of using the cache")

    monkeypatch.setattr(dsdl_loader, "build_model", fail)
    assert load_model(include_dronecan=False, cache_dir=tmp_path) == first
    assert len(list(tmp_path.glob("model-*.marshal"))) == 1


def test_default_cache_dir_from_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PX4PARAMS_CACHE_DIR", str(tmp_path / "env"))
    assert model_cache.default_cache_dir() == str(tmp_path / "env")
    load_model(include_dronecan=False)
    assert len(list((tmp_path / "env").glob("model-*.marshal"))) == 1
    monkeypatch.delenv("PX4PARAMS_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert model_cache.default_cache_dir() == str(tmp_path / "xdg" / "px4params")


def test_cache_key_follows_file_contents(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    path = write(root, "Thing.1.0.dsdl", "uint8 a\n# @default 1\n@sealed\n")
    assert load_ext(tmp_path, root)["types"]["ext.Thing.1.0"]["fields"][0]["doc"]["tags"] == {
        "default": 1
    }
    path.write_text("uint8 a\n# @default 2\n@sealed\n", encoding="utf-8")
    assert load_ext(tmp_path, root)["types"]["ext.Thing.1.0"]["fields"][0]["doc"]["tags"] == {
        "default": 2
    }
    assert len(list((tmp_path / "cache").glob("model-*.marshal"))) == 2
    # Options are part of the key as well.
    keys = {
        model_cache.cache_key_text(model_roots.collect_roots([root], flag), flag)
        for flag in (True, False)
    }
    assert len(keys) == 2


def _flip_last_byte(data: bytes) -> bytes:
    return data[:-1] + bytes([data[-1] ^ 1])


def _marshal_with_crc(value: object) -> bytes:
    body = marshal.dumps(value)
    return b"P4MC" + zlib.crc32(body).to_bytes(4, "little") + body


@pytest.mark.parametrize(
    "damage",
    [
        lambda _: b"",
        lambda _: b"{not json",
        lambda _: b"\xff\xfe\x00",
        lambda data: data[: len(data) // 2],  # torn
        _flip_last_byte,  # the CRC catches it before marshal sees it
        lambda data: _marshal_with_crc((marshal.loads(data[8:])[0], {"format": 99})),  # older
        lambda data: _marshal_with_crc(("another key", marshal.loads(data[8:])[1])),
        lambda _: _marshal_with_crc([]),
        lambda _: b"P4MC" + zlib.crc32(b"\xff").to_bytes(4, "little") + b"\xff",  # bad marshal
    ],
)
def test_corrupt_cache_is_rebuilt(tmp_path: Path, damage: Any) -> None:
    good = load_model(include_dronecan=False, cache_dir=tmp_path)
    (cache_file,) = tmp_path.glob("model-*.marshal")
    cache_file.write_bytes(damage(cache_file.read_bytes()))
    assert load_model(include_dronecan=False, cache_dir=tmp_path) == good
    rewritten = cache_file.read_bytes()
    assert rewritten[4:8] == zlib.crc32(rewritten[8:]).to_bytes(4, "little")
    stored = marshal.loads(rewritten[8:])[1]  # each type packed on its own
    assert {k: marshal.loads(v) for k, v in stored["types"].items()} == dict(good["types"].items())
    assert stored["newest"] == good["newest"]
    assert not list(tmp_path.glob(".*.tmp"))


def test_unwritable_cache_dir_still_loads(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder", encoding="utf-8")
    model = load_model(include_dronecan=False, cache_dir=blocker / "cache")
    assert "px.Ina238.1.1" in model["types"]


def _run_python(code: str, cache_dir: Path) -> str:
    path = os.pathsep.join(p for p in (str(PYTHON_DIR), os.environ.get("PYTHONPATH")) if p)
    env = {**os.environ, "PYTHONPATH": path, "PX4PARAMS_CACHE_DIR": str(cache_dir)}
    result = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return result.stdout.strip()


def test_cache_hit_imports_no_parser(tmp_path: Path) -> None:
    code = (
        "import sys; from px4params.dsdl.cache import load_model; load_model(); "
        "print(sorted(m for m in sys.modules if m.partition('.')[0] in "
        "('pydsdl', 'dronecan', '_px4params_dronecan_dsdl')))"
    )
    cold = _run_python(code, tmp_path)
    # A cold load parses, but never runs dronecan/__init__.py (the slow full parse).
    assert "'pydsdl'" in cold
    assert "'_px4params_dronecan_dsdl'" in cold
    assert "'dronecan'" not in cold
    assert _run_python(code, tmp_path) == "[]"


# --------------------------------------------------------------------------------------------------
# Errors


def _error(tmp_path: Path, root: Path, **kwargs: Any) -> DsdlError:
    with pytest.raises(DsdlError) as info:
        load_model(
            [root], include_dronecan=kwargs.get("include_dronecan", False), cache_dir=tmp_path / "c"
        )
    assert isinstance(info.value, Px4ParamsError)
    assert "\n" not in str(info.value)
    return info.value


def test_unknown_type_tag(tmp_path: Path) -> None:
    path = write(
        tmp_path / "ext", "Foo.1.0.dsdl", "# Foo\n# @group Sensors\n# @foo bar\nuint8 a\n@sealed\n"
    )
    error = _error(tmp_path, tmp_path / "ext")
    assert (error.file, error.line) == (str(path), 3)
    assert str(error).startswith(f"{path}:3: unknown metadata tag @foo (expected one of: ")
    assert "@max_instances" in str(error)


def test_unknown_field_tag(tmp_path: Path) -> None:
    path = write(tmp_path / "ext", "Foo.1.0.dsdl", "uint8 a\n# A\n# @units m\n@sealed\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error).startswith(f"{path}:3: unknown metadata tag @units (expected one of: ")
    assert "@unit" in str(error)


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        ("# @max_instances many", "@max_instances expects an integer 1..256, got 'many'"),
        ("# @max_instances 0", "@max_instances expects an integer 1..256"),
        ("# @reboot_required yes", "@reboot_required expects true or false, got 'yes'"),
        ("# @param ina238", "@param expects an upper-case parameter name"),
        ("# @category Fancy", "@category expects one of Standard, Developer, System"),
    ],
)
def test_wrong_kind_type_tag(tmp_path: Path, doc: str, message: str) -> None:
    path = write(tmp_path / "ext", "Foo.1.0.dsdl", f"# Foo\n{doc}\n\nuint8 a\n@sealed\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error).startswith(f"{path}:2: {message}")


@pytest.mark.parametrize(
    ("field", "doc", "message"),
    [
        ("uint8 a", "@default 0.5", "@default expects an integer for uint8, got '0.5'"),
        ("uint7 a", "@max 0x80", "@max 0x80 is out of range for uint7 (0..127)"),
        ("uint8 a", "@min lots", "@min expects a number"),
        ("float16 a", "@default 1e6", "@default 1e6 does not fit float16"),
        ("bool a", "@default 1", "@default expects true or false, got '1'"),
        ("bool a", "@unit m", "@unit does not apply to a bool field"),
        ("uint8 a", "@value x", "@value expects '<number> <description>'"),
        ("uint4 a", "@bit 4 Four", "@bit bit 4 does not exist in uint4"),
        ("uint8 a", "@decimal -1", "@decimal expects an integer >= 0"),
        ("px.Bus.1.0 bus", "@min 0", "@min does not apply to a px.Bus.1.0 field"),
        (
            "px.Bus.1.0 bus",
            "@default 3",
            "@default on a composite field takes '<field.path> <value>'",
        ),
    ],
)
def test_wrong_kind_field_tag(tmp_path: Path, field: str, doc: str, message: str) -> None:
    path = write(tmp_path / "ext", "Foo.1.0.dsdl", f"{field}\n# Doc\n# {doc}\n@sealed\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error).startswith(f"{path}:3: {message}"), str(error)


def test_default_outside_min_max(tmp_path: Path) -> None:
    path = write(
        tmp_path / "ext", "Foo.1.0.dsdl", "uint8 a\n# @min 1\n# @max 10\n# @default 11\n@sealed\n"
    )
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error) == f"{path}:4: @default 11 is above the field's @max 10"


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        ("@default i2c.port 1", "@default i2c.port: px.I2c has no field 'port'"),
        ("@default i2c.address 200", "@default i2c.address: 200 is out of range for uint7"),
        ("@default i2c.p_version 1", "p_version is filled in by the code"),
        ("@default i2c", "@default on a composite field takes"),
    ],
)
def test_bad_path_default(tmp_path: Path, doc: str, message: str) -> None:
    path = write(tmp_path / "ext", "Foo.1.0.dsdl", f"px.Bus.1.0 bus\n# {doc}\n@sealed\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error).startswith(f"{path}:2: "), str(error)
    assert message in str(error)


def test_conflicting_union_defaults(tmp_path: Path) -> None:
    path = write(
        tmp_path / "ext",
        "Foo.1.0.dsdl",
        "px.Bus.1.0 bus\n# @default i2c.address 0x45\n# @default spi.bus_id 1\n@sealed\n",
    )
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error).startswith(f"{path}:3: @default spi.bus_id: selects union variant 'spi'")


def test_text_after_tags(tmp_path: Path) -> None:
    path = write(
        tmp_path / "ext", "Foo.1.0.dsdl", "uint8 a\n# Doc\n# @min 0\n# more text\n@sealed\n"
    )
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error).startswith(f"{path}:4: description text after the metadata tags")


def test_pydsdl_syntax_error(tmp_path: Path) -> None:
    path = write(tmp_path / "ext", "Foo.1.0.dsdl", "# Foo\nuint8 a\nuint8 b c d\n@sealed\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert (error.file, error.line) == (str(path), 3)
    assert str(error).startswith(f"{path}:3: ")


def test_pydsdl_semantic_error(tmp_path: Path) -> None:
    path = write(tmp_path / "ext", "Foo.1.0.dsdl", "uint8 a\npx.Missing.1.0 m\n@sealed\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert (error.file, error.line) == (str(path), 2)


def test_malformed_uavcan_file(tmp_path: Path) -> None:
    path = write(tmp_path / "vendor", "Bad.uavcan", "uint8 a\nuint99 b\n")
    error = _error(tmp_path, tmp_path / "vendor")
    assert (error.file, error.line) == (str(path), 2)
    assert str(error) == f"{path}:2: Invalid bit length [99] (note: use bool instead of uint1)"


def test_malformed_nested_uavcan_file(tmp_path: Path) -> None:
    write(tmp_path / "vendor", "Top.uavcan", "uint8 a\nNested n\n")
    nested = write(tmp_path / "vendor", "Nested.uavcan", "uint8 x\nfloat7 y\n")
    error = _error(tmp_path, tmp_path / "vendor")
    assert (error.file, error.line) == (str(nested), 2)
    assert "float" in str(error)


def test_uavcan_error_with_standard_set(tmp_path: Path) -> None:
    path = write(tmp_path / "vendor", "Bad.uavcan", "uavcan.NoSuchType x\n")
    error = _error(tmp_path, tmp_path / "vendor", include_dronecan=True)
    assert (error.file, error.line) == (str(path), 1)


def test_delimited_type_refused(tmp_path: Path) -> None:
    path = write(tmp_path / "ext", "Foo.1.0.dsdl", "# Foo\nuint8 a\n@extent 64\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert (error.file, error.line) == (str(path), 3)
    assert "not @sealed" in str(error)


def test_bad_roots(tmp_path: Path) -> None:
    error = _error(tmp_path, tmp_path / "missing")
    assert error.file == str(tmp_path / "missing")
    write(tmp_path / "empty", "README.md", "nothing here\n")
    assert "no .dsdl or .uavcan files" in str(_error(tmp_path, tmp_path / "empty"))
    write(tmp_path / "mixed", "A.1.0.dsdl", "uint8 a\n@sealed\n")
    write(tmp_path / "mixed", "B.uavcan", "uint8 a\n")
    assert "mixes .dsdl" in str(_error(tmp_path, tmp_path / "mixed"))


def test_duplicate_type(tmp_path: Path) -> None:
    write(tmp_path / "one" / "px", "Ina238.1.0.dsdl", "uint8 a\n@sealed\n")
    with pytest.raises(DsdlError):
        load_model([tmp_path / "one" / "px"], include_dronecan=False, cache_dir=tmp_path / "c")


def test_bundled_root_given_again_is_read_once(tmp_path: Path) -> None:
    bundled = Path(__file__).resolve().parents[1] / "dsdl" / "px"  # through the root symlink
    model = load_model([bundled], include_dronecan=False, cache_dir=tmp_path)
    assert "px.Ina238.1.0" in model["types"]


def test_dsdl_error_is_picklable() -> None:
    error = DsdlError("bad\nthing", "/x/y.dsdl", 7)
    copy = pickle.loads(pickle.dumps(error))
    assert (copy.file, copy.line, copy.message) == ("/x/y.dsdl", 7, "bad\nthing")
    assert str(copy) == "/x/y.dsdl:7: bad thing"
    assert str(DsdlError("no location")) == "no location"
    assert str(DsdlError("no line", Path("/x"))) == "/x: no line"


# --------------------------------------------------------------------------------------------------
# Named value lists (@values)


def test_values_names_a_bundled_list(tmp_path: Path) -> None:
    root = tmp_path / "ext"
    write(root, "Mag.1.0.dsdl", "# M\nuint6 rotation\n# @values rotation\n# @default 0\n@sealed\n")
    tags = load_ext(tmp_path, root)["types"]["ext.Mag.1.0"]["fields"][0]["doc"]["tags"]
    # PX4's Rotation enum (src/lib/conversion/rotation.h): 41 entries, 0..40.
    assert [n for n, _ in tags["value"]] == list(range(41))
    assert tags["value"][10] == [10, "Roll 180 deg, Yaw 90 deg"]
    assert tags["value"][38] == [38, "Roll 90 deg, Pitch 68 deg, Yaw 293 deg"]


@pytest.mark.parametrize(
    ("field", "message"),
    [
        ("uint6 r\n# @values compass", "@values names no value list 'compass' (expected one of: "),
        ("uint4 r\n# @values rotation", "@values 16 is out of range for uint4 (0..15)"),
        ("uint6 r\n# @value 3 three\n# @values rotation", "@values rotation: lists 3 twice"),
        ("bool r\n# @values rotation", "@values does not apply to a bool field"),
    ],
)
def test_values_errors(tmp_path: Path, field: str, message: str) -> None:
    path = write(tmp_path / "ext", "Bad.1.0.dsdl", f"# B\n{field}\n@sealed\n")
    error = _error(tmp_path, tmp_path / "ext")
    assert str(error).startswith(f"{path}:") and message in str(error)


# -- hostile types (defects 2, 3 and 13 of an outside audit) -----------------------------------


def _types(tmp_path: Path, files: dict[str, str | bytes]) -> px4params.Schema:
    root = tmp_path / "acme"
    root.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (root / name).write_bytes(text if isinstance(text, bytes) else text.encode())
    return px4params.load_schema(
        [root], include_dronecan=False, use_env=False, cache_dir=tmp_path / "cache"
    )


def test_a_type_too_large_is_refused_before_anything_is_allocated(tmp_path: Path) -> None:
    with pytest.raises(DsdlError) as e:
        _types(
            tmp_path,
            {
                "L1.1.0.dsdl": "uint8[65535] x\n@sealed\n",
                "L2.1.0.dsdl": "L1.1.0[65535] x\n@sealed\n",
            },
        )
    assert str(e.value).endswith(
        "acme.L2.1.0: its largest value has 34,358,689,800 bits (4,294,836,225 bytes); types "
        "are limited to 65,535 bytes"
    )
    # Far below the limit: accepted.
    schema = _types(tmp_path / "ok", {"Ok.1.0.dsdl": "uint8[65000] x\n@sealed\n"})
    assert schema.get("acme.Ok").max_bits == 65000 * 8


def test_max_instances_is_bounded(tmp_path: Path) -> None:
    with pytest.raises(DsdlError, match=r"@max_instances expects an integer 1\.\.256, got '65536'"):
        _types(tmp_path, {"W.1.0.dsdl": "# @max_instances 65536\nuint8 x\n@sealed\n"})


def test_pydsdl_internal_errors_say_what_is_wrong_with_the_file(tmp_path: Path) -> None:
    with pytest.raises(DsdlError) as e:
        _types(tmp_path, {"B.1.0.dsdl": b"\xc7\x00binary"})
    assert "not a text file: byte 0xC7 at offset 0 is not UTF-8" in str(e.value)
    assert "PLEASE REPORT" not in str(e.value)


def test_types_that_use_each_other_too_often_are_refused_before_pydsdl(tmp_path: Path) -> None:
    """Found by the fuzz run: pydsdl recomputes a type's alignment for every use, so six small
    files that use each other a few hundred times over took it 18 s (and more types, minutes).
    They are counted first and refused."""
    files = {
        "T0.1.0.dsdl": "int3 a\nfloat16 b\n@sealed\n",
        "T1.1.0.dsdl": "@union\n"
        + "".join(f"T0.1.0[<=2] v{i}\n" for i in range(300))
        + "@sealed\n",
        "T2.1.0.dsdl": "".join(f"T1.1.0 f{i}\n" for i in range(100)) + "@sealed\n",
    }
    with pytest.raises(DsdlError) as e:
        _types(tmp_path, files)
    assert "acme.T2.1.0 uses its types so many times over (" in str(e.value)
    assert "at most 20,000): pydsdl would take seconds to minutes to read it" in str(e.value)


@pytest.mark.parametrize(
    ("field", "minor", "top"), [("uint4", 16, 15), ("int4", 8, 7), ("int8", 128, 127)]
)
def test_a_p_version_too_narrow_for_the_minor_version_is_refused(
    tmp_path: Path, field: str, minor: int, top: int
) -> None:
    # The codec writes the minor version into p_version; a field that cannot hold it would be
    # written cut (minor 16 in a uint4 as 0) by firmware's walk.
    text = f"# doc\n{field} p_version\nuint8 a\n@sealed\n"
    with pytest.raises(DsdlError) as e:
        _types(tmp_path / "bad", {f"P.1.{minor}.dsdl": text})
    assert str(e.value) == (
        f"{tmp_path / 'bad' / 'acme' / f'P.1.{minor}.dsdl'}:2: acme.P.1.{minor}: p_version is "
        f"{field}, which cannot hold the type's minor version {minor} (expected 0 to {top}: a "
        "wider p_version, or a lower minor version)"
    )
    # The largest it holds loads, and is written as the value's first field (its bits first).
    schema = _types(tmp_path / "ok", {f"P.1.{top}.dsdl": text})
    bits = int(field.removeprefix("u").removeprefix("int"))
    assert schema.get("acme.P").encode({"a": 1})[:1] == bytes([(top << (8 - bits)) & 0xFF])
