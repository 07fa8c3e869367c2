"""``px4params.migrate.build``: the proposal's tables of PX4 facts (renamed modules and chips,
switches that are not drivers, start-line options the types have no field for, the sensor
kinds of log topics), each checked against what PX4 does, on configurations written here.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import shared_data
from px4params import migrate
from px4params.migrate.config import OldConfig
from px4params.vehicle import devid
from shared_data import shared_file

pytestmark = pytest.mark.issue40


def config(
    params: dict[str, int | float] | None = None,
    console: str | None = None,
    published: list[tuple[str, int, int]] | None = None,
) -> OldConfig:
    """A log's configuration as the reader gives it (PX4 1.11: the era of the renamed names)."""
    return OldConfig(
        "test.ulg", "ULog", dict(params or {}), version=(1, 11, 2), console=console,
        published=list(published or []),
    )  # fmt: skip


def test_thermal_control_is_reported_with_px4s_meaning_of_each_value() -> None:
    # SENS_EN_THERMAL is thermal control, not a driver: each value is reported with the
    # meaning PX4's parameter metadata gives it (a real parameters.json, read where it is)
    path = shared_file(shared_data.PARAMETERS_JSON)
    metadata = json.loads(path.read_text())
    rows = metadata.get("parameters", metadata)
    (thermal,) = [p for p in rows if p["name"] == "SENS_EN_THERMAL"]
    assert {v["value"] for v in thermal["values"]} == {-1, 0, 1}
    for entry in thermal["values"]:
        value, meaning = entry["value"], entry["description"]
        proposal = migrate.migrate(config({"SENS_EN_THERMAL": value}), table="px4-v1.11")
        assert proposal.not_carried == [
            f"SENS_EN_THERMAL = {value} ({meaning[0].lower()}{meaning[1:]}): not a driver "
            "switch; it stays a classic parameter"
        ]
        assert proposal.disabled == [] and proposal.instances == []


@pytest.mark.parametrize(("switch", "param"), [("SENS_EN_INA226", "INA226"),
                                               ("SENS_EN_INA228", "INA228")])  # fmt: skip
def test_a_power_monitors_battery_index_nothing_names_is_said_unknown(
    switch: str, param: str
) -> None:
    # PX4 1.11's rc.sensors starts no power monitor: a board's script does, each with its own
    # battery index (`-t 1` on bus 1, `-t 2` on bus 2, `-t 3` or `-t 1` on bus 3: the board
    # table's rows). With no board named and no boot console, nothing says which; the type has
    # no field for it either way, and the note says the index is not known
    proposal = migrate.migrate(config({switch: 1}), table="px4-v1.11")
    (inst,) = proposal.instances
    assert inst.name == f"{param}#0"
    assert inst.notes == [
        "today's start line also sets a battery index (-t), which nothing here names (without "
        f"-t the driver uses 1): {param} has no field for it"
    ]


@pytest.mark.parametrize(
    ("module", "param", "address"),
    # PX4 1.13 renamed the airspeed drivers (ms4525_airspeed -> ms4525do, ...); a 1.11 boot
    # console names the old module, and the driver is today's (at its default address, which
    # a 1.11 console line does not print)
    [("ms4525_airspeed", "MS4525DO", 0x28), ("ms5525_airspeed", "MS5525DSO", 0x76),
     ("sdp3x_airspeed", "SDP3X", 0x21)],
)  # fmt: skip
def test_an_airspeed_driver_by_its_name_before_px4_1_13(
    module: str, param: str, address: int
) -> None:
    console = f"{module} #0 on I2C bus 2 (external, equal to '-b 1')\n"
    proposal = migrate.migrate(config(console=console), table="px4-v1.11")
    assert [(i.name, i.values["bus.i2c.bus_id"], i.values["bus.i2c.address"])
            for i in proposal.instances] == [(f"{param}#0", 2, address)]  # fmt: skip
    assert not [n for n in proposal.not_carried if module in n], proposal.not_carried


def test_an_ms5525_of_px4_1_11_is_todays_ms5525dso() -> None:
    # PX4 1.11's drv_sensor.h: 0x48 is DRV_DIFF_PRESS_DEVTYPE_MS5525, which 1.13 renamed
    # MS5525DSO (the driver's chip): the airspeed topic's device is proposed as MS5525DSO
    ms5525 = devid.encode("i2c", 2, 0x76, 0x48)
    proposal = migrate.migrate(
        config(published=[("differential_pressure", 0, ms5525)]), table="px4-v1.11"
    )
    assert [(i.name, i.values["bus.i2c.bus_id"], i.values["bus.i2c.address"])
            for i in proposal.instances] == [("MS5525DSO#0", 2, 0x76)]  # fmt: skip


def test_a_barometer_topic_of_an_unknown_chip_is_taken_as_the_boards() -> None:
    # a device of a devtype the table does not know, published on sensor_baro: a barometer,
    # which sits on the flight controller (started by the board's script), not a sensor to
    # carry over
    unknown = devid.encode("i2c", 4, 0x77, 0xFE)
    proposal = migrate.migrate(config(published=[("sensor_baro", 0, unknown)]), table="px4-v1.11")
    assert proposal.instances == [] and proposal.not_carried == []
    (line,) = proposal.not_in_manifest
    assert line.startswith(f"sensor_baro 0 = {unknown}: ")
    assert line.endswith(": a barometer: assumed started by the board's script")


@pytest.mark.parametrize(
    "topic",
    ["sensor_accel", "sensor_gyro", "sensor_mag", "sensor_baro", "differential_pressure",
     "distance_sensor"],
)  # fmt: skip
def test_one_device_on_two_instances_of_a_topic_is_reported_once(topic: str) -> None:
    # issue 34, defect 10: one device in two slots of a kind is reported once, both named
    icm20602 = devid.encode("spi", 1, 0, 0x38)
    proposal = migrate.migrate(
        config(published=[(topic, 0, icm20602), (topic, 1, icm20602)]), table="current"
    )
    (line,) = proposal.not_in_manifest
    assert line.startswith(f"{topic} 0, {topic} 1 = {icm20602}: ")
    assert line.endswith(f"; {topic} 0 and {topic} 1 hold the same device (reported once)")


def today(params: dict[str, int | float], console: str | None = None) -> OldConfig:
    """A PX4 1.15 log's parameters (and boot console), read with today's devtype table."""
    return OldConfig("test.ulg", "ULog", dict(params), version=(1, 15, 0), console=console)


#: What the report says of Pixhawk 6X's second launcher bus (PX4's boards/px4/fmu-v6x/init/
#: rc.board_sensors, v1.18 and main: `if [ $HAVE_PM2 = yes ]` around `i2c_launcher start -b 2`
#: on line 64; the script sets HAVE_PM2 yes on line 5, and no when the hardware manifest says
#: MFT_PM2 0).
ONLY_WITH_PM2 = (
    "bus 2 only where $HAVE_PM2 == yes (PX4/PX4-Autopilot boards/px4/fmu-v6x/init/"
    "rc.board_sensors:5 at main (branch main, bb59c637cd, 2026-08-13) sets "
    "HAVE_PM2 yes; line 8: no where mft MFT_PM2 == 0 (the board's hardware manifest, which the "
    "parameters do not tell)) "
    "(PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors:64 at main (branch main, "
    "bb59c637cd, 2026-08-13))"
)


def test_a_driver_switch_without_a_bundled_type_stays_classic() -> None:
    proposal = migrate.migrate(today({"SENS_EN_FOOBAR": 1, "SENS_EN_INA238": 1}), table="current")
    assert [i.name for i in proposal.instances] == ["INA238#0"]
    assert proposal.not_carried == [
        "SENS_EN_FOOBAR = 1: no bundled parameter type FOOBAR; the driver stays enabled by this "
        "classic parameter, outside the manifest"
    ]


def test_a_model_switch_and_a_setting_out_of_its_fields_range() -> None:
    # SENS_EN_SF1XX's value is the rangefinder's model (PX4's lightware_laser_i2c parameters:
    # 6 is the LW20/c): it goes into the type's model field; SF1XX_ROT is a Rotation (0..40 in
    # the type's @min/@max): 99 is not carried, and says why, 40 is
    proposal = migrate.migrate(
        today({"SENS_EN_SF1XX": 6, "SF1XX_ROT": 99, "SF1XX_MODE": 1}), table="current"
    )
    (inst,) = proposal.instances
    assert inst.name == "SF1XX#0"
    assert inst.values == {"bus.i2c.bus_id": 1, "bus.i2c.address": 0x66, "model": 6, "mode": 1}
    assert proposal.not_carried == ["SF1XX_ROT = 99: SF1XX#0.rotation must be 0..40"]
    proposal = migrate.migrate(today({"SENS_EN_SF1XX": 6, "SF1XX_ROT": 40}), table="current")
    assert proposal.instances[0].values["rotation"] == 40 and proposal.not_carried == []


def test_a_setting_given_as_a_float_zero_where_zero_is_in_range_is_carried() -> None:
    # A REAL32 line of SF1XX_MODE (a .params of another release): 0.0 is the mode "on", in
    # 0..3; only a positive quantity (@min above 0) refuses zero or less.
    proposal = migrate.migrate(
        today({"SENS_EN_SF1XX": 6, "SF1XX_MODE": 0.0, "SF1XX_ROT": -0.0}), table="current"
    )
    (inst,) = proposal.instances
    assert (inst.values["mode"], inst.values["rotation"]) == (0, 0)
    assert proposal.not_carried == []


def test_a_calibration_slot_that_holds_no_device_id_is_said_so() -> None:
    # a device ID is a uint32 of PX4's DeviceStructure; a .params file may carry it as a float;
    # 0 is an empty slot (nothing to report)
    ak09916 = devid.encode("i2c", 1, 0x0C, 0x09)
    proposal = migrate.migrate(
        today(
            {"CAL_MAG0_ID": float(ak09916), "CAL_MAG1_ID": -5, "CAL_MAG2_ID": 1.5, "CAL_MAG3_ID": 0}
        ),
        table="current",
    )
    assert [(i.name, i.origin) for i in proposal.instances] == [
        ("AK09916#0", f"CAL_MAG0_ID = {ak09916}: AK09916 (MAG), I2C bus 1, address 0x0C")
    ]
    assert proposal.not_carried == [
        "CAL_MAG1_ID = -5: not a device ID",
        "CAL_MAG2_ID = 1.5: not a device ID",
    ]


def test_a_board_named_without_a_board_table_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    from px4params.errors import MigrationError

    # an installation without the board table (px4params.vehicle.boards cannot be imported)
    monkeypatch.setitem(sys.modules, "px4params.vehicle.boards", None)
    with pytest.raises(MigrationError) as e:
        migrate.migrate(today({}), board="px4_fmu-v6x", table="current")
    assert str(e.value) == (
        "--board px4_fmu-v6x: this installation has no board table (px4params.vehicle.boards)"
    )
    # a log's board is then judged from the parameters, and the report says so
    log = OldConfig("t.ulg", "ULog", {}, version=(1, 15, 0), hardware="PX4_FMU_V6X")
    assert migrate.migrate(log, table="current").assumptions == [
        "board PX4_FMU_V6X: no board table here; what its script starts is judged from the "
        "parameters and the boot console"
    ]


