"""store/file.py in process: what a load applies and keeps, what it reports, and what a refused
file or save leaves (issue 40: the survivors of its mutation run). The files are built from
docs/store-format.md by test_storefile.py's helpers, independently of the code that reads them;
the saving process killed mid-write is test_storefile.py's (it runs subprocesses).
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import px4params
import pytest
from px4params.errors import StoreFileError
from px4params.store.classic import ClassicParam
from px4params.store.file import encode_file, table_lines
from test_storefile import (
    CLASSIC,
    FIRST_BUNDLED,
    HAS_DEFAULT,
    HAS_VALUE,
    KIND_STRUCTURED,
    _file,
    _table,
    _varint,
    write_records,
)

KIND_CLASSIC = 2  # docs/store-format.md: kind 2, a classic parameter


@pytest.fixture
def store(schema: px4params.Schema) -> px4params.Store:
    return px4params.Store(schema, classic=CLASSIC)


def _classic_record(
    name: str, default: bytes | None, value: bytes | None, *, float32: bool = False
) -> bytes:
    """Kind 2; in a format 3 file, flag 0x40 says float32 values (else int32)."""
    flags = (HAS_DEFAULT if default is not None else 0) | (HAS_VALUE if value is not None else 0)
    flags |= 0x40 if float32 else 0
    return (
        bytes([KIND_CLASSIC | flags, len(name)]) + name.encode() + (default or b"") + (value or b"")
    )


def _ina238(store: px4params.Store, version: str, value: dict) -> bytes:
    return store.schema[version].encode(value, tao=False)


def _lines(store: px4params.Store) -> list[str]:
    return table_lines(store.specs)


def test_a_load_marks_what_it_applied_as_saved(store: px4params.Store, tmp_path: Path) -> None:
    store.add("INA238#0")
    store.set("INA238#0.current", 120)
    store.set("SYS_AUTOSTART", 4001)
    path = tmp_path / "a.store"
    store.save(path)
    other = px4params.Store(store.schema, classic=CLASSIC)
    other.add("INA238#0")
    other.set("INA238#0.current", 7)  # unsaved here
    other.load_from(path)
    assert other.get("INA238#0.current") == 120
    assert other.state("INA238#0") == (False, False)
    assert other.state("SYS_AUTOSTART") == (False, False)
    other.import_from(path)
    assert other.state("INA238#0") == (False, False)


def test_an_import_keeps_foreign_classic_records_a_load_replaces(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """A classic record the store has no parameter for is kept and saved back (nothing lost);
    an import merges (keeps those kept before), a load starts from nothing."""
    full = px4params.Store(schema, classic=CLASSIC)
    full.set("BAT1_CAPACITY", 4200.0)
    with_capacity = tmp_path / "capacity.store"
    full.save(with_capacity)
    plain = tmp_path / "plain.store"
    px4params.Store(schema, classic=CLASSIC).save(plain)

    fewer = px4params.Store(schema, classic=CLASSIC[:1])
    assert fewer.load_from(with_capacity) == [
        "BAT1_CAPACITY: not a classic parameter of this store; kept unchanged"
    ]
    assert fewer.import_from(plain) == []
    out = tmp_path / "out.store"
    fewer.save(out)
    assert px4params.Store.load(out, schema, classic=CLASSIC).get("BAT1_CAPACITY") == 4200.0
    fewer.load_from(plain)  # a load: the file is the whole store
    fewer.save(out)
    assert px4params.Store.load(out, schema, classic=CLASSIC).get("BAT1_CAPACITY") == -1.0


def test_a_refused_load_keeps_what_was_there(schema: px4params.Schema, tmp_path: Path) -> None:
    """A record that cannot be applied (the 3rd of 3) refuses the whole file: values, instances
    and the kept foreign records stay as they were, and the next save writes them."""
    full = px4params.Store(schema, classic=CLASSIC)
    full.set("BAT1_CAPACITY", 4200.0)
    good = tmp_path / "good.store"
    full.save(good)
    fewer = px4params.Store(schema, classic=CLASSIC[:1])
    fewer.load_from(good)
    fewer.add("INA238#1")
    fewer.set("SYS_AUTOSTART", 4001)
    before = encode_file(fewer)
    bad = tmp_path / "bad.store"
    line = "INA238=px.Ina238.1"
    content = _file(
        2,
        zlib.crc32(line.encode()),
        [
            _table([line]),
            _classic_record("SYS_AUTOSTART", None, (13).to_bytes(4, "little")),
            bytes([KIND_STRUCTURED, 0, 2]),  # INA238#2
            bytes([KIND_STRUCTURED, 0, 9]),  # INA238#9: out of range
        ],
    )
    bad.write_bytes(content)
    for apply in (fewer.load_from, fewer.import_from):
        with pytest.raises(StoreFileError) as info:
            apply(bad)
        assert str(info.value) == (
            f"{bad}: record cannot be applied: INA238#9: instance 9 is out of range "
            f"(max_instances is 4: instances 0..3) (at byte {len(content) - 4 - 5})"
        )
        assert encode_file(fewer) == before
    assert fewer.get("SYS_AUTOSTART") == 4001
    assert fewer.instances("INA238") == ["INA238#1"]


def test_classic_defaults_and_values_both_load(store: px4params.Store, tmp_path: Path) -> None:
    path = tmp_path / "c.store"
    path.write_bytes(
        _file(
            3,
            zlib.crc32(b""),
            [
                _table([]),
                _classic_record("SYS_AUTOSTART", (10).to_bytes(4, "little"), None),
                _classic_record("BAT1_CAPACITY", None, struct.pack("<f", 5000.0), float32=True),
            ],
        )
    )
    assert store.load_from(path) == []
    assert store.get("SYS_AUTOSTART", default=True) == 10
    assert store.get("SYS_AUTOSTART") == 10  # the value follows its default
    assert store.get("BAT1_CAPACITY") == 5000.0
    assert store.get("BAT1_CAPACITY", default=True) == -1.0


def test_a_format_1_file_of_todays_whole_list_loads(store: px4params.Store, tmp_path: Path) -> None:
    """Format 1's fingerprint is the CRC-32 of every structured parameter's line of the writer's
    schema: a file written by a schema like this one indexes today's list."""
    lines = _lines(store)
    index = lines.index("INA238=px.Ina238.1")
    assert index != FIRST_BUNDLED.index("INA238=px.Ina238.1")
    path = tmp_path / "f1.store"
    path.write_bytes(
        _file(1, zlib.crc32("\n".join(lines).encode()), [bytes([KIND_STRUCTURED, index, 3])])
    )
    store.load_from(path)
    assert store.instances("INA238") == ["INA238#3"]


