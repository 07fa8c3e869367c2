"""Destructured parameters: every leaf of a structured instance as a flat PX4 parameter.

MAVLink and today's tools carry flat parameters: a name of at most 16 characters and a 32-bit
value, ``int32`` or ``float32``. A structured instance is also offered destructured, one flat
parameter per leaf (``p_version`` leaves excluded), named from the instance and a letter::

    INA238#1.bus._tag          -> INA238_1A   (the talk's "bus_type")
    INA238#1.bus.i2c.bus_id    -> INA238_1B
    INA238#1.bus.i2c.address   -> INA238_1C
    INA238#1.current           -> INA238_1P
    INA238#1.shunt             -> INA238_1Q

A shared parameter (no instances) has no number: ``INA238_SHARED_A``.

**Letters.** Letters are given over the *type*, not over a value, so that a name never moves:
walk the type in declaration order and give the next letter to every leaf of *every* union
variant (not only the selected one), every union tag, every dynamic array length and every
element slot up to the array's maximum; ``p_version`` fields and padding get none. Letters run
``A``..``Z``, then ``AA``, ``AB``, ... (spreadsheet columns). For ``px.Ina238`` (``Bus`` is
``@union {I2c i2c; Spi spi; Serial serial; Dronecan dronecan; Simulation sim; Mavlink
mavlink}``): ``A`` bus tag, ``B``/``C`` i2c bus_id/address, ``D``..``G`` spi, ``H``/``I``
serial, ``J``/``K`` dronecan, ``L`` sim, ``M``..``O`` mavlink, ``P`` current, ``Q`` shunt. With
I2C first this gives exactly the talk's ``A``/``B``/``C``. Appending a variant or field to a
type (the way DSDL types grow) appends letters and moves no existing name; inserting one in the
middle moves the letters after it, as it moves the ``[k]`` indices.

**Live leaves.** Only the leaves present in the instance's current value are offered: those of
the selected union variants and of the existing dynamic array elements. Selecting another
variant (writing the tag, e.g. ``INA238_1A = 1`` for SPI) makes that variant's leaves appear
(with their defaults) and the old ones disappear; their letters never change.

**Values.** Integer leaves (``uintN``/``intN``, union tags, array lengths) are ``int32``; a
``uint32`` travels as its bit pattern (values from 2^31 read negative, the same bits). Float
leaves are ``float32``; a ``float16`` is exactly representable, and a ``float32`` written to a
``float16`` leaf is rounded as the DroneCAN rules say (the value read back is the stored one).
Booleans are ``int32`` 0 or 1: a one-bit bitmask (the talk's "booleans -> bitmask"; ground
stations show a checkbox). A leaf wider than 32 bits (``uint64``, ``float64``, ...) cannot be
offered: such a parameter type is refused (:class:`FlatError`) when the map is built. Dynamic
arrays are offered as their length (a leaf like any other) plus one slot per element up to the
maximum length, each live only below the current length; a long array therefore needs many
letters, and the 16-character limit refuses types that would need too many.

**Instances.** Each instanced parameter also has an *instance mask*, ``INA238_INST`` (int32):
bit N is set while ``INA238#N`` exists. Writing it adds the instances whose bits it sets (with
their defaults) and removes those it clears, all or nothing; this is how a ground station adds
and removes instances with nothing but PARAM_SET (QGC edits it as a bitmask). Parameters with
more than 31 instance slots have no mask.

Names are checked once per store (:func:`flat_map`): at most 16 characters for every instance
number up to ``max_instances``, unique, and none equal to a classic or structured parameter's
name; a violation is a :class:`FlatError` naming the parameter.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping

from px4params._records import TYPE_CHECKING
from px4params.dsdl.model import Field, length_bits
from px4params.dsdl.schema import DataType, Leaf
from px4params.errors import FlatError, InstanceError, LeafError
from px4params.numbers import FLOAT_MAX
from px4params.store.key import Key
from px4params.store.spec import MAX_NAME_LEN, ParamSpec

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, NamedTuple

    from px4params.store.store import Store
else:
    from px4params._records import NamedTuple

__all__ = [
    "FlatError",
    "FlatLayout",
    "FlatMap",
    "FlatParam",
    "FlatSlot",
    "flat_map",
    "flat_table",
    "from_flat",
    "get_flat",
    "layout",
    "letters",
    "resolve_flat",
    "set_flat",
    "to_flat",
    "write_live",
]

#: MAVLink carries 32 bits per parameter.
MAX_LEAF_BITS = 32
INT32 = "int32"
FLOAT32 = "float32"


#: An instance mask is one int32: parameters with more instance slots have none.
MASK_BITS = 31


def mask_name(spec: ParamSpec) -> str:
    """``INA238_INST``: the flat parameter whose bit N says whether ``INA238#N`` exists. A
    ground station adds and removes instances by writing it (as QGC edits a bitmask)."""
    return f"{spec.name}_INST"


def letters(number: int) -> str:
    """``0`` -> ``A``, ``25`` -> ``Z``, ``26`` -> ``AA``, ``27`` -> ``AB`` (bijective base 26)."""
    if number < 0:
        raise ValueError(f"letter number {number} is negative")
    text = ""
    number += 1
    while number:
        number, rest = divmod(number - 1, 26)
        text = chr(ord("A") + rest) + text
    return text


def letter_number(text: str) -> int | None:
    """The inverse of :func:`letters`: ``A`` -> 0, ``AB`` -> 27; None for anything else."""
    if not text:
        return None
    number = 0
    for char in text:
        if not "A" <= char <= "Z":
            return None
        number = number * 26 + ord(char) - ord("A") + 1
    return number - 1


def _first_with_letters(count: int) -> int:
    """The first letter number written with ``count`` letters (``A`` 0, ``AA`` 26, ...)."""
    return sum(26**n for n in range(1, count)) if count > 0 else 0


class FlatSlot(NamedTuple):
    """One letter of a type: a leaf that may be live, depending on the value.

    ``requires`` lists what must hold for the leaf to exist, outermost first: ``(path, "==",
    n)`` for a union tag selecting variant ``n``, ``(path, ">", i)`` for an array length
    above element ``i``.
    """

    letter: str
    #: Leaf path as :meth:`DataType.leaves` writes it (``bus.i2c.address``, ``bus._tag``).
    path: str
    #: DSDL type of the leaf (``uint7``, ``float16``, ``bool``; ``uint3`` for a 6-variant tag).
    type: str
    #: ``int32`` or ``float32``: how the flat parameter carries it.
    mav_type: str
    #: ``value``, ``union_tag`` or ``length``.
    role: str
    #: Smallest and largest value of the leaf itself (a tag's range is its variants).
    min: int | float
    max: int | float
    requires: tuple[tuple[str, str, int], ...] = ()

    def to_flat(self, value: int | float | bool) -> int | float:
        """A leaf value as the flat parameter carries it."""
        if self.mav_type == FLOAT32:
            return float(value)
        number = int(value)
        if self.type == "uint32" and number >= 1 << 31:
            number -= 1 << 32  # bit pattern
        return number

    def from_flat(self, number: object) -> int | float | bool:
        """A flat parameter's number as the leaf's value (type-checked; range is the store's)."""
        if self.mav_type == FLOAT32:
            if isinstance(number, bool) or not isinstance(number, int | float):
                raise FlatError(f"expected a number, got {number!r}")
            return float(number)
        if isinstance(number, float) and number.is_integer():
            number = int(number)
        if isinstance(number, bool) or not isinstance(number, int):
            raise FlatError(f"expected an integer, got {number!r}")
        if self.type == "bool":
            if number not in (0, 1):
                raise FlatError(f"value {number} is not a boolean (expected 0 or 1)")
            return bool(number)
        if self.type == "uint32" and -(1 << 31) <= number < 0:
            number += 1 << 32  # bit pattern
        return number


class FlatLayout:
    """The letters of one type (see the module doc for the rule)."""

    def __init__(self, key: str, slots: list[FlatSlot]) -> None:
        self.key = key
        self.slots = slots
        self._by_letter = {s.letter: s for s in slots}
        self._by_path = {s.path: s for s in slots}

    def slot(self, letter: str) -> FlatSlot | None:
        return self._by_letter.get(letter)

    def slot_for_path(self, path: str) -> FlatSlot | None:
        return self._by_path.get(path)

    def __len__(self) -> int:
        return len(self.slots)

    def __iter__(self) -> Iterator[FlatSlot]:
        return iter(self.slots)


def layout(data_type: DataType) -> FlatLayout:
    """The letters of ``data_type`` (computed once per type, kept in its ``derived``);
    :class:`FlatError` if a leaf is wider than 32 bits."""
    cached = data_type.derived.get("flat_layout")
    if cached is None:
        cached = FlatLayout(data_type.key, _Walker(data_type).run())
        data_type.derived["flat_layout"] = cached
    return cached


def slot_count(data_type: DataType) -> int:
    """How many letters ``data_type`` has (its :func:`layout`'s length), counted over the type's
    declaration without listing them; :class:`FlatError` if a leaf is wider than 32 bits."""
    cached = data_type.derived.get("flat_count")
    if cached is None:
        cached = _count(data_type, {"kind": "ref", "name": data_type.key}, "")
        data_type.derived["flat_count"] = cached
    return int(cached)


def _count(data_type: DataType, spec: Mapping[str, Any], path: str) -> int:
    """The letters of ``spec`` (the rule of :class:`_Walker`, counted)."""
    kind = spec["kind"]
    if kind == "ref":
        declared = data_type.nested_type_def(spec["name"])
        fields = declared.data_fields
        if declared.is_union:
            return 1 + sum(_count(data_type, f.type, _join(path, f.name)) for f in fields)
        return sum(
            _count(data_type, f.type, _join(path, f.name)) for f in fields if not _is_version(f)
        )
    if kind == "array":
        n = int(spec["len"])
        return n * _count(data_type, spec["elem"], f"{path}[0]") if n else 0
    if kind == "dynarray":
        n = int(spec["max"])
        return 1 + (n * _count(data_type, spec["elem"], f"{path}[0]") if n else 0)
    if kind in ("uint", "int", "float"):
        bits = int(spec["bits"])
        if bits > MAX_LEAF_BITS:
            raise FlatError(
                f"{data_type.key}: leaf {path or '(value)'} is {kind}{bits}: destructured "
                f"parameters carry at most {MAX_LEAF_BITS} bits (MAVLink), so this type cannot "
                "be a parameter"
            )
        return 1
    return 1 if kind == "bool" else 0  # void: padding, not a leaf


def _is_version(field: Field) -> bool:
    """``p_version``: filled in by the code, never set by users, so no letter of its own."""
    return field.name == "p_version" and field.kind in ("uint", "int")


class _Walker:
    def __init__(self, data_type: DataType) -> None:
        self.key = data_type.key
        self.data_type = data_type
        self.slots: list[FlatSlot] = []

    def run(self) -> list[FlatSlot]:
        self.walk({"kind": "ref", "name": self.key}, "", ())
        return self.slots

    def add(
        self,
        path: str,
        type_name: str,
        mav_type: str,
        role: str,
        lo: float,
        hi: float,
        requires: tuple[tuple[str, str, int], ...],
    ) -> None:
        slot = FlatSlot(letters(len(self.slots)), path, type_name, mav_type, role, lo, hi, requires)
        self.slots.append(slot)

    def walk(self, spec: Mapping[str, Any], path: str, requires: tuple[Any, ...]) -> None:
        kind = spec["kind"]
        if kind == "ref":
            declared = self.data_type.nested_type_def(spec["name"])
            fields = declared.data_fields
            if declared.is_union:
                tag = _join(path, "_tag")
                bits = max(1, math.ceil(math.log2(len(fields))))
                self.add(tag, f"uint{bits}", INT32, "union_tag", 0, len(fields) - 1, requires)
                for number, f in enumerate(fields):
                    self.walk(f.type, _join(path, f.name), (*requires, (tag, "==", number)))
                return
            for f in fields:
                if not _is_version(f):
                    self.walk(f.type, _join(path, f.name), requires)
        elif kind == "array":
            for i in range(spec["len"]):
                self.walk(spec["elem"], f"{path}[{i}]", requires)
        elif kind == "dynarray":
            length = _join(path, "_len")
            bits = max(1, length_bits(int(spec["max"])))
            self.add(length, f"uint{bits}", INT32, "length", 0, spec["max"], requires)
            for i in range(spec["max"]):
                self.walk(spec["elem"], f"{path}[{i}]", (*requires, (length, ">", i)))
        elif kind == "bool":
            self.add(path, "bool", INT32, "value", 0, 1, requires)
        elif kind in ("uint", "int", "float"):
            bits = int(spec["bits"])
            name = f"{kind}{bits}"
            if bits > MAX_LEAF_BITS:
                raise FlatError(
                    f"{self.key}: leaf {path or '(value)'} is {name}: destructured parameters "
                    f"carry at most {MAX_LEAF_BITS} bits (MAVLink), so this type cannot be a "
                    "parameter"
                )
            if kind == "float":
                top = FLOAT_MAX[16 if bits == 16 else 32]
                self.add(path, name, FLOAT32, "value", -top, top, requires)
            elif kind == "uint":
                self.add(path, name, INT32, "value", 0, (1 << bits) - 1, requires)
            else:
                half = 1 << (bits - 1)
                self.add(path, name, INT32, "value", -half, half - 1, requires)
        # void: padding, not a leaf


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


# -- type level: values <-> flat letters ------------------------------------------------------


def to_flat(data_type: DataType, value: Mapping[str, Any] | bytes) -> dict[str, int | float]:
    """The live leaves of a value (or of its stored bytes) as ``{letter: number}``, in letter
    order, numbers as the flat parameters carry them."""
    data = value if isinstance(value, bytes) else data_type.encode(value, tao=False)
    return _flat_of_leaves(layout(data_type), data_type.leaves(data, tao=False))


def _flat_of_leaves(lay: FlatLayout, leaves: list[Leaf]) -> dict[str, int | float]:
    flat: dict[str, int | float] = {}
    for leaf in leaves:
        slot = lay.slot_for_path(leaf.path)
        if slot is not None:
            flat[slot.letter] = slot.to_flat(leaf.value)
    return flat


def from_flat(data_type: DataType, flat: Mapping[str, Any]) -> dict[str, Any]:
    """The value whose live leaves are ``flat`` (``{letter: number}``): the inverse of
    :func:`to_flat`. Every live letter must be given and no other."""
    lay = layout(data_type)
    used: set[str] = set()

    def take(path: str) -> Any:
        slot = lay.slot_for_path(path)
        assert slot is not None
        if slot.letter not in flat:
            raise FlatError(f"{data_type.key}: letter {slot.letter} ({path}) is missing")
        used.add(slot.letter)
        try:
            return slot.from_flat(flat[slot.letter])
        except FlatError as e:
            raise FlatError(f"{data_type.key}: letter {slot.letter} ({path}): {e}") from None

    def build(spec: Mapping[str, Any], path: str) -> Any:
        kind = spec["kind"]
        if kind == "ref":
            declared = data_type.nested_type_def(spec["name"])
            fields = declared.data_fields
            if declared.is_union:
                tag = take(_join(path, "_tag"))
                if not 0 <= tag < len(fields):
                    raise FlatError(
                        f"{data_type.key}: {_join(path, '_tag')}: no variant {tag} "
                        f"(expected 0 to {len(fields) - 1})"
                    )
                chosen = fields[tag]
                return {chosen.name: build(chosen.type, _join(path, chosen.name))}
            return {
                f.name: build(f.type, _join(path, f.name)) for f in fields if not _is_version(f)
            }
        if kind == "array":
            return [build(spec["elem"], f"{path}[{i}]") for i in range(spec["len"])]
        if kind == "dynarray":
            length = take(_join(path, "_len"))
            if not 0 <= length <= spec["max"]:
                raise FlatError(
                    f"{data_type.key}: {_join(path, '_len')}: length {length} is out of range "
                    f"(expected 0 to {spec['max']})"
                )
            return [build(spec["elem"], f"{path}[{i}]") for i in range(length)]
        return take(path)

    value: dict[str, Any] = build({"kind": "ref", "name": data_type.key}, "")
    extra = [letter for letter in flat if letter not in used]
    if extra:
        paths = ", ".join(
            f"{x} ({s.path})" if (s := lay.slot(x)) else f"{x} (no such letter)" for x in extra
        )
        raise FlatError(f"{data_type.key}: letters not live in this value: {paths}")
    return value


# -- store level: flat names of instances -----------------------------------------------------


class FlatParam(NamedTuple):
    """One live destructured parameter of a store."""

    #: Flat name, e.g. ``INA238_1C``.
    name: str
    #: The instance, e.g. ``INA238#1``.
    instance: Key
    #: The leaf's ``[k]`` index in the current value.
    index: int  # type: ignore[assignment]  # a field named index hides tuple.index, as Leaf's must
    slot: FlatSlot
    #: The value as the flat parameter carries it (``int`` for ``int32``).
    value: int | float

    @property
    def leaf(self) -> Key:
        """The leaf's structured key, ``INA238#1[4]``."""
        return self.instance.at(self.index)

    @property
    def target(self) -> Key:
        """The leaf by its path, ``INA238#1.bus.i2c.address``: what a write names (the store
        takes its range from the path without asking the core which leaf ``[k]`` is)."""
        return self.instance.at(self.slot.path)

    @property
    def path(self) -> str:
        return self.slot.path

    @property
    def type(self) -> str:
        return self.slot.type

    @property
    def mav_type(self) -> str:
        return self.slot.mav_type

    def as_dict(self) -> dict[str, Any]:
        value: Any = self.value
        if isinstance(value, float) and not math.isfinite(value):
            value = "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
        return {
            "name": self.name,
            "leaf": str(self.leaf),
            "path": f"{self.instance}.{self.path}",
            "type": self.type,
            "mav_type": self.mav_type,
            "role": self.slot.role,
            "value": value,
        }


class FlatMap:
    """The destructured names of a store's parameter set, checked at construction in time
    proportional to the parameter set (not to ``max_instances`` times the letters): a name is
    worked out when it is asked for, and a type's letters when one of its instances is."""

    def __init__(self, store: Store) -> None:
        self._store = store
        self._specs = {spec.name: spec for spec in store.specs}
        structured = set(self._specs)
        classic = [name for name in store.parameters if name not in structured]
        for spec in store.specs:
            self._check_length(spec, slot_count(spec.data_type))
        # Flat names cannot clash with each other (a parameter name, then "_", then digits and
        # letters: each name has one owner); they can be another parameter's name.
        for kind, names in (("classic", classic), ("structured", sorted(structured))):
            for name in names:
                owner = self._parse(name)
                if owner is not None:
                    spec, number, index = owner
                    slot = self.layout_of(spec.name).slots[index]
                    raise FlatError(
                        f"{spec.name}: destructured name {name} "
                        f"({spec.instance_name(number or 0)}.{slot.path}) is the name of a "
                        f"{kind} parameter"
                    )
        self._masks: dict[str, ParamSpec] = {}
        for spec in store.specs:
            if spec.shared or (spec.max_instances or 0) > MASK_BITS:
                continue  # no instances to add, or more than one int32 can list
            name = mask_name(spec)
            if len(name) > MAX_NAME_LEN or name in classic or self._parse(name) is not None:
                raise FlatError(
                    f"{spec.name}: instance mask {name} is longer than {MAX_NAME_LEN} characters "
                    "or the name of another parameter"
                )
            self._masks[name] = spec

    def _check_length(self, spec: ParamSpec, count: int) -> None:
        """Refuses the first name (in instance, then letter order) over 16 characters."""
        if not count:
            return
        numbers = [None] if spec.shared else [0, *(10**d for d in range(1, 6))]
        for number in numbers:
            if number is not None and number >= (spec.max_instances or 0):
                break
            room = (
                MAX_NAME_LEN - len(spec.name) - 1 - len(str(number) if number is not None else "")
            )
            first = _first_with_letters(room + 1)  # the first letter number too long to fit
            if first < count:
                name = _flat_name(spec, number, letters(first))
                raise FlatError(
                    f"{spec.name}: destructured name {name} has {len(name)} characters "
                    f"(at most {MAX_NAME_LEN}): {spec.data_type.key} has {count} flat leaves; "
                    "shorten the parameter name or the type"
                )

    def _parse(self, name: str) -> tuple[ParamSpec, int | None, int] | None:
        """``(parameter, instance number, letter number)`` whose flat name ``name`` is exactly,
        or None."""
        if len(name) > MAX_NAME_LEN:
            return None
        at = name.find("_")
        while at > 0:
            spec = self._specs.get(name[:at])
            if spec is not None:
                found = self._parse_rest(spec, name[at + 1 :])
                if found is not None:
                    return found
            at = name.find("_", at + 1)
        return None

    def _parse_rest(self, spec: ParamSpec, rest: str) -> tuple[ParamSpec, int | None, int] | None:
        number: int | None = None
        if not spec.shared:
            end = 0
            while end < len(rest) and rest[end] in "0123456789":
                end += 1
            digits, rest = rest[:end], rest[end:]
            if not digits or str(int(digits)) != digits or int(digits) >= (spec.max_instances or 0):
                return None
            number = int(digits)
        index = letter_number(rest)
        if index is None or index >= slot_count(spec.data_type):
            return None
        return spec, number, index

    def names(self) -> Iterator[str]:
        """Every destructured name a vehicle can report (each instance slot, each letter): a
        long walk for types with many; commands ask for names one by one instead."""
        for spec in self._store.specs:
            numbers: list[int | None] = (
                [None] if spec.shared else list(range(spec.max_instances or 0))
            )
            for number in numbers:
                for slot in self.layout_of(spec.name):
                    yield self.name_of(spec, number, slot)

    # -- instance masks: adding and removing instances with a flat write -------------------

    def masks(self) -> list[tuple[str, ParamSpec, int]]:
        """``(name, parameter, value)`` of every instance mask: bit N set while ``NAME#N``
        exists."""
        return [(name, spec, self.mask_value(spec)) for name, spec in self._masks.items()]

    def mask_spec(self, name: str) -> ParamSpec | None:
        """The parameter whose instance mask ``name`` is, or None."""
        return self._masks.get(name)  # exact, as PX4's names

    def mask_value(self, spec: ParamSpec) -> int:
        return sum(1 << (key.instance or 0) for key in self._store.instance_keys(spec.name))

    def set_mask(self, name: str, number: Any) -> tuple[list[str], list[str]]:
        """Adds the instances whose bits ``number`` sets and removes those it clears, all or
        nothing; returns ``(added, removed)``."""
        spec = self.mask_spec(name)
        if spec is None:
            raise InstanceError(f"'{name}' is not an instance mask")
        if isinstance(number, float) and number.is_integer():
            number = int(number)
        slots = spec.max_instances or 0
        if isinstance(number, bool) or not isinstance(number, int) or not 0 <= number < 1 << slots:
            raise FlatError(
                f"{mask_name(spec)}: value {number!r} is not a mask of {spec.name}'s "
                f"{slots} instances (expected 0 to {(1 << slots) - 1})"
            )
        current = self.mask_value(spec)
        added = [
            spec.instance_key(n) for n in range(slots) if number >> n & 1 and not current >> n & 1
        ]
        removed = [
            spec.instance_key(n) for n in range(slots) if current >> n & 1 and not number >> n & 1
        ]
        with self._store.transaction():
            for instance in removed:
                self._store.remove(instance)
            for instance in added:
                self._store.add(instance)
        return [str(k) for k in added], [str(k) for k in removed]

    @staticmethod
    def name_of(spec: ParamSpec, number: int | None, slot: FlatSlot) -> str:
        return _flat_name(spec, number, slot.letter)

    def layout_of(self, param: str) -> FlatLayout:
        """The letters of ``param``'s type (worked out on first use)."""
        return layout(self._specs[param].data_type)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self._parse(name) is not None

    def _owner(self, name: str) -> tuple[ParamSpec, int | None, FlatSlot] | None:
        found = self._parse(name)  # exact, as PX4's names
        if found is None:
            return None
        spec, number, index = found
        return spec, number, self.layout_of(spec.name).slots[index]

    def lookup(self, name: str) -> tuple[Key, FlatSlot] | None:
        """``(instance, slot)`` of a flat name, live or not; None if it is not one."""
        found = self._owner(name)
        if found is None:
            return None
        spec, number, slot = found
        return spec.instance_key(number or 0), slot

    def owner(self, name: str) -> tuple[Key, FlatSlot]:
        """``(instance, slot)`` of a flat name, live or not; :class:`InstanceError` if the name
        belongs to no structured parameter."""
        found = self.lookup(name)
        if found is None:
            beyond = self._beyond_max(name)
            if beyond is not None:
                raise InstanceError(beyond)
            exact = name.strip().upper()
            hint = f" (did you mean {exact}?)" if exact != name and exact in self else ""
            raise InstanceError(f"'{name}' is not a destructured parameter name{hint}")
        return found

    def _beyond_max(self, name: str) -> str | None:
        """Why ``name`` would be a flat name but for its instance number (``INA238_9P`` where
        INA238 has 4), as the store says it of ``INA238#9``; None if that is not why."""
        for at in (i for i, c in enumerate(name) if c == "_"):
            spec = self._specs.get(name[:at])
            if spec is None or spec.shared or not spec.max_instances:
                continue
            rest = name[at + 1 :]
            digits = rest[: len(rest) - len(rest.lstrip("0123456789"))]
            beyond = digits and str(int(digits)) == digits and int(digits) >= spec.max_instances
            if beyond and self._parse_rest(spec, "0" + rest[len(digits) :]) is not None:
                top = spec.max_instances
                return (
                    f"{name}: instance {digits} is out of range (max_instances is {top}: "
                    f"instances 0..{top - 1})"
                )
        return None

    def table(self) -> list[FlatParam]:
        """Every live flat parameter of every existing instance, in store order."""
        rows: list[FlatParam] = []
        for instance in self._store.instance_keys():
            spec = self._specs.get(instance.param)
            if spec is None:
                continue  # a classic parameter
            lay = self.layout_of(spec.name)  # (worked out for types with instances only)
            for leaf in self._store.leaves(instance):
                slot = lay.slot_for_path(leaf.path)
                if slot is None:
                    continue  # p_version
                name = self.name_of(spec, instance.instance, slot)
                rows.append(FlatParam(name, instance, leaf.index, slot, slot.to_flat(leaf.value)))
        return rows

    def find(self, name: str) -> FlatParam:
        """The live flat parameter ``name``; a clear error when its instance does not exist or
        its leaf is not live (an unselected variant, an array element past the length)."""
        return self.live(name, *self.owner(name))

    def live(self, name: str, instance: Key, slot: FlatSlot) -> FlatParam:
        """:meth:`find` of a name whose :meth:`owner` is known: its leaf, looked up once."""
        try:
            leaf = self._store.leaf(instance.at(slot.path))
        except InstanceError:
            if instance in self._store:
                raise
            raise InstanceError(
                f"{name} belongs to {instance}, which does not exist (add it first: "
                f"param add {instance})"
            ) from None
        except LeafError:
            why = self._why(instance, slot)
            raise LeafError(f"{name} ({instance}.{slot.path}) is not live: {why}") from None
        return FlatParam(name, instance, leaf.index, slot, slot.to_flat(leaf.value))

    def _why(self, instance: Key, slot: FlatSlot) -> str:
        spec = self._specs[instance.param]
        live = {leaf.path: leaf.value for leaf in self._store.leaves(instance)}
        for path, op, n in slot.requires:
            if path not in live:
                continue  # an outer requirement fails first
            selector = self.layout_of(spec.name).slot_for_path(path)
            assert selector is not None
            selector_name = self.name_of(spec, instance.instance, selector)
            if op == "==" and live[path] != n:
                return f"{path} selects variant {live[path]}, not {n} (set {selector_name} to {n})"
            if op == ">" and not live[path] > n:
                return f"{path} is {live[path]} (set {selector_name} above {n})"
        return "not in the current value"  # pragma: no cover - requires cover every case


def _flat_name(spec: ParamSpec, number: int | None, letter: str) -> str:
    """``INA238_1C``; ``INA238_SHARED_A`` for a shared parameter."""
    if spec.shared or number is None:
        return f"{spec.name}_{letter}"
    return f"{spec.name}_{number}{letter}"


def flat_map(store: Store) -> FlatMap:
    """The store's :class:`FlatMap` (built and checked with the store)."""
    return store.destructured


def flat_table(store: Store) -> list[FlatParam]:
    """Every live destructured parameter (``px4params param flat``)."""
    return flat_map(store).table()


def resolve_flat(store: Store, name: str) -> str:
    """The structured leaf name of a live flat parameter: ``INA238_1C`` -> ``INA238#1[4]``."""
    return str(flat_map(store).find(name).leaf)


def get_flat(store: Store, name: str) -> int | float:
    """A live flat parameter's value as it is carried (``int32`` or ``float32``)."""
    return flat_map(store).find(name).value


def set_flat(store: Store, name: str, number: Any, *, default: bool = False) -> FlatParam:
    """Writes a flat parameter's number to its leaf (the store checks the range; a refused
    write changes nothing) and returns the parameter as stored (floats rounded)."""
    return write_live(store, flat_map(store).find(name), number, default=default)


def write_live(
    store: Store, param: FlatParam, number: Any, *, default: bool = False, force: bool = False
) -> FlatParam:
    """:func:`set_flat` of a parameter found already (:meth:`FlatMap.live`); ``force`` as
    :meth:`Store.set`'s."""
    try:
        value = param.slot.from_flat(number)
    except FlatError as e:
        raise FlatError(f"{param.name} ({param.instance}.{param.path}): {e}") from None
    target = param.target
    if default:
        store.set_default(target, value, force=force)
    else:
        store.set(target, value, force=force)
    # As the vehicle now carries it (the value: after a new default, it follows unless
    # changed); the leaf keeps its [k] (a union tag or a length is before what it changes).
    return param._replace(value=param.slot.to_flat(store.get(target)))


def flat_values(store: Store) -> dict[str, int | float]:
    """What a ground station sees of a store: every classic parameter, every live destructured
    name and every instance mask, with the numbers they carry (name -> int or float)."""
    fmap = flat_map(store)
    values: dict[str, int | float] = {}
    for name in store.parameters:
        if store.classic(name) is not None:
            values[name] = store.get(name)
    for row in fmap.table():
        values[row.name] = row.value
    for name, _, mask in fmap.masks():
        values[name] = mask
    return values


def merged_mask(now: int, was: int, wanted: int) -> int:
    """The instance mask ``now`` with the bits a writer changed from ``was`` to ``wanted``:
    another writer's additions and removals since ``was`` stay."""
    changed = was ^ wanted
    return (now & ~changed) | (wanted & changed)


def write_flat(store: Store, name: str, number: Any, *, was: int | None = None) -> str:
    """Writes one parameter as a ground station names it (a classic name, a destructured name
    or an instance mask), checked by the store; a refused write raises and changes nothing.
    ``was``: for an instance mask, the mask the writer's value was made from; only the bits it
    changes are written (:func:`merged_mask`). Returns a short description of what changed."""
    fmap = flat_map(store)
    owner = fmap.lookup(name)  # the name read once: it names the leaf the write is given
    if owner is not None:
        param = write_live(store, fmap.live(name, *owner), number)
        return f"{name} = {param.value}"
    spec = fmap.mask_spec(name)
    if spec is not None:
        if was is not None and type(number) is int:
            number = merged_mask(fmap.mask_value(spec), was, number)
        added, removed = fmap.set_mask(name, number)
        changes = [f"added {n}" for n in added] + [f"removed {n}" for n in removed]
        return f"{name}: " + (", ".join(changes) or "no change")
    classic = store.classic(name)
    if classic is None:
        raise InstanceError(f"unknown parameter '{name}'")
    store.set(name, number)
    return f"{name} = {store.get(name)}"
