"""Reading today's configuration (migrate/config.py) and what a proposal says about it
(migrate/proposal.py), where test_migrate.py leaves them open. The inputs are written by hand
in QGC's ``.params`` format (QGroundControl's ParameterManager: a ``#`` header, then
``vehicle-id component-id name value type`` separated by TABs) and an airframe's ``param set``
lines."""

from __future__ import annotations

from pathlib import Path

import pytest
from px4params import migrate
from px4params.vehicle import devid

DEVTYPES = "code\tname\n0x09\tDRV_MAG_DEVTYPE_AK09916\n"


@pytest.fixture
def devtypes(tmp_path: Path) -> devid.DevtypeTable:
    path = tmp_path / "devtypes.tsv"
    path.write_text(DEVTYPES)
    return devid.load_table("current", path)


def test_a_params_file_has_no_board_and_the_report_says_so(
    tmp_path: Path, devtypes: devid.DevtypeTable
) -> None:
    path = tmp_path / "vehicle.params"
    path.write_text("# Onboard parameters for Vehicle 1\n1\t1\tSYS_AUTOSTART\t4001\t6\n")
    config = migrate.read_config(path)
    # nor a hardware type: `ver hwtypecmp` rows stay unsettled, not false
    assert (config.hardware, config.release, config.console) == (None, None, None)
    assert config.hw_type is None
    proposal = migrate.migrate(config, table=devtypes)
    assert proposal.board is None
    assert any(
        a.startswith("no board information in a QGC .params: ") for a in proposal.assumptions
    )
    assert "  board: not known\n" in proposal.report()


def test_a_proposal_of_a_configuration_made_by_hand_reports_it() -> None:
    """OldConfig is public: a caller may build one from its own reading (details, skipped
    lines and the rest left out) and have the proposal's report and JSON of it."""
    config = migrate.OldConfig("bench.params", "QGC .params", {"SYS_AUTOSTART": 4001})
    assert (config.details, config.skipped, config.published) == ([], [], [])
    proposal = migrate.Proposal(config, table="current")
    report = proposal.report()
    assert report.startswith("Migration of bench.params (QGC .params, 1 parameters)\n")
    assert "Unchanged: 1 other parameters stay classic parameters" in report
    assert "\nNot known, assumed: none\n" in report and "  board: not known\n" in report
    document = proposal.as_dict()
    assert (document["not_carried"], document["assumptions"], document["board"]) == ([], [], None)
    # nothing compared, no target: JSON's null and empty list, as for a file read by migrate
    assert (document["target_release"], document["compared_releases"]) == (None, [])
    # a device left out by hand: no later releases compared for it (null, not "")
    proposal.left_out.append(migrate.LeftOut("CAL_MAG0_ID = 1", "a compass", "dronecan", "-"))
    assert proposal.as_dict()["left_out"][0]["later"] is None
    # an instance proposed by hand, its indices left to be filled in
    proposal.instances.append(migrate.ProposedInstance("INA238#0", "on the bench", {}))
    assert proposal.as_dict()["instances"][0]["indices"] == {}
    assert "\n# INA238#0: on the bench\nparam add INA238#0\n" in proposal.airframe()


def test_the_airframe_of_a_cut_log_says_so_in_its_header() -> None:
    whole = migrate.OldConfig("run.ulg", "ULog", {"SYS_AUTOSTART": 4001})
    cut = migrate.OldConfig("run.ulg", "ULog", {"SYS_AUTOSTART": 4001}, cut=True)
    header = [
        "# Device manifest migrated by px4params from run.ulg (ULog)",
        "# Review before use: see the migration report.",
    ]
    warning = (
        "# Warning: the log is cut short or damaged: devices logged after the break are missing "
        "here."
    )
    none = "# No device could be carried over."
    assert migrate.Proposal(whole, table="current").airframe().splitlines() == [*header, none]
    cut_proposal = migrate.Proposal(cut, table="current")
    assert cut_proposal.airframe().splitlines() == [*header, warning, none]
    assert cut_proposal.as_dict()["log_cut"] is True


