"""Parameter files into the page's review, and the configuration out as files
(``px4params.gui.files``), without a browser: every kind of file the page loads."""

from __future__ import annotations

from typing import Any

import px4params
import pytest
from px4params.errors import Px4ParamsError
from px4params.gcs.metadata import build_parameters_json
from px4params.gui import files
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.store.flat import flat_values


@pytest.fixture
def vehicle(schema: px4params.Schema) -> tuple[dict[str, Any], dict[str, Any]]:
    """The values and metadata of a vehicle with INA238#1 on I2C bus 2 at 0x45."""
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    store.set("INA238#1.bus.i2c.bus_id", 2)
    classic = [c for c in map(store.classic, store.parameters) if c is not None]
    metadata = build_parameters_json(schema, specs=store.specs, classic_params=classic)
    return flat_values(store), metadata


def test_an_airframe_file_becomes_changes_in_write_order(vehicle: Any) -> None:
    values, metadata = vehicle
    airframe = (
        "# the talk's lines, for another instance\n"
        "param add INA238#0\n"
        "param set-default INA238#0[3] 1\n"
        "param set-default INA238#0[4] 0x46\n"
        "param set INA238#1.bus.i2c.address 0x47\n"
    )
    review = files.review_file("more.airframe", airframe, values, metadata)
    changes = {c["name"]: (c["current"], c["new"]) for c in review["changes"]}
    assert changes["INA238_INST"] == (0b10, 0b11)
    assert changes["INA238_0C"] == (None, 0x46) and changes["INA238_0B"] == (None, 1)
    assert changes["INA238_1C"] == (0x45, 0x47)
    assert "INA238_1B" not in changes  # unchanged
    order = [c["name"] for c in review["changes"]]
    assert order[0] == "INA238_INST" and order.index("INA238_0A") < order.index("INA238_0C")


def test_a_failing_airframe_names_its_line(vehicle: Any) -> None:
    values, metadata = vehicle
    with pytest.raises(Px4ParamsError, match=r"^bad\.airframe:2: .*INA238#9"):
        files.review_file(
            "bad.airframe", "param add INA238#0\nparam add INA238#9\n", values, metadata
        )


def test_a_json_export_becomes_changes(vehicle: Any) -> None:
    values, metadata = vehicle
    value = '{"bus": {"i2c": {"bus_id": 3, "address": 64}}, "current": 100, "shunt": 0.001}'
    text = (
        '{"format": "px4params", "version": 1, "instances": {"INA238#1": {"value": '
        + value
        + '}}, "classic": {"SYS_AUTOSTART": 4001}}'
    )
    review = files.review_file("vehicle.json", text, values, metadata)
    changes = {c["name"]: c["new"] for c in review["changes"]}
    assert (changes["INA238_1B"], changes["INA238_1C"], changes["INA238_1P"]) == (3, 64, 100)
    assert changes["SYS_AUTOSTART"] == 4001


def test_a_params_file_with_bad_lines(vehicle: Any) -> None:
    values, metadata = vehicle
    with pytest.raises(Px4ParamsError, match=r"^x\.params:2: expected 5 TAB-separated columns"):
        files.review_file("x.params", "# c\n1\t1\tINA238_1C\n", values, metadata)
    with pytest.raises(
        Px4ParamsError, match=r"^x\.params:1: INA238_1C: value 'abc' is not a number"
    ):
        files.review_file("x.params", "1\t1\tINA238_1C\tabc\t6\n", values, metadata)


def test_exports_rebuild_the_vehicle(vehicle: Any, schema: px4params.Schema, tmp_path: Any) -> None:
    values, metadata = vehicle
    params = files.export_params(values, metadata)
    assert "1\t1\tINA238_1B\t2\t6" in params
    airframe = files.export_airframe(values, metadata)
    assert airframe.splitlines()[2] == "param add INA238#1"
    # the airframe, run on an empty vehicle, gives back the same flat values
    empty = {k: v for k, v in values.items() if not k.startswith("INA238_1")}
    empty["INA238_INST"] = 0
    review = files.review_file("saved.airframe", airframe, empty, metadata)
    rebuilt = dict(empty) | {c["name"]: c["new"] for c in review["changes"]}
    assert rebuilt == values


