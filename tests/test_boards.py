"""The board table (``data/boards.toml``) and its loader, against PX4's own scripts read by hand.

Each known answer below names the PX4-Autopilot file and release it was read from. Where a
fetched PX4-Autopilot git directory is on this machine (``$PX4_AUTOPILOT_GIT``, colon-separated,
or the mirrors the table was transcribed from), every row is also checked line by line against
the script it cites.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from pathlib import Path
from typing import Any

import pytest
import pyulog
from px4_git import px4_git_dirs, show
from px4params.errors import BoardsError, BoardsFileError
from px4params.vehicle.boards import (
    Board,
    BoardDevice,
    SwitchStart,
    load_boards,
    parse_boards,
    release_version,
    render_markdown,
)
from shared_data import shared_file

SNAPSHOTS = ("v1.11.0", "v1.12.0", "v1.13.0", "v1.14.0", "v1.15.0", "v1.18", "main")


def device(board: Board, driver: str, bus: int | None = None) -> BoardDevice:
    found = [d for d in board.devices if d.driver == driver and (bus is None or d.bus == bus)]
    assert len(found) == 1, (driver, bus, board.devices)
    return found[0]


def switches(board: Board, param: str) -> list[SwitchStart]:
    return [s for s in board.switches if s.param == param]


# -- known answers, read by hand from PX4-Autopilot ---------------------------------------------


def test_fmu_v6c_compass_on_bus_4_is_external_since_v1_14() -> None:
    # boards/px4/fmu-v6c/init/rc.board_sensors, v1.14.0 and main: "ist8310 -X -b 4 -a 0xc start"
    for release in ("v1.14.0", "v1.15.3", None):
        board = load_boards().by_name("px4_fmu-v6c", release)
        assert board is not None
        mag = device(board, "ist8310", bus=4)
        assert (mag.kind, mag.bus_kind, mag.address, mag.rotation, mag.internal) == (
            "mag",
            "I2C",
            0x0C,
            None,
            False,
        )
        assert "boards/px4/fmu-v6c/init/rc.board_sensors" in mag.source
    # v1.13.0 started it as internal: "ist8310 -I -b 4 -a 0xc start"
    old = load_boards().by_name("px4_fmu-v6c", "v1.13.2")
    assert old is not None and device(old, "ist8310", bus=4).internal is True
    # the GPS compass: "ist8310 -X -b 1 -R 10 start"
    gps = device(old, "ist8310", bus=1)
    assert (gps.rotation, gps.internal, gps.address) == (10, False, None)


def test_fmu_v5_internal_compass_carries_the_board_rotation() -> None:
    # boards/px4/fmu-v5/init/rc.board_sensors, v1.13.0 line 28: "ist8310 -I -R 10 start"
    board = load_boards().by_name("px4_fmu-v5", "v1.13.0")
    assert board is not None
    internal = [d for d in board.devices if d.driver == "ist8310" and d.internal]
    assert [(d.bus, d.rotation, d.bus_kind) for d in internal] == [(None, 10, "I2C")]
    assert internal[0].source.startswith(
        "PX4/PX4-Autopilot boards/px4/fmu-v5/init/rc.board_sensors:28 at v1.13.0"
    )
    # its src/i2c.cpp: external 4, 2, 1; internal 3
    assert board.external_i2c_buses == (1, 2, 4)
    assert board.internal_i2c_buses == (3,)
    # so the -I compass is on bus 3 (userguide_tteparams_v1.13.params: CAL_MAG0_ID on bus 3)
    assert board.buses_of(internal[0]) == (3,)
    assert board.buses_of(device(board, "ist8310", bus=1)) == (1,)
    assert board.buses_of(device(board, "icm20689")) == ()  # SPI, no -b


def test_mr_tropic_bmm350() -> None:
    # boards/nxp/mr-tropic/init/rc.board_sensors (release/1.18, main): "bmm350 -I -b 4 -R 6 start"
    board = load_boards().for_ulog("NXP_MR_TROPIC", None)
    assert board is not None and board.name == "nxp_mr-tropic"
    mag = device(board, "bmm350")
    assert (mag.bus_kind, mag.bus, mag.rotation, mag.internal) == ("I2C", 4, 6, True)
    # "if ! icm45686 -R 2 -b 3 -s start / then icm42688p -R 2 -b 3 -s -6 start": the second
    # runs only when the first fails
    fallback = device(board, "icm42688p")
    assert fallback.when == "not icm45686 started (-R 2 -b 3 -s start)"
    assert device(board, "icm45686").when == ""


def test_6x_class_ina238_starts_one_monitor_per_power_port() -> None:
    # boards/px4/fmu-v6x/init/rc.board_sensors (main): under "if param compare SENS_EN_INA238 1"
    # "ina238 -X -b 1 -t 1 -k start", and with a second power module "ina238 -X -b 2 -t 2 -k start"
    board = load_boards().by_name("px4_fmu-v6x")
    assert board is not None
    found = switches(board, "SENS_EN_INA238")
    assert [(s.driver, s.bus, s.address) for s in found] == [
        ("ina238", 1, None),
        ("ina238", 2, None),
    ]
    assert "-t 1" in found[0].args and "-t 2" in found[1].args
    assert found[1].when == "SENS_EN_INA238 == 1 and $HAVE_PM2 == yes"
    assert all(s.kind == "power" and not s.internal for s in found)
    # with no SENS_EN_INA2xx set, "i2c_launcher start -b 1" (and -b 2 with a second module)
    assert board.i2c_launcher_buses == (1, 2)
    assert board.i2c_launcher_when == (
        "bus 1: $INA_CONFIGURED == no; bus 2: $INA_CONFIGURED == no and $HAVE_PM2 == yes"
    )


def test_rc_sensors_switch_probes_every_external_bus() -> None:
    # ROMFS/px4fmu_common/init.d/rc.sensors (v1.13.0): "ms4525do start -X" behind
    # SENS_EN_MS4525DO, so on fmu-v5 it probes external buses 1, 2 and 4, not bus 1 alone
    board = load_boards().by_name("px4_fmu-v5", "v1.13.0")
    assert board is not None
    found = switches(board, "SENS_EN_MS4525DO")
    assert [(s.driver, s.bus) for s in found] == [("ms4525do", 1), ("ms4525do", 2), ("ms4525do", 4)]
    assert "ROMFS/px4fmu_common/init.d/rc.sensors" in found[0].source


def test_cubeorange_imus_are_on_spi() -> None:
    # boards/cubepilot/cubeorange/init/rc.board_sensors (v1.14.0):
    # "icm20602 -s -b 4 -R 12 start", "icm20948 -s -b 4 -R 10 -M start", "ms5611 -s -b 1 start"
    board = load_boards().by_name("cubepilot_cubeorange", "v1.14.0")
    assert board is not None
    imu = device(board, "icm20602")
    assert (imu.kind, imu.bus_kind, imu.bus, imu.rotation, imu.internal) == (
        "imu",
        "SPI",
        4,
        12,
        True,
    )
    assert device(board, "ms5611", bus=1).kind == "baro"
    # "-M": the ICM-20948's own magnetometer (icm20948_main.cpp's usage: "Enable Magnetometer"),
    # so the board starts an internal compass on SPI 4 with the IMU's rotation
    kinds = [
        (d.kind, d.bus_kind, d.bus, d.rotation) for d in board.devices if d.driver == "icm20948"
    ]
    assert kinds == [("imu", "SPI", 4, 10), ("mag", "SPI", 4, 10)]
    assert board.i2c_launcher_buses == ()


def test_hardware_revisions_and_fallbacks_are_kept_as_conditions() -> None:
    # fmu-v6c (v1.15.0): "if ver hwtypecmp V6C000002 V6C002002" BMI088, else BMI055
    board = load_boards().by_name("px4_fmu-v6c", "v1.15.0")
    assert board is not None
    bmi = [(d.driver, d.when) for d in board.devices if d.driver.startswith("bmi")]
    assert bmi == [
        ("bmi088", "hw_type in V6C000002,V6C002002"),
        ("bmi088", "hw_type in V6C000002,V6C002002"),
        ("bmi055", "not hw_type in V6C000002,V6C002002"),
        ("bmi055", "not hw_type in V6C000002,V6C002002"),
    ]


# -- the table as a whole ------------------------------------------------------------------------


def test_every_row_loads_and_names_are_unique() -> None:
    table = load_boards()
    boards = table.all()
    names = [b.name for b in boards]
    assert len(names) == len(set(names)) >= 100
    assert table.releases == SNAPSHOTS
    for name in (
        "px4_fmu-v2",
        "px4_fmu-v3",
        "px4_fmu-v4",
        "px4_fmu-v4pro",
        "px4_fmu-v5",
        "px4_fmu-v5x",
        "px4_fmu-v6c",
        "px4_fmu-v6u",
        "px4_fmu-v6x",
        "px4_fmu-v6xrt",
        "cubepilot_cubeorange",
        "cubepilot_cubeorangeplus",
        "cubepilot_cubeyellow",
        "cuav_nora",
        "cuav_x7pro",
        "cuav_7-nano",
        "holybro_durandal-v1",
        "holybro_kakutef7",
        "holybro_pix32v5",
        "holybro_kakuteh7",
        "ark_fmu-v6x",
        "ark_pi6x",
        "modalai_fc-v1",
        "modalai_fc-v2",
        "nxp_fmuk66-v3",
        "nxp_mr-canhubk3",
        "nxp_tropic-community",
        "nxp_mr-tropic",
    ):
        assert name in names, name
    ver_hw = [hw for b in boards for hw in b.ver_hw]
    assert len(ver_hw) == len(set(ver_hw))
    for board in boards:
        assert board.ver_hw[0] == board.name.upper().replace("-", "_")
        for variant in table.variants(board.name):
            assert variant.source.startswith("PX4/PX4-Autopilot boards/")
            for d in variant.devices:
                assert d.kind in ("mag", "baro", "imu", "power", "other")
                assert d.bus_kind in ("I2C", "SPI")
                assert re.match(r"PX4/PX4-Autopilot \S+:\d+ at \S+ \(", d.source), d.source
            for s in variant.switches:
                assert s.bus >= 0 and s.param


def test_each_release_reads_the_newest_snapshot_before_it() -> None:
    table = load_boards()
    assert table.snapshot_for("v1.13.3") == "v1.13.0"
    assert table.snapshot_for("v1.16.1") == "v1.15.0"  # no v1.16/v1.17 snapshot
    assert table.snapshot_for("v1.18.0-rc1") == "v1.18"
    assert table.snapshot_for("v1.19.0") == "main"
    assert table.snapshot_for(None) == "main"
    assert table.snapshot_for("v1.10.1") is None
    assert table.by_name("px4_fmu-v6c", "v1.10.1") is None
    assert table.by_name("no_such-board") is None
    # ULog ver_sw_release 0x010B0200 is v1.11.2
    assert release_version(0x010B02FF) == (1, 11, 2)
    assert release_version("1.15.0-beta1") == (1, 15, 0)


@pytest.mark.issue40
def test_every_uint32_ver_sw_release_is_a_version() -> None:
    """ULog's ver_sw_release is a uint32 (0xMMmmpptt, the last byte the release type): its
    smallest and largest values are versions too."""
    assert release_version(0) == (0, 0, 0)
    assert release_version(0xFFFFFFFF) == (255, 255, 255)


@pytest.mark.parametrize(
    ("release", "message"),
    [
        ("latest", "release 'latest' is no PX4 version (expected e.g. 'v1.13.0')"),
        ("v1", "release 'v1' is no PX4 version (expected e.g. 'v1.13.0')"),
        (-1, "release -1 is no ULog ver_sw_release (0 .. 2**32-1)"),
        pytest.param(
            1 << 32,
            "release 4294967296 is no ULog ver_sw_release (0 .. 2**32-1)",
            marks=pytest.mark.issue40,  # the mutation run's survivors (issue 40)
        ),
    ],
)
def test_a_release_that_is_no_version_is_refused(release: str | int, message: str) -> None:
    with pytest.raises(BoardsError) as err:
        load_boards().for_ulog("PX4_FMU_V5", release)
    assert str(err.value) == message


# -- real ULogs ------------------------------------------------------------------------------------


def ulog_info(name: str) -> dict[str, object]:
    log = pyulog.ULog(str(shared_file(name)), [], False)
    return dict(log.msg_info_dict)


def test_ulog_of_a_cubeorange_on_v1_11() -> None:
    info = ulog_info("sample_log_small.ulg")
    assert info["ver_hw"] == "CUBEPILOT_CUBEORANGE"
    board = load_boards().for_ulog(str(info["ver_hw"]), int(info["ver_sw_release"]))  # type: ignore[call-overload]
    assert board is not None and board.name == "cubepilot_cubeorange"
    assert board.releases[0] == "v1.11.0"


def test_cubeorange_log_device_ids_are_on_the_buses_the_table_names() -> None:
    # sample_log_small.ulg's calibration IDs, decoded by hand (bits 0-2 bus type, 2 = SPI;
    # bits 3-7 bus; bits 16-23 devtype): CAL_ACC0_ID 2424842 = SPI 1 ICM20649 (0x25),
    # CAL_ACC1_ID 3670050 = SPI 4 ICM20602 (0x38), CAL_ACC2_ID 2621474 = SPI 4 ICM20948 (0x28),
    # CAL_MAG0_ID 589858 = SPI 4 AK09916 (0x09): the ICM-20948's compass, started by its -M
    log = pyulog.ULog(str(shared_file("sample_log_small.ulg")), [], False)
    params = log.initial_parameters
    assert [params[f"CAL_ACC{i}_ID"] for i in range(3)] == [2424842, 3670050, 2621474]
    assert params["CAL_MAG0_ID"] == 589858
    board = load_boards().for_ulog(log.msg_info_dict["ver_hw"], log.msg_info_dict["ver_sw_release"])
    assert board is not None
    on_spi = {(d.driver, d.kind, d.bus) for d in board.devices if d.bus_kind == "SPI"}
    assert {
        ("icm20649", "imu", 1),
        ("icm20602", "imu", 4),
        ("icm20948", "imu", 4),
        ("icm20948", "mag", 4),
    } <= on_spi


def test_ulog_of_sitl_and_of_an_old_release_name_no_board_entry() -> None:
    sitl = ulog_info("sample_px4_events.ulg")
    assert load_boards().for_ulog(str(sitl["ver_hw"]), int(sitl["ver_sw_release"])) is None  # type: ignore[call-overload]
    # PX4 v1.6 wrote board_config.h's BOARD_NAME "PX4FMU_V4PRO"; boards/ scripts came later
    old = ulog_info("sample_appended_multiple.ulg")
    assert old["ver_hw"] == "PX4FMU_V4PRO"
    table = load_boards()
    assert table.for_ulog("PX4FMU_V4PRO", None) == table.by_name("px4_fmu-v4pro")
    assert table.for_ulog(str(old["ver_hw"]), int(old["ver_sw_release"])) is None  # type: ignore[call-overload]


def test_mr_tropic_log_agrees_with_the_table_where_the_script_did_not_change() -> None:
    # frrs_ekf_failure.ulg: PX4 v1.15.0 beta from a vendor branch (before the board was merged);
    # its boot console prints where each driver started.
    path = shared_file("frrs_ekf_failure.ulg")
    log = pyulog.ULog(str(path), [], False)
    console = "".join(
        "".join(part) for part in log.msg_info_multiple_dict["boot_console_output"][0]
    )
    board = load_boards().for_ulog(log.msg_info_dict["ver_hw"], log.msg_info_dict["ver_sw_release"])
    assert board is not None and board.name == "nxp_mr-tropic"
    started = re.findall(r"^(\w+) #0 on I2C bus (\d+).*?rotation (\d+)", console, re.M)
    assert ("bmm350", "4", "6") in started and ("ist8310", "1", "10") in started
    for driver, bus, rotation in started:
        table_device = device(board, driver, bus=int(bus))
        assert table_device.rotation == int(rotation)
    # CAL_MAG1_ID 15012897 = I2C (1) bus 4 address 0x14 BMM350 (0xE5); CAL_BARO0_ID 7239201 =
    # I2C bus 4 address 0x76: the board's own compass, and the baro SENS_INT_BARO_EN starts
    params = log.initial_parameters
    assert (params["CAL_MAG1_ID"], params["CAL_BARO0_ID"]) == (15012897, 7239201)
    assert device(board, "bmm350").internal and device(board, "bmm350").bus == 4
    baro = switches(board, "SENS_INT_BARO_EN")
    assert [(s.driver, s.kind, s.bus, s.internal) for s in baro] == [("bmp388", "baro", 4, True)]
    # the vendor branch ran its launcher on bus 1; the merged board scans bus 3
    assert "running 'ina228 -X -b 1 -t 1 start'" in console
    assert board.i2c_launcher_buses == (3,)
    # what it found is what the launcher tries (src/systemcmds/i2c_launcher/i2c_launcher.hpp:
    # ina226 at 0x41, then ina228 and ina238 at 0x45)
    found = re.search(r"Found address (0x[0-9a-f]+), running '(\w+) (.*)'", console)
    assert found
    probes = [(p.address, p.driver) for p in board.i2c_launcher_probes]
    assert probes == [(0x41, "ina226"), (0x45, "ina228"), (0x45, "ina238")]
    assert (int(found[1], 16), found[2]) in probes
    args = board.i2c_launcher_probes[1].args.format(bus=1, index=1)
    assert found[3] == args == "-X -b 1 -t 1 start"


# -- bad rows ------------------------------------------------------------------------------------

GOOD = """
[[snapshot]]
release = "v1.14.0"
ref = "tag v1.14.0"
commit = "0123456789abcdef0123456789abcdef01234567"
date = "2023-10-23"