def test_an_unreadable_file_is_named(store: px4params.Store, tmp_path: Path) -> None:
    with pytest.raises(StoreFileError) as info:
        store.load_from(tmp_path)  # a folder
    assert str(info.value) == f"{tmp_path}: cannot read: is a folder, not a file"
    assert info.value.file == str(tmp_path) and info.value.offset is None


def test_a_refused_save_names_the_file(store: px4params.Store, tmp_path: Path) -> None:
    target = tmp_path / "folder.store"
    target.mkdir()
    with pytest.raises(StoreFileError) as info:
        store.save(target)
    assert info.value.file == str(target)
    assert str(info.value) == f"{target}: cannot write: a directory, not a regular file"


def test_a_translated_default_and_value_are_both_reported(
    store: px4params.Store, tmp_path: Path
) -> None:
    """A record of px.Ina238.1.0 with a default and a value: each is translated to 1.1 (the
    default from the type's default, the value from the instance's default) and reported."""
    default = _ina238(
        store,
        "px.Ina238.1.0",
        {"bus": {"i2c": {"bus_id": 1, "address": 0x40}}, "current": 100, "shunt_uohm": 300},
    )
    value = _ina238(
        store,
        "px.Ina238.1.0",
        {
            "bus": {"spi": {"bus_id": 2, "chip_select": 1, "max_frequency": 8, "mode": 3}},
            "current": 90,
            "shunt_uohm": 700,
        },
    )
    index = store.parameters.index("INA238")
    record = bytes([KIND_STRUCTURED | HAS_DEFAULT | HAS_VALUE]) + _varint(index) + _varint(2)
    record += _varint(len(default)) + default + _varint(len(value)) + value
    path = tmp_path / "old.store"
    write_records(path, store, [record])
    report = store.load_from(path)
    assert report == [
        "INA238#2: translated px.Ina238.1.0 -> px.Ina238.1.1: kept bus.i2c.bus_id, "
        "bus.i2c.address, current; new, from defaults: shunt; dropped: shunt_uohm=300",
        "INA238#2: translated px.Ina238.1.0 -> px.Ina238.1.1: kept bus.spi.bus_id, "
        "bus.spi.chip_select, bus.spi.max_frequency, bus.spi.mode, current; new, from "
        "defaults: shunt; dropped: shunt_uohm=700",
    ]
    assert store.get("INA238#2.bus.i2c.address", default=True) == 0x40
    assert store.get("INA238#2.current", default=True) == 100
    assert store.get("INA238#2.bus.spi.chip_select") == 1
    assert store.get("INA238#2.current") == 90


