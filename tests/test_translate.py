"""Translation of stored values between minor versions of a type (``px4params_core::translate``,
run by ``param load`` and by firmware): checked against a reference written here from the
documented rules (docs/store-format.md, "Type versions"), over values hypothesis draws."""

from __future__ import annotations

from typing import Any

import px4params
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from px4params.errors import StoreError
from strategies import budget

# Version 1.1 moves, adds, drops and changes fields of 1.0 in every way the rules cover.
# (pydsdl wants the minor versions of a major version to be equally long: hence the voids.)
TYPES = {
    "Bus.1.0.dsdl": "@union\nuint8 i2c\nuint16 spi\nbool can\n@sealed\n",
    "Link.1.0.dsdl": "@union\nuint8 i2c\nbool can\nuint32 serial\n@sealed\n",
    "Inner.1.0.dsdl": "uint8 x\nuint8 y\n@sealed\n",
    "Inner2.1.0.dsdl": "uint8 x\nuint8 z\nuint8 y\n@sealed\n",
    "Evolve.1.0.dsdl": (
        "uint4 p_version\nuint8 a\nuint16 gone\ntst.Bus.1.0 bus\nuint8[<=4] arr\n"
        "float16 kind_changes\ntst.Inner.1.0 inner\nuint3[2] fixed\nvoid24\n@sealed\n"
    ),
    "Evolve.1.1.dsdl": (
        "uint4 p_version\ntst.Inner2.1.0 inner\nuint8 a\ntst.Link.1.0 bus\nuint8[<=4] arr\n"
        "tst.Inner.1.0 kind_changes\nuint16 added\nuint3[2] fixed\n@sealed\n"
    ),
}
OLD, NEW = "tst.Evolve.1.0", "tst.Evolve.1.1"
TYPES["Narrow.1.0.dsdl"] = "uint4 p_version\nuint8 n\n@sealed\n"
TYPES["Narrow.1.1.dsdl"] = "uint4 p_version\nuint4 n\nvoid4\n@sealed\n"


@pytest.fixture(scope="module")
def schema(tmp_path_factory: pytest.TempPathFactory) -> px4params.Schema:
    base = tmp_path_factory.mktemp("translate")
    root = base / "tst"
    root.mkdir()
    for name, text in TYPES.items():
        (root / name).write_text(text)
    return px4params.load_schema(
        [root], include_dronecan=False, use_env=False, cache_dir=base / "cache"
    )


# -- the reference ------------------------------------------------------------------------------


def shape(spec: dict[str, Any], schema: px4params.Schema) -> str:
    if spec["kind"] == "ref":
        return schema.model["types"][spec["name"]]["kind"]  # "struct" or "union"
    return "array" if spec["kind"] in ("array", "dynarray") else "scalar"


def reference(
    schema: px4params.Schema, key_old: str, key_new: str, old: Any, base: Any, prefix: str = ""
) -> tuple[Any, list[tuple[str, str]]]:
    """The documented rules, on decoded values: fields by name in the new type's order; a field
    of another kind of value is dropped; a union keeps a variant of the same name and kind;
    arrays whole; what the old struct has and the new lacks is dropped where it ends."""
    types = schema.model["types"]
    new_def, old_def = types[key_new], types[key_old]
    new_fields = {f["name"]: f["type"] for f in new_def["fields"] if f["type"]["kind"] != "void"}
    old_fields = {f["name"]: f["type"] for f in old_def["fields"] if f["type"]["kind"] != "void"}
    changes: list[tuple[str, str]] = []
    if new_def["kind"] == "union":
        ((variant, inner),) = old.items()
        same = variant in new_fields and shape(new_fields[variant], schema) == shape(
            old_fields[variant], schema
        )
        if not same:
            return base, [("dropped", f"{prefix}{variant}")]
        if new_fields[variant]["kind"] == "ref":
            start = base.get(variant) if isinstance(base, dict) else None
            sub_base = (
                start
                if start is not None
                else schema[new_fields[variant]["name"]].decode(
                    schema[new_fields[variant]["name"]].default(tao=False), tao=False
                )
            )
            value, sub = reference(
                schema, old_fields[variant]["name"], new_fields[variant]["name"], inner,
                sub_base, f"{prefix}{variant}.",
            )  # fmt: skip
            return {variant: value}, sub
        return {variant: inner}, [("kept", f"{prefix}{variant}")]
    out = dict(base)
    for name, spec in new_fields.items():
        if name == "p_version":
            continue
        path = f"{prefix}{name}"
        if name not in old_fields:
            changes.append(("new", path))
        elif shape(spec, schema) != shape(old_fields[name], schema):
            changes.append(("dropped", path))
        elif spec["kind"] == "ref":
            out[name], sub = reference(
                schema, old_fields[name]["name"], spec["name"], old[name], base[name], f"{path}."
            )
            changes += sub
        else:
            out[name] = old[name]
            changes.append(("kept", path))
    for name in old_fields:
        if name not in new_fields and name != "p_version":
            changes.append(("dropped", f"{prefix}{name}"))
    return out, changes


