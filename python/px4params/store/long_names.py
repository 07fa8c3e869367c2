"""DroneCAN's names of destructured parameters: the talk's long, readable names.

DroneCAN's ``uavcan.protocol.param.GetSet`` carries names of up to 92 characters and 64-bit
integers, so the leaves of a structured instance need no letters there (MAVLink's 16 characters
do, :mod:`px4params.store.flat`). A leaf's long name is the instance and the leaf's path, upper
case, joined with ``_``::

    INA238#1.bus._tag          -> INA238_1_BUS_TYPE      (a union's tag: <FIELD>_TYPE)
    INA238#1.bus.i2c.bus_id    -> INA238_1_I2C_BUS_ID    (the variant names the union)
    INA238#1.bus.i2c.address   -> INA238_1_I2C_ADDRESS
    INA238#1.shunt             -> INA238_1_SHUNT
    INA238_SHARED.x            -> INA238_SHARED_X        (a shared parameter: no number)

Inside a union the selected variant's name stands for the union field (``I2C_ADDRESS``, not
``BUS_I2C_ADDRESS``), as in the talk. Array elements are numbered (``CELLS_3``), a dynamic
array's length is ``<FIELD>_LEN``. Where two leaves of one type would get the same short name
(two unions with a variant of one name), those leaves keep their whole path instead. Names are
given over the type, like the letters, so a leaf's name never depends on its value; which
leaves are *live* (selected variant, existing elements) does. The instance mask keeps its flat
name (``INA238_INST``).

Names are checked when the map is built: at most 92 characters and none equal to another
parameter's name; a violation is a :class:`FlatError` naming the parameter.
"""

from __future__ import annotations

from collections import Counter
from typing import TYPE_CHECKING, NamedTuple

from px4params.errors import FlatError
from px4params.store.flat import FlatLayout, FlatSlot, layout, mask_name
from px4params.store.key import Key
from px4params.store.spec import ParamSpec

if TYPE_CHECKING:
    from px4params.store.store import Store

__all__ = ["MAX_LONG_NAME_LEN", "LongLeaf", "LongNames", "leaf_names"]

#: ``uavcan.protocol.param.GetSet``'s name is ``uint8[<=92]``.
MAX_LONG_NAME_LEN = 92


def _components(path: str, unions: set[str]) -> list[str]:
    """The name parts of a leaf path: ``bus.i2c.address`` -> ``[I2C, ADDRESS]`` when ``bus``
    is a union."""
    parts: list[str] = []
    prefix, plain = "", False
    for piece in path.split("."):
        field, _, rest = piece.partition("[")
        if prefix in unions and plain and field != "_tag":
            parts.pop()  # the variant stands for the union field (not for an element number)
        parts.append({"_tag": "TYPE", "_len": "LEN"}.get(field, field.upper()))
        if rest:
            parts.extend(rest.rstrip("]").split("]["))
        prefix, plain = (f"{prefix}.{piece}" if prefix else piece), not rest
    return parts


def leaf_names(lay: FlatLayout) -> dict[str, str]:
    """``{leaf path: long name part}`` of every slot of a type (see the module doc)."""
    unions = {
        tag[: -len("._tag")] if tag != "_tag" else ""
        for slot in lay
        for tag, op, _ in slot.requires
        if op == "=="
    }
    short = {slot.path: "_".join(_components(slot.path, unions)) for slot in lay}
    counts = Counter(short.values())
    return {
        path: name if counts[name] == 1 else "_".join(_components(path, set()))
        for path, name in short.items()
    }


class LongLeaf(NamedTuple):
    """One live leaf under its long name."""

    name: str
    #: The instance, e.g. ``INA238#1``.
    instance: Key
    #: The leaf's ``[k]`` index in the current value.
    index: int  # type: ignore[assignment]  # a field named index hides tuple.index, as Leaf's must
    slot: FlatSlot

    @property
    def leaf(self) -> Key:
        """``INA238#1[4]``."""
        return self.instance.at(self.index)

    @property
    def target(self) -> Key:
        """The leaf by its path, ``INA238#1.bus.i2c.address``: what a write names (resolved
        already: the store takes its range from the path and the core finds the leaf once)."""
        return self.instance.at(self.slot.path)


