"""store/classic.py: classic PX4 parameters from a ``parameters.json``, and their values.

The rules: PX4's build writes ``parameters.json`` as ``{"version": 1, "parameters": [...]}``,
each entry with ``name`` (at most 16 characters: MAVLink's param_id), ``type`` ``Int32`` or
``Float`` and ``default``; a classic value is a 32-bit integer or an IEEE float32 (PX4's
``param_t`` holds an ``int32_t`` or a ``float``).
"""

from __future__ import annotations

import json
import math
import os
import struct
import time
from pathlib import Path

import pytest
from px4params.cache_file import cache_path, default_cache_dir, write_cached
from px4params.store import classic
from px4params.store.classic import ClassicParam, ClassicParamsError, classic_value, load_classic


@pytest.fixture(autouse=True)
def cache_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("PX4PARAMS_CACHE_DIR", str(folder))
    return folder


def parameters_json(tmp_path: Path, parameters: object, version: object = 1) -> Path:
    path = tmp_path / "parameters.json"
    path.write_text(json.dumps({"version": version, "parameters": parameters}))
    return path


def settled(monkeypatch: pytest.MonkeyPatch) -> None:
    """Makes the files written so far older than the cache's racy window (the clock moved on)."""
    now = time.time() + 60
    monkeypatch.setattr(time, "time", lambda: now)


# -- parameters.json --------------------------------------------------------------------------


def test_entries_in_file_order_kept_whole(tmp_path: Path) -> None:
    entries = [
        {"name": "SYS_AUTOSTART", "type": "Int32", "default": 0, "group": "System"},
        {"name": "BAT1_CAPACITY", "type": "Float", "default": -1.0, "units": "mAh"},
        {"name": "NO_DEFAULT", "type": "Int32"},  # PX4 writes a default; none reads as 0
        {"name": "FLOAT_NO_DEF", "type": "Float"},
        {"name": "A234567890123456", "type": "Int32", "default": True},  # 16 characters
    ]
    params = load_classic(parameters_json(tmp_path, entries))
    assert [(p.name, p.type, p.default) for p in params] == [
        ("SYS_AUTOSTART", "Int32", 0),
        ("BAT1_CAPACITY", "Float", -1.0),
        ("NO_DEFAULT", "Int32", 0),
        ("FLOAT_NO_DEF", "Float", 0.0),
        ("A234567890123456", "Int32", 1),
    ]
    assert [dict(p.entry) for p in params] == entries
    assert [p.is_float for p in params] == [False, True, False, True, False]
    assert isinstance(params[3].default, float)
    assert repr(params[0]) == "ClassicParam(name='SYS_AUTOSTART', type='Int32', default=0)"


