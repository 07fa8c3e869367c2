"""Tests for PX4 device IDs: python/px4params/devid.py and ``px4params devid``.

Data from other projects (today's devtype table as TSV, a real flight log) is not in this
repository: it is found through $PX4PARAMS_SHARED_DATA, by default the ``shared/data`` folder
beside the repository, and the tests that need it are skipped when it is absent.
"""

from __future__ import annotations

import json
import os
import re
import struct
import subprocess
import sys
from pathlib import Path

import pytest
import shared_data
from hypothesis import given, settings
from hypothesis import strategies as st
from px4params.cli.main import main
from px4params.errors import DeviceIdError, Px4ParamsError
from px4params.vehicle import devid
from shared_data import SHARED_DATA, shared_file
from strategies import budget

CURRENT_TSV = SHARED_DATA / shared_data.CURRENT_TSV

# The driver guide's three magnetometers: (id, guide's bit groups, devtype, bus type, bus, address)
GUIDE = [
    (73225, "00000001 00011110 00001 001", "HMC5883", "I2C", 1, 0x1E),
    (66826, "00000001 00000101 00001 010", "HMC5883", "SPI", 1, 5),
    (263178, "00000100 00000100 00001 010", "MPU9250", "SPI", 1, 4),
]

# A drv_sensor.h in the header's own style (tabs or spaces, lower- or upper-case hex, comments,
# a code used twice, unrelated defines), written for these tests.
HEADER = """\
#ifndef _DRV_SENSOR_H
#define _DRV_SENSOR_H
#include <stdint.h>

#define DRV_MAG_DEVTYPE_HMC5883  0x01
#define DRV_MAG_DEVTYPE_AK09916  0x09
#define DRV_DIFF_PRESS_DEVTYPE_SIM\t0x15
#define DRV_ACC_DEVTYPE_BMI088          0x6a
#define DRV_GYR_DEVTYPE_BMI088          0x66 // gyro half of the same chip
#define DRV_INS_DEVTYPE_ONE 0xE9
#define DRV_LED_DEVTYPE_TWO 0xe9
#define DRV_DEVTYPE_UNUSED\t\t0xff
#define SENSOR_COUNT 4

#endif /* _DRV_SENSOR_H */
"""


@pytest.fixture(autouse=True)
def no_table_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """The caller's own $PX4PARAMS_DEVTYPES must not change what these tests see."""
    monkeypatch.delenv(devid.DEVTYPES_ENV, raising=False)


