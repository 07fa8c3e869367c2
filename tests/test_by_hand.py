"""What the short commands do by hand, held to the modules they do without: importing ``re``
(or ``json``, which imports it) costs ``param show`` or ``decode`` a third of Python's start."""

from __future__ import annotations

import json
import math
import re

from hypothesis import example, given, settings
from hypothesis import strategies as st
from px4params.numbers import dump_json
from px4params.store.key import _KEY, Key, _split_key
from strategies import budget

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
def test_names_are_split_as_the_expression_matches(text: str) -> None:
    match = re.fullmatch(_KEY, text)
    expected = match.group("name", "instance", "index", "path") if match else None
    assert _split_key(text) == expected


def test_a_name_is_parsed_once_into_its_parts() -> None:
    assert Key.parse("INA238#2[4]") == Key("INA238", 2, 4)
    assert Key.parse("INA238#0.bus.i2c.address") == Key("INA238", 0, "bus.i2c.address")
    assert Key.parse("SYS_AUTOSTART") == Key("SYS_AUTOSTART", None, None)


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