def test_a_param_set_list_reads_every_command_of_a_line_joined_by_semicolons(
    tmp_path: Path,
) -> None:
    # One line of shell: the `then` and `else` parts are read (as if their condition held), and
    # so is what follows the `fi`; exactly ten lines of other commands are all named.
    path = tmp_path / "vehicle.airframe"
    path.write_text(
        "if param compare SYS_AUTOSTART 4001; then param set CAL_MAG1_PRIO 50; "
        "else param set CAL_MAG2_PRIO 75; fi; param set SENS_EN_INA238 1\n"
        + "".join(f"echo {n}\n" for n in range(10))
        + "fi\nparam set SYS_AUTOSTART 4001\n"  # (a `fi` too many closes nothing)
    )
    config = migrate.read_config(path)
    assert config.params == {
        "CAL_MAG1_PRIO": 50,
        "CAL_MAG2_PRIO": 75,
        "SENS_EN_INA238": 1,
        "SYS_AUTOSTART": 4001,
    }
    assert config.details == [
        "'param set' inside if ... fi (line 1): read as if every condition held"
    ]
    not_read = "not a 'param set NAME VALUE' command, not read"
    assert config.skipped == [f"line {2 + n}: 'echo {n}': {not_read}" for n in range(10)]


def test_a_logs_details_and_version_are_its_information_fields() -> None:
    """sample_log_small.ulg, read by hand with pyulog: ver_hw CUBEPILOT_CUBEORANGE,
    ver_sw_branch v1.11.2_w_rc_sysid, ver_sw 8583f1da..., ver_sw_release 0x010B0200 (PX4's
    encoding: major, minor, patch, type bytes): PX4 1.11.2, type 0, which px4_version.h's
    FIRMWARE_TYPE_DEV is (a build of a branch, not a tagged release: 255)."""
    from shared_data import SAMPLE_LOG, shared_file

    config = migrate.read_config(shared_file(SAMPLE_LOG))
    assert config.details == [
        "ver_hw CUBEPILOT_CUBEORANGE",
        "ver_sw_release 0x010B0200: PX4 1.11.2 dev",
        "ver_sw_branch v1.11.2_w_rc_sysid",
        "ver_sw 8583f1da30b63154d6ba0bc187d86135dfe33cf9",
    ]
    assert (config.release, config.version) == (0x010B0200, (1, 11, 2))
    assert config.hardware == "CUBEPILOT_CUBEORANGE"


def test_a_folder_given_as_the_configuration_is_named_with_the_reason(tmp_path: Path) -> None:
    with pytest.raises(migrate.MigrationError) as refused:
        migrate.read_config(tmp_path)
    assert str(refused.value) == f"{tmp_path}: cannot read: is a folder, not a file"


def test_without_the_autopilots_component_the_lowest_is_read(tmp_path: Path) -> None:
    """The autopilot is MAVLink component 1 (MAV_COMP_ID_AUTOPILOT1); a file without it (a
    second autopilot, 2, and a gimbal, 154) is read from its lowest component."""
    path = tmp_path / "vehicle.params"
    path.write_text(
        "# Onboard parameters for Vehicle 1\n"
        "1\t154\tGMB_MODE\t2\t6\n1\t2\tSYS_AUTOSTART\t4001\t6\n1\t2\tMC_ROLL_P\t6.5\t9\n"
    )
    config = migrate.read_config(path)
    assert config.params == {"SYS_AUTOSTART": 4001, "MC_ROLL_P": 6.5}
    assert config.details[0] == "component 2"
    assert config.skipped == ["component 154: 1 parameters (not the autopilot's)"]