@pytest.fixture
def current(monkeypatch: pytest.MonkeyPatch) -> Path:
    """Point the current table at the shared TSV, for the library and the CLI alike."""
    path = shared_file(shared_data.CURRENT_TSV)
    monkeypatch.setenv(devid.DEVTYPES_ENV, str(path))
    return path


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(["devid", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(err: str, *fragments: str) -> None:
    assert err.count("\n") == 1 and err.startswith("px4params: error: "), err
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in err, (fragment, err)


# --- the driver guide's examples, legacy table ---------------------------------------------------


@pytest.mark.parametrize(("value", "bits", "chip", "bus_type", "bus", "address"), GUIDE)
def test_guide_examples_legacy(
    value: int, bits: str, chip: str, bus_type: str, bus: int, address: int
) -> None:
    # The guide writes the ID as devtype, address, bus (5 bits) and bus type (3 bits).
    b = f"{value:024b}"
    assert f"{b[:8]} {b[8:16]} {b[16:21]} {b[21:]}" == bits
    d = devid.decode(value, "legacy")
    assert (d.devtype_name, d.bus_type_name, d.bus, d.address) == (chip, bus_type, bus, address)
    assert d.devtype_kind == "MAG" and d.table == "legacy" and not d.no_device
    where = f"address 0x{address:02X}" if bus_type == "I2C" else f"device {address}"
    assert d.describe() == f"{chip} (MAG), {bus_type} bus {bus}, {where}"


def test_guide_examples_cli(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "--table", "legacy", "73225", "66826", "0x4040A")
    assert (code, err) == (0, "")
    assert out.splitlines() == [
        "73225 (0x011E09): HMC5883 (MAG), I2C bus 1, address 0x1E",
        "66826 (0x01050A): HMC5883 (MAG), SPI bus 1, device 5",
        "263178 (0x04040A): MPU9250 (MAG), SPI bus 1, device 4",
    ]
    code, out, _ = run_cli(capsys, "--table", "legacy", "--json", *(str(g[0]) for g in GUIDE))
    rows = json.loads(out)
    assert code == 0
    assert [(r["devtype_name"], r["bus_type_name"], r["address"]) for r in rows] == [
        (g[2], g[3], g[5]) for g in GUIDE
    ]


def test_legacy_table_contents() -> None:
    table = devid.legacy_table()
    assert len(table) == 16
    assert table.name_of(0x04) == "MPU9250" and table.kind_of(0x04) == "MAG"
    assert table.name_of(0x11) == "LSM303D" and table.kind_of(0x11) == "ACC"
    assert table.name_of(0x32) == "LL40LS" and table.name_of(0x05) is None


# --- the current table ---------------------------------------------------------------------------


def test_current_table_from_tsv(current: Path) -> None:
    table = devid.load_table("current")
    assert table.label == "current" and Path(table.source) == current
    assert len(table) == 177 and len(list(table)) == 178  # 0xE9 is defined twice
    assert table.name_of(0x04) == "AK8963"  # the guide's MPU9250 code, reused
    assert table.name_of(0xE9) == "ILABS/RGBLED_AW2023" and table.kind_of(0xE9) == "INS/LED"
    ak = table.lookup(0x09)[0]
    assert (ak.name, ak.kind, ak.macro) == ("AK09916", "MAG", "DRV_MAG_DEVTYPE_AK09916")
    assert devid.decode(0xE90000, table).describe().startswith("ILABS/RGBLED_AW2023 (INS/LED)")


def test_current_table_is_shipped(tmp_path: Path) -> None:
    """Today's table is part of the package: no variable, no file beside a checkout. It holds
    what drv_sensor.h's #define lines say (the shared TSV, read from PX4-Autopilot), row for
    row, and names where it was read."""
    table = devid.load_table("current")
    assert Path(table.source).name == "current.tsv" and "data/devtypes" in table.source
    text = Path(table.source).read_text()
    assert "src/drivers/drv_sensor.h in PX4/PX4-Autopilot commit" in text
    assert "023ba6e01a6624e7b3f6782593a19e8870f9b973" in text
    assert (len(table), len(list(table))) == (177, 178)
    shared = devid.load_table("current", shared_file(shared_data.CURRENT_TSV))
    assert [(e.code, e.macro) for e in table] == [(e.code, e.macro) for e in shared]
    # An installed command, outside any checkout and with no variable set.
    env = {k: v for k, v in os.environ.items() if k != devid.DEVTYPES_ENV}
    r = subprocess.run([sys.executable, "-m", "px4params", "devid", "592905"], cwd=tmp_path,
                       capture_output=True, text=True, env=env, timeout=60)  # fmt: skip
    assert (r.returncode, r.stdout) == (
        0,
        "592905 (0x090C09): AK09916 (MAG), I2C bus 1, address 0x0C\n",
    )


def test_drv_sensor_header(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    header = tmp_path / "drv_sensor.h"
    header.write_text(HEADER)
    table = devid.load_table("current", header)
    assert [(e.code, e.qualified) for e in table] == [
        (0x01, "MAG_HMC5883"),
        (0x09, "MAG_AK09916"),
        (0x15, "DIFF_PRESS_SIM"),
        (0x66, "GYR_BMI088"),
        (0x6A, "ACC_BMI088"),
        (0xE9, "INS_ONE"),
        (0xE9, "LED_TWO"),
        (0xFF, "UNUSED"),
    ]
    assert table.name_of(0xE9) == "ONE/TWO" and table.kind_of(0xFF) is None
    # The same file through the environment variable, and through the CLI's --devtypes.
    monkeypatch.setenv(devid.DEVTYPES_ENV, str(header))
    assert devid.decode(592905).devtype_name == "AK09916"
    assert main(["devid", "--devtypes", str(header), "--list", "--json"]) == 0


def test_tsv_variants(tmp_path: Path) -> None:
    # No header row, decimal codes, a comment, a blank line, a plain name, a repeated row.
    tsv = tmp_path / "t.tsv"
    tsv.write_text(
        "# mine\n9\tDRV_MAG_DEVTYPE_AK09916\n\n0x40\tmy chip\n9\tDRV_MAG_DEVTYPE_AK09916\n"
    )
    table = devid.load_table("current", tsv)
    assert [(e.code, e.name, e.kind) for e in table] == [
        (9, "AK09916", "MAG"),
        (64, "MY CHIP", None),
    ]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("code\tname\n0x01\n", "t.tsv:2: expected 'code<TAB>name'"),
        ("0x01\tA\tB\n", "t.tsv:1: expected 'code<TAB>name'"),
        ("0x01\t \n", "t.tsv:1: expected 'code<TAB>name'"),
        ("one\tA\n", "t.tsv:1: devtype code 'one' is not a number"),
        ("0x100\tA\n", "t.tsv:1: devtype code 0x100 is out of range 0..255"),
        ("code\tname\n", "t.tsv: no devtypes found"),
        ("#define DRV_MAG_DEVTYPE_X FOO\n", "t.tsv:1: devtype code 'FOO' is not a number"),
    ],
)
def test_bad_table_files(tmp_path: Path, text: str, message: str) -> None:
    tsv = tmp_path / "t.tsv"
    tsv.write_text(text)
    with pytest.raises(DeviceIdError) as e:
        devid.load_table("current", tsv)
    assert message in str(e.value) and "\n" not in str(e.value)


def test_missing_table_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "nope.tsv"
    code, _, err = run_cli(capsys, "--devtypes", str(missing), "1")
    assert code == 1
    assert_one_line_error(err, f"devtypes file not found: {missing}")
    monkeypatch.setenv(devid.DEVTYPES_ENV, str(missing))
    with pytest.raises(DeviceIdError, match=r"\$PX4PARAMS_DEVTYPES not found: .*nope\.tsv"):
        devid.load_table("current")


def test_unknown_table(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(DeviceIdError, match=r"unknown devtype table 'newest' \(expected one of: "):
        devid.load_table("newest")
    with pytest.raises(DeviceIdError, match="unknown devtype table 'newest'"):
        devid.decode(1, "newest")
    # On the command line the choice is checked by argparse: a usage error.
    with pytest.raises(SystemExit) as e:
        main(["devid", "--table", "newest", "1"])
    out, err = capsys.readouterr()
    assert (e.value.code, out) == (2, "")
    assert "invalid choice: 'newest'" in err.splitlines()[-1] and "Traceback" not in err


# --- decoding and encoding -----------------------------------------------------------------------


def test_decode_fields_and_no_device() -> None:
    d = devid.decode(592905, None)
    assert (d.bus_type, d.bus_type_name, d.bus, d.address, d.devtype) == (1, "I2C", 1, 0x0C, 9)
    assert d.devtype_name is None and d.table is None and int(d) == 592905 and d.hex == "0x090C09"
    assert d.describe() == "devtype 0x09, I2C bus 1, address 0x0C"
    zero = devid.decode(0, "legacy")
    assert zero.no_device and zero.describe() == "no device" and zero.as_dict()["no_device"]
    # Bus type 7 has no name; UAVCAN's address byte is the node ID.
    assert devid.decode(0x050107, "legacy").describe() == (
        "devtype 0x05 (not in the legacy table), bus type 7, bus 0, address 0x01"
    )
    assert devid.decode(0x887D03, None).describe().endswith("UAVCAN bus 0, node 125")
    with pytest.raises(DeviceIdError):  # a DeviceIdError is a Px4ParamsError
        devid.decode(True, None)  # type: ignore[arg-type]
    assert issubclass(DeviceIdError, Px4ParamsError)


def test_encode_forms(current: Path) -> None:
    expected = 592905
    for dt in ("AK09916", "ak09916", "0x09", 9, "9", "MAG_AK09916", "DRV_MAG_DEVTYPE_AK09916"):
        assert devid.encode("i2c", 1, "0x0c", dt) == expected, dt
    assert devid.encode(1, "1", 12, 9) == expected
    assert devid.encode("SPI", 1, 5, "HMC5883", "legacy") == 66826
    assert devid.encode("spi", 1, 4, "mag_mpu9250", devid.legacy_table()) == 263178
    assert devid.encode("sim", 0, 0, 0) == 4 and devid.encode("dronecan", 0, 0, 0) == 3
    assert devid.encode("MAVLink", 0, 0, 0) == 6 and devid.encode("7", 0, 0, 0) == 7


def test_encode_cli(current: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["--encode", "--bus-type", "i2c", "--bus", "1", "--address", "0x0c", "--devtype"]
    code, out, err = run_cli(capsys, *args, "AK09916")
    assert (code, out, err) == (
        0,
        "592905 (0x090C09): AK09916 (MAG), I2C bus 1, address 0x0C\n",
        "",
    )
    code, out, _ = run_cli(capsys, *args, "0x09", "--json")
    row = json.loads(out)
    assert code == 0 and row["id"] == 592905 and row["hex"] == "0x090C09"
    assert (row["devtype_name"], row["bus_type_name"], row["address"]) == ("AK09916", "I2C", 12)


@pytest.mark.parametrize(
    ("parts", "message"),
    [
        (("i2c", 32, 0, 0), "bus 32 is out of range 0..31"),
        (("i2c", -1, 0, 0), "bus -1 is out of range 0..31"),
        (("i2c", 1, "0x100", 0), "address 0x100 is out of range 0..255, 0x00..0xFF"),
        (("i2c", 1, 0, 256), "devtype 256 is out of range 0..255, 0x00..0xFF"),
        ((8, 1, 0, 0), "bus type 8 is out of range 0..7"),
        (("usb", 1, 0, 0), "unknown bus type 'usb' (expected one of: unknown, i2c, spi"),
        (("i2c", "one", 0, 0), "bus 'one' is not a number (expected 0..31)"),
        (("i2c", 1.0, 0, 0), "bus must be an int, not float"),
        (("i2c", 1, 0, "HMC5833"), "unknown devtype 'HMC5833' in the legacy table (did you mean"),
        (("i2c", 1, 0, "QQQ"), "unknown devtype 'QQQ' in the legacy table (give a code 0..255"),
        (("i2c", 1, 0, "MPU9250"), "devtype 'MPU9250' is ambiguous in the legacy table: give one"),
    ],
)
def test_encode_errors(parts: tuple[object, ...], message: str) -> None:
    with pytest.raises(DeviceIdError) as e:
        devid.encode(*parts, table="legacy")  # type: ignore[arg-type]
    assert message in str(e.value) and "\n" not in str(e.value)


def test_unknown_devtype_name_current(current: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(DeviceIdError, match=r"did you mean AK09916"):
        devid.encode("i2c", 1, 0x0C, "AK9916")
    with pytest.raises(DeviceIdError, match=r"'sim' is ambiguous .* IMU_SIM \(0x14\)"):
        devid.encode("i2c", 1, 0x0C, "sim")
    args = ["--encode", "--bus-type", "i2c", "--bus", "1", "--address", "12", "--devtype", "NOPE"]
    code, out, err = run_cli(capsys, *args)
    assert (code, out) == (1, "")
    assert_one_line_error(err, "unknown devtype 'NOPE' in the current table")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "abc",
            "not a device ID: 'abc' (expected decimal, 0x hex or a whole number such as 73225.0, "
            "0..16777215)",
        ),
        ("1.5", "not a device ID: '1.5'"),
        ("0x", "not a device ID: '0x'"),
        ("", "not a device ID: ''"),
        ("16777216", "device ID 16777216 does not fit in 24 bits (expected 0..16777215"),
        ("0x1000000", "device ID 16777216 does not fit in 24 bits"),
        ("-1", "device ID -1 does not fit in 24 bits"),
    ],
)
def test_bad_ids(text: str, message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(DeviceIdError) as e:
        devid.parse_device_id(text)
    assert message in str(e.value)
    # One bad ID fails the whole command before anything is printed.
    code, out, err = run_cli(capsys, "--table", "legacy", "73225", text)
    assert (code, out) == (1, "")
    assert_one_line_error(err, message)


def test_id_spellings() -> None:
    # The guide prints parameters as floats ("CAL_MAG0_ID = 73225.0").
    for text in ("73225", "0x11e09", "0X011E09", " 73225 ", "73225.0", "+73225"):
        assert devid.parse_device_id(text) == 73225, text
    with pytest.raises(DeviceIdError, match="does not fit in 24 bits"):
        devid.decode(1 << 24, None)


@settings(max_examples=budget(300), deadline=None)
@given(
    bus_type=st.integers(0, 7),
    bus=st.integers(0, 31),
    address=st.integers(0, 255),
    devtype=st.integers(0, 255),
)
def test_encode_decode_round_trip(bus_type: int, bus: int, address: int, devtype: int) -> None:
    value = devid.encode(bus_type, bus, address, devtype)
    assert 0 <= value <= devid.MAX_DEVICE_ID
    d = devid.decode(value, "legacy")
    assert (d.bus_type, d.bus, d.address, d.devtype) == (bus_type, bus, address, devtype)
    assert d.bus_type_name == devid.BUS_TYPES.get(bus_type)
    assert d.devtype_name == devid.legacy_table().name_of(devtype)
    # The same parts given as text (as the CLI passes them) build the same ID.
    assert devid.encode(str(bus_type), hex(bus), str(address), hex(devtype)) == value


@settings(max_examples=budget(300), deadline=None)
@given(st.integers(0, devid.MAX_DEVICE_ID))
def test_decode_encode_round_trip(value: int) -> None:
    d = devid.decode(value, None)
    assert devid.encode(d.bus_type, d.bus, d.address, d.devtype) == value
    assert devid.parse_device_id(str(value)) == devid.parse_device_id(d.hex) == value


def test_every_unique_legacy_name_encodes_to_its_code() -> None:
    table = devid.legacy_table()
    for entry in table:
        assert table.resolve(entry.qualified) == entry.code
        assert table.resolve(entry.macro.lower()) == entry.code


# --- flight logs ---------------------------------------------------------------------------------


def test_sample_log(current: Path) -> None:
    log = shared_file(shared_data.SAMPLE_LOG)
    entries = {(e.param, e.timestamp_us): e for e in devid.decode_log(log)}
    mag1 = entries["CAL_MAG1_ID", None]
    assert mag1.value == 592905 and mag1.device is not None and mag1.problem is None
    d = mag1.device
    assert (d.devtype_name, d.bus_type_name, d.bus, d.address) == ("AK09916", "I2C", 1, 0x0C)
    for empty in ("CAL_MAG2_ID", "CAL_MAG3_ID"):
        device = entries[empty, None].device
        assert device is not None and device.no_device and device.describe() == "no device"
    names = {param for param, _ in entries}
    assert {f"CAL_{s}{i}_ID" for s in ("ACC", "GYRO") for i in range(3)} <= names
    assert all(name.startswith("CAL_") for name in names)
    assert "CAL_MAG_SIDES" not in names and "CAL_ACC0_XOFF" not in names


def test_sample_log_cli(current: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = str(shared_file(shared_data.SAMPLE_LOG))
    code, out, err = run_cli(capsys, "--log", log)
    assert (code, err) == (0, "")
    lines = {line.split()[0]: line for line in out.splitlines()}
    assert lines["CAL_MAG1_ID"].endswith("592905 0x090C09  AK09916 (MAG), I2C bus 1, address 0x0C")
    assert lines["CAL_MAG2_ID"].endswith("no device")
    code, out, _ = run_cli(capsys, "--log", log, "--json")
    doc = json.loads(out)
    # The log's firmware is v1.11.2 (ver_sw_release 0x010B0200): read with that era's table.
    assert code == 0 and doc["file"] == log and doc["table"] == "px4-v1.11"
    rows = {r["param"]: r for r in doc["parameters"]}
    assert rows["CAL_MAG1_ID"]["device"]["devtype_name"] == "AK09916"
    assert rows["CAL_MAG2_ID"]["device"]["no_device"] is True


def ulog_message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def ulog_param(name: str, value: int | float) -> bytes:
    if isinstance(value, float):
        ctype, packed = "float", struct.pack("<f", value)
    else:
        ctype, packed = "int32_t", struct.pack("<i", value)
    key = f"{ctype} {name}".encode()
    return ulog_message(b"P", bytes([len(key)]) + key + packed)


def write_ulog(path: Path, initial: dict[str, int | float], changed: dict[str, int]) -> Path:
    """A minimal ULog: header, flag bits, parameters, a log line, then changed parameters."""
    data = b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 2_500_000)
    data += ulog_message(b"B", bytes(16) + bytes(24))
    data += b"".join(ulog_param(k, v) for k, v in initial.items())
    data += ulog_message(b"L", b"6" + struct.pack("<Q", 2_500_000) + b"armed")  # data section
    data += b"".join(ulog_param(k, v) for k, v in changed.items())
    path.write_bytes(data)
    return path


def test_crafted_log(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = write_ulog(
        tmp_path / "crafted.ulg",
        {"CAL_MAG0_ID": 73225, "CAL_ACC0_ID": 66826.0, "CAL_GYRO0_ID": -1, "SYS_ID": 3},
        {"CAL_MAG0_ID": 263178},
    )
    entries = devid.decode_log(log, "legacy")
    summary = [
        (e.param, e.value, e.device.devtype_name if e.device else e.problem, e.timestamp_us)
        for e in entries
    ]
    assert summary == [
        ("CAL_ACC0_ID", 66826, "HMC5883", None),  # an old float parameter still decodes
        ("CAL_GYRO0_ID", -1, "-1 is not a 24-bit device ID", None),
        ("CAL_MAG0_ID", 73225, "HMC5883", None),
        ("CAL_MAG0_ID", 263178, "MPU9250", 2_500_000),
    ]
    code, out, err = run_cli(capsys, "--table", "legacy", "--log", str(log))
    assert (code, err) == (0, "")
    assert "invalid: -1 is not a 24-bit device ID" in out and "@2.500s" in out


def test_log_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    missing = tmp_path / "missing.ulg"
    not_ulog = tmp_path / "notes.ulg"
    not_ulog.write_text("these are not flight data\n")
    empty = write_ulog(tmp_path / "empty.ulg", {"SYS_ID": 1}, {})
    cases = [
        (missing, f"{missing}: cannot read: No such file or directory"),
        (not_ulog, f"{not_ulog}: not a ULog file (it does not start with ULog's magic bytes)"),
        (tmp_path, f"{tmp_path}: cannot read: is a folder, not a file"),
        (empty, f"{empty}: no CAL_*_ID parameters in this log"),
    ]
    for path, message in cases:
        if path != empty:
            with pytest.raises(DeviceIdError) as e:
                devid.decode_log(path, "legacy")
            assert message in str(e.value)
        code, out, err = run_cli(capsys, "--table", "legacy", "--log", str(path))
        assert (code, out) == (1, "")
        assert_one_line_error(err, message)
    assert devid.decode_log(empty, "legacy") == []


# --- the command line ----------------------------------------------------------------------------


def test_list(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "--list", "--table", "legacy")
    assert code == 0 and out.splitlines()[0].split() == ["0x01", "MAG", "HMC5883"]
    code, out, _ = run_cli(capsys, "--list", "--table", "legacy", "--json")
    rows = json.loads(out)
    assert rows[3] == {
        "code": 4,
        "name": "MPU9250",
        "kind": "MAG",
        "macro": "DRV_MAG_DEVTYPE_MPU9250",
    }


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "give device IDs, or one of --encode, --log FILE, --list"),
        (["1", "--list"], "give device IDs, or one of"),
        (["--encode", "--bus", "1"], "--encode needs --bus-type, --address, --devtype"),
        (["--bus", "1", "5"], "go with --encode"),
        (["--devtypes", "x.tsv", "--table", "legacy", "1"], "does not go with --table legacy"),
    ],
)
def test_usage_errors(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["devid", *argv])
    err = capsys.readouterr().err
    assert e.value.code == 2 and message in err.splitlines()[-1] and "Traceback" not in err


