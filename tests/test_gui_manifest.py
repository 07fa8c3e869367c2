"""The page's manifest view without a browser: the picker from the driver declarations, the
devices a set of flat values configures (as a ground station sees them) with what stops each
from starting, and the ``@format hex`` tag behind addresses shown in hex."""

from __future__ import annotations

import asyncio
import json
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import px4params
import pytest
from gui_server import load_store, make_store
from px4params.errors import BoardsError, DsdlError
from px4params.gcs.metadata import build_parameters_json
from px4params.gui import manifest
from px4params.gui.manifest import _instance_value, devices, picker, status_location
from px4params.store import flat
from px4params.store.flat import flat_values
from px4params.vehicle.boards import load_boards
from px4params.vehicle.drivers import Drivers, load_drivers
from starlette.applications import Starlette


@pytest.fixture(scope="module")
def vehicle(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], dict[str, Any]]:
    """The example airframe's flat values and metadata, as the page gets them."""
    tmp = tmp_path_factory.mktemp("manifest")
    store = load_store(make_store(tmp))
    classic = [c for c in map(store.classic, store.parameters) if c is not None]
    metadata = build_parameters_json(store.schema, specs=store.specs, classic_params=classic)
    return dict(flat_values(store)), metadata


def test_locations_as_px4_status_prints_them() -> None:
    assert status_location("i2c", 1, 0x45) == "I2C bus 1, 0x45"
    assert status_location("i2c", 3, 0x0C) == "I2C bus 3, 0x0C"
    assert status_location("spi", 2, 1) == "SPI bus 2, chip select 1"


def test_the_picker_groups_chips_and_starts_from_the_declarations(vehicle: Any) -> None:
    chosen = picker(vehicle[1], load_drivers())
    groups = list(dict.fromkeys(d["group"] for d in chosen))
    kinds = ["magnetometers", "power monitors", "airspeed", "distance", "barometers", "other"]
    assert groups == kinds
    by = {d["parameter"]: d for d in chosen}
    # drivers.toml: ist8310 default_address 0x0E (iSentek_IST8310::I2C_ADDRESS_DEFAULT)
    assert by["IST8310"]["needs"] == "I2C, address 0x0E (the driver's default)"
    assert by["IST8310"]["start"] == {
        "bus": "i2c",
        "variants": {"i2c": {"bus_id": 1, "address": 14}},
    }
    assert by["LIS3MDL"]["start"]["variants"] == {
        "i2c": {"bus_id": 1, "address": 0x1E},
        "spi": {"bus_id": 1},
    }
    assert by["INA238"]["group"] == "power monitors" and by["MS4525DO"]["group"] == "airspeed"


def test_devices_from_flat_values_with_what_stops_them(vehicle: Any) -> None:
    values, metadata = vehicle
    drivers = load_drivers()
    found = {d["instance"]: d for d in devices(values, metadata, drivers)}
    assert [(d["location"], d["problems"]) for d in found.values()] == [
        ("I2C bus 1, 0x45", []),
        ("I2C bus 2, 0x45", []),
        ("I2C bus 1, 0x0C", []),
    ]
    staged = dict(values, INA238_INST=7, INA238_2A=0, INA238_2B=1, INA238_2C=0x45)
    staged.update(INA238_1B=0)  # bus 0: unset
    found = {d["instance"]: d for d in devices(staged, metadata, drivers)}
    assert found["INA238#1"]["problems"] == ["i2c bus_id is 0 (unset; buses are numbered from 1)"]
    assert found["INA238#2"]["problems"] == ["I2C bus 1 address 0x45 is already INA238#0's"]
    spi = dict(values, INA238_1A=1, INA238_1D=2, INA238_1E=3)  # the I2C leaves are stale
    found = {d["instance"]: d for d in devices(spi, metadata, drivers)}
    assert found["INA238#1"]["location"] == "SPI bus 2, chip select 3"
    assert found["INA238#1"]["problems"] == [
        "bus kind spi is not accepted by ina238 (accepts: i2c)"
    ]


