"""Issue 34's ten defects of ``px4params migrate``, one test each, on inputs of our own writing
(QGC ``.params`` text, a ``param set-default`` list, ULogs written with our ULog writer). Each
expected answer is PX4's behaviour as the issue states it, not what the code computes:

1. internal sensors (``CAL_MAGn_ROT = -1``) are started by the board's script, never instances;
2. ``CAL_<S>n_PRIO = 0`` disables a slot (PX4 1.12 on);
3. ``CAL_MAGn_ROT`` is calibration's; the driver's ``-R`` is the board's (probing passes none);
4. a QGC file's ``# Version:`` picks the devtype table; a file without one, its parameters;
5. a log without ``ver_sw_release`` is read with the era rule, not today's table;
6. a board-started barometer is not "found by probing, needs a type";
7. a power monitor ``i2c_launcher`` started (boot console) is carried over;
8. a switch-started driver runs where the evidence or the board says, one per power port;
9. a ``param set-default`` list (airframe syntax) is read;
10. one device in two slots is reported once, with both slots and their rotations named.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from px4params import migrate
from px4params.cli.main import main
from px4params.formats.ulog import ULogWriter
from px4params.vehicle import devid
from px4params.vehicle.boards import load_boards

IST8310_INTERNAL = devid.encode("i2c", 4, 0x0C, 0x06)  # 396321, Pixhawk 6C's
IST8310_GPS = devid.encode("i2c", 1, 0x0E, 0x06)  # 396809, a GPS puck's
QMC5883L_GPS = devid.encode("i2c", 1, 0x0D, 0x08)  # 527625
BMP390_INTERNAL = devid.encode("i2c", 4, 0x76, 0x6E)  # 7239201, MR-Tropic's


def params_file(path: Path, rows: dict[str, int | float], version: str | None = "1.15.4") -> Path:
    lines = ["# Onboard parameters for Vehicle 1", "#", "# Stack: PX4"]
    if version:
        lines.append(f"# Version: {version}")
    lines += ["#", "# Vehicle-Id Component-Id Name Value Type"]
    for name, value in rows.items():
        text, kind = (f"{value:.18f}", 9) if isinstance(value, float) else (str(value), 6)
        lines.append(f"1\t1\t{name}\t{text}\t{kind}")
    path.write_text("\n".join(lines) + "\n")
    return path


def ulog_file(
    path: Path,
    params: dict[str, int | float],
    console: str | None = None,
    release: int | None = 0x010F0000,  # 1.15.0
    hardware: str = "TEST_BOARD_NOT_IN_ANY_TABLE",
) -> Path:
    log = ULogWriter()
    log.info("ver_hw", hardware)
    if release is not None:
        log.info("ver_sw_release", release)
    for name, value in params.items():
        log.parameter(name, value)
    if console is not None:
        log.info("boot_console_output", console, multi=True)
    path.write_bytes(log.getvalue())
    return path


def run_json(path: Path, capsys: pytest.CaptureFixture[str], *extra: str) -> dict:
    assert main(["migrate", str(path), "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)


def instances(report: dict) -> list[tuple[str, int, int, int | None]]:
    return [
        (
            i["name"],
            i["values"]["bus.i2c.bus_id"],
            i["values"]["bus.i2c.address"],
            i["values"].get("rotation"),
        )
        for i in report["instances"]
    ]


def test_1_internal_compasses_are_the_boards(tmp_path: Path, capsys) -> None:
    path = params_file(
        tmp_path / "v6c.params", {"CAL_MAG0_ID": IST8310_INTERNAL, "CAL_MAG0_ROT": -1}
    )
    report = run_json(path, capsys)
    assert report["instances"] == []
    assert report["left_out"] == [
        {
            "found": f"CAL_MAG0_ID = {IST8310_INTERNAL}",
            "device": "IST8310 (MAG), I2C bus 4, address 0x0C",
            "reason": "board",
            "line": f"CAL_MAG0_ID = {IST8310_INTERNAL}: IST8310 (MAG), I2C bus 4, address 0x0C: "
            "CAL_MAG0_ROT = -1 (Internal): started by the board's script",
            "later": None,  # no board known: no later release compared
        }
    ]


def test_2_a_slot_with_priority_0_is_disabled(tmp_path: Path, capsys) -> None:
    rows = {"CAL_MAG2_ID": IST8310_GPS, "CAL_MAG2_PRIO": 0, "CAL_MAG2_ROT": 0}
    report = run_json(params_file(tmp_path / "stale.params", rows), capsys)
    assert report["instances"] == []
    (item,) = report["left_out"]
    assert item["reason"] == "disabled"
    assert item["line"].endswith(
        ": disabled (CAL_MAG2_PRIO = 0): not proposed, an instance would make it required"
    )


def test_3_calibration_rotation_is_not_the_drivers(tmp_path: Path, capsys) -> None:
    rows = {"CAL_MAG1_ID": IST8310_GPS, "CAL_MAG1_ROT": 4, "CAL_MAG1_PRIO": 75}
    report = run_json(params_file(tmp_path / "tte.params", rows, "1.13.0 beta"), capsys)
    assert instances(report) == [("IST8310#0", 1, 0x0E, 0)]
    assert report["instances"][0]["notes"] == [
        "CAL_MAG1_ROT = 4 stays a classic parameter: calibration applies it; the driver's "
        "rotation is 0 (rc.sensors starts it without -R)"
    ]
    assert "param set-default IST8310#0[6] 4" not in report["airframe"]
    # A driver started with -R (the boot console says so) keeps that rotation: the board's.
    console = "ist8310 #0 on I2C bus 1 (external) address 0xE rotation 10\n"
    log = ulog_file(tmp_path / "r.ulg", {"CAL_MAG0_ID": IST8310_GPS, "CAL_MAG0_ROT": 0}, console)
    report = run_json(log, capsys)
    assert report["instances"] == []
    assert report["left_out"][0]["line"].endswith(
        ": runs with rotation 10 (boot console line 1): rc.sensors probes without -R, so the "
        "board's script started it"
    )


def test_4_the_qgc_version_line_picks_the_devtype_table(tmp_path: Path, capsys) -> None:
    """0x16 on SPI: an MPU9250 accelerometer in PX4 1.6's drv_sensor.h, today FLOW SIM."""
    acc = devid.encode("spi", 1, 4, 0x16)
    report = run_json(params_file(tmp_path / "old.params", {"CAL_ACC0_ID": acc}, "1.6.5"), capsys)
    assert (report["table"], report["version"]) == ("px4-v1.6", "1.6.5")
    assert report["left_out"][0]["device"] == "MPU9250 (ACC), SPI bus 1, device 4"
    headerless = params_file(tmp_path / "2016.params", {"CAL_ACC0_ID": acc}, None)
    report = run_json(headerless, capsys)
    assert report["table"] == "px4-v1.6"
    assert report["assumptions"][0] == (
        "no firmware version and no CAL_*_PRIO parameters (PX4 before 1.12): the px4-v1.6 "
        "devtype table is assumed (files without a version predate it: ULog's ver_sw_release and "
        "QGC's '# Version' came with PX4 1.6)"
    )


