"""The parameter set: which types are parameters, their names, instances and default values.

A ``px`` type is a parameter when its doc comment carries ``@max_instances N`` (an instanced
parameter: ``INA238#0`` .. ``INA238#<N-1>``) or ``@param NAME`` without ``@max_instances`` (a
single value shared by all instances, e.g. ``INA238_SHARED``). The parameter's name is
``@param`` when given, otherwise the type's short name in upper snake case
(``px.Ina238`` -> ``INA238``, ``px.Ina238Shared`` -> ``INA238_SHARED``). A parameter always
uses the newest version of its type; older versions stay loadable for translating stored data.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping

from px4params._records import TYPE_CHECKING
from px4params.dsdl.schema import DataType, Schema
from px4params.errors import ParameterSetError

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, NamedTuple
else:
    from px4params._records import NamedTuple

__all__ = [
    "ParamSpec",
    "ParameterSetError",
    "metadata_default",
    "parameter_specs",
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
        return self.name if self.shared else f"{self.name}#{instance}"


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
        definition = schema.model["types"][key]
        if definition.get("dialect") != "dsdl" or definition.get("service"):
            continue
        name = str(definition["name"])
        if name not in newest or schema.resolve(name) == key:
            newest[name] = schema.resolve(name)
    for type_name, key in sorted(newest.items()):
        data_type = schema[key]
        tags = data_type.doc.get("tags") or {}
        if "max_instances" not in tags and "param" not in tags:
            continue
        name = tags.get("param") or default_param_name(type_name)
        if not _is_param_name(name) or len(name) > MAX_NAME_LEN:
            raise ParameterSetError(
                f"{data_type.definition.get('file')}: parameter name {name!r} of {type_name} "
                f"is not an upper-case name of at most {MAX_NAME_LEN} characters "
                "(set one with @param NAME)"
            )
        if name in specs:
            raise ParameterSetError(
                f"{data_type.definition.get('file')}: parameter name {name} of {type_name} "
                f"is already used by {origin[name]} (set another with @param NAME)"
            )
        max_instances = tags.get("max_instances")
        specs[name] = ParamSpec(name, data_type, int(max_instances) if max_instances else None)
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
        definition = schema.model["types"][type_spec["name"]]
        fields = {f["name"]: f for f in definition["fields"] if f["type"]["kind"] != "void"}
        defaults = default if isinstance(default, Mapping) else {}
        if definition["kind"] == "union":
            if len(given) != 1 or next(iter(given)) not in fields:
                return given
            name, inner = next(iter(given.items()))
            base = (
                defaults[name] if name in defaults else _field_default(schema, fields[name], None)
            )
            return {name: _fill(schema, fields[name]["type"], inner, base)}
        out = dict(given)
        for name, f in fields.items():
            if name == "p_version":
                continue  # filled in by the codec
            base = defaults[name] if name in defaults else _field_default(schema, f, None)
            out[name] = _fill(schema, f["type"], given[name], base) if name in given else base
        return out
    if kind in ("array", "dynarray") and isinstance(given, list):
        element = _default_of(schema, type_spec["elem"], None)
        return [_fill(schema, type_spec["elem"], item, element) for item in given]
    return given


def _default_of(schema: Schema, type_spec: Mapping[str, Any], given: Any) -> Any:
    kind = type_spec["kind"]
    if kind == "ref":
        definition = schema.model["types"][type_spec["name"]]
        overrides = _nest(given) if isinstance(given, Mapping) else {}
        fields = [f for f in definition["fields"] if f["type"]["kind"] != "void"]
        if definition["kind"] == "union":
            chosen = next((f for f in fields if f["name"] in overrides), fields[0])
            return {chosen["name"]: _field_default(schema, chosen, overrides.get(chosen["name"]))}
        return {
            f["name"]: _field_default(schema, f, overrides.get(f["name"]))
            for f in fields
            if f["name"] != "p_version"
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


def _field_default(schema: Schema, field: Mapping[str, Any], override: Any) -> Any:
    tags = (field.get("doc") or {}).get("tags") or {}
    declared = tags.get("default")
    if isinstance(declared, Mapping) and isinstance(override, Mapping):
        declared = {**declared, **_flatten(override)}
    elif override is not None:
        declared = override
    return _default_of(schema, field["type"], declared)


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