def test_a_compass_the_board_starts_itself(vehicle: Any) -> None:
    values, metadata = vehicle
    staged = dict(values, IST8310_INST=3, IST8310_0A=0, IST8310_0B=1, IST8310_0C=0x0E)
    staged.update(IST8310_0P=2, IST8310_1A=0, IST8310_1B=2, IST8310_1C=0x0E)
    v6c = load_boards().by_name("px4_fmu-v6c")
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), v6c)}
    # boards/px4/fmu-v6c/init/rc.board_sensors: ist8310 -X -b 1 -R 10 start (bus 1 only)
    assert found["IST8310#0"]["problems"] == [
        "the board Pixhawk 6C (FMUv6C) starts this compass itself (ist8310 -X -b 1 -R 10 start, "
        "rotation 10 (Roll 180 deg, Yaw 90 deg)) before the manifest; this instance's rotation "
        "2 (Yaw 90 deg) is not used"
    ]
    assert found["IST8310#1"]["problems"] == []
    assert found["AK09916#0"]["problems"] == []


def test_a_barometer_the_board_starts_itself(vehicle: Any) -> None:
    # boards/zeroone/x6/init/rc.board_sensors: "if ! icp201xx -X start" then
    # "spa06 -X -a 0x77 start": the board's own SPA06 on any external I2C bus (1, 2, 3) at 0x77.
    # PX4's I2C drivers refuse a second instance at one bus and address, so the manifest's
    # start would fail there; at 0x76, or on the internal bus 4, it is the manifest's own.
    values, metadata = vehicle
    staged = dict(values, SPA06_INST=0b111, SPA06_0A=0, SPA06_0B=2, SPA06_0C=0x77)
    staged.update(SPA06_1A=0, SPA06_1B=2, SPA06_1C=0x76, SPA06_2A=0, SPA06_2B=4, SPA06_2C=0x77)
    board = load_boards().by_name("zeroone_x6")
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), board)}
    assert found["SPA06#0"]["problems"] == [
        f"the board {board.label} starts this barometer itself when not icp201xx started (-X "
        "start) (spa06 -X -a 0x77 start) before the manifest"
    ]
    assert found["SPA06#1"]["problems"] == [] and found["SPA06#2"]["problems"] == []


@pytest.mark.parametrize(
    ("line", "error"),
    [
        (
            "uint7 address\n# @format octal\n",
            "@format expects hex on an integer field, got 'octal'",
        ),
        ("float32 gain\n# @format hex\n", "@format expects hex on an integer field, got 'hex'"),
    ],
)
def test_format_tag_errors_name_the_line(tmp_path: Path, line: str, error: str) -> None:
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Thing.1.0.dsdl").write_text("# A thing\n" + line + "@sealed\n")
    with pytest.raises(DsdlError) as e:
        px4params.load_schema([root], include_dronecan=False, cache_dir=None)
    assert str(e.value).endswith(f"Thing.1.0.dsdl:3: {error}"), str(e.value)


def test_instances_are_named_by_their_number_as_the_store_names_them(vehicle: Any) -> None:
    """``NAME#N`` for instance N, counted from 0 (docs/store.md): the picker names every slot
    (the page shows these names, composing none) and a configured instance is named by its
    bit of the ``_INST`` mask. ``@max_instances 4`` of px.Ina238 (dsdl/px/Ina238.1.1.dsdl)."""
    values, metadata = vehicle
    drivers = load_drivers()
    by = {d["parameter"]: d for d in picker(metadata, drivers)}
    assert by["INA238"]["instances"] == ["INA238#0", "INA238#1", "INA238#2", "INA238#3"]
    assert by["AK09916"]["instances"][0] == "AK09916#0"
    # Bit 2 alone: INA238#2, with the leaves INA238_2x (bus 1, address 0x41).
    staged = dict(values, INA238_INST=0b100, INA238_2A=0, INA238_2B=1, INA238_2C=0x41)
    found = [d for d in devices(staged, metadata, drivers) if d["parameter"] == "INA238"]
    assert [(d["instance"], d["location"]) for d in found] == [("INA238#2", "I2C bus 1, 0x41")]
    # The store, given the same instance, names it the same.
    store = px4params.Store(px4params.load_schema(use_env=False), classic=[])
    assert [d["instance"] for d in found] == [store.add("INA238#2")]


