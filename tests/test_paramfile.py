"""store/paramfile.py driven directly: QGC's ``.params`` and the JSON export, written and read.

The rules: a QGC ``.params`` file is ``#`` comment lines, then one TAB-separated line per
parameter, ``vehicle-id component-id name value type`` (MAV_PARAM_TYPE 6 int32, 9 float32),
as QGroundControl saves and loads them; QGC refuses a type that is not the parameter's. The
JSON export is documented in the module and in docs/. Reading is all or nothing.
"""

from __future__ import annotations

import json
from pathlib import Path

import px4params
import pytest
from px4params.errors import ParamFileError
from px4params.store import paramfile
from px4params.store.classic import BUNDLED_CLASSIC

QGC_HEADER = "# Vehicle-Id\tComponent-Id\tName\tValue\tType"


@pytest.fixture
def store(schema: px4params.Schema) -> px4params.Store:
    return px4params.Store(schema, classic=BUNDLED_CLASSIC)


def parameter_lines(text: str) -> list[list[str]]:
    """The parameter lines of a .params text as their five columns; every other line must be
    a comment (QGC skips lines that start with #)."""
    rows = []
    for line in text.splitlines():
        if line.startswith("#"):
            continue
        columns = line.split("\t")
        assert len(columns) == 5, line
        rows.append(columns)
    return rows


def read_file(store: px4params.Store, path: Path, text: str, reset: bool = False) -> list[str]:
    path.write_text(text)
    return paramfile.read(store, str(path), reset=reset)


# -- the file's kind --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("vehicle.params", "qgc"),
        ("VEHICLE.PARAMS", "qgc"),
        ("dir.json/x.Json", "json"),
        ("vehicle.store", None),
        ("params", None),
    ],
)
def test_the_kind_is_the_extension_in_any_case(name: str, kind: str | None) -> None:
    assert paramfile.kind_of(name) == kind


# -- writing QGC's .params ----------------------------------------------------------------------


