"""The board's own starts in ``px4params migrate``: a device row of the board table counts as
the board's only where its condition holds, as PX4's script tests it; what nothing settles
never drops a device; the hardware variables (HAVE_PM2, HAVE_PM3) as each board's own script
sets them.

The expected answers are PX4's scripts as read in PX4-Autopilot (a fork's snapshot of main
bb59c637, release/1.18 83c4f4e5, v1.15.0 30e763b6, v1.12.0 9524e8ec; v1.14.0's scripts at the
main commits whose lines the board table has): boards/*/init/rc.board_sensors,
ROMFS/px4fmu_common/init.d/rc.sensors, src/systemcmds/ver/ver.cpp (``ver hwtypecmp`` compares
``px4_board_sub_type()``) and src/modules/logger/logger.cpp (which logs that as
``ver_hw_subtype``). Device IDs are worked by hand: devtype << 16 | address << 8 | bus << 3 |
bus type (1: I2C).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest
import shared_data
from px4params import migrate
from px4params.migrate.conditions import (
    HARDWARE_VARIABLES,
    Facts,
    Verdict,
    board_variables,
    evaluate,
)
from px4params.migrate.config import OldConfig
from px4params.vehicle.boards import Board, SwitchStart, load_boards

IST8310_BUS1 = 0x06 << 16 | 0x0E << 8 | 1 << 3 | 1  # 396809, a GPS puck's compass
HMC5883_BUS2 = 0x01 << 16 | 0x1E << 8 | 2 << 3 | 1  # 73233
BMM150_BUS4 = 0x43 << 16 | 0x10 << 8 | 4 << 3 | 1  # 4395041
AK09916_BUS1 = 0x09 << 16 | 0x0C << 8 | 1 << 3 | 1  # 592905, a Here2's compass


def board(name: str, release: str | None = None) -> Board:
    found = load_boards().by_name(name, release)
    assert found is not None
    return found


def config(
    params: dict[str, int | float],
    version: tuple[int, int, int] = (1, 15, 0),
    hw_type: str | None = None,
) -> OldConfig:
    """A log's parameters (with its ``ver_hw_subtype`` where given), else a QGC file's."""
    kind = "ULog" if hw_type is not None else "QGC .params"
    return OldConfig("t", kind, dict(params), version=version, hw_type=hw_type)


def placed(proposal: migrate.Proposal) -> list[tuple[str, int, int]]:
    return [
        (i.name, i.values["bus.i2c.bus_id"], i.values["bus.i2c.address"])
        for i in proposal.instances
    ]


def left_out(proposal: migrate.Proposal) -> dict[str, tuple[str, str]]:
    return {o.found: (o.reason, o.line) for o in proposal.left_out}


def assert_the_boards(proposal: migrate.Proposal, found: str, cited: str) -> str:
    """``found`` is left out as started by the board's script, its line (returned) citing
    ``cited``."""
    reason, line = left_out(proposal)[found]
    assert reason == "board"
    assert cited in line
    return line


# -- a device row counts where its condition holds -------------------------------------------


#: What a CANHUBK3 proposal says of the bus-1 IST8310's rotation where nothing says the board
#: is an ADAP: line 10 starts it with -R 10 there, rc.sensors' probe (`ist8310 -X -q start`)
#: elsewhere, without -R.
CANHUBK3_ROTATION = (
    "; its rotation 0 (rc.sensors starts it without -R) holds only where that line does not run: "
    "where it runs, it starts the device with -R 10 and the device is the board's, not the "
    "manifest's"
)
CANHUBK3_LINE_10 = (
    "the board's 'ist8310 -X -b 1 -R 10 start' (PX4/PX4-Autopilot boards/nxp/mr-canhubk3/init/"
    "rc.board_sensors:10 at main (branch main, bb59c637cd, 2026-08-13)) runs only where hw_type "
    "in MR-CANHUBK3-ADAP (the hardware revision, which the parameters do not tell)"
)


def test_a_compass_the_board_starts_only_on_one_hardware_type_is_proposed_and_named() -> None:
    # NXP MR-CANHUBK3 (main): `if ver hwtypecmp MR-CANHUBK3-ADAP` starts `ist8310 -X -b 1 -R
    # 10` (line 10), else `ist8310 -X -b 2 -R 10` (line 22). A QGC file does not say the
    # hardware type: an IST8310 on bus 1 may be a GPS puck's, so it is not dropped on a guess,
    # and its rotation 0 is said to hold only where line 10 does not run
    mr = board("nxp_mr-canhubk3")
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": IST8310_BUS1, "CAL_MAG0_ROT": 0}), table="current", board=mr
    )
    assert placed(proposal) == [("IST8310#0", 1, 0x0E)]
    (said,) = [a for a in proposal.assumptions if a.startswith("CAL_MAG0_ID")]
    assert said == (
        f"CAL_MAG0_ID = 396809: IST8310 (MAG), I2C bus 1, address 0x0E: {CANHUBK3_LINE_10}: "
        f"proposed, not left out on a guess{CANHUBK3_ROTATION}"
    )
    (ist,) = proposal.instances
    assert (ist.values["rotation"], ist.notes) == (0, [CANHUBK3_LINE_10 + CANHUBK3_ROTATION])


def test_a_real_gps_compass_on_a_canhubk3_says_its_rotation_rests_on_the_hardware_type(
    tmp_path: Path,
) -> None:
    # MakeTech's Pathfinder file (PX4 1.14.0, a real vehicle): its GPS's IST8310 on I2C bus 1 at
    # 0x0E (CAL_MAG1_ID 396809, PRIO 75). Named as a CANHUBK3, whose line 10 starts exactly that
    # device with -R 10 on an ADAP only, the instance's rotation 0 is named as resting on it
    from test_migrate_corpus import CORPUS, locate

    (truth,) = [t for t in CORPUS if t.name.startswith("20260515 Pathfinder")]
    config = migrate.read_config(locate(truth, tmp_path))
    proposal = migrate.migrate(config, board=board("nxp_mr-canhubk3", "v1.14.0"))
    (ist,) = [i for i in proposal.instances if i.name.startswith("IST8310")]
    assert ist.values["rotation"] == 0
    (note,) = [n for n in ist.notes if "mr-canhubk3" in n]
    assert "rc.board_sensors:10 at main " in note
    assert note.endswith(CANHUBK3_ROTATION)


#: The NXP MR-Tropic log of PX4 1.15.0 (frrs_ekf_failure.ulg): its GPS's IST8310 on I2C bus
#: 1 at 0x0E (CAL_MAG0_ID 396809, sensor_mag 0), started with -R 10 (console line 36).
FRRS_IST8310 = "ist8310 #0 on I2C bus 1 (external) address 0xE rotation 10"


def frrs_on_canhubk3(console_rotation: bool = True, slots: bool = True) -> migrate.Proposal:
    """The MR-Tropic log named as a CANHUBK3 of v1.15.0; without ``console_rotation`` its
    line 36 as PX4 1.13 on prints a start without -R (i2c_spi_buses.cpp prints a rotation
    only when not 0: battery_brownout.ulg's `ist8310 #0 on I2C bus 4 (external) address
    0xC`); without ``slots`` the IST8310 is only in the boot console."""
    import dataclasses

    config = migrate.read_config(shared_data.shared_file("frrs_ekf_failure.ulg"))
    assert config.console is not None and FRRS_IST8310 in config.console.splitlines()
    if not console_rotation:
        line = FRRS_IST8310.removesuffix(" rotation 10")
        config = dataclasses.replace(config, console=config.console.replace(FRRS_IST8310, line))
    if not slots:
        params = {k: v for k, v in config.params.items() if not k.startswith("CAL_MAG0_")}
        published = [p for p in config.published if p[2] != IST8310_BUS1]
        config = dataclasses.replace(config, params=params, published=published)
    return migrate.migrate(config, board=board("nxp_mr-canhubk3", "v1.15.0"))


#: What the bus-1 IST8310's instance says where the boot console shows it runs without -R.
CANHUBK3_CONSOLE = (
    "; boot console line 36 shows it runs without -R, not with that line's -R 10: that line did "
    "not start it"
)


def test_a_console_start_with_line_10s_rotation_is_the_boards_without_a_note() -> None:
    # The real console: the IST8310 runs with -R 10, which rc.sensors' probe never passes: the
    # board's (line 10 on an ADAP), left out, and nothing names line 10's condition
    proposal = frrs_on_canhubk3()
    assert left_out(proposal)["CAL_MAG0_ID = 396809"][0] == "board"
    assert not [i for i in proposal.instances if i.name.startswith("IST8310")]
    said = [n for i in proposal.instances for n in i.notes] + proposal.assumptions
    assert not [n for n in said if "rc.board_sensors:10 " in n]


@pytest.mark.parametrize("console_rotation", [True, False])
def test_a_row_giving_the_rotation_the_device_runs_with_adds_no_rotation_note(
    console_rotation: bool,
) -> None:
    # No bundled row gives an unsettled device the rotation it is proposed with (a scan of the
    # table: only fmu-v6x's internal `bmm150 -I -R 0`, whose bus 4 settles it as the board's),
    # so line 10 is read here as `ist8310 -X -b 1 -R 0 start` and the MR-Tropic console's
    # IST8310 as started without -R: the row's -R is the rotation proposed, which neither
    # rests on the row nor tells whether the row started it; the instance gets no rotation note
    import dataclasses

    mr = board("nxp_mr-canhubk3", "v1.15.0")
    zero = tuple(
        dataclasses.replace(r, rotation=0, args="-X -b 1 -R 0 start") if r.rotation == 10 else r
        for r in mr.devices
    )
    config = migrate.read_config(shared_data.shared_file("frrs_ekf_failure.ulg"))
    assert config.console is not None
    if not console_rotation:  # the log without its console: nothing shows the rotation
        config = dataclasses.replace(config, console=None)
    line = FRRS_IST8310.removesuffix(" rotation 10")
    config = dataclasses.replace(config, console=config.console and config.console.replace(
        FRRS_IST8310, line))  # fmt: skip
    proposal = migrate.migrate(config, board=dataclasses.replace(mr, devices=zero))
    (ist,) = [i for i in proposal.instances if i.name.startswith("IST8310")]
    assert (ist.values["rotation"], ist.notes) == (0, [])
    (said,) = [a for a in proposal.assumptions if a.startswith("CAL_MAG0_ID")]
    assert said.endswith(": proposed, not left out on a guess")


@pytest.mark.parametrize("slots", [True, False])
def test_a_console_start_without_rotation_settles_that_line_10_did_not_start_it(
    slots: bool,
) -> None:
    # PX4 1.15 prints every -R but 0: an IST8310 on bus 1 started without -R was not started
    # by line 10 (-R 10), whatever the hardware type. Its note says so, from the console, not
    # that rotation 0 holds only where line 10 does not run (nor why rc.sensors would). With
    # the CAL_MAG0 slot the device is proposed from it; without, from its console line
    proposal = frrs_on_canhubk3(console_rotation=False, slots=slots)
    (ist,) = [i for i in proposal.instances if i.name.startswith("IST8310")]
    assert (ist.values["rotation"], ist.notes) == (0, [CANHUBK3_LINE_10 + CANHUBK3_CONSOLE])
    found = "CAL_MAG0_ID = 396809: IST8310 (MAG)" if slots else "boot console line 36: ist8310"
    (said,) = [a for a in proposal.assumptions if a.startswith(found)]
    assert said.endswith(f"{CANHUBK3_LINE_10}: proposed, not left out on a guess{CANHUBK3_CONSOLE}")


@pytest.mark.parametrize(
    ("hw_type", "boards"), [("MR-CANHUBK3-ADAP", True), ("MR-CANHUBK3", False)]
)
def test_a_logs_hardware_type_settles_which_compass_the_board_starts(
    hw_type: str, boards: bool
) -> None:
    # A log's ver_hw_subtype is what `ver hwtypecmp` compares: on the ADAP the bus-1 IST8310
    # is line 10's; on any other type line 10 does not run, and nothing is left to name
    mr = board("nxp_mr-canhubk3")
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": IST8310_BUS1}, hw_type=hw_type), table="current", board=mr
    )
    assert not [a for a in proposal.assumptions if a.startswith("CAL_MAG0_ID")]
    if boards:
        assert placed(proposal) == []
        assert_the_boards(
            proposal, "CAL_MAG0_ID = 396809", "boards/nxp/mr-canhubk3/init/rc.board_sensors:10 "
        )
    else:
        assert placed(proposal) == [("IST8310#0", 1, 0x0E)]


def test_a_compass_found_on_the_internal_bus_is_the_boards_whatever_its_revision() -> None:
    # Pixhawk 6X (main): `bmm150 -I -R 0 start` only `if ! ver hwtypecmp V6X001` (line 133);
    # bus 4 is its internal bus (src/i2c.cpp), which rc.sensors never probes (-X only): a
    # BMM150 found there was started by line 133, so it is not proposed
    v6x = board("px4_fmu-v6x")
    assert v6x.internal_i2c_buses == (4,)
    proposal = migrate.migrate(config({"CAL_MAG0_ID": BMM150_BUS4}), table="current", board=v6x)
    assert placed(proposal) == []
    line = assert_the_boards(
        proposal, "CAL_MAG0_ID = 4395041", "boards/px4/fmu-v6x/init/rc.board_sensors:133 "
    )
    assert line.endswith(
        "it runs only where not hw_type in V6X001 (the hardware revision, which the parameters "
        "do not tell), and being found on internal I2C bus 4 (boards/px4/fmu-v6x/src/i2c.cpp) "
        "shows it did"
    )


def test_the_pixhawk_2_and_pixhawk_4_scripts_hardware_tests_start_only_spi_sensors() -> None:
    # fmu-v2/v3 (`ver hwtypecmp V30`, `V2M`, then `$BOARD_FMUV3` from which start succeeded)
    # and fmu-v5 (`ver hwtypecmp V5005002 V5006002`) choose only SPI sensors; their I2C
    # starts (hmc5883 -T -I -R 4 on line 12 of fmu-v3, ist8310 -I / -X -b 1 on fmu-v5) are
    # unconditional. Every I2C decision on these boards is the same on every revision.
    for name in ("px4_fmu-v2", "px4_fmu-v3", "px4_fmu-v5"):
        for row in (r for b in load_boards().variants(name) for r in b.devices):
            if "hw_type" in row.when or "BOARD_FMUV3" in row.when:
                assert row.bus_kind == "SPI", (name, row)
            if row.bus_kind == "I2C":
                assert row.when == "", (name, row)


@pytest.mark.parametrize("hw_type", ["V30", "V2M", None])
def test_fmu_v3s_internal_compass_line_runs_only_where_bus_2_is_internal(
    hw_type: str | None,
) -> None:
    # PX4 v1.12.0, boards/px4/fmu-v3/src/i2c.cpp lines 50-63: where `HW_VER_FMUV3 ==
    # board_get_hw_version()` (line 52) every I2C bus is external, else every bus but 2; that
    # version is the one init.c names "V30" (lines 374-376: hw_type[1]++, hw_type[2] = '0'),
    # the log's ver_hw_subtype. platforms/common/i2c.cpp's I2CBusIterator::next (lines 63-70)
    # tries an -I start only on a bus that is not external. So line 12's `hmc5883 -T -I -R 4
    # start` starts the HMC5883 on bus 2 of a Pixhawk Mini (V2M) and finds no bus on a Cube
    # (V30), whose bus 2 rc.sensors' `hmc5883 -T -X -q start` (line 136, SENS_EXT_I2C_PRB)
    # probes: there it is proposed, as with no type known, where the report names both lines.
    # The GPS's IST8310 on bus 1 is probed on each: proposed.
    v3 = board("px4_fmu-v3", "v1.12.0")
    proposal = migrate.migrate(
        config(
            {"CAL_MAG0_ID": IST8310_BUS1, "CAL_MAG1_ID": HMC5883_BUS2, "SENS_EXT_I2C_PRB": 1},
            version=(1, 12, 3),
            hw_type=hw_type,
        ),
        table="current",
        board=v3,
    )
    script = "boards/px4/fmu-v3/init/rc.board_sensors:12 "
    i2c = "boards/px4/fmu-v3/src/i2c.cpp:52 "
    if hw_type == "V2M":
        assert placed(proposal) == [("IST8310#0", 1, 0x0E)]
        reason, line = left_out(proposal)["CAL_MAG1_ID = 73233"]
        assert reason == "board" and script in line
        assert not [a for a in proposal.assumptions if "runs only where" in a]
        return
    assert sorted(placed(proposal)) == [("HMC5883#0", 2, 0x1E), ("IST8310#0", 1, 0x0E)]
    assert left_out(proposal) == {}
    (hmc,) = [i for i in proposal.instances if i.name == "HMC5883#0"]
    if hw_type == "V30":
        assert not unasked(proposal)
        (note,) = hmc.notes
        assert note.startswith("I2C bus 2 is external where hw_type in V30 (PX4/PX4-Autopilot ")
        assert i2c in note
        return
    assert not [n for n in hmc.notes if n.startswith("I2C bus 2 is external")]
    (said,) = [a for a in proposal.assumptions if "runs only where" in a]
    assert said.startswith("CAL_MAG1_ID = 73233: HMC5883 (MAG), I2C bus 2, address 0x1E: ")
    assert script in said and i2c in said
    assert (
        "runs only where not hw_type in V30 (the hardware revision, which the parameters " in said
    )
    assert "; the bus is internal only there: PX4/PX4-Autopilot " in said
    assert "proposed, not left out on a guess" in said


@pytest.mark.parametrize(
    ("when", "hw_type", "holds", "unchecked"),
    [
        ("hw_type in V30", "V30", True, ()),
        ("hw_type in V30", "V2M", False, ()),
        ("not hw_type in V2M", "V30", True, ()),
        ("hw_type in V30", None, None,
         ("hw_type in V30 (the hardware revision, which the parameters do not tell)",)),
        # `ver hwbasecmp` compares the base, which no log names
        ("hw_base in 008", "V5X00a000", None,
         ("hw_base in 008 (the hardware revision, which the parameters do not tell)",)),
    ],
)  # fmt: skip
def test_the_hardware_type_is_settled_by_a_logs_ver_hw_subtype(
    when: str, hw_type: str | None, holds: bool | None, unchecked: tuple[str, ...]
) -> None:
    facts = Facts({}, {}, (), None, "ULog", hw_type=hw_type)
    verdict = evaluate(when, facts)
    assert (verdict.holds, verdict.unchecked) == (holds, unchecked)


def unasked(proposal: migrate.Proposal) -> list[str]:
    """The report's assumptions but the line that says a log of PX4 1.11 is decoded with the
    current devtype table as the test asked (``table="current"``: the codes these tests use)."""
    return [a for a in proposal.assumptions if not a.startswith("--table current: ")]


# -- rc.sensors' probe rotation counts where the probe runs ----------------------------------


@pytest.mark.parametrize(
    ("params", "rotation", "named"),
    [
        ({"SENS_EXT_I2C_PRB": 1}, 6, False),
        ({"SENS_EXT_I2C_PRB": 0}, 0, False),  # line 102 does not run: no -R of it
        ({}, 6, True),  # nothing says: the probe is what starts it, and that is said
    ],
)
def test_the_probes_rotation_counts_only_where_probing_runs(
    params: dict[str, int], rotation: int, named: bool
) -> None:
    # PX4 1.11's rc.sensors: `if param compare -s SENS_EXT_I2C_PRB 1` ... `ak09916 -X -R 6
    # start` (line 102, a Here2's compass, rotated 270 degrees yaw)
    v5 = board("px4_fmu-v5", "v1.11.0")
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": AK09916_BUS1, **params}, version=(1, 11, 3)),
        table="current",
        board=v5,
    )
    (ak,) = proposal.instances
    assert (ak.name, ak.values["rotation"]) == ("AK09916#0", rotation)
    said = [a for a in proposal.assumptions if a.startswith("'ak09916 -X -R 6 start'")]
    assert bool(said) == named
    if named:
        assert said[0].endswith(
            "runs only where SENS_EXT_I2C_PRB == 1 (SENS_EXT_I2C_PRB is not in the QGC .params): "
            "its -R 6 taken"
        )
    # Probing off: nothing says the sensor was started, and its instance says so.
    off = [n for n in ak.notes if n.startswith("SENS_EXT_I2C_PRB = 0")]
    assert off == (
        [
            "SENS_EXT_I2C_PRB = 0: PX4 probed for no external I2C sensor, so nothing in the file "
            "says this one was started (its calibration may be of an earlier setup); the manifest "
            "starts it and arming requires it: drop its line if it is gone"
        ]
        if params.get("SENS_EXT_I2C_PRB") == 0
        else []
    )


