"""Every error the binding raises of its own (not the core's: those are in test_schema.py,
test_store.py and others) has one message, worded in one place (``errors.rs``): a Python
value that does not fit its field, a call's argument it refuses, a schema model it cannot
compile. Each is checked here word for word, on a small model written out by hand, with the
field's path, the value and what the field takes; and it is one line."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import pytest
from px4params import _native
from px4params.errors import (
    DecodeError,
    EncodeError,
    LeafError,
    StoreFileError,
    TransferError,
    ValueShapeError,
)


def uint(bits: int) -> dict[str, Any]:
    return {"kind": "uint", "bits": bits, "cast": "saturated"}


def struct(*fields: tuple[str, dict[str, Any]], kind: str = "struct") -> dict[str, Any]:
    return {"kind": kind, "version": None, "fields": [{"name": n, "type": t} for n, t in fields]}


def ref(name: str) -> dict[str, Any]:
    return {"kind": "ref", "name": name}


MODEL = {
    "t.S": struct(("x", uint(8))),
    "t.U": struct(("a", uint(8)), ("b", ref("t.S")), kind="union"),
    "t.T": struct(
        ("u8", uint(8)),
        ("i7", {"kind": "int", "bits": 7, "cast": "saturated"}),
        ("f", {"kind": "float", "bits": 16, "cast": "saturated"}),
        ("flag", {"kind": "bool"}),
        ("", {"kind": "void", "bits": 3}),  # padding: no name, as DSDL writes it
        ("u", ref("t.U")),
        ("s", ref("t.S")),
        ("bytes", {"kind": "dynarray", "elem": uint(8), "max": 4}),
    ),
}
SCHEMA = _native.Schema(MODEL)
T = SCHEMA.get("t.T")
GOOD: dict[str, Any] = {
    "u8": 1,
    "i7": -2,
    "f": 0.5,
    "flag": True,
    "u": {"a": 3},
    "s": {"x": 4},
    "bytes": [5],
}


def with_(**changes: Any) -> dict[str, Any]:
    return {**GOOD, **changes}


# (value, exception class, message): one per kind of value error, and per wording of a kind.
VALUE_ERRORS: list[tuple[dict[str, Any], type[Exception], str]] = [
    (with_(u8="7"), ValueShapeError, "t.T: u8: expected an integer, got str"),
    (with_(u8=True), ValueShapeError, "t.T: u8: expected an integer, got bool"),
    (with_(f=True), ValueShapeError, "t.T: f: expected a number, got bool"),
    (with_(f=[1.0]), ValueShapeError, "t.T: f: expected a number, got list"),
    (with_(flag=0.5), ValueShapeError, "t.T: flag: expected a boolean, got float"),
    (
        with_(f=-(10**309)),
        EncodeError,
        f"t.T: f: value {-(10**309)} is out of range of a float64 (at most ±1.8e308)",
    ),
    (with_(s=5), ValueShapeError, "t.T: s: expected a dict (struct), got int"),
    (with_(bytes=5), ValueShapeError, "t.T: bytes: expected a list (array), got int"),
    (with_(bytes={"x": 1}), ValueShapeError, "t.T: bytes: expected a list (array), got dict"),
    (
        with_(f=" Lots "),
        ValueShapeError,
        't.T: f: expected a number (or "nan", "inf", "-inf"), got \'lots\'',
    ),
    # Beyond 64 bits: the binding's own range error (the core's holds 64-bit numbers).
    (
        with_(u8=1 << 70),
        EncodeError,
        "t.T: u8: value 1180591620717411303424 is out of range (expected 0 to 255)",
    ),
    (
        with_(i7=-(1 << 64)),
        EncodeError,
        "t.T: i7: value -18446744073709551616 is out of range (expected -64 to 63)",
    ),
    (
        with_(flag=2),
        EncodeError,
        "t.T: flag: value 2 is out of range (expected a boolean: true, false, 0 or 1)",
    ),
    (
        with_(flag=1 << 80),
        EncodeError,
        "t.T: flag: value 1208925819614629174706176 is out of range "
        "(expected a boolean: true, false, 0 or 1)",
    ),
    (
        with_(colour=1),
        ValueShapeError,
        "t.T: unknown field 'colour' (expected: u8, i7, f, flag, u, s, bytes)",
    ),
    (
        with_(s={"x": 1, 2: 3}),
        ValueShapeError,
        "t.T: s: unknown field 2 (expected: x)",
    ),
    (
        with_(u=[3]),
        ValueShapeError,
        "t.T: u: expected a dict with one key, the union variant (a, b), got list",
    ),
    (
        with_(u={}),
        ValueShapeError,
        "t.T: u: a union takes exactly one variant (a, b), got 0 keys",
    ),
    (
        with_(u={"a": 1, "b": {"x": 1}}),
        ValueShapeError,
        "t.T: u: a union takes exactly one variant (a, b), got 2 keys",
    ),
    (
        with_(u={"c": 1}),
        ValueShapeError,
        "t.T: u: unknown union variant 'c' (expected one of: a, b)",
    ),
    (
        with_(bytes="\ud800"),
        ValueShapeError,
        "t.T: bytes: expected a str encodable as UTF-8 (it has lone surrogates)",
    ),
]


@pytest.mark.parametrize(("value", "cls", "message"), VALUE_ERRORS)
def test_value_errors(value: dict[str, Any], cls: type[Exception], message: str) -> None:
    with pytest.raises(cls) as info:
        T.encode(value)
    assert str(info.value) == message
    assert type(info.value) is cls
    path = message.split(": ")[1] if message.count(": ") > 1 else ""
    if not message.startswith("t.T: unknown field"):
        assert info.value.path == path  # type: ignore[attr-defined]
    assert info.value.bit_offset is None  # type: ignore[attr-defined]


def test_the_good_value_encodes() -> None:
    """The values above are broken one field at a time from this one."""
    assert T.decode(T.encode(GOOD)) == {**GOOD, "f": 0.5}


def test_a_leaf_value_is_worded_as_a_field() -> None:
    data = T.encode(GOOD)
    with pytest.raises(ValueShapeError) as info:
        T.set_leaf(data, "u8", "x")
    assert str(info.value) == "t.T: u8: expected an integer, got str"
    assert info.value.path == "u8"  # type: ignore[attr-defined]
    with pytest.raises(EncodeError) as info:
        T.set_leaf(data, "s.x", 1 << 65)
    assert str(info.value) == (
        "t.T: s.x: value 36893488147419103232 is out of range (expected 0 to 255)"
    )
    # A tag is read as a count (then the core checks it against the variants).
    with pytest.raises(EncodeError) as info:
        T.set_leaf(data, "u._tag", 1 << 70)
    assert str(info.value) == (
        "t.T: u._tag: value 1180591620717411303424 is out of range (expected 0 to 4294967295)"
    )


class Raising(Sequence[int]):
    """A sequence whose length raises: Python's own error goes through as it is."""

    def __getitem__(self, index: Any) -> Any:
        raise AssertionError("not read")

    def __len__(self) -> int:
        raise RuntimeError("no length today")