def test_a_parameter_made_by_hand_has_an_empty_read_only_entry() -> None:
    # readers of the entry (its min/max for DroneCAN, metadata written back out) take a mapping
    param = ClassicParam("SYS_AUTOSTART", "Int32", 0)
    assert dict(param.entry) == {} and param.entry.get("min") is None
    with pytest.raises(TypeError):
        param.entry["min"] = 1  # type: ignore[index]


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ("[]", "not a parameters.json (expected an object with a 'parameters' list)"),
        ('{"version": 1}', "not a parameters.json (expected an object with a 'parameters' list)"),
        (
            '{"version": 1, "parameters": {}}',
            "not a parameters.json (expected an object with a 'parameters' list)",
        ),
        ('{"parameters": []}', "parameters.json version null (expected 1)"),
        ('{"version": true, "parameters": []}', "parameters.json version true (expected 1)"),
        # A name with a space went into the metadata written, and failed at 'param show'
        (
            '{"version": 1, "parameters": [{"name": "foo bar", "type": "Int32"}]}',
            "parameters[0]: 'name' \"foo bar\" is not a PX4 parameter name (upper-case letters, "
            "digits and '_', a letter first)",
        ),
        (
            '{"version": 1, "parameters": [{"name": "1ST", "type": "Int32"}]}',
            "parameters[0]: 'name' \"1ST\" is not a PX4 parameter name (upper-case letters, "
            "digits and '_', a letter first)",
        ),
        ('{"version": 2, "parameters": []}', "parameters.json version 2 (expected 1)"),
        ('{"version": 1, "parameters": [1]}', "parameters[0]: expected an object"),
        (
            '{"version": 1, "parameters": [{"type": "Int32"}]}',
            "parameters[0]: 'name' must be 1 to 16 characters",
        ),
        (
            '{"version": 1, "parameters": [{"name": "", "type": "Int32"}]}',
            "parameters[0]: 'name' must be 1 to 16 characters",
        ),
        (
            '{"version": 1, "parameters": [{"name": 5, "type": "Int32"}]}',
            "parameters[0]: 'name' must be 1 to 16 characters",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A2345678901234567", "type": "Int32"}]}',
            "parameters[0]: 'name' must be 1 to 16 characters",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Int32"}, {"name": "B"}]}',
            "parameters[1] (B): 'type' None is not Int32 or Float",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Double"}]}',
            "parameters[0] (A): 'type' 'Double' is not Int32 or Float",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Int32"}, '
            '{"name": "A", "type": "Float"}]}',
            "parameters[1]: duplicate parameter A",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Int32", "default": 0.5}]}',
            "parameters[0] (A): default: expected an integer, got 0.5",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Float", "default": "1"}]}',
            "parameters[0] (A): default: expected a number, got '1'",
        ),
        ("{", "not JSON: Expecting property name enclosed in double quotes"),
        # Python's json reads these, JSON has none: a NaN default went into the metadata and
        # failed there with a traceback (json.dumps refuses it)
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Float", "default": NaN}]}',
            "not JSON: NaN is not a JSON number",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Float", "min": -Infinity}]}',
            "not JSON: -Infinity is not a JSON number",
        ),
        (
            '{"version": 1, "parameters": [{"name": "A", "type": "Float", "default": 1e999}]}',
            "the number 1e999 does not fit a double",
        ),
    ],
)
def test_a_bad_parameters_json_is_named(tmp_path: Path, document: str, message: str) -> None:
    path = tmp_path / "parameters.json"
    path.write_text(document)
    with pytest.raises(ClassicParamsError) as e:
        load_classic(path)
    assert str(e.value).startswith(f"{path}: {message}"), str(e.value)
    assert "\n" not in str(e.value)


def test_an_unreadable_or_binary_parameters_json_is_named(tmp_path: Path) -> None:
    missing = tmp_path / "missing.json"
    with pytest.raises(ClassicParamsError) as e:
        load_classic(missing)
    assert str(e.value) == f"{missing}: cannot read: No such file or directory"
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ClassicParamsError) as e:
        load_classic(binary)
    assert str(e.value) == f"{binary}: not a text file: byte 0xFF at offset 0 is not UTF-8"


# -- the cache of a parameters.json ----------------------------------------------------------


def test_a_settled_file_is_read_from_its_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, cache_dir: Path
) -> None:
    path = parameters_json(tmp_path, [{"name": "A", "type": "Int32", "default": 3}])
    settled(monkeypatch)
    first = load_classic(path)
    (cached,) = cache_dir.iterdir()
    assert cached.name.startswith("classic-")
    # the cache is what a second load reads: a row put there under the same key is taken
    key = classic._cache_key(str(path))
    assert key is not None and cache_path(default_cache_dir(), "classic", key) == str(cached)
    write_cached(str(cached), key, [("A", "Int32", 7, {"name": "A"})])
    again = load_classic(path)
    assert again == [ClassicParam("A", "Int32", 7, {"name": "A"})]
    assert again != first