# -- HAVE_PM2 and HAVE_PM3 as each board's script sets them ----------------------------------


def test_every_board_row_testing_a_hardware_variable_has_the_boards_own_setting() -> None:
    # Every board whose own rows test $HAVE_PM2, $HAVE_PM3 or $BOARD_FMUV3, in every release,
    # has the way its own script sets them: 15 boards, read one by one (rc.sensors' rows are
    # every board's and run after the board's script: not its own)
    tested = set()
    table = load_boards()
    for b in (v for name in {b.name for b in table.all()} for v in table.variants(name)):
        own = [r for r in (*b.switches, *b.devices) if "rc.sensors" not in r.source]
        conditions = [r.when for r in own] + [b.i2c_launcher_when]
        for name in ("HAVE_PM2", "HAVE_PM3", "BOARD_FMUV3"):
            if any(f"${name} " in c for c in conditions):
                assert name in board_variables(b.name, b.releases), (b.name, b.releases, name)
                tested.add(b.name)
    assert tested == set(HARDWARE_VARIABLES)
    assert len(tested) == 15


def test_radiolink_pix6_always_has_its_second_power_module_port() -> None:
    # boards/radiolink/PIX6/init/rc.board_sensors (v1.18, main): `set HAVE_PM2 yes` on line 6
    # and nothing sets it no: `ina226 -X -b 2 -t 2 -k start` runs whenever SENS_EN_INA226 is
    # 1, nothing to name
    pix6 = board("radiolink_PIX6")
    proposal = migrate.migrate(config({"SENS_EN_INA226": 1}), table="current", board=pix6)
    assert placed(proposal) == [("INA226#0", 2, 0x41)]
    assert not [a for a in proposal.assumptions if "HAVE_PM2" in a], proposal.assumptions