def test_a_log_with_changed_parameters_is_read_at_their_last_values(tmp_path: Path) -> None:
    from test_devid import write_ulog

    log = write_ulog(
        tmp_path / "changed.ulg",
        {"SYS_AUTOSTART": 4001, "MC_ROLL_P": 6.5, "SENS_EN_INA238": 0},
        {"SYS_AUTOSTART": 4002, "SENS_EN_INA238": 1},
    )
    config = migrate.read_config(log)
    assert config.params == {"SYS_AUTOSTART": 4002, "MC_ROLL_P": 6.5, "SENS_EN_INA238": 1}
    assert config.details == ["last values of 2 parameters changed during the log"]
    assert (config.release, config.version, config.hardware) == (None, None, None)


def test_only_the_header_before_the_first_row_describes_the_file(tmp_path: Path) -> None:
    """QGC writes ``# Stack``, ``# Vehicle``, ``# Version`` at the top; a ``#`` line among the
    rows (a user's note) is no header: it neither changes the version nor refuses the file."""
    path = tmp_path / "vehicle.params"
    path.write_text(
        "# Onboard parameters for Vehicle 1\n#\n# Stack: PX4 Pro\n# Vehicle: Multi-Rotor\n"
        "# Version: 1.14.0 dev\n#\n# Vehicle-Id Component-Id Name Value Type\n"
        "1\t1\tSYS_AUTOSTART\t4001\t6\n"
        "# Stack: ArduPilot\n# Version: 4.5.1\n"
        "1\t1\tMC_ROLL_P\t6.5\t9\n"
    )
    config = migrate.read_config(path)
    assert config.version == (1, 14, 0)
    assert config.details == [
        "component 1", "Stack: PX4 Pro", "Vehicle: Multi-Rotor", "Version: 1.14.0 dev",
    ]  # fmt: skip
    assert config.params == {"SYS_AUTOSTART": 4001, "MC_ROLL_P": 6.5}


def test_a_param_set_list_reads_every_set_line_and_names_the_others(tmp_path: Path) -> None:
    """An airframe's syntax: ``param set`` / ``param set-default NAME VALUE``; other shell
    lines are not run, each named; integers stay integers (PX4's INT32), the rest floats."""
    path = tmp_path / "vehicle.airframe"
    path.write_text(
        "# an airframe\nparam set-default SYS_AUTOSTART 4001\necho starting\n"
        "param set MC_ROLL_P 6.5  # tuned\nif param compare X 1\nparam set SENS_EN_INA238 1\n"
    )
    config = migrate.read_config(path)
    assert config.kind == "param set list"
    assert config.params == {"SYS_AUTOSTART": 4001, "MC_ROLL_P": 6.5, "SENS_EN_INA238": 1}
    assert [type(v) for v in config.params.values()] == [int, float, int]
    assert config.skipped == [
        "line 3: 'echo starting': not a 'param set NAME VALUE' command, not read"
    ]
    assert config.details == [
        "'param set' inside if ... fi (line 6): read as if every condition held"
    ]


def test_a_param_set_list_names_each_line_it_does_not_read_and_the_conditional_ones(
    tmp_path: Path,
) -> None:
    # Two power monitors joined by ';' were dropped as "1 other lines (not 'param set')", with
    # no line number, and a 'param set' inside if/fi was taken as unconditional without a word.
    path = tmp_path / "vehicle.airframe"
    path.write_text(
        "param set SENS_EN_INA238 1; param set SENS_EN_INA226 1\n"
        "if param compare SYS_AUTOSTART 4001; then\n"
        "  param set CAL_MAG1_PRIO 50\n"
        "else param set CAL_MAG1_PRIO 75\n"
        "fi\n" + "".join(f"echo {n}\n" for n in range(12))
    )
    config = migrate.read_config(path)
    assert config.params == {"SENS_EN_INA238": 1, "SENS_EN_INA226": 1, "CAL_MAG1_PRIO": 75}
    assert config.details == [
        "'param set' inside if ... fi (lines 3, 4): read as if every condition held"
    ]
    not_read = "not a 'param set NAME VALUE' command, not read"
    assert config.skipped == [
        *(f"line {6 + n}: 'echo {n}': {not_read}" for n in range(10)),
        "... and 2 more lines of other commands",
        "line 3: CAL_MAG1_PRIO 50: set again on line 4 (75), which holds",
    ]