def test_5_a_log_without_a_release_uses_the_era_rule(tmp_path: Path, capsys) -> None:
    acc = devid.encode("spi", 1, 4, 0x16)
    log = ulog_file(tmp_path / "2016.ulg", {"CAL_ACC0_ID": acc, "CAL_MAG0_EN": 1}, release=None)
    report = run_json(log, capsys)
    assert report["table"] == "px4-v1.6" and report["version"] is None
    assert report["left_out"][0]["device"] == "MPU9250 (ACC), SPI bus 1, device 4"


def test_6_a_board_started_barometer_needs_no_type(tmp_path: Path, capsys) -> None:
    console = "bmp390 #0 on I2C bus 4 address 0x76\n"
    log = ulog_file(tmp_path / "baro.ulg", {"CAL_BARO0_ID": BMP390_INTERNAL}, console)
    report = run_json(log, capsys)
    assert not [n for n in report["not_carried"] if "found by probing" in n]
    (item,) = report["left_out"]
    assert (item["reason"], item["device"]) == ("board", "BMP390 (BARO), I2C bus 4, address 0x76")
    assert item["line"].endswith(
        ": on an internal bus (boot console line 1): started by the board's startup scripts"
    )
    # A .params file says nothing of the board: the barometer is assumed the board's, said so.
    report = run_json(params_file(tmp_path / "b.params", {"CAL_BARO0_ID": BMP390_INTERNAL}), capsys)
    assert report["left_out"][0]["reason"] == "board"
    assert (
        "I2C barometers without a board table row are taken as started by the board's script "
        "(barometers sit on the flight controller)"
    ) in report["assumptions"]


