"""Driver declarations (drivers.toml), the generated startup script and the autostart plan.

Every error path of the declarations file and of finding the manifest is checked by message.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from px4params import Store
from px4params.cli.main import main
from px4params.store.spec import parameter_specs
from px4params.vehicle import autostart, devid, simbench
from px4params.vehicle.autostart import (
    ManifestError,
    configured,
    load_manifest,
    plan,
    plan_lines,
    script,
)
from px4params.vehicle.drivers import (
    BUS_KINDS,
    DEFAULT_DRIVERS,
    DriversFileError,
    load_drivers,
    parse_drivers,
)
from px4params.vehicle.simbench import parse_bench
from shared_data import current_devtypes

REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"

INA238 = """
[[driver]]
name = "ina238"
parameter = "INA238"
chip = "INA238"
order = 30
buses = ["i2c"]
default_address = 0x45
devtype = 0xD4
chip_id_register = 0x3F
chip_id = 0x238
rate_hz = 10
"""


@pytest.fixture(scope="module")
def specs(schema):
    return parameter_specs(schema)


@pytest.fixture(scope="module")
def drivers(specs):
    return load_drivers(DEFAULT_DRIVERS, specs)


@pytest.fixture()
def store(schema) -> Store:
    """The example airframe's manifest: INA238#0 (I2C 1, 0x45), INA238#1 (I2C 2, 0x45),
    AK09916#0 (I2C 1, 0x0C)."""
    return load_manifest(None, AIRFRAME)


# -- the bundled declarations -------------------------------------------------------------------


def test_every_bundled_parameter_has_a_driver(drivers, specs):
    instanced = [s.name for s in specs if not s.shared]
    assert instanced, "the bundled schema has instanced parameters"
    assert drivers.missing(specs) == []
    assert sorted(d.parameter for d in drivers) == sorted(instanced)


def test_devtypes_are_todays_drv_sensor_codes(drivers):
    # Each chip's devtype must be its DRV_<KIND>_DEVTYPE_<CHIP> in today's drv_sensor.h.
    table = current_devtypes()
    for d in drivers:
        names = [r.name for r in table.lookup(d.devtype)]
        assert d.chip in names, f"{d.name}: 0x{d.devtype:02X} is {names} in the current table"
        for chip in d.also_chips:  # the other devtypes it publishes (SDP32, SDP33) exist too
            assert table.resolve(chip), f"{d.name}: {chip} is not in the current table"


def test_known_codes_and_chip_ids(drivers):
    expected = {
        "ina226": (0xD0, 0xFF, 0x2260),
        "ina228": (0xD1, 0x3F, 0x228),
        "ina238": (0xD4, 0x3F, 0x238),
        "ak09916": (0x09, 0x01, 0x09),
        "bmm350": (0xE5, 0x00, 0x33),
        "ist8310": (0x06, 0x00, 0x10),
        "lis3mdl": (0x05, 0x0F, 0x3D),
        "qmc5883l": (0x08, 0x0D, 0xFF),
        "rm3100": (0x07, 0x36, 0x22),
        # rc.sensors' probe block (SENS_EXT_I2C_PRB)
        "icm20948_i2c_passthrough": (0x28, 0x00, 0xEA),
        "hmc5883": (0x01, 0x0A, ord("H")),
        "iis2mdc": (0x0E, 0x4F, 0x40),
        "ist8308": (0x0B, 0x00, 0x08),
        "qmc5883p": (0x0F, 0x00, 0x80),
        # rc.sensors' SENS_EN_* starts; None: the probe reads no ID register
        "ms4525do": (0x48, None, None),
        "ms4515": (0x47, None, None),
        "ms5525dso": (0x49, None, None),
        "sdp3x": (0x4A, None, None),
        "ets_airspeed": (0x46, None, None),
        "asp5033": (0xE4, None, None),
        "auav": (0xE6, None, None),
        "ll40ls": (0x70, None, None),
        "lightware_laser_i2c": (0x73, None, None),
        "teraranger": (0x75, 0x01, 0xA1),
        "vl53l0x": (0x76, 0xC0, 0xEE),
        "vl53l1x": (0x91, None, None),
        "mb12xx": (0x72, None, None),
        "tf02pro": (0xE0, None, None),
        "spl06": (0x4F, 0x0D, 0x10),
        "spa06": (0xE8, 0x0D, 0x11),
        "mcp9808": (0xEE, 0x06, 0x54),
        "tmp102": (0xF0, None, None),
        "sht3x": (0xB1, None, None),
        "pcf8583": (0x7E, None, None),
        "irlock": (0x7D, None, None),
        "batt_smbus": (0x7C, None, None),
        "batmon": (0x9D, None, None),
    }
    got = {d.name: (d.devtype, d.chip_id_register, d.chip_id) for d in drivers}
    assert got == expected
    assert drivers["ina238"].default_address == 0x45
    assert drivers["ak09916"].default_address == 0x0C