def test_a_param_list_without_set_lines_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "vehicle.airframe"
    path.write_text("param show SYS_AUTOSTART\nparam save\n")
    with pytest.raises(migrate.MigrationError) as refused:
        migrate.read_config(path)
    assert str(refused.value) == f"{path}: no 'param set' lines"


def test_a_proposals_airframe_and_json_written_out_by_hand() -> None:
    """The airframe's lines (``param add``, then ``param set-default NAME[k] VALUE`` under a
    ``# [k] path`` comment) and the JSON's values: booleans as 0/1, floats to 9 significant
    digits, addresses in hex; an infinity, which JSON cannot hold, as text."""
    config = migrate.OldConfig(
        "/logs/vehicle.params", "QGC .params", {"A": 1, "B": 2}, version=(1, 14, 0)
    )
    proposal = migrate.Proposal(config, table="px4-v1.14")
    assert proposal.airframe() == (
        "# Device manifest migrated by px4params from vehicle.params (QGC .params)\n"
        "# Review before use: see the migration report.\n"
        "# No device could be carried over.\n"
    )
    instance = migrate.ProposedInstance(
        "TST#0",
        "CAL_MAG0_ID = 1: by hand",
        {"bus.i2c.address": 0x1E, "enabled": True, "off": False, "gain": 1 / 3, "limit": 300},
        notes=["a note"],
        indices={"bus.i2c.address": 4, "enabled": 5, "off": 6, "gain": 7, "limit": 8},
    )
    proposal.instances.append(instance)
    proposal.used.add("A")
    assert proposal.airframe().splitlines()[2:] == [
        "",
        "# TST#0: CAL_MAG0_ID = 1: by hand",
        "param add TST#0",
        "# [4] bus.i2c.address",
        "param set-default TST#0[4] 0x1E",
        "# [5] enabled",
        "param set-default TST#0[5] 1",
        "# [6] off",
        "param set-default TST#0[6] 0",
        "# [7] gain",
        "param set-default TST#0[7] 0.333333333",
        "# [8] limit",
        "param set-default TST#0[8] 300",
    ]
    report = proposal.report()
    assert (
        "Instances proposed:\n  TST#0: CAL_MAG0_ID = 1: by hand\n"
        "    bus.i2c.address = 0x1E, enabled = 1, off = 0, gain = 0.333333333, limit = 300\n"
        "    note: a note\n"
    ) in report
    assert report.endswith(
        "Unchanged: 1 other parameters stay classic parameters (calibration, tuning, ...); "
        "the manifest does not replace them.\n"
    )
    instance.values["gain"] = float("inf")
    document = proposal.as_dict()
    assert document["version"] == "1.14.0" and document["table"] == "px4-v1.14"
    assert document["instances"][0]["values"]["gain"] == "inf"
    assert document["instances"][0]["values"]["limit"] == 300
    assert document["unchanged"] == 1 and document["parameters"] == 2