[[board]]
name = "px4_fmu-v5"
label = "Pixhawk 4"
ver_hw = ["PX4_FMU_V5"]
releases = ["v1.14.0"]
path = "boards/px4/fmu-v5/init/rc.board_sensors"
external_i2c_buses = [1, 2, 4]
internal_i2c_buses = [3]
i2c_launcher_buses = []

[[board.device]]
driver = "ist8310"
kind = "mag"
bus_kind = "I2C"
rotation = 10
internal = true
args = "-I -R 10 start"
line = 28

[[board.switch]]
param = "SENS_EN_X"
driver = "ms4525do"
kind = "other"
bus_kind = "I2C"
internal = false
args = "start -X"
line = 3
"""


def test_a_good_table_parses() -> None:
    table = parse_boards(GOOD)
    board = table.by_name("px4_fmu-v5", "v1.14.0")
    assert board is not None
    assert [s.bus for s in board.switches] == [1, 2, 4]
    assert board.source == (
        "PX4/PX4-Autopilot boards/px4/fmu-v5/init/rc.board_sensors at v1.14.0 "
        "(tag v1.14.0, 0123456789, 2023-10-23)"
    )


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "rotation = 10",
            "rotation = 99",
            "boards.toml: board 'px4_fmu-v5' at v1.14.0 device 1: "
            "rotation 99 is out of range 0..40",
        ),
        (
            'kind = "mag"',
            'kind = "compass"',
            "boards.toml: board 'px4_fmu-v5' at v1.14.0 device 1: "
            "kind 'compass' is not one of mag, baro, imu, power, other",
        ),
        (
            "rotation = 10",
            "rotation = 10\naddress = 0x80",
            "boards.toml: board 'px4_fmu-v5' at v1.14.0 device 1: "
            "address 128 is out of range 0..127",
        ),
        (
            'releases = ["v1.14.0"]',
            'releases = ["v1.14.1"]',
            "boards.toml: board 'px4_fmu-v5': "
            "release 'v1.14.1' is not a [[snapshot]] (known: v1.14.0)",
        ),
        (
            'param = "SENS_EN_X"\n',
            "",
            "boards.toml: board 'px4_fmu-v5' at v1.14.0 switch 1: missing key 'param'",
        ),
        (
            "internal = true",
            "internal = true\nbus_nr = 3",
            "boards.toml: board 'px4_fmu-v5' at v1.14.0 device 1: unknown key 'bus_nr' "
            "(expected one of driver, kind, bus_kind, internal, args, line, bus, address, "
            "rotation, when)",
        ),
        (
            'ver_hw = ["PX4_FMU_V5"]',
            'ver_hw = ["px4_fmu_v5"]',
            "boards.toml: board 'px4_fmu-v5' at v1.14.0: "
            "ver_hw 'px4_fmu_v5' is not upper case (PX4 writes it upper case)",
        ),
        (
            'name = "px4_fmu-v5"',
            'name = "Pixhawk 4"',
            "boards.toml: board 1: name 'Pixhawk 4' is not a PX4 target name like 'px4_fmu-v6c'",
        ),
        (
            'commit = "0123456789abcdef0123456789abcdef01234567"',
            'commit = "0123456"',
            "boards.toml: snapshot 'v1.14.0': commit '0123456' is not 40 hex digits",
        ),
        (
            "external_i2c_buses = [1, 2, 4]",
            'external_i2c_buses = ["1"]',
            "boards.toml: board 'px4_fmu-v5' at v1.14.0: "
            "external_i2c_buses ['1'] is not a list of integers 0..255",
        ),
        (
            'driver = "ist8310"',
            'driver = "IST8310"',
            "boards.toml: board 'px4_fmu-v5' at v1.14.0 device 1: "
            "driver 'IST8310' is not a PX4 module name (lower case, digits, _)",
        ),
        (
            "[[board]]",
            "[[board]]]",
            "boards.toml: not TOML: ",
        ),
    ],
)
def test_a_bad_row_is_named_in_one_line(old: str, new: str, message: str) -> None:
    assert old in GOOD
    with pytest.raises(BoardsFileError) as err:
        parse_boards(GOOD.replace(old, new, 1))
    text = str(err.value)
    assert text.startswith(message) if message.endswith(": ") else text == message
    assert "\n" not in text


def test_a_launcher_without_what_it_tries_is_refused() -> None:
    with pytest.raises(BoardsFileError) as err:
        parse_boards(GOOD.replace("i2c_launcher_buses = []", "i2c_launcher_buses = [1]"))
    assert str(err.value) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0: "
        "i2c_launcher_buses but no [[i2c_launcher]] row for 'v1.14.0'"
    )


def test_a_board_twice_for_one_release_is_refused() -> None:
    board = GOOD[GOOD.index("[[board]]") :]
    with pytest.raises(BoardsFileError) as err:
        parse_boards(GOOD + board)
    assert str(err.value) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0: "
        "release 'v1.14.0' already has a row for this board"
    )


def test_two_boards_with_one_ver_hw_are_refused() -> None:
    other = GOOD[GOOD.index("[[board]]") :].replace('name = "px4_fmu-v5"', 'name = "px4_fmu-v5x"')
    with pytest.raises(BoardsFileError) as err:
        parse_boards(GOOD + other)
    assert str(err.value) == (
        "boards.toml: board 'px4_fmu-v5x' at v1.14.0: "
        "ver_hw 'PX4_FMU_V5' already names board 'px4_fmu-v5'"
    )


# -- the table against PX4's scripts, where a PX4-Autopilot git directory is at hand --------------


def test_every_start_is_on_the_line_it_cites() -> None:
    dirs = px4_git_dirs()
    if not dirs:
        pytest.skip("no PX4-Autopilot git directory (set $PX4_AUTOPILOT_GIT)")
    cite = re.compile(r"PX4/PX4-Autopilot (\S+):(\d+) at \S+ \([^,]+, ([0-9a-f]{10}),")
    checked = 0
    table = load_boards()
    for board in table.all():
        for variant in table.variants(board.name):
            for start in (*variant.devices, *variant.switches):
                m = cite.match(start.source)
                assert m, start.source
                path, line, short = m.group(1), int(m.group(2)), m.group(3)
                text = show(tuple(dirs), short, path)
                if text is None:
                    pytest.skip(f"commit {short} is in none of {dirs}")
                written = text.split("\n")[line - 1]
                words = " ".join(written.split("#")[0].split())
                assert f"{start.driver} {start.args}" in words or (
                    start.args.replace(" start", "") in words and start.driver in words
                ), (start, written)
                checked += 1
            for probe in variant.i2c_launcher_probes:
                m = cite.match(probe.source)
                assert m, probe.source
                text = show(tuple(dirs), m.group(3), m.group(1))
                assert text is not None
                written = text.split("\n")[int(m.group(2)) - 1]
                assert f'{{"{probe.driver}", 0x{probe.address:02x},' in written.replace("0x0", "0x")
    assert checked > 1000


def test_every_launcher_bus_is_on_the_line_it_cites() -> None:
    # Each bus's `i2c_launcher start -b N` (every board that runs one: fmu-v6x, fmu-v6xrt at
    # v1.15.0, v1.18 and main; cuav fmu-v6x, godwit ga1, mr-tropic, tropic-community), checked
    # against the script at each snapshot at hand (v1.15.0, release/1.18 and main are in the
    # dakejahl mirror)
    dirs = px4_git_dirs()
    cite = re.compile(r"PX4/PX4-Autopilot (\S+):(\d+) at \S+ \([^,]+, ([0-9a-f]{10}),")
    table = load_boards()
    checked, missing = 0, set()
    skipped = 0
    for board in table.all():
        for variant in table.variants(board.name):
            sources = variant.i2c_launcher_sources
            for bus, source in zip(variant.i2c_launcher_buses, sources, strict=True):
                m = cite.match(source)
                assert m, source
                text = show(tuple(dirs), m.group(3), m.group(1))
                if text is None:
                    missing.add(m.group(3))
                    skipped += 1
                    continue
                words = text.split("\n")[int(m.group(2)) - 1].split()
                assert words[:4] == ["i2c_launcher", "start", "-b", str(bus)], (source, words)
                checked += 1
    if not checked:
        pytest.skip(f"commits {sorted(missing)} are in none of {dirs} (set $PX4_AUTOPILOT_GIT)")
    assert checked + skipped == 15  # 9 rows, 15 buses


# -- docs/boards.md -----------------------------------------------------------------------------

DOCS = Path(__file__).resolve().parents[1] / "docs" / "boards.md"
GENERATED = "<!-- generated from python/px4params/data/boards.toml"


def test_docs_table_is_the_toml() -> None:
    page = DOCS.read_text(encoding="utf-8")
    assert GENERATED in page
    generated = page.split(GENERATED, 1)[1].split("-->\n\n", 1)[1]
    assert generated == render_markdown(load_boards()), (
        "docs/boards.md is not boards.toml: regenerate its part after the 'generated' comment "
        "with px4params.vehicle.boards.render_markdown(load_boards())"
    )


def test_docs_python_example_prints_what_it_says(capsys: pytest.CaptureFixture[str]) -> None:
    page = DOCS.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", page, re.S)
    assert len(blocks) == 1
    exec(compile(blocks[0], str(DOCS), "exec"), {})
    promised = re.findall(r"# (.+)$", blocks[0], re.M)
    assert capsys.readouterr().out.splitlines() == promised


# -- issue 40: what the mutation run of boards.py let through -----------------------------------


@pytest.mark.issue40
def test_the_bundled_table_is_read_once_and_no_caller_can_change_it() -> None:
    """load_boards() is read once and shared by every caller (migration, the page's manifest):
    a row one caller could change would be changed for all of them."""
    table = load_boards()
    assert load_boards() is table
    board = table.by_name("px4_fmu-v5", "v1.13.0")
    v6x = table.by_name("px4_fmu-v6x")
    assert board is not None and v6x is not None
    rows: list[tuple[object, str]] = [
        (board, "label"),
        (board.devices[0], "rotation"),
        (board.switches[0], "bus"),
        (v6x.i2c_launcher_probes[0], "address"),
    ]
    for row, field in rows:
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(row, field, None)


@pytest.mark.issue40
def test_a_board_missing_from_a_release_is_described_by_its_nearest_row() -> None:
    """by_name's rule: a release older than the board's first snapshot reads its oldest row, one
    after the board was removed its newest. PX4-Autopilot's trees at the snapshots' commits:
    boards/zeroone/x6 first in release/1.18 (83c4f4e5), not at v1.15.0; boards/intel/aerofc-v1
    at v1.11.0 only; boards/nxp/fmurt1062-v1 at v1.11.0 .. v1.14.0, not at v1.15.0."""
    table = load_boards()
    x6 = table.by_name("zeroone_x6", "v1.15.0")  # one row, v1.18 and main
    assert x6 is not None and x6.releases == ("v1.18", "main")
    tropic = table.by_name("nxp_mr-tropic", "v1.15.0")  # rows v1.18, main: the oldest
    assert tropic is not None and tropic.releases == ("v1.18",)
    aerofc = table.by_name("intel_aerofc-v1")  # today's main: its one row, v1.11.0
    assert aerofc is not None and aerofc.releases == ("v1.11.0",)
    fmurt = table.by_name("nxp_fmurt1062-v1", "v1.15.0")  # rows v1.11.0, v1.12.0..v1.14.0
    assert fmurt is not None and fmurt.releases == ("v1.12.0", "v1.13.0", "v1.14.0")


def _with_snapshot(text: str, release: str) -> str:
    """GOOD with one more [[snapshot]] (before its first [[board]])."""
    snapshot = (
        f'[[snapshot]]\nrelease = "{release}"\nref = "tag {release}"\n'
        f'commit = "{"ab" * 20}"\ndate = "2024-08-29"\n\n'
    )
    at = text.index("[[board]]")
    return text[:at] + snapshot + text[at:]


LAUNCHER = """
[[i2c_launcher]]
releases = ["v1.14.0"]
path = "src/systemcmds/i2c_launcher/i2c_launcher.hpp"
args = "-X -b {bus} -t {bus} start"
probe = [
  { driver = "ina226", kind = "power", address = 0x41, line = 74 },
  { driver = "ina228", kind = "power", address = 0x45, line = 75 },
]
"""


def _rc_switch(param: str, driver: str, when: str, line: int, internal: str = "false") -> str:
    """One inline [[rc_sensors]] switch entry, started with -X (-I when internal) and no -b."""
    args = "start -I" if internal == "true" else "start -X"
    return (
        f'  {{ param = "{param}", driver = "{driver}", kind = "other", bus_kind = "I2C", '
        f'internal = {internal}, args = "{args}", when = "{when}", line = {line} }},\n'
    )


def _rc_sensors(*switch: str, release: str = "v1.14.0") -> str:
    return (
        f'\n[[rc_sensors]]\nreleases = ["{release}"]\n'
        f'path = "ROMFS/px4fmu_common/init.d/rc.sensors"\nswitch = [\n{"".join(switch)}]\n'
    )


RC_SENSORS = _rc_sensors(_rc_switch("SENS_EN_MS4525DO", "ms4525do", "SENS_EN_MS4525DO == 1", 20))


def _launching(text: str) -> str:
    """GOOD whose board runs the i2c_launcher on bus 1, with LAUNCHER's row."""
    launched = "i2c_launcher_buses = [1]\ni2c_launcher_lines = [40]"
    return text.replace("i2c_launcher_buses = []", launched) + LAUNCHER


def _refused(text: str) -> str:
    with pytest.raises(BoardsFileError) as err:
        parse_boards(text)
    assert "\n" not in str(err.value)
    return str(err.value)


def _board(text: str, release: str = "v1.14.0") -> Board:
    board = parse_boards(text).by_name("px4_fmu-v5", release)
    assert board is not None
    return board


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("old", "new", "field", "value"),
    [
        # the bounds each error message states are in the range: a bus 0..255, an I2C address
        # 0..127 (7 bits), a line 1..100000, a bus list's numbers 0..255
        ("rotation = 10", "rotation = 10\nbus = 0", "bus", 0),
        ("rotation = 10", "rotation = 10\nbus = 255", "bus", 255),
        ("rotation = 10", "rotation = 10\naddress = 0", "address", 0),
        ("rotation = 10", "rotation = 10\naddress = 0x7f", "address", 0x7F),
        ("line = 28", "line = 1", "line", 1),
        ("line = 28", "line = 100000", "line", 100_000),
        ("internal_i2c_buses = [3]", "internal_i2c_buses = [0, 255]", "internal", (0, 255)),
    ],
)
def test_a_value_at_a_bound_of_its_range_is_taken(
    old: str, new: str, field: str, value: object
) -> None:
    board = _board(GOOD.replace(old, new, 1))
    ist = board.devices[0]
    read = {
        "bus": ist.bus,
        "address": ist.address,
        "line": int(ist.source.split(" at ")[0].rsplit(":", 1)[1]),
        "internal": board.internal_i2c_buses,
    }
    assert read[field] == value


