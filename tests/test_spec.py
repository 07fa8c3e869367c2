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
            f"px4params: error: {params}:2: INA238_1Q: INA238#1.shunt: 0 {SHUNT_RANGE}\n"
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
