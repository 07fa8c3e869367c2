"""The parameter set: which types are parameters, their names, instances and default values.

A ``px`` type is a parameter when its doc comment carries ``@max_instances N`` (an instanced
parameter: ``INA238#0`` .. ``INA238#<N-1>``) or ``@param NAME`` without ``@max_instances`` (a
single value shared by all instances, e.g. ``INA238_SHARED``). The parameter's name is
``@param`` when given, otherwise the type's short name in upper snake case
(``px.Ina238`` -> ``INA238``, ``px.Ina238Shared`` -> ``INA238_SHARED``). A parameter always
uses the newest version of its type; older versions stay loadable for translating stored data.
"""

from __future__ import annotations

import decimal
import itertools
import math
import struct
from collections.abc import Iterable, Mapping

from px4params._records import TYPE_CHECKING
from px4params.dsdl.model import NO_DOC, Field, FieldDoc
from px4params.dsdl.schema import DataType, Leaf, Schema
from px4params.errors import ParameterSetError, ValueRangeError
from px4params.numbers import FLOAT_MAX
from px4params.store.key import Key

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, NamedTuple
else:
    from px4params._records import NamedTuple

__all__ = [
    "LeafRange",
    "ParamSpec",
    "ParameterSetError",
    "check_leaves",
    "check_stored",
    "generic_path",
    "leaf_ranges",
    "metadata_default",
    "parameter_specs",
    "stored_number",
    "with_defaults",
]

#: What a parameter name is made of (after a first letter A-Z).
_NAME_CHARS = "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_"
#: PX4 parameter names have at most 16 characters.
MAX_NAME_LEN = 16


class ParamSpec(NamedTuple):
    """One structured parameter."""

    #: Parameter name, e.g. ``INA238``.
    name: str
    #: The type (its newest version).
    data_type: DataType
    #: Number of instance slots, or None for a shared (not instanced) parameter.
    max_instances: int | None

    @property
    def shared(self) -> bool:
        """A single value shared by all instances (no ``#N``)."""
        return self.max_instances is None

    @property
    def slots(self) -> int:
        """Slots reserved: ``max_instances``, or 1 for a shared parameter."""
        return self.max_instances or 1

    def instance_name(self, instance: int) -> str:
        """``INA238#0``, or the bare name for a shared parameter."""
        return str(self.instance_key(instance))

    def instance_key(self, instance: int) -> Key:
        """The key of instance ``instance`` (of the parameter, for a shared one)."""
        return Key(self.name, None if self.shared else instance, None)


def default_param_name(type_name: str) -> str:
    """``px.Ina238Shared`` -> ``INA238_SHARED``."""
    short = type_name.rsplit(".", 1)[-1]
    out = short[:1]
    for before, char in itertools.pairwise(short):  # "_" where a capital follows a-z or 0-9
        if "A" <= char <= "Z" and ("a" <= before <= "z" or "0" <= before <= "9"):
            out += "_"
        out += char
    return out.upper()


def _is_param_name(name: str) -> bool:
    """``[A-Z][A-Z0-9_]*`` (without a regular expression: compiling one costs every command)."""
    return "A" <= name[:1] <= "Z" and not name.strip(_NAME_CHARS)


def parameter_specs(schema: Schema) -> list[ParamSpec]:
    """Every parameter of ``schema``, sorted by name."""
    specs: dict[str, ParamSpec] = {}
    origin: dict[str, str] = {}
    newest: dict[str, str] = {}
    for key in schema:
        declared = schema.type_def(key)
        if not declared.versioned or declared.service:
            continue
        if declared.name not in newest or schema.resolve(declared.name) == key:
            newest[declared.name] = schema.resolve(declared.name)
    for type_name, key in sorted(newest.items()):
        data_type = schema[key]
        declared = data_type.type_def
        doc = declared.doc
        if not doc.declares_parameter:
            continue
        name = doc.param or default_param_name(type_name)
        if not _is_param_name(name) or len(name) > MAX_NAME_LEN:
            raise ParameterSetError(
                f"{declared.file}: parameter name {name!r} of {type_name} "
                f"is not an upper-case name of at most {MAX_NAME_LEN} characters "
                "(set one with @param NAME)"
            )
        if name in specs:
            raise ParameterSetError(
                f"{declared.file}: parameter name {name} of {type_name} "
                f"is already used by {origin[name]} (set another with @param NAME)"
            )
        specs[name] = ParamSpec(name, data_type, doc.max_instances)
        origin[name] = type_name
    return [specs[n] for n in sorted(specs)]


