"""Firmware: the C ABI (crates/px4params-ffi) with the tables of ``metadata --firmware``, the
talk's C++ API, and the example ``examples/firmware/ina238_auto.cpp``, built with g++ and run
against store files that ``px4params`` wrote; each with the core as hosts build it and as
firmware builds it for size (``compact``)."""

from __future__ import annotations

import binascii
import os
import re
import shutil
import subprocess
import sys
import zlib
from pathlib import Path

import px4params
import pytest
from metadata_support import require_compilers
from px4params.store.classic import BUNDLED_CLASSIC

ROOT = Path(__file__).resolve().parent.parent
FFI = ROOT / "crates" / "px4params-ffi"
EXAMPLE = ROOT / "examples" / "firmware" / "ina238_auto.cpp"
AIRFRAME = ROOT / "examples" / "two_batteries.airframe"
CLI = [sys.executable, "-m", "px4params"]


def run(command: list[str], cwd: Path, **kw: object) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=900, **kw)  # type: ignore[call-overload]
    assert proc.returncode == 0, f"{command}: {proc.stderr[-4000:]}"
    return proc


@pytest.fixture(scope="module", params=["default", "compact"])
def staticlib(request: pytest.FixtureRequest) -> Path:
    """The C ABI's static library, with the core as hosts build it and as firmware builds it
    for size (feature ``compact``: every value goes through the small walk)."""
    if shutil.which("cargo") is None:
        pytest.skip("cargo is not installed: the C ABI cannot be built")
    command = ["cargo", "build", "-q", "-p", "px4params-ffi", "--release"]
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if request.param == "compact":
        target = target / "compact"
        command += ["--features", "compact", "--target-dir", str(target)]
    run(command, ROOT)
    lib = target / "release" / "libpx4params_ffi.a"
    assert lib.exists()
    return lib


@pytest.fixture(scope="module")
def example(tmp_path_factory: pytest.TempPathFactory, staticlib: Path) -> Path:
    """The example, built as a firmware build would: generated header and tables, the C ABI's
    static library, g++."""
    gcc, gxx = require_compilers()
    build = tmp_path_factory.mktemp("firmware")
    generate = ["metadata", "--header", "px4_params.h", "--firmware", "px4_param_tables.c"]
    run([*CLI, *generate], build)
    include = f"-I{FFI / 'include'}"
    run(
        [gcc, "-std=c11", "-Wall", "-Wextra", "-Werror", include, "-c", "px4_param_tables.c"], build
    )
    run(
        [gxx, "-std=c++17", "-Wall", "-Wextra", "-Werror", include, "-I.", str(EXAMPLE),
         "px4_param_tables.o", str(staticlib), "-lpthread", "-ldl", "-o", "ina238_auto"],
        build,
    )  # fmt: skip
    return build / "ina238_auto"


@pytest.fixture(scope="module")
def abi_checks(example: Path, staticlib: Path) -> Path:
    gcc, _ = require_compilers()
    build = example.parent
    source = ROOT / "tests" / "firmware" / "abi_checks.c"
    run(
        [gcc, "-std=c11", "-Wall", "-Wextra", "-Werror", f"-I{FFI / 'include'}", "-I.",
         str(source), "px4_param_tables.o", str(staticlib), "-lpthread", "-ldl", "-o", "abi"],
        build,
    )  # fmt: skip
    return build / "abi"


# Every C ABI call's answer, as docs/firmware.md describes them: the INA238 has 4 instance
# slots, a 6-byte stored value, `current` is leaf [5] (uint10, default 327) and `p_version`
# leaf [0].
ABI_ANSWERS = """\
get from a store never opened: -1 PX4P_ERR_ARGUMENT
open without tables: -1 PX4P_ERR_ARGUMENT
open with too little memory: -2 PX4P_ERR_TABLES
open: 0 PX4P_OK
get an absent instance: -5 PX4P_ERR_NOT_PRESENT
add the lowest free: 0 PX4P_OK
add #2: 2 PX4P_OK
add #2 again: -6 PX4P_ERR_ALREADY_PRESENT
add #9: -4 PX4P_ERR_INSTANCE_RANGE
add the lowest free: 1 PX4P_OK
add the lowest free: 3 PX4P_OK
add the lowest free: -7 PX4P_ERR_FULL
add to no such parameter: -3 PX4P_ERR_NO_SUCH_PARAM
get into 1 byte: -13 PX4P_ERR_BUFFER
get: 6 PX4P_OK
set the same bytes: 0 PX4P_OK
set one byte short: -9 PX4P_ERR_VALUE
get leaf [5] (current): 0 PX4P_OK
  value kind 1: 327
set leaf [5] to 200: 0 PX4P_OK
  read back: 200
set leaf [5] to 5000: -9 PX4P_ERR_VALUE
set leaf [5] to 5000, saturated: 0 PX4P_OK
  read back: 1023
set leaf [0] (p_version): -11 PX4P_ERR_VERSION_LEAF
get leaf [99]: -10 PX4P_ERR_NO_SUCH_LEAF
remove #2: 0 PX4P_OK
remove #2 again: -5 PX4P_ERR_NOT_PRESENT
instances: 0 1 3
save into 8 bytes: -13 PX4P_ERR_BUFFER
save: 59 PX4P_OK
load it back: 3 PX4P_OK
load with a flipped bit: -14 PX4P_ERR_FILE
load nothing: -14 PX4P_ERR_FILE
load from NULL: -1 PX4P_ERR_ARGUMENT
name of -99: -99 PX4P_ERR_UNKNOWN
"""


