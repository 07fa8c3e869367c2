"""What a PX4 boot console says was started (``vehicle/console.py``): the lines written here are
spelled as PX4's ``I2CSPIDriverBase`` (``<driver> #<n> on <I2C|SPI> bus <b> (external) address
0x<a> rotation <r>``) and ``i2c_launcher`` (``Found address 0x<a>, running '<command>'``) print
them; the expected starts are read off those lines by hand."""

from __future__ import annotations

from px4params.vehicle.console import DriverStart, started_drivers


def _fields(start: DriverStart) -> tuple:
    return (
        start.driver, start.bus_kind, start.bus, start.external, start.address, start.rotation,
        start.launcher, start.line,
    )  # fmt: skip


def test_console_a_script_started_driver_after_a_launched_one_is_its_own_start() -> None:
    # i2c_launcher found an INA226 at 0x40; the board's script then started a second INA226 on
    # the same bus at 0x41 (-a 0x41). Two devices: the second line is not the launcher's.
    console = (
        "INFO  [i2c_launcher] Found address 0x40, running 'ina226 -X -b 1 -t 1 start'\n"
        "ina226 #0 on I2C bus 1 (external) address 0x40\n"
        "ina226 #1 on I2C bus 1 (external) address 0x41\n"
    )
    assert [_fields(s) for s in started_drivers(console)] == [
        ("ina226", "I2C", 1, True, 0x40, None, True, 1),
        ("ina226", "I2C", 1, True, 0x41, None, False, 3),
    ]


def test_console_each_launched_device_takes_its_own_driver_line() -> None:
    # Two launcher lines first, then the drivers' lines in the other order: each driver line
    # joins the launcher line of its own address.
    console = (
        "INFO  [i2c_launcher] Found address 0x41, running 'ina226 -X -b 2 -t 1 start'\n"
        "INFO  [i2c_launcher] Found address 0x45, running 'ina226 -X -b 2 -t 2 start'\n"
        "ina226 #1 on I2C bus 2 (external) address 0x45 rotation 0\n"
        "ina226 #0 on I2C bus 2 (external) address 0x41\n"
    )
    assert [_fields(s) for s in started_drivers(console)] == [
        ("ina226", "I2C", 2, True, 0x41, None, True, 1),
        ("ina226", "I2C", 2, True, 0x45, 0, True, 2),
    ]


def test_console_driver_line_details_replace_the_launchers() -> None:
    # The launcher assumes external; the driver's own line (no "(external)") is the truth, and
    # keeps the launcher's line number and text.
    launcher = "INFO  [i2c_launcher] Found address 0x45, running 'ina238 -X -b 3 start'"
    starts = started_drivers(f"{launcher}\nina238 #0 on I2C bus 3 address 0x45 rotation 4\n")
    assert [_fields(s) for s in starts] == [("ina238", "I2C", 3, False, 0x45, 4, True, 1)]
    assert starts[0].text == launcher and starts[0].internal


def test_console_driver_line_without_address_joins_the_launched_device() -> None:
    # PX4 1.11/1.12 print no address: the line is the launched device's (same driver, bus).
    console = (
        "INFO  [i2c_launcher] Found address 0x45, running 'ina228 -X -b 1 start'\n"
        "ina228 #0 on I2C bus 1 (external, equal to '-b 1')\n"
    )
    assert [_fields(s) for s in started_drivers(console)] == [
        ("ina228", "I2C", 1, True, 0x45, None, True, 1)
    ]


def test_console_a_driver_on_another_bus_is_not_the_launched_one() -> None:
    console = (
        "INFO  [i2c_launcher] Found address 0x45, running 'ina228 -X -b 1 start'\n"
        "ina228 #1 on I2C bus 2 (external) address 0x45\n"
        "ina238 #0 on I2C bus 1 (external) address 0x45\n"
    )
    assert [_fields(s) for s in started_drivers(console)] == [
        ("ina228", "I2C", 1, True, 0x45, None, True, 1),
        ("ina228", "I2C", 2, True, 0x45, None, False, 2),
        ("ina238", "I2C", 1, True, 0x45, None, False, 3),
    ]


def test_console_launcher_commands_as_written() -> None:
    # -a in decimal or 0X hex overrides the found address; no -b leaves the bus unknown (0);
    # an empty command names no driver.
    console = (
        "INFO  [i2c_launcher] Found address 0x45, running 'ina226 -X -a 69 start'\n"
        "INFO  [i2c_launcher] Found address 0x40, running 'ina226 -X -b 4 -a 0X4A start'\n"
        "INFO  [i2c_launcher] Found address 0x1F, running ''\n"
        "INFO  [i2c_launcher] Found address 0x44, running 'ina228 -b x -a 68 start'\n"
    )
    assert [_fields(s) for s in started_drivers(console)] == [
        ("ina226", "I2C", 0, True, 69, None, True, 1),
        ("ina226", "I2C", 4, True, 0x4A, None, True, 2),
        ("", "I2C", 0, True, 0x1F, None, True, 3),
        ("ina228", "I2C", 0, True, 68, None, True, 4),
    ]


