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
#: PX4-Autopilot's docs/assets as a fork's snapshot holds them (dakejahl's, 2026-08-13; the
#: forks INDI-FLO, slgrobotics and others hold slightly different versions of three of them).
PX4DOCS = ("dakejahl/PX4-Autopilot", "bb59c637cd74e04c000a0b8e35aac184251150d6")
AIRFRAMES = "docs/assets/airframes"
AUTERION = ("Auterion/px4-ulog-rs", "a11df05aef8b1ff0b442165951909751557d7dc4")
CHAINPLAIN = ("Chainplain/PX4_ulog_2_xlsx", "dafdcfed06486b082026eb91f36e118730555843")
MAKETECH = ("Carl-Thibault/PX4-Config", "4ac665a7e6598a056cb0d1184fc382ae2cc79d86")
CONGTRANV = ("congtranv/px4-param", "e45f6db777116edb273243180120fa845da59507")
HANG = ("Hang020713/Cartographer_test1", "8f01354b2947c5ebd07d2e5ba80798bebac53c04")
MRN = ("MalteLoos/MRN", "914970d9225834a4273ab7d81d9d47171afb3d35")
LEARNGIT = ("1874522282/learngit", "e0d12cec1801a75e659693db15af0ca9c5f0b235")
ABDELHAKIM = ("abdelhakim96/drone_code", "d4a8f92bb0d0956fb11388a0b6033eb614859578")

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
        # bus 1 at 0x0C (592905 = 0x090C09), which the board's rc.board_sensors:17 `ak09916 -X
        # -b 2 -R 6 start` starts (1.11 counts external buses; the console says "equal to '-b
        # 2'"); the boot console shows ms4525_airspeed on I2C bus 2, its differential_pressure
        # topic 0x472811 (I2C bus 2, 0x28), and both MS5611 on SPI.
        "sample_log_small.ulg", *PYULOG[:1], "test/sample_log_small.ulg", "", True, "px4-v1.11",
        [("MS4525DO", 2, 0x28, None)],
        {
            # 0x090C09 AK09916 I2C 1: console "(external, equal to '-b 2')", PX4 1.11's second
            # external bus (i2c.cpp lists 2, then 1): cubeorange rc.board_sensors:17 -X -b 2
            "CAL_MAG1_ID": BOARD,
            "CAL_ACC0_ID, CAL_GYRO0_ID": BOARD,  # 0x25000A ICM20649 SPI 1
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,  # 0x380022 ICM20602 SPI 4
            "CAL_ACC2_ID, CAL_GYRO2_ID": BOARD,  # 0x280022 ICM20948 SPI 4
            "CAL_MAG0_ID": BOARD,  # 0x090022 AK09916 SPI 4 (CAL_MAG0_EN 0)
            # sensor_baro 0 and 1 published 0x3D000A and 0x3D0022: MS5611 on SPI 1 and 4.
            "MS5611 (BARO), SPI bus 1, device 0": BOARD,
            "MS5611 (BARO), SPI bus 4, device 0": BOARD,
        },
        needs_boards="CubeOrange's 1.11 line 'ak09916 -X -b 2 -R 6 start' is in the board table",
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
        # Pixhawk 2 (FMUv3), PX4 1.9.0: the GPS's IST8310 on I2C bus 1 (0x060E09, rotation 0:
        # 10 for today's driver, whose axes PX4 1.12's rewrite changed); every other sensor on
        # SPI; SENS_EN_LL40LS 2 (the I2C Lidar-Lite), bus not known.
        "motor_failure.ulg", *FRRS[:1], "crates/converter/tests/fixtures/motor_failure.ulg",
        FRRS[1], False, "px4-v1.8",
        [("IST8310", 1, 0x0E, 10), ("LL40LS", 1, 0x62, None)],
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
    Truth(
        # Reptile Dragon 2 (the docs: ARK6X FMU, MS4525DO airspeed), a `param set-default`
        # list of 63 lines, no version and no CAL_*_ID at all. OSD_SCROLL_RATE and the other
        # msp_osd parameters are PX4 1.14 or later (no msp_osd in 1.13): today's table.
        # SENS_EN_MS4525DO 1 is rc.sensors' `ms4525do start -X`, every external bus: the bus is
        # not known; 0x28 is the MS4525DO's address.
        "reptile_dragon_2_params.params", *PX4DOCS[:1],
        f"{AIRFRAMES}/fw/reptile_dragon_2/reptile_dragon_2_params.params", PX4DOCS[1], False,
        "current",
        [("MS4525DO", 1, 0x28, None)],
        {},
        {"SENS_EN_MS4525DO"},
    ),
    Truth(
        # Omnicopter (the docs: Holybro KakuteH7), "# Version: 1.13.0 dev": 118 rows of
        # control allocation, PWM outputs and tuning; no CAL_*, no SENS_EN_*: nothing to carry.
        "omnicopter.params", *PX4DOCS[:1], f"{AIRFRAMES}/multicopter/omnicopter/omnicopter.params",
        PX4DOCS[1], False, "px4-v1.13", [], {},
    ),
    Truth(
        # Foxtech Loong 2160 VTOL (the docs: Skynode or Pixhawk 6C, an SDP33 airspeed sensor,
        # Auterion's digital power module), "# Version: 1.13.0", no CAL_*. SENS_EN_INA238 1:
        # boards start `ina238 -X -b 1 -t 1 -k start` (5X/6X-class: also -b 2), rc.sensors
        # never does, and no board is named: bus 1 is a guess, 0x45 the INA238's address.
        # SENS_EN_SDP3X 1: rc.sensors' `sdp3x start -X` (0x21, else -a 0x22), any external bus.
        "loong.params", *PX4DOCS[:1], f"{AIRFRAMES}/vtol/foxtech_loong_2160/loong.params",
        PX4DOCS[1], False, "px4-v1.13",
        [("INA238", 1, 0x45, None), ("SDP3X", 1, 0x21, None)],
        {},
        {"SENS_EN_INA238", "SENS_EN_SDP3X"},
    ),
    Truth(
        # OMP Hobby ZMO tiltrotor VTOL (the docs: Skynode or Pixhawk 6C), a hand-trimmed QGC
        # file without a version line: tuning and outputs only. FW_THR_ASPD_MIN,
        # FW_T_THR_DAMPING and MPC_VEL_MAN_SIDE are not in PX4 1.13: today's table.
        "omp_hobby_zmo.params", *PX4DOCS[:1],
        f"{AIRFRAMES}/vtol/omp_hobby_zmo_fpv/omp_hobby_zmo.params", PX4DOCS[1], False, "current",
        [], {},
    ),
    Truth(
        # SITL, PX4 1.8.0 beta (ver_sw_release 0x01080080, ver_hw SITL, no boot console, no
        # sensor topics logged): the simulator's IDs of then have bus type 0, bus 1:
        # 0x150008 (devtype 0x15, none in 1.8), 0x140008 ACCELSIM, 0x230008 GYROSIM, 0x030008
        # MAGSIM. (sensor_selection's IDs are what the simulator reported, not configuration.)
        "6ba1abc7-b433-4029-b8f5-3b2bb12d3b6c.ulg", *AUTERION[:1],
        "tests/fixtures/6ba1abc7-b433-4029-b8f5-3b2bb12d3b6c.ulg", AUTERION[1], False, "px4-v1.8",
        [],
        {"CAL_ACC0_ID": OTHER, "CAL_ACC1_ID": OTHER, "CAL_GYRO0_ID": OTHER, "CAL_MAG0_ID": OTHER},
    ),
    Truth(
        # Pixhawk 6C, PX4 v1.13.3 release (0x010D03FF), a fixed-wing (airframe 3000). Console
        # lines 29-34: bmi055 and icm42688p on SPI 1; ms5611 on I2C bus 4 at 0x77 and ist8310
        # at 0x0C on bus 4 (CAL_MAG0 0x060C21, CAL_MAG0_ROT -1); the GPS's IST8310 on bus 1 at
        # 0x0E (CAL_MAG1 0x060E09) with rotation 10: the board's `ist8310 -X -b 1 -R 10 start`,
        # so not probed; CAL_MAG1_ROT 0 is calibration's. Every SENS_EN_* driver switch is 0.
        "log_9_2024-10-14-15-00-06.ulg", *CHAINPLAIN[:1], "log_9_2024-10-14-15-00-06.ulg",
        CHAINPLAIN[1], False, "px4-v1.13", [],
        {
            "CAL_ACC0_ID": BOARD,  # 0x41000A BMI055 accelerometer
            "CAL_GYRO0_ID": BOARD,  # 0x42000A BMI055 gyroscope
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,  # 0x26000A ICM42688P
            "CAL_MAG0_ID": BOARD,
            "CAL_MAG1_ID": BOARD,
            "MS5611 (BARO), I2C bus 4, address 0x77": BOARD,  # sensor_baro 0: 0x3D7721
        },
    ),
    Truth(
        # MakeTech's "Pathfinder" quadrotor (its release notes: field tested, PX4 1.14.0),
        # "# Version: 1.14.0": today's table. BMI055 (0x41000A, 0x42000A) and ICM42688P
        # (0x26000A) on SPI 1, the IST8310 at I2C bus 4, 0x0C (0x060C21, CAL_MAG0_ROT -1): the
        # Pixhawk 6C set, but the file names no board. The GPS's IST8310 on bus 1 at 0x0E
        # (0x060E09, CAL_MAG1_ROT 0, PRIO 75) is then taken as found by probing, rotation 0.
        "20260515 Pathfinder HW1.1 PX4-1.14.0.params", *MAKETECH[:1],
        "aircraft/pathfinder/HW-1.1/PX4-1.14.0/20260515 Pathfinder HW1.1 PX4-1.14.0.params",
        MAKETECH[1], False, "current",
        [("IST8310", 1, 0x0E, 0)],
        {
            "CAL_ACC0_ID": BOARD,
            "CAL_GYRO0_ID": BOARD,
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,
            "CAL_MAG0_ID": BOARD,
        },
    ),
    Truth(
        # A Pixhawk 4 (its README) flown with PX4 "1.10.1 dev": the px4-v1.8 table, _EN not
        # _PRIO (all 1). ICM20689 accelerometer 0x3B000A and gyroscope 0x3C000A and BMI055
        # (0x41030A, 0x42020A) on SPI 1; the internal IST8310 on I2C bus 3 (0x060E19,
        # CAL_MAG1_ROT -1); the GPS's IST8310 on bus 1 at 0x0E (0x060E09, CAL_MAG0_ROT 0),
        # probed without -R: rotation 10 for today's driver (PX4 1.12 changed its axes).
        "px4-practice.params", *CONGTRANV[:1], "px4-practice.params", CONGTRANV[1], False,
        "px4-v1.8",
        [("IST8310", 1, 0x0E, 10)],
        {
            "CAL_ACC0_ID": BOARD,
            "CAL_ACC1_ID": BOARD,
            "CAL_GYRO0_ID": BOARD,
            "CAL_GYRO1_ID": BOARD,
            "CAL_MAG1_ID": BOARD,
        },
    ),
    Truth(
        # The same Pixhawk 4 set up for HITL (SYS_HITL 1, airframe 1001), "1.10.1 dev": only
        # the board's ICM20689 slots (SPI 1) are set, every CAL_MAGn_ID is 0.
        "px4-hitl-simulation.params", *CONGTRANV[:1], "px4-hitl-simulation.params",
        CONGTRANV[1], False, "px4-v1.8", [],
        {"CAL_ACC0_ID": BOARD, "CAL_GYRO0_ID": BOARD},
    ),
    Truth(
        # A rover (airframe 50000), "# Version: 1.18.0 alpha": BMI088 (0x6A000A, 0x66000A) and
        # ICM42688P (0x26000A) on SPI 1; MS5611 on I2C bus 4 at 0x77 (CAL_BARO0 0x3D7721), an
        # I2C barometer: the board's; IST8310 at bus 4, 0x0C, CAL_MAG0_ROT -1. CAL_GYRO2_ID
        # 0x14010C is a simulator's IMU (bus type 4) left in the slot.
        "original_px4.params", *HANG[:1], "data/original_px4.params", HANG[1], False, "current",
        [],
        {
            "CAL_ACC0_ID": BOARD,
            "CAL_GYRO0_ID": BOARD,
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,
            "CAL_BARO0_ID": BOARD,
            "CAL_GYRO2_ID": SIM,
            "CAL_MAG0_ID": BOARD,
        },
    ),
    Truth(
        # The same owner's boat (airframe 22001), "1.18.0 alpha": BMI055 (0x41000A, 0x42000A
        # in CAL_GYRO3), BMI088 gyroscope 0x66000A, ICM42688P 0x26000A, all SPI 1; the same
        # simulator IMU in CAL_GYRO2; the internal IST8310 (0x060C21, ROT -1); no CAL_BARO.
        "px4_boat.param.params", *HANG[:1], "onboard_scripts/px4_boat.param.params", HANG[1],
        False, "current", [],
        {
            "CAL_ACC0_ID": BOARD,
            "CAL_GYRO0_ID": BOARD,
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,
            "CAL_GYRO2_ID": SIM,
            "CAL_GYRO3_ID": BOARD,
            "CAL_MAG0_ID": BOARD,
        },
    ),
    Truth(
        # SITL, "# Version: 1.17.0 alpha" (here named mrn_px4.params; px4.params in the repo):
        # three simulated IMUs 0x14010C/0x140114/0x14011C (bus type 4, buses 1-3), BAROSIM
        # 0x65010C, MAGSIM 0x03030C and 0x03040C. CAL_ACC*_PRIO -1 is "not set".
        "mrn_px4.params", *MRN[:1], "px4.params", MRN[1], False, "current", [],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": SIM,
            "CAL_ACC1_ID, CAL_GYRO1_ID": SIM,
            "CAL_ACC2_ID, CAL_GYRO2_ID": SIM,
            "CAL_BARO0_ID": SIM,
            "CAL_MAG0_ID": SIM,
            "CAL_MAG1_ID": SIM,
        },
    ),
    Truth(
        # SITL (airframe 10016), "# Version: 1.9.0 dev" (learngit_px4.params here; px4.params in
        # the repo): the px4-v1.8 table; the simulator's IDs of then have bus type 0 (0x150008,
        # 0x140008 ACCELSIM, 0x230008 GYROSIM, 0x030008 MAGSIM).
        "learngit_px4.params", *LEARNGIT[:1], "px4.params", LEARNGIT[1], False, "px4-v1.8", [],
        {"CAL_ACC0_ID": OTHER, "CAL_ACC1_ID": OTHER, "CAL_GYRO0_ID": OTHER, "CAL_MAG0_ID": OTHER},
    ),
    Truth(
        # A 250 racer (airframe 4050), "# Version: 1.11.3": the px4-v1.11 table, _EN (all 1).
        # ICM20689 IMU 0x3C000A and BMI055 (0x41000A, 0x42000A) on SPI 1, the IST8310 on I2C
        # bus 3 at 0x0E (0x060E19, CAL_MAG0_ROT -1: the FMUv5 set). No external sensor.
        "px4_params.params", *ABDELHAKIM[:1], "px4_params.params", ABDELHAKIM[1], False,
        "px4-v1.11", [],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": BOARD,
            "CAL_ACC1_ID": BOARD,
            "CAL_GYRO1_ID": BOARD,
            "CAL_MAG0_ID": BOARD,
        },
    ),
    Truth(
        # The same vehicle's older file, another flight controller: ICM20602 0x38000A and
        # ICM20689 0x3C000A (IMUs in 1.11's table) on SPI 1, the same internal IST8310.
        "px4_params_kaffe_old.params", *ABDELHAKIM[:1], "px4_params_kaffe_old.params",
        ABDELHAKIM[1], False, "px4-v1.11", [],
        {
            "CAL_ACC0_ID, CAL_GYRO0_ID": BOARD,
            "CAL_ACC1_ID, CAL_GYRO1_ID": BOARD,
            "CAL_MAG0_ID": BOARD,
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
    assert len(CORPUS) >= 29
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


def test_a_board_the_table_has_only_from_a_later_release_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """flight-review-rs's CUAV 7-Nano log is of PX4 1.16.0 (ver_sw_release 0x011000FF); the
    board table has the 7-Nano from v1.18 on (boards/cuav/7-nano is not in v1.15.0, the newest
    snapshot at or before 1.16). Its IST8310 and ICP201XX were left out as the board script's
    at v1.18 with no word that a later release's script was read."""
    try:
        import px4params.vehicle.boards  # noqa: F401
    except ImportError:
        pytest.skip("needs px4params.vehicle.boards (the board table)")
    (truth,) = [t for t in CORPUS if t.name == "gps_interference.ulg"]
    assert main(["migrate", str(locate(truth, tmp_path)), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["board"] == "cuav_7-nano"
    assert report["assumptions"] == [
        "board cuav_7-nano: in the board table from PX4 v1.18 on, not at v1.15.0, the newest "
        "release it has at or before this file's 1.16.0; what its script starts is taken as at "
        "v1.18"
    ]


def test_the_reptile_dragon_with_its_board_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The Reptile Dragon 2 flies an ARK6X FMU (its docs page, docs/en/frames_plane/
    reptile_dragon_2.md). With `--board ark_fmu-v6x` the MS4525DO is still rc.sensors'
    `ms4525do start -X` (ROMFS/px4fmu_common/init.d/rc.sensors line 172, read at bb59c637):
    the driver tries every external bus, which on that board are I2C 1, 2 and 3
    (boards/ark/fmu-v6x/src/i2c.cpp: initI2CBusExternal(1..3), bus 4 internal). So the bus stays
    unknown and the report says so, naming the board's three buses instead of guessing blind."""
    try:
        import px4params.vehicle.boards  # noqa: F401
    except ImportError:
        pytest.skip("needs px4params.vehicle.boards (the board table)")
    (truth,) = [t for t in CORPUS if t.name == "reptile_dragon_2_params.params"]
    path = locate(truth, tmp_path)
    assert main(["migrate", str(path), "--json", "--board", "ark_fmu-v6x"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["board"] == "ark_fmu-v6x"
    assert [
        (i["name"], i["values"]["bus.i2c.bus_id"], i["values"]["bus.i2c.address"])
        for i in report["instances"]
    ] == [("MS4525DO#0", 1, 0x28)]
    (said,) = [a for a in report["assumptions"] if a.startswith("SENS_EN_MS4525DO:")]
    assert "'ms4525do start -X' on every external I2C bus (1, 2, 3;" in said
    assert "ROMFS/px4fmu_common/init.d/rc.sensors:172" in said
    assert said.endswith("so the bus it is found on is not known: bus 1 proposed")
    assert not [a for a in report["assumptions"] if "no board information" in a]


def test_an_ardupilot_file_is_not_migrated(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A real QGC file of another autopilot: ArduPilot Copter 4.6.3 (gyumingim/drone's
    param.params, "# Stack: ArduPilot" on line 3, INS_ACC_ID and COMPASS_DEV_ID instead of
    CAL_*_ID). Nothing in it is PX4 configuration: migrate refuses it, naming the line."""
    truth = Truth(
        "ardupilot_param.params", "gyumingim/drone", "param.params",
        "99313d7bbae4fba3ffd263aa1c33fb6fcbbdc36e", False, "", [], {},
    )  # fmt: skip
    path = locate(truth, tmp_path)
    assert main(["migrate", str(path), "--json"]) == 1
    assert capsys.readouterr().err == (
        f"px4params: error: {path}:3: '# Stack: ArduPilot': not a PX4 parameter file (QGC "
        "writes 'PX4' or 'PX4 Pro' there for PX4's)\n"
    )


def test_each_real_power_monitors_battery_index_is_the_one_its_start_line_gives(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The battery index (`-t`) of a power monitor's start line, which no type has a field for,
    is named as the line gives it, or said unknown: the NXP MR-Tropic log's i2c_launcher ran
    `ina228 -X -b 1 -t 1 start` (boot console line 29); the Loong 2160's SENS_EN_INA238 = 1
    on a Skynode (`--board px4_fmu-v5x`, PX4 v1.13.0's boards/px4/fmu-v5x/init/
    rc.board_sensors) starts `ina238 -X -b 1 -t 1 -k start` and `ina238 -X -b 2 -t 2 -k start`;
    with no board named nothing gives the line. Its SENS_EN_SDP3X = 1 runs rc.sensors' `sdp3x
    start -X`, and `sdp3x start -X -a 0x22` only if that found nothing: a .params cannot say,
    so the fallback is named, not proposed."""
    try:
        import px4params.vehicle.boards  # noqa: F401
    except ImportError:
        pytest.skip("needs px4params.vehicle.boards (the board table)")

    def notes(name: str, *options: str) -> tuple[dict[str, list[str]], list[str]]:
        (truth,) = [t for t in CORPUS if t.name == name]
        assert main(["migrate", str(locate(truth, tmp_path)), "--json", *options]) == 0
        report = json.loads(capsys.readouterr().out)
        found = {
            i["name"]: [n for n in i["notes"] if "battery index" in n]
            for i in report["instances"]
            if i["name"].startswith("INA")
        }
        return found, report["assumptions"]

    line = "today's start line also sets the battery index (-t {}): {} has no field for it"
    assert notes("frrs_ekf_failure.ulg")[0] == {"INA228#0": [line.format(1, "INA228")]}
    found, assumptions = notes("loong.params", "--board", "px4_fmu-v5x")
    assert found == {
        "INA238#0": [line.format(1, "INA238")],
        "INA238#1": [line.format(2, "INA238")],
    }
    (fallback,) = [a for a in assumptions if a.startswith("SENS_EN_SDP3X: 'sdp3x start -X -a")]
    assert fallback.startswith(
        "SENS_EN_SDP3X: 'sdp3x start -X -a 0x22' (PX4/PX4-Autopilot ROMFS/px4fmu_common/init.d/"
        "rc.sensors:135 at v1.13.0 "
    )
    assert fallback.endswith(
        "runs only where not sdp3x started (start -X) (a QGC .params has no boot console to "
        "say): not proposed from it"
    )
    assert notes("loong.params")[0] == {
        "INA238#0": [
            "today's start line also sets a battery index (-t), which nothing here names "
            "(without -t the driver uses 1): INA238 has no field for it"
        ]
    }
