"""Board rows' conditions in ``px4params migrate``: every clause of a row's ``when`` decides, as
PX4's startup script tests it; a clause the configuration cannot settle is taken as PX4's
default only where PX4 has one, and is always named with the row's line. With it: the battery
index (``-t``) each power monitor's start line gives.

The expected answers are PX4's scripts as read (PX4-Autopilot boards/px4/fmu-v6x/init/
rc.board_sensors, ROMFS/px4fmu_common/init.d/rc.sensors, src/drivers/power_monitor/ina2xx/
*_main.cpp), transcribed in the board table with their lines. Where a PX4-Autopilot git
directory is at hand (tests/px4_git.py), the table of variables the hardware decides is also
read against every board script it cites, at every snapshot.
"""

from __future__ import annotations

import dataclasses

import pytest
from px4_git import px4_git_dirs, show, snapshot_commits
from px4params import migrate
from px4params.migrate.conditions import (
    HARDWARE_VARIABLES,
    UNSET_BEFORE_RC_SENSORS,
    Facts,
    HardwareVariable,
    Setting,
    Verdict,
    board_variables,
    evaluate,
)
from px4params.migrate.config import OldConfig
from px4params.vehicle.boards import Board, SwitchStart, load_boards
from px4params.vehicle.console import started_drivers

pytestmark = pytest.mark.issue40

#: Why PX4's HAVE_PM2 is not the parameters' to tell (boards/px4/fmu-v6x/init/
#: rc.board_sensors: `set HAVE_PM2 yes` on line 5, then `set HAVE_PM2 no` if `mft query -q -k
#: MFT -s MFT_PM2 -v 0` on line 8, the board's hardware manifest).
PM2_WHY = (
    "PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors:5 at {} sets HAVE_PM2 yes; line "
    "8: no where mft MFT_PM2 == 0 (the board's hardware manifest, which the parameters do not "
    "tell)"
).format("main (branch main, bb59c637cd, 2026-08-13)")
NO_CONSOLE = "a QGC .params has no boot console to say"


def params(values: dict[str, int | float], console: str | None = None) -> OldConfig:
    """A configuration of today's PX4 (1.15), as a QGC file (no console) or a log gives it."""
    kind = "ULog" if console is not None else "QGC .params"
    return OldConfig("t", kind, dict(values), version=(1, 15, 0), console=console)


def v6x(release: str | None = None) -> Board:
    board = load_boards().by_name("px4_fmu-v6x", release)
    assert board is not None
    return board


def rows(board: Board, switch: str) -> list[SwitchStart]:
    return [r for r in board.switches if r.param == switch]


def facts(values: dict[str, int | float], console: str | None = None, **variables: str) -> Facts:
    starts = started_drivers(console) if console is not None else None
    hardware = board_variables("px4_fmu-v6x", ("main",))
    return Facts(values, variables, ("PX4_FMU_V3",), starts, "QGC .params", hardware=hardware,
                 cite=v6x().cite)  # fmt: skip


# -- every clause decides --------------------------------------------------------------------


def test_a_second_power_monitor_behind_have_pm2_is_proposed_as_px4s_default_naming_the_clause(
) -> None:  # fmt: skip
    # Pixhawk 6X (main, read at 01486656): `if param compare SENS_EN_INA226 1` starts
    # `ina226 -X -b 1 -t 1 -k start` (line 24) and, inside `if [ $HAVE_PM2 = yes ]`, `ina226 -X
    # -b 2 -t 2 -k start` (line 28). HAVE_PM2 is the hardware's (yes unless its manifest says
    # no second power module): PX4 runs line 28 on a standard 6X, so it is proposed, and the
    # report names the clause it rests on and the line
    board = v6x()
    bus1, bus2 = rows(board, "SENS_EN_INA226")
    assert bus1.when == "SENS_EN_INA226 == 1"
    assert bus2.when == "SENS_EN_INA226 == 1 and $HAVE_PM2 == yes"
    assert "boards/px4/fmu-v6x/init/rc.board_sensors:28 at " in bus2.source
    proposal = migrate.migrate(params({"SENS_EN_INA226": 1}), table="current", board=board)
    assert [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances] == [
        ("INA226#0", 1), ("INA226#1", 2)
    ]  # fmt: skip
    assert [a for a in proposal.assumptions if a.startswith("SENS_EN_INA226")] == [
        f"SENS_EN_INA226: 'ina226 -X -b 2 -t 2 -k start' ({bus2.source}) runs only where "
        f"$HAVE_PM2 == yes ({PM2_WHY}): taken as holding (PX4's default)"
    ]


