"""Byte-for-byte agreement with pydronecan over every type it bundles, TAO on and off."""

from __future__ import annotations

import px4params
import pytest
from dronecan_oracle import bundled_keys, fill, new_value, pack, same, to_plain, unpack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import budget, value_strategy

SCHEMA = px4params.load_schema(use_env=False)
STANDARD = sorted(k for k, d in SCHEMA.model["types"].items() if d.get("dialect") == "uavcan")


def test_every_bundled_type_is_covered() -> None:
    assert set(STANDARD) == bundled_keys()
    assert len(STANDARD) > 150


@pytest.mark.parametrize("key", STANDARD)
@settings(max_examples=budget(20), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), tao=st.booleans())
def test_same_bytes_as_pydronecan(key: str, data: st.DataObject, tao: bool) -> None:
    value = data.draw(value_strategy(SCHEMA.model["types"], key, infinities=False))
    ours = SCHEMA[key].encode(value, tao=tao, saturate=True)
    theirs = pack(fill(new_value(key), value), tao=tao)
    assert ours.hex() == theirs.hex()
    decoded = SCHEMA[key].decode(ours, tao=tao)
    assert same(decoded, to_plain(unpack(key, ours, tao=tao)))
    # And our decode is a fixpoint: encoding it again gives the same bytes.
    assert SCHEMA[key].encode(decoded, tao=tao, saturate=True) == ours


@pytest.mark.parametrize(
    ("bits", "signed", "value"),
    [(8, False, 300), (8, False, -5), (7, True, -100), (7, True, 100), (11, False, 5000)],
)
def test_saturation_matches_pydronecan(bits: int, signed: bool, value: int) -> None:
    kind = "int" if signed else "uint"
    model = {
        "types": {
            "t.T": {
                "name": "t.T",
                "version": None,
                "kind": "struct",
                "dialect": "uavcan",
                "fields": [
                    {"name": "x", "type": {"kind": kind, "bits": bits, "cast": "saturated"}}
                ],
            }
        }
    }
    t = px4params.Schema(model)["t.T"]
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    assert t.decode(t.encode({"x": value}, saturate=True)) == {"x": min(max(value, lo), hi)}
    with pytest.raises(px4params.EncodeError, match=r"x: value .* is out of range"):
        t.encode({"x": value})


@pytest.mark.parametrize("variants", [2, 3, 4, 5, 8, 9, 16, 17])
def test_union_tags_as_wide_as_pydronecan_makes_them(variants: int, tmp_path_factory) -> None:
    """No bundled union has 2, 4 or 8 variants, where a tag one bit too wide would show:
    unions of every width edge, against pydronecan's own parser and packer."""
    import dronecan
    from dronecan import transport
    from dronecan_oracle import pack

    root = tmp_path_factory.mktemp("unions") / "tstu"
    root.mkdir()
    fields = "".join(f"uint7 v{i}\n" for i in range(variants))
    (root / f"Union{variants}.uavcan").write_text("@union\n" + fields)
    (root / f"Holder{variants}.uavcan").write_text(f"Union{variants} u\nuint3 after\n")
    ours = px4params.load_schema([root], use_env=False, cache_dir=root.parent / "cache")
    theirs = {t.full_name: t for t in dronecan.dsdl.parse_namespaces([str(root)])}
    holder = f"tstu.Holder{variants}"
    assert ours[f"tstu.Union{variants}"].max_bits == (variants - 1).bit_length() + 7
    for k in {0, 1, variants // 2, variants - 1}:
        value = {"u": {f"v{k}": 100 + k}, "after": 5}
        obj = transport.CompoundValue(theirs[holder])
        setattr(obj.u, f"v{k}", 100 + k)
        obj.after = 5
        for tao in (True, False):
            assert ours[holder].encode(value, tao=tao).hex() == pack(obj, tao=tao).hex()
            assert ours[holder].decode(pack(obj, tao=tao), tao=tao) == value
