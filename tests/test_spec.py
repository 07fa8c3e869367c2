"""Ranges mean something: a field's ``@min``/``@max`` and finite floats are enforced by the store
itself, so every way in refuses the same values with the same words: the Python API, the CLI
(``param set``, ``set-default``, an airframe file), ``.params`` and JSON files, MAVLink
``PARAM_SET`` (pymavlink), DroneCAN GetSet (pydronecan) and the page's API.

The ranges asserted here are read from the DSDL by hand: ``px/Ina238.1.1.dsdl`` has
``float16 shunt`` with ``@min 0.00001`` and ``@max 0.1`` (PX4's INA238_SHUNT, in
``src/drivers/power_monitor/ina238/ina238_params.yaml``, is 1e-9..0.1 Ohm; a float16 holds
nothing useful below 0.00001) and ``uint10 current`` with ``@min 1`` and ``@max 327``.
"""

from __future__ import annotations

import json
import math
import os
import re
import struct
import subprocess
import sys
import urllib.request
from pathlib import Path
from typing import Any

import px4params
import pytest
from gui_server import GUI_LINE
from px4params.dsdl.schema import Schema, load_schema
from px4params.errors import Px4ParamsError, StoreError, ValueRangeError
from px4params.store.classic import BUNDLED_CLASSIC, ClassicParam
from px4params.store.file import encode_file

CLI = [sys.executable, "-m", "px4params"]
SHUNT_RANGE = "is outside 0.00001..0.1 (@min/@max)"
NOT_FINITE = "is not a finite number (float16: NaN and infinities are refused)"

#: What INA238#1.shunt must refuse, with the refusal's text.
REFUSED_SHUNTS = [
    (math.nan, f"INA238#1.shunt: nan {NOT_FINITE}"),
    (math.inf, f"INA238#1.shunt: inf {NOT_FINITE}"),
    (-math.inf, f"INA238#1.shunt: -inf {NOT_FINITE}"),
    (-1.0, f"INA238#1.shunt: -1 {SHUNT_RANGE}"),
    (0.0, f"INA238#1.shunt: 0 {SHUNT_RANGE}"),
]


@pytest.fixture
def store() -> px4params.Store:
    store = px4params.Store(classic=[ClassicParam("BAT1_CAPACITY", "Float", -1.0)])
    store.add("INA238#1")
    return store


def _env(tmp: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp / "cache"))
    return env


def _cli(tmp: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*CLI, *args], capture_output=True, text=True, env=_env(tmp), cwd=tmp, timeout=120
    )


# -- the store: one check under every entry point ----------------------------------------------


@pytest.mark.parametrize(("value", "message"), REFUSED_SHUNTS)
@pytest.mark.parametrize("target", ["INA238#1.shunt", "INA238#1[6]"])
@pytest.mark.parametrize("default", [False, True])
def test_a_leaf_outside_its_range_or_not_finite_is_refused(
    store: px4params.Store, target: str, value: float, message: str, default: bool
) -> None:
    before = encode_file(store)
    write = store.set_default if default else store.set
    with pytest.raises(ValueRangeError) as e:
        write(target, value)
    assert str(e.value) == message
    assert encode_file(store) == before


@pytest.mark.parametrize(("value", "message"), REFUSED_SHUNTS)
def test_a_whole_value_and_its_bytes_are_checked_too(
    store: px4params.Store, value: float, message: str
) -> None:
    whole = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": value}
    before = encode_file(store)
    with pytest.raises(ValueRangeError, match=f"^{re.escape(message)}$"):
        store.set("INA238#1", whole)
    data = store.data_type("INA238").encode(whole, tao=False)  # the codec itself takes it
    with pytest.raises(ValueRangeError, match=f"^{re.escape(message)}$"):
        store.set_encoded("INA238#1", data)
    assert encode_file(store) == before


def test_the_range_ends_are_inside_and_integers_are_checked(store: px4params.Store) -> None:
    # @min 0.00001 and @max 0.1 given exactly are taken, although float16 stores 0.1 as
    # 0.0999755859375 and 0.00001 as 1.00135...e-05.
    store.set("INA238#1.shunt", 0.00001)
    store.set("INA238#1.shunt", 0.1)
    assert store.get("INA238#1.shunt") == 0.0999755859375
    store.set("INA238#1.current", 1)
    store.set("INA238#1.current", 327)
    for number in (0, 328, 1023):  # uint10 holds 1023, @max says 327
        with pytest.raises(ValueRangeError) as e:
            store.set("INA238#1.current", number)
        assert str(e.value) == f"INA238#1.current: {number} is outside 1..327 (@min/@max)"
        assert e.value.bounds_only
    assert store.get("INA238#1.current") == 327


def test_force_lets_a_range_pass_but_never_a_nan(store: px4params.Store) -> None:
    store.set("INA238#1.shunt", 0.0, force=True)
    assert store.get("INA238#1.shunt") == 0.0
    with pytest.raises(ValueRangeError, match=f"^INA238#1.shunt: nan {re.escape(NOT_FINITE)}$"):
        store.set("INA238#1.shunt", math.nan, force=True)
    # A value stored with force stays: writing another leaf, or selecting another bus, checks
    # only what that write changes.
    store.set("INA238#1.current", 100)
    store.set("INA238#1.bus._tag", 1)
    assert store.get("INA238#1.shunt") == 0.0 and store.get("INA238#1.current") == 100


def test_a_classic_float_refuses_nan(store: px4params.Store) -> None:
    for value in (math.nan, math.inf):
        with pytest.raises(ValueRangeError) as e:
            store.set("BAT1_CAPACITY", value)
        assert str(e.value) == (
            f"BAT1_CAPACITY: {value} is not a finite number (Float: NaN and infinities are refused)"
        )
    assert store.get("BAT1_CAPACITY") == -1.0


def test_the_refusal_is_a_store_error() -> None:
    # Servers and the CLI catch Px4ParamsError; "the store is left as it was" is StoreError's.
    assert issubclass(ValueRangeError, StoreError) and issubclass(ValueRangeError, Px4ParamsError)
    assert px4params.ValueRangeError is ValueRangeError


# -- the CLI ---------------------------------------------------------------------------------


@pytest.fixture
def store_file(tmp_path: Path) -> Path:
    path = tmp_path / "vehicle.store"
    result = _cli(tmp_path, "param", "--store", str(path), "add", "INA238#1")
    assert result.returncode == 0, result.stderr
    return path


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("nan", f"nan {NOT_FINITE}"),
        ("inf", f"inf {NOT_FINITE}"),
        ("-inf", f"-inf {NOT_FINITE}"),
        ("-1", f"-1 {SHUNT_RANGE}"),
        ("0", f"0 {SHUNT_RANGE}"),
    ],
)
@pytest.mark.parametrize("verb", ["set", "set-default"])
def test_param_set_refuses_and_changes_nothing(
    tmp_path: Path, store_file: Path, verb: str, text: str, message: str
) -> None:
    before = store_file.read_bytes()
    args = ("param", "--store", str(store_file), verb, "--", "INA238#1.shunt", text)
    result = _cli(tmp_path, *args)
    assert (result.returncode, result.stdout) == (1, "")
    assert result.stderr == f"px4params: error: INA238#1.shunt: {message}\n"
    assert store_file.read_bytes() == before