# -- the route, in-process over ASGI (issue 40) ------------------------------------------------

EXPECTED = "expected {'values': {name: value}, 'board': name}: "


def _ask(metadata: dict[str, Any], method: str, body: bytes = b"") -> tuple[int, Any]:
    """One request to ``/api/manifest`` as a server hands it over; the status and the JSON."""
    app = Starlette(routes=manifest.routes(SimpleNamespace(metadata=metadata), load_drivers()))
    scope = {
        "type": "http", "method": method, "path": "/api/manifest", "root_path": "",
        "query_string": b"", "headers": [(b"content-type", b"application/json")],
    }  # fmt: skip
    incoming = [{"type": "http.request", "body": body, "more_body": False}]
    sent: list[dict[str, Any]] = []

    async def receive() -> dict[str, Any]:
        if incoming:
            return incoming.pop(0)
        await asyncio.Event().wait()
        raise AssertionError("unreachable")

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)

    asyncio.run(app(scope, receive, send))
    return sent[0]["status"], json.loads(b"".join(m.get("body", b"") for m in sent[1:]))


def _post(metadata: dict[str, Any], payload: Any) -> tuple[int, Any]:
    data = payload if isinstance(payload, bytes) else json.dumps(payload).encode()
    return _ask(metadata, "POST", data)


@pytest.mark.issue40
def test_the_route_serves_the_picker_and_the_boards(vehicle: Any) -> None:
    status, answer = _ask(vehicle[1], "GET")
    assert status == 200
    assert answer["drivers"] == picker(vehicle[1], load_drivers())
    # every board of the bundled table, by name with its label (boards.toml)
    assert answer["boards"] == [{"name": b.name, "label": b.label} for b in load_boards().all()]
    assert {"name": "px4_fmu-v6c", "label": "Pixhawk 6C (FMUv6C)"} in answer["boards"]


@pytest.mark.issue40
def test_the_route_answers_the_devices_of_posted_values_on_a_board(vehicle: Any) -> None:
    values, metadata = vehicle
    staged = dict(values, IST8310_INST=1, IST8310_0A=0, IST8310_0B=1, IST8310_0C=0x0E)
    status, answer = _post(metadata, {"values": staged, "board": "px4_fmu-v6c"})
    assert status == 200
    found = {d["instance"]: d for d in answer["devices"]}
    # boards/px4/fmu-v6c/init/rc.board_sensors starts an ist8310 on bus 1 itself
    assert found["IST8310#0"]["problems"][0].startswith("the board Pixhawk 6C (FMUv6C) starts")
    assert found["IST8310#0"]["location"] == "I2C bus 1, 0x0E"
    # no board (null or an empty name): the same devices without the board's starts
    for board in (None, ""):
        status, answer = _post(metadata, {"values": staged, "board": board})
        assert status == 200
        found = {d["instance"]: d for d in answer["devices"]}
        assert found["IST8310#0"]["problems"] == []
    status, answer = _post(metadata, {"values": staged})  # "board" left out
    assert status == 200 and answer["devices"] == devices(staged, metadata, load_drivers())


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("payload", "error"),
    [
        ({"values": [1]}, "values is not an object"),
        ({"values": {"INA238_INST": True}}, "values: INA238_INST is true, not a number"),
        ({"values": {"INA238_INST": "1"}}, 'values: INA238_INST is "1", not a number'),
        ({"values": {"INA238_INST": None}}, "values: INA238_INST is null, not a number"),
        ({"values": {}, "board": 6}, "board is not a name"),
        ({"board": "px4_fmu-v6c"}, "'values'"),
    ],
)
def test_the_route_refuses_a_post_it_cannot_read_naming_what(
    vehicle: Any, payload: Any, error: str
) -> None:
    assert _post(vehicle[1], payload) == (400, {"error": EXPECTED + error})


