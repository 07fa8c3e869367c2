"""The store file: atomic saves, complete checks before anything is applied, translation."""

from __future__ import annotations

import binascii
import math
import os
import random
import re
import signal
import struct
import subprocess
import sys
import time
import zlib
from pathlib import Path

import px4params
import pytest
from px4params.errors import StoreFileError
from px4params.store.classic import ClassicParam
from px4params.store.file import encode_file, fingerprint

# The format's constants, as docs/store-format.md gives them (written here, not imported: the
# tests build files independently of the code that reads them).
MAGIC = b"PX4P"
HEADER = struct.Struct("<4sBBI")
KIND_STRUCTURED = 1
HAS_DEFAULT = 0x10
HAS_VALUE = 0x20


def _varint(n: int) -> bytes:
    """LEB128: 7 bits a byte, low bits first, the top bit on every byte but the last."""
    out = bytearray()
    while n >= 0x80:
        out.append(n & 0x7F | 0x80)
        n >>= 7
    return bytes(out + bytes([n]))


def _crc16(data: bytes) -> int:
    """CRC-16-CCITT-FALSE: ``binascii.crc_hqx`` (XMODEM's polynomial) from 0xFFFF."""
    return binascii.crc_hqx(data, 0xFFFF)


CLASSIC = [ClassicParam("SYS_AUTOSTART", "Int32", 0), ClassicParam("BAT1_CAPACITY", "Float", -1.0)]


@pytest.fixture
def store(schema: px4params.Schema) -> px4params.Store:
    return px4params.Store(schema, classic=CLASSIC)


def realistic(store: px4params.Store) -> px4params.Store:
    """The talk's INA238, a second one on SPI, an external compass, classic values."""
    store.add("INA238#0")
    store.set_default("INA238#0[3]", 1)
    store.set_default("INA238#0[4]", 0x45)
    store.set_default("INA238#0[5]", 200)
    store.set_default("INA238#0[6]", 0.0003)
    store.add("INA238#2")
    store.set("INA238#2.bus._tag", 1)
    store.set("INA238#2.bus.spi.bus_id", 2)
    store.add("AK09916#0")
    store.set("AK09916#0.bus.i2c.bus_id", 1)
    store.set("SYS_AUTOSTART", 4001)
    store.set_default("BAT1_CAPACITY", 5000.0)
    return store


def test_save_load_round_trip(store: px4params.Store, tmp_path: Path) -> None:
    realistic(store)
    path = tmp_path / "params.store"
    size = store.save(path)
    assert size == path.stat().st_size
    again = px4params.Store.load(path, store.schema, classic=CLASSIC)
    assert list(again.names()) == list(store.names())
    for name in store.names():
        assert again.get(name) == store.get(name)
        assert again.get(name, default=True) == store.get(name, default=True)
    assert again.state("INA238#0") == (False, False)  # loaded = saved


def test_only_what_differs_is_written(store: px4params.Store, tmp_path: Path) -> None:
    empty = encode_file(store)
    assert len(empty) == HEADER.size + 4 + 4  # header, an empty table, trailer, no record
    store.add("INA238#1")  # presence is configuration: one record without payloads
    one = encode_file(store)
    line = len("INA238=px.Ina238.1") + 1  # the table names it once: length, text
    assert len(one) == len(empty) + line + 5  # + kind, parameter, instance, CRC-16
    store.add("INA238#2")
    assert len(encode_file(store)) == len(one) + 5


def test_save_keeps_a_backup(store: px4params.Store, tmp_path: Path) -> None:
    path = tmp_path / "params.store"
    store.save(path)
    first = path.read_bytes()
    store.add("INA238#0")
    store.save(path)
    assert Path(str(path) + ".bak").read_bytes() == first
    assert path.read_bytes() != first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.store", "params.store.bak"]


def test_load_resets_import_merges(store: px4params.Store, tmp_path: Path) -> None:
    path = tmp_path / "params.store"
    store.add("INA238#0")
    store.save(path)
    store.remove("INA238#0")
    store.add("INA238#3")
    store.import_from(path)
    assert store.instances("INA238") == ["INA238#0", "INA238#3"]
    store.load_from(path)
    assert store.instances("INA238") == ["INA238#0"]


