"""``parameters.json`` for ground stations: QGC component metadata with structured parameters.

The document is QGC's parameter component metadata (``{"version": 1, "parameters": [...]}``).
Classic parameters are copied unchanged from the ``parameters.json`` they came from. Each
structured parameter gets one entry with QGC's keys (``name``, ``type``, ``default``, ``group``,
``category``, ``shortDesc``, ``longDesc``, ``rebootRequired``) and, beside them, keys QGC ignores:

``max_instances``
    number of instance slots (``INA238#0`` ..), ``null`` for a shared parameter.
``default`` (a QGC key) is the hex encoding of the default value (DroneCAN rules, no tail
array optimization: how parameters are stored), a scalar QGC can hold as bytes; the value itself
is ``default_value``.
``dsdl_type``, ``max_bytes``, ``default_value``
    the DSDL type, the largest encoding and the default as a structured value.
``flat``
    the destructured names' letters in order (``letter``, ``path``, ``type`` ``Int32`` or
    ``Float``); each name (``INA238_1C``) also has an entry of its own, as classic parameters
    do, after the structured entries (see :func:`flat_entries`).
``fields``
    every leaf of the default value in ``[k]`` order (``index`` is ``k``). Each leaf has
    ``name`` (its DSDL field), ``path`` (``bus.i2c.address``), ``type`` (``uint7``,
    ``float16``, ``bool``), ``role`` and ``default``, ``min``, ``max``, and when the DSDL
    says so ``unit``, ``shortDesc``, ``longDesc``, ``decimalPlaces``, ``increment``,
    ``values`` (QGC's enum format), ``format`` (``hex``: shown in hex, from ``@format hex``)
    and ``cast`` (``saturated``/``truncated``).

Roles: ``value``; ``version`` (``p_version``, filled in by the code, its ``default`` is the
type's version); ``union_tag`` (path ``<union>._tag``; ``variants`` lists every variant with
its own ``fields``, so that any variant can be decoded; the selected variant's leaves follow the
tag inline); ``length`` (a dynamic array's length prefix, path ``<array>._len``; ``element``
describes one element with paths ``<array>[]...``, ``element_min_bits`` decides tail array
optimization); ``padding`` (``voidN`` bits, path ``<struct>._pad``, not a leaf: no ``index``).
Static array elements are leaves ``<array>[i]``. :mod:`px4params.gcs.codec` encodes and decodes
values from this description alone.
"""

from __future__ import annotations

import copy
import json
import os
from collections.abc import Mapping, Sequence
from typing import Any

from px4params.dsdl.model import NO_DOC, FieldDoc, length_bits, tag_bits
from px4params.dsdl.schema import Schema, to_json_value
from px4params.errors import FlatError, MetadataError
from px4params.numbers import FLOAT_MAX
from px4params.reading import CLASSIC_JSON, read_text
from px4params.store import flat
from px4params.store.classic import CLASSIC_ENV, ClassicParam, load_classic
from px4params.store.spec import ParamSpec, metadata_default, parameter_specs

__all__ = [
    "METADATA_VERSION",
    "QGC_TYPE",
    "MetadataError",
    "build_parameters_json",
    "classic_source",
    "describe_value",
    "destructured_names",
    "length_bits",
    "min_bits",
    "structured_entry",
    "tag_bits",
    "type_name",
]

#: QGC reads only version 1 of the parameter metadata and ignores the file otherwise.
METADATA_VERSION = 1

#: The ``type`` of a structured entry. QGC's FactMetaData::stringToType knows Uint8 .. Int64,
#: Float, Double, String, Bool, ElapsedSeconds and Custom (case-insensitively); an unknown type
#: makes QGC drop the entry's metadata with an "Unknown type" warning. "Custom" is the one type
#: that is honest (the value is no int32 or float) and whose conversions accept anything: QGC
#: turns the structured ``default`` into an (empty) byte array without an "Invalid default
#: value" warning, where "Int32" (the talk's slide) would warn. QGC builds older than the Custom
#: type skip just these entries, and QGC ignores the keys it does not know (max_instances,
#: fields, ...), so classic parameters load either way.
QGC_TYPE = "Custom"

#: PX4's names for a parameter without @group / @category.
DEFAULT_GROUP = "Miscellaneous"
DEFAULT_CATEGORY = "Standard"


def classic_source(explicit: str | os.PathLike[str] | None) -> str | None:
    """The classic ``parameters.json`` to include: ``explicit``, else
    ``$PX4PARAMS_PARAMETERS_JSON``, else None (no classic parameters)."""
    if explicit is not None:
        return os.fspath(explicit)
    return os.environ.get(CLASSIC_ENV) or None