def test_help_has_an_example(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["devid", "--help"]) == 0
    out = capsys.readouterr().out
    assert "px4params devid --table legacy 73225" in out and "--encode --bus-type i2c" in out


def test_subprocess_contract(tmp_path: Path) -> None:
    """The installed command: exit codes, one stderr line, no traceback, JSON on stdout."""
    env = {**os.environ, devid.DEVTYPES_ENV: str(tmp_path / "absent.tsv")}

    def run(*argv: str) -> subprocess.CompletedProcess[str]:
        command = [sys.executable, "-m", "px4params", "devid", *argv]
        return subprocess.run(command, capture_output=True, text=True, env=env, check=False)

    ok = run("--table", "legacy", "--json", "73225")
    assert ok.returncode == 0 and json.loads(ok.stdout)[0]["devtype_name"] == "HMC5883"
    for argv, message in (
        (("--table", "legacy", "0x1000000"), "does not fit in 24 bits"),
        (("592905",), "$PX4PARAMS_DEVTYPES not found"),
        (("--table", "legacy", "--log", str(tmp_path / "x.ulg")), "x.ulg: cannot read: No such"),
    ):
        bad = run(*argv)
        assert bad.returncode == 1 and bad.stdout == ""
        assert_one_line_error(bad.stderr, message)


