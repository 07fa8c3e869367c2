"""The driver declarations (``px4params.vehicle.drivers``), in-process: each key of the module's
documentation read as it says (ranges inclusive at both ends, the optional keys' defaults), every
refusal as its whole one-line message, and the lookups the startup script, the plan and the
bench use. The bus kinds' numbers are PX4's ``DeviceBusType`` (src/lib/drivers/device/Device.hpp:
UNKNOWN 0, I2C 1, SPI 2, UAVCAN 3, SIMULATION 4, SERIAL 5, MAVLINK 6)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from px4params.store.spec import ParamSpec, parameter_specs
from px4params.vehicle import drivers as drivers_module
from px4params.vehicle.drivers import (
    BUS_KINDS,
    DEFAULT_DRIVERS,
    Driver,
    DriversFileError,
    load_drivers,
    parse_drivers,
)

pytestmark = pytest.mark.issue40

#: One declaration with the required keys only (an I2C driver: default_address too).
INA238 = """
[[driver]]
name = "ina238"
parameter = "INA238"
chip = "INA238"
order = 30
buses = ["i2c"]
default_address = 0x45
devtype = 0xD4
rate_hz = 10
"""

#: The same with every optional key.
EVERY_KEY = (
    INA238
    + """\
autostart = false
chip_id_register = 0x3F
chip_id = 0x238
description = "power monitor, 85 V"
kind = "power monitor"
also_chips = ["INA239", "ina237"]
started_by = "parameter"
enabled_by = "SENS_EN_INA238"
enabled_values = [1, 3]
switch_field = "p_version"
settings = { INA238_CURRENT = "current", INA238_SHUNT = "shunt" }
probe = "reads MANUFACTURER_ID"
sources = ["src/drivers/power_monitor/ina238/ina238.cpp"]
"""
)

BUSES = "i2c, spi, serial, dronecan, sim, mavlink"


@pytest.fixture(scope="module")
def specs(schema):
    return parameter_specs(schema)


def refusal(text: str, specs=None) -> str:
    with pytest.raises(DriversFileError) as e:
        parse_drivers(text, "drivers.toml", specs)
    return str(e.value)


def one(text: str, specs=None) -> Driver:
    (driver,) = parse_drivers(text, "d.toml", specs)
    return driver


# -- what is read -------------------------------------------------------------------------------


def test_every_key_is_read_into_its_field(specs) -> None:
    d = one(EVERY_KEY, specs)
    assert (d.name, d.parameter, d.chip, d.autostart, d.order) == (
        "ina238",
        "INA238",
        "INA238",
        False,
        30,
    )
    assert (d.buses, d.default_address, d.devtype) == (("i2c",), 0x45, 0xD4)
    assert (d.chip_id_register, d.chip_id) == (0x3F, 0x238)
    assert d.rate_hz == 10.0 and isinstance(d.rate_hz, float)
    assert (d.description, d.kind, d.probe) == (
        "power monitor, 85 V",
        "power monitor",
        "reads MANUFACTURER_ID",
    )
    assert d.also_chips == ("INA239", "ina237")
    assert d.chips == ("INA238", "INA239", "INA237")  # drv_sensor.h's names are upper case
    assert (d.started_by, d.enabled_by, d.enabled_values) == (
        "parameter",
        "SENS_EN_INA238",
        (1, 3),
    )
    assert d.switch_field == "p_version"
    assert d.settings == {"INA238_CURRENT": "current", "INA238_SHUNT": "shunt"}
    assert d.sources == ("src/drivers/power_monitor/ina238/ina238.cpp",)


def test_the_optional_keys_default_as_documented() -> None:
    """autostart true; no chip ID read; started_by "probe"; without enabled_values, values
    above 0 (PX4's `param greater <switch> 0`); the rest empty."""
    d = one(INA238)
    assert d.autostart is True
    assert (d.chip_id_register, d.chip_id) == (None, None)
    assert (d.description, d.kind, d.probe, d.also_chips, d.sources) == ("", "", "", (), ())
    assert (d.started_by, d.enabled_by, d.enabled_values, d.switch_field) == (
        "probe",
        None,
        (),
        None,
    )
    assert d.settings == {} and d.chips == ("INA238",)
    assert [d.starts_on(v) for v in (0, 1, 2, -1, 0.5)] == [False, True, True, False, True]


def test_a_driver_made_in_code_has_the_same_defaults() -> None:
    """A Driver built with the required fields only (as the migration builds one for a type
    without a declaration) defaults like an omitted key."""
    d = Driver(
        name="probe_one",
        parameter="PROBE_ONE",
        chip="PROBE1",
        autostart=True,
        order=0,
        buses=("i2c",),
        default_address=None,
        devtype=0,
        chip_id_register=None,
        chip_id=None,
        rate_hz=1.0,
    )
    assert (d.description, d.kind, d.probe, d.also_chips, d.sources) == ("", "", "", (), ())
    assert (d.started_by, d.enabled_by, d.enabled_values, d.switch_field) == (
        "probe",
        None,
        (),
        None,
    )
    assert d.settings == {} and d.chips == ("PROBE1",)
    assert d.starts_on(7) and not d.starts_on(0)
    other = Driver(**{**d.__dict__, "settings": {}})
    other.settings["X"] = "y"  # type: ignore[index]  # each driver its own table
    assert d.settings == {}


def test_only_the_listed_values_start_a_driver_that_lists_them() -> None:
    d = one(EVERY_KEY)
    assert [d.starts_on(v) for v in (0, 1, 2, 3, 4)] == [False, True, False, True, False]
    # written as the board table writes a script's `param compare` tests; no switch, no test
    assert d.switch_test == "SENS_EN_INA238 == 1 or SENS_EN_INA238 == 3"
    assert one(INA238).switch_test == ""


def test_the_startup_lines_name_the_module() -> None:
    d = one(INA238)
    assert (d.auto_line, d.legacy_line) == ("ina238 auto", "ina238 -X -q start")


@pytest.mark.parametrize(
    ("old", "new", "field", "value"),
    [
        ("order = 30", "order = 0", "order", 0),
        ("order = 30", "order = 1000000", "order", 1_000_000),
        ("default_address = 0x45", "default_address = 0", "default_address", 0),
        ("default_address = 0x45", "default_address = 127", "default_address", 127),
        ("devtype = 0xD4", "devtype = 0", "devtype", 0),
        ("devtype = 0xD4", "devtype = 255", "devtype", 255),
        ("rate_hz = 10", "rate_hz = 10000", "rate_hz", 10000.0),
        ("rate_hz = 10", "rate_hz = 0.001", "rate_hz", 0.001),
        ("rate_hz = 10", "rate_hz = 9999.5", "rate_hz", 9999.5),
        ("rate_hz = 10", "rate_hz = 10\nchip_id_register = 0\nchip_id = 0", "chip_id", 0),
        (
            "rate_hz = 10",
            "rate_hz = 10\nchip_id_register = 255\nchip_id = 65535",
            "chip_id_register",
            255,
        ),
        ("rate_hz = 10", "rate_hz = 10\nchip_id_register = 255\nchip_id = 65535", "chip_id", 65535),
    ],
)
def test_the_ends_of_each_range_are_taken(old: str, new: str, field: str, value: object) -> None:
    assert getattr(one(INA238.replace(old, new)), field) == value


def test_a_driver_without_i2c_needs_no_address() -> None:
    text = INA238.replace('buses = ["i2c"]', 'buses = ["spi", "sim"]')
    d = one(text.replace("default_address = 0x45\n", ""))
    assert (d.buses, d.default_address) == (("spi", "sim"), None)
    assert one(text).default_address == 0x45  # given anyway: kept


@pytest.mark.parametrize("started_by", ["probe", "launcher"])
def test_each_way_of_starting_without_a_switch_is_taken(started_by: str) -> None:
    assert one(INA238 + f'started_by = "{started_by}"\n').started_by == started_by


def test_the_bus_kinds_are_px4_s_device_bus_types() -> None:
    assert BUS_KINDS == {"i2c": 1, "spi": 2, "serial": 5, "dronecan": 3, "sim": 4, "mavlink": 6}
    assert ", ".join(BUS_KINDS) == BUSES  # the union's tag order, which messages list


# -- every refusal, whole -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "order = 30",
            "order = 30\nspeed = 3",
            "unknown key 'speed' (expected: name, parameter, chip, order, buses, devtype, rate_hz, "
            "autostart, default_address, chip_id_register, chip_id, description, kind, "
            "also_chips, started_by, enabled_by, enabled_values, switch_field, settings, probe, "
            "sources)",
        ),
        ("order = 30\n", "", "missing key 'order'"),
        ("rate_hz = 10\n", "", "missing key 'rate_hz'"),
        ('parameter = "INA238"', "parameter = 5", "parameter must be a string, not 5"),
        ('chip = "INA238"', 'chip = "INA 238"', "chip 'INA 238' is not a chip name like INA238"),
        ('chip = "INA238"', "chip = 238", "chip must be a string, not 238"),
        ("order = 30", "order = 30\nautostart = 1", "autostart must be true or false, not 1"),
        ("order = 30", "order = -1", "order -1 is out of range 0..1000000"),
        ("order = 30", "order = 1000001", "order 1000001 is out of range 0..1000000"),
        ("order = 30", "order = true", "order must be an integer, not True"),
        (
            'buses = ["i2c"]',
            "buses = []",
            f"buses must be a non-empty list of bus kinds ({BUSES})",
        ),
        (
            'buses = ["i2c"]',
            'buses = "i2c"',
            f"buses must be a non-empty list of bus kinds ({BUSES})",
        ),
        (
            'buses = ["i2c"]',
            'buses = ["i2c", "can"]',
            f"unknown bus kind 'can' (expected one of: {BUSES})",
        ),
        ('buses = ["i2c"]', "buses = [1]", f"unknown bus kind 1 (expected one of: {BUSES})"),
        (
            'buses = ["i2c"]',
            'buses = ["i2c", "spi", "i2c"]',
            "buses lists a kind twice: ['i2c', 'spi', 'i2c']",
        ),
        (
            "default_address = 0x45",
            "default_address = 128",
            "default_address 128 is out of range 0..127, 0x00..0x7F",
        ),
        (
            "default_address = 0x45",
            "default_address = -1",
            "default_address -1 is out of range 0..127, 0x00..0x7F",
        ),
        (
            "default_address = 0x45\n",
            "",
            "missing key 'default_address' (required for an i2c driver)",
        ),
        ("devtype = 0xD4", "devtype = 256", "devtype 256 is out of range 0..255, 0x00..0xFF"),
        ("devtype = 0xD4", "devtype = false", "devtype must be an integer, not False"),
        ("rate_hz = 10", "rate_hz = true", "rate_hz must be a number, not True"),
        ("rate_hz = 10", 'rate_hz = "10"', "rate_hz must be a number, not '10'"),
        (
            "rate_hz = 10",
            "rate_hz = 0",
            "rate_hz 0 is out of range (expected > 0 and <= 10000)",
        ),
        (
            "rate_hz = 10",
            "rate_hz = 10000.5",
            "rate_hz 10000.5 is out of range (expected > 0 and <= 10000)",
        ),
        (
            "rate_hz = 10",
            "rate_hz = -0.5",
            "rate_hz -0.5 is out of range (expected > 0 and <= 10000)",
        ),
        ("rate_hz = 10", "rate_hz = 10\ndescription = 3", "description must be a string, not 3"),
        ("rate_hz = 10", "rate_hz = 10\nkind = []", "kind must be a string, not []"),
        ("rate_hz = 10", "rate_hz = 10\nprobe = false", "probe must be a string, not False"),
        (
            "rate_hz = 10",
            "rate_hz = 10\nchip_id = 0x238",
            "chip_id_register and chip_id go together (or neither, for a probe that reads no ID)",
        ),
        (
            "rate_hz = 10",
            "rate_hz = 10\nchip_id_register = 0x3F",
            "chip_id_register and chip_id go together (or neither, for a probe that reads no ID)",
        ),
        (
            "rate_hz = 10",
            "rate_hz = 10\nchip_id_register = 256\nchip_id = 1",
            "chip_id_register 256 is out of range 0..255, 0x00..0xFF",
        ),
        (
            "rate_hz = 10",
            "rate_hz = 10\nchip_id_register = 1\nchip_id = 65536",
            "chip_id 65536 is out of range 0..65535, 0x00..0xFFFF",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nalso_chips = ["SDP32", "SDP-33"]',
            "also_chips: 'SDP-33' is not a chip name like SDP32",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nalso_chips = "SDP32"',
            "also_chips must be a list of strings, not 'SDP32'",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nalso_chips = ["SDP32", 33]',
            "also_chips must be a list of strings, not ['SDP32', 33]",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nstarted_by = "magic"',
            "started_by 'magic' is not one of: probe, launcher, parameter",
        ),
        (
            "rate_hz = 10",
            "rate_hz = 10\nenabled_by = 1",
            "enabled_by 1 is not an upper-case parameter name like SENS_EN_SDP3X",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nenabled_by = "sens_en_ina238"',
            "enabled_by 'sens_en_ina238' is not an upper-case parameter name like SENS_EN_SDP3X",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nstarted_by = "parameter"',
            'started_by = "parameter" needs enabled_by (the parameter that starts it today)',
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nenabled_by = "SENS_EN_X"\nenabled_values = 1',
            "enabled_values must be a list of non-zero integers, not 1",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nenabled_by = "SENS_EN_X"\nenabled_values = [1, true]',
            "enabled_values must be a list of non-zero integers, not [1, True]",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nenabled_by = "SENS_EN_X"\nenabled_values = [1, 0]',
            "enabled_values must be a list of non-zero integers, not [1, 0]",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nenabled_by = "SENS_EN_X"\nenabled_values = [1.5]',
            "enabled_values must be a list of non-zero integers, not [1.5]",
        ),
        ("rate_hz = 10", "rate_hz = 10\nenabled_values = [2]", "enabled_values needs enabled_by"),
        (
            "rate_hz = 10",
            "rate_hz = 10\nsettings = 3",
            'settings must be a table of legacy parameter = "field.path"',
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nsettings = { ina238_c = "current" }',
            'settings must be a table of legacy parameter = "field.path"',
        ),
        (
            "rate_hz = 10",
            "rate_hz = 10\nsettings = { INA238_C = 3 }",
            'settings must be a table of legacy parameter = "field.path"',
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nswitch_field = "current"',
            "switch_field must be a field name, with enabled_by",
        ),
        (
            "rate_hz = 10",
            'rate_hz = 10\nenabled_by = "SENS_EN_X"\nswitch_field = 3',
            "switch_field must be a field name, with enabled_by",
        ),
        (
            "rate_hz = 10",
            "rate_hz = 10\nsources = ['a', 1]",
            "sources must be a list of strings, not ['a', 1]",
        ),
    ],
)
def test_a_refused_declaration_is_named_and_said_whole(old: str, new: str, message: str) -> None:
    assert old in INA238
    assert refusal(INA238.replace(old, new, 1)) == f"drivers.toml: driver 'ina238': {message}"