def test_qgc_export_is_comments_then_five_tab_separated_columns(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.set("INA238#0.bus.i2c.address", 0x45)
    text = paramfile.export_qgc(store)
    lines = text.split("\n")
    # QGC's header ends with the column names; the file ends with a newline, no blank lines
    assert QGC_HEADER in lines
    assert lines[-1] == "" and "" not in lines[:-1]
    rows = parameter_lines(text)
    assert all(row[:2] == ["1", "1"] for row in rows)
    by_name = {row[2]: row for row in rows}
    assert by_name["INA238_0C"] == ["1", "1", "INA238_0C", "69", "6"]  # an int32, type 6
    assert by_name["INA238_0Q"][4] == "9"  # the shunt, a float32
    # every comment line precedes the parameters (QGC writes its header first)
    first = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    assert all(line.startswith("#") for line in lines[:first])
    assert all(not line.startswith("#") for line in lines[first:])


def test_qgc_export_names_the_vehicle_and_component_given(store: px4params.Store) -> None:
    store.set("SYS_AUTOSTART", 4001)
    rows = parameter_lines(paramfile.export_qgc(store, vehicle=7, component=190))
    assert rows == [["7", "190", "SYS_AUTOSTART", "4001", "6"]]


def test_qgc_export_writes_only_changed_classic_parameters_with_their_type(
    store: px4params.Store,
) -> None:
    assert parameter_lines(paramfile.export_qgc(store)) == []  # nothing changed, nothing written
    store.set("BAT1_CAPACITY", 5000.0)
    store.set("SYS_AUTOSTART", 4001)
    rows = {row[2]: row for row in parameter_lines(paramfile.export_qgc(store))}
    assert set(rows) == {"BAT1_CAPACITY", "SYS_AUTOSTART"}
    assert rows["BAT1_CAPACITY"][3:] == ["5000.000000000000000000", "9"]  # 18 decimals, float
    assert rows["SYS_AUTOSTART"][3:] == ["4001", "6"]


def test_a_qgc_export_reads_back_into_an_empty_store(
    store: px4params.Store, schema: px4params.Schema, tmp_path: Path
) -> None:
    store.add("INA238#2")
    store.set("INA238#2.bus._tag", 1)
    store.set("INA238#2.bus.spi.chip_select", 3)
    store.set("BAT1_CAPACITY", 4200.0)
    path = tmp_path / "vehicle.params"
    assert paramfile.write(store, str(path)) == len(path.read_bytes())
    other = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    # Every leaf named, the instance's adding alone is said (the line naming it first).
    assert paramfile.read(other, str(path), reset=False) == [f"{path}:7: added INA238#2"]
    assert other.get("INA238#2") == store.get("INA238#2")
    assert other.get("BAT1_CAPACITY") == 4200.0
    assert "INA238#0" not in other


# -- writing the JSON export ----------------------------------------------------------------


def test_json_export_holds_every_instance_and_the_changed_classic_parameters(
    store: px4params.Store,
) -> None:
    store.add("INA238#0")  # its defaults only: still exported, it exists
    store.add("INA238#1")
    store.set("INA238#1.bus.i2c.address", 0x41)
    store.set("SYS_AUTOSTART", 4001)
    text = paramfile.export_json(store)
    assert text.endswith("}\n")
    document = json.loads(text)
    assert document["format"] == "px4params" and document["version"] == 1
    assert set(document) == {"format", "version", "instances", "classic"}
    assert set(document["instances"]) == {"INA238#0", "INA238#1"}
    assert document["classic"] == {"SYS_AUTOSTART": 4001}  # BAT1_CAPACITY unchanged: left out
    one = document["instances"]["INA238#1"]
    assert set(one) == {"value", "default"}
    assert one["value"]["bus"]["i2c"]["address"] == 0x41
    assert one["default"]["bus"]["i2c"]["address"] == 0x45  # the type's default


def test_json_export_is_indented_by_one_space_as_documented(store: px4params.Store) -> None:
    # docs/file-formats.md shows the export: keys indented one space per level
    assert paramfile.export_json(store) == (
        '{\n "format": "px4params",\n "version": 1,\n "instances": {},\n "classic": {}\n}\n'
    )


def test_json_values_carry_no_p_version() -> None:
    value = {"p_version": 2, "a": [{"p_version": 1, "b": 3}, 4], "c": {"d": 5}}
    assert paramfile._without_versions(value) == {"a": [{"b": 3}, 4], "c": {"d": 5}}


def test_a_json_export_reads_back_into_an_empty_store(
    store: px4params.Store, schema: px4params.Schema, tmp_path: Path
) -> None:
    store.add("INA238#3")
    store.set_default("INA238#3.current", 200)
    store.set("INA238#3.current", 250)
    store.set("SENS_EN_INA238", 1)
    path = tmp_path / "vehicle.json"
    paramfile.write(store, str(path))
    other = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    assert paramfile.read(other, str(path), reset=False) == []
    assert other.get("INA238#3.current") == 250
    assert other.get("INA238#3.current", default=True) == 200
    assert other.get("SENS_EN_INA238") == 1


def test_write_refuses_other_extensions_and_keeps_no_backup(
    store: px4params.Store, tmp_path: Path
) -> None:
    with pytest.raises(ParamFileError) as e:
        paramfile.write(store, str(tmp_path / "vehicle.txt"))
    assert str(e.value) == f"{tmp_path / 'vehicle.txt'}: export writes .params (QGC) or .json files"
    path = tmp_path / "vehicle.params"
    paramfile.write(store, str(path))
    store.set("SYS_AUTOSTART", 4001)
    paramfile.write(store, str(path))  # over the first: an export is no store, no .bak
    assert sorted(p.name for p in tmp_path.iterdir()) == ["vehicle.params"]
    assert "SYS_AUTOSTART\t4001" in path.read_text()


def test_write_over_a_directory_is_a_param_file_error(
    store: px4params.Store, tmp_path: Path
) -> None:
    target = tmp_path / "a.json"
    target.mkdir()
    with pytest.raises(ParamFileError) as e:
        paramfile.write(store, str(target))
    assert str(target) in str(e.value)
    assert target.is_dir()


# -- reading: the file ------------------------------------------------------------------------


def test_an_unreadable_or_binary_file_is_named(store: px4params.Store, tmp_path: Path) -> None:
    missing = tmp_path / "missing.params"
    with pytest.raises(ParamFileError) as e:
        paramfile.read(store, str(missing), reset=False)
    assert str(e.value) == f"{missing}: cannot read: No such file or directory"
    binary = tmp_path / "binary.params"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ParamFileError) as e:
        paramfile.read(store, str(binary), reset=False)
    assert str(e.value) == f"{binary}: not a text file: byte 0xFF at offset 0 is not UTF-8"


