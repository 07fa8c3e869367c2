"""``px4params migrate`` across PX4 releases whose drivers changed the axes they report: a
rotation of the file's release becomes the one giving the same orientation on the release the
manifest is for (python/px4params/migrate/axes.py, data/driver_axes.toml).

The answers are PX4's own: the board scripts PX4 changed together with each driver (read at
PX4-Autopilot v1.11.0 71db0903a9 and v1.12.0 9524e8ec03), the hand-coded fast paths of
src/lib/conversion/rotation.h at v1.12.0, and real parameter files of the corpus
(tests/test_migrate_corpus.py) whose GPS compass is an IST8310 found by probing on PX4 1.9
and 1.10.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path

import pytest
import test_migrate_corpus as corpus
from px4params.errors import MigrationError
from px4params.migrate import axes
from px4params.vehicle import devid
from test_migrate_build import config
from test_migrate_upgrade import run

GPS_IST8310 = devid.encode("i2c", 1, 0x0E, 0x06)  # the GPS's IST8310 on a Pixhawk 4
IST8310_NOTE = (
    "rotation 10 (was 0 on PX4 {version}: rc.sensors starts it without -R): ist8310 reports "
    "other axes from PX4 v1.12.0 (PX4 commit 7569722821): the same orientation as before"
)


def c_of(module: str, internal: bool = False) -> int:
    """C of the table's change for ``module``."""
    (change,) = [c for c in axes.changes() if module in c.modules]
    if internal and change.internal_rotation is not None:
        return change.internal_rotation
    return change.rotation


# (board script, module, internal bus, -R at v1.11.0, -R at v1.12.0): PX4's own fixes
BOARD_FIXES = [
    ("boards/px4/fmu-v5/init/rc.board_sensors:19 -> :22", "ist8310", False, 0, 10),
    ("boards/holybro/pix32v5/init/rc.board_sensors:19", "ist8310", False, 0, 10),
    ("boards/holybro/durandal-v1/init/rc.board_sensors:15", "ist8310", False, 0, 10),
    ("boards/nxp/fmurt1062-v1/init/rc.board_sensors:31", "ist8310", False, 0, 10),
    # changed by the rewrite commit itself; the board was gone before v1.12.0
    ("boards/intel/aerofc-v1/init/rc.board_sensors (7569722821)", "ist8310", False, 4, 14),
    ("boards/airmind/mindpx-v2/init/rc.board_sensors:10 (qmc5883 -I)", "qmc5883", True, 12, 6),
    ("boards/spracing/h7extreme/init/rc.board_sensors:8 -> :10", "mpu6000", False, 11, 5),
    ("boards/spracing/h7extreme/init/rc.board_sensors:9 -> :11 (commented)", "mpu6000", False,
     10, 4),
    ("boards/bitcraze/crazyflie/init/rc.board_sensors:9", "mpu9250", False, 12, 6),
]  # fmt: skip


@pytest.mark.parametrize(("script", "module", "internal", "old", "new"), BOARD_FIXES)
def test_the_composition_gives_pX4s_own_board_script_fixes(
    script: str, module: str, internal: bool, old: int, new: int
) -> None:
    assert axes.composed(c_of(module, internal), old) == new, script


def test_the_rotation_matrices_are_rotation_hs_fast_paths() -> None:
    # src/lib/conversion/rotation.h at v1.12.0, rotate_3(): ROLL_180_YAW_90 (:195-201)
    # x' = y, y' = x, z' = -z; ROLL_180_YAW_270 (:214-220) x' = -y, y' = -x, z' = -z;
    # YAW_270 (:180-183) x' = y, y' = -x; PITCH_180 (:207-209) x' = -x, z' = -z
    x, y, z = 1.0, 2.0, 3.0
    for value, want in [(10, (y, x, -z)), (14, (-y, -x, -z)), (6, (y, -x, z)), (12, (-x, y, -z))]:
        m = axes.rotations()[value]
        got = tuple(m[i][0] * x + m[i][1] * y + m[i][2] * z for i in range(3))
        assert got == pytest.approx(want, abs=1e-12), value


def test_composition_applies_c_first_where_the_order_matters() -> None:
    # 12 (pitch 180) and 14 (roll 180, yaw 270) do not commute: mindpx-v2's 12 -> 6 needs 12∘14
    assert axes.composed(14, 12) == 6
    assert axes.composed(12, 14) != 6
    # an orientation no enum value names (the research note's tables: 17 and 38 under C 10)
    assert axes.composed(10, 17) is None and axes.composed(10, 38) is None
    assert axes.composed(10, 16) == 35 and axes.composed(14, 16) == 30  # the note's tables


