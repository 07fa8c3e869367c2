"""DroneCAN GetSet over the store (``px4params.links.dronecan_params``): rules that a wrong
product would break without the rest of the suite noticing (issue 40: bugs planted one at a
time stayed green). Each expected answer comes from the rule, not from our code:
``uavcan.protocol.param.Value`` (DroneCAN DSDL, as pydronecan ships it) carries
``boolean_value`` as a ``uint8`` "for alignment reasons": only 0 and 1 are booleans. A GetSet
request whose value is not one is refused, and the response carries the value the node still
holds (GetSet.uavcan: the response is the parameter's state after the request)."""

from __future__ import annotations

import subprocess
from collections import Counter
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from core_calls import count_core_calls
from dronecan_bus import PX4PARAMS, served
from px4params.errors import Px4ParamsError
from px4params.links.dronecan_params import DronecanParams
from px4params.store.classic import BUNDLED_CLASSIC

#: Written for issue 40 (bugs planted one at a time stayed green): the mutation baseline
#: (MUTATION_BASELINE=1 scripts/mutation.sh) runs without them.
pytestmark = pytest.mark.issue40

GETSET = dronecan.uavcan.protocol.param.GetSet
OPCODE = dronecan.uavcan.protocol.param.ExecuteOpcode
NODE = 1
#: An IST8310 magnetometer: its ``internal`` field is a DSDL ``bool`` (dsdl/px/Ist8310.1.0.dsdl)
#: with ``@default false``; DroneCAN's long name of instance 0's is IST8310_0_INTERNAL.
AIRFRAME = "param add IST8310#0\nparam set-default IST8310#0.bus.i2c.bus_id 1\n"
BOOLEAN = "IST8310_0_INTERNAL"


@pytest.fixture
def ist8310_store(tmp_path: Path) -> Path:
    airframe = tmp_path / "ist8310.airframe"
    airframe.write_text(AIRFRAME)
    store = tmp_path / "vehicle.store"
    subprocess.run(
        [*PX4PARAMS, "run", str(airframe), "--store", str(store)],
        check=True,
        capture_output=True,
        timeout=120,
    )
    return store


def _load(path: Path) -> px4params.Store:
    return px4params.Store.load(path, classic=BUNDLED_CLASSIC)


@pytest.mark.parametrize("number", [2, 255])
def test_getset_boolean_outside_0_1_is_refused_and_the_value_unchanged(
    ist8310_store: Path, number: int
) -> None:
    store = _load(ist8310_store)
    params = DronecanParams(store)
    entry = params.entry(BOOLEAN)
    assert entry is not None and entry.value == {"boolean_value": 0}  # @default false
    before = {n: store.encoded(n) for n in store.names()}
    with pytest.raises(Px4ParamsError) as refused:
        params.set(BOOLEAN, {"boolean_value": number})
    assert str(refused.value) == f"{BOOLEAN}: value {number} is not a boolean (0 or 1)"
    assert {n: store.encoded(n) for n in store.names()} == before
    assert store.get("IST8310#0.internal") is False
    # 1 and 0 are booleans: taken.
    params.set(BOOLEAN, {"boolean_value": 1})
    assert store.get("IST8310#0.internal") is True
    params.set(BOOLEAN, {"boolean_value": 0})
    assert store.get("IST8310#0.internal") is False
    # GetSet's bounds are a NumericValue (no boolean variant): integers 0 and 1.
    entry = params.entry(BOOLEAN)
    assert entry is not None
    assert (entry.default, entry.min, entry.max) == (
        {"boolean_value": 0},
        {"integer_value": 0},
        {"integer_value": 1},
    )


def _active(value: Any) -> tuple[str, Any]:
    kind = dronecan.get_active_union_field(value)
    return kind, getattr(value, kind) if kind != "empty" else None