def test_a_current_version_record_is_taken_as_it_is(store: px4params.Store, tmp_path: Path) -> None:
    payload = _ina238(
        store,
        "px.Ina238.1.1",
        {"bus": {"i2c": {"bus_id": 3, "address": 0x44}}, "current": 50, "shunt": 0.001},
    )
    index = store.parameters.index("INA238")
    record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(index) + _varint(0)
    path = tmp_path / "now.store"
    write_records(path, store, [record + _varint(len(payload)) + payload])
    assert store.load_from(path) == []
    assert store.encoded("INA238#0") == payload


def test_an_unknown_classic_name_in_a_store_of_none(schema: px4params.Schema, tmp_path) -> None:
    bare = px4params.Store(schema, classic=[ClassicParam("SYS_AUTOSTART", "Int32", 0)])
    path = tmp_path / "x.store"
    path.write_bytes(
        _file(3, zlib.crc32(b""), [_table([]), _classic_record("INA238", None, bytes(4))])
    )
    # a structured parameter's name in a classic record: not a classic parameter here either
    assert bare.load_from(path) == ["INA238: not a classic parameter of this store; kept unchanged"]
    assert bare.instances("INA238") == []


def test_a_record_beyond_the_table_is_refused(store: px4params.Store, tmp_path: Path) -> None:
    line = "INA238=px.Ina238.1"
    content = _file(2, zlib.crc32(line.encode()), [_table([line]), bytes([KIND_STRUCTURED, 5, 0])])
    path = tmp_path / "x.store"
    path.write_bytes(content)
    with pytest.raises(StoreFileError) as info:
        store.load_from(path)
    assert str(info.value) == (
        f"{path}: record cannot be applied: no parameter #5 (at byte {len(content) - 4 - 5})"
    )


def test_an_import_onto_an_existing_instance_merges_its_values(
    store: px4params.Store, tmp_path: Path
) -> None:
    """``param import`` merges: an instance the store has already (used by a driver or not)
    takes the file's value, and is not added twice."""
    store.add("INA238#0")
    store.set("INA238#0.current", 120)
    path = tmp_path / "a.store"
    store.save(path)
    other = px4params.Store(store.schema, classic=CLASSIC)
    other.add("INA238#0")
    other.set("INA238#0.current", 5)
    other.add("INA238#1")
    other.mark_used("INA238#1")
    assert other.import_from(path) == []
    assert other.get("INA238#0.current") == 120
    assert other.instances("INA238") == ["INA238#0", "INA238#1"]
    other.mark_used("INA238#0")
    other.set("INA238#0.current", 6)
    other.import_from(path)
    assert other.get("INA238#0.current") == 120


def test_a_translated_value_takes_new_fields_from_the_instances_default(
    store: px4params.Store, tmp_path: Path
) -> None:
    """docs/store-format.md: "fields the new version added take their defaults": imported onto
    an instance whose value differs from its default, the new field ``shunt`` comes from the
    instance's default, not from the value it had."""
    store.add("INA238#0")
    store.set_default("INA238#0.shunt", 0.001)
    store.set("INA238#0.shunt", 0.002)
    value = _ina238(
        store,
        "px.Ina238.1.0",
        {"bus": {"i2c": {"bus_id": 1, "address": 0x40}}, "current": 80, "shunt_uohm": 900},
    )
    index = store.parameters.index("INA238")
    record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(index) + _varint(0)
    path = tmp_path / "old.store"
    write_records(path, store, [record + _varint(len(value)) + value])
    store.import_from(path)
    assert store.get("INA238#0.current") == 80
    assert store.get("INA238#0.shunt") == pytest.approx(0.001, rel=1e-3)