@pytest.mark.parametrize(
    ("name", "shown"), [('"INA-238"', "'INA-238'"), ('"Ina238"', "'Ina238'"), ("238", "238")]
)
def test_a_declaration_without_a_module_name_is_named_by_its_place(name: str, shown: str) -> None:
    """Until a declaration has a usable name, its place in the file names it (the first is #1)."""
    second = INA238.replace('name = "ina238"', f"name = {name}").replace("order = 30", "order = 31")
    assert refusal(INA238 + second) == (
        f"drivers.toml: driver #2: name {shown} is not a PX4 module name (lower case letters, "
        "digits, _)"
    )
    broken = second.replace("rate_hz = 10", "rate_hz = 0")
    assert refusal(broken).startswith("drivers.toml: driver #1: ")
    nameless = INA238.replace('name = "ina238"\n', "")
    assert refusal(nameless) == "drivers.toml: driver #1: missing key 'name'"


def test_a_declaration_against_the_schema_is_held_to_its_parameters_and_fields(specs) -> None:
    assert refusal(INA238.replace('"INA238"', '"QQQQ"', 1), specs) == (
        "drivers.toml: driver 'ina238': parameter QQQQ is not a parameter of the schema"
    )
    leaves = (
        "bus._tag, bus.i2c.address, bus.i2c.bus_id, bus.i2c.p_version, current, p_version, shunt"
    )
    switch = INA238 + 'enabled_by = "SENS_EN_INA238"\nswitch_field = "model"\n'
    assert refusal(switch, specs) == (
        f"drivers.toml: driver 'ina238': INA238 has no field 'model' (its fields: {leaves})"
    )
    setting = INA238 + 'settings = { INA238_C = "current", INA238_V = "volts" }\n'
    assert refusal(setting, specs) == (
        f"drivers.toml: driver 'ina238': INA238 has no field 'volts' (its fields: {leaves})"
    )
    assert one(EVERY_KEY, specs).switch_field == "p_version"  # every named field exists


