"""Hypothesis strategies for values of any type in a schema model."""

from __future__ import annotations

import math
import os
import struct
from collections.abc import Mapping
from typing import Any

from hypothesis import strategies as st

FLOAT16_MAX = 65504.0

#: Hypothesis budgets are multiplied by this: 1 in CI (seconds), more in the scheduled long run
#: (``scripts/fuzz.sh``), which also lifts the cap on array lengths below; a fraction (0.2) for
#: a quicker run while working (every property still runs at least once).
SCALE_ENV = "PX4PARAMS_HYPOTHESIS_SCALE"


def _scale(text: str) -> float:
    try:
        scale = float(text or 1)
    except ValueError:
        raise SystemExit(f"${SCALE_ENV}: '{text}' is not a number (1 is CI's budget)") from None
    if not 0 < scale < 10_000:
        raise SystemExit(f"${SCALE_ENV}: {text} is out of range (more than 0, less than 10000)")
    return scale


SCALE = _scale(os.environ.get(SCALE_ENV, "1"))
#: The scheduled long run: larger arrays, and a deadline that reports a slow input.
LONG_RUN = SCALE > 1


def budget(examples: int) -> int:
    """``examples`` in CI, ``SCALE`` times as many in the long run (at least one)."""
    return max(1, round(examples * SCALE))


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
    types: Mapping[str, Any],
    key: str,
    *,
    infinities: bool = True,
    max_len: int | None = None,
    storable: bool = False,
) -> st.SearchStrategy[dict[str, Any]]:
    """Values of type ``key``; dynamic arrays are capped at ``max_len`` elements (default 6 in
    CI, none in the long run) plus their maximum now and then, to keep CI's examples small.
    ``storable`` values are what a store takes: within each field's ``@min``/``@max`` and
    ``@value`` list, floats finite."""
    if max_len is None:
        max_len = 1 << 30 if LONG_RUN else 6
    memo: dict[str, st.SearchStrategy[Any]] = {}

    def of_type(spec: Mapping[str, Any], tags: Mapping[str, Any]) -> st.SearchStrategy[Any]:
        kind = spec["kind"]
        if kind == "ref":
            return composite(spec["name"])
        if kind == "array":
            elem = of_type(spec["elem"], tags)
            return st.lists(elem, min_size=spec["len"], max_size=spec["len"])
        if kind == "dynarray":
            elem = of_type(spec["elem"], tags)
            short = st.lists(elem, max_size=min(spec["max"], max_len))
            if spec["max"] <= max_len:
                return short
            return st.one_of(short, st.lists(elem, min_size=spec["max"], max_size=spec["max"]))
        if storable and kind != "bool":
            return _within(spec, tags)
        return scalar_strategy(spec, infinities=infinities)

    def composite(name: str) -> st.SearchStrategy[Any]:
        if name not in memo:
            definition = types[name]
            fields = [f for f in definition["fields"] if f["type"]["kind"] != "void"]
            if definition["kind"] == "union":
                memo[name] = st.one_of(
                    *[
                        of_type(f["type"], _tags(f)).map(lambda v, n=f["name"]: {n: v})
                        for f in fields
                    ]
                )
            else:
                memo[name] = st.fixed_dictionaries(
                    {
                        f["name"]: of_type(f["type"], _tags(f))
                        for f in fields
                        if f["name"] != "p_version"
                    }
                )
        return memo[name]

    return composite(key)


def _tags(field: Mapping[str, Any]) -> Mapping[str, Any]:
    return (field.get("doc") or {}).get("tags") or {}


def _within(spec: Mapping[str, Any], tags: Mapping[str, Any]) -> st.SearchStrategy[Any]:
    """A finite number of scalar type ``spec`` within the field's ``@min``/``@max``, one of its
    ``@value`` list where it has one."""
    if tags.get("value"):
        return st.sampled_from([number for number, _ in tags["value"]])
    bits, kind = spec["bits"], spec["kind"]
    if kind == "float":
        top = {16: FLOAT16_MAX, 32: 3.4028234663852886e38}.get(bits, 1.7976931348623157e308)
        low, high = tags.get("min", -top), tags.get("max", top)
        return st.floats(low, high)
    low, high = (0, (1 << bits) - 1) if kind == "uint" else (
        -(1 << (bits - 1)), (1 << (bits - 1)) - 1)  # fmt: skip
    return st.integers(max(low, tags.get("min", low)), min(high, tags.get("max", high)))


def expected_decoded(types: Mapping[str, Any], key: str, value: Any) -> Any:
    """What decoding the encoding of ``value`` must give, worked out from the type's fields
    alone (not by the codec): the same value, floats rounded to their field's width by Python's
    own IEEE 754 conversion (``struct``), and the ``p_version`` a struct carries left out (the
    codec fills it in). Compare with :func:`same_decoded`."""

    def of(spec: Mapping[str, Any], v: Any) -> Any:
        kind = spec["kind"]
        if kind == "ref":
            definition = types[spec["name"]]
            fields = {f["name"]: f["type"] for f in definition["fields"]}
            return {k: of(fields[k], x) for k, x in v.items() if k != "p_version"}
        if kind in ("array", "dynarray"):
            return [of(spec["elem"], x) for x in v]
        if kind == "float" and spec["bits"] in (16, 32) and math.isfinite(v):
            code = "<e" if spec["bits"] == 16 else "<f"
            return struct.unpack(code, struct.pack(code, v))[0]
        return v

    return of({"kind": "ref", "name": key}, value)


def same_decoded(expected: Any, decoded: Any) -> bool:
    """``decoded`` is ``expected`` (its extra ``p_version`` keys aside); floats equal, or both
    NaN, or one float16 rounding step apart (DroneCAN breaks ties away from zero, Python to
    even)."""
    if isinstance(expected, dict):
        return isinstance(decoded, dict) and all(
            k in decoded and same_decoded(v, decoded[k]) for k, v in expected.items()
        )
    if isinstance(expected, list):
        return (
            isinstance(decoded, list)
            and len(expected) == len(decoded)
            and all(same_decoded(a, b) for a, b in zip(expected, decoded, strict=True))
        )
    if isinstance(expected, float):
        if isinstance(decoded, str):  # non-finite values decode as "nan", "inf", "-inf"
            decoded = float(decoded)
        if math.isnan(expected):
            return isinstance(decoded, float) and math.isnan(decoded)
        return decoded == expected or math.isclose(decoded, expected, rel_tol=2**-10)
    return bool(expected == decoded) and type(expected) is type(decoded)