@pytest.mark.issue40
def test_the_route_refuses_a_body_that_is_not_a_json_object(vehicle: Any) -> None:
    status, answer = _post(vehicle[1], b"{not json")
    assert status == 400 and answer["error"].startswith(EXPECTED + "Expecting property name")
    status, answer = _post(vehicle[1], [1, 2])
    assert status == 400 and answer["error"].startswith(EXPECTED)


@pytest.mark.issue40
def test_the_route_refuses_a_board_not_in_the_table(vehicle: Any) -> None:
    answer = _post(vehicle[1], {"values": {}, "board": "acme_nothing"})
    assert answer == (400, {"error": "board 'acme_nothing': not in the board table"})


@pytest.mark.issue40
def test_without_a_readable_board_table_the_picker_stays_and_a_board_is_refused(
    vehicle: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    # An installation whose boards.toml cannot be read: the page still gets its picker (no
    # boards to choose from), and a post naming a board gets the table's error, not a crash.
    def broken() -> Any:
        raise BoardsError("boards.toml:1: not TOML")

    monkeypatch.setattr(manifest, "load_boards", broken)
    status, answer = _ask(vehicle[1], "GET")
    assert status == 200 and answer["boards"] == [] and answer["drivers"]
    assert _post(vehicle[1], {"values": {}, "board": "px4_fmu-v6c"}) == (
        400, {"error": "boards.toml:1: not TOML"},
    )  # fmt: skip


# -- the picker and the locations, every kind (issue 40) ---------------------------------------


@pytest.mark.issue40
def test_every_bus_variant_has_its_location_in_words() -> None:
    # The six variants of px.Bus (dsdl/px/Bus.1.0.dsdl), each with what its two numbers mean
    # there: a DroneCAN interface and node ID, a simulated instance, a MAVLink instance and
    # system ID, a serial port (no address); anything else is on no bus.
    assert status_location("dronecan", 1, 125) == "DroneCAN interface 1, node 125"
    assert status_location("sim", 0, 2) == "simulation, instance 2"
    assert status_location("mavlink", 1, 42) == "MAVLink instance 1, system 42"
    assert status_location("serial", 3, 0) == "serial port 3"
    assert status_location("", 0, 0) == "no bus"
    assert status_location("can", 1, 1) == "no bus"


@pytest.mark.issue40
def test_the_picker_groups_every_driver_by_what_it_measures(vehicle: Any) -> None:
    # docs: a compass behind an IMU (icm20948's passthrough) is a magnetometer, a smart battery
    # (batt_smbus, batmon) a power monitor, an airspeed sensor that also reads pressure (auav)
    # airspeed; temperature, humidity, RPM and IR-beacon chips are "other".
    measures = {
        "magnetometer": "magnetometers", "IMU (magnetometer passthrough)": "magnetometers",
        "power monitor": "power monitors", "battery": "power monitors",
        "airspeed": "airspeed", "airspeed / barometer": "airspeed",
        "distance": "distance", "barometer": "barometers",
    }  # fmt: skip
    chosen = picker(vehicle[1], load_drivers())
    for d in chosen:
        assert d["group"] == measures.get(d["kind"], "other"), d["parameter"]
    by = {d["parameter"]: d["group"] for d in chosen}
    assert (by["ICM20948"], by["BATT_SMBUS"], by["AUAV"]) == (
        "magnetometers", "power monitors", "airspeed",
    )  # fmt: skip
    assert by["MCP9808"] == "other"
    for group in dict.fromkeys(by.values()):  # by chip name within a group
        names = [d["chips"][0] for d in chosen if d["group"] == group]
        assert names == sorted(names)
    # each chip says what it needs in PX4's words for the bus
    needs = {d["parameter"]: d["needs"] for d in chosen}
    assert needs["LIS3MDL"] == "I2C, address 0x1E (the driver's default) or SPI"


@pytest.mark.issue40
def test_the_picker_of_drivers_declared_otherwise(vehicle: Any) -> None:
    """A driver on every bus kind, one without a default address, one that does not
    autostart, and parameters no driver declares (drivers.toml of another installation)."""
    real = load_drivers()
    drivers = Drivers(
        [
            replace(real["ina238"], buses=("i2c", "spi", "serial", "dronecan"), autostart=False),
            replace(real["ist8310"], default_address=None),
        ],
        "test",
    )
    _, metadata = vehicle
    by = {d["parameter"]: d for d in picker(metadata, drivers)}
    assert by["INA238"]["needs"] == (
        "I2C, address 0x45 (the driver's default) or SPI or serial or DroneCAN; its driver "
        "does not autostart"
    )
    # bus 1 on I2C and SPI (the driver's address on I2C); serial and DroneCAN start from their
    # DSDL defaults
    assert by["INA238"]["start"] == {
        "bus": "i2c", "variants": {"i2c": {"bus_id": 1, "address": 0x45}, "spi": {"bus_id": 1}},
    }  # fmt: skip
    assert by["IST8310"]["needs"] == "I2C"
    assert by["IST8310"]["start"]["variants"] == {"i2c": {"bus_id": 1}}
    # No driver: listed under "other" by its own name, nothing to start it with.
    assert {k: v for k, v in by["AK09916"].items() if k != "instances"} == {
        "parameter": "AK09916", "driver": None, "chips": ["AK09916"], "kind": "",
        "group": "other", "order": None, "buses": [], "default_address": None,
        "needs": "no driver declared: nothing starts it", "start": {},
    }  # fmt: skip


@pytest.mark.issue40
def test_the_picker_lists_instanced_structured_parameters_only(vehicle: Any) -> None:
    # A structured parameter without @max_instances is one value, not instances to add; a
    # classic parameter is no structure at all.
    _, metadata = vehicle
    (ina,) = [e for e in metadata["parameters"] if e["name"] == "INA238"]
    single = {k: v for k, v in ina.items() if k != "max_instances"} | {"name": "ACME"}
    classic = {"name": "ACME_CLASSIC", "type": "Int32", "max_instances": 4}
    shown = picker({"parameters": [*metadata["parameters"], single, classic]}, load_drivers())
    names = [d["parameter"] for d in shown]
    assert "ACME" not in names and "ACME_CLASSIC" not in names and "INA238" in names


@pytest.mark.issue40
def test_an_instance_rebuilt_from_flat_values_is_the_stores_own(tmp_path: Path) -> None:
    """The page rebuilds an instance from the flat values a ground station holds, stale leaves
    of unselected variants included (a GCS keeps every letter): only the selected variants'
    leaves are the instance's, a union inside a variant too, as ``Store.get`` returns it."""
    root = tmp_path / "tst"
    root.mkdir()
    for name, text in {
        "Mode.1.0.dsdl": "@union\nuint8 a\nfloat32 b\n@sealed\n",
        "Wired.1.0.dsdl": "uint7 bus_id\nMode.1.0 mode\n@sealed\n",
        # the union inside the second variant: only that variant's fields list its tag
        "Link.1.0.dsdl": "@union\nuint8 radio\nWired.1.0 wired\n@sealed\n",
        "Thing.1.0.dsdl": "# @max_instances 2\nuint4 p_version\nLink.1.0 link\n@sealed\n",
    }.items():
        (root / name).write_text(text)
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema, classic=[])
    store.add("THING#1")
    letters = {row.path: row.name for row in flat.flat_table(store)}
    flat.set_flat(store, letters["link._tag"], 1)  # link: wired
    letters = {row.path: row.name for row in flat.flat_table(store)}
    flat.set_flat(store, letters["link.wired.mode._tag"], 1)  # mode: b
    letters = {row.path: row.name for row in flat.flat_table(store)}
    flat.set_flat(store, letters["link.wired.mode.b"], 2.5)
    flat.set_flat(store, letters["link.wired.bus_id"], 3)
    (entry,) = [e for e in build_parameters_json(schema)["parameters"] if e["name"] == "THING"]
    values = dict(flat.flat_values(store))
    paths = {f["letter"]: f["path"] for f in entry["flat"]}
    assert (paths["B"], paths["E"]) == ("link.radio", "link.wired.mode.a")
    values.update(THING_1B=9, THING_1E=7)  # stale: the radio variant and mode.a
    rebuilt = _instance_value(entry, 1, values)
    assert rebuilt == {"link": store.get("THING#1")["link"]}
    assert rebuilt == {"link": {"wired": {"bus_id": 3, "mode": {"b": 2.5}}}}