def test_a_shared_parameter_cannot_be_started(specs) -> None:
    ina = next(s for s in specs if s.name == "INA238")
    shared = ParamSpec("INA238_COMMON", ina.data_type, None)  # @param without @max_instances
    text = INA238.replace('parameter = "INA238"', 'parameter = "INA238_COMMON"')
    assert refusal(text, [*specs, shared]) == (
        "drivers.toml: driver 'ina238': parameter INA238_COMMON is shared (has no instances to "
        "start)"
    )


# -- the declarations of a file -----------------------------------------------------------------


def _declared(name: str, parameter: str, order: int, extra: str = "") -> str:
    return (
        INA238.replace('"ina238"', f'"{name}"')
        .replace('parameter = "INA238"', f'parameter = "{parameter}"')
        .replace('chip = "INA238"', f'chip = "{parameter}"')
        .replace("order = 30", f"order = {order}")
        + extra
    )


def test_the_declarations_are_in_start_order_and_looked_up_by_name_and_parameter(specs) -> None:
    text = (
        _declared("ina238", "INA238", 30, 'also_chips = ["SHARED9"]\n')
        + _declared("ina226", "INA226", 10, "autostart = false\n")
        + _declared("ina228", "INA228", 20, 'also_chips = ["shared9", "INA238"]\n')
    )
    drivers = parse_drivers(text, "mine.toml", specs)
    assert drivers.source == "mine.toml" and len(drivers) == 3
    assert [d.name for d in drivers] == ["ina226", "ina228", "ina238"]
    assert drivers["ina228"].order == 20
    with pytest.raises(KeyError):
        drivers["ina229"]
    assert drivers.for_parameter("INA238") is drivers["ina238"]
    assert drivers.for_parameter("ina238") is None and drivers.for_parameter("AK09916") is None
    assert [d.name for d in drivers.autostart()] == ["ina228", "ina238"]
    # the first in start order declaring a chip answers for it
    chips = {chip: d.name for chip, d in drivers.chips().items()}
    assert chips == {
        "INA226": "ina226",
        "INA228": "ina228",
        "SHARED9": "ina228",
        "INA238": "ina228",
    }
    assert drivers.switches() == {}
    missing = drivers.missing(specs)
    assert "AK09916" in missing and not {"INA226", "INA228", "INA238"} & set(missing)


