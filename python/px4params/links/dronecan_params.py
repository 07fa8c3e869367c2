"""The store's parameters as DroneCAN's ``uavcan.protocol.param.GetSet`` sees them.

Every classic parameter, every live leaf of every structured instance under its long name
(:mod:`px4params.store.long_names`: ``INA238_1_I2C_ADDRESS``) and every instance mask
(``INA238_INST``), sorted by name as PX4 sorts its parameters; the index of GetSet is the
position in that list. Writing a union tag, an array length or a mask changes which names are
live, and so the list.

Values travel in ``uavcan.protocol.param.Value``'s variants, one per kind of leaf, and a write
must use the parameter's own variant (PX4's node ignores others too):

* ``integer_value`` (int64): integer leaves, union tags, array lengths, masks, Int32 classics;
* ``real_value`` (float32): float leaves (a float16 leaf stores the value rounded) and Float
  classics;
* ``boolean_value``: bool leaves.

``min_value``/``max_value`` are a leaf's range, which the store checks, or a classic
parameter's metadata ``min``/``max`` (shown, not enforced, as PX4 does; int32's range without
them); ``default_value`` is the default (empty where the default value has another shape, e.g.
selects another union variant).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

from px4params.errors import Px4ParamsError
from px4params.numbers import FLOAT_MAX
from px4params.store import flat
from px4params.store.classic import INT32_MAX, INT32_MIN, ClassicParam
from px4params.store.long_names import LongLeaf, LongNames
from px4params.store.spec import ParamSpec, generic_path, leaf_ranges

if TYPE_CHECKING:
    from px4params.store.store import Store

__all__ = ["EMPTY", "DronecanParams", "GetSetEntry"]

#: The empty variant of ``Value`` and ``NumericValue``.
EMPTY: dict[str, Any] = {"empty": {}}


class GetSetEntry(NamedTuple):
    """One parameter of the list: what GetSet's response carries for it."""

    name: str
    value: dict[str, Any]
    default: dict[str, Any]
    min: dict[str, Any]
    max: dict[str, Any]


def _real(number: float) -> dict[str, Any]:
    return {"real_value": float(number)}


def _integer(number: int | float) -> dict[str, Any]:
    return {"integer_value": int(number)}


def _numeric(number: Any, variant: str) -> dict[str, Any]:
    if number is None or isinstance(number, bool) or not isinstance(number, int | float):
        return EMPTY
    if variant == "real_value":
        return _real(number) if math.isfinite(number) and abs(number) <= FLOAT_MAX[32] else EMPTY
    return _integer(number) if float(number).is_integer() else EMPTY


def variant_name(value: dict[str, Any]) -> str:
    """``integer_value`` of ``{"integer_value": 3}``."""
    return next(iter(value)) if value else "empty"


def _variant_of(ref: ClassicParam | ParamSpec | LongLeaf) -> str:
    """The ``Value`` variant a parameter of the list takes (see the module doc)."""
    if isinstance(ref, ClassicParam):
        return "real_value" if ref.is_float else "integer_value"
    if isinstance(ref, ParamSpec):
        return "integer_value"
    if ref.slot.type == "bool":
        return "boolean_value"
    return "real_value" if ref.slot.mav_type == flat.FLOAT32 else "integer_value"