def test_every_single_bit_flip_is_detected(store: px4params.Store, tmp_path: Path) -> None:
    realistic(store)
    path = tmp_path / "params.store"
    store.save(path)
    good = path.read_bytes()
    target = px4params.Store(store.schema, classic=CLASSIC)
    target.add("RM3100#1")
    before = encode_file(target)
    for bit in range(len(good) * 8):
        bad = bytearray(good)
        bad[bit // 8] ^= 0x80 >> (bit % 8)
        path.write_bytes(bad)
        with pytest.raises(StoreFileError) as info:
            target.load_from(path)
        assert "\n" not in str(info.value)
        assert encode_file(target) == before, f"bit {bit} changed the store"


def test_truncated_files_are_refused(store: px4params.Store, tmp_path: Path) -> None:
    realistic(store)
    path = tmp_path / "params.store"
    store.save(path)
    good = path.read_bytes()
    for length in range(len(good)):
        path.write_bytes(good[:length])
        with pytest.raises(StoreFileError):
            store.import_from(path)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "not a px4params store file (no PX4P header) (at byte 0)"),
        (b"BSON\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00", "not a px4params store file"),
        (b"PX4P\x04\x00\x00\x00\x00\x00", "format version 4 (this px4params reads 1 to 3)"),
        (b"PX4P\x01\x00\x00\x00\x00\x00", "file is truncated (no trailer)"),
    ],
)
def test_foreign_files(
    store: px4params.Store, tmp_path: Path, content: bytes, message: str
) -> None:
    path = tmp_path / "x.store"
    path.write_bytes(content)
    with pytest.raises(StoreFileError) as info:
        store.load_from(path)
    assert str(info.value).startswith(f"{path}: ")
    assert message in str(info.value)


def test_file_of_another_schema(store: px4params.Store, tmp_path: Path) -> None:
    body = HEADER.pack(MAGIC, 1, 0, 0x12345678)
    path = tmp_path / "other.store"
    path.write_bytes(body + struct.pack("<I", zlib.crc32(body)))
    with pytest.raises(StoreFileError, match=r"written for another schema \(fingerprint "):
        store.load_from(path)


def test_missing_file(store: px4params.Store, tmp_path: Path) -> None:
    with pytest.raises(StoreFileError, match=r"nope.store: cannot read: No such file"):
        store.load_from(tmp_path / "nope.store")


def test_unwritable_folder(store: px4params.Store, tmp_path: Path) -> None:
    with pytest.raises(StoreFileError, match=r"cannot write: No such file or directory"):
        store.save(tmp_path / "no" / "such" / "dir.store")


def test_a_record_that_cannot_be_applied(store: px4params.Store, tmp_path: Path) -> None:
    # Well-formed and CRC-correct, but instance 7 of a parameter with 4 slots.
    path = tmp_path / "bad.store"
    index = store.parameters.index("INA238")
    write_records(path, store, [bytes([KIND_STRUCTURED]) + _varint(index) + _varint(7)])
    with pytest.raises(StoreFileError) as info:
        store.load_from(path)
    assert "record cannot be applied: INA238#7: instance 7 is out of range" in str(info.value)
    assert store.instances("INA238") == []


def write_records(path: Path, store: px4params.Store, records: list[bytes]) -> None:
    body = bytearray(HEADER.pack(MAGIC, 1, 0, fingerprint(store.specs)))
    for r in records:
        body += r + struct.pack("<H", _crc16(r))
    body += struct.pack("<I", zlib.crc32(body))
    path.write_bytes(bytes(body))


def test_translation_from_an_older_version(store: px4params.Store, tmp_path: Path) -> None:
    """A value stored by px.Ina238.1.0 (shunt in micro-ohms) loads as 1.1: bus and current are
    carried over by name, the new float `shunt` takes its default, `shunt_uohm` is reported."""
    old = store.schema["px.Ina238.1.0"]
    value = {"bus": {"i2c": {"bus_id": 2, "address": 0x41}}, "current": 150, "shunt_uohm": 500}
    payload = old.encode(value, tao=False)
    index = store.parameters.index("INA238")
    record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(index) + _varint(1)
    record += _varint(len(payload)) + payload
    path = tmp_path / "old.store"
    write_records(path, store, [record])
    report = store.load_from(path)
    now = store.get("INA238#1")
    assert now["p_version"] == 1
    assert now["bus"]["i2c"] == {"p_version": 0, "bus_id": 2, "address": 0x41}
    assert now["current"] == 150
    assert now["shunt"] == pytest.approx(0.0003, rel=1e-3)  # its default
    assert report == [
        "INA238#1: translated px.Ina238.1.0 -> px.Ina238.1.1: kept bus.i2c.bus_id, "
        "bus.i2c.address, current; new, from defaults: shunt; dropped: shunt_uohm=500"
    ]
    # Saved again, it is written in the new version.
    store.save(path)
    assert px4params.Store.load(path, store.schema, classic=CLASSIC).get("INA238#1") == now