def test_pydronecan_getset_of_boolean_2_answers_the_unchanged_value(ist8310_store: Path) -> None:
    """The same rule end to end: pydronecan (its own SLCAN driver) asks ``dronecan serve``."""
    with served(ist8310_store) as path:
        node = dronecan.make_node(path, node_id=100, bitrate=1_000_000)
        try:

            def call(request: Any) -> Any:
                got: list[Any] = []
                node.request(request, NODE, got.append, timeout=3.0)
                for _ in range(400):  # at most about 4 s
                    if got:
                        break
                    node.spin(0.01)
                assert got and got[0] is not None, f"no response to {type(request).__name__}"
                return got[0].response

            def getset(**value: Any) -> Any:
                request = GETSET.Request(name=BOOLEAN.encode())
                if value:
                    request.value = dronecan.uavcan.protocol.param.Value(**value)
                return call(request)

            assert _active(getset().value) == ("boolean_value", 0)
            assert _active(getset(boolean_value=2).value) == ("boolean_value", 0)
            assert _active(getset().value) == ("boolean_value", 0)
            assert call(OPCODE.Request(opcode=OPCODE.Request().OPCODE_SAVE)).ok
        finally:
            node.close()
    assert _load(ist8310_store).get("IST8310#0.internal") is False
    assert f"refused: {BOOLEAN}: value 2 is not a boolean (0 or 1)" in served.output  # type: ignore[attr-defined]


# -- GetSet entries (issue 40's mutation run: what survived in dronecan_params.py) ---------------

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "two_batteries.airframe"
INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1
#: IEEE 754 single precision's largest finite value, (2 - 2**-23) * 2**127.
FLT_MAX = (2 - 2**-23) * 2.0**127


@pytest.fixture
def example_params(tmp_path: Path) -> tuple[px4params.Store, DronecanParams]:
    store_path = tmp_path / "vehicle.store"
    subprocess.run(
        [*PX4PARAMS, "run", str(EXAMPLE), "--store", str(store_path)],
        check=True,
        capture_output=True,
        timeout=120,
    )
    store = _load(store_path)
    return store, DronecanParams(store)


def _integers(*numbers: int) -> tuple[dict[str, int], ...]:
    return tuple({"integer_value": n} for n in numbers)


def test_getset_entries_of_classic_parameters_and_masks(
    example_params: tuple[px4params.Store, DronecanParams],
) -> None:
    """Bounds and defaults as PX4's parameter metadata gives them (BAT1_CAPACITY: Float,
    default -1 "when unknown", -1..100000 mAh); an Int32 without bounds spans int32, what
    MAVLink and the store can hold; an instance mask of INA238 (@max_instances 4) is 0..15,
    no instance by default."""
    store, params = example_params
    capacity = params.entry("BAT1_CAPACITY")
    assert capacity is not None
    assert (capacity.value, capacity.default, capacity.min, capacity.max) == (
        {"real_value": -1.0},
        {"real_value": -1.0},
        {"real_value": -1.0},
        {"real_value": 100000.0},
    )
    mag = params.entry("CAL_MAG0_ID")
    assert mag is not None
    assert (mag.value, mag.default, mag.min, mag.max) == _integers(0, 0, INT32_MIN, INT32_MAX)
    mask = params.entry("INA238_INST")
    assert mask is not None
    assert (mask.value, mask.default, mask.min, mask.max) == _integers(0b11, 0, 0, 15)
    # Writes say what changed.
    assert params.set("SYS_AUTOSTART", {"integer_value": 4001}) == "SYS_AUTOSTART = 4001"
    assert store.get("SYS_AUTOSTART") == 4001
    assert params.set("INA238_INST", {"integer_value": 0b11}) == "INA238_INST: no change"


def test_getset_entries_of_leaves_keep_their_default_apart(
    example_params: tuple[px4params.Store, DronecanParams],
) -> None:
    _, params = example_params
    params.set("INA238_1_I2C_ADDRESS", {"integer_value": 0x44})
    address = params.entry("INA238_1_I2C_ADDRESS")
    assert address is not None
    assert (address.value, address.default) == _integers(0x44, 0x45)  # the airframe's default
    # On SPI the default (an I2C value) has no such leaf: GetSet's "empty" variant.
    params.set("INA238_1_BUS_TYPE", {"integer_value": 1})
    names = [params.name_at(i) or "" for i in range(len(params))]
    spi = [params.entry(n) for n in names if n.startswith("INA238_1_SPI_")]
    assert len(spi) >= 3  # bus_id, chip_select, mode, ...
    assert all(e is not None and e.default == {"empty": {}} for e in spi)
    # A write without a value is refused by its variant's name.
    with pytest.raises(Px4ParamsError) as refused:
        params.set("INA238_1_SPI_BUS_ID", {})
    assert str(refused.value) == (
        "INA238_1_SPI_BUS_ID: empty refused: the parameter takes integer_value"
    )