def _extra_probe_schema(tmp_path: Path, bus_doc: str = "") -> Any:
    """The bundled schema with an extra DSDL folder's type PROBE (no driver declaration): a
    bus (its doc lines ``bus_doc``) and a gain."""
    import px4params

    root = tmp_path / "acme"
    root.mkdir()
    (root / "Probe.1.0.dsdl").write_text(
        "# A probe\n# @max_instances 2\n\nuint4 p_version\npx.Bus.1.0 bus\n# Bus\n"
        f"{bus_doc}uint8 gain\n@sealed\n"
    )
    return px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")


def test_a_type_whose_bus_defaults_to_spi_is_proposed_on_i2c_tag_first(tmp_path: Path) -> None:
    # a type of an extra DSDL folder (no driver declaration) whose bus defaults to SPI: its
    # switch starts it on I2C as the power monitors are, so the proposal selects the I2C
    # variant (px.Bus's variant 0) before it sets the I2C fields (a tag set later would
    # reset them)
    schema = _extra_probe_schema(tmp_path, "# @default spi.bus_id 1\n")
    proposal = migrate.migrate(today({"SENS_EN_PROBE": 1}), schema=schema, table="current")
    (inst,) = proposal.instances
    assert inst.values == {"bus._tag": 0, "bus.i2c.bus_id": 1, "bus.i2c.address": 0}
    lines = [line for line in proposal.airframe().splitlines() if line.startswith("param ")]
    assert lines == [
        "param add PROBE#0",
        "param set-default PROBE#0[1] 0",
        "param set-default PROBE#0[3] 1",
        "param set-default PROBE#0[4] 0x00",
    ]


def test_a_switched_driver_runs_where_the_boot_console_shows_it() -> None:
    # issue 34, defect 8: a switch-started driver runs where the evidence says; the boot
    # console's start line names its bus and address
    console = "nsh: sercon\nina238 #0 on I2C bus 2 (external) address 0x44\n"
    proposal = migrate.migrate(today({"SENS_EN_INA238": 1}, console), table="current")
    (inst,) = proposal.instances
    assert (inst.name, inst.values) == ("INA238#0", {"bus.i2c.bus_id": 2, "bus.i2c.address": 0x44})
    assert inst.origin == (
        "SENS_EN_INA238 = 1: ina238 started on I2C bus 2 (boot console line 2: 'ina238 #0 on "
        "I2C bus 2 (external) address 0x44') at address 0x44"
    )
    # the line is the switch's: not reported again, nor taken as a second finding
    assert proposal.not_in_manifest == []
    assert not [n for n in inst.notes if n.startswith("also ")], inst.notes
    assert not [a for a in proposal.assumptions if "INA238" in a]


def test_a_switched_driver_the_boot_console_does_not_show_is_a_guess_said_so() -> None:
    proposal = migrate.migrate(today({"SENS_EN_INA238": 1}, "nsh: sercon\n"), table="current")
    (inst,) = proposal.instances
    assert inst.values == {"bus.i2c.bus_id": 1, "bus.i2c.address": 0x45}  # INA238's default
    assert [a for a in proposal.assumptions if "INA238" in a] == [
        "SENS_EN_INA238: the boot console shows no ina238 start (not connected at boot?); "
        "proposed on I2C bus 1",
        "SENS_EN_INA238: I2C bus 1 is a guess (PX4 starts ina238 -X -b 1 on the board; nothing "
        "here says which bus it is on)",
    ]


def test_a_setting_below_its_fields_minimum_is_rounded_then_raised_to_it() -> None:
    # a physical quantity is rounded to nearest (0.2 A -> 0) and held to the field's range
    # (INA238's current: 1..327 A); a value the store refuses (NaN) is not carried, with the
    # store's reason
    params = {"SENS_EN_INA238": 1, "INA238_CURRENT": 0.2, "INA238_SHUNT": float("nan")}
    proposal = migrate.migrate(today(params), table="current")
    (inst,) = proposal.instances
    assert inst.values["current"] == 1 and "shunt" not in inst.values
    assert inst.notes[0] == "INA238_CURRENT = 0.2 A becomes current = 1 A (uint10, 1..327)"
    assert proposal.not_carried == [
        "INA238_SHUNT = nan: INA238#0.shunt: nan is not a finite number (float16: NaN and "
        "infinities are refused)"
    ]


@pytest.mark.parametrize("given", [-5.0, 0.0, -0.0])
def test_a_positive_quantity_given_as_zero_or_less_is_not_carried(given: float) -> None:
    # -5 A became the valid-looking "current = 1 A" with a note only: a maximum current of
    # zero or less is no setting (PX4's INA238_CURRENT is 0.1..327.68 A), not one to round.
    params = {"SENS_EN_INA238": 1, "INA238_CURRENT": given, "INA238_SHUNT": -0.0003}
    proposal = migrate.migrate(today(params), table="current")
    (inst,) = proposal.instances
    assert "current" not in inst.values and "shunt" not in inst.values
    assert not [n for n in inst.notes if "becomes" in n]
    assert proposal.not_carried == [
        f"INA238_CURRENT = {given:g}: INA238#0.current must be 1..327",
        "INA238_SHUNT = -0.0003: INA238#0.shunt must be 1e-05..0.1",
    ]


def test_an_spi_sensor_the_console_shows_on_an_external_bus_is_not_called_internal() -> None:
    # I2CSPIDriverBase::module_start (platforms/common/i2c_spi_buses.cpp) prints an -S start as
    # "... on SPI bus N (external, equal to '-b K')": rc.sensors' `adis16448 -S start` behind
    # SENS_EN_ADIS164X, or MR-CANHUBK3's `icm20649 -b 4 -S` (SPI5, PX4's bus 6). Both are left
    # out of the manifest, as started by PX4's scripts, without calling them internal.
    console = (
        "adis16448 #0 on SPI bus 4 (external, equal to '-b 1')\n"
        "icm20649 #0 on SPI bus 6 (external, equal to '-b 4') rotation 6\n"
        "icm42688p #0 on SPI bus 1 rotation 6\n"
    )
    imu = devid.encode("spi", 6, 0, 0x25)  # drv_sensor.h: DRV_IMU_DEVTYPE_ICM20649 0x25
    proposal = migrate.migrate(today({"CAL_ACC0_ID": imu}, console), table="current")
    external = "SPI sensor on an external bus: started by PX4's startup scripts"
    assert proposal.not_in_manifest == [
        f"CAL_ACC0_ID = {imu}: ICM20649 (IMU), SPI bus 6, device 0: {external}, not by the "
        "manifest",
        f"boot console line 1: adis16448, SPI bus 4: {external}",
        "boot console line 3: icm42688p, SPI bus 1: internal SPI sensor: started by the board's "
        "startup script",
    ]
    assert proposal.instances == []


def test_one_device_in_two_slots_one_of_them_disabled_is_proposed_with_a_note() -> None:
    # issue 34, defects 2 and 10: CAL_MAG0_PRIO = 0 disables that slot; the device is still
    # used through the other slot, so it is proposed, and the disabled slot is said
    ak09916 = devid.encode("i2c", 1, 0x0C, 0x09)
    params = {"CAL_MAG0_ID": ak09916, "CAL_MAG1_ID": ak09916, "CAL_MAG0_PRIO": 0,
              "CAL_MAG1_PRIO": 50}  # fmt: skip
    proposal = migrate.migrate(today(params), table="current")
    (inst,) = proposal.instances
    assert inst.name == "AK09916#0"
    assert inst.notes == [
        "CAL_MAG0_PRIO = 0: one of its slots was disabled for use",
        "CAL_MAG0_ID and CAL_MAG1_ID hold the same device (reported once)",
    ]


def test_boot_console_lines_of_the_boards_own_sensors_are_reported_not_proposed() -> None:
    # an SPI sensor and a sensor on an internal I2C bus are the flight controller's, started
    # by the board's scripts; an external one started outside them is proposed
    console = (
        "ms5611 #0 on SPI bus 1 (devid=0x3d)\n"
        "bmm350 #0 on I2C bus 4 address 0x14\n"
        "ak09916 #0 on I2C bus 1 (external) address 0x0D\n"
    )
    proposal = migrate.migrate(today({}, console), table="current")
    assert proposal.not_in_manifest == [
        "boot console line 1: ms5611, SPI bus 1: internal SPI sensor: started by the board's "
        "startup script",
        "boot console line 2: bmm350, I2C bus 4, address 0x14: on an internal bus: started by "
        "the board's startup scripts",
    ]
    assert [(i.name, i.values["bus.i2c.address"], i.origin) for i in proposal.instances] == [
        ("AK09916#0", 0x0D, "boot console line 3: 'ak09916 #0 on I2C bus 1 (external) address "
         "0x0D' (started outside the board's script)"),
    ]  # fmt: skip


def test_a_console_line_at_another_address_is_not_the_slots_device() -> None:
    # the boot console's line is a device's evidence only at the device's address: an
    # AK09916 at 0x0D is a second device, not the calibrated one at 0x0C
    ak09916 = devid.encode("i2c", 1, 0x0C, 0x09)
    console = "ak09916 #0 on I2C bus 1 (external) address 0x0D\n"
    proposal = migrate.migrate(today({"CAL_MAG0_ID": ak09916}, console), table="current")
    assert [(i.name, i.values["bus.i2c.address"], i.origin) for i in proposal.instances] == [
        ("AK09916#0", 0x0C, f"CAL_MAG0_ID = {ak09916}: AK09916 (MAG), I2C bus 1, address 0x0C"),
        ("AK09916#1", 0x0D, "boot console line 1: 'ak09916 #0 on I2C bus 1 (external) address "
         "0x0D' (started outside the board's script)"),
    ]  # fmt: skip