@pytest.mark.parametrize(
    ("hw_type", "buses"),
    [("V6X005000", [1]), ("V6X000000", [1, 2]), (None, [1, 2])],
)
def test_pixhawk_6x_of_px4_1_14_has_no_second_port_on_its_mini_base(
    hw_type: str | None, buses: list[int]
) -> None:
    # PX4 1.14's fmu-v6x script: `set HAVE_PM2 yes` (line 5), `no` if `ver hwtypecmp V6X005000
    # V6X005001 V6X005003 V6X005004` (line 7, the Holybro mini base board). A log's hardware
    # type settles it; without one it is yes, and the report names line 7's test
    v6x = board("px4_fmu-v6x", "v1.14.0")
    proposal = migrate.migrate(
        config({"SENS_EN_INA226": 1}, version=(1, 14, 0), hw_type=hw_type),
        table="current",
        board=v6x,
    )
    assert [bus for _, bus, _ in placed(proposal)] == buses
    said = [a for a in proposal.assumptions if "HAVE_PM2" in a]
    if hw_type is not None:
        assert said == []
    else:
        (line,) = said
        assert (
            "$HAVE_PM2 == yes (PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors:5 at "
            "v1.14.0 (tag v1.14.0, b8c541dd72, 2023-10-18) sets HAVE_PM2 yes; "
            "line 7: no where hw_type in V6X005000,V6X005001,V6X005003,V6X005004 (the hardware "
            "revision, which the parameters do not tell)): taken as holding (PX4's default)"
        ) in line


@pytest.mark.parametrize(
    ("name", "hw_type"), [("motor_failure.ulg", "V30"), ("battery_brownout.ulg", "V6C000001")]
)
def test_a_real_logs_hardware_type_is_read(name: str, hw_type: str, tmp_path: Path) -> None:
    # ver_hw_subtype as pyulog prints it: a Pixhawk 2 Cube's log (PX4_FMU_V3) and a Pixhawk
    # 6C's (PX4_FMU_V6C)
    from test_migrate_corpus import CORPUS, locate

    (truth,) = [t for t in CORPUS if t.name == name]
    assert migrate.read_config(locate(truth, tmp_path)).hw_type == hw_type