@pytest.mark.issue40
def test_launcher_values_at_the_bounds_of_their_ranges_are_taken() -> None:
    text = _launching(GOOD).replace("i2c_launcher_buses = [1]", "i2c_launcher_buses = [0, 255]")
    text = text.replace("i2c_launcher_lines = [40]", "i2c_launcher_lines = [1, 100000]")
    text = text.replace("address = 0x41, line = 74", "address = 0, line = 1")
    text = text.replace("address = 0x45, line = 75", "address = 0x7f, line = 100000")
    board = _board(text)
    assert board.i2c_launcher_buses == (0, 255)
    assert [p.address for p in board.i2c_launcher_probes] == [0, 0x7F]
    assert [p.source.split(" at ")[0].rsplit(":", 1)[1] for p in board.i2c_launcher_probes] == [
        "1",
        "100000",
    ]
    assert [s.split(" at ")[0].rsplit(":", 1)[1] for s in board.i2c_launcher_sources] == [
        "1",
        "100000",
    ]


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "rotation = 10",
            "rotation = 10\nbus = 256",
            "board 'px4_fmu-v5' at v1.14.0 device 1: bus 256 is out of range 0..255",
        ),
        (
            "line = 28",
            "line = 100001",
            "board 'px4_fmu-v5' at v1.14.0 device 1: line 100001 is out of range 1..100000",
        ),
        (
            "line = 28",
            "line = true",
            "board 'px4_fmu-v5' at v1.14.0 device 1: line True is not an integer",
        ),
        (
            "internal = true",
            "internal = 1",
            "board 'px4_fmu-v5' at v1.14.0 device 1: internal 1 is not true or false",
        ),
        (
            'label = "Pixhawk 4"',
            "label = 4",
            "board 'px4_fmu-v5' at v1.14.0: label 4 is not a non-empty string",
        ),
        (
            "internal_i2c_buses = [3]",
            "internal_i2c_buses = [256]",
            "board 'px4_fmu-v5' at v1.14.0: internal_i2c_buses [256] is not a list of integers "
            "0..255",
        ),
        (
            'releases = ["v1.14.0"]',
            'releases = [""]',
            "board 'px4_fmu-v5': releases [''] is not a non-empty list of strings",
        ),
        (
            'releases = ["v1.14.0"]',
            'releases = "v1.14.0"',
            "board 'px4_fmu-v5': releases 'v1.14.0' is not a non-empty list of strings",
        ),
        (
            'param = "SENS_EN_X"',
            'param = "sens_en_x"',
            "board 'px4_fmu-v5' at v1.14.0 switch 1: param 'sens_en_x' is not a PX4 parameter name",
        ),
        (
            'release = "v1.14.0"',
            'release = "latest"',
            "snapshot 'latest': release is not 'main' nor a PX4 version like 'v1.14.0'",
        ),
    ],
)
def test_a_bad_value_is_named_with_its_row(old: str, new: str, message: str) -> None:
    assert old in GOOD
    assert _refused(GOOD.replace(old, new, 1)) == f"boards.toml: {message}"