def test_the_boot_console_settles_which_power_module_ports_run() -> None:
    # With HAVE_PM2 no, line 28 does not run and the console prints one INA226 (bus 1): the
    # console is what ran, so nothing rests on HAVE_PM2 and bus 2 is not proposed
    console = "ina226 #0 on I2C bus 1 (external) address 0x41\n"
    proposal = migrate.migrate(params({"SENS_EN_INA226": 1}, console), table="current", board=v6x())
    assert [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances] == [("INA226#0", 1)]
    assert not [a for a in proposal.assumptions if "HAVE_PM2" in a], proposal.assumptions


def test_a_fallback_start_nothing_settles_is_not_proposed_and_is_named() -> None:
    # rc.sensors (v1.15.0, line 150/153): `if ! sdp3x start -X` then `sdp3x start -X -a 0x22`:
    # the 0x22 start runs only when the first found nothing, which a .params cannot tell. PX4
    # tries 0x21 first: that is proposed; the fallback is named, not silently dropped or taken
    board = load_boards().by_name("px4_fmu-v6c", "v1.15.0")
    assert board is not None
    fallback = [r for r in rows(board, "SENS_EN_SDP3X") if r.address == 0x22]
    assert fallback and {r.when for r in fallback} == {
        "SENS_EN_SDP3X == 1 and not sdp3x started (start -X)"
    }
    proposal = migrate.migrate(params({"SENS_EN_SDP3X": 1}), table="current", board=board)
    found = [(i.name, i.values["bus.i2c.address"]) for i in proposal.instances]
    assert found == [("SDP3X#0", 0x21)]
    assert (
        f"SENS_EN_SDP3X: 'sdp3x start -X -a 0x22' ({fallback[0].source}) runs only where not "
        f"sdp3x started (start -X) ({NO_CONSOLE}): not proposed from it"
    ) in proposal.assumptions


def test_a_condition_px4params_cannot_read_is_reported_never_taken_as_holding() -> None:
    board = v6x()
    bus1 = rows(board, "SENS_EN_INA226")[0]
    odd = dataclasses.replace(
        bus1, bus=2, args="-X -b 2 -t 2 -k start", source="rc.board_sensors:7",
        when="SENS_EN_INA226 == 1 and the moon is full",
    )  # fmt: skip
    board = dataclasses.replace(board, switches=(bus1, odd))
    proposal = migrate.migrate(params({"SENS_EN_INA226": 1}), table="current", board=board)
    assert [(i.name, i.values["bus.i2c.bus_id"]) for i in proposal.instances] == [("INA226#0", 1)]
    assert proposal.assumptions == [
        "SENS_EN_INA226: 'ina226 -X -b 2 -t 2 -k start' (rc.board_sensors:7) runs only where "
        "the moon is full (a test px4params cannot read): not proposed from it"
    ]


@pytest.mark.parametrize(
    ("when", "values", "console", "holds", "unchecked"),
    [
        # rc.sensors v1.12: the ADIS16448 with -R 4 only when SENS_OR_ADIS164X is 4
        ("SENS_EN_ADIS164X == 1 and SENS_OR_ADIS164X == 4", {"SENS_EN_ADIS164X": 1,
         "SENS_OR_ADIS164X": 4}, None, True, ()),
        ("SENS_EN_ADIS164X == 1 and SENS_OR_ADIS164X == 4", {"SENS_EN_ADIS164X": 1,
         "SENS_OR_ADIS164X": 0}, None, False, ()),
        ("SENS_EN_ADIS164X == 1 and SENS_OR_ADIS164X == 4", {"SENS_EN_ADIS164X": 1}, None, None,
         ("SENS_OR_ADIS164X == 4 (SENS_OR_ADIS164X is not in the QGC .params)",)),
        # a clause settled false decides whatever the others are
        ("SENS_EN_ADIS164X == 1 and hw_type in V30", {"SENS_EN_ADIS164X": 0}, None, False, ()),
        # fmu-v3: $BOARD_FMUV3 is set by the board's script from the hardware
        ("$BOARD_FMUV3 != 0 and $BOARD_FMUV3 == 20", {}, None, None, (
            "$BOARD_FMUV3 != 0 ($BOARD_FMUV3 is set by PX4's startup scripts from what the QGC "
            ".params does not tell)",
            "$BOARD_FMUV3 == 20 ($BOARD_FMUV3 is set by PX4's startup scripts from what the QGC "
            ".params does not tell)")),
        ("hw_type in V30 and not mpu6000 started (-s -b 4 -R 10 start)", {}, None, None, (
            "hw_type in V30 (the hardware revision, which the parameters do not tell)",
            f"not mpu6000 started (-s -b 4 -R 10 start) ({NO_CONSOLE})")),
        # the console settles an earlier start: it ran, so its fallback did not
        ("hw_type in V30 and not mpu6000 started (-s -b 4 -R 10 start)", {},
         "mpu6000 #0 on SPI bus 4 (devid=0x1)\n", False, ()),
        ("hw_type in V30 and not mpu6000 started (-s -b 4 -R 10 start)", {},
         "mpu6000 #0 on SPI bus 1 (devid=0x1)\n", None,
         ("hw_type in V30 (the hardware revision, which the parameters do not tell)",)),
        ("board in PX4_FMU_V2,PX4_FMU_V3", {}, None, True, ()),
        ("not board in PX4_FMU_V3", {}, None, False, ()),
        ("$INA_CONFIGURED == no", {}, None, True, ()),
        ("$HAVE_PM2 == yes", {}, None, True, (f"$HAVE_PM2 == yes ({PM2_WHY})",)),
        ("not $HAVE_PM2 == yes", {}, None, False, (f"not $HAVE_PM2 == yes ({PM2_WHY})",)),
        # -o: one settled true test is enough
        ("$VEHICLE_TYPE == fw -o SENS_EN_X == 1", {"SENS_EN_X": 1}, None, True, ()),
        ("$VEHICLE_TYPE == fw -o SENS_EN_X == 1", {"SENS_EN_X": 0}, None, None, (
            "$VEHICLE_TYPE == fw -o SENS_EN_X == 1 ($VEHICLE_TYPE is set by PX4's startup scripts "
            "from what the QGC .params does not tell)",)),
    ],
)  # fmt: skip
def test_each_kind_of_clause_is_settled_or_named(
    when: str, values: dict, console: str | None, holds: bool | None, unchecked: tuple
) -> None:
    verdict = evaluate(when, facts(values, console, INA_CONFIGURED="no"))
    assert (verdict.holds, verdict.unchecked) == (holds, unchecked)