def acme_store(tmp_path: Path, files: dict[str, str]) -> px4params.Store:
    """A store of the bundled types and ACME's DSDL ``files`` (name: text), no classic ones."""
    root = tmp_path / "acme"
    root.mkdir()
    for name, text in files.items():
        (root / name).write_text(text)
    return px4params.Store(px4params.load_schema([str(root)], use_env=False), classic=[])


def test_a_shared_parameter_is_loaded_without_instances(tmp_path: Path) -> None:
    """A parameter shared by all instances (``@param`` without ``@max_instances``) is stored as
    instance 0 and loads into its one value."""
    gadget = "# @param GADGET_SHARED\n\nuint8 gain\n# @default 3\n\n@sealed\n"
    store = acme_store(tmp_path, {"GadgetShared.1.0.dsdl": gadget})
    schema = store.schema
    store.set("GADGET_SHARED.gain", 9)
    path = tmp_path / "g.store"
    store.save(path)
    again = px4params.Store.load(path, schema, classic=[])
    assert again.get("GADGET_SHARED.gain") == 9
    again.set("GADGET_SHARED.gain", 4)
    again.import_from(path)
    assert again.get("GADGET_SHARED.gain") == 9


def test_translation_names_the_old_type_by_major_then_minor(tmp_path: Path) -> None:
    """A value written by acme.Gadget.2.0 (p_version 0) is read with that type and translated
    to 2.1: the old type's key is NAME.MAJOR.MINOR, major from the current type, minor from the
    value (a type whose major and minor differ, unlike px.Ina238.1.1)."""
    root = tmp_path / "acme"
    root.mkdir()
    head = "# @param GADGET\n# @max_instances 2\nuint4 p_version\nuint8 gain\n"
    (root / "Gadget.2.0.dsdl").write_text(head + "uint8 spare\n@sealed\n")  # the same size
    (root / "Gadget.2.1.dsdl").write_text(head + "uint8 offset\n# @default 7\n@sealed\n")
    schema = px4params.load_schema([str(root)], use_env=False)
    store = px4params.Store(schema, classic=[])
    payload = schema["acme.Gadget.2.0"].encode({"gain": 9, "spare": 5}, tao=False)
    lines = table_lines(store.specs)
    record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(lines.index("GADGET=acme.Gadget.2"))
    record += _varint(1) + _varint(len(payload)) + payload
    path = tmp_path / "g.store"
    path.write_bytes(_file(2, zlib.crc32("\n".join(lines).encode()), [_table(lines), record]))
    assert store.load_from(path) == [
        "GADGET#1: translated acme.Gadget.2.0 -> acme.Gadget.2.1: kept gain; new, from "
        "defaults: offset; dropped: spare=5"
    ]
    assert store.get("GADGET#1") == {"p_version": 1, "gain": 9, "offset": 7}


#: Types of an extra DSDL folder whose minor versions differ the ways docs/store-format.md's
#: "Type versions" describes: fields kept, new, dropped (nested and a trailing array among
#: them), nothing kept, a carried value that no longer fits.
ACME = {
    "Pair.1.0.dsdl": "uint8 x\nuint8 y\n@sealed\n",
    "Single.1.0.dsdl": "uint8 x\nuint8 z\n@sealed\n",
    "Widget.1.0.dsdl": "uint4 p_version\nuint8 a\nPair.1.0 pair\nuint8[<=2] cal\n@sealed\n",
    "Widget.1.1.dsdl": "uint4 p_version\nuint8 c\nSingle.1.0 pair\nuint8 d\nuint8 e\nuint8 f\n"
    "@sealed\n",
    "Gizmo.1.0.dsdl": "uint4 p_version\nuint8 a\nPair.1.0 old\n@sealed\n",
    "Gizmo.1.1.dsdl": "uint4 p_version\nuint8 b\nuint16 spare\n@sealed\n",
    "Doohickey.1.0.dsdl": "uint4 p_version\nuint12 level\n@sealed\n",
    "Doohickey.1.1.dsdl": "uint4 p_version\nuint4 level\nuint8 pad\n@sealed\n",
}