@pytest.mark.issue40
@pytest.mark.parametrize("tag", [6, 7, -1])
def test_a_bus_tag_beyond_the_variants_selects_no_bus(vehicle: Any, tag: int) -> None:
    # px.Bus has six variants (tags 0..5, dsdl/px/Bus.1.0.dsdl) in a 3-bit tag: a ground
    # station can send 6 or 7 (or any int32): no variant is selected, so the instance has no
    # bus and says so; the leaves of the I2C variant are not taken for it.
    values, metadata = vehicle
    staged = dict(values, INA238_INST=1, INA238_0A=tag, INA238_0B=1, INA238_0C=0x45)
    (ina,) = [d for d in devices(staged, metadata, load_drivers()) if d["parameter"] == "INA238"]
    assert (ina["location"], ina["problems"]) == ("no bus", ["its value has no bus"])


@pytest.mark.issue40
def test_a_board_compass_started_without_address_or_rotation(vehicle: Any) -> None:
    # boards/accton-godwit/ga1/init/rc.board_sensors: "rm3100 -I -b 4 start": no -a (the
    # driver's default address, 0x20 for the RM3100) and no -R. An RM3100 there is the board's;
    # at another address or on another bus it is another chip.
    values, metadata = vehicle
    staged = dict(values, RM3100_INST=0b111, RM3100_0A=0, RM3100_0B=4, RM3100_0C=0x20)
    staged.update(RM3100_0P=2, RM3100_1A=0, RM3100_1B=4, RM3100_1C=0x21)
    staged.update(RM3100_2A=0, RM3100_2B=1, RM3100_2C=0x20, RM3100_2P=0)
    board = load_boards().by_name("accton-godwit_ga1")
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), board)}
    assert found["RM3100#0"]["problems"] == [
        f"the board {board.label} starts this compass itself (rm3100 -I -b 4 start, no "
        "rotation given) before the manifest; this instance's rotation 2 (Yaw 90 deg) is not "
        "used"
    ]
    assert found["RM3100#1"]["problems"] == [] and found["RM3100#2"]["problems"] == []
    # without a rotation of its own (no P leaf): nothing about its rotation
    del staged["RM3100_0P"]
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), board)}
    assert found["RM3100#0"]["problems"] == [
        f"the board {board.label} starts this compass itself (rm3100 -I -b 4 start, no "
        "rotation given) before the manifest"
    ]