def test_start_order_is_the_talks(drivers):
    names = [d.name for d in drivers.autostart()]
    assert names[:3] == ["ina226", "ina228", "ina238"]
    orders = [d.order for d in drivers]
    assert orders == sorted(orders) and len(set(orders)) == len(orders)


# -- script ---------------------------------------------------------------------------------------


def test_script_lists_every_autostart_driver_in_order(drivers):
    lines = script(drivers)
    assert lines == [f"{d.name} auto" for d in drivers.autostart()]
    assert lines[2] == "ina238 auto"


def test_script_skips_drivers_without_autostart(specs):
    text = INA238 + INA238.replace('"ina238"', '"ina228"').replace('"INA238"', '"INA228"').replace(
        "order = 30", "order = 20\nautostart = false"
    )
    drivers = parse_drivers(text, "d.toml", specs)
    assert script(drivers) == ["ina238 auto"]


def test_cli_script(capsys):
    assert main(["autostart", "script"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("# generated by px4params from the bundled drivers.toml")
    assert out[1:4] == ["ina226 auto", "ina228 auto", "ina238 auto"]
    assert all(re.fullmatch(r"[a-z0-9_]+ auto", line) for line in out[1:])


# -- plan -----------------------------------------------------------------------------------------


def test_plan_of_the_example_airframe(store, drivers):
    entries = {e.driver.name: e for e in plan(store, drivers) if e.driver}
    assert [c.instance for c in entries["ina238"].instances] == ["INA238#0", "INA238#1"]
    assert entries["ina226"].instances == ()
    first, second = entries["ina238"].instances
    assert (first.bus_kind, first.bus_id, first.address) == ("i2c", 1, 0x45)
    assert first.settings["current"] == 200
    assert first.settings["shunt"] == pytest.approx(0.0003, rel=1e-3)
    assert (second.bus_id, second.address) == (2, 0x45)
    assert first.device_id == devid.encode("i2c", 1, 0x45, 0xD4) == 0xD44509
    (mag,) = entries["ak09916"].instances
    assert mag.device_id == 592905  # CAL_MAG1_ID of the CubeOrange sample log


def test_plan_text_and_json(tmp_path, capsys):
    assert main(["autostart", "plan", "--airframe", str(AIRFRAME)]) == 0
    out = capsys.readouterr().out
    idle = out.splitlines()[-1]  # the drivers with no instance, together, in start order
    assert idle.startswith("nothing to start (35 drivers): ina226, ina228, icm20948_i2c_passth")
    assert "ina238" not in idle and "ak09916" not in idle
    assert "ina238 auto  (order 30, parameter INA238, devtype 0xD4): 2 instances" in out
    line = next(x for x in out.splitlines() if "INA238#0" in x)
    assert "I2C bus 1 address 0x45" in line and "current=200" in line and "0xD44509" in line
    assert main(["autostart", "plan", "--airframe", str(AIRFRAME), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    ina = next(r for r in rows if r["driver"] == "ina238")
    assert [i["instance"] for i in ina["instances"]] == ["INA238#0", "INA238#1"]
    assert ina["instances"][0]["address"] == 0x45 and ina["instances"][0]["problems"] == []


def test_plan_reads_the_store_file(tmp_path, capsys, monkeypatch, store):
    path = tmp_path / "vehicle.store"
    store.save(path)
    assert main(["autostart", "plan", "--store", str(path)]) == 0
    assert "INA238#1" in capsys.readouterr().out
    monkeypatch.setenv("PX4PARAMS_STORE", str(path))
    assert main(["autostart", "plan"]) == 0
    assert "AK09916#0" in capsys.readouterr().out


def test_plan_reports_instances_that_cannot_start(schema, drivers):
    s = Store(schema)
    s.add("INA238#0")
    value = s.get("INA238#0")
    value["bus"] = {"spi": {"bus_id": 1, "chip_select": 2, "max_frequency": 0, "mode": 3}}
    s.set("INA238#0", value)
    s.add("INA238#1")  # bus_id left 0
    s.add("RM3100#0")
    s.set("RM3100#0.bus.i2c.bus_id", 1)
    s.add("LIS3MDL#0")
    s.set("LIS3MDL#0.bus.i2c.bus_id", 1)
    s.set("LIS3MDL#0.bus.i2c.address", 0x20)  # where RM3100#0 is; lis3mdl starts first
    found = {c.instance: c for c in configured(s, drivers)}
    assert found["INA238#0"].problems == ("bus kind spi is not accepted by ina238 (accepts: i2c)",)
    assert found["INA238#1"].problems == ("i2c bus_id is 0 (unset; buses are numbered from 1)",)
    assert found["LIS3MDL#0"].problems == ()
    assert found["RM3100#0"].problems == ("I2C bus 1 address 0x20 is already LIS3MDL#0's",)
    text = "\n".join(plan_lines(plan(s, drivers)))
    assert "NOT STARTED: bus kind spi is not accepted by ina238" in text


def test_instances_of_a_parameter_without_driver(schema, specs):
    drivers = parse_drivers(INA238, "d.toml", specs)
    s = Store(schema)
    s.add("AK09916#0")
    s.set("AK09916#0.bus.i2c.bus_id", 1)
    (c,) = configured(s, drivers)
    assert c.driver is None
    assert c.problems == ("no driver declared for parameter AK09916",)
    entries = plan(s, drivers)
    assert entries[-1].driver is None and entries[-1].parameter == "AK09916"
    assert "(no driver) parameter AK09916: 1 instance(s)" in plan_lines(entries)


# -- finding the manifest: errors -----------------------------------------------------------------


def test_no_store_file(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    assert main(["autostart", "plan"]) == 1
    err = capsys.readouterr().err
    assert err == (
        "px4params: error: no store file px4params.store (write one with 'px4params run "
        "AIRFRAME --store px4params.store', or give --store FILE or --airframe FILE)\n"
    )
    with pytest.raises(ManifestError, match=r"no store file .*missing\.store"):
        load_manifest(tmp_path / "missing.store")


def test_store_file_that_is_not_a_store(tmp_path, capsys):
    bad = tmp_path / "bad.store"
    bad.write_bytes(b"hello")
    assert main(["autostart", "plan", "--store", str(bad)]) == 1
    assert "not a px4params store file" in capsys.readouterr().err


def test_airframe_errors(tmp_path, capsys):
    frame = tmp_path / "frame.txt"
    frame.write_text("param add INA238#0\nparam set INA238#0[4] banana\n")
    with pytest.raises(ManifestError, match=r"frame\.txt:2: "):
        load_manifest(None, frame)
    assert main(["autostart", "plan", "--airframe", str(tmp_path / "none.txt")]) == 1
    assert "none.txt" in capsys.readouterr().err


def test_store_and_airframe_exclude_each_other(capsys):
    with pytest.raises(SystemExit) as e:
        main(["autostart", "plan", "--store", "a", "--airframe", "b"])
    assert e.value.code == 2
    assert "not allowed with argument" in capsys.readouterr().err


# -- drivers file: every error, by message --------------------------------------------------------


def _error(text: str, specs=None) -> str:
    with pytest.raises(DriversFileError) as e:
        parse_drivers(text, "drivers.toml", specs)
    message = str(e.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("order = 30", "order = 30\nspeed = 3"), "driver 'ina238': unknown key 'speed'"),
        (
            ("order = 30", "ordr = 30"),
            "driver 'ina238': unknown key 'ordr' (did you mean 'order'?)",
        ),
        (("order = 30\n", ""), "driver 'ina238': missing key 'order'"),
        (('name = "ina238"', 'name = "INA-238"'), "driver #1: name 'INA-238' is not a PX4 module"),
        (('parameter = "INA238"', 'parameter = "ina238"'), "parameter 'ina238' is not an upper"),
        (('parameter = "INA238"', "parameter = 5"), "parameter must be a string, not 5"),
        (('chip = "INA238"', 'chip = "INA 238"'), "chip 'INA 238' is not a chip name"),
        (("order = 30", "order = -1"), "driver 'ina238': order -1 is out of range 0..1000000"),
        (("order = 30", 'order = "first"'), "order must be an integer, not 'first'"),
        (("order = 30", "order = 30\nautostart = 1"), "autostart must be true or false, not 1"),
        (('buses = ["i2c"]', "buses = []"), "buses must be a non-empty list of bus kinds"),
        (('buses = ["i2c"]', 'buses = ["can"]'), "unknown bus kind 'can' (expected one of: i2c"),
        (('buses = ["i2c"]', 'buses = ["i2c", "i2c"]'), "buses lists a kind twice"),
        (
            ("default_address = 0x45", "default_address = 200"),
            "driver 'ina238': default_address 200 is out of range 0..127, 0x00..0x7F",
        ),
        (
            ("default_address = 0x45\n", ""),
            "missing key 'default_address' (required for an i2c driver)",
        ),
        (("devtype = 0xD4", "devtype = 0x1D4"), "devtype 468 is out of range 0..255, 0x00..0xFF"),
        (("devtype = 0xD4", "devtype = 1.5"), "devtype must be an integer, not 1.5"),
        (("chip_id = 0x238", "chip_id = 0x10000"), "chip_id 65536 is out of range 0..65535"),
        (("chip_id_register = 0x3F", "chip_id_register = 256"), "chip_id_register 256 is out"),
        (("rate_hz = 10", "rate_hz = 0"), "rate_hz 0 is out of range (expected > 0 and <= 10000)"),
        (("rate_hz = 10", 'rate_hz = "fast"'), "rate_hz must be a number, not 'fast'"),
        (("rate_hz = 10", "rate_hz = 10\ndescription = 3"), "description must be a string"),
        (("chip_id = 0x238\n", ""), "chip_id_register and chip_id go together"),
        (("rate_hz = 10", "rate_hz = 10\nkind = 7"), "kind must be a string, not 7"),
        (("rate_hz = 10", 'rate_hz = 10\nalso_chips = ["SDP 32"]'), "also_chips: 'SDP 32' is not"),
        (("rate_hz = 10", "rate_hz = 10\nalso_chips = 3"), "also_chips must be a list of strings"),
        (("rate_hz = 10", 'rate_hz = 10\nstarted_by = "magic"'), "started_by 'magic' is not one"),
        (
            ("rate_hz = 10", 'rate_hz = 10\nstarted_by = "parameter"'),
            'started_by = "parameter" needs enabled_by',
        ),
        (("rate_hz = 10", 'rate_hz = 10\nenabled_by = "sens_en"'), "enabled_by 'sens_en' is not"),
        (("rate_hz = 10", "rate_hz = 10\nenabled_values = [2]"), "enabled_values needs enabled_by"),
        (
            ("rate_hz = 10", 'rate_hz = 10\nenabled_by = "SENS_EN_X"\nenabled_values = [0]'),
            "enabled_values must be a list of non-zero integers, not [0]",
        ),
        (("rate_hz = 10", 'rate_hz = 10\nsettings = { x = "y" }'), "settings must be a table"),
        (("rate_hz = 10", 'rate_hz = 10\nswitch_field = "current"'), "switch_field must be a"),
        (("rate_hz = 10", "rate_hz = 10\nsources = [1]"), "sources must be a list of strings"),
    ],
)
def test_drivers_file_errors(change, message):
    old, new = change
    assert old in INA238
    assert _error(INA238.replace(old, new, 1)).startswith("drivers.toml: ")
    assert message in _error(INA238.replace(old, new, 1))


def test_drivers_file_document_errors(specs):
    assert _error("[[driver]\n").startswith("drivers.toml: not TOML: ")
    assert _error("") == "drivers.toml: no [[driver]] tables"
    assert _error("[tools]\nx = 1\n" + INA238) == (
        "drivers.toml: unknown top-level key 'tools' (expected [[driver]] tables)"
    )
    assert _error("driver = 3") == "drivers.toml: no [[driver]] tables"
    assert _error("driver = [3]") == "drivers.toml: driver #1: is not a table"


def test_drivers_file_uniqueness():
    twice = INA238 + INA238
    assert _error(twice) == "drivers.toml: driver 'ina238': is declared twice"
    other = INA238.replace('name = "ina238"', 'name = "ina238b"')
    assert _error(INA238 + other) == (
        "drivers.toml: driver 'ina238b': parameter INA238 is also ina238's"
    )
    other = other.replace('parameter = "INA238"', 'parameter = "INA228"')
    assert _error(INA238 + other) == "drivers.toml: driver 'ina238b': order 30 is also ina238's"


def test_drivers_file_against_the_schema(specs):
    bad = INA238.replace('parameter = "INA238"', 'parameter = "INA239"')
    assert _error(bad, specs) == (
        "drivers.toml: driver 'ina238': parameter INA239 is not a parameter of the schema "
        "(did you mean INA238?)"
    )
    assert parse_drivers(INA238, "d.toml", specs).missing(specs)  # the others lack drivers
    unknown = INA238.replace("rate_hz = 10", 'rate_hz = 10\nsettings = { INA238_X = "volts" }')
    assert _error(unknown, specs).startswith(
        "drivers.toml: driver 'ina238': INA238 has no field 'volts' (its fields: bus._tag, "
    )


def test_every_bundled_driver_is_documented(drivers):
    """docs/drivers.md has a row per declared driver, with its facts (nothing rots)."""
    rows = {}
    for line in (REPO / "docs" / "drivers.md").read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if line.startswith("| `") and len(cells) == 9:
            rows[cells[0].strip("`")] = cells
    assert set(rows) == {d.name for d in drivers}
    for d in drivers:
        row = rows[d.name]
        assert row[1] == f"`{d.parameter}`" and row[3] == ", ".join(d.chips)
        assert (row[4], row[5]) == (f"0x{d.default_address:02X}", f"0x{d.devtype:02X}")
        assert (d.enabled_by or "-") in row[8]


def test_legacy_boot_starts_only_what_todays_px4_starts_unasked(drivers):
    # rc.sensors' probe block and the power monitors' launcher start on their own; a SENS_EN_*
    # switch starts the others, and a legacy boot has no switch set: an airspeed sensor on the
    # bench stays unstarted, while an HMC5883 is found by probing.
    bench = parse_bench(
        '[[device]]\nchip = "MS4525DO"\nbus = "i2c"\nbus_id = 1\naddress = 0x28\n\n'
        '[[device]]\nchip = "HMC5883"\nbus = "i2c"\nbus_id = 1\naddress = 0x1E\n',
        "bench.toml",
        drivers,
    )
    result = simbench.run(bench, drivers, None, duration=1.0, legacy=True, record_events=True)
    started = {e["driver"] for e in result.events or () if e["event"] == "legacy_start"}
    assert started == {d.name for d in drivers if d.started_by in ("probe", "launcher")}
    assert {"ist8310", "hmc5883", "iis2mdc", "ist8308", "qmc5883p", "ak09916", "ina238"} <= started
    assert not started & {"ms4525do", "sdp3x", "ll40ls", "lightware_laser_i2c", "batt_smbus"}
    running = {i.driver for i in result.instances if i.started_at is not None}
    assert running == {"hmc5883"}  # iis2mdc, lis3mdl at 0x1E read the wrong ID: quiet


def test_drivers_file_not_found_and_env(tmp_path, monkeypatch, capsys):
    with pytest.raises(DriversFileError, match=r"^.*nope\.toml: no such drivers file$"):
        load_drivers(tmp_path / "nope.toml")
    custom = tmp_path / "mine.toml"
    custom.write_text(INA238)
    monkeypatch.setenv("PX4PARAMS_DRIVERS", str(custom))
    assert [d.name for d in load_drivers()] == ["ina238"]
    assert main(["autostart", "script"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [
        f"# generated by px4params from {custom}: every autostart driver, in order",
        "ina238 auto",
    ]
    bad = tmp_path / "bad.toml"
    bad.write_text(INA238.replace("rate_hz = 10", "rate_hz = -1"))
    assert main(["autostart", "script", "--drivers", str(bad)]) == 1
    err = capsys.readouterr().err
    assert err == (
        f"px4params: error: {bad}: driver 'ina238': rate_hz -1 is out of range "
        "(expected > 0 and <= 10000)\n"
    )


def test_bus_kinds_are_the_bus_union(schema):
    variants = [f["name"] for f in schema.model["types"][schema.resolve("px.Bus")]["fields"]]
    assert sorted(BUS_KINDS) == sorted(variants)
    # PX4 device ID bus types.
    assert (BUS_KINDS["i2c"], BUS_KINDS["spi"], BUS_KINDS["dronecan"]) == (1, 2, 3)


def test_help_has_examples(capsys):
    for verb in ("script", "plan", "run"):
        assert main(["autostart", verb, "--help"]) == 0
        assert "example" in capsys.readouterr().out


def test_module_exports():
    assert set(autostart.__all__) >= {"configured", "plan", "script", "load_manifest"}


# -- each bus variant, each refusal, the plan's words (issue 40: autostart.py's survivors) --------

#: A driver of INA238 declared on every bus kind, so that each px.Bus variant is read as its
#: driver's ``auto`` reads it (the bundled ina238 accepts I2C only).
EVERY_BUS = INA238.replace(
    'buses = ["i2c"]', 'buses = ["i2c", "spi", "serial", "dronecan", "sim", "mavlink"]'
)


def _device_id(bus_type: int, bus: int, address: int, devtype: int) -> int:
    """PX4's DeviceStructure (src/lib/drivers/device/Device.hpp): bus_type 3 bits, bus 5,
    address 8, devtype 8, from the low bits up."""
    return bus_type | bus << 3 | address << 8 | devtype << 16


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("bus", "where", "location", "device_id"),
    [
        # px/I2c.1.0: bus_id, address; PX4's bus type 1
        ({"i2c": {"bus_id": 2, "address": 0x41}}, (2, 0x41), "I2C bus 2 address 0x41",
         _device_id(1, 2, 0x41, 0xD4)),
        # px/Spi.1.0: bus_id, chip_select (the device's "address"); bus type 2
        ({"spi": {"bus_id": 3, "chip_select": 5, "max_frequency": 0, "mode": 3}}, (3, 5),
         "SPI bus 3 chip select 5", _device_id(2, 3, 5, 0xD4)),
        # px/Dronecan.1.0: interface (the bus), node_id; bus type 3 (UAVCAN)
        ({"dronecan": {"node_id": 42, "interface": 1}}, (1, 42), "DroneCAN interface 1 node 42",
         _device_id(3, 1, 42, 0xD4)),
        # px/Simulation.1.0: instance only; bus type 4
        ({"sim": {"instance": 3}}, (0, 3), "simulation instance 3", _device_id(4, 0, 3, 0xD4)),
        # px/Serial.1.0: port (the bus), no address; bus type 5
        ({"serial": {"port": 2, "baudrate": 115200}}, (2, 0), "serial 2",
         _device_id(5, 2, 0, 0xD4)),
        # px/Mavlink.1.0: instance (the bus), system_id; bus type 6
        ({"mavlink": {"instance": 1, "system_id": 7, "component_id": 1}}, (1, 7),
         "MAVLink instance 1 system 7", _device_id(6, 1, 7, 0xD4)),
    ],
)  # fmt: skip
def test_each_bus_variant_is_read_from_its_own_fields(specs, bus, where, location, device_id):
    drivers = parse_drivers(EVERY_BUS, "d.toml", specs)
    value = {"p_version": 1, "bus": bus, "current": 200, "shunt": 0.0003}
    c = autostart.configured_value(value, drivers, "INA238", "INA238#0")
    assert (c.bus_kind, (c.bus_id, c.address)) == (next(iter(bus)), where)
    assert c.location == location
    assert c.device_id == device_id
    assert c.problems == () and c.startable
    assert c.settings == {"current": 200, "shunt": 0.0003}  # neither p_version nor bus
    assert c.as_dict() == {
        "instance": "INA238#0",
        "parameter": "INA238",
        "driver": "ina238",
        "bus": next(iter(bus)),
        "bus_id": where[0],
        "address": where[1],
        "location": location,
        "settings": {"current": 200, "shunt": 0.0003},
        "problems": [],
        "device_id": device_id,
    }


@pytest.mark.issue40
def test_a_value_without_one_bus_is_not_started(drivers):
    for value in ({"current": 1}, {"bus": {}}, 7):
        c = autostart.configured_value(value, drivers, "INA238", "INA238#3")
        assert (c.bus_kind, c.bus_id, c.address) == ("none", 0, 0)
        assert c.problems == ("its value has no bus",)
        assert c.location == "none 0" and c.device_id is None and not c.startable


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("address", "problems"),
    [
        (0x02, ("I2C address 0x02 is reserved (use 0x03..0x77)",)),
        (0x03, ()),  # the I2C specification's first and last general addresses
        (0x77, ()),
        (0x78, ("I2C address 0x78 is reserved (use 0x03..0x77)",)),
    ],
)
def test_reserved_i2c_addresses_are_refused(drivers, address, problems):
    value = {"bus": {"i2c": {"bus_id": 1, "address": address}}}
    c = autostart.configured_value(value, drivers, "INA238", "INA238#0")
    assert c.problems == problems
    assert c.startable is (problems == ())


@pytest.mark.issue40
def test_an_spi_bus_0_and_a_driver_without_autostart_are_refused(specs):
    drivers = parse_drivers(EVERY_BUS, "d.toml", specs)
    spi = {"bus": {"spi": {"bus_id": 0, "chip_select": 1}}}
    c = autostart.configured_value(spi, drivers, "INA238", "INA238#0")
    assert c.problems == ("spi bus_id is 0 (unset; buses are numbered from 1)",)
    # bus 0 of a kind numbered otherwise is no problem: DroneCAN's first interface is 0
    can = {"bus": {"dronecan": {"node_id": 10, "interface": 0}}}
    assert autostart.configured_value(can, drivers, "INA238", "INA238#0").problems == ()
    manual = parse_drivers(EVERY_BUS + "autostart = false\n", "d.toml", specs)
    ok = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}}
    c = autostart.configured_value(ok, manual, "INA238", "INA238#0")
    assert c.problems == ("driver ina238 does not autostart",)
    assert not c.startable


@pytest.mark.issue40
def test_a_shared_address_is_marked_on_i2c_and_spi_only(specs):
    drivers = parse_drivers(EVERY_BUS, "d.toml", specs)

    def at(name, bus):
        return autostart.configured_value({"bus": bus}, drivers, "INA238", name)

    found = [
        at("INA238#0", {"spi": {"bus_id": 1, "chip_select": 2}}),
        at("INA238#1", {"spi": {"bus_id": 1, "chip_select": 2}}),  # the same device
        at("INA238#2", {"spi": {"bus_id": 2, "chip_select": 2}}),  # another bus
        at("INA238#3", {"i2c": {"bus_id": 1, "address": 2}}),  # refused already: not taken
        at("INA238#4", {"i2c": {"bus_id": 1, "address": 2}}),
        at("INA238#5", {"sim": {"instance": 1}}),  # simulated devices share nothing
        at("INA238#6", {"sim": {"instance": 1}}),
    ]
    marked = autostart.shared_locations(found)
    assert [c.problems for c in marked] == [
        (),
        ("SPI bus 1 chip select 2 is already INA238#0's",),
        (),
        ("I2C address 0x02 is reserved (use 0x03..0x77)",),
        ("I2C address 0x02 is reserved (use 0x03..0x77)",),
        (),
        (),
    ]
    assert found[1].problems == ()  # a marked copy: the list given is left as it was


@pytest.mark.issue40
def test_the_plan_lists_every_declared_driver_then_the_undeclared_parameters(schema, specs):
    drivers = parse_drivers(INA238, "d.toml", specs)
    s = Store(schema)
    s.add("RM3100#1")
    s.add("AK09916#0")
    s.add("AK09916#2")
    entries = plan(s, drivers)
    assert [(e.driver and e.driver.name, e.parameter) for e in entries] == [
        ("ina238", "INA238"),
        (None, "AK09916"),  # undeclared, sorted by name, each once
        (None, "RM3100"),
    ]
    assert [c.instance for c in entries[1].instances] == ["AK09916#0", "AK09916#2"]
    assert entries[0].as_dict() == {
        "driver": "ina238",
        "parameter": "INA238",
        "autostart": True,
        "order": 30,
        "devtype": 0xD4,
        "instances": [],
    }
    assert entries[1].as_dict()["driver"] is None
    assert entries[1].as_dict()["autostart"] is False
    assert entries[1].as_dict()["order"] is None and entries[1].as_dict()["devtype"] is None


@pytest.mark.issue40
def test_a_driver_declared_for_a_parameter_the_schema_lacks_starts_nothing(schema, specs):
    drivers = parse_drivers(INA238.replace('"INA238"', '"FUTURE"', 1), "d.toml", None)
    s = Store(schema)
    s.add("INA238#0")
    found = configured(s, drivers)
    assert [(c.parameter, c.instance) for c in found] == [("INA238", "INA238#0")]


@pytest.mark.issue40
def test_plan_lines_word_by_word(schema, specs):
    drivers = parse_drivers(
        INA238
        + INA238.replace("ina238", "ina226").replace("INA238", "INA226").replace("30", "31")
        + "autostart = false\n",
        "d.toml",
        specs,
    )
    s = Store(schema)
    s.add("INA238#0")
    s.set("INA238#0.bus.i2c.bus_id", 1)
    s.set("INA238#0.bus.i2c.address", 0x45)
    s.set("INA238#0.current", 200)  # the shunt's default, 0.0003, is float16's 0.00029993
    s.add("AK09916#0")
    lines = plan_lines(plan(s, drivers))
    assert lines == [
        "ina238 auto  (order 30, parameter INA238, devtype 0xD4): 1 instance",
        "  INA238#0     I2C bus 1 address 0x45   current=200 shunt=0.00029993  "
        "device id 13911305 (0xD44509)",
        "(no driver) parameter AK09916: 1 instance(s)",
        "  AK09916#0    I2C bus 0 address 0x0C   rotation=0 odr=3  "
        "NOT STARTED: no driver declared for parameter AK09916",
        "nothing to start (1 drivers): ina226",
    ]
    s.add("INA226#0")
    s.add("INA226#1")
    lines = plan_lines(plan(s, drivers))
    assert "ina226 auto  (order 31, parameter INA226, devtype 0xD4, no autostart): 2 instances" in (
        lines
    )
    assert not any(line.startswith("nothing to start") for line in lines)


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("settings", "text"),
    [
        ({"shunt": 0.000300000014}, "shunt=0.0003"),  # float32's nearest, 5 significant digits
        ({"gain": 123456.7}, "gain=1.2346e+05"),
        ({"enabled": True, "off": False}, "enabled=true off=false"),
        ({"rows": [1, 2], "pair": {"a": 1}}, 'rows=[1,2] pair={"a":1}'),
        ({"n": 3}, "n=3"),
        ({}, ""),
    ],
)
def test_settings_are_shown_one_word_each(settings, text):
    assert autostart.format_settings(settings) == text