@pytest.mark.parametrize(
    ("console", "proposed"),
    [
        # line 28's IST8310 answered: line 31 did not run, the RM3100 was probed
        ("ist8310 #0 on I2C bus 4 (external) address 0x0C\n"
         "rm3100 #0 on I2C bus 4 (external) address 0x20\n", True),
        # no IST8310 on bus 4: the 6C variant's RM3100 is line 31's
        ("rm3100 #0 on I2C bus 4 (external) address 0x20\n", False),
    ],
)  # fmt: skip
def test_the_boot_console_settles_the_6c_variants_fallback_compass(
    console: str, proposed: bool
) -> None:
    # Pixhawk 6C (main): `if ! ist8310 -X -b 4 -a 0xc -q start` then `rm3100 -X -b 4 -R 8
    # start` (lines 28 and 31); bus 4 is marked external (src/i2c.cpp), so rc.sensors' probe
    # also reaches it
    v6c = board("px4_fmu-v6c")
    proposal = migrate.migrate(
        OldConfig("t", "ULog", {}, version=(1, 16, 0), console=console),
        table="current",
        board=v6c,
    )
    if proposed:
        assert placed(proposal) == [("RM3100#0", 4, 0x20)]
    else:
        assert placed(proposal) == []
        (line,) = [o.line for o in proposal.left_out if o.device.startswith("rm3100")]
        assert "boards/px4/fmu-v6c/init/rc.board_sensors:31 " in line


def test_a_disabled_compass_beside_an_unsettled_row_is_not_said_to_be_proposed(
    tmp_path: Path,
) -> None:
    # The Amovlab F410's file keeps a stale IST8310 (bus 1, 0x0E) in CAL_MAG2 with
    # CAL_MAG2_PRIO 0: it is left out as disabled, and on a CANHUBK3 the line naming line 10's
    # condition says so instead of "proposed"
    from test_migrate_corpus import CORPUS, locate

    (truth,) = [t for t in CORPUS if t.name == "px4docs_amovlabf410_v1.15.4.params"]
    config = migrate.read_config(locate(truth, tmp_path))
    proposal = migrate.migrate(config, board=board("nxp_mr-canhubk3"))
    assert left_out(proposal)["CAL_MAG2_ID = 396809"][0] == "disabled"
    (said,) = [a for a in proposal.assumptions if a.startswith("CAL_MAG2_ID")]
    assert said == (
        f"CAL_MAG2_ID = 396809: IST8310 (MAG), I2C bus 1, address 0x0E: {CANHUBK3_LINE_10}: "
        "left out as disabled, not as the board's on a guess"
    )


# -- i2c_launcher's conditions cite their lines ----------------------------------------------


@pytest.mark.parametrize(
    ("release", "said"),
    [
        # main: `i2c_launcher start -b 1` (line 61) under `if [ $INA_CONFIGURED = no ]` only;
        # `-b 2` (line 64) also under `if [ $HAVE_PM2 = yes ]`
        (None, ["bus 2 only where $HAVE_PM2 == yes (", "rc.board_sensors:64 at main "]),
        # v1.15.0: both in the else of `if ver hwbasecmp 009 010 011` (line 59): 66 and 69
        ("v1.15.0", [
            "bus 1 only where not hw_base in 009,010,011 (the hardware revision, which the "
            "parameters do not tell) (PX4/PX4-Autopilot boards/px4/fmu-v6x/init/"
            "rc.board_sensors:66 at v1.15.0 ",
            "rc.board_sensors:69 at v1.15.0 ",
        ]),
    ],
)  # fmt: skip
def test_the_launchers_unsettled_buses_name_their_start_lines(
    release: str | None, said: list[str], tmp_path: Path
) -> None:
    # The Amovlab F410's QGC file (PX4 1.15.4, no SENS_EN_INA2xx) on a Pixhawk 6X: which
    # launcher buses run rests on what the file cannot tell; each is named with the line of
    # its `i2c_launcher start -b N`, as every other start of the board's script is
    from test_migrate_corpus import CORPUS, locate

    (truth,) = [t for t in CORPUS if t.name == "px4docs_amovlabf410_v1.15.4.params"]
    config = migrate.read_config(locate(truth, tmp_path))
    proposal = migrate.migrate(config, board=board("px4_fmu-v6x", release))
    (line,) = [a for a in proposal.assumptions if "i2c_launcher scans" in a]
    for part in said:
        assert part in line
    assert "rc.board_sensors)" not in line  # the script without a line


def test_a_launcher_bus_without_its_line_is_refused_not_left_uncited(tmp_path: Path) -> None:
    # The board table gives each launcher bus its `i2c_launcher start -b N` line (parse_boards
    # refuses a row without); a board whose lines fell out of step is an error, not a bus
    # named without its line
    import dataclasses

    from test_migrate_corpus import CORPUS, locate

    (truth,) = [t for t in CORPUS if t.name == "px4docs_amovlabf410_v1.15.4.params"]
    config = migrate.read_config(locate(truth, tmp_path))
    v6x = board("px4_fmu-v6x", "v1.15.0")
    assert len(v6x.i2c_launcher_buses) == len(v6x.i2c_launcher_sources) == 2
    short = dataclasses.replace(v6x, i2c_launcher_sources=v6x.i2c_launcher_sources[:1])
    with pytest.raises(ValueError, match="zip"):
        migrate.migrate(config, board=short)


# -- $BOARD_FMUV3 from the boot console ------------------------------------------------------

#: fmu-v2's and fmu-v3's script (v1.12.0 .. main, read at 9524e8ec, 30e763b6, 83c4f4e5,
#: bb59c637): `set BOARD_FMUV3 0` (line 20); `if ver hwtypecmp V30` then `if mpu6000 -s -b 4
#: -R 10 start` (line 27) sets 20 (line 29), else `if mpu9250 -s -b 4 -R 10 start` (line 33)
#: sets 21 (line 35); `if ver hwtypecmp V2M` likewise on SPI 1 (lines 50 and 56 test, 52 and
#: 58 set). The console lines are the
#: drivers' own (platforms/common/i2c_spi_buses.cpp: "<name> #<n> on SPI bus <b>", then
#: "(devid=...)" in 1.11 and " rotation <r>" when not 0 from 1.12); a start that found
#: nothing prints "no instance started".
CUBE_20 = "mpu6000 #0 on SPI bus 4 rotation 10\n"
CUBE_21 = (
    "WARN  [SPI_I2C] mpu6000: no instance started (no device on bus?)\n"
    "mpu9250 #0 on SPI bus 4 rotation 10\n"
)
PIXHAWK_1 = "mpu6000 #0 on SPI bus 1 rotation 14\n"


def fmuv3_facts(hw_type: str | None, console: str | None, board: str = "px4_fmu-v3") -> Facts:
    from px4params.vehicle.console import started_drivers

    starts = started_drivers(console) if console is not None else None
    kind = "ULog" if console is not None or hw_type is not None else "QGC .params"
    cite = load_boards().by_name(board, "v1.15.0").cite  # type: ignore[union-attr]
    return Facts({}, {}, ("PX4_FMU_V3",), starts, kind, hw_type,
                 board_variables(board, ("v1.15.0",)), cite)  # fmt: skip


@pytest.mark.parametrize(
    ("hw_type", "console", "value"),
    [
        ("V30", CUBE_20, "20"),  # a Cube 2.0: the isolated MPU6000 answered
        ("V30", CUBE_21, "21"),  # a Cube 2.1: no MPU6000, the MPU9250 answered
        ("V30", "", "0"),  # a Cube whose SPI 4 IMU did not answer
        ("V2", PIXHAWK_1, "0"),  # a Pixhawk 1: neither V30 nor V2M is tested true
        ("V2M", "mpu6000 #0 on SPI bus 1 rotation 10\n", "20"),  # a Pixhack
    ],
)
@pytest.mark.parametrize("board_name", ["px4_fmu-v2", "px4_fmu-v3"])
def test_board_fmuv3_is_what_the_boot_console_shows_answered(
    hw_type: str, console: str, value: str, board_name: str
) -> None:
    facts = fmuv3_facts(hw_type, console, board_name)
    for tested in ("0", "20", "21"):
        verdict = evaluate(f"$BOARD_FMUV3 == {tested}", facts)
        assert (verdict.holds, verdict.unchecked) == (tested == value, ())


def test_board_fmuv3_without_a_console_names_each_line_that_sets_it() -> None:
    # A log with its hardware type but no boot console (PX4 before 1.12, or none logged): the
    # Cube's start on line 27 or 33 answered, which one only a console says; 0 is the script's
    # first value. Each `if` line is named, the missing console once, the script as every
    # board line is cited (at the newest snapshot of the board's row: main)
    verdict = evaluate("$BOARD_FMUV3 == 21", fmuv3_facts("V30", None))
    assert verdict.holds is False
    (said,) = verdict.unchecked
    started = "started (-s -b 4 -R 10 start)"
    assert said == (
        "$BOARD_FMUV3 == 21 (PX4/PX4-Autopilot boards/px4/fmu-v3/init/rc.board_sensors:20 at main "
        "(branch main, bb59c637cd, 2026-08-13) sets BOARD_FMUV3 0; "
        f"line 27: 20 where mpu6000 {started}; line 33: 21 where not mpu6000 {started} and "
        f"mpu9250 {started}; for each, a ULog has no boot console to say)"
    )