@pytest.mark.issue40
def test_bad_rows_of_the_file_as_a_whole_are_named() -> None:
    snapshot = GOOD[: GOOD.index("[[board]]")]
    assert _refused(snapshot + GOOD) == "boards.toml: snapshot 'v1.14.0': release appears twice"
    board = GOOD[GOOD.index("[[board]]") :]
    assert _refused("snapshot = []\n" + board) == "boards.toml: top level: no [[snapshot]] table"
    assert (
        _refused("snapshot = [1]\n" + board) == "boards.toml: snapshot 1: expected a table, got int"
    )
    assert _refused('rc_sensors = "rc.sensors"\n' + GOOD) == (
        "boards.toml: top level: rc_sensors is not a list of tables"
    )
    two = _with_snapshot(GOOD, "v1.15.0")
    assert _refused(two.replace('releases = ["v1.14.0"]', 'releases = ["v1.16.0"]')) == (
        "boards.toml: board 'px4_fmu-v5': release 'v1.16.0' is not a [[snapshot]] "
        "(known: v1.14.0, v1.15.0)"
    )
    # a board row over two snapshots is named with both
    both = two.replace('releases = ["v1.14.0"]', 'releases = ["v1.14.0", "v1.15.0"]')
    assert _refused(both.replace("internal = true", "internal = 1")) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0, v1.15.0 device 1: "
        "internal 1 is not true or false"
    )


@pytest.mark.issue40
def test_bad_rows_of_rc_sensors_and_the_launcher_are_named() -> None:
    assert _refused(GOOD + RC_SENSORS.replace('param = "SENS_EN_MS4525DO", ', "")) == (
        "boards.toml: rc_sensors 1 switch 1: missing key 'param'"
    )
    assert _refused(GOOD + RC_SENSORS + RC_SENSORS) == (
        "boards.toml: rc_sensors 2: release 'v1.14.0' has two [[rc_sensors]] rows"
    )
    assert _refused(_launching(GOOD).replace("address = 0x45", "address = 0x80")) == (
        "boards.toml: i2c_launcher 1 probe 2: address 128 is out of range 0..127"
    )
    assert _refused(_launching(GOOD).replace("line = 75", "line = 100001")) == (
        "boards.toml: i2c_launcher 1 probe 2: line 100001 is out of range 1..100000"
    )
    assert _refused(_launching(GOOD) + LAUNCHER) == (
        "boards.toml: i2c_launcher 2: release 'v1.14.0' has two [[i2c_launcher]] rows"
    )
    wide = _launching(GOOD).replace("i2c_launcher_buses = [1]", "i2c_launcher_buses = [256]")
    assert _refused(wide) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0: "
        "i2c_launcher_buses [256] is not a list of integers 0..255"
    )
    # each bus's `i2c_launcher start -b` line, so a condition of it is cited as a start's is
    unlined = _launching(GOOD).replace("i2c_launcher_lines = [40]", "i2c_launcher_lines = []")
    assert _refused(unlined) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0: "
        "i2c_launcher_lines [] do not give one line for each of i2c_launcher_buses [1]"
    )
    long = _launching(GOOD).replace("i2c_launcher_lines = [40]", "i2c_launcher_lines = [100001]")
    assert _refused(long) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0: "
        "i2c_launcher_lines [100001] is not a list of integers 1..100000"
    )


@pytest.mark.issue40
def test_a_start_behind_ver_hwcmp_is_only_the_listed_boards() -> None:
    """rc.sensors' ``if ver hwcmp A B`` runs its block on boards A and B only (PX4's ``ver
    hwcmp``: "Compare hardware version (returns 0 on match)", any of its arguments), written
    ``board in A,B`` by scripts/transcribe_boards.py; ``if ! ver hwcmp`` on every other board."""
    switches_of_v5 = _rc_sensors(
        _rc_switch("SENS_EN_A", "drv_a", "SENS_EN_A == 1 and board in PX4_FMU_V5X,PX4_FMU_V5", 10),
        _rc_switch("SENS_EN_B", "drv_b", "SENS_EN_B == 1 and board in PX4_FMU_V6X", 11),
        _rc_switch("SENS_EN_C", "drv_c", "not board in PX4_FMU_V5", 12),
        _rc_switch("SENS_EN_D", "drv_d", "not board in PX4_FMU_V6X", 13),
    )
    board = _board(GOOD + switches_of_v5)
    started = sorted({s.param for s in board.switches})
    assert started == ["SENS_EN_A", "SENS_EN_D", "SENS_EN_X"]


# The generated docs page is GitHub-flavoured Markdown: a "|" inside a table cell is written "\|"
# (GFM, tables: "include a pipe in a cell's content by escaping it").


@pytest.mark.issue40
def test_docs_tables_escape_a_pipe_and_name_every_internal_bus() -> None:
    piped = GOOD.replace('args = "-I -R 10 start"', 'args = "-I -R 10 start || true"')
    page = render_markdown(parse_boards(piped))
    assert "| `-I -R 10 start \\|\\| true` |" in page
    # an rc.sensors start with -I and no -b probes every internal I2C bus of the board
    internal = _rc_sensors(
        _rc_switch("SENS_EN_MS4525DO", "ms4525do", "SENS_EN_MS4525DO == 1", 20, internal="true")
    )
    page = render_markdown(parse_boards(GOOD + internal))
    rows = [line for line in page.splitlines() if line.startswith("| SENS_EN_MS4525DO |")]
    assert rows == [
        "| SENS_EN_MS4525DO | ms4525do | other | I2C every internal |  |  | yes | "
        "SENS_EN_MS4525DO == 1 | `start -I` | 20 |"
    ]


