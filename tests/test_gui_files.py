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