# -- values -------------------------------------------------------------------------------------

u8 = st.integers(0, 255)
old_values = st.fixed_dictionaries(
    {
        "a": u8,
        "gone": st.integers(0, 0xFFFF),
        "bus": st.one_of(
            st.builds(lambda v: {"i2c": v}, u8),
            st.builds(lambda v: {"spi": v}, st.integers(0, 0xFFFF)),
            st.builds(lambda v: {"can": v}, st.booleans()),
        ),
        "arr": st.lists(u8, max_size=4),
        "kind_changes": st.sampled_from([0.0, 1.5, -2.25]),
        "inner": st.fixed_dictionaries({"x": u8, "y": u8}),
        "fixed": st.lists(st.integers(0, 7), min_size=2, max_size=2),
    }
)
base_values = st.fixed_dictionaries(
    {
        "inner": st.fixed_dictionaries({"x": u8, "z": u8, "y": u8}),
        "a": u8,
        "bus": st.one_of(
            st.builds(lambda v: {"i2c": v}, u8),
            st.builds(lambda v: {"serial": v}, st.integers(0, 2**32 - 1)),
        ),
        "arr": st.lists(u8, max_size=4),
        "kind_changes": st.fixed_dictionaries({"x": u8, "y": u8}),
        "added": st.integers(0, 0xFFFF),
        "fixed": st.lists(st.integers(0, 7), min_size=2, max_size=2),
    }
)


@settings(max_examples=budget(300), deadline=None)
@given(old=old_values, base=base_values)
def test_translation_follows_the_rules(schema: px4params.Schema, old: Any, base: Any) -> None:
    old_bytes = schema[OLD].encode(old, tao=False)
    base_bytes = schema[NEW].encode(base, tao=False)
    data, changes = schema._native.translate(OLD, old_bytes, NEW, base_bytes)
    expected, expected_changes = reference(schema, OLD, NEW, {**old, "p_version": 0}, base)
    got = schema[NEW].decode(data, tao=False)
    assert got["p_version"] == 1
    del got["p_version"]
    expected.pop("p_version", None)
    assert got == expected
    assert changes == expected_changes


def test_the_documented_example(schema: px4params.Schema) -> None:
    old = {"a": 7, "gone": 500, "bus": {"spi": 3}, "arr": [1, 2], "kind_changes": 1.5,
           "inner": {"x": 1, "y": 2}, "fixed": [1, 2]}  # fmt: skip
    base = {"inner": {"x": 0, "z": 9, "y": 0}, "a": 0, "bus": {"serial": 5}, "arr": [],
            "kind_changes": {"x": 4, "y": 4}, "added": 77, "fixed": [0, 0]}  # fmt: skip
    data, changes = schema._native.translate(
        OLD, schema[OLD].encode(old, tao=False), NEW, schema[NEW].encode(base, tao=False)
    )
    assert schema[NEW].decode(data, tao=False) == {
        "p_version": 1, "inner": {"x": 1, "z": 9, "y": 2}, "a": 7, "bus": {"serial": 5},
        "arr": [1, 2], "kind_changes": {"x": 4, "y": 4}, "added": 77, "fixed": [1, 2],
    }  # fmt: skip
    assert changes == [
        ("kept", "inner.x"), ("new", "inner.z"), ("kept", "inner.y"), ("kept", "a"),
        ("dropped", "bus.spi"), ("kept", "arr"), ("dropped", "kind_changes"), ("new", "added"),
        ("kept", "fixed"), ("dropped", "gone"),
    ]  # fmt: skip


def test_an_old_value_that_does_not_fit_the_new_field_is_refused(
    schema: px4params.Schema,
) -> None:
    old = schema["tst.Narrow.1.0"].encode({"n": 200}, tao=False)
    base = schema["tst.Narrow.1.1"].default(tao=False)
    with pytest.raises(StoreError, match=r"^n: value 200 is out of range \(expected 0 to 15\)$"):
        schema._native.translate("tst.Narrow.1.0", old, "tst.Narrow.1.1", base)
    fits = schema["tst.Narrow.1.0"].encode({"n": 9}, tao=False)
    data, changes = schema._native.translate("tst.Narrow.1.0", fits, "tst.Narrow.1.1", base)
    assert schema["tst.Narrow.1.1"].decode(data, tao=False) == {"p_version": 1, "n": 9}
    assert changes == [("kept", "n")]


def test_unreadable_old_data_and_unknown_types_are_refused(schema: px4params.Schema) -> None:
    old = schema[OLD].encode(
        {"a": 1, "gone": 0, "bus": {"i2c": 1}, "arr": [], "kind_changes": 0.0,
         "inner": {"x": 0, "y": 0}, "fixed": [0, 0]},
        tao=False,
    )  # fmt: skip
    with pytest.raises(StoreError, match="the stored value cannot be read"):
        schema._native.translate(OLD, old[:4], NEW, schema[NEW].default(tao=False))
    with pytest.raises(KeyError):
        schema._native.translate("tst.Nope.1.0", old, NEW, b"")
