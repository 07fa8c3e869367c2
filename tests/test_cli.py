"""Tests for the ``px4params`` command line (python/px4params/cli.py).

Exit codes, stderr and the no-traceback contract are checked through real subprocesses
(``python -m px4params``); output details also in-process through ``cli.main`` with capsys.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from px4params import load_schema
from px4params.cli.main import build_parser, main
from px4params.store.classic import BUNDLED_CLASSIC

CACHE_ENV = "PX4PARAMS_CACHE_DIR"
DSDL_PATH_ENV = "PX4PARAMS_DSDL_PATH"

GOLDEN_SOURCE = "truncated uint12 a\nint3 b\nint4 c\nint2 d\ntruncated uint4 e\n"
GOLDEN_VALUE = '{"a":48858,"b":-1,"c":-5,"d":-1,"e":136}'
GOLDEN_HEX = "daef7c00"

INA = '{"bus":{"i2c":{"bus_id":1,"address":69}},"current":200,"shunt":0.0003}'
INA_HEX = "10031720ea0c"
INA_LEAVES = [
    ("p_version", "uint4", "1"),
    ("bus._tag", "uint3", "0 (i2c)"),
    ("bus.i2c.p_version", "uint4", "0"),
    ("bus.i2c.bus_id", "uint4", "1"),
    ("bus.i2c.address", "uint7", "69 (0x45)"),
    ("current", "uint10", "200"),
    ("shunt", "float16", "0.0002999306"),
]

BATTERY = "uavcan.equipment.power.BatteryInfo"
BATTERY_VALUE: dict[str, Any] = {
    "temperature": 300,
    "voltage": 12,
    "current": 1,
    "average_power_10sec": 1,
    "remaining_capacity_wh": 1,
    "full_charge_capacity_wh": 1,
    "hours_to_full_charge": 0,
    "status_flags": 0,
    "state_of_health_pct": 100,
    "state_of_charge_pct": 50,
    "state_of_charge_pct_stdev": 1,
    "battery_id": 0,
    "model_instance_id": 0,
    "model_name": "abc",
}


def ina(**changes: Any) -> str:
    """The talk's INA238 value as JSON, with top-level fields replaced (None drops one)."""
    value: dict[str, Any] = {
        "bus": {"i2c": {"bus_id": 1, "address": 69}},
        "current": 200,
        "shunt": 0.0003,
    }
    for key, new in changes.items():
        if new is None:
            del value[key]
        else:
            value[key] = new
    return json.dumps(value)


def battery(**changes: Any) -> str:
    return json.dumps({**BATTERY_VALUE, **changes})


# --------------------------------------------------------------------------------------------------
# Fixtures and helpers


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("px4params-cache")


@pytest.fixture(scope="session")
def dsdl_dirs(tmp_path_factory: pytest.TempPathFactory) -> Mapping[str, Path]:
    """Root namespace folders, good and bad, named by what they hold."""
    base = tmp_path_factory.mktemp("dsdl")
    files = {
        "golden/Vector.uavcan": GOLDEN_SOURCE,
        "extra/Thing.uavcan": "uint8 x\n",
        # pydsdl syntax error on line 3
        "badsyntax/Thing.1.0.dsdl": "@sealed\nuint8 x\nuint8 y z\n",
        # pydronecan cannot parse line 2
        "badcan/Thing.uavcan": "uint8 x\nfoo bar baz\n",
        # unknown tag in the type's doc (line 2) and in a field's doc (line 5)
        "typetag/Thing.1.0.dsdl": "# A thing\n# @bogus 1\nuint8 x\n@sealed\n",
        "fieldtag/Thing.1.0.dsdl": "# A thing\n\nuint8 x\n# X\n# @colour red\n@sealed\n",
        "unsealed/Thing.1.0.dsdl": "uint8 x\n@extent 64\n",
        "mixed/A.uavcan": "uint8 x\n",
        "mixed/B.1.0.dsdl": "uint8 x\n@sealed\n",
    }
    for relative, text in files.items():
        path = base / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    (base / "empty").mkdir()
    (base / "plainfile").write_text("not a folder\n", encoding="utf-8")
    names = {relative.split("/")[0] for relative in files} | {"empty", "plainfile"}
    return {name: base / name for name in names} | {"missing": base / "does-not-exist"}


@pytest.fixture(scope="session")
def base_env(cache_dir: Path) -> dict[str, str]:
    env = dict(os.environ)
    env.pop(DSDL_PATH_ENV, None)
    env[CACHE_ENV] = str(cache_dir)
    return env


