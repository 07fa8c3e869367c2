"""``px4params migrate --json`` against real files: QGC parameter files and flight logs written
by PX4 and QGroundControl, none of them ours, none copied into this repository.

For every file a truth table, written by reading the file by hand (its parameters with pyulog's
``ulog_params`` or a text editor, each ``CAL_*_ID`` split into bus type (bits 0-2), bus (3-7),
address (8-15) and devtype (16-23) on paper, its boot console line by line, and the
``device_id`` its sensor topics published, read with pyulog), says which
instances a correct migration proposes (type, I2C bus, address, driver rotation) and what it
leaves out and why:

``board``       started by the board's script: an SPI sensor, PX4's "Internal"
                ``CAL_MAGn_ROT = -1``, an internal bus in the boot console, a ``-R`` rotation
                (rc.sensors probes without one), an I2C barometer
``disabled``    ``CAL_<S>n_PRIO = 0`` (PX4 1.12 on) or ``CAL_<S>n_EN = 0``
``simulation``  a simulator's sensor (bus type 4)
``other bus``   bus type 0: the IDs of 2016/2017 firmware and of QGC's MockLink
``dronecan``    bus type 3

A file is found in ``$PX4PARAMS_CORPUS`` (a folder holding the files by their base name), in
``../shared/data`` (see its SOURCES.md), or read with ``git show`` from a snapshot of its
repository under ``/work/.mirror``; else its test is skipped naming where to get it.
"""

from __future__ import annotations

import json
import os
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import shared_data
from px4params.cli.main import main

CORPUS_ENV = "PX4PARAMS_CORPUS"
MIRRORS = Path("/work/.mirror")
PYULOG = ("PX4/pyulog", "3cf17793f14709713ab297d3743314c658874068")
FRRS = ("PX4/flight-review-rs", "0b1d5ee209e3b4ccfb30d91b675a9f7e8c484ad8")
STIFAEL = ("Stifael/px4ulogtests", "c269c07b7822c6ac7097eddffbea1f9969bfa60d")

BOARD, DISABLED, SIM, OTHER = "board", "disabled", "simulation", "other bus"
Instance = tuple[str, int, int, "int | None"]  # type, I2C bus, address, driver rotation


@dataclass(frozen=True)
class Truth:
    """One real file and what a correct migration of it is."""

    name: str  # the file's base name (in $PX4PARAMS_CORPUS or ../shared/data)
    repo: str
    path: str
    commit: str  # "" where ../shared/data's SOURCES.md names the version
    shared: bool
    table: str
    instances: list[Instance]
    #: Left out: the slots (``CAL_ACC0_ID, CAL_GYRO0_ID``) or the boot console's device
    #: (``ms5611, SPI bus 1``) -> the reason.
    left_out: dict[str, str]
    #: SENS_EN_* switches whose I2C bus nothing in the file says (the report says it guessed).
    guessed: set[str] = field(default_factory=set)
    #: Why the right answer needs the board table (px4params.vehicle.boards), or "".
    needs_boards: str = ""