def test_the_c_abi_answers_good_and_bad_calls(abi_checks: Path) -> None:
    out = run([str(abi_checks)], abi_checks.parent).stdout
    assert out == ABI_ANSWERS


@pytest.fixture()
def store_file(tmp_path: Path) -> Path:
    path = tmp_path / "vehicle.store"
    run([*CLI, "run", str(AIRFRAME), "--store", str(path)], tmp_path)
    return path


def plan_lines(store: Path, parameter: str) -> list[str]:
    """The instances ``autostart plan`` lists under ``parameter``'s driver, as
    ``INA238#0 I2C bus 1 address 0x45 current=200 shunt=0.00029993`` (without the device ID)."""
    out = run([*CLI, "autostart", "plan", "--store", str(store)], store.parent).stdout
    lines = []
    for line in out.splitlines():
        if line.startswith(f"  {parameter}#"):
            lines.append(" ".join(line.split("device id")[0].split()))
    return lines


def test_the_example_starts_what_the_plan_says(example: Path, store_file: Path) -> None:
    out = run([str(example), str(store_file)], store_file.parent).stdout.splitlines()
    assert out[0] == "ina238 auto"
    started = [" ".join(line.split()) for line in out[1:]]
    assert started == plan_lines(store_file, "INA238")
    assert len(started) == 2  # the airframe's two batteries


def test_a_python_file_goes_through_the_c_abi_byte_identical(
    example: Path, store_file: Path
) -> None:
    back = store_file.parent / "back.store"
    run([str(example), str(store_file), str(back)], store_file.parent)
    assert back.read_bytes() == store_file.read_bytes()


def test_a_file_the_c_abi_wrote_loads_in_python(example: Path, store_file: Path) -> None:
    import px4params

    # Changed in Python after the airframe ran, so that the C side writes what it loaded,
    # not what the airframe wrote.
    store = px4params.Store(px4params.load_schema(use_env=False), classic=[])
    store.load_from(store_file)
    store.set("INA238#1.current", 150)
    store.remove("AK09916#0")
    store.add("INA238#3")
    store.save(store_file)
    back = store_file.parent / "back.store"
    run([str(example), str(store_file), str(back)], store_file.parent)
    loaded = px4params.Store(px4params.load_schema(use_env=False), classic=[])
    loaded.load_from(back)
    assert loaded.get("INA238#1.current") == 150
    assert loaded.instances("INA238") == ["INA238#0", "INA238#1", "INA238#3"]
    assert loaded.instances("AK09916") == []
    assert back.read_bytes() == store_file.read_bytes()


@pytest.mark.parametrize(
    ("damage", "name"),
    [
        (lambda b: b[:-1], "PX4P_ERR_FILE"),  # truncated
        (lambda b: b[:20] + bytes([b[20] ^ 1]) + b[21:], "PX4P_ERR_FILE"),  # one bit
        (lambda b: b"PX4Q" + b[4:], "PX4P_ERR_FILE"),
    ],
)
def test_a_damaged_file_is_refused_with_the_errors_name(
    example: Path, store_file: Path, damage: object, name: str
) -> None:
    store_file.write_bytes(damage(store_file.read_bytes()))  # type: ignore[operator]
    proc = subprocess.run([str(example), str(store_file)], capture_output=True, text=True)
    assert proc.returncode == 1
    assert proc.stderr == f"ina238_auto: loading the store file: {name}\n"
    assert proc.stdout == ""