def test_the_boards_script_starts_its_compass_on_the_buses_it_names_only() -> None:
    # PX4's boards/px4/fmu-v5/init/rc.board_sensors: `ist8310 -I -R 10 start` (any internal
    # bus: 3 on fmu-v5) and `ist8310 -X -b 1 -R 10 start` (external bus 1, the GPS port): an
    # IST8310 on bus 3 or 1 is the board's; on bus 2 or 4 it was found by probing
    from px4params.vehicle.boards import load_boards

    v5 = load_boards().by_name("px4_fmu-v5")
    assert v5 is not None and v5.internal_i2c_buses == (3,)
    rows = [r for r in v5.devices if r.driver == "ist8310"]
    assert [(r.bus, r.internal) for r in rows] == [(None, True), (1, False)]
    for bus, row in ((3, rows[0]), (1, rows[1])):
        ist8310 = devid.encode("i2c", bus, 0x0E, 0x06)
        proposal = migrate.migrate(today({"CAL_MAG0_ID": ist8310}), table="current", board=v5)
        assert proposal.instances == []
        assert proposal.not_in_manifest == [
            f"CAL_MAG0_ID = {ist8310}: IST8310 (MAG), I2C bus {bus}, address 0x0E: started by "
            f"the board's script ({row.source})"
        ]
    for bus in (2, 4):
        ist8310 = devid.encode("i2c", bus, 0x0E, 0x06)
        proposal = migrate.migrate(today({"CAL_MAG0_ID": ist8310}), table="current", board=v5)
        assert [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances] == [
            ("IST8310#0", bus)
        ]
    # nor does it start another chip on those buses: an AK09916 on bus 1 was found by probing
    ak09916 = devid.encode("i2c", 1, 0x0C, 0x09)
    proposal = migrate.migrate(today({"CAL_MAG0_ID": ak09916}), table="current", board=v5)
    assert [i.name for i in proposal.instances] == ["AK09916#0"]


def test_a_row_without_a_bus_starts_on_the_external_buses_only() -> None:
    # PX4's boards/saam/saampixv1_1/init/rc.board_sensors: `hmc5883 -X start`, no -b: the
    # driver tries every external I2C bus, and the board's i2c.cpp has one, bus 2 (bus 1 is
    # internal). An HMC5883 on bus 2 is the board's; on bus 1 that line never looked for it.
    from px4params.vehicle.boards import load_boards

    saam = load_boards().by_name("saam_saampixv1_1")
    assert saam is not None
    assert (saam.internal_i2c_buses, saam.external_i2c_buses) == ((1,), (2,))
    [row] = [r for r in saam.devices if r.driver == "hmc5883"]
    assert (row.bus, row.internal) == (None, False)
    on_2 = devid.encode("i2c", 2, 0x1E, 0x01)
    proposal = migrate.migrate(today({"CAL_MAG0_ID": on_2}), table="current", board=saam)
    assert proposal.instances == []
    assert proposal.not_in_manifest == [
        f"CAL_MAG0_ID = {on_2}: HMC5883 (MAG), I2C bus 2, address 0x1E: started by "
        f"the board's script ({row.source})"
    ]
    on_1 = devid.encode("i2c", 1, 0x1E, 0x01)
    proposal = migrate.migrate(today({"CAL_MAG0_ID": on_1}), table="current", board=saam)
    assert [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances] == [("HMC5883#0", 1)]


def test_a_driver_running_with_the_rotation_rc_sensors_probes_with_is_the_probes() -> None:
    # PX4 1.11's rc.sensors probes `ak09916 -X -R 6 start` (external compass): an AK09916 the
    # boot console shows running with rotation 6 was started by that probe (proposed, with the
    # driver's -R); with rotation 4 another script started it (the board's)
    from px4params.vehicle.boards import load_boards

    cube = load_boards().by_name("cubepilot_cubeorange", "v1.11.2")
    assert cube is not None
    # on bus 2, the Cube's first external bus (src/i2c.cpp:37): its own line 17's `-X -b 2`
    # is bus 1 at v1.11 (platforms/common/i2c.cpp:76 counts external buses)
    ak09916 = devid.encode("i2c", 2, 0x0C, 0x09)
    line = "ak09916 #0 on I2C bus 2 (external, equal to '-b 1') rotation {}\n"
    old = OldConfig("t.ulg", "ULog", {"CAL_MAG0_ID": ak09916}, version=(1, 11, 2),
                    console=line.format(6))  # fmt: skip
    proposal = migrate.migrate(old, table="px4-v1.11", board=cube)
    (inst,) = proposal.instances
    assert (inst.name, inst.values["rotation"]) == ("AK09916#0", 6)
    assert inst.notes == ["rotation 6: the driver's -R (boot console)"]
    old.console = line.format(4)
    proposal = migrate.migrate(old, table="px4-v1.11", board=cube)
    assert proposal.instances == []
    assert proposal.not_in_manifest == [
        f"CAL_MAG0_ID = {ak09916}: AK09916 (MAG), I2C bus 2, address 0x0C: runs with rotation 4 "
        "(boot console line 1): rc.sensors probes without -R, so the board's script started it"
    ]


#: PX4's boot console line of a driver's start, as platforms/common/i2c_spi_buses.cpp prints it:
#: v1.11.3 (line 502) the bus and "(external, equal to '-b N')", never the -R; from v1.12.0
#: (PX4 47b9016f5e, "I2CSPIDriverBase: print rotation and i2c address if set"; line 529 at
#: v1.12.0) also " address 0x.." and " rotation N", the latter only `if (cli.rotation != 0)`.
IST8310_STARTED = {
    (1, 11, 3): "ist8310 #0 on I2C bus 1 (external, equal to '-b 1')",
    (1, 12, 0): "ist8310 #0 on I2C bus 1 (external) address 0xE",
}


@pytest.mark.parametrize(
    ("version", "printed", "why"),
    [((1, 11, 3), (1, 11, 3), "rc.sensors starts it without -R"),
     ((1, 12, 0), (1, 12, 0), "the boot console shows no -R"),
     ((1, 12, 3), (1, 12, 0), "the boot console shows no -R"),
     ((1, 13, 0), (1, 12, 0), "the boot console shows no -R")],
)  # fmt: skip
def test_a_console_start_without_rotation_shows_rotation_0_from_px4_1_12(
    version: tuple[int, int, int], printed: tuple[int, int, int], why: str
) -> None:
    # A GPS's IST8310 the boot console shows started with no " rotation": from v1.12.0 that
    # line says the driver runs with -R 0; a 1.11 line never prints one, so only rc.sensors'
    # probe (no -R) tells
    ist8310 = devid.encode("i2c", 1, 0x0E, 0x06)
    old = OldConfig("t.ulg", "ULog", {"CAL_MAG0_ID": ist8310, "CAL_MAG0_ROT": 2},
                    version=version, console=IST8310_STARTED[printed] + "\n")  # fmt: skip
    (inst,) = migrate.migrate(old).instances
    # today's IST8310 reports other axes than 1.11's (tests/test_migrate_axes.py): 0 is now 10
    turned = version < (1, 12, 0)
    rotation = 10 if turned else 0
    assert (inst.name, inst.values["rotation"]) == ("IST8310#0", rotation)
    shown = f"0 on PX4 v1.11.3 ({why}), turned for ist8310's axes" if turned else why
    assert inst.notes[-1] == (
        "CAL_MAG0_ROT = 2 stays a classic parameter: calibration applies it; the driver's "
        f"rotation is {rotation} ({shown})"
    )


def test_what_the_i2c_launcher_started_is_proposed_and_nothing_guessed() -> None:
    # Pixhawk 6X's rc.board_sensors runs `i2c_launcher start -b 1` (and -b 2): the boot
    # console's launcher line says which power monitor it found; without one, the scan is
    # an assumption the report says
    from px4params.vehicle.boards import load_boards

    v6x = load_boards().by_name("px4_fmu-v6x")
    assert v6x is not None and v6x.i2c_launcher_buses == (1, 2)
    console = (
        "INFO  [i2c_launcher] Found address 0x45, running 'ina228 -X -b 1 -a 0x45 -t 1 start'\n"
        "ina228 #0 on I2C bus 1 (external) address 0x45\n"
    )
    proposal = migrate.migrate(today({}, console), table="current", board=v6x)
    (inst,) = proposal.instances
    assert (inst.name, inst.values) == ("INA228#0", {"bus.i2c.bus_id": 1, "bus.i2c.address": 0x45})
    assert inst.origin.endswith(" (found by i2c_launcher)")
    assert not [a for a in proposal.assumptions if "i2c_launcher" in a], proposal.assumptions
    proposal = migrate.migrate(today({}, "nsh: sercon\n"), table="current", board=v6x)
    assert proposal.instances == []
    assert proposal.assumptions == [
        "the board's i2c_launcher scans I2C bus 1, 2 for power monitors (INA226, INA228, INA238) "
        "when no SENS_EN_INA2xx is 1: the boot console shows none it started; " + ONLY_WITH_PM2
    ]


@pytest.mark.parametrize(
    ("when", "holds_for"),
    # a board row's test of its switch, as the board table writes PX4's `param compare` (==)
    # and `param greater` (>) tests, the others alike
    [("SENS_EN_LL40LS == 2", {2}), ("SENS_EN_SF1XX > 0", {1, 2}), ("X != 1", {-1, 0, 2}),
     ("X >= 1", {1, 2}), ("X <= 1", {-1, 0, 1}), ("X < 1", {-1, 0}), ("X == -1", {-1}),
     ("not X > 0", {-1, 0}), ("", {-1, 0, 1, 2})],
)  # fmt: skip
def test_a_board_rows_switch_test_holds_as_the_shell_test_does(when: str, holds_for: set) -> None:
    from px4params.migrate.conditions import Facts, evaluate

    def holds(value: int) -> bool | None:
        facts = Facts({"SENS_EN_LL40LS": value, "SENS_EN_SF1XX": value, "X": value}, {}, (),
                      None, "QGC .params")  # fmt: skip
        verdict = evaluate(when, facts)
        assert verdict.unchecked == ()
        return verdict.holds

    assert {v for v in (-1, 0, 1, 2) if holds(v)} == holds_for


def test_a_setting_rounded_into_its_field_is_noted_with_the_fields_unit_if_it_has_one() -> None:
    # a `param set` list may give a whole-number setting with a fraction: it is rounded to
    # nearest into the field (PCF8583_MAGNET: pulses, no unit; PCF8583_POOL: microseconds)
    params = {"SENS_EN_PCF8583": 1, "PCF8583_MAGNET": 2.6, "PCF8583_POOL": 1000000.4}
    (inst,) = migrate.migrate(today(params), table="current").instances
    assert (inst.values["magnet_pulses"], inst.values["pool_interval"]) == (3, 1000000)
    assert inst.notes == [
        "PCF8583_POOL = 1000000.4 us becomes pool_interval = 1000000 us (uint24, 1..16777215)",
        "PCF8583_MAGNET = 2.6 becomes magnet_pulses = 3 (uint8, 1..255)",
    ]


def test_a_boot_console_line_is_the_evidence_of_one_device_only() -> None:
    # PX4 1.11 prints no address: one ist8310 line on bus 1 is the start of one of two
    # IST8310s there (the first found); the other was not started at boot by that line
    first, second = devid.encode("i2c", 1, 0x0E, 0x06), devid.encode("i2c", 1, 0x0F, 0x06)
    console = "ist8310 #0 on I2C bus 1 (external, equal to '-b 2')\n"
    old = OldConfig("t.ulg", "ULog", {"CAL_MAG0_ID": first, "CAL_MAG1_ID": second},
                    version=(1, 11, 2), console=console)  # fmt: skip
    proposal = migrate.migrate(old, table="current")
    origins = [i.origin for i in proposal.instances]
    assert [i.name for i in proposal.instances] == ["IST8310#0", "IST8310#1"]
    assert sum("boot console line 1" in o for o in origins) == 1, origins