@pytest.mark.issue40
def test_a_location_beyond_a_device_id_has_none(schema, specs):
    """A device ID holds a 5-bit bus (PX4's DeviceStructure): a serial port numbered 101
    (TELEM 1, px/Serial.1.0's values) has no device ID, and the plan shows none."""
    drivers = parse_drivers(EVERY_BUS, "d.toml", specs)
    value = {"bus": {"serial": {"port": 101, "baudrate": 57600}}}
    c = autostart.configured_value(value, drivers, "INA238", "INA238#0")
    assert (c.location, c.device_id, c.problems) == ("serial 101", None, ())
    entry = autostart.PlanEntry(c.driver, "INA238", (c,))
    assert plan_lines([entry])[1] == "  INA238#0     serial 101"


# -- issue 40, the remainder of autostart.py's mutation run (mutveh2) ----------------------------


@pytest.mark.issue40
def test_a_refused_bus_kind_names_every_kind_the_driver_takes(drivers):
    """drivers.toml's lis3mdl takes I2C and SPI (PX4 starts lis3mdl with -I/-X or -s/-S): on a
    serial port it cannot start, and the problem lists both kinds it takes."""
    value = {"bus": {"serial": {"port": 2, "baudrate": 57600}}}
    c = autostart.configured_value(value, drivers, "LIS3MDL", "LIS3MDL#0")
    assert c.problems == ("bus kind serial is not accepted by lis3mdl (accepts: i2c, spi)",)