def store_file_bytes(table: list[str], records: list[bytes]) -> bytes:
    """A store file built from docs/store-format.md, independently of the code that reads it."""

    def varint(n: int) -> bytes:
        out = bytearray()
        while n >= 0x80:
            out.append(n & 0x7F | 0x80)
            n >>= 7
        return bytes(out + bytes([n]))

    def crc16(data: bytes) -> bytes:
        return binascii.crc_hqx(data, 0xFFFF).to_bytes(2, "little")

    fingerprint = zlib.crc32("\n".join(table).encode())
    body = b"PX4P" + bytes([2, 0]) + fingerprint.to_bytes(4, "little")
    chunk = bytes([3]) + varint(len(table)) + b"".join(varint(len(x)) + x.encode() for x in table)
    body += chunk + crc16(chunk)
    for record in records:
        body += record + crc16(record)
    return body + zlib.crc32(body).to_bytes(4, "little")


def test_a_value_of_an_older_minor_version_is_translated_as_the_host_does(
    example: Path, tmp_path: Path
) -> None:
    """A store written before INA238 1.1 (shunt in micro-ohms): firmware translates it with the
    older layout the tables carry, as ``param load`` does, to the same bytes."""
    import px4params

    schema = px4params.load_schema(use_env=False)
    old = schema["px.Ina238.1.0"].encode(
        {"bus": {"i2c": {"bus_id": 3, "address": 0x41}}, "current": 100, "shunt_uohm": 500},
        tao=False,
    )
    record = bytes([0x21, 0, 0, len(old)]) + old  # kind 1 with a value: INA238#0
    path = tmp_path / "old.store"
    path.write_bytes(store_file_bytes(["INA238=px.Ina238.1"], [record]))
    back = tmp_path / "back.store"
    out = run([str(example), str(path), str(back)], tmp_path).stdout
    # shunt is new in 1.1: the default's (0.0003 as a float16)
    assert out.splitlines()[1].split() == [
        "INA238#0", "I2C", "bus", "3", "address", "0x41", "current=100", "shunt=0.00029993",
    ]  # fmt: skip
    store = px4params.Store(schema, classic=[])
    report = store.load_from(path)
    assert report == [
        "INA238#0: translated px.Ina238.1.0 -> px.Ina238.1.1: kept bus.i2c.bus_id, "
        "bus.i2c.address, current; new, from defaults: shunt; dropped: shunt_uohm=500"
    ]
    host = tmp_path / "host.store"
    store.save(host)
    assert back.read_bytes() == host.read_bytes()


def test_a_value_of_an_unknown_minor_version_is_refused(example: Path, tmp_path: Path) -> None:
    import px4params

    schema = px4params.load_schema(use_env=False)
    value = bytearray(schema["px.Ina238"].encode(schema["px.Ina238"].decode(
        schema["px.Ina238"].default(tao=False), tao=False), tao=False))  # fmt: skip
    value[0] = (value[0] & 0x0F) | (5 << 4)  # p_version 5: no such version
    record = bytes([0x21, 0, 0, len(value)]) + bytes(value)
    path = tmp_path / "future.store"
    path.write_bytes(store_file_bytes(["INA238=px.Ina238.1"], [record]))
    proc = subprocess.run([str(example), str(path)], capture_output=True, text=True)
    assert (proc.returncode, proc.stderr) == (
        1,
        "ina238_auto: loading the store file: PX4P_ERR_VERSION\n",
    )
    with pytest.raises(px4params.errors.StoreFileError, match=r"px\.Ina238\.1\.5"):
        px4params.Store(schema, classic=[]).load_from(path)


def test_the_committed_header_is_what_cbindgen_generates(tmp_path: Path) -> None:
    cbindgen = shutil.which("cbindgen")
    if cbindgen is None:
        pytest.skip("cbindgen is not installed (setup.sh installs Debian's as root)")
    out = tmp_path / "px4params.h"
    run(
        [cbindgen, "--config", str(FFI / "cbindgen.toml"), "--crate", "px4params-ffi",
         "--output", str(out), "--quiet"],
        ROOT,
    )  # fmt: skip
    committed = (FFI / "include" / "px4params.h").read_text()
    assert out.read_text() == committed, "regenerate with: " + " ".join(
        ["cbindgen", "--config", "crates/px4params-ffi/cbindgen.toml", "--crate",
         "px4params-ffi", "--output", "crates/px4params-ffi/include/px4params.h"]
    )  # fmt: skip