def build_parameters_json(
    schema: Schema,
    classic_path: str | os.PathLike[str] | None = None,
    *,
    specs: Sequence[ParamSpec] | None = None,
    classic_params: Sequence[ClassicParam] | None = None,
) -> dict[str, Any]:
    """The whole document: the classic parameters of ``classic_path`` (in file order,
    unchanged, with its ``translation`` section), or ``classic_params`` (a store's), followed by
    every structured parameter and every destructured name."""
    classic: list[ClassicParam] = (
        load_classic(classic_path) if classic_path is not None else list(classic_params or ())
    )
    chosen = parameter_specs(schema) if specs is None else specs
    structured = [structured_entry(schema, s) for s in chosen]
    destructured = [
        e for s, entry in zip(chosen, structured, strict=True) for e in flat_entries(s, entry)
    ]
    classic_names = {p.name for p in classic}
    for entry in structured:
        if entry["name"] in classic_names:
            raise MetadataError(
                f"parameter {entry['name']} is both structured ({entry['dsdl_type']}) and "
                f"classic (in {os.fspath(classic_path or '')})"
            )
    for entry in destructured:  # a vehicle reports one value per name: QGC would show two
        if entry["name"] in classic_names:
            raise MetadataError(
                f"{entry['name']} is both a destructured name ({entry['shortDesc']}) and a "
                f"classic parameter (in {os.fspath(classic_path or '')})"
            )
    document: dict[str, Any] = {
        "version": METADATA_VERSION,
        "parameters": [dict(p.entry) for p in classic] + structured + destructured,
    }
    translation = _classic_translation(classic_path) if classic_path is not None else None
    if translation is not None:
        # QGC translates shortDesc/longDesc/... through this section; it keys entries by name,
        # so it covers the structured entries too.
        document["translation"] = translation
    return document


def destructured_names(entry: Mapping[str, Any]) -> set[str]:
    """The flat names a vehicle reports for a structured entry (:func:`structured_entry`): its
    instance mask ``INA238_INST`` (when the slots fit one) and every letter of every slot,
    ``INA238_0A`` .. ``INA238_3Q`` (``NAME_A`` .. for a shared parameter). None for another
    entry. A classic parameter may share the prefix (``INA238_CURRENT``): it is none of these."""
    letters = [slot["letter"] for slot in entry.get("flat", ())]
    slots = entry.get("max_instances") or 0
    name = entry["name"]
    if not slots:
        return {f"{name}_{letter}" for letter in letters}
    names = {f"{name}_{n}{letter}" for n in range(slots) for letter in letters}
    if letters and slots <= flat.MASK_BITS:
        names.add(f"{name}_INST")
    return names


def count_entries(document: Mapping[str, Any]) -> dict[str, int]:
    """How many entries of a document are structured, destructured (flat names) and classic."""
    entries = document["parameters"]
    structured = sum(1 for e in entries if e.get("type") == QGC_TYPE)
    destructured = sum(len(destructured_names(e)) for e in entries if e.get("type") == QGC_TYPE)
    return {
        "structured": structured,
        "destructured": destructured,
        "classic": len(entries) - structured - destructured,
    }


def _classic_translation(path: str | os.PathLike[str]) -> Any:
    # load_classic has read and checked the file already; it keeps only the parameters.
    return json.loads(read_text(path, CLASSIC_JSON)).get("translation")


def structured_entry(schema: Schema, spec: ParamSpec) -> dict[str, Any]:
    """The ``parameters.json`` entry of one structured parameter."""
    data_type = spec.data_type
    doc = data_type.doc
    default = metadata_default(schema, data_type.key)
    entry: dict[str, Any] = {
        "name": spec.name,
        "type": QGC_TYPE,
        # QGC holds a Custom default as bytes (QVariant::toByteArray): the encoding, in hex.
        "default": data_type.encode(default, tao=False).hex(),
        "group": doc.group or DEFAULT_GROUP,
        "category": doc.category or DEFAULT_CATEGORY,
        "shortDesc": doc.short or spec.name,
    }
    if doc.long:
        entry["longDesc"] = doc.long
    if doc.reboot_required is not None:
        entry["rebootRequired"] = doc.reboot_required
    entry["max_instances"] = spec.max_instances
    entry["dsdl_type"] = data_type.key
    entry["max_bytes"] = data_type.max_bytes
    entry["default_value"] = to_json_value(default)
    entry["fields"] = describe_value(schema, data_type.key, default)
    try:
        letters = flat.layout(data_type)
    except FlatError:
        return entry  # a leaf wider than 32 bits: the type has no destructured names
    entry["flat"] = [
        {"letter": slot.letter, "path": slot.path, "type": _QGC_FLAT_TYPE[slot.mav_type]}
        for slot in letters
    ]
    return entry