def test_reset_starts_from_the_initial_store_and_without_it_the_file_merges(
    store: px4params.Store, tmp_path: Path
) -> None:
    store.add("INA238#1")
    store.set("BAT1_CAPACITY", 4200.0)
    path = tmp_path / "x.params"
    read_file(store, path, "1\t1\tSYS_AUTOSTART\t4001\t6\n")
    assert "INA238#1" in store and store.get("BAT1_CAPACITY") == 4200.0
    read_file(store, path, "1\t1\tSYS_AUTOSTART\t4002\t6\n", reset=True)
    assert "INA238#1" not in store and store.get("BAT1_CAPACITY") == -1.0
    assert store.get("SYS_AUTOSTART") == 4002


def test_other_ground_stations_files_are_named(tmp_path: Path) -> None:
    planner = tmp_path / "copter.param"
    planner.write_text("# saved\nSYS_AUTOSTART,4001\n")
    with pytest.raises(ParamFileError) as e:
        paramfile.refuse_other_ground_station_file(str(planner))
    assert str(e.value) == (
        f"{planner}:2: a comma-separated NAME,VALUE line (Mission Planner's parameter file), "
        "not a store file or QGC's .params: param load and import read store files, .params "
        "(QGC) and .json"
    )
    qgc = tmp_path / "qgc.params"
    qgc.write_text("1\t1\tSYS_AUTOSTART\t4001\t6\n")
    assert paramfile.refuse_other_ground_station_file(str(qgc)) is None
    assert paramfile.refuse_other_ground_station_file(str(tmp_path / "missing")) is None
    binary = tmp_path / "x.store"
    binary.write_bytes(b"\xff\xfe\x00")
    assert paramfile.refuse_other_ground_station_file(str(binary)) is None


# -- reading QGC's .params --------------------------------------------------------------------


def test_a_float_line_of_an_integer_value_sets_a_float(
    store: px4params.Store, tmp_path: Path
) -> None:
    # QGC writes every float with decimals, but a hand-edited "5000" of type 9 is a float
    read_file(store, tmp_path / "x.params", "1\t1\tBAT1_CAPACITY\t5000\t9\n")
    value = store.get("BAT1_CAPACITY")
    assert value == 5000.0 and isinstance(value, float)


def test_flat_lines_add_their_instance_and_set_the_leaf(
    store: px4params.Store, tmp_path: Path
) -> None:
    path = tmp_path / "x.params"
    report = read_file(store, path, "1\t1\tINA238_3C\t70\t6\n1\t1\tINA238_3Q\t0.0625\t9\n")
    # The instance was made without a word, its bus id 0 from the defaults (it cannot start).
    assert report == [
        f"{path}:1: added INA238#3; INA238_3A, INA238_3B, INA238_3P not set by the file: the "
        "type's defaults"
    ]
    assert "INA238#3" in store
    assert store.get("INA238#3.bus.i2c.address") == 70
    assert store.get("INA238#3.shunt") == 0.0625


def test_a_type_changed_between_releases_is_converted_where_nothing_is_lost(
    store: px4params.Store, tmp_path: Path
) -> None:
    # A QGC file of an older PX4 holds RC10_REV as REAL32 and COM_DISARM_LAND as INT32, the
    # other way round today: the whole file was refused at the first such line. Converted where
    # no digit is lost; else skipped, as QGroundControl skips a type mismatch; each said.
    path = tmp_path / "old.params"
    text = (
        "1\t1\tSYS_AUTOSTART\t4001.0\t9\n"  # an integral float: 4001
        "1\t1\tBAT1_CAPACITY\t5000\t6\n"  # an integer a float32 holds: 5000.0
        "1\t1\tINA238_0C\t69.0\t9\n"
        "1\t1\tINA238_0P\t200.0\t9\n"
        "1\t1\tINA238_0B\t0.5\t9\n"  # half an integer: skipped
        "1\t1\tINA238_0Q\t16777217\t6\n"  # 2**24 + 1: no float32 holds it (skipped)
    )
    said = "(its type changed between PX4 releases)"
    assert read_file(store, path, text) == [
        f"{path}:1: SYS_AUTOSTART: REAL32 (9) in the file, INT32 (6) here {said}: 4001.0 taken "
        "as 4001",
        f"{path}:2: BAT1_CAPACITY: INT32 (6) in the file, REAL32 (9) here {said}: 5000 taken as "
        "5000.0",
        f"{path}:3: INA238_0C: REAL32 (9) in the file, INT32 (6) here {said}: 69.0 taken as 69",
        f"{path}:4: INA238_0P: REAL32 (9) in the file, INT32 (6) here {said}: 200.0 taken as 200",
        f"{path}:5: INA238_0B: REAL32 (9) in the file, INT32 (6) here: 0.5 does not fit; skipped",
        f"{path}:6: INA238_0Q: INT32 (6) in the file, REAL32 (9) here: 16777217 does not fit; "
        "skipped",
        f"{path}:3: added INA238#0; INA238_0A, INA238_0B, INA238_0Q not set by the file: the "
        "type's defaults",
    ]
    assert (store.get("SYS_AUTOSTART"), store.get("BAT1_CAPACITY")) == (4001, 5000.0)
    assert store.get("INA238#0.bus.i2c.address") == 69 and store.get("INA238#0.current") == 200