def test_the_tables_name_every_parameter_in_id_order(tmp_path: Path) -> None:
    run([*CLI, "metadata", "--header", "h.h", "--firmware", "t.c"], tmp_path)
    header = (tmp_path / "h.h").read_text()
    tables = (tmp_path / "t.c").read_text()
    ids = re.findall(r"PX4_PARAM_(\w+) = (\d+),", header)
    names = re.findall(r'\.file_name = "(\w+)=', tables)
    assert [n for n, _ in ids] == names
    assert [int(i) for _, i in ids] == list(range(len(names)))


# -- the C ABI at the end of its tables (issue 40) ---------------------------------------------
# The C ABI (crates/px4params-ffi) at the end of its tables: the last parameter in ID order is
# a parameter like any other (it opens, a new instance starts from its type's default, it is
# saved), and an ID one beyond the table is refused with ``PX4P_ERR_NO_SUCH_PARAM``. Issue 40:
# with the table bound in store open taken as ``param_count - 1``, the suite stayed green: its
# C checks use the INA238, in the middle of the table.
#
# The expected values come from the DSDL by hand: the last parameter is the VL53L1X
# (dsdl/px/Vl53l1x.1.0.dsdl), leaves in depth-first order (docs/codec.md): [0] p_version,
# [1] bus._tag (0: i2c, the union's first variant), [2] bus.i2c.p_version, [3] bus.i2c.bus_id
# (no default: 0), [4] bus.i2c.address (``@default i2c.address 0x29``, VL53L1X_BASEADDR), [5]
# rotation (``@default 25``, PX4's ROTATION_DOWNWARD_FACING); the type is version 1.0, so both
# p_version leaves hold minor version 0.


EXPECTED = """\
open: 0 PX4P_OK
add the last parameter: 0 PX4P_OK
value [0]: PX4P_OK kind 1: 0
value [1]: PX4P_OK kind 1: 0
value [2]: PX4P_OK kind 1: 0
value [3]: PX4P_OK kind 1: 0
value [4]: PX4P_OK kind 1: 41
value [5]: PX4P_OK kind 1: 25
default [0]: PX4P_OK kind 1: 0
default [1]: PX4P_OK kind 1: 0
default [2]: PX4P_OK kind 1: 0
default [3]: PX4P_OK kind 1: 0
default [4]: PX4P_OK kind 1: 41
default [5]: PX4P_OK kind 1: 25
add beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
get beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
get a leaf beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
instances beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
save: 0 PX4P_OK
"""


@pytest.fixture(scope="module")
def last_param(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/firmware/last_param.c built against the generated tables and the C ABI's static
    library, as a firmware build would."""
    if shutil.which("cargo") is None:
        pytest.skip("cargo is not installed: the C ABI cannot be built")
    gcc, _ = require_compilers()
    run(["cargo", "build", "-q", "-p", "px4params-ffi", "--release"], ROOT)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    lib = target / "release" / "libpx4params_ffi.a"
    build = tmp_path_factory.mktemp("last_param")
    run([*CLI, "metadata", "--header", "px4_params.h", "--firmware", "px4_param_tables.c"], build)
    run(
        [gcc, "-std=c11", "-Wall", "-Wextra", "-Werror", f"-I{FFI / 'include'}", "-I.",
         str(ROOT / "tests" / "firmware" / "last_param.c"), "px4_param_tables.c", str(lib),
         "-lpthread", "-ldl", "-o", "last_param"],
        build,
    )  # fmt: skip
    return build / "last_param"


@pytest.mark.issue40
def test_the_c_abi_opens_a_store_whose_last_parameter_is_in_the_table(last_param: Path) -> None:
    header = (last_param.parent / "px4_params.h").read_text()
    ids = {name: int(n) for name, n in re.findall(r"PX4_PARAM_(\w+) = (\d+),", header)}
    count = len(ids)
    assert max(ids.values()) == count - 1
    assert ids["VL53L1X"] == count - 1, "the last parameter is no longer the VL53L1X"
    saved = last_param.parent / "from_c.store"
    out = run([str(last_param), str(saved)], last_param.parent).stdout
    assert out == EXPECTED
    # The file the C ABI wrote, read by px4params: the new instance with its type's defaults.
    store = px4params.Store.load(saved, classic=BUNDLED_CLASSIC)
    assert store.instances("VL53L1X") == ["VL53L1X#0"]
    assert store.get("VL53L1X#0.bus.i2c.address") == 0x29
    assert store.get("VL53L1X#0.rotation") == 25