@pytest.mark.issue40
def test_docs_list_a_launcher_of_one_address_and_every_rc_sensors_row() -> None:
    # a launcher row that tries one address is listed with its command
    one = _launching(GOOD).replace(
        '  { driver = "ina228", kind = "power", address = 0x45, line = 75 },\n', ""
    )
    page = render_markdown(parse_boards(one))
    assert "**from v1.14.0**: `-X -b {bus} -t {bus} start`" in page
    # rc.sensors read at v1.14.0 and v1.18 but not at v1.15.0 (between them): both rows listed
    text = _with_snapshot(_with_snapshot(GOOD, "v1.15.0"), "v1.18") + RC_SENSORS
    text += _rc_sensors(
        _rc_switch("SENS_EN_MS4525DO", "ms4525do", "SENS_EN_MS4525DO == 1", 30), release="v1.18"
    )
    page = render_markdown(parse_boards(text))
    assert "**v1.14.0**" in page and "**v1.18**" in page


def test_the_transcription_refuses_a_launcher_bus_started_twice() -> None:
    # Pixhawk 6X (main): `i2c_launcher start -b 1` on line 61, `-b 2` on line 64, one line per
    # bus as the table cites them; the same script with `-b 1` started again at its end would
    # leave one bus with two lines, and the later one would stand for both: refused
    module = _transcriber()
    path = "boards/px4/fmu-v6x/init/rc.board_sensors"
    text = show(tuple(px4_git_dirs()), "bb59c637cd", path)
    if text is None:
        pytest.skip(f"commit bb59c637cd is in none of {px4_git_dirs()}")
    _, _, launcher = module.facts(text)
    assert [(bus, line) for bus, _, line in launcher] == [(1, 61), (2, 64)]
    assert module.launcher_keys(path, launcher)[:2] == [
        "i2c_launcher_buses = [1, 2]",
        "i2c_launcher_lines = [61, 64]",
    ]
    again = text + "\ni2c_launcher start -b 1\n"
    _, _, launcher = module.facts(again)
    with pytest.raises(AssertionError, match=r"-b 1' on lines 61, \d+: the board table cites"):
        module.launcher_keys(path, launcher)


def _transcriber() -> Any:
    import importlib.util

    script = Path(__file__).parents[1] / "scripts" / "transcribe_boards.py"
    spec = importlib.util.spec_from_file_location("transcribe_boards", script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_nxp_boards_number_their_i2c_buses_as_px4_does() -> None:
    # boards/nxp/fmuk66-v3/src/i2c.cpp: initI2CBusInternal(PX4_BUS_NUMBER_TO_PX4(1)) and
    # initI2CBusExternal(PX4_BUS_NUMBER_TO_PX4(0)); the K66's micro_hal.h defines
    # PX4_BUS_OFFSET 1 (Kinetis numbers buses from 0, PX4 from 1): external 1, internal 2.
    # mr-canhubk3 (S32K344, offset 1): external 1, internal 2; ucans32k146: external 1.
    table = load_boards()
    for name, release, external, internal in [
        ("nxp_fmuk66-v3", "v1.15.0", (1,), (2,)),
        ("nxp_fmuk66-e", "v1.11.0", (1,), (2,)),
        ("nxp_mr-canhubk3", "v1.18", (1,), (2,)),
        ("nxp_ucans32k146", "v1.18", (1,), ()),
    ]:
        board = table.by_name(name, release)
        assert board is not None, name
        assert (board.external_i2c_buses, board.internal_i2c_buses) == (external, internal), name
    # rc.board_sensors line 40 of mr-canhubk3: "bmp388 -X -a 0x77 start" behind
    # SENS_INT_BARO_EN probes the external bus 1 (with no bus known it probed none)
    canhub = table.by_name("nxp_mr-canhubk3", "v1.18")
    assert canhub is not None
    found = switches(canhub, "SENS_INT_BARO_EN")
    assert [(s.driver, s.bus, s.address) for s in found] == [("bmp388", 1, 0x77)]


def test_the_transcription_adds_the_chips_bus_offset_or_refuses() -> None:
    module = _transcriber()
    i2c = (
        "constexpr px4_i2c_bus_t px4_i2c_buses[I2C_BUS_MAX_BUS_ITEMS] = {\n"
        "\tinitI2CBusExternal(PX4_BUS_NUMBER_TO_PX4(0)),\n"
        "\tinitI2CBusInternal(PX4_BUS_NUMBER_TO_PX4(1)),\n"
        "\tinitI2CBusExternal(3),\n"
        "};\n"
    )
    files = {
        "path": "boards/acme/k1/init/rc.board_sensors",
        "src/i2c.cpp": i2c,
        "nuttx-config/nsh/defconfig": 'CONFIG_ARCH_CHIP="s32k3xx"\nCONFIG_ARCH_CHIP_S32K344=y\n',
    }
    offsets = {
        "CONFIG_ARCH_CHIP_MK66FN2M0VMD18": (1, "k66/micro_hal.h"),
        "CONFIG_ARCH_CHIP_S32K344": (1, "s32k34x/micro_hal.h"),
    }
    external, internal, path, source, lines = module.i2c_buses(files, offsets)
    assert (external, internal, path) == ([1, 3], [2], "src/i2c.cpp")
    assert lines == [2, 4, 3]  # buses 1 and 3, then 2
    assert source == "s32k34x/micro_hal.h (PX4_BUS_OFFSET 1, CONFIG_ARCH_CHIP_S32K344)"
    # A chip whose offset PX4's headers do not give: refused, not guessed
    unknown = dict(files, **{"nuttx-config/nsh/defconfig": "CONFIG_ARCH_CHIP_ACME9=y\n"})
    with pytest.raises(
        SystemExit,
        match=r"^boards/acme/k1/init/rc.board_sensors: src/i2c.cpp "
        r"numbers buses with PX4_BUS_NUMBER_TO_PX4, but no chip flag of its "
        r"nuttx-config/nsh/defconfig has a PX4_BUS_OFFSET \(expected one of ",
    ):
        module.i2c_buses(unknown, offsets)
    # Plain numbers need no offset
    plain = dict(files, **{"src/i2c.cpp": "initI2CBusExternal(1),\ninitI2CBusInternal(4),\n"})
    assert module.i2c_buses(plain, {}) == ([1], [4], "src/i2c.cpp", "", [1, 2])


def test_the_chips_bus_offsets_are_read_from_px4s_headers() -> None:
    # platforms/nuttx/src/px4/nxp/{k66,s32k34x}/include/px4_arch/micro_hal.h: PX4_BUS_OFFSET 1;
    # nxp/rt106x: 0; STM32's headers define none of their own (stm32_common's is shared)
    module = _transcriber()
    dirs = [d for d in px4_git_dirs() if show((d,), "bb59c637cd", "Makefile") is not None]
    if not dirs:
        pytest.skip(f"commit bb59c637cd is in none of {px4_git_dirs()}")
    offsets = module.bus_offsets(dirs[0], "bb59c637cd")
    assert offsets["CONFIG_ARCH_CHIP_MK66FN2M0VMD18"][0] == 1
    assert offsets["CONFIG_ARCH_CHIP_S32K344"][0] == 1
    assert offsets["CONFIG_ARCH_CHIP_S32K146"][0] == 1
    assert offsets["CONFIG_ARCH_CHIP_MIMXRT1062DVL6A"][0] == 0
    assert offsets["CONFIG_ARCH_CHIP_S32K344"][1].endswith(
        "nxp/s32k34x/include/px4_arch/micro_hal.h"
    )


# -- which buses a start can be on, as PX4's I2CBusIterator finds them ----------------------------
# platforms/common/i2c.cpp (main, bb59c637): I2CBusIterator::next, lines 80-96: an InternalBus
# filter (-I) keeps a bus only where `!px4_i2c_bus_external(bus)`, an ExternalBus filter (-X)
# only where `px4_i2c_bus_external(bus)`, and then `_bus == bus_data.bus || _bus == -1`: -b N
# is tried only if bus N passed the filter.


def test_an_explicit_bus_of_the_other_kind_finds_no_bus() -> None:
    # boards/nxp/mr-canhubk3/src/i2c.cpp (main) line 38:
    # initI2CBusInternal(PX4_BUS_NUMBER_TO_PX4(1)), bus 2 (the S32K344's PX4_BUS_OFFSET 1); its
    # rc.board_sensors line 22 "ist8310 -X -b 2 -R 10 start" and line 32 "lis3mdl -X -b 2 -R 2
    # start" ask for an external bus 2: none is found
    board = load_boards().by_name("nxp_mr-canhubk3")
    assert board is not None and board.internal_i2c_buses == (2,)
    for driver, line in (("ist8310", 22), ("lis3mdl", 32)):
        start = device(board, driver, bus=2)
        assert f"rc.board_sensors:{line} " in start.source
        assert board.buses_of(start) == () and board.bus_conditions(start) == ()
    # line 10, "ist8310 -X -b 1 -R 10 start": bus 1 is external (line 37), it is tried
    assert board.buses_of(device(board, "ist8310", bus=1)) == (1,)


def test_a_switch_on_a_bus_of_the_other_kind_is_no_switch_row() -> None:
    # GOOD's fmu-v5 buses: external 1, 2, 4; internal 3. "-I -b 1" and "-X -b 3" find nothing;
    # "-X -b 9", a bus the lists do not name, is kept (board_config.h's lists can be short).
    text = GOOD.replace('args = "start -X"', 'args = "start -I -b 1"\nbus = 1').replace(
        "internal = false", "internal = true"
    )
    assert _board(text).switches == ()
    text = GOOD.replace('args = "start -X"', 'args = "start -X -b 3"\nbus = 3')
    assert _board(text).switches == ()
    # "-X -b 9", a bus neither list names: where the lists are the board's i2c.cpp (PX4's
    # iterator walks only its px4_i2c_buses), none; where the table knows no file, kept
    text = GOOD.replace('args = "start -X"', 'args = "start -X -b 9"\nbus = 9')
    assert [(s.bus, s.bus_when) for s in _board(text).switches] == [(9, "")]
    path = 'internal_i2c_buses = [3]\ni2c_buses_path = "boards/px4/fmu-v5/src/i2c.cpp"'
    assert _board(text.replace("internal_i2c_buses = [3]", path)).switches == ()
    # a device row alike
    mag = GOOD.replace('args = "-I -R 10 start"', 'args = "-I -b 9 -R 10 start"\nbus = 9')
    assert [d.bus for d in _board(mag).devices] == [9]
    assert _board(mag).buses_of(_board(mag).devices[0]) == (9,)
    known = _board(mag.replace("internal_i2c_buses = [3]", path))
    assert known.buses_of(known.devices[0]) == () and known.bus_conditions(known.devices[0]) == ()


def test_a_bus_the_boards_i2c_cpp_does_not_declare_finds_no_bus() -> None:
    # PX4 v1.11.0: ROMFS/px4fmu_common/init.d/rc.sensors line 125 `ms5525_airspeed start -X -b
    # 2`, line 127 `ms5525_airspeed start -X`; boards/px4/fmu-v4/src/i2c.cpp declares one bus,
    # line 37 initI2CBusExternal(1). platforms/common/i2c.cpp (v1.11.0) lines 48-86: the
    # iterator visits px4_i2c_buses' entries only. So on fmu-v4 line 125 starts nothing.
    board = load_boards().by_name("px4_fmu-v4", "v1.11.0")
    assert board is not None and board.i2c_bus_source(1) is not None
    found = [s for s in board.switches if s.driver == "ms5525_airspeed"]
    assert [(s.args, s.bus) for s in found] == [("start -X", 1)]
    assert found[0].source.startswith(
        "PX4/PX4-Autopilot ROMFS/px4fmu_common/init.d/rc.sensors:127 at v1.11.0"
    )


def test_fmu_v3_makes_every_bus_external_on_cube_hardware() -> None:
    # boards/px4/fmu-v3/src/board_config.h line 96: #define BOARD_OVERRIDE_I2C_BUS_EXTERNAL; its
    # src/i2c.cpp lines 44-47: initI2CBusExternal(1), initI2CBusInternal(2); lines 50-63:
    # `if (HW_VER_FMUV3 == board_get_hw_version())` (line 52) every bus is external, else every
    # bus but 2. init.c lines 388-390: that version is the one whose hw_type is "V30"
    # (hw_type[1]++, hw_type[2] = '0' of "V2"), what `ver hwtypecmp V30` tests. Every snapshot.
    table = load_boards()
    for release in SNAPSHOTS:
        for name in ("px4_fmu-v2", "px4_fmu-v3"):
            board = table.by_name(name, None if release == "main" else release)
            assert board is not None and release in board.releases
            override = board.external_i2c_buses_when
            assert override is not None, (name, release)
            assert (override.when, override.external) == ("hw_type in V30", (1, 2))
            assert override.source.startswith(
                f"PX4/PX4-Autopilot boards/px4/{name[4:]}/src/i2c.cpp:52 at "
            )
            assert (board.i2c_buses(False), board.i2c_buses(True)) == ((1,), (2,))
            assert (board.i2c_buses(False, True), board.i2c_buses(True, True)) == ((1, 2), ())
    board = table.by_name("px4_fmu-v3")
    assert board is not None
    # rc.board_sensors line 12, "hmc5883 -T -I -R 4 start": bus 2, but not on a V30
    (hmc,) = [d for d in board.devices if d.driver == "hmc5883" and d.bus_kind == "I2C"]
    assert board.buses_of(hmc) == (2,) and board.buses_of(hmc, overridden=True) == ()
    assert board.bus_conditions(hmc) == ((2, "not hw_type in V30"),)
    # rc.sensors line 172, "ms4525do start -X": bus 1, and bus 2 on a V30
    found = switches(board, "SENS_EN_MS4525DO")
    assert [(s.bus, s.bus_when) for s in found] == [(1, ""), (2, "hw_type in V30")]
    # no other board of the table overrides it
    assert [b.name for b in table.all() if b.external_i2c_buses_when] == [
        "px4_fmu-v2",
        "px4_fmu-v3",
    ]


def test_the_override_is_on_the_line_it_cites() -> None:
    cite = re.compile(r"PX4/PX4-Autopilot (\S+):(\d+) at \S+ \([^,]+, ([0-9a-f]{10}),")
    dirs, checked = tuple(px4_git_dirs()), 0
    table = load_boards()
    for name in ("px4_fmu-v2", "px4_fmu-v3"):
        for variant in table.variants(name):
            assert variant.external_i2c_buses_when is not None
            m = cite.match(variant.external_i2c_buses_when.source)
            assert m
            text = show(dirs, m.group(3), m.group(1))
            if text is None:
                continue
            line = text.split("\n")[int(m.group(2)) - 1].strip()
            assert line == "if (HW_VER_FMUV3 == board_get_hw_version()) {"
            checked += 1
    if not checked:
        pytest.skip(f"no snapshot of fmu-v2/fmu-v3 in {dirs} (set $PX4_AUTOPILOT_GIT)")


OVERRIDE = 'external_i2c_buses_when = { when = "hw_type in V30", buses = [1, 2], line = 52 }'
OVERRIDDEN = GOOD.replace(
    "internal_i2c_buses = [3]",
    'internal_i2c_buses = [3]\ni2c_buses_path = "boards/px4/fmu-v5/src/i2c.cpp"\n' + OVERRIDE,
)


def test_a_good_override_parses() -> None:
    board = _board(OVERRIDDEN)
    assert board.external_i2c_buses_when is not None
    assert board.external_i2c_buses_when.source.startswith(
        "PX4/PX4-Autopilot boards/px4/fmu-v5/src/i2c.cpp:52 at v1.14.0"
    )
    assert (board.i2c_buses(False, True), board.i2c_buses(True, True)) == ((1, 2), (3, 4))


@pytest.mark.parametrize(
    ("new", "problem"),
    [
        ("external_i2c_buses_when = [1, 2]", "expected a table, got list"),
        (
            'external_i2c_buses_when = { when = "hw_type in V30", buses = [1, 2] }',
            "missing key 'line'",
        ),
        (
            OVERRIDE.replace("line = 52", "line = 52, bus = 2"),
            "unknown key 'bus' (expected one of when, buses, line)",
        ),
        (OVERRIDE.replace('"hw_type in V30"', '""'), "when '' is not a non-empty string"),
        (
            OVERRIDE.replace('"hw_type in V30"', '"hw_type in V30 and P == 1"'),
            "when 'hw_type in V30 and P == 1' is not one test (its negation is written 'not WHEN')",
        ),
        (
            OVERRIDE.replace('"hw_type in V30"', '"not hw_type in V30"'),
            "when 'not hw_type in V30' is not one test (its negation is written 'not WHEN')",
        ),
        (
            OVERRIDE.replace("[1, 2]", '["1"]'),
            "buses ['1'] is not a list of integers 0..255",
        ),
        (
            OVERRIDE.replace("[1, 2]", "[1, 5]"),
            "buses [5] are not I2C buses of the board (external [1, 2, 4], internal [3])",
        ),
        (OVERRIDE.replace("52", "0"), "line 0 is out of range 1..100000"),
    ],
)
def test_a_bad_override_is_named_in_one_line(new: str, problem: str) -> None:
    with pytest.raises(BoardsFileError) as err:
        parse_boards(OVERRIDDEN.replace(OVERRIDE, new))
    where = "boards.toml: board 'px4_fmu-v5' at v1.14.0 external_i2c_buses_when: "
    assert str(err.value) == where + problem


def test_an_override_without_its_file_is_refused() -> None:
    with pytest.raises(BoardsFileError) as err:
        parse_boards(
            GOOD.replace("internal_i2c_buses = [3]", "internal_i2c_buses = [3]\n" + OVERRIDE)
        )
    assert str(err.value) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0: external_i2c_buses_when but no "
        "i2c_buses_path (the file its line 52 is in)"
    )