def _acme_file(tmp_path: Path, param: str, key: str, value: dict) -> tuple[px4params.Store, Path]:
    """A store of the bundled types and ACME's, and a file holding ``value`` (written by type
    ``key``) as instance 0 of ``param``."""
    root = tmp_path / "acme"
    root.mkdir()
    for name, text in ACME.items():
        head = f"# @param {name.split('.')[0].upper()}\n# @max_instances 2\n"
        (root / name).write_text(text if name[0] in "PS" else head + text)
    schema = px4params.load_schema([str(root)], use_env=False)
    store = px4params.Store(schema, classic=[])
    payload = schema[key].encode(value, tao=False)
    lines = table_lines(store.specs)
    record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(lines.index(f"{param}={key[:-2]}"))
    record += _varint(0) + _varint(len(payload)) + payload
    path = tmp_path / "acme.store"
    path.write_bytes(_file(2, zlib.crc32("\n".join(lines).encode()), [_table(lines), record]))
    return store, path


def test_the_translation_report_lists_every_field_and_dropped_value(tmp_path: Path) -> None:
    value = {"a": 1, "pair": {"x": 2, "y": 3}, "cal": [4, 5]}
    store, path = _acme_file(tmp_path, "WIDGET", "acme.Widget.1.0", value)
    assert store.load_from(path) == [
        "WIDGET#0: translated acme.Widget.1.0 -> acme.Widget.1.1: kept pair.x; new, from "
        "defaults: c, pair.z, d, e, f; dropped: pair.y=3, a=1, cal=[4,5]"
    ]
    assert store.get("WIDGET#0") == {
        "p_version": 1, "c": 0, "pair": {"x": 2, "z": 0}, "d": 0, "e": 0, "f": 0
    }  # fmt: skip


def test_a_translation_that_keeps_nothing_says_so(tmp_path: Path) -> None:
    store, path = _acme_file(tmp_path, "GIZMO", "acme.Gizmo.1.0", {"a": 7, "old": {"x": 1, "y": 2}})
    # a dropped struct is shown whole, as JSON that can be typed back in
    assert store.load_from(path) == [
        "GIZMO#0: translated acme.Gizmo.1.0 -> acme.Gizmo.1.1: kept nothing; new, from "
        'defaults: b, spare; dropped: a=7, old={"x":1,"y":2}'
    ]


def test_a_carried_value_that_does_not_fit_refuses_the_file(tmp_path: Path) -> None:
    store, path = _acme_file(tmp_path, "DOOHICKEY", "acme.Doohickey.1.0", {"level": 300})
    with pytest.raises(StoreFileError) as info:
        store.load_from(path)
    assert str(info.value).startswith(
        f"{path}: record cannot be applied: DOOHICKEY#0: cannot translate from "
        "acme.Doohickey.1.0: level: value 300 is out of range (expected 0 to 15) (at byte "
    )
    assert store.instances("DOOHICKEY") == []


def test_a_value_of_a_minor_version_the_schema_lacks_is_refused(
    store: px4params.Store, tmp_path: Path
) -> None:
    value = {"bus": {"i2c": {"bus_id": 1, "address": 1}}, "current": 1, "shunt": 0.001}
    payload = bytearray(_ina238(store, "px.Ina238.1.1", value))
    payload[0] = (payload[0] & 0x0F) | 0x50  # p_version 5: no px.Ina238.1.5
    index = store.parameters.index("INA238")
    record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(index) + _varint(3)
    path = tmp_path / "future.store"
    write_records(path, store, [record + _varint(len(payload)) + bytes(payload)])
    with pytest.raises(StoreFileError) as info:
        store.load_from(path)
    assert str(info.value).startswith(
        f"{path}: record cannot be applied: INA238#3 was stored by px.Ina238.1.5, which this "
        "schema does not have (at byte "
    )


