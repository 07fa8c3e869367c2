"""Hypothesis strategies for values of any type in a schema model."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from hypothesis import strategies as st

FLOAT16_MAX = 65504.0


def scalar_strategy(spec: Mapping[str, Any], *, infinities: bool) -> st.SearchStrategy[Any]:
    kind = spec["kind"]
    if kind == "bool":
        return st.booleans()
    bits = spec["bits"]
    if kind == "uint":
        return st.integers(0, (1 << bits) - 1)
    if kind == "int":
        return st.integers(-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
    # pydronecan clamps infinities in saturated mode (a documented deviation): only truncated
    # fields get them when comparing against it.
    inf = infinities or spec.get("cast") == "truncated"
    if bits == 16:
        finite = st.floats(-FLOAT16_MAX, FLOAT16_MAX, width=32)
    elif bits == 32:
        finite = st.floats(width=32, allow_nan=False, allow_infinity=False)
    else:
        finite = st.floats(allow_nan=False, allow_infinity=False)
    extra = [st.just(float("nan"))]
    if inf:
        extra += [st.just(float("inf")), st.just(float("-inf"))]
    return st.one_of(finite, *extra)


def value_strategy(
    types: Mapping[str, Any], key: str, *, infinities: bool = True, max_len: int = 6
) -> st.SearchStrategy[dict[str, Any]]:
    """Values of type ``key``; dynamic arrays are capped at ``max_len`` elements (plus their
    maximum now and then) to keep examples small."""
    memo: dict[str, st.SearchStrategy[Any]] = {}

    def of_type(spec: Mapping[str, Any]) -> st.SearchStrategy[Any]:
        kind = spec["kind"]
        if kind == "ref":
            return composite(spec["name"])
        if kind == "array":
            return st.lists(of_type(spec["elem"]), min_size=spec["len"], max_size=spec["len"])
        if kind == "dynarray":
            elem = of_type(spec["elem"])
            short = st.lists(elem, max_size=min(spec["max"], max_len))
            if spec["max"] <= max_len:
                return short
            return st.one_of(short, st.lists(elem, min_size=spec["max"], max_size=spec["max"]))
        return scalar_strategy(spec, infinities=infinities)

    def composite(name: str) -> st.SearchStrategy[Any]:
        if name not in memo:
            definition = types[name]
            fields = [f for f in definition["fields"] if f["type"]["kind"] != "void"]
            if definition["kind"] == "union":
                memo[name] = st.one_of(
                    *[of_type(f["type"]).map(lambda v, n=f["name"]: {n: v}) for f in fields]
                )
            else:
                memo[name] = st.fixed_dictionaries(
                    {f["name"]: of_type(f["type"]) for f in fields if f["name"] != "p_version"}
                )
        return memo[name]

    return composite(key)