# -- the i2c_launcher's condition ------------------------------------------------------------


def test_a_power_monitor_switch_at_2_leaves_the_i2c_launcher_scanning() -> None:
    # Pixhawk 6X sets INA_CONFIGURED yes only inside `if param compare SENS_EN_INA226 1`, and
    # runs `i2c_launcher start -b 1` while it is no: SENS_EN_INA226 = 2 starts no INA226 and
    # leaves the launcher scanning; a .params cannot say what it found, so the report says so
    proposal = migrate.migrate(params({"SENS_EN_INA226": 2}), table="current", board=v6x())
    assert proposal.instances == []
    assert [a for a in proposal.assumptions if "i2c_launcher" in a] == [
        "the board's i2c_launcher scans I2C bus 1, 2 for power monitors (INA226, INA228, INA238) "
        f"when no SENS_EN_INA2xx is 1: a QGC .params does not say which it found; bus 2 only "
        f"where $HAVE_PM2 == yes ({PM2_WHY}) (PX4/PX4-Autopilot boards/px4/fmu-v6x/init/"
        "rc.board_sensors:64 at main (branch main, bb59c637cd, 2026-08-13))"
    ]


def test_the_launchers_hardware_clause_of_px4_1_15_is_named_for_each_bus() -> None:
    # v1.15.0's 6X script runs the launcher only in the else of `if ver hwbasecmp 009 010 011`
    # (line 59): `i2c_launcher start -b 1` on line 66, `-b 2` on line 69
    board = v6x("v1.15.0")
    assert board.i2c_launcher_when.startswith("bus 1: not hw_base in 009,010,011 and ")
    proposal = migrate.migrate(params({}), table="current", board=board)
    hw = "not hw_base in 009,010,011 (the hardware revision, which the parameters do not tell)"
    script = "PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors"
    at = "at v1.15.0 (tag v1.15.0, 30e763b678, 2024-08-27)"
    assert [a for a in proposal.assumptions if "i2c_launcher" in a] == [
        "the board's i2c_launcher scans I2C bus 1, 2 for power monitors (INA226, INA228, INA238) "
        f"when no SENS_EN_INA2xx is 1: a QGC .params does not say which it found; bus 1 only "
        f"where {hw} ({script}:66 {at}); bus 2 only where {hw} and $HAVE_PM2 == yes "
        f"({PM2_WHY.replace('at main (branch main, bb59c637cd, 2026-08-13)', at)}) "
        f"({script}:69 {at})"
    ]


# -- the battery index of each start line ----------------------------------------------------


def battery_notes(proposal: migrate.Proposal) -> list[tuple[str, int, str]]:
    return [
        (i.name, i.values["bus.i2c.bus_id"], note)
        for i in proposal.instances
        for note in i.notes
        if "battery index" in note
    ]


