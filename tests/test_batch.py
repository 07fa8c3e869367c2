"""Batch calls: ``encode_many`` and ``decode_many`` give exactly what ``encode`` and ``decode``
give item by item (bytes, values, and the first failure's class and message, told which item
failed), over lists, tuples and any other iterable."""

from __future__ import annotations

from typing import Any

import px4params
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import budget, value_strategy
from test_plain_path import Sneaky, spoiled

SCHEMA = px4params.load_schema(use_env=False)
TYPES = SCHEMA.model["types"]
KEYS = sorted(k for k, d in TYPES.items() if d["kind"] in ("struct", "union"))
NODE_STATUS = SCHEMA["uavcan.protocol.NodeStatus"]
STATUS = {"uptime_sec": 1, "health": 0, "mode": 0, "sub_mode": 0, "vendor_specific_status_code": 7}


def one_by_one(call: Any, items: list[Any], **options: Any) -> tuple[str, str]:
    """What calling ``call`` on each item gives: the results (as their ``repr``, which NaNs
    compare equal in), or the first failure as the batch words it."""
    results = []
    for i, item in enumerate(items):
        try:
            results.append(call(item, **options))
        except px4params.CodecError as e:
            return (type(e).__name__, f"item {i}: {e}")
    return ("results", repr(results))


def batched(call: Any, items: Any, **options: Any) -> tuple[str, str]:
    try:
        return ("results", repr(call(items, **options)))
    except px4params.CodecError as e:
        return (type(e).__name__, str(e))


@pytest.mark.parametrize("key", KEYS)
@settings(max_examples=budget(4), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data(), tao=st.booleans(), saturate=st.booleans())
def test_a_batch_gives_what_single_calls_give(
    key: str, data: st.DataObject, tao: bool, saturate: bool
) -> None:
    t = SCHEMA[key]
    # Values of different lengths one after another, so that the batch's one output buffer is
    # reused over a longer value's bytes; sometimes one of them broken.
    values = data.draw(st.lists(value_strategy(TYPES, key, infinities=False), max_size=5))
    if values and data.draw(st.booleans()):
        at = data.draw(st.integers(0, len(values) - 1))
        how, key_index = data.draw(st.integers(0, 9)), data.draw(st.integers(0, 50))
        values[at] = spoiled(values[at], how, key_index)
    options = {"tao": tao, "saturate": saturate}
    expected = one_by_one(t.encode, values, **options)
    assert batched(t.encode_many, values, **options) == expected
    assert batched(t.encode_many, tuple(values), **options) == expected
    assert batched(t.encode_many, iter(values), **options) == expected
    if expected[0] != "results":
        return
    # The bytes back, some of them cut short or with a byte after them.
    items = [t.encode(v, **options) for v in values]
    if items and data.draw(st.booleans()):
        at = data.draw(st.integers(0, len(items) - 1))
        items[at] = items[at][:-1] if data.draw(st.booleans()) else items[at] + b"\x00"
    decode_options = {"tao": tao, "allow_trailing": data.draw(st.booleans())}
    expected = one_by_one(t.decode, items, **decode_options)
    assert batched(t.decode_many, items, **decode_options) == expected
    assert batched(t.decode_many, (bytearray(b) for b in items), **decode_options) == expected


def test_the_failing_item_is_named_in_the_message_and_the_index() -> None:
    bad = dict(STATUS, health=9)
    with pytest.raises(px4params.EncodeError) as raised:
        NODE_STATUS.encode_many([STATUS, STATUS, bad, bad])
    assert str(raised.value) == (
        "item 2: uavcan.protocol.NodeStatus: health: value 9 is out of range (expected 0 to 3)"
    )
    assert (raised.value.index, raised.value.path) == (2, "health")
    missing = {k: v for k, v in STATUS.items() if k != "mode"}
    with pytest.raises(px4params.ValueShapeError, match=r"^item 1: .*: mode: missing field$"):
        NODE_STATUS.encode_many(iter([STATUS, missing]))
    good = NODE_STATUS.encode(STATUS)
    with pytest.raises(px4params.DecodeError) as raised:
        NODE_STATUS.decode_many([good, good[:3]])
    assert str(raised.value) == (
        "item 1: uavcan.protocol.NodeStatus: uptime_sec: data is truncated: needs at least 32 "
        "bits, has 24 (at bit 0)"
    )
    assert raised.value.index == 1
    # A single call's error has no index.
    with pytest.raises(px4params.DecodeError) as raised:
        NODE_STATUS.decode(good[:3])
    assert raised.value.index is None


def test_errors_not_of_the_codec_get_a_note_naming_the_item() -> None:
    with pytest.raises(TypeError, match="cannot convert 'int' object to bytes") as raised:
        NODE_STATUS.decode_many([NODE_STATUS.encode(STATUS), 5])
    assert raised.value.__notes__ == ["(item 1 of the batch)"]
    with pytest.raises(TypeError, match="'int' object is not iterable"):
        NODE_STATUS.encode_many(5)

    def broken_iterable() -> Any:
        yield STATUS
        raise RuntimeError("the source broke")

    with pytest.raises(RuntimeError, match="the source broke"):
        NODE_STATUS.encode_many(broken_iterable())


def test_empty_batches_and_batches_of_one() -> None:
    assert NODE_STATUS.encode_many([]) == []
    assert NODE_STATUS.decode_many(()) == []
    data = NODE_STATUS.encode(STATUS)
    assert NODE_STATUS.encode_many([STATUS]) == [data]
    assert NODE_STATUS.decode_many([memoryview(data)]) == [STATUS]


def test_a_list_emptied_while_its_items_are_encoded_is_survived() -> None:
    # Item 1's field look-up runs Python code that empties the batch's list.
    values: list[Any] = []
    value: dict[Any, Any] = {}
    sneaky = Sneaky("mode", values.clear)
    value[sneaky] = 1
    value.update(STATUS)
    values.extend([STATUS, value, STATUS])
    sneaky.armed = True
    with pytest.raises(px4params.ValueShapeError, match=r"^item 1: .*unknown field"):
        NODE_STATUS.encode_many(values)
    assert values == []