def test_the_cube_21s_own_rows_run_by_its_boot_console() -> None:
    # Line 83 `mpu9250 -s -b 1 start` runs inside `if [ $BOARD_FMUV3 = 21 ]`, line 96's FMUv2
    # `mpu6000 -s -b 1 -R 14 start` only in the else of `if [ $BOARD_FMUV3 != 0 ]`
    v3 = board("px4_fmu-v3", "v1.15.0")
    when = {r.source.split(" at ")[0].rsplit(":", 1)[1]: r.when for r in v3.devices}
    facts = fmuv3_facts("V30", CUBE_21)
    assert evaluate(when["83"], facts) == Verdict(True)
    assert evaluate(when["96"], facts) == Verdict(False)


# -- a start on a bus of the other kind starts nothing ------------------------------------------

LIS3MDL_BUS2 = 0x05 << 16 | 0x1E << 8 | 2 << 3 | 1  # 335377
IST8310_BUS2 = 0x06 << 16 | 0x0E << 8 | 2 << 3 | 1  # 396817


@pytest.mark.parametrize("hw_type", ["MR-CANHUBK3", None])
def test_canhubk3s_external_starts_on_its_internal_bus_start_nothing(hw_type: str | None) -> None:
    # PX4 main, boards/nxp/mr-canhubk3/src/i2c.cpp line 38: initI2CBusInternal(
    # PX4_BUS_NUMBER_TO_PX4(1)), bus 2; its rc.board_sensors line 22 `ist8310 -X -b 2 -R 10
    # start` (where not hw_type in MR-CANHUBK3-ADAP) and line 32 `lis3mdl -X -b 2 -R 2 start`.
    # platforms/common/i2c.cpp lines 89-96: an -X start is tried only on a bus for which
    # px4_i2c_bus_external() is true, its -b among them: neither line starts anything, so
    # neither leaves a compass on bus 2 out as the board's; the report names each line.
    # Line 10's `ist8310 -X -b 1 -R 10 start` (bus 1 external, line 37) is no such line.
    params = {"CAL_MAG0_ID": LIS3MDL_BUS2, "CAL_MAG1_ID": IST8310_BUS2, "CAL_MAG2_ID": IST8310_BUS1}
    proposal = migrate.migrate(
        config(params, hw_type=hw_type),
        table="current",
        board=board("nxp_mr-canhubk3", "v1.15.0"),
    )
    assert left_out(proposal) == {}
    assert sorted(placed(proposal)) == [
        ("IST8310#0", 2, 0x0E),
        ("IST8310#1", 1, 0x0E),
        ("LIS3MDL#0", 2, 0x1E),
    ]
    assert not [a for a in proposal.assumptions if a.startswith("CAL_MAG2_ID") and "did not" in a]
    script = "PX4/PX4-Autopilot boards/nxp/mr-canhubk3/init/rc.board_sensors"
    for found, start, line in (
        (
            "CAL_MAG0_ID = 335377: LIS3MDL (MAG), I2C bus 2, address 0x1E",
            "lis3mdl -X -b 2 -R 2",
            32,
        ),
        (
            "CAL_MAG1_ID = 396817: IST8310 (MAG), I2C bus 2, address 0x0E",
            "ist8310 -X -b 2 -R 10",
            22,
        ),
    ):
        (said,) = [a for a in proposal.assumptions if a.startswith(found)]
        assert said.startswith(f"{found}: the board's '{start} start' ({script}:{line} at ")
        assert said.endswith(
            ") did not start it: I2C bus 2 is internal (PX4/PX4-Autopilot "
            "boards/nxp/mr-canhubk3/src/i2c.cpp:38 at main (branch main, bb59c637cd, "
            "2026-08-13)), and PX4's -X tries no bus of that kind (platforms/common/i2c.cpp, "
            "I2CBusIterator::next), so that line starts nothing"
        )


@pytest.mark.parametrize("hw_type", ["V30", "V2M", None])
def test_rc_sensors_probes_fmu_v3s_bus_2_on_a_cube(hw_type: str | None) -> None:
    # PX4 v1.15.0, ROMFS/px4fmu_common/init.d/rc.sensors line 166: `ms4525do start -X` behind
    # SENS_EN_MS4525DO. boards/px4/fmu-v3/src/i2c.cpp lines 44-63: bus 1 external, bus 2
    # external only where HW_VER_FMUV3 == board_get_hw_version() (line 52), hw_type "V30"
    # (init.c lines 388-390). So the -X start tries buses 1 and 2 on a Cube, bus 1 elsewhere.
    proposal = migrate.migrate(
        config({"SENS_EN_MS4525DO": 1}, hw_type=hw_type),
        table="current",
        board=board("px4_fmu-v3", "v1.15.0"),
    )
    assert placed(proposal) == [("MS4525DO#0", 1, 0x28)]
    every = [a for a in proposal.assumptions if "on every external I2C bus" in a]
    buses = "1, 2" if hw_type == "V30" else "1"
    assert len(every) == 1 and f"on every external I2C bus ({buses}; " in every[0]
    bus_2 = [a for a in proposal.assumptions if " on I2C bus 2 runs only where " in a]
    if hw_type is not None:
        assert bus_2 == []
        return
    (said,) = bus_2
    assert said.startswith("SENS_EN_MS4525DO: 'ms4525do start -X' (PX4/PX4-Autopilot ")
    assert "ROMFS/px4fmu_common/init.d/rc.sensors:166 " in said
    assert (
        "runs only where hw_type in V30 (the hardware revision, which the parameters do not "
        in said
    )
    assert (
        "; the bus is external only there: PX4/PX4-Autopilot boards/px4/fmu-v3/src/i2c.cpp:52 "
        in said
    )
    assert said.endswith("): not proposed from it")


AK09916_BUS2 = 0x09 << 16 | 0x0C << 8 | 2 << 3 | 1  # 592913


def test_a_cube_oranges_v1_11_here2_line_is_its_second_external_bus() -> None:
    # PX4 v1.11.0: boards/cubepilot/cubeorange/init/rc.board_sensors:17 `ak09916 -X -b 2 -R 6
    # start`; platforms/common/i2c.cpp:72-79 takes -X -b 2 as the second external bus of
    # px4_i2c_buses, and src/i2c.cpp:37-38 lists bus 2 then bus 1: the line starts the Here2's
    # AK09916 on bus 1 (its comment: "standard Here/Here2 connected to GPS1"). So one on bus 1
    # is the board's, one on bus 2 is not (SENS_EXT_I2C_PRB 0: rc.sensors probes nothing).
    cube = board("cubepilot_cubeorange", "v1.11.0")
    for found, proposed in ((AK09916_BUS1, []), (AK09916_BUS2, [("AK09916#0", 2, 0x0C)])):
        proposal = migrate.migrate(
            config({"CAL_MAG0_ID": found, "SENS_EXT_I2C_PRB": 0}, version=(1, 11, 3)),
            table="current",
            board=cube,
        )
        assert placed(proposal) == proposed
        if not proposed:
            assert_the_boards(
                proposal,
                f"CAL_MAG0_ID = {found}",
                "boards/cubepilot/cubeorange/init/rc.board_sensors:17 at v1.11.0 ",
            )


# -- a board whose I2C buses the table does not know ---------------------------------------------

HMC5883_BUS1 = 0x01 << 16 | 0x1E << 8 | 1 << 3 | 1  # 73225


@pytest.mark.issue40
@pytest.mark.parametrize("bus", [1, 2])
def test_a_row_without_b_is_on_any_bus_where_the_buses_are_unknown(bus: int) -> None:
    # PX4 main, boards/airmind/mindpx-v2/init/rc.board_sensors line 9 `hmc5883 -T -I -R 12
    # start`: without the board's i2c.cpp (no i2c_buses_path) which buses -I tries is not
    # known, so the row may be on any bus: an HMC5883 on bus 1 or 2 is the board's.
    mindpx = dataclasses.replace(board("airmind_mindpx-v2", "v1.15.0"), i2c_buses_path="")
    found = HMC5883_BUS1 if bus == 1 else HMC5883_BUS2
    proposal = migrate.migrate(config({"CAL_MAG0_ID": found}), table="current", board=mindpx)
    assert placed(proposal) == []
    assert_the_boards(
        proposal, f"CAL_MAG0_ID = {found}", "boards/airmind/mindpx-v2/init/rc.board_sensors:9 at "
    )