def test_each_board_line_gives_its_own_battery_index() -> None:
    # 6X: `ina238 -X -b 1 -t 1 -k start`, `ina238 -X -b 2 -t 2 -k start`
    proposal = migrate.migrate(params({"SENS_EN_INA238": 1}), table="current", board=v6x())
    assert battery_notes(proposal) == [
        ("INA238#0", 1, "today's start line also sets the battery index (-t 1): INA238 has no "
         "field for it"),
        ("INA238#1", 2, "today's start line also sets the battery index (-t 2): INA238 has no "
         "field for it"),
    ]  # fmt: skip


def test_a_driver_line_on_the_console_takes_the_index_of_the_boards_line_on_its_bus() -> None:
    # the driver's own line prints no options: the 6X's line on bus 2 is `-t 2`
    console = "ina238 #0 on I2C bus 2 (external) address 0x45\n"
    proposal = migrate.migrate(params({"SENS_EN_INA238": 1}, console), table="current", board=v6x())
    assert battery_notes(proposal) == [
        ("INA238#0", 2, "today's start line also sets the battery index (-t 2): INA238 has no "
         "field for it"),
    ]  # fmt: skip


def test_the_launchers_line_gives_the_index_it_ran_with() -> None:
    # i2c_launcher (PX4 1.15) runs `<driver> -X -b {bus} -t {bus} start`: on bus 2, -t 2
    console = (
        "INFO  [i2c_launcher] Found address 0x41, running 'ina226 -X -b 2 -t 2 start'\n"
        "ina226 #0 on I2C bus 2 (external) address 0x41\n"
    )
    proposal = migrate.migrate(params({}, console), table="current", board=v6x())
    assert battery_notes(proposal) == [
        ("INA226#0", 2, "today's start line also sets the battery index (-t 2): INA226 has no "
         "field for it"),
    ]  # fmt: skip


def test_a_line_without_t_leaves_the_drivers_own_index() -> None:
    # boards/svehicle/e2 (main, line 17): `ina228 -X start`: no -t, the driver uses 1
    # (ina228_main.cpp: `cli.custom1 = 1`)
    board = load_boards().by_name("svehicle_e2")
    assert board is not None
    assert {r.args for r in rows(board, "SENS_EN_INA228")} == {"-X start"}
    proposal = migrate.migrate(params({"SENS_EN_INA228": 1}), table="current", board=board)
    assert battery_notes(proposal) == [
        ("INA228#0", 1, "today's start line also sets the battery index (no -t: the driver's 1): "
         "INA228 has no field for it"),
    ]  # fmt: skip


def test_a_later_setting_that_runs_clears_what_an_earlier_one_left_open() -> None:
    # A script variable set twice after its first value, as fmu-v3's BOARD_FMUV3 is (line 29
    # where the hardware type decides, line 35 later): where line 29 rests on the hardware
    # type nothing here tells but line 35 settles as run, line 35's value decides and nothing
    # is left to name. No board's own script is of this shape (fmu-v3's later lines test the
    # hardware type too), so the variable is written here in the board table's form
    path = "boards/px4/fmu-v3/init/rc.board_sensors"
    var = HardwareVariable(
        "0", path, 20, (Setting("20", "hw_type in V30", 29), Setting("21", "SYS_HAS_MAG == 1", 35))
    )
    facts = Facts({"SYS_HAS_MAG": 1}, {}, (), None, "QGC .params", hardware={"BOARD_FMUV3": var})
    assert evaluate("$BOARD_FMUV3 == 21", facts) == Verdict(True)
    # Where line 35 does not run, line 29's open value is named with its line
    facts = dataclasses.replace(facts, params={"SYS_HAS_MAG": 0})
    (said,) = evaluate("$BOARD_FMUV3 == 0", facts).unchecked
    assert said.startswith(f"$BOARD_FMUV3 == 0 ({path}:20 sets BOARD_FMUV3 0; line 29: 20 where ")


# -- the hardware variables' table against PX4's scripts -------------------------------------


def _script_test(text: str) -> str:
    """An ``if`` line's test in the board table's condition form (a form not read here is
    kept as written, so that it equals no condition of the table)."""
    words = text.split()
    if words[0] == "!":
        return f"not {_script_test(' '.join(words[1:]))}"
    if words[:2] == ["ver", "hwtypecmp"]:
        return f"hw_type in {','.join(words[2:])}"
    if words[:5] == ["mft", "query", "-q", "-k", "MFT"] and words[5::2] == ["-s", "-v"]:
        return f"mft {words[6]} == {words[8]}"
    if words[-1] == "start":  # a driver's start: it holds where the driver started
        return f"{words[0]} started ({' '.join(words[1:])})"
    return f"<{text}>"