def metadata_default(schema: Schema, key: str) -> dict[str, Any]:
    """The value of type ``key`` built from its fields' ``@default`` metadata (recursively);
    fields without one are zero, unions take their first variant unless a path default
    (``@default i2c.address 0x45``) names another."""
    value = _default_of(schema, {"kind": "ref", "name": key}, None)
    assert isinstance(value, dict)
    return value


def with_defaults(schema: Schema, key: str, value: Any) -> Any:
    """``value`` with every field it leaves out taken from the type's defaults (as
    :func:`metadata_default` builds them), at every depth: in a union, the given variant is
    completed from that variant's defaults. What ``value`` gives is kept as it is, so the codec
    still reports what is wrong with it."""
    return _fill(schema, {"kind": "ref", "name": key}, value, metadata_default(schema, key))


def _fill(schema: Schema, type_spec: Mapping[str, Any], given: Any, default: Any) -> Any:
    kind = type_spec["kind"]
    if kind == "ref" and isinstance(given, Mapping):
        declared = schema.type_def(type_spec["name"])
        fields = {f.name: f for f in declared.data_fields}
        defaults = default if isinstance(default, Mapping) else {}
        if declared.is_union:
            if len(given) != 1 or next(iter(given)) not in fields:
                return given
            name, inner = next(iter(given.items()))
            base = (
                defaults[name] if name in defaults else _field_default(schema, fields[name], None)
            )
            return {name: _fill(schema, fields[name].type, inner, base)}
        out = dict(given)
        for name, f in fields.items():
            if name == "p_version":
                continue  # filled in by the codec
            base = defaults[name] if name in defaults else _field_default(schema, f, None)
            out[name] = _fill(schema, f.type, given[name], base) if name in given else base
        return out
    if kind in ("array", "dynarray") and isinstance(given, list):
        element = _default_of(schema, type_spec["elem"], None)
        return [_fill(schema, type_spec["elem"], item, element) for item in given]
    return given


def _default_of(schema: Schema, type_spec: Mapping[str, Any], given: Any) -> Any:
    kind = type_spec["kind"]
    if kind == "ref":
        declared = schema.type_def(type_spec["name"])
        overrides = _nest(given) if isinstance(given, Mapping) else {}
        fields = declared.data_fields
        if declared.is_union:
            chosen = next((f for f in fields if f.name in overrides), fields[0])
            return {chosen.name: _field_default(schema, chosen, overrides.get(chosen.name))}
        return {
            f.name: _field_default(schema, f, overrides.get(f.name))
            for f in fields
            if f.name != "p_version"
        }
    if kind == "array":
        return [_default_of(schema, type_spec["elem"], None) for _ in range(type_spec["len"])]
    if kind == "dynarray":
        return []
    if given is not None:
        return given
    if kind == "bool":
        return False
    if kind == "float":
        return 0.0
    return 0


def _field_default(schema: Schema, field: Field, override: Any) -> Any:
    declared = field.declared_default  # (the other tags are not read: see Field)
    if isinstance(declared, Mapping) and isinstance(override, Mapping):
        declared = {**declared, **_flatten(override)}
    elif override is not None:
        declared = override
    return _default_of(schema, field.type, declared)


def _nest(paths: Mapping[str, Any]) -> dict[str, Any]:
    """``{"i2c.address": 69}`` -> ``{"i2c": {"address": 69}}``."""
    nested: dict[str, Any] = {}
    for path, value in paths.items():
        head, _, rest = path.partition(".")
        if rest:
            inner = nested.setdefault(head, {})
            if isinstance(inner, dict):
                inner[rest] = value
        else:
            nested[head] = value
    return nested


