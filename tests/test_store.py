"""The parameter store: instances, defaults, classic parameters, all-or-nothing changes."""

from __future__ import annotations

import atexit
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

import px4params
import pytest
from core_calls import count_core_calls
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule
from px4params.errors import (
    EncodeError,
    InstanceError,
    LeafError,
    StoreError,
    ValueRangeError,
    ValueShapeError,
)
from px4params.store.classic import ClassicParam, ClassicParamsError
from px4params.store.file import encode_file
from px4params.store.key import _KEY, Key, _split_key
from px4params.store.spec import metadata_default, parameter_specs
from shared_data import PARAMETERS_JSON, shared_file
from strategies import budget

CLASSIC = [
    ClassicParam("SYS_AUTOSTART", "Int32", 0),
    ClassicParam("BAT1_CAPACITY", "Float", -1.0),
    ClassicParam("SENS_EXT_I2C_PRB", "Int32", 1),
]


@pytest.fixture
def store(schema: px4params.Schema) -> px4params.Store:
    return px4params.Store(schema, classic=CLASSIC)


def talk_lines(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.set_default("INA238#0[3]", 1)
    store.set_default("INA238#0[4]", 0x45)
    store.set_default("INA238#0[5]", 200)
    store.set_default("INA238#0[6]", 0.0003)


def test_parameter_set(store: px4params.Store) -> None:
    structured = store.parameters[:-3]  # sorted; the bundled drivers' types
    assert structured == sorted(structured) and len(structured) == 37
    assert {"AK09916", "BMM350", "HMC5883", "INA238", "SDP3X"} <= set(structured)
    assert store.parameters[-3:] == ["SYS_AUTOSTART", "BAT1_CAPACITY", "SENS_EXT_I2C_PRB"]
    assert store.spec("INA238").max_instances == 4
    assert store.spec("INA238").data_type.key == "px.Ina238.1.1"


def test_talk_airframe_lines(store: px4params.Store) -> None:
    talk_lines(store)
    value = store.get("INA238#0")
    assert value["bus"] == {"i2c": {"p_version": 0, "bus_id": 1, "address": 0x45}}
    assert value["current"] == 200
    assert value["shunt"] == pytest.approx(0.0003, rel=1e-3)
    assert store.get("INA238#0", default=True) == value  # set-default moved the value along
    assert not store.changed("INA238#0")
    assert [leaf.value for leaf in store.leaves("INA238#0")][:6] == [1, 0, 0, 1, 69, 200]
    assert store.encoded("INA238#0").hex() == "10031720ea0c"


def test_new_instance_starts_from_metadata_defaults(store: px4params.Store) -> None:
    assert store.add("INA238") == "INA238#0"
    value = store.get("INA238#0")
    assert value["bus"]["i2c"]["address"] == 0x45
    assert value["current"] == 327
    assert value["shunt"] == pytest.approx(0.0003, rel=1e-3)


def test_pythonic_access(store: px4params.Store) -> None:
    store.add("INA238#2")
    view = store["INA238#2"]
    view[4] = 0x46
    assert view.bus.i2c.address == 0x46
    view.current = 10
    assert view["current"] == 10 and view[5] == 10
    view.bus.i2c.bus_id = 3
    assert store.get("INA238#2.bus.i2c.bus_id") == 3
    assert view.name == "INA238#2"
    assert store.changed() == ["INA238#2"]


def test_instances_are_stable(store: px4params.Store) -> None:
    assert [store.add("INA238") for _ in range(3)] == ["INA238#0", "INA238#1", "INA238#2"]
    store.set("INA238#2.current", 7)
    store.remove("INA238#1")
    assert store.instances("INA238") == ["INA238#0", "INA238#2"]
    assert store.get("INA238#2.current") == 7
    assert store.add("INA238") == "INA238#1"  # the lowest free number
    assert store.add("INA238") == "INA238#3"
    assert "INA238#3" in store and "INA238#9" not in store


def test_set_default_does_not_move_a_changed_value(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.set("INA238#0.current", 100)
    store.set_default("INA238#0.current", 200)
    assert store.get("INA238#0.current") == 100
    assert store.get("INA238#0.current", default=True) == 200
    store.reset("INA238#0")
    assert store.get("INA238#0.current") == 200


def test_whole_value_and_union_switch(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.set(
        "INA238#0",
        {
            "bus": {"spi": {"bus_id": 2, "chip_select": 1, "max_frequency": 8000, "mode": 3}},
            "current": 5,
            "shunt": 0.001,
        },
    )
    assert list(store.get("INA238#0")["bus"]) == ["spi"]
    store.set("INA238#0.bus._tag", 0)  # back to I2C with its default
    assert list(store.get("INA238#0")["bus"]) == ["i2c"]


def test_classic_parameters(store: px4params.Store) -> None:
    assert store.get("SYS_AUTOSTART") == 0
    store.set("SYS_AUTOSTART", 4001)
    store.set("BAT1_CAPACITY", 5000.5)
    assert store.get("SYS_AUTOSTART") == 4001
    assert store.get("BAT1_CAPACITY") == 5000.5
    assert set(store.changed()) == {"SYS_AUTOSTART", "BAT1_CAPACITY"}
    store.reset_all()
    assert store.changed() == []


def test_real_parameters_json(schema: px4params.Schema) -> None:
    store = px4params.Store(schema, classic=shared_file(PARAMETERS_JSON))
    assert len(store.parameters) == 1909 + len(parameter_specs(schema))
    assert store.get("SENS_EXT_I2C_PRB") == 1
    store.set("MPC_XY_VEL_MAX", 8.5)
    assert store.get("MPC_XY_VEL_MAX") == 8.5


BAD = [
    (
        "add",
        ("INA238#4",),
        InstanceError,
        "INA238#4: instance 4 is out of range (max_instances is 4: instances 0..3)",
    ),
    ("add", ("INA238#0",), InstanceError, "INA238#0: instance exists already"),
    ("add", ("NOPE#0",), InstanceError, "unknown parameter 'NOPE'"),
    ("add", ("INA283#0",), InstanceError, "unknown parameter 'INA283' (did you mean: INA238"),
    (
        "add",
        ("SYS_AUTOSTART",),
        InstanceError,
        "SYS_AUTOSTART: a classic parameter has no instances to add",
    ),
    ("add", ("INA238#0[4]",), InstanceError, "add takes an instance, not a leaf: INA238#0[4]"),
    (
        "remove",
        ("INA238#1",),
        InstanceError,
        "INA238#1: instance does not exist (add it first: param add)",
    ),
    ("get", ("INA238",), InstanceError, "INA238 has instances: name one, e.g. INA238#0"),
    (
        "get",
        ("SYS_AUTOSTART#0",),
        InstanceError,
        "SYS_AUTOSTART is not instanced: write SYS_AUTOSTART, not SYS_AUTOSTART#0",
    ),
    (
        "get",
        ("INA238#0[9]",),
        LeafError,
        "INA238#0: no leaf [9] (the value has 7 leaves: [0]..[6])",
    ),
    ("get", ("INA238#0.bus.i2c.nope",), LeafError, "INA238#0: bus.i2c: no such field"),
    ("get", ("INA238#0 x",), InstanceError, "'INA238#0 x' is not a parameter name"),
    (
        "set",
        ("INA238#0[0]", 1),
        StoreError,
        "INA238#0: p_version is set automatically to the type's version and cannot be written",
    ),
    (
        "set",
        ("INA238#0.bus.i2c.p_version", 0),
        StoreError,
        "INA238#0: bus.i2c.p_version is set automatically",
    ),
    (
        "set",
        ("INA238#0[4]", 200),
        EncodeError,
        "INA238#0: bus.i2c.address: value 200 is out of range (expected 0 to 127)",
    ),
    (
        "set",
        ("INA238#0[4]", "0x45"),
        ValueShapeError,
        "INA238#0: bus.i2c.address: expected an integer, got str",
    ),
    ("set", ("INA238#0[6]", True), ValueShapeError, "INA238#0: shunt: expected a number, got bool"),
    (
        "set",
        ("INA238#0.bus.spi.cs", 1),
        LeafError,
        "INA238#0: bus.spi: this union variant is not the selected one",
    ),
    ("set", ("INA238#0", {"current": 1}), ValueShapeError, "INA238#0: bus: missing field"),
    (
        "set",
        (
            "INA238#0",
            {"bus": {"i2c": {"bus_id": 1, "address": 1}}, "current": 1, "shunt": 1.0, "x": 1},
        ),
        ValueShapeError,
        "unknown field",
    ),
    (
        "set",
        (
            "INA238#0",
            {
                "p_version": 0,
                "bus": {"i2c": {"bus_id": 1, "address": 1}},
                "current": 1,
                "shunt": 1.0,
            },
        ),
        EncodeError,
        "p_version is set automatically; got 0, the type's version is 1",
    ),
    (
        "set",
        ("SYS_AUTOSTART", 1.5),
        ClassicParamsError,
        "SYS_AUTOSTART: expected an integer, got 1.5",
    ),
    (
        "set",
        ("SYS_AUTOSTART", 2**31),
        ClassicParamsError,
        "SYS_AUTOSTART: value 2147483648 is out of range (expected -2147483648 to 2147483647)",
    ),
    (
        "set",
        ("BAT1_CAPACITY", "x"),
        ClassicParamsError,
        "BAT1_CAPACITY: expected a number, got 'x'",
    ),
    (
        "set",
        ("BAT1_CAPACITY[0]", 1),
        InstanceError,
        "BAT1_CAPACITY is a classic parameter: it has no leaves",
    ),
    ("set_default", ("INA238#3.current", 2000), EncodeError, "INA238#3: instance does not exist"),
    # The field's @min/@max are named before its type's range (0..1023 for a uint10).
    (
        "set_default",
        ("INA238#0.current", 2000),
        ValueRangeError,
        "INA238#0.current: 2000 is outside 1..327 (@min/@max)",
    ),
    # With --force (the Python API's force=True), the type's range still holds.
    (
        "set_default_forced",
        ("INA238#0.current", 2000),
        EncodeError,
        "INA238#0: current: value 2000 is out of range (expected 0 to 1023)",
    ),
    ("reset", ("INA238#2",), InstanceError, "INA238#2: instance does not exist"),
    (
        "leaves",
        ("SYS_AUTOSTART",),
        InstanceError,
        "SYS_AUTOSTART is a classic parameter: it has no leaves",
    ),
]


@pytest.mark.parametrize(("method", "args", "exc", "message"), BAD, ids=[b[3][:40] for b in BAD])
def test_refused_changes_leave_the_store_as_it_was(
    store: px4params.Store, method: str, args: tuple, exc: type, message: str
) -> None:
    talk_lines(store)
    store.set("SYS_AUTOSTART", 4001)
    before = encode_file(store)
    with pytest.raises((exc, InstanceError)) as info:
        if method.endswith("_forced"):
            getattr(store, method.removesuffix("_forced"))(*args, force=True)
        else:
            getattr(store, method)(*args)
    assert message in str(info.value)
    assert "\n" not in str(info.value)
    assert encode_file(store) == before


def test_full(store: px4params.Store) -> None:
    for _ in range(4):
        store.add("INA238")
    with pytest.raises(
        InstanceError, match=r"^INA238: all 4 instances are in use \(max_instances is 4\)$"
    ):
        store.add("INA238")


def test_transaction_is_all_or_nothing(store: px4params.Store) -> None:
    before = encode_file(store)
    with pytest.raises(ValueRangeError), store.transaction():
        store.add("INA238#0")
        store.set("INA238#0.current", 5)
        store.set("INA238#0.current", 5000)
    assert encode_file(store) == before
    assert store.instances("INA238") == []


def test_memory_is_reserved_up_front(store: px4params.Store) -> None:
    slots, size = store.capacity
    ina = store.spec("INA238")
    assert ina is not None
    # Each parameter: a type default plus a value and a default per instance.
    assert slots == sum(1 + (s.max_instances or 1) for s in store.specs) + 2 * len(CLASSIC)
    assert size >= 9 * ina.data_type.max_bytes


# -- property test: the store against a simple model ---------------------------------------------

KINDS = ("uint", "int", "float", "bool")


def _to_the_defaults_variant(
    data_type: Any, value: bytes, dflt: bytes, leaf: Any, new: Any, changed: bytes
) -> bytes:
    """A value's union tag switched to the variant its default selects takes that variant as
    the default holds it (the store's rule, docs/store.md: SPI then I2C again keeps the default
    address), not the variant's zeros (DSDL's, ``DataType.set_leaf``'s)."""
    from px4params.dsdl.schema import put_at, value_at

    parent, _, last = leaf.path.rpartition(".")
    if last != "_tag":
        return changed
    tags = {
        which: next((x.value for x in data_type.leaves(v, tao=False) if x.path == leaf.path), None)
        for which, v in (("value", value), ("default", dflt))
    }
    if new != tags["default"] or new == tags["value"]:
        return changed
    whole, default_value = data_type.decode(value), data_type.decode(dflt)
    if not parent:
        return dflt
    put_at(whole, parent, value_at(default_value, parent))
    return bytes(data_type.encode(whole, tao=False))


class StoreMachine(RuleBasedStateMachine):
    """Random operations on the store and on a model (a dict of encoded value and default per
    instance, changed with the codec's pure functions); after each step they agree, refused
    operations change nothing, and save + load reproduces the store exactly."""

    def __init__(self) -> None:
        super().__init__()
        self.schema = SCHEMA
        self.store = px4params.Store(self.schema, classic=CLASSIC)
        self.model: dict[str, tuple[bytes, bytes]] = {}
        self.classic = bytes(4)
        self.types = {s.name: s for s in self.store.specs}
        self.defaults = {
            s.name: s.data_type.encode(metadata_default(self.schema, s.data_type.key), tao=False)
            for s in self.store.specs
        }

    def names(self) -> list[str]:
        return sorted(self.model)

    @rule(
        param=st.sampled_from(["INA238", "AK09916", "RM3100", "BMM350"]), number=st.integers(0, 5)
    )
    def add(self, param: str, number: int) -> None:
        name = f"{param}#{number}"
        before = encode_file(self.store)
        if number >= 4 or name in self.model:
            with pytest.raises(InstanceError):
                self.store.add(name)
            assert encode_file(self.store) == before
            return
        assert self.store.add(name) == name
        self.model[name] = (self.defaults[param], self.defaults[param])

    @precondition(lambda self: self.model)
    @rule(data=st.data())
    def remove(self, data: st.DataObject) -> None:
        name = data.draw(st.sampled_from(self.names()))
        self.store.remove(name)
        del self.model[name]

    @precondition(lambda self: self.model)
    @rule(data=st.data(), default=st.booleans())
    def set_leaf(self, data: st.DataObject, default: bool) -> None:
        name = data.draw(st.sampled_from(self.names()))
        value, dflt = self.model[name]
        data_type = self.types[name.split("#")[0]].data_type
        leaves = data_type.leaves(dflt if default else value, tao=False)
        leaf = data.draw(st.sampled_from(leaves))
        new = data.draw(_leaf_value(leaf.type))
        before = encode_file(self.store)
        try:
            self.store._write(f"{name}[{leaf.index}]", new, default=default, saturate=False)
        except px4params.Px4ParamsError:
            assert encode_file(self.store) == before
            assert leaf.path.endswith("p_version") or not _fits(
                self.schema, data_type.key, leaf.path, leaf.type, new
            )
            return
        assert _fits(self.schema, data_type.key, leaf.path, leaf.type, new)
        assert not leaf.path.endswith("p_version")
        if default:
            new_default = data_type.set_leaf(dflt, leaf.index, new, tao=False)
            self.model[name] = (new_default if value == dflt else value, new_default)
        else:
            changed = data_type.set_leaf(value, leaf.index, new, tao=False)
            self.model[name] = (
                _to_the_defaults_variant(data_type, value, dflt, leaf, new, changed),
                dflt,
            )

    @precondition(lambda self: self.model)
    @rule(data=st.data())
    def reset(self, data: st.DataObject) -> None:
        name = data.draw(st.sampled_from(self.names()))
        self.store.reset(name)
        self.model[name] = (self.model[name][1], self.model[name][1])

    @rule(value=st.integers(-(2**31), 2**31 - 1))
    def set_classic(self, value: int) -> None:
        self.store.set("SYS_AUTOSTART", value)
        self.classic = value.to_bytes(4, "little", signed=True)

    @invariant()
    def agrees_with_model(self) -> None:
        assert self.store.encoded("SYS_AUTOSTART") == self.classic
        for name, (value, default) in self.model.items():
            assert self.store.encoded(name) == value
            assert self.store.encoded(name, default=True) == default
        structured = [n for n in self.store.names() if "#" in n]
        assert structured == sorted(self.model, key=_order(self.store))

    @invariant()
    def save_and_load_reproduce_it(self) -> None:
        data = encode_file(self.store)
        path = TMP / "machine.store"
        self.store.save(path)
        again = px4params.Store.load(path, self.schema, classic=CLASSIC)
        assert encode_file(again) == data
        for name in self.store.names():
            assert again.encoded(name) == self.store.encoded(name)
            assert again.encoded(name, default=True) == self.store.encoded(name, default=True)


def _fits(schema: px4params.Schema, key: str, path: str, type_name: str, new: object) -> bool:
    """Whether a leaf takes ``new``, worked out from the DSDL alone (not by the codec): the
    range of ``uintN``/``intN``/``floatN``, a union tag's variants, an array length's maximum,
    the field's ``@min``/``@max`` and ``@value`` list, and no NaN or infinity in a float."""
    if type_name == "bool":
        return isinstance(new, bool)
    tags = _field_tags(schema, key, path)
    if type_name.startswith("float"):
        top = {"float16": 65504.0, "float32": 3.4028234663852886e38}.get(type_name, math.inf)
        if not (isinstance(new, float) and math.isfinite(new) and abs(new) <= top):
            return False
        code = {"float16": "<e", "float32": "<f"}[type_name]

        def stored(x: float) -> float:  # the store compares what it would keep
            return struct.unpack(code, struct.pack(code, x))[0]

        low_ok = "min" not in tags or stored(new) >= min(tags["min"], stored(tags["min"]))
        high_ok = "max" not in tags or stored(new) <= max(tags["max"], stored(tags["max"]))
        return low_ok and high_ok
    assert isinstance(new, int)
    bits = int(type_name.lstrip("uint"))
    low, high = (0, (1 << bits) - 1) if type_name.startswith("u") else (
        -(1 << (bits - 1)), (1 << (bits - 1)) - 1)  # fmt: skip
    if path.endswith("_tag") or path.endswith("_len"):
        high = min(high, _selector_limit(schema, key, path))
    low, high = max(low, tags.get("min", low)), min(high, tags.get("max", high))
    listed = {number for number, _ in tags.get("value", ())}  # @value: only these
    return low <= new <= high and (not listed or new in listed)


def _field_tags(schema: px4params.Schema, key: str, path: str) -> dict:
    """The doc tags of the field a leaf path ends at (an array's tags are its elements')."""
    types = schema.model["types"]
    spec: dict = {"kind": "ref", "name": key}
    tags: dict = {}
    for part in path.split("."):
        name = part.partition("[")[0]
        if spec["kind"] != "ref" or name in ("_tag", "_len"):
            return {}
        field = next(f for f in types[spec["name"]]["fields"] if f["name"] == name)
        tags = (field.get("doc") or {}).get("tags") or {}
        spec = field["type"]
        while spec["kind"] in ("array", "dynarray"):
            spec = spec["elem"]
    return tags


def _selector_limit(schema: px4params.Schema, key: str, path: str) -> int:
    """The largest value of a union tag (variants - 1) or a dynamic array length (its maximum),
    found by following ``path`` through the model's type definitions."""
    types = schema.model["types"]
    spec: dict = {"kind": "ref", "name": key}
    for part in path.split(".")[:-1]:
        name, _, index = part.partition("[")
        definition = types[spec["name"]]
        spec = next(f["type"] for f in definition["fields"] if f["name"] == name)
        while index and spec["kind"] in ("array", "dynarray"):
            spec, index = spec["elem"], index.partition("[")[2]
    if path.endswith("_len"):
        return int(spec["max"])
    fields = [f for f in types[spec["name"]]["fields"] if f["type"]["kind"] != "void"]
    return len(fields) - 1


def _order(store: px4params.Store):
    index = {p: i for i, p in enumerate(store.parameters)}

    def key(name: str) -> tuple[int, int]:
        param, _, number = name.partition("#")
        return index[param], int(number or 0)

    return key


def _leaf_value(type_name: str) -> st.SearchStrategy[object]:
    if type_name == "bool":
        return st.booleans()
    if type_name.startswith("float"):
        return st.floats(-70000, 70000, width=32) | st.just(float("nan"))
    bits = int("".join(c for c in type_name if c.isdigit()) or 8)
    if type_name.startswith("int"):
        return st.integers(-(1 << (bits - 1)) - 2, (1 << (bits - 1)) + 1)
    return st.integers(-1, (1 << bits) + 1)


SCHEMA = px4params.load_schema(use_env=False)
# The state machine cannot take fixtures: a folder of its own, removed when the run ends.
TMP = Path(tempfile.mkdtemp(prefix="px4params-store-machine-"))
atexit.register(shutil.rmtree, TMP, ignore_errors=True)

TestStoreMachine = StoreMachine.TestCase
TestStoreMachine.settings = settings(
    max_examples=budget(60),
    stateful_step_count=25,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


@given(value=st.data())
@settings(max_examples=budget(40), deadline=None)
def test_whole_values_round_trip(value: st.DataObject) -> None:
    from strategies import expected_decoded, same_decoded, value_strategy

    store = px4params.Store(SCHEMA)
    spec = value.draw(st.sampled_from(store.specs))
    types, key = SCHEMA.model["types"], spec.data_type.key
    v = value.draw(value_strategy(types, key, infinities=False, storable=True))
    name = store.add(spec.name)
    store.set(name, v)
    # The value read back is the value set, floats rounded as Python rounds them (not the codec).
    assert same_decoded(expected_decoded(types, key, v), store.get(name))


def test_restore_takes_only_a_copy_of_the_same_store(schema: px4params.Schema) -> None:
    one, other = px4params.Store(schema), px4params.Store(schema, classic=CLASSIC)
    with pytest.raises(ValueError, match=r"^restore takes a copy of this store"):
        one._native.restore(other._native)
    one._native.restore(one._native.copy())


def test_a_leaf_read_before_reads_the_same_and_fails_the_same(store: px4params.Store) -> None:
    # Store.get keeps the core's arguments for leaf names it has read: what it answers, and
    # how it refuses once the instance is gone, must not change.
    store.add("INA238#1")
    store.set("INA238#1.current", 200)
    first = [
        store.get(name) for name in ("INA238#1.current", "INA238#1[4]", "INA238#1.bus.i2c.address")
    ]
    assert [
        store.get(name) for name in ("INA238#1.current", "INA238#1[4]", "INA238#1.bus.i2c.address")
    ] == first
    assert first[0] == 200
    assert store.get("INA238#1.current", default=True) == 327
    store.set("INA238#1.bus._tag", 1)  # spi: the i2c path names nothing now
    with pytest.raises(px4params.LeafError, match=r"bus\.i2c"):
        store.get("INA238#1.bus.i2c.address")
    store.remove("INA238#1")
    with pytest.raises(
        px4params.InstanceError, match=r"^INA238#1: instance does not exist \(add it first"
    ):
        store.get("INA238#1.current")


# -- names split by hand (no re at run time), as the name expression would ---------------------


#: Characters that mean something to the name expression, and some that do not.
NAME_CHARS = "AZaz09_#[].-+ \t\n" + "\u0663\u00b2\u0130\u017f\u212a\u00e9"


@settings(max_examples=budget(2000), deadline=None)
@given(st.text(NAME_CHARS, max_size=14))
@example("INA238#0.bus.i2c.address")
@example("ina238#12[4]")
@example("X#\u0663")  # an Arabic-Indic digit: not a digit of a name (ASCII only, as PX4)
@example("K#1.\u212a")  # the Kelvin sign: [A-Za-z] is ASCII
@example("A[1].b")
@example("A#")
@example("A#01")
@example("A#0[00]")
def test_names_are_split_as_the_expression_matches(text: str) -> None:
    match = re.fullmatch(_KEY, text)
    expected = match.group("name", "instance", "index", "path") if match else None
    assert _split_key(text) == expected


def test_a_name_is_parsed_once_into_its_parts() -> None:
    assert Key.parse("INA238#2[4]") == Key("INA238", 2, 4)
    assert Key.parse("INA238#0.bus.i2c.address") == Key("INA238", 0, "bus.i2c.address")
    assert Key.parse("SYS_AUTOSTART") == Key("SYS_AUTOSTART", None, None)


# -- names are exact, as PX4's -----------------------------------------------------------------
# Names are exact, as PX4's: ASCII digits only, upper case, no padding. PX4 finds a parameter by
# comparing its name byte for byte (``param_find`` uses ``strcmp``), so ``ina238#0`` or ``INA238#٣``
# (an Arabic-Indic three) name nothing there; here they are refused with the exact name as a hint,
# at the one place names are parsed (``Key.parse``) and for destructured (MAVLink) names.


EXACT = "names are exact, in upper case with ASCII digits and no spaces, as PX4's"


@pytest.mark.parametrize(
    ("text", "hint"),
    [
        ("INA238#\u0663", "INA238#3"),  # Arabic-Indic digit three
        ("INA238#\u0661[4]", "INA238#1[4]"),
        ("INA238#\uff11", "INA238#1"),  # fullwidth digit one
        ("ina238#0", "INA238#0"),
        ("Ina238#0.bus.i2c.address", "INA238#0.bus.i2c.address"),
        (" INA238#0", "INA238#0"),
        ("INA238#0 ", "INA238#0"),
        ("INA238#0\t", "INA238#0"),
        ("sys_autostart", "SYS_AUTOSTART"),
        # one instance, one name: its number has no leading zeros
        ("INA238#01", "INA238#1"),
        ("INA238#000001", "INA238#1"),
        ("INA238#00[4]", "INA238#0[4]"),
        ("INA238#1[04]", "INA238#1[4]"),
        # and an index in a path neither (docs/store.md: one leaf, one name)
        ("MIX#0.arr[01]", "MIX#0.arr[1]"),
        ("MIX#00.arr[0].b[007]", "MIX#0.arr[0].b[7]"),
    ],
)
def test_an_inexact_name_is_refused_with_the_exact_one(text: str, hint: str) -> None:
    with pytest.raises(InstanceError) as e:
        Key.parse(text)
    assert str(e.value) == f"'{text}' is not a parameter name: {EXACT} (did you mean {hint}?)"


def test_no_instance_is_added_under_an_inexact_name() -> None:
    store = px4params.Store()
    for text in ("INA238#\u0663", "ina238#3", "INA238#3 ", "ina238"):
        with pytest.raises(InstanceError, match="did you mean INA238"):
            store.add(text)
    assert list(store.names()) == []
    assert store.add("INA238#3") == "INA238#3"
    assert "ina238#3" not in store and " INA238#3" not in store and "INA238#3" in store
    with pytest.raises(InstanceError, match=rf"^'ina238' is not a parameter name: {EXACT} \("):
        store.instances("ina238")


def test_a_destructured_name_is_exact_too() -> None:
    from px4params.store.flat import resolve_flat

    store = px4params.Store()
    store.add("INA238#1")
    assert resolve_flat(store, "INA238_1C") == "INA238#1[4]"
    for text in ("ina238_1c", "INA238_1C ", " INA238_1C"):
        with pytest.raises(InstanceError) as e:
            resolve_flat(store, text)
        assert str(e.value) == (
            f"'{text}' is not a destructured parameter name (did you mean INA238_1C?)"
        )
    assert "ina238_1c" not in store.destructured
    assert store.destructured.mask_spec("ina238_inst") is None


def test_the_cli_refuses_them_and_changes_nothing(tmp_path: Path) -> None:
    store = tmp_path / "vehicle.store"
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))

    def cli(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-m", "px4params", "param", "--store", str(store), *args],
            capture_output=True,
            text=True,
            env=env,
            timeout=120,
        )

    assert cli("add", "INA238#0").returncode == 0
    before = store.read_bytes()
    for args, hint in (
        (("add", "INA238#\u0663"), "INA238#3"),
        (("add", "ina238#1"), "INA238#1"),
        (("set", "INA238#0.current ", "100"), "INA238#0.current"),
        (("set", "ina238_0p", "100"), "INA238_0P"),
    ):
        result = cli(*args)
        assert (result.returncode, result.stdout) == (1, "")
        assert result.stderr == (
            f"px4params: error: '{args[1]}' is not a parameter name: {EXACT} "
            f"(did you mean {hint}?)\n"
        )
    assert store.read_bytes() == before


# -- refusals that name what they refuse (an outside audit's defect 10) ------------------------


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


# -- issue 40: the survivors of store.py's mutation run ------------------------------------------


@pytest.mark.issue40
def test_the_store_file_is_named_by_the_environment_else_px4params_store(
    store: px4params.Store, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from px4params.store.store import default_store_path

    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    assert default_store_path() == "px4params.store"
    monkeypatch.setenv("PX4PARAMS_STORE", "")  # empty: not a name
    assert default_store_path() == "px4params.store"
    store.add("INA238#1")
    assert store.save() == (tmp_path / "px4params.store").stat().st_size
    monkeypatch.setenv("PX4PARAMS_STORE", str(tmp_path / "env.store"))
    store.set("SYS_AUTOSTART", 4001)
    store.save()
    assert px4params.Store.load(None, store.schema, classic=CLASSIC).get("SYS_AUTOSTART") == 4001
    other = px4params.Store(store.schema, classic=CLASSIC)
    other.add("INA238#3")
    other.import_from()
    assert other.instances("INA238") == ["INA238#1", "INA238#3"]
    other.load_from()
    assert other.instances("INA238") == ["INA238#1"]
    monkeypatch.delenv("PX4PARAMS_STORE")
    assert px4params.Store.load(None, store.schema, classic=CLASSIC).get("SYS_AUTOSTART") == 0


@pytest.mark.issue40
def test_saving_and_loading_mark_instances_saved(store: px4params.Store, tmp_path: Path) -> None:
    """``(used, unsaved)``: a change is unsaved until a save or a load; reading by a driver
    (``mark_used``, PX4's ``x`` in ``param show``) is kept apart."""
    store.add("INA238#0")
    assert store.state("INA238#0") == (False, True)
    store.mark_used("INA238#0")
    assert store.state("INA238#0") == (True, True)
    path = tmp_path / "s.store"
    assert store.save(path) == path.stat().st_size
    assert store.state("INA238#0") == (True, False)
    store.set("SYS_AUTOSTART", 7)
    assert store.state("SYS_AUTOSTART") == (False, True)
    loaded = px4params.Store.load(path, store.schema, classic=CLASSIC)
    assert loaded.state("INA238#0") == (False, False)
    assert loaded.get("SYS_AUTOSTART") == 0
    for call, word in ((store.state, "state"), (store.mark_used, "touch")):
        with pytest.raises(InstanceError, match=rf"^{word} takes an instance or parameter, not a "
                           r"leaf: INA238#0\[4\]$"):  # fmt: skip
            call("INA238#0[4]")


@pytest.mark.issue40
def test_a_classic_list_from_the_environment(
    schema: px4params.Schema, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``$PX4PARAMS_PARAMETERS_JSON`` names the classic parameters when none are given."""
    path = tmp_path / "parameters.json"
    path.write_text(
        '{"version": 1, "parameters": [{"name": "MY_PARAM", "type": "Int32", "default": 3}]}'
    )
    monkeypatch.setenv("PX4PARAMS_PARAMETERS_JSON", str(path))
    store = px4params.Store(schema)
    assert store.parameters[-1] == "MY_PARAM" and store.get("MY_PARAM") == 3
    assert px4params.Store(schema, classic=[]).parameters[-1] != "MY_PARAM"  # given: taken


@pytest.mark.issue40
def test_classic_names_must_be_new_and_distinct(schema: px4params.Schema) -> None:
    with pytest.raises(
        StoreError, match=r"^classic parameter INA238 has the name of a structured one$"
    ):
        px4params.Store(schema, classic=[ClassicParam("INA238", "Int32", 0)])
    twice = [ClassicParam("A_B", "Int32", 0), ClassicParam("A_B", "Float", 1.0)]
    with pytest.raises(StoreError, match=r"^two classic parameters have the same name$"):
        px4params.Store(schema, classic=twice)


@pytest.mark.issue40
def test_what_a_structured_and_a_classic_parameter_are(store: px4params.Store) -> None:
    assert store.classic("SYS_AUTOSTART") == CLASSIC[0]
    assert store.classic("INA238") is None
    assert store.data_type("INA238#2.current").key == "px.Ina238.1.1"
    with pytest.raises(
        InstanceError, match=r"^SYS_AUTOSTART is a classic parameter, not a structured one$"
    ):
        store.data_type("SYS_AUTOSTART")
    assert str(store.instance_key("INA238", 2)) == "INA238#2"
    assert str(store.instance_key("SYS_AUTOSTART", 2)) == "SYS_AUTOSTART"
    store.add("INA238#1")
    structured = [p for p in store.parameters if store.classic(p) is None]
    assert len(store._type_defaults()) == len(structured)
    assert store._type_defaults()[structured.index("INA238")] == store.encoded(
        "INA238#1", default=True
    )


@pytest.mark.issue40
def test_removing_refuses_leaves_and_shared_parameters(store: px4params.Store) -> None:
    store.add("INA238#0")
    with pytest.raises(InstanceError, match=r"^rm takes an instance, not a leaf: INA238#0\[4\]$"):
        store.remove("INA238#0[4]")
    with pytest.raises(
        InstanceError, match=r"^SYS_AUTOSTART: a classic parameter has no instances to remove$"
    ):
        store.remove("SYS_AUTOSTART")
    assert store.instances("INA238") == ["INA238#0"]


@pytest.mark.issue40
def test_indexing_takes_an_existing_instance_only(store: px4params.Store) -> None:
    store.add("INA238#0")
    with pytest.raises(
        InstanceError,
        match=r"^store\[\.\.\.\] takes an instance; use store\.get\('INA238#0\[4\]'\)$",
    ):
        store["INA238#0[4]"]
    with pytest.raises(
        InstanceError,
        match=r"^INA238#1: instance does not exist \(add it first: param add\)$",
    ):
        store["INA238#1"]
    assert 5 not in store and None not in store
    assert "INA238#0" in store and "INA238#1" not in store and "NOPE#0" not in store
    assert list(store) == list(store.names())


@pytest.mark.issue40
def test_a_classic_parameter_has_no_leaves(store: px4params.Store) -> None:
    for call in (store.get, store.leaf):
        with pytest.raises(
            InstanceError,
            match=r"^'SYS_AUTOSTART\.x' names no leaf \(expected NAME#N\[k\] or NAME#N\.path\)$",
        ):
            call("SYS_AUTOSTART.x")
    with pytest.raises(InstanceError, match=r"^SYS_AUTOSTART is a classic parameter: it has no "
                       r"leaves$"):  # fmt: skip
        store.leaves("SYS_AUTOSTART")
    with pytest.raises(InstanceError, match=r"^SYS_AUTOSTART is a classic parameter: it has no "
                       r"leaves$"):  # fmt: skip
        store.set("SYS_AUTOSTART.x", 1)
    store.add("INA238#0")
    with pytest.raises(InstanceError, match=r"^'INA238#0' names no leaf"):
        store.leaf("INA238#0")
    with pytest.raises(InstanceError, match=r"^encoded takes an instance or parameter, not a "
                       r"leaf: INA238#0\[4\]$"):  # fmt: skip
        store.encoded("INA238#0[4]")


@pytest.mark.issue40
def test_a_classic_value_that_is_not_a_number_names_the_parameter(store: px4params.Store) -> None:
    with pytest.raises(ClassicParamsError, match=r"^SYS_AUTOSTART: "):
        store.set("SYS_AUTOSTART", "banana")
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(
            ValueRangeError,
            match=rf"^BAT1_CAPACITY: {bad} is not a finite number \(Float: NaN and infinities "
            r"are refused\)$",
        ):
            store.set("BAT1_CAPACITY", bad)
    assert store.get("BAT1_CAPACITY") == -1.0
    store.set("BAT1_CAPACITY", 3.4e38)  # finite, near float32's largest: taken
    assert store.get("BAT1_CAPACITY") == pytest.approx(3.4e38, rel=1e-6)


@pytest.mark.issue40
def test_set_encoded_checks_the_ranges(store: px4params.Store) -> None:
    """Stored bytes go through the same @min/@max check as values (nothing written when
    refused)."""
    store.add("INA238#0")
    data_type = store.data_type("INA238")
    value = store.get("INA238#0")
    value["current"] = 100
    store.set_encoded("INA238#0", data_type.encode(value, tao=False))
    assert store.get("INA238#0.current") == 100
    store.set_encoded("INA238#0", data_type.encode(value, tao=False), default=True)
    assert store.get("INA238#0.current", default=True) == 100
    before = store.encoded("INA238#0")
    bad = dict(value, current=328)  # px/Ina238.1.1.dsdl: current @min 1 @max 327 (a uint10)
    with pytest.raises(ValueRangeError, match=r"^INA238#0\.current: 328 "):
        store.set_encoded("INA238#0", data_type.encode(bad, tao=False))
    assert store.encoded("INA238#0") == before


@pytest.mark.issue40
def test_resetting(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.set_default("INA238#0.current", 150)
    store.set("INA238#0.current", 90)
    store.set("INA238#0.bus.i2c.address", 0x41)
    store.set("SYS_AUTOSTART", 4001)
    store.reset("INA238#0.current")  # one leaf: back to the instance's default
    assert store.get("INA238#0.current") == 150
    assert store.get("INA238#0.bus.i2c.address") == 0x41
    assert store.changed() == ["INA238#0", "SYS_AUTOSTART"]
    assert store.changed("INA238#0") and not store.changed("BAT1_CAPACITY")
    store.set("INA238#0.bus._tag", 1)  # now SPI: the default value is I2C
    with pytest.raises(
        LeafError,
        match=r"\(the default value has another shape: no default for it\)$",
    ):
        store.reset("INA238#0.bus.spi.chip_select")
    store.reset_all()
    assert store.changed() == []
    assert store.instances("INA238") == ["INA238#0"]  # instances stay
    assert store.get("INA238#0.current") == 150
    store.reset_to_initial()
    assert list(store.names()) == ["SYS_AUTOSTART", "BAT1_CAPACITY", "SENS_EXT_I2C_PRB"]
    assert store.get("SYS_AUTOSTART") == 0


def test_resetting_a_leaf_by_index_resets_that_field_not_the_defaults_kth(
    store: px4params.Store,
) -> None:
    # With SPI selected and the default I2C, leaf [5] is bus.spi.max_frequency in the value
    # and current (327) in the default: reset [5] wrote 327 into max_frequency, reset [3] the
    # I2C bus_id into the SPI one, exit 0.
    store.add("INA238#0")
    store.set("INA238#0[1]", 1)
    store.set("INA238#0[5]", 5000)
    before = store.encoded("INA238#0")
    for k, path in ((5, "bus.spi.max_frequency"), (3, "bus.spi.bus_id")):
        with pytest.raises(LeafError) as e:
            store.reset(f"INA238#0[{k}]")
        assert str(e.value) == (
            "INA238#0: bus.spi: this union variant is not the selected one (the default value "
            "has another shape: no default for it)"
        )
        assert path in [leaf.path for leaf in store.leaves("INA238#0")]
    assert store.encoded("INA238#0") == before
    with pytest.raises(LeafError) as e:  # a leaf the value has not: not the default's doing
        store.reset("INA238#0[9]")
    assert str(e.value) == "INA238#0: no leaf [9] (the value has 9 leaves: [0]..[8])"


def test_resetting_a_union_tag_brings_back_the_defaults_variant_with_its_values(
    store: px4params.Store,
) -> None:
    # The tag alone went back: I2C with address 0, where the default's is 0x45.
    store.add("INA238#0")
    store.set_default("INA238#0.bus.i2c.bus_id", 2)
    store.set("INA238#0.bus._tag", 1)
    store.set("INA238#0.current", 100)
    store.reset("INA238#0[1]")
    assert store.get("INA238#0")["bus"] == {"i2c": {"p_version": 0, "bus_id": 2, "address": 0x45}}
    assert store.get("INA238#0.current") == 100  # the rest as it was


def test_switching_a_union_back_to_the_defaults_variant_brings_its_values(
    store: px4params.Store,
) -> None:
    # A pilot who changes their mind: SPI, then I2C again. DSDL's rule alone gave I2C with
    # address 0, a device no bus has; the default's variant is the board's own (0x45).
    store.add("INA238#0")
    store.set_default("INA238#0.bus.i2c.bus_id", 2)
    store.set("INA238#0.bus.i2c.address", 0x46)
    store.set("INA238#0.current", 100)
    store.set("INA238#0.bus._tag", 1)
    assert store.get("INA238#0.bus.spi.chip_select") == 0  # no default for SPI: its zeros
    store.set("INA238#0.bus._tag", 0)
    assert store.get("INA238#0")["bus"] == {"i2c": {"p_version": 0, "bus_id": 2, "address": 0x45}}
    assert store.get("INA238#0.current") == 100  # the rest as it was
    # By index, as MAVLink's INA238_0A and `param set 'INA238#0[1]'` write it.
    store.set("INA238#0[1]", 1)
    store.set("INA238#0[1]", 0)
    assert store.get("INA238#0.bus.i2c.address") == 0x45
    # The tag it already has changes nothing: the address given stays.
    store.set("INA238#0.bus.i2c.address", 0x40)
    store.set("INA238#0.bus._tag", 0)
    assert store.get("INA238#0.bus.i2c.address") == 0x40


def test_a_tag_written_by_index_is_found_in_the_value_not_the_default(tmp_path: Path) -> None:
    # Two unions: the first one's variant moves the second one's tag. The value's [3] is
    # second._tag; the default's [3] is second.a, no tag at all.
    from test_file import acme_store

    files = {
        "First.1.0.dsdl": "@union\nuint8 x\nuint8[2] y\n@sealed\n",
        "Second.1.0.dsdl": "@union\nuint8 a\nuint16 b\n@sealed\n",
        "Pair.1.0.dsdl": (
            "# @param PAIR\n# @max_instances 2\nacme.First.1.0 first\nacme.Second.1.0 second\n"
            "@sealed\n"
        ),
    }
    store = acme_store(tmp_path, files)
    store.add("PAIR#0")
    store.set_default("PAIR#0", {"first": {"x": 1}, "second": {"b": 500}})
    store.set("PAIR#0", {"first": {"y": [1, 2]}, "second": {"a": 3}})
    assert store.leaf("PAIR#0[3]").path == "second._tag"
    store.set("PAIR#0[3]", 1)
    assert store.get("PAIR#0") == {"first": {"y": [1, 2]}, "second": {"b": 500}}


def test_a_union_parameter_switched_back_is_its_default(tmp_path: Path) -> None:
    from test_file import acme_store

    link = "# @param LINK\n# @max_instances 2\n@union\nuint8 serial\nuint16 can\n@sealed\n"
    store = acme_store(tmp_path, {"Link.1.0.dsdl": link})
    store.add("LINK#0")
    store.set_default("LINK#0", {"can": 1000})
    store.set("LINK#0", {"serial": 3})
    store.set("LINK#0._tag", 1)
    assert store.get("LINK#0") == {"can": 1000}
    store.set("LINK#0", {"serial": 3})
    store.set("LINK#0[0]", 1)
    assert store.get("LINK#0") == {"can": 1000}


def test_resetting_an_array_length_brings_back_the_defaults_elements(tmp_path: Path) -> None:
    from test_file import acme_store

    probe = "# @param PROBE\n# @max_instances 2\nuint8 gain\nuint8[<=3] cal\n@sealed\n"
    store = acme_store(tmp_path, {"Probe.1.0.dsdl": probe})
    store.add("PROBE#0")
    store.set_default("PROBE#0", {"gain": 1, "cal": [7]})
    store.set("PROBE#0", {"gain": 4, "cal": [1, 2, 3]})
    length = next(leaf.index for leaf in store.leaves("PROBE#0") if leaf.path == "cal._len")
    store.reset(f"PROBE#0[{length}]")
    assert store.get("PROBE#0") == {"gain": 4, "cal": [7]}


def _with_kept_classic(schema: px4params.Schema, path: Path) -> px4params.Store:
    """A store of one classic parameter that loaded a file of two: BAT1_CAPACITY is kept."""
    full = px4params.Store(schema, classic=CLASSIC)
    full.set("BAT1_CAPACITY", 4200.0)
    full.save(path)
    fewer = px4params.Store(schema, classic=CLASSIC[:1])
    fewer.load_from(path)
    return fewer


@pytest.mark.issue40
def test_reset_to_initial_forgets_kept_classic_records(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    path = tmp_path / "p.store"
    fewer = _with_kept_classic(schema, path)
    fewer.reset_to_initial()
    fewer.save(path)
    assert px4params.Store.load(path, schema, classic=CLASSIC).get("BAT1_CAPACITY") == -1.0


@pytest.mark.issue40
def test_an_instance_view(store: px4params.Store) -> None:
    store.add("INA238#0")
    view = store["INA238#0"]
    assert view.name == "INA238#0"
    view.current = 120
    assert view.value["current"] == 120 and view.default["current"] != 120
    bus = view.bus
    assert bus.i2c.value == store.get("INA238#0")["bus"]["i2c"]
    assert repr(bus.i2c) == f"<INA238#0.bus.i2c {bus.i2c.value!r}>"
    assert repr(view) == f"<INA238#0 {view.value!r}>"
    with pytest.raises(InstanceError, match=r"^INA238#0\.bus\.: set whole values on the instance$"):
        bus.set({})
    with pytest.raises(InstanceError, match=r"^INA238#0\.bus\.: \[k\] counts from the instance$"):
        bus[0]
    with pytest.raises(AttributeError):
        view.__wrapped__  # noqa: B018  (dunder names are Python's, never a field)
    with pytest.raises(LeafError, match="nope"):
        view.nope  # noqa: B018
    assert [leaf.path for leaf in view.leaves()] == [leaf.path for leaf in store.leaves("INA238#0")]
    value = store.get("INA238#0")
    value["current"] = 5
    view.set(value)
    assert store.get("INA238#0.current") == 5


@pytest.mark.issue40
def test_the_store_says_what_it_holds(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.add("INA238#2")
    n = len(store.parameters)
    assert repr(store) == f"<Store 5 instances of {n} parameters>"


@pytest.mark.issue40
def test_a_transaction_interrupted_changes_nothing(store: px4params.Store) -> None:
    store.add("INA238#0")
    before = encode_file(store)
    with pytest.raises(KeyboardInterrupt), store.transaction() as s:
        s.add("INA238#1")
        raise KeyboardInterrupt
    assert encode_file(store) == before
    with store.transaction() as s:
        s.add("INA238#1")
    assert store.instances("INA238") == ["INA238#0", "INA238#1"]


@pytest.mark.issue40
def test_the_flat_name_check_is_remembered_per_schema(
    schema: px4params.Schema, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The destructured names are checked when a store is made; the verdict is kept in the
    cache folder, so that the next store of the same schema and classic names works them out
    only on first use. A schema not loaded through the model cache is checked every time."""
    monkeypatch.setenv("PX4PARAMS_CACHE_DIR", str(tmp_path))
    first = px4params.Store(schema, classic=CLASSIC)
    assert first._destructured is not None  # checked now
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith("flatcheck-")] != []
    second = px4params.Store(schema, classic=CLASSIC)
    assert second._destructured is None  # the verdict was read
    assert second.destructured is not None
    other = px4params.Store(schema, classic=CLASSIC[:1])  # other classic names: checked again
    assert other._destructured is not None
    bare = px4params.Schema(dict(schema.model, key=None))
    for _ in range(2):
        assert px4params.Store(bare, classic=[])._destructured is not None


@pytest.mark.issue40
def test_an_unknown_name_gets_three_hints_at_most(schema: px4params.Schema) -> None:
    store = px4params.Store(schema, classic=[ClassicParam(f"BAT1_{c}", "Int32", 0) for c in "ABCD"])
    with pytest.raises(
        InstanceError,
        match=r"^unknown parameter 'BAT1_X' \(did you mean: BAT1_D, BAT1_C, BAT1_B\?\)$",
    ):
        store.spec("BAT1_X")


@pytest.mark.issue40
def test_the_names_a_store_remembers_are_bounded(store: px4params.Store) -> None:
    """Names can come from anywhere (a GCS, a file): at most 4096 resolutions are kept."""
    for k in range(4097):
        assert f"INA238#0[{k}]" not in store
    assert 0 < len(store._resolved) <= 4096


def _table_store(tmp_path: Path) -> px4params.Store:
    """A store holding TABLE#0: a gain (@max 100) and, last, a variable array of cells (@max 50),
    so that the type's value is kept whole, its length prefix in the bytes."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Table.1.0.dsdl").write_text(
        "# @max_instances 2\nuint4 p_version\nuint8 gain\n# @max 100\n"
        "uint8[<=200] cells\n# @max 50\n@sealed\n"
    )
    store = px4params.Store(px4params.load_schema([str(root)], use_env=False), classic=[])
    store.add("TABLE#0")
    return store


@pytest.mark.issue40
def test_a_type_ending_in_a_variable_array_is_kept_whole(tmp_path: Path) -> None:
    """Values are kept without tail array optimization (docs/store-format.md): the array of a
    type whose last field is a variable-length array keeps its length prefix, and every read,
    write and range check of the store takes the bytes so."""
    store = _table_store(tmp_path)
    assert store.get("TABLE#0") == {"p_version": 0, "gain": 0, "cells": []}
    # 4 + 8 bits, then the length prefix (8 bits for up to 200 cells): 3 bytes, not 2
    assert store.encoded("TABLE#0", default=True) == bytes(3)
    store.set("TABLE#0", {"gain": 5, "cells": [1, 2, 3]})
    # p_version 0, gain 5, length 3, cells 1 2 3 (4-bit offset): the bytes read by hand
    assert store.encoded("TABLE#0") == bytes.fromhex("005030102030")
    assert [(leaf.path, leaf.value) for leaf in store.leaves("TABLE#0")] == [
        ("p_version", 0), ("gain", 5), ("cells._len", 3), ("cells[0]", 1), ("cells[1]", 2),
        ("cells[2]", 3),
    ]  # fmt: skip
    with pytest.raises(ValueRangeError, match=r"^TABLE#0\.cells\[1\]: 51 is above 50 \(@max\)$"):
        store.set("TABLE#0.cells[1]", 51)
    with pytest.raises(ValueRangeError, match=r"^TABLE#0\.cells\[3\]: 60 is above 50 \(@max\)$"):
        store.set("TABLE#0", {"gain": 5, "cells": [1, 2, 3, 60]})
    with pytest.raises(ValueRangeError, match=r"^TABLE#0\.gain: 101 is above 100 \(@max\)$"):
        store.set("TABLE#0.gain", 101)
    store.set("TABLE#0.cells._len", 4)  # a length brings a cell in: its default 0 is in range
    assert store.get("TABLE#0")["cells"] == [1, 2, 3, 0]
    store.set("TABLE#0.cells[3]", 50)
    store.set_encoded("TABLE#0", bytes.fromhex("0050201000"), default=True)
    assert store.get("TABLE#0", default=True)["cells"] == [1, 0]
    assert store.get("TABLE#0")["cells"] == [1, 2, 3, 50]  # a changed value stays


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("call", "name", "message"),
    [
        ("get", "SYS_AUTOSTART#0", "SYS_AUTOSTART is not instanced: write SYS_AUTOSTART, not "
         "SYS_AUTOSTART#0"),
        ("get", "INA238", "INA238 has instances: name one, e.g. INA238#0"),
        ("get", "ZZZZ", "unknown parameter 'ZZZZ'"),
        ("add", "INA238#0[4]", "add takes an instance, not a leaf: INA238#0[4]"),
        ("add", "SYS_AUTOSTART", "SYS_AUTOSTART: a classic parameter has no instances to add"),
    ],
)  # fmt: skip
def test_naming_errors_word_for_word(store: px4params.Store, call, name, message) -> None:
    with pytest.raises(InstanceError) as info:
        getattr(store, call)(name)
    assert str(info.value) == message


@pytest.mark.issue40
def test_a_name_that_is_not_text_is_refused_by_reads_and_writes(store: px4params.Store) -> None:
    """(A list cannot be a key of the store's remembered names: it goes to the parser, which
    refuses it in one line.)"""
    for call in (store.get, store.encoded, store.reset, lambda name: store.set(name, 1)):
        with pytest.raises(InstanceError, match=r"^\['INA238#0'\] is not a parameter name"):
            call(["INA238#0"])


@pytest.mark.issue40
def test_reads_give_the_value_unless_the_default_is_asked_for(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.set("INA238#0.current", 99)
    leaves = {leaf.path: leaf.value for leaf in store.leaves("INA238#0")}
    defaults = {leaf.path: leaf.value for leaf in store.leaves("INA238#0", default=True)}
    assert leaves["current"] == 99 and defaults["current"] != 99
    assert store.encoded("INA238#0") != store.encoded("INA238#0", default=True)
    assert store.data_type("INA238").decode(store.encoded("INA238#0"), tao=False)["current"] == 99
    view = store["INA238#0"].bus
    assert view["i2c.address"] == store.get("INA238#0.bus.i2c.address")  # a path from the view
    with pytest.raises(LeafError) as info:
        store.get("INA238#0.bus")
    assert str(info.value) == "INA238#0: bus: not a leaf (a struct, union or array)"
    with pytest.raises(InstanceError) as info:
        store.changed("INA238#0[4]")
    assert str(info.value) == "changed takes an instance or parameter, not a leaf: INA238#0[4]"


@pytest.mark.issue40
def test_the_leaf_reads_a_store_remembers_are_bounded(tmp_path: Path) -> None:
    """As names, the leaf reads kept to answer the next read in one call are bounded (4096):
    here 4097 distinct names of existing leaves (cells[i] by path, then by [k])."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Big.1.0.dsdl").write_text(
        "# @max_instances 1\nuint4 p_version\nuint8[<=2100] cells\n@sealed\n"
    )
    schema = px4params.load_schema([str(root)], use_env=False)
    store = px4params.Store(schema, classic=[])
    store.add("BIG#0")
    store.set("BIG#0", {"cells": [7] * 2100})
    for i in range(2100):
        assert store.get(f"BIG#0.cells[{i}]") == 7
    for i in range(4097 - 2100):
        assert store.get(f"BIG#0[{i + 2}]") == 7  # [0] p_version, [1] the length
    assert 0 < len(store._leaf_reads) <= 4096


@pytest.mark.issue40
def test_an_int32_whose_bits_spell_a_float_nan_is_a_number(store: px4params.Store) -> None:
    """Only Float classic parameters refuse NaN: an Int32 holds any 32-bit integer, also one
    whose bytes would read as a float NaN (0x7FC00000) or infinity (0x7F800000)."""
    for number in (0x7FC00000, 0x7F800000, -1):
        store.set("SYS_AUTOSTART", number)
        assert store.get("SYS_AUTOSTART") == number


@pytest.mark.issue40
def test_a_tag_or_a_length_brings_leaves_that_are_checked_too(tmp_path: Path) -> None:
    """Selecting a union's variant or growing an array brings leaves in at their defaults:
    those are held to their @min/@max like any written leaf. And only what a write changes is
    checked: a value stored out of range with force stays writable as it is."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Choice.1.0.dsdl").write_text("@union\nuint8 low\nuint8 high\n# @min 1\n@sealed\n")
    (root / "Row.1.0.dsdl").write_text(
        "# @max_instances 1\nuint4 p_version\nChoice.1.0 choice\n"
        "uint8[<=8] cells\n# @min 1\n# @max 50\n@sealed\n"
    )
    schema = px4params.load_schema([str(root)], use_env=False)
    store = px4params.Store(schema, classic=[])
    store.add("ROW#0")
    store.set("ROW#0.cells._len", 0)
    with pytest.raises(
        ValueRangeError, match=r"^ROW#0\.cells\[0\]: 0 is outside 1\.\.50 \(@min/@max\)$"
    ):
        store.set("ROW#0.cells._len", 1)  # a new cell at 0
    with pytest.raises(ValueRangeError, match=r"^ROW#0\.choice\.high: 0 is below 1 \(@min\)$"):
        store.set("ROW#0.choice._tag", 1)  # high, at 0
    assert store.get("ROW#0") == {"p_version": 0, "choice": {"low": 0}, "cells": []}
    store.set("ROW#0", {"choice": {"low": 3}, "cells": [60]}, force=True)
    store.set("ROW#0", {"choice": {"low": 4}, "cells": [60]})  # the cell is not changed
    assert store.get("ROW#0")["cells"] == [60]


@pytest.mark.issue40
def test_set_encoded_sets_the_value_and_leaves_the_default(store: px4params.Store) -> None:
    """Stored bytes given without ``default=True`` are the value (as set is): the default stays."""
    store.add("INA238#0")
    store.set("INA238#0.current", 300)
    data = store.encoded("INA238#0")
    store.reset("INA238#0")
    store.set_encoded("INA238#0", data)
    assert store.get("INA238#0.current") == 300
    assert store.get("INA238#0.current", default=True) == 327  # the type's @default
    store.set_encoded("INA238#0", store.encoded("INA238#0"), default=True)
    assert store.get("INA238#0.current", default=True) == 300


@pytest.mark.issue40
def test_a_saturated_leaf_write_is_held_to_its_range_as_stored(tmp_path: Path) -> None:
    """``saturate`` clamps a number to what its field's type holds (the cast mode "saturated",
    docs/codec.md); the field's @min/@max then still apply to what would be stored (``set``:
    only ``force`` lets them pass). A uint8 cell given 300 would keep 255, above its @max 50:
    refused, nothing written; 40 is kept. The cells are the last field: a type ending in a
    variable array is kept whole, its length prefix in the bytes (docs/store-format.md)."""
    store = _table_store(tmp_path)
    store.set("TABLE#0", {"gain": 5, "cells": [1, 2, 3]})
    for value in (51, 300):
        with pytest.raises(ValueRangeError, match=rf"^TABLE#0\.cells\[1\]: {value} is above 50"):
            store.set("TABLE#0.cells[1]", value, saturate=True)
    with pytest.raises(ValueRangeError, match=r"^TABLE#0\.gain: 300 is above 100 \(@max\)$"):
        store.set("TABLE#0.gain", 300, saturate=True)
    assert store.get("TABLE#0") == {"p_version": 0, "gain": 5, "cells": [1, 2, 3]}
    store.set("TABLE#0.cells[1]", 40, saturate=True)
    store.set("TABLE#0.gain", 300, saturate=True, force=True)  # force: the type's 255 is kept
    assert store.get("TABLE#0") == {"p_version": 0, "gain": 255, "cells": [1, 40, 3]}


def test_a_signed_p_version_holds_the_types_version_as_an_unsigned_one_does(
    tmp_path: Path,
) -> None:
    """SPEC: p_version holds the type's version, whatever its integer kind. A type declaring
    `int4 p_version` (version 3 of Signed.1.3: 0b0011 in the top four bits) is stored, its
    default checked and its value saved and read back like a `uint4` one."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Signed.1.3.dsdl").write_text(
        "# @max_instances 1\nint4 p_version\nuint8 a\n# @default 5\n@sealed\n"
    )
    schema = px4params.load_schema([str(root)], use_env=False)
    store = px4params.Store(schema, classic=[])
    store.add("SIGNED#0")
    assert store.get("SIGNED#0") == {"p_version": 3, "a": 5}
    store.set("SIGNED#0.a", 200)
    # 0011 then 200 = 1100 1000: 0011 1100 | 1000 0000
    assert store.encoded("SIGNED#0") == bytes([0x3C, 0x80])
    saved = tmp_path / "params.bin"
    store.save(saved)
    again = px4params.Store.load(saved, schema, classic=[])
    assert again.get("SIGNED#0") == {"p_version": 3, "a": 200}


