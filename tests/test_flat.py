"""Destructured (flat) parameters: letters over the type, live leaves, round trips, refusals."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import px4params
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from px4params.errors import InstanceError, LeafError, Px4ParamsError
from px4params.store import flat
from px4params.store.classic import ClassicParam
from strategies import budget, value_strategy

BUNDLED_PX = [key for key in px4params.load_schema(use_env=False) if key.startswith("px.")]

# A type with every leaf kind the bundled ones lack: static and dynamic arrays (of structs and
# unions), bool, int32, uint32, float32, a top-level union.
EXTRA_DSDL = {
    "Inner.1.0.dsdl": "uint4 p_version\nbool flag\nint7 y\n@sealed\n",
    "Choice.1.0.dsdl": "@union\nuint8 a\nfloat32 b\nint3[2] c\n@sealed\n",
    "Arrays.1.0.dsdl": (
        "# Arrays\n# @max_instances 2\n\n"
        "uint4 p_version\nInner.1.0[2] pair\nuint8[<=3] dyn\nInner.1.0[<=2] items\n"
        "Choice.1.0[<=2] choices\nChoice.1.0 choice\nuint32 big\nint32 neg\nfloat32 f\n@sealed\n"
    ),
}


def dsdl_root(tmp: Path, files: dict[str, str], namespace: str = "tst") -> Path:
    root = tmp / namespace
    root.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (root / name).write_text(text)
    return root


@pytest.fixture(scope="module")
def extra_schema(tmp_path_factory: pytest.TempPathFactory) -> px4params.Schema:
    tmp = tmp_path_factory.mktemp("flat")
    root = dsdl_root(tmp, EXTRA_DSDL)
    return px4params.load_schema([root], use_env=False, cache_dir=tmp / "cache")


@pytest.fixture
def store(schema: px4params.Schema) -> px4params.Store:
    return px4params.Store(schema, classic=[ClassicParam("SYS_AUTOSTART", "Int32", 0)])


def test_letters() -> None:
    assert [flat.letters(n) for n in (0, 1, 25, 26, 27, 51, 52, 701, 702)] == [
        "A", "B", "Z", "AA", "AB", "AZ", "BA", "ZZ", "AAA",
    ]  # fmt: skip
    with pytest.raises(ValueError):
        flat.letters(-1)


def test_talk_names(store: px4params.Store) -> None:
    """SPEC: INA238#1.bus_type -> INA238_1A, .i2c.bus_id -> INA238_1B, .i2c.address -> 1C."""
    store.add("INA238#1")
    table = {row.name: row for row in flat.flat_table(store)}
    assert list(table) == ["INA238_1A", "INA238_1B", "INA238_1C", "INA238_1P", "INA238_1Q"]
    assert [table[n].path for n in table] == [
        "bus._tag", "bus.i2c.bus_id", "bus.i2c.address", "current", "shunt",
    ]  # fmt: skip
    assert [str(table[n].leaf) for n in table] == [f"INA238#1[{k}]" for k in (1, 3, 4, 5, 6)]
    assert flat.resolve_flat(store, "INA238_1C") == "INA238#1[4]"
    with pytest.raises(InstanceError, match=r"did you mean INA238_1C\?\)$"):  # exact, as PX4's
        flat.resolve_flat(store, "ina238_1c")
    assert table["INA238_1C"].mav_type == "int32"
    assert table["INA238_1Q"].mav_type == "float32"
    assert table["INA238_1Q"].value == store.get("INA238#1.shunt")  # float16 exactly


def test_letters_do_not_move_when_the_variant_changes(store: px4params.Store) -> None:
    store.add("INA238#1")
    flat.set_flat(store, "INA238_1C", 0x46)
    assert store.get("INA238#1.bus.i2c.address") == 0x46
    flat.set_flat(store, "INA238_1A", 1)  # select SPI: its leaves appear, I2C's go
    names = [row.name for row in flat.flat_table(store)]
    assert names == [f"INA238_1{x}" for x in "ADEFGPQ"]
    assert flat.resolve_flat(store, "INA238_1E") == "INA238#1[4]"  # spi.chip_select is [4] now
    assert flat.resolve_flat(store, "INA238_1P") == "INA238#1[7]"  # current: [k] moved, P not
    with pytest.raises(LeafError, match=r"^INA238_1C \(INA238#1.bus.i2c.address\) is not live: "
                       r"bus._tag selects variant 1, not 0 \(set INA238_1A to 0\)$"):  # fmt: skip
        flat.resolve_flat(store, "INA238_1C")
    flat.set_flat(store, "INA238_1A", 0)
    names = [row.name for row in flat.flat_table(store)]
    assert names == [f"INA238_1{x}" for x in "ABCPQ"]


def test_every_bundled_letter_map_is_listed(schema: px4params.Schema) -> None:
    lay = flat.layout(schema["px.Ina238"])
    assert "".join(s.letter for s in lay) == "ABCDEFGHIJKLMNOPQ"
    assert lay.slot("A").role == "union_tag" and (lay.slot("A").min, lay.slot("A").max) == (0, 5)
    assert lay.slot("D").requires == (("bus._tag", "==", 1),)
    assert lay.slot_for_path("shunt").type == "float16"
    assert lay.slot("Z") is None and len(lay) == 17


def test_values_as_carried(extra_schema: px4params.Schema) -> None:
    store = px4params.Store(extra_schema)
    store.add("ARRAYS#0")
    store.set("ARRAYS#0.big", 0xFFFFFFFF)
    store.set("ARRAYS#0.pair[1].flag", True)
    rows = {row.path: row for row in flat.flat_table(store)}
    assert rows["big"].value == -1  # uint32 travels as its bit pattern
    assert rows["pair[1].flag"].value == 1 and rows["pair[1].flag"].type == "bool"
    flat.set_flat(store, rows["big"].name, -2)
    assert store.get("ARRAYS#0.big") == 0xFFFFFFFE
    flat.set_flat(store, rows["big"].name, 7.0)  # an integral float is an integer
    assert store.get("ARRAYS#0.big") == 7
    # dynamic array: the length is a leaf, elements are live below it
    length = rows["dyn._len"].name
    assert "dyn[0]" not in rows
    flat.set_flat(store, length, 2)
    rows = {row.path: row for row in flat.flat_table(store)}
    assert "dyn[1]" in rows and "dyn[2]" not in rows
    hidden = flat.flat_map(store).layout_of("ARRAYS").slot_for_path("dyn[2]")
    name = f"ARRAYS_0{hidden.letter}"
    with pytest.raises(LeafError, match=rf"^{name} \(ARRAYS#0.dyn\[2\]\) is not live: "
                       rf"dyn._len is 2 \(set {length} above 2\)$"):  # fmt: skip
        flat.get_flat(store, name)