def test_a_2017_log_is_read_with_the_table_of_its_era(current: Path) -> None:
    """sample_appended_multiple.ulg is PX4 v1.6.0 (2017): its CAL_ACC0_ID 0x370E0A is the
    ICM-20602 of drv_sensor.h then (DRV_ACC_DEVTYPE_ICM20602 0x37), not today's BMI270, and its
    CAL_ACC1_ID 0x16040A an MPU9250 accelerometer, not today's FLOW simulator."""
    log = shared_file("sample_appended_multiple.ulg")
    entries = {e.param: e for e in devid.decode_log(log) if e.timestamp_us is None}
    acc0, acc1 = entries["CAL_ACC0_ID"].device, entries["CAL_ACC1_ID"].device
    assert acc0 is not None and acc1 is not None
    assert (acc0.table, acc0.devtype_name, acc0.devtype_kind) == ("px4-v1.6", "ICM20602", "ACC")
    assert (acc1.devtype_name, acc1.devtype_kind) == ("MPU9250", "ACC")
    assert not any(e.warning for e in entries.values())
    # With today's table the same codes are other chips, and a FLOW code in CAL_ACC is flagged.
    today = {e.param: e for e in devid.decode_log(log, "current") if e.timestamp_us is None}
    assert today["CAL_ACC0_ID"].device.devtype_name == "BMI270"  # type: ignore[union-attr]
    assert today["CAL_ACC1_ID"].warning == (
        "devtype 0x16 is FLOW in the current table, which does not fit CAL_ACC1_ID (ACC/IMU): "
        "the log may be of another era (--table)"
    )


def test_tables_by_release() -> None:
    release = lambda major, minor, patch: major << 24 | minor << 16 | patch << 8  # noqa: E731
    assert devid.table_for_release(release(1, 6, 0)) == "px4-v1.6"
    assert devid.table_for_release(release(1, 10, 2)) == "px4-v1.8"
    assert devid.table_for_release(release(1, 12, 3)) == "px4-v1.11"
    assert devid.table_for_release(release(1, 13, 2)) == "px4-v1.13"
    assert devid.table_for_release(release(1, 14, 0)) == "current"
    assert devid.table_for_release(release(1, 5, 5)) == "legacy"
    # No version: the era rule (PX4 1.12's CAL_*_PRIO parameters, else before 1.6).
    assert devid.table_for_release(None) == "px4-v1.6"
    assert devid.table_for_release(0, {"CAL_MAG0_EN": 1}) == "px4-v1.6"
    assert devid.table_for_release(None, {"CAL_MAG0_PRIO": 50}) == "current"
    # A parameter PX4 1.13 did not have (msp_osd's, the performance model's) says 1.14 on.
    assert devid.table_for_release(None, {"FW_THR_ASPD_MIN": 0.34}) == "current"
    assert devid.table_for_release(None, {"OSD_SYMBOLS": 2637823, "CAL_MAG0_EN": 1}) == "current"
    assert devid.table_for_version((1, 7, 99)) == "px4-v1.6"
    assert devid.table_for_version((1, 8, 0)) == "px4-v1.8"
    # Known answers written down from each era's drv_sensor.h: 0x37 and the ICM-20602.
    assert devid.load_table("px4-v1.8").name_of(0x37) == "ICM20602"
    assert devid.load_table("px4-v1.11").name_of(0x37) == "ICM20602_LEGACY"
    assert devid.load_table("px4-v1.11").name_of(0x38) == "ICM20602"
    assert devid.load_table("px4-v1.13").name_of(0x37) is None


def test_a_log_without_a_release_is_read_with_the_era_rule(tmp_path: Path) -> None:
    """Issue 34, defect 5: a ULog without ver_sw_release (PX4 before 1.6) is not read with
    today's table. 0x160000 in CAL_ACC1_ID is the MPU9250 accelerometer of 2016/2017
    (DRV_ACC_DEVTYPE_MPU9250 0x16), today's FLOW simulator; with a CAL_*_PRIO parameter
    (PX4 1.12 on) the log is read with today's table."""
    old = write_ulog(tmp_path / "old.ulg", {"CAL_ACC1_ID": 0x160000, "CAL_MAG0_EN": 1}, {})
    (acc,) = [e for e in devid.decode_log(old) if e.param == "CAL_ACC1_ID"]
    assert acc.device is not None
    assert (acc.device.table, acc.device.devtype_name, acc.device.devtype_kind) == (
        "px4-v1.6", "MPU9250", "ACC",
    )  # fmt: skip
    assert acc.warning is None
    new = write_ulog(tmp_path / "new.ulg", {"CAL_ACC1_ID": 0x370000, "CAL_ACC1_PRIO": 50}, {})
    (acc,) = [e for e in devid.decode_log(new) if e.param == "CAL_ACC1_ID"]
    assert acc.device is not None and (acc.device.table, acc.device.devtype_name) == (
        "current", "BMI270",
    )  # fmt: skip


# -- a PX4 1.7 log with the 1.6 era's table (issue 40) -----------------------------------------
# ``px4params devid --log`` reads a log of PX4 1.7.x with the 1.6 era's devtype table
# (docs/device-ids.md: "``px4-v1.6`` ... are ``drv_sensor.h`` as PX4 1.6-1.7"; ``px4-v1.8`` from
# 1.8). Issue 40: with that era ending at 1.6.99, the suite stayed green: no test log is of 1.7.
#
# No real 1.7 ULog is at hand (``../shared/data/qgc_px4_mocklink.params`` is PX4 1.7.2 but a
# ``.params`` file carries no firmware version), so the logs are written here byte by byte from
# the ULog specification (PX4 dev guide, "ULog File Format"): the header, the flag bits, an
# information message ``uint32_t ver_sw_release`` (major, minor, patch, type in its four bytes,
# type 255 a release) and a parameter ``int32_t CAL_MAG0_ID``.
#
# The known answer that tells the eras apart: devtype 0x03 of a magnetometer was
# ``DRV_MAG_DEVTYPE_ACCELSIM`` in drv_sensor.h as PX4 1.6-1.7 had it (and in the PX4 driver
# guide's table of that time), ``DRV_MAG_DEVTYPE_MAGSIM`` from 1.8.


CLI = [sys.executable, "-m", "px4params"]
#: A simulated magnetometer: bus type 4 (simulation), bus 1, address 0, devtype 0x03.
SIM_MAG = 0x03 << 16 | 0 << 8 | 1 << 3 | 4


def _message(kind: str, body: bytes) -> bytes:
    return struct.pack("<HB", len(body), ord(kind)) + body


def _key_value(key: str, value: bytes) -> bytes:
    return bytes([len(key)]) + key.encode() + value