def test_a_switch_lists_every_driver_it_starts_in_order() -> None:
    on = 'started_by = "parameter"\nenabled_by = "SENS_EN_MB12XX"\n'
    lidar = 'started_by = "parameter"\nenabled_by = "SENS_EN_LL40LS"\n'
    text = (
        _declared("mb12xx", "MB12XX", 5, on)
        + _declared("ina238", "INA238", 1)
        + _declared("srf02", "SRF02", 2, on)
        + _declared("ll40ls", "LL40LS", 3, lidar)
    )
    switches = parse_drivers(text).switches()
    assert {k: [d.name for d in v] for k, v in switches.items()} == {
        "SENS_EN_MB12XX": ["srf02", "mb12xx"],
        "SENS_EN_LL40LS": ["ll40ls"],
    }


def test_a_shared_parameter_needs_no_driver(specs) -> None:
    ina = next(s for s in specs if s.name == "INA238")
    shared = ParamSpec("INA238_COMMON", ina.data_type, None)
    drivers = parse_drivers(INA238)
    assert drivers.missing([ina, shared]) == []
    assert drivers.missing([shared, ParamSpec("INA999", ina.data_type, 4)]) == ["INA999"]


# -- the file -----------------------------------------------------------------------------------


def test_the_file_is_the_argument_else_the_environment_s_else_the_bundled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    mine, theirs = tmp_path / "mine.toml", tmp_path / "theirs.toml"
    mine.write_text(INA238)
    theirs.write_text(INA238.replace('"ina238"', '"ina238x"'))
    monkeypatch.setenv("PX4PARAMS_DRIVERS", str(theirs))
    assert [d.name for d in load_drivers(mine)] == ["ina238"]
    assert load_drivers(mine).source == str(mine)
    assert [d.name for d in load_drivers()] == ["ina238x"]
    monkeypatch.setenv("PX4PARAMS_DRIVERS", "")  # empty: as if unset
    bundled = load_drivers()
    assert bundled.source == str(DEFAULT_DRIVERS) and bundled["ina238"].parameter == "INA238"
    assert DEFAULT_DRIVERS.name == "drivers.toml" and DEFAULT_DRIVERS.parent.name == "data"


