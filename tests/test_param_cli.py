"""`px4params param ...` and `px4params run`: every verb, and bad input with its message."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from px4params.cli.main import main

TALK = """\
param add INA238#0
param set-default INA238#0[3] 1
param set-default INA238#0[4] 0x45
param set-default INA238#0[5] 200
param set-default INA238#0[6] 0.0003
"""


@pytest.fixture
def store(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    path = tmp_path / "vehicle.store"
    monkeypatch.setenv("PX4PARAMS_STORE", str(path))
    monkeypatch.delenv("PX4PARAMS_PARAMETERS_JSON", raising=False)
    return path


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def param(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    return run(capsys, "param", *argv)


def airframe(tmp_path: Path, text: str, name: str = "test.airframe") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def talk(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert run(capsys, "run", airframe(tmp_path, TALK, "talk.airframe"))[0] == 0


def test_the_talks_five_lines(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    talk(capsys, tmp_path)
    code, out, _ = param(capsys, "show")
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == "Symbols: x = used, + = saved, * = unsaved"
    assert lines[1] == (
        "    INA238#0 [-1,12] : {bus: {i2c: {bus_id: 1, address: 69}}, current: 200, shunt: 0.0003}"
    )
    code, out, _ = param(capsys, "show", "-l", "INA238#0")
    assert code == 0
    rows = [line.split() for line in out.splitlines()]
    assert rows == [
        ["[0]", "p_version", "uint4", "1", "1"],
        ["[1]", "bus._tag", "uint3", "0", "0"],
        ["[2]", "bus.i2c.p_version", "uint4", "0", "0"],
        ["[3]", "bus.i2c.bus_id", "uint4", "1", "1"],
        ["[4]", "bus.i2c.address", "uint7", "69", "69"],
        ["[5]", "current", "uint10", "200", "200", "A"],
        ["[6]", "shunt", "float16", "0.0003", "0.0003", "Ohm"],
    ]

    # One leaf, by path or [k], or the leaves under a path.
    for name, paths in (
        ("INA238#0.current", ["current"]),
        ("INA238#0[4]", ["bus.i2c.address"]),
        ("INA238#0.bus", ["bus._tag", "bus.i2c.p_version", "bus.i2c.bus_id", "bus.i2c.address"]),
        ("INA238#0.bus.i2c", ["bus.i2c.p_version", "bus.i2c.bus_id", "bus.i2c.address"]),
    ):
        code, out, _ = param(capsys, "show", "-l", name)
        assert code == 0
        assert [line.split()[1] for line in out.splitlines()] == paths, name


def test_set_changes_and_marks_unsaved_then_saved(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    talk(capsys, tmp_path)
    assert param(capsys, "set", "INA238#0.bus.i2c.address", "0x46")[0] == 0
    _, out, _ = param(capsys, "show", "-c")
    assert "  + INA238#0 [-1,12] : {bus: {i2c: {bus_id: 1, address: 70}}" in out
    _, out, _ = param(capsys, "show", "--json", "INA*")
    [row] = json.loads(out)
    assert row["value"]["bus"]["i2c"]["address"] == 70
    assert row["default"]["bus"]["i2c"]["address"] == 69
    assert row["changed"] and row["saved"]


def test_add_rm_instances_find_status(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert param(capsys, "add", "INA238", "INA238") == (0, "INA238#0\nINA238#1\n", "")
    assert param(capsys, "add", "AK09916#2")[0] == 0
    assert param(capsys, "rm", "INA238#0")[0] == 0
    assert param(capsys, "instances", "INA238") == (0, "INA238#1\n", "")
    assert param(capsys, "instances", "INA238", "--json") == (0, '["INA238#1"]\n', "")
    assert param(capsys, "find", "INA238#1") == (0, "Found param INA238 at index 12\n", "")
    _, out, _ = param(capsys, "status", "--json")
    status = json.loads(out)
    assert status["instances"] == 2 and status["store"] == str(store)
    _, out, _ = param(capsys, "status")
    assert "instances: 2 (AK09916#2, INA238#1)" in out


def test_whole_values_as_json(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    param(capsys, "add", "INA238#0")
    value = (
        '{"bus": {"spi": {"bus_id": 1, "chip_select": 2, "max_frequency": 8000, "mode": 0}}, '
        '"current": 10, "shunt": 0.001}'
    )
    assert param(capsys, "set", "INA238#0", value)[0] == 0
    assert param(capsys, "show", "-q", "INA238#0.bus.spi.chip_select") == (0, "2\n", "")
    assert param(capsys, "compare", "INA238#0", value)[0] == 0


def test_classic_parameters(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert param(capsys, "set", "SYS_AUTOSTART", "4001")[0] == 0
    assert param(capsys, "set", "BAT1_CAPACITY", "5000.5", "fail")[0] == 0
    assert param(capsys, "show", "-q", "SYS_AUTOSTART") == (0, "4001\n", "")
    assert param(capsys, "compare", "SYS_AUTOSTART", "1", "4001")[0] == 0
    assert param(capsys, "compare", "SYS_AUTOSTART", "1")[0] == 1
    assert param(capsys, "greater", "BAT1_CAPACITY", "5000")[0] == 0
    assert param(capsys, "greater", "BAT1_CAPACITY", "6000")[0] == 1
    _, out, _ = param(capsys, "show", "-a", "BAT1_*")
    assert "  + BAT1_CAPACITY [-1,44] : 5000.5" in out
    assert "    BAT1_N_CELLS [-1,43] : 0" in out
    assert param(capsys, "reset", "BAT1_*")[0] == 0
    assert param(capsys, "show", "-q", "BAT1_CAPACITY") == (0, "-1\n", "")
    assert param(capsys, "reset_all", "SYS_AUTOSTART")[0] == 0
    assert param(capsys, "show", "-q", "SYS_AUTOSTART") == (0, "4001\n", "")


def test_compare_floats_as_stored(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    talk(capsys, tmp_path)
    assert param(capsys, "compare", "INA238#0[6]", "0.0003")[0] == 0  # float16 of 0.0003
    assert param(capsys, "compare", "INA238#0.current", "0xc8")[0] == 0
    assert param(capsys, "greater", "INA238#0.current", "199")[0] == 0
    assert param(capsys, "compare", "-s", "NOPE#0", "1") == (1, "", "")


def test_save_load_import(store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    talk(capsys, tmp_path)
    backup = tmp_path / "backup.store"
    code, out, _ = param(capsys, "save", str(backup))
    assert code == 0 and out.startswith(f"saved {backup} (")
    param(capsys, "rm", "INA238#0")
    param(capsys, "add", "INA226#1")
    assert param(capsys, "import", str(backup))[0] == 0
    assert param(capsys, "instances", "INA238")[1] == "INA238#0\n"
    assert param(capsys, "instances", "INA226")[1] == "INA226#1\n"
    assert param(capsys, "load", str(backup))[0] == 0
    assert param(capsys, "instances", "INA226")[1] == ""
    assert param(capsys, "touch", "INA238#0")[0] == 0


@pytest.mark.parametrize("name", ["saved.params", "saved.json", "SAVED.PARAMS"])
def test_save_writes_what_the_extension_names_and_load_reads_it_back(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    # docs/store.md: save, load and import choose by the extension. save wrote a binary store
    # to x.params, which load then refused as "not a text file".
    talk(capsys, tmp_path)
    path = tmp_path / name
    code, out, err = param(capsys, "save", str(path))
    assert (code, err) == (0, "") and out == f"saved {path} ({path.stat().st_size} bytes)\n"
    text = path.read_text()
    if name.lower().endswith(".params"):
        assert text.startswith("# Onboard parameters for Vehicle 1") and "INA238_0C" in text
    else:
        assert json.loads(text)["format"] == "px4params"
    param(capsys, "rm", "INA238#0")
    assert param(capsys, "load", str(path))[:3:2] == (0, "")
    assert param(capsys, "show", "-q", "INA238#0.bus.i2c.address")[1] == "69\n"


@pytest.mark.parametrize("name", ["forced.params", "forced.json"])
def test_a_forced_value_exported_loads_back_with_force(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    # 'param set --force' stored 500 beyond INA238's @max 327; its export was refused by load
    # and import, with no way to take it.
    talk(capsys, tmp_path)
    assert param(capsys, "set", "--force", "INA238#0.current", "500")[0] == 0
    path = tmp_path / name
    assert param(capsys, "export", str(path))[0] == 0
    param(capsys, "reset", "INA238#0")
    before = store.read_bytes()
    where = f"{path}:9: INA238_0P" if name.endswith(".params") else f"{path}: instances"
    broken = f"{where}: INA238#0.current: 500 is outside 1..327 (@min/@max)"
    for verb in ("load", "import"):
        code, out, err = param(capsys, verb, str(path))
        assert (code, out) == (1, "") and store.read_bytes() == before
        assert err == f"px4params: error: {broken} ('param {verb} --force' takes it)\n"
    code, _, err = param(capsys, "load", "--force", str(path))
    assert (code, err) == (0, f"px4params: warning: --force: {broken}; stored anyway\n")
    assert param(capsys, "show", "-q", "INA238#0.current")[1] == "500\n"


def test_a_forced_default_in_a_json_export_loads_back_with_force(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    talk(capsys, tmp_path)
    assert param(capsys, "set-default", "--force", "INA238#0.current", "400")[0] == 0
    path = tmp_path / "default.json"
    assert param(capsys, "export", str(path))[0] == 0
    assert json.loads(path.read_text())["instances"]["INA238#0"]["default"]["current"] == 400
    broken = f"{path}: instances: INA238#0.current: 400 is outside 1..327 (@min/@max)"
    code, _, err = param(capsys, "load", str(path))
    assert (code, err) == (1, f"px4params: error: {broken} ('param load --force' takes it)\n")
    code, _, err = param(capsys, "load", "--force", str(path))
    assert (code, err) == (0, f"px4params: warning: --force: {broken}; stored anyway\n")
    assert param(capsys, "show", "-q", "INA238#0.current")[1] == "400\n"


@pytest.mark.parametrize(
    ("verb", "line", "refused"),
    [
        # beyond @max 327 and beyond a uint10: "stored anyway" was said before the type refused
        (
            "import",
            "INA238_0P\t2000\t6",
            "INA238#0: current: value 2000 is out of range (expected 0 to 1023)",
        ),
        (
            "load",
            "INA238_0Q\tnan\t9",
            "INA238#0.shunt: nan is not a finite number (float16: NaN and infinities are refused)",
        ),
    ],
)
def test_force_takes_no_nan_and_nothing_beyond_the_type_from_a_file(
    store: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    verb: str,
    line: str,
    refused: str,
) -> None:
    talk(capsys, tmp_path)
    path = tmp_path / "forced.params"
    path.write_text(f"1\t1\t{line}\n")
    before = store.read_bytes()
    code, _, err = param(capsys, verb, "--force", str(path))
    name = line.partition("\t")[0]
    assert (code, err) == (1, f"px4params: error: {path}:1: {name}: {refused}\n")
    assert store.read_bytes() == before


@pytest.mark.parametrize(
    ("given", "shown"), [("-1e-3", "-0.001"), ("-1E+2", "-100"), ("-0x10", "-16"), ("-.5", "-0.5")]
)
def test_a_negative_value_in_any_notation_is_a_value_not_an_option(
    store: Path, capsys: pytest.CaptureFixture[str], given: str, shown: str
) -> None:
    # argparse took -1e-3 and -0x10 for unknown options: "the following arguments are
    # required: value".
    assert param(capsys, "set", "BAT1_CAPACITY", given) == (0, "", "")
    assert param(capsys, "show", "-q", "BAT1_CAPACITY")[1] == f"{shown}\n"


def test_a_negative_infinity_gets_the_stores_refusal(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = param(capsys, "set", "BAT1_CAPACITY", "-inf")
    assert (code, err) == (
        1,
        "px4params: error: BAT1_CAPACITY: -inf is not a finite number (Float: NaN and "
        "infinities are refused)\n",
    )


@pytest.mark.parametrize(
    ("argv", "where", "given"),
    [
        (["set", "INA238#0.shunt", "1e999"], "INA238#0.shunt", "1e999"),
        (["set", "INA238#0[6]", "-1e400"], "INA238#0[6]", "-1e400"),
        (["set", "INA238#0", '{"shunt": 1e999}'], "INA238#0", "1e999"),
        (["set", "BAT1_CAPACITY", "1e309"], "BAT1_CAPACITY", "1e309"),
        (["set-default", "INA238#0.shunt", "1e999"], "INA238#0.shunt", "1e999"),
    ],
)
def test_a_float_beyond_float64_is_refused_without_suggesting_infinity(
    store: Path,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    where: str,
    given: str,
) -> None:
    # The refusal said "(write inf or -inf for infinity)", which the store then refused too.
    assert param(capsys, "add", "INA238#0")[0] == 0
    before = store.read_bytes()
    code, _, err = param(capsys, *argv)
    assert (code, err) == (
        1,
        f"px4params: error: {where}: {given} is out of range of a float64 (a stored float is a "
        "finite number)\n",
    )
    assert store.read_bytes() == before


def test_load_says_which_instances_its_reset_removed(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A classic-only .params file loaded over a store with two sensors removed both without a
    # word (load is "reset, then load", as PX4's is): the vehicle lost its devices silently.
    talk(capsys, tmp_path)
    param(capsys, "add", "INA226#1")
    classic = tmp_path / "classic.params"
    classic.write_text("1\t1\tSYS_AUTOSTART\t4001\t6\n")
    code, out, err = param(capsys, "load", str(classic))
    assert (code, err) == (0, "")
    assert out == (
        f"removed 2 instances not in {classic}: INA226#1, INA238#0 ('param load' resets the "
        "store first; 'param import' keeps what a file does not name)\n"
    )
    assert param(capsys, "instances", "INA238")[1] == param(capsys, "instances", "INA226")[1] == ""
    # What the file brings back is not said to be removed; import removes nothing.
    backup = tmp_path / "backup.store"
    talk(capsys, tmp_path)
    param(capsys, "save", str(backup))
    param(capsys, "add", "INA226#1")
    assert param(capsys, "load", str(backup))[1] == (
        f"removed 1 instance not in {backup}: INA226#1 ('param load' resets the store first; "
        "'param import' keeps what a file does not name)\n"
    )
    param(capsys, "add", "INA226#1")
    assert param(capsys, "import", str(classic))[1] == ""
    assert param(capsys, "instances", "INA238")[1] == "INA238#0\n"
    assert param(capsys, "instances", "INA226")[1] == "INA226#1\n"


def test_run_if_then_else_and_variables(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = """\
# a startup script
set ADDR 0x45