def write_release_ulog(path: Path, release: tuple[int, int, int, int], device_id: int) -> None:
    major, minor, patch, kind = release
    data = b"ULog\x01\x12\x35" + b"\x01" + struct.pack("<Q", 0)  # magic, version 1, start
    data += _message("B", bytes(8) + bytes(8) + bytes(3 * 8))  # no flags, no appended data
    version = major << 24 | minor << 16 | patch << 8 | kind
    data += _message("I", _key_value("uint32_t ver_sw_release", struct.pack("<I", version)))
    data += _message("P", _key_value("int32_t CAL_MAG0_ID", struct.pack("<i", device_id)))
    path.write_bytes(data)


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("release", "table", "name"),
    [
        ((1, 7, 0, 255), "px4-v1.6", "ACCELSIM"),
        ((1, 7, 2, 255), "px4-v1.6", "ACCELSIM"),  # MockLink's PX4 version
        ((1, 7, 4, 128), "px4-v1.6", "ACCELSIM"),  # a 1.7.4 beta
        ((1, 6, 0, 255), "px4-v1.6", "ACCELSIM"),
        ((1, 8, 0, 255), "px4-v1.8", "MAGSIM"),
    ],
    ids=["1.7.0", "1.7.2", "1.7.4beta", "1.6.0", "1.8.0"],
)
def test_a_px4_1_7_log_is_read_with_the_1_6_era_table(
    tmp_path: Path, release: tuple[int, int, int, int], table: str, name: str
) -> None:
    log = tmp_path / "era.ulg"
    write_release_ulog(log, release, SIM_MAG)
    result = subprocess.run(
        [*CLI, "devid", "--log", str(log), "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env={k: v for k, v in os.environ.items() if k != "PX4PARAMS_DEVTYPES"},
    )
    assert result.returncode == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["table"] == table
    (entry,) = doc["parameters"]
    assert entry["param"] == "CAL_MAG0_ID" and entry["value"] == SIM_MAG
    assert entry["device"]["devtype"] == 3
    assert entry["device"]["devtype_name"] == name
    assert entry["device"]["devtype_kind"] == "MAG"


# -- what the mutation run of issue 40 found no test for ------------------------------------------
# Each from the rule: PX4's DeviceStructure and DeviceBusType (drivers/device/Device.hpp), the
# drivers' device IDs, the eras of docs/device-ids.md, and the device IDs of the real logs in
# ../shared/data (decoded by hand below from the layout).


#: A release's ver_sw_release: major, minor, patch and type (255: a release) in its four bytes.
def _release(major: int, minor: int, patch: int, kind: int = 255) -> int:
    return major << 24 | minor << 16 | patch << 8 | kind


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("first", "last", "label"),
    [
        ((1, 6), (1, 7), "px4-v1.6"),
        ((1, 8), (1, 10), "px4-v1.8"),
        ((1, 11), (1, 12), "px4-v1.11"),
        ((1, 13), (1, 13), "px4-v1.13"),
    ],
)
def test_every_patch_release_of_an_era_reads_with_its_table(
    first: tuple[int, int], last: tuple[int, int], label: str
) -> None:
    """docs/device-ids.md: the tables are drv_sensor.h as PX4 1.6-1.7, 1.8-1.10, 1.11-1.12 and
    1.13 had it: every patch release of those lines, and ver_sw_release's patch is a byte."""
    for major, minor in {first, last}:
        for patch in (0, 1, 9, 99, 100, 255):
            assert devid.table_for_version((major, minor, patch)) == label, (minor, patch)
            assert devid.table_for_release(_release(major, minor, patch)) == label
            assert devid.table_for_release(_release(major, minor, patch, 0)) == label  # a dev build
    # The lines either side belong to the neighbouring tables.
    assert devid.table_for_version((first[0], first[1] - 1, 255)) != label
    assert devid.table_for_version((last[0], last[1] + 1, 0)) != label


@pytest.mark.issue40
def test_the_eras_end_at_legacy_below_and_current_above() -> None:
    assert devid.table_for_version((1, 5, 255)) == "legacy"
    assert devid.table_for_version((0, 9, 0)) == "legacy"
    assert devid.table_for_version((1, 14, 0)) == "current"
    assert devid.table_for_version((1, 15, 4)) == "current"
    assert devid.table_for_version((2, 0, 0)) == "current"


@pytest.mark.issue40
def test_every_table_can_be_named(capsys: pytest.CaptureFixture[str]) -> None:
    """The tables of docs/device-ids.md, each by its name, in the library and on the command line
    (the shipped current table: no variable, no file)."""
    names = ("legacy", "current", "px4-v1.6", "px4-v1.8", "px4-v1.11", "px4-v1.13")
    with pytest.raises(DeviceIdError) as e:
        devid.load_table("px4-v1.7")
    assert str(e.value) == (
        f"unknown devtype table 'px4-v1.7' (expected one of: {', '.join(names)})"
    )
    for name in names:
        assert devid.load_table(name).label == name
        code, out, err = run_cli(capsys, "--table", name, "--json", "73225")
        assert (code, err) == (0, "") and json.loads(out)[0]["table"] == name
    code, out, _ = run_cli(capsys, "--table", "current", "592905")
    assert (code, out) == (0, "592905 (0x090C09): AK09916 (MAG), I2C bus 1, address 0x0C\n")


#: PX4's DeviceBusType (drivers/device/Device.hpp): the bus type in bits 0-2 of a device ID.
PX4_BUS_TYPES = {0: "unknown", 1: "I2C", 2: "SPI", 3: "UAVCAN", 4: "simulation", 5: "serial",
                 6: "MAVLink"}  # fmt: skip


@pytest.mark.issue40
def test_bus_types_are_px4s() -> None:
    for code, name in PX4_BUS_TYPES.items():
        value = 0x4A << 16 | 0x21 << 8 | 2 << 3 | code  # devtype 0x4A, address 0x21, bus 2
        d = devid.decode(value, None)
        assert (d.bus_type, d.bus_type_name, d.bus, d.address) == (code, name, 2, 0x21)
        # By name, in any case, as the CLI's --bus-type takes it.
        for spelling in (name, name.lower(), name.upper()):
            assert devid.encode(spelling, 2, 0x21, 0x4A) == value, spelling
    assert devid.decode(7, None).bus_type_name is None
    # Each bus type's address byte, as the driver guide explains it.
    assert devid.decode(0x4A2115, None).describe() == "devtype 0x4A, serial bus 2, address 0x21"
    assert devid.decode(0x4A2116, None).describe() == "devtype 0x4A, MAVLink bus 2, address 0x21"
    assert devid.decode(0x4A2112, None).describe() == "devtype 0x4A, SPI bus 2, device 33"
    assert devid.decode(0x4A2113, None).describe() == "devtype 0x4A, UAVCAN bus 2, node 33"
    assert devid.decode(0x4A2110, None).describe() == (
        "devtype 0x4A, bus type 0, bus 2, address 0x21"
    )


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("spelling", "code"), [("sim", 4), ("dronecan", 3), ("can", 3), ("uart", 5), ("CAN", 3)]
)
def test_bus_type_spellings(spelling: str, code: int, capsys: pytest.CaptureFixture[str]) -> None:
    """DroneCAN is UAVCAN v0 (bus type 3) and rides on CAN; a serial port is a UART."""
    assert devid.encode(spelling, 0, 0, 0) == code
    argv = ["--encode", "--bus-type", spelling, "--bus", "1", "--address", "2", "--devtype", "3"]
    code_, out, _ = run_cli(capsys, *argv, "--json")
    assert code_ == 0 and json.loads(out)["bus_type_name"] == PX4_BUS_TYPES[code]


@pytest.mark.issue40
def test_a_table_row_cannot_be_changed() -> None:
    """A table hands out its rows: a caller changing one would change the table for everyone."""
    row = devid.legacy_table().lookup(0x01)[0]
    with pytest.raises(AttributeError):
        row.name = "QMC5883"  # type: ignore[misc]
    assert devid.legacy_table().name_of(0x01) == "HMC5883"
    assert {row, devid.Devtype(0x01, "HMC5883", "MAG")} == {row}  # rows are values


def _no_device_or_decoded(entries: list[devid.LogDeviceId]) -> dict[str, str]:
    return {e.param: e.device.describe() for e in entries if e.device and e.timestamp_us is None}


@pytest.mark.issue40
def test_a_px4_1_15_log_known_answers() -> None:
    """frrs_ekf_failure.ulg (PX4 1.15 beta, NXP MR-Tropic), decoded by hand from the layout:
    0x660022 is devtype 0x66 (DRV_GYR_DEVTYPE_BMI088), address 0, 0x22 = bus 4 << 3 | SPI;
    0x6E7621 is 0x6E (DRV_BARO_DEVTYPE_BMP390) at 0x76 on I2C bus 4; 0xE51421 the BMM350
    (0xE5) at 0x14 on I2C bus 4. Each is the sensor kind of its parameter: no warning."""
    entries = devid.decode_log(shared_file("frrs_ekf_failure.ulg"))
    shown = _no_device_or_decoded(entries)
    assert shown["CAL_GYRO1_ID"] == "BMI088 (GYR), SPI bus 4, device 0"
    assert shown["CAL_ACC1_ID"] == "BMI088 (ACC), SPI bus 4, device 0"
    assert shown["CAL_BARO0_ID"] == "BMP390 (BARO), I2C bus 4, address 0x76"
    assert shown["CAL_MAG1_ID"] == "BMM350 (MAG), I2C bus 4, address 0x14"
    assert shown["CAL_GYRO0_ID"] == shown["CAL_ACC0_ID"] == "ICM42686P (IMU), SPI bus 3, device 0"
    assert all(e.device and e.device.table == "current" for e in entries)
    assert [e.param for e in entries if e.warning] == []


