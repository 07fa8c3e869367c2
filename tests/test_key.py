"""A name is a ``Key`` all the way down (``px4params.store.key``): parsed once where it enters,
passed down as the key, text again only where it is shown; and a write looks its leaf up once.

The leaf numbers are read off ``px.Ina238`` by hand: ``[0]`` p_version, ``[1]`` bus._tag,
``[2]`` bus.i2c.p_version, ``[3]`` bus.i2c.bus_id, ``[4]`` bus.i2c.address, ``[5]`` current,
``[6]`` shunt (the SPEC's talk: ``INA238_1C`` is ``INA238#1[4]``, the I2C address)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import px4params
import pytest
from core_calls import CountingCore, count_core_calls
from px4params.errors import InstanceError
from px4params.store import flat
from px4params.store.key import MAX_LEAF, Key


@pytest.fixture
def store() -> px4params.Store:
    store = px4params.Store(px4params.load_schema(use_env=False), classic=[])
    store.add("INA238#1")
    return store


def test_a_key_names_a_leaf_of_its_instance() -> None:
    instance = Key.parse("INA238#1")
    assert instance.at(4) == Key("INA238", 1, 4) == Key.parse("INA238#1[4]")
    assert instance.at("bus.i2c.address") == Key.parse("INA238#1.bus.i2c.address")
    assert instance.at("cells[3].volts") == Key("INA238", 1, "cells[3].volts")
    assert Key.parse("INA238#1[4]").whole == instance
    assert instance.whole is instance
    assert str(Key.parse("INA238_SHARED").at(2)) == "INA238_SHARED[2]"


@pytest.mark.parametrize(
    ("leaf", "message"),
    [
        (-1, r"^'INA238#1\[-1\]' is not a parameter name \(expected NAME, NAME#N"),
        (1 << 40, r"^INA238#1\[1099511627776\]: no leaf \[1099511627776\]$"),
        ("bus i2c", r"^'INA238#1\.bus i2c' is not a parameter name"),
        ("", r"^'INA238#1\.' is not a parameter name"),
        ("1st", r"^'INA238#1\.1st' is not a parameter name"),
    ],
)
def test_a_leaf_that_no_name_could_hold_is_refused_as_parse_refuses_it(
    leaf: Any, message: str
) -> None:
    with pytest.raises(InstanceError, match=message):
        Key.parse("INA238#1").at(leaf)


def test_a_key_is_shown_as_its_name_with_a_format_spec() -> None:
    key = Key.parse("INA238#1[4]")
    assert f"{key:<14}|" == "INA238#1[4]   |"
    assert f"{key}" == "INA238#1[4]"


def test_the_store_lists_its_instances_as_keys(store: px4params.Store) -> None:
    store.add("INA238#3")
    keys = [k for k in store.instance_keys() if k.param == "INA238"]
    assert keys == [Key("INA238", 1, None), Key("INA238", 3, None)]
    assert list(store.instance_keys("INA238")) == keys
    assert [str(k) for k in store.instance_keys()] == list(store.names())


def test_a_flat_parameter_carries_its_leaf_as_a_key(store: px4params.Store) -> None:
    found = flat.flat_map(store).find("INA238_1C")
    assert found.instance == Key("INA238", 1, None)
    assert found.leaf == Key("INA238", 1, 4)
    assert found.target == Key("INA238", 1, "bus.i2c.address")
    assert found.as_dict()["leaf"] == "INA238#1[4]"  # text again where it is shown
    assert flat.resolve_flat(store, "INA238_1C") == "INA238#1[4]"


@pytest.fixture
def counted(store: px4params.Store, monkeypatch: pytest.MonkeyPatch) -> CountingCore:
    counting = count_core_calls(store, monkeypatch)
    parsed: list[str] = []
    original = Key.parse.__func__  # type: ignore[attr-defined]

    def parse(cls: type[Key], text: str | Key) -> Key:
        if not isinstance(text, Key):
            parsed.append(text)
        return original(cls, text)

    monkeypatch.setattr(Key, "parse", classmethod(parse))
    counting.parsed = parsed  # type: ignore[attr-defined]
    return counting


def test_a_write_by_path_looks_its_leaf_up_once(
    store: px4params.Store, counted: CountingCore
) -> None:
    store.set("INA238#1.current", 100)  # a leaf with @min/@max: checked without the core
    assert counted.calls == Counter(set_leaf=1)
    assert store.get("INA238#1.current") == 100


def test_a_write_of_a_union_tag_by_path_looks_its_leaf_up_once(
    store: px4params.Store, counted: CountingCore
) -> None:
    # The tag brings SPI's leaves in: the value is read once to check them, the tag found
    # and written once (its path needs no asking the core which leaf it is). The default's tag
    # is read first: a switch to the default's variant takes the default's values there.
    store.set(Key("INA238", 1, "bus._tag"), 1)
    assert counted.calls == Counter(get=1, set_leaf=1, get_leaf_value=1)
    assert list(store.get("INA238#1")["bus"]) == ["spi"]


def test_a_write_of_a_key_parses_no_text(store: px4params.Store, counted: CountingCore) -> None:
    instance = Key("INA238", 1, None)  # (as a page or a file line parsed it, at the edge)
    store.set(instance.at("shunt"), 0.001)
    view = store[instance]
    view.current = 200
    view[4] = 0x41
    assert counted.parsed == []  # type: ignore[attr-defined]
    assert (store.get("INA238#1.current"), store.get("INA238#1[4]")) == (200, 0x41)


def test_a_flat_write_looks_its_leaf_up_once(store: px4params.Store, counted: CountingCore) -> None:
    written = flat.set_flat(store, "INA238_1C", 0x41)
    # Found (one lookup, which also says it is live), written by path (one), read back (one
    # value: what the vehicle is told); no whole value decoded, no name parsed from text.
    assert counted.calls == Counter(get_leaf=1, set_leaf=1, get_leaf_value=1)
    assert counted.parsed == []  # type: ignore[attr-defined]
    assert (written.leaf, written.value) == (Key("INA238", 1, 4), 0x41)
    assert store.get("INA238#1.bus.i2c.address") == 0x41


def test_a_flat_write_of_a_float_returns_what_is_stored(store: px4params.Store) -> None:
    # 0.001 kept as a float16 is 0.0010004043579101562 (IEEE half: 0x1419).
    written = flat.set_flat(store, "INA238_1Q", 0.001)
    assert written.value == pytest.approx(0.0010004043579101562, rel=0, abs=1e-12)
    assert written.leaf == Key("INA238", 1, 6)


def test_a_flat_name_of_an_instance_that_does_not_exist_says_so(store: px4params.Store) -> None:
    with pytest.raises(InstanceError, match=r"^INA238_2C belongs to INA238#2, which does not"):
        flat.set_flat(store, "INA238_2C", 0x41)


def test_a_flat_name_of_an_unselected_variant_says_which_selector(
    store: px4params.Store,
) -> None:
    from px4params.errors import LeafError

    # INA238_1D is bus.spi's first leaf; bus._tag (INA238_1A) selects I2C (0).
    owner, slot = flat.flat_map(store).owner("INA238_1D")
    assert (owner, slot.path.startswith("bus.spi")) == (Key("INA238", 1, None), True)
    with pytest.raises(
        LeafError, match=r"^INA238_1D \(INA238#1\.bus\.spi\.[a-z_]+\) is not live: "
    ):
        flat.set_flat(store, "INA238_1D", 1)
    with pytest.raises(
        LeafError, match=r"bus\._tag selects variant 0, not 1 \(set INA238_1A to 1\)"
    ):
        flat.set_flat(store, "INA238_1D", 1)


def test_a_ground_station_write_reads_the_flat_name_once(
    store: px4params.Store, counted: CountingCore, monkeypatch: pytest.MonkeyPatch
) -> None:
    fmap = flat.flat_map(store)
    reads: list[str] = []
    original = fmap._parse

    def parse(name: str) -> Any:
        reads.append(name)
        return original(name)

    monkeypatch.setattr(fmap, "_parse", parse)
    assert flat.write_flat(store, "INA238_1C", 0x41) == "INA238_1C = 65"
    assert reads == ["INA238_1C"]
    assert counted.calls == Counter(get_leaf=1, set_leaf=1, get_leaf_value=1)


#: How the naming rule would be written out again: a name composed (``f"{p}#{n}"``,
#: ``p + "#" + n``, a page's `${p}#${n}`) or taken apart by hand (``split("#")``,
#: ``partition("#")``, a page's ``/#(\d+)/``).
_RULE_WRITTEN_OUT = ("}#{", '"#" +', '+ "#"', 'split("#")', 'partition("#")', "}#${", "#(\\d")


def test_the_naming_rule_is_written_in_key_py_alone() -> None:
    """``NAME#N`` is :meth:`Key.__str__`'s (and :meth:`Key.parse`'s) alone: no other module of
    the package, nor the page's script, composes or splits a name by hand. (The DSDL loader's
    ``#`` is a comment's, not a name's.)"""
    package = Path(__file__).resolve().parents[1] / "python" / "px4params"
    allowed = {"store/key.py", "dsdl/loader.py"}
    sources = [*package.rglob("*.py"), package / "gui" / "static" / "app.js"]
    found = [
        f"{path.relative_to(package)}: {pattern}"
        for path in sources
        if str(path.relative_to(package)) not in allowed
        for pattern in _RULE_WRITTEN_OUT
        if pattern in path.read_text()
    ]
    assert found == []
    key = (package / "store" / "key.py").read_text()
    assert "}#{" in key  # (the patterns find the rule where it is)