# fmu-v3's src/i2c.cpp lines 44-63 at main, in our own spacing; and line 96 of its board_config.h
_FMUV3_I2C = """
constexpr px4_i2c_bus_t px4_i2c_buses[I2C_BUS_MAX_BUS_ITEMS] = {
\tinitI2CBusExternal(1),
\tinitI2CBusInternal(2),
};

bool px4_i2c_bus_external(int bus)
{
\tif (HW_VER_FMUV3 == board_get_hw_version()) {
\t\t/* every bus */
\t\treturn true;

\t} else {
\t\tif (bus != 2) {
\t\t\treturn true;
\t\t}
\t}

\treturn false;
}
"""
_OVERRIDING = {
    "path": "boards/px4/fmu-v3/init/rc.board_sensors",
    "src/board_config.h": "/* I2C busses */\n#define BOARD_OVERRIDE_I2C_BUS_EXTERNAL\n",
    "src/i2c.cpp": _FMUV3_I2C,
}


def test_the_transcription_reads_a_boards_own_px4_i2c_bus_external() -> None:
    module = _transcriber()
    assert module.bus_override(_OVERRIDING, [1], [2]) == {
        "when": "hw_type in V30",
        "buses": [1, 2],
        "line": 9,
    }
    # v1.11.0 to v1.13.0 took the bus's table entry: `(const px4_i2c_bus_t &bus)`, `bus.bus != 2`
    old = _FMUV3_I2C.replace("(int bus)", "(const px4_i2c_bus_t &bus)").replace(
        "(bus != 2)", "(bus.bus != 2)"
    )
    assert module.bus_override(dict(_OVERRIDING, **{"src/i2c.cpp": old}), [1], [2]) is not None
    # without the define, PX4's own px4_i2c_bus_external reads the lists
    plain = dict(_OVERRIDING, **{"src/board_config.h": "/* I2C busses */\n"})
    assert module.bus_override(plain, [1], [2]) is None


@pytest.mark.parametrize(
    ("change", "external", "internal", "problem"),
    [
        (
            ("return true;\n\n", "return bus == 1;\n\n"),
            [1],
            [2],
            ", but its src/i2c.cpp's px4_i2c_bus_external is not 'if (HW_VER_... == "
            "board_get_hw_version()) every bus external, else every bus but one'",
        ),
        (
            ("HW_VER_FMUV3 ==", "HW_VER_FMUV2MINI =="),
            [1],
            [2],
            ": no hardware type known for HW_VER_FMUV2MINI (['HW_VER_FMUV3'])",
        ),
        (
            ("", ""),
            [1],
            [2, 3],
            ": elsewhere every bus but 2 is external, not src/i2c.cpp's lists (external [1], "
            "internal [2, 3])",
        ),
    ],
)
def test_the_transcription_refuses_another_px4_i2c_bus_external(
    change: tuple[str, str], external: list[int], internal: list[int], problem: str
) -> None:
    module = _transcriber()
    files = dict(_OVERRIDING, **{"src/i2c.cpp": _FMUV3_I2C.replace(*change)})
    with pytest.raises(SystemExit) as err:
        module.bus_override(files, external, internal)
    assert str(err.value) == (
        "boards/px4/fmu-v3/init/rc.board_sensors: src/board_config.h defines "
        "BOARD_OVERRIDE_I2C_BUS_EXTERNAL" + problem
    )