@pytest.mark.issue40
def test_a_simulator_log_known_answers() -> None:
    """sample_px4_events.ulg is a SITL log: its sensors are on bus type 4, simulation.
    0x14010C: devtype 0x14 (DRV_IMU_DEVTYPE_SIM), address 1, 0x0C = bus 1 << 3 | 4;
    0x03030C: 0x03 (DRV_MAG_DEVTYPE_MAGSIM) at address 3."""
    entries = devid.decode_log(shared_file("sample_px4_events.ulg"))
    shown = _no_device_or_decoded(entries)
    assert shown["CAL_ACC0_ID"] == "SIM (IMU), simulation bus 1, address 0x01"
    assert shown["CAL_GYRO2_ID"] == "SIM (IMU), simulation bus 3, address 0x01"
    assert shown["CAL_MAG0_ID"] == "MAGSIM (MAG), simulation bus 1, address 0x03"
    assert shown["CAL_BARO0_ID"] == "no device"
    assert [e.param for e in entries if e.warning] == []


@pytest.mark.issue40
def test_the_cubeorange_log_has_no_kind_warnings() -> None:
    """sample_log_small.ulg (PX4 1.11.2): IMU devtypes in CAL_ACC and CAL_GYRO, AK09916s in
    CAL_MAG, each of its parameter's kind."""
    entries = devid.decode_log(shared_file(shared_data.SAMPLE_LOG))
    assert {e.device.devtype_kind for e in entries if e.device and not e.device.no_device} == {
        "IMU", "MAG",
    }  # fmt: skip
    assert [e.param for e in entries if e.warning] == []


#: An ADIS16448 on SPI bus 1, chip select 0: DRV_IMU_DEVTYPE_ADIS16448 0x57 (drv_sensor.h).
ADIS16448 = 0x57 << 16 | 0 << 8 | 1 << 3 | 2


@pytest.mark.issue40
@pytest.mark.parametrize("param", ["CAL_ACC0_ID", "CAL_GYRO0_ID", "CAL_MAG0_ID", "CAL_BARO0_ID"])
def test_an_imus_devtype_fits_each_of_its_sensors(param: str) -> None:
    """PX4's ADIS16448 driver publishes its accelerometer, gyro, magnetometer and barometer with
    the one device ID of the chip (PX4/PX4-Autopilot
    src/drivers/imu/analog_devices/adis16448/ADIS16448.cpp): an IMU devtype is no mistake in
    any of the four calibration slots."""
    device = devid.decode(ADIS16448, "current")
    assert (device.devtype_name, device.devtype_kind) == ("ADIS16448", "IMU")
    assert devid.kind_mismatch(param, device) is None


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("param", "value", "allowed"),
    [
        ("CAL_MAG0_ID", 0x6E7621, "IMU/MAG"),  # the BMP390 barometer
        ("CAL_BARO0_ID", 0xE51421, "BARO/IMU"),  # the BMM350 magnetometer
        ("CAL_ACC1_ID", 0x660022, "ACC/IMU"),  # the BMI088's gyro
        ("CAL_GYRO1_ID", 0x6A0022, "GYR/GYRO/IMU"),  # the BMI088's accelerometer
    ],
)
def test_a_devtype_of_another_sensor_is_flagged(param: str, value: int, allowed: str) -> None:
    device = devid.decode(value, "current")
    assert devid.kind_mismatch(param, device) == (
        f"devtype 0x{device.devtype:02X} is {device.devtype_kind} in the current table, which "
        f"does not fit {param} ({allowed}): the log may be of another era (--table)"
    )


@pytest.mark.issue40
def test_a_table_spelling_the_gyro_kind_gyro_fits_cal_gyro(tmp_path: Path) -> None:
    """The parameters spell the sensor GYRO (CAL_GYRO0_ID), drv_sensor.h GYR: a table of one's
    own may use either."""
    tsv = tmp_path / "mine.tsv"
    tsv.write_text("0x66\tDRV_GYRO_DEVTYPE_BMI088\n")
    device = devid.decode(0x660022, devid.load_table("current", tsv))
    assert device.devtype_kind == "GYRO"
    assert devid.kind_mismatch("CAL_GYRO1_ID", device) is None
    assert devid.kind_mismatch("CAL_ACC1_ID", device) is not None


@pytest.mark.issue40
def test_a_devtype_without_a_kind_keeps_its_macro(capsys: pytest.CaptureFixture[str]) -> None:
    """Today's drv_sensor.h defines DRV_DEVTYPE_UNUSED 0xff, a macro with no sensor kind: it is
    listed, and looked up, by that spelling."""
    table = devid.load_table("current")
    (unused,) = table.lookup(0xFF)
    assert (unused.name, unused.kind, unused.macro) == ("UNUSED", None, "DRV_DEVTYPE_UNUSED")
    assert table.resolve("drv_devtype_unused") == table.resolve("UNUSED") == 0xFF
    assert devid.encode("i2c", 1, 0x0C, "DRV_DEVTYPE_UNUSED") == 0xFF0C09
    code, out, _ = run_cli(capsys, "--list", "--json")
    assert code == 0 and json.loads(out)[-1] == {
        "code": 255, "name": "UNUSED", "kind": None, "macro": "DRV_DEVTYPE_UNUSED",
    }  # fmt: skip
    assert repr(devid.legacy_table()) == "DevtypeTable('legacy', 'the PX4 driver guide', 16 codes)"


#: The PX4 driver guide's "Device IDs" table, as the guide prints it (drv_sensor.h's defines).
DRIVER_GUIDE_TABLE = """\
#define DRV_MAG_DEVTYPE_HMC5883  0x01
#define DRV_MAG_DEVTYPE_LSM303D  0x02
#define DRV_MAG_DEVTYPE_ACCELSIM 0x03
#define DRV_MAG_DEVTYPE_MPU9250  0x04
#define DRV_ACC_DEVTYPE_LSM303D  0x11
#define DRV_ACC_DEVTYPE_BMA180   0x12
#define DRV_ACC_DEVTYPE_MPU6000  0x13
#define DRV_ACC_DEVTYPE_ACCELSIM 0x14
#define DRV_ACC_DEVTYPE_GYROSIM  0x15
#define DRV_ACC_DEVTYPE_MPU9250  0x16
#define DRV_GYR_DEVTYPE_MPU6000  0x21
#define DRV_GYR_DEVTYPE_L3GD20   0x22
#define DRV_GYR_DEVTYPE_GYROSIM  0x23
#define DRV_GYR_DEVTYPE_MPU9250  0x24
#define DRV_RNG_DEVTYPE_MB12XX   0x31
#define DRV_RNG_DEVTYPE_LL40LS   0x32
"""


@pytest.mark.issue40
def test_the_legacy_table_is_the_driver_guides_row_for_row() -> None:
    guide = [line.split()[1:] for line in DRIVER_GUIDE_TABLE.splitlines()]
    assert [(e.macro, f"0x{e.code:02X}") for e in devid.legacy_table()] == [
        (macro, code.upper().replace("0X", "0x")) for macro, code in guide
    ]
    # The 1.6 era's header names each of these codes the same (the era rule relies on it).
    era = devid.load_table("px4-v1.6")
    for entry in devid.legacy_table():
        assert (era.name_of(entry.code), era.kind_of(entry.code)) == (entry.name, entry.kind)