CORPUS = [
    Truth(
        # CubeOrange, PX4 v1.11.2. IMUs and a disabled AK09916 on SPI; the GPS's AK09916 on I2C
        # bus 1 at 0x0C (592905 = 0x090C09), which PX4 1.11's rc.sensors probes with
        # `ak09916 -X -R 6 start` (the console of 1.11 prints no rotation); the boot console
        # shows ms4525_airspeed on I2C bus 2, its differential_pressure topic 0x472811 (I2C bus
        # 2, 0x28), and both MS5611 on SPI.
        "sample_log_small.ulg", *PYULOG[:1], "test/sample_log_small.ulg", "", True, "px4-v1.11",
        [("AK09916", 1, 0x0C, 6), ("MS4525DO", 2, 0x28, None)],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": BOARD,  # 0x25000A ICM20649 SPI 1
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,  # 0x380022 ICM20602 SPI 4
            "CAL_ACC2_ID, CAL_GYRO2_ID": BOARD,  # 0x280022 ICM20948 SPI 4
            "CAL_MAG0_ID": BOARD,  # 0x090022 AK09916 SPI 4 (CAL_MAG0_EN 0)
            # sensor_baro 0 and 1 published 0x3D000A and 0x3D0022: MS5611 on SPI 1 and 4.
            "MS5611 (BARO), SPI bus 1, device 0": BOARD,
            "MS5611 (BARO), SPI bus 4, device 0": BOARD,
        },
        needs_boards="PX4 1.11's rc.sensors line 'ak09916 -X -R 6 start' is in the board table",
    ),
    Truth(
        # Pixhawk 3 Pro (FMUv4 Pro), PX4 v1.6.0: the HMC5883 on I2C bus 2 at 0x1E (73233 =
        # 0x011E11, CAL_MAG2_ROT 0); every other sensor on SPI.
        "sample_appended_multiple.ulg", *PYULOG[:1], "test/sample_appended_multiple.ulg", "",
        True, "px4-v1.6",
        [("HMC5883", 2, 0x1E, 0)],
        {
            "CAL_ACC0_ID": BOARD,  # 0x370E0A, ICM20602 in 1.6
            "CAL_ACC1_ID": BOARD,  # 0x16040A MPU9250
            "CAL_GYRO0_ID": BOARD,  # 0x380E0A
            "CAL_GYRO1_ID": BOARD,  # 0x24040A
            "CAL_MAG0_ID": BOARD,  # 0x04040A MPU9250
            "CAL_MAG1_ID": BOARD,  # 0x05070A LIS3MDL
        },
    ),
    Truth(
        # SITL, PX4 1.15: three simulated IMUs (0x14010C, 0x140114, 0x14011C) and two
        # simulated compasses (bus type 4). CAL_GYRO*_PRIO -1 is "not set", not disabled.
        "sample_px4_events.ulg", *PYULOG[:1], "test/sample_px4_events.ulg", "", True, "current",
        [],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": SIM,
            "CAL_ACC1_ID, CAL_GYRO1_ID": SIM,
            "CAL_ACC2_ID, CAL_GYRO2_ID": SIM,
            "CAL_MAG0_ID": SIM,
            "CAL_MAG1_ID": SIM,
            # sensor_baro 0 and 1 published 0x65040C and 0x65050C: BAROSIM, simulation bus 1.
            "BAROSIM (BARO), simulation bus 1, address 0x04": SIM,
            "BAROSIM (BARO), simulation bus 1, address 0x05": SIM,
        },
    ),
    Truth(
        # NXP MR-Tropic, PX4 1.15.0. Console: bmm350 on I2C bus 4 (internal), ist8310 on bus 1
        # (external) with rotation 10 (the board's `ist8310 -X -b 1 -R 10 start`), bmp390 on
        # bus 4 (internal), the LED on bus 1 (internal), and i2c_launcher's INA228 at 0x45 on
        # bus 1 although every SENS_EN_INA2xx is 0.
        "frrs_ekf_failure.ulg", *FRRS[:1], "crates/converter/tests/fixtures/ekf_failure.ulg",
        "9ca6321", True, "current",
        [("INA228", 1, 0x45, None)],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": BOARD,  # 0x2D001A ICM42686P SPI 3
            "CAL_ACC1_ID": BOARD,  # 0x6A0022 BMI088 SPI 4
            "CAL_GYRO1_ID": BOARD,  # 0x660022
            "CAL_BARO0_ID": BOARD,  # 0x6E7621 BMP390 I2C 4
            "CAL_MAG0_ID": BOARD,  # 0x060E09 IST8310 I2C 1, -R 10
            "CAL_MAG1_ID": BOARD,  # 0xE51421 BMM350 I2C 4, CAL_MAG1_ROT -1
            "rgbled_ncp5623c, I2C bus 1, address 0x39": BOARD,
        },
    ),
    Truth(
        # Amovlab F410, PX4 1.15.4 (Pixhawk 6C class). IST8310 on I2C bus 4 at 0x0C in
        # CAL_MAG0 and again in CAL_MAG3 (396321 = 0x060C21, Internal); the GPS's QMC5883L on
        # bus 1 at 0x0D with calibration rotation 36; a stale IST8310 (bus 1, 0x0E) in CAL_MAG2
        # with CAL_MAG2_PRIO 0.
        "px4docs_amovlabf410_v1.15.4.params", "PX4/PX4-Autopilot",
        "docs/assets/airframes/multicopter/amovlab_f410/amovlabf410_drone_v1.15.4.params",
        "0148665", True, "current",
        [("QMC5883L", 1, 0x0D, 0)],
        {
            "CAL_ACC0_ID": BOARD,  # 0x41000A BMI055 SPI 1
            "CAL_GYRO0_ID": BOARD,  # 0x42000A
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,  # 0x26000A ICM42688P
            "CAL_MAG0_ID, CAL_MAG3_ID": BOARD,
            "CAL_MAG2_ID": DISABLED,
        },
    ),
    Truth(
        # Turbo Timber Evolution, PX4 1.13.0 beta (FMUv5 class): internal IST8310 on I2C bus
        # 3 (Internal), the GPS's IST8310 on bus 1 with calibration rotation 4 (0x060E09),
        # SENS_EN_MS4525DO 1 with no word on its bus.
        "userguide_tteparams_v1.13.params", "PX4/PX4-user_guide",
        "assets/airframes/fw/turbo_timber_evolution/tteparams.params", "65738e0", True,
        "px4-v1.13",
        [("IST8310", 1, 0x0E, 0), ("MS4525DO", 1, 0x28, None)],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": BOARD,  # 0x3C000A ICM20689
            "CAL_ACC1_ID": BOARD,
            "CAL_GYRO1_ID": BOARD,
            "CAL_MAG0_ID": BOARD,  # 0x060E19, CAL_MAG0_ROT -1
        },
        {"SENS_EN_MS4525DO"},
    ),
    Truth(
        # QGC's offline-editing file (PX4 1.4, no version line, no CAL_*_PRIO): every slot 0.
        "qgc_offline_editing_v1.4.params", "mavlink/qgroundcontrol", "(see SOURCES.md)", "",
        True, "px4-v1.6", [], {},
    ),
    Truth(
        # QGC's MockLink, "# Version: 1.7.2 dev": its sensors' IDs have bus type 0.
        "qgc_px4_mocklink.params", "mavlink/qgroundcontrol", "(see SOURCES.md)", "", True,
        "px4-v1.6", [],
        {"CAL_ACC0_ID": OTHER, "CAL_ACC1_ID": OTHER, "CAL_GYRO0_ID": OTHER, "CAL_MAG0_ID": OTHER},
    ),
    Truth(
        # AUAV-X2.1 (2016, no ver_sw_release, no CAL_*_PRIO: the px4-v1.6 table). One ID has
        # a bus (0x13010A, MPU6000 on SPI 1); the others are bus type 0.
        "sample.ulg", *PYULOG[:1], "test/sample.ulg", PYULOG[1], False, "px4-v1.6", [],
        {
            "CAL_ACC0_ID": BOARD,
            "CAL_ACC1_ID": OTHER,  # 0x160000: MPU9250 accelerometer then, FLOW SIM today
            "CAL_GYRO0_ID": OTHER,
            "CAL_GYRO1_ID": OTHER,
            "CAL_MAG0_ID": OTHER,
        },
    ),
    Truth(
        # SITL, PX4 1.13.0: simulated sensors only.
        "sample_logging_tagged_and_default_params.ulg", *PYULOG[:1],
        "test/sample_logging_tagged_and_default_params.ulg", PYULOG[1], False, "px4-v1.13", [],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": SIM,
            "CAL_ACC1_ID, CAL_GYRO1_ID": SIM,
            "CAL_ACC2_ID, CAL_GYRO2_ID": SIM,
            "CAL_MAG0_ID": SIM,
            "CAL_MAG1_ID": SIM,
            # sensor_baro 0 and 1 published 0x65040C and 0x65050C: BAROSIM, simulation bus 1.
            "BAROSIM (BARO), simulation bus 1, address 0x04": SIM,
            "BAROSIM (BARO), simulation bus 1, address 0x05": SIM,
        },
    ),
    Truth(
        # Pixhawk 6C, PX4 1.15.1: IST8310 on I2C bus 4 at 0x0C (Internal); the console shows the
        # board's ms5611 on bus 4 at 0x77 (no CAL_BARO ID) and no external compass.
        "battery_brownout.ulg", *FRRS[:1], "crates/converter/tests/fixtures/battery_brownout.ulg",
        FRRS[1], False, "current", [],
        {
            "CAL_ACC0_ID": BOARD,
            "CAL_GYRO0_ID": BOARD,
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,
            "CAL_MAG0_ID": BOARD,
            "MS5611 (BARO), I2C bus 4, address 0x77": BOARD,  # sensor_baro 0: 0x3D7721
        },
    ),
    Truth(
        # CUAV 7-Nano, PX4 1.16.0: IST8310 on I2C bus 3 (Internal, rotation 18 in the console,
        # CAL_MAG0_PRIO 0), ICP201XX barometer on bus 4 at 0x63, BMP581 on SPI, and the GPS's
        # QMC5883L on bus 1 at 0x0D (527625 = 0x080D09) that the console shows started
        # without a rotation.
        "gps_interference.ulg", *FRRS[:1], "crates/converter/tests/fixtures/gps_interference.ulg",
        FRRS[1], False, "current",
        [("QMC5883L", 1, 0x0D, 0)],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": BOARD,  # 0x2B000A IIM42652
            "CAL_ACC1_ID": BOARD,  # 0x6A0012 BMI088 SPI 2
            "CAL_GYRO1_ID": BOARD,
            "CAL_BARO0_ID": BOARD,  # 0x6F0022 BMP581 SPI 4
            "CAL_BARO1_ID": BOARD,  # 0xB86321 ICP201XX I2C 4
            "CAL_MAG0_ID": BOARD,
        },
    ),
    Truth(
        # Pixhawk 2 (FMUv3), PX4 1.9.0: the GPS's IST8310 on I2C bus 1 (0x060E09, rotation 0);
        # every other sensor on SPI; SENS_EN_LL40LS 2 (the I2C Lidar-Lite), bus not known.
        "motor_failure.ulg", *FRRS[:1], "crates/converter/tests/fixtures/motor_failure.ulg",
        FRRS[1], False, "px4-v1.8",
        [("IST8310", 1, 0x0E, 0), ("LL40LS", 1, 0x62, None)],
        {
            "CAL_ACC0_ID": BOARD,  # 0x160422 MPU9250 SPI 4 (CAL_ACC0_EN 0)
            "CAL_ACC1_ID": BOARD,  # 0x110222 LSM303D
            "CAL_ACC2_ID": BOARD,  # 0x16040A
            "CAL_GYRO0_ID": BOARD,
            "CAL_GYRO1_ID": BOARD,
            "CAL_GYRO2_ID": BOARD,
            "CAL_MAG1_ID": BOARD,  # 0x040422
            "CAL_MAG2_ID": BOARD,  # 0x020222
            "CAL_MAG3_ID": BOARD,  # 0x04040A
        },
        {"SENS_EN_LL40LS"},
    ),
    Truth(
        # SITL, PX4 1.7.3 (2018): the simulator's IDs of then, bus type 0.
        "14_19_29.ulg", *STIFAEL[:1], "inputlog/14_19_29.ulg", STIFAEL[1], False, "px4-v1.6", [],
        {
            "CAL_ACC0_ID": OTHER, "CAL_ACC1_ID": OTHER, "CAL_GYRO0_ID": OTHER,
            "CAL_MAG0_ID": OTHER,
            # sensor_baro 0 published 0x074CFB: bus type 3 (UAVCAN) bus 31, node 0x4C,
            # devtype 0x07 (none in 1.6): what SITL 1.7 wrote, not a device to carry.
            "devtype 0x07 (not in the px4-v1.6 table), UAVCAN bus 31, node 76": "dronecan",
        },
    ),
]  # fmt: skip