# -- issue 40: what the mutation run of gui/files.py found untested --------------------------


@pytest.fixture
def two_monitors(schema: px4params.Schema) -> tuple[px4params.Store, dict[str, Any], Any]:
    """A vehicle with INA238#0 and INA238#1 on I2C, and classic parameters changed: the
    legacy INA238_CURRENT (a classic Float that shares the structured parameter's prefix),
    BAT1_CAPACITY (Float) and SYS_AUTOSTART (Int32)."""
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("INA238#0")
    store.add("INA238#1")
    store.set("INA238#1.bus.i2c.bus_id", 2)
    store.set("INA238_CURRENT", 100.0)
    store.set("BAT1_CAPACITY", 5000.0)
    store.set("SYS_AUTOSTART", 4001)
    classic = [c for c in map(store.classic, store.parameters) if c is not None]
    metadata = build_parameters_json(schema, specs=store.specs, classic_params=classic)
    return store, flat_values(store), metadata


@pytest.mark.issue40
def test_changes_are_written_masks_then_union_tags_then_the_rest(two_monitors: Any) -> None:
    """docs/ground-stations.md: "Writing goes in order (instance masks, then union tags, then
    the rest)": a tag makes its variant's fields live, so INA238#1's switch to SPI (1A) goes
    before INA238#0's address (0C), which sorts before it by name."""
    _, values, metadata = two_monitors
    airframe = (
        "param set INA238#0.bus.i2c.address 0x41\n"
        "param set INA238#1.bus._tag 1\n"
        "param add INA238#2\n"
    )
    review = files.review_file("spi.airframe", airframe, values, metadata)
    assert [c["name"] for c in review["changes"]] == [
        "INA238_INST",  # INA238#2 added
        "INA238_1A",  # INA238#1 to SPI
        "INA238_2A",
        "INA238_0C",
        "INA238_1D",  # SPI's fields, live once 1A is written
        "INA238_1E",
        "INA238_1F",
        "INA238_1G",
        "INA238_2B",
        "INA238_2C",
        "INA238_2P",
        "INA238_2Q",
    ]


@pytest.mark.issue40
def test_a_params_file_skips_names_the_vehicle_lacks_with_a_note(vehicle: Any) -> None:
    values, metadata = vehicle
    text = "1\t1\tNO_SUCH_PARAM\t3\t6\n1\t1\tINA238_1C\t70\t6\n1\t1\tSYS_AUTOSTART\t4001\t6\n"
    review = files.review_file("x.params", text, values, metadata)
    assert review["notes"] == [
        "x.params:1: NO_SUCH_PARAM: the vehicle has no such parameter; skipped"
    ]
    assert review["changes"] == [
        {"name": "INA238_1C", "current": 0x45, "new": 70},
        {"name": "SYS_AUTOSTART", "current": 0, "new": 4001},
    ]


@pytest.mark.issue40
def test_a_json_file_changes_only_what_it_names(two_monitors: Any) -> None:
    """A file that names one classic parameter leaves the instances and the other values as
    the vehicle has them (loading a file onto the vehicle is no reset)."""
    _, values, metadata = two_monitors
    text = '{"format": "px4params", "version": 1, "classic": {"SYS_AUTOSTART": 4002}}'
    review = files.review_file("Vehicle.JSON", text, values, metadata)
    assert review == {
        "changes": [{"name": "SYS_AUTOSTART", "current": 4001, "new": 4002}],
        "notes": [],
    }


@pytest.mark.issue40
def test_an_airframe_setting_a_classic_float_is_reviewed(two_monitors: Any) -> None:
    """Without the offline store the classic parameters come from the metadata: Float ones
    too, and a legacy name that shares a structured parameter's prefix (INA238_CURRENT)."""
    _, values, metadata = two_monitors
    airframe = "param set INA238_CURRENT 150\nparam set BAT1_CAPACITY 4000\n"
    review = files.review_file("legacy.airframe", airframe, values, metadata)
    changes = {c["name"]: (c["current"], c["new"]) for c in review["changes"]}
    assert changes == {"INA238_CURRENT": (100.0, 150.0), "BAT1_CAPACITY": (5000.0, 4000.0)}