@pytest.mark.issue40
def test_the_plan_names_every_problem_of_an_instance(drivers):
    """An instance with two problems (no bus, no driver) says both on its NOT STARTED line."""
    c = autostart.configured_value({}, drivers, "NO_SUCH_DEVICE", "NO_SUCH_DEVICE#0")
    line = plan_lines([autostart.PlanEntry(None, "NO_SUCH_DEVICE", (c,))])[1]
    assert line.endswith(
        "NOT STARTED: its value has no bus; no driver declared for parameter NO_SUCH_DEVICE"
    )


@pytest.mark.issue40
def test_an_airframe_manifest_holds_classic_parameters(tmp_path, monkeypatch):
    """load_manifest reads an airframe with the parameter set 'px4params param' and 'px4params
    run' use: the structured ones and PX4's classic parameters (the bundled list when
    $PX4PARAMS_PARAMETERS_JSON names none)."""
    monkeypatch.delenv("PX4PARAMS_PARAMETERS_JSON", raising=False)
    frame = tmp_path / "frame.txt"
    frame.write_text("param add INA238#0\nparam set SYS_AUTOSTART 4001\n")
    store = load_manifest(None, frame)
    assert store.get("SYS_AUTOSTART") == 4001
    assert store.instances("INA238") == ["INA238#0"]


