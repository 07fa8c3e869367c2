"""px4params: structured, instanced PX4 parameters stored with the DroneCAN serialization rules.

>>> import px4params
>>> schema = px4params.load_schema()
>>> ina = schema["px.Ina238"]
>>> value = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}
>>> data = ina.encode(value)
>>> ina.get_leaf(data, 4).value
69

The names below are imported on first use: ``import px4params`` itself costs next to nothing,
so a command that needs only part of the package loads only that part.
"""

from __future__ import annotations

#: The package's version (pyproject.toml's; a test keeps them equal).
__version__ = "0.1.0"

#: Public name -> the module that defines it.
_EXPORTS = {
    "CodecError": "px4params.errors",
    "CommandError": "px4params.errors",
    "DecodeError": "px4params.errors",
    "DeviceIdError": "px4params.errors",
    "DsdlError": "px4params.errors",
    "EncodeError": "px4params.errors",
    "InstanceError": "px4params.errors",
    "LeafError": "px4params.errors",
    "Px4ParamsError": "px4params.errors",
    "StoreError": "px4params.errors",
    "StoreFileError": "px4params.errors",
    "TransferError": "px4params.errors",
    "ValueRangeError": "px4params.errors",
    "ValueShapeError": "px4params.errors",
    "DataType": "px4params.dsdl.schema",
    "Leaf": "px4params.dsdl.schema",
    "Schema": "px4params.dsdl.schema",
    "StructValue": "px4params.dsdl.schema",
    "load_schema": "px4params.dsdl.schema",
    "to_json_value": "px4params.dsdl.schema",
    "InstanceView": "px4params.store.store",
    "Key": "px4params.store.key",
    "Store": "px4params.store.store",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'px4params' has no attribute {name!r}")
    value = getattr(__import__(module, fromlist=[name]), name)
    globals()[name] = value  # once imported, a plain attribute
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