@pytest.mark.issue40
def test_a_board_compass_on_spi_is_any_chip_select_of_its_bus(vehicle: Any) -> None:
    # boards/ark/mag: "rm3100 -s -b 2 start" (internal SPI bus 2, the board's chip select): an
    # RM3100 on SPI bus 2 is the board's; on I2C bus 2 or SPI bus 1 it is not.
    values, metadata = vehicle
    staged = dict(values, RM3100_INST=0b111, RM3100_0A=1, RM3100_0D=2, RM3100_0E=1)
    staged.update(RM3100_1A=0, RM3100_1B=2, RM3100_1C=0x20, RM3100_2A=1, RM3100_2D=1)
    staged.update(RM3100_2E=1)
    board = load_boards().by_name("ark_mag")
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), board)}
    assert found["RM3100#0"]["location"] == "SPI bus 2, chip select 1"
    assert found["RM3100#0"]["problems"] == [
        f"the board {board.label} starts this compass itself (rm3100 -s -b 2 start, no "
        "rotation given) before the manifest"
    ]
    assert found["RM3100#1"]["problems"] == [] and found["RM3100#2"]["problems"] == []


@pytest.mark.issue40
def test_a_board_compass_started_on_a_condition_says_when(vehicle: Any) -> None:
    # zeroone x6's rc.board_sensors starts "ist8310 -I -a 0x0E -R 12 start" when the RM3100
    # did not start ("if ! rm3100 -I -b 4 start"): the problem says so. Rotation 12 is PX4's
    # ROTATION_PITCH_180 (src/lib/conversion/rotation.h).
    values, metadata = vehicle
    staged = dict(values, IST8310_INST=1, IST8310_0A=0, IST8310_0B=4, IST8310_0C=0x0E)
    board = load_boards().by_name("zeroone_x6")
    (start,) = [s for s in board.devices if s.driver == "ist8310" and s.when]
    assert (start.args, start.when) == (
        "-I -a 0x0E -R 12 start", "not rm3100 started (-I -b 4 start)",
    )  # fmt: skip
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), board)}
    assert found["IST8310#0"]["problems"] == [
        f"the board {board.label} starts this compass itself when not rm3100 started (-I -b 4 "
        "start) (ist8310 -I -a 0x0E -R 12 start, rotation 12 (Pitch 180 deg)) "
        "before the manifest"
    ]