class DronecanParams:
    """The GetSet list of ``store`` (built on demand, rebuilt after a write changes it)."""

    def __init__(self, store: Store) -> None:
        self.store = store
        self.names = LongNames(store)  # refuses names over 92 characters or clashing ones
        self._masks = self.names.mask_names()
        self._list: list[tuple[str, Any]] | None = None
        self._index: dict[str, int] = {}

    # -- the list ------------------------------------------------------------------------------

    def _rows(self) -> list[tuple[str, Any]]:
        if self._list is None:
            rows: list[tuple[str, Any]] = []
            for name in self.store.parameters:
                classic = self.store.classic(name)
                if classic is not None:
                    rows.append((name, classic))
            rows += [(leaf.name, leaf) for leaf in self.names.table()]
            rows += list(self._masks.items())
            rows.sort(key=lambda row: row[0].encode())
            self._list = rows
            self._index = {name: i for i, (name, _) in enumerate(rows)}
        return self._list

    def __len__(self) -> int:
        return len(self._rows())

    def name_at(self, index: int) -> str | None:
        rows = self._rows()
        return rows[index][0] if 0 <= index < len(rows) else None

    def index_of(self, name: str) -> int | None:
        self._rows()
        return self._index.get(name)

    def entry(self, name: str) -> GetSetEntry | None:
        """What GetSet answers for ``name``; None when no such parameter is live."""
        index = self.index_of(name)
        if index is None:
            return None
        ref = self._rows()[index][1]
        if isinstance(ref, ClassicParam):
            return self._classic_entry(ref)
        if isinstance(ref, ParamSpec):
            mask = self.store.destructured.mask_value(ref)
            top = (1 << (ref.max_instances or 0)) - 1
            return GetSetEntry(name, _integer(mask), _integer(0), _integer(0), _integer(top))
        return self._leaf_entry(ref)

    def _classic_entry(self, classic: ClassicParam) -> GetSetEntry:
        variant = _variant_of(classic)
        value = self.store.get(classic.name)
        low, high = classic.entry.get("min"), classic.entry.get("max")
        if not classic.is_float:  # without metadata bounds, the store checks int32's
            low = INT32_MIN if low is None else low
            high = INT32_MAX if high is None else high
        return GetSetEntry(
            classic.name,
            {variant: value},
            _numeric(classic.default, variant) if classic.default is not None else EMPTY,
            _numeric(low, variant),
            _numeric(high, variant),
        )

    def _leaf_entry(self, leaf: LongLeaf) -> GetSetEntry:
        slot = leaf.slot
        current = self.store.leaf(leaf.leaf).value
        try:
            default_leaf = self.store.leaf(leaf.leaf, default=True)
            default: Any = default_leaf.value if default_leaf.path == slot.path else None
        except Px4ParamsError:  # the default value has another shape
            default = None
        variant = _variant_of(leaf)
        if variant == "boolean_value":
            value = {variant: int(bool(current))}
            shown = EMPTY if default is None else {variant: int(bool(default))}
            return GetSetEntry(leaf.name, value, shown, _integer(0), _integer(1))
        # The range the store enforces: the field's @min/@max where given, else its type's.
        spec = self.store.spec(leaf.instance.param)
        bounds = leaf_ranges(spec.data_type).get(generic_path(slot.path)) if spec else None
        low = slot.min if bounds is None or bounds.low is None else bounds.low
        high = slot.max if bounds is None or bounds.high is None else bounds.high
        return GetSetEntry(
            leaf.name,
            {variant: current},
            EMPTY if default is None else {variant: default},
            _numeric(low, variant),
            _numeric(high, variant),
        )

    # -- writes --------------------------------------------------------------------------------

    def set(self, name: str, value: dict[str, Any]) -> str:
        """Writes ``value`` (a ``Value`` variant) to ``name``, checked by the store; returns a
        line saying what changed.

        Raises:
            Px4ParamsError: the write is refused (no such parameter, another variant, out of
                range); nothing changed. The message names the parameter.
        """
        index = self.index_of(name)
        if index is None:
            raise Px4ParamsError(f"{name}: no such parameter")
        ref = self._rows()[index][1]
        # The variant is the parameter's kind's: known without reading its value.
        given, expected = variant_name(value), _variant_of(ref)
        if given != expected:
            raise Px4ParamsError(f"{name}: {given} refused: the parameter takes {expected}")
        number = value[given]
        try:
            with self.store.transaction():
                if isinstance(ref, ClassicParam):
                    flat.write_flat(self.store, name, number)
                    change = f"{name} = {self.store.get(name)}"
                elif isinstance(ref, ParamSpec):
                    added, removed = self.store.destructured.set_mask(name, number)
                    changes = [f"added {n}" for n in added] + [f"removed {n}" for n in removed]
                    change = f"{name}: " + (", ".join(changes) or "no change")
                else:
                    leaf_value = bool(number) if given == "boolean_value" else number
                    if given == "boolean_value" and number not in (0, 1):
                        raise Px4ParamsError(f"value {number} is not a boolean (0 or 1)")
                    # Written by its path, resolved when the list was made: the core finds
                    # the leaf once (a [k] would be looked up for its range, then again to be
                    # written); read back as stored (a float16 rounds).
                    target = ref.target
                    self.store.set(target, leaf_value)
                    change = f"{name} ({ref.leaf}) = {self.store.get(target)}"
        except Px4ParamsError as e:
            text = str(e)
            raise Px4ParamsError(text if text.startswith(name) else f"{name}: {text}") from None
        self._list = None  # a tag, length or mask may have changed what is live
        return change