@pytest.mark.issue40
def test_a_row_with_b_is_on_that_bus_alone_where_the_buses_are_unknown() -> None:
    # PX4 main, boards/cuav/nora/init/rc.board_sensors line 29 `ist8310 -X -b 1 -R 10 start`:
    # without the board's i2c.cpp its -b 1 is taken as bus 1: an IST8310 there is the
    # board's, one on bus 2 is proposed.
    nora = dataclasses.replace(board("cuav_nora", "v1.15.0"), i2c_buses_path="")
    for found, proposed in ((IST8310_BUS1, []), (IST8310_BUS2, [("IST8310#0", 2, 0x0E)])):
        proposal = migrate.migrate(config({"CAL_MAG0_ID": found}), table="current", board=nora)
        assert placed(proposal) == proposed
        if not proposed:
            assert_the_boards(
                proposal, f"CAL_MAG0_ID = {found}", "boards/cuav/nora/init/rc.board_sensors:29 at "
            )


RM3100_BUS4 = 0x07 << 16 | 0x20 << 8 | 4 << 3 | 1  # 466977


@pytest.mark.issue40
def test_an_internal_row_settled_not_to_run_does_not_take_the_device() -> None:
    # PX4 v1.15.0, boards/px4/fmu-v6x/init/rc.board_sensors line 143 `rm3100 -I -b 4 start`
    # runs only where hw_type in V6X001; a log of a V6X000000 settles that it does not, so
    # the row does not make an RM3100 on internal bus 4 the board's: it is proposed.
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": RM3100_BUS4}, hw_type="V6X000000"),
        table="current",
        board=board("px4_fmu-v6x", "v1.15.0"),
    )
    assert left_out(proposal) == {}
    assert placed(proposal) == [("RM3100#0", 4, 0x20)]


@pytest.mark.issue40
def test_a_cubes_bus_2_compass_notes_that_only_x_starts_reach_it() -> None:
    # PX4 main, boards/px4/fmu-v3/src/i2c.cpp line 52: bus 2 is external where hw_type is V30
    # (a Cube); platforms/common/i2c.cpp tries -I starts only on internal buses, -X starts only
    # on external ones: rc.sensors' probe finds an IST8310 there, the board's -I rows do not.
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": IST8310_BUS2, "SENS_EXT_I2C_PRB": 1}, hw_type="V30"),
        table="current",
        board=board("px4_fmu-v3", "v1.15.0"),
    )
    (inst,) = proposal.instances
    assert inst.notes == [
        "I2C bus 2 is external where hw_type in V30 (PX4/PX4-Autopilot "
        "boards/px4/fmu-v3/src/i2c.cpp:52 at main (branch main, bb59c637cd, 2026-08-13)): the "
        "board's -I starts try no bus there, rc.sensors' -X starts do"
    ]


# -- the lines a user reads, whole: rows edited where no bundled row has two open clauses --------

#: A second clause a QGC file leaves open beside the hardware type: `ver hwbasecmp 008`
#: (the base board, which no parameter names).
HW_BASE = "hw_base in 008"
HW_BASE_WHY = "hw_base in 008 (the hardware revision, which the parameters do not tell)"


def with_row(b: Board, line: int, of: str = "devices", **edit: Any) -> Board:
    """``b`` with its rows of script line ``line`` edited (``when``, ``args``, ...): its device
    rows, or ``of="switches"`` its switch rows."""
    old = getattr(b, of)
    rows = tuple(
        dataclasses.replace(r, **edit) if f"rc.board_sensors:{line} " in r.source else r
        for r in old
    )
    assert rows != old
    return dataclasses.replace(b, **{of: rows})


@pytest.mark.issue40
def test_an_unsettled_row_of_two_open_clauses_names_both_in_the_assumption_and_the_note() -> None:
    # CANHUBK3's line 10 read as running where the type is an ADAP and the base is 008: both
    # clauses, joined by "and", in the assumption of the proposed IST8310 and in its note
    mr = with_row(board("nxp_mr-canhubk3"), 10, when=f"hw_type in MR-CANHUBK3-ADAP and {HW_BASE}")
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": IST8310_BUS1, "CAL_MAG0_ROT": 0}), table="current", board=mr
    )
    line_10 = f"{CANHUBK3_LINE_10} and {HW_BASE_WHY}"
    (said,) = [a for a in proposal.assumptions if a.startswith("CAL_MAG0_ID")]
    assert said == (
        f"CAL_MAG0_ID = 396809: IST8310 (MAG), I2C bus 1, address 0x0E: {line_10}: "
        f"proposed, not left out on a guess{CANHUBK3_ROTATION}"
    )
    (ist,) = proposal.instances
    assert ist.notes == [line_10 + CANHUBK3_ROTATION]


@pytest.mark.issue40
def test_an_internal_bus_row_of_two_open_clauses_names_both_where_finding_it_shows_it_ran() -> None:
    # Pixhawk 6X's line 133 (`bmm150 -I -R 0 start`, bus 4 internal) read as running where the
    # type is not V6X001 and the base is 008: a BMM150 found there is the board's, and the line
    # names both clauses
    v6x = with_row(board("px4_fmu-v6x"), 133, when=f"not hw_type in V6X001 and {HW_BASE}")
    proposal = migrate.migrate(config({"CAL_MAG0_ID": BMM150_BUS4}), table="current", board=v6x)
    line = assert_the_boards(
        proposal, "CAL_MAG0_ID = 4395041", "boards/px4/fmu-v6x/init/rc.board_sensors:133 "
    )
    assert line.endswith(
        "it runs only where not hw_type in V6X001 (the hardware revision, which the parameters "
        f"do not tell) and {HW_BASE_WHY}, and being found on internal I2C bus 4 "
        "(boards/px4/fmu-v6x/src/i2c.cpp) shows it did"
    )


@pytest.mark.issue40
def test_a_board_row_holding_by_pX4s_default_is_named_as_taken() -> None:
    # Pixhawk 6X's line 133 read as running where $HAVE_PM2 is yes, which line 5 sets and line
    # 8 unsets where the hardware manifest says no second power module: a QGC file does not
    # say, so the row holds by PX4's default, the BMM150 is the board's and the report says so
    v6x = with_row(board("px4_fmu-v6x"), 133, when="$HAVE_PM2 == yes")
    proposal = migrate.migrate(config({"CAL_MAG0_ID": BMM150_BUS4}), table="current", board=v6x)
    assert_the_boards(
        proposal, "CAL_MAG0_ID = 4395041", "boards/px4/fmu-v6x/init/rc.board_sensors:133 "
    )
    script = "PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors"
    main = "at main (branch main, bb59c637cd, 2026-08-13)"
    (said,) = [a for a in proposal.assumptions if a.startswith("CAL_MAG0_ID")]
    assert said == (
        "CAL_MAG0_ID = 4395041: BMM150 (MAG), I2C bus 4, address 0x10: the board's 'bmm150 -I "
        f"-R 0 start' ({script}:133 {main}) runs only where $HAVE_PM2 == yes ({script}:5 {main} "
        "sets HAVE_PM2 yes; line 8: no where mft MFT_PM2 == 0 (the board's hardware manifest, "
        "which the parameters do not tell)): taken as holding (PX4's default)"
    )


def probe_rows(
    v5: Board, edit: dict[str, Any] | None = None, first: SwitchStart | None = None
) -> Board:
    """PX4 1.11's fmu-v5 with rc.sensors' `ak09916 -X -R 6 start` (line 102) edited, and
    ``first`` (a row) before every switch row."""
    rows = tuple(
        dataclasses.replace(r, **edit)
        if edit and r.source.startswith(f"PX4/PX4-Autopilot {RC_SENSORS_102}")
        else r
        for r in v5.switches
    )
    return dataclasses.replace(v5, switches=((first,) if first else ()) + rows)


RC_SENSORS_102 = "ROMFS/px4fmu_common/init.d/rc.sensors:102 "