@pytest.mark.issue40
def test_a_failing_airframe_stops_at_its_first_error(vehicle: Any) -> None:
    """One line naming the first failing line, as `px4params run` stops there."""
    values, metadata = vehicle
    with pytest.raises(Px4ParamsError) as caught:
        files.review_file(
            "bad.airframe",
            "param add INA238#9\nparam add INA238#8\nparam set NO_SUCH 1\n",
            values,
            metadata,
        )
    assert str(caught.value) == (
        "bad.airframe:1: INA238#9: instance 9 is out of range (max_instances is 4: instances 0..3)"
    )


@pytest.mark.issue40
def test_the_airframe_export_lists_the_classic_parameters_changed(two_monitors: Any) -> None:
    """PX4 airframes set classic parameters with `param set-default NAME VALUE`; those at
    their default are left out. Over MAVLink (no offline store) as from the store."""
    store, values, metadata = two_monitors
    expected = [
        "param set-default SYS_AUTOSTART 4001",
        "param set-default INA238_CURRENT 100.0",
        "param set-default BAT1_CAPACITY 5000.0",
    ]
    for offline in (None, store):
        lines = files.export_airframe(values, metadata, offline).splitlines()
        classic = [line for line in lines if line.startswith("param set-default ")]
        classic = [line for line in classic if "#" not in line]
        assert sorted(classic) == sorted(expected), offline


@pytest.mark.issue40
def test_a_metadata_entry_without_a_default_defaults_to_zero(vehicle: Any) -> None:
    """PX4's parameter metadata may leave "default" out (it is optional in its schema): such
    a parameter at 0 is unchanged, so the airframe leaves it out."""
    values, metadata = vehicle
    extra = {"name": "TEST_NO_DEF", "type": "Int32", "group": "Test"}
    doc = {**metadata, "parameters": [*metadata["parameters"], extra]}
    airframe = files.export_airframe({**values, "TEST_NO_DEF": 0}, doc)
    assert "TEST_NO_DEF" not in airframe
    airframe = files.export_airframe({**values, "TEST_NO_DEF": 7}, doc)
    assert "param set-default TEST_NO_DEF 7" in airframe.splitlines()
    # a default that is no number (null in a hand-written document) counts as 0 too
    doc["parameters"][-1] = {**extra, "default": None}
    assert "TEST_NO_DEF" not in files.export_airframe({**values, "TEST_NO_DEF": 0}, doc)


@pytest.mark.issue40
def test_a_file_without_a_name_is_read_as_an_airframe(vehicle: Any) -> None:
    """The page sends the file's name; a script may send none: its lines are airframe lines."""
    values, metadata = vehicle
    review = files.review_file("", "param set SYS_AUTOSTART 4001\n", values, metadata)
    assert review["changes"] == [{"name": "SYS_AUTOSTART", "current": 0, "new": 4001}]


@pytest.mark.issue40
def test_reviews_and_exports_use_the_offline_store_s_types(two_monitors: Any) -> None:
    """With the offline store, the scratch copy is the store's (its schema and classic
    parameters), not the bundled types: the review and both files are the same."""
    store, values, metadata = two_monitors
    text = "param set INA238#1.bus.i2c.address 0x46\n"
    assert files.review_file("a.airframe", text, values, metadata, store) == files.review_file(
        "a.airframe", text, values, metadata
    )
    params = files.export_params(values, metadata, store)
    assert "1\t1\tINA238_CURRENT\t100" in params and "1\t1\tINA238_1B\t2\t6" in params