@pytest.mark.parametrize(
    ("line", "taken"),
    [
        ("SYS_AUTOSTART\t-2147483648.0\t9", -(1 << 31)),  # the edges of an int32
        ("SYS_AUTOSTART\t2147483647.0\t9", (1 << 31) - 1),
        ("SYS_AUTOSTART\t-2147483649.0\t9", None),
        ("SYS_AUTOSTART\t2147483648.0\t9", None),
        ("BAT1_CAPACITY\t16777216\t6", 16777216.0),  # 2**24: a float32 holds it
        ("BAT1_CAPACITY\t-16777216\t6", -16777216.0),
        ("BAT1_CAPACITY\t-16777217\t6", None),
    ],
)
def test_a_converted_value_is_taken_only_where_its_new_type_holds_it(
    store: px4params.Store, tmp_path: Path, line: str, taken: int | float | None
) -> None:
    # Each line followed by another, which is read whatever became of the first.
    name = line.split("\t")[0]
    before = store.get(name)
    path = tmp_path / "edge.params"
    report = read_file(store, path, f"1\t1\t{line}\n1\t1\tINA238_1C\t70\t6\n")
    assert report[0].endswith("skipped" if taken is None else f"taken as {taken!r}"), report
    assert store.get(name) == (before if taken is None else taken)
    assert store.get("INA238#1.bus.i2c.address") == 70


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("1\t1\tSYS_AUTOSTART\t1\t4", "SYS_AUTOSTART: type '4' is not 6 (int32) or 9 (float)"),
        ("1\t1\tSYS_AUTOSTART\t1\t10", "SYS_AUTOSTART: type '10' is not 6 (int32) or 9 (float)"),
        ("1\t1\tINA238_0C\t300\t6", "INA238_0C: INA238#0: bus.i2c.address: value 300"),
        ("1\t1\tINA238_0ZZ\t1\t6", "INA238_0ZZ: "),
    ],
)
def test_a_bad_line_is_named_and_changes_nothing(
    store: px4params.Store, tmp_path: Path, line: str, message: str
) -> None:
    store.add("INA238#1")
    before = store.get("INA238#1")
    path = tmp_path / "x.params"
    # a good line first: it is undone with the rest
    with pytest.raises(ParamFileError) as e:
        read_file(store, path, f"# QGC\n1\t1\tINA238_1C\t70\t6\n{line}\n")
    assert str(e.value).startswith(f"{path}:3: {message}"), str(e.value)
    assert "\n" not in str(e.value)
    assert store.get("INA238#1") == before
    assert "INA238#0" not in store
    assert store.get("SYS_AUTOSTART") == 0


def test_a_store_error_is_named_once_by_the_files_name(
    store: px4params.Store, tmp_path: Path
) -> None:
    # the store's own message names the parameter already: not named twice
    path = tmp_path / "x.params"
    with pytest.raises(ParamFileError) as e:
        read_file(store, path, "1\t1\tSENS_EN_INA238\t4294967296\t6\n")
    assert str(e.value).startswith(f"{path}:1: SENS_EN_INA238: ")
    assert str(e.value).count("SENS_EN_INA238") == 1, str(e.value)


def test_an_integer_out_of_range_is_named_as_written(
    store: px4params.Store, tmp_path: Path
) -> None:
    # 2^53 + 1 has no float64: the message names the number of the file, not a rounded one
    path = tmp_path / "x.params"
    with pytest.raises(ParamFileError) as e:
        read_file(store, path, "1\t1\tSYS_AUTOSTART\t9007199254740993\t6\n")
    assert str(e.value) == (
        f"{path}:1: SYS_AUTOSTART: value 9007199254740993 is out of range "
        "(expected -2147483648 to 2147483647)"
    )


