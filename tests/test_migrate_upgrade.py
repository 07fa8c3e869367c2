"""``px4params migrate`` for the firmware a vehicle will run: a device the board's script of the
file's release starts, judged again with the board's scripts of every later release the board
table knows, and ``--target-release`` making the proposal for one of them.

The answers are PX4's scripts, read at the table's snapshots: the Cube Orange's
boards/cubepilot/cubeorange/init/rc.board_sensors line 17 at v1.11.0 is
``ak09916 -X -b 2 -R 6 start`` (the Here2 GPS's compass; ``-X -b 2`` was the second external
bus then, I2C bus 1), and from v1.12.0 that script starts no I2C device; rc.sensors at v1.12.0
line 145 probes ``ak09916 -X -q start`` (no -R) while SENS_EXT_I2C_PRB is 1. The real log
``sample_log_small.ulg`` is such a Cube Orange on v1.11.2 (its boot console: "ak09916 #0 on
I2C bus 1 (external, equal to '-b 2')", CAL_MAG1_ID 592905, SENS_EXT_I2C_PRB 1).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest
import shared_data
from px4params import migrate
from px4params.cli.main import main
from px4params.vehicle import devid
from px4params.vehicle.boards import load_boards

CUBE = "cubepilot_cubeorange"
SCRIPT = "boards/cubepilot/cubeorange/init/rc.board_sensors"
OLD_LINE = f"'ak09916 -X -b 2 -R 6 start' (PX4/PX4-Autopilot {SCRIPT}:17 at v1.11.0"
RC_SENSORS = "ROMFS/px4fmu_common/init.d/rc.sensors"
PROBE = f"'ak09916 -X -q start' (PX4/PX4-Autopilot {RC_SENSORS}:145 at v1.12.0"
HERE2_MAG = devid.encode("i2c", 1, 0x0C, 0x09)  # 592905: the sample log's CAL_MAG1_ID
RELEASES = ["v1.12.0", "v1.13.0", "v1.14.0", "v1.15.0", "v1.18", "main"]


def run(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    assert main(["migrate", *args, "--json"]) == 0
    report: dict[str, Any] = json.loads(capsys.readouterr().out)
    return report


def cube_params(path: Path, probe: int) -> Path:
    """A Cube Orange's QGC file of PX4 1.11.2 with the Here2 compass in CAL_MAG1."""
    rows = {"CAL_MAG1_ID": HERE2_MAG, "CAL_MAG1_ROT": 0, "SENS_EXT_I2C_PRB": probe}
    lines = ["# Onboard parameters for Vehicle 1", "#", "# Stack: PX4", "# Version: 1.11.2"]
    lines += ["#", "# Vehicle-Id Component-Id Name Value Type"]
    lines += [f"1\t1\t{name}\t{value}\t6" for name, value in rows.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_tables_cube_orange_rows_are_pX4s_scripts() -> None:
    """What the tests below rest on, as the table transcribes PX4's scripts."""
    table = load_boards()
    old = table.by_name(CUBE, "v1.11.0")
    assert old is not None
    (i2c,) = [d for d in old.devices if d.bus_kind == "I2C"]
    assert (i2c.driver, i2c.args, i2c.rotation) == ("ak09916", "-X -b 2 -R 6 start", 6)
    assert i2c.source.startswith(f"PX4/PX4-Autopilot {SCRIPT}:17 at v1.11.0")
    assert old.buses_of(i2c) == (1,)  # v1.11.0: the second external bus of i2c.cpp, bus 1
    for release in RELEASES:
        board = table.by_name(CUBE, None if release == "main" else release)
        assert board is not None
        assert [d for d in board.devices if d.bus_kind == "I2C"] == []


def test_the_real_cube_orange_log_says_its_compass_needs_the_manifest_on_newer_px4(
    capsys: pytest.CaptureFixture[str],
) -> None:
    log = shared_data.shared_file(shared_data.SAMPLE_LOG)
    report = run(capsys, str(log))
    # Today's proposal is unchanged: at v1.11 the board's script starts the compass.
    assert [i["name"] for i in report["instances"]] == ["MS4525DO#0"]
    assert report["target_release"] is None
    assert report["compared_releases"] == RELEASES
    (mag,) = [i for i in report["left_out"] if i["found"].startswith("CAL_MAG1_ID")]
    assert mag["reason"] == "board"
    later = mag["later"]
    assert OLD_LINE in later
    assert f"PX4 v1.12.0 .. main: not the board's; only where SENS_EXT_I2C_PRB == 1: {PROBE}" in (
        later
    )
    assert "rotation 0 (was 6)" in later
    assert later.endswith("--target-release v1.12.0 (or later) proposes it as an instance")
    # The text report carries the same line beneath the device's.
    assert main(["migrate", str(log)]) == 0
    text = capsys.readouterr().err
    assert f"\n  {mag['line']}\n    later: {later}\n" in text
    assert "  the board's scripts compared with PX4 v1.12.0 .. main\n" in text


@pytest.mark.parametrize(
    ("given", "target"),
    [("v1.12.0", "v1.12.0"), ("main", "main"), ("MAIN", "main"), ("V1.12.0", "v1.12.0")],
)
def test_for_a_newer_target_the_real_logs_compass_is_an_instance_with_its_old_rotation(
    given: str, target: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # (MAIN and V1.12.0 were refused: "not a PX4 release")
    log = shared_data.shared_file(shared_data.SAMPLE_LOG)
    report = run(capsys, str(log), "--target-release", given)
    assert report["target_release"] == target
    assert report["compared_releases"] == RELEASES[: RELEASES.index(target) + 1]
    got = {
        i["name"]: (i["values"]["bus.i2c.bus_id"], i["values"]["bus.i2c.address"],
                    i["values"].get("rotation"))
        for i in report["instances"]
    }  # fmt: skip
    assert got == {"AK09916#0": (1, 0x0C, 6), "MS4525DO#0": (2, 0x28, None)}
    (mag,) = [i for i in report["instances"] if i["name"] == "AK09916#0"]
    assert mag["origin"].startswith(f"CAL_MAG1_ID = {HERE2_MAG}: AK09916 (MAG), I2C bus 1")
    said, rotation = mag["notes"]
    assert OLD_LINE in said and PROBE in said
    assert said.endswith(
        f"at {target} the board's script does not start it: the manifest does, with the -R 6 "
        "the file's line gives"
    )
    # the rotation's note points at the v1.11.0 start the note above cites
    assert rotation == "rotation 6: the -R of PX4 v1.11.0's start (above)"
    assert not [i for i in report["left_out"] if i["found"].startswith("CAL_MAG1_ID")]
    assert "param add AK09916#0\n" in report["airframe"]
    # The text report says which firmware the proposal is for, and how it was asked for.
    assert main(["migrate", str(log), "--target-release", target]) == 0
    text = capsys.readouterr().err
    assert f"\n  proposed for PX4 {target} (--target-release)\n" in text


def test_the_files_own_release_as_target_is_todays_proposal(
    capsys: pytest.CaptureFixture[str],
) -> None:
    log = shared_data.shared_file(shared_data.SAMPLE_LOG)
    today = run(capsys, str(log))
    own = run(capsys, str(log), "--target-release", "v1.11.0")
    assert own["instances"] == today["instances"]
    assert own["compared_releases"] == [] and own["target_release"] is None
    assert [i["reason"] for i in own["left_out"]] == [i["reason"] for i in today["left_out"]]


def test_without_probing_nothing_starts_the_cube_compass_on_newer_px4(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """SENS_EXT_I2C_PRB = 0: from v1.12.0 neither the board's script nor rc.sensors starts the
    Here2 compass, the silent failure; with a target it is proposed."""
    path = cube_params(tmp_path / "cube.params", probe=0)
    report = run(capsys, str(path), "--board", CUBE)
    (mag,) = report["left_out"]
    assert mag["reason"] == "board"
    assert (
        f"PX4 v1.12.0 .. main: no start (not in PX4/PX4-Autopilot {SCRIPT}, nor behind a switch "
        "this file sets)"
    ) in mag["later"]
    assert OLD_LINE in mag["later"]
    upgraded = run(capsys, str(path), "--board", CUBE, "--target-release", "v1.15.0")
    assert [(i["name"], i["values"]["rotation"]) for i in upgraded["instances"]] == [
        ("AK09916#0", 6)
    ]
    assert upgraded["left_out"] == []


def test_a_start_the_newer_scripts_keep_is_said_to_be_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pixhawk 6C: rc.board_sensors starts the GPS's IST8310 with `ist8310 -X -b 1 -R 10 start`
    at v1.13.0 (line 21) and still at main (line 35, read at bb59c637cd): left out at every
    target."""
    gps = devid.encode("i2c", 1, 0x0E, 0x06)
    path = tmp_path / "v6c.params"
    path.write_text(
        "# Stack: PX4\n# Version: 1.13.3\n#\n"
        f"1\t1\tCAL_MAG1_ID\t{gps}\t6\n1\t1\tSENS_EXT_I2C_PRB\t1\t6\n"
    )
    for extra in ((), ("--target-release", "main")):
        report = run(capsys, str(path), "--board", "px4_fmu-v6c", *extra)
        assert report["instances"] == []
        (mag,) = report["left_out"]
        assert mag["later"] == (
            "still started by the board's script through PX4 main: 'ist8310 -X -b 1 -R 10 "
            "start' (PX4/PX4-Autopilot boards/px4/fmu-v6c/init/rc.board_sensors:35 at main "
            "(branch main, bb59c637cd, 2026-08-13))"
        )


def test_a_start_whose_rotation_changed_stays_the_boards_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pixhawk 5: boards/px4/fmu-v5/init/rc.board_sensors starts its internal IST8310 (I2C bus
    3) with `ist8310 -I start` at v1.11.0 (line 19) and `ist8310 -I -R 10 start` from v1.12.0
    (line 22): still the board's at every target, its -R changed for the rewritten driver's
    axes (PX4 7569722821, tests/test_migrate_axes.py): the same orientation, nothing to check."""
    internal = devid.encode("i2c", 3, 0x0E, 0x06)
    path = tmp_path / "v5.params"
    path.write_text(f"# Stack: PX4\n# Version: 1.11.3\n#\n1\t1\tCAL_MAG0_ID\t{internal}\t6\n")
    script = "PX4/PX4-Autopilot boards/px4/fmu-v5/init/rc.board_sensors"
    for extra in ((), ("--target-release", "main")):
        report = run(capsys, str(path), "--board", "px4_fmu-v5", *extra)
        assert report["instances"] == []
        (mag,) = report["left_out"]
        assert mag["later"] == (
            f"the board's script of PX4 v1.11.0 starts it with 'ist8310 -I start' ({script}:19 "
            "at v1.11.0 (tag v1.11.0, 71db0903a9, 2020-09-07)); PX4 v1.12.0 .. main: the "
            f"board's 'ist8310 -I -R 10 start' ({script}:22 at v1.12.0 (tag v1.12.0, "
            "9524e8ec03, 2021-07-05)), rotation 10 (was 0): the board's script still starts "
            "it, with -R 10: the same orientation (ist8310 reports other axes from PX4 v1.12.0 "
            "(PX4 commit 7569722821))"
        )


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        ("latest", "not a PX4 release (expected a PX4 version from v1.11.0 on, such as v1.16.0, "
         "or main)"),
        ("v1.10.0", "older than every release of the board table (expected a PX4 version from "
         "v1.11.0 on, such as v1.16.0, or main)"),
        ("v1.11.0", "older than the file's PX4 v1.13.0 (expected one of v1.13.0, v1.14.0, "
         "v1.15.0, v1.18, main)"),
        # v1.12.5 runs v1.12.0's scripts, older than the file's: named as asked
        ("v1.12.5", "older than the file's PX4 v1.13.0 (expected one of v1.13.0, v1.14.0, "
         "v1.15.0, v1.18, main)"),
    ],
)  # fmt: skip
def test_a_target_release_the_table_cannot_judge_is_refused_in_one_line(
    value: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "v6c.params"
    path.write_text("# Stack: PX4\n# Version: 1.13.3\n#\n1\t1\tSENS_EXT_I2C_PRB\t1\t6\n")
    out = tmp_path / "out.airframe"
    code = main(["migrate", str(path), "--board", "px4_fmu-v6c", "--target-release", value,
                 "-o", str(out)])  # fmt: skip
    assert code != 0
    err = capsys.readouterr().err
    assert err == f"px4params: error: --target-release {value}: {expected}\n"
    assert "Traceback" not in err
    assert not out.exists()


def test_a_probed_compass_a_later_board_script_starts_itself_is_left_out_for_that_target(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pixhawk 5 on v1.11.3 with a GPS's IST8310 (I2C bus 1, 0x0E): at v1.11.0 only rc.sensors'
    probe `ist8310 -X start` (line 105) starts it, so it is an instance; from v1.12.0 the board's
    rc.board_sensors line 25 starts it itself, `ist8310 -X -b 1 -R 10 start`: an instance would
    start it twice there. Its -R 10 is the old 0 for the rewritten driver's axes (v1.12.0), the
    rotation the instance gets too: no rotation change to report."""
    gps = devid.encode("i2c", 1, 0x0E, 0x06)
    path = tmp_path / "v5.params"
    path.write_text(
        "# Stack: PX4\n# Version: 1.11.3\n#\n"
        f"1\t1\tCAL_MAG1_ID\t{gps}\t6\n1\t1\tSENS_EXT_I2C_PRB\t1\t6\n"
    )
    said = (
        "the board's script starts it from PX4 v1.12.0: 'ist8310 -X -b 1 -R 10 start' "
        "(PX4/PX4-Autopilot boards/px4/fmu-v5/init/rc.board_sensors:25 at v1.12.0 (tag v1.12.0, "
        "9524e8ec03, 2021-07-05))"
    )
    today = run(capsys, str(path), "--board", "px4_fmu-v5")
    (inst,) = today["instances"]
    assert (inst["name"], inst["values"]["rotation"]) == ("IST8310#0", 10)
    assert inst["notes"] == [
        f"{said}: for that firmware --target-release v1.12.0 (or later) leaves it out",
        "rotation 10 (was 0 on PX4 v1.11.3: rc.sensors starts it without -R): ist8310 reports "
        "other axes from PX4 v1.12.0 (PX4 commit 7569722821): the same orientation as before",
    ]
    for target in ("v1.12.0", "main"):
        upgraded = run(capsys, str(path), "--board", "px4_fmu-v5", "--target-release", target)
        assert upgraded["instances"] == []
        (mag,) = upgraded["left_out"]
        assert mag["reason"] == "board"
        assert mag["line"].endswith(
            f"{said}; on PX4 {target} it is the board's, not the manifest's"
        )


def test_a_target_without_a_known_board_is_said_to_compare_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A QGC file names no board: nothing to judge at any release, and the report says so
    rather than silently proposing as for the file's release."""
    path = cube_params(tmp_path / "cube.params", probe=1)
    report = run(capsys, str(path), "--target-release", "main")
    assert report["target_release"] is None and report["compared_releases"] == []
    assert (
        "--target-release main: no board known, so no board script is compared (--board NAME "
        "names it)"
    ) in report["assumptions"]


def test_a_target_for_a_file_naming_no_release_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """QGC's offline-editing file has no '# Version' line: its board script is judged with the
    newest row, and a target older than that is refused saying the file named no release (not
    "older than the file's PX4 main", which the file never said)."""
    path = shared_data.shared_file("qgc_offline_editing_v1.4.params")
    out = tmp_path / "out.airframe"
    code = main(["migrate", str(path), "--board", "px4_fmu-v5", "--target-release", "v1.15.0",
                 "-o", str(out)])  # fmt: skip
    assert code != 0
    err = capsys.readouterr().err
    assert err == (
        "px4params: error: --target-release v1.15.0: older than PX4 main, taken for a file that "
        "names no release (no '# Version' line) (expected one of main)\n"
    )
    assert not out.exists()


@pytest.mark.issue40
def test_a_start_without_r_in_every_release_is_kept_unrotated(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """ARK FMU v6X: boards/ark/fmu-v6x/init/rc.board_sensors starts its internal BMM150 (I2C
    bus 4) with `bmm150 -I start` at v1.14.0 (line 75) and still at main (line 95), never with
    -R: rotation 0 throughout, no rotation change to report."""
    internal = devid.encode("i2c", 4, 0x10, 0x43)
    path = tmp_path / "ark.params"
    path.write_text(f"# Stack: PX4\n# Version: 1.14.0\n#\n1\t1\tCAL_MAG0_ID\t{internal}\t6\n")
    report = run(capsys, str(path), "--board", "ark_fmu-v6x")
    assert report["instances"] == []
    (mag,) = report["left_out"]
    assert mag["later"] == (
        "still started by the board's script through PX4 main: 'bmm150 -I start' "
        "(PX4/PX4-Autopilot boards/ark/fmu-v6x/init/rc.board_sensors:95 at main "
        "(branch main, bb59c637cd, 2026-08-13))"
    )


@pytest.mark.issue40
def test_without_a_target_the_dropped_start_is_said_in_one_whole_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """SENS_EXT_I2C_PRB = 0, no --target-release: the Cube's v1.11.0 line 17 start, the
    releases from v1.12.0 that start nothing, and which target makes the manifest start it."""
    path = cube_params(tmp_path / "cube.params", probe=0)
    (mag,) = run(capsys, str(path), "--board", CUBE)["left_out"]
    assert mag["later"] == (
        f"the board's script of PX4 v1.11.0 starts it with {OLD_LINE} (tag v1.11.0, "
        "71db0903a9, 2020-09-07)); PX4 v1.12.0 .. main: no start (not in PX4/PX4-Autopilot "
        f"{SCRIPT}, nor behind a switch this file sets): on PX4 v1.12.0 and later the board's "
        "script does not start it, the manifest must: --target-release v1.12.0 (or later) "
        "proposes it as an instance"
    )


#: Pixhawk 5X's boards/px4/fmu-v5x/init/rc.board_sensors starts its internal BMM150 (I2C bus 4)
#: with `bmm150 -I start` at v1.11.0 (line 22); in the first hardware branch of each later
#: script with `bmm150 -I -R 6 start` at v1.12.0 (line 32) and v1.13.0 (line 56), with
#: `bmm150 -I start` at v1.14.0 (line 73), and with `bmm150 -I -R 6 start` again from v1.15.0
#: (line 73; at main too): no hardware revision in a QGC file settles the branches, and the
#: first runs.
V5X_SCRIPT = "PX4/PX4-Autopilot boards/px4/fmu-v5x/init/rc.board_sensors"
V5X_START = {
    "v1.11.0": f"'bmm150 -I start' ({V5X_SCRIPT}:22 at v1.11.0 (tag v1.11.0, 71db0903a9, "
    "2020-09-07))",
    "v1.12.0": f"'bmm150 -I -R 6 start' ({V5X_SCRIPT}:32 at v1.12.0 (tag v1.12.0, 9524e8ec03, "
    "2021-07-05))",
    "v1.13.0": f"'bmm150 -I -R 6 start' ({V5X_SCRIPT}:56 at v1.13.0 (tag v1.13.0, 6823cbc414, "
    "2022-06-07))",
    "v1.14.0": f"'bmm150 -I start' ({V5X_SCRIPT}:73 at v1.14.0 (tag v1.14.0, b8c541dd72, "
    "2023-10-18))",
    "main": f"'bmm150 -I -R 6 start' ({V5X_SCRIPT}:73 at main (branch main, bb59c637cd, "
    "2026-08-13))",
}


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("version", "later"),
    [
        # -R 0 at v1.11.0: each later run with -R 6 is a change, v1.14.0's -I start is not,
        # and the last release's -R 6 is not the file's
        ("1.11.3", f"the board's script of PX4 v1.11.0 starts it with {V5X_START['v1.11.0']}; "
         f"PX4 v1.12.0 .. v1.13.0: the board's {V5X_START['v1.12.0']}, rotation 6 (was 0); "
         f"PX4 v1.15.0 .. main: the board's {V5X_START['main']}, rotation 6 (was 0): the "
         "board's script still starts it, with -R 6: check its calibration after the update"),
        # -R 6 at v1.13.0: v1.14.0 alone differs, and at main it is -R 6 again: nothing to
        # check after the update
        ("1.13.0", f"the board's script of PX4 v1.13.0 starts it with {V5X_START['v1.13.0']}; "
         f"PX4 v1.14.0: the board's {V5X_START['v1.14.0']}, rotation 0 (was 6): the board's "
         "script still starts it"),
    ],
)  # fmt: skip
def test_a_rotation_that_changes_back_is_said_change_by_change_and_checked_only_if_it_differs(
    version: str, later: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    internal = devid.encode("i2c", 4, 0x10, 0x43)
    path = tmp_path / "v5x.params"
    path.write_text(f"# Stack: PX4\n# Version: {version}\n#\n1\t1\tCAL_MAG0_ID\t{internal}\t6\n")
    report = run(capsys, str(path), "--board", "px4_fmu-v5x")
    assert report["instances"] == []
    (mag,) = report["left_out"]
    assert (mag["reason"], mag["later"]) == ("board", later)


@pytest.mark.issue40
def test_a_later_board_start_with_the_rotation_it_ran_with_names_no_rotation_change(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pixhawk 6X on v1.13.0 with an RM3100 on internal I2C bus 4 (0x20): boards/px4/fmu-v6x/
    init/rc.board_sensors at v1.13.0 starts no RM3100, so it is an instance (rotation 0: no
    -R); from v1.14.0 line 103 starts it, `rm3100 -I -b 4 start`, also without -R: the note
    names the start and no rotation change."""
    rm3100 = devid.encode("i2c", 4, 0x20, 0x07)
    path = tmp_path / "v6x.params"
    path.write_text(f"# Stack: PX4\n# Version: 1.13.0\n#\n1\t1\tCAL_MAG0_ID\t{rm3100}\t6\n")
    said = (
        "the board's script starts it from PX4 v1.14.0: 'rm3100 -I -b 4 start' "
        "(PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors:103 at v1.14.0 (tag "
        "v1.14.0, b8c541dd72, 2023-10-18))"
    )
    today = run(capsys, str(path), "--board", "px4_fmu-v6x")
    (inst,) = today["instances"]
    assert (inst["name"], inst["values"]["rotation"]) == ("RM3100#0", 0)
    assert inst["notes"] == [
        f"{said}: for that firmware --target-release v1.14.0 (or later) leaves it out"
    ]
    upgraded = run(capsys, str(path), "--board", "px4_fmu-v6x", "--target-release", "v1.14.0")
    assert upgraded["instances"] == []
    (mag,) = upgraded["left_out"]
    assert mag["line"].endswith(f": {said}; on PX4 v1.14.0 it is the board's, not the manifest's")


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("edit", "bus", "address", "devtype"),
    [
        # LIS3MDL (drv_sensor.h 0x05) on internal bus 3: rc.sensors' `lis3mdl -X -q start`
        # tries the external buses (1, 2, 4) only
        ({"driver": "lis3mdl"}, 3, 0x1E, 0x05),
        # IST8310 (0x06) at 0x0C on external bus 2 (v1.11.0's `-X -b 2`: the second external
        # bus in src/i2c.cpp's order 4, 2, 1): `ist8310 -X -q start` tries its default 0x0E only
        ({"args": "-X -b 2 -a 0xc start", "bus": 2, "address": 0x0C, "internal": False},
         2, 0x0C, 0x06),
    ],
)  # fmt: skip
def test_a_dropped_start_no_probe_can_reach_is_said_to_start_nowhere(
    edit: dict[str, Any], bus: int, address: int, devtype: int, tmp_path: Path
) -> None:
    """A Pixhawk 5 whose v1.11.0 script (edited here: the file's board row) starts a compass
    that no later fmu-v5 script starts: from v1.12.0 only rc.sensors' probe could, and PX4's
    probe (`-X`, no `-a`) tries only the external buses at the driver's default address
    (platforms/common/i2c.cpp's I2CBusIterator; at v1.12.0 ist8310_main.cpp:75 sets
    I2C_ADDRESS_DEFAULT, 0x0E), so with SENS_EXT_I2C_PRB = 1 still nothing starts it."""
    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    assert v5 is not None
    (real,) = [d for d in v5.devices if d.bus_kind == "I2C"]  # line 19: `ist8310 -I start`
    row = dataclasses.replace(real, source="the edited rc.board_sensors:19", **edit)
    edited = dataclasses.replace(v5, devices=(row,))
    assert edited.buses_of(row) == (bus,)
    compass = devid.encode("i2c", bus, address, devtype)
    path = tmp_path / "v5.params"
    path.write_text(
        "# Stack: PX4\n# Version: 1.11.3\n#\n"
        f"1\t1\tCAL_MAG0_ID\t{compass}\t6\n1\t1\tSENS_EXT_I2C_PRB\t1\t6\n"
    )
    proposal = migrate.migrate(migrate.read_config(path), board=edited)
    assert proposal.instances == []
    (mag,) = proposal.left_out
    assert mag.later == (
        f"the board's script of PX4 v1.11.0 starts it with '{row.driver} {row.args}' (the "
        "edited rc.board_sensors:19); PX4 v1.12.0 .. main: no start (not in PX4/PX4-Autopilot "
        "boards/px4/fmu-v5/init/rc.board_sensors, nor behind a switch this file sets): on PX4 "
        "v1.12.0 and later the board's script does not start it, the manifest must: "
        "--target-release v1.12.0 (or later) proposes it as an instance"
    )


class _EditedLater:
    """The bundled board table with each board row after v1.11.0 given ``row`` too."""

    def __init__(self, row: Any) -> None:
        self.table = load_boards()
        self.row = row

    def __getattr__(self, name: str) -> Any:
        return getattr(self.table, name)

    def by_name(self, name: str, release: str | None = None) -> Any:
        board = self.table.by_name(name, release)
        if board is None or release == "v1.11.0":
            return board
        return dataclasses.replace(board, devices=(*board.devices, self.row))


@pytest.mark.issue40
def test_a_later_start_without_r_of_a_device_probed_with_r_says_it_runs_with_0(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Pixhawk 5 on v1.11.3 with a Here2's AK09916 on I2C bus 1: at v1.11.0 rc.sensors' probe
    `ak09916 -X -R 6 start` (line 102) starts it with -R 6. Read here with every later fmu-v5
    script starting `ak09916 -X -b 1 start`, without -R: from v1.12.0 the driver runs with
    PX4's rotation 0 (no -R: ROTATION_NONE), which the note names against the file's 6."""
    from px4params.migrate import build

    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    assert v5 is not None
    (ist,) = [d for d in v5.devices if d.bus_kind == "I2C"]
    row = dataclasses.replace(
        ist,
        driver="ak09916",
        args="-X -b 1 start",
        bus=1,
        rotation=None,
        internal=False,
        source="the edited rc.board_sensors:26",
    )
    monkeypatch.setattr(build, "_board_table", lambda: _EditedLater(row))
    here2 = devid.encode("i2c", 1, 0x0C, 0x09)
    config = migrate.OldConfig(
        "t", "QGC .params", {"CAL_MAG0_ID": here2, "SENS_EXT_I2C_PRB": 1}, version=(1, 11, 3)
    )
    (inst,) = migrate.migrate(config, board=v5).instances
    assert (inst.name, inst.values["rotation"]) == ("AK09916#0", 6)
    probe = (
        f"'ak09916 -X -R 6 start' (PX4/PX4-Autopilot {RC_SENSORS}:102 at v1.11.0 (tag v1.11.0, "
        "71db0903a9, 2020-09-07))"
    )
    assert inst.notes == [
        "the board's script starts it from PX4 v1.12.0: 'ak09916 -X -b 1 start' (the edited "
        "rc.board_sensors:26), with -R 0 where PX4 v1.11.0 ran it with 6 (rc.sensors probes it "
        f"with {probe}; check its calibration after the update): for that firmware "
        "--target-release v1.12.0 (or later) leaves it out",
        f"rotation 6: rc.sensors probes it with {probe}",
    ]


@pytest.mark.issue40
def test_a_console_start_the_target_drops_is_said_started_by_the_files_board_script() -> None:
    """The sample log without its CAL_MAG1 slot: the Here2's AK09916 is only its boot console
    line 25, which v1.11.0's line 17 started (-R 6). For v1.12.0, where no board line starts
    it, the instance says where it came from (the file's board script, not "outside" it) and
    that its rotation is that start's."""
    config = migrate.read_config(shared_data.shared_file(shared_data.SAMPLE_LOG))
    config = dataclasses.replace(
        config,
        params={k: v for k, v in config.params.items() if not k.startswith("CAL_MAG1_")},
        published=[p for p in config.published if p[2] != HERE2_MAG],
    )
    proposal = migrate.migrate(config, target_release="v1.12.0")
    (mag,) = [i for i in proposal.instances if i.name == "AK09916#0"]
    assert mag.origin == (
        "boot console line 25: 'ak09916 #0 on I2C bus 1 (external, equal to '-b 2')' (started "
        "by the board's script of PX4 v1.11.0)"
    )
    later, rotation = mag.notes
    assert later.startswith(f"the board's script of PX4 v1.11.0 starts it with {OLD_LINE}")
    assert (mag.values["rotation"], rotation) == (
        6,
        "rotation 6: the -R of PX4 v1.11.0's start (above)",
    )


@pytest.mark.issue40
@pytest.mark.parametrize("target", [None, "v1.12.0"])
def test_a_probed_console_start_a_later_board_script_starts_is_left_out_for_that_target(
    target: str | None,
) -> None:
    """The Pixhawk 5 case above as a v1.11.3 log with no calibration slot, only its boot
    console line (PX4 1.11 prints neither address nor rotation; bus 1 is fmu-v5's third
    external bus, src/i2c.cpp's order 4, 2, 1): the same line, on the instance without a
    target and as the reason it is left out for v1.12.0."""
    console = "ist8310 #0 on I2C bus 1 (external, equal to '-b 3')\n"
    config = migrate.OldConfig(
        "t.ulg", "ULog", {"SENS_EXT_I2C_PRB": 1}, version=(1, 11, 3), console=console
    )
    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    proposal = migrate.migrate(config, board=v5, target_release=target)
    # v1.12.0's -R 10 is the 1.11 probe's 0 on the rewritten driver's axes: no rotation change
    said = (
        "the board's script starts it from PX4 v1.12.0: 'ist8310 -X -b 1 -R 10 start' "
        "(PX4/PX4-Autopilot boards/px4/fmu-v5/init/rc.board_sensors:25 at v1.12.0 (tag v1.12.0, "
        "9524e8ec03, 2021-07-05))"
    )
    if target is None:
        (inst,) = proposal.instances
        assert (inst.name, inst.values["rotation"]) == ("IST8310#0", 10)
        assert inst.notes == [
            f"{said}: for that firmware --target-release v1.12.0 (or later) leaves it out",
            "rotation 10 (was 0 on PX4 v1.11.3: rc.sensors starts it without -R): ist8310 "
            "reports other axes from PX4 v1.12.0 (PX4 commit 7569722821): the same orientation "
            "as before",
        ]
        return
    assert proposal.instances == []
    (ist,) = proposal.left_out
    assert (ist.found, ist.reason, ist.line) == (
        "boot console line 1",
        "board",
        f"boot console line 1: ist8310, I2C bus 1: {said}; on PX4 v1.12.0 it is the board's, not "
        "the manifest's",
    )


@pytest.mark.issue40
def test_a_console_start_left_out_for_the_target_leaves_the_next_line_to_be_proposed() -> None:
    """The Pixhawk 5 log above with a second console line, a GPS's LIS3MDL rc.sensors' probe
    started (`lis3mdl -X -q start`, SENS_EXT_I2C_PRB): the IST8310 v1.12.0's board script takes
    over is left out for that target, and the line after it is still read and proposed."""
    console = (
        "ist8310 #0 on I2C bus 1 (external, equal to '-b 3')\n"
        "lis3mdl #0 on I2C bus 1 (external, equal to '-b 3')\n"
    )
    config = migrate.OldConfig(
        "t.ulg", "ULog", {"SENS_EXT_I2C_PRB": 1}, version=(1, 11, 3), console=console
    )
    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    proposal = migrate.migrate(config, board=v5, target_release="v1.12.0")
    assert [(o.found, o.device) for o in proposal.left_out] == [
        ("boot console line 1", "ist8310, I2C bus 1")
    ]
    (lis,) = proposal.instances
    assert lis.name == "LIS3MDL#0" and lis.origin.startswith("boot console line 2: ")


@pytest.mark.issue40
def test_a_dropped_start_a_probe_reaches_with_the_same_rotation_is_said_without_one() -> None:
    """The edited Pixhawk 5 of v1.11.0 above, its line 19 read as `lis3mdl -X -b 2 start`
    (bus 2, external): from v1.12.0 no fmu-v5 script line starts a LIS3MDL, and rc.sensors'
    `lis3mdl -X -q start` (v1.12.0 line 140, SENS_EXT_I2C_PRB) reaches it at its default 0x1E,
    also without -R: the change is whose start it is, with no rotation to name."""
    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    assert v5 is not None
    (real,) = [d for d in v5.devices if d.bus_kind == "I2C"]
    row = dataclasses.replace(
        real,
        source="the edited rc.board_sensors:19",
        driver="lis3mdl",
        args="-X -b 2 start",
        bus=2,
        internal=False,
    )
    lis3mdl = devid.encode("i2c", 2, 0x1E, 0x05)
    config = migrate.OldConfig(
        "t", "QGC .params", {"CAL_MAG0_ID": lis3mdl, "SENS_EXT_I2C_PRB": 1}, version=(1, 11, 3)
    )
    proposal = migrate.migrate(config, board=dataclasses.replace(v5, devices=(row,)))
    assert proposal.instances == []
    (mag,) = proposal.left_out
    assert mag.later == (
        "the board's script of PX4 v1.11.0 starts it with 'lis3mdl -X -b 2 start' (the edited "
        "rc.board_sensors:19); PX4 v1.12.0 .. main: not the board's; only where SENS_EXT_I2C_PRB "
        f"== 1: 'lis3mdl -X -q start' (PX4/PX4-Autopilot {RC_SENSORS}:140 at v1.12.0 (tag "
        "v1.12.0, 9524e8ec03, 2021-07-05)): on PX4 v1.12.0 and later the board's script does "
        "not start it, the manifest must: --target-release v1.12.0 (or later) proposes it as an "
        "instance"
    )


@pytest.mark.issue40
def test_an_installation_without_a_board_table_compares_nothing_and_refuses_a_target(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """px4params.vehicle.boards is optional (build._board_table: None where it cannot be
    imported): a board given as an object is judged at the file's release alone, and a
    --target-release is refused in one line saying why no release can be named."""
    from px4params.errors import MigrationError
    from px4params.migrate import build

    v5 = load_boards().by_name("px4_fmu-v5", "v1.11.0")
    monkeypatch.setattr(build, "_board_table", lambda: None)
    gps = devid.encode("i2c", 1, 0x0E, 0x06)
    config = migrate.OldConfig(
        "t", "QGC .params", {"CAL_MAG1_ID": gps, "SENS_EXT_I2C_PRB": 1}, version=(1, 11, 3)
    )
    proposal = migrate.migrate(config, board=v5)
    assert proposal.compared == [] and proposal.target_release is None
    (inst,) = proposal.instances
    # no later release's line; only today's driver axes (a fact of the package, not the table)
    assert (inst.name, inst.notes) == (
        "IST8310#0",
        [
            "rotation 10 (was 0 on PX4 v1.11.3: rc.sensors starts it without -R): ist8310 "
            "reports other axes from PX4 v1.12.0 (PX4 commit 7569722821): the same orientation "
            "as before"
        ],
    )
    with pytest.raises(MigrationError) as refused:
        migrate.migrate(config, board=v5, target_release="v1.12.0")
    assert str(refused.value) == (
        "--target-release v1.12.0: this installation has no board table to judge it by"
    )


@pytest.mark.parametrize("target", ["v1.12.3", "1.13"])
def test_a_release_between_the_tables_snapshots_runs_the_older_ones_scripts(
    target: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """PX4 v1.12.3 and v1.13 were not read into the board table; their board scripts are
    v1.12.0's and v1.13.0's, as a log of them is read. The proposal is the snapshot's, made for
    the release asked for, and the report says which scripts stood in for it."""
    log = shared_data.shared_file(shared_data.SAMPLE_LOG)
    stood_in = "v1.12.0" if target == "v1.12.3" else "v1.13.0"
    snapshot = run(capsys, str(log), "--target-release", stood_in)
    asked = run(capsys, str(log), "--target-release", target)
    assert asked["instances"] == snapshot["instances"]
    assert asked["left_out"] == snapshot["left_out"]
    assert asked["target_release"] == target
    assert asked["compared_releases"] == RELEASES[: RELEASES.index(stood_in) + 1]
    assert (
        f"--target-release {target}: the board table has no {target}; its scripts are taken as "
        f"at {stood_in}, the newest release it has at or before it"
    ) in asked["assumptions"]
    assert main(["migrate", str(log), "--target-release", target]) == 0
    assert f"\n  proposed for PX4 {target} (--target-release)\n" in capsys.readouterr().err


def test_a_release_newer_than_every_one_read_runs_mains_scripts(
    capsys: pytest.CaptureFixture[str],
) -> None:
    log = shared_data.shared_file(shared_data.SAMPLE_LOG)
    asked = run(capsys, str(log), "--target-release", "v1.19.0")
    assert asked["instances"] == run(capsys, str(log), "--target-release", "main")["instances"]
    assert asked["compared_releases"] == RELEASES
    assert (
        "--target-release v1.19.0: the board table has no v1.19.0; its scripts are taken as at "
        "main, the newest it has (newer than every release it has)"
    ) in asked["assumptions"]


@pytest.mark.parametrize(
    ("version", "said"),
    [
        # the table's snapshots: v1.11.0 .. v1.15.0, v1.18, main (boards.toml)
        ("1.17.0", "taken as at v1.15.0 (at or before it)"),
        ("1.19.0", "taken as at main (newer than every release it has)"),
        ("1.13.3", None),  # v1.13.0's scripts are 1.13.3's
    ],
)
def test_a_files_own_release_the_table_lacks_is_said_as_a_target_would_be(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], version: str, said: str | None
) -> None:
    # (a CubeOrange log of 1.17.0 alpha was judged on v1.15.0's scripts without a word)
    path = cube_params(tmp_path / "cube.params", probe=1)
    path.write_text(path.read_text().replace("# Version: 1.11.2", f"# Version: {version}"))
    lines = [
        a
        for a in run(capsys, str(path), "--board", "cubepilot_cubeorange")["assumptions"]
        if "this file's release" in a
    ]
    expected = (
        f"board cubepilot_cubeorange: the board table has no {version}, this file's release; "
        f"what its script starts is {said}"
    )
    assert lines == ([expected] if said else [])
