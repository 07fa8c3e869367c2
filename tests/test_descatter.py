"""Decoding from a payload in pieces equals decoding it joined, for every bundled type."""

from __future__ import annotations

import itertools

import px4params
import pytest
from dronecan_oracle import same
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import budget, value_strategy

SCHEMA = px4params.load_schema(use_env=False)
KEYS = sorted(SCHEMA.model["types"])


def _pieces(data: bytes, cuts: list[int]) -> list[bytes]:
    points = sorted({c % (len(data) + 1) for c in cuts})
    return [data[a:b] for a, b in itertools.pairwise([0, *points, len(data)])]


@pytest.mark.parametrize("key", KEYS)
@settings(max_examples=budget(10), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), cuts=st.lists(st.integers(0, 10_000), max_size=12), tao=st.booleans())
def test_fragments_decode_like_flat(
    key: str, data: st.DataObject, cuts: list[int], tao: bool
) -> None:
    t = SCHEMA[key]
    value = data.draw(value_strategy(SCHEMA.model["types"], key))
    encoded = t.encode(value, tao=tao)
    pieces = _pieces(encoded, cuts)
    assert b"".join(pieces) == encoded
    assert same(t.decode_fragments(pieces, tao=tao), t.decode(encoded, tao=tao))


@given(data=st.binary(max_size=60), cuts=st.lists(st.integers(0, 100), max_size=8))
@settings(max_examples=budget(300), deadline=None)
def test_bad_fragments_fail_like_flat(data: bytes, cuts: list[int]) -> None:
    t = SCHEMA["px.Ina238"]
    try:
        flat = t.decode(data)
    except px4params.DecodeError as e:
        with pytest.raises(px4params.DecodeError) as info:
            t.decode_fragments(_pieces(data, cuts))
        assert str(info.value) == str(e)
    else:
        assert same(t.decode_fragments(_pieces(data, cuts)), flat)