@pytest.mark.parametrize("given", [["INA238#0"], 7, None, b"INA238#0"])
def test_what_is_not_text_is_refused_as_no_parameter_name(store, given: Any) -> None:
    """A name that is not text (a list, a number, bytes) is refused in one line by every entry
    point, as a name the parser cannot read, not with a Python error about ``strip``."""
    message = rf"^{abbreviated_repr(given)} is not a parameter name \(a {type(given).__name__}; "
    for call in (Key.parse, store.get, store.remove, store.leaf, store.add, store.data_type):
        with pytest.raises(InstanceError, match=message + r"expected text or a Key\)$"):
            call(given)
    assert given not in store


def abbreviated_repr(given: Any) -> str:
    import re

    return re.escape(repr(given))


# -- the parts of a name, at their bounds (issue 40) -------------------------------------------
#: The refusal of text that is no name, word for word.
NO_NAME = (
    "is not a parameter name (expected NAME, NAME#N, NAME#N[k] or NAME#N.path, "
    "e.g. INA238#0.bus.i2c.address)"
)


@pytest.mark.issue40
def test_an_instance_number_is_16_bit() -> None:
    """Instance numbers are 16-bit in the core: 65535 is the last one a name can carry."""
    assert Key.parse("INA238#65535") == Key("INA238", 65535, None)
    with pytest.raises(InstanceError) as info:
        Key.parse("INA238#65536")
    assert str(info.value) == "INA238#65536: instance 65536 is out of range"