def test_a_name_set_twice_is_refused_with_both_lines(
    store: px4params.Store, tmp_path: Path
) -> None:
    path = tmp_path / "x.params"
    with pytest.raises(ParamFileError) as e:
        read_file(store, path, "1\t1\tINA238_0C\t70\t6\n#\n1\t1\tINA238_0C\t71\t6\n")
    assert str(e.value) == f"{path}:3: INA238_0C: also set on line 1"
    assert "INA238#0" not in store


def test_unknown_names_are_skipped_and_counted(store: px4params.Store, tmp_path: Path) -> None:
    path = tmp_path / "x.params"
    report = read_file(
        store,
        path,
        "1\t1\tMPC_XY_VEL_MAX\t8.5\t9\n1\t1\tNOPE_0C\t1\t6\n1\t1\tSYS_AUTOSTART\t4001\t6\n"
        "1\t1\tINA238X\t1\t6\n",
    )
    assert report == [
        f"{path}:1: MPC_XY_VEL_MAX: not a parameter of this store; skipped",
        f"{path}:2: NOPE_0C: not a parameter of this store; skipped",
        f"{path}:4: INA238X: not a parameter of this store; skipped",
        f"{path}: 3 parameters not in this store were skipped",
    ]
    assert store.get("SYS_AUTOSTART") == 4001
    assert read_file(store, path, "1\t1\tSYS_AUTOSTART\t4002\t6\n") == []


# -- reading the JSON export -------------------------------------------------------------------


def json_text(**document: object) -> str:
    return json.dumps({"format": "px4params", "version": 1, **document})


def test_an_empty_instance_entry_adds_the_instance_with_its_defaults(
    store: px4params.Store, tmp_path: Path
) -> None:
    read_file(store, tmp_path / "x.json", json_text(instances={"INA238#3": {}}))
    assert "INA238#3" in store
    assert store.get("INA238#3.bus.i2c.address") == 0x45


def test_default_then_value_are_both_applied(store: px4params.Store, tmp_path: Path) -> None:
    store.add("INA238#0")
    value = store.get("INA238#0")
    changed = dict(value, current=300)
    default = dict(value, current=200)
    read_file(
        store,
        tmp_path / "x.json",
        json_text(instances={"INA238#0": {"value": changed, "default": default}}),
    )
    assert store.get("INA238#0.current") == 300
    assert store.get("INA238#0.current", default=True) == 200


def test_classic_values_are_set(store: px4params.Store, tmp_path: Path) -> None:
    read_file(store, tmp_path / "x.json", json_text(classic={"BAT1_CAPACITY": 3300.0}))
    assert store.get("BAT1_CAPACITY") == 3300.0


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ("[1]", 'not a px4params JSON export (no "format": "px4params")'),
        ('{"version": 1}', 'not a px4params JSON export (no "format": "px4params")'),
        # (the version as JSON writes it: it printed Python's None, '1' and True)
        ('{"format": "px4params"}', "JSON export version null (expected 1)"),
        ('{"format": "px4params", "version": "1"}', 'JSON export version "1" (expected 1)'),
        ('{"format": "px4params", "version": true}', "JSON export version true (expected 1)"),
        (
            json_text(classic={"SYS_AUTOSTART": True}),
            "classic: SYS_AUTOSTART: expected a number, got a boolean",
        ),
        (
            json_text(extra=1),
            "unknown top-level key 'extra'",
        ),
        (
            json_text(instances=[]),
            "'instances' must be an object, not an array; nothing was changed",
        ),
        (
            json_text(classic=True),
            "'classic' must be an object, not a boolean; nothing was changed",
        ),
        (json_text(classic="x"), "'classic' must be an object, not a string; nothing was changed"),
        (json_text(classic=1.5), "'classic' must be an object, not a number; nothing was changed"),
        (json_text(instances=None), "'instances' must be an object, not null; nothing was changed"),
        (
            json_text(instances={"INA238#0.current": {"value": 1}}),
            "instances: INA238#0.current: 'instances' holds whole structured parameters "
            "(INA238#0, not a leaf or a classic parameter)",
        ),
        (
            json_text(instances={"SYS_AUTOSTART": {"value": 1}}),
            "instances: SYS_AUTOSTART: 'instances' holds whole structured parameters",
        ),
        (
            json_text(instances={"INA238#0": 5}),
            'instances: INA238#0: expected {"value": ..., "default": ...}',
        ),
        (
            json_text(instances={"INA238#0": {"defualt": {}}}),
            "instances: INA238#0: unknown key 'defualt' (did you mean 'default'?)",
        ),
        (json_text(instances={"INA238#0": {"value": 1}}), "instances: INA238#0: "),
        (json_text(instances={"NOPE#0": {}}), "instances: unknown parameter 'NOPE'"),
        (json_text(instances={"INA238#": {}}), "instances: 'INA238#' is not a parameter name"),
        (
            json_text(classic={"INA238#0": 1}),
            "classic: INA238#0: not a classic parameter of this store",
        ),
        (json_text(classic={"SYS_AUTOSTART": 1.5}), "classic: SYS_AUTOSTART: "),
        (json_text(classic={"NOPE NOPE": 1}), "classic: "),
        ("{\n\n", ":3: not JSON: Expecting property name enclosed in double quotes"),
        (
            '{"format": "px4params", "version": 1e999}',
            ": 1e999 is out of range of a float64 (a stored float is a finite number)",
        ),
    ],
)
def test_a_bad_json_export_is_named_and_changes_nothing(
    store: px4params.Store, tmp_path: Path, document: str, message: str
) -> None:
    store.add("INA238#1")
    store.set("SYS_AUTOSTART", 4001)
    path = tmp_path / "x.json"
    with pytest.raises(ParamFileError) as e:
        # reset first: undone with the rest
        read_file(store, path, document, reset=True)
    assert str(e.value).startswith(f"{path}"), str(e.value)
    assert message in str(e.value), str(e.value)
    assert "\n" not in str(e.value)
    assert "INA238#1" in store and store.get("SYS_AUTOSTART") == 4001
    assert "INA238#0" not in store