@pytest.mark.issue40
def test_a_plain_number_is_checked_against_its_range_without_decoding_the_value(
    store: px4params.Store, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A plain number for a leaf with @min/@max (Ina238.1.1.dsdl: shunt 0.00001..0.1, leaf 6)
    is checked as the leaf would keep it, without the value decoded: by [k], the leaf is looked
    up once and written once; refused by path, it is looked up only to say why."""
    store.add("INA238#0")
    counted = count_core_calls(store, monkeypatch)
    store.set("INA238#0[6]", 0.05)
    assert counted.calls == Counter(get_leaf=1, set_leaf=1)
    counted.calls.clear()
    with pytest.raises(ValueRangeError) as e:
        store.set("INA238#0.shunt", 0.2)
    assert str(e.value) == "INA238#0.shunt: 0.2 is outside 0.00001..0.1 (@min/@max)"
    assert counted.calls == Counter(get_leaf=1)
    assert store.get("INA238#0.shunt") == pytest.approx(0.05, abs=1e-4)  # a float16 of it


@pytest.mark.issue40
def test_an_int_beyond_every_float64_is_refused_in_one_line_not_raised_as_overflow(
    store: px4params.Store,
) -> None:
    """Python's float() of 10**400 raises OverflowError; a store write of it to a float leaf
    (by path, by [k]) is refused as the CLI refuses 1e400, and the store keeps its value."""
    store.add("INA238#0")
    store.set("INA238#0.shunt", 0.05)
    before = store.get("INA238#0.shunt")
    huge = 10**400
    for key, value in (("INA238#0.shunt", huge), ("INA238#0[6]", -huge)):
        with pytest.raises(px4params.Px4ParamsError) as e:
            store.set(key, value)
        message = str(e.value)
        assert "\n" not in message and not isinstance(e.value, OverflowError)
        assert message == (
            f"INA238#0: shunt: value {value} is out of range of a float64 (at most ±1.8e308)"
        )
        assert store.get("INA238#0.shunt") == before


def test_a_copied_store_changes_on_its_own(store: px4params.Store) -> None:
    # copy.copy shared the core's memory: a value set on the copy showed in the original.
    import copy
    import pickle

    from px4params.store import flat

    store.add("INA238#0")
    for copied in (copy.copy(store), copy.deepcopy(store)):
        copied.set("INA238#0.current", 100)
        copied.add("INA238#1")
        assert copied.schema is store.schema
        assert (store.get("INA238#0.current"), store.instances("INA238")) == (327, ["INA238#0"])
        assert copied.instances("INA238") == ["INA238#0", "INA238#1"]
        assert (flat.get_flat(copied, "INA238_0P"), flat.get_flat(store, "INA238_0P")) == (100, 327)
        assert copied.get("INA238#0.current") == copied.get("INA238#0.current") == 100
    with pytest.raises(TypeError) as refused:
        pickle.dumps(store)
    assert str(refused.value) == (
        "a Store is not pickled: save it to a store file (store.save(path)) and load that "
        "(Store.load(path)), or send store.encoded(name) values"
    )


def test_a_copied_store_keeps_the_classic_records_it_was_given(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    import copy

    path = tmp_path / "p.store"
    fewer = _with_kept_classic(schema, path)
    copied = copy.copy(fewer)
    assert copied.kept_classic == ["BAT1_CAPACITY"]
    copied.reset_to_initial()
    assert (copied.kept_classic, fewer.kept_classic) == ([], ["BAT1_CAPACITY"])