@pytest.mark.issue40
def test_devices_come_in_start_order(vehicle: Any) -> None:
    # The order the autostart runs them (docs/autostart.md): the declared drivers by their
    # "order" (lower first), each instance by number, then the parameters no driver starts, by
    # name.
    real = load_drivers()
    drivers = Drivers([real["ina238"], replace(real["ist8310"], order=5)], "test")
    assert real["ina238"].order == 30
    values, metadata = vehicle
    staged = dict(values, INA238_INST=0b11, IST8310_INST=1, BMM350_INST=1, AK09916_INST=1)
    staged.update(INA238_1A=0, INA238_1B=3, INA238_1C=0x44)
    staged.update(IST8310_0A=0, IST8310_0B=1, IST8310_0C=0x0E)
    staged.update(BMM350_0A=0, BMM350_0B=1, BMM350_0C=0x14)
    found = devices(staged, metadata, drivers)
    assert [d["instance"] for d in found] == [
        "IST8310#0", "INA238#0", "INA238#1", "AK09916#0", "BMM350#0",
    ]  # fmt: skip
    # an instance no driver starts: no driver, no kind, and it says so
    assert {k: found[3][k] for k in ("driver", "kind", "problems", "location")} == {
        "driver": None, "kind": "", "problems": ["no driver declared for parameter AK09916"],
        "location": "I2C bus 1, 0x0C",
    }  # fmt: skip
    assert (found[0]["driver"], found[0]["kind"]) == ("ist8310", "magnetometer")
    # A ground station that has not got a parameter's _INST (yet): the others are still read.
    del staged["IST8310_INST"], staged["INA238_INST"]
    assert [d["instance"] for d in devices(staged, metadata, drivers)] == [
        "AK09916#0", "BMM350#0",
    ]  # fmt: skip
    # A structured parameter without instances has no _INST to read, whatever a GCS holds.
    (ina,) = [e for e in metadata["parameters"] if e["name"] == "INA238"]
    single = {k: v for k, v in ina.items() if k != "max_instances"} | {"name": "ACME"}
    with_single = {"parameters": [*metadata["parameters"], single]}
    found = devices(dict(staged, ACME_INST=1, ACME_0A=0), with_single, drivers)
    assert [d["instance"] for d in found] == ["AK09916#0", "BMM350#0"]


@pytest.mark.issue40
def test_a_rotation_without_a_name_is_shown_as_its_number(vehicle: Any) -> None:
    # PX4's Rotation enum (src/lib/conversion/rotation.h) names 0..40 (ROTATION_MAX is 41): a
    # staged 41 (the page stages what a ground station may send) is shown as its number.
    values, metadata = vehicle
    staged = dict(values, RM3100_INST=1, RM3100_0A=0, RM3100_0B=4, RM3100_0C=0x20)
    staged.update(RM3100_0P=41)
    board = load_boards().by_name("accton-godwit_ga1")
    (found,) = [d for d in devices(staged, metadata, load_drivers(), board)
                if d["instance"] == "RM3100#0"]  # fmt: skip
    assert found["problems"][0].endswith("; this instance's rotation 41 is not used")


