"""The catalogue of bad inputs: every command and file format given what a clumsy user or an
attacker would give it. Each case asserts the exit status, a message without a traceback (one
``px4params: error:`` line naming what was wrong; argparse's usage lines for usage errors) and
that the store file's bytes did not change.

Cases run in-process (``cli.main``) in a scratch folder with the example airframe's store; the
count is checked, so that the catalogue cannot shrink unnoticed.

Hostile files (the second part) run as processes with a 20 s timeout: every kind of file the
product reads (store, bench, drivers, parameters.json, DSDL definition, .params/JSON for import
and load, migrate's .params and .ulg, health's and devid's logs, airframe) given as a FIFO, a
device, ``/dev/zero`` itself, a folder, a link to itself and a file one byte over its kind's
cap; none may hang, print a traceback, change the store or replace the hostile file.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import stat
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from px4params.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
AIRFRAME = ROOT / "examples" / "two_batteries.airframe"
HUGE = "9" * 5000
HUGE_HEX = "0x" + "f" * 5000
HUGE_TEXT = "x" * 100_000
INA_VALUE = '{"bus": {"i2c": {"bus_id": 1, "address": 69}}, "current": 200, "shunt": 0.0003}'


@dataclass(frozen=True)
class Case:
    """``px4params ARGS`` (``{dir}`` is the scratch folder); ``files`` are written there first
    (text or bytes)."""

    args: tuple[str, ...]
    status: int = 1
    #: A fragment the error lines must hold.
    says: str = ""
    files: dict[str, str | bytes] = field(default_factory=dict)

    @property
    def id(self) -> str:
        text = " ".join(self.args)
        return text if len(text) <= 60 else text[:40] + "..." + text[-12:]


def _cases() -> Iterator[Case]:
    # -- param set / set-default: every kind of target, every kind of bad value -------------
    targets = {
        "SYS_AUTOSTART": "int",  # classic Int32
        "INA238_SHUNT": "float",  # classic Float
        "INA238#0[4]": "int",  # uint7 leaf
        "INA238#0.bus.i2c.bus_id": "int",  # uint4 leaf by path
        "INA238#0.shunt": "float",  # float16 leaf
        "INA238#0.bus._tag": "int",  # union tag
    }
    bad_for = {
        "int": [HUGE, HUGE_HEX, "abc", "1.5", "1e400", "0x", "", "nan", "inf", "0x1G", "1_0"],
        "float": [HUGE, HUGE_HEX, "abc", "1e400", "1e4000", "", "0x1p3", "1,5", "one"],
    }
    for verb in ("set", "set-default"):
        for target, kind in targets.items():
            for value in bad_for[kind]:
                says = target if value else ""
                yield Case(("param", "--store", "{dir}/v.store", verb, target, value), says=says)
    # out of range for the leaf (checked by the store)
    for target, value in [
        ("INA238#0[4]", "128"),
        ("INA238#0[4]", "-1"),
        ("INA238#0.bus.i2c.bus_id", "16"),
        ("INA238#0.bus._tag", "6"),
        ("SYS_AUTOSTART", "2147483648"),
        ("SYS_AUTOSTART", "-2147483649"),
    ]:
        yield Case(("param", "--store", "{dir}/v.store", "set", target, value), says="out of range")
    # beyond the type's range too, but its @min/@max are what the refusal names
    for target, value, says in [
        ("INA238#0.shunt", "70000", "70000 is outside 0.00001..0.1 (@min/@max)"),
        ("INA238#0.current", "1024", "1024 is outside 1..327 (@min/@max)"),
    ]:
        yield Case(("param", "--store", "{dir}/v.store", "set", target, value), says=says)
    # whole values as JSON
    for value, says in [
        ('{"current": ' + HUGE + "}", "out of range"),
        ('{"shunt": 1e400}', "out of range"),
        ('{"shunt": Infinity}', "Infinity is not JSON"),
        ('{"shunt": NaN}', "NaN is not JSON"),
        ("{", "JSON"),
        ("[" * 100_000, "INA238#0"),
        (INA_VALUE[:-1] + ', "nope": 1}', "nope"),
        ('{"bus": {"usb": {}}}', "usb"),
        (INA_VALUE.replace("200", '"200"'), "current"),
        (INA_VALUE.replace("200", "true"), "current"),
        ("null", "INA238#0"),
        ("[]", "INA238#0"),
    ]:
        yield Case(("param", "--store", "{dir}/v.store", "set", "INA238#0", value), says=says)
    # names
    for name, says in [
        ("INA238#" + HUGE, "out of range"),
        ("INA238#0[" + HUGE + "]", "no leaf"),
        ("INA238#4[4]", "INA238#4"),
        ("INA238#99999", "INA238#99999"),
        ("INA238#-1", "INA238#-1"),
        ("NOPE#0", "NOPE"),
        ("NOPE", "NOPE"),
        ("INA238#0[99]", "no leaf [99]"),
        ("INA238#0.bus.spi.bus_id", "INA238#0"),
        ("INA238#0.nope", "nope"),
        ("#0", "#0"),
        ("INA238#0..x", "INA238#0..x"),
        ("INA238#2[4]", "INA238#2"),
        (HUGE_TEXT, "(100000 characters)"),
    ]:
        yield Case(("param", "--store", "{dir}/v.store", "set", name, "1"), says=says)
    # compare / greater
    for verb in ("compare", "greater"):
        for name, value in [
            ("SYS_AUTOSTART", HUGE),
            ("SYS_AUTOSTART", "abc"),
            ("INA238#0.shunt", "1e400"),
            ("NOPE", "1"),
            ("INA238#3.current", "1"),
        ]:
            yield Case(("param", "--store", "{dir}/v.store", verb, name, value), says=name[:6])
    # add / rm / reset / instances
    for verb, name in [
        ("add", "INA238#" + HUGE),
        ("add", "INA238#4"),
        ("add", "INA238#0"),
        ("add", "NOPE#0"),
        ("add", "SYS_AUTOSTART"),
        ("add", "INA238#0.current"),
        ("rm", "INA238#3"),
        ("rm", "NOPE#0"),
        ("rm", "INA238#" + HUGE),
        ("rm", "SYS_AUTOSTART"),
        ("reset", "NOPE#0"),
        ("reset", "INA238#3"),
        ("instances", "NOPE"),
    ]:
        yield Case(("param", "--store", "{dir}/v.store", verb, name))
    # -- param import / load: bad files -------------------------------------------------------
    params_files: dict[str, tuple[str | bytes, str]] = {
        "columns.params": ("1\t1\tSYS_AUTOSTART\t4001\n", "expected 5"),
        # another type (an older PX4's): converted, then beyond the field
        "type.params": ("1\t1\tINA238_0C\t200.0\t9\n", "INA238_0C: INA238#0: bus.i2c.address"),
        "fraction.params": ("1\t1\tSYS_AUTOSTART\t1.5\t6\n", "not an integer"),
        "huge.params": (f"1\t1\tSYS_AUTOSTART\t{HUGE}\t6\n", "out of range"),
        "hugeid.params": (f"{HUGE}\t1\tSYS_AUTOSTART\t1\t6\n", "must be integers"),
        "range.params": ("1\t1\tSYS_AUTOSTART\t4294967296\t6\n", "SYS_AUTOSTART"),
        "word.params": ("1\t1\tSYS_AUTOSTART\tabc\t6\n", "not a number"),
        "kind.params": ("1\t1\tSYS_AUTOSTART\t1\t4\n", "is not 6 (int32) or 9 (float)"),
        "leaf.params": ("1\t1\tINA238_0C\t200\t6\n", "INA238_0C"),
        "twice.params": (
            "1\t1\tSYS_AUTOSTART\t4001\t6\n# \n1\t1\tSYS_AUTOSTART\t4002\t6\n",
            "twice.params:3: SYS_AUTOSTART: also set on line 1",
        ),
        "binary.params": (b"\xff\xfe\x00garbage\x00", "not a text file"),
        "binary.json": (b"\x89PNG\r\n\x1a\n", "json"),
        "bad.json": ("{", "not JSON"),
        "inf.json": ('{"format": "px4params", "version": 1, "x": Infinity}', "Infinity"),
        "e400.json": ('{"format": "px4params", "version": 1, "x": 1e400}', "out of range"),
        "hugeint.json": ('{"format": "px4params", "version": 1, "x": ' + HUGE + "}", "range"),
        "deep.json": ("[" * 100_000 + "]" * 100_000, "deep.json"),
        "other.json": ('{"format": "qgc"}', "not a px4params JSON export"),
        "version.json": ('{"format": "px4params", "version": 99}', "version"),
        "empty.store": (b"", "empty.store"),
        "magic.store": (b"NOPE" + bytes(20), "magic.store"),
        "truncated.store": (b"PX4P\x01", "truncated.store"),
        "random.store": (bytes(range(256)) * 4, "random.store"),
        "noext.txt": ("hello\n", "noext.txt"),
        # strict JSON exports: a misspelled key used to empty the store (load) or do nothing
        "instancez.json": (
            '{"format": "px4params", "version": 1, "instancez": {}}',
            "unknown top-level key 'instancez' (did you mean 'instances'?); nothing was changed",
        ),
        "null.json": (
            '{"format": "px4params", "version": 1, "instances": null}',
            "'instances' must be an object, not null",
        ),
        "array.json": (
            '{"format": "px4params", "version": 1, "classic": [1]}',
            "'classic' must be an object, not an array",
        ),
        "valeu.json": (
            '{"format": "px4params", "version": 1, "instances": {"INA238#0": {"valeu": 1}}}',
            "unknown key 'valeu' (did you mean 'value'?)",
        ),
        "leaf.json": (
            '{"format": "px4params", "version": 1, "instances": {"INA238#0[4]": {"value": 1}}}',
            "'instances' holds whole structured parameters",
        ),
        "classic.json": (
            '{"format": "px4params", "version": 1, "classic": {"INA238#0": 1}}',
            "INA238#0: not a classic parameter of this store",
        ),
    }
    for name, (content, says) in params_files.items():
        for verb in ("import", "load"):
            yield Case(
                ("param", "--store", "{dir}/v.store", verb, "{dir}/" + name),
                says=says,
                files={name: content},
            )
    yield Case(("param", "--store", "{dir}/v.store", "import", "{dir}/missing.params"))
    # -- encode / decode --------------------------------------------------------------------
    ina = "px.Ina238"
    for value, says in [
        ('{"current": ' + HUGE + "}", "out of range"),
        ('{"shunt": 1e400}', "out of range"),
        ('{"shunt": -Infinity}', "-Infinity is not JSON"),
        ('{"bus": {"i2c": {"bus_id": 1, "address": 69}}, "current": 200}', "missing field"),
        ('{"bus": {"i2c": {"bus_id": 1, "address": 128}}, "current": 200, "shunt": 0}', "128"),
        ('{"bus": {"i2c": {}, "spi": {}}, "current": 1, "shunt": 0}', "bus"),
        ("[" * 100_000, "JSON"),
        ("", "JSON"),
        (HUGE_TEXT, "JSON"),
        ('"text"', "dict"),
    ]:
        yield Case(("encode", ina, value), says=says)
    for type_name, value in [
        ("uavcan.equipment.power.BatteryInfo", '{"voltage": 1}'),
        ("uavcan.protocol.NodeStatus", '{"uptime_sec": -1}'),
        ("uavcan.protocol.NodeStatus", '{"health": 4}'),
        ("px.Nope", "{}"),
        ("uavcan.protocol.param.GetSet.Request", '{"name": "' + "a" * 93 + '"}'),
    ]:
        yield Case(("encode", type_name, value))
    for hex_text, says in [
        ("1003", "truncated"),
        ("10031720ea0c00", "too long"),
        ("xyz", "not hex bytes"),
        ("100", "not hex bytes"),
        ("ff" * 70_000, "union tag 7 selects no variant"),
        ("1f", "union tag"),
    ]:
        yield Case(("decode", ina, hex_text), says=says)
    yield Case(("decode", "uavcan.protocol.NodeStatus", "00"), says="truncated")
    yield Case(("frames", ina, '{"current": 1}'), says="no default data type ID")
    yield Case(("frames", ina, '{"current": 1}', "--dtid", "1"), says="missing field")
    # a float beyond its field, named with an exponent (it was 301 digits long)
    yield Case(("encode", ina, "--defaults", '{"shunt": 1e300}'), says="shunt: value 1e300 is")
    # -- devid ----------------------------------------------------------------------------------
    for args in [
        (HUGE,),
        (HUGE_HEX,),
        ("abc",),
        ("-1",),
        ("16777216",),
        ("1.5",),
        ("--encode", "--bus", HUGE, "--bus-type", "I2C", "--address", "1", "--devtype", "1"),
        ("--encode", "--bus", "32", "--bus-type", "I2C", "--address", "1", "--devtype", "1"),
        ("--encode", "--bus", "1", "--bus-type", "USB", "--address", "1", "--devtype", "1"),
        ("--encode", "--bus", "1", "--bus-type", "I2C", "--address", "256", "--devtype", "1"),
        ("--encode", "--bus", "1", "--bus-type", "I2C", "--address", "1", "--devtype", HUGE),
        ("--log", "{dir}/missing.ulg"),
        ("--log", "{dir}/bad.ulg"),
    ]:
        yield Case(("devid", "--table", "legacy", *args), files={"bad.ulg": b"ULog\x01garbage"})
    # -- run: airframe files --------------------------------------------------------------------
    for line, says in [
        (f"param set SYS_AUTOSTART {HUGE}", "frame.airframe:1"),
        ("param set INA238#0.shunt 1e400", "frame.airframe:1"),
        ("param add INA238#" + HUGE, "frame.airframe:1"),
        ("param nope", "frame.airframe:1"),
        ("if param compare SYS_AUTOSTART 1\nthen", "'if' without 'fi'"),
        ("fi", "frame.airframe:1"),
        ("set X", "frame.airframe:1"),
        ("param set INA238#0 '{'", "frame.airframe:1"),
        ("reboot now", "frame.airframe:1"),
        ("param set SYS_AUTOSTART 'unterminated", "frame.airframe:1"),
        ("param load {dir}/missing.store", "frame.airframe:1"),
        # lines are bounded as written and as expanded (they took quadratic time)
        ("param set SYS_AUTOSTART " + "1" * 1_000_000, "frame.airframe:1: line of 1,000,024"),
        (
            "set A x\n" + "set A $A$A\n" * 40,
            "frame.airframe:17: the line expands to more than 65,536 characters",
        ),
        ('param set SYS_AUTOSTART "4001', "frame.airframe:1: No closing quotation"),
        # a '#' later in a line is a word (INA238#0): it was left out of the message
        (
            "param set SYS_AUTOSTART 4003 # x y",
            "frame.airframe:1: param: unrecognized arguments: x y (a '#' after a command is "
            "no comment: give comments a line of their own)",
        ),
        ("param set SYS_AUTOSTART 4001\\", "frame.airframe:1: No escaped character"),
    ]:
        yield Case(
            ("run", "{dir}/frame.airframe", "--store", "{dir}/v.store"),
            says=says,
            files={"frame.airframe": line.replace("{dir}", "DIR") + "\n"},
        )
    yield Case(("run", "{dir}/missing.airframe", "--store", "{dir}/v.store"), says="cannot read")
    # -- the store's own file -------------------------------------------------------------------
    # '-' made a store file named '-'; a missing folder was named as FOLDER/x.store.lock
    yield Case(("param", "--store", "-", "show"), status=2, says="'-' is no store file here")
    yield Case(
        ("param", "--store", "{dir}/nodir/x.store", "set", "SYS_AUTOSTART", "1"),
        says="/nodir/x.store: no folder ",
    )
    yield Case(
        ("run", "{dir}/bin.airframe", "--store", "{dir}/v.store"),
        says="not a text file",
        files={"bin.airframe": b"\xff\xfe\xfa"},
    )
    # -- migrate --------------------------------------------------------------------------------
    for name, content in [
        ("bad.params", "not\ta\tparams\tfile\n"),
        ("bin.params", b"\x00\x01\xff"),
        ("trunc.ulg", b"ULog\x01\x12\x35"),
        ("junk.ulg", bytes(range(256))),
    ]:
        yield Case(("migrate", "{dir}/" + name, "--table", "legacy"), files={name: content})
    yield Case(("migrate", "{dir}/missing.params", "--table", "legacy"))
    # -- hostile DSDL ---------------------------------------------------------------------------
    dsdl_cases: dict[str, tuple[dict[str, str | bytes], str]] = {
        "binary": ({"B.1.0.dsdl": bytes(range(128, 256))}, "not a text file"),
        "nested": (
            {
                "L1.1.0.dsdl": "uint8[65535] x\n@sealed\n",
                "L2.1.0.dsdl": "L1.1.0[65535] x\n@sealed\n",
            },
            "types are limited to 65,535 bytes",
        ),
        "huge": ({"L3.1.0.dsdl": "uint8[100000000] x\n@sealed\n"}, "limited to 65,535 bytes"),
        "instances": (
            {"W.1.0.dsdl": "# @max_instances 65536\nuint8 x\n@sealed\n"},
            "@max_instances expects an integer 1..256",
        ),
        "unknown": ({"R.1.0.dsdl": "Nope.1.0 x\n@sealed\n"}, "R.1.0.dsdl"),
        "syntax": ({"S.1.0.dsdl": "uint8 x y z\n@sealed\n"}, "S.1.0.dsdl"),
        "tag": ({"T.1.0.dsdl": "# @nope 1\nuint8 x\n@sealed\n"}, "unknown metadata tag @nope"),
        "default": (
            {"D.1.0.dsdl": "uint8 x\n# @default " + HUGE + "\n@sealed\n"},
            "out of range",
        ),
    }
    for name, (files, says) in dsdl_cases.items():
        yield Case(
            ("types", "--dsdl", "{dir}/" + name + "/acme"),
            says=says,
            files={f"{name}/acme/{f}": c for f, c in files.items()},
        )
    # DSDL roots that are not namespace folders: refused at once, not walked for minutes
    yield Case(("types", "--dsdl", "/"), says="the file system's root is not a DSDL root")
    yield Case(("types", "--dsdl", "/usr"), says="/usr: DSDL root holds more than 10,000")
    # -- bench and drivers TOML: unknown keys and wrong shapes ---------------------------------
    bench = str(ROOT / "examples" / "two_batteries.bench.toml")
    for text, says in [
        ("benchz = 1\n", "unknown top-level key 'benchz' (did you mean 'bench'?)"),
        ("bus = 1\n", "'bus' must be [[bus]] tables"),
        ("device = 'x'\n", "'device' must be [[device]] tables"),
        ("bench = [1]\n", "[bench] must be a table"),
        ("[[bus]]\nkind = []\n", "kind [] is not a simulated bus kind"),
        ("[[device]]\nchip = 'INA238'\nbus = 'i2c'\nbus_id = 'x'\naddress = 1\n", "bus_id"),
    ]:
        yield Case(
            ("autostart", "run", "--store", "{dir}/v.store", "--bench", "{dir}/b.toml"),
            says=says,
            files={"b.toml": text},
        )
    for text, says in [
        ("drivers = 1\n", "unknown top-level key 'drivers' (expected [[driver]] tables)"),
        ("driver = [1]\n", "driver #1: is not a table"),
        ("[[driver]]\nname = 'ina238'\nnope = 1\n", "unknown key 'nope' (expected: name,"),
        (
            "[[driver]]\nname = 'x'\nparameter = 'INA238'\nchip = 'INA238'\norder = 1\n"
            "devtype = 1\nrate_hz = 1\nbuses = [{}]\n",
            "unknown bus kind {}",
        ),
    ]:
        yield Case(
            (
                "autostart",
                "run",
                "--store",
                "{dir}/v.store",
                "--bench",
                bench,
                "--drivers",
                "{dir}/d.toml",
            ),
            says=says,
            files={"d.toml": text},
        )
    # -- usage errors (exit 2) -------------------------------------------------------------------
    for args in [
        ("nope",),
        ("param",),
        ("param", "--store", "{dir}/v.store", "set", "SYS_AUTOSTART"),
        ("encode",),
        ("decode", ina),
        ("devid", "--table", "nope", "1"),
        ("dronecan", "param", "list", "--slcan", "{dir}/x", "--node", "0"),
        ("dronecan", "param", "list", "--slcan", "{dir}/x", "--node", HUGE),
        ("dronecan", "serve", "--slcan-pty", "--node-id", "128"),
        ("mavlink", "serve", "--udp", "nope"),
        ("mavlink", "serve", "--udp", "127.0.0.1:" + HUGE),
        ("autostart", "run", "--duration", "x"),
        ("frames", ina, "{}", "--transfer-id", HUGE),
        ("frames", ina, "{}", "--transfer-id", "zz"),
        # an empty file name (an unset shell variable) meant the default store without a word
        ("param", "--store", "", "show"),
        ("param", "show", "--store", ""),
        ("param", "--classic", "", "show"),
        ("run", "{dir}/x.airframe", "--store", ""),
        # durations: a server given one that is not a time used to start and fail every 2 s
        *[
            (*server, f"--bench-duration={value}")
            for server in (("mavlink", "serve"), ("dronecan", "serve", "--slcan-pty"))
            for value in ("nan", "-1", "inf", "-inf", "0", HUGE)
        ],
        ("autostart", "run", "--bench", "x.toml", "--duration=nan"),
        ("dronecan", "param", "list", "--slcan", "{dir}/x", "--node", "1", "--timeout=-1"),
    ]:
        yield Case(args, status=2)
    yield Case(
        ("dronecan", "param", "list", "--slcan", "{dir}/x", "--node", "1"), says="cannot open"
    )
    yield Case(("dronecan", "serve", "--slcan", "{dir}/x", "--store", "{dir}/v.store"))


CASES = list(_cases())


def test_the_catalogue_is_large() -> None:
    assert len(CASES) >= 350, len(CASES)
    assert len(HOSTILE) >= 71, len(HOSTILE)


@pytest.fixture(scope="module")
def template(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("template")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "px4params",
            "run",
            str(AIRFRAME),
            "--store",
            str(folder / "v.store"),
        ],
        check=True,
        capture_output=True,
    )
    return folder / "v.store"


def _run(args: list[str], cwd: Path) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    old = os.getcwd()
    os.chdir(cwd)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                status = main(args)
            except SystemExit as e:  # argparse's usage errors
                status = int(e.code or 0)
    finally:
        os.chdir(old)
    return status, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(case: Case, template: Path, tmp_path: Path) -> None:
    shutil.copy(template, tmp_path / "v.store")
    for name, content in case.files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content.replace("DIR", str(tmp_path)))
    before = (tmp_path / "v.store").read_bytes()
    args = [a.replace("{dir}", str(tmp_path)) for a in case.args]
    status, _, err = _run(args, tmp_path)
    assert status == case.status, err
    assert "Traceback" not in err
    lines = err.splitlines()
    if case.status == 1:
        errors = [line for line in lines if line.startswith("px4params: ")]
        assert errors and len(errors[-1]) < 2000, err[:500]
    else:
        assert lines and "error:" in lines[-1], err
    assert case.says in err, (case.says, err[:500])
    assert (tmp_path / "v.store").read_bytes() == before


# -- hostile files: each kind of file the product reads, as what is not a file to read ---------
#
# Run as processes with a timeout: read as a file, a FIFO blocks for ever and /dev/zero grows
# until memory runs out. Each file kind is given as a FIFO, a device (a link to /dev/zero), a
# folder, a link to itself and a sparse file one byte over its kind's cap.

#: (file name, command line with {f} for the file, the size cap of its kind)
FILE_KINDS: dict[str, tuple[str, tuple[str, ...], int]] = {
    "store": ("h.store", ("param", "--store", "{f}", "show"), 16 << 20),
    "bench": (
        "h.bench.toml",
        ("autostart", "run", "--store", "{dir}/v.store", "--bench", "{f}"),
        1 << 20,
    ),
    "drivers": (
        "h.drivers.toml",
        ("autostart", "run", "--store", "{dir}/v.store", "--bench", "{bench}", "--drivers", "{f}"),
        1 << 20,
    ),
    "classic": (
        "h.json",
        ("param", "--store", "{dir}/v.store", "--classic", "{f}", "show"),
        32 << 20,
    ),
    "dsdl": ("acme/H.1.0.dsdl", ("types", "--dsdl", "{dir}/acme"), 1 << 20),
    "import": ("h.params", ("param", "--store", "{dir}/v.store", "import", "{f}"), 16 << 20),
    "load": ("h.json", ("param", "--store", "{dir}/v.store", "load", "{f}"), 16 << 20),
    "migrate-params": ("h.params", ("migrate", "{f}", "--table", "legacy"), 16 << 20),
    "migrate-ulog": ("h.ulg", ("migrate", "{f}", "--table", "legacy"), 1 << 30),
    "health": ("h.ulg", ("health", "{f}"), 1 << 30),
    "devid": ("h.ulg", ("devid", "--table", "legacy", "--log", "{f}"), 1 << 30),
    "airframe": ("h.airframe", ("run", "{f}", "--store", "{dir}/v.store"), 1 << 20),
}

#: What each shape of hostile file is, and what the error line says about it.
SHAPES = {
    "fifo": "is a FIFO (named pipe), not a regular file",
    "device": "is a character device, not a regular file",
    "dev-zero": "is a character device, not a regular file",
    "folder": "is a folder, not a file",
    "loop": "Too many levels of symbolic links",
    "oversize": "too large for",
}

# (/dev/zero itself is given where a file is named; a definition is found in a folder)
HOSTILE = [
    (kind, shape)
    for kind in FILE_KINDS
    for shape in SHAPES
    if not (kind == "dsdl" and shape == "dev-zero")
]


def _make_hostile(path: Path, shape: str, cap: int) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if shape == "fifo":
        os.mkfifo(path)
    elif shape == "device":
        path.symlink_to("/dev/zero")
    elif shape == "folder":
        path.mkdir()
    elif shape == "loop":
        path.symlink_to(path.name)
    else:
        with open(path, "wb") as f:
            f.truncate(cap + 1)  # sparse: one byte over the cap costs no disk


@pytest.mark.parametrize(("kind", "shape"), HOSTILE, ids=[f"{k}-{s}" for k, s in HOSTILE])
def test_hostile_file(kind: str, shape: str, template: Path, tmp_path: Path) -> None:
    name, args, cap = FILE_KINDS[kind]
    shutil.copy(template, tmp_path / "v.store")
    before = (tmp_path / "v.store").read_bytes()
    hostile = tmp_path / name
    if shape == "dev-zero":
        hostile = Path("/dev/zero")
    else:
        _make_hostile(hostile, shape, cap)
    kind_before = stat.S_IFMT(os.lstat(hostile).st_mode)
    bench = ROOT / "examples" / "two_batteries.bench.toml"
    words = [
        a.replace("{f}", str(hostile))
        .replace("{dir}", str(tmp_path))
        .replace("{bench}", str(bench))
        for a in args
    ]
    # A folder named like a definition is a namespace folder: a root without definitions.
    says = "contains no .dsdl" if (kind, shape) == ("dsdl", "folder") else SHAPES[shape]
    result = subprocess.run(
        [sys.executable, "-m", "px4params", *words],
        capture_output=True,
        text=True,
        timeout=20,
        cwd=tmp_path,
        check=False,
        env={**os.environ, "PX4PARAMS_DSDL_PATH": ""},
    )
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("px4params: error: "), result.stderr
    named = hostile.parent if (kind, shape) == ("dsdl", "folder") else hostile  # the root
    assert says in lines[0] and str(named) in lines[0], lines[0]
    assert (tmp_path / "v.store").read_bytes() == before
    assert stat.S_IFMT(os.lstat(hostile).st_mode) == kind_before  # not replaced by a file
