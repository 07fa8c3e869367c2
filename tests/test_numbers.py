"""``px4params.numbers``' JSON writer, held to :mod:`json`: it writes by hand what the short
commands print, as importing ``json`` (which imports ``re``) costs ``param show`` or ``decode``
a third of Python's start."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from px4params.errors import NumberError
from px4params.numbers import abbreviated, dump_json, load_json, parse_float, parse_int
from strategies import budget


def _plain() -> st.SearchStrategy[object]:
    scalars = st.one_of(
        st.none(),
        st.booleans(),
        st.integers(),
        st.floats(),  # NaN and infinities too: json's to write
        st.text(max_size=8),  # escapes and non-ASCII too: json's
    )
    return st.recursive(
        scalars,
        lambda inner: st.one_of(
            st.lists(inner, max_size=4),
            st.tuples(inner, inner),
            st.dictionaries(st.one_of(st.text(max_size=6), st.integers()), inner, max_size=4),
        ),
        max_leaves=12,
    )


@settings(max_examples=budget(1000), deadline=None)
@given(_plain(), st.sampled_from([(", ", ": "), (",", ":")]))
def test_json_of_plain_values_is_jsons(value: object, separators: tuple[str, str]) -> None:
    assert dump_json(value, separators) == json.dumps(value, separators=separators)


def test_json_of_a_decoded_value() -> None:
    value = {"uptime_sec": 12345, "health": 0, "voltage": 3.5, "id": [1, 2], "ok": True}
    assert dump_json(value) == json.dumps(value)
    assert dump_json([math.inf, "é"]) == '[Infinity, "\\u00e9"]'
    cycle: list[object] = []
    cycle.append(cycle)
    try:
        dump_json(cycle)
    except ValueError as e:
        assert "Circular reference" in str(e)
    else:
        raise AssertionError("a cycle was written")


# -- numbers bounded before conversion (an outside audit's defects 1 and 8) --------------------


def test_numbers_are_bounded_before_conversion() -> None:
    assert parse_int("0x45", 16) == 0x45 and parse_int("-12") == -12
    assert parse_int("9" * 64) == int("9" * 64)
    with pytest.raises(NumberError, match=r"^999999999999\.\.\.999999 \(5000 characters\) is out"):
        parse_int("9" * 5000)
    with pytest.raises(NumberError, match="65 digits"):
        parse_int("0x" + "f" * 65, 16)
    assert parse_float("inf") == float("inf") and parse_float("1e300") == 1e300
    with pytest.raises(NumberError, match=r"^1e400 is out of range of a float64"):
        parse_float("1e400")
    with pytest.raises(NumberError, match=r'^Infinity is not JSON; write "inf"'):
        load_json('{"x": Infinity}')
    with pytest.raises(NumberError, match=r"^1e400 is out of range"):
        load_json("[1e400]")
    assert load_json('{"x": 1.5, "y": "inf"}') == {"x": 1.5, "y": "inf"}


@pytest.mark.parametrize(
    ("given", "shown"),
    [
        ("15\x000", "15\\x000"),  # a NUL in an airframe line: "'150' is not an integer"
        ("\x1b[2Jx", "\\x1b[2Jx"),  # an escape sequence acted on the terminal
        ("a\tb", "a\\tb"),
        ("é and ü", "é and ü"),  # printable, as given
    ],
)
def test_a_character_that_does_not_print_is_shown_escaped(given: str, shown: str) -> None:
    assert abbreviated(given) == shown