def test_every_i2c_bus_is_on_the_line_it_cites() -> None:
    # Each bus of a row's lists names the line of i2c_buses_path that declares it:
    # initI2CBusExternal(N) / initI2CBusInternal(N) (or PX4_BUS_NUMBER_TO_PX4(N - 1) on the NXP
    # chips, whose PX4_BUS_OFFSET is 1), or board_config.h's PX4_I2C_BUS_EXPANSION* / _ONBOARD.
    cite = re.compile(r"PX4/PX4-Autopilot (\S+):(\d+) at \S+ \([^,]+, ([0-9a-f]{10}),")
    dirs, checked, missing = tuple(px4_git_dirs()), 0, set()
    table = load_boards()
    for board in table.all():
        for variant in table.variants(board.name):
            listed = (*variant.external_i2c_buses, *variant.internal_i2c_buses)
            assert [b for b, _ in variant.i2c_bus_sources] == list(listed), variant.name
            for bus, source in variant.i2c_bus_sources:
                m = cite.match(source)
                assert m, source
                text = show(dirs, m.group(3), m.group(1))
                if text is None:
                    missing.add(m.group(3))
                    continue
                written = text.split("\n")[int(m.group(2)) - 1]
                external = bus in variant.external_i2c_buses
                if m.group(1).endswith("i2c.cpp"):
                    kind = "External" if external else "Internal"
                    assert re.search(
                        rf"initI2CBus{kind}\(({bus}|PX4_BUS_NUMBER_TO_PX4\({bus - 1}\))\)", written
                    ), (source, written)
                else:
                    kind = r"EXPANSION\d*" if external else "ONBOARD"
                    assert re.search(rf"#define\s+PX4_I2C_BUS_{kind}\s+{bus}\b", written), source
                checked += 1
    if not checked:
        pytest.skip(f"commits {sorted(missing)} are in none of {dirs} (set $PX4_AUTOPILOT_GIT)")
    assert checked > 300


@pytest.mark.parametrize(
    ("lines", "problem"),
    [
        (
            "i2c_buses_lines = [37, 38]",
            "i2c_buses_lines [37, 38] do not give one line for each of external_i2c_buses "
            "[1, 2, 4] and internal_i2c_buses [3]",
        ),
        ("i2c_buses_lines = [1, 2, 3, 0]", "i2c_buses_lines [1, 2, 3, 0] is not a list of "
         "integers 1..100000"),
    ],
)  # fmt: skip
def test_bad_i2c_bus_lines_are_named_in_one_line(lines: str, problem: str) -> None:
    text = OVERRIDDEN.replace(OVERRIDE, lines)
    with pytest.raises(BoardsFileError) as err:
        parse_boards(text)
    assert str(err.value) == f"boards.toml: board 'px4_fmu-v5' at v1.14.0: {problem}"
    board = _board(OVERRIDDEN.replace(OVERRIDE, "i2c_buses_lines = [40, 41, 43, 42]"))
    assert board.i2c_bus_source(4) == (
        "PX4/PX4-Autopilot boards/px4/fmu-v5/src/i2c.cpp:43 at v1.14.0 (tag v1.14.0, "
        "0123456789, 2023-10-23)"
    )
    assert board.i2c_bus_source(5) is None


def test_i2c_bus_lines_without_their_file_are_refused() -> None:
    text = GOOD.replace(
        "internal_i2c_buses = [3]", "internal_i2c_buses = [3]\ni2c_buses_lines = [1]"
    )
    with pytest.raises(BoardsFileError) as err:
        parse_boards(text)
    assert str(err.value) == (
        "boards.toml: board 'px4_fmu-v5' at v1.14.0: i2c_buses_lines but no i2c_buses_path "
        "(the file they are lines of)"
    )


# -- `-X -b N` at v1.11.0: the N-th external bus ----------------------------------------------


def test_x_b_at_v1_11_0_is_the_nth_external_bus_of_px4_i2c_buses() -> None:
    # PX4 v1.11.0 platforms/common/i2c.cpp:72-79: the -X case counts each external bus of
    # px4_i2c_buses (++_external_bus_counter) and stops where `_bus == _external_bus_counter`;
    # 787f9c1213 ("use board-specific bus numbering for '-X -b <bus>'", first in v1.12.0) made
    # it `_bus == bus_data.bus`. Cube Orange v1.11.0 src/i2c.cpp:37-38: initI2CBusExternal(2),
    # then (1): its rc.board_sensors:17 `ak09916 -X -b 2 -R 6 start` is on bus 1 (the commit
    # changed that line to `-b 1`). Cube Yellow's are the same.
    table = load_boards()
    for name in ("cubepilot_cubeorange", "cubepilot_cubeyellow"):
        cube = table.by_name(name, "v1.11.0")
        assert cube is not None and cube.i2c_bus_order == (2, 1)
        (ak,) = [d for d in cube.devices if d.driver == "ak09916"]
        assert (ak.args, ak.source.split()[1].rsplit(":")[-1]) == ("-X -b 2 -R 6 start", "17")
        assert cube.bus_conditions(ak) == ((1, ""),) and cube.buses_of(ak) == (1,)

    # rc.sensors v1.11.0 line 125 `ms5525_airspeed start -X -b 2`, v1.12.0 line 161 `-X -b 2 -q`:
    # av_x-v1's i2c.cpp (the same file at both) lists external buses 2 then 4
    def ms5525(name: str, release: str) -> list[tuple[int, str]]:
        found = table.by_name(name, release)
        assert found is not None
        return [(s.bus, s.bus_when) for s in found.switches if "-b 2" in s.args]

    assert ms5525("av_x-v1", "v1.11.0") == [(4, "")]
    assert ms5525("av_x-v1", "v1.12.0") == [(2, "")]
    assert ms5525("cubepilot_cubeorange", "v1.11.0") == [(1, "")]
    assert ms5525("cubepilot_cubeorange", "v1.12.0") == [(2, "")]
    # fmu-v3 (i2c.cpp:45-46 buses 1 then 2): the second external bus exists only on a Cube (V30)
    assert ms5525("px4_fmu-v3", "v1.11.0") == [(2, "hw_type in V30")]
    # fmu-v4pro: one external bus (2): no second one at v1.11.0; bus 2 itself at v1.12.0
    assert ms5525("px4_fmu-v4pro", "v1.11.0") == []
    assert ms5525("px4_fmu-v4pro", "v1.12.0") == [(2, "")]


def test_each_snapshots_x_b_rule_is_its_i2c_cpps() -> None:
    # x_b_counts_external is true exactly where platforms/common/i2c.cpp's -X case compares -b
    # with _external_bus_counter (v1.11.0 line 76), false where with bus_data.bus
    dirs = px4_git_dirs()
    if not dirs:
        pytest.skip("no PX4-Autopilot git directory (set $PX4_AUTOPILOT_GIT)")
    text = (Path(__file__).parents[1] / "python/px4params/data/boards.toml").read_text()
    snapshots = tomllib.loads(text)["snapshot"]
    counted = {}
    for snap in snapshots:
        source = show(tuple(dirs), snap["commit"], "platforms/common/i2c.cpp")
        if source is None:
            pytest.skip(f"commit {snap['commit']} is in none of {dirs}")
        number = "if (_bus == bus_data.bus || _bus == -1)" in source.split("ExternalBus:")[1]
        counter = "if (_bus == _external_bus_counter || _bus == -1)" in source
        assert number != counter, snap["release"]
        counted[snap["release"]] = counter
        assert snap.get("x_b_counts_external", False) == counter, snap["release"]
    assert [r for r, c in counted.items() if c] == ["v1.11.0"] and len(counted) == 7


def test_a_snapshots_x_b_rule_is_true_or_false() -> None:
    date = 'date = "2023-10-23"\n'
    text = GOOD.replace(date, date + "x_b_counts_external = 1\n", 1)
    with pytest.raises(BoardsFileError) as err:
        parse_boards(text)
    assert str(err.value) == (
        "boards.toml: snapshot 'v1.14.0': x_b_counts_external 1 is not true or false"
    )


# -- `-S -b N`: the N-th external SPI bus ------------------------------------------------------


def test_s_b_is_the_nth_external_spi_bus_of_px4_spi_buses() -> None:
    # platforms/common/include/px4_platform_common/spi.h (v1.14.0 .. main): SPIBusIterator takes
    # `-S -b N` as the N-th external bus of px4_spi_buses (`_external_bus_counter`, from 1) and
    # `-S` alone as the first (`bus == -1 ? 1 : bus`). MR-CANHUBK3's src/spi.cpp lines 64-77
    # list SPI1, SPI2 external, SPI3 internal, SPI4, SPI5 external; s32k3xx's
    # hw_description.h numbers them from SPI0 = 1. So rc.board_sensors line 18 `icm42688p -c 1
    # -b 3 -R 10 -S ...` is on SPI4, PX4's bus 5, and line 15 `icm20649 -b 4 -S -R 10` on
    # SPI5, bus 6 (not buses 3 and 4, the -b as written, as the table had them).
    for release in ("v1.14.0", "v1.18", "v1.19.0"):  # v1.19.0: main's
        board = load_boards().by_name("nxp_mr-canhubk3", release)
        assert board is not None
        assert [b for b, _ in board.external_spi_buses] == [2, 3, 5, 6]
        assert board.external_spi_buses[2][1].startswith(
            "PX4/PX4-Autopilot boards/nxp/mr-canhubk3/src/spi.cpp:73 at main"
        )
        found = {
            (d.driver, d.source.split()[1].rsplit(":")[-1]): board.buses_of(d)
            for d in board.devices
            if d.bus_kind == "SPI"
        }
        assert found == {
            ("icm42688p", "7"): (5,),
            ("icm20649", "15"): (6,),
            ("icm42688p", "18"): (5,),
            ("icm20649", "25"): (6,),
            ("icm42688p", "28"): (5,),
        }
        assert "SPI buses from boards/nxp/mr-canhubk3/src/spi.cpp" in board.source
    # Raspberry Pi Pico: src/spi.cpp lists SPI0 internal, SPI1 external (rpi_common numbers
    # SPI0 = 1): `mpu9250 start -S` (line 9) is on the first external bus, PX4's bus 2
    pico = load_boards().by_name("raspberrypi_pico", "v1.15.0")
    assert pico is not None
    assert pico.buses_of(device(pico, "mpu9250")) == (2,)
    # AV-X v1: SPI2 external (stm32_common: SPI1 = 1): the adis16497 its script starts with -S
    # unless SENS_EN_PMW3901 is set is a switch row on bus 2 (before: no bus, no row)
    avx = load_boards().by_name("av_x-v1", "v1.15.0")
    assert avx is not None
    adis = [(s.driver, s.bus, s.when) for s in avx.switches if s.driver == "adis16497"]
    assert adis == [("adis16497", 2, "not SENS_EN_PMW3901 > 0")]