def test_a_proposals_whole_report_written_out_by_hand() -> None:
    config = migrate.OldConfig(
        "vehicle.ulg", "ULog", {"A": 1, "B": 2, "C": 3}, details=["ver_hw X", "ver_sw y"],
        skipped=["component 100: 1 parameters (not the autopilot's)"],
    )  # fmt: skip
    proposal = migrate.Proposal(
        config,
        table="px4-v1.11",
        instances=[
            migrate.ProposedInstance(
                "INA238#0",
                "SENS_EN_INA238 = 1",
                {"current": 300, "shunt": 0.5},
                ["a note"],
                indices={"current": 5, "shunt": 6},
            )
        ],
        left_out=[
            migrate.LeftOut(
                "CAL_MAG1_ID", "IST8310", "board", "CAL_MAG1_ID: the board's", "no start at main"
            )
        ],
        assumptions=["bus 1 assumed"],
        board="px4_fmu-v5",
        compared=["v1.15.0", "main"],
        replaced=["SENS_EN_INA238"],
        disabled=["SENS_EN_INA226", "SENS_EN_INA228"],
        not_carried=["INA238_CONFIG = 3: no field"],
        used={"A"},
    )
    assert proposal.report() == (
        "Migration of vehicle.ulg (ULog, 3 parameters)\n"
        "  ver_hw X\n"
        "  ver_sw y\n"
        "  device IDs decoded with the px4-v1.11 devtype table\n"
        "  board: px4_fmu-v5\n"
        "  the board's scripts compared with PX4 v1.15.0 .. main\n"
        "\n"
        "Instances proposed:\n"
        "  INA238#0: SENS_EN_INA238 = 1\n"
        "    current = 300, shunt = 0.5\n"
        "    note: a note\n"
        "\n"
        "Sensors found but not in the manifest:\n"
        "  CAL_MAG1_ID: the board's\n"
        "    later: no start at main\n"
        "\n"
        "Not known, assumed:\n"
        "  bus 1 assumed\n"
        "\n"
        "Replaced by the manifest:\n"
        "  SENS_EN_INA238\n"
        "  not enabled, nothing to carry over: SENS_EN_INA226, SENS_EN_INA228\n"
        "\n"
        "Not carried over:\n"
        "  INA238_CONFIG = 3: no field\n"
        "  component 100: 1 parameters (not the autopilot's)\n"
        "\n"
        "Unchanged: 2 other parameters stay classic parameters (calibration, tuning, ...); the "
        "manifest does not replace them.\n"
    )
    document = proposal.as_dict()
    assert document == {
        "source": "vehicle.ulg",
        "kind": "ULog",
        "parameters": 3,
        "details": ["ver_hw X", "ver_sw y"],
        "log_cut": False,
        "table": "px4-v1.11",
        "board": "px4_fmu-v5",
        "version": None,
        "target_release": None,
        "compared_releases": ["v1.15.0", "main"],
        "assumptions": ["bus 1 assumed"],
        "left_out": [
            {"found": "CAL_MAG1_ID", "device": "IST8310", "reason": "board",
             "line": "CAL_MAG1_ID: the board's", "later": "no start at main"},
        ],
        "instances": [
            {"name": "INA238#0", "origin": "SENS_EN_INA238 = 1",
             "values": {"current": 300, "shunt": 0.5}, "indices": {"current": 5, "shunt": 6},
             "notes": ["a note"]},
        ],
        "not_in_manifest": ["CAL_MAG1_ID: the board's"],
        "replaced": ["SENS_EN_INA238"],
        "disabled": ["SENS_EN_INA226", "SENS_EN_INA228"],
        "not_carried": [
            "INA238_CONFIG = 3: no field", "component 100: 1 parameters (not the autopilot's)",
        ],
        "unchanged": 2,
        "airframe": proposal.airframe(),
    }  # fmt: skip


def test_a_text_file_too_large_for_a_parameter_file_is_named_with_the_limit(
    tmp_path: Path,
) -> None:
    """Not a ULog (no magic), and over the 16 MiB a parameter file may have: refused, one
    line, before anything is read (a sparse file: nothing is written to disk)."""
    path = tmp_path / "huge.params"
    with open(path, "wb") as f:
        f.truncate(16 * 1024 * 1024 + 1)
    with pytest.raises(migrate.MigrationError) as refused:
        migrate.read_config(path)
    assert str(refused.value) == (
        f"{path}: cannot read: too large for a parameter file (16 MiB; at most 16 MiB)"
    )