@pytest.fixture(autouse=True)
def _in_process_env(cache_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # For main(): the shared cache, and no extra roots from the caller's environment.
    monkeypatch.setenv(CACHE_ENV, str(cache_dir))
    monkeypatch.delenv(DSDL_PATH_ENV, raising=False)


class Cli:
    """Runs ``python -m px4params`` in a subprocess."""

    def __init__(self, env: Mapping[str, str], cwd: Path) -> None:
        self.env = dict(env)
        self.cwd = cwd

    def __call__(
        self,
        *args: str | os.PathLike[str],
        input: str | bytes | None = None,
        env: Mapping[str, str] | None = None,
    ) -> subprocess.CompletedProcess[str]:
        run_env = {**self.env, **(env or {})}
        text_mode = not isinstance(input, bytes)
        proc = subprocess.run(
            [sys.executable, "-m", "px4params", *map(os.fspath, args)],
            input=input,
            capture_output=True,
            text=text_mode,
            env=run_env,
            cwd=self.cwd,
            timeout=60,
        )
        if not text_mode:  # decode for the assertions, never losing bytes
            proc = subprocess.CompletedProcess(
                proc.args,
                proc.returncode,
                proc.stdout.decode("utf-8", "backslashreplace"),
                proc.stderr.decode("utf-8", "backslashreplace"),
            )
        assert "Traceback" not in proc.stdout + proc.stderr, proc.stderr
        return proc


@pytest.fixture(scope="session")
def run(base_env: dict[str, str], tmp_path_factory: pytest.TempPathFactory) -> Cli:
    return Cli(base_env, tmp_path_factory.mktemp("cwd"))


def ok_lines(proc: subprocess.CompletedProcess[str]) -> list[str]:
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    return proc.stdout.splitlines()


def one_error(proc: subprocess.CompletedProcess[str], *fragments: str) -> str:
    """Asserts exit 1, nothing on stdout and exactly one ``px4params: error:`` line on stderr."""
    assert proc.returncode == 1, (proc.stdout, proc.stderr)
    assert proc.stdout == ""
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    line = lines[0]
    assert line.startswith("px4params: error: "), line
    for fragment in fragments:
        assert fragment in line, f"{fragment!r} not in {line!r}"
    return line


def usage_error(proc: subprocess.CompletedProcess[str], fragment: str) -> None:
    assert proc.returncode == 2, (proc.stdout, proc.stderr)
    assert proc.stdout == ""
    assert proc.stderr.startswith("usage: px4params")
    last = proc.stderr.splitlines()[-1]
    assert re.match(r"px4params( \w+)?: error: ", last), last
    assert fragment in last


def main_out(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture
def stdin(monkeypatch: pytest.MonkeyPatch) -> Callable[[str], None]:
    def feed(text: str) -> None:
        monkeypatch.setattr(sys, "stdin", io.StringIO(text))

    return feed


# --------------------------------------------------------------------------------------------------
# Golden vector: a five-field .uavcan type given with --dsdl or the environment


def test_golden_vector_with_dsdl_option(run: Cli, dsdl_dirs: Mapping[str, Path]) -> None:
    proc = run("encode", "golden.Vector", GOLDEN_VALUE, "--dsdl", dsdl_dirs["golden"])
    assert ok_lines(proc) == [GOLDEN_HEX]


def test_golden_vector_with_env_var(run: Cli, dsdl_dirs: Mapping[str, Path]) -> None:
    # Colon-separated, with an empty component that must be ignored.
    path = f"{dsdl_dirs['extra']}::{dsdl_dirs['golden']}"
    proc = run("encode", "golden.Vector", GOLDEN_VALUE, env={DSDL_PATH_ENV: path})
    assert ok_lines(proc) == [GOLDEN_HEX]
    proc = run("encode", "extra.Thing", '{"x": 255}', env={DSDL_PATH_ENV: path})
    assert ok_lines(proc) == ["ff"]


def test_golden_type_unknown_without_its_root(run: Cli) -> None:
    one_error(run("encode", "golden.Vector", GOLDEN_VALUE), "unknown type 'golden.Vector'")


def test_golden_vector_in_process(
    dsdl_dirs: Mapping[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["encode", "golden.Vector", GOLDEN_VALUE, "--dsdl", str(dsdl_dirs["golden"])]
    assert main_out(argv, capsys) == (0, GOLDEN_HEX + "\n", "")
    # Truncated casts keep the low bits: 0xBEDA -> 0xEDA, 0x88 -> 0x8.
    argv = ["decode", "golden.Vector", GOLDEN_HEX, "--dsdl", str(dsdl_dirs["golden"])]
    code, out, err = main_out(argv, capsys)
    assert (code, err) == (0, "")
    assert json.loads(out) == {"a": 0xEDA, "b": -1, "c": -5, "d": -1, "e": 0x8}


def test_dsdl_option_is_repeatable(
    dsdl_dirs: Mapping[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    roots = ["--dsdl", str(dsdl_dirs["golden"]), "--dsdl", str(dsdl_dirs["extra"])]
    assert main_out(["encode", "extra.Thing", '{"x": 7}', *roots], capsys) == (0, "07\n", "")
    assert main_out(["encode", "golden.Vector", GOLDEN_VALUE, *roots], capsys) == (
        0,
        GOLDEN_HEX + "\n",
        "",
    )


def test_dsdl_option_and_env_var_combine(
    dsdl_dirs: Mapping[str, Path],
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv(DSDL_PATH_ENV, str(dsdl_dirs["extra"]))
    argv = ["types", "--json", "--dsdl", str(dsdl_dirs["golden"])]
    code, out, _ = main_out(argv, capsys)
    keys = {row["key"] for row in json.loads(out)}
    assert code == 0
    assert {"golden.Vector", "extra.Thing", "px.Ina238.1.1"} <= keys


def test_dsdl_relative_path(run: Cli, dsdl_dirs: Mapping[str, Path]) -> None:
    in_dsdl_folder = Cli(run.env, dsdl_dirs["golden"].parent)
    proc = in_dsdl_folder("encode", "golden.Vector", GOLDEN_VALUE, "--dsdl=golden")
    assert ok_lines(proc) == [GOLDEN_HEX]


# --------------------------------------------------------------------------------------------------
# encode / decode


def test_encode_ina238(run: Cli) -> None:
    assert ok_lines(run("encode", "px.Ina238", INA)) == [INA_HEX]


def test_encode_by_full_key_and_with_explicit_p_version(capsys: pytest.CaptureFixture[str]) -> None:
    value = json.loads(INA) | {"p_version": 1}
    argv = ["encode", "px.Ina238.1.1", json.dumps(value)]
    assert main_out(argv, capsys) == (0, INA_HEX + "\n", "")


def test_decode_ina238_fills_p_version(run: Cli) -> None:
    [line] = ok_lines(run("decode", "px.Ina238", INA_HEX))
    value = json.loads(line)
    assert value["p_version"] == 1
    assert value["bus"] == {"i2c": {"p_version": 0, "bus_id": 1, "address": 69}}
    assert value["current"] == 200
    assert value["shunt"] == pytest.approx(0.0003, rel=1e-3)
    assert set(value) == {"p_version", "bus", "current", "shunt"}


@pytest.mark.parametrize(
    "text", ["10 03 17 20 ea 0c", "0x10031720ea0c", "0X10031720EA0C", "  0x1003 1720\tEA0C  "]
)
def test_decode_accepts_spaces_case_and_0x_prefix(
    text: str, capsys: pytest.CaptureFixture[str]
) -> None:
    expected = main_out(["decode", "px.Ina238", INA_HEX], capsys)
    assert expected[0] == 0
    assert main_out(["decode", "px.Ina238", text], capsys) == expected


def test_decode_spaced_hex_in_subprocess(run: Cli) -> None:
    [line] = ok_lines(run("decode", "px.Ina238", "0x10 03 17 20 ea 0c"))
    assert json.loads(line)["bus"]["i2c"]["address"] == 69


def test_encode_decode_round_trip_is_stable(capsys: pytest.CaptureFixture[str]) -> None:
    code, decoded, _ = main_out(["decode", "px.Ina238", INA_HEX], capsys)
    assert code == 0
    assert main_out(["encode", "px.Ina238", decoded], capsys) == (0, INA_HEX + "\n", "")


def test_no_tao_differs_for_battery_model_name(capsys: pytest.CaptureFixture[str]) -> None:
    code, tao_out, _ = main_out(["encode", BATTERY, battery()], capsys)
    assert code == 0
    code, plain_out, _ = main_out(["encode", BATTERY, battery(), "--no-tao"], capsys)
    assert code == 0
    tao, plain = bytes.fromhex(tao_out.strip()), bytes.fromhex(plain_out.strip())
    assert tao != plain
    # Tail array optimization drops the 5-bit length and leaves the bytes byte-aligned.
    assert tao.endswith(b"abc")
    assert len(plain) == len(tao) + 1
    assert tao[:-4] == plain[:-5]
    # Each decodes back only with the same option.
    for hex_text, flags in ((tao_out, []), (plain_out, ["--no-tao"])):
        code, out, err = main_out(["decode", BATTERY, hex_text.strip(), *flags], capsys)
        assert (code, err) == (0, "")
        assert json.loads(out)["model_name"] == list(b"abc")
    code, out, err = main_out(["decode", BATTERY, tao_out.strip(), "--no-tao"], capsys)
    assert code == 1
    assert out == ""
    assert err.startswith("px4params: error: ") and "model_name" in err


def test_no_tao_on_ina238_changes_nothing(capsys: pytest.CaptureFixture[str]) -> None:
    # No dynamic array: tail array optimization does not apply.
    assert main_out(["encode", "px.Ina238", INA, "--no-tao"], capsys) == (0, INA_HEX + "\n", "")


@pytest.mark.parametrize(
    ("spelled", "message"),
    [
        ("NaN", 'NaN is not JSON; write "nan" (a string) instead'),
        ("Infinity", 'Infinity is not JSON; write "inf" (a string) instead'),
        ("-Infinity", '-Infinity is not JSON; write "-inf" (a string) instead'),
        ("1e400", "1e400 is out of range of a float64 (write inf or -inf for infinity)"),
        ("-1e400", "-1e400 is out of range of a float64 (write inf or -inf for infinity)"),
    ],
)
def test_non_finite_floats_are_strings_not_json_extensions(
    spelled: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """JSON has no infinities: Python's NaN/Infinity extensions and numbers beyond float64
    (which Python reads as infinity) are refused, not encoded as infinity."""
    code, out, err = main_out(["encode", "px.Ina238", INA.replace("0.0003", spelled)], capsys)
    assert (code, out, err) == (1, "", f"px4params: error: {message}\n")


@pytest.mark.parametrize(
    ("spelled", "hex_text", "shown"),
    [
        ('"nan"', "10031720ff7f", "nan"),
        ('"inf"', "10031720007c", "inf"),
        ('"-inf"', "1003172000fc", "-inf"),
    ],
)
def test_non_finite_floats(
    spelled: str, hex_text: str, shown: str, capsys: pytest.CaptureFixture[str]
) -> None:
    value = INA.replace("0.0003", spelled)
    assert main_out(["encode", "px.Ina238", value], capsys) == (0, hex_text + "\n", "")
    code, out, err = main_out(["decode", "px.Ina238", hex_text], capsys)
    assert (code, err) == (0, "")
    assert f'"shunt": "{shown}"' in out  # a JSON string: JSON has no NaN or infinity
    assert json.loads(out)["shunt"] == shown


def test_non_finite_decode_output_is_strict_json(run: Cli) -> None:
    [line] = ok_lines(run("decode", "px.Ina238", "10031720ff7f"))

    def refuse(token: str) -> None:
        raise AssertionError(f"non-standard JSON constant {token}")

    assert json.loads(line, parse_constant=refuse)["shunt"] == "nan"


def test_nan_round_trips_through_a_dronecan_type(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = main_out(["encode", BATTERY, battery(temperature="nan", voltage="-inf")], capsys)
    assert code == 0
    code, out, _ = main_out(["decode", BATTERY, out.strip()], capsys)
    value = json.loads(out)
    assert code == 0
    assert (value["temperature"], value["voltage"], value["current"]) == ("nan", "-inf", 1.0)


def test_saturate_clamps_instead_of_refusing(
    run: Cli, capsys: pytest.CaptureFixture[str], dsdl_dirs: Mapping[str, Path]
) -> None:
    too_big = ina(current=5000)
    one_error(
        run("encode", "px.Ina238", too_big),
        "current: value 5000 is out of range (expected 0 to 1023)",
    )
    assert ok_lines(run("encode", "px.Ina238", too_big, "--saturate")) == ["100317ffea0c"]
    code, out, _ = main_out(["decode", "px.Ina238", "100317ffea0c"], capsys)
    assert code == 0 and json.loads(out)["current"] == 1023

    code, out, _ = main_out(["encode", "px.Ina238", ina(current=-1), "--saturate"], capsys)
    assert code == 0
    code, out, _ = main_out(["decode", "px.Ina238", out.strip()], capsys)
    assert json.loads(out)["current"] == 0

    code, out, _ = main_out(["encode", "px.Ina238", ina(shunt=1e10), "--saturate"], capsys)
    assert code == 0
    code, out, _ = main_out(["decode", "px.Ina238", out.strip()], capsys)
    assert json.loads(out)["shunt"] == 65504.0  # float16 max, not infinity

    golden = ["--dsdl", str(dsdl_dirs["golden"])]
    value = '{"a":1,"b":-10,"c":0,"d":0,"e":0}'
    code, _, err = main_out(["encode", "golden.Vector", value, *golden], capsys)
    assert code == 1
    assert (
        err == "px4params: error: golden.Vector: b: value -10 is out of range (expected -4 to 3)\n"
    )
    code, out, _ = main_out(["encode", "golden.Vector", value, "--saturate", *golden], capsys)
    assert code == 0
    code, out, _ = main_out(["decode", "golden.Vector", out.strip(), *golden], capsys)
    assert json.loads(out)["b"] == -4


# --------------------------------------------------------------------------------------------------
# Batch use: '-' reads one item per line


def test_batch_encode(run: Cli) -> None:
    lines = [INA, ina(current=1), ina(shunt="nan")]
    proc = run("encode", "px.Ina238", "-", input="\n".join(lines) + "\n")
    assert ok_lines(proc) == [INA_HEX, "10031404ea0c", "10031720ff7f"]


def test_batch_decode(run: Cli) -> None:
    proc = run("decode", "px.Ina238", "-", input=f"{INA_HEX}\r\n0x10 03 17 20 ff 7f\n")
    out = [json.loads(line) for line in ok_lines(proc)]
    assert [v["current"] for v in out] == [200, 200]
    assert out[1]["shunt"] == "nan"


def test_batch_gives_one_line_per_line_and_blank_is_the_empty_payload(run: Cli) -> None:
    proc = run("decode", "uavcan.protocol.param.Empty", "-", input="\n\n")
    assert ok_lines(proc) == ["{}", "{}"]
    proc = run("encode", "uavcan.protocol.param.Empty", "-", input="{}\n{}\n")
    assert ok_lines(proc) == ["", ""]
    proc = run("decode", "px.Ina238", "-", input=f"{INA_HEX}\n\n{INA_HEX}\n")
    assert proc.returncode == 1
    lines = proc.stdout.splitlines()
    assert len(lines) == 3 and lines[1].startswith("error: px.Ina238.1.1: ")
    assert json.loads(lines[0]) == json.loads(lines[2])


def test_batch_encode_reports_bad_lines_and_goes_on(run: Cli) -> None:
    lines = [INA, "{bad", "", ina(current=None), ina(current=2), "[1"]
    proc = run("encode", "px.Ina238", "-", input="\n".join(lines) + "\n")
    assert proc.returncode == 1
    errors = [
        "not JSON: Expecting property name enclosed in double quotes at column 2 in '{bad'",
        "not JSON: Expecting value at column 1 in ''",
        "px.Ina238.1.1: current: missing field (give every field, or use --defaults to fill the "
        "missing ones from the type's defaults)",
        "not JSON: Expecting ',' delimiter at column 3 in '[1'",
    ]
    assert proc.stdout.splitlines() == [
        INA_HEX,
        f"error: {errors[0]}",
        f"error: {errors[1]}",
        f"error: {errors[2]}",
        "10031408ea0c",
        f"error: {errors[3]}",
    ]
    assert proc.stderr.splitlines() == [
        f"px4params: <stdin>:{n}: {e}" for n, e in zip((2, 3, 4, 6), errors, strict=True)
    ]


def test_batch_decode_one_bad_line(run: Cli) -> None:
    proc = run("decode", "px.Ina238", "-", input=f"{INA_HEX}\nxyz\n00031720ff7f\n")
    assert proc.returncode == 1
    first, error, third = proc.stdout.splitlines()
    assert error == "error: not hex bytes: 'xyz' (expected e.g. 'daef7c00')"
    first, third = json.loads(first), json.loads(third)
    assert (first["current"], third["shunt"]) == (200, "nan")
    assert proc.stderr.splitlines() == [
        "px4params: <stdin>:2: not hex bytes: 'xyz' (expected e.g. 'daef7c00')",
        # the third line's p_version is 0: px.Ina238.1.0's data
        "px4params: warning: p_version 0: the data was written by px.Ina238.1.0, and is "
        "decoded with px.Ina238.1.1's layout",
    ]


def test_batch_empty_input(run: Cli) -> None:
    assert ok_lines(run("encode", "px.Ina238", "-", input="")) == []


def test_batch_in_process(stdin: Callable[[str], None], capsys: pytest.CaptureFixture[str]) -> None:
    stdin(f"{INA_HEX}\n000317\n")
    code, out, err = main_out(["decode", "px.Ina238", "-"], capsys)
    assert code == 1
    assert json.loads(out.splitlines()[0])["current"] == 200
    assert out.splitlines()[1].startswith("error: px.Ina238.1.1: current: data is truncated")
    assert err.startswith("px4params: <stdin>:2: px.Ina238.1.1: current: data is truncated")
    assert len(err.splitlines()) == 1


def test_batch_unknown_type_is_one_error(run: Cli) -> None:
    one_error(run("encode", "px.Nope", "-", input=INA + "\n"), "unknown type 'px.Nope'")


@pytest.mark.parametrize("encoding", ["utf-8:strict", "utf-8:surrogateescape"])
def test_batch_stdin_that_is_not_text_is_named_by_line_and_byte(run: Cli, encoding: str) -> None:
    # Python hands such bytes over as surrogate escapes ('\udcff\udcfe' in the message), or
    # with a strict stdin (e.g. a en_US.UTF-8 locale) fails reading the line, ending the batch.
    proc = run(
        "decode",
        "px.Ina238",
        "-",
        input=b"\xff\xfe\n" + INA_HEX.encode() + b"\n00\xc3\n",
        env={"PYTHONIOENCODING": encoding},
    )
    assert proc.returncode == 1
    first, second, third = proc.stdout.splitlines()
    assert first == "error: not text: byte 0xFF at column 1 is not UTF-8"
    assert json.loads(second)["current"] == 200
    assert third == "error: not text: byte 0xC3 at column 3 is not UTF-8"
    assert proc.stderr.splitlines() == [
        "px4params: <stdin>:1: not text: byte 0xFF at column 1 is not UTF-8",
        "px4params: <stdin>:3: not text: byte 0xC3 at column 3 is not UTF-8",
    ]


def test_an_argument_or_frames_input_that_is_not_text_is_named(run: Cli) -> None:
    one_error(
        run("decode", "px.Ina238", "12\udcff"),
        "not text: byte 0xFF at column 3 is not UTF-8",
    )
    proc = run(
        "frames", "uavcan.protocol.NodeStatus", "-", "--source-node", "5", input=b'{"a\xe9": 1}'
    )
    one_error(proc, "not text: byte 0xE9 at column 4 is not UTF-8")


# --------------------------------------------------------------------------------------------------
# types


def test_types_text(run: Cli) -> None:
    lines = ok_lines(run("types"))
    by_key = {line.split()[0]: line for line in lines}
    assert len(by_key) == len(lines) > 20
    schema = load_schema(use_env=False)
    for key, text in (
        ("px.Ina238.1.1", "INA238 power monitor"),
        (BATTERY, "Single battery info."),
    ):
        t = schema[key]
        line = by_key[key]
        assert re.search(
            rf"\bstruct\s+{t.min_bits}\.\.{t.max_bits} bits\s+{re.escape(text)}$", line
        )
    assert re.search(r"\bstruct\s+15 bits\s+I2C bus location", by_key["px.I2c.1.0"])
    assert [line.split()[0] for line in lines] == sorted(by_key)


def test_types_json(run: Cli) -> None:
    rows = json.loads("\n".join(ok_lines(run("types", "--json"))))
    by_key = {row["key"]: row for row in rows}
    ina238, info = by_key["px.Ina238.1.1"], by_key[BATTERY]
    assert ina238["name"] == "px.Ina238"
    assert ina238["version"] == [1, 1]
    assert (ina238["kind"], ina238["dialect"]) == ("struct", "dsdl")
    assert ina238["max_instances"] == 4
    assert ina238["short"] == "INA238 power monitor"
    assert ina238["min_bits"] <= len(bytes.fromhex(INA_HEX)) * 8 <= ina238["max_bits"]
    assert ina238["min_bits"] < ina238["max_bits"]
    assert info["version"] is None
    assert (info["kind"], info["dialect"]) == ("struct", "uavcan")
    assert (info["min_bits"], info["max_bits"]) == (189, 437)  # 184 + uint5 length + 31 bytes
    assert by_key["px.Bus.1.0"]["kind"] == "union"
    for row in rows:
        assert isinstance(row["min_bits"], int) and isinstance(row["max_bits"], int)
        assert 0 <= row["min_bits"] <= row["max_bits"]


def test_types_with_dsdl_lists_the_extra_type(
    dsdl_dirs: Mapping[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, _ = main_out(["types", "--dsdl", str(dsdl_dirs["golden"])], capsys)
    assert code == 0
    [line] = [line for line in out.splitlines() if line.startswith("golden.Vector ")]
    assert re.fullmatch(r"golden\.Vector\s+struct\s+25 bits", line)  # 12 + 3 + 4 + 2 + 4
    code, out, _ = main_out(["types", "--json", "--dsdl", str(dsdl_dirs["golden"])], capsys)
    [row] = [row for row in json.loads(out) if row["key"] == "golden.Vector"]
    assert (row["min_bits"], row["max_bits"], row["version"]) == (25, 25, None)


# --------------------------------------------------------------------------------------------------
# demo and python -m


def check_demo(out: str) -> None:
    assert "10 03 17 20 ea 0c" in out
    assert "da ef 7c 00" in out
    leaves = [line.split(None, 3) for line in out.splitlines() if re.match(r"\s+\[\d+\] ", line)]
    assert leaves == [
        [f"[{k}]", path, kind, shown] for k, (path, kind, shown) in enumerate(INA_LEAVES)
    ]
    [decoded] = [line for line in out.splitlines() if line.startswith("decoded back: ")]
    assert json.loads(decoded.removeprefix("decoded back: "))["bus"]["i2c"]["address"] == 69


def test_demo(run: Cli) -> None:
    proc = run("demo")
    assert proc.returncode == 0
    assert proc.stderr == ""
    check_demo(proc.stdout)


def test_demo_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = main_out(["demo"], capsys)
    assert (code, err) == (0, "")
    check_demo(out)


def test_console_script_matches_python_m(run: Cli) -> None:
    script = shutil.which("px4params")
    assert script is not None, "the package is installed: its px4params script should be too"
    proc = subprocess.run(
        [script, "encode", "px.Ina238", INA],
        capture_output=True,
        text=True,
        env=run.env,
        timeout=60,
    )
    assert ok_lines(proc) == [INA_HEX]


def test_python_m_help(run: Cli) -> None:
    out = "\n".join(ok_lines(run("--help")))
    for command in ("types", "encode", "decode", "demo"):
        assert command in out
    encode_help = "\n".join(ok_lines(run("encode", "--help")))
    assert "--saturate" in encode_help and "--no-tao" in encode_help and "--dsdl" in encode_help
    assert "--saturate" not in "\n".join(ok_lines(run("decode", "--help")))


# --------------------------------------------------------------------------------------------------
# Errors: exit 1, one line, no traceback


ERRORS: list[tuple[str, list[str], list[str]]] = [
    # (id, argv, fragments of the one error line)
    (
        "unknown-type-suggest",
        ["encode", "px.Ina23", INA],
        ["unknown type 'px.Ina23' (did you mean: px.Ina238", "?)"],
    ),
    (
        "unknown-type-no-suggestion",
        ["decode", "zzzzzzz", INA_HEX],
        ["unknown type 'zzzzzzz' (see 'px4params types')"],
    ),
    (
        "unknown-type-version",
        ["encode", "px.Ina238.9.9", INA],
        ["unknown type 'px.Ina238.9.9' (did you mean: ", "px.Ina238.1.1"],
    ),
    (
        "invalid-json",
        ["encode", "px.Ina238", "{bad"],
        ["not JSON: Expecting property name enclosed in double quotes at column 2 in '{bad'"],
    ),
    ("empty-json", ["encode", "px.Ina238", ""], ["not JSON: Expecting value at column 1"]),
    (
        "json-huge-integer",
        ["encode", "px.Ina238", '{"current": ' + "1" * 5000 + "}"],
        ["111111111111...111111 (5000 characters) is out of range (5000 digits"],
    ),
    (
        "json-too-deep",
        ["encode", "px.Ina238", "[" * 100_000],
        ["error: JSON nested deeper than this reader goes ("],
    ),
    ("invalid-hex", ["decode", "px.Ina238", "zz"], ["not hex bytes: 'zz' (expected e.g."]),
    ("odd-hex", ["decode", "px.Ina238", "0x123"], ["not hex bytes: '0x123'"]),
    (
        "out-of-range-nested",
        ["encode", "px.Ina238", INA.replace("69", "200")],
        ["px.Ina238.1.1: bus.i2c.address: value 200 is out of range (expected 0 to 127)"],
    ),
    (
        "out-of-range-negative",
        ["encode", "px.Ina238", ina(current=-1)],
        ["current: value -1 is out of range (expected 0 to 1023)"],
    ),
    (
        "out-of-range-float16",
        ["encode", "px.Ina238", ina(shunt=1e10)],
        ["shunt: value 10000000000 is out of range (expected -65504 to 65504)"],
    ),
    (
        "out-of-range-huge-int",
        ["encode", "px.Ina238", ina(current=10**30)],
        [f"current: value {10**30} is out of range"],
    ),
    (
        "unknown-field",
        ["encode", "px.Ina238", ina(foo=1)],
        ["unknown field 'foo' (expected: p_version, bus, current, shunt)"],
    ),
    ("missing-field", ["encode", "px.Ina238", ina(current=None)], ["current: missing field"]),
    (
        "missing-nested-field",
        ["encode", "px.Ina238", ina(bus={"i2c": {"bus_id": 1}})],
        ["bus.i2c.address: missing field"],
    ),
    (
        "p-version-set",
        ["encode", "px.Ina238", ina(p_version=3)],
        ["p_version: p_version is set automatically; got 3"],
    ),
    (
        "union-two-variants",
        ["encode", "px.Ina238", ina(bus={"i2c": {"bus_id": 1, "address": 1}, "spi": {}})],
        [
            "bus: a union takes exactly one variant (i2c, spi, serial, dronecan, sim, mavlink)",
            "2 keys",
        ],
    ),
    (
        "union-no-variant",
        ["encode", "px.Ina238", ina(bus={})],
        ["bus: a union takes exactly one variant", "got 0 keys"],
    ),
    (
        "union-unknown-variant",
        ["encode", "px.Ina238", ina(bus={"usb": {}})],
        ["bus: unknown union variant 'usb' (expected one of: i2c, spi,"],
    ),
    (
        "union-not-a-dict",
        ["encode", "px.Ina238", ina(bus=[1])],
        ["bus: expected a dict with one key, the union variant", "got list"],
    ),
    (
        "struct-not-a-dict",
        ["encode", "px.Ina238", "[1, 2]"],
        ["expected a dict (struct), got list"],
    ),
    ("null-value", ["encode", "px.Ina238", "null"], ["expected a dict (struct), got NoneType"]),
    (
        "string-for-int",
        ["encode", "px.Ina238", ina(current="x")],
        ["current: expected an integer, got str"],
    ),
    (
        "float-for-int",
        ["encode", "px.Ina238", ina(current=1.5)],
        ["current: expected an integer, got float"],
    ),
    (
        "bool-for-int",
        ["encode", "px.Ina238", ina(current=True)],
        ["current: expected an integer, got bool"],
    ),
    (
        "bad-float-string",
        ["encode", BATTERY, battery(temperature="bogus")],
        [f'{BATTERY}: temperature: expected a number (or "nan", "inf", "-inf"), got \'bogus\''],
    ),
    (
        "array-too-long",
        ["encode", BATTERY, battery(model_name="a" * 32)],
        ["model_name: array has 32 elements, at most 31 allowed"],
    ),
    (
        "lone-surrogate",
        ["encode", BATTERY, battery(model_name="\udcff")],
        ["model_name: expected a str encodable as UTF-8 (it has lone surrogates)"],
    ),
    (
        "truncated",
        ["decode", "px.Ina238", "100317"],
        ["px.Ina238.1.1: current: data is truncated: needs at least 32 bits, has 24"],
    ),
    ("empty-data", ["decode", "px.Ina238", ""], ["p_version: data is truncated"]),
    (
        "trailing-bytes",
        ["decode", "px.Ina238", INA_HEX + "00"],
        ["data is too long: the value ends after 6 bytes, the data has 7"],
    ),
    (
        "bad-union-tag-7",
        ["decode", "px.Ina238", "0e031720ea0c"],
        ["bus: union tag 7 selects no variant (expected 0..5) (at bit 4)"],
    ),
    (
        "bad-union-tag-6",
        ["decode", "px.Ina238", "0c031720ea0c"],
        ["bus: union tag 6 selects no variant (expected 0..5)"],
    ),
]


@pytest.mark.parametrize(("argv", "fragments"), [e[1:] for e in ERRORS], ids=[e[0] for e in ERRORS])
def test_error(run: Cli, argv: list[str], fragments: list[str]) -> None:
    one_error(run(*argv), *fragments)


DSDL_ERRORS: list[tuple[str, str, str, str, str]] = [
    # (root folder, file in it or "", text after "<path>", how it is passed, command)
    ("badsyntax", "Thing.1.0.dsdl", ":3: Syntax error", "option", "types"),
    ("badsyntax", "Thing.1.0.dsdl", ":3: Syntax error", "env", "encode"),
    ("badcan", "Thing.uavcan", ":2: Type definition not found [foo]", "option", "decode"),
    (
        "typetag",
        "Thing.1.0.dsdl",
        ":2: unknown metadata tag @bogus (expected one of: @category, @group,",
        "option",
        "types",
    ),
    (
        "fieldtag",
        "Thing.1.0.dsdl",
        ":5: unknown metadata tag @colour (expected one of: @bit, @decimal,",
        "env",
        "types",
    ),
    ("unsealed", "Thing.1.0.dsdl", ":2: unsealed.Thing.1.0 is not @sealed", "option", "types"),
    ("missing", "", ": DSDL root namespace folder does not exist", "option", "encode"),
    ("missing", "", ": DSDL root namespace folder does not exist", "env", "types"),
    ("plainfile", "", ": DSDL root namespace folder does not exist", "option", "types"),
    ("empty", "", ": DSDL root contains no .dsdl or .uavcan files", "option", "demo"),
    (
        "mixed",
        "",
        ": DSDL root mixes .dsdl (pydsdl) and .uavcan (DroneCAN) files",
        "option",
        "types",
    ),
]

COMMAND_ARGV = {
    "types": ["types"],
    "encode": ["encode", "px.Ina238", INA],
    "decode": ["decode", "px.Ina238", INA_HEX],
    "demo": ["demo"],
}


@pytest.mark.parametrize(
    ("root", "file", "message", "how", "command"),
    DSDL_ERRORS,
    ids=[f"{e[0]}-{e[3]}-{e[4]}" for e in DSDL_ERRORS],
)
def test_dsdl_error(
    run: Cli,
    dsdl_dirs: Mapping[str, Path],
    root: str,
    file: str,
    message: str,
    how: str,
    command: str,
) -> None:
    folder = dsdl_dirs[root]
    where = str(folder / file) if file else str(folder)
    argv = COMMAND_ARGV[command]
    if how == "option":
        proc = run(*argv, "--dsdl", folder)
    else:  # a good root first: every component of the path is loaded
        proc = run(*argv, env={DSDL_PATH_ENV: f"{dsdl_dirs['golden']}:{folder}"})
    line = one_error(proc, where + message)
    assert line.startswith(f"px4params: error: {where}")


def test_dsdl_error_in_process(
    dsdl_dirs: Mapping[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    path = dsdl_dirs["badsyntax"] / "Thing.1.0.dsdl"
    code, out, err = main_out(["demo", "--dsdl", str(dsdl_dirs["badsyntax"])], capsys)
    assert (code, out) == (1, "")
    assert err == f"px4params: error: {path}:3: Syntax error\n"


def test_error_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = main_out(["decode", "px.Ina238", "10031720ea0c00"], capsys)
    assert (code, out) == (1, "")
    assert err == (
        "px4params: error: px.Ina238.1.1: data is too long: "
        "the value ends after 6 bytes, the data has 7 (at bit 48)\n"
    )


# --------------------------------------------------------------------------------------------------
# Usage errors: exit 2 from argparse


USAGE_ERRORS = [
    ([], "the following arguments are required: COMMAND"),
    (["bogus"], "invalid choice: 'bogus'"),
    (["encode"], "the following arguments are required: TYPE, VALUE"),
    (["decode", "px.Ina238"], "the following arguments are required: HEX"),
    (["encode", "px.Ina238", INA, "--bogus"], "unrecognized arguments: --bogus"),
    (["decode", "px.Ina238", INA_HEX, "--saturate"], "unrecognized arguments: --saturate"),
    (["types", "--dsdl"], "argument --dsdl: expected one argument"),
    (["demo", "extra"], "unrecognized arguments: extra"),
]


@pytest.mark.parametrize(("argv", "fragment"), USAGE_ERRORS, ids=lambda v: str(v)[:30])
def test_usage_error(run: Cli, argv: list[str], fragment: str) -> None:
    usage_error(run(*argv), fragment)


def test_usage_error_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["encode", "px.Ina238"])
    assert exit_info.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "error: the following arguments are required: VALUE" in captured.err


# -- px4params --version -----------------------------------------------------------------------
# What works without options: ``px4params --version`` and ``autostart run`` without
# ``--bench`` (a bench where every configured device is present and healthy).


REPO = Path(__file__).resolve().parents[1]


def test_version_names_package_core_and_dsdl_set() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "px4params", "--version"], capture_output=True, text=True
    )
    assert (proc.returncode, proc.stderr) == (0, "")
    package = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["version"]
    core = tomllib.loads((REPO / "Cargo.toml").read_text())["workspace"]["package"]["version"]
    files = sorted((REPO / "python/px4params/data/dsdl/px").rglob("*.dsdl"))
    digest = hashlib.sha256()
    for f in files:
        digest.update(f.relative_to(REPO / "python/px4params/data/dsdl/px").as_posix().encode())
        digest.update(b"\0" + f.read_bytes() + b"\0")
    assert proc.stdout.splitlines() == [
        f"px4params {package}",
        f"core {core} (Rust, px4params-core; store file format 3)",
        f"DSDL px: {len(files)} types (bundled), sha256 {digest.hexdigest()[:16]}",
    ]
    assert len(files) >= 40


def test_version_first_ends_the_parse(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version", "param", "show"]) == 0
    assert capsys.readouterr().out.startswith("px4params ")


# -- small frictions a new user met (issue 38) -------------------------------------------------
# Small frictions a new user met (issue 38): a failed all-or-nothing run prints nothing on
# stdout; reading a store that does not exist leaves no lock file; ``--store`` is taken after the
# verb too; counts of one are singular.


AIRFRAME = REPO / "examples" / "two_batteries.airframe"


def run_here(capsys: pytest.CaptureFixture[str], *words: str) -> tuple[int, str, str]:
    status = main(list(words))
    out, err = capsys.readouterr()
    return status, out, err


def test_a_failed_run_prints_only_its_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    airframe = tmp_path / "bad.airframe"
    airframe.write_text("param add INA238#0\nparam add INA238#1\nparam add BOGUS#0\n")
    store = tmp_path / "v.store"
    status, out, err = run_here(capsys, "run", str(airframe), "--store", str(store))
    # Nothing of the file is kept, so nothing of it is shown as done.
    assert (status, out) == (1, "")
    assert err == f"px4params: error: {airframe}:3: unknown parameter 'BOGUS'\n"
    assert not store.exists()
    # With --keep-going the lines that succeeded are kept: they are shown.
    status, out, err = run_here(capsys, "run", str(airframe), "--store", str(store), "--keep-going")
    assert (status, out) == (1, "INA238#0\nINA238#1\n")
    assert store.exists()


def test_a_run_that_succeeds_prints_what_its_lines_print(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run_here(capsys, "run", str(AIRFRAME), "--store", str(tmp_path / "v.store"))
    assert (status, out, err) == (0, "INA238#0\nINA238#1\nAK09916#0\n", "")


@pytest.mark.parametrize(
    "verb",
    [
        ["show"],
        ["show", "-c"],
        ["status"],
        ["flat"],
        ["find", "INA"],
        ["instances", "INA238"],
        ["compare", "SYS_AUTOSTART", "0"],
    ],
)
def test_reading_a_store_that_does_not_exist_leaves_no_file(
    verb: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    main(["param", *verb])
    capsys.readouterr()
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_reading_a_store_takes_no_lock_and_a_refused_one_gets_none(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # 'param show' of an existing store made FILE.lock beside it, and a refused store (a FIFO,
    # /dev/null) got one too, even in /dev: reading needs no lock (saves replace files whole).
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    assert run_here(capsys, "param", "add", "INA238#0")[0] == 0
    Path("px4params.store.lock").unlink()
    for verb in (["show"], ["show", "-q", "INA238#0"], ["export", "out.params"], ["status"]):
        assert run_here(capsys, "param", *verb)[0] == 0
    os.mkfifo("fifo.store")
    code, _, err = run_here(capsys, "param", "--store", "fifo.store", "set", "SYS_AUTOSTART", "1")
    assert (code, err) == (
        1,
        "px4params: error: fifo.store: cannot read: is a FIFO (named pipe), not a regular file\n",
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "fifo.store",
        "out.params",
        "px4params.store",
    ]


def test_writing_verbs_still_lock(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    assert run_here(capsys, "param", "add", "INA238#0")[0] == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["px4params.store", "px4params.store.lock"]


def test_store_after_the_verb(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "v.store")
    assert run_here(capsys, "run", str(AIRFRAME), "--store", store)[0] == 0
    before = run_here(capsys, "param", "--store", store, "show", "-l", "INA238#0")
    after = run_here(capsys, "param", "show", "-l", "INA238#0", "--store", store)
    assert before == after and before[1].startswith("[0] p_version")
    # after the verb it wins over the one before it
    assert run_here(
        capsys, "param", "--store", "other.store", "show", "--store", store
    ) == run_here(capsys, "param", "show", "--store", store)
    assert run_here(capsys, "param", "set", "INA238#0.current", "150", "--store", store)[0] == 0
    assert (
        run_here(capsys, "param", "--store", store, "show", "-q", "INA238#0.current")[1] == "150\n"
    )


def _leaves(
    parser: argparse.ArgumentParser, path: str, above: set[str]
) -> list[tuple[str, set[str], set[str]]]:
    """Every command line's last parser, the options its parents take and its own."""
    own = {o for a in parser._actions for o in a.option_strings}
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        return [(path, above, own)]
    found = []
    for name, sub in subs[0].choices.items():
        found += _leaves(sub, f"{path} {name}", above | own)
    return found


def test_every_command_takes_its_store_options_after_the_verb() -> None:
    leaves = _leaves(build_parser(), "px4params", set())
    checked = 0
    for path, above, own in leaves:
        for option in ("--store", "--classic", "--dsdl"):
            if option in above:
                assert option in own, f"{path}: {option} only before the verb"
                checked += 1
        if "--store" in above | own:
            checked += 1
    assert checked > 20  # param's verbs, run, autostart plan and run, gui, servers ...


def test_counts_of_one_are_singular(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "run.ulg"
    faults = REPO / "examples" / "two_batteries_faults.bench.toml"
    argv = ["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(faults)]
    assert run_here(capsys, *argv, "--ulog", str(log))[0] == 1
    story = run_here(capsys, "health", str(log))[1]
    # INA238#1 is lost once: one reset, which the story counts as one timeout
    assert ", 1 timeout, " in story and "1 timeouts" not in story
    migrated = tmp_path / "legacy.airframe"
    params = REPO / "examples" / "two_batteries.params"
    status, out, _ = run_here(
        capsys, "migrate", "--table", "legacy", str(params), "-o", str(migrated)
    )
    assert status == 0
    # the legacy table does not know the AK09916 (devtype 0x09): INA238#0 alone
    assert out.endswith(f"\nwrote {migrated}: 1 instance\n")


# -- the defects an outside audit found (those of the command line) ----------------------------
# The defects an outside audit found, one test each (the catalogue of bad inputs is
# ``test_cli_bad_inputs.py``): what users expect instead of a crash or a silently lost intent.


CLI = [sys.executable, "-m", "px4params"]


def cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*CLI, *args], capture_output=True, text=True, timeout=120, cwd=cwd, check=False
    )


@pytest.fixture
def store(tmp_path: Path) -> Path:
    path = tmp_path / "real.store"
    assert cli("run", str(AIRFRAME), "--store", str(path)).returncode == 0
    return path


# -- 8: a float below its leaf type's smallest ---------------------------------------------------


def test_a_float_too_small_for_its_leaf_is_stored_as_zero_with_a_warning(store: Path) -> None:
    # Below the shunt's @min (0.00001): refused, naming the number given (not the 0 it rounds
    # to); with --force both what is overridden and the rounding are said.
    result = cli("param", "--store", str(store), "set", "INA238#0.shunt", "1e-12")
    assert (result.returncode, result.stderr) == (
        1,
        "px4params: error: INA238#0.shunt: 1e-12 is outside 0.00001..0.1 (@min/@max)\n",
    )
    result = cli("param", "--store", str(store), "set", "--force", "INA238#0.shunt", "1e-12")
    assert result.returncode == 0
    assert result.stderr == (
        "px4params: warning: --force: INA238#0.shunt: 1e-12 is outside 0.00001..0.1 "
        "(@min/@max); stored anyway\n"
        "px4params: warning: INA238#0.shunt: 1e-12 is below the smallest float16 and is "
        "stored as 0\n"
    )
    assert px4params.Store.load(store).get("INA238#0.shunt") == 0.0


@pytest.mark.parametrize("how", ["set", "json"])
def test_a_whole_number_a_float_does_not_hold_is_said_where_it_is_rounded(
    store: Path, how: str
) -> None:
    # BAT1_CAPACITY is a classic Float: 16777217 was stored as 16777216 without a word (a
    # store file of the other type says "does not fit"; a .params row, "skipped").
    said = (
        "BAT1_CAPACITY: 16777217 is stored as 16777216 (a Float holds whole numbers exactly "
        "only up to 2**24)"
    )
    if how == "set":
        result = cli("param", "--store", str(store), "set", "BAT1_CAPACITY", "16777217")
        assert (result.returncode, result.stderr) == (0, f"px4params: warning: {said}\n")
    else:
        path = store.with_name("c.json")
        path.write_text(
            '{"format": "px4params", "version": 1, "classic": {"BAT1_CAPACITY": 16777217}}'
        )
        result = cli("param", "--store", str(store), "import", str(path))
        assert result.returncode == 0 and f"{path}: classic: {said}" in result.stdout
    loaded = px4params.Store.load(store, classic=BUNDLED_CLASSIC)
    assert loaded.get("BAT1_CAPACITY") == 16777216.0
    # 2**25 is a float32: nothing to say
    result = cli("param", "--store", str(store), "set", "BAT1_CAPACITY", "33554432")
    assert (result.returncode, result.stderr) == (0, "")


# -- 4, 5: the store file -----------------------------------------------------------------------


def test_a_symlinked_store_stays_a_link_and_its_file_changes(store: Path) -> None:
    link = store.with_name("link.store")
    link.symlink_to(store.name)
    assert cli("param", "--store", str(link), "set", "SYS_AUTOSTART", "4001").returncode == 0
    assert link.is_symlink() and os.readlink(link) == store.name
    assert px4params.Store.load(store, classic=BUNDLED_CLASSIC).get("SYS_AUTOSTART") == 4001
    # One lock for both names: the lock file is the real file's.
    assert store.with_name("real.store.lock").exists()
    assert not store.with_name("link.store.lock").exists()


def test_a_save_into_another_store_waits_for_that_stores_writer(store: Path) -> None:
    # `param save b.store` wrote without b.store's lock: a writer of b.store in the middle of a
    # change saved over it after it said "saved" (2 of 120 saves lost; helper-110). Here the
    # other writer holds the lock, and saves its change 1.5 s later: this save comes after.
    other = store.with_name("b.store")
    holder = subprocess.Popen(
        [sys.executable, "-c", (
            "import fcntl, os, sys, time\n"
            "fd = os.open(sys.argv[1] + '.lock', os.O_RDWR | os.O_CREAT)\n"
            "fcntl.flock(fd, fcntl.LOCK_EX)\n"
            "print('held', flush=True)\n"
            "time.sleep(1.5)\n"
            "open(sys.argv[1], 'wb').write(b'the other writer')\n"
        ), str(other)],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        saved = cli("param", "--store", str(store), "save", str(other))
        assert saved.returncode == 0, saved.stderr
        assert holder.wait(timeout=30) == 0
    finally:
        holder.kill()
    assert other.read_bytes() == store.read_bytes()  # this save, last


def test_temporary_files_of_killed_saves_are_removed(store: Path) -> None:
    dead = 2**22 + 12345  # beyond Linux's default pid_max: no such process
    leftovers = [f".real.store.{dead}.abc123.tmp", f"real.store.bak.{dead}.tmp"]
    alive = f".real.store.{os.getpid()}.zzz.tmp"  # this process: a save under way, kept
    # Saves of other stores whose names begin with this one's: a dated copy's (helper-110: its
    # date read as a dead process, a running save's file removed, "cannot write"), and others.
    others = [
        f".real.store.20261128.{os.getpid()}.abc123.tmp",
        f".real.store.{dead}.x.{dead}.abc123.tmp",
        f"real.store.bak.{dead}.bak.{dead}.tmp",
    ]
    for name in [*leftovers, alive, *others]:
        store.with_name(name).write_bytes(b"half a save")
    assert cli("param", "--store", str(store), "set", "SYS_AUTOSTART", "1").returncode == 0
    names = {p.name for p in store.parent.iterdir()}
    assert not names & set(leftovers)
    assert alive in names and set(others) <= names


# -- 6, 7, 9, 14: commands ------------------------------------------------------------------------


def test_an_airframe_of_comments_still_makes_its_store(tmp_path: Path) -> None:
    airframe = tmp_path / "empty.airframe"
    airframe.write_text("# nothing yet\n\n")
    result = cli("run", str(airframe), "--store", str(tmp_path / "new.store"))
    assert result.returncode == 0
    assert (tmp_path / "new.store").is_file()
    shown = cli("param", "--store", str(tmp_path / "new.store"), "show")
    assert shown.returncode == 0 and "parameters shown" in shown.stdout


def test_the_type_column_of_a_params_file_is_checked(store: Path, tmp_path: Path) -> None:
    # Another type than the parameter's (an older PX4's): taken where nothing is lost (2.0 is
    # 2), else skipped (2.5 is no INT32), each said; the store changes only by what is taken.
    params = tmp_path / "x.params"
    params.write_text("1\t1\tSYS_AUTOSTART\t2.5\t9\n")
    before = store.read_bytes()
    result = cli("param", "--store", str(store), "import", str(params))
    assert (result.returncode, result.stderr) == (0, "")
    assert result.stdout == (
        f"{params}:1: SYS_AUTOSTART: REAL32 (9) in the file, INT32 (6) here: 2.5 does not fit; "
        "skipped\n"
    )
    assert store.read_bytes() == before


def test_encode_fills_missing_fields_on_request() -> None:
    battery = "uavcan.equipment.power.BatteryInfo"
    refused = cli("encode", battery, '{"voltage": 12.5}')
    assert refused.returncode == 1
    assert refused.stderr.endswith(
        "temperature: missing field (give every field, or use --defaults to fill the missing "
        "ones from the type's defaults)\n"
    )
    filled = cli("encode", battery, '{"voltage": 12.5}', "--defaults")
    assert filled.returncode == 0
    # pydronecan's answer: its BatteryInfo of zeros but voltage 12.5, packed with TAO.
    from dronecan_oracle import pack

    message = dronecan.uavcan.equipment.power.BatteryInfo(voltage=12.5)
    assert bytes.fromhex(filled.stdout.strip()) == pack(message, tao=True)


def test_decoding_another_minor_versions_data_says_so(capsys: pytest.CaptureFixture[str]) -> None:
    # p_version 2 was shown as decoded, and encode then refused the value it printed.
    code, out, err = main_out(["decode", "px.Ina238", "20031720ea0c"], capsys)
    assert code == 0 and json.loads(out)["p_version"] == 2
    assert err == (
        "px4params: warning: p_version 2: the data was written by px.Ina238.1.2, and is decoded "
        "with px.Ina238.1.1's layout\n"
    )
    hex_of_today = main_out(
        ["encode", "px.Ina238", out.strip().replace('"p_version": 2, ', "")], capsys
    )[1]
    assert main_out(["decode", "px.Ina238", hex_of_today.strip()], capsys)[2] == ""