@pytest.mark.issue40
def test_a_probe_of_two_open_clauses_names_both_where_its_rotation_is_taken() -> None:
    # line 102 read as running where SENS_EXT_I2C_PRB is 1 and the base is 008: a QGC file
    # without SENS_EXT_I2C_PRB settles neither, and the assumption names both
    when = f"SENS_EXT_I2C_PRB == 1 and {HW_BASE}"
    v5 = probe_rows(board("px4_fmu-v5", "v1.11.0"), {"when": when})
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": AK09916_BUS1}, version=(1, 11, 3)), table="current", board=v5
    )
    (ak,) = proposal.instances
    assert ak.values["rotation"] == 6
    (said,) = [a for a in proposal.assumptions if a.startswith("'ak09916 -X -R 6 start'")]
    assert said == (
        f"'ak09916 -X -R 6 start' (PX4/PX4-Autopilot {RC_SENSORS_102}at v1.11.0 (tag v1.11.0, "
        "71db0903a9, 2020-09-07)) runs only where SENS_EXT_I2C_PRB == 1 (SENS_EXT_I2C_PRB is "
        f"not in the QGC .params) and {HW_BASE_WHY}: its -R 6 taken"
    )


@pytest.mark.issue40
def test_a_probe_that_does_not_run_is_passed_over_for_the_next_that_does() -> None:
    # a probe `ak09916 -X -R 2 start` where SENS_EXT_I2C_PRB is 2, before line 102: with
    # SENS_EXT_I2C_PRB 1 it does not run, line 102 does: the AK09916's rotation is 6
    v5 = board("px4_fmu-v5", "v1.11.0")
    (real,) = [r for r in v5.switches if r.driver == "ak09916" and r.bus == 1]
    other = dataclasses.replace(
        real,
        args="-X -R 2 start",
        rotation=2,
        when="SENS_EXT_I2C_PRB == 2",
        source="rc.sensors:101",
    )
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": AK09916_BUS1, "SENS_EXT_I2C_PRB": 1}, version=(1, 11, 3)),
        table="current",
        board=probe_rows(v5, first=other),
    )
    (ak,) = proposal.instances
    assert (ak.name, ak.values["rotation"]) == ("AK09916#0", 6)
    assert ak.notes == [
        f"rotation 6: rc.sensors probes it with 'ak09916 -X -R 6 start' ({real.source})"
    ]


#: What the report says of a CANHUBK3 row that tries no bus of its kind, after the row.
NO_BUS_OF_THAT_KIND = (
    "and PX4's {option} tries no bus of that kind (platforms/common/i2c.cpp, "
    "I2CBusIterator::next), so that line starts nothing"
)
CANHUBK3_I2C = "PX4/PX4-Autopilot boards/nxp/mr-canhubk3/src/i2c.cpp:{line} at main (branch main, "


@pytest.mark.issue40
def test_an_internal_start_on_an_external_bus_is_said_to_start_nothing() -> None:
    # CANHUBK3's line 10 read as `ist8310 -I -b 1 -R 10 start` on every type: bus 1 is
    # external (src/i2c.cpp line 37), and an -I start tries only internal buses
    # (platforms/common/i2c.cpp): the line starts nothing, the IST8310 on bus 1 is proposed
    mr = with_row(
        board("nxp_mr-canhubk3", "v1.15.0"),
        10,
        args="-I -b 1 -R 10 start",
        internal=True,
        when="",
    )
    proposal = migrate.migrate(config({"CAL_MAG0_ID": IST8310_BUS1}), table="current", board=mr)
    assert placed(proposal) == [("IST8310#0", 1, 0x0E)]
    (said,) = proposal.assumptions
    assert said == (
        "CAL_MAG0_ID = 396809: IST8310 (MAG), I2C bus 1, address 0x0E: the board's 'ist8310 -I "
        "-b 1 -R 10 start' (PX4/PX4-Autopilot boards/nxp/mr-canhubk3/init/rc.board_sensors:10 "
        "at main (branch main, bb59c637cd, 2026-08-13)) did not start it: I2C bus 1 is external "
        f"({CANHUBK3_I2C.format(line=37)}bb59c637cd, 2026-08-13)), "
        + NO_BUS_OF_THAT_KIND.format(option="-I")
    )


IST8310_0C_BUS2 = 0x06 << 16 | 0x0C << 8 | 2 << 3 | 1  # 396305


@pytest.mark.issue40
def test_a_start_on_a_bus_of_the_other_kind_is_named_only_for_its_own_chip_and_address() -> None:
    # CANHUBK3's line 22 `ist8310 -X -b 2 -R 10` starts an IST8310 at its default 0x0E (PX4's
    # ist8310 I2C_ADDRESS_DEFAULT), line 32 `lis3mdl -X -b 2 -R 2` a LIS3MDL: neither is named
    # for an IST8310 at 0x0C, nor for an HMC5883 at 0x1E (LIS3MDL's address, not its chip)
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": IST8310_0C_BUS2, "CAL_MAG1_ID": HMC5883_BUS2}),
        table="current",
        board=board("nxp_mr-canhubk3", "v1.15.0"),
    )
    assert sorted(placed(proposal)) == [("HMC5883#0", 2, 0x1E), ("IST8310#0", 2, 0x0C)]
    assert proposal.assumptions == []


@pytest.mark.issue40
def test_a_console_start_without_address_is_named_beside_the_line_of_its_chip() -> None:
    # PX4 1.11's boot console prints no address (v1.11.0 platforms/common/i2c_spi_buses.cpp
    # line 502: "%s #%i on I2C bus %d", then " (external, ...)" on an external bus only): an
    # IST8310 on bus 2 may be at line 22's 0x0E, so line 22 is named as starting nothing there
    proposal = migrate.migrate(
        OldConfig("t", "ULog", {}, version=(1, 11, 3), console="ist8310 #0 on I2C bus 2\n"),
        table="current",
        board=board("nxp_mr-canhubk3", "v1.15.0"),
    )
    # The board came after 1.11 into the table: a later release's script is what is read.
    (later, said) = unasked(proposal)
    assert later == (
        "board nxp_mr-canhubk3: in the board table from PX4 v1.14.0 on, not at v1.11.0, the "
        "newest release it has at or before this file's 1.11.3; what its script starts is taken "
        "as at v1.14.0"
    )
    assert said == (
        "boot console line 1: ist8310, I2C bus 2: the board's 'ist8310 -X -b 2 -R 10 start' "
        "(PX4/PX4-Autopilot boards/nxp/mr-canhubk3/init/rc.board_sensors:22 at main (branch "
        "main, bb59c637cd, 2026-08-13)) did not start it: I2C bus 2 is internal "
        f"({CANHUBK3_I2C.format(line=38)}bb59c637cd, 2026-08-13)), "
        + NO_BUS_OF_THAT_KIND.format(option="-X")
    )


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("hw_type", "edit", "proposed"),
    [
        # a Pixhawk Mini: bus 2 is internal, which rc.sensors never probes: line 12 ran
        ("V2M", {}, []),
        # a Cube: bus 2 is external, which rc.sensors probes too: not the board's on a guess
        ("V30", {"args": "-T -X -b 2 -R 4 start", "internal": False, "bus": 2},
         [("HMC5883#0", 2, 0x1E)]),
    ],
)  # fmt: skip
def test_an_unsettled_row_is_the_boards_only_where_the_hardware_type_makes_its_bus_internal(
    hw_type: str, edit: dict[str, Any], proposed: list[tuple[str, int, int]]
) -> None:
    # PX4 v1.12.0 fmu-v3: bus 2 is external where hw_type is V30 (src/i2c.cpp line 52), else
    # internal. Line 12 (`hmc5883 -T -I -R 4 start`, or read as `-X -b 2`) read as running
    # only where the base is 008, which nothing here settles: an HMC5883 found on bus 2 is
    # the board's where the log's type makes bus 2 internal, and proposed where external
    v3 = with_row(board("px4_fmu-v3", "v1.12.0"), 12, when=HW_BASE, **edit)
    proposal = migrate.migrate(
        config({"CAL_MAG0_ID": HMC5883_BUS2}, version=(1, 12, 3), hw_type=hw_type),
        table="current",
        board=v3,
    )
    assert placed(proposal) == proposed
    if not proposed:
        line = assert_the_boards(
            proposal, "CAL_MAG0_ID = 73233", "boards/px4/fmu-v3/init/rc.board_sensors:12 "
        )
        assert line.endswith(
            f"it runs only where {HW_BASE_WHY}, and being found on internal I2C bus 2 "
            "(boards/px4/fmu-v3/src/i2c.cpp) shows it did"
        )