def test_translation_needs_the_old_type(store: px4params.Store, tmp_path: Path) -> None:
    payload = bytearray(
        store.schema["px.Ina238"].encode(
            {"bus": {"i2c": {"bus_id": 1, "address": 1}}, "current": 1, "shunt": 1.0}, tao=False
        )
    )
    payload[0] = (payload[0] & 0x0F) | 0x70  # p_version 7: no px.Ina238.1.7
    index = store.parameters.index("INA238")
    record = bytes([KIND_STRUCTURED | HAS_DEFAULT]) + _varint(index) + _varint(0)
    record += _varint(len(payload)) + bytes(payload)
    path = tmp_path / "future.store"
    write_records(path, store, [record])
    with pytest.raises(
        StoreFileError,
        match=r"INA238#0 was stored by px\.Ina238\.1\.7, which this schema does not have",
    ):
        store.load_from(path)


SAVER = """
import sys, px4params
from px4params.store.classic import ClassicParam
schema = px4params.load_schema(use_env=False)
store = px4params.Store(schema)
store.add("INA238#0")
print("ready", flush=True)
n = 0
while True:
    n = (n + 1) % 1000
    store.set("INA238#0.current", n)
    store.save(sys.argv[1])
"""


@pytest.mark.skipif(sys.platform == "win32", reason="uses SIGKILL")
def test_killing_a_saving_process_never_loses_the_file(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """A process saves again and again; it is killed at random moments, 40 times. Every time,
    the file (and its backup) is intact: one complete save or the other, never a mix."""
    path = tmp_path / "params.store"
    rng = random.Random(1234)
    seen_values: set[int] = set()
    env = dict(os.environ)
    for _ in range(40):
        proc = subprocess.Popen(
            [sys.executable, "-c", SAVER, str(path)], stdout=subprocess.PIPE, env=env
        )
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == b"ready"
        time.sleep(rng.uniform(0.0, 0.05))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        for candidate in (path, Path(str(path) + ".bak")):
            if candidate.exists():
                loaded = px4params.Store.load(candidate, schema)
                seen_values.add(loaded.get("INA238#0.current"))
        assert path.exists() or not Path(str(path) + ".bak").exists()
        leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
        for name in leftovers:  # a temporary file of an interrupted save: never the store
            (tmp_path / name).unlink()
    assert len(seen_values) > 1  # the kills really landed at different moments


def test_classic_values_of_unknown_parameters_are_kept(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """A store opened with fewer classic parameters keeps the others' records and saves them
    back unchanged."""
    full = px4params.Store(schema, classic=CLASSIC)
    full.set("BAT1_CAPACITY", 4200.0)
    path = tmp_path / "params.store"
    full.save(path)
    fewer = px4params.Store(schema, classic=CLASSIC[:1])
    report = fewer.load_from(path)
    assert report == ["BAT1_CAPACITY: not a classic parameter of this store; kept unchanged"]
    fewer.set("SYS_AUTOSTART", 4001)
    fewer.save(path)
    again = px4params.Store.load(path, schema, classic=CLASSIC)
    assert again.get("BAT1_CAPACITY") == 4200.0
    assert again.get("SYS_AUTOSTART") == 4001


def test_a_refused_load_keeps_unknown_classic_records(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    full = px4params.Store(schema, classic=CLASSIC)
    full.set("BAT1_CAPACITY", 4200.0)
    good = tmp_path / "good.store"
    full.save(good)
    fewer = px4params.Store(schema, classic=CLASSIC[:1])
    fewer.load_from(good)
    bad = tmp_path / "bad.params"
    bad.write_text("1\t1\tSYS_AUTOSTART\tx\t6\n")
    from px4params.store import paramfile

    with pytest.raises(paramfile.ParamFileError):
        paramfile.read(fewer, str(bad), reset=True)
    fewer.save(good)
    assert px4params.Store.load(good, schema, classic=CLASSIC).get("BAT1_CAPACITY") == 4200.0


# -- a classic parameter whose type changed between PX4 releases --------------------------------

#: COM_DISARM_LAND was an Int32 (whole seconds) and is a Float today; RC10_REV the other way
#: round (docs/file-formats.md). Here both sets are written down, one per release.
TODAY = [ClassicParam("COM_DISARM_LAND", "Float", 2.0), ClassicParam("RC10_REV", "Int32", 1)]
BEFORE = [ClassicParam("COM_DISARM_LAND", "Int32", 2), ClassicParam("RC10_REV", "Float", 1.0)]


def _classic_file(records: list[bytes], version: int = 3) -> bytes:
    return _file(version, zlib.crc32(b""), [_table([]), *records])


def _classic_record(name: str, value: bytes, flags: int = 0) -> bytes:
    """Kind 2 with a value (0x20); ``flags`` 0x40 for a float32 (format 3)."""
    return bytes([0x02 | 0x20 | flags, len(name)]) + name.encode() + value


def test_a_classic_value_saved_as_one_type_is_never_read_as_the_other(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """A float's bits read as an int32 (2.5 shown as 1075838976) or an int32's read as a float
    (-1 as NaN, the whole store then refused as damaged) would be values nobody set."""
    path = tmp_path / "v.store"
    today = px4params.Store(schema, classic=TODAY)
    today.set("COM_DISARM_LAND", 2.5)
    today.set("RC10_REV", -1)
    today.save(path)
    before = px4params.Store(schema, classic=BEFORE)
    report = before.load_from(path)
    assert report == [
        "COM_DISARM_LAND: stored as Float 2.5, Int32 in this parameter set: does not fit; "
        "kept unchanged (shown here as its default)",
        "RC10_REV: stored as Int32 -1, Float in this parameter set (its type changed between "
        "PX4 releases): taken as -1",
    ]
    assert before.get("COM_DISARM_LAND") == 2  # its default: 2.5 is no whole number of seconds
    assert before.get("RC10_REV") == -1.0
    assert before.kept_classic == ["COM_DISARM_LAND"]
    # Saved by the older set, the kept record is written back as it was, and today's set reads
    # 2.5 again (RC10_REV now as the float it became).
    before.save(path)
    again = px4params.Store.load(path, schema, classic=TODAY)
    assert again.get("COM_DISARM_LAND") == 2.5
    assert again.get("RC10_REV") == -1


def test_a_whole_float_is_taken_by_an_int32_and_a_big_integer_is_not_taken_by_a_float(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    path = tmp_path / "v.store"
    three = struct.pack("<f", 3.0)
    big = struct.pack("<i", (1 << 24) + 1)  # the first integer a float32 rounds
    path.write_bytes(
        _classic_file(
            [_classic_record("COM_DISARM_LAND", three, 0x40), _classic_record("RC10_REV", big)]
        )
    )
    before = px4params.Store(schema, classic=BEFORE)
    assert before.load_from(path) == [
        "COM_DISARM_LAND: stored as Float 3, Int32 in this parameter set (its type changed "
        "between PX4 releases): taken as 3",
        "RC10_REV: stored as Int32 16777217, Float in this parameter set: does not fit; kept "
        "unchanged (shown here as its default)",
    ]
    assert (before.get("COM_DISARM_LAND"), before.get("RC10_REV")) == (3, 1.0)


def test_a_kept_record_gives_way_to_a_value_set_since(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """Two records of one parameter would make the file unreadable: the one set wins."""
    path = tmp_path / "v.store"
    path.write_bytes(
        _classic_file([_classic_record("COM_DISARM_LAND", struct.pack("<f", 2.5), 0x40)])
    )
    before = px4params.Store(schema, classic=BEFORE)
    before.load_from(path)
    before.set("COM_DISARM_LAND", 4)
    before.save(path)
    assert px4params.Store.load(path, schema, classic=BEFORE).get("COM_DISARM_LAND") == 4
    assert px4params.Store.load(path, schema, classic=TODAY).get("COM_DISARM_LAND") == 4.0


def test_a_format_2_classic_record_is_read_as_the_set_has_it(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """Format 2 did not say a classic record's type: its four bytes are the set's type, as
    before, and a float flag there is no flag that format knew."""
    path = tmp_path / "v.store"
    path.write_bytes(_classic_file([_classic_record("RC10_REV", struct.pack("<i", -1))], version=2))
    assert px4params.Store.load(path, schema, classic=TODAY).get("RC10_REV") == -1
    flagged = _classic_record("RC10_REV", struct.pack("<f", -1.0), 0x40)
    path.write_bytes(_classic_file([flagged], version=2))
    with pytest.raises(StoreFileError) as refused:
        px4params.Store.load(path, schema, classic=TODAY)
    assert str(refused.value) == f"{path}: record is malformed: unknown flags 0x62 (at byte 14)"


def test_records_with_impossible_instance_numbers(store: px4params.Store, tmp_path: Path) -> None:
    path = tmp_path / "x.store"
    index = store.parameters.index("INA238")
    write_records(path, store, [bytes([KIND_STRUCTURED]) + _varint(index) + _varint(70000)])
    with pytest.raises(
        StoreFileError, match=r"record is malformed: instance 70000 is out of range"
    ):
        store.load_from(path)


def _crc16_ccitt_false(data: bytes) -> int:
    """CRC-16-CCITT-FALSE written from its definition (poly 0x1021, init 0xFFFF, no reflection,
    no final xor), independent of the product's table."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def test_crc16_reference_check_value() -> None:
    assert _crc16_ccitt_false(b"123456789") == 0x29B1  # the catalogue's check value


def test_golden_file_bytes_follow_the_documented_format(schema: px4params.Schema) -> None:
    """The bytes of a small store, written down from docs/store-format.md: header with the
    table's fingerprint, the parameter table, one structured record (an instance of defaults
    only), two classic records (an int32's default and value; a float32's value, flag 0x40),
    CRC-16 per record, CRC-32 trailer."""
    classic = [
        ClassicParam("SYS_AUTOSTART", "Int32", 0),
        ClassicParam("BAT1_R_INTERNAL", "Float", -1.0),
    ]
    store = px4params.Store(schema, classic=classic)
    store.add("INA238#0")
    store.set_default("SYS_AUTOSTART", 10)
    store.set("SYS_AUTOSTART", 4001)
    store.set("BAT1_R_INTERNAL", 0.005)
    line = b"INA238=px.Ina238.1"  # the only structured parameter with a record
    header = b"PX4P" + bytes([3, 0]) + zlib.crc32(line).to_bytes(4, "little")
    table = bytes([0x03, 1, len(line)]) + line  # kind 3, one entry, its length, its text
    structured = bytes([0x01, 0, 0])  # kind 1, no flags, table entry 0, instance 0
    autostart = (
        bytes([0x02 | 0x10 | 0x20, 13])
        + b"SYS_AUTOSTART"
        + (10).to_bytes(4, "little", signed=True)
        + (4001).to_bytes(4, "little", signed=True)
    )
    # 0.005 as a float32 is 0x3BA3D70A
    resistance = bytes([0x02 | 0x20 | 0x40, 15]) + b"BAT1_R_INTERNAL" + bytes.fromhex("0ad7a33b")
    body = header
    for record in (table, structured, autostart, resistance):
        body += record + _crc16_ccitt_false(record).to_bytes(2, "little")
    expected = body + zlib.crc32(body).to_bytes(4, "little")
    assert encode_file(store) == expected


# -- format 1, and schemas that differ from the writer's ----------------------------------------

#: The structured parameters px4params bundled while the store file had no table (format 1).
FIRST_BUNDLED = [
    "AK09916=px.Ak09916.1",
    "BMM350=px.Bmm350.1",
    "INA226=px.Ina226.1",
    "INA228=px.Ina228.1",
    "INA238=px.Ina238.1",
    "IST8310=px.Ist8310.1",
    "LIS3MDL=px.Lis3mdl.1",
    "QMC5883L=px.Qmc5883l.1",
    "RM3100=px.Rm3100.1",
]


def _file(version: int, fp: int, records: list[bytes]) -> bytes:
    body = bytearray(HEADER.pack(MAGIC, version, 0, fp))
    for r in records:
        body += r + struct.pack("<H", _crc16(r))
    return bytes(body + struct.pack("<I", zlib.crc32(body)))


def _table(lines: list[str]) -> bytes:
    out = bytes([0x03]) + _varint(len(lines))
    return out + b"".join(_varint(len(x)) + x.encode() for x in lines)


def test_a_format_1_file_of_the_first_bundled_types_loads(store, tmp_path) -> None:
    """The upgrade path: a store saved by px4params before its types grew (no table; records
    index the first nine bundled parameters) loads into today's schema."""
    fp = zlib.crc32("\n".join(FIRST_BUNDLED).encode())
    ina238 = FIRST_BUNDLED.index("INA238=px.Ina238.1")  # 4 then; 12 in today's list
    payload = store.schema["px.Ina238"].encode(
        {"bus": {"i2c": {"bus_id": 2, "address": 0x41}}, "current": 150, "shunt": 0.0005},
        tao=False,
    )
    record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(ina238) + _varint(1)
    path = tmp_path / "old.store"
    path.write_bytes(_file(1, fp, [record + _varint(len(payload)) + payload]))
    store.load_from(path)
    assert store.instances("INA238") == ["INA238#1"]
    assert store.get("INA238#1.bus.i2c.address") == 0x41
    store.save(path)  # written back in today's format, with its table
    assert path.read_bytes()[4] == 3
    assert px4params.Store.load(path, store.schema, classic=CLASSIC).get("INA238#1") == store.get(
        "INA238#1"
    )


def test_a_format_1_file_of_another_schema_is_refused(store, tmp_path) -> None:
    path = tmp_path / "other.store"
    path.write_bytes(_file(1, 0x12345678, []))
    with pytest.raises(StoreFileError, match=r"written for another schema \(fingerprint "
                       r"0x12345678, this schema has 0x[0-9a-f]{8}: its parameters or their "
                       r"types differ\) \(at byte 6\)$"):  # fmt: skip
        store.load_from(path)


def test_a_table_entry_this_schema_lacks(store, tmp_path) -> None:
    lines = ["FOO=vendor.Foo.1", "INA226=px.Ina226.2", "INA238=px.Ina238.1"]
    fp = zlib.crc32("\n".join(lines).encode())
    path = tmp_path / "t.store"
    # Unused entries are harmless: only entry 2 has a record.
    path.write_bytes(_file(2, fp, [_table(lines), bytes([KIND_STRUCTURED, 2, 0])]))
    store.load_from(path)
    assert store.instances("INA238") == ["INA238#0"]
    for entry, message in (
        (0, "FOO was stored as vendor.Foo.1; this schema has no such parameter"),
        (1, "INA226 was stored as px.Ina226.2; this schema has px.Ina226.1"),
    ):
        path.write_bytes(_file(2, fp, [_table(lines), bytes([KIND_STRUCTURED, entry, 1])]))
        with pytest.raises(StoreFileError, match=re.escape(f"record cannot be applied: {message}")):
            store.load_from(path)
        assert store.instances("INA238") == ["INA238#0"]  # left as it was


@pytest.mark.parametrize(
    ("records", "message"),
    [
        ([], "record is malformed: it runs past the end of the file (at byte 10)"),
        ([bytes([0x01, 0, 0])], "a file of format 2 or later starts with its parameter table"),
        ([_table(["X"])], "parameter table entry 'X' is not NAME=TYPE.MAJOR"),
        ([_table([])[:1] + b"\x01\x02\xff\xfe"], "a parameter table entry is not ASCII"),
        ([_table([]), _table([])], "record is malformed: a second parameter table"),
    ],
)
def test_malformed_tables(store, tmp_path, records, message) -> None:
    path = tmp_path / "t.store"
    path.write_bytes(_file(2, zlib.crc32(b""), records))
    with pytest.raises(StoreFileError, match=re.escape(message)):
        store.load_from(path)


def test_a_table_that_does_not_match_its_fingerprint(store, tmp_path) -> None:
    path = tmp_path / "t.store"
    path.write_bytes(_file(2, 0xDEADBEEF, [_table(["INA238=px.Ina238.1"])]))
    with pytest.raises(StoreFileError, match=r"the parameter table does not match the header's "
                       r"fingerprint \(at byte 10\)$"):  # fmt: skip
        store.load_from(path)


@pytest.mark.parametrize(
    ("name", "shown"),
    [
        (b"X\x1b[31mRED\n", "'X\\x1b[31mRED\\n'"),  # escapes a terminal would act on
        (b"", "''"),
        (b"A" * 17, "'" + "A" * 17 + "'"),
        (b"sys_autostart", "'sys_autostart'"),
        (b"1ABC", "'1ABC'"),
        (b"NAME\xff", "'NAME\\xff'"),
    ],
)
def test_a_classic_record_whose_name_is_no_parameter_name_is_refused(
    store: px4params.Store, tmp_path: Path, name: bytes, shown: str
) -> None:
    # A crafted file (valid CRCs) planted such names: kept on every save, and printed raw by
    # import, status and export.
    path = tmp_path / "x.store"
    record = bytes([0x02 | 0x20, len(name)]) + name + (5).to_bytes(4, "little")
    path.write_bytes(_file(2, zlib.crc32(b""), [_table([]), record]))
    store.set("SYS_AUTOSTART", 4001)
    with pytest.raises(StoreFileError) as refused:
        store.load_from(path)
    assert str(refused.value) == (
        f"{path}: record is malformed: classic parameter name {shown} is not 1 to 16 "
        f"upper-case letters, digits and '_', a letter first (at byte {10 + 2 + 2})"
    )
    assert store.get("SYS_AUTOSTART") == 4001  # left as it was


def test_a_second_record_of_one_instance_is_refused(store: px4params.Store, tmp_path: Path) -> None:
    # Two records of INA238#0, or of SYS_AUTOSTART, loaded with the last one winning.
    line = "INA238=px.Ina238.1"
    twice = [bytes([KIND_STRUCTURED]) + _varint(0) + _varint(0)] * 2
    fp = zlib.crc32(line.encode())
    path = tmp_path / "x.store"
    path.write_bytes(_file(2, fp, [_table([line]), *twice]))
    first = 10 + len(_table([line])) + 2  # the header, the table and its CRC
    with pytest.raises(StoreFileError) as refused:
        store.load_from(path)
    assert str(refused.value) == (
        f"{path}: record is malformed: a second record of the same parameter instance "
        f"(at byte {first + 3 + 2})"  # the first record and its CRC
    )
    classic = bytes([0x02 | 0x20, 13]) + b"SYS_AUTOSTART" + (6).to_bytes(4, "little")
    path.write_bytes(_file(2, zlib.crc32(b""), [_table([]), classic, classic]))
    with pytest.raises(StoreFileError, match=r"a second record of the same parameter instance"):
        store.load_from(path)
    assert store.instances("INA238") == []


def test_a_table_that_names_a_parameter_twice_is_refused(
    store: px4params.Store, tmp_path: Path
) -> None:
    # Records of each line were INA238#0's, the last one winning, on the host and in the
    # firmware alike (the check of two records keyed on the line, not the parameter).
    lines = ["INA238=px.Ina238.1", "INA238=px.Ina238.1"]
    records = [bytes([KIND_STRUCTURED]) + _varint(n) + _varint(0) for n in (0, 1)]
    path = tmp_path / "x.store"
    path.write_bytes(_file(2, zlib.crc32("\n".join(lines).encode()), [_table(lines), *records]))
    store.add("AK09916#0")
    with pytest.raises(StoreFileError) as refused:
        store.load_from(path)
    assert str(refused.value) == (
        f"{path}: record is malformed: the parameter table names 'INA238' twice (at byte 10)"
    )
    assert store.instances("AK09916") == ["AK09916#0"]  # left as it was


def test_an_import_over_a_kept_record_replaces_it(schema: px4params.Schema, tmp_path: Path) -> None:
    """A record kept for its type, then a value of this set's type merged in: the newer one
    holds, and the kept one is gone (not saved beside it)."""
    kept, newer = tmp_path / "kept.store", tmp_path / "newer.store"
    kept.write_bytes(
        _classic_file([_classic_record("COM_DISARM_LAND", struct.pack("<f", 2.5), 0x40)])
    )
    newer.write_bytes(_classic_file([_classic_record("COM_DISARM_LAND", struct.pack("<i", 5))]))
    before = px4params.Store(schema, classic=BEFORE)
    before.load_from(kept)
    assert before.kept_classic == ["COM_DISARM_LAND"]
    before.import_from(newer)
    assert before.kept_classic == [] and before.get("COM_DISARM_LAND") == 5
    before.save(kept)
    assert px4params.Store.load(kept, schema, classic=TODAY).get("COM_DISARM_LAND") == 5.0


@pytest.mark.parametrize("value", [33554432.0, 16777218.0, -2147483648.0, 1e9])
def test_a_whole_float_carried_through_the_older_set_and_back_is_the_same(
    schema: px4params.Schema, tmp_path: Path, value: float
) -> None:
    """Float -> Int32 takes every whole float32 in int32's range; Int32 -> Float must take them
    back (each is a float32 exactly), not only |n| <= 2**24."""
    flipped = [ClassicParam("COM_DISARM_LAND", "Float", 2.0)]
    older = [ClassicParam("COM_DISARM_LAND", "Int32", 2)]
    path = tmp_path / "v.store"
    today = px4params.Store(schema, classic=flipped)
    today.set("COM_DISARM_LAND", value)
    today.save(path)
    before = px4params.Store.load(path, schema, classic=older)
    assert before.get("COM_DISARM_LAND") == int(value)
    before.save(path)  # rewritten as an Int32 record
    assert px4params.Store.load(path, schema, classic=flipped).get("COM_DISARM_LAND") == value


@pytest.mark.parametrize("how", ["set to its default", "reset"])
def test_setting_or_resetting_a_kept_value_replaces_it_even_at_the_default(
    schema: px4params.Schema, tmp_path: Path, how: str
) -> None:
    """The kept 2.5 gave way only when the new value had a record of its own: set to its
    default (2, no record) or reset, the old 2.5 was saved on, and read back by today's set."""
    path = tmp_path / "v.store"
    path.write_bytes(
        _classic_file([_classic_record("COM_DISARM_LAND", struct.pack("<f", 2.5), 0x40)])
    )
    before = px4params.Store.load(path, schema, classic=BEFORE)
    if how == "reset":
        before.reset("COM_DISARM_LAND")
    else:
        before.set("COM_DISARM_LAND", 2)
    assert before.kept_classic == []
    before.save(path)
    assert px4params.Store.load(path, schema, classic=TODAY).get("COM_DISARM_LAND") == 2.0


@pytest.mark.parametrize("name", ["COM_DISARM_LAND", "NOT_IN_THE_SET"])
@pytest.mark.parametrize("number", [math.nan, math.inf])
def test_a_float_record_holding_nan_is_refused_by_every_set(
    schema: px4params.Schema, tmp_path: Path, name: str, number: float
) -> None:
    """Format 3 says a record is a float32: a NaN in it is damage whatever the reading set has
    (kept unread and saved on, the set owning it would refuse the whole store, .bak too)."""
    path = tmp_path / "v.store"
    path.write_bytes(_classic_file([_classic_record(name, struct.pack("<f", number), 0x40)]))
    store = px4params.Store(schema, classic=BEFORE)
    store.set("RC10_REV", -1.0)
    with pytest.raises(StoreFileError) as refused:
        store.load_from(path)
    assert str(refused.value) == (
        f"{path}: record cannot be applied: {name}: {number} is not a finite number (a Float "
        "record: NaN and infinities are refused) (at byte 14)"
    )
    assert store.get("RC10_REV") == -1.0  # left as it was


def test_a_format_2_file_with_classic_records_says_how_they_are_read(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    path = tmp_path / "v.store"
    path.write_bytes(_classic_file([_classic_record("RC10_REV", struct.pack("<i", -1))], version=2))
    said = (
        f"{path}: store file format 2, whose classic records do not say their type: read as "
        "this parameter set types them (if it was saved with another, load it with that one "
        "first)"
    )
    assert px4params.Store(schema, classic=TODAY).load_from(path) == [said]
    # Read with the set where it is a Float, -1's bits are NaN: the likely cause is named.
    with pytest.raises(StoreFileError) as refused:
        px4params.Store(schema, classic=BEFORE).load_from(path)
    assert str(refused.value) == (
        f"{path}: record cannot be applied: RC10_REV: nan is not a finite number (Float: NaN "
        "and infinities are refused) (a format 2 file: saved with a parameter set where it is "
        "the other type?) (at byte 14)"
    )


def test_a_value_converted_from_the_other_type_is_unsaved_until_saved(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """The file still holds the other type (firmware built with this set skips such a record):
    the value is shown unsaved, not as what the file holds, until a save rewrites it."""
    path = tmp_path / "v.store"
    path.write_bytes(_classic_file([_classic_record("RC10_REV", struct.pack("<i", -1))]))
    store = px4params.Store.load(path, schema, classic=BEFORE)  # RC10_REV a Float there
    assert store.get("RC10_REV") == -1.0
    assert store.state("RC10_REV")[1] is True  # unsaved
    assert store.state("COM_DISARM_LAND")[1] is False
    store.save(path)
    assert px4params.Store.load(path, schema, classic=BEFORE).state("RC10_REV")[1] is False


def test_a_classic_record_of_the_other_type_without_values_is_read_as_nothing(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    # (neither flag: a crafted record was reported "stored as Float , ... taken as ")
    path = tmp_path / "v.store"
    path.write_bytes(_classic_file([bytes([0x02 | 0x40, 8]) + b"RC10_REV"]))
    store = px4params.Store(schema, classic=TODAY)
    assert store.load_from(path) == []
    assert store.get("RC10_REV") == 1 and store.kept_classic == []