def _script_sets(text: str, name: str) -> list[tuple[int, str, int, str]]:
    """Each ``set NAME value`` of a board script, in its order: (its line, the value, the line
    of the innermost ``if`` it is in (0: none), the conditions of the ``if``s it is in, outer
    first and joined by `` and ``, each negated in its ``else``)."""
    blocks: list[tuple[int, list[str]]] = []  # per open `if`: its line, its branch's clauses
    found = []
    for number, written in enumerate(text.split("\n"), 1):
        words = written.split("#")[0].split()
        if not words:
            continue
        test = " ".join(words[1:]).removesuffix("; then").removesuffix(";then")
        if words[0] == "if":
            blocks.append((number, [_script_test(test)]))
        elif words[0] == "elif":
            line, clauses = blocks.pop()
            blocks.append((line, [*(f"not {c}" for c in clauses), _script_test(test)]))
        elif words[0] == "else":
            line, clauses = blocks.pop()
            blocks.append((line, [f"not {c}" for c in clauses]))
        elif words[0] == "fi" and blocks:  # fmu-v6xrt's at v1.15.0 (line 86) closes none
            blocks.pop()
        elif words[:2] == ["set", name] and len(words) == 3:
            when = " and ".join(c for _, clauses in blocks for c in clauses)
            found.append((number, words[2], blocks[-1][0] if blocks else 0, when))
    assert not blocks, "an `if` without its `fi`"
    return found


def _read(dirs: tuple[str, ...], commit: str, path: str, name: str) -> object:
    """How the script at ``commit`` sets ``name``, in the table's terms: (the line and value of
    its unconditioned ``set``s, then (the innermost ``if``'s line, value, condition) of each
    other): "absent" where the file is not there."""
    text = show(dirs, commit, path)
    if text is None:
        return "absent"
    sets = _script_sets(text, name)
    return (
        [(line, value) for line, value, within, _ in sets if not within],
        [(within, value, when) for _, value, within, when in sets if within],
    )


def _table(var: HardwareVariable) -> object:
    return [(var.line, var.first)], [(s.line, s.value, s.when) for s in var.settings]


def _px4_commits() -> tuple[tuple[str, ...], dict[str, str]]:
    """The PX4-Autopilot git directories and each snapshot's commit; skips where a commit is
    in none of them (CI has no directory)."""
    dirs, commits = tuple(px4_git_dirs()), snapshot_commits()
    if not dirs:
        pytest.skip("no PX4-Autopilot git directory (set $PX4_AUTOPILOT_GIT)")
    for commit in commits.values():
        if show(dirs, commit, "Makefile") is None:
            pytest.skip(f"commit {commit} is in none of {dirs} (set $PX4_AUTOPILOT_GIT)")
    return dirs, commits


def test_each_hardware_variable_is_set_on_the_lines_it_cites_at_exactly_its_releases() -> None:
    # Each board's script at each snapshot, read here: the variable's unconditioned `set` on
    # its line with its first value; each setting's `set` inside the `if` on the setting's line,
    # with the value, under the `if`s it is in (`ver hwtypecmp V30` -> hw_type in V30, `mft
    # query ... -s MFT_PM2 -v 0` -> mft MFT_PM2 == 0, `mpu6000 -s -b 4 -R 10 start` -> mpu6000
    # started (...), its else -> not ...), in the script's order. At a snapshot a row does not
    # list, the script is not so (other lines, another test, or no file): a release list cut
    # short or run on is caught
    dirs, commits = _px4_commits()
    checked = 0
    for board, entries in HARDWARE_VARIABLES.items():
        vendor, model = board.split("_", 1)
        for entry in entries:
            assert set(entry.releases) <= set(commits), (board, entry.releases)
            for name, var in entry.variables.items():
                assert var.path == f"boards/{vendor}/{model}/init/rc.board_sensors", board
                for release, commit in commits.items():
                    read = _read(dirs, commit, var.path, name)
                    if release in entry.releases:
                        assert read == _table(var), (board, name, release)
                        checked += 1
                    else:
                        assert read != _table(var), (board, name, release)
    assert checked == 52  # HAVE_PM2 and HAVE_PM3: 38 (13 boards), BOARD_FMUV3: 14 (2 boards)


def test_every_release_whose_board_script_sets_a_hardware_variable_has_its_row() -> None:
    # A board's rows list each snapshot once, and every snapshot at which the board's script
    # sets one of its variables at all (board_variables answers by the newest release asked)
    dirs, commits = _px4_commits()
    for board, entries in HARDWARE_VARIABLES.items():
        listed = [release for entry in entries for release in entry.releases]
        assert len(listed) == len(set(listed)), board
        for name, var in {n: v for e in entries for n, v in e.variables.items()}.items():
            for release, commit in commits.items():
                read = _read(dirs, commit, var.path, name)
                if read != "absent" and any(read):  # type: ignore[arg-type]
                    assert release in listed, (board, name, release)
                    assert name in board_variables(board, (release,)), (board, name, release)


# -- an earlier start on the console: the script's options as PX4 reads them ----------------