@pytest.mark.issue40
def test_a_leaf_number_is_at_most_max_leaf() -> None:
    """``[k]`` up to ``MAX_LEAF`` (2**31) is a leaf number; one more names no leaf of any
    storable value, by ``parse`` and by ``at`` alike."""
    assert MAX_LEAF == 2**31
    assert Key.parse(f"INA238#1[{MAX_LEAF}]") == Key("INA238", 1, MAX_LEAF)
    assert Key.parse("INA238#1").at(MAX_LEAF) == Key("INA238", 1, MAX_LEAF)
    for refuse in (lambda: Key.parse(f"INA238#1[{MAX_LEAF + 1}]"),
                   lambda: Key.parse("INA238#1").at(MAX_LEAF + 1)):  # fmt: skip
        with pytest.raises(InstanceError) as info:
            refuse()
        assert str(info.value) == "INA238#1[2147483649]: no leaf [2147483649]"


@pytest.mark.issue40
@pytest.mark.parametrize(
    "text", ["INA238#", "INA238#X", "INA238#1[X]", "INA238#1[]", "INA238#1[4", "INA238#1.",
             "INA238#1.x-", "INA238#1.x y", "INA238#1.4x", "#1", "INA238#1[4]x"],
)  # fmt: skip
def test_what_the_naming_rule_does_not_hold_is_no_name(text: str) -> None:
    """``NAME#N[k]`` or ``NAME#N.path``: N and k are ASCII digits, a path starts with a letter or
    ``_`` and holds letters, digits, ``_``, ``.`` and brackets; nothing follows."""
    with pytest.raises(InstanceError) as info:
        Key.parse(text)
    assert str(info.value) == f"'{text}' {NO_NAME}"