@pytest.mark.parametrize(
    "row",
    [
        ("A", "Int32", 7),
        ("A", "Int32", 7, {}, 1),
        (1, "Int32", 7, {}),
        ("A", "Double", 7, {}),
        ("A", "Int32", "7", {}),
        ("A", "Int32", 7, []),
        "A",
    ],
)
def test_a_cache_of_another_shape_is_rebuilt(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    cache_dir: Path,
    row: object,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = parameters_json(tmp_path, [{"name": "A", "type": "Int32", "default": 3}])
    settled(monkeypatch)
    key = classic._cache_key(str(path))
    assert key is not None
    cached = cache_path(str(cache_dir), "classic", key)
    write_cached(cached, key, [row])
    assert [(p.name, p.default) for p in load_classic(path)] == [("A", 3)]
    assert "not a list of classic parameters; rebuilding it" in capsys.readouterr().err
    # and rebuilt: the next load takes the file's rows from the cache
    assert [(p.name, p.default) for p in load_classic(path)] == [("A", 3)]
    assert capsys.readouterr().err == ""


def test_a_cache_that_is_not_a_list_is_rebuilt(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, cache_dir: Path
) -> None:
    path = parameters_json(tmp_path, [{"name": "A", "type": "Float", "default": 0.5}])
    settled(monkeypatch)
    key = classic._cache_key(str(path))
    assert key is not None
    write_cached(cache_path(str(cache_dir), "classic", key), key, {"A": 1})
    assert [(p.name, p.default) for p in load_classic(path)] == [("A", 0.5)]


def test_a_file_just_written_is_not_cached(tmp_path: Path, cache_dir: Path) -> None:
    # within the time stamps' resolution another write could keep its stamp: parsed each time
    path = parameters_json(tmp_path, [{"name": "A", "type": "Int32", "default": 3}])
    assert classic._cache_key(str(path)) is None
    load_classic(path)
    assert not cache_dir.exists() or list(cache_dir.iterdir()) == []


def test_the_cache_key_names_the_real_file_and_its_stamp(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = parameters_json(tmp_path, [])
    link = tmp_path / "link.json"
    link.symlink_to(path)
    settled(monkeypatch)
    key = classic._cache_key(str(link))
    assert key is not None and key == classic._cache_key(str(path))
    st = os.stat(path)
    assert key.endswith(f"\n{path} {st.st_dev}:{st.st_ino} {st.st_size} {st.st_mtime_ns} "
                        f"{st.st_ctime_ns}")  # fmt: skip
    assert classic._cache_key(str(tmp_path / "missing.json")) is None
    assert classic._cache_key("bad\0name") is None


# -- values -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (0, 0),
        (-(2**31), -(2**31)),
        (2**31 - 1, 2**31 - 1),
        (4001.0, 4001),
        (True, 1),
        (False, 0),
    ],
)
def test_int32_values(value: object, expected: int) -> None:
    got = classic_value("Int32", value)
    assert got == expected and type(got) is int


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (2**31, "value 2147483648 is out of range (expected -2147483648 to 2147483647)"),
        (-(2**31) - 1, "value -2147483649 is out of range (expected -2147483648 to 2147483647)"),
        (1.5, "expected an integer, got 1.5"),
        ("1", "expected an integer, got '1'"),
        (None, "expected an integer, got None"),
    ],
)
def test_int32_values_refused(value: object, message: str) -> None:
    with pytest.raises(ClassicParamsError) as e:
        classic_value("Int32", value)
    assert str(e.value) == message


def test_float_values_are_rounded_to_float32() -> None:
    third = classic_value("Float", 1 / 3)
    assert third == struct.unpack("<f", struct.pack("<f", 1 / 3))[0] and third != 1 / 3
    assert classic_value("Float", 5) == 5.0 and type(classic_value("Float", 5)) is float
    assert classic_value("Float", True) == 1.0
    flt_max = 3.4028234663852886e38
    assert classic_value("Float", flt_max) == flt_max
    assert classic_value("Float", -flt_max) == -flt_max
    # FLT_MAX as C's float.h and PX4's parameter files print it: above it as a double, but it
    # rounds to it (refused until helper-110 found it); the last double that rounds there too
    assert classic_value("Float", 3.4028235e38) == flt_max
    assert classic_value("Float", -3.4028235e38) == -flt_max
    assert classic_value("Float", math.nextafter(flt_max + 2.0**103, 0)) == flt_max
    assert classic_value("Float", math.inf) == math.inf


FLT_MAX = 3.4028234663852886e38


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (3.4028236e38, "value 3.4028236e+38 does not fit a float32"),
        (FLT_MAX + 2.0**103, f"value {FLT_MAX + 2.0**103} does not fit a float32"),  # halfway
        (-1e39, "value -1e+39 does not fit a float32"),
        (2**200, f"value {float(2**200)} does not fit a float32"),
        ("0.5", "expected a number, got '0.5'"),
        (None, "expected a number, got None"),
    ],
)
def test_float_values_refused(value: object, message: str) -> None:
    with pytest.raises(ClassicParamsError) as e:
        classic_value("Float", value)
    assert str(e.value) == message