#: Starts as the board table's conditions (and, -S, its rc.sensors row) write them.
MPU9250_X = "mpu9250_i2c started (-X -b 2 -a 0x68 -R 28 start)"  # an ak8963's condition
IST8310_I = "ist8310 started (-I -a 0x0E -R 12 start)"
MS5611_S = "ms5611 started (-T 5607 -s -b 1 start)"  # fmu-v3: `if ! ms5611 -T 5607 -s -b 1 start`
ADIS_EXT_SPI = "adis16448 started (-S start)"  # rc.sensors: `adis16448 -S start`


@pytest.mark.parametrize(
    ("when", "console", "holds"),
    [
        # -X -b 2 -a 0x68: PX4 tries external I2C bus 2 at address 0x68 only
        (MPU9250_X, "mpu9250_i2c #0 on I2C bus 2 (external) address 0x68 rotation 28", True),
        (MPU9250_X, "mpu9250_i2c #0 on I2C bus 1 (external) address 0x68 rotation 28", False),
        (MPU9250_X, "mpu9250_i2c #0 on I2C bus 2 address 0x68 rotation 28", False),  # internal
        (MPU9250_X, "mpu9250_i2c #0 on I2C bus 2 (external) address 0x69 rotation 28", False),
        # a line printing no address: the -a cannot tell it from the start asked for
        (MPU9250_X, "mpu9250_i2c #0 on I2C bus 2 (external)", True),
        # -I -a 0x0E (written with a leading zero, as C reads it: 0xE): internal buses only
        (IST8310_I, "ist8310 #0 on I2C bus 1 address 0xE rotation 12", True),
        (IST8310_I, "ist8310 #0 on I2C bus 1 (external) address 0xE rotation 12", False),
        (IST8310_I, "ist8310 #0 on I2C bus 1 address 0xF rotation 12", False),
        # -s: internal SPI; the same driver on I2C is another start
        (MS5611_S, "ms5611 #0 on SPI bus 1 (devid=0x3d)", True),
        (MS5611_S, "ms5611 #0 on I2C bus 1 address 0x77", False),
        # -S: external SPI, an SPI start all the same
        (ADIS_EXT_SPI, "adis16448 #0 on SPI bus 5 (devid=0x1)", True),
        (ADIS_EXT_SPI, "adis16448 #0 on I2C bus 5 address 0x10", False),
    ],
)  # fmt: skip
def test_a_console_start_is_the_scripts_only_where_its_options_allow(
    when: str, console: str, holds: bool
) -> None:
    assert evaluate(when, facts({}, console + "\n")) == Verdict(holds)


# -- the hardware type a log names ------------------------------------------------------------

#: Pixhawk 6X at v1.14.0 (boards/px4/fmu-v6x/init/rc.board_sensors): `set HAVE_PM2 yes` on line
#: 5, `if ver hwtypecmp V6X005000 V6X005001 V6X005003 V6X005004` on line 7, `set HAVE_PM2 no`.
V6X_1_14 = board_variables("px4_fmu-v6x", ("v1.14.0",))


def hw_facts(hw_type: str | None, kind: str = "ULog") -> Facts:
    return Facts({}, {}, (), None, kind, hw_type, V6X_1_14)


@pytest.mark.parametrize(
    ("hw_type", "holds"),
    [("V6X005001", False), ("V6X005004", False), ("V6X005002", True), ("V6X000000", True)],
)
def test_a_logs_hardware_type_settles_what_the_board_script_sets_from_it(
    hw_type: str, holds: bool
) -> None:
    # ver hwtypecmp compares the board's type with each listed: on a listed one line 9 runs
    # (HAVE_PM2 no), on any other HAVE_PM2 stays yes; nothing is left to name either way
    assert evaluate("$HAVE_PM2 == yes", hw_facts(hw_type)) == Verdict(holds)
    assert evaluate(
        "hw_type in V6X005000,V6X005001,V6X005003,V6X005004", hw_facts(hw_type)
    ) == Verdict(not holds)


def test_without_a_hardware_type_the_scripts_first_value_is_taken_and_the_test_named() -> None:
    (said,) = evaluate("$HAVE_PM2 == yes", hw_facts(None, "QGC .params")).unchecked
    assert said.endswith(
        "rc.board_sensors:5 sets HAVE_PM2 yes; line 7: no where hw_type in V6X005000,V6X005001,"
        "V6X005003,V6X005004 (the hardware revision, which the parameters do not tell))"
    )


# -- fmu-v3's BOARD_FMUV3: each setting left open is named with its line ----------------------

V3 = board_variables("px4_fmu-v3", ("main",))
V3_AT = "boards/px4/fmu-v3/init/rc.board_sensors:20 sets BOARD_FMUV3 0"