def test_7_a_monitor_the_i2c_launcher_started_is_carried(tmp_path: Path, capsys) -> None:
    console = (
        "INFO  [i2c_launcher] Found address 0x45, running 'ina228 -X -b 1 -t 1 start'\n"
        "ina228 #0 on I2C bus 1 (external) address 0x45\n"
    )
    rows = {"SENS_EN_INA226": 0, "SENS_EN_INA228": 0, "SENS_EN_INA238": 0}
    report = run_json(ulog_file(tmp_path / "l.ulg", rows, console), capsys)
    assert instances(report) == [("INA228#0", 1, 0x45, None)]
    (ina,) = report["instances"]
    assert ina["origin"] == (
        "boot console line 1: 'INFO  [i2c_launcher] Found address 0x45, running 'ina228 -X -b 1 "
        "-t 1 start'' (found by i2c_launcher)"
    )
    assert report["left_out"] == []


def test_8_switch_started_drivers_run_where_the_evidence_says(tmp_path: Path, capsys) -> None:
    console = "ms4525do #0 on I2C bus 2 (external) address 0x28\n"
    log = ulog_file(tmp_path / "a.ulg", {"SENS_EN_MS4525DO": 1}, console)
    report = run_json(log, capsys)
    assert instances(report) == [("MS4525DO#0", 2, 0x28, None)]
    assert not [a for a in report["assumptions"] if "is a guess" in a]
    # Without evidence, one instance per row of the board's switch (one per power port). PX4's
    # boards/px4/fmu-v6x/init/rc.board_sensors: `if param compare SENS_EN_INA238 1` starts
    # `ina238 -X -b 1 -t 1 -k start`, and `ina238 -X -b 2 -t 2 -k start` when the board has
    # its second power port ($HAVE_PM2); the board table's rows name their lines.
    board = load_boards().by_name("px4_fmu-v6x")
    assert board is not None
    rows = [s for s in board.switches if s.param == "SENS_EN_INA238"]
    assert [(r.bus, r.args) for r in rows] == [
        (1, "-X -b 1 -t 1 -k start"),
        (2, "-X -b 2 -t 2 -k start"),
    ]
    assert all("boards/px4/fmu-v6x/init/rc.board_sensors:" in r.source for r in rows)
    config = migrate.read_config(params_file(tmp_path / "p.params", {"SENS_EN_INA238": 1}))
    proposal = migrate.migrate(config, board=board)
    got = [
        (i.name, i.values["bus.i2c.bus_id"], i.values["bus.i2c.address"])
        for i in proposal.instances
    ]
    assert got == [("INA238#0", 1, 0x45), ("INA238#1", 2, 0x45)]
    assert proposal.instances[1].origin == (
        "SENS_EN_INA238 = 1: ina238 started on I2C bus 2 (the board starts it with 'ina238 -X -b "
        f"2 -t 2 -k start' ({rows[1].source})) at the driver's default address 0x45"
    )
    assert proposal.board == "px4_fmu-v6x"
    # Nothing says where: bus 1, and the report says it guessed.
    report = run_json(params_file(tmp_path / "q.params", {"SENS_EN_MS4525DO": 1}), capsys)
    assert instances(report) == [("MS4525DO#0", 1, 0x28, None)]
    assert (
        "SENS_EN_MS4525DO: I2C bus 1 is a guess (PX4 starts ms4525do -X, on every external bus; "
        "nothing here says which bus it is on)"
    ) in report["assumptions"]