#: How a destructured leaf is carried, in parameters.json's type names.
_QGC_FLAT_TYPE = {flat.INT32: "Int32", flat.FLOAT32: "Float"}
_INT32_RANGE = (-(1 << 31), (1 << 31) - 1)


def flat_entries(spec: ParamSpec, entry: Mapping[str, Any]) -> list[dict[str, Any]]:
    """One ``parameters.json`` entry per destructured name a vehicle can report for ``spec``
    (its instance mask ``INA238_INST``, a bitmask, and every letter of every instance slot:
    ``INA238_0A`` .. ``INA238_3Q``), as the classic
    entries QGC matches by name: ``Int32`` or ``Float``, the leaf's default, range, unit,
    decimal places and enum values, and a description naming the instance and the path
    (``INA238 #1: bus.i2c.address``). ``entry`` is the parameter's :func:`structured_entry`."""
    if "flat" not in entry:
        return []
    out: list[dict[str, Any]] = []
    if not spec.shared and spec.slots <= flat.MASK_BITS:
        out.append(_mask_entry(spec, entry))
    leaves = _leaves_by_path(entry["fields"])
    numbers: list[int | None] = [None] if spec.shared else list(range(spec.slots))
    for number in numbers:
        owner = spec.name if number is None else f"{spec.name} #{number}"
        for slot in flat.layout(spec.data_type):
            leaf = leaves.get(slot.path) or leaves.get(_generic_path(slot.path)) or {}
            item: dict[str, Any] = {
                "name": flat.FlatMap.name_of(spec, number, slot),
                "type": _QGC_FLAT_TYPE[slot.mav_type],
                "default": slot.to_flat(leaf.get("default", 0)),
                "group": entry["group"],
                "category": entry["category"],
                "shortDesc": f"{owner}: {slot.path}",
            }
            about = [leaf.get("shortDesc", ""), leaf.get("longDesc", "")]
            live = [_condition(spec, number, path, op, n) for path, op, n in slot.requires]
            where = f"Leaf {slot.path} of {spec.instance_name(number or 0)} ({spec.name}, "
            where += f"{entry['dsdl_type']})" + (
                f", present while {' and '.join(live)}." if live else "."
            )
            item["longDesc"] = "\n".join(t for t in (*about, where) if t)
            low, high = _flat_range(slot, leaf)
            if low is not None:
                item["min"], item["max"] = low, high
            if "unit" in leaf:
                item["units"] = leaf["unit"]
            for key in ("decimalPlaces", "increment", "values"):
                if key in leaf:
                    item[key] = leaf[key]
            if "rebootRequired" in entry:
                item["rebootRequired"] = entry["rebootRequired"]
            out.append(item)
    return out


def _mask_entry(spec: ParamSpec, entry: Mapping[str, Any]) -> dict[str, Any]:
    """``INA238_INST``: which instances exist, one bit each; writing it adds and removes them."""
    item: dict[str, Any] = {
        "name": flat.mask_name(spec),
        "type": "Int32",
        "default": 0,
        "group": entry["group"],
        "category": entry["category"],
        "shortDesc": f"{spec.name} instances",
        "longDesc": (
            f"Bit N is set while {spec.name}#N exists. Setting a bit adds that instance with its "
            "defaults; clearing one removes it (the other instances keep their numbers)."
        ),
        "min": 0,
        "max": (1 << spec.slots) - 1,
        "bitmask": [{"index": n, "description": f"{spec.name} #{n}"} for n in range(spec.slots)],
    }
    if "rebootRequired" in entry:
        item["rebootRequired"] = entry["rebootRequired"]
    return item


def _leaves_by_path(fields: Sequence[Mapping[str, Any]]) -> dict[str, Mapping[str, Any]]:
    """Every described leaf by path, those of every union variant and array element too."""
    found: dict[str, Mapping[str, Any]] = {}
    for leaf in fields:
        if "path" in leaf:
            found.setdefault(leaf["path"], leaf)
        for variant in leaf.get("variants", ()):
            found.update(
                (k, v) for k, v in _leaves_by_path(variant["fields"]).items() if k not in found
            )
        if "element" in leaf:
            found.update(
                (k, v) for k, v in _leaves_by_path(leaf["element"]).items() if k not in found
            )
    return found


def _generic_path(path: str) -> str:
    """``arr[3].x`` -> ``arr[].x``: how a dynamic array's element is described."""
    import re

    return re.sub(r"\[\d+\]", "[]", path)