def test_console_driver_lines_as_px4_prints_them() -> None:
    console = (
        "  lsm9ds1_mag #0 on SPI bus 1  \n"
        "ist8310 #0 on I2C bus 1 (external) address 0xE rotation 10\n"
        "bmp388 #0 on I2C bus 4 address 0x7F\n"
        "ms5611 #0 on SPI bus 12 (devid=0x3d) rotation 0\n"
        "Ist8310 #0 on I2C bus 1 address 0xE\n"  # not a driver name: PX4's are lower case
        "nsh> ist8310 #0 on I2C bus 1\n"  # echoed text, not the driver's line
    )
    starts = started_drivers(console)
    assert [_fields(s) for s in starts] == [
        ("lsm9ds1_mag", "SPI", 1, False, None, None, False, 1),
        ("ist8310", "I2C", 1, True, 0x0E, 10, False, 2),
        ("bmp388", "I2C", 4, False, 0x7F, None, False, 3),
        ("ms5611", "SPI", 12, False, None, 0, False, 4),
    ]
    assert starts[0].text == "lsm9ds1_mag #0 on SPI bus 1"
    assert [s.internal for s in starts] == [True, False, True, True]


def _boot_console(log: str) -> tuple[object, str]:
    """A real log (read with pyulog) and its boot console as PX4 logged it."""
    from pyulog import ULog
    from shared_data import shared_file

    ulog = ULog(str(shared_file(log)))  # skips with the reason when ../shared is absent
    (pieces,) = ulog.msg_info_multiple_dict["boot_console_output"]
    return ulog, "".join("".join(p) for p in pieces)


def _devid_bus(device_id: int) -> tuple[int, int, int]:
    """PX4's DeviceId bit fields: bus type (bits 0-2), bus (3-7), address (8-15)."""
    return device_id & 0x7, (device_id >> 3) & 0x1F, (device_id >> 8) & 0xFF


def test_console_an_i2c_bus_is_the_device_ids_not_the_external_index_of_px4_1_11() -> None:
    # sample_log_small.ulg, PX4 v1.11.2 (a Cube: its board lists external I2C bus 2 before
    # bus 1): "ak09916 #0 on I2C bus 1 (external, equal to '-b 2')" and "ms4525_airspeed #0 on
    # I2C bus 2 (external, equal to '-b 1')". The "-b" there is the n-th external bus (PX4 1.11's
    # -X -b; PX4-Autopilot#15679 made it the bus number after 1.11); the device IDs the log
    # recorded for the same chips name the printed bus: sensor_mag's 0x90C09 (I2C, bus 1, 0x0C)
    # and differential_pressure's (I2C, bus 2, 0x28).
    ulog, console = _boot_console("sample_log_small.ulg")
    recorded = {
        _devid_bus(int(d.data["device_id"][0]))
        for d in ulog.data_list
        if d.name in ("sensor_mag", "differential_pressure")
    }
    assert {(1, 1, 0x0C), (1, 2, 0x28)} <= recorded  # I2C is bus type 1
    starts = {s.driver: s for s in started_drivers(console)}
    assert (starts["ak09916"].bus_kind, starts["ak09916"].bus) == ("I2C", 1)
    assert (starts["ms4525_airspeed"].bus_kind, starts["ms4525_airspeed"].bus) == ("I2C", 2)
    assert starts["ak09916"].external and starts["ms4525_airspeed"].external


def test_console_the_launchers_bus_is_the_bus_its_driver_prints() -> None:
    # frrs_ekf_failure.ulg, PX4 1.15 beta: i2c_launcher probes a bus by its number and runs
    # "<driver> -X -b <that number>", and since PX4-Autopilot#15679 an I2C driver's -b is the
    # board's bus number, the one its start line prints: "ina228 -X -b 1 -t 1 start" and
    # "ina228 #0 on I2C bus 1 (external) address 0x45" are one device, started once.
    _, console = _boot_console("frrs_ekf_failure.ulg")
    assert "running 'ina228 -X -b 1 -t 1 start'" in console
    assert "ina228 #0 on I2C bus 1 (external) address 0x45" in console
    (ina,) = [s for s in started_drivers(console) if s.driver == "ina228"]
    assert (ina.bus_kind, ina.bus, ina.address, ina.external, ina.launcher) == (
        "I2C", 1, 0x45, True, True,
    )  # fmt: skip
    assert "[i2c_launcher]" in ina.text  # the start is the launcher's line