class BadKey:
    def __repr__(self) -> str:
        raise RuntimeError("no repr today")


def test_python_errors_while_reading_pass_through() -> None:
    with pytest.raises(RuntimeError, match=r"^no length today$"):
        T.encode(with_(bytes=Raising()))
    # Showing the value raised: that error, not a half-worded message.
    with pytest.raises(RuntimeError, match=r"^no repr today$"):
        T.encode(with_(s={"x": 1, BadKey(): 2}))


def test_leaf_targets() -> None:
    data = T.encode(GOOD)
    with pytest.raises(LeafError) as info:
        T.get_leaf(data, -1)
    assert str(info.value) == "no leaf [-1] (leaf indices are 0 and up)"
    with pytest.raises(LeafError) as info:
        T.get_leaf(data, 10**40)
    assert (
        str(info.value) == "no leaf [a number of more than 32 digits] (leaf indices are 0 and up)"
    )
    with pytest.raises(TypeError) as type_info:
        T.get_leaf(data, 1.5)
    assert str(type_info.value) == (
        "a leaf is named by its index [k] (int >= 0) or a path (str), got float"
    )


def test_refused_calls() -> None:
    with pytest.raises(KeyError) as key_info:
        SCHEMA.get("t.Nope")
    assert key_info.value.args == ("t.Nope",)
    with pytest.raises(KeyError):
        SCHEMA.translate("t.S", b"\x01", "t.Nope", b"\x00")
    union = SCHEMA.get("t.U")
    with pytest.raises(TypeError) as info:
        union.decode_struct(union.encode({"a": 1}))
    assert str(info.value) == "t.U: a union has no struct value; decode() gives its one-key dict"
    value = SCHEMA.get("t.S").decode_struct(b"\x07")
    with pytest.raises(AttributeError) as attr_info:
        _ = value.y
    assert str(attr_info.value) == "t.S has no field 'y' (its fields: x)"