@pytest.mark.parametrize(
    ("field", "value", "hw_type"),
    [
        ("char[9] ver_hw_subtype", b"V6X005000", "V6X005000"),
        ("char[0] ver_hw_subtype", b"", None),  # a board without a subtype
        ("uint32_t ver_hw_subtype", (5).to_bytes(4, "little"), None),  # not PX4's string
        ("char[9] ver_hw_subtypes", b"V6X005000", None),  # another key
    ],
)
def test_a_logs_hardware_type_is_its_ver_hw_subtype_string(
    tmp_path: Path, field: str, value: bytes, hw_type: str | None
) -> None:
    """PX4's logger writes px4_board_sub_type(), what ``ver hwtypecmp`` compares, as the
    information field ``char[N] ver_hw_subtype`` (src/modules/logger/logger.cpp)."""
    import struct

    from test_devid import _key_value, _message

    data = b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0)
    data += _message("B", bytes(8) + bytes(8) + bytes(3 * 8))
    data += _message("I", _key_value(field, value))
    data += _message("P", _key_value("int32_t SYS_AUTOSTART", struct.pack("<i", 4001)))
    log = tmp_path / "subtype.ulg"
    log.write_bytes(data)
    config = migrate.read_config(log)
    assert config.params == {"SYS_AUTOSTART": 4001}
    assert config.hw_type == hw_type


def test_nested_ifs_make_their_lines_conditional_until_their_fi(tmp_path: Path) -> None:
    path = tmp_path / "vehicle.airframe"
    path.write_text(
        "if param compare SYS_AUTOSTART 4001; then if param compare SENS_EN_INA238 1; then\n"
        "  param set CAL_MAG1_PRIO 50\n"
        "  fi\n"
        "  param set CAL_MAG2_PRIO 75\n"
        "fi\n"
        "param set SENS_EN_INA226 1\n"
    )
    config = migrate.read_config(path)
    assert config.params == {"CAL_MAG1_PRIO": 50, "CAL_MAG2_PRIO": 75, "SENS_EN_INA226": 1}
    assert config.details == [
        "'param set' inside if ... fi (lines 2, 4): read as if every condition held"
    ]
    assert config.skipped == []


def test_a_file_of_two_vehicles_is_refused_as_import_refuses_it(tmp_path: Path) -> None:
    # migrate took vehicle 2's CAL_MAG1_ID as this vehicle's ("hold the same device").
    path = tmp_path / "two.params"
    path.write_text("1\t1\tCAL_MAG0_ID\t592905\t6\n2\t1\tCAL_MAG1_ID\t592905\t6\n")
    with pytest.raises(migrate.MigrationError) as refused:
        migrate.read_config(path)
    assert str(refused.value) == (
        f"{path}:2: vehicle 2: the file holds parameters of vehicles 1, 2 (one vehicle's are "
        "read: split the file)"
    )


def test_a_value_set_twice_is_said_where_a_shell_list_keeps_the_last() -> None:
    # (a `param set` list setting CAL_MAG1_ID twice kept the second silently: the first
    # device, an IST8310, appeared nowhere in the report)
    import tempfile

    text = (
        "param set CAL_MAG1_ID 396809\n"
        "param set CAL_MAG1_ROT 0\n"
        "param set CAL_MAG1_ID 592905\n"
        "param set CAL_MAG1_ROT 0\n"
    )
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "list.params"
        path.write_text(text)
        config = migrate.read_config(path)
    assert config.params["CAL_MAG1_ID"] == 592905  # NSH runs both lines
    assert config.skipped == [
        "line 1: CAL_MAG1_ID 396809: set again on line 3 (592905), which holds"
    ]


def test_a_qgc_line_given_twice_alike_is_read_once_and_said() -> None:
    import tempfile

    line = "1\t1\tCAL_MAG1_ID\t396809\t6\n"
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "joined.params"
        path.write_text(line + "1\t1\tSYS_AUTOSTART\t4001\t6\n" + line)
        config = migrate.read_config(path)
    assert config.params == {"CAL_MAG1_ID": 396809, "SYS_AUTOSTART": 4001}
    assert config.skipped == ["line 3: CAL_MAG1_ID again, as on line 1"]