class LongNames:
    """The long names of a store's parameter set, checked at construction in time proportional
    to its types' leaves (not to ``max_instances`` times them: a name's owner is worked out by
    reading the name, not by listing every instance's names)."""

    def __init__(self, store: Store) -> None:
        self._store = store
        self._specs = {spec.name: spec for spec in store.specs}
        self._parts: dict[str, dict[str, str]] = {}
        #: Per parameter, ``{long name part: slot}``.
        self._slots: dict[str, dict[str, FlatSlot]] = {}
        for spec in store.specs:
            lay = layout(spec.data_type)
            parts = self._parts[spec.name] = leaf_names(lay)
            by_part: dict[str, FlatSlot] = {}
            for slot in lay:
                part = parts[slot.path]
                if part in by_part:  # one instance's names clash with each other
                    self._clash(spec, None if spec.shared else 0, slot, by_part[part])
                by_part[part] = slot
            self._slots[spec.name] = by_part
            self._check_length(spec, lay)
        taken = set(store.parameters) | {name for name, _, _ in store.destructured.masks()}
        for name in sorted(taken):
            owner = self._parse(name)
            if owner is not None:
                self._clash(*owner)
        # A parameter named like another's long names (INA238_1 beside INA238): its names are
        # listed and read back as the other's (rare: parameters are named after their types).
        for longer in store.specs:
            if any(longer.name.startswith(f"{name}_") for name in self._specs):
                for name, number, slot in self._names_of(longer):
                    other = self._parse(name)
                    if other is not None and other[0] is not longer:
                        self._clash(longer, number, slot)

    def _check_length(self, spec: ParamSpec, lay: FlatLayout) -> None:
        """Refuses the first name (in instance, then leaf order) over 92 characters."""
        numbers = [None] if spec.shared else [0, *(10**d for d in range(1, 6))]
        parts = self._parts[spec.name]
        for number in numbers:
            if number is not None and number >= (spec.max_instances or 0):
                break
            for slot in lay:
                name = self.name_of(spec, number, parts[slot.path])
                if len(name) > MAX_LONG_NAME_LEN:
                    where = f"{spec.instance_name(number or 0)}.{slot.path}"
                    raise FlatError(
                        f"{spec.name}: DroneCAN name {name} ({where}) has {len(name)} "
                        f"characters (at most {MAX_LONG_NAME_LEN})"
                    )

    def _clash(
        self, spec: ParamSpec, number: int | None, slot: FlatSlot, leaf: FlatSlot | None = None
    ) -> None:
        """Refuses a long name taken twice: by another parameter, or by ``leaf`` of the same."""
        name = self.name_of(spec, number, self._parts[spec.name][slot.path])
        instance = spec.instance_name(number or 0)
        if leaf is not None:
            raise FlatError(
                f"{spec.name}: DroneCAN name {name} is the name of two of its leaves, "
                f"{instance}.{leaf.path} and {instance}.{slot.path}"
            )
        raise FlatError(
            f"{spec.name}: DroneCAN name {name} ({instance}.{slot.path}) is the name of another "
            "parameter"
        )

    def _names_of(self, spec: ParamSpec) -> list[tuple[str, int | None, FlatSlot]]:
        numbers: list[int | None] = [None] if spec.shared else list(range(spec.max_instances or 0))
        parts = self._parts[spec.name]
        return [
            (self.name_of(spec, number, parts[slot.path]), number, slot)
            for number in numbers
            for slot in layout(spec.data_type)
        ]

    def _parse(self, name: str) -> tuple[ParamSpec, int | None, FlatSlot] | None:
        """``(parameter, instance number, slot)`` whose long name ``name`` is exactly, or None."""
        at = name.find("_")
        while at > 0:
            spec = self._specs.get(name[:at])
            if spec is not None:
                rest, number = name[at + 1 :], None
                if not spec.shared:
                    digits, _, rest = rest.partition("_")
                    ok = digits.isascii() and digits.isdigit() and str(int(digits)) == digits
                    number = int(digits) if ok else None
                    if number is None or number >= (spec.max_instances or 0):
                        at = name.find("_", at + 1)
                        continue
                slot = self._slots[spec.name].get(rest)
                if slot is not None:
                    return spec, number, slot
            at = name.find("_", at + 1)
        return None

    @staticmethod
    def name_of(spec: ParamSpec, number: int | None, part: str) -> str:
        if spec.shared or number is None:
            return f"{spec.name}_{part}"
        return f"{spec.name}_{number}_{part}"

    def table(self) -> list[LongLeaf]:
        """Every live leaf of every existing instance, in store order."""
        rows: list[LongLeaf] = []
        for instance in self._store.instance_keys():
            spec = self._specs.get(instance.param)
            if spec is None:
                continue  # a classic parameter
            lay, parts = layout(spec.data_type), self._parts[spec.name]
            for leaf in self._store.leaves(instance):
                slot = lay.slot_for_path(leaf.path)
                if slot is not None:  # p_version has none
                    name = self.name_of(spec, instance.instance, parts[slot.path])
                    rows.append(LongLeaf(name, instance, leaf.index, slot))
        return rows

    def mask_names(self) -> dict[str, ParamSpec]:
        """The instance masks, by name (``INA238_INST``)."""
        return {mask_name(spec): spec for _, spec, _ in self._store.destructured.masks()}