def locate(truth: Truth, tmp_path: Path) -> Path:
    """The file, from $PX4PARAMS_CORPUS, ../shared/data or a repository snapshot; skips with
    where to get it otherwise."""
    folder = os.environ.get(CORPUS_ENV)
    if folder and (Path(folder) / truth.name).is_file():
        return Path(folder) / truth.name
    if truth.shared:
        return shared_data.shared_file(truth.name)
    owner, name = truth.repo.split("/")
    for git_dir in (
        MIRRORS / f"{owner}+{name}" / "repo",
        MIRRORS / f"{owner}+{name}" / "repo" / ".git",
    ):
        if (git_dir / "HEAD").is_file():
            shown = subprocess.run(
                ["git", "--git-dir", str(git_dir), "show", f"{truth.commit}:{truth.path}"],
                capture_output=True, timeout=120, check=False,
            )  # fmt: skip
            if shown.returncode == 0:
                out = tmp_path / truth.name
                out.write_bytes(shown.stdout)
                return out
    pytest.skip(
        f"{truth.name} not found: {truth.repo} {truth.path} at {truth.commit} (put it in "
        f"${CORPUS_ENV}, or a snapshot of the repository in {MIRRORS})"
    )


def left_out_key(item: dict[str, str]) -> str:
    found = item["found"]
    return found.split(" = ")[0] if found.startswith("CAL_") else item["device"]