@pytest.mark.parametrize(
    ("bad", "said"),
    [
        ("value", "INA238#0.shunt: nan is not a finite number (float16: NaN and infinities"),
        ("default", "INA238#0.shunt: -inf is not a finite number (float16: NaN and infinities"),
        ("classic", "BAT1_CAPACITY: inf is not a finite number (Float: NaN and infinities"),
    ],
)
def test_a_nan_or_infinity_in_a_file_is_refused(
    store: px4params.Store, tmp_path: Path, bad: str, said: str
) -> None:
    # Nothing stores a NaN or an infinity, yet a file holding one (its CRCs right: written by
    # something else, or damaged before its CRCs were made) loaded, and its export was then
    # refused by import.
    ina238 = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 150}
    payload = {
        "value": _ina238(store, "px.Ina238", {**ina238, "shunt": float("nan")}),
        "default": _ina238(store, "px.Ina238", {**ina238, "shunt": float("-inf")}),
    }.get(bad)
    flag = HAS_DEFAULT if bad == "default" else HAS_VALUE
    records = [_classic_record("BAT1_CAPACITY", None, struct.pack("<f", float("inf")))]
    if payload is not None:
        index = store.parameters.index("INA238")
        records = [bytes([KIND_STRUCTURED | flag]) + _varint(index) + _varint(0)]
        records[0] += _varint(len(payload)) + payload
    path = tmp_path / "nan.store"
    write_records(path, store, records)
    store.add("INA226#1")
    before = encode_file(store)
    for apply in (store.load_from, store.import_from):
        with pytest.raises(StoreFileError) as info:
            apply(path)
        assert str(info.value).startswith(f"{path}: record cannot be applied: {said} are refused)")
        assert encode_file(store) == before


def test_a_value_beyond_its_max_stored_with_force_loads_as_written(
    store: px4params.Store, tmp_path: Path
) -> None:
    # Store files are the store's own saved state: what 'param set --force' stored comes back.
    store.add("INA238#0")
    store.set("INA238#0.current", 500, force=True)
    path = tmp_path / "forced.store"
    store.save(path)
    again = px4params.Store(store.schema, classic=CLASSIC)
    assert again.load_from(path) == [] and again.get("INA238#0.current") == 500


def test_a_nan_in_a_last_array_is_found_where_it_is(tmp_path: Path) -> None:
    # Stored values are encoded without tail array optimization: the check reads them so (read
    # with it, the length prefix is taken for the array's first bits).
    probe = "# @param PROBE\n# @max_instances 2\nuint8 gain\nfloat32[<=3] cal\n@sealed\n"
    store = acme_store(tmp_path, {"Probe.1.0.dsdl": probe})
    schema = store.schema
    lines = table_lines(store.specs)
    index = lines.index("PROBE=acme.Probe.1")

    def file_of(cal: list[float]) -> Path:
        payload = schema["acme.Probe.1.0"].encode({"gain": 2, "cal": cal}, tao=False)
        record = bytes([KIND_STRUCTURED | HAS_VALUE]) + _varint(index) + _varint(1)
        record += _varint(len(payload)) + payload
        path = tmp_path / "probe.store"
        path.write_bytes(_file(2, zlib.crc32("\n".join(lines).encode()), [_table(lines), record]))
        return path

    assert store.load_from(file_of([0.5, 1.5])) == []
    assert store.get("PROBE#1")["cal"] == [0.5, 1.5]
    with pytest.raises(StoreFileError) as info:
        store.load_from(file_of([0.5, float("inf"), 2.5]))
    assert "record cannot be applied: PROBE#1.cal[1]: inf is not a finite number" in str(info.value)
    assert store.get("PROBE#1")["cal"] == [0.5, 1.5]


def test_an_integer_classic_whose_bits_would_be_a_float_nan_loads(
    store: px4params.Store, tmp_path: Path
) -> None:
    # 0x7FC00000 is a NaN as a float: an Int32 parameter holding it is a number like any other.
    path = tmp_path / "int.store"
    value = (0x7FC00000).to_bytes(4, "little")
    write_records(path, store, [_classic_record("SYS_AUTOSTART", None, value)])
    assert store.load_from(path) == [] and store.get("SYS_AUTOSTART") == 0x7FC00000