def test_a_reviewed_airframe_reads_and_writes_no_file_on_this_computer(
    vehicle: Any, tmp_path: Any
) -> None:
    """The page's review of a file (a pilot previewing an airframe from a forum) ran its
    'param save FILE' and 'param export FILE' lines: the vehicle's store and any file the
    user could write were replaced before anything was confirmed, and 'param load FILE' read
    local files into the review. Those lines are passed over, each said in the notes."""
    values, metadata = vehicle
    victim, local = tmp_path / "victim.txt", tmp_path / "local.params"
    victim.write_text("important\n")
    local.write_text("1\t1\tINA238_1C\t99\t6\n")
    airframe = (
        "param set INA238#1.bus.i2c.address 0x47\n"
        f"param save {victim}\n"
        f"param export {tmp_path / 'new.params'}\n"
        f"param load {local}\n"
        f"param import {local}\n"
        "param save\n"  # the (scratch) store's own file: harmless, and run
        "param load\n"  # the store's: it named the server's scratch copy, which does not exist
        "param import\n"
    )
    review = files.review_file("forum.airframe", airframe, values, metadata)
    assert victim.read_text() == "important\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["local.params", "victim.txt"]
    assert review["changes"] == [{"name": "INA238_1C", "current": 0x45, "new": 0x47}]
    why = "not run here: it would read or write a file on this computer"
    assert review["notes"] == [
        f"forum.airframe:2: param save {victim}: {why}",
        f"forum.airframe:3: param export {tmp_path / 'new.params'}: {why}",
        f"forum.airframe:4: param load {local}: {why}",
        f"forum.airframe:5: param import {local}: {why}",
        "forum.airframe:7: param load: not run here: it would read the vehicle's saved store",
        "forum.airframe:8: param import: not run here: it would read the vehicle's saved store",
    ]


def test_a_bad_json_file_is_named_as_the_page_named_it(vehicle: Any) -> None:
    # The refusal named the copy read on the server (/tmp/tmp.../vehicle.json).
    values, metadata = vehicle
    text = '{"format": "px4params", "version": 1, "instances": {"NOPE#0": {}}}'
    with pytest.raises(Px4ParamsError) as e:
        files.review_file("vehicle.json", text, values, metadata)
    assert str(e.value) == "vehicle.json: instances: unknown parameter 'NOPE'"


def test_a_params_file_is_its_autopilots_and_one_vehicles(vehicle: Any) -> None:
    # The page took every row: a gimbal's (component 154) INA238_1C over the vehicle's, and a
    # second vehicle's values, where import and migrate read the autopilot's alone.
    values, metadata = vehicle
    gimbal = "1\t1\tINA238_1C\t70\t6\n1\t154\tINA238_1C\t99\t6\n1\t154\tGMB_MODE\t2\t6\n"
    review = files.review_file("x.params", gimbal, values, metadata)
    assert review["changes"] == [{"name": "INA238_1C", "current": 0x45, "new": 70}]
    assert review["notes"] == [
        "x.params: component 154: 2 parameters skipped (not the autopilot's, component 1)"
    ]
    two = "1\t1\tINA238_1C\t70\t6\n2\t1\tINA238_1C\t71\t6\n"
    with pytest.raises(Px4ParamsError) as refused:
        files.review_file("x.params", two, values, metadata)
    assert str(refused.value) == (
        "x.params:2: vehicle 2: the file holds parameters of vehicles 1, 2 (one vehicle's are "
        "read: split the file)"
    )


@pytest.mark.parametrize(
    ("filename", "text", "error"),
    [
        # each was a 500 and a traceback: the page's name was the scratch copy's
        ("a\x00b.json", "{", "a\\x00b.json:"),
        ("a\x00b.airframe", "param set NOPE 1", "a\\x00b.airframe:1: "),
        ("a" * 300 + ".json", "{", "aaaaaaaaaaaa...a.json (305 characters):"),
        ("a" * 250 + ".json", "{", "a" * 250 + ".json:"),  # 255 characters: shown whole
        ("a" * 251 + ".json", "{", "aaaaaaaaaaaa...a.json (256 characters):"),
        ("..", "param set NOPE 1", "..:1: "),
        ("x/.", "param set NOPE 1", "x/.:1: "),
        ("v.json", '{"a": "\ud800"}', "v.json: not text: a lone surrogate (U+D800) at character 7"),
        ("v.airframe", "param set X \udcff", "v.airframe: not text: a lone surrogate (U+DCFF) at "),
    ],
)
def test_odd_names_and_text_the_page_sends_are_refused_by_name(
    vehicle: Any, filename: str, text: str, error: str
) -> None:
    values, metadata = vehicle
    with pytest.raises(Px4ParamsError) as refused:
        files.review_file(filename, text, values, metadata)
    assert str(refused.value).startswith(error), str(refused.value)