def test_store_arguments() -> None:
    with pytest.raises(ValueError) as info:
        _native.Store(SCHEMA, [("P", "t.Nope", None)])
    assert str(info.value) == "parameter P: unknown type t.Nope"
    with pytest.raises(ValueError) as info:
        _native.Store(SCHEMA, [("P", "t.S", 0)])
    assert str(info.value) == "parameter P: max_instances must be at least 1"
    store = _native.Store(SCHEMA, [("P", "t.S", 2)])
    other = _native.Store(SCHEMA, [("Q", "t.S", 2)])
    with pytest.raises(ValueError) as info:
        store.restore(other)
    assert str(info.value) == "restore takes a copy of this store (same schema and parameters)"
    store.restore(store.copy())


MODEL_ERRORS: list[tuple[dict[str, Any], str]] = [
    ({"t.A": {"kind": "struct", "fields": [{"name": "x"}]}}, "schema model: t.A has no 'type'"),
    ({"t.A": {"fields": []}}, "schema model: t.A has no 'kind'"),
    ({"t.A": struct(("x", {"kind": "uint"}))}, "schema model: t.A.x has no 'bits'"),
    ({"t.A": struct(("me", ref("t.A")))}, "schema model: type t.A contains itself"),
    ({"t.A": struct(("b", ref("t.B")))}, "schema model: unknown type t.B"),
    (
        {"t.A": struct(("x", {"kind": "complex"}))},
        "schema model: t.A.x: unknown type kind 'complex'",
    ),
    ({"t.A": struct(("x", uint(99)))}, "schema model: t.A.x: bit length 99 is out of range"),
    (
        {"t.A": struct(("x", {"kind": "float", "bits": 8}))},
        "schema model: t.A.x: float8 does not exist (expected float16, float32 or float64)",
    ),
    (
        {"t.A": struct(("only", uint(8)), kind="union")},
        "schema model: t.A: a union needs at least two variants",
    ),
]


@pytest.mark.parametrize(("model", "message"), MODEL_ERRORS)
def test_model_errors(model: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError) as info:
        _native.Schema(model)
    assert str(info.value) == message


def test_batch_items_are_named() -> None:
    with pytest.raises(ValueShapeError) as info:
        T.encode_many([GOOD, with_(u8="7")])
    assert str(info.value) == "item 1: t.T: u8: expected an integer, got str"
    assert info.value.index == 1
    with pytest.raises(DecodeError) as decode_info:
        T.decode_many([T.encode(GOOD), b""])
    assert str(decode_info.value).startswith("item 1: t.T: u8: data is truncated")
    # Not px4params' own: told by a note.
    with pytest.raises(RuntimeError) as other:
        T.encode_many([GOOD, with_(bytes=Raising())])
    assert other.value.__notes__ == ["(item 1 of the batch)"]


def test_file_and_transfer_errors_keep_the_cores_words() -> None:
    """Worded by the core (its own tests check the words): raised here as one line, with the
    file's place where the class has one."""
    with pytest.raises(StoreFileError) as info:
        _native.check_store_file(b"nope", "f.bin")
    assert info.value.args[1:] == ("f.bin", 0)
    assert "\n" not in str(info.value)
    with pytest.raises(TransferError) as transfer_info:
        _native.reassemble([b""], signature=0)
    assert str(transfer_info.value) and "\n" not in str(transfer_info.value)