def _flatten(value: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    flat: dict[str, Any] = {}
    for k, v in value.items():
        if isinstance(v, Mapping):
            flat.update(_flatten(v, f"{prefix}{k}."))
        else:
            flat[f"{prefix}{k}"] = v
    return flat


# -- what a leaf accepts: @min/@max, @value lists, finite floats -----------------------------------


class LeafRange(NamedTuple):
    """What one leaf of a parameter accepts beyond its type's own range: its field's ``@min``
    and ``@max`` (None where not given, or where it only repeats the type's range), the values
    its ``@value`` list (or ``@values`` set) names, where it has one (a ground station offers
    those alone, as QGC's list of a parameter's values), and, for a float leaf, finite numbers
    only (no bundled type needs NaN or an infinity, so no type can ask for them: a NaN shunt
    is a battery monitor that reads nothing)."""

    low: int | float | None
    high: int | float | None
    #: 16, 32 or 64 for a float leaf (whose stored value is rounded), 0 for an integer one.
    float_bits: int
    #: The bounds a stored value is compared with: ``low``/``high`` widened to where they
    #: round at the leaf's width (0.1 is kept as 0.09998 by a float16, and is inside).
    stored_low: int | float | None = None
    stored_high: int | float | None = None
    #: The leaf's DSDL type (``float16``, ``uint10``).
    type: str = ""
    #: The field's named values (``@value N text``), in order; none: any value in range.
    values: tuple[tuple[int | float | bool, str], ...] = ()
    #: Those values as the leaf stores them (a float rounded to its width).
    stored_values: frozenset[int | float] = frozenset()

    @classmethod
    def of(
        cls,
        low: float | None,
        high: float | None,
        float_bits: int,
        type: str,
        values: tuple[tuple[int | float | bool, str], ...] = (),
    ) -> LeafRange:
        stored = frozenset(_rounded(v, float_bits) if float_bits else v for v, _ in values)
        if not float_bits:
            return cls(low, high, 0, low, high, type, values, stored)
        return cls(
            low,
            high,
            float_bits,
            None if low is None else min(low, _rounded(low, float_bits)),
            None if high is None else max(high, _rounded(high, float_bits)),
            type,
            values,
            stored,
        )


def leaf_ranges(data_type: DataType) -> dict[str, LeafRange]:
    """``{path: LeafRange}`` of every leaf of ``data_type`` with something to check, its path
    as :meth:`DataType.leaves` writes it with array indices left empty (``cells[].volts``).
    Worked out once per type (kept in its ``derived``), in time proportional to the type's
    declaration, not to its arrays' lengths."""
    found = data_type.derived.get("leaf_ranges")
    if found is None:
        found = {}
        _ranges_of(data_type, {"kind": "ref", "name": data_type.key}, "", NO_DOC, found)
        data_type.derived["leaf_ranges"] = found
    return found


def _ranges_of(
    data_type: DataType,
    spec: Mapping[str, Any],
    path: str,
    doc: FieldDoc,
    found: dict[str, LeafRange],
) -> None:
    kind = spec["kind"]
    if kind == "ref":
        for f in data_type.nested_type_def(spec["name"]).data_fields:
            _ranges_of(data_type, f.type, f"{path}.{f.name}" if path else f.name, f.doc, found)
    elif kind in ("array", "dynarray"):  # a field's tags describe its elements
        _ranges_of(data_type, spec["elem"], f"{path}[]", doc, found)
    elif kind in ("uint", "int", "float"):
        bits = int(spec["bits"])
        low, high, values = doc.minimum, doc.maximum, doc.values
        if kind == "float":
            found[path] = LeafRange.of(low, high, bits, f"float{bits}", values)
            return
        top = (1 << bits) - 1 if kind == "uint" else (1 << (bits - 1)) - 1
        bottom = 0 if kind == "uint" else -(1 << (bits - 1))
        low = None if low is None or low <= bottom else low
        high = None if high is None or high >= top else high
        if low is not None or high is not None or values:
            found[path] = LeafRange.of(low, high, 0, f"{kind}{bits}", values)


def generic_path(path: str) -> str:
    """``cells[3].volts`` -> ``cells[].volts``: the key of :func:`leaf_ranges`."""
    if "[" not in path:
        return path
    out, start = [], 0
    while (open_at := path.find("[", start)) >= 0:
        out.append(path[start : open_at + 1])
        start = path.find("]", open_at)
        if start < 0:
            return path
    out.append(path[start:])
    return "".join(out)


def check_leaves(
    where: str,
    leaves: Iterable[Leaf],
    ranges: Mapping[str, LeafRange],
    *,
    bounds: bool = True,
    given: object = None,
) -> None:
    """Refuses (:class:`ValueRangeError`) the first leaf that is a NaN or an infinity, or, with
    ``bounds``, outside its ``@min``/``@max``. ``where`` names the instance (``INA238#1``).
    Leaves are stored values: a float is compared with its bounds as they round to the leaf's
    width, so that a value given as exactly ``@min`` is never refused once stored. ``given``,
    the number a one-leaf write was given, is what a refusal names (1e-12, not the 0 a float16
    keeps of it)."""
    for leaf in leaves:
        rng = ranges.get(generic_path(leaf.path))
        if rng is not None and not isinstance(leaf.value, bool):
            check_stored(f"{where}.{leaf.path}", leaf.value, rng, bounds, given)


def check_stored(
    name: str,
    value: float,
    rng: LeafRange,
    bounds: bool = True,
    given: object = None,
    *,
    forcible: bool = True,
) -> None:
    """:func:`check_leaves` for one leaf named ``name`` that would store ``value``. A refusal
    of bounds alone is one ``--force`` takes (:attr:`ValueRangeError.bounds_only`), unless not
    ``forcible``: a value beyond the leaf's type too, which no write can store."""
    if rng.float_bits and not math.isfinite(value):
        raise ValueRangeError(
            f"{name}: {shown_number(value)} is not a finite number ({rng.type}: NaN and infinities "
            "are refused)"
        )
    if not bounds:
        return
    low, high = rng.stored_low, rng.stored_high
    outside = (low is not None and value < low) or (high is not None and value > high)
    if outside or (rng.stored_values and value not in rng.stored_values):
        bits = rng.float_bits or 64  # the stored value's width, or a number given's (float64)
        if isinstance(given, int | float) and not isinstance(given, bool):
            value, bits = given, 64
        if outside:
            why = describe_outside(value, rng, bits)
        else:
            why = describe_not_listed(value, rng, bits)
        raise ValueRangeError(f"{name}: {why}", bounds_only=forcible)


def within(value: float, rng: LeafRange, bounds: bool = True) -> bool:
    """Whether a leaf of ``rng`` may store ``value`` (:func:`check_stored` says why not)."""
    if rng.float_bits and not math.isfinite(value):
        return False
    if not bounds:
        return True
    low, high = rng.stored_low, rng.stored_high
    return (
        (low is None or value >= low)
        and (high is None or value <= high)
        and (not rng.stored_values or value in rng.stored_values)
    )


def in_type_range(value: float, type_name: str) -> bool:
    """Whether a leaf of DSDL type ``type_name`` (``uint10``, ``float16``) can hold ``value`` at
    all; outside it, the codec's own refusal is the one to give."""
    kind = type_name.rstrip("0123456789")
    bits = int(type_name[len(kind) :] or 0)
    if kind == "float":
        top = FLOAT_MAX.get(bits)
        return top is None or not math.isfinite(value) or abs(value) <= top
    if kind == "uint":
        return 0 <= value < 1 << bits
    if kind == "int":
        return -(1 << (bits - 1)) <= value < 1 << (bits - 1)
    return True


def stored_number(value: object, rng: LeafRange) -> int | float | None:
    """What a leaf of ``rng`` keeps of a plain ``int``/``float`` given to it (a float rounded to
    the leaf's width), or None where only the codec can say (another kind of value, a float
    for an integer leaf, a number beyond the float's range): then the write is checked on the
    value it encodes."""
    if rng.float_bits:
        if type(value) is not float and type(value) is not int:
            return None
        try:
            number = float(value)
        except OverflowError:  # an int beyond every double: the codec refuses it
            return None
        if not math.isfinite(number):
            return number
        packer = _FLOAT_PACKERS.get(rng.float_bits)
        if packer is None:
            return number
        try:
            return float(packer.unpack(packer.pack(number))[0])
        except OverflowError:
            return None
    return value if type(value) is int else None


def describe_outside(value: float, rng: LeafRange, bits: int = 64) -> str:
    """``0 is outside 0.00001..0.1 (@min/@max)`` (or below @min / above @max alone); ``value``
    a float of ``bits``, the bounds as the doc gives them (see :func:`shown_number`)."""
    shown = shown_number(value, bits)
    if rng.low is not None and rng.high is not None:
        return f"{shown} is outside {shown_number(rng.low)}..{shown_number(rng.high)} (@min/@max)"
    if rng.low is not None:
        return f"{shown} is below {shown_number(rng.low)} (@min)"
    assert rng.high is not None  # a value outside a range that has a bound
    return f"{shown} is above {shown_number(rng.high)} (@max)"


#: A value list longer than this is named by its numbers alone (PX4's rotations are 41).
_NAMED_AT_MOST = 12


def describe_not_listed(value: float, rng: LeafRange, bits: int = 64) -> str:
    """``7 is not one of its values (@value): 0 (10 Hz), 1 (20 Hz), 2 (50 Hz)``; a long
    list by its numbers, runs shortened (``0..40``); ``value`` a float of ``bits``."""
    if len(rng.values) <= _NAMED_AT_MOST:
        allowed = ", ".join(f"{shown_number(v)} ({text})" for v, text in rng.values)
    else:
        allowed = _runs(sorted(v for v, _ in rng.values))
    return f"{shown_number(value, bits)} is not one of its values (@value): {allowed}"


def _runs(numbers: list[int | float | bool]) -> str:
    """``0, 6, 101..104, 201..203``: consecutive integers as one run."""
    runs: list[list[float]] = []
    for n in numbers:
        if runs and type(n) is int and type(runs[-1][1]) is int and n == runs[-1][1] + 1:
            runs[-1][1] = n
        else:
            runs.append([n, n])
    return ", ".join(
        shown_number(low) if low == high else f"{shown_number(low)}..{shown_number(high)}"
        for low, high in runs
    )


_FLOAT_PACKERS = {16: struct.Struct("<e"), 32: struct.Struct("<f")}


def _rounded(value: float, bits: int) -> float:
    """``value`` as a float of ``bits`` stores it (IEEE rounding; the DroneCAN rules round a tie
    away from zero, which only widens what :func:`check_leaves` accepts by that tie)."""
    code = {16: "<e", 32: "<f"}.get(bits)
    if code is None:
        return float(value)
    try:
        return float(struct.unpack(code, struct.pack(code, value))[0])
    except OverflowError:
        return float(value)


def shown_number(value: float, bits: int = 64) -> str:
    """A number as a person writes it: ``0``, ``-1``, ``0.00001``, ``nan``, ``-inf``; a float
    as the fewest digits that read back as the same float of ``bits`` (16, 32, 64): a float32
    just above @max 0.1 is ``0.10000001``, never ``0.1`` (two numbers a refusal shows differ)."""
    if isinstance(value, int) or not math.isfinite(value):
        return str(value)
    if value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    text = repr(value)  # the shortest that reads back as this float64
    if bits != 64:
        kept = _rounded(value, bits)
        text = next(
            t for t in (f"{value:.{n}g}" for n in range(1, 18)) if _rounded(float(t), bits) == kept
        )
    if "e" in text and 1e-9 <= abs(value) < 1e16:
        text = format(decimal.Decimal(text), "f")  # its digits, without the exponent
    return text