# -- a switch's rows: what runs, and which lines are its driver's ------------------------------

V6X_SCRIPT = "PX4/PX4-Autopilot boards/px4/fmu-v6x/init/rc.board_sensors"
V6X_MAIN = "at main (branch main, bb59c637cd, 2026-08-13)"
#: Why $HAVE_PM2 is open on a Pixhawk 6X (main) where a QGC file says nothing of its manifest.
V6X_PM2_WHY = (
    f"{V6X_SCRIPT}:5 {V6X_MAIN} sets HAVE_PM2 yes; line 8: no where mft MFT_PM2 == 0 (the "
    "board's hardware manifest, which the parameters do not tell)"
)


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("when", "open_", "then"),
    [
        # $HAVE_PM2 is yes by PX4's default: a row needing no does not run
        ("$HAVE_PM2 == no", f"$HAVE_PM2 == no ({V6X_PM2_WHY})",
         "by PX4's default it does not run, not proposed from it"),
        # and the base board nothing settles beside it: not known, both named
        (f"$HAVE_PM2 == yes and {HW_BASE}", f"$HAVE_PM2 == yes ({V6X_PM2_WHY}) and {HW_BASE_WHY}",
         "not proposed from it"),
    ],
)  # fmt: skip
def test_a_switch_row_that_does_not_run_by_default_or_is_not_known_says_so_whole(
    when: str, open_: str, then: str
) -> None:
    # Pixhawk 6X (main) line 28 `ina226 -X -b 2 -t 2 -k start` (SENS_EN_INA226 == 1 and
    # $HAVE_PM2 == yes) read with another clause beside SENS_EN_INA226 == 1: only line 24's
    # INA226 on bus 1 is proposed, and the report names line 28's open clauses whole
    v6x = with_row(board("px4_fmu-v6x"), 28, of="switches", when=f"SENS_EN_INA226 == 1 and {when}")
    proposal = migrate.migrate(config({"SENS_EN_INA226": 1}), table="current", board=v6x)
    assert placed(proposal) == [("INA226#0", 1, 0x41)]
    (said,) = [a for a in proposal.assumptions if a.startswith("SENS_EN_INA226")]
    assert said == (
        f"SENS_EN_INA226: 'ina226 -X -b 2 -t 2 -k start' ({V6X_SCRIPT}:28 {V6X_MAIN}) runs only "
        f"where {open_}: {then}"
    )


@pytest.mark.issue40
@pytest.mark.parametrize("console", [None, "ina226 #0 on I2C bus 2 (external) address 0x41\n"])
def test_a_switch_starting_two_drivers_gives_each_driver_only_its_own_lines(
    console: str | None,
) -> None:
    # A switch may start more than one driver (v1.18's fmu-v6x: SENS_INT_BARO_EN starts bmp388
    # and icp201xx). Pixhawk 6X (main) read as also starting `ina238 -X -b 2 -t 3 start` under
    # SENS_EN_INA226, before its own lines 24 (`ina226 -X -b 1 -t 1 -k start`) and 28 (`-b 2
    # -t 2`): the INA226's places and battery indices are its own lines', whether the board's
    # rows place it or its console line does (which prints no options)
    v6x = board("px4_fmu-v6x")
    (line_28,) = [r for r in v6x.switches if r.source.startswith(f"{V6X_SCRIPT}:28 ")]
    other = dataclasses.replace(
        line_28,
        driver="ina238",
        args="-X -b 2 -t 3 start",
        when="SENS_EN_INA226 == 1",
        source="the edited rc.board_sensors:27",
    )
    edited = dataclasses.replace(v6x, switches=(other, *v6x.switches))
    proposal = migrate.migrate(
        OldConfig("t", "ULog", {"SENS_EN_INA226": 1}, version=(1, 16, 0), console=console),
        table="current",
        board=edited,
    )
    index = "today's start line also sets the battery index (-t {}): INA226 has no field for it"
    runs = [(1, 0x41, 1), (2, 0x41, 2)] if console is None else [(2, 0x41, 2)]
    assert [
        (i.name, i.values["bus.i2c.bus_id"], i.values["bus.i2c.address"], i.notes)
        for i in proposal.instances
    ] == [(f"INA226#{n}", bus, at, [index.format(t)]) for n, (bus, at, t) in enumerate(runs)]


# -- what a boot console line says of an unsettled row's rotation --------------------------------


@pytest.mark.issue40
def test_a_console_showing_another_rotation_than_the_rows_says_the_row_did_not_start_it() -> None:
    # CANHUBK3's rc.sensors probe (v1.15.0 line 216, `ist8310 -X -q start`) read as passing -R 2,
    # as PX4 1.11's probed `ak09916 -X -R 6 start`: a PX4 1.15 console line showing the IST8310
    # on bus 1 running with -R 2 is that probe's, not line 10's (-R 10), and both the
    # assumption and the instance's note say the console showed it
    mr = board("nxp_mr-canhubk3", "v1.15.0")
    probes = tuple(
        dataclasses.replace(r, args="-X -R 2 -q start", rotation=2)
        if (r.param, r.driver) == ("SENS_EXT_I2C_PRB", "ist8310")
        else r
        for r in mr.switches
    )
    console = "ist8310 #0 on I2C bus 1 (external) address 0xE rotation 2\n"
    proposal = migrate.migrate(
        OldConfig("t", "ULog", {}, version=(1, 15, 0), console=console),
        table="current",
        board=dataclasses.replace(mr, switches=probes),
    )
    shown = (
        "; boot console line 1 shows it runs with -R 2, not with that line's -R 10: that line "
        "did not start it"
    )
    (said,) = [a for a in proposal.assumptions if a.startswith("boot console line 1")]
    assert said == (
        f"boot console line 1: ist8310, I2C bus 1, address 0x0E: {CANHUBK3_LINE_10}: proposed, "
        f"not left out on a guess{shown}"
    )
    (ist,) = proposal.instances
    assert (ist.values["rotation"], ist.notes) == (
        2,
        ["rotation 2: the driver's -R (boot console)", CANHUBK3_LINE_10 + shown],
    )


@pytest.mark.issue40
def test_a_px4_1_11_console_line_shows_no_rotation_so_the_rows_condition_is_named() -> None:
    # PX4 1.11's console prints no rotation (v1.11.0 platforms/common/i2c_spi_buses.cpp line
    # 502): its IST8310 line on bus 1 does not say whether line 10 (-R 10) started it, so the
    # rotation 0 of rc.sensors' probe is said to hold only where line 10 does not run
    console = "ist8310 #0 on I2C bus 1 (external, equal to '-b 1')\n"
    proposal = migrate.migrate(
        OldConfig("t", "ULog", {}, version=(1, 11, 3), console=console),
        table="current",
        board=board("nxp_mr-canhubk3", "v1.15.0"),
    )
    (said,) = [a for a in proposal.assumptions if a.startswith("boot console line 1: ist8310")]
    assert said == (
        f"boot console line 1: ist8310, I2C bus 1: {CANHUBK3_LINE_10}: proposed, not left out on "
        f"a guess{CANHUBK3_ROTATION}"
    )
    (ist,) = proposal.instances
    # for today's PX4 the 1.11 probe's 0 is 10: the IST8310 driver's axes (test_migrate_axes.py)
    turned = (
        "rotation 10 (was 0 on PX4 v1.11.3: rc.sensors starts it without -R): ist8310 reports "
        "other axes from PX4 v1.12.0 (PX4 commit 7569722821): the same orientation as before"
    )
    assert (ist.values["rotation"], ist.notes) == (
        10,
        [turned, CANHUBK3_LINE_10 + CANHUBK3_ROTATION],
    )


@pytest.mark.issue40
def test_an_internal_bus_of_a_board_without_its_i2c_file_cites_the_boards_buses() -> None:
    # Pixhawk 6X (main) without the path of its src/i2c.cpp: line 133's BMM150 found on
    # internal bus 4 is the board's as above, its line citing the board's I2C buses instead
    v6x = dataclasses.replace(board("px4_fmu-v6x"), i2c_buses_path="")
    proposal = migrate.migrate(config({"CAL_MAG0_ID": BMM150_BUS4}), table="current", board=v6x)
    line = assert_the_boards(
        proposal, "CAL_MAG0_ID = 4395041", "boards/px4/fmu-v6x/init/rc.board_sensors:133 "
    )
    assert line.endswith(
        ", and being found on internal I2C bus 4 (the board's I2C buses) shows it did"
    )