def test_a_file_that_cannot_be_read_is_named_with_why(tmp_path: Path) -> None:
    folder = tmp_path / "drivers.toml"
    folder.mkdir()
    with pytest.raises(DriversFileError) as e:
        load_drivers(folder)
    assert str(e.value) == f"{folder}: cannot read: is a folder, not a file"
    latin = tmp_path / "latin.toml"
    latin.write_bytes(INA238.encode() + b'description = "caf\xe9"\n')
    with pytest.raises(DriversFileError) as e:
        load_drivers(latin)
    at = len(INA238.encode()) + len('description = "caf')
    assert str(e.value) == f"{latin}: not a text file: byte 0xE9 at offset {at} is not UTF-8"


def test_a_file_that_is_not_toml_or_holds_other_tables_is_refused() -> None:
    message = refusal("[[driver]\n")
    assert message.startswith("drivers.toml: not TOML: ") and "\n" not in message
    assert refusal("driver = []\n") == "drivers.toml: no [[driver]] tables"
    assert refusal(INA238 + "[[drivers]]\nname = 'x'\n") == (
        "drivers.toml: unknown top-level key 'drivers' (expected [[driver]] tables)"
    )


def test_a_declaration_cannot_be_changed_once_read() -> None:
    """The declarations of a file are shared by every caller (the script, the plan, the bench,
    the page): a Driver is frozen."""
    d = one(INA238)
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.order = 1  # type: ignore[misc]
    assert d.order == 30 and d == one(INA238)