def test_a_cube_log_without_a_console_names_both_of_its_imu_tests_with_one_reason() -> None:
    # A Cube (hw_type V30) log without a boot console: lines 50 and 56 (V2M) do not run;
    # line 27 (mpu6000 on SPI 4 -> 20) and line 33 (else mpu9250 on SPI 4 -> 21) rest on what
    # started, which only a console tells: BOARD_FMUV3 is 0 unless one ran
    facts = Facts({}, {}, (), None, "ULog", "V30", V3)
    spi4 = "started (-s -b 4 -R 10 start)"
    assert evaluate("$BOARD_FMUV3 == 21", facts).unchecked == (
        f"$BOARD_FMUV3 == 21 ({V3_AT}; line 27: 20 where mpu6000 {spi4}; line 33: 21 where "
        f"not mpu6000 {spi4} and mpu9250 {spi4}; for each, a ULog has no boot console to say)",
    )


def test_two_settings_left_open_by_one_reason_name_it_once() -> None:
    # mpu6000 on SPI 4 and on SPI 1: line 27 (V30) and line 50 (V2M) each run on their
    # hardware type, which a .params does not tell
    console = "mpu6000 #0 on SPI bus 4 (devid=0x1)\nmpu6000 #1 on SPI bus 1 (devid=0x2)\n"
    facts = Facts({}, {}, (), started_drivers(console), "QGC .params", None, V3)
    assert evaluate("$BOARD_FMUV3 == 20", facts) == Verdict(
        False,
        (("$BOARD_FMUV3 == 20", f"{V3_AT}; line 27: 20 where hw_type in V30; line 50: 20 where "
          "hw_type in V2M; for each, the hardware revision, which the parameters do not tell"),),
    )  # fmt: skip


def test_a_setting_not_run_only_by_px4s_default_is_named() -> None:
    # A variable set under another's test (as ark fmu-v6s sets HAVE_PM3 where it sets
    # HAVE_PM2): where HAVE_PM2 is PX4's default yes, `[ $HAVE_PM2 = no ]` does not run its
    # setting, but only by that default: the setting is named, not dropped
    pm2 = board_variables("px4_fmu-v6x", ("main",))["HAVE_PM2"]
    pm3 = HardwareVariable("yes", pm2.path, 6, (Setting("no", "$HAVE_PM2 == no", 12),))
    facts = Facts({}, {}, (), None, "QGC .params", hardware={"HAVE_PM2": pm2, "HAVE_PM3": pm3})
    verdict = evaluate("$HAVE_PM3 == yes", facts)
    assert verdict.holds is True
    (said,) = verdict.unchecked
    assert f"{pm2.path}:6 sets HAVE_PM3 yes; line 12: no where $HAVE_PM2 == no (" in said


def test_a_clause_false_only_by_px4s_default_is_named() -> None:
    # `[ $HAVE_PM2 = no ]` on a 6X: false where the manifest keeps PX4's yes, which nothing
    # here tells: false, with the reason
    assert evaluate("$HAVE_PM2 == no", facts({})).unchecked == (f"$HAVE_PM2 == no ({PM2_WHY})",)
    assert evaluate("$HAVE_PM2 == no", facts({})).holds is False


def test_each_open_test_of_an_or_is_named() -> None:
    assert evaluate("$VEHICLE_TYPE == fw -o SENS_EN_X == 1", facts({})).unchecked == (
        "$VEHICLE_TYPE == fw -o SENS_EN_X == 1 ($VEHICLE_TYPE is set by PX4's startup scripts "
        "from what the QGC .params does not tell; SENS_EN_X is not in the QGC .params)",
    )


def test_a_board_whose_script_sets_no_hardware_variable_leaves_the_variable_unknown() -> None:
    # Facts without `hardware`: no variable of the board's script is the hardware's
    facts = Facts({}, {}, (), None, "QGC .params")
    assert evaluate("$VEHICLE_TYPE == fw", facts).unchecked == (
        "$VEHICLE_TYPE == fw ($VEHICLE_TYPE is set by PX4's startup scripts from what the QGC "
        ".params does not tell)",
    )


def test_a_variable_the_script_sets_once_keeps_that_value() -> None:
    # radiolink PIX6 (release/1.18 and main): `set HAVE_PM2 yes` on line 6 and no other
    pix6 = board_variables("radiolink_PIX6", ("main",))["HAVE_PM2"]
    once = HardwareVariable("yes", pix6.path, 6)
    assert once == pix6
    facts = Facts({}, {}, (), None, "QGC .params", hardware={"HAVE_PM2": once})
    assert evaluate("$HAVE_PM2 == yes", facts) == Verdict(True)


# -- the shared table cannot be changed -------------------------------------------------------