def test_a_devices_console_line_is_found_past_lines_of_other_addresses() -> None:
    ak09916 = devid.encode("i2c", 1, 0x0C, 0x09)
    console = (
        "ak09916 #0 on I2C bus 1 (external) address 0x0D\n"
        "ak09916 #1 on I2C bus 1 (external) address 0x0C\n"
    )
    proposal = migrate.migrate(today({"CAL_MAG0_ID": ak09916}, console), table="current")
    assert [(i.name, i.values["bus.i2c.address"]) for i in proposal.instances] == [
        ("AK09916#0", 0x0C), ("AK09916#1", 0x0D)
    ]  # fmt: skip
    assert proposal.instances[0].origin.endswith(
        "; boot console line 2: 'ak09916 #1 on I2C bus 1 (external) address 0x0C'"
    )


def test_a_thermal_control_value_px4_does_not_list_is_said_so() -> None:
    # PX4's parameter metadata lists SENS_EN_THERMAL's values (-1, 0, 1); one beyond them has
    # no meaning to report, and the report says that instead of inventing one
    path = shared_file(shared_data.PARAMETERS_JSON)
    metadata = json.loads(path.read_text())
    rows = metadata.get("parameters", metadata)
    (thermal,) = [p for p in rows if p["name"] == "SENS_EN_THERMAL"]
    unlisted = max(v["value"] for v in thermal["values"]) + 1
    proposal = migrate.migrate(config({"SENS_EN_THERMAL": unlisted}), table="px4-v1.11")
    assert proposal.not_carried == [
        f"SENS_EN_THERMAL = {unlisted} (a value PX4 does not list): not a driver switch; it "
        "stays a classic parameter"
    ]


def test_the_bmi088s_console_lines_are_its_slots_evidence_not_other_findings() -> None:
    # A real PX4 1.15 log (NXP MR-Tropic, ../shared/data): its boot console starts the BMI088
    # as two modules, `bmi088_accel #0 on SPI bus 4 rotation 2` (line 31) and `bmi088_gyro #0
    # on SPI bus 4 rotation 2` (line 33); CAL_ACC1_ID = 6946850 (0x6A0022) and CAL_GYRO1_ID =
    # 6684706 (0x660022) are that chip on SPI bus 4 (bus type 2, bus 4, devtypes 0x6A and
    # 0x66, read by hand). The lines are those slots' evidence: each SPI device is reported
    # once, by its slot, and no console line of the BMI088 is reported again.
    from px4params.migrate.config import read_config

    log = read_config(shared_file("frrs_ekf_failure.ulg"))
    proposal = migrate.migrate(log)
    left = proposal.not_in_manifest
    spi = [line for line in left if ", SPI bus " in line]
    assert [line.split(" = ")[0] for line in spi] == [
        "CAL_ACC0_ID, CAL_GYRO0_ID",
        "CAL_ACC1_ID",
        "CAL_GYRO1_ID",
    ]
    assert not [line for line in left if line.startswith(("boot console line 31", "boot console "
                                                         "line 33"))], left  # fmt: skip
    assert not [line for line in left if "bmi088" in line], left


def test_a_board_line_with_an_address_starts_the_device_at_that_address_only() -> None:
    # PX4's boards/px4/fmu-v6c/init/rc.board_sensors: `ist8310 -X -b 4 -a 0xc -q start` (bus 4,
    # address 0x0C, not the driver's default 0x0E) and `ist8310 -X -b 1 -R 10 start` (bus 1,
    # no -a: the driver's default address, I2C_ADDRESS_DEFAULT 0x0E). A device is the
    # board's only where one of those lines looks for it.
    from px4params.vehicle.boards import load_boards

    v6c = load_boards().by_name("px4_fmu-v6c")
    assert v6c is not None
    rows = {(r.bus, r.address): r for r in v6c.devices if r.driver == "ist8310"}
    assert set(rows) == {(4, 0x0C), (1, None)}

    def proposed(bus: int, address: int) -> list[str]:
        ist8310 = devid.encode("i2c", bus, address, 0x06)
        proposal = migrate.migrate(today({"CAL_MAG0_ID": ist8310}), table="current", board=v6c)
        if not proposal.instances:
            assert proposal.not_in_manifest == [
                f"CAL_MAG0_ID = {ist8310}: IST8310 (MAG), I2C bus {bus}, address 0x{address:02X}: "
                f"started by the board's script ({rows[(bus, 0x0C if bus == 4 else None)].source})"
            ]
        return [i.name for i in proposal.instances]

    assert proposed(4, 0x0C) == []  # the -a 0xc line's
    assert proposed(4, 0x0E) == ["IST8310#0"]  # no line on bus 4 looks at 0x0E
    assert proposed(1, 0x0E) == []  # the default address of the line without -a
    assert proposed(1, 0x0C) == ["IST8310#0"]  # not where that line looks


def test_a_probed_compass_gets_the_rotation_of_its_own_chips_probe_only() -> None:
    # PX4 1.11's rc.sensors (SENS_EXT_I2C_PRB) probes `ak09916 -X -R 6 start` but `ist8310 -X
    # start` (no -R): an AK09916 found on the external bus runs with rotation 6, an IST8310
    # found there with none; CubeOrange's own script starts its AK09916 on bus 1 only (line 17's
    # `-X -b 2`: the second external bus of src/i2c.cpp:37-38 at v1.11), so they are on bus 2
    from px4params.vehicle.boards import load_boards

    cube = load_boards().by_name("cubepilot_cubeorange", "v1.11.2")
    assert cube is not None
    ak09916, ist8310 = devid.encode("i2c", 2, 0x0C, 0x09), devid.encode("i2c", 2, 0x0E, 0x06)
    old = OldConfig("t.ulg", "ULog", {"CAL_MAG0_ID": ak09916, "CAL_MAG1_ID": ist8310},
                    version=(1, 11, 2))  # fmt: skip
    # for the file's own release: today's ist8310 reports other axes (tests/test_migrate_axes.py)
    proposal = migrate.migrate(old, table="px4-v1.11", board=cube, target_release="v1.11.0")
    ak, ist = proposal.instances
    assert (ak.name, ak.values["rotation"]) == ("AK09916#0", 6)
    assert ak.notes == [
        "rotation 6: rc.sensors probes it with 'ak09916 -X -R 6 start' (PX4/PX4-Autopilot "
        "ROMFS/px4fmu_common/init.d/rc.sensors:102 at v1.11.0 (tag v1.11.0, 71db0903a9, "
        "2020-09-07))"
    ]
    assert (ist.name, ist.values.get("rotation", 0), ist.notes) == ("IST8310#0", 0, [])


def test_a_switch_places_its_driver_on_its_own_console_lines_only() -> None:
    # SENS_EN_INA238 starts ina238; the boot console's line of another driver (the board's
    # BMM350 on internal bus 4) is not a place of the power monitor, it is reported as the
    # board's own sensor
    console = (
        "bmm350 #0 on I2C bus 4 address 0x14\nina238 #0 on I2C bus 2 (external) address 0x44\n"
    )
    proposal = migrate.migrate(today({"SENS_EN_INA238": 1}, console), table="current")
    assert [(i.name, i.values) for i in proposal.instances] == [
        ("INA238#0", {"bus.i2c.bus_id": 2, "bus.i2c.address": 0x44})
    ]
    assert proposal.not_in_manifest == [
        "boot console line 1: bmm350, I2C bus 4, address 0x14: on an internal bus: started by "
        "the board's startup scripts"
    ]


def test_a_board_line_whose_switch_test_fails_is_not_where_the_driver_runs() -> None:
    # PX4's boards/px4/fmu-v6x/init/rc.board_sensors starts `ina226 -X -b 1 -t 1 -k start`
    # under `param compare SENS_EN_INA226 1` (the board table's "SENS_EN_INA226 == 1"):
    # with the switch at 2 that test fails, the line does not run, and it is not the place the
    # report gives the power monitor
    from px4params.vehicle.boards import load_boards

    v6x = load_boards().by_name("px4_fmu-v6x")
    assert v6x is not None
    lines = [r for r in v6x.switches if r.param == "SENS_EN_INA226"]
    assert lines and {r.when.split(" and ")[0] for r in lines} == {"SENS_EN_INA226 == 1"}
    proposal = migrate.migrate(today({"SENS_EN_INA226": 1}), table="current", board=v6x)
    assert [i.origin for i in proposal.instances if "the board starts it with" in i.origin]
    proposal = migrate.migrate(today({"SENS_EN_INA226": 2}), table="current", board=v6x)
    assert not [i.origin for i in proposal.instances if "the board starts" in i.origin]


def test_an_extra_folders_type_is_guessed_on_bus_1_as_a_power_monitor_is(tmp_path: Path) -> None:
    # migrate/build.py's rule for a type of an extra DSDL folder without a driver declaration:
    # its SENS_EN_<NAME> starts it as PX4's board scripts start the power monitors (`-X -b 1`),
    # so the guess of its bus says that, not "every external bus"
    schema = _extra_probe_schema(tmp_path)
    proposal = migrate.migrate(today({"SENS_EN_PROBE": 1}), schema=schema, table="current")
    assert [i.name for i in proposal.instances] == ["PROBE#0"]
    assert [a for a in proposal.assumptions if a.startswith("SENS_EN_PROBE")] == [
        "SENS_EN_PROBE: I2C bus 1 is a guess (PX4 starts probe -X -b 1 on the board; nothing "
        "here says which bus it is on)"
    ]


def test_a_switch_started_on_every_external_bus_is_proposed_on_the_first_said_so() -> None:
    # PX4's rc.sensors runs `ms4525do start -X` while SENS_EN_MS4525DO is 1: -X without -b
    # tries every external I2C bus (Pixhawk 6C's: 1, 2 and 4), the sensor at its fixed
    # address 0x28 (MS4525DO's datasheet); which bus it was found on nothing here says, so the
    # first is proposed and the report says why, once
    from px4params.vehicle.boards import load_boards

    v6c = load_boards().by_name("px4_fmu-v6c")
    assert v6c is not None and v6c.external_i2c_buses == (1, 2, 4)
    rows = [r for r in v6c.switches if r.param == "SENS_EN_MS4525DO"]
    assert {(r.bus, r.args) for r in rows} == {(1, "start -X"), (2, "start -X"), (4, "start -X")}
    proposal = migrate.migrate(today({"SENS_EN_MS4525DO": 1}), table="current", board=v6c)
    (inst,) = proposal.instances
    assert (inst.name, inst.values) == (
        "MS4525DO#0",
        {"bus.i2c.bus_id": 1, "bus.i2c.address": 0x28},
    )
    assert inst.origin == (
        "SENS_EN_MS4525DO = 1: ms4525do started on I2C bus 1 at the driver's default address 0x28"
    )
    assert proposal.assumptions == [
        "SENS_EN_MS4525DO: px4_fmu-v6c starts 'ms4525do start -X' on every external I2C bus "
        f"(1, 2, 4; {rows[0].source}), so the bus it is found on is not known: bus 1 proposed"
    ]