SPI_KEYS = (
    'external_spi_buses = [2, 3]\nspi_buses_path = "boards/px4/fmu-v5/src/spi.cpp"\n'
    "spi_buses_lines = [40, 44]\n"
)


def _spi_board(args: str, bus: int | None, keys: str = SPI_KEYS) -> Board:
    text = GOOD.replace("i2c_launcher_buses = []", keys + "i2c_launcher_buses = []")
    internal = "true" if "-s" in args else "false"
    row = f'bus_kind = "SPI"\nrotation = 10\ninternal = {internal}\nargs = "{args}"'
    row += f"\nbus = {bus}" if bus is not None else ""
    mag = 'bus_kind = "I2C"\nrotation = 10\ninternal = true\nargs = "-I -R 10 start"'
    return _board(text.replace(mag, row))


def test_an_external_spi_start_past_the_boards_external_buses_starts_nowhere() -> None:
    # two external SPI buses, 2 then 3: -S is bus 2, -S -b 2 bus 3, -S -b 3 none (PX4 counts
    # past the last and starts nothing), -S -b 0 none
    for args, bus, found in [
        ("-S -R 10 start", None, (2,)),
        ("-S -b 1 -R 10 start", 1, (2,)),
        ("-S -b 2 -R 10 start", 2, (3,)),
        ("-S -b 3 -R 10 start", 3, ()),
        ("-S -b 0 -R 10 start", 0, ()),
        # -s -b N: internal bus N itself (the InternalBus filter compares bus numbers)
        ("-s -b 4 -R 10 start", 4, (4,)),
        ("-s -R 10 start", None, ()),
    ]:
        board = _spi_board(args, bus)
        assert board.buses_of(board.devices[0]) == found, args
        assert board.bus_conditions(board.devices[0]) == tuple((b, "") for b in found), args
    # a board whose SPI buses the table does not know: -S names no bus (it had -b's number)
    board = _spi_board("-S -b 2 -R 10 start", 2, keys="")
    assert board.spi_buses_path == "" and board.buses_of(board.devices[0]) == ()
    keyed = GOOD.replace("i2c_launcher_buses = []", SPI_KEYS + "i2c_launcher_buses = []")
    page = render_markdown(parse_boards(keyed))
    assert "External SPI buses, in the order `-S -b N` counts them: [2, 3] " in page
    # the docs table names the bus PX4 counts to, or that there is none
    for args, bus, cell in [
        ("-S -b 2 -R 10 start", 2, "SPI 3"),
        ("-S -b 3 -R 10 start", 3, "SPI none"),
    ]:
        row = f'bus_kind = "SPI"\nrotation = 10\ninternal = false\nargs = "{args}"\nbus = {bus}'
        mag = 'bus_kind = "I2C"\nrotation = 10\ninternal = true\nargs = "-I -R 10 start"'
        page = render_markdown(parse_boards(keyed.replace(mag, row)))
        assert (
            f"|  | ist8310 | mag | {cell} |  | 10 | no |  | `{args.removesuffix(' start')}` | 28 |"
            in page
        )


@pytest.mark.parametrize(
    ("keys", "problem"),
    [
        (
            "external_spi_buses = [2]\n",
            "external_spi_buses but no spi_buses_path or spi_buses_lines (the three go together)",
        ),
        (
            'spi_buses_path = "x/spi.cpp"\nspi_buses_lines = [1]\n',
            "spi_buses_path but no external_spi_buses (the three go together)",
        ),
        (
            'external_spi_buses = [2, 3]\nspi_buses_path = "x/spi.cpp"\nspi_buses_lines = [1]\n',
            "spi_buses_lines [1] do not give one line for each of external_spi_buses [2, 3]",
        ),
        (
            'external_spi_buses = [256]\nspi_buses_path = "x/spi.cpp"\nspi_buses_lines = [1]\n',
            "external_spi_buses [256] is not a list of integers 0..255",
        ),
        (
            'external_spi_buses = [2]\nspi_buses_path = "x/spi.cpp"\nspi_buses_lines = [100001]\n',
            "spi_buses_lines [100001] is not a list of integers 1..100000",
        ),
    ],
)
def test_bad_spi_bus_keys_are_named_in_one_line(keys: str, problem: str) -> None:
    text = GOOD.replace("i2c_launcher_buses = []", keys + "i2c_launcher_buses = []")
    with pytest.raises(BoardsFileError) as err:
        parse_boards(text)
    assert str(err.value) == f"boards.toml: board 'px4_fmu-v5' at v1.14.0: {problem}"


def test_every_external_spi_bus_is_on_the_line_it_cites() -> None:
    # Each bus names the line of src/spi.cpp declaring it, initSPIBusExternal(SPI::Bus::X),
    # whose number the chip's SPI::Bus enum gives (every one read starts at 1, in order).
    cite = re.compile(r"PX4/PX4-Autopilot (\S+):(\d+) at \S+ \([^,]+, ([0-9a-f]{10}),")
    dirs, checked, missing = tuple(px4_git_dirs()), 0, set()
    table = load_boards()
    for board in table.all():
        for variant in table.variants(board.name):
            for bus, source in variant.external_spi_buses:
                m = cite.match(source)
                assert m and m.group(1) == variant.spi_buses_path, source
                text = show(dirs, m.group(3), m.group(1))
                if text is None:
                    missing.add(m.group(3))
                    continue
                written = text.split("\n")[int(m.group(2)) - 1]
                named = re.search(r"initSPIBusExternal\(SPI::Bus::(LP)?SPI(\d)\b", written)
                assert named, (source, written)
                # SPI0 = 1 on the NXP S32K and RP2040, SPI1 = 1 on the STM32
                first = 0 if variant.name.startswith(("nxp_", "raspberrypi_")) else 1
                assert int(named.group(2)) - first + 1 == bus, (source, written)
                checked += 1
    if not checked:
        pytest.skip(f"commits {sorted(missing)} are in none of {dirs} (set $PX4_AUTOPILOT_GIT)")
    assert checked == 9  # ark_cannode 2 rows, av_x-v1 2, pico 1: one bus each; canhubk3 4


def test_the_transcription_numbers_spi_buses_by_the_chips_enum() -> None:
    module = _transcriber()
    spi = (
        "constexpr px4_spi_bus_t px4_spi_buses[SPI_BUS_MAX_BUS_ITEMS] = {\n"
        "\tinitSPIBus(SPI::Bus::SPI1, {\n"
        "\t}),\n"
        "\tinitSPIBusExternal(SPI::Bus::SPI4, {\n"
        "\t}),\n"
        "\tinitSPIBusExternal(SPI::Bus::SPI2, {\n"
        "\t}),\n"
        "};\n"
    )
    files = {
        "path": "boards/acme/k1/init/rc.board_sensors",
        "src/spi.cpp": spi,
        # CONFIG_STM32_STM32F4XXX, the flag PX4's CMake tests, is one Kconfig derives
        "nuttx-config/nsh/defconfig": "CONFIG_ARCH_CHIP_STM32=y\nCONFIG_ARCH_CHIP_STM32F412CE=y\n",
    }
    chips = {
        ("CONFIG_STM32_STM32F10XX", "stm32f1"): ({"SPI1": 1, "SPI2": 2}, "f1.h"),
        ("CONFIG_STM32_STM32F4XXX", "stm32f4"): ({"SPI1": 1, "SPI2": 2, "SPI4": 4}, "f4.h"),
    }
    # in the table's order (4 before 2), each with its line
    assert module.spi_buses(files, chips) == {"buses": [4, 2], "lines": [4, 6], "source": "f4.h"}
    per_hw = dict(files, **{"src/spi.cpp": "constexpr px4_spi_bus_all_hw_t px4_spi_buses_all_hw"})
    assert module.spi_buses(per_hw, chips) is None
    assert module.spi_buses({"path": "p"}, chips) is None
    odd = dict(files, **{"src/spi.cpp": "initSPIBusExternal(SPI::Bus::SPI9, {"})
    with pytest.raises(SystemExit, match=r"^boards/acme/k1/init/rc.board_sensors: src/spi.cpp's "
                       r"SPI::Bus::SPI9 is not in f4.h$"):  # fmt: skip
        module.spi_buses(odd, chips)
    unknown = dict(files, **{"nuttx-config/nsh/defconfig": "CONFIG_ARCH_CHIP_ACME9=y\n"})
    expected = r"an SPI::Bus enum \(expected one of \['CONFIG_STM32_STM32F10XX', "
    with pytest.raises(
        SystemExit, match=r"no chip flag of its nuttx-config/nsh/defconfig has " + expected
    ):
        module.spi_buses(unknown, chips)


def test_the_chips_spi_bus_numbers_are_read_from_px4s_headers() -> None:
    dirs = [d for d in px4_git_dirs() if show((d,), "bb59c637cd", "Makefile") is not None]
    if not dirs:
        pytest.skip(f"commit bb59c637cd is in none of {px4_git_dirs()}")
    chips = _transcriber().spi_bus_numbers(dirs[0], "bb59c637cd")
    by_chip = {chip: numbers for (_, chip), (numbers, _) in chips.items()}
    # s32k3xx/include/px4_arch/hw_description.h: enum class Bus { SPI0 = 1, SPI1, ... SPI5 }
    assert by_chip["s32k34x"] == {f"SPI{i}": i + 1 for i in range(6)}
    # stm32_common's, which stm32f4 includes: SPI1 = 1 .. SPI6
    assert by_chip["stm32f4"] == {f"SPI{i}": i for i in range(1, 7)}
    assert by_chip["rp2040"] == {"SPI0": 1, "SPI1": 2}