def test_9_a_param_set_default_list_is_read(tmp_path: Path, capsys) -> None:
    path = tmp_path / "airframe.params"
    path.write_text(
        "# exported from an airframe\n"
        "param set-default SENS_EN_INA238 1\n"
        f"param set CAL_MAG1_ID {QMC5883L_GPS}\n"
        "param set CAL_MAG1_PRIO 50\n"
        "param set-default INA238_CURRENT 120.4  # the 120 A module\n"
        "set VEHICLE_TYPE mc\n"
    )
    config = migrate.read_config(path)
    assert config.kind == "param set list"
    assert config.params == {
        "SENS_EN_INA238": 1,
        "CAL_MAG1_ID": QMC5883L_GPS,
        "CAL_MAG1_PRIO": 50,
        "INA238_CURRENT": 120.4,
    }
    assert config.skipped == [
        "line 6: 'set VEHICLE_TYPE mc': not a 'param set NAME VALUE' command, not read"
    ]
    report = run_json(path, capsys)
    # No version: CAL_MAG1_PRIO (PX4 1.12 on) says today's devtype table, and the report says so.
    assert report["table"] == "current"
    assert report["assumptions"][0].startswith("no firmware version: CAL_MAG1_PRIO exists")
    assert instances(report) == [("INA238#0", 1, 0x45, None), ("QMC5883L#0", 1, 0x0D, 0)]
    assert report["instances"][0]["values"]["current"] == 120
    bad = tmp_path / "bad.params"
    bad.write_text("param set-default SENS_EN_INA238 1\nparam set CAL_MAG1_ID 0x09zz\n")
    with pytest.raises(migrate.MigrationError) as e:
        migrate.read_config(bad)
    assert str(e.value) == f"{bad}:2: CAL_MAG1_ID: value '0x09zz' is not a number"
    assert main(["migrate", str(bad)]) == 1
    assert capsys.readouterr().err == (
        f"px4params: error: {bad}:2: CAL_MAG1_ID: value '0x09zz' is not a number\n"
    )


def test_a_version_less_list_of_px4_1_14_is_not_read_as_1_6(tmp_path: Path, capsys) -> None:
    """Found with the corpus (PX4's docs asset reptile_dragon_2_params.params, a set-default
    list with OSD_SCROLL_RATE): a version-less file without CAL_*_PRIO was read with the
    px4-v1.6 table although it holds a parameter PX4 1.13 did not have. A GPS's QMC5883P
    (devtype 0x0F, which drv_sensor.h of 1.6 does not name) then became "no bundled parameter
    type" instead of the instance that probing found; OSD_SCROLL_RATE (msp_osd, not in the v1.13
    tree) says PX4 1.14 or later, so today's table applies."""
    qmc5883p = devid.encode("i2c", 1, 0x2C, 0x0F)
    path = tmp_path / "plane.params"
    path.write_text(
        f"param set-default CAL_MAG1_ID {qmc5883p}\n"
        "param set-default CAL_MAG1_ROT 0\n"
        "param set-default OSD_SCROLL_RATE 50\n"
    )
    report = run_json(path, capsys)
    assert report["table"] == "current"
    assert report["assumptions"][0] == (
        "no firmware version: OSD_SCROLL_RATE exists (PX4 1.14 and later; not in 1.13, "
        "src/drivers/osd/msp_osd/module.yaml), so today's devtype table is assumed"
    )
    assert instances(report) == [("QMC5883P#0", 1, 0x2C, 0)]
    assert report["not_carried"] == []
    # Without such a parameter the era rule stays: a file without a version predates 1.6.
    path.write_text(f"param set-default CAL_MAG1_ID {qmc5883p}\n")
    assert run_json(path, capsys)["table"] == "px4-v1.6"


