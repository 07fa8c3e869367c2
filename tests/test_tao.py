"""Tail array optimization corner cases, decided as the spec and pydronecan decide them.

The flag passes down only to the last field of a struct, the selected variant of a union and
the last element of an array; elements of a tail-optimized array are encoded without it, and
an array of elements shorter than 8 bits keeps its length prefix.
"""

from __future__ import annotations

import os
from pathlib import Path

import dronecan
import px4params
import pytest
from dronecan import transport
from dronecan_oracle import fill, pack

TYPES = {
    # Corner case 1: the tail array sits in the last field of a nested struct.
    "Inner.uavcan": "uint8 x\nuint8[<=5] tail\n",
    "NestedTail.uavcan": "uint8 a\nInner inner\n",
    # Corner case 2: the tail array is inside the selected variant of a union.
    "Choice.uavcan": "@union\nuint16 number\nuint8[<=7] bytes\n",
    "UnionTail.uavcan": "uint3 a\nChoice choice\n",
    # The last element of a static array gets the flag.
    "ArrayTail.uavcan": "Inner[2] pairs\n",
    # Elements of a tail array lose it; short elements keep the prefix.
    "ElementsLose.uavcan": "Inner[<=3] items\n",
    "ShortElements.uavcan": "uint7 a\nuint4[<=6] nibbles\n",
    "NotLast.uavcan": "uint8[<=4] first\nuint8 last\n",
}

VALUES = {
    "NestedTail": {"a": 1, "inner": {"x": 2, "tail": [3, 4, 5]}},
    "UnionTail": {"a": 5, "choice": {"bytes": [9, 8, 7]}},
    "ArrayTail": {"pairs": [{"x": 1, "tail": [2]}, {"x": 3, "tail": [4, 5]}]},
    "ElementsLose": {"items": [{"x": 1, "tail": [2, 3]}, {"x": 4, "tail": []}]},
    "ShortElements": {"a": 1, "nibbles": [1, 2, 3]},
    "NotLast": {"first": [1, 2], "last": 3},
}

# Bytes worked out by hand from the rules (TAO on), so a shared misreading cannot pass.
EXPECTED_TAO = {
    # 00000001 00000010 | 00000011 00000100 00000101: no 3-bit prefix before 3 4 5
    "NestedTail": "0102030405",
    # 101 | tag 1 | 00001001 00001000 00000111 | pad: 9 8 7 unprefixed inside the variant
    "UnionTail": "b0908070",
    # 00000001 001 00000010 | 00000011 00000100 00000101: only the last element is unprefixed
    "ArrayTail": "0120406080a0",
    # 00000001 010 00000010 00000011 | 00000100 000: the elements keep their inner prefixes
    "ElementsLose": "0140406080",
    # 0000001 | 011 0001 0010 0011: uint4 elements are too short, the prefix stays
    "ShortElements": "02c48c",
    # 010 00000001 00000010 | 00000011: not the last field, prefixed
    "NotLast": "40204060",
}


@pytest.fixture(scope="module")
def corner(tmp_path_factory: pytest.TempPathFactory) -> tuple[px4params.Schema, dict[str, object]]:
    root = tmp_path_factory.mktemp("dsdl") / "corner"
    root.mkdir()
    for name, text in TYPES.items():
        (root / name).write_text(text)
    schema = px4params.load_schema([root], use_env=False, cache_dir=root.parent / "cache")
    theirs = {t.full_name: t for t in dronecan.dsdl.parse_namespaces([os.fspath(root)])}
    return schema, theirs


@pytest.mark.parametrize("name", sorted(VALUES))
@pytest.mark.parametrize("tao", [True, False])
def test_tail_array_rules_match_pydronecan(corner, name: str, tao: bool) -> None:
    schema, theirs = corner
    t = schema[f"corner.{name}"]
    ours = t.encode(VALUES[name], tao=tao)
    assert (
        ours.hex()
        == pack(
            fill(transport.CompoundValue(theirs[f"corner.{name}"]), VALUES[name]), tao=tao
        ).hex()
    )
    assert t.decode(ours, tao=tao) == VALUES[name]


def test_tail_array_rules_by_hand(corner) -> None:
    # The expected bytes above are derived by hand; check the derivations too.
    schema, _ = corner
    got = {name: schema[f"corner.{name}"].encode(v).hex() for name, v in VALUES.items()}
    assert got == EXPECTED_TAO


def test_tao_off_keeps_every_prefix(corner) -> None:
    schema, _ = corner
    t = schema["corner.NestedTail"]
    # 3-bit length prefix 011 before 03 04 05: 01 02 | 011 00000011 00000100 00000101 | pad
    assert t.encode(VALUES["NestedTail"], tao=False).hex() == "0102606080a0"
    assert len(t.encode(VALUES["NestedTail"], tao=False)) == 6


def test_model_path_is_used(corner) -> None:
    schema, _ = corner
    assert Path(schema["corner.NestedTail"].definition["file"]).name == "NestedTail.uavcan"
