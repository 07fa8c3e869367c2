"""Destructured names are worked out on demand: building a store costs what its parameter set
declares, not ``max_instances`` times every letter (a type of ``uint8[<=65000]`` with
``@max_instances 256`` took 117 s to build a store for when every name was listed at once),
and the names themselves are the ones the eager map gave (pinned below)."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import px4params
import pytest
from px4params.errors import FlatError
from px4params.store import flat
from px4params.store.key import Key
from test_flat import dsdl_root

BIG = {
    "Big.1.0.dsdl": "# Big blob\n# @max_instances 256\n\nuint4 p_version\nuint8[<=65000] data\n"
    "@sealed\n"
}

#: The bundled parameters when the names were listed eagerly, and a digest of every one of
#: their names with its owner (``NAME INSTANCE LETTER PATH`` lines, sorted), taken from the
#: eager map before it was replaced: 2384 names.
BUNDLED = [
    "AK09916", "ASP5033", "AUAV", "BATMON", "BATT_SMBUS", "BMM350", "ETS3", "HMC5883",
    "ICM20948", "IIS2MDC", "INA226", "INA228", "INA238", "IRLOCK", "IST8308", "IST8310",
    "LIS3MDL", "LL40LS", "MB12XX", "MCP9808", "MS4515", "MS4525DO", "MS5525DSO", "PCF8583",
    "QMC5883L", "QMC5883P", "RM3100", "SDP3X", "SF1XX", "SHT3X", "SPA06", "SPL06", "TERARANGER",
    "TF02PRO", "TMP102", "VL53L0X", "VL53L1X",
]  # fmt: skip
BUNDLED_NAMES = 2384
BUNDLED_DIGEST = "8e646d44699ca1b11703da609d839d7b63419ce5be5f1dd18fb66c4d663ea993"


def _env(tmp: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = str(tmp / "cache")
    return env


def test_the_talks_names_are_unchanged() -> None:
    # SPEC: INA238#1.bus_type -> INA238_1A, i2c.bus_id -> INA238_1B, i2c.address -> INA238_1C.
    store = px4params.Store()
    names = store.destructured
    assert names.owner("INA238_1A") == (Key.parse("INA238#1"), names.layout_of("INA238").slot("A"))
    assert [names.owner(n)[1].path for n in ("INA238_1A", "INA238_1B", "INA238_1C")] == [
        "bus._tag",
        "bus.i2c.bus_id",
        "bus.i2c.address",
    ]
    assert names.owner("INA238_3Q") == (Key.parse("INA238#3"), names.layout_of("INA238").slot("Q"))
    for missing in ("INA238_4A", "INA238_1R", "INA238_01A", "INA238_A", "INA238_1", "X_1A"):
        assert missing not in names


def test_every_bundled_name_is_the_eager_maps() -> None:
    store = px4params.Store()
    names = store.destructured
    rows = []
    for name in names.names():
        instance, slot = names.owner(name)  # the lazy lookup is the listing's inverse
        spec = store.spec(instance.param)
        assert spec is not None
        assert flat.FlatMap.name_of(spec, instance.instance, slot) == name
        if instance.param in BUNDLED:
            rows.append(f"{name} {instance} {slot.letter} {slot.path}")
    rows.sort()
    assert len(rows) == BUNDLED_NAMES
    assert hashlib.sha256("\n".join(rows).encode()).hexdigest() == BUNDLED_DIGEST


def test_a_store_of_a_huge_type_is_built_without_listing_its_names(tmp_path: Path) -> None:
    root = dsdl_root(tmp_path, BIG, "acme")
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    big = schema["acme.Big"]
    store = px4params.Store(schema)
    assert store.destructured.owner("BIG_255" + flat.letters(65000)) == (
        Key.parse("BIG#255"),
        flat.layout(big).slots[65000],
    )
    # Asking for a name of another type, or listing a store with no BIG instance, works out
    # none of BIG's 65001 letters.
    fresh = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(fresh)
    assert "INA238_1C" in store.destructured
    store.add("INA238#1")
    assert [r.name for r in flat.flat_table(store)][:3] == ["INA238_1A", "INA238_1B", "INA238_1C"]
    assert "flat_layout" not in fresh["acme.Big"].derived
    assert flat.slot_count(fresh["acme.Big"]) == 65001


def test_the_cli_with_a_huge_type_does_not_hang(tmp_path: Path) -> None:
    root = dsdl_root(tmp_path, BIG, "acme")
    store = tmp_path / "vehicle.store"
    argv = [sys.executable, "-m", "px4params", "param", "--store", str(store), "--dsdl", str(root)]
    for args in (("add", "INA238#1"), ("set", "INA238_1C", "70"), ("flat", "INA238_1*")):
        result = subprocess.run(
            [*argv, *args],
            capture_output=True,
            text=True,
            env=_env(tmp_path),
            timeout=30,  # does not hang: 117 s per command when every name was listed
        )
        assert result.returncode == 0, result.stderr
    assert "INA238_1C" in result.stdout and "70" in result.stdout


def test_names_too_long_are_refused_at_the_first_one(tmp_path: Path) -> None:
    # 13 characters + "_" + instance + letter: instance 10 is the first to need 17.
    files = {
        "Thirteen.1.0.dsdl": "# T\n# @param ABCDEFGHIJKLM\n# @max_instances 12\n\n"
        "uint4 p_version\nuint8 x\n@sealed\n"
    }
    root = dsdl_root(tmp_path, files, "bad")
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    with pytest.raises(FlatError) as e:
        px4params.Store(schema)
    assert str(e.value) == (
        "ABCDEFGHIJKLM: destructured name ABCDEFGHIJKLM_10A has 17 characters (at most 16): "
        "bad.Thirteen.1.0 has 1 flat leaves; shorten the parameter name or the type"
    )
    # One instance, 27 letters: the 27th is AA, one letter too many.
    files = {
        "Wide.1.0.dsdl": "# W\n# @param ABCDEFGHIJKLM\n# @max_instances 1\n\n"
        "uint4 p_version\nuint8[27] x\n@sealed\n"
    }
    root = dsdl_root(tmp_path / "two", files, "bad")
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "two" / "cache")
    with pytest.raises(FlatError) as e:
        px4params.Store(schema)
    assert str(e.value) == (
        "ABCDEFGHIJKLM: destructured name ABCDEFGHIJKLM_0AA has 17 characters (at most 16): "
        "bad.Wide.1.0 has 27 flat leaves; shorten the parameter name or the type"
    )


def test_letters_and_their_numbers_are_inverse() -> None:
    for number in (0, 25, 26, 27, 701, 702, 18277, 18278, 65000):
        assert flat.letter_number(flat.letters(number)) == number
    assert (flat.letters(26), flat.letters(702)) == ("AA", "AAA")
    for text in ("", "a", "A1", "Ä", "A_"):
        assert flat.letter_number(text) is None


def test_dronecan_long_names_are_read_not_listed(tmp_path: Path) -> None:
    from px4params.store.long_names import LongNames

    root = dsdl_root(tmp_path, BIG, "acme")
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema)
    names = LongNames(store)  # 256 x 65001 names were listed and checked here, one by one
    spec = store.spec("INA238")
    assert spec is not None
    assert names._parse("INA238_1_I2C_ADDRESS") == (spec, 1, flat.layout(spec.data_type).slot("C"))
    assert names._parse("BIG_255_DATA_64999") is not None
    for missing in ("BIG_256_DATA_0", "BIG_01_DATA_0", "BIG_1_DATA_65000", "INA238_1_NOPE"):
        assert names._parse(missing) is None
    store.add("BIG#7")
    store.set("BIG#7", {"data": [1, 2]})
    assert [row.name for row in names.table()] == ["BIG_7_DATA_LEN", "BIG_7_DATA_0", "BIG_7_DATA_1"]