@pytest.mark.issue40
def test_a_path_of_one_letter_is_a_path() -> None:
    assert Key.parse("INA238#0.x") == Key("INA238", 0, "x")
    assert Key.parse("INA238_SHARED._") == Key("INA238_SHARED", None, "_")


@pytest.mark.issue40
def test_an_inexact_name_is_shown_as_typed_when_short_and_abbreviated_when_long() -> None:
    """The refusal shows a name of up to 32 characters as typed, the padding that made it
    inexact included; a longer one by its ends and length (``px4params.numbers.abbreviated``)."""
    short = " INA238#0.bus.i2c.address_abcdef"  # 32 characters, a space first
    with pytest.raises(InstanceError) as info:
        Key.parse(short)
    assert str(info.value).startswith(f"'{short}' is not a parameter name: names are exact")
    long = "ina238#0.bus.i2c.address_abcdefg"  # 33 characters... with the padding below
    for text in (long + "h", " " + long):
        with pytest.raises(InstanceError) as info:
            Key.parse(text)
        shown = f"{text.strip()[:12]}...{text.strip()[-6:]} ({len(text.strip())} characters)"
        if len(text.strip()) <= 32:
            shown = text.strip()
        assert str(info.value).startswith(f"'{shown}' is not a parameter name: names are exact")


@pytest.mark.issue40
def test_a_hint_is_worked_out_for_up_to_1000_characters() -> None:
    """(Bounded work for a refusal: text beyond 1000 characters gets the plain refusal.)"""
    with pytest.raises(InstanceError, match=r"\(did you mean A{1000}\?\)$"):
        Key.parse("a" * 1000)
    with pytest.raises(InstanceError) as info:
        Key.parse("a" * 1001)
    assert str(info.value) == f"'{'a' * 12}...{'a' * 6} (1001 characters)' {NO_NAME}"


@pytest.mark.issue40
@pytest.mark.parametrize(
    "name",
    ["SYS_AUTOSTART", "INA238#1", "INA238#1[4]", "INA238#1.bus.i2c.address", "INA238_SHARED.x"],
)
def test_a_key_is_written_back_as_the_name_it_was_read_from(name: str) -> None:
    """The naming rule both ways: ``NAME``, ``NAME#N``, ``NAME#N[k]``, ``NAME#N.path``."""
    assert str(Key.parse(name)) == name


EXACT = "names are exact, in upper case with ASCII digits and no spaces, as PX4's"


@pytest.mark.parametrize(
    ("text", "hint"),
    [
        # each index of a path is checked, not only the first "[0" (here a good one)
        ("INA238#0.bus[0].i2c[01]", "INA238#0.bus[0].i2c[1]"),
        # a typo does not hide a leading zero: cut short, or a bracket left out
        ("INA238#0.bus[01", "INA238#0.bus[1"),
        ("INA238#0.bus[0[01]", "INA238#0.bus[0[1]"),
        # the hint rewrites numbers only: an index that is none is kept as typed
        ("ina238#0.bus[a1]", "INA238#0.bus[a1]"),
    ],
)
def test_a_leading_zero_anywhere_in_a_path_is_refused_with_the_exact_name(
    text: str, hint: str
) -> None:
    with pytest.raises(InstanceError) as refused:
        Key.parse(text)
    assert str(refused.value) == f"'{text}' is not a parameter name: {EXACT} (did you mean {hint}?)"


def test_a_path_cut_short_after_a_zero_is_no_field(store: px4params.Store) -> None:
    # "[0" at the path's very end has no digit after it: no leading zero; the type refuses it.
    assert str(Key.parse("INA238#1.bus[0")) == "INA238#1.bus[0"
    with pytest.raises(px4params.LeafError) as refused:
        store.get("INA238#1.bus[0")
    assert str(refused.value) == "INA238#1: bus: no such field: bus[0"