@pytest.mark.issue40
def test_an_airframe_error_is_raised_once_and_printed_nowhere(tmp_path, capsys):
    """The error of an airframe read for a manifest is the ManifestError's one line (the CLI
    prints it once): load_manifest itself writes nothing to stdout or stderr."""
    frame = tmp_path / "frame.txt"
    frame.write_text("param add INA238#0\nparam set INA238#0[4] banana\n")
    with pytest.raises(ManifestError) as err:
        load_manifest(None, frame)
    assert str(err.value).startswith(f"{frame}:2: ")
    assert capsys.readouterr() == ("", "")


@pytest.mark.issue40
def test_an_airframe_manifest_holds_the_parameters_of_extra_dsdl_folders(tmp_path):
    """With --dsdl DIR, an airframe's manifest has DIR's instanced types as parameters, as a
    store opened with the same folders has (docs/codec.md: a type with @max_instances in a
    namespace folder acme is a parameter PITOT#0..)."""
    acme = tmp_path / "acme"
    acme.mkdir()
    (acme / "Pitot.1.0.dsdl").write_text(
        "# Pitot tube\n# @max_instances 2\n\nuint4 p_version\nfloat16 scale\n@sealed\n"
    )
    frame = tmp_path / "frame.txt"
    frame.write_text("param add PITOT#0\nparam add INA238#0\n")
    store = load_manifest(None, frame, [str(acme)])
    assert store.instances("PITOT") == ["PITOT#0"]
    assert store.instances("INA238") == ["INA238#0"]


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            'parameter = "INA238"',
            'parameter = "ina238"',
            "d.toml: driver 'ina238': parameter 'ina238' is not an upper-case parameter name "
            "like INA238",
        ),
        (
            'chip = "INA238"',
            'chip = "INA-238"',
            "d.toml: driver 'ina238': chip 'INA-238' is not a chip name like INA238",
        ),
    ],
)
def test_a_declaration_with_a_bad_parameter_or_chip_name_is_named(specs, old, new, message):
    """PX4 parameter names are upper case (INA238, SENS_EN_INA238); chip names are drv_sensor.h's
    words (letters, digits, _): a declaration breaking either is refused naming it."""
    with pytest.raises(DriversFileError) as err:
        parse_drivers(INA238.replace(old, new), "d.toml", specs)
    assert str(err.value) == message
