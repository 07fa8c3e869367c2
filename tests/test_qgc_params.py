"""QGC .params files (px4params.formats.qgc_params): what QGC writes reads back exactly, and
the real files in ../shared/data read as QGC wrote them."""

from __future__ import annotations

import math
import os
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st
from px4params.errors import ParamFileError
from px4params.formats import qgc_params
from shared_data import shared_file


@given(
    st.floats(width=32, allow_nan=False, allow_infinity=False).filter(
        lambda v: v == 0 or abs(v) >= 1e-9  # 18 decimals: smaller ones lose digits (QGC's format)
    )
)
def test_a_float32_written_with_18_decimals_reads_back_exactly(value: float) -> None:
    (row,) = qgc_params.read(qgc_params.format_line(1, 1, "X", value, True), "f")
    assert struct.pack("<f", row.value) == struct.pack("<f", value)
    assert row.type == qgc_params.REAL32


@given(st.integers(-(2**31), 2**31 - 1))
def test_int32_reads_back(value: int) -> None:
    (row,) = qgc_params.read(qgc_params.format_line(1, 1, "X", value, False), "f")
    assert (row.value, row.type) == (value, qgc_params.INT32)


def test_non_finite_floats_are_written_readably() -> None:
    (row,) = qgc_params.read(qgc_params.format_line(1, 1, "X", math.inf, True), "f")
    assert row.value == math.inf


@pytest.mark.parametrize("name", ["qgc_offline_editing_v1.4.params", "qgc_px4_mocklink.params"])
def test_real_qgc_files(name: str) -> None:
    path = shared_file(name)
    rows = qgc_params.read(path.read_text(encoding="utf-8"), name)
    assert len(rows) > 100
    assert {r.type for r in rows} <= {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}
    assert all(isinstance(r.value, float) == (r.type in qgc_params.FLOAT_TYPES) for r in rows)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "1\t1\tA\t5\n",
            "f:1: expected 5 TAB-separated columns (vehicle-id, component-id, name, value, type), "
            "got 4",
        ),
        (
            "# c\n1\tx\tA\t5\t6\n",
            "f:2: A: vehicle-id, component-id and type must be integers, got '1', 'x', '6'",
        ),
        ("1\t1\tA\tfive\t6\n", "f:1: A: value 'five' is not a number"),
        ("1\t1\tA\t5.5\t6\n", "f:1: A: value '5.5' is not an integer (type 6)"),
    ],
)
def test_errors_name_the_line_and_field(text: str, message: str) -> None:
    with pytest.raises(ParamFileError) as caught:
        qgc_params.read(text, "f")
    assert str(caught.value) == message


def test_spaces_instead_of_tabs() -> None:
    (row,) = qgc_params.read("1 1 SYS_AUTOSTART 4001 6", "f")
    assert (row.name, row.value) == ("SYS_AUTOSTART", 4001)


# Other ground stations' parameter files, as they save them: Mission Planner (ArduPilot's
# ``.param``) writes a ``#NOTE:`` line, then NAME,VALUE comma-separated with six decimals;
# MAVProxy's ``param save`` writes NAME and VALUE padded with spaces. Neither is QGC's.
MISSION_PLANNER = (
    "#NOTE: 26/11/2026 12:00:00 Frame : Quad\nACRO_BAL_PITCH,1.000000\nACRO_BAL_ROLL,1.000000\n"
)
MAVPROXY = "ACRO_BAL_PITCH   1.000000\nACRO_BAL_ROLL    1.000000\n"
EXPECTED = "expected 5 TAB-separated columns (vehicle-id, component-id, name, value, type)"


@pytest.mark.parametrize(
    ("text", "found"),
    [
        (
            MISSION_PLANNER,
            "2: a comma-separated NAME,VALUE line (Mission Planner's parameter file)",
        ),
        (MAVPROXY, "1: a NAME VALUE line (MAVProxy's parameter file)"),
    ],
    ids=["mission-planner", "mavproxy"],
)
def test_another_ground_stations_file_is_named(text: str, found: str) -> None:
    with pytest.raises(ParamFileError) as caught:
        qgc_params.read(text, "f")
    assert str(caught.value) == f"f:{found}, not QGC's .params: {EXPECTED}"


@pytest.mark.parametrize(
    "text",
    ["1,2,3\n", "ACRO BAL PITCH,1\n", "A,one\n", "1\t1\tA\t5\n"],
    ids=["three-commas", "name-with-spaces", "value-not-a-number", "four-columns"],
)
def test_what_looks_like_no_other_format_gets_the_column_count(text: str) -> None:
    with pytest.raises(ParamFileError) as caught:
        qgc_params.read(text, "f")
    assert "Mission Planner" not in str(caught.value) and "MAVProxy" not in str(caught.value)
    assert str(caught.value).startswith(f"f:1: {EXPECTED}, got ")


@pytest.mark.parametrize("command", ["migrate", "param import"])
def test_migrate_and_param_import_name_a_mission_planner_file(tmp_path: Path, command: str) -> None:
    given = tmp_path / "copter.params"
    given.write_text(MISSION_PLANNER, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))
    env["PX4PARAMS_STORE"] = str(tmp_path / "vehicle.store")
    result = subprocess.run(
        [sys.executable, "-m", "px4params", *command.split(), str(given)],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert (result.returncode, result.stdout) == (1, "")
    assert result.stderr == (
        f"px4params: error: {given}:2: a comma-separated NAME,VALUE line (Mission Planner's "
        f"parameter file), not QGC's .params: {EXPECTED}\n"
    )
    assert not (tmp_path / "vehicle.store").exists()


@pytest.mark.parametrize("verb", ["import", "load"])
def test_mission_planners_own_extension_is_named_too(tmp_path: Path, verb: str) -> None:
    """Mission Planner saves ``.param`` files, which param load/import take for a store file:
    the error names the format, not the missing store header."""
    given = tmp_path / "copter.param"
    given.write_text(MISSION_PLANNER, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))
    env["PX4PARAMS_STORE"] = str(tmp_path / "vehicle.store")
    result = subprocess.run(
        [sys.executable, "-m", "px4params", "param", verb, str(given)],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert (result.returncode, result.stdout) == (1, "")
    assert result.stderr == (
        f"px4params: error: {given}:2: a comma-separated NAME,VALUE line (Mission Planner's "
        "parameter file), not a store file or QGC's .params: param load and import read store "
        "files, .params (QGC) and .json\n"
    )
    assert not (tmp_path / "vehicle.store").exists()


@given(st.floats(width=32, allow_nan=False, allow_infinity=False))
def test_every_finite_float32_is_written_so_that_it_reads_back_exactly(value: float) -> None:
    # 18 decimals wrote 1e-30 as 0.000000000000000000 and 1.2345678e-12 as
    # 0.000000000001234568: an export read back changed them.
    line = qgc_params.format_line(1, 1, "X", value, True)
    written = line.split("\t")[3]
    assert struct.unpack("<f", struct.pack("<f", float(written)))[0] == value


def test_floats_18_decimals_keep_are_written_as_qgc_writes_them() -> None:
    assert qgc_params.format_line(1, 1, "X", 0.5, True) == "1\t1\tX\t0.500000000000000000\t9"
    tiny = struct.unpack("<f", struct.pack("<f", 1e-30))[0]  # as a float32 parameter holds it
    assert qgc_params.format_line(1, 1, "X", tiny, True) == "1\t1\tX\t1.0000000031710769e-30\t9"