def test_the_corpus_is_large_enough() -> None:
    assert len(CORPUS) >= 15 - 1  # and the duplicate fixtures below are counted once
    assert len({t.name for t in CORPUS}) == len(CORPUS)
    assert all(t.commit or t.shared for t in CORPUS)


@pytest.mark.parametrize("truth", CORPUS, ids=[t.name for t in CORPUS])
def test_migrate_json_matches_the_truth_table(
    truth: Truth, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if truth.needs_boards:
        try:
            import px4params.vehicle.boards  # noqa: F401
        except ImportError:
            pytest.skip(f"needs px4params.vehicle.boards: {truth.needs_boards}")
    path = locate(truth, tmp_path)
    assert main(["migrate", str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["table"] == truth.table
    got = sorted(
        (
            i["name"].partition("#")[0],
            i["values"]["bus.i2c.bus_id"],
            i["values"]["bus.i2c.address"],
            i["values"].get("rotation"),
        )
        for i in report["instances"]
    )
    assert got == sorted(truth.instances)
    assert {left_out_key(i): i["reason"] for i in report["left_out"]} == truth.left_out
    assert len(report["left_out"]) == len(truth.left_out)  # each device reported once
    guessed = {line.split(":")[0] for line in report["assumptions"] if "is a guess" in line}
    assert guessed == truth.guessed
    # Every proposed instance says where it came from; the airframe carries them all.
    for inst in report["instances"]:
        assert inst["origin"] and f"param add {inst['name']}\n" in report["airframe"]


def test_the_amovlab_file_with_its_board_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The Amovlab F410 is a Pixhawk 6C: with `--board px4_fmu-v6c` the board's script decides.
    PX4-Autopilot's boards/px4/fmu-v6c/init/rc.board_sensors (read at 13cbb684) starts
    `ist8310 -X -b 4 -a 0xc start` (line 25: the internal compass of CAL_MAG0/CAL_MAG3) and
    `ist8310 -X -b 1 -R 10 start` (line 28: the GPS puck's IST8310 at 0x0E, the stale
    CAL_MAG2), so only the QMC5883L that rc.sensors probes stays an instance."""
    try:
        import px4params.vehicle.boards  # noqa: F401
    except ImportError:
        pytest.skip("needs px4params.vehicle.boards (the board table)")
    (truth,) = [t for t in CORPUS if t.name == "px4docs_amovlabf410_v1.15.4.params"]
    path = locate(truth, tmp_path)
    assert main(["migrate", str(path), "--json", "--board", "px4_fmu-v6c"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["board"] == "px4_fmu-v6c"
    assert [
        (i["name"], i["values"]["bus.i2c.bus_id"], i["values"]["bus.i2c.address"],
         i["values"]["rotation"])
        for i in report["instances"]
    ] == [("QMC5883L#0", 1, 0x0D, 0)]  # fmt: skip
    lines = {left_out_key(i): i["line"] for i in report["left_out"]}
    script = "boards/px4/fmu-v6c/init/rc.board_sensors"
    assert f"{script}:25" in lines["CAL_MAG0_ID, CAL_MAG3_ID"]
    assert f"{script}:28" in lines["CAL_MAG2_ID"]
    assert not [a for a in report["assumptions"] if "no board information" in a]