def test_force_says_what_it_overrides(tmp_path: Path, store_file: Path) -> None:
    args = ("param", "--store", str(store_file))
    result = _cli(tmp_path, *args, "set", "--force", "INA238#1[6]", "0.5")
    assert result.returncode == 0
    assert result.stderr == (
        f"px4params: warning: --force: INA238#1.shunt: 0.5 {SHUNT_RANGE}; stored anyway\n"
    )
    result = _cli(tmp_path, *args, "set-default", "INA238#1.current", "500", "--force")
    assert result.returncode == 0
    assert result.stderr == (
        "px4params: warning: --force: INA238#1.current: 500 is outside 1..327 (@min/@max); "
        "stored anyway\n"
    )
    stored = px4params.Store.load(store_file)
    assert stored.get("INA238#1.shunt") == 0.5
    assert stored.get("INA238#1.current", default=True) == 500
    before = store_file.read_bytes()
    result = _cli(tmp_path, *args, "set", "--force", "INA238#1.shunt", "nan")
    assert (result.returncode, result.stderr) == (
        1,
        f"px4params: error: INA238#1.shunt: nan {NOT_FINITE}\n",
    )
    assert store_file.read_bytes() == before


def test_an_airframe_line_outside_the_range_fails_and_takes_no_force(tmp_path: Path) -> None:
    airframe = tmp_path / "vehicle.airframe"
    store = tmp_path / "vehicle.store"
    airframe.write_text("param add INA238#0\nparam set-default INA238#0[6] 0\n")
    result = _cli(tmp_path, "run", str(airframe), "--store", str(store))
    assert result.returncode != 0
    assert f"{airframe}:2: INA238#0.shunt: 0 {SHUNT_RANGE}" in result.stderr
    assert not store.exists()  # nothing saved
    airframe.write_text("param add INA238#0\nparam set-default --force INA238#0[6] 0\n")
    result = _cli(tmp_path, "run", str(airframe), "--store", str(store))
    assert result.returncode != 0
    assert f"{airframe}:2: " in result.stderr and "--force" in result.stderr
    assert not store.exists()


# -- files -----------------------------------------------------------------------------------


def test_a_params_file_with_a_shunt_of_zero_is_refused(tmp_path: Path, store_file: Path) -> None:
    # QGC's format: vehicle, component, name, value, type (9: float); INA238_1Q is shunt.
    params = tmp_path / "vehicle.params"
    params.write_text("# Onboard parameters\n1\t1\tINA238_1Q\t0.000000000000000000\t9\n")
    before = store_file.read_bytes()
    for verb in ("import", "load"):
        result = _cli(tmp_path, "param", "--store", str(store_file), verb, str(params))
        assert result.returncode == 1
        assert result.stderr == (
            f"px4params: error: {params}:2: INA238_1Q: INA238#1.shunt: 0 {SHUNT_RANGE} "
            f"('param {verb} --force' takes it)\n"
        )
        assert store_file.read_bytes() == before


def test_a_json_export_with_a_nan_shunt_is_refused(tmp_path: Path, store_file: Path) -> None:
    export = tmp_path / "vehicle.json"
    result = _cli(tmp_path, "param", "--store", str(store_file), "export", str(export))
    assert result.returncode == 0, result.stderr
    document = json.loads(export.read_text())
    document["instances"]["INA238#1"]["value"]["shunt"] = "nan"
    export.write_text(json.dumps(document))
    before = store_file.read_bytes()
    result = _cli(tmp_path, "param", "--store", str(store_file), "import", str(export))
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {export}: instances: INA238#1.shunt: nan {NOT_FINITE}\n"
    )
    assert store_file.read_bytes() == before


# -- MAVLink: PARAM_SET from pymavlink -------------------------------------------------------


@pytest.mark.parametrize(("value", "message"), REFUSED_SHUNTS)
def test_mavlink_param_set_is_refused_and_the_old_value_echoed(
    tmp_path: Path, value: float, message: str
) -> None:
    from px4params.links.mavlink import MavlinkParamServer
    from test_mavlink import REAL32, Client, value_of

    store = px4params.Store()
    store.add("INA238#1")
    before = store.get("INA238#1.shunt")
    server = MavlinkParamServer(store, "127.0.0.1", 0, save_path=tmp_path / "vehicle.store")
    server.start()
    client = Client(server.address[1])
    try:
        client.set("INA238_1Q", value, REAL32)
        got: list[Any] = []
        for _ in range(40):  # until the reason's last chunk is in (at most 10 s)
            got += client.collect(0.25)
            if Client.text(got) and Client.text(got)[-1].endswith(")"):
                break
        # As PX4 answers a refused PARAM_SET: the value it keeps, and why in a STATUSTEXT.
        assert [value_of(m) for m in got if m.get_type() == "PARAM_VALUE"] == [before]
        assert Client.text(got) == [f"INA238_1Q: {message}"]
    finally:
        client.close()
        server.stop()
    assert store.get("INA238#1.shunt") == before
    assert server.stats["refused"] == 1 and server.stats["accepted"] == 0


# -- DroneCAN: GetSet ------------------------------------------------------------------------