@pytest.mark.issue40
def test_the_devtype_name_errors_word_for_word() -> None:
    """docs/device-ids.md's ambiguous name, and a misspelling's hint of at most three spellings
    (one line: MPU9250 has four close ones in the guide's table)."""
    with pytest.raises(DeviceIdError) as e:
        devid.encode("spi", 1, 4, "MPU9250", "legacy")
    assert str(e.value) == (
        "devtype 'MPU9250' is ambiguous in the legacy table: give one of MAG_MPU9250 (0x04), "
        "ACC_MPU9250 (0x16), GYR_MPU9250 (0x24), or a code"
    )
    with pytest.raises(DeviceIdError) as e:
        devid.encode("spi", 1, 4, "MPU925", "legacy")
    message = str(e.value)
    hint = message.split("did you mean ", 1)[1].split("? ", 1)[0].split(", ")
    assert len(hint) == 3 and hint[0] == "MPU9250" and set(hint) < {
        "MPU9250", "MAG_MPU9250", "ACC_MPU9250", "GYR_MPU9250",
    }  # fmt: skip
    assert message == (
        f"unknown devtype 'MPU925' in the legacy table (did you mean {', '.join(hint)}? give a "
        "code 0..255 or a name from 'px4params devid --list --table legacy')"
    )


@pytest.mark.issue40
def test_header_values_in_c_spellings(tmp_path: Path) -> None:
    """A #define's value is a C integer literal, maybe in parentheses and with the suffixes C
    allows (u, U, l, L); decimal codes are read in base 10."""
    header = tmp_path / "drv_sensor.h"
    header.write_text(
        "#define DRV_MAG_DEVTYPE_A (0x0A)\n#define DRV_MAG_DEVTYPE_B 0x0Bu\n"
        "#define DRV_MAG_DEVTYPE_C 0x0CUL\n#define DRV_BARO_DEVTYPE_D 55\n"
        "#define DRV_BARO_DEVTYPE_E (19L)\n"
    )
    table = devid.load_table("current", header)
    assert [(e.code, e.name) for e in table] == [
        (0x0A, "A"), (0x0B, "B"), (0x0C, "C"), (19, "E"), (55, "D"),
    ]  # fmt: skip


@pytest.mark.issue40
def test_bad_table_lines_word_for_word(tmp_path: Path) -> None:
    tsv = tmp_path / "t.tsv"
    for text, message in (
        ("one\tA\n", f"{tsv}:1: devtype code 'one' is not a number"),
        (
            f"{'1' * 70}\tA\n",
            f"{tsv}:1: devtype code 111111111111...111111 (70 characters) is out of range "
            "(70 digits: no value is wider than 64 bits)",
        ),
        ("0x100\tA\n", f"{tsv}:1: devtype code 0x100 is out of range 0..255 (0x00..0xFF)"),
    ):
        tsv.write_text(text)
        with pytest.raises(DeviceIdError) as e:
            devid.load_table("current", tsv)
        assert str(e.value) == message


@pytest.mark.issue40
def test_the_default_table_is_todays() -> None:
    assert devid.load_table().label == "current"
    assert devid.load_table().name_of(0x37) == "BMI270"  # docs/device-ids.md: since 1.14


@pytest.mark.issue40
def test_a_table_file_with_a_stray_byte_or_too_large(tmp_path: Path) -> None:
    """A header saved in Latin-1 (a comment's author name) still gives its codes; a file over
    the devtypes cap is refused by name before it is read."""
    header = tmp_path / "drv_sensor.h"
    header.write_bytes(b"/* Fran\xe7ois */\n#define DRV_MAG_DEVTYPE_AK09916 0x09\n")
    assert devid.load_table("current", header).name_of(0x09) == "AK09916"
    big = tmp_path / "big.tsv"
    big.write_bytes(b"# " + b"x" * (2 * 1024 * 1024) + b"\n0x09\tAK09916\n")
    with pytest.raises(DeviceIdError) as e:
        devid.load_table("current", big)
    assert str(e.value) == (
        f"cannot read devtypes file {big}: too large for a devtypes table (2 MiB; at most 1 MiB)"
    )


#: Parameters PX4 1.14 added (not in the 1.13 tree), each where PX4-Autopilot defines it.
SINCE_PX4_1_14 = {
    "OSD_SYMBOLS": "src/drivers/osd/msp_osd/module.yaml",
    "OSD_SCROLL_RATE": "src/drivers/osd/msp_osd/module.yaml",
    "MPC_VEL_MAN_SIDE": "src/modules/mc_pos_control/multicopter_position_mode_params.yaml",
    "FW_THR_ASPD_MIN": "src/lib/fw_performance_model/performance_model_params.yaml",
    "FW_T_THR_DAMPING": "src/modules/fw_lateral_longitudinal_control/fw_lat_long_params.yaml",
}


@pytest.mark.issue40
@pytest.mark.parametrize("name", sorted(SINCE_PX4_1_14))
def test_each_parameter_newer_than_1_13_means_todays_table(name: str) -> None:
    """docs/device-ids.md: a file without a version that holds a parameter PX4 1.13 did not
    have is read with today's table, and the report says which parameter and where PX4 has it."""
    table, why = devid.table_for_parameters({name: 1, "CAL_MAG0_EN": 1})
    assert table == "current"
    assert why == (
        f"no firmware version: {name} exists (PX4 1.14 and later; not in 1.13, "
        f"{SINCE_PX4_1_14[name]}), so today's devtype table is assumed"
    )


@pytest.mark.issue40
def test_the_era_rule_says_why_word_for_word() -> None:
    assert devid.table_for_parameters({"CAL_GYRO1_PRIO": 50, "CAL_ACC0_PRIO": 50}) == (
        "current",
        "no firmware version: CAL_ACC0_PRIO exists (PX4 1.12 and later), so today's devtype "
        "table is assumed",
    )
    assert devid.table_for_parameters({"CAL_MAG0_EN": 1}) == (
        "px4-v1.6",
        "no firmware version and no CAL_*_PRIO parameters (PX4 before 1.12): the px4-v1.6 "
        "devtype table is assumed (files without a version predate it: ULog's ver_sw_release "
        "and QGC's '# Version' came with PX4 1.6)",
    )


@pytest.mark.issue40
def test_a_code_two_sensors_share_fits_either(capsys: pytest.CaptureFixture[str]) -> None:
    """drv_sensor.h as PX4 1.13 had it defines 0x4C twice: DRV_DIFF_PRESS_DEVTYPE_SDP33 and
    DRV_BARO_DEVTYPE_LPS33HW. An LPS33HW (I2C bus 1, 0x5C) in a barometer slot is no mistake;
    in a magnetometer slot it is."""
    device = devid.decode(0x4C5C09, "px4-v1.13")
    assert (device.devtype_name, device.devtype_kind) == ("SDP33/LPS33HW", "DIFF_PRESS/BARO")
    assert devid.kind_mismatch("CAL_BARO0_ID", device) is None
    assert devid.kind_mismatch("CAL_MAG0_ID", device) == (
        "devtype 0x4C is DIFF_PRESS/BARO in the px4-v1.13 table, which does not fit CAL_MAG0_ID "
        "(IMU/MAG): the log may be of another era (--table)"
    )


@pytest.mark.issue40
def test_a_decoded_id_is_a_value_and_its_json_fields() -> None:
    """docs/device-ids.md's 592905: devtype 0x09, address 0x0C, I2C bus 1. A decoded ID is a
    value (equal, hashable, not to be changed), and --json gives each field by name."""
    d = devid.decode(592905, "current")
    assert d == devid.decode(0x090C09, "current") and len({d, devid.decode(592905)}) == 1
    with pytest.raises(AttributeError):
        d.bus = 2  # type: ignore[misc]
    assert d.as_dict() == {
        "id": 592905,
        "hex": "0x090C09",
        "no_device": False,
        "bus_type": 1,
        "bus_type_name": "I2C",
        "bus": 1,
        "address": 12,
        "devtype": 9,
        "devtype_name": "AK09916",
        "devtype_kind": "MAG",
        "table": "current",
        "description": "AK09916 (MAG), I2C bus 1, address 0x0C",
    }
    # A devtype without a sensor kind is named alone.
    assert devid.decode(0xFF0C09, "current").describe() == "UNUSED, I2C bus 1, address 0x0C"


