"""``DataType.encode`` and ``decode`` called with the value alone take a short path into the
codec; every other call goes through the full argument parsing. Both give the same bytes,
values and errors, the methods keep their signatures and documentation, and the short path
leaks no references."""

from __future__ import annotations

import inspect
import sys
from typing import Any

import px4params
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from px4params import _native
from strategies import budget, value_strategy
from test_native_plain_path import spoiled

SCHEMA = px4params.load_schema(use_env=False)
TYPES = SCHEMA.model["types"]
KEYS = sorted(k for k, d in TYPES.items() if d["kind"] in ("struct", "union"))
NODE_STATUS = SCHEMA["uavcan.protocol.NodeStatus"]
STATUS = {"uptime_sec": 1, "health": 0, "mode": 0, "sub_mode": 0, "vendor_specific_status_code": 7}


def outcome(call: Any, *args: Any, **options: Any) -> tuple[str, str]:
    """What a call gives: its result's ``repr`` (NaNs compare equal), or its error."""
    try:
        return ("result", repr(call(*args, **options)))
    except Exception as e:  # the class and message are what is compared
        return (type(e).__name__, str(e))


@pytest.mark.parametrize("key", KEYS)
@settings(max_examples=budget(6), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_the_short_path_gives_what_the_full_one_gives(key: str, data: st.DataObject) -> None:
    t = SCHEMA[key]
    value = data.draw(value_strategy(TYPES, key, infinities=False))
    if data.draw(st.booleans()):
        value = spoiled(value, data.draw(st.integers(0, 9)), data.draw(st.integers(0, 50)))
    # Passing the defaults by keyword takes the full path.
    encoded = outcome(t.encode, value)
    assert encoded == outcome(t.encode, value, tao=True, saturate=False)
    if encoded[0] != "result":
        return
    raw = t.encode(value, tao=True)
    for item in (raw, raw[:-1], raw + b"\x00", bytearray(raw), memoryview(raw)):
        assert outcome(t.decode, item) == outcome(t.decode, item, tao=True, allow_trailing=False)


def test_keywords_and_positions_are_taken_as_before() -> None:
    t = NODE_STATUS
    data = t.encode(STATUS)
    assert t.encode(STATUS, tao=False) == t.encode(value=STATUS) == data
    assert t.encode({**STATUS, "health": 9}, saturate=True) == t.encode({**STATUS, "health": 3})
    assert t.decode(data + b"\x00", allow_trailing=True) == t.decode(data=data) == STATUS
    # The class's own attribute, called with the instance first.
    assert _native.DataType.encode(t, STATUS) == data
    assert _native.DataType.decode(t, data, tao=False) == STATUS


ENCODE, DECODE = NODE_STATUS.encode, NODE_STATUS.decode
WRONG_CALLS = [
    (lambda: ENCODE(), "DataType.encode() missing 1 required positional argument: 'value'"),
    (lambda: DECODE(), "DataType.decode() missing 1 required positional argument: 'data'"),
    (lambda: ENCODE(STATUS, 1), "DataType.encode() takes 1 positional arguments but 2 were given"),
    (lambda: ENCODE(STATUS, crc=1), "DataType.encode() got an unexpected keyword argument 'crc'"),
    (lambda: DECODE(b"", tao=1), "'int' object is not an instance of 'bool'"),
    (lambda: DECODE(5), "cannot convert 'int' object to bytes"),
    (
        lambda: _native.DataType.encode(5, STATUS),
        "descriptor 'encode' for 'px4params._native.DataType' objects doesn't apply to a 'int'",
    ),
]


@pytest.mark.parametrize(("call", "message"), WRONG_CALLS)
def test_wrong_calls_raise_type_errors_naming_the_method(call: Any, message: str) -> None:
    with pytest.raises(TypeError) as raised:
        call()
    assert message in str(raised.value)


def test_signatures_and_documentation_are_kept() -> None:
    encode, decode = _native.DataType.encode, _native.DataType.decode
    assert str(inspect.signature(encode)) == "(self, /, value, *, tao=True, saturate=False)"
    assert str(inspect.signature(decode)) == "(self, /, data, *, tao=True, allow_trailing=False)"
    assert encode.__doc__.startswith("Encodes ``value`` (a dict; see the class) to bytes.")
    assert decode.__doc__.startswith("Decodes ``data`` (bytes, or anything ``bytes()`` takes)")
    assert (encode.__name__, decode.__name__) == ("encode", "decode")


def test_no_references_are_leaked_or_lost() -> None:
    data = NODE_STATUS.encode(STATUS)
    bad = {**STATUS, "health": 9}
    buffer = bytearray(data)
    before = [sys.getrefcount(x) for x in (NODE_STATUS, STATUS, data, bad, buffer)]
    for _ in range(1000):
        NODE_STATUS.encode(STATUS)
        NODE_STATUS.decode(data)
        NODE_STATUS.decode(buffer)
        with pytest.raises(px4params.EncodeError):
            NODE_STATUS.encode(bad)
        with pytest.raises(px4params.DecodeError):
            NODE_STATUS.decode(data[:3])
    after = [sys.getrefcount(x) for x in (NODE_STATUS, STATUS, data, bad, buffer)]
    assert after == before