param add INA238#0
if param compare INA238#0.bus.i2c.address 0x45
then
  echo already at the default address
else
  param set INA238#0.bus.i2c.address ${ADDR}
  if param greater INA238#0.current 100
  then
    param set INA238#0.current 100
  fi
fi
param set SYS_AUTOSTART 4001
"""
    code, out, err = run(capsys, "run", airframe(tmp_path, text))
    assert (code, err) == (0, "")
    assert out == "INA238#0\nalready at the default address\n"
    assert param(capsys, "show", "-q", "INA238#0.current")[1] == "327\n"


def test_run_is_all_or_nothing(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    param(capsys, "add", "INA226#0")
    before = store.read_bytes()
    text = (
        "param add INA238#0\nparam set INA238#0[4] 0x45\nparam set INA238#0[4] 300\n"
        "param add RM3100#0\n"
    )
    path = airframe(tmp_path, text)
    code, _, err = run(capsys, "run", path)
    assert code == 1
    assert err == (
        f"px4params: error: {path}:3: INA238#0: bus.i2c.address: value 300 is out of range "
        "(expected 0 to 127)\n"
    )
    assert store.read_bytes() == before
    code, _, err = run(capsys, "run", path, "--keep-going")
    assert code == 1
    assert param(capsys, "instances", "RM3100")[1] == "RM3100#0\n"  # what succeeded is kept
    assert param(capsys, "show", "-q", "INA238#0[4]")[1] == "69\n"


def test_keep_going_past_an_if_whose_condition_fails_runs_neither_branch(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A misspelt parameter in the condition: PX4's `param compare` fails, so its `if` takes
    # the else branch on a vehicle; here the line is an error, and --keep-going must not run
    # both branches (nor call then/else/fi orphans). The lines after the block run.
    param(capsys, "add", "INA238#1")
    param(capsys, "set", "BAT1_N_CELLS", "3")
    text = (
        "if param compare SYS_AUTOSTRT 4001\nthen\n  param set BAT1_N_CELLS 4\nelse\n"
        "  param set BAT1_N_CELLS 6\n  param rm INA238#1\nfi\nparam add RM3100#0\n"
    )
    path = airframe(tmp_path, text)
    code, _, err = run(capsys, "run", path, "--keep-going")
    assert code == 1
    assert err.splitlines() == [
        f"px4params: error: {path}:1: unknown parameter 'SYS_AUTOSTRT' (did you mean: "
        "SYS_AUTOSTART, "
        "SYS_AUTOCONFIG?)"
    ]
    assert param(capsys, "show", "-q", "BAT1_N_CELLS")[1] == "3\n"
    assert param(capsys, "instances", "INA238")[1] == "INA238#1\n"
    assert param(capsys, "instances", "RM3100")[1] == "RM3100#0\n"


BAD_PARAM = [
    (
        ["add", "INA238#4"],
        "INA238#4: instance 4 is out of range (max_instances is 4: instances 0..3)",
    ),
    (["add", "NOPE"], "unknown parameter 'NOPE'"),
    (["add", "INA283"], "unknown parameter 'INA283' (did you mean: INA238"),
    (["add", "SYS_AUTOSTART"], "SYS_AUTOSTART: a classic parameter has no instances to add"),
    (["add", "INA238#0[4]"], "add takes an instance, not a leaf: INA238#0[4]"),
    (["add", "INA238#x"], "'INA238#x' is not a parameter name"),
    (["rm", "INA238#3"], "INA238#3: instance does not exist (add it first: param add)"),
    (["rm", "SYS_AUTOSTART"], "SYS_AUTOSTART: a classic parameter has no instances to remove"),
    (
        ["set", "INA238#0", '{"shunt": 0.001, "shunt": 0.002}'],
        "INA238#0: the key 'shunt' is given twice in one object",
    ),
    # a misspelt exclude reset the very value it was to keep, exit 0
    (
        ["reset_all", "SYS_AUTOSTRAT"],
        "unknown parameter 'SYS_AUTOSTRAT' (did you mean: SYS_AUTOSTART?)",
    ),
    (["set", "INA238#3[4]", "1"], "INA238#3: instance does not exist"),
    (
        ["set", "INA238#0[4]", "0x4G"],
        "INA238#0[4]: '0x4G' is not an integer (expected decimal or 0x hex, e.g. 69 or 0x45)",
    ),
    (["set", "INA238#0[4]", "69.5"], "INA238#0[4]: '69.5' is not an integer"),
    (["set", "INA238#0[4]", ""], "INA238#0[4]: '' is not an integer"),
    (
        ["set", "INA238#0[4]", "200"],
        "INA238#0: bus.i2c.address: value 200 is out of range (expected 0 to 127)",
    ),
    (
        ["set", "INA238#0[4]", "-1"],
        "INA238#0: bus.i2c.address: value -1 is out of range (expected 0 to 127)",
    ),
    (
        ["set", "INA238#0[6]", "abc"],
        "INA238#0[6]: 'abc' is not a number (expected e.g. 0.0003, 2e-4 or 5)",
    ),
    (
        ["set", "INA238#0[6]", "1e9"],
        # (the field's @min/@max, not a float16's -65504..65504)
        "INA238#0.shunt: 1000000000 is outside 0.00001..0.1 (@min/@max)",
    ),
    (
        ["set", "INA238#0[0]", "1"],
        "INA238#0: p_version is set automatically to the type's version and cannot be written",
    ),
    (["set", "INA238#0[9]", "1"], "INA238#0: no leaf [9] (the value has 7 leaves: [0]..[6])"),
    (
        ["set", "INA238#0.bus.spi.bus_id", "1"],
        "INA238#0: bus.spi: this union variant is not the selected one",
    ),
    (["set", "INA238#0.bus", "1"], "INA238#0: bus: not a leaf (a struct, union or array)"),
    (["set", "INA238#0.nope", "1"], "INA238#0: no such field"),
    (["set", "INA238#0.bus._tag", "7"], "INA238#0: bus: value 7 is out of range (expected 0 to 5)"),
    (
        ["set", "INA238#0", "{bad"],
        "INA238#0: a whole value is JSON (Expecting property name enclosed in double quotes",
    ),
    (["set", "INA238#0", '{"current": 1}'], "INA238#0: bus: missing field"),
    (["set", "INA238#0", "[1]"], "INA238#0: expected a dict (struct), got list"),
    (["set", "INA238#0", "1", "now"], "unexpected 'now' after the value (only 'fail' may follow)"),
    (["set", "SYS_AUTOSTART", "40.5"], "SYS_AUTOSTART: '40.5' is not an integer"),
    (
        ["set", "SYS_AUTOSTART", "99999999999"],
        "SYS_AUTOSTART: value 99999999999 is out of range (expected -2147483648 to 2147483647)",
    ),
    (["set", "BAT1_CAPACITY", "lots"], "BAT1_CAPACITY: 'lots' is not a number"),
    (["set", "BAT1_CAPACITY", "1e40"], "BAT1_CAPACITY: value 1e+40 does not fit a float32"),
    (
        ["set", "SYS_AUTOSTART#1", "1"],
        "SYS_AUTOSTART is not instanced: write SYS_AUTOSTART, not SYS_AUTOSTART#1",
    ),
    (["set", "INA238", "1"], "INA238 has instances: name one, e.g. INA238#0"),
    (
        ["set-default", "INA238#0[5]", "2000"],
        "INA238#0.current: 2000 is outside 1..327 (@min/@max)",
    ),
    (
        # With --force the type's range still holds, and nothing is said stored.
        ["set", "--force", "INA238#0[5]", "2000"],
        "INA238#0: current: value 2000 is out of range (expected 0 to 1023)",
    ),
    (["set-default", "NOPE", "1"], "unknown parameter 'NOPE'"),
    (["compare", "NOPE", "1"], "unknown parameter 'NOPE'"),
    (["compare", "INA238#0[4]", "x"], "INA238#0[4]: 'x' is not an integer"),
    (["greater", "INA238#0", "{}"], "INA238#0: greater compares numbers, not whole values"),
    (["show", "-l", "INA238#3"], "INA238#3: instance does not exist"),
    (["show", "-l"], "show -l takes one instance, e.g. show -l INA238#0"),
    (["show", "-q", "INA*"], "show -q takes one exact name"),
    (
        ["show", "-l", "INA238#0.bus.spi"],
        "INA238#0.bus.spi: no such leaf in the value (show -l INA238#0 lists its leaves)",
    ),
    (["show", "-l", "INA238#0[7]"], "INA238#0[7]: no such leaf in the value"),
    (["show", "-l", "SYS_AUTOSTART"], "SYS_AUTOSTART is a classic parameter: it has no leaves"),
    (["reset", "INA238#2"], "INA238#2: instance does not exist"),
    (["instances", "NOPE"], "unknown parameter 'NOPE'"),
    (["find", "NOPE"], "unknown parameter 'NOPE'"),
    (
        ["load", "/nonexistent/x.store"],
        "/nonexistent/x.store: cannot read: No such file or directory",
    ),
    (["import", "/nonexistent/x.store"], "/nonexistent/x.store: cannot read"),
    (
        ["save", "/nonexistent/dir/x.store"],
        "/nonexistent/dir/x.store: cannot write: No such file or directory",
    ),
]


@pytest.mark.parametrize(("argv", "message"), BAD_PARAM, ids=[" ".join(a) for a, _ in BAD_PARAM])
def test_bad_input(
    store: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    param(capsys, "add", "INA238#0")
    before = store.read_bytes()
    code, _, err = param(capsys, *argv)
    assert code == 1
    assert err.startswith("px4params: error: ")
    assert message in err, err
    assert err.count("\n") == 1
    assert store.read_bytes() == before


def test_a_file_that_is_not_a_store(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store.write_bytes(b"garbage that is not ours")
    code, _, err = param(capsys, "show")
    assert code == 1
    assert (
        err
        == f"px4params: error: {store}: not a px4params store file (no PX4P header) (at byte 0)\n"
    )
    assert store.read_bytes() == b"garbage that is not ours"


BAD_RUN = [
    ("param set-default INA238#0[4] 0x45\n", 1, "INA238#0: instance does not exist"),
    (
        "param add INA238#0\nparam frobnicate\n",
        2,
        "param: argument VERB: invalid choice: 'frobnicate'",
    ),
    ("param add\n", 1, "param: the following arguments are required: NAME"),
    (
        "ina238 -X -b 1 start\n",
        1,
        "unknown command 'ina238' (airframe files run param, set, echo and if/then/else/fi)",
    ),
    ("set X\n", 1, "set takes a variable name and one value: set VAR value"),
    ("param set SYS_AUTOSTART $NOPE\n", 1, "$NOPE is not set (set NOPE value)"),
    (
        # PX4's airframes (ROMFS/px4fmu_common/init.d/airframes/4001_quad_x, line 11) source
        # their type's defaults: $R was the error named, and setting it did not help.
        "# @name Generic Quadcopter\n\n. ${R}etc/init.d/rc.mc_defaults\n",
        3,
        "'. ${R}etc/init.d/rc.mc_defaults' runs another script, which px4params does not (a "
        "file runs its own lines: copy the param lines of that script in, or leave the line "
        "out)",
    ),
    ("source x.sh\n", 1, "'source x.sh' runs another script, which px4params does not"),
    ("if param compare SYS_AUTOSTART 0\nparam add INA238#0\n", 2, "expected 'then' after 'if'"),
    ("then\n", 1, "'then' without 'if'"),
    ("fi\n", 1, "'fi' without 'if'"),
    (
        "if param compare SYS_AUTOSTART 0\nthen\nelse\nelse\nfi\n",
        4,
        "'else' must follow 'then' once",
    ),
    ("if param compare SYS_AUTOSTART 0\nthen\n", 1, "'if' without 'fi'"),
    (
        "if param set SYS_AUTOSTART 1\nthen\nfi\n",
        1,
        "'if' takes a 'param compare' or 'param greater' command",
    ),
    ("param set SYS_AUTOSTART 'unterminated\n", 1, "No closing quotation"),
    ("then extra\n", 1, "'then' stands alone on its line"),
]


@pytest.mark.parametrize(("text", "line", "message"), BAD_RUN, ids=[m for _, _, m in BAD_RUN])
def test_bad_airframe_lines(
    store: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    text: str,
    line: int,
    message: str,
) -> None:
    path = airframe(tmp_path, text)
    code, _, err = run(capsys, "run", path)
    assert code == 1
    assert err.startswith(f"px4params: error: {path}:{line}: "), err
    assert message in err
    assert err.count("\n") == 1
    assert not store.exists()


def test_run_missing_file(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "run", "/nonexistent.airframe")
    assert (code, err) == (
        1,
        "px4params: error: /nonexistent.airframe: cannot read: No such file or directory\n",
    )


def test_usage_errors_exit_2() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "px4params", "param", "set", "INA238#0[4]"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "the following arguments are required: value" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_every_verb_has_help_with_an_example() -> None:
    from px4params.cli.main import build_parser
    from px4params.nsh.param import VERBS

    build_parser()
    assert set(VERBS) >= {
        "add",
        "rm",
        "set",
        "set-default",
        "show",
        "reset",
        "reset_all",
        "compare",
        "greater",
        "save",
        "load",
        "import",
        "status",
        "find",
        "instances",
    }
    for verb in VERBS:
        proc = subprocess.run(
            [sys.executable, "-m", "px4params", "param", verb, "--help"],
            capture_output=True,
            text=True,
        )
        assert proc.returncode == 0
        assert "example:\n  px4params param " in proc.stdout


def test_destructured_names_set_the_same_leaf(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    talk(capsys, tmp_path)
    assert param(capsys, "set", "INA238_0C", "0x46")[0] == 0
    assert param(capsys, "show", "-q", "INA238#0[4]") == (0, "70\n", "")
    code, out, _ = param(capsys, "flat", "--json", "INA238_0*")
    rows = {row["name"]: row for row in json.loads(out)}
    assert rows["INA238_0C"]["leaf"] == "INA238#0[4]"
    assert rows["INA238_0C"]["value"] == 70
    assert code == 0


@pytest.mark.parametrize("suffix", [".params", ".json"])
def test_export_and_import_other_formats(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    talk(capsys, tmp_path)
    param(capsys, "add", "INA238#2")
    param(capsys, "set", "INA238#2.bus._tag", "1")
    param(capsys, "set", "INA238#2.bus.spi.chip_select", "3")
    param(capsys, "set", "BAT1_CAPACITY", "5000")
    exported = tmp_path / f"vehicle{suffix}"
    code, out, _ = param(capsys, "export", str(exported))
    assert code == 0 and out.startswith(f"wrote {exported} (")
    if suffix == ".params":
        lines = exported.read_text().splitlines()
        assert "1\t1\tINA238_0C\t69\t6" in lines
        assert "1\t1\tBAT1_CAPACITY\t5000.000000000000000000\t9" in lines
    other = tmp_path / "other.store"
    assert param(capsys, "--store", str(other), "import", str(exported))[0] == 0
    for name in ("INA238#0", "INA238#2"):
        assert param(capsys, "--store", str(other), "show", "-q", name) == param(
            capsys, "show", "-q", name
        )
    assert param(capsys, "--store", str(other), "show", "-q", "BAT1_CAPACITY")[1] == "5000\n"


BAD_FILES = [
    (
        "x.params",
        "1\t1\tSYS_AUTOSTART\t4001\n",
        "x.params:1: expected 5 TAB-separated columns "
        "(vehicle-id, component-id, name, value, type), got 4",
    ),
    ("x.params", "1\t1\tSYS_AUTOSTART\t4001\t7\n", "x.params:1: SYS_AUTOSTART: type '7' is not 6"),
    (
        "x.params",
        "1\t1\tSYS_AUTOSTART\tmany\t6\n",
        "x.params:1: SYS_AUTOSTART: value 'many' is not",
    ),
    (
        "x.params",
        "#\n1\t1\tINA238_0C\t300\t6\n",
        "x.params:2: INA238_0C: INA238#0: bus.i2c.address: value 300",
    ),
    ("x.json", "{", "x.json:1: not JSON: Expecting property name"),
    ("x.json", '{"format": "other"}', 'not a px4params JSON export (no "format": "px4params")'),
    ("x.json", '{"format": "px4params", "version": 2}', "JSON export version 2 (expected 1)"),
    ("x.json", '{"format": "px4params", "version": 1.0}', "JSON export version 1.0 (expected 1)"),
    # Python's own words were "maximum recursion depth exceeded while decoding a JSON array"
    ("x.json", "[" * 100_000, "x.json: JSON nested deeper than this reader goes ("),
    # an instance beyond max_instances was "not a destructured parameter name"
    (
        "x.params",
        "1\t1\tINA238_9P\t150\t6\n",
        "x.params:1: INA238_9P: instance 9 is out of range (max_instances is 4: instances 0..3)",
    ),
    (
        "x.json",
        '{"format": "px4params", "version": 1, "instances": {"INA238#9": {}}}',
        "x.json: instances: INA238#9: instance 9 is out of range",
    ),
    (
        "x.json",
        '{"format": "px4params", "version": 1, "classic": {"SYS_AUTOSTART": "x"}}',
        "x.json: classic: SYS_AUTOSTART: expected an integer, got 'x'",
    ),
    # JSON leaves a key named twice open; the last one was taken silently
    (
        "x.json",
        '{"format": "px4params", "version": 1, "classic": {"SYS_AUTOSTART": 4001, '
        '"SYS_AUTOSTART": 4002}}',
        "x.json: the key 'SYS_AUTOSTART' is given twice in one object",
    ),
]


@pytest.mark.parametrize(("name", "text", "message"), BAD_FILES, ids=[m for *_, m in BAD_FILES])
def test_bad_parameter_files(
    store: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    name: str,
    text: str,
    message: str,
) -> None:
    param(capsys, "add", "INA238#1")
    before = store.read_bytes()
    path = tmp_path / name
    path.write_text(text)
    code, _, err = param(capsys, "import", str(path))
    assert code == 1
    assert message in err, err
    assert err.count("\n") == 1
    assert store.read_bytes() == before


def test_unknown_names_in_params_files_are_reported(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "x.params"
    path.write_text("1\t1\tMPC_XY_VEL_MAX\t8.5\t9\n1\t1\tSYS_AUTOSTART\t4001\t6\n")
    code, out, _ = param(capsys, "import", str(path))
    assert code == 0
    assert out == (
        f"{path}:1: MPC_XY_VEL_MAX: not a parameter of this store; skipped\n"
        f"{path}: 1 parameters not in this store were skipped\n"
    )


def test_shell_completion(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    param(capsys, "add", "INA238#1")
    code, out, _ = run(capsys, "completion", "names")
    names = out.splitlines()
    assert code == 0
    assert {"INA238", "INA238#0", "INA238#3", "SYS_AUTOSTART"} <= set(names)
    assert "INA238#1.bus.i2c.address" in names
    code, script, _ = run(capsys, "completion", "bash")
    assert code == 0 and "complete -F _px4params px4params" in script
    bash = subprocess.run(
        [
            "bash",
            "-c",
            script + "COMP_WORDS=(px4params param set-d); COMP_CWORD=2; _px4params; "
            'echo "${COMPREPLY[@]}"',
        ],
        capture_output=True,
        text=True,
    )
    assert bash.stdout.split() == ["set-default"]


def test_shell_completion_reads_the_store_the_command_line_names(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Names came from $PX4PARAMS_STORE (or ./px4params.store) whatever --store the line gave:
    # 'param --store other.store set AK09916#0.<TAB>' completed nothing.
    other = tmp_path / "other.store"
    assert run(capsys, "param", "--store", str(other), "add", "AK09916#0")[0] == 0
    _, script, _ = run(capsys, "completion", "bash")
    env = {**os.environ, "PX4PARAMS_STORE": str(tmp_path / "empty.store")}
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env['PATH']}"
    for words in (
        f"param --store {other} set AK09916#0.bus.i2c.b",
        f"param set --store {other} AK09916#0.bus.i2c.b",  # (after the verb too)
    ):
        bash = subprocess.run(
            ["bash", "-c", f"{script}COMP_WORDS=(px4params {words}); "
             "COMP_CWORD=$((${#COMP_WORDS[@]} - 1)); _px4params; echo \"${COMPREPLY[@]}\""],
            capture_output=True, text=True, env=env, timeout=60,
        )  # fmt: skip
        assert bash.stdout.split() == ["AK09916#0.bus.i2c.bus_id"], (words, bash.stderr)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["add", "INA238#70000"], "INA238#70000: instance 70000 is out of range"),
        (["set", "INA238#0[99999999999]", "1"], "INA238#0[99999999999]: no leaf [99999999999]"),
        (["show", "INA238#0.current"], "show lists instances and parameters; for the leaf"),
        (["touch", "INA238#0[4]"], "touch takes an instance or parameter, not a leaf"),
    ],
)
def test_more_bad_names(
    store: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    param(capsys, "add", "INA238#0")
    code, _, err = param(capsys, *argv)
    assert code == 1
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_import_of_a_store_merges_existing_instances(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    param(capsys, "add", "INA238#0")
    param(capsys, "set", "INA238#0.current", "100")
    backup = tmp_path / "backup.store"
    param(capsys, "save", str(backup))
    param(capsys, "set", "INA238#0.current", "50")
    assert param(capsys, "import", str(backup))[0] == 0
    assert param(capsys, "import")[0] == 0  # the store's own file, instances and all
    assert param(capsys, "show", "-q", "INA238#0.current")[1] == "100\n"


def test_a_failing_run_writes_no_file(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    copy, export = tmp_path / "copy.store", tmp_path / "x.params"
    text = (
        f"param add INA238#0\nparam save\nparam save {copy}\nparam export {export}\n"
        "param set INA238#0[4] 300\n"
    )
    assert run(capsys, "run", airframe(tmp_path, text))[0] == 1
    assert not store.exists() and not copy.exists() and not export.exists()
    good = text.replace("300", "70")
    assert run(capsys, "run", airframe(tmp_path, good))[0] == 0
    assert store.exists() and copy.exists() and export.exists()
    # Each file holds the store as it was at its line (as PX4's shell writes it), written once
    # the whole file had succeeded; the store's own file holds the end.
    assert "1\t1\tINA238_0C\t69\t6" in export.read_text()
    assert param(capsys, "show", "-q", "INA238#0[4]")[1] == "70\n"
    assert param(capsys, "--store", str(copy), "show", "-q", "INA238#0[4]")[1] == "69\n"


@pytest.mark.parametrize(
    ("target", "reason"),
    [
        ("{tmp}/gone/x.store", "cannot write: No such file or directory"),
        ("{tmp}", "cannot write: a directory, not a regular file"),
        ("{tmp}/fifo", "cannot write: a FIFO, not a regular file"),
    ],
    ids=["no-folder", "folder", "fifo"],
)
def test_a_run_whose_save_cannot_be_written_saves_nothing(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], target: str, reason: str
) -> None:
    # The store was saved, then the write of the later file failed: exit 1 ("nothing of the
    # file is kept") with the store changed and the first copy written.
    os.mkfifo(tmp_path / "fifo")
    assert param(capsys, "add", "AK09916#0")[0] == 0
    before = store.read_bytes()
    good, bad = tmp_path / "good.store", target.format(tmp=tmp_path)
    text = f"param rm AK09916#0\nparam save {good}\nparam save {bad}\n"
    path = airframe(tmp_path, text)
    code, out, err = run(capsys, "run", path)
    assert (code, out) == (1, "")
    assert err == f"px4params: error: {path}:3: {bad}: {reason}\n"
    assert store.read_bytes() == before and not good.exists()
    # The same for an export (a .params), and without --keep-going or with it.
    text = f"param rm AK09916#0\nparam export {tmp_path}/gone/x.params\n"
    assert run(capsys, "run", airframe(tmp_path, text), "--keep-going")[0] == 1
    assert store.read_bytes() != before  # --keep-going keeps the lines that succeeded
    assert not (tmp_path / "gone").exists()


def test_a_run_does_not_save_over_its_own_airframe_file_or_its_store_by_another_name(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # 'param save FILE' of the airframe file itself replaced it with a store file (exit 0); of
    # the store through a symbolic link, the copy at that line replaced what the run saved.
    path = tmp_path / "self.airframe"
    path.write_text(f"param add INA238#0\nparam save {path}\n")
    code, _, err = run(capsys, "run", str(path))
    assert code == 1
    assert err == (
        f"px4params: error: {path}:2: {path}: is the file this run reads ({path}): give it "
        "another name\n"
    )
    assert path.read_text().startswith("param add") and not store.exists()
    assert param(capsys, "add", "AK09916#0")[0] == 0
    link = tmp_path / "link.store"
    link.symlink_to(store)
    text = f"param rm AK09916#0\nparam save {link}\nparam add INA238#2\n"
    assert run(capsys, "run", airframe(tmp_path, text))[0] == 0
    assert param(capsys, "instances", "INA238")[1] == "INA238#2\n"
    assert "AK09916" not in param(capsys, "show")[1]
    assert link.is_symlink()


def test_a_backup_saved_before_changes_holds_the_store_before_them(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # 'param save' and 'param export' of another file wrote the end state: a backup taken
    # first held the changes it was meant to undo.
    talk(capsys, tmp_path)
    assert param(capsys, "add", "INA238#1")[0] == 0
    before = store.read_bytes()
    backup, exported = tmp_path / "backup.store", tmp_path / "backup.params"
    text = (
        f"param save {backup}\nparam export {exported}\nparam rm INA238#1\n"
        "param set INA238#0.current 150\n"
    )
    assert run(capsys, "run", airframe(tmp_path, text))[0] == 0
    assert param(capsys, "show", "-q", "INA238#0.current")[1] == "150\n"
    assert param(capsys, "--store", str(backup), "show", "-q", "INA238#0.current")[1] == "200\n"
    assert "INA238#1" in param(capsys, "--store", str(backup), "show")[1]
    assert "1\t1\tINA238_1C\t" in exported.read_text()
    # The backup is the store as it was, byte for byte.
    assert backup.read_bytes() == before


@pytest.mark.parametrize(("autostart", "bus"), [("4001", "2"), ("0", "1")])
def test_a_variable_set_in_a_branch_is_read_only_where_that_branch_runs(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], autostart: str, bus: str
) -> None:
    # $BUS was expanded in the branch that does not run, where it is not set: the file was
    # refused on every vehicle but the one the branch is for.
    assert param(capsys, "set", "SYS_AUTOSTART", autostart)[0] == 0
    text = (
        "param add INA238#1\nif param compare SYS_AUTOSTART 4001\nthen\n  set BUS 2\n"
        "  param set-default INA238#1.bus.i2c.bus_id $BUS\nelse\n"
        "  param set-default INA238#1.bus.i2c.bus_id 1\nfi\n"
    )
    assert run(capsys, "run", airframe(tmp_path, text))[0] == 0
    assert param(capsys, "show", "-q", "INA238#1.bus.i2c.bus_id")[1] == f"{bus}\n"
    # A variable set nowhere is still refused where its line runs.
    path = airframe(tmp_path, "if param compare SYS_AUTOSTART 0\nthen\necho $NOPE\nfi\n")
    code, _, err = run(capsys, "run", path)
    assert (code == 1) == (autostart == "0")
    assert err == (
        ""
        if autostart != "0"
        else f"px4params: error: {path}:3: $NOPE is not set (set NOPE value)\n"
    )


def test_reset_of_one_leaf(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    param(capsys, "add", "INA238#0")
    param(capsys, "set", "INA238#0.current", "300")
    param(capsys, "set", "INA238#0[4]", "0x46")
    assert param(capsys, "reset", "INA238#0[4]")[0] == 0
    assert param(capsys, "show", "-q", "INA238#0[4]")[1] == "69\n"
    assert param(capsys, "show", "-q", "INA238#0.current")[1] == "300\n"


def test_reset_all_keeps_what_is_excluded(store: Path, capsys: pytest.CaptureFixture[str]) -> None:
    param(capsys, "add", "INA238#0")
    param(capsys, "add", "AK09916#0")
    param(capsys, "set", "INA238#0.current", "300")
    param(capsys, "set", "AK09916#0.rotation", "2")
    param(capsys, "set", "SYS_AUTOSTART", "4001")
    assert param(capsys, "reset_all", "INA238", "SYS_AUTOSTART")[0] == 0
    assert param(capsys, "show", "-q", "INA238#0.current")[1] == "300\n"
    assert param(capsys, "show", "-q", "SYS_AUTOSTART")[1] == "4001\n"
    assert param(capsys, "show", "-q", "AK09916#0.rotation")[1] == "0\n"


def test_flat_names_work_in_every_verb(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    talk(capsys, tmp_path)
    assert param(capsys, "compare", "INA238_0C", "69")[0] == 0
    assert param(capsys, "greater", "INA238_0P", "199")[0] == 0
    assert param(capsys, "show", "-q", "INA238_0C") == (0, "69\n", "")
    param(capsys, "set", "INA238_0C", "70")
    assert param(capsys, "reset", "INA238_0C")[0] == 0
    assert param(capsys, "show", "-q", "INA238#0[4]")[1] == "69\n"


def test_a_damaged_store_points_to_its_backup(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    param(capsys, "add", "INA238#0")
    param(capsys, "add", "INA238#1")  # the first save is now the backup
    data = bytearray(store.read_bytes())
    data[-1] ^= 1
    store.write_bytes(bytes(data))
    code, _, err = param(capsys, "show")
    assert code == 1
    assert f"the previous save is in {store}.bak: px4params param load {store}.bak" in err
    backup = Path(f"{store}.bak").read_bytes()
    code, out, _ = param(capsys, "load", f"{store}.bak")  # the way back
    assert code == 0
    assert param(capsys, "instances", "INA238")[1] == "INA238#0\n"
    # The last good save stays where the refusal pointed, and the damaged file is set aside:
    # the first save over it made it the .bak (helper-110).
    assert f"kept the damaged {store} as {store}.damaged; {store}.bak is unchanged" in out
    assert Path(f"{store}.bak").read_bytes() == backup
    assert Path(f"{store}.damaged").read_bytes() == bytes(data)
    recovered = store.read_bytes()
    param(capsys, "add", "INA238#2")  # and the next save keeps its backup as before
    assert Path(f"{store}.bak").read_bytes() == recovered != store.read_bytes()


def test_saved_files_are_readable_by_others(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import os

    old = os.umask(0o022)
    try:
        param(capsys, "add", "INA238#0")
    finally:
        os.umask(old)
    assert store.stat().st_mode & 0o777 == 0o644


def test_a_flat_name_that_is_not_live_says_why(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    talk(capsys, tmp_path)
    assert param(capsys, "set", "INA238_0A", "1")[0] == 0  # SPI: the I2C leaves are not live
    code, _, err = param(capsys, "set", "INA238_0C", "70")
    assert code == 1
    assert err == (
        "px4params: error: INA238_0C (INA238#0.bus.i2c.address) is not live: bus._tag selects "
        "variant 1, not 0 (set INA238_0A to 0)\n"
    )
    code, _, err = param(capsys, "set", "INA238_3C", "70")
    assert (code, err) == (
        1,
        "px4params: error: INA238_3C belongs to INA238#3, which does not exist "
        "(add it first: param add INA238#3)\n",
    )


def test_a_binary_airframe_file_says_which_byte_is_not_text(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # It said "not a text file (invalid start byte)": the codec's words, and no byte.
    path = tmp_path / "binary.airframe"
    path.write_bytes(b"param set SYS_AUTOSTART 4001\n\x89PNG")
    code, out, err = run(capsys, "run", str(path))
    assert (code, out) == (1, "")
    assert (
        err == f"px4params: error: {path}: not a text file: byte 0x89 at offset 29 is not UTF-8\n"
    )


def test_set_default_s_of_a_parameter_this_build_lacks_lets_the_script_run_on(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # PX4's do_set_custom_default: with -s an unknown name fails silently (status 1) and its
    # script runs on. A run stopped at it with "param set-default failed", naming nothing.
    path = airframe(tmp_path, "param set-default -s NOPE 1\nparam set SYS_AUTOSTART 4001\n")
    assert run(capsys, "run", path) == (0, "", "")
    assert param(capsys, "show", "-q", "SYS_AUTOSTART")[1] == "4001\n"
    assert param(capsys, "set-default", "-s", "NOPE", "1") == (1, "", "")
    # Without -s the name is refused, and the file stops there.
    path = airframe(tmp_path, "param set-default NOPE 1\nparam set SYS_AUTOSTART 1\n")
    code, _, err = run(capsys, "run", path)
    assert code == 1 and err.startswith(f"px4params: error: {path}:1: ") and "NOPE" in err
    assert param(capsys, "show", "-q", "SYS_AUTOSTART")[1] == "4001\n"


@pytest.mark.parametrize("outermost", ["0", "4001"])
def test_deeply_nested_ifs_run_as_nested_and_in_time_linear_in_the_lines(
    store: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    outermost: str,
) -> None:
    # Every line asked every open block whether it ran: 12,000 nested ifs took 16 s. Counted,
    # not timed: the blocks asked per line do not grow with the depth.
    from px4params.nsh import airframe as nsh_airframe

    asked = 0
    active = nsh_airframe._Block.active

    def counted(self: nsh_airframe._Block) -> bool:
        nonlocal asked
        asked += 1
        return active(self)

    monkeypatch.setattr(nsh_airframe._Block, "active", counted)
    depth = 2000
    text = f"if param compare SYS_AUTOSTART {outermost}\nthen\n"
    text += "if param compare SYS_AUTOSTART 0\nthen\n" * depth
    text += "param set BAT1_CAPACITY 5000\nelse\nparam set BAT1_CAPACITY 7\n" + "fi\n" * (depth + 1)
    path = airframe(tmp_path, text)
    assert run(capsys, "run", path)[:2] == (0, "")
    assert param(capsys, "show", "-q", "BAT1_CAPACITY")[1] == (
        "5000\n" if outermost == "0" else "-1\n"
    )
    assert asked < 3 * len(text.splitlines())


def test_a_command_whose_output_cannot_be_written_says_its_change_was_saved(
    store: Path, tmp_path: Path
) -> None:
    # 'param add INA238 > /dev/full' failed (exit 1) with INA238#0 saved: a retry made #1, and
    # nothing said the first had been kept.
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    command = [sys.executable, "-m", "px4params", "param", "--store", str(store)]
    with open("/dev/full", "w") as full:
        done = subprocess.run([*command, "add", "INA238"], stdout=full, stderr=subprocess.PIPE,
                              text=True, timeout=60)  # fmt: skip
        shown = subprocess.run([*command, "show"], stdout=full, stderr=subprocess.PIPE,
                               text=True, timeout=60)  # fmt: skip
    assert (done.returncode, done.stderr) == (
        1,
        "px4params: error: cannot write the output: No space left on device (the change was "
        f"saved all the same, to {store})\n",
    )
    assert (shown.returncode, shown.stderr) == (
        1,
        "px4params: error: cannot write the output: No space left on device\n",
    )


def test_classic_values_of_another_parameter_set_are_said_where_they_are_left_out(
    store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A store saved with a full parameters.json holds MPC_XY_VEL_MAX; opened with the bundled
    # set (no --classic), export wrote a backup without it, status did not count it and
    # reset_all left it set, each without a word (load said "kept unchanged").
    full = tmp_path / "full.json"
    entry = {"name": "MPC_XY_VEL_MAX", "type": "Float", "default": 12.0}
    full.write_text(json.dumps({"version": 1, "parameters": [entry]}))
    assert param(capsys, "--classic", str(full), "set", "MPC_XY_VEL_MAX", "8")[0] == 0
    note = (
        "MPC_XY_VEL_MAX (not in this parameter set: give --classic the parameters.json that has it)"
    )
    backup = tmp_path / "backup.params"
    code, _, err = param(capsys, "export", str(backup))
    assert (code, err) == (
        0,
        f"px4params: warning: 1 classic value of the store not written to {backup}: {note}\n",
    )
    assert "MPC_XY_VEL_MAX" not in backup.read_text()
    out = param(capsys, "status")[1]
    assert "classic values of another parameter set, kept: 1 (MPC_XY_VEL_MAX)\n" in out
    assert json.loads(param(capsys, "status", "--json")[1])["kept_classic"] == 1
    code, _, err = param(capsys, "reset_all")
    assert (code, err) == (
        0,
        f"px4params: warning: 1 classic value of the store kept, not reset: {note}\n",
    )
    assert param(capsys, "--classic", str(full), "show", "-q", "MPC_XY_VEL_MAX")[1] == "8\n"


def test_the_largest_floats_are_shown_and_what_is_shown_is_taken_back(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # FLT_MAX in a classic float and 65504 (float16's largest) in the shunt: show ended in an
    # OverflowError traceback (its shortest form, 3.4028235e38 and 7e+04, is beyond the type),
    # and 3.4028235e38 was refused when typed back.
    assert param(capsys, "set", "BAT1_CAPACITY", "3.4028234663852886e38")[0] == 0
    assert param(capsys, "add", "INA238#0")[0] == 0
    assert param(capsys, "set", "--force", "INA238#0.shunt", "-65504")[0] == 0
    shown_forms = (
        ("BAT1_CAPACITY", "3.402823466e+38", ()),
        ("INA238#0.shunt", "-65500", ("--force",)),
    )
    for name, shown, force in shown_forms:  # (the shunt's @min/@max still wants --force)
        code, out, err = param(capsys, "show", "-q", name)
        assert (code, out, err) == (0, f"{shown}\n", "")
        before = store.read_bytes()
        assert param(capsys, "set", *force, name, shown)[0] == 0  # the same float, again
        assert store.read_bytes() == before
    code, out, _ = param(capsys, "show", "-l", "INA238#0")
    assert code == 0 and ["[6]", "shunt", "float16", "-65500", "0.0003", "Ohm"] in [
        line.split() for line in out.splitlines()
    ]


def test_a_store_whose_name_is_not_utf8_is_read_again_and_named_with_its_byte(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Created, then never readable: "'utf-8' codec can't encode character '\udcff'" (the
    # core's file check took the path as Rust text), naming neither the file nor the problem.
    odd = os.fsdecode(bytes(tmp_path) + b"/bad\xff.store")
    assert param(capsys, "--store", odd, "set", "SYS_AUTOSTART", "4001")[0] == 0
    assert param(capsys, "--store", odd, "show", "-q", "SYS_AUTOSTART") == (0, "4001\n", "")
    junk = os.fsdecode(bytes(tmp_path) + b"/junk\xfe.store")
    Path(junk).write_bytes(b"junk")
    code, out, err = param(capsys, "--store", junk, "show")
    assert (code, out) == (1, "")
    assert err == (
        f"px4params: error: {tmp_path}/junk\\xfe.store: not a px4params store file (no PX4P "
        "header) (at byte 0)\n"
    )


def test_save_refuses_the_stores_own_lock_file(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # 'param save vehicle.store.lock' replaced the lock file with the store's bytes (a new
    # file: a writer holding the old one would no longer keep others out).
    assert param(capsys, "set", "SYS_AUTOSTART", "4001")[0] == 0
    lock = Path(f"{store}.lock")
    before = lock.read_bytes()
    code, out, err = param(capsys, "save", str(lock))
    assert (code, out) == (1, "")
    assert err == f"px4params: error: {lock}: is {store}'s lock file: give the save another name\n"
    assert lock.read_bytes() == before and not Path(f"{lock}.bak").exists()