@pytest.mark.issue40
def test_bad_device_ids_word_for_word() -> None:
    """docs/device-ids.md's error for an ID wider than 24 bits, and the others, whole."""
    with pytest.raises(DeviceIdError) as e:
        devid.decode(16777216, None)
    assert str(e.value) == (
        "device ID 16777216 does not fit in 24 bits (expected 0..16777215, 0x000000..0xFFFFFF)"
    )
    with pytest.raises(DeviceIdError) as e:
        devid.decode(True, None)  # type: ignore[arg-type]
    assert str(e.value) == "a device ID is an int, not bool"
    with pytest.raises(DeviceIdError) as e:
        devid.parse_device_id("9" * 70)
    assert str(e.value) == (
        "not a device ID: 999999999999...999999 (70 characters) is out of range (70 digits: no "
        "value is wider than 64 bits)"
    )


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("parts", "message"),
    [
        (("i2c", 32, 0, 0), "bus 32 is out of range 0..31"),
        (("i2c", 1, "0x100", 0), "address 0x100 is out of range 0..255, 0x00..0xFF"),
        ((8, 1, 0, 0), "bus type 8 is out of range 0..7"),
        (("i2c", "one", 0, 0), "bus 'one' is not a number (expected 0..31)"),
        (("i2c", "X1", 0, 0), "bus 'X1' is not a number (expected 0..31)"),
        (("i2c", 1.0, 0, 0), "bus must be an int, not float"),
        (
            ("i2c", 1, "9" * 70, 0),
            "address: 999999999999...999999 (70 characters) is out of range (70 digits: no value "
            "is wider than 64 bits)",
        ),
        (
            ("X1", 1, 0, 0),
            "unknown bus type 'X1' (expected one of: unknown, i2c, spi, uavcan, simulation, "
            "serial, mavlink, or 0..7)",
        ),
        (
            ("i2c", 1, 0, "X9"),
            "unknown devtype 'X9' in the legacy table (give a code 0..255 or a name from "
            "'px4params devid --list --table legacy')",
        ),
    ],
)
def test_encode_errors_word_for_word(parts: tuple[object, ...], message: str) -> None:
    with pytest.raises(DeviceIdError) as e:
        devid.encode(*parts, table="legacy")  # type: ignore[arg-type]
    assert str(e.value) == message


@pytest.mark.issue40
def test_a_log_entry_is_a_value_and_its_json(tmp_path: Path) -> None:
    """The largest 24-bit ID is still a device ID (all fields at their top: devtype 0xFF,
    address 0xFF, bus 31, bus type 7); one past it is not. --json gives each entry's fields by
    name, null where there is nothing."""
    log = write_ulog(tmp_path / "edge.ulg", {"CAL_MAG0_ID": 0xFFFFFF, "CAL_MAG1_ID": 0x1000000}, {})
    top, past = devid.decode_log(log, None)
    assert top.device is not None and top.problem is None
    assert (top.device.devtype, top.device.address, top.device.bus, top.device.bus_type) == (
        0xFF, 0xFF, 31, 7,
    )  # fmt: skip
    assert past.as_dict() == {
        "param": "CAL_MAG1_ID",
        "value": 16777216,
        "timestamp_us": None,
        "device": None,
        "problem": "16777216 is not a 24-bit device ID",
        "warning": None,
    }
    with pytest.raises(AttributeError):
        top.value = 1  # type: ignore[misc]
    bare = devid.LogDeviceId("CAL_MAG0_ID", 0, devid.decode(0, None))
    assert (bare.problem, bare.timestamp_us, bare.warning) == (None, None, None)


@pytest.mark.issue40
def test_header_values_c_does_not_allow_are_refused(tmp_path: Path) -> None:
    """Parentheses and the suffixes u, U, l, L around a C integer literal are all that is taken
    off a #define's value (``(0x12U)``, ``0x13UL``): an X after the digits is no C suffix."""
    header = tmp_path / "drv_sensor.h"
    header.write_text("#define DRV_MAG_DEVTYPE_A (0x12U)\n#define DRV_MAG_DEVTYPE_B 0x13UL\n")
    assert [(e.code, e.name) for e in devid.load_table("current", header)] == [
        (0x12, "A"), (0x13, "B"),
    ]  # fmt: skip
    for value in ("0x1AX", "(0x1A)X"):
        header.write_text(f"#define DRV_MAG_DEVTYPE_A 0x12\n#define DRV_MAG_DEVTYPE_B {value}\n")
        with pytest.raises(DeviceIdError) as e:
            devid.load_table("current", header)
        assert str(e.value) == f"{header}:2: devtype code {value.strip('()')!r} is not a number"


@pytest.mark.issue40
def test_bad_table_file_messages_word_for_word(tmp_path: Path) -> None:
    """A TSV line that is not ``code<TAB>name`` and a file without a devtype: the whole line."""
    tsv = tmp_path / "t.tsv"
    tsv.write_text("code\tname\n0x01\n")
    with pytest.raises(DeviceIdError) as e:
        devid.load_table("current", tsv)
    assert str(e.value) == (
        f"{tsv}:2: expected 'code<TAB>name' (e.g. '0x09<TAB>DRV_MAG_DEVTYPE_AK09916'), got '0x01'"
    )
    tsv.write_text("code\tname\n")
    with pytest.raises(DeviceIdError) as e:
        devid.load_table("current", tsv)
    assert str(e.value) == (
        f"{tsv}: no devtypes found (expected 'code<TAB>name' lines or a drv_sensor.h with "
        "'#define DRV_..._DEVTYPE_... 0x..' lines)"
    )


@pytest.mark.issue40
def test_parse_devtypes_without_a_source_names_the_text_devtypes() -> None:
    with pytest.raises(DeviceIdError) as e:
        devid.parse_devtypes("0x01\n")
    assert str(e.value).startswith("<devtypes>:1: expected 'code<TAB>name' ")


@pytest.mark.issue40
def test_a_missing_devtypes_file_word_for_word(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """--devtypes and $PX4PARAMS_DEVTYPES name the file they give; an install whose own
    current.tsv is gone says which file it could not read."""
    missing = tmp_path / "nope.tsv"
    code, _, err = run_cli(capsys, "--devtypes", str(missing), "1")
    assert (code, err) == (1, f"px4params: error: devtypes file not found: {missing}\n")
    monkeypatch.setenv(devid.DEVTYPES_ENV, str(missing))
    with pytest.raises(DeviceIdError) as e:
        devid.load_table("current")
    assert str(e.value) == f"$PX4PARAMS_DEVTYPES not found: {missing}"
    monkeypatch.delenv(devid.DEVTYPES_ENV)
    monkeypatch.setattr("px4params.data.DEVTYPES_DIR", str(tmp_path))
    with pytest.raises(DeviceIdError) as e:
        devid.load_table("current")
    assert str(e.value) == (
        f"cannot read devtypes file {tmp_path / 'current.tsv'}: No such file or directory"
    )


def test_a_folder_or_fifo_given_as_the_devtypes_file_is_named_as_what_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A folder was "devtypes file not found": it is there, it is not a file.
    fifo = tmp_path / "devtypes.fifo"
    os.mkfifo(fifo)
    for path, what in (
        (tmp_path, "is a folder, not a file"),
        (fifo, "is a FIFO (named pipe), not a regular file"),
    ):
        code, _, err = run_cli(capsys, "--devtypes", str(path), "1")
        assert (code, err) == (1, f"px4params: error: cannot read devtypes file {path}: {what}\n")


def test_the_px4_v1_8_table_names_every_sensor_code_of_px4_1_8() -> None:
    """PX4's drv_sensor.h at tag v1.8.0-beta1 (read from a fetched PX4-Autopilot): every code
    there is in the px4-v1.8 table, of the same kind. 0x15 (the simulated gyro's accelerometer,
    in 1.8 SITL logs' CAL_ACC0_ID) was missing; 0x03 is a simulated magnetometer under either
    of its names (ACCELSIM then, MAGSIM from 2019-05-30)."""
    from px4_git import px4_git_dirs, show

    dirs = tuple(px4_git_dirs())
    header = show(dirs, "v1.8.0-beta1", "src/drivers/drv_sensor.h") if dirs else None
    if header is None:
        pytest.skip(
            "needs a PX4-Autopilot git directory with tag v1.8.0-beta1 ($PX4_AUTOPILOT_GIT)"
        )
    table = devid.load_table("px4-v1.8")
    defined = re.findall(r"#define DRV_(\w+?)_DEVTYPE_(\w+)\s+(0x[0-9A-Fa-f]+)", header)
    assert len(defined) > 50
    assert [
        (name, code) for kind, name, code in defined if table.kind_of(int(code, 16)) != kind
    ] == []