def test_10_one_device_in_two_slots_is_reported_once(tmp_path: Path, capsys) -> None:
    rows = {
        "CAL_MAG0_ID": QMC5883L_GPS, "CAL_MAG0_ROT": 0,
        "CAL_MAG3_ID": QMC5883L_GPS, "CAL_MAG3_ROT": 2,
    }  # fmt: skip
    report = run_json(params_file(tmp_path / "twice.params", rows), capsys)
    assert instances(report) == [("QMC5883L#0", 1, 0x0D, 0)]
    notes = report["instances"][0]["notes"]
    assert notes[0] == (
        "CAL_MAG0_ID and CAL_MAG3_ID hold the same device (reported once), with different "
        "rotations (CAL_MAG0_ROT = 0, CAL_MAG3_ROT = 2)"
    )


def test_an_unknown_board_is_refused(tmp_path: Path, capsys) -> None:
    path = params_file(tmp_path / "p.params", {"SENS_EN_INA238": 1})
    assert main(["migrate", str(path), "--board", "no_such-board"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("px4params: error: ")
    assert "no_such-board" in err


def test_a_board_known_only_for_later_releases_is_named_so(tmp_path: Path, capsys) -> None:
    """Found with the corpus (congtranv/px4-param's Pixhawk 4 file of PX4 1.10.1, and
    flight-review-rs's Pixhawk 2 log of 1.9.0): the board table starts at PX4 v1.11.0, and a
    board it has was called "unknown board 'px4_fmu-v5'" for an older file (and a log's
    ver_hw "not in the board table"). The board is known; its start scripts of that release
    are not, and the message says that."""
    path = params_file(tmp_path / "pixhawk4.params", {"CAL_MAG0_ID": IST8310_GPS}, "1.10.1 dev")
    assert main(["migrate", str(path), "--board", "px4_fmu-v5"]) == 1
    assert capsys.readouterr().err == (
        f"px4params: error: --board px4_fmu-v5: the board table describes PX4 v1.11.0 and "
        f"later, {path} is of PX4 1.10.1 (run without --board: the parameters and assumptions "
        "decide)\n"
    )
    # Of a release the table has, the board's facts apply.
    assert run_json(params_file(path, {"CAL_MAG0_ID": IST8310_GPS}, "1.13.0"), capsys, "--board",
                    "px4_fmu-v5")["board"] == "px4_fmu-v5"  # fmt: skip
    log = ulog_file(tmp_path / "v3.ulg", {"CAL_MAG0_ID": IST8310_GPS}, release=0x010900FF,
                    hardware="PX4_FMU_V3")  # fmt: skip
    report = run_json(log, capsys)
    assert report["board"] is None
    assert report["assumptions"][0] == (
        "board PX4_FMU_V3: px4_fmu-v3 in the board table from PX4 v1.11.0 on, not for this log's "
        "1.9.0; what its script starts is judged from the parameters and the boot console"
    )


def test_another_autopilots_file_is_refused(tmp_path: Path, capsys) -> None:
    """Found with the corpus (gyumingim/drone's param.params, an ArduPilot Copter 4.6.3 file
    QGC wrote): it was "migrated" as PX4's, its version 4.6.3 picking today's devtype table and
    1047 ArduPilot parameters reported as classic parameters that stay. QGC's '# Stack:' line
    names the firmware; only PX4's parameters mean anything to a PX4 manifest."""
    path = tmp_path / "copter.params"
    path.write_text(
        "# Onboard parameters for Vehicle 1\n#\n# Stack: ArduPilot\n# Vehicle: Quadrotor\n"
        "# Version: 4.6.3 \n#\n# Vehicle-Id Component-Id Name Value Type\n"
        "1\t1\tINS_ACC_ID\t3408650\t6\n"
    )
    assert main(["migrate", str(path)]) == 1
    assert capsys.readouterr().err == (
        f"px4params: error: {path}:3: '# Stack: ArduPilot': not a PX4 parameter file (QGC "
        "writes 'PX4' or 'PX4 Pro' there for PX4's)\n"
    )
    # QGC's two spellings of PX4 are read.
    for stack in ("PX4", "PX4 Pro"):
        path.write_text(path.read_text().replace("ArduPilot", stack, 1))
        assert run_json(path, capsys)["kind"] == "QGC .params"
        path.write_text(path.read_text().replace(stack, "ArduPilot", 1))


def test_the_board_table_says_what_the_board_starts(tmp_path: Path) -> None:
    """A board row starting a compass leaves that compass out, naming the row; `-I` without
    `-b` covers the internal buses only, so a GPS compass on another external bus is still an
    instance. A switch whose rows have no -b (rc.sensors' `-X`: every external bus) gives one
    instance and says the bus is not known; the launcher's buses are reported when nothing says
    what it found. Pixhawk 4 (px4_fmu-v5), as PX4's boards/px4/fmu-v5/init/rc.board_sensors
    starts it: `ist8310 -I -R 10 start` (internal I2C bus 3) and `ist8310 -X -b 1 -R 10 start`
    (its GPS port, external bus 1); external buses 1, 2, 4 (boards/px4/fmu-v5/src/i2c.cpp)."""
    boards = load_boards()
    board = boards.by_name("px4_fmu-v5")
    assert board is not None
    assert (board.external_i2c_buses, board.internal_i2c_buses) == ((1, 2, 4), (3,))
    ist8310 = {d.args: d for d in board.devices if d.driver == "ist8310"}
    internal, gps = ist8310["-I -R 10 start"], ist8310["-X -b 1 -R 10 start"]
    ms4525do = [s for s in board.switches if s.param == "SENS_EN_MS4525DO"]
    assert [(s.bus, s.args) for s in ms4525do] == [
        (1, "start -X"),
        (2, "start -X"),
        (4, "start -X"),
    ]
    rows = {
        "CAL_MAG0_ID": devid.encode("i2c", 3, 0x0E, 0x06), "CAL_MAG0_ROT": -1,
        "CAL_MAG1_ID": IST8310_GPS, "CAL_MAG1_ROT": 0,
        "CAL_MAG2_ID": devid.encode("i2c", 2, 0x0E, 0x06), "CAL_MAG2_ROT": 0,
        "SENS_EN_MS4525DO": 1,
    }  # fmt: skip
    proposal = migrate.migrate(migrate.read_config(params_file(tmp_path / "b.params", rows)),
                               board=board)  # fmt: skip
    got = [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances]
    assert got == [("MS4525DO#0", 1), ("IST8310#0", 2)]
    lines = {o.found.split(" = ")[0]: o.line for o in proposal.left_out}
    assert lines["CAL_MAG0_ID"].endswith(f": started by the board's script ({internal.source})")
    assert lines["CAL_MAG1_ID"].endswith(f": started by the board's script ({gps.source})")
    assert proposal.assumptions == [
        "SENS_EN_MS4525DO: px4_fmu-v5 starts 'ms4525do start -X' on every external I2C bus (1, "
        f"2, 4; {ms4525do[0].source}), so the bus it is found on is not known: bus 1 proposed",
    ]
    # Pixhawk 6X runs `i2c_launcher start -b 1` (and `-b 2` with its second power port) when
    # no SENS_EN_INA2xx is 1 (boards/px4/fmu-v6x/init/rc.board_sensors, lines 61 and 64).
    v6x = boards.by_name("px4_fmu-v6x")
    assert v6x is not None and v6x.i2c_launcher_buses == (1, 2)
    proposal = migrate.migrate(
        migrate.read_config(params_file(tmp_path / "c.params", {"SENS_EN_MS4525DO": 0})),
        board=v6x,
    )
    assert proposal.assumptions == [
        "the board's i2c_launcher scans I2C bus 1, 2 for power monitors (INA226, INA228, "
        "INA238) when no SENS_EN_INA2xx is 1: a QGC .params does not say which it found; bus 2 "
        "only where $HAVE_PM2 == yes (PX4/PX4-Autopilot boards/px4/fmu-v6x/init/"
        "rc.board_sensors:5 at main (branch main, bb59c637cd, 2026-08-13) sets HAVE_PM2 "
        "yes; line 8: no where mft MFT_PM2 == 0 (the board's hardware manifest, which the "
        "parameters do not tell)) (PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors:64 "
        "at main (branch main, bb59c637cd, 2026-08-13))",
    ]
    # With a power-monitor switch set, $INA_CONFIGURED is yes and the launcher does not run:
    # the switch's starts are what runs, and nothing is left to guess about the launcher.
    proposal = migrate.migrate(
        migrate.read_config(params_file(tmp_path / "d.params", {"SENS_EN_INA238": 1})),
        board=v6x,
    )
    assert [i.name for i in proposal.instances] == ["INA238#0", "INA238#1"]
    assert not [a for a in proposal.assumptions if "i2c_launcher" in a], proposal.assumptions


def test_console_lines_are_read_as_px4_prints_them() -> None:
    from px4params.vehicle.console import started_drivers

    console = (
        "ms5611 #0 on SPI bus 1 (devid=0x3d)\n"
        "ak09916 #0 on I2C bus 1 (external, equal to '-b 2')\n"
        "bmm350 #0 on I2C bus 4 address 0x14 rotation 6\n"
        "INFO  [i2c_launcher] Found address 0x41, running 'ina226 -X -b 2 -a 0x41 -t 2 start'\n"
        "ina226 #0 on I2C bus 2 (external) address 0x41\n"
        "INFO  [i2c_launcher] Found address 0x45, running 'ina238 -X -b 1 -a 0xzz start'\n"
        "WARN  [SPI_I2C] ist8310: no instance started (no device on bus?)\n"
    )
    got = [
        (s.driver, s.bus_kind, s.bus, s.external, s.address, s.rotation, s.launcher, s.line)
        for s in started_drivers(console)
    ]
    assert got == [
        ("ms5611", "SPI", 1, False, None, None, False, 1),
        ("ak09916", "I2C", 1, True, None, None, False, 2),
        ("bmm350", "I2C", 4, False, 0x14, 6, False, 3),
        ("ina226", "I2C", 2, True, 0x41, None, True, 4),  # the launcher's, with the driver's line
        ("ina238", "I2C", 1, True, 0x45, None, True, 6),  # a bad -a keeps the found address
    ]


def test_migrate_needs_no_checkout_and_no_variable(tmp_path: Path) -> None:
    """Today's devtype table ships with px4params: an installed `px4params migrate` decodes a
    1.15 file's AK09916 (0x09) in any folder, with no $PX4PARAMS_DEVTYPES."""
    import os
    import subprocess
    import sys

    path = params_file(tmp_path / "v.params", {"CAL_MAG1_ID": devid.encode("i2c", 1, 0x0C, 0x09)})
    env = {k: v for k, v in os.environ.items() if k != devid.DEVTYPES_ENV}
    r = subprocess.run(
        [sys.executable, "-m", "px4params", "migrate", str(path), "--json"],
        cwd=tmp_path, capture_output=True, text=True, env=env, timeout=120, check=False,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["table"] == "current"
    assert instances(report) == [("AK09916#0", 1, 0x0C, 0)]


def test_a_params_file_naming_a_parameter_twice_is_refused(tmp_path: Path, capsys) -> None:
    """QGC writes each parameter once. A file holding CAL_MAG1_ID twice (an HMC5883 and an
    AK09916 ID) was migrated from the last one, exit 0: which device the vehicle had is not
    known, so the file is refused, as 'param import' refuses it. A second component's copy of
    a name (a gimbal's) is not the autopilot's and does not count."""
    path = tmp_path / "twice.params"
    path.write_text(
        "# Vehicle-Id Component-Id Name Value Type\n"
        "1\t1\tCAL_MAG1_ID\t592905\t6\n1\t154\tCAL_MAG1_ID\t1\t6\n1\t1\tCAL_MAG1_ID\t73225\t6\n"
    )
    assert main(["migrate", str(path)]) == 1
    assert capsys.readouterr().err == (
        f"px4params: error: {path}:4: CAL_MAG1_ID: also set on line 2, to 592905\n"
    )
    path.write_text(path.read_text().replace("1\t1\tCAL_MAG1_ID\t73225\t6\n", ""))
    assert run_json(path, capsys)["kind"] == "QGC .params"