def test_the_largest_device_id_is_one_and_one_beyond_it_is_not() -> None:
    # PX4's DeviceStructure packs bus type (3 bits), bus (5), address (8) and devtype (8) into
    # 24 bits: 0xFFFFFF (bus type 7, bus 31, address 0xFF, devtype 0xFF, drv_sensor.h's
    # DRV_DEVTYPE_UNUSED) is a device ID, of no bus the manifest knows; 0x1000000 needs a
    # 25th bit and is no device ID
    largest, beyond = 0xFFFFFF, 0x1000000
    what = "UNUSED, bus type 7, bus 31, address 0xFF: not an I2C device: not part of the manifest"
    proposal = migrate.migrate(
        today({"CAL_MAG0_ID": largest, "CAL_MAG1_ID": beyond}), table="current"
    )
    assert proposal.not_in_manifest == [f"CAL_MAG0_ID = {largest}: {what}"]
    assert proposal.not_carried == [f"CAL_MAG1_ID = {beyond}: not a device ID"]
    published = [("sensor_baro", 0, largest), ("sensor_baro", 1, beyond)]
    proposal = migrate.migrate(config(published=published), table="current")
    assert proposal.not_in_manifest == [f"sensor_baro 0 = {largest}: {what}"]


@pytest.mark.parametrize("device", ["i2c", "spi"])
def test_one_compass_in_two_slots_says_different_rotations_only_when_they_differ(
    device: str,
) -> None:
    # CAL_MAGn_ROT is calibration's rotation of slot n: one compass held by two slots with the
    # same rotation is reported once, plainly; with two different rotations the report names
    # both (one of them is stale). Probing starts the driver without -R: its rotation is 0.
    compass = devid.encode(device, 1, 0x0C if device == "i2c" else 0, 0x09)
    slots = {"CAL_MAG0_ID": compass, "CAL_MAG1_ID": compass}
    twice = "CAL_MAG0_ID and CAL_MAG1_ID hold the same device (reported once)"
    calibration = (
        "CAL_MAG{} = 2 stays a classic parameter: calibration applies it; the driver's rotation "
        "is 0 (rc.sensors starts it without -R)"
    )
    differ = ", with different rotations (CAL_MAG0_ROT = 0, CAL_MAG1_ROT = 2)"
    for rotations, said in (((2, 2), ""), ((0, 2), differ)):
        params = {**slots, "CAL_MAG0_ROT": rotations[0], "CAL_MAG1_ROT": rotations[1]}
        proposal = migrate.migrate(today(params), table="current")
        if device == "spi":
            (line,) = proposal.not_in_manifest
            assert line.endswith(f"not by the manifest; {twice}{said}")
            continue
        (inst,) = proposal.instances
        rotated = [calibration.format(f"{n}_ROT") for n, r in enumerate(rotations) if r]
        assert inst.notes == [twice + said, *rotated]


def test_what_is_left_out_says_why_in_the_reports_words() -> None:
    # The report's word for each device left out (migrate.proposal.LeftOut): "board" (the
    # board's script starts it: an SPI sensor, PX4's "Internal" CAL_MAGn_ROT = -1), "disabled"
    # (CAL_<S>n_PRIO = 0 in every slot holding it), and by PX4's DeviceStructure bus type:
    # 3 UAVCAN "dronecan", 4 simulation "simulation", 0 (unknown) "other bus". A device in
    # two disabled slots names both settings.
    def device_id(bus_type: int, bus: int, address: int, devtype: int) -> int:
        return bus_type | bus << 3 | address << 8 | devtype << 16

    icm20602, second = devid.encode("spi", 1, 0, 0x38), devid.encode("spi", 4, 0, 0x38)
    ist8310 = devid.encode("i2c", 1, 0x0E, 0x06)
    ak09916 = devid.encode("i2c", 2, 0x0C, 0x09)
    ms5611 = 0x3D  # drv_sensor.h's DRV_BARO_DEVTYPE_MS5611
    params = {
        "CAL_ACC0_ID": icm20602, "CAL_GYRO0_ID": icm20602, "CAL_ACC0_PRIO": 0,
        "CAL_GYRO0_PRIO": 0, "CAL_ACC1_ID": second, "CAL_MAG0_ID": ist8310, "CAL_MAG1_ID": ist8310,
        "CAL_MAG0_ROT": -1, "CAL_MAG0_PRIO": 0, "CAL_MAG1_PRIO": 0, "CAL_MAG2_ID": ak09916,
        "CAL_MAG3_ID": ak09916, "CAL_MAG2_PRIO": 0, "CAL_MAG3_PRIO": 0,
        "CAL_BARO0_ID": device_id(3, 0, 125, ms5611), "CAL_BARO1_ID": device_id(4, 0, 0, ms5611),
        "CAL_BARO2_ID": device_id(0, 0, 0x77, ms5611),
    }  # fmt: skip
    proposal = migrate.migrate(today(params), table="current")
    assert proposal.instances == [] and proposal.not_carried == []
    once = "hold the same device (reported once)"
    assert [(out.reason, out.line) for out in proposal.left_out] == [
        ("board", f"CAL_ACC0_ID, CAL_GYRO0_ID = {icm20602}: ICM20602 (IMU), SPI bus 1, device 0 "
         "(disabled: CAL_ACC0_PRIO = 0, CAL_GYRO0_PRIO = 0): internal SPI sensor: started by the "
         "board's startup script, not by the manifest"),
        ("board", f"CAL_ACC1_ID = {second}: ICM20602 (IMU), SPI bus 4, device 0: internal SPI "
         "sensor: started by the board's startup script, not by the manifest"),
        ("dronecan", f"CAL_BARO0_ID = {params['CAL_BARO0_ID']}: MS5611 (BARO), UAVCAN bus 0, "
         "node 125: DroneCAN sensor: found on the CAN bus, not by the manifest"),
        ("simulation", f"CAL_BARO1_ID = {params['CAL_BARO1_ID']}: MS5611 (BARO), simulation bus "
         "0, address 0x00: simulated sensor: not part of the manifest"),
        ("other bus", f"CAL_BARO2_ID = {params['CAL_BARO2_ID']}: MS5611 (BARO), bus type 0, bus "
         "0, address 0x77: not an I2C device: not part of the manifest"),
        ("board", f"CAL_MAG0_ID, CAL_MAG1_ID = {ist8310}: IST8310 (MAG), I2C bus 1, address 0x0E: "
         "CAL_MAG0_ROT = -1 (Internal): started by the board's script (disabled: CAL_MAG0_PRIO = "
         f"0, CAL_MAG1_PRIO = 0); CAL_MAG0_ID and CAL_MAG1_ID {once}"),
        ("disabled", f"CAL_MAG2_ID, CAL_MAG3_ID = {ak09916}: AK09916 (MAG), I2C bus 2, address "
         "0x0C: disabled (CAL_MAG2_PRIO = 0, CAL_MAG3_PRIO = 0): not proposed, an instance would "
         f"make it required; CAL_MAG2_ID and CAL_MAG3_ID {once}"),
    ]  # fmt: skip


@pytest.mark.parametrize(("devtype", "chip"), [(0x4A, "SDP31"), (0x4B, "SDP32"), (0x4C, "SDP33")])
def test_an_sdp3x_airspeed_sensor_of_any_model_is_the_sdp3x_type(devtype: int, chip: str) -> None:
    # drv_sensor.h names the Sensirion models apart (DRV_DIFF_PRESS_DEVTYPE_SDP31 0x4A, SDP32
    # 0x4B, SDP33 0x4C); PX4's one sdp3x driver runs all three, and its type is SDP3X
    sdp = devid.encode("i2c", 2, 0x21, devtype)
    log = OldConfig("t.ulg", "ULog", {}, version=(1, 15, 0),
                    published=[("differential_pressure", 0, sdp)])  # fmt: skip
    proposal = migrate.migrate(log, table="current")
    assert [(i.name, i.values, i.origin) for i in proposal.instances] == [
        ("SDP3X#0", {"bus.i2c.bus_id": 2, "bus.i2c.address": 0x21},
         f"differential_pressure 0 = {sdp}: {chip} (DIFF_PRESS), I2C bus 2, address 0x21"),
    ]  # fmt: skip
    assert proposal.not_carried == [] and proposal.not_in_manifest == []


def test_a_device_still_used_by_one_slot_names_every_disabled_one() -> None:
    # CAL_MAGn_PRIO = 0 disables slot n (PX4 1.12 on); a compass held by three slots, two of
    # them disabled, is still used through the third: proposed, both disabled slots named, in
    # a note that agrees in number with them
    ak09916 = devid.encode("i2c", 1, 0x0C, 0x09)
    params = {"CAL_MAG0_ID": ak09916, "CAL_MAG1_ID": ak09916, "CAL_MAG2_ID": ak09916,
              "CAL_MAG0_PRIO": 0, "CAL_MAG1_PRIO": 0, "CAL_MAG2_PRIO": 50}  # fmt: skip
    (inst,) = migrate.migrate(today(params), table="current").instances
    assert inst.notes == [
        "CAL_MAG0_PRIO = 0, CAL_MAG1_PRIO = 0: 2 of its slots were disabled for use",
        "CAL_MAG0_ID and CAL_MAG1_ID and CAL_MAG2_ID hold the same device (reported once)",
    ]


def test_boot_console_lines_of_the_boards_sensors_say_board_and_a_barometer_is_the_boards() -> None:
    # The board's own sensors in a boot console: an SPI one, one on an internal I2C bus (no
    # "(external)"), and an I2C barometer on an external bus (BMP388: drv_sensor.h's kind
    # BARO), which the report assumes is the flight controller's, and says so; each is left
    # out with the word "board"
    console = (
        "ms5611 #0 on SPI bus 1 (devid=0x3d)\n"
        "bmm350 #0 on I2C bus 4 address 0x14\n"
        "bmp388 #0 on I2C bus 2 (external) address 0x77\n"
    )
    proposal = migrate.migrate(today({}, console), table="current")
    assert proposal.instances == [] and proposal.not_carried == []
    assert [(out.found, out.device, out.reason) for out in proposal.left_out] == [
        ("boot console line 1", "ms5611, SPI bus 1", "board"),
        ("boot console line 2", "bmm350, I2C bus 4, address 0x14", "board"),
        ("boot console line 3", "bmp388, I2C bus 2, address 0x77", "board"),
    ]
    assert proposal.left_out[2].line == (
        "boot console line 3: bmp388, I2C bus 2, address 0x77: a barometer: assumed started by "
        "the board's script"
    )
    assert proposal.assumptions[-1] == (
        "I2C barometers without a board table row are taken as started by the board's script "
        "(barometers sit on the flight controller)"
    )