def test_every_exported_name_is_defined() -> None:
    """``from px4params.vehicle.drivers import *`` gives each name of ``__all__``."""
    namespace: dict[str, object] = {}
    exec("from px4params.vehicle.drivers import *", namespace)
    assert set(drivers_module.__all__) <= set(namespace)
    assert {"BUS_KINDS", "Driver", "Drivers", "DriversFileError", "load_drivers"} <= set(
        drivers_module.__all__
    )


def test_declarations_given_as_text_are_named_as_such() -> None:
    """Without a file name, messages and ``source`` call the text ``<drivers>``."""
    assert parse_drivers(INA238).source == "<drivers>"
    with pytest.raises(DriversFileError) as e:
        parse_drivers("")
    assert str(e.value) == "<drivers>: no [[driver]] tables"


@pytest.mark.parametrize(
    ("switch", "driver"),
    [("SENS_EN_TRANGER", "teraranger"), ("SENS_EN_SF1XX", "lightware_laser_i2c"),
     ("SENS_EN_MB12XX", "mb12xx"), ("SENS_EN_AUAVX", "auav")],
)  # fmt: skip
def test_a_switch_px4_tests_with_param_greater_starts_on_values_above_0_only(
    switch: str, driver: str
) -> None:
    # rc.sensors: `if param greater -s SENS_EN_TRANGER 0` (the board table's "> 0"): -1 fails
    # the test as 0 does; 1 and a model number pass it
    from px4params.vehicle.boards import load_boards

    board = load_boards().by_name("px4_fmu-v6x")
    assert board is not None
    (row, *_) = [r for r in board.switches if r.param == switch]
    assert row.when == f"{switch} > 0"
    declared = load_drivers()[driver]
    assert declared.switch_test == row.when
    assert [declared.starts_on(v) for v in (-2, -1, 0, 1, 6)] == [False, False, False, True, True]