def test_json_kinds_are_named_as_json_names_them() -> None:
    kinds = [(None, "null"), (False, "a boolean"), ([], "an array"), ("", "a string")]
    kinds += [(0, "a number"), (0.5, "a number"), ({}, "an object")]
    assert [paramfile._json_kind(value) for value, _ in kinds] == [name for _, name in kinds]


def test_other_components_lines_are_skipped_and_said(store: px4params.Store, tmp_path) -> None:
    # QGC's MockLink file (as QGC saves a vehicle) holds COMP_2_PARAM and COMP_3_PARAM of
    # components 2 and 3: a gimbal's or a camera's, not the autopilot's. import took every line
    # as the autopilot's, without a word (migrate skipped them).
    from shared_data import shared_file

    mocklink = shared_file("qgc_px4_mocklink.params")
    path = tmp_path / "mock.params"
    path.write_text(mocklink.read_text())
    report = paramfile.read(store, str(path), reset=False)
    said = [line for line in report if ": component " in line]
    assert said == [
        f"{path}: component 2: 1 parameters skipped (not the autopilot's, component 1)",
        f"{path}: component 3: 1 parameters skipped (not the autopilot's, component 1)",
    ]
    mixed = tmp_path / "mixed.params"
    mixed.write_text("1\t1\tSYS_AUTOSTART\t4001\t6\n1\t154\tSYS_AUTOSTART\t13\t6\n")
    assert paramfile.read(store, str(mixed), reset=False) == [
        f"{mixed}: component 154: 1 parameters skipped (not the autopilot's, component 1)"
    ]
    assert store.get("SYS_AUTOSTART") == 4001


def test_a_file_of_two_vehicles_is_refused(store: px4params.Store, tmp_path: Path) -> None:
    path = tmp_path / "two.params"
    path.write_text("1\t1\tSYS_AUTOSTART\t4001\t6\n2\t1\tSYS_AUTOSTART\t4002\t6\n")
    before = store.get("SYS_AUTOSTART")
    with pytest.raises(ParamFileError) as e:
        paramfile.read(store, str(path), reset=False)
    assert str(e.value) == (
        f"{path}:2: vehicle 2: the file holds parameters of vehicles 1, 2 (one vehicle's are "
        "read: split the file)"
    )
    assert store.get("SYS_AUTOSTART") == before
    # One vehicle other than 1 (saved from vehicle 2) is that vehicle's file: read.
    path.write_text("2\t1\tSYS_AUTOSTART\t4002\t6\n")
    assert paramfile.read(store, str(path), reset=False) == []
    assert store.get("SYS_AUTOSTART") == 4002