@pytest.mark.parametrize(("value", "message"), REFUSED_SHUNTS)
def test_dronecan_getset_is_refused(value: float, message: str) -> None:
    from px4params.links.dronecan_params import DronecanParams

    store = px4params.Store(classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    params = DronecanParams(store)
    before = {n: store.encoded(n) for n in store.names()}
    with pytest.raises(Px4ParamsError) as e:
        params.set("INA238_1_SHUNT", {"real_value": value})
    assert str(e.value) == f"INA238_1_SHUNT: {message}"
    assert {n: store.encoded(n) for n in store.names()} == before


def test_pydronecan_getset_keeps_the_shunt(tmp_path: Path) -> None:
    from dronecan_bus import served
    from test_dronecan import Peer, _field

    store = tmp_path / "vehicle.store"
    result = _cli(tmp_path, "param", "--store", str(store), "add", "INA238#1")
    assert result.returncode == 0, result.stderr
    with served(store) as path:
        peer = Peer(path)
        try:
            for value in (0.0, -1.0, math.nan, math.inf):
                response = peer.getset(name=b"INA238_1_SHUNT", real_value=value)
                kind, kept = _field(response.value)  # the answer is the value it kept
                assert kind == "real_value" and kept == pytest.approx(0.0003, rel=1e-3)
        finally:
            peer.close()
    output = served.output  # type: ignore[attr-defined]
    assert f"refused: INA238_1_SHUNT: INA238#1.shunt: 0 {SHUNT_RANGE}" in output
    assert f"refused: INA238_1_SHUNT: INA238#1.shunt: nan {NOT_FINITE}" in output
    assert px4params.Store.load(store).get("INA238#1.shunt") == pytest.approx(0.0003, rel=1e-3)


# -- the page's API --------------------------------------------------------------------------


def test_the_page_api_refuses_a_shunt_of_zero(tmp_path: Path, store_file: Path) -> None:
    proc = subprocess.Popen(
        [*CLI, "gui", "--store", str(store_file), "--http", "127.0.0.1:0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(tmp_path),
        cwd=tmp_path,
    )
    try:
        assert proc.stdout is not None
        match = re.search(GUI_LINE, proc.stdout.readline())
        assert match, proc.stderr.read() if proc.stderr else ""
        before = store_file.read_bytes()
        changes = [{"name": "INA238_1Q", "value": v} for v in (0, -1, "nan", "inf")]
        request = urllib.request.Request(
            match[1] + "api/write",
            data=json.dumps({"changes": changes}).encode(),
            headers={"content-type": "application/json", "authorization": f"token {match[3]}"},
            method="POST",
        )
        with urllib.request.urlopen(request, timeout=20) as response:
            results: list[dict[str, Any]] = json.loads(response.read())["results"]
    finally:
        proc.terminate()
        proc.wait(timeout=10)
    reasons = [(r["ok"], r["reason"]) for r in results]
    assert reasons == [
        (False, f"INA238_1Q: INA238#1.shunt: 0 {SHUNT_RANGE}"),
        (False, f"INA238_1Q: INA238#1.shunt: -1 {SHUNT_RANGE}"),
        (False, f"INA238_1Q: INA238#1.shunt: nan {NOT_FINITE}"),
        (False, f"INA238_1Q: INA238#1.shunt: inf {NOT_FINITE}"),
    ]
    assert store_file.read_bytes() == before


def test_a_store_reads_its_defaults_without_the_fields_other_tags(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Building a store's defaults reads each field's ``@default`` alone: units, ranges and
    value names are read for what is shown or checked (``param show`` reads none)."""
    from px4params.dsdl import model

    read: list[str] = []
    original = model._field_doc

    def field_doc(key: str, file: str | None, field: Any) -> Any:
        read.append(f"{key}.{field.get('name')}")
        return original(key, file, field)

    monkeypatch.setattr(model, "_field_doc", field_doc)
    schema = Schema(load_schema(use_env=False).model)  # its types not read yet
    store = px4params.Store(schema, classic=[])
    assert read == []
    # The defaults are the declared ones (dsdl/px/Ina238.1.1.dsdl: @default 327, 0.0003).
    store.add("INA238#0")
    assert store.get("INA238#0.current") == 327
    assert store.get("INA238#0.shunt") == pytest.approx(0.0003, rel=1e-3)
    store.set("INA238#0.current", 100)  # a write checks the range: the doc is read then
    assert "px.Ina238.1.1.current" in read


# -- @value lists ------------------------------------------------------------------------------

#: ``px.Serial.1.0``'s ``port`` (dsdl/px/Serial.1.0.dsdl), its @value lines as written there.
SERIAL_PORTS = (
    "0 (Disabled), 6 (UART 6), 101 (TELEM 1), 102 (TELEM 2), 103 (TELEM 3), "
    "104 (TELEM/SERIAL 4), 201 (GPS 1), 202 (GPS 2), 203 (GPS 3), 300 (Radio Controller), "
    "301 (Wifi Port), 401 (Pixhawk Payload Bus)"
)
NOT_A_PORT = f"INA238#1.bus.serial.port: 105 is not one of its values (@value): {SERIAL_PORTS}"


@pytest.fixture
def on_serial(store: px4params.Store) -> px4params.Store:
    store.set_default("INA238#1.bus._tag", 2)  # 0 i2c, 1 spi, 2 serial (dsdl/px/Bus.1.0.dsdl)
    store.set("INA238#1.bus._tag", 2)
    assert store.leaf("INA238#1[3]").path == "bus.serial.port"
    return store


@pytest.mark.parametrize("target", ["INA238#1.bus.serial.port", "INA238#1[3]"])
@pytest.mark.parametrize("default", [False, True])
def test_a_value_its_field_does_not_list_is_refused(
    on_serial: px4params.Store, target: str, default: bool
) -> None:
    write = on_serial.set_default if default else on_serial.set
    before = on_serial.encoded("INA238#1", default=default)
    with pytest.raises(ValueRangeError) as e:
        write(target, 105)
    assert str(e.value) == NOT_A_PORT
    assert e.value.bounds_only  # what --force may override
    assert on_serial.encoded("INA238#1", default=default) == before
    write(target, 104)  # TELEM/SERIAL 4: listed
    assert on_serial.get("INA238#1.bus.serial.port", default=default) == 104


def test_every_port_px4_numbers_is_listed(on_serial: px4params.Store) -> None:
    # PX4's serial_ports table (Tools/serial/generate_config.py) numbers its ports 6, 101-104,
    # 201-203, 300, 301 and 401 (Pixhawk Payload Bus); 0 is "disabled". Each must be storable
    # without --force, or a real vehicle's port would be refused.
    for port in (0, 6, 101, 102, 103, 104, 201, 202, 203, 300, 301, 401):
        on_serial.set("INA238#1.bus.serial.port", port)
        assert on_serial.get("INA238#1.bus.serial.port") == port


def test_a_whole_value_and_a_flat_name_are_held_to_the_list(on_serial: px4params.Store) -> None:
    from px4params.store import flat

    value = {"bus": {"serial": {"port": 105, "baudrate": 0}}, "current": 100, "shunt": 0.001}
    with pytest.raises(ValueRangeError, match=f"^{re.escape(NOT_A_PORT)}$"):
        on_serial.set("INA238#1", value)
    port = next(p for p in flat.flat_map(on_serial).table() if p.path == "bus.serial.port")
    with pytest.raises(ValueRangeError, match=f"^{re.escape(NOT_A_PORT)}$"):
        flat.write_flat(on_serial, port.name, 105)
    assert on_serial.get("INA238#1.bus.serial.port") == 0
    on_serial.set("INA238#1.bus.serial.port", 105, force=True)  # --force, as for @min/@max
    assert on_serial.get("INA238#1.bus.serial.port") == 105


def test_a_long_list_is_named_by_its_numbers_in_runs(tmp_path: Path) -> None:
    root = tmp_path / "acme"
    root.mkdir()
    values = "".join(f"# @value {n} Mode {n}\n" for n in (*range(13), 20, 22, 23))
    (root / "Gadget.1.0.dsdl").write_text(
        f"# A gadget\n# @max_instances 1\n\nuint4 p_version\nuint5 mode\n# Mode\n{values}"
        "\n@sealed\n"
    )
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema, classic=[])
    store.add("GADGET#0")
    with pytest.raises(ValueRangeError) as e:
        store.set("GADGET#0.mode", 21)
    assert str(e.value) == "GADGET#0.mode: 21 is not one of its values (@value): 0..12, 20, 22..23"
    store.set("GADGET#0.mode", 22)


def test_every_bundled_default_is_in_its_list() -> None:
    """A new instance, and every variant a tag can select, starts from values its lists take
    (else a write that switches to it would be refused for a value nobody chose)."""
    from px4params.store.spec import check_leaves, leaf_ranges

    store = px4params.Store(load_schema(use_env=False), classic=[])
    switched = 0
    for spec in store.specs:
        key = spec.instance_key(0)
        if not spec.shared:
            store.add(key)
        check_leaves(str(key), store.leaves(key), leaf_ranges(spec.data_type))
        for leaf in store.leaves(key):
            if leaf.path.endswith("._tag"):
                union = spec.data_type.field_at(leaf.path[: -len("._tag")])
                assert union is not None
                variants = store.schema.type_def(union.type["name"]).data_fields
                for number in range(len(variants)):
                    store.set(key.at(leaf.path), number)  # the variant's leaves are checked
                    switched += 1
    assert switched >= 6 * 30  # (every bus of every device type)


def test_param_set_outside_the_list_is_one_line_and_force_stores_it(
    tmp_path: Path, store_file: Path
) -> None:
    args = ("param", "--store", str(store_file))
    assert _cli(tmp_path, *args, "set", "INA238#1.bus._tag", "2").returncode == 0
    before = store_file.read_bytes()
    result = _cli(tmp_path, *args, "set", "INA238#1.bus.serial.port", "105")
    assert (result.returncode, result.stdout) == (1, "")
    assert result.stderr == f"px4params: error: {NOT_A_PORT}\n"
    assert store_file.read_bytes() == before
    result = _cli(tmp_path, *args, "set", "--force", "INA238#1.bus.serial.port", "105")
    assert result.returncode == 0
    assert result.stderr == f"px4params: warning: --force: {NOT_A_PORT}; stored anyway\n"
    assert px4params.Store.load(store_file).get("INA238#1.bus.serial.port") == 105


# -- issue 40: the parameter set's rules, each from the docs (docs/codec.md's tags, the module
# doc of px4params.store.spec), for mutants of store/spec.py that test_spec.py let through ---


def _acme(tmp_path: Path, files: dict[str, str]) -> Schema:
    """The bundled types and a namespace ``acme`` of ``{file name: DSDL text}``."""
    root = tmp_path / "acme"
    root.mkdir(parents=True)
    for name, text in files.items():
        (root / name).write_text(text)
    return px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")


def _dsdl(tags: str, fields: str = "uint8 level\n") -> str:
    """A sealed type whose doc carries ``tags``."""
    return f"# A test type\n{tags}\n\nuint4 p_version\n{fields}@sealed\n"


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("type_name", "name"),
    [
        # docs/codec.md and the module doc: px.Ina238 is INA238, px.Ina238Shared INA238_SHARED
        ("px.Ina238", "INA238"),
        ("px.Ina238Shared", "INA238_SHARED"),
        # an underscore where a capital follows a small letter or a digit, at each end of
        # those ranges: a..z, 0..9 before, A..Z after
        ("acme.GammaAlpha", "GAMMA_ALPHA"),
        ("acme.JazzZone", "JAZZ_ZONE"),
        ("acme.Mk0Able", "MK0_ABLE"),
        ("acme.Mk9Zulu", "MK9_ZULU"),
        ("acme.deep.PitotTube", "PITOT_TUBE"),  # the short name: after the last dot
        ("acme.Pitot_Tube", "PITOT_TUBE"),  # an underscore written is kept, none added
        ("Pitot", "PITOT"),
        # a run of capitals stays one word (no underscore between two capitals), as in the
        # names DroneCAN's C generator makes of these types (dronecan/dronecan_dsdlc:
        # UAVCAN_EQUIPMENT_ESC_RPMCOMMAND_ID, UAVCAN_EQUIPMENT_GNSS_ECEFPOSITIONVELOCITY_...)
        ("uavcan.equipment.esc.RPMCommand", "RPMCOMMAND"),
        ("uavcan.equipment.gnss.ECEFPositionVelocity", "ECEFPOSITION_VELOCITY"),
    ],
)
def test_a_parameter_is_named_after_its_type_in_upper_snake_case(type_name: str, name: str) -> None:
    from px4params.store.spec import default_param_name

    assert default_param_name(type_name) == name


@pytest.mark.issue40
def test_an_instanced_and_a_shared_parameter_and_their_slots(tmp_path: Path) -> None:
    from px4params.store.spec import parameter_specs

    schema = _acme(
        tmp_path,
        {
            "PitotTube.1.0.dsdl": _dsdl("# @max_instances 3"),
            "TubeShared.1.0.dsdl": _dsdl("# @param TUBE_COMMON"),
            "Plain.1.0.dsdl": _dsdl("# not a parameter: no @max_instances, no @param"),
        },
    )
    specs = {s.name: s for s in parameter_specs(schema) if s.data_type.key.startswith("acme.")}
    assert sorted(specs) == ["PITOT_TUBE", "TUBE_COMMON"]
    tube, common = specs["PITOT_TUBE"], specs["TUBE_COMMON"]
    # @max_instances 3: PITOT_TUBE#0..#2, three slots; @param alone: one value, no #N
    assert (tube.shared, tube.max_instances, tube.slots) == (False, 3, 3)
    assert (tube.instance_name(2), tube.instance_key(2).instance) == ("PITOT_TUBE#2", 2)
    assert (common.shared, common.max_instances, common.slots) == (True, None, 1)
    assert (common.instance_name(0), common.instance_key(0).instance) == ("TUBE_COMMON", None)


@pytest.mark.issue40
def test_the_parameter_set_is_sorted_by_name_and_takes_each_types_newest_version(
    tmp_path: Path,
) -> None:
    from px4params.store.spec import parameter_specs

    schema = _acme(
        tmp_path,
        {
            "Zeta.1.0.dsdl": _dsdl("# @max_instances 1"),
            "Zeta.1.2.dsdl": _dsdl("# @max_instances 2", "uint2 level\nuint6 more\n"),
            "Zeta.1.1.dsdl": _dsdl("# @max_instances 1", "uint8 level\nuint4 more\n"),
            "Alpha.2.0.dsdl": _dsdl("# @max_instances 1"),
        },
    )
    specs = parameter_specs(schema)
    names = [s.name for s in specs]
    assert names == sorted(names) and {"ALPHA", "ZETA", "INA238"} <= set(names)
    by_name = {s.name: s for s in specs}
    assert by_name["ZETA"].data_type.key == "acme.Zeta.1.2"
    assert by_name["ZETA"].max_instances == 2  # the newest version's doc
    assert (
        by_name["INA238"].data_type.key == "px.Ina238.1.1"
    )  # px.Ina238.1.0 is kept for translating


@pytest.mark.issue40
def test_a_name_of_16_characters_is_a_parameter_and_of_17_is_refused(tmp_path: Path) -> None:
    from px4params.errors import ParameterSetError
    from px4params.store.spec import parameter_specs

    # PX4's names have at most 16 characters (MAVLink's PARAM_VALUE.param_id is char[16]).
    ok = _acme(tmp_path / "ok", {"Abcdefghijklmnop.1.0.dsdl": _dsdl("# @max_instances 1")})
    assert "ABCDEFGHIJKLMNOP" in {s.name for s in parameter_specs(ok)}
    file = tmp_path / "long" / "acme" / "Abcdefghijklmnopq.1.0.dsdl"
    long = _acme(tmp_path / "long", {file.name: _dsdl("# @max_instances 1")})
    with pytest.raises(ParameterSetError) as e:
        parameter_specs(long)
    assert str(e.value) == (
        f"{file}: parameter name 'ABCDEFGHIJKLMNOPQ' of acme.Abcdefghijklmnopq is not an "
        "upper-case name of at most 16 characters (set one with @param NAME)"
    )


@pytest.mark.issue40
def test_two_types_under_one_parameter_name_are_refused(tmp_path: Path) -> None:
    from px4params.errors import ParameterSetError
    from px4params.store.spec import parameter_specs

    schema = _acme(
        tmp_path,
        {
            "PitotTube.1.0.dsdl": _dsdl("# @max_instances 2"),
            "Other.1.0.dsdl": _dsdl("# @param PITOT_TUBE"),
        },
    )
    with pytest.raises(ParameterSetError) as e:
        parameter_specs(schema)
    assert str(e.value) == (
        f"{tmp_path / 'acme' / 'PitotTube.1.0.dsdl'}: parameter name PITOT_TUBE of "
        "acme.PitotTube is already used by acme.Other (set another with @param NAME)"
    )


#: Types whose defaults are worked out by hand below from their DSDL (docs/codec.md: ``@default
#: V``, for a nested field ``@default i2c.address 0x45``, repeatable; fields without one are
#: zero; a union takes its first variant unless a path default names another).
DEFAULTS_DSDL = {
    "Pair.1.0.dsdl": "# A pair\n\nuint4 p_version\nuint8 a\n# A\n# @default 5\nbool b\n@sealed\n",
    "Probe.1.0.dsdl": (
        "# A probe\n# @max_instances 2\n\nuint4 p_version\npx.Bus.1.0 bus\n# Bus\n"
        "# @default spi.chip_select 2\n# @default spi.bus_id 1\nbool armed\nfloat16 gain\n"
        "int8 offset\n# Offset\n# @default -3\nPair.1.0[2] pairs\nuint8[<=4] log\n"
        "Pair.1.0[<=2] more\n@sealed\n"
    ),
    # px.Ina238.1.1 nested, its own path default (i2c.address 0x45) completed by the outer
    # field's (bus.i2c.bus_id 2); the probe's spi defaults completed by bus.spi.mode 1
    "Rig.1.0.dsdl": (
        "# A rig\n# @max_instances 1\n\nuint4 p_version\npx.Ina238.1.1 monitor\n# Monitor\n"
        "# @default bus.i2c.bus_id 2\n# @default current 100\nProbe.1.0 probe\n# Probe\n"
        "# @default bus.spi.mode 1\n@sealed\n"
    ),
}
#: px.Spi.1.0: bus_id, chip_select, max_frequency without a default, mode @default 3.
PROBE_SPI = {"bus_id": 1, "chip_select": 2, "max_frequency": 0, "mode": 3}
PAIR = {"a": 5, "b": False}
PROBE_DEFAULT = {
    "bus": {"spi": PROBE_SPI},
    "armed": False,
    "gain": 0.0,
    "offset": -3,
    "pairs": [PAIR, PAIR],
    "log": [],
    "more": [],
}


@pytest.fixture(scope="module")
def defaults_schema(tmp_path_factory: pytest.TempPathFactory) -> Schema:
    return _acme(tmp_path_factory.mktemp("defaults"), DEFAULTS_DSDL)


def _kinds(value: Any) -> Any:
    """``value`` with each number's type beside it (False == 0 == 0.0 in Python)."""
    if isinstance(value, dict):
        return {k: _kinds(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_kinds(v) for v in value]
    return (type(value).__name__, value)


@pytest.mark.issue40
def test_a_new_value_is_built_from_the_declared_defaults(defaults_schema: Schema) -> None:
    from px4params.store.spec import metadata_default

    # dsdl/px/Ina238.1.1.dsdl: bus @default i2c.address 0x45 (I2C first: no other variant
    # named), current @default 327, shunt @default 0.0003; p_version is never a value's field
    assert metadata_default(defaults_schema, "px.Ina238.1.1") == {
        "bus": {"i2c": {"bus_id": 0, "address": 0x45}},
        "current": 327,
        "shunt": 0.0003,
    }
    # a union with nothing named takes its first variant (dsdl/px/Bus.1.0.dsdl: i2c first)
    assert metadata_default(defaults_schema, "px.Bus.1.0") == {"i2c": {"bus_id": 0, "address": 0}}
    # a path default naming spi selects it; a bool without a default is False, a float 0.0
    assert _kinds(metadata_default(defaults_schema, "acme.Probe.1.0")) == _kinds(PROBE_DEFAULT)
    rig = metadata_default(defaults_schema, "acme.Rig.1.0")
    assert rig == {
        "monitor": {
            "bus": {"i2c": {"bus_id": 2, "address": 0x45}},
            "current": 100,
            "shunt": 0.0003,
        },
        "probe": {**PROBE_DEFAULT, "bus": {"spi": {**PROBE_SPI, "mode": 1}}},
    }
    store = px4params.Store(defaults_schema, classic=[])
    store.add("RIG#0")  # and a new instance starts from it, as stored
    assert store.get("RIG#0.monitor.bus.i2c.address") == 0x45
    assert store.get("RIG#0.probe.bus.spi.mode") == 1


@pytest.mark.issue40
def test_a_value_given_in_part_is_completed_from_the_defaults(defaults_schema: Schema) -> None:
    from px4params.store.spec import with_defaults

    probe = "acme.Probe.1.0"
    # another variant than the default's: completed from that variant's own defaults (px.I2c
    # declares none); what is given is kept; array elements completed one by one
    given = {
        "bus": {"i2c": {"address": 0x41}},
        "pairs": [{"b": True}, {}],
        "log": [3],
        "more": [{"b": True}],
    }
    kept = json.loads(json.dumps(given))
    assert _kinds(with_defaults(defaults_schema, probe, given)) == _kinds(
        {
            **PROBE_DEFAULT,
            "bus": {"i2c": {"bus_id": 0, "address": 0x41}},
            "pairs": [{"a": 5, "b": True}, PAIR],
            "log": [3],
            "more": [{"a": 5, "b": True}],
        }
    )
    assert given == kept  # (not changed in place)
    # the default's variant: completed from the path defaults that chose it
    spi = with_defaults(defaults_schema, probe, {"bus": {"spi": {"mode": 0}}})
    assert spi["bus"] == {"spi": {**PROBE_SPI, "mode": 0}}
    rig = with_defaults(defaults_schema, "acme.Rig.1.0", {"probe": {"bus": {"spi": {}}}})
    assert rig["probe"]["bus"] == {"spi": {**PROBE_SPI, "mode": 1}}
    assert rig["monitor"]["bus"] == {"i2c": {"bus_id": 2, "address": 0x45}}
    # what is wrong stays for the codec to name: not a mapping, two variants, no such variant
    assert with_defaults(defaults_schema, probe, 5) == 5
    for bus in ({"i2c": {}, "spi": {}}, {"can": {}}, {}):
        assert with_defaults(defaults_schema, probe, {"bus": bus})["bus"] == bus
    assert with_defaults(defaults_schema, probe, {"offset": "x"})["offset"] == "x"
    assert with_defaults(defaults_schema, probe, {"pairs": "x"})["pairs"] == "x"


@pytest.mark.issue40
def test_a_service_is_no_parameter_even_with_max_instances(tmp_path: Path) -> None:
    from px4params.store.spec import parameter_specs

    # A DSDL service is a request and a response (a call), not a value a vehicle keeps.
    ask = "# Ask\n# @max_instances 1\n\nuint4 p_version\nuint8 a\n@sealed\n---\nuint8 b\n@sealed\n"
    schema = _acme(tmp_path, {"Ask.1.0.dsdl": ask, "Keep.1.0.dsdl": _dsdl("# @max_instances 1")})
    assert [s.name for s in parameter_specs(schema) if s.data_type.key.startswith("acme.")] == [
        "KEEP"
    ]


#: A type whose ranges are worked out by hand below (docs/store.md#ranges: @min/@max beside the
#: field's own range, a float finite only, an array field's tags for each element).
GAUGE_DSDL = (
    "# A gauge\n# @max_instances 1\n\nuint4 p_version\n"
    "float16 gain\n# Gain\n# @default 0.5\n# @min 0.1\n# @max 1000\n"  # 0.1 rounds down in float16
    "float16 tiny\n# Tiny\n# @max 0.00001\n"  # 0.00001 rounds up in float16
    "int8 offset\n# Offset\n# @min -128\n# @max 100\n"  # -128: int8's own bottom
    "uint24 baud\n# Baud\n# @min 0\n# @max 16000000\n"  # 0: uint24's own bottom
    "uint5 select\n# Select\n# @min 0\n# @max 31\n"  # both: uint5's own range
    "uint5 part\n# Part\n# @max 30\n"  # one below uint5's top
    "int8 trim\n# Trim\n# @min -127\n# @max 127\n"  # one above int8's bottom; its top
    "int8 bias\n# Bias\n# @max 126\n"  # one below int8's top
    "uint8[3] taps\n# Taps\n# @max 9\n"
    "uint8[<=2] levels\n# Levels\n# @max 5\n"
    "float32 scale\n# Scale\n# @default 1\n# @min -1.5\n"
    "uint8 plain\n# Plain\n"
    "float16 ratio\n# Ratio\n# @default 0.5\n# @value 0.1 tenth\n# @value 0.5 half\n"
    "@sealed\n"
)


def _float16(value: float) -> float:
    """``value`` as a float16 keeps it (IEEE 754 binary16, round to nearest)."""
    return float(struct.unpack("<e", struct.pack("<e", value))[0])


@pytest.fixture(scope="module")
def gauge_schema(tmp_path_factory: pytest.TempPathFactory) -> Schema:
    return _acme(tmp_path_factory.mktemp("gauge"), {"Gauge.1.0.dsdl": GAUGE_DSDL})


@pytest.fixture
def gauge(gauge_schema: Schema) -> px4params.Store:
    store = px4params.Store(gauge_schema, classic=[])
    store.add("GAUGE#0")
    return store


@pytest.mark.issue40
def test_the_ranges_of_a_type_read_from_its_tags(gauge_schema: Schema) -> None:
    from px4params.store.spec import LeafRange, leaf_ranges

    assert _float16(0.1) < 0.1 and _float16(0.00001) > 0.00001
    ranges = leaf_ranges(gauge_schema["acme.Gauge"])
    assert ranges == {
        # a float's bounds widened to where they round at its width (0.1 is kept below 0.1)
        "gain": LeafRange(0.1, 1000, 16, _float16(0.1), 1000, "float16"),
        "tiny": LeafRange(None, 0.00001, 16, None, _float16(0.00001), "float16"),
        # a bound that repeats the type's own is none; an integer's bounds stay as written
        "offset": LeafRange(None, 100, 0, None, 100, "int8"),
        "baud": LeafRange(None, 16000000, 0, None, 16000000, "uint24"),
        "part": LeafRange(None, 30, 0, None, 30, "uint5"),
        "trim": LeafRange(-127, None, 0, -127, None, "int8"),
        "bias": LeafRange(None, 126, 0, None, 126, "int8"),
        "taps[]": LeafRange(None, 9, 0, None, 9, "uint8"),
        "levels[]": LeafRange(None, 5, 0, None, 5, "uint8"),
        "scale": LeafRange(-1.5, None, 32, -1.5, None, "float32"),
        # uint5 0..31 and a plain integer have nothing to check beyond their type
        "ratio": LeafRange(
            None,
            None,
            16,
            None,
            None,
            "float16",
            ((0.1, "tenth"), (0.5, "half")),
            frozenset({_float16(0.1), 0.5}),  # a listed float as the leaf keeps it
        ),
    }
    assert ranges["gain"].values == () and ranges["gain"].stored_values == frozenset()
    # worked out once per type (docstring of leaf_ranges): the same table each time
    assert leaf_ranges(gauge_schema["acme.Gauge"]) is ranges


@pytest.mark.issue40
def test_each_bound_is_held_where_the_store_keeps_the_value(gauge: px4params.Store) -> None:
    def refused(leaf: str, value: float) -> str:
        before = gauge.encoded("GAUGE#0")
        with pytest.raises(ValueRangeError) as e:
            gauge.set(f"GAUGE#0.{leaf}", value)
        assert gauge.encoded("GAUGE#0") == before
        return str(e.value)

    # a bound given exactly is taken, whichever way its float16 rounds
    gauge.set("GAUGE#0.gain", 0.1)
    assert gauge.get("GAUGE#0.gain") == _float16(0.1)
    gauge.set("GAUGE#0.tiny", 0.00001)
    assert gauge.get("GAUGE#0.tiny") == _float16(0.00001)
    assert refused("gain", 0.0999) == "GAUGE#0.gain: 0.0999 is outside 0.1..1000 (@min/@max)"
    assert refused("tiny", 0.00002) == "GAUGE#0.tiny: 0.00002 is above 0.00001 (@max)"
    # a bound that is the type's own is not named; the type's own range is the codec's
    gauge.set("GAUGE#0.offset", -128)
    assert refused("offset", 101) == "GAUGE#0.offset: 101 is above 100 (@max)"
    assert refused("offset", 127) == "GAUGE#0.offset: 127 is above 100 (@max)"
    gauge.set("GAUGE#0.baud", 0)
    assert refused("baud", 16000001) == "GAUGE#0.baud: 16000001 is above 16000000 (@max)"
    gauge.set("GAUGE#0.select", 31)
    assert refused("part", 31) == "GAUGE#0.part: 31 is above 30 (@max)"
    assert refused("trim", -128) == "GAUGE#0.trim: -128 is below -127 (@min)"
    gauge.set("GAUGE#0.trim", 127)
    assert refused("bias", 127) == "GAUGE#0.bias: 127 is above 126 (@max)"
    assert refused("taps[2]", 10) == "GAUGE#0.taps[2]: 10 is above 9 (@max)"
    gauge.set("GAUGE#0.taps[2]", 9)
    assert refused("scale", -1.6) == "GAUGE#0.scale: -1.6 is below -1.5 (@min)"
    value = gauge.get("GAUGE#0")
    with pytest.raises(ValueRangeError) as e:
        gauge.set("GAUGE#0", {**value, "levels": [5, 6]})  # each element of a variable array
    assert str(e.value) == "GAUGE#0.levels[1]: 6 is above 5 (@max)"
    gauge.set("GAUGE#0", {**value, "levels": [5, 0]})
    gauge.set("GAUGE#0.scale", -1.5)
    gauge.set("GAUGE#0.scale", -1.50000001)  # kept by a float32 as -1.5: inside
    assert gauge.get("GAUGE#0.scale") == -1.5
    gauge.set("GAUGE#0.ratio", 0.1)  # listed, although a float16 keeps 0.0999755859375
    assert refused("ratio", 0.2) == (
        "GAUGE#0.ratio: 0.2 is not one of its values (@value): 0.1 (tenth), 0.5 (half)"
    )
    assert refused("scale", -math.inf) == (
        "GAUGE#0.scale: -inf is not a finite number (float32: NaN and infinities are refused)"
    )
    assert (gauge.get("GAUGE#0.offset"), gauge.get("GAUGE#0.baud")) == (-128, 0)
    assert (gauge.get("GAUGE#0.taps[2]"), gauge.get("GAUGE#0.scale")) == (9, -1.5)


@pytest.mark.issue40
def test_a_value_the_type_cannot_hold_is_the_codecs_refusal_and_one_it_can_the_ranges(
    store: px4params.Store, gauge: px4params.Store
) -> None:
    from px4params.errors import EncodeError

    def refusal(s: px4params.Store, name: str, value: float) -> tuple[str, str]:
        with pytest.raises(Px4ParamsError) as e:
            s.set(name, value)
        return type(e.value).__name__, str(e.value)

    # uint10 holds 0..1023, float16 up to 65504 (IEEE 754 binary16), int8 -128..127. A field's
    # @min/@max refuse first, inside the type's range or beyond it (the message a pilot can act
    # on: 0.00001..0.1, not a float16's 65504); beyond the type, the refusal is no bounds alone
    # (--force cannot take it). A field without @min/@max: the codec says what the type holds.
    assert refusal(store, "INA238#1.current", 1023)[0] == "ValueRangeError"
    assert refusal(store, "INA238#1.current", 1024) == (
        "ValueRangeError",
        "INA238#1.current: 1024 is outside 1..327 (@min/@max)",
    )
    assert refusal(store, "INA238#1.shunt", 65504.0) == (
        "ValueRangeError",
        f"INA238#1.shunt: 65504 {SHUNT_RANGE}",
    )
    assert refusal(store, "INA238#1.shunt", 70000.0) == (
        "ValueRangeError",
        f"INA238#1.shunt: 70000 {SHUNT_RANGE}",
    )
    for name, value, forcible in (
        ("INA238#1.current", 327 + 1, True),
        ("INA238#1.current", 1024, False),
        ("INA238#1.current", -1, False),
        ("INA238#1.shunt", -65504.0, True),
        ("INA238#1.shunt", 70000.0, False),
    ):
        with pytest.raises(ValueRangeError) as e:
            store.set(name, value)
        assert e.value.bounds_only is forcible, (name, value)
    # a whole value's leaf beyond @min/@max only: --force takes it
    with pytest.raises(ValueRangeError) as e:
        store.set("INA238#1", {**store.get("INA238#1"), "current": 500})
    assert e.value.bounds_only is True
    # --force takes a value beyond @min/@max, never one beyond the type
    with pytest.raises(EncodeError, match=r"value 1024 is out of range \(expected 0 to 1023\)"):
        store.set("INA238#1.current", 1024, force=True)
    # int8 with @min -128 (its own bottom) and @max 100
    assert refusal(gauge, "GAUGE#0.offset", 128) == (
        "ValueRangeError",
        "GAUGE#0.offset: 128 is above 100 (@max)",
    )
    # (its @min only repeats the type's bottom: below it, the type's range is the refusal)
    assert refusal(gauge, "GAUGE#0.offset", -129) == (
        "EncodeError",
        "GAUGE#0: offset: value -129 is out of range (expected -128 to 127)",
    )
    assert issubclass(EncodeError, Px4ParamsError)


@pytest.mark.issue40
def test_a_refusal_names_the_number_given_not_the_one_the_leaf_would_keep(
    store: px4params.Store,
) -> None:
    # 1e-12 is kept as 0 by a float16: the refusal says what was written
    with pytest.raises(ValueRangeError) as e:
        store.set("INA238#1.shunt", 1e-12)
    assert str(e.value) == f"INA238#1.shunt: 1e-12 {SHUNT_RANGE}"


@pytest.mark.issue40
def test_the_public_checks_hold_the_bounds_unless_told_not_to(store: px4params.Store) -> None:
    from px4params.store.spec import check_leaves, check_stored, leaf_ranges

    data_type = store.data_type("INA238")
    ranges = leaf_ranges(data_type)
    whole = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0}
    leaves = data_type.leaves(data_type.encode(whole, tao=False), tao=False)
    with pytest.raises(ValueRangeError, match=f"^INA238#1.shunt: 0 {re.escape(SHUNT_RANGE)}$"):
        check_leaves("INA238#1", leaves, ranges)
    check_leaves("INA238#1", leaves, ranges, bounds=False)  # as --force: the range passes
    with pytest.raises(ValueRangeError, match=f"^X: 0 {re.escape(SHUNT_RANGE)}$"):
        check_stored("X", 0.0, ranges["shunt"])
    check_stored("X", 0.0, ranges["shunt"], bounds=False)


# -- issue 40 (mutstore4): the leaf checks' own functions, each against numbers worked out by hand


@pytest.mark.issue40
def test_within_says_exactly_what_check_stored_refuses() -> None:
    """``within`` is the store's quick yes: a value inside INA238's current (uint10, @min 1,
    @max 327) and shunt (float16, 0.00001..0.1) ranges, or in a listed port, and no other."""
    from px4params.store.spec import LeafRange, check_stored, within

    current = LeafRange.of(1, 327, 0, "uint10")
    shunt = LeafRange.of(0.00001, 0.1, 16, "float16")
    low_only = LeafRange.of(-1.5, None, 32, "float32")
    high_only = LeafRange.of(None, 30, 0, "uint5")
    ports = LeafRange.of(None, None, 0, "uint16", ((0, "Disabled"), (101, "TELEM 1")))
    cases = [
        (current, 1, True), (current, 327, True), (current, 0, False), (current, 328, False),
        (shunt, 0.05, True), (shunt, _float16(0.1), True), (shunt, 0.0, False),
        (shunt, 0.2, False), (shunt, math.nan, False), (shunt, math.inf, False),
        (low_only, -1.5, True), (low_only, 1e30, True), (low_only, -1.6, False),
        (high_only, 0, True), (high_only, 30, True), (high_only, 31, False),
        (ports, 101, True), (ports, 0, True), (ports, 102, False),
    ]  # fmt: skip
    for rng, value, inside in cases:
        assert within(value, rng) is inside, (rng.type, value)
        try:
            check_stored("X", value, rng)
            refused = False
        except ValueRangeError:
            refused = True
        assert refused is not inside, (rng.type, value)
    # bounds=False (--force): only what is no finite number is refused
    assert within(0.0, shunt, bounds=False) and within(328, current, bounds=False)
    assert within(102, ports, bounds=False)
    assert not within(math.nan, shunt, bounds=False)


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("type_name", "value", "holds"),
    [
        # uintN: 0..2^N-1; intN: -2^(N-1)..2^(N-1)-1 (DroneCAN's integer types)
        ("uint10", 0, True), ("uint10", 1023, True), ("uint10", 1024, False), ("uint10", -1, False),
        ("uint1", 1, True), ("uint1", 2, False),
        ("int8", -128, True), ("int8", 127, True), ("int8", 128, False), ("int8", -129, False),
        ("int32", -(2**31), True), ("int32", 2**31 - 1, True), ("int32", 2**31, False),
        # IEEE 754: binary16's largest finite number is 65504, binary32's 3.4028234663852886e38
        ("float16", 65504.0, True), ("float16", -65504.0, True), ("float16", 65536.0, False),
        ("float16", 65505.0, False),  # the codec refuses it: "expected -65504 to 65504"
        ("float16", -70000.0, False),
        ("float32", 3.4028234663852886e38, True), ("float32", -3.4028234663852886e38, True),
        ("float32", 3.5e38, False), ("float32", -1e39, False),
        ("float64", 1e300, True),
        # a NaN or an infinity is the range check's to refuse, not the codec's
        ("float16", math.inf, True), ("float16", math.nan, True),
        # a bool leaf holds what it is given (no number range)
        ("bool", 1, True),
    ],
)  # fmt: skip
def test_in_type_range_is_the_dsdl_types_own_range(
    type_name: str, value: float, holds: bool
) -> None:
    from px4params.store.spec import in_type_range

    assert in_type_range(value, type_name) is holds


@pytest.mark.issue40
def test_stored_number_is_the_number_the_leaf_keeps() -> None:
    """A float leaf keeps the given number rounded to its width (IEEE 754 round to nearest):
    0.1 is 0.0999755859375 in a float16 and 0.10000000149011612 in a float32; an integer leaf
    keeps an int as it is; anything else is left to the codec (None)."""
    from px4params.store.spec import LeafRange, stored_number

    half = LeafRange.of(None, None, 16, "float16")
    single = LeafRange.of(None, None, 32, "float32")
    double = LeafRange.of(None, None, 64, "float64")
    byte = LeafRange.of(None, None, 0, "uint8")
    assert stored_number(0.1, half) == 0.0999755859375
    assert stored_number(0.1, single) == 0.10000000149011612
    assert stored_number(0.1, double) == 0.1
    one = stored_number(1, half)
    assert one == 1.0 and type(one) is float
    assert stored_number(math.inf, half) == math.inf
    assert math.isnan(stored_number(math.nan, half))  # type: ignore[arg-type]
    assert stored_number(1e6, half) is None  # beyond float16: the codec's refusal
    assert stored_number(True, half) is None and stored_number("0.1", half) is None
    assert stored_number(7, byte) == 7
    assert stored_number(7.0, byte) is None and stored_number(True, byte) is None


@pytest.mark.issue40
def test_a_list_of_up_to_12_values_is_named_and_a_longer_one_numbered() -> None:
    # the module's rule (_NAMED_AT_MOST): a value list longer than 12 is named by its numbers
    # alone, in runs; PX4's serial ports, 12, are named (test_every_port_px4_numbers_is_listed)
    from px4params.store.spec import LeafRange, describe_not_listed

    def modes(count: int) -> LeafRange:
        return LeafRange.of(None, None, 0, "uint8", tuple((n, f"Mode {n}") for n in range(count)))

    named = ", ".join(f"{n} (Mode {n})" for n in range(12))
    assert describe_not_listed(20, modes(12)) == f"20 is not one of its values (@value): {named}"
    assert describe_not_listed(20, modes(13)) == "20 is not one of its values (@value): 0..12"


@pytest.mark.issue40
def test_a_float32_bound_given_exactly_is_taken_although_the_leaf_keeps_it_above(
    tmp_path: Path,
) -> None:
    # float32 keeps 0.1 as 0.10000000149011612 (IEEE 754 binary32, round to nearest), above
    # @max 0.1: a bound given exactly is never refused once stored (check_leaves' rule)
    assert struct.unpack("<f", struct.pack("<f", 0.1))[0] == 0.10000000149011612
    level = _dsdl("# @max_instances 1", "float32 gain\n# Gain\n# @max 0.1\n")
    schema = _acme(tmp_path, {"Level.1.0.dsdl": level})
    store = px4params.Store(schema, classic=[])
    store.add("LEVEL#0")
    store.set("LEVEL#0.gain", 0.1)
    assert store.get("LEVEL#0.gain") == 0.10000000149011612
    with pytest.raises(ValueRangeError) as e:
        store.set("LEVEL#0.gain", 0.100001)  # kept as 0.10000099986791611: above
    assert str(e.value) == "LEVEL#0.gain: 0.100001 is above 0.1 (@max)"


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("value", "text"),
    [
        (0, "0"), (-1.0, "-1"), (2.5, "2.5"), (0.1, "0.1"),
        (1 / 3, "0.3333333333333333"),  # a float64's digits, as many as read back as it
        (0.00001, "0.00001"),  # not 1e-05: a bound as a DSDL file writes it
        (1e-9, "0.000000001"),  # down to a billionth in decimals
        (1e-12, "1e-12"),  # below: with an exponent
        (9e15, "9000000000000000"),  # an integer a float64 holds exactly (below 2^53 = 9.007e15)
        (1e16, "1e+16"),  # from 1e16 on, a float64's last digits are not the number's
        (123456789.5, "123456789.5"),  # no exponent
        # the next float64 above 0.1 (0x3FB999999999999B; 0.1 is ...9A): not 0.1 again
        (struct.unpack("<d", (0x3FB999999999999B).to_bytes(8, "little"))[0], "0.10000000000000002"),
        (math.nan, "nan"), (-math.inf, "-inf"),
    ],
)  # fmt: skip
def test_a_number_in_a_refusal_is_written_as_a_person_writes_it(value: float, text: str) -> None:
    from px4params.store.spec import shown_number

    assert shown_number(value) == text


def _from_bits(code: str, bits: int) -> float:
    """The float whose IEEE 754 encoding (``<e`` binary16, ``<f`` binary32, ``<d`` binary64)
    is ``bits``."""
    return float(struct.unpack(code, bits.to_bytes(struct.calcsize(code), "little"))[0])


# The next float above 0.1 of a parameter's widths (IEEE 754, by hand), written with the fewest
# digits that read back as the same float: binary16 0.1 is 0x2E66 (0.0999755859375), the next
# 0x2E67 = 0.10003662109375, written 0.10004 (0.1000 is 0x2E66 again); binary32 0.1 is
# 0x3DCCCCCD, the next 0x3DCCCCCE = 0.10000000894069672, written 0.10000001 (0.1000000 is
# 0x3DCCCCCD). (A float64 is no parameter's leaf: MAVLink carries 32 bits.)
ABOVE_A_TENTH = [
    ("float16", _from_bits("<e", 0x2E67), "0.10004"),
    ("float32", _from_bits("<f", 0x3DCCCCCE), "0.10000001"),
]


@pytest.mark.parametrize(("kind", "value", "text"), ABOVE_A_TENTH)
def test_a_value_just_above_max_reads_as_another_number_than_max(
    tmp_path: Path, kind: str, value: float, text: str
) -> None:
    assert _from_bits("<e", 0x2E66) == 0.0999755859375 and 0x2E67 - 0x2E66 == 1
    assert _from_bits("<f", 0x3DCCCCCD) == 0.10000000149011612
    level = _dsdl("# @max_instances 1", f"{kind} gain\n# Gain\n# @max 0.1\n")
    store = px4params.Store(_acme(tmp_path, {"Level.1.0.dsdl": level}), classic=[])
    store.add("LEVEL#0")
    store.set("LEVEL#0.gain", 0.1)
    before = store.encoded("LEVEL#0")
    # the instance written whole: its stored leaf is named, at the field's width
    with pytest.raises(ValueRangeError) as e:
        store.set("LEVEL#0", {"gain": value})
    assert str(e.value) == f"LEVEL#0.gain: {text} is above 0.1 (@max)"
    # one leaf written: the number given is named, as Python reads it (a float64)
    with pytest.raises(ValueRangeError) as e:
        store.set("LEVEL#0.gain", float(text))
    assert str(e.value) == f"LEVEL#0.gain: {text} is above 0.1 (@max)"
    assert store.encoded("LEVEL#0") == before