def test_refused_flat_values(store: px4params.Store) -> None:
    store.add("IST8310#0")
    rows = {row.path: row.name for row in flat.flat_table(store)}
    internal = rows["internal"]
    with pytest.raises(flat.FlatError, match=rf"^{internal} \(IST8310#0.internal\): value 2 is "
                       r"not a boolean \(expected 0 or 1\)$"):  # fmt: skip
        flat.set_flat(store, internal, 2)
    with pytest.raises(flat.FlatError, match=r"expected an integer, got 1.5$"):
        flat.set_flat(store, rows["bus.i2c.address"], 1.5)
    store.add("INA238#0")
    with pytest.raises(flat.FlatError, match=r"^INA238_0Q \(INA238#0.shunt\): expected a number, "
                       r"got 'x'$"):  # fmt: skip
        flat.set_flat(store, "INA238_0Q", "x")
    with pytest.raises(px4params.EncodeError, match=r"value 200 is out of range"):
        flat.set_flat(store, rows["bus.i2c.address"], 200)
    assert store.get("IST8310#0.bus.i2c.address") == 0x0E  # refused: unchanged
    with pytest.raises(InstanceError, match=r"^'SYS_AUTOSTART' is not a destructured parameter"):
        flat.resolve_flat(store, "SYS_AUTOSTART")
    with pytest.raises(InstanceError, match=r"^IST8310_1B belongs to IST8310#1, which does not "
                       r"exist \(add it first: param add IST8310#1\)$"):  # fmt: skip
        flat.resolve_flat(store, "IST8310_1B")


def test_default_writes(store: px4params.Store) -> None:
    store.add("INA238#0")
    flat.set_flat(store, "INA238_0P", 200, default=True)
    assert store.get("INA238#0.current", default=True) == 200
    assert not store.changed("INA238#0")


# -- round trips ------------------------------------------------------------------------------


def _round_trip(data_type: px4params.DataType, value: dict) -> None:
    data = data_type.encode(value, tao=False)
    letters = flat.to_flat(data_type, data)
    back = flat.from_flat(data_type, letters)
    assert data_type.encode(back, tao=False) == data
    # every leaf but p_version is offered, and under the letter of its path
    lay = flat.layout(data_type)
    paths = [leaf.path for leaf in data_type.leaves(data, tao=False)]
    offered = [p for p in paths if not p.endswith("p_version")]
    assert [lay.slot(x).path for x in letters] == offered