def test_the_variables_every_migration_is_handed_are_the_tables_own_and_cannot_change() -> None:
    # board_variables hands each caller the module table's own objects (every migration's
    # Facts holds them, and build caches its Facts for all rows): one changed in place would
    # change every later answer
    table = board_variables("px4_fmu-v3", ("main",))
    assert board_variables("px4_fmu-v3", ("v1.15.0",)) is table
    var = table["BOARD_FMUV3"]
    (entry,) = [e for e in HARDWARE_VARIABLES["px4_fmu-v3"] if "main" in e.releases]
    for frozen, field_ in [(var, "first"), (var.settings[0], "value"), (entry, "releases")]:
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(frozen, field_, "x")
    with pytest.raises(dataclasses.FrozenInstanceError):
        facts({}).params = {}  # type: ignore[misc]


# -- rc.sensors runs after fmu-v2/v3's rc.board_sensors has unset BOARD_FMUV3 ---------------------

#: A Cube 2.1's boot console at PX4 1.12: its MPU9250 on SPI bus 4, so fmu-v3's rc.board_sensors
#: (line 35 at v1.12.0: `set BOARD_FMUV3 21`) took it for an FMUv3 2.1.
CUBE_21_CONSOLE = "mpu9250 #0 on SPI bus 4\n"


@pytest.mark.parametrize(
    ("when", "holds"),
    [("$BOARD_FMUV3 == 21", False), ("not $BOARD_FMUV3 == 21", True),
     ("$BOARD_FMUV3 != 0", False)],
)  # fmt: skip
def test_rc_sensors_sees_board_fmuv3_unset_so_each_test_of_it_is_false(
    when: str, holds: bool
) -> None:
    # boards/px4/fmu-v3/init/rc.board_sensors ends with `unset BOARD_FMUV3` (line 110 at v1.12.0)
    # before rcS runs rc.sensors, whose `if [ $BOARD_FMUV3 = 21 ]` (line 159) is then nsh's
    # `[ = 21 ]`: false, and its else branch runs, on a Cube whose script had set 21
    cube = Facts({}, {}, (), started_drivers(CUBE_21_CONSOLE), "ULog", "V30", V3)
    assert evaluate("$BOARD_FMUV3 == 21", cube) == Verdict(True)  # in rc.board_sensors itself
    seen = dataclasses.replace(cube, unset=UNSET_BEFORE_RC_SENSORS)
    assert evaluate(when, seen) == Verdict(holds)


def test_an_rc_sensors_row_is_judged_with_board_fmuv3_unset_a_board_row_with_it_set() -> None:
    # v1.12.0 rc.sensors:161 `ms5525_airspeed start -X -b 2 -q` runs only where $BOARD_FMUV3 =
    # 21, never after fmu-v3's script unset it; fmu-v3's own line 69 (`l3gd20 -s -b 4 -R 4 start`
    # where $BOARD_FMUV3 != 0) still sees the 21 its script set on a Cube 2.1. (No migration
    # shows the rc.sensors row's verdict today: its $VEHICLE_TYPE clause is never known either,
    # so the builder's own judgement is asked.)
    from px4params.dsdl.schema import load_schema
    from px4params.migrate import build
    from px4params.vehicle import devid

    cube = load_boards().by_name("px4_fmu-v3", "v1.12.0")
    assert cube is not None
    (sensors_row,) = [r for r in cube.switches if r.args == "start -X -b 2 -q"]
    (board_row,) = [r for r in cube.devices if r.args == "-s -b 4 -R 4 start"]
    assert "/rc.sensors:" in sensors_row.source and "$BOARD_FMUV3 == 21" in sensors_row.when
    assert "/rc.sensors:" not in board_row.source and board_row.when == "$BOARD_FMUV3 != 0"
    config = OldConfig("t.ulg", "ULog", {"SENS_EXT_I2C_PRB": 1, "CBRK_AIRSPD_CHK": 0},
                       version=(1, 12, 0), console=CUBE_21_CONSOLE, hw_type="V30")  # fmt: skip
    table = devid.load_table("px4-v1.11")
    builder = build._Builder(config, load_schema(include_dronecan=False), table, cube, [])
    assert builder.start_verdict(sensors_row, "") == Verdict(False)
    assert builder.start_verdict(board_row, "") == Verdict(True)


def test_a_boards_variables_cannot_be_changed_by_a_caller() -> None:
    # board_variables hands out the table's own mapping: one migration changing it would
    # change every later one's verdicts.
    v6x = board_variables("px4_fmu-v6x", ("main",))
    with pytest.raises(TypeError):
        v6x["HAVE_PM2"] = v6x["HAVE_PM2"]  # type: ignore[index]
    assert board_variables("px4_fmu-v6x", ("main",)).keys() == {"HAVE_PM2"}