def _condition(spec: ParamSpec, number: int | None, path: str, op: str, n: int) -> str:
    selector = flat.layout(spec.data_type).slot_for_path(path)
    name = flat.FlatMap.name_of(spec, number, selector) if selector is not None else path
    return f"{name} = {n}" if op == "==" else f"{name} > {n}"


def _flat_range(slot: flat.FlatSlot, leaf: Mapping[str, Any]) -> tuple[Any, Any]:
    """The leaf's range (its ``@min``/``@max`` when given) as the flat parameter carries it;
    ``(None, None)`` when that is not one interval (a uint32 carried as its bit pattern)."""
    low, high = leaf.get("min", slot.min), leaf.get("max", slot.max)
    if slot.mav_type == flat.FLOAT32:
        return float(low), float(high)
    low, high = int(low), int(high)
    if not _INT32_RANGE[0] <= low <= high <= _INT32_RANGE[1]:
        return None, None
    return low, high


def describe_value(schema: Schema, key: str, value: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Every leaf of ``value`` (a value of type ``key`` as :meth:`DataType.encode` takes it;
    ``p_version`` may be left out) in ``[k]`` order, with the descriptions of unselected
    variants and array elements (see the module doc)."""
    # Refuse what does not encode (wrong shape, out of range) with the codec's messages.
    schema[key].encode(value, tao=False)
    entries: list[dict[str, Any]] = []
    _Describer(schema).struct(key, value, "", entries)
    numbered: list[dict[str, Any]] = []
    k = 0
    for entry in entries:
        if entry["role"] == "padding":
            numbered.append(entry)
        else:
            numbered.append({"index": k, **entry})
            k += 1
    return numbered


def type_name(spec: Mapping[str, Any]) -> str:
    """``uint7``, ``float16``, ``bool``, ``void3``, ``px.I2c.1.0``, ``uint8[<=92]``,
    ``float16[4]``."""
    kind = spec["kind"]
    if kind == "bool":
        return "bool"
    if kind in ("uint", "int", "float", "void"):
        return f"{kind}{spec['bits']}"
    if kind == "ref":
        return str(spec["name"])
    if kind == "array":
        return f"{type_name(spec['elem'])}[{spec['len']}]"
    return f"{type_name(spec['elem'])}[<={spec['max']}]"


def min_bits(schema: Schema, spec: Mapping[str, Any]) -> int:
    """The fewest bits a field of type ``spec`` encodes to (what decides whether a dynamic
    array's elements allow tail array optimization)."""
    kind = spec["kind"]
    if kind == "bool":
        return 1
    if kind in ("uint", "int", "float", "void"):
        return int(spec["bits"])
    if kind == "array":
        return int(spec["len"]) * min_bits(schema, spec["elem"])
    if kind == "dynarray":
        return length_bits(spec["max"])
    return schema[spec["name"]].min_bits


class _Describer:
    def __init__(self, schema: Schema) -> None:
        self.schema = schema

    # -- walking a value -------------------------------------------------------------------

    def struct(self, key: str, value: Any, path: str, out: list[dict[str, Any]]) -> None:
        declared = self.schema.type_def(key)
        if declared.is_union:
            raise MetadataError(f"{key}: a parameter's type must be a struct, not a union")
        for field in declared.fields:
            ftype, name = field.type, field.name
            if field.is_padding:
                out.append(
                    {"path": _join(path, "_pad"), "type": type_name(ftype), "role": "padding"}
                )
                continue
            fpath = _join(path, name)
            if declared.versioned and name == "p_version":
                version = (declared.version or (0, 0))[1]
                out.append(self.leaf(ftype, fpath, name, field.doc, version, "version"))
                continue
            self.field(ftype, value[name], fpath, name, field.doc, out)

    def field(
        self,
        spec: Mapping[str, Any],
        value: Any,
        path: str,
        name: str,
        doc: FieldDoc,
        out: list[dict[str, Any]],
    ) -> None:
        kind = spec["kind"]
        if kind == "ref":
            if self.schema.type_def(spec["name"]).is_union:
                self.union(spec["name"], value, path, name, doc, out)
            else:
                self.struct(spec["name"], value, path, out)
        elif kind == "array":
            for i, item in enumerate(value):
                self.field(spec["elem"], item, f"{path}[{i}]", name, doc, out)
        elif kind == "dynarray":
            element: list[dict[str, Any]] = []
            self.field(
                spec["elem"], self.default_of(spec["elem"], NO_DOC), f"{path}[]", name, doc, element
            )
            entry = _described(
                {
                    "name": name,
                    "path": f"{path}._len",
                    "type": f"uint{length_bits(spec['max'])}",
                    "role": "length",
                },
                doc,
            )
            entry.update(
                default=len(value),
                min=0,
                max=spec["max"],
                element_min_bits=min_bits(self.schema, spec["elem"]),
                element=element,
            )
            out.append(entry)
            for i, item in enumerate(value):
                self.field(spec["elem"], item, f"{path}[{i}]", name, doc, out)
        else:
            out.append(self.leaf(spec, path, name, doc, value, "value"))

    def union(
        self,
        key: str,
        value: Any,
        path: str,
        name: str,
        doc: FieldDoc,
        out: list[dict[str, Any]],
    ) -> None:
        fields = self.schema.type_def(key).fields
        selected = next(iter(value))
        index = next(i for i, f in enumerate(fields) if f.name == selected)
        variants: list[dict[str, Any]] = []
        for i, field in enumerate(fields):
            given = value[selected] if i == index else self.default_of(field.type, field.doc)
            described: list[dict[str, Any]] = []
            vpath = _join(path, field.name)
            self.field(field.type, given, vpath, field.name, field.doc, described)
            variant: dict[str, Any] = {
                "tag": i,
                "name": field.name,
                "type": type_name(field.type),
            }
            if field.doc.short:
                variant["shortDesc"] = field.doc.short
            variant["fields"] = described
            variants.append(variant)
        entry = _described(
            {
                "name": name,
                "path": f"{path}._tag",
                "type": f"uint{tag_bits(len(fields))}",
                "role": "union_tag",
            },
            doc,
        )
        entry.update(
            default=index,
            min=0,
            max=len(fields) - 1,
            values=[
                {"value": v["tag"], "description": v.get("shortDesc", v["name"])} for v in variants
            ],
            variants=variants,
        )
        out.append(entry)
        # The selected variant's leaves follow the tag and get numbered; its copy in
        # ``variants`` stays unnumbered, like the others.
        out.extend(copy.deepcopy(variants[index]["fields"]))

    def leaf(
        self,
        spec: Mapping[str, Any],
        path: str,
        name: str,
        doc: FieldDoc,
        value: Any,
        role: str,
    ) -> dict[str, Any]:
        kind = spec["kind"]
        entry = _described({"name": name, "path": path, "type": type_name(spec), "role": role}, doc)
        if doc.unit is not None:
            entry["unit"] = doc.unit
        entry["default"] = to_json_value(value)
        # A version takes one value: the code fills it in and refuses any other.
        low, high = (value, value) if role == "version" else _natural_range(spec)
        entry["min"] = to_json_value(low if doc.minimum is None else doc.minimum)
        entry["max"] = to_json_value(high if doc.maximum is None else doc.maximum)
        if doc.decimal_places is not None:
            entry["decimalPlaces"] = doc.decimal_places
        if doc.increment is not None:
            entry["increment"] = doc.increment
        if doc.values:
            entry["values"] = [{"value": v, "description": d} for v, d in doc.values]
        if doc.display_format is not None:
            entry["format"] = doc.display_format
        if kind != "bool":
            entry["cast"] = spec.get("cast", "saturated")
        return entry

    # -- defaults and sizes ----------------------------------------------------------------

    def default_of(self, spec: Mapping[str, Any], doc: FieldDoc) -> Any:
        """The default of an unselected variant or of an array element: its @default metadata
        for our DSDL types, zero for DroneCAN's."""
        kind = spec["kind"]
        if kind == "ref":
            if self.schema.type_def(spec["name"]).versioned:
                return metadata_default(self.schema, spec["name"])
            data_type = self.schema[spec["name"]]
            return data_type.decode(data_type.default(tao=False), tao=False)
        if kind == "array":
            return [self.default_of(spec["elem"], NO_DOC) for _ in range(spec["len"])]
        if kind == "dynarray":
            return []
        if doc.default is not None:
            return doc.default
        return False if kind == "bool" else 0.0 if kind == "float" else 0


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _described(entry: dict[str, Any], doc: FieldDoc) -> dict[str, Any]:
    if doc.short:
        entry["shortDesc"] = doc.short
    if doc.long:
        entry["longDesc"] = doc.long
    return entry


def _natural_range(spec: Mapping[str, Any]) -> tuple[Any, Any]:
    kind = spec["kind"]
    if kind == "bool":
        return False, True
    bits = int(spec["bits"])
    if kind == "uint":
        return 0, (1 << bits) - 1
    if kind == "int":
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return -FLOAT_MAX[bits], FLOAT_MAX[bits]