def test_a_console_line_without_an_address_assumes_the_drivers_default_and_says_so() -> None:
    # PX4 1.11's start line prints no address (`ms4525_airspeed #0 on I2C bus 2 (external,
    # equal to '-b 1')`; from v1.12.0, PX4 47b9016f5e, i2c_spi_buses.cpp prints
    # " address 0x.." where the driver's cli.i2c_address is set): the sensor is taken at its
    # driver's default, MS4525DO's fixed 0x28, and the report says that this was assumed
    line = "ms4525_airspeed #0 on I2C bus 2 (external, equal to '-b 1')"
    proposal = migrate.migrate(config(console=line + "\n"), table="px4-v1.11")
    (inst,) = proposal.instances
    assert (inst.name, inst.values["bus.i2c.address"]) == ("MS4525DO#0", 0x28)
    assert [a for a in proposal.assumptions if a.startswith("boot console")] == [
        f"boot console line 1: '{line}' names no address (PX4 1.11 prints none, later releases "
        "only one the driver sets): ms4525do's default 0x28 assumed"
    ]


def test_the_power_monitor_a_real_logs_i2c_launcher_found_keeps_its_battery_index_note() -> None:
    # The same real log's boot console, line 29: "[i2c_launcher] Found address 0x45, running
    # 'ina228 -X -b 1 -t 1 start'": the INA228 at 0x45 on bus 1 is proposed, and its start
    # line's -t 1 (the battery index) is an option the type has no field for, said
    from px4params.migrate.config import read_config

    proposal = migrate.migrate(read_config(shared_file("frrs_ekf_failure.ulg")))
    (inst,) = proposal.instances
    assert (inst.name, inst.values) == ("INA228#0", {"bus.i2c.bus_id": 1, "bus.i2c.address": 0x45})
    assert inst.origin.startswith("boot console line 29: ")
    assert inst.notes == [
        "today's start line also sets the battery index (-t 1): INA228 has no field for it"
    ]


def test_probing_on_is_replaced_by_the_devices_the_manifest_states() -> None:
    # A real PX4 1.11 log (CubeOrange, ../shared/data) has SENS_EXT_I2C_PRB = 1: rc.sensors
    # probed its airspeed sensor (its external compass is the board's line 17, `-X -b 2`, bus 1
    # at 1.11: test_migrate.py's test_sample_log); the manifest states it instead, and
    # the report names them (with nothing found, it says none)
    from px4params.migrate.config import read_config

    log = read_config(shared_file(shared_data.SAMPLE_LOG))
    assert log.params["SENS_EXT_I2C_PRB"] == 1
    said = (
        "SENS_EXT_I2C_PRB = 1: external I2C devices were found by probing; the manifest states "
        "its devices ({}) and a missing one fails the arming check instead of being skipped "
        "silently"
    )
    proposal = migrate.migrate(log)
    assert [i.name for i in proposal.instances] == ["MS4525DO#0"]
    assert proposal.replaced == [said.format("MS4525DO#0")]
    proposal = migrate.migrate(today({"SENS_EXT_I2C_PRB": 1}), table="current")
    assert proposal.replaced == [said.format("none")]
    # for v1.12.0, whose board script no longer starts the Here2's compass, both are named
    proposal = migrate.migrate(log, target_release="v1.12.0")
    assert proposal.replaced == [said.format("AK09916#0, MS4525DO#0")]


def test_the_i2c_launcher_runs_unless_a_power_monitor_switch_is_set() -> None:
    # Pixhawk 6X's rc.board_sensors runs i2c_launcher while $INA_CONFIGURED is no, which only
    # a set SENS_EN_INA226/228/238 makes yes: other parameters set (a battery's cell count,
    # another sensor's switch) leave the launcher's scan, and the report's word on it
    from px4params.vehicle.boards import load_boards

    v6x = load_boards().by_name("px4_fmu-v6x")
    assert v6x is not None and "$INA_CONFIGURED == no" in v6x.i2c_launcher_when
    params = {"BAT1_N_CELLS": 4, "SENS_EN_MS4525DO": 1, "SENS_EN_INA238": 0}
    proposal = migrate.migrate(today(params, "nsh: sercon\n"), table="current", board=v6x)
    assert [a for a in proposal.assumptions if "i2c_launcher" in a] == [
        "the board's i2c_launcher scans I2C bus 1, 2 for power monitors (INA226, INA228, INA238) "
        "when no SENS_EN_INA2xx is 1: the boot console shows none it started; " + ONLY_WITH_PM2
    ]
    # a log without a boot console (before PX4 1.12) cannot say what the scan found
    proposal = migrate.migrate(today(params), table="current", board=v6x)
    assert [a for a in proposal.assumptions if "i2c_launcher" in a] == [
        "the board's i2c_launcher scans I2C bus 1, 2 for power monitors (INA226, INA228, INA238) "
        "when no SENS_EN_INA2xx is 1: a ULog does not say which it found; " + ONLY_WITH_PM2
    ]
    params["SENS_EN_INA238"] = 1
    proposal = migrate.migrate(today(params, "nsh: sercon\n"), table="current", board=v6x)
    assert not [a for a in proposal.assumptions if "i2c_launcher" in a], proposal.assumptions


V6X_MAIN = "at main (branch main, bb59c637cd, 2026-08-13)"
V6X_SCRIPT = "PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors"
#: Why $HAVE_PM2 is open on a Pixhawk 6X (main) where a QGC file says nothing of its manifest.
V6X_PM2_WHY = (
    f"{V6X_SCRIPT}:5 {V6X_MAIN} sets HAVE_PM2 yes; line 8: no where mft MFT_PM2 == 0 (the "
    "board's hardware manifest, which the parameters do not tell)"
)
SCANS = "the board's i2c_launcher scans I2C bus {} for power monitors (INA226, INA228, INA238)"
QGC_SAYS = "a QGC .params does not say which it found"


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("name", "when", "said"),
    [
        # NXP MR-Tropic (main): `i2c_launcher start -b 3` (line 44) inside `if [ $INA_CONFIGURED
        # = no ]` (line 41): no switch set, bus 3 scanned, nothing open to name
        ("nxp_mr-tropic", None,
         f"{SCANS.format(3)} when no SENS_EN_INA2xx is 1: {QGC_SAYS}"),
        # the same line read without its if: the scan does not hinge on a switch
        ("nxp_mr-tropic", "", f"{SCANS.format(3)}: {QGC_SAYS}"),
        # Pixhawk 6X's bus 1 read without a condition: scanned, whatever "bus 2:" says
        ("px4_fmu-v6x", "bus 2: $INA_CONFIGURED == no",
         f"{SCANS.format('1, 2')} when no SENS_EN_INA2xx is 1: {QGC_SAYS}"),
        # both buses read as scanned only where $HAVE_PM2 is no, which PX4's default is not
        ("px4_fmu-v6x", "bus 1: $HAVE_PM2 == no; bus 2: $HAVE_PM2 == no",
         f"{SCANS.format('none')}: {QGC_SAYS}; "
         f"bus 1 not, by PX4's default: $HAVE_PM2 == no ({V6X_PM2_WHY}) ({V6X_SCRIPT}:61 "
         f"{V6X_MAIN}); bus 2 not, by PX4's default: $HAVE_PM2 == no ({V6X_PM2_WHY}) "
         f"({V6X_SCRIPT}:64 {V6X_MAIN})"),
        # bus 2 read as scanned where $HAVE_PM2 is yes and the base is 008: both clauses named
        ("px4_fmu-v6x", "bus 2: $HAVE_PM2 == yes and hw_base in 008",
         f"{SCANS.format('1, 2')}: {QGC_SAYS}; bus 2 only where $HAVE_PM2 == yes ({V6X_PM2_WHY}) "
         "and hw_base in 008 (the hardware revision, which the parameters do not tell) "
         f"({V6X_SCRIPT}:64 {V6X_MAIN})"),
    ],
)  # fmt: skip
def test_the_i2c_launchers_scan_is_said_whole_bus_by_bus(
    name: str, when: str | None, said: str
) -> None:
    import dataclasses

    from px4params.vehicle.boards import load_boards

    board = load_boards().by_name(name)
    assert board is not None
    if when is not None:
        board = dataclasses.replace(board, i2c_launcher_when=when)
    config = OldConfig("t", "QGC .params", {}, version=(1, 15, 0))
    proposal = migrate.migrate(config, table="current", board=board)
    assert [a for a in proposal.assumptions if "i2c_launcher" in a] == [said]


@pytest.mark.issue40
def test_a_set_power_monitor_switch_makes_ina_configured_yes_as_a_script_tests_it() -> None:
    # PX4 main's boards/auterion/fmu-v6s/init/rc.board_sensors sets INA_CONFIGURED yes in each
    # power-monitor switch's block (lines 37, 48, 59) and tests `[ "$INA_CONFIGURED" != "yes" ]`
    # (line 67), where fmu-v6x tests `= no`: Pixhawk 6X's launcher condition read that way
    # still runs the launcher without a switch set, and not with SENS_EN_INA238 = 1
    import dataclasses

    from px4params.vehicle.boards import load_boards

    v6x = load_boards().by_name("px4_fmu-v6x")
    assert v6x is not None
    when = v6x.i2c_launcher_when.replace("$INA_CONFIGURED == no", "$INA_CONFIGURED != yes")
    edited = dataclasses.replace(v6x, i2c_launcher_when=when)
    for ina238, scans in ((0, True), (1, False)):
        params = {"SENS_EN_INA238": ina238}
        proposal = migrate.migrate(today(params, "nsh: sercon\n"), table="current", board=edited)
        said = [a for a in proposal.assumptions if "i2c_launcher" in a]
        assert bool(said) == scans, proposal.assumptions


@pytest.mark.issue40
def test_a_board_test_of_ver_hwcmp_is_settled_by_the_boards_own_names() -> None:
    # PX4's scripts test the board with `ver hwcmp` (v1.12.0's rc.sensors line 8: `if ! ver
    # hwcmp OMNIBUS_F4SD`), which the table reads as `board in`: PX4 1.11's rc.sensors line 102
    # (`ak09916 -X -R 6 start`) read as running only on a PX4_FMU_V5 runs on fmu-v5, whose
    # ver_hw names it, and the AK09916 it probes gets its -R 6 with nothing left to name
    import dataclasses

    from px4params.vehicle.boards import load_boards

    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    assert v5 is not None and "PX4_FMU_V5" in v5.ver_hw
    probes = tuple(
        dataclasses.replace(r, when=f"{r.when} and board in PX4_FMU_V5")
        if "rc.sensors:102 " in r.source
        else r
        for r in v5.switches
    )
    here2 = devid.encode("i2c", 1, 0x0C, 0x09)
    proposal = migrate.migrate(
        OldConfig("t", "QGC .params", {"CAL_MAG0_ID": here2, "SENS_EXT_I2C_PRB": 1},
                  version=(1, 11, 3)),
        table="current",
        board=dataclasses.replace(v5, switches=probes),
    )  # fmt: skip
    (ak,) = proposal.instances
    assert (ak.name, ak.values["rotation"]) == ("AK09916#0", 6)
    # (but the line that says the table asked for is not the file's era's)
    assert [a for a in proposal.assumptions if not a.startswith("--table current: ")] == []


