"""The page's manifest view without a browser: the picker from the driver declarations, the
devices a set of flat values configures (as a ground station sees them) with what stops each
from starting, and the ``@format hex`` tag behind addresses shown in hex."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import px4params
import pytest
from gui_server import load_store, make_store
from px4params.errors import DsdlError
from px4params.gcs.metadata import build_parameters_json
from px4params.gui.manifest import devices, picker, status_location
from px4params.store.flat import flat_values
from px4params.vehicle.boards import load_boards
from px4params.vehicle.drivers import load_drivers


@pytest.fixture(scope="module")
def vehicle(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], dict[str, Any]]:
    """The example airframe's flat values and metadata, as the page gets them."""
    tmp = tmp_path_factory.mktemp("manifest")
    store = load_store(make_store(tmp))
    classic = [c for c in map(store.classic, store.parameters) if c is not None]
    metadata = build_parameters_json(store.schema, specs=store.specs, classic_params=classic)
    return dict(flat_values(store)), metadata


def test_locations_as_px4_status_prints_them() -> None:
    assert status_location("i2c", 1, 0x45) == "I2C bus 1, 0x45"
    assert status_location("i2c", 3, 0x0C) == "I2C bus 3, 0x0C"
    assert status_location("spi", 2, 1) == "SPI bus 2, chip select 1"


def test_the_picker_groups_chips_and_starts_from_the_declarations(vehicle: Any) -> None:
    chosen = picker(vehicle[1], load_drivers())
    groups = list(dict.fromkeys(d["group"] for d in chosen))
    kinds = ["magnetometers", "power monitors", "airspeed", "distance", "barometers", "other"]
    assert groups == kinds
    by = {d["parameter"]: d for d in chosen}
    # drivers.toml: ist8310 default_address 0x0E (iSentek_IST8310::I2C_ADDRESS_DEFAULT)
    assert by["IST8310"]["needs"] == "I2C, address 0x0E (the driver's default)"
    assert by["IST8310"]["start"] == {
        "bus": "i2c",
        "variants": {"i2c": {"bus_id": 1, "address": 14}},
    }
    assert by["LIS3MDL"]["start"]["variants"] == {
        "i2c": {"bus_id": 1, "address": 0x1E},
        "spi": {"bus_id": 1},
    }
    assert by["INA238"]["group"] == "power monitors" and by["MS4525DO"]["group"] == "airspeed"


def test_devices_from_flat_values_with_what_stops_them(vehicle: Any) -> None:
    values, metadata = vehicle
    drivers = load_drivers()
    found = {d["instance"]: d for d in devices(values, metadata, drivers)}
    assert [(d["location"], d["problems"]) for d in found.values()] == [
        ("I2C bus 1, 0x45", []),
        ("I2C bus 2, 0x45", []),
        ("I2C bus 1, 0x0C", []),
    ]
    staged = dict(values, INA238_INST=7, INA238_2A=0, INA238_2B=1, INA238_2C=0x45)
    staged.update(INA238_1B=0)  # bus 0: unset
    found = {d["instance"]: d for d in devices(staged, metadata, drivers)}
    assert found["INA238#1"]["problems"] == ["i2c bus_id is 0 (unset; buses are numbered from 1)"]
    assert found["INA238#2"]["problems"] == ["I2C bus 1 address 0x45 is already INA238#0's"]
    spi = dict(values, INA238_1A=1, INA238_1D=2, INA238_1E=3)  # the I2C leaves are stale
    found = {d["instance"]: d for d in devices(spi, metadata, drivers)}
    assert found["INA238#1"]["location"] == "SPI bus 2, chip select 3"
    assert found["INA238#1"]["problems"] == [
        "bus kind spi is not accepted by ina238 (accepts: i2c)"
    ]


def test_a_compass_the_board_starts_itself(vehicle: Any) -> None:
    values, metadata = vehicle
    staged = dict(values, IST8310_INST=3, IST8310_0A=0, IST8310_0B=1, IST8310_0C=0x0E)
    staged.update(IST8310_0P=2, IST8310_1A=0, IST8310_1B=2, IST8310_1C=0x0E)
    v6c = load_boards().by_name("px4_fmu-v6c")
    found = {d["instance"]: d for d in devices(staged, metadata, load_drivers(), v6c)}
    # boards/px4/fmu-v6c/init/rc.board_sensors: ist8310 -X -b 1 -R 10 start (bus 1 only)
    assert found["IST8310#0"]["problems"] == [
        "the board Pixhawk 6C (FMUv6C) starts this compass itself (ist8310 -X -b 1 -R 10 start, "
        "rotation 10 (Roll 180 deg, Yaw 90 deg)) before the manifest; this instance's rotation "
        "2 (Yaw 90 deg) is not used"
    ]
    assert found["IST8310#1"]["problems"] == []
    assert found["AK09916#0"]["problems"] == []


@pytest.mark.parametrize(
    ("line", "error"),
    [
        (
            "uint7 address\n# @format octal\n",
            "@format expects hex on an integer field, got 'octal'",
        ),
        ("float32 gain\n# @format hex\n", "@format expects hex on an integer field, got 'hex'"),
    ],
)
def test_format_tag_errors_name_the_line(tmp_path: Path, line: str, error: str) -> None:
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Thing.1.0.dsdl").write_text("# A thing\n" + line + "@sealed\n")
    with pytest.raises(DsdlError) as e:
        px4params.load_schema([root], include_dronecan=False, cache_dir=None)
    assert str(e.value).endswith(f"Thing.1.0.dsdl:3: {error}"), str(e.value)


def test_instances_are_named_by_their_number_as_the_store_names_them(vehicle: Any) -> None:
    """``NAME#N`` for instance N, counted from 0 (docs/store.md): the picker names every slot
    (the page shows these names, composing none) and a configured instance is named by its
    bit of the ``_INST`` mask. ``@max_instances 4`` of px.Ina238 (dsdl/px/Ina238.1.1.dsdl)."""
    values, metadata = vehicle
    drivers = load_drivers()
    by = {d["parameter"]: d for d in picker(metadata, drivers)}
    assert by["INA238"]["instances"] == ["INA238#0", "INA238#1", "INA238#2", "INA238#3"]
    assert by["AK09916"]["instances"][0] == "AK09916#0"
    # Bit 2 alone: INA238#2, with the leaves INA238_2x (bus 1, address 0x41).
    staged = dict(values, INA238_INST=0b100, INA238_2A=0, INA238_2B=1, INA238_2C=0x41)
    found = [d for d in devices(staged, metadata, drivers) if d["parameter"] == "INA238"]
    assert [(d["instance"], d["location"]) for d in found] == [("INA238#2", "I2C bus 1, 0x41")]
    # The store, given the same instance, names it the same.
    store = px4params.Store(px4params.load_schema(use_env=False), classic=[])
    assert [d["instance"] for d in found] == [store.add("INA238#2")]