@pytest.mark.parametrize("key", BUNDLED_PX)
def test_round_trip_bundled(schema: px4params.Schema, key: str) -> None:
    """structured -> flat -> structured is identical for random values of every bundled type."""
    data_type = schema[key]

    @settings(max_examples=budget(60), deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(value_strategy(schema.model["types"], key))
    def check(value: dict) -> None:
        _round_trip(data_type, value)

    check()


def test_round_trip_arrays_and_unions(extra_schema: px4params.Schema) -> None:
    data_type = extra_schema["tst.Arrays"]

    @settings(max_examples=budget(150), deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(value_strategy(extra_schema.model["types"], "tst.Arrays.1.0"))
    def check(value: dict) -> None:
        _round_trip(data_type, value)

    check()
    top = extra_schema["tst.Choice"]
    assert flat.to_flat(top, {"c": [1, -2]}) == {"A": 2, "D": 1, "E": -2}
    assert flat.from_flat(top, {"A": 1, "C": 2.5}) == {"b": 2.5}


@settings(max_examples=budget(40), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_round_trip_through_the_store(schema: px4params.Schema, data: st.DataObject) -> None:
    """Flat values written one by one in letter order rebuild the instance exactly."""
    source = px4params.Store(schema)
    target = px4params.Store(schema)
    for spec in source.specs:
        instance = f"{spec.name}#1"
        key = spec.data_type.key
        source.add(instance)
        target.add(instance)
        source.set(instance, data.draw(value_strategy(schema.model["types"], key, storable=True)))
    for row in flat.flat_table(source):
        flat.set_flat(target, row.name, row.value)
    for spec in source.specs:
        assert target.encoded(f"{spec.name}#1") == source.encoded(f"{spec.name}#1")


def test_from_flat_refusals(schema: px4params.Schema) -> None:
    ina = schema["px.Ina238"]
    good = flat.to_flat(ina, {"bus": {"i2c": {"bus_id": 1, "address": 69}}, "current": 2,
                              "shunt": 0.5})  # fmt: skip
    assert good == {"A": 0, "B": 1, "C": 69, "P": 2, "Q": 0.5}
    with pytest.raises(flat.FlatError, match=r"^px.Ina238.1.1: letter C \(bus.i2c.address\) "
                       r"is missing$"):  # fmt: skip
        flat.from_flat(ina, {k: v for k, v in good.items() if k != "C"})
    with pytest.raises(flat.FlatError, match=r"^px.Ina238.1.1: letters not live in this value: "
                       r"D \(bus.spi.bus_id\), ZZ \(no such letter\)$"):  # fmt: skip
        flat.from_flat(ina, {**good, "D": 1, "ZZ": 0})
    with pytest.raises(flat.FlatError, match=r"^px.Ina238.1.1: bus._tag: no variant 7 "
                       r"\(expected 0 to 5\)$"):  # fmt: skip
        flat.from_flat(ina, {**good, "A": 7})
    with pytest.raises(flat.FlatError, match=r"^px.Ina238.1.1: letter P \(current\): expected "
                       r"an integer, got 2.5$"):  # fmt: skip
        flat.from_flat(ina, {**good, "P": 2.5})


def test_from_flat_refuses_a_long_array(extra_schema: px4params.Schema) -> None:
    arrays = extra_schema["tst.Arrays"]
    letters = flat.to_flat(arrays, {"pair": [{"flag": False, "y": 0}] * 2, "dyn": [], "items": [],
                                    "choices": [], "choice": {"a": 1}, "big": 0, "neg": 0,
                                    "f": 0.0})  # fmt: skip
    length = flat.layout(arrays).slot_for_path("dyn._len").letter
    with pytest.raises(flat.FlatError, match=r"dyn._len: length 4 is out of range \(expected 0 "
                       r"to 3\)$"):  # fmt: skip
        flat.from_flat(arrays, {**letters, length: 4})


# -- refused at load --------------------------------------------------------------------------


def _store_with(tmp_path: Path, files: dict[str, str], **kwargs: object) -> px4params.Store:
    root = dsdl_root(tmp_path, files, "bad")
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    return px4params.Store(schema, **kwargs)  # type: ignore[arg-type]


def test_wide_leaf_refused(tmp_path: Path) -> None:
    # Refused when the store is built (the store checks its flat names once, at load).
    with pytest.raises(flat.FlatError, match=r"^bad.Wide.1.0: leaf x is float64: destructured "
                       r"parameters carry at most 32 bits \(MAVLink\), so this type cannot be "
                       r"a parameter$"):  # fmt: skip
        _store_with(tmp_path, {"Wide.1.0.dsdl": "# W\n# @max_instances 2\n\nuint4 p_version\n"
                               "float64 x\n@sealed\n"})  # fmt: skip


def test_long_name_refused(tmp_path: Path) -> None:
    files = {"Long.1.0.dsdl": "# L\n# @param LONGNAME_PARAM\n# @max_instances 12\n\n"
             "uint4 p_version\nuint8 x\n@sealed\n"}  # fmt: skip
    with pytest.raises(flat.FlatError, match=r"^LONGNAME_PARAM: destructured name "
                       r"LONGNAME_PARAM_0A has 17 characters \(at most 16\): bad.Long.1.0 has 1 "
                       r"flat leaves; shorten the parameter name or the type$"):  # fmt: skip
        flat.flat_map(_store_with(tmp_path, files))


def test_clash_with_classic_refused(tmp_path: Path) -> None:
    files = {"Foo.1.0.dsdl": "# F\n# @max_instances 2\n\nuint4 p_version\nuint8 x\n@sealed\n"}
    with pytest.raises(flat.FlatError, match=r"^FOO: destructured name FOO_1A \(FOO#1.x\) is "
                       r"the name of a classic parameter$"):  # fmt: skip
        _store_with(tmp_path, files, classic=[ClassicParam("FOO_1A", "Int32", 0)])


def test_clash_with_structured_refused(tmp_path: Path) -> None:
    files = {
        "Foo.1.0.dsdl": "# F\n# @max_instances 2\n\nuint4 p_version\nuint8 x\n@sealed\n",
        "Bar.1.0.dsdl": "# B\n# @param FOO_0A\n\nuint4 p_version\nuint8 y\n@sealed\n",
    }
    with pytest.raises(flat.FlatError, match=r"^FOO: destructured name FOO_0A \(FOO#0.x\) is "
                       r"the name of a structured parameter$"):  # fmt: skip
        flat.flat_map(_store_with(tmp_path, files))


def test_shared_parameter_names(tmp_path: Path) -> None:
    files = {"Foo.1.0.dsdl": "# F\n# @param FOO_SHARED\n\nuint4 p_version\nbool on\nint8 t\n"
             "@sealed\n"}  # fmt: skip
    store = _store_with(tmp_path, files)
    rows = flat.flat_table(store)  # a shared parameter always exists, without a number
    assert [r.name for r in rows] == ["FOO_SHARED_A", "FOO_SHARED_B"]
    assert flat.resolve_flat(store, "FOO_SHARED_B") == "FOO_SHARED[2]"
    flat.set_flat(store, "FOO_SHARED_A", 1)
    assert store.get("FOO_SHARED.on") is True


def test_errors_are_px4params_errors() -> None:
    assert issubclass(flat.FlatError, Px4ParamsError)


def test_the_flat_check_is_remembered_per_schema_and_classic_names(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PX4PARAMS_CACHE_DIR", str(tmp_path / "verdicts"))
    files = {"Foo.1.0.dsdl": "# F\n# @max_instances 2\n\nuint4 p_version\nuint8 x\n@sealed\n"}
    root = dsdl_root(tmp_path, files, "bad")
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    first = px4params.Store(schema, classic=[])
    assert first._destructured is not None  # checked now, the verdict written
    again = px4params.Store(schema, classic=[])
    assert again._destructured is None  # remembered: the names are worked out on first use
    assert "FOO_1A" in again.destructured
    # Other classic names are another check: a clash is still refused at load.
    with pytest.raises(flat.FlatError, match=r"^FOO: destructured name FOO_1A \(FOO#1.x\) is "
                       r"the name of a classic parameter$"):  # fmt: skip
        px4params.Store(schema, classic=[ClassicParam("FOO_1A", "Int32", 0)])
    # A schema built by hand (no model cache key) is checked every time.
    hand = px4params.Schema({"types": dict(schema.model["types"].items())})
    assert px4params.Store(hand, classic=[])._destructured is not None


# -- issue 40: the rules of the module doc, one by one ------------------------------------------


@pytest.mark.issue40
def test_letter_numbers_are_bijective_base_26() -> None:
    assert [flat.letter_number(t) for t in ("A", "Z", "AA", "AB", "ZZ", "AAA")] == [
        0, 25, 26, 27, 701, 702,
    ]  # fmt: skip
    for text in ("", "a", "A1", "_", "[", "@"):
        assert flat.letter_number(text) is None, text
    # the first letter number written with 1, 2 and 3 letters: A, AA, AAA
    assert [flat._first_with_letters(n) for n in (0, 1, 2, 3)] == [0, 0, 26, 702]
    with pytest.raises(ValueError, match=r"^letter number -1 is negative$"):
        flat.letters(-1)


@pytest.mark.issue40
def test_the_ina238_letters_and_their_ranges(store: px4params.Store) -> None:
    """The module doc's px.Ina238: A bus tag (6 variants: uint3, 0..5), B/C i2c, D..G spi, H/I
    serial, J/K dronecan, L sim, M..O mavlink, P current, Q shunt (float16: +-65504)."""
    slots = list(flat.flat_map(store).layout_of("INA238"))
    assert "".join(s.letter for s in slots) == "ABCDEFGHIJKLMNOPQ"
    tag, bus_id, address = slots[:3]
    assert tag == flat.FlatSlot("A", "bus._tag", "uint3", "int32", "union_tag", 0, 5, ())
    assert bus_id.requires == (("bus._tag", "==", 0),)
    assert (address.path, address.type, address.min, address.max) == (
        "bus.i2c.address", "uint7", 0, 127,
    )  # fmt: skip
    assert slots[3].requires == (("bus._tag", "==", 1),)
    assert [s.requires[0][2] for s in slots[1:15]] == [0, 0, 1, 1, 1, 1, 2, 2, 3, 3, 4, 5, 5, 5]
    assert (slots[15].path, slots[15].type, slots[15].max, slots[15].requires) == (
        "current", "uint10", 1023, (),
    )  # fmt: skip
    shunt = slots[16]
    assert (shunt.type, shunt.mav_type, shunt.min, shunt.max) == (
        "float16", "float32", -65504.0, 65504.0,
    )  # fmt: skip


@pytest.mark.issue40
def test_leaf_ranges_and_length_slots(extra_schema: px4params.Schema) -> None:
    """uintN 0..2^N-1, intN -2^(N-1)..2^(N-1)-1, float32 +-FLT_MAX, bool 0..1; a dynamic
    array's length ``uintB`` (B bits for its maximum) with one slot per element up to it."""
    lay = flat.layout(extra_schema["tst.Arrays"])
    by_path = {s.path: s for s in lay}
    assert (by_path["big"].type, by_path["big"].min, by_path["big"].max) == ("uint32", 0, 2**32 - 1)
    assert (by_path["neg"].type, by_path["neg"].min, by_path["neg"].max) == (
        "int32", -(2**31), 2**31 - 1,
    )  # fmt: skip
    assert (by_path["pair[0].y"].min, by_path["pair[0].y"].max) == (-64, 63)
    f32 = by_path["f"]
    assert (f32.mav_type, f32.min, f32.max) == (
        "float32",
        -3.4028234663852886e38,
        3.4028234663852886e38,
    )
    flag = by_path["pair[1].flag"]
    assert (flag.type, flag.mav_type, flag.min, flag.max) == ("bool", "int32", 0, 1)
    dyn = by_path["dyn._len"]
    assert (dyn.type, dyn.role, dyn.min, dyn.max) == ("uint2", "length", 0, 3)
    assert by_path["dyn[2]"].requires == (("dyn._len", ">", 2),)
    choice = by_path["choice._tag"]
    assert (choice.type, choice.max) == ("uint2", 2)  # 3 variants: 2 bits
    assert by_path["choices[1].c[1]"].requires == (
        ("choices._len", ">", 1), ("choices[1]._tag", "==", 2),
    )  # fmt: skip
    assert "p_version" not in " ".join(by_path)
    assert flat.slot_count(extra_schema["tst.Arrays"]) == len(lay)


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("slot_type", "mav_type", "number", "value"),
    [
        ("uint32", "int32", -1, 2**32 - 1),  # bit pattern
        ("uint32", "int32", -(2**31), 2**31),
        ("uint32", "int32", 2**31 - 1, 2**31 - 1),
        ("int32", "int32", -1, -1),  # only uint32 travels as a bit pattern
        ("uint8", "int32", 7.0, 7),
        ("bool", "int32", 1, True),
        ("bool", "int32", 0, False),
        ("float32", "float32", 2, 2.0),
    ],
)
def test_numbers_as_carried_and_back(
    slot_type: str, mav_type: str, number: object, value: object
) -> None:
    slot = flat.FlatSlot("A", "x", slot_type, mav_type, "value", 0, 0)
    got = slot.from_flat(number)
    assert got == value and type(got) is type(value)
    back = slot.to_flat(got)
    assert back == number and type(back) is (float if mav_type == "float32" else int)


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("slot_type", "mav_type", "number", "message"),
    [
        ("float32", "float32", True, "expected a number, got True"),
        ("float32", "float32", None, "expected a number, got None"),
        ("uint8", "int32", True, "expected an integer, got True"),
        ("uint8", "int32", 2.5, "expected an integer, got 2.5"),
        ("uint8", "int32", "1", "expected an integer, got '1'"),
        ("bool", "int32", 2, "value 2 is not a boolean (expected 0 or 1)"),
        ("bool", "int32", -1, "value -1 is not a boolean (expected 0 or 1)"),
    ],
)
def test_numbers_refused(slot_type: str, mav_type: str, number: object, message: str) -> None:
    slot = flat.FlatSlot("A", "x", slot_type, mav_type, "value", 0, 0)
    with pytest.raises(flat.FlatError) as e:
        slot.from_flat(number)
    assert str(e.value) == message


@pytest.mark.issue40
def test_the_instance_mask_adds_and_removes_instances(store: px4params.Store) -> None:
    """Bit N of INA238_INST is INA238#N: writing it adds and removes instances (QGC's bitmask)."""
    fmap = flat.flat_map(store)
    assert flat.mask_name(fmap.mask_spec("INA238_INST")) == "INA238_INST"
    assert fmap.mask_spec("INA238_0C") is None and fmap.mask_spec("ina238_inst") is None
    assert flat.write_flat(store, "INA238_INST", 0b101) == (
        "INA238_INST: added INA238#0, added INA238#2"
    )
    assert [str(k) for k in store.instance_keys("INA238")] == ["INA238#0", "INA238#2"]
    assert flat.write_flat(store, "INA238_INST", 5.0) == "INA238_INST: no change"
    assert flat.write_flat(store, "INA238_INST", 0b1010) == (
        "INA238_INST: added INA238#1, added INA238#3, removed INA238#0, removed INA238#2"
    )
    assert dict((n, v) for n, _, v in fmap.masks())["INA238_INST"] == 0b1010
    values = flat.flat_values(store)
    assert values["INA238_INST"] == 0b1010 and values["SYS_AUTOSTART"] == 0
    assert values["INA238_1C"] == 0x45 and "INA238_0C" not in values
    assert flat.write_flat(store, "INA238_INST", 0) == (
        "INA238_INST: removed INA238#1, removed INA238#3"
    )


@pytest.mark.issue40
@pytest.mark.parametrize("number", [16, -1, True, 1.5, "3", None])
def test_a_mask_outside_the_instances_is_refused(store: px4params.Store, number: object) -> None:
    store.add("INA238#1")
    with pytest.raises(flat.FlatError) as e:
        flat.write_flat(store, "INA238_INST", number)
    assert str(e.value) == (
        f"INA238_INST: value {number!r} is not a mask of INA238's 4 instances (expected 0 to 15)"
    )
    assert [str(k) for k in store.instance_keys("INA238")] == ["INA238#1"]


@pytest.mark.issue40
def test_write_flat_names_what_changed(store: px4params.Store) -> None:
    store.add("INA238#0")
    assert flat.write_flat(store, "INA238_0C", 70) == "INA238_0C = 70"
    assert flat.write_flat(store, "SYS_AUTOSTART", 4001) == "SYS_AUTOSTART = 4001"
    with pytest.raises(InstanceError, match=r"^unknown parameter 'NOPE'$"):
        flat.write_flat(store, "NOPE", 1)
    with pytest.raises(InstanceError, match=r"^'INA238_0C' is not an instance mask$"):
        flat.flat_map(store).set_mask("INA238_0C", 1)


@pytest.mark.issue40
def test_flat_names_are_exact_with_a_hint(store: px4params.Store) -> None:
    fmap = flat.flat_map(store)
    assert fmap.lookup("INA238_0C") is not None and "INA238_3Q" in fmap
    for name in ("INA238_4C", "INA238_00C", "INA238_0R", "INA238_C", "INA238_0", 5):
        assert name not in fmap, name
    with pytest.raises(InstanceError) as e:
        fmap.owner("ina238_0c")
    assert str(e.value) == (
        "'ina238_0c' is not a destructured parameter name (did you mean INA238_0C?)"
    )
    with pytest.raises(InstanceError) as e:
        fmap.owner("NOPE_0C")
    assert str(e.value) == "'NOPE_0C' is not a destructured parameter name"


@pytest.mark.issue40
def test_a_leaf_of_another_variant_is_not_live_and_says_which(store: px4params.Store) -> None:
    store.add("INA238#0")
    with pytest.raises(LeafError) as e:
        flat.get_flat(store, "INA238_0D")
    assert str(e.value) == (
        "INA238_0D (INA238#0.bus.spi.bus_id) is not live: bus._tag selects variant 0, not 1 "
        "(set INA238_0A to 1)"
    )


@pytest.mark.issue40
def test_a_flat_row_as_a_dict(store: px4params.Store) -> None:
    store.add("INA238#0")
    row = flat.flat_map(store).find("INA238_0Q")
    assert (str(row.leaf), str(row.target)) == ("INA238#0[6]", "INA238#0.shunt")
    assert row.as_dict() == {
        "name": "INA238_0Q",
        "leaf": "INA238#0[6]",
        "path": "INA238#0.shunt",
        "type": "float16",
        "mav_type": "float32",
        "role": "value",
        "value": row.value,
    }
    # JSON has no NaN or infinities: they are written as words
    words = [row._replace(value=v).as_dict()["value"] for v in (math.nan, math.inf, -math.inf)]
    assert words == ["nan", "inf", "-inf"]
    assert flat.resolve_flat(store, "INA238_0C") == "INA238#0[4]"


@pytest.mark.issue40
def test_an_instance_mask_is_one_int32_of_31_instances(tmp_path: Path) -> None:
    """Bit N of the mask is instance N, in an int32 whose sign bit is no instance: a parameter
    with 31 instance slots has a mask, one with 32 has none."""
    files = {
        f"{name.capitalize()}.1.0.dsdl": f"# {name}\n# @max_instances {slots}\n\nuint8 x\n@sealed\n"
        for name, slots in (("wide", 31), ("wider", 32))
    }
    root = dsdl_root(tmp_path, files)
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    fmap = flat.flat_map(px4params.Store(schema))
    assert fmap.mask_spec("WIDE_INST") is not None
    assert fmap.mask_spec("WIDER_INST") is None
    assert "WIDER_INST" not in {name for name, _, _ in fmap.masks()}


@pytest.mark.issue40
def test_a_uint32_takes_the_int32_range_as_its_bits_and_nothing_beyond(
    extra_schema: px4params.Schema,
) -> None:
    # MAVLink's int32 carries -2**31..2**31-1, which are a uint32's 32 bits; a number below
    # -2**31 is no int32, so no bit pattern: the leaf's own range (0..2**32-1) refuses it.
    store = px4params.Store(extra_schema)
    store.add("ARRAYS#0")
    name = {row.path: row.name for row in flat.flat_table(store)}["big"]
    flat.set_flat(store, name, -(2**31))
    assert store.get("ARRAYS#0.big") == 2**31
    for number in (-(2**31) - 1, -(2**32)):
        with pytest.raises(px4params.EncodeError, match=f"value {number} is out of range"):
            flat.set_flat(store, name, number)
        assert store.get("ARRAYS#0.big") == 2**31


@pytest.mark.issue40
def test_a_types_letters_and_their_count_are_worked_out_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # layout's and slot_count's rule: worked out once per type and kept (a store asks for them
    # at every flat name it reads)
    root = dsdl_root(tmp_path, EXTRA_DSDL)
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    data_type = schema["tst.Arrays"]  # a schema of its own: nothing worked out yet
    walks: list[str] = []
    count = flat._count

    def counting(dt: Any, spec: Any, path: str) -> int:
        if not path:
            walks.append(dt.key)  # a walk of the whole type
        return count(dt, spec, path)

    monkeypatch.setattr(flat, "_count", counting)
    first = flat.slot_count(data_type)
    assert flat.slot_count(data_type) == first == len(flat.layout(data_type))
    assert walks == [data_type.key]
    assert flat.layout(data_type) is flat.layout(data_type)


@pytest.mark.issue40
@pytest.mark.parametrize(("field", "path"), [("uint64[2] x", "x[0]"), ("int40[<=3] x", "x[0]")])
def test_a_wide_leaf_in_an_array_is_named_by_its_element(
    tmp_path: Path, field: str, path: str
) -> None:
    text = f"# W\n# @max_instances 2\n\nuint4 p_version\n{field}\n@sealed\n"
    kind = field.split("[")[0]
    with pytest.raises(flat.FlatError, match=rf"^bad.Wide.1.0: leaf {re.escape(path)} is {kind}:"):
        _store_with(tmp_path, {"Wide.1.0.dsdl": text})


@pytest.mark.issue40
def test_padding_gets_no_letter(tmp_path: Path) -> None:
    # the module doc: p_version fields and padding get none
    text = "# P\n# @max_instances 1\n\nuint4 p_version\nuint8 a\nvoid4\nuint4 b\n@sealed\n"
    store = _store_with(tmp_path, {"Pad.1.0.dsdl": text})
    data_type = store.data_type("PAD")
    assert [s.path for s in flat.layout(data_type)] == ["a", "b"]
    assert flat.slot_count(data_type) == 2


@pytest.mark.issue40
def test_the_tag_of_a_two_variant_union_is_one_bit(tmp_path: Path) -> None:
    # DroneCAN's union tag is ceil(log2(variants)) bits (dronecan/dronecan_dsdlc's
    # union_msg_tag_bitlen_from_num_fields): 1 for 2 variants, 2 for 3 and 4
    files = {
        "Two.1.0.dsdl": "@union\nuint8 a\nfloat16 b\n@sealed\n",
        "Three.1.0.dsdl": "@union\nuint8 a\nfloat16 b\nbool c\n@sealed\n",
        "Holder.1.0.dsdl": "# H\n# @max_instances 1\n\nuint4 p_version\nTwo.1.0 two\n"
        "Three.1.0 three\n@sealed\n",
    }
    schema = px4params.load_schema([dsdl_root(tmp_path, files)], use_env=False,
                                   cache_dir=tmp_path / "cache")  # fmt: skip
    tags = {s.path: s for s in flat.layout(schema["tst.Holder.1.0"]) if s.role == "union_tag"}
    assert (tags["two._tag"].type, tags["two._tag"].min, tags["two._tag"].max) == ("uint1", 0, 1)
    assert (tags["three._tag"].type, tags["three._tag"].max) == ("uint2", 2)


@pytest.mark.issue40
def test_a_signed_p_version_gets_no_letter_either(tmp_path: Path) -> None:
    # the module doc: p_version fields get no letter; a type read from its DSDL alone (as the
    # ground-station metadata reads it) may declare one signed
    files = {"Signed.1.0.dsdl": "# S\n# @max_instances 1\n\nint4 p_version\nuint8 a\n@sealed\n"}
    schema = px4params.load_schema([dsdl_root(tmp_path, files)], use_env=False,
                                   cache_dir=tmp_path / "cache")  # fmt: skip
    assert [(s.letter, s.path) for s in flat.layout(schema["tst.Signed.1.0"])] == [("A", "a")]
    assert flat.slot_count(schema["tst.Signed.1.0"]) == 1


@pytest.mark.issue40
def test_a_wide_leaf_is_refused_when_the_letters_are_listed_first(tmp_path: Path) -> None:
    # the letters listed before they are counted (a ground station's metadata reads the
    # layout of a type straight from its DSDL): the same refusal, naming the leaf
    files = {"Wide.1.0.dsdl": "# W\n# @max_instances 2\n\nuint4 p_version\nuint8 a\n"
             "int33[2] x\n@sealed\n"}  # fmt: skip
    schema = px4params.load_schema([dsdl_root(tmp_path, files)], use_env=False,
                                   cache_dir=tmp_path / "cache")  # fmt: skip
    with pytest.raises(flat.FlatError) as e:
        flat.layout(schema["tst.Wide.1.0"])
    assert str(e.value) == (
        "tst.Wide.1.0: leaf x[0] is int33: destructured parameters carry at most 32 bits "
        "(MAVLink), so this type cannot be a parameter"
    )


@pytest.mark.issue40
def test_an_instance_mask_longer_than_16_characters_is_refused(tmp_path: Path) -> None:
    # PX4's names have at most 16 characters: ABCDEFGHIJKLM_0A fits, ABCDEFGHIJKLM_INST not
    files = {"Long.1.0.dsdl": "# L\n# @param ABCDEFGHIJKLM\n# @max_instances 2\n\n"
             "uint4 p_version\nuint8 x\n@sealed\n"}  # fmt: skip
    with pytest.raises(flat.FlatError) as e:
        flat.flat_map(_store_with(tmp_path / "long", files))
    assert str(e.value) == (
        "ABCDEFGHIJKLM: instance mask ABCDEFGHIJKLM_INST is longer than 16 characters or the "
        "name of another parameter"
    )
    files = {"Fits.1.0.dsdl": "# L\n# @param ABCDEFGHIJK\n# @max_instances 2\n\n"
             "uint4 p_version\nuint8 x\n@sealed\n"}  # fmt: skip
    masks = flat.flat_map(_store_with(tmp_path / "fits", files)).masks()
    assert "ABCDEFGHIJK_INST" in [name for name, _, _ in masks]  # 16 characters: fits


@pytest.mark.issue40
def test_an_instance_mask_of_a_classic_name_is_refused(tmp_path: Path) -> None:
    files = {"Foo.1.0.dsdl": "# F\n# @max_instances 2\n\nuint4 p_version\nuint8 x\n@sealed\n"}
    with pytest.raises(flat.FlatError, match=r"^FOO: instance mask FOO_INST is longer than 16 "
                       r"characters or the name of another parameter$"):  # fmt: skip
        flat.flat_map(_store_with(tmp_path, files, classic=[ClassicParam("FOO_INST", "Int32", 0)]))


@pytest.mark.issue40
def test_a_write_of_a_name_that_is_no_parameter_is_refused(store: px4params.Store) -> None:
    # a ground station sees classic names, destructured names and instance masks only: a
    # structured parameter's own name (INA238) is none of them, nor is a name nothing has
    before = flat.flat_values(store)
    with pytest.raises(InstanceError, match=r"^unknown parameter 'INA238'$"):
        flat.write_flat(store, "INA238", 1)
    with pytest.raises(InstanceError, match=r"^unknown parameter 'ZZZ_NOPE'$"):
        flat.write_flat(store, "ZZZ_NOPE", 1)
    assert flat.flat_values(store) == before


@pytest.mark.issue40
def test_every_name_a_vehicle_can_report(tmp_path: Path) -> None:
    # each instance slot (up to @max_instances, existing or not) times each letter; a shared
    # parameter's letters without a number
    files = {
        "Foo.1.0.dsdl": "# F\n# @max_instances 2\n\nuint4 p_version\nuint8 x\nbool on\n@sealed\n",
        "Bar.1.0.dsdl": "# B\n# @param BAR_SHARED\n\nuint4 p_version\nint8 t\n@sealed\n",
    }
    store = _store_with(tmp_path, files)
    names = set(flat.flat_map(store).names())
    ours = {n for n in names if n.startswith(("FOO_", "BAR_"))}
    assert ours == {"FOO_0A", "FOO_0B", "FOO_1A", "FOO_1B", "BAR_SHARED_A"}


# -- issue 40 (mutstore4): the 16-character rule at its edges ----------------------------------


def _named(name: str, max_instances: int | None, fields: str = "uint8 x\n") -> dict[str, str]:
    """One type whose parameter is ``name`` (shared without ``max_instances``)."""
    slots = f"# @max_instances {max_instances}\n" if max_instances else ""
    return {"Named.1.0.dsdl": f"# N\n# @param {name}\n{slots}\nuint4 p_version\n{fields}@sealed\n"}


@pytest.mark.issue40
def test_every_instance_number_up_to_max_instances_is_held_to_16_characters(
    tmp_path: Path,
) -> None:
    # docs/ground-stations.md: a name longer than 16 characters for any instance up to
    # max_instances is refused. A 12-character name leaves room for _99A (16) but not _100A
    # (17): 100 instances (#0..#99) fit, 101 do not. (More than 31 slots: no instance mask.)
    fmap = flat.flat_map(_store_with(tmp_path / "fits", _named("ABCDEFGHIJKL", 100)))
    assert "ABCDEFGHIJKL_99A" in fmap and "ABCDEFGHIJKL_0A" in fmap
    assert fmap.lookup("ABCDEFGHIJKL_99A") is not None
    with pytest.raises(flat.FlatError) as e:
        flat.flat_map(_store_with(tmp_path / "over", _named("ABCDEFGHIJKL", 101)))
    assert str(e.value) == (
        "ABCDEFGHIJKL: destructured name ABCDEFGHIJKL_100A has 17 characters (at most 16): "
        "bad.Named.1.0 has 1 flat leaves; shorten the parameter name or the type"
    )
    # 13 characters: _9A fits, _10A does not (40 instances: #10 is one of them)
    with pytest.raises(flat.FlatError) as e:
        flat.flat_map(_store_with(tmp_path / "ten", _named("ABCDEFGHIJKLM", 40)))
    assert str(e.value).startswith(
        "ABCDEFGHIJKLM: destructured name ABCDEFGHIJKLM_10A has 17 characters (at most 16): "
    )


@pytest.mark.issue40
def test_a_single_instance_name_is_held_to_16_characters_at_number_0(tmp_path: Path) -> None:
    # @max_instances 1: the one instance, #0, is named ABCDEFGHIJKLMN_0A (17 characters); the
    # names are refused before the instance mask is looked at
    with pytest.raises(flat.FlatError) as e:
        flat.flat_map(_store_with(tmp_path, _named("ABCDEFGHIJKLMN", 1)))
    assert str(e.value) == (
        "ABCDEFGHIJKLMN: destructured name ABCDEFGHIJKLMN_0A has 17 characters (at most 16): "
        "bad.Named.1.0 has 1 flat leaves; shorten the parameter name or the type"
    )


@pytest.mark.issue40
def test_a_shared_parameter_has_room_for_as_many_letters_as_its_name_leaves(
    tmp_path: Path,
) -> None:
    # a shared parameter's names have no number: 14 characters + "_" leave one letter, A..Z
    # (26 leaves); a 27th leaf would be ABCDEFGHIJKLMN_AA, 17 characters
    fmap = flat.flat_map(_store_with(tmp_path / "fits", _named("ABCDEFGHIJKLMN", None,
                                                                 "uint8[26] x\n")))  # fmt: skip
    assert "ABCDEFGHIJKLMN_Z" in fmap and "ABCDEFGHIJKLMN_AA" not in fmap
    with pytest.raises(flat.FlatError) as e:
        flat.flat_map(_store_with(tmp_path / "over", _named("ABCDEFGHIJKLMN", None,
                                                              "uint8[27] x\n")))  # fmt: skip
    assert str(e.value) == (
        "ABCDEFGHIJKLMN: destructured name ABCDEFGHIJKLMN_AA has 17 characters (at most 16): "
        "bad.Named.1.0 has 27 flat leaves; shorten the parameter name or the type"
    )


@pytest.mark.issue40
def test_a_flat_write_changes_the_value_and_leaves_the_default(store: px4params.Store) -> None:
    # a ground station's PARAM_SET changes a parameter's value, as PX4's param set does: the
    # default stays, and the parameter now differs from it (saved, shown with `+`)
    store.add("INA238#0")
    default = store.get("INA238#0.bus.i2c.address", default=True)
    assert default != 0x46 and not store.changed("INA238#0")
    row = flat.set_flat(store, "INA238_0C", 0x46)
    assert row.value == 0x46 and store.changed("INA238#0")
    assert store.get("INA238#0.bus.i2c.address", default=True) == default
    store.reset("INA238#0")
    assert flat.write_flat(store, "INA238_0C", 0x47) == "INA238_0C = 71"
    assert store.changed("INA238#0")
    assert store.get("INA238#0.bus.i2c.address", default=True) == default


@pytest.mark.issue40
def test_the_hint_names_only_a_flat_name_that_exists(store: px4params.Store) -> None:
    # INA238 has 4 instance slots (#0..#3): ina238_9c upper-cased is no name either
    fmap = flat.flat_map(store)
    with pytest.raises(InstanceError) as e:
        fmap.owner("ina238_9c")
    assert str(e.value) == "'ina238_9c' is not a destructured parameter name"
    with pytest.raises(InstanceError) as e:
        fmap.owner(" INA238_1C")
    assert str(e.value) == (
        "' INA238_1C' is not a destructured parameter name (did you mean INA238_1C?)"
    )


@pytest.mark.issue40
def test_a_one_letter_parameter_has_flat_names_too(tmp_path: Path) -> None:
    # @param takes an upper-case name, a letter first ([A-Z][A-Z0-9_]*, as PX4 names): X is
    # one, its leaves X_0A and X_0B
    store = _store_with(tmp_path, _named("X", 2, "uint8 a\nbool b\n"))
    fmap = flat.flat_map(store)
    assert fmap.lookup("X_1B") is not None and "X_0A" in fmap
    store.add("X#1")
    assert flat.resolve_flat(store, "X_1B") == "X#1[2]"


@pytest.mark.issue40
def test_a_dynamic_arrays_length_has_the_bits_of_its_maximum(tmp_path: Path) -> None:
    # DroneCAN's length prefix of T[<=N] is N.bit_length() bits (pydronecan's ArrayType,
    # dronecan/dsdl/parser.py): 1 bit for at most 1, 3 bits for at most 4
    files = {"Lists.1.0.dsdl": "# L\n# @max_instances 1\n\nuint4 p_version\nuint8[<=1] one\n"
             "uint8[<=4] four\n@sealed\n"}  # fmt: skip
    schema = px4params.load_schema([dsdl_root(tmp_path, files)], use_env=False,
                                   cache_dir=tmp_path / "cache")  # fmt: skip
    lengths = {s.path: s for s in flat.layout(schema["tst.Lists.1.0"]) if s.role == "length"}
    assert (lengths["one._len"].type, lengths["one._len"].max) == ("uint1", 1)
    assert (lengths["four._len"].type, lengths["four._len"].max) == ("uint3", 4)


@pytest.mark.issue40
def test_every_leaf_that_is_no_tag_nor_length_has_the_role_value(
    extra_schema: px4params.Schema,
) -> None:
    # FlatSlot.role: "value", "union_tag" or "length" (the module doc's kinds of letters)
    roles = {s.path: s.role for s in flat.layout(extra_schema["tst.Arrays"])}
    for path in ("pair[0].flag", "pair[0].y", "dyn[0]", "choice.a", "choice.b", "big", "neg", "f"):
        assert roles[path] == "value", path
    assert (roles["choice._tag"], roles["dyn._len"]) == ("union_tag", "length")


@pytest.mark.issue40
def test_a_value_and_its_stored_bytes_give_the_same_letters(tmp_path: Path) -> None:
    # to_flat takes a value or its stored bytes; the store keeps values without DroneCAN's
    # tail array optimisation, so a last field that is a dynamic array keeps its length there
    files = {"Tail.1.0.dsdl": "# T\n# @max_instances 1\n\nuint4 p_version\nuint8 a\n"
             "uint8[<=3] rest\n@sealed\n"}  # fmt: skip
    schema = px4params.load_schema([dsdl_root(tmp_path, files)], use_env=False,
                                   cache_dir=tmp_path / "cache")  # fmt: skip
    data_type = schema["tst.Tail.1.0"]
    value = {"a": 7, "rest": [1, 2]}
    expected = {"A": 7, "B": 2, "C": 1, "D": 2}  # a, rest._len, rest[0], rest[1]
    assert flat.to_flat(data_type, value) == expected
    store = px4params.Store(schema, classic=[])
    store.add("TAIL#0")
    store.set("TAIL#0", value)
    assert flat.to_flat(data_type, store.encoded("TAIL#0")) == expected


@pytest.mark.issue40
def test_a_union_tag_one_past_the_last_variant_is_refused(schema: px4params.Schema) -> None:
    # px.Ina238's bus has 6 variants, tags 0..5: 6 is none
    ina = schema["px.Ina238"]
    good = {"A": 0, "B": 1, "C": 69, "P": 2, "Q": 0.5}
    with pytest.raises(flat.FlatError) as e:
        flat.from_flat(ina, {**good, "A": 6})
    assert str(e.value) == "px.Ina238.1.1: bus._tag: no variant 6 (expected 0 to 5)"


@pytest.mark.issue40
def test_a_shared_parameter_has_no_instance_mask(tmp_path: Path) -> None:
    # docs/ground-stations.md: each instanced parameter has an instance mask; a shared one has
    # no instances to add or remove
    store = _store_with(tmp_path, _named("FOO_SHARED", None, "uint8 x\n"))
    fmap = flat.flat_map(store)
    assert fmap.mask_spec("FOO_SHARED_INST") is None
    assert "FOO_SHARED" not in {spec.name for _, spec, _ in fmap.masks()}
    assert fmap.mask_spec("INA238_INST") is not None  # the instanced ones after it keep theirs
    assert "FOO_SHARED_INST" not in flat.flat_values(store)
    with pytest.raises(InstanceError, match=r"^unknown parameter 'FOO_SHARED_INST'"):
        flat.write_flat(store, "FOO_SHARED_INST", 1)


@pytest.mark.issue40
def test_a_parameter_name_ending_in_an_underscore_has_flat_names_too(tmp_path: Path) -> None:
    # [A-Z][A-Z0-9_]* takes X_: its names are X_, "_", the number and the letter (X__0A), read
    # back exactly although X__0A has another _ right after the first
    store = _store_with(tmp_path, _named("X_", 2, "uint8 a\n"))
    fmap = flat.flat_map(store)
    assert fmap.lookup("X__1A") is not None and "X__0A" in fmap and "X_0A" not in fmap
    store.add("X_#1")
    assert flat.resolve_flat(store, "X__1A") == "X_#1[1]"


@pytest.mark.issue40
def test_the_24th_letter_x_follows_an_instance_number(tmp_path: Path) -> None:
    # letters A..Z follow the instance number: the 24th leaf of FOO#1 is FOO_1X (X is a letter,
    # not a digit of the number)
    store = _store_with(tmp_path, _named("FOO", 2, "uint8[24] x\n"))
    store.add("FOO#1")
    assert flat.resolve_flat(store, "FOO_1X") == "FOO#1[24]"
    assert flat.flat_map(store).lookup("FOO_1X") is not None and "FOO_1Y" not in flat.flat_map(
        store
    )


@pytest.mark.issue40
def test_a_leaf_that_is_not_live_names_the_first_requirement_that_fails(
    extra_schema: px4params.Schema,
) -> None:
    # requires lists outermost first (FlatSlot): the refusal names the first that does not hold,
    # a length by its value and what to set it above, a tag by the variant it selects
    store = px4params.Store(extra_schema)
    store.add("ARRAYS#0")
    lay = flat.flat_map(store).layout_of("ARRAYS")

    def name(path: str) -> str:
        slot = lay.slot_for_path(path)
        assert slot is not None
        return f"ARRAYS_0{slot.letter}"

    def why(path: str) -> str:
        with pytest.raises(LeafError) as e:
            flat.get_flat(store, name(path))
        return str(e.value)

    # dyn is empty: its third element needs a length above 2
    assert why("dyn[2]") == (
        f"{name('dyn[2]')} (ARRAYS#0.dyn[2]) is not live: dyn._len is 0 "
        f"(set {name('dyn._len')} above 2)"
    )
    # two choices, both variant a (0): choices[1].c[1] needs the length (it holds) and variant c
    flat.set_flat(store, name("choices._len"), 2)
    assert why("choices[1].c[1]") == (
        f"{name('choices[1].c[1]')} (ARRAYS#0.choices[1].c[1]) is not live: choices[1]._tag "
        f"selects variant 0, not 2 (set {name('choices[1]._tag')} to 2)"
    )


@given(st.integers(0, 15), st.integers(0, 15), st.integers(0, 15))
def test_a_merged_mask_takes_the_writers_changes_and_keeps_the_rest(
    now: int, was: int, wanted: int
) -> None:
    # Bit by bit: a bit the writer changed (was -> wanted) is the writer's; any other bit is as
    # it is now (another writer's since).
    merged = flat.merged_mask(now, was, wanted)
    for bit in range(4):
        mine = (was >> bit & 1) != (wanted >> bit & 1)
        expected = (wanted if mine else now) >> bit & 1
        assert merged >> bit & 1 == expected, (now, was, wanted, bit)


def test_a_mask_write_with_the_mask_it_was_made_from_keeps_other_instances(
    store: px4params.Store,
) -> None:
    store.add("INA238#1")
    store.add("INA238#3")  # added since the writer read 0b0010
    assert (
        flat.write_flat(store, "INA238_INST", 0b0011, was=0b0010) == "INA238_INST: added INA238#0"
    )
    assert store.instances("INA238") == ["INA238#0", "INA238#1", "INA238#3"]
    # Without it, the mask as given (a ground station's PARAM_SET).
    assert flat.write_flat(store, "INA238_INST", 0b0001) == (
        "INA238_INST: removed INA238#1, removed INA238#3"
    )
    assert store.instances("INA238") == ["INA238#0"]