def test_a_devtype_two_chips_share_is_matched_to_the_console_line_of_either() -> None:
    # PX4 1.13's drv_sensor.h gives 0x4C to two chips (DRV_DIFF_PRESS_DEVTYPE_SDP33 and
    # DRV_BARO_DEVTYPE_LPS33HW): CAL_BARO0_ID's device of that code at 0x5D on bus 1 is the
    # LPS33HW the boot console started there, so that line is its evidence, not a second
    # barometer to report
    lps33hw = devid.encode("i2c", 1, 0x5D, 0x4C)
    console = "lps33hw #0 on I2C bus 1 (external) address 0x5D\n"
    log = OldConfig("t.ulg", "ULog", {"CAL_BARO0_ID": lps33hw}, version=(1, 13, 0),
                    console=console)  # fmt: skip
    proposal = migrate.migrate(log, table="px4-v1.13")
    assert proposal.instances == [] and proposal.not_carried == []
    assert proposal.not_in_manifest == [
        f"CAL_BARO0_ID = {lps33hw}: SDP33/LPS33HW (DIFF_PRESS/BARO), I2C bus 1, address 0x5D: a "
        "barometer: assumed started by the board's script"
    ]


def test_a_setting_equal_to_its_field_as_px4_stores_it_is_carried_without_a_note() -> None:
    # PX4 holds a float parameter as a float32: a list's INA238_CURRENT 30.00000001 is 30.0 in
    # PX4 (the nearest float32), so 30 A in the integer field is the same setting, noted as
    # nothing; 30.4 is rounded to 30 and noted
    params = {"SENS_EN_INA238": 1, "INA238_CURRENT": 30.00000001}
    (inst,) = migrate.migrate(today(params), table="current").instances
    assert inst.values["current"] == 30
    assert not [n for n in inst.notes if n.startswith("INA238_CURRENT")], inst.notes
    params["INA238_CURRENT"] = 30.4
    (inst,) = migrate.migrate(today(params), table="current").instances
    assert inst.values["current"] == 30
    assert [n for n in inst.notes if n.startswith("INA238_CURRENT")] == [
        "INA238_CURRENT = 30.4 A becomes current = 30 A (uint10, 1..327)"
    ]


def test_a_board_the_table_does_not_know_is_refused_or_said() -> None:
    # --board names a PX4 board (boards/<vendor>/<model>: px4_fmu-v6c); a name PX4 has no
    # board of is refused with what was expected, and a log's ver_hw that no board of the
    # table reports is said, its sensors judged from the parameters
    from px4params.errors import MigrationError

    with pytest.raises(MigrationError) as e:
        migrate.migrate(today({}), board="acme_fc-v1", table="current")
    assert str(e.value) == (
        "unknown board 'acme_fc-v1' (expected a PX4 board name such as px4_fmu-v6c)"
    )
    log = OldConfig("t.ulg", "ULog", {}, version=(1, 15, 0), hardware="ACME_FC_V1")
    assert migrate.migrate(log, table="current").assumptions == [
        "board ACME_FC_V1: not in the board table; what its script starts is judged from the "
        "parameters and the boot console"
    ]


def test_a_switch_after_thermal_control_still_starts_its_driver() -> None:
    # SENS_EN_THERMAL is thermal control, not a driver; the switches after it (in name order,
    # SENS_EN_VL53L1X) start their drivers as ever: PX4's rc.sensors tests each on its own
    proposal = migrate.migrate(today({"SENS_EN_THERMAL": 1, "SENS_EN_VL53L1X": 1}), table="current")
    assert [i.name for i in proposal.instances] == ["VL53L1X#0"]
    assert proposal.not_carried == [
        "SENS_EN_THERMAL = 1 (thermal control enabled): not a driver switch; it stays a classic "
        "parameter"
    ]


def test_a_board_starting_one_chip_at_two_addresses_on_a_bus_starts_both() -> None:
    # Pixhawk 6C's script starts `ist8310 -X -b 4 -a 0xc -q start`; a board whose script also
    # started `ist8310 -X -b 4 -a 0xe start` (a second IST8310 on the same bus) starts both:
    # the one at 0x0E is found by the second line past the first's other address
    import dataclasses

    from px4params.vehicle.boards import load_boards

    v6c = load_boards().by_name("px4_fmu-v6c")
    assert v6c is not None
    (first,) = [r for r in v6c.devices if r.driver == "ist8310" and r.bus == 4]
    second = dataclasses.replace(first, address=0x0E, args="-X -b 4 -a 0xe start")
    rows = list(v6c.devices)
    rows.insert(rows.index(first) + 1, second)
    board = dataclasses.replace(v6c, devices=tuple(rows))
    for address in (0x0C, 0x0E):
        ist8310 = devid.encode("i2c", 4, address, 0x06)
        proposal = migrate.migrate(today({"CAL_MAG0_ID": ist8310}), table="current", board=board)
        assert proposal.instances == []
        (line,) = proposal.not_in_manifest
        assert line.endswith(
            f"address 0x{address:02X}: started by the board's script ({first.source})"
        )


def test_a_switch_after_one_that_starts_no_i2c_driver_still_starts_its_own() -> None:
    # SENS_EN_LL40LS = 1 is the PWM Lidar-Lite (PX4's ll40ls parameters.yaml: 1 PWM, 2 I2C):
    # no I2C driver, it stays a classic parameter; SENS_EN_MS4525DO after it starts its sensor
    proposal = migrate.migrate(today({"SENS_EN_LL40LS": 1, "SENS_EN_MS4525DO": 1}), table="current")
    assert [i.name for i in proposal.instances] == ["MS4525DO#0"]
    assert proposal.not_carried == [
        "SENS_EN_LL40LS = 1: starts no I2C driver of the manifest (its ll40ls starts on "
        "SENS_EN_LL40LS == 2); it stays a classic parameter"
    ]


def test_a_console_line_after_one_without_a_type_is_still_proposed() -> None:
    # The boot console's lines each say what started: an LED driver (rgbled, no parameter
    # type: it stays started as today) does not hide the compass started after it
    console = (
        "rgbled #0 on I2C bus 1 (external) address 0x55\n"
        "ak09916 #0 on I2C bus 1 (external) address 0x0D\n"
    )
    proposal = migrate.migrate(today({}, console), table="current")
    assert [(i.name, i.values["bus.i2c.address"]) for i in proposal.instances] == [
        ("AK09916#0", 0x0D)
    ]
    assert proposal.not_carried == [
        "boot console line 1: 'rgbled #0 on I2C bus 1 (external) address 0x55': no bundled "
        "parameter type for rgbled; it stays started as today"
    ]


def test_a_file_without_board_information_says_how_its_sensors_are_judged() -> None:
    # A parameter list names no board (a log's ver_hw does): the report says which of its
    # sensors are taken as the board's and which as probed, and how to name the board instead
    proposal = migrate.migrate(today({}), table="current")
    assert proposal.assumptions == [
        "no board information in a ULog: sensors with CAL_MAGn_ROT = -1 (Internal) and I2C "
        "barometers are taken as the board's, other external I2C sensors as found by probing "
        "(--board NAME uses the board's table)"
    ]


def test_a_switch_px4_compares_with_1_starts_nothing_at_2_and_says_so() -> None:
    # PX4's boards' rc.board_sensors (v1.14, v1.15: boards/px4/fmu-v6x/init/rc.board_sensors)
    # start the INA226 only under `param compare -s SENS_EN_INA226 1`: at 2 the test fails and
    # no power monitor runs, so none is proposed; the value is said, not dropped
    proposal = migrate.migrate(today({"SENS_EN_INA226": 2}), table="current")
    assert proposal.instances == []
    assert proposal.not_carried == [
        "SENS_EN_INA226 = 2: starts no I2C driver of the manifest (its ina226 starts on "
        "SENS_EN_INA226 == 1); it stays a classic parameter"
    ]


def test_every_switch_starts_its_driver_on_the_values_the_board_scripts_test_for() -> None:
    # The board table transcribes each script's test of a switch from PX4 (v1.11.0 to main:
    # ROMFS/px4fmu_common/init.d/rc.sensors, boards/*/init/rc.board_sensors), `param compare X
    # 1` as "X == 1", `param greater X 0` as "X > 0": a driver declaration's test is the one
    # every row of its switch writes, and it starts on exactly the values that test passes,
    # negative ones included (`param greater X 0` fails for -1)
    from px4params.migrate.build import RENAMED_MODULES
    from px4params.vehicle.boards import load_boards
    from px4params.vehicle.drivers import load_drivers

    drivers = {d.name: d for d in load_drivers()}
    table = load_boards()
    checked = set()
    for board in table.all():
        for variant in table.variants(board.name):
            for row in variant.switches:
                driver = drivers.get(RENAMED_MODULES.get(row.driver, row.driver))
                if driver is None or driver.enabled_by != row.param:
                    continue
                (test,) = [c for c in row.when.split(" and ") if c.startswith(f"{row.param} ")]
                assert driver.switch_test == test, (driver.name, row.when, row.source)
                _, operator, limit = test.split(" ")
                passes = {"==": lambda v, n: v == n, ">": lambda v, n: v > n}[operator]
                values = range(-3, 8)
                assert [v for v in values if driver.starts_on(v)] == [
                    v for v in values if passes(v, int(limit))
                ], (driver.name, row.when, row.source)
                checked.add(driver.name)
    assert {"ina226", "ina228", "ina238", "ms4525do", "sdp3x", "ll40ls", "mb12xx", "teraranger",
            "lightware_laser_i2c", "auav"} <= checked  # fmt: skip


def test_the_crazyflie_21s_bmi088_i2c_rows_start_its_imu() -> None:
    # PX4's boards/bitcraze/crazyflie21/init/rc.board_sensors (v1.12 to main) starts the BMI088 as
    # `bmi088_i2c -A ... -I -a 0x18 start` and `bmi088_i2c -G ... -I -a 0x69 start`; the module
    # (src/drivers/imu/bosch/bmi088_i2c, MAIN bmi088_i2c) publishes drv_sensor.h's
    # DRV_ACC_DEVTYPE_BMI088 (0x6A) and DRV_GYR_DEVTYPE_BMI088 (0x66): the slots' devices are
    # the board's, started by those rows
    from px4params.vehicle.boards import load_boards

    cf21 = load_boards().by_name("bitcraze_crazyflie21", "v1.15.0")
    assert cf21 is not None
    rows = {r.address: r for r in cf21.devices if r.driver == "bmi088_i2c"}
    assert set(rows) == {0x18, 0x69} and cf21.internal_i2c_buses == (3,)
    accel = devid.encode("i2c", 3, 0x18, 0x6A)
    gyro = devid.encode("i2c", 3, 0x69, 0x66)
    params = {"CAL_ACC0_ID": accel, "CAL_GYRO0_ID": gyro}
    proposal = migrate.migrate(today(params), table="current", board=cf21)
    assert proposal.instances == [] and proposal.not_carried == []
    assert proposal.not_in_manifest == [
        f"CAL_ACC0_ID = {accel}: BMI088 (ACC), I2C bus 3, address 0x18: started by the board's "
        f"script ({rows[0x18].source})",
        f"CAL_GYRO0_ID = {gyro}: BMI088 (GYR), I2C bus 3, address 0x69: started by the board's "
        f"script ({rows[0x69].source})",
    ]