@pytest.mark.issue40
def test_a_board_starting_a_compass_twice_claims_each_address(vehicle: Any) -> None:
    # A script may start one driver at two addresses of a bus ("ist8310 -X -b 1 -a 0x0C start"
    # then the driver's default 0x0E): each start claims its own address, whatever its rank.
    values, metadata = vehicle
    v6c = load_boards().by_name("px4_fmu-v6c")
    (ist,) = [s for s in v6c.devices if s.driver == "ist8310" and s.bus == 1]
    first = replace(ist, address=0x0C, args="-X -b 1 -a 0x0C -R 10 start")
    board = replace(v6c, devices=(first, ist))
    staged = dict(values, IST8310_INST=1, IST8310_0A=0, IST8310_0B=1, IST8310_0C=0x0E)
    (found,) = [d for d in devices(staged, metadata, load_drivers(), board)
                if d["instance"] == "IST8310#0"]  # fmt: skip
    assert found["problems"][0].startswith(
        "the board Pixhawk 6C (FMUv6C) starts this compass itself (ist8310 -X -b 1 -R 10 start,"
    )


@pytest.mark.issue40
def test_a_leaf_the_ground_station_lacks_counts_as_unset(vehicle: Any) -> None:
    # A GCS that has not read INA238_0B (the I2C bus) yet: the bus is unset, as 0 would be.
    values, metadata = vehicle
    staged = {k: v for k, v in values.items() if not k.startswith("INA238_")}
    staged.update(INA238_INST=1, INA238_0A=0, INA238_0C=0x45)
    (ina,) = [d for d in devices(staged, metadata, load_drivers()) if d["parameter"] == "INA238"]
    assert ina["problems"] == ["i2c bus_id is 0 (unset; buses are numbered from 1)"]


def test_a_board_compass_on_a_bus_internal_only_on_some_hardware_says_where(vehicle: Any) -> None:
    # boards/px4/fmu-v3/init/rc.board_sensors:12 (main): "hmc5883 -T -I -R 4 start" probes the
    # internal buses; src/i2c.cpp:50-63 makes every bus external where HW_VER_FMUV3 ==
    # board_get_hw_version() (hw_type V30, a Cube), so there PX4's I2CBusIterator
    # (platforms/common/i2c.cpp) finds no bus for it and an HMC5883 on bus 2 is not the board's.
    # The page cannot tell the hardware: it names the condition, as migrate does. Rotation 4 is
    # ROTATION_YAW_180 (src/lib/conversion/rotation.h).
    values, metadata = vehicle
    staged = dict(values, HMC5883_INST=0b11, HMC5883_0A=0, HMC5883_0B=2, HMC5883_0C=0x1E)
    staged.update(HMC5883_1A=0, HMC5883_1B=1, HMC5883_1C=0x1E)
    board = load_boards().by_name("px4_fmu-v3")
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), board)}
    assert found["HMC5883#0"]["problems"] == [
        f"the board {board.label} starts this compass itself when not hw_type in V30 (hmc5883 "
        "-T -I -R 4 start, rotation 4 (Yaw 180 deg)) before the manifest"
    ]
    assert found["HMC5883#1"]["problems"] == []  # bus 1 is external on every hardware


def test_a_board_start_with_its_own_condition_on_such_a_bus_names_both(vehicle: Any) -> None:
    # No bundled board starts an I2C device behind a condition of its own on a board whose
    # buses change kind with the hardware; fmu-v3's hmc5883 given one shows how the page words
    # it: the script's condition, then the bus's, both of which must hold.
    values, metadata = vehicle
    staged = dict(values, HMC5883_INST=0b1, HMC5883_0A=0, HMC5883_0B=2, HMC5883_0C=0x1E)
    board = load_boards().by_name("px4_fmu-v3")
    hmc = next(d for d in board.devices if d.driver == "hmc5883" and d.bus_kind == "I2C")
    guarded = replace(hmc, when="$SENS_EXT_MAG == 0")
    board = replace(board, devices=(guarded,))
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), board)}
    assert found["HMC5883#0"]["problems"] == [
        f"the board {board.label} starts this compass itself when $SENS_EXT_MAG == 0 and not "
        "hw_type in V30 (hmc5883 -T -I -R 4 start, rotation 4 (Yaw 180 deg)) before the manifest"
    ]