def test_getset_bounds_of_float_leaves_are_their_types(tmp_path: Path) -> None:
    """A float32 leaf spans IEEE 754 single precision (its largest finite value is a valid
    bound, sent as real_value), a float16 one +-65504."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Floats.1.0.dsdl").write_text(
        "# Floats\n# @max_instances 1\n\nfloat32 single\n# a\n\nfloat16 half\n# b\n\n@sealed\n"
    )
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("FLOATS#0")
    params = DronecanParams(store)
    single, half = params.entry("FLOATS_0_SINGLE"), params.entry("FLOATS_0_HALF")
    assert single is not None and half is not None
    assert (single.min, single.max) == ({"real_value": -FLT_MAX}, {"real_value": FLT_MAX})
    assert (half.min, half.max) == ({"real_value": -65504.0}, {"real_value": 65504.0})


def test_getset_default_of_an_element_the_default_array_lacks_is_empty(tmp_path: Path) -> None:
    """A dynamic array's default is empty: the elements a value has have no default, which
    GetSet says with its "empty" variant; the length's default is 0, its bounds 0..capacity."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Things.1.0.dsdl").write_text(
        "# Things\n# @max_instances 1\n\nuint8[<=3] items\n# x\n\n@sealed\n"
    )
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("THINGS#0")
    store.set("THINGS#0", {"items": [7, 8]})
    params = DronecanParams(store)
    for name, value in (("THINGS_0_ITEMS_0", 7), ("THINGS_0_ITEMS_1", 8)):
        entry = params.entry(name)
        assert entry is not None
        assert (entry.value, entry.default) == ({"integer_value": value}, {"empty": {}})
        assert (entry.min, entry.max) == _integers(0, 255)  # uint8
    length = params.entry("THINGS_0_ITEMS_LEN")
    assert length is not None
    assert (length.value, length.default, length.min, length.max) == _integers(2, 0, 0, 3)


@pytest.mark.parametrize(
    ("name", "value", "change"),
    [
        # The leaf numbers of px.Ina238 by hand (tests/test_key.py): [4] bus.i2c.address,
        # [6] shunt, a float16 that keeps 0.001 as 0.0010004043579101562 (IEEE half 0x1419).
        ("INA238_1_I2C_ADDRESS", {"integer_value": 0x41}, "(INA238#1[4]) = 65"),
        ("INA238_1_SHUNT", {"real_value": 0.001}, "(INA238#1[6]) = 0.0010004043579101562"),
    ],
)
def test_a_getset_write_finds_its_leaf_once(
    monkeypatch: pytest.MonkeyPatch, name: str, value: dict[str, Any], change: str
) -> None:
    """The list holds each leaf resolved (its instance and path): a write is one core call
    that finds and writes the leaf, and one that reads back what is stored (what the response
    and the change line carry); the value is not read first to learn its variant."""
    store = px4params.Store(px4params.load_schema(use_env=False), classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    params = DronecanParams(store)
    assert params.index_of(name) is not None  # the list is made before counting
    counted = count_core_calls(store, monkeypatch)
    assert params.set(name, value) == f"{name} {change}"
    assert counted.calls == Counter(set_leaf=1, get_leaf_value=1)


def test_a_getset_write_of_a_union_tag_reads_the_value_once_to_check_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A tag brings another variant's leaves in: the default's tag is read (a switch to its
    variant would take the default's values there), the whole value once (their @min/@max
    checked), the tag found and written once, and read back."""
    store = px4params.Store(px4params.load_schema(use_env=False), classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    params = DronecanParams(store)
    assert params.index_of("INA238_1_BUS_TYPE") is not None
    counted = count_core_calls(store, monkeypatch)
    assert params.set("INA238_1_BUS_TYPE", {"integer_value": 1}).endswith("(INA238#1[1]) = 1")
    assert counted.calls == Counter(get=1, set_leaf=1, get_leaf_value=2)
    assert "spi" in store.get("INA238#1")["bus"]