def test_a_devtype_two_chips_share_is_the_chip_of_the_slots_sensor_kind() -> None:
    # PX4 v1.13.0's src/drivers/drv_sensor.h gives 0x4C to DRV_DIFF_PRESS_DEVTYPE_SDP33 and
    # DRV_BARO_DEVTYPE_LPS33HW: on the differential_pressure topic the device is the airspeed
    # sensor (an SDP33, run by the sdp3x driver: the SDP3X type), not a barometer
    sdp33 = devid.encode("i2c", 2, 0x21, 0x4C)
    log = OldConfig("t.ulg", "ULog", {}, version=(1, 13, 0),
                    published=[("differential_pressure", 0, sdp33)])  # fmt: skip
    proposal = migrate.migrate(log, table="px4-v1.13")
    assert [(i.name, i.values, i.origin) for i in proposal.instances] == [
        ("SDP3X#0", {"bus.i2c.bus_id": 2, "bus.i2c.address": 0x21},
         f"differential_pressure 0 = {sdp33}: SDP33/LPS33HW (DIFF_PRESS/BARO), I2C bus 2, "
         "address 0x21"),
    ]  # fmt: skip
    assert proposal.not_carried == [] and proposal.not_in_manifest == []


def test_px4_1_11s_sf1xx_is_todays_lightware_laser_i2c() -> None:
    # PX4 v1.11.0's ROMFS/px4fmu_common/init.d/rc.sensors starts `sf1xx start -X` on
    # SENS_EN_SF1XX > 0 (src/drivers/distance_sensor/sf1xx); from v1.12.0 the same switch starts
    # `lightware_laser_i2c start -X`: the 1.11 rows (on each external bus) place the driver,
    # and its boot console line names it
    from px4params.vehicle.boards import load_boards

    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    assert v5 is not None
    rows = [r for r in v5.switches if r.param == "SENS_EN_SF1XX"]
    assert {r.driver for r in rows} == {"sf1xx"} and rows[0].args == "start -X"
    buses = ", ".join(str(b) for b in sorted(r.bus for r in rows))
    proposal = migrate.migrate(config({"SENS_EN_SF1XX": 6}), board=v5)
    assert [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances] == [
        ("SF1XX#0", rows[0].bus)
    ]
    assert (
        f"SENS_EN_SF1XX: px4_fmu-v5 starts 'sf1xx start -X' on every external I2C bus ({buses}; "
        f"{rows[0].source}), so the bus it is found on is not known: bus {rows[0].bus} proposed"
    ) in proposal.assumptions
    console = "sf1xx #0 on I2C bus 2 (external)\n"
    proposal = migrate.migrate(config({"SENS_EN_SF1XX": 6}, console=console), board=v5)
    assert [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances] == [("SF1XX#0", 2)]
    assert not [n for n in proposal.not_carried if "sf1xx" in n], proposal.not_carried


def test_a_negative_switch_value_starts_nothing_and_is_said() -> None:
    # rc.sensors' `param greater -s SENS_EN_TRANGER 0` fails for -1: no TeraRanger runs
    proposal = migrate.migrate(today({"SENS_EN_TRANGER": -1}), table="current")
    assert proposal.instances == []
    assert proposal.not_carried == [
        "SENS_EN_TRANGER = -1: starts no I2C driver of the manifest (its teraranger starts on "
        "SENS_EN_TRANGER > 0); it stays a classic parameter"
    ]


def test_a_log_cut_short_says_so(tmp_path: Path) -> None:
    # sample_log_small.ulg (pyulog's test log, Cube Orange, v1.11.2) holds 980 parameters; its
    # first 25,000 bytes hold 87 of them and end inside a message. The cut log was read as
    # whole: "Not carried over: none", no word of the 893 missing.
    from px4params.migrate.config import read_config

    whole = shared_file("sample_log_small.ulg")
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(whole.read_bytes()[:25_000])
    said = (
        "the log is cut short or damaged: parameters and devices logged after the break are missing"
    )
    config = read_config(cut)
    assert len(config.params) == 87 and said in config.details
    assert said in migrate.migrate(config).report()
    assert said not in read_config(whole).details and len(read_config(whole).params) == 980
    # `--json` and the airframe file say so too: both read as a whole log's.
    document = migrate.migrate(config).as_dict()
    assert document["log_cut"] is True and said in document["details"]
    assert document["airframe"].splitlines()[2] == (
        "# Warning: the log is cut short or damaged: devices logged after the break are missing "
        "here."
    )
    whole_document = migrate.migrate(read_config(whole)).as_dict()
    assert whole_document["log_cut"] is False and "# Warning" not in whole_document["airframe"]


def test_a_devtype_of_another_kind_than_its_slot_is_left_out_not_proposed() -> None:
    # 15619337 = 0xEE5509: devtype 0xEE is today's MCP9808, a temperature sensor, on I2C bus 1
    # at 0x55, in a compass slot. It was proposed as MCP9808#0, an instance arming requires.
    proposal = migrate.migrate(
        today({"CAL_MAG0_ID": 15619337, "CAL_MAG0_PRIO": 50, "SENS_EXT_I2C_PRB": 1}),
        table="current",
    )
    assert proposal.instances == []
    [left] = proposal.left_out
    assert (left.found, left.reason) == ("CAL_MAG0_ID = 15619337", "kind")
    assert left.line == (
        "CAL_MAG0_ID = 15619337: MCP9808 (TEMP), I2C bus 1, address 0x55: not proposed: devtype "
        "0xEE is TEMP in the current table, which does not fit CAL_MAG0_ID (IMU/MAG): the log "
        "may be of another era (--table)"
    )


def test_a_table_asked_for_that_is_not_the_files_era_is_said_in_the_report() -> None:
    """A PX4 1.15 file migrated with --table px4-v1.6 decodes its device IDs as asked, and the
    report says the file's own era's table is another (its IDs may name other chips)."""
    asked = migrate.migrate(today({}), table="px4-v1.6")
    assert asked.assumptions[0] == (
        "--table px4-v1.6: the file is of PX4 1.15.0, whose device IDs follow the current "
        "devtype table; they are decoded with px4-v1.6 as asked (without --table, the file's own)"
    )
    # The file's own era's table, asked for or not, and a file naming no version: nothing said.
    for config, table in ((today({}), "current"), (today({}), None)):
        assert not any(
            line.startswith("--table") for line in migrate.migrate(config, table=table).assumptions
        )
    older = OldConfig("t.ulg", "ULog", {}, version=(1, 11, 2))
    assert not any(
        "--table" in line for line in migrate.migrate(older, table="px4-v1.11").assumptions
    )
    unversioned = OldConfig("t.params", "QGC .params", {})
    assert not any(
        line.startswith("--table")
        for line in migrate.migrate(unversioned, table="legacy").assumptions
    )


# -- a file that names no board ---------------------------------------------------------------


def test_a_file_naming_no_board_hears_which_boards_start_an_instance_themselves(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # A Pixhawk 4's parameters (PX4 1.13, no board in a QGC file): ICM20689 and BMI055 on SPI,
    # the internal IST8310 on I2C bus 3, and the GPS mast's IST8310 on bus 1, which fmu-v5's
    # rc.board_sensors starts itself (`ist8310 -X -b 1 -R 10 start`). A manifest instance of it
    # would start it a second time, at another rotation.
    from px4params.cli.main import main

    path = shared_file("userguide_tteparams_v1.13.params")
    assert main(["migrate", str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    (compass,) = [i for i in report["instances"] if i["name"] == "IST8310#0"]
    fmu_v5 = (
        "IST8310#0: the file's SPI sensors (BMI055, ICM20689) are ones px4_fmu-v5 starts; on a "
        "px4_fmu-v5, this IST8310 is the board's own, started by the board's script "
        "(PX4/PX4-Autopilot boards/px4/fmu-v5/init/rc.board_sensors:31 at v1.13.0 (tag v1.13.0, "
        "6823cbc414, 2022-06-07)): --board px4_fmu-v5 leaves it out"
    )
    assert fmu_v5 in compass["notes"]
    boards = [n.split(" are ones ")[1].split(" ")[0] for n in compass["notes"] if "are ones" in n]
    assert boards == ["holybro_pix32v5", "px4_fmu-v5"]  # the two with both chips on SPI
    # What the note says --board does, it does.
    assert main(["migrate", str(path), "--json", "--board", "px4_fmu-v5"]) == 0
    named = [i["name"] for i in json.loads(capsys.readouterr().out)["instances"]]
    assert "IST8310#0" not in named and named


def test_sensors_many_boards_have_name_no_board() -> None:
    # BMI088 is on the SPI buses of most boards: it says nothing of which one this is.
    gps_compass = devid.encode("i2c", 1, 0x0E, 0x06)  # IST8310 on a GPS mast, 396809
    bmi088 = devid.encode("spi", 1, 0, 0x6A)  # drv_sensor.h: DRV_ACC_DEVTYPE_BMI088
    proposal = migrate.migrate(
        OldConfig(
            "x.params", "QGC .params", {"CAL_MAG0_ID": gps_compass, "CAL_ACC0_ID": bmi088},
            version=(1, 15, 0),
        ),
    )  # fmt: skip
    (compass,) = proposal.instances
    assert compass.name == "IST8310#0"
    assert not [n for n in compass.notes if "--board" in n], compass.notes


@pytest.mark.parametrize("hitl", [0, 1, 2])
def test_a_hardware_in_the_loop_configuration_is_said_to_have_run_no_sensor_drivers(
    hitl: int,
) -> None:
    # PX4's rcS: `if param greater SYS_HITL 0` starts the simulator's sensors instead of
    # rc.board_sensors and rc.sensors, so a HITL log's sensors are not the vehicle's
    proposal = migrate.migrate(today({"SYS_HITL": hitl, "SYS_AUTOSTART": 4001}))
    said = [a for a in proposal.assumptions if a.startswith("SYS_HITL")]
    assert said == (
        [
            f"SYS_HITL = {hitl}: hardware in the loop, where PX4 starts neither the board's "
            "sensor script nor rc.sensors (rcS); what it logged is the simulator's, and the "
            "proposal is for the vehicle flying with SYS_HITL 0"
        ]
        if hitl
        else []
    )