def write_params(path: Path, version: str | None, rows: dict[str, int]) -> Path:
    lines = ["# Onboard parameters for Vehicle 1", "#", "# Stack: PX4"]
    lines += [f"# Version: {version}"] if version else []
    lines += ["#", "# Vehicle-Id Component-Id Name Value Type"]
    lines += [f"1\t1\t{name}\t{value}\t6" for name, value in rows.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_pixhawk_4_gps_compass_of_px4_1_11_gets_rotation_10_for_todays_px4(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pixhawk 4 on v1.11.3, the GPS's IST8310 found by rc.sensors' probe `ist8310 -X start`
    (no -R): today's driver reports other axes, so the manifest's -R is 10, as fmu-v5's own
    script has it from v1.12.0 (`ist8310 -X -b 1 -R 10 start`, line 25)."""
    rows = {"CAL_MAG1_ID": GPS_IST8310, "CAL_MAG1_ROT": 0, "SENS_EXT_I2C_PRB": 1}
    path = write_params(tmp_path / "v5.params", "1.11.3", rows)
    for board in ((), ("--board", "px4_fmu-v5")):
        (inst,) = run(capsys, str(path), *board)["instances"]
        assert inst["values"]["rotation"] == 10
        assert IST8310_NOTE.format(version="v1.11.3") in inst["notes"]
    # fmu-v5's v1.12.0 start has the -R the instance gets: no "check its calibration" clause,
    # neither in the note nor where that release's board script takes the compass over
    (note,) = [n for n in inst["notes"] if n.startswith("the board's script starts it")]
    assert "-R 10 start" in note and "check its calibration" not in note
    upgraded = run(capsys, str(path), "--board", "px4_fmu-v5", "--target-release", "v1.12.0")
    (mag,) = upgraded["left_out"]
    assert "-R 10 start" in mag["line"] and "check its calibration" not in mag["line"]


def test_the_same_compass_of_px4_1_13_keeps_its_rotation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = {"CAL_MAG1_ID": GPS_IST8310, "SENS_EXT_I2C_PRB": 1}
    path = write_params(tmp_path / "v13.params", "1.13.3", rows)
    (inst,) = run(capsys, str(path))["instances"]
    assert (inst["values"]["rotation"], inst["notes"]) == (0, [])


@pytest.mark.parametrize(
    ("release", "turned"),
    [("v1.11.0", 0), ("v1.11.3", 0), ("v1.12.0", 10), ("v1.12.1", 10), ("main", 10)],
)
def test_a_target_release_before_the_change_keeps_the_rotation(
    release: str, turned: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without a board no target drops the probed compass: the rotation follows the target's
    driver, the boundary being v1.12.0."""
    rows = {"CAL_MAG1_ID": GPS_IST8310, "SENS_EXT_I2C_PRB": 1}
    path = write_params(tmp_path / "v11.params", "1.11.3", rows)
    (inst,) = run(capsys, str(path), "--target-release", release)["instances"]
    assert inst["values"]["rotation"] == turned
    said = [n for n in inst["notes"] if "other axes" in n]
    assert said == ([IST8310_NOTE.format(version="v1.11.3")] if turned else [])


def test_a_gps_qmc5883_of_px4_1_11_on_an_external_bus_gets_rotation_10(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """v1.11's qmc5883 on an external bus reported (-y, x, z), today's qmc5883l (x, -y, -z):
    C 10 (an internal one's would be 14, as mindpx-v2's 12 -> 6 shows)."""
    qmc = devid.encode("i2c", 1, 0x0D, 0x08)
    path = write_params(tmp_path / "q.params", "1.11.3", {"CAL_MAG0_ID": qmc})
    (inst,) = run(capsys, str(path), "--board", "px4_fmu-v5")["instances"]
    assert inst["values"]["rotation"] == 10
    assert inst["notes"] == [
        "rotation 10 (was 0 on PX4 v1.11.3: rc.sensors starts it without -R): qmc5883 (today "
        "qmc5883l) on an external bus reports other axes from PX4 v1.12.0 (PX4 commit "
        "24125b3da4, PR #14384): the same orientation as before"
    ]


@pytest.mark.parametrize(("bus", "turned", "kind"), [(1, 14, "internal"), (2, 10, "external")])
def test_a_qmc5883_of_px4_1_11_is_turned_by_its_bus_kind(bus: int, turned: int, kind: str) -> None:
    """mindpx-v2 at v1.11.0: I2C bus 1 internal, 2 external (its src/i2c.cpp). Its script's
    own QMC5883 row taken away, a QMC5883 found on either bus is an instance: v1.11's driver
    reported (y, -x, z) on an internal bus, (-y, x, z) on an external one."""
    from px4params import migrate
    from px4params.vehicle.boards import load_boards

    mindpx = load_boards().by_name("airmind_mindpx-v2", "v1.11.0")
    assert mindpx is not None and mindpx.internal_i2c_buses == (1,)
    rows = tuple(r for r in mindpx.devices if r.driver != "qmc5883")
    board = dataclasses.replace(mindpx, devices=rows)
    qmc = devid.encode("i2c", bus, 0x0D, 0x08)
    proposal = migrate.migrate(config({"CAL_MAG0_ID": qmc}), table="px4-v1.11", board=board)
    (inst,) = proposal.instances
    assert inst.values["rotation"] == turned
    assert f"qmc5883 (today qmc5883l) on an {kind} bus reports" in inst.notes[-1]
    # the board's own fix, through the same function: -I -R 12 became -R 6
    assert axes.turn(["qmc5883l"], 12, "w", (1, 11, 0), None, True, None).rotation == 6


def test_a_boot_consoles_rotation_of_px4_1_11_is_turned_too() -> None:
    from px4params import migrate

    console = "ist8310 #0 on I2C bus 2 (external, equal to '-b 1')\n"
    proposal = migrate.migrate(config(console=console), table="px4-v1.11")
    (inst,) = proposal.instances
    assert inst.values["rotation"] == 10
    assert inst.notes == [
        "rotation 10 (was 0 on PX4 v1.11.2: rc.sensors starts it without -R): ist8310 reports "
        "other axes from PX4 v1.12.0 (PX4 commit 7569722821): the same orientation as before"
    ]


@pytest.mark.parametrize("rotation", [41, 44, 99, -1])
def test_a_rotation_beyond_px4s_enum_is_not_turned(rotation: int) -> None:
    # v1.11's 41-45 and values no PX4 has: left to the rotation field's range check, no KeyError
    assert axes.turn(["lis2mdl"], rotation, "why", (1, 15, 0), None, False, None) is None
    assert axes.turn(["ist8310"], rotation, "why", (1, 11, 3), None, False, None) is None


@pytest.mark.parametrize(("name", "version"), [("px4-practice.params", "v1.10.1")])
def test_a_real_pixhawk_4_files_gps_compass_is_turned(
    name: str, version: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A real Pixhawk 4 file of PX4 "1.10.1 dev": its GPS IST8310 (CAL_MAG0_ID 396809, I2C bus
    1, 0x0E, CAL_MAG0_ROT 0) ran with the old driver's axes."""
    (truth,) = [t for t in corpus.CORPUS if t.name == name]
    path = corpus.locate(truth, tmp_path)
    (inst,) = run(capsys, str(path))["instances"]
    assert inst["values"]["rotation"] == 10
    assert inst["notes"] == [IST8310_NOTE.format(version=version)]


def test_a_file_naming_no_release_keeps_the_rotation_and_says_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = {"CAL_MAG1_ID": GPS_IST8310, "SENS_EXT_I2C_PRB": 1}
    path = write_params(tmp_path / "nover.params", None, rows)
    (inst,) = run(capsys, str(path))["instances"]
    assert inst["values"]["rotation"] == 0
    assert inst["notes"] == [
        "rotation 0 taken as is (rc.sensors starts it without -R): the file names no PX4 "
        "release, and ist8310 reports other axes from PX4 v1.12.0 (PX4 commit 7569722821): for "
        "a file of PX4 v1.11 or older it is 10"
    ]


def test_a_release_nobody_checked_keeps_the_rotation_and_says_so() -> None:
    # lis2mdl -> iis2mdc: old axes at v1.15.0, new at release/1.18; v1.16 was not read
    turned = axes.turn(["iis2mdc"], 4, "why", (1, 16, 0), None, False, None)
    assert turned is not None and turned.rotation == 4
    assert turned.note == (
        "rotation 4 taken as is (why): lis2mdl (today iis2mdc) reports other axes from PX4 v1.18 "
        "(PX4 commit f0a852918b), and the axes of PX4 v1.16.0 were not checked (PX4 v1.15 "
        "reports the old ones): for a file of PX4 v1.15 or older it is 14"
    )
    assert axes.turn(["iis2mdc"], 4, "why", (1, 15, 2), "v1.18", False, None).rotation == 14
    assert axes.turn(["iis2mdc"], 4, "why", (1, 15, 2), "v1.15.0", False, None) is None


def test_an_orientation_no_rotation_value_names_is_kept_and_said() -> None:
    # 17 (roll 90, yaw 45) after ist8310's C 10 is roll 90 and yaw 45 about other axes: no
    # value of the enum (the research note's table: 17 -> none)
    turned = axes.turn(["ist8310"], 17, "why", (1, 11, 3), None, False, None)
    assert turned is not None and turned.rotation == 17
    assert turned.note == (
        "rotation 17 taken as is (why): ist8310 reports other axes from PX4 v1.12.0 (PX4 commit "
        "7569722821), and no -R value gives its orientation of PX4 v1.11.3 on the other axes "
        "(17 after 10): check it, and set it by calibration"
    )


def test_a_driver_only_some_boards_built_old_turns_only_there() -> None:
    # v1.11.0 built the legacy imu/mpu6000 only for fmurt1062-v1 and spracing h7extreme
    old = (1, 11, 0)
    assert axes.turn(["mpu6000"], 11, "w", old, None, False, "spracing_h7extreme").rotation == 5
    assert axes.turn(["mpu6000"], 11, "w", old, None, False, "px4_fmu-v4") is None
    unknown = axes.turn(["mpu6000"], 11, "w", old, None, False, None)
    assert unknown == axes.Turned(
        11,
        "w",
        "rotation 11 taken as is (w): mpu6000 reports other axes from PX4 v1.12.0 (PX4 commit "
        "11ad41f7cb) where the build had the old driver (nxp_fmurt1062-v1, spracing_h7extreme), "
        "and the board is not known",
        # nothing turned, so nothing to say the board script's new -R keeps (build.py)
        what="",
    )


@pytest.mark.parametrize(
    ("row", "error"),
    [
        ({"modules": ["x"]}, "driver_axes.toml: change 1: old_through missing"),
        ({**{"colour": 1}}, "driver_axes.toml: change 1: unknown key 'colour' (expected modules,"),
        ({"rotation": 41}, "driver_axes.toml: change 1: rotation = 41: not a value of PX4's"),
        ({"internal_rotation": 45}, "driver_axes.toml: change 1: internal_rotation = 45: not a"),
        ({"new_from": "soon"}, "driver_axes.toml: change 1: new_from: release 'soon' is no PX4"),
        ({"pr": "14384"}, "driver_axes.toml: change 1: pr = '14384': expected a int"),
    ],
)
def test_a_wrong_table_row_is_refused_naming_it(row: dict[str, object], error: str) -> None:
    good = {
        "modules": ["x"], "old_through": "v1.11", "new_from": "v1.12.0", "rotation": 10,
        "commit": "0", "old_source": "a", "new_source": "b",
    }  # fmt: skip
    bad = {**good, **row}
    if row == {"modules": ["x"]}:
        del bad["old_through"]
    with pytest.raises(MigrationError) as e:
        axes.parse_changes({"change": [bad]})
    assert str(e.value).startswith(error)


def test_a_rotation_name_without_its_angles_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    names = {"0": "No rotation", "1": "Yaw 45 deg", "2": "Quarter turn"}
    monkeypatch.setattr(axes, "value_set", lambda name: names)
    axes.rotations.cache_clear()
    try:
        with pytest.raises(MigrationError) as e:
            axes.rotations()
    finally:
        axes.rotations.cache_clear()
    assert str(e.value) == (
        "value_sets.toml: rotation 2 = 'Quarter turn': expected 'Roll R deg, Pitch P deg, Yaw Y "
        "deg' (each part optional) or 'No rotation'"
    )


@pytest.mark.parametrize(
    ("value", "then"),
    # the same rotation worked out by hand from rot_lookup's angles (v1.11.0 rotation.h:149-151):
    # 41 = yaw 180 after roll 270 = pitch 180 after roll 90 (31); 44 (pitch 9, yaw 180) and 45
    # (pitch 45) are no rotation of the enum from v1.12.0
    [(41, "set CAL_MAG1_ROT = 31, the same rotation"),
     (42, "set CAL_MAG1_ROT = 36, the same rotation"),
     (43, "set CAL_MAG1_ROT = 29, the same rotation"),
     (44, "no value of today's enum is that rotation: calibrate the compass again"),
     (45, "no value of today's enum is that rotation: calibrate the compass again")],
)  # fmt: skip
def test_a_1_11_compass_rotation_px4_1_12_resets_is_said_with_the_value_that_keeps_it(
    value: int, then: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = {"CAL_MAG1_ID": GPS_IST8310, "CAL_MAG1_ROT": value, "SENS_EXT_I2C_PRB": 1}
    path = write_params(tmp_path / "v5.params", "1.11.3", rows)
    (inst,) = run(capsys, str(path))["instances"]
    assert inst["notes"][-1] == (
        f"CAL_MAG1_ROT = {value}: PX4 1.12 and later have no rotation {value} (removed by PX4 "
        f"commit 00e955cc3e) and reset it to 0 at boot; {then}"
    )
    # for PX4 1.11 itself the rotation is still there: nothing said
    (inst,) = run(capsys, str(path), "--target-release", "v1.11.0")["instances"]
    assert not [n for n in inst["notes"] if "reset it to 0" in n]


def test_a_rotation_the_enum_still_has_or_a_file_of_px4_1_12_is_not_said_to_be_reset() -> None:
    assert axes.removed_rotation("CAL_MAG0_ROT", 40, (1, 11, 3), None) is None
    assert axes.removed_rotation("CAL_MAG0_ROT", 46, (1, 11, 3), None) is None
    assert axes.removed_rotation("CAL_MAG0_ROT", 41.5, (1, 11, 3), None) is None
    assert axes.removed_rotation("CAL_MAG0_ROT", 41.0, (1, 11, 3), None) == (
        axes.removed_rotation("CAL_MAG0_ROT", 41, (1, 11, 3), None)
    )
    # a file of 1.12 on: its PX4 had reset the value at boot already
    assert axes.removed_rotation("CAL_MAG0_ROT", 41, (1, 12, 0), None) is None
    # a file naming no release: 41 is of 1.11 or older whatever it says
    assert axes.removed_rotation("CAL_MAG0_ROT", 41, None, "v1.12.0") is not None


def test_a_board_imu_whose_new_r_keeps_its_orientation_is_said_the_same_not_to_check() -> None:
    """Crazyflie: its script starts the MPU9250 with `mpu9250 -I -R 12 start` at v1.11.0 (line
    9) and `mpu9250_i2c -I -b 3 -a 0x69 -R 6 start` from v1.12.0: PX4's own fix for the rewritten
    driver's axes (12 after C 14 is 6). No declared driver drives an MPU9250: the board rows'
    modules say whose axes changed, and only a Crazyflie (or BeagleBone Blue) built the old one."""
    from px4params import migrate
    from px4params.migrate.config import OldConfig
    from px4params.vehicle.boards import load_boards

    imu = devid.encode("i2c", 3, 0x69, 0x24)  # MPU9250 (PX4 1.11's devtype 0x24)
    config = OldConfig("t.params", "QGC .params", {"CAL_ACC0_ID": imu}, version=(1, 11, 3))
    crazyflie = load_boards().by_name("bitcraze_crazyflie", "v1.11.0")
    (imu_out,) = migrate.migrate(config, board=crazyflie).left_out
    assert imu_out.later is not None and imu_out.later.endswith(
        "rotation 6 (was 12): the board's script still starts it, with -R 6: the same "
        "orientation (mpu9250 reports other axes from PX4 v1.12.0 (PX4 commit 3abe2e82d1))"
    )


# PX4 1.11's hand-coded axis mapping of every rotation (src/lib/conversion/rotation.cpp at
# v1.11.0 71db0903a9, rotate_3f(), lines 67-391): what -R N makes of a driver's (x, y, z).
# 38's numbers are PX4's own 6-digit ones; the rest are exact (S: PX4's M_SQRT1_2_F).
S = 0.5**0.5
Vector = tuple[float, float, float]
PX4_AXES: dict[int, Callable[[float, float, float], Vector]] = {
    0: lambda x, y, z: (x, y, z),
    1: lambda x, y, z: (S * (x - y), S * (x + y), z),
    2: lambda x, y, z: (-y, x, z),
    3: lambda x, y, z: (-S * (x + y), S * (x - y), z),
    4: lambda x, y, z: (-x, -y, z),
    5: lambda x, y, z: (S * (y - x), -S * (x + y), z),
    6: lambda x, y, z: (y, -x, z),
    7: lambda x, y, z: (S * (x + y), S * (y - x), z),
    8: lambda x, y, z: (x, -y, -z),
    9: lambda x, y, z: (S * (x + y), S * (x - y), -z),
    10: lambda x, y, z: (y, x, -z),
    11: lambda x, y, z: (S * (y - x), S * (x + y), -z),
    12: lambda x, y, z: (-x, y, -z),
    13: lambda x, y, z: (-S * (x + y), S * (y - x), -z),
    14: lambda x, y, z: (-y, -x, -z),
    15: lambda x, y, z: (S * (x - y), -S * (x + y), -z),
    16: lambda x, y, z: (x, -z, y),
    17: lambda x, y, z: (S * (x + z), S * (x - z), y),  # 16, then 1
    18: lambda x, y, z: (z, x, y),
    19: lambda x, y, z: (S * (z - x), S * (x + z), y),  # 16, then 3
    20: lambda x, y, z: (x, z, -y),
    21: lambda x, y, z: (S * (x - z), S * (x + z), -y),  # 20, then 1
    22: lambda x, y, z: (-z, x, -y),
    23: lambda x, y, z: (-S * (x + z), S * (x - z), -y),  # 20, then 3
    24: lambda x, y, z: (z, y, -x),
    25: lambda x, y, z: (-z, y, x),
    26: lambda x, y, z: (-y, -x, -z),
    27: lambda x, y, z: (y, x, -z),
    28: lambda x, y, z: (y, -z, -x),
    29: lambda x, y, z: (-z, -y, -x),
    30: lambda x, y, z: (-y, z, -x),
    31: lambda x, y, z: (-x, -z, -y),
    32: lambda x, y, z: (-x, z, y),
    33: lambda x, y, z: (-y, -z, x),
    34: lambda x, y, z: (z, -y, x),
    35: lambda x, y, z: (y, z, x),
    36: lambda x, y, z: (z, -x, -y),
    37: lambda x, y, z: (-z, -x, y),
    38: lambda x, y, z: (
        0.146371 * x + 0.362280 * y - 0.920505 * z,
        -0.344827 * x - 0.853477 * y - 0.390731 * z,
        -0.927184 * x + 0.374607 * y,
    ),
    39: lambda x, y, z: (S * (x - z), y, S * (x + z)),
    40: lambda x, y, z: (S * (x - y), -z, S * (x + y)),
}
# the same function's 41-45, gone from 1.12 (axes.REMOVED_AT_1_12 keeps their angles)
PX4_1_11_AXES: dict[int, Callable[[float, float, float], Vector]] = {
    41: lambda x, y, z: (-x, -z, -y),
    42: lambda x, y, z: (z, -x, -y),
    43: lambda x, y, z: (-z, -y, -x),
    44: lambda x, y, z: (-0.987688 * x - 0.156434 * z, -y, -0.156434 * x + 0.987688 * z),
    45: lambda x, y, z: (S * (x + z), y, S * (z - x)),
}


def as_matrix(axes_of: Callable[[float, float, float], Vector]) -> list[Vector]:
    """The matrix of a mapping of (x, y, z), by rows: its columns are the unit axes' images."""
    columns = [axes_of(*unit) for unit in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
    return [(columns[0][i], columns[1][i], columns[2][i]) for i in range(3)]


def test_the_enum_is_pX4s_whole_rotation_enum() -> None:
    assert sorted(axes.rotations()) == sorted(PX4_AXES)


@pytest.mark.parametrize("value", sorted(PX4_AXES))
def test_each_rotations_matrix_turns_axes_as_pX4s_rotate_3f(value: int) -> None:
    want = as_matrix(PX4_AXES[value])
    for got_row, want_row in zip(axes.rotations()[value], want, strict=True):
        assert got_row == pytest.approx(want_row, abs=1e-6), value


@pytest.mark.parametrize("value", sorted(PX4_1_11_AXES))
def test_a_removed_rotations_angles_turn_axes_as_pX4_1_11_did(value: int) -> None:
    want = as_matrix(PX4_1_11_AXES[value])
    got = axes.matrix(*axes.REMOVED_AT_1_12[value])
    for got_row, want_row in zip(got, want, strict=True):
        assert got_row == pytest.approx(want_row, abs=1e-6), value


def about(axis: str, degrees: float) -> list[Vector]:
    """The right-handed rotation by ``degrees`` about the x, y or z axis, by rows."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return {
        "x": [(1, 0, 0), (0, c, -s), (0, s, c)],
        "y": [(c, 0, s), (0, 1, 0), (-s, 0, c)],
        "z": [(c, -s, 0), (s, c, 0), (0, 0, 1)],
    }[axis]


def product(a: list[Vector], b: list[Vector]) -> list[Vector]:
    """``a · b``: b's rotation first, then a's."""

    def row_of(row: Vector) -> Vector:
        x, y, z = (sum(r * b[k][j] for k, r in enumerate(row)) for j in range(3))
        return x, y, z

    return [row_of(row) for row in a]


@pytest.mark.parametrize(("roll", "pitch", "yaw"), [(30, 50, 70), (-110, 20, 250), (200, -35, 100)])
def test_the_matrix_of_any_angles_is_yaw_then_pitch_then_roll(
    roll: float, pitch: float, yaw: float
) -> None:
    """PX4's matrix::Dcm of Euler angles (PX4-Matrix matrix/Dcm.hpp): a 3-2-1 intrinsic
    Tait-Bryan sequence, yaw about z, pitch about the new y, roll about the newest x; worked
    here as the product of the three single-axis rotations. No angle is a right one, so no
    cos or sin term is 0 and each entry's every term counts."""
    want = product(about("z", yaw), product(about("y", pitch), about("x", roll)))
    for got_row, want_row in zip(axes.matrix(roll, pitch, yaw), want, strict=True):
        assert got_row == pytest.approx(want_row, abs=1e-12)


# rotation.h at v1.12.0, rotate_3(): 26 falls through to 14's case and 27 to 10's, the same
# rotation: composed() names it by the lower value
ALIASES = {26: 14, 27: 10}
# the 24 rotations of a cube, all in the enum: any two of them compose to one of them
RIGHT_ANGLED = [0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 25, *range(28, 38)]


def test_a_rotation_composed_with_its_inverse_is_no_rotation() -> None:
    for value in axes.rotations():
        assert axes.composed(value, value, inverse=True) == 0, value


def test_turning_by_a_rotation_and_back_gives_the_rotation_again() -> None:
    for first in axes.rotations():
        for then in axes.rotations():
            there = axes.composed(first, then)
            if there is not None:
                back = axes.composed(first, there, inverse=True)
                assert back == ALIASES.get(then, then), (first, then)


def test_two_right_angled_rotations_compose_to_a_right_angled_one() -> None:
    for first in RIGHT_ANGLED:
        for then in RIGHT_ANGLED:
            assert axes.composed(first, then) in RIGHT_ANGLED, (first, then)


# the boards of the changes PX4 built only for some (driver_axes.toml's only_boards)
FIX_BOARDS = {"mpu6000": "spracing_h7extreme", "mpu9250": "bitcraze_crazyflie"}


@pytest.mark.parametrize(("script", "module", "internal", "old", "new"), BOARD_FIXES)
def test_a_file_of_px4_1_12_for_a_1_11_target_gets_the_board_scripts_old_rotation(
    script: str, module: str, internal: bool, old: int, new: int
) -> None:
    """PX4's board fixes read backwards: the v1.12.0 -R of a file of 1.12 is the v1.11.0 one
    for a 1.11 target (turned by C's inverse)."""
    board = FIX_BOARDS.get(module)
    turned = axes.turn([module], new, "w", (1, 12, 0), "v1.11.0", internal, board)
    assert turned is not None and turned.rotation == old, script


@pytest.mark.parametrize(
    ("release", "side"),
    [("v1.11.0", "old"), ((1, 10, 1), "old"), ((1, 11, 3), "old"), ("v1.12.0", "new"),
     ((1, 13, 3), "new"), ("main", "new"), (None, "new")],
)  # fmt: skip
def test_a_release_reports_the_ist8310s_old_axes_through_1_11_and_the_new_from_1_12(
    release: str | tuple[int, ...] | None, side: str
) -> None:
    (ist8310,) = [c for c in axes.changes() if c.modules == ("ist8310",)]
    assert ist8310.side(release) == side


def test_a_release_between_the_two_read_is_on_neither_side() -> None:
    # lis2mdl -> iis2mdc: read at v1.15.0 (old) and release/1.18 (new), v1.16 and v1.17 not
    (lis2mdl,) = [c for c in axes.changes() if "lis2mdl" in c.modules]
    sides = [lis2mdl.side(r) for r in ((1, 15, 2), (1, 16, 0), "v1.17.0", "v1.18")]
    assert sides == ["old", None, None, "new"]


def only_change(monkeypatch: pytest.MonkeyPatch, **row: object) -> None:
    """The table as one made-up change (old axes through v1.11, new from v1.12.0, C 10)."""
    base = {
        "modules": ["drv"], "old_through": "v1.11", "new_from": "v1.12.0", "rotation": 10,
        "commit": "0123456789", "old_source": "a", "new_source": "b",
    }  # fmt: skip
    monkeypatch.setattr(axes, "changes", lambda: axes.parse_changes({"change": [base | row]}))


def test_a_driver_renamed_twice_is_named_by_its_first_and_todays_name(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    only_change(monkeypatch, modules=["first", "second", "third"])
    turned = axes.turn(["second"], 0, "w", (1, 11, 0), None, False, None)
    assert turned is not None and turned.what == (
        "first (today third) reports other axes from PX4 v1.12.0 (PX4 commit 0123456789)"
    )
    assert turned.why == "0 on PX4 v1.11.0 (w), turned for third's axes"


def test_a_change_that_is_no_half_turn_is_undone_by_its_inverse(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Every real C is a half turn, its own inverse; a made-up C of yaw 90 (2) tells them
    apart. Its old report is the new one turned by yaw 90, so -R 0 on the new axes is -R 6
    (yaw 270, C's inverse) on the old, and -R 0 on the old is -R 2 on the new."""
    only_change(monkeypatch, rotation=2, new_from="v1.13.0")

    def turn(file: tuple[int, int, int] | None, release: str | None) -> axes.Turned | None:
        return axes.turn(["drv"], 0, "w", file, release, False, None)

    for file, release, rotation in [((1, 11, 0), None, 2), ((1, 13, 0), "v1.11.0", 6)]:
        turned = turn(file, release)
        assert turned is not None and turned.rotation == rotation, release
    # v1.12 is between the releases read: the note gives the other side's value
    unread = "rotation 0 taken as is (w): drv reports other axes from PX4 v1.13.0 (PX4 commit "
    unread += "0123456789), and the axes of PX4 v1.12.0 were not checked (PX4 v1.11 reports the "
    unread += "old ones): for a file of PX4 {}"
    assert turn((1, 12, 0), None) == axes.Turned(0, "w", unread.format("v1.11 or older it is 2"))
    assert turn((1, 12, 0), "v1.11.0") == axes.Turned(
        0, "w", unread.format("v1.13.0 or newer it is 6")
    )
    # a target between them: the file's side is known, each way turned by C or its inverse
    target = "rotation 0 taken as is (w): drv reports other axes from PX4 v1.13.0 (PX4 commit "
    target += "0123456789), and the axes of PX4 v1.12.0 were not checked (PX4 v1.11 reports the "
    target += "old ones): for PX4 {}"
    assert turn((1, 11, 0), "v1.12.0") == axes.Turned(
        0, "w", target.format("v1.13.0 or newer it is 2")
    )
    assert turn((1, 13, 0), "v1.12.0") == axes.Turned(
        0, "w", target.format("v1.11 or older it is 6")
    )


def test_a_file_naming_no_release_whose_orientation_no_value_names_says_so() -> None:
    # 17 after ist8310's C 10: no value (the research note's table, as above)
    turned = axes.turn(["ist8310"], 17, "w", None, None, False, None)
    assert turned == axes.Turned(
        17,
        "w",
        "rotation 17 taken as is (w): the file names no PX4 release, and ist8310 reports other "
        "axes from PX4 v1.12.0 (PX4 commit 7569722821): for a file of PX4 v1.11 or older no -R "
        "value names it",
    )


def test_the_cached_tables_rows_and_a_turns_answer_cannot_be_changed_in_place() -> None:
    # changes() hands every caller the same rows: one caller's edit would be everyone's
    change = axes.changes()[0]
    turned = axes.turn(["ist8310"], 0, "w", (1, 11, 3), None, False, None)
    assert turned is not None
    with pytest.raises(dataclasses.FrozenInstanceError):
        change.rotation = 0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        turned.rotation = 0  # type: ignore[misc]
    assert hash(change) == hash(axes.changes()[0])
    assert hash(turned) == hash(dataclasses.replace(turned))


def test_a_target_release_nobody_checked_keeps_the_rotation_and_says_both_sides(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A LIS2MDL of PX4 v1.15.2 for a vehicle going to v1.16.0: the table read the driver's
    old axes at v1.15.0 and the new ones at release/1.18, so for v1.16 nobody knows which; the
    rotation stays, and the note gives what it becomes from v1.18 (the change C = 10 after 0)."""
    mag = devid.encode("i2c", 1, 0x1E, 0x0E)  # DRV_MAG_DEVTYPE_LIS2MDL (today IIS2MDC)
    rows = {"CAL_MAG1_ID": mag, "CAL_MAG1_ROT": 4, "SENS_EXT_I2C_PRB": 1}
    path = write_params(tmp_path / "v15.params", "1.15.2", rows)
    (inst,) = run(capsys, str(path), "--target-release", "v1.16.0")["instances"]
    assert inst["values"]["rotation"] == 0
    assert inst["notes"][0] == (
        "rotation 0 taken as is (rc.sensors starts it without -R): lis2mdl (today iis2mdc) "
        "reports other axes from PX4 v1.18 (PX4 commit f0a852918b), and the axes of PX4 v1.16.0 "
        "were not checked (PX4 v1.15 reports the old ones): for PX4 v1.18 or newer it is 10"
    )
    (inst,) = run(capsys, str(path), "--target-release", "v1.18")["instances"]
    assert inst["values"]["rotation"] == 10
    # from the new side back: a file of v1.18 for a v1.16 vehicle
    turned = axes.turn(["iis2mdc"], 10, "why", (1, 18, 0), "v1.16.0", False, None)
    assert turned is not None and turned.rotation == 10
    assert turned.note.endswith("for PX4 v1.15 or older it is 0")
    # ROTATION_ROLL_90_PITCH_68_YAW_293 (38) after C is no value of the enum
    turned = axes.turn(["iis2mdc"], 38, "why", (1, 15, 2), "v1.16.0", False, None)
    assert turned is not None and turned.rotation == 38
    assert turned.note.endswith("for PX4 v1.18 or newer no -R value names it")
