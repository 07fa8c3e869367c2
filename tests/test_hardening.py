"""The defects an outside audit found, one test each (the catalogue of bad inputs is
``test_bad_inputs.py``): what users expect instead of a crash or a silently lost intent."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import dronecan
import px4params
import pytest
from px4params.errors import DsdlError, LeafError, NumberError, StoreError
from px4params.numbers import load_json, parse_float, parse_int
from px4params.store.classic import BUNDLED_CLASSIC

ROOT = Path(__file__).resolve().parents[1]
AIRFRAME = ROOT / "examples" / "two_batteries.airframe"
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


# -- 1, 8: numbers ------------------------------------------------------------------------------


def test_numbers_are_bounded_before_conversion() -> None:
    assert parse_int("0x45", 16) == 0x45 and parse_int("-12") == -12
    assert parse_int("9" * 64) == int("9" * 64)
    with pytest.raises(NumberError, match=r"^999999999999\.\.\.999999 \(5000 characters\) is out"):
        parse_int("9" * 5000)
    with pytest.raises(NumberError, match="65 digits"):
        parse_int("0x" + "f" * 65, 16)
    assert parse_float("inf") == float("inf") and parse_float("1e300") == 1e300
    with pytest.raises(NumberError, match=r"^1e400 is out of range of a float64"):
        parse_float("1e400")
    with pytest.raises(NumberError, match=r'^Infinity is not JSON; write "inf"'):
        load_json('{"x": Infinity}')
    with pytest.raises(NumberError, match=r"^1e400 is out of range"):
        load_json("[1e400]")
    assert load_json('{"x": 1.5, "y": "inf"}') == {"x": 1.5, "y": "inf"}


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


# -- 2, 3, 13: hostile types ------------------------------------------------------------------


def _types(tmp_path: Path, files: dict[str, str | bytes]) -> px4params.Schema:
    root = tmp_path / "acme"
    root.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (root / name).write_bytes(text if isinstance(text, bytes) else text.encode())
    return px4params.load_schema(
        [root], include_dronecan=False, use_env=False, cache_dir=tmp_path / "cache"
    )


def test_a_type_too_large_is_refused_before_anything_is_allocated(tmp_path: Path) -> None:
    with pytest.raises(DsdlError) as e:
        _types(
            tmp_path,
            {
                "L1.1.0.dsdl": "uint8[65535] x\n@sealed\n",
                "L2.1.0.dsdl": "L1.1.0[65535] x\n@sealed\n",
            },
        )
    assert str(e.value).endswith(
        "acme.L2.1.0: its largest value has 34,358,689,800 bits (4,294,836,225 bytes); types "
        "are limited to 65,535 bytes"
    )
    # Far below the limit: accepted.
    schema = _types(tmp_path / "ok", {"Ok.1.0.dsdl": "uint8[65000] x\n@sealed\n"})
    assert schema.get("acme.Ok").max_bits == 65000 * 8


def test_max_instances_is_bounded(tmp_path: Path) -> None:
    with pytest.raises(DsdlError, match=r"@max_instances expects an integer 1\.\.256, got '65536'"):
        _types(tmp_path, {"W.1.0.dsdl": "# @max_instances 65536\nuint8 x\n@sealed\n"})


def test_pydsdl_internal_errors_say_what_is_wrong_with_the_file(tmp_path: Path) -> None:
    with pytest.raises(DsdlError) as e:
        _types(tmp_path, {"B.1.0.dsdl": b"\xc7\x00binary"})
    assert "not a text file: byte 0xC7 at offset 0 is not UTF-8" in str(e.value)
    assert "PLEASE REPORT" not in str(e.value)


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


def test_temporary_files_of_killed_saves_are_removed(store: Path) -> None:
    dead = 2**22 + 12345  # beyond Linux's default pid_max: no such process
    leftovers = [f".real.store.{dead}.abc123.tmp", f"real.store.bak.{dead}.tmp"]
    alive = f".real.store.{os.getpid()}.zzz.tmp"  # this process: a save under way, kept
    for name in [*leftovers, alive]:
        store.with_name(name).write_bytes(b"half a save")
    assert cli("param", "--store", str(store), "set", "SYS_AUTOSTART", "1").returncode == 0
    names = {p.name for p in store.parent.iterdir()}
    assert not names & set(leftovers)
    assert alive in names


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
    params = tmp_path / "x.params"
    params.write_text("1\t1\tSYS_AUTOSTART\t2.0\t9\n")
    before = store.read_bytes()
    result = cli("param", "--store", str(store), "import", str(params))
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {params}:1: SYS_AUTOSTART: type REAL32 (9) in the file, but the "
        "parameter is INT32 (6)\n"
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


# -- 10: leaf indices ----------------------------------------------------------------------------


@pytest.mark.parametrize("index", [-1, 2**80, 10**100])
def test_a_leaf_index_out_of_every_range_is_a_leaf_error(
    schema: px4params.Schema, index: int
) -> None:
    ina = schema.get("px.Ina238")
    data = ina.encode({"bus": {"i2c": {"bus_id": 1, "address": 69}}, "current": 200, "shunt": 0})
    with pytest.raises(LeafError, match=r"^no leaf \[.+\] \(leaf indices are 0 and up\)$"):
        ina.get_leaf(data, index)
    with pytest.raises(LeafError):
        ina.set_leaf(data, index, 1)


def test_the_store_names_a_field_it_did_not_find(schema: px4params.Schema) -> None:
    store = px4params.Store(schema)
    store.add("INA238#0")
    with pytest.raises(LeafError, match=r"^INA238#0: no such field: nope$"):
        store.leaf("INA238#0.nope")
    with pytest.raises(LeafError, match=r"^INA238#0: no such field: nope$"):
        store.set("INA238#0.nope", 1)


def test_a_parameter_the_store_cannot_hold_is_named() -> None:
    """Past the loader's size limit (a model built by hand), the store names the parameter,
    not its internal number."""
    big = {"kind": "array", "len": 70000, "elem": {"kind": "uint", "bits": 8, "cast": "saturated"}}
    model = {
        "types": {
            "t.Big.1.0": {
                "name": "t.Big",
                "version": [1, 0],
                "kind": "struct",
                "dialect": "dsdl",
                "file": "Big.1.0.dsdl",
                "line": 1,
                "dtid": None,
                "service": None,
                "signature_override": None,
                "doc": {"short": "Big", "long": "", "tags": {"max_instances": 1}},
                "fields": [{"name": "x", "type": big, "line": 2}],
            }
        }
    }
    with pytest.raises(StoreError, match=r"^parameter BIG cannot be stored \(no slot, or a value"):
        px4params.Store(px4params.Schema(model), classic=[])


def test_types_that_use_each_other_too_often_are_refused_before_pydsdl(tmp_path: Path) -> None:
    """Found by the fuzz run: pydsdl recomputes a type's alignment for every use, so six small
    files that use each other a few hundred times over took it 18 s (and more types, minutes).
    They are counted first and refused."""
    files = {
        "T0.1.0.dsdl": "int3 a\nfloat16 b\n@sealed\n",
        "T1.1.0.dsdl": "@union\n"
        + "".join(f"T0.1.0[<=2] v{i}\n" for i in range(300))
        + "@sealed\n",
        "T2.1.0.dsdl": "".join(f"T1.1.0 f{i}\n" for i in range(100)) + "@sealed\n",
    }
    with pytest.raises(DsdlError) as e:
        _types(tmp_path, files)
    assert "acme.T2.1.0 uses its types so many times over (" in str(e.value)
    assert "at most 20,000): pydsdl would take seconds to minutes to read it" in str(e.value)
