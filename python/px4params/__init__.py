"""px4params: structured, instanced PX4 parameters stored with the DroneCAN serialization rules.

>>> import px4params
>>> schema = px4params.load_schema()
>>> ina = schema["px.Ina238"]
>>> value = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}
>>> data = ina.encode(value)
>>> ina.get_leaf(data, 4).value
69
"""

from .errors import (
    CodecError,
    DecodeError,
    DsdlError,
    EncodeError,
    InstanceError,
    LeafError,
    Px4ParamsError,
    StoreError,
    StoreFileError,
    TransferError,
    ValueShapeError,
)
from .schema import DataType, Leaf, Schema, load_schema, to_json_value
from .store import InstanceView, Store

__all__ = [
    "CodecError",
    "DataType",
    "DecodeError",
    "DsdlError",
    "EncodeError",
    "InstanceError",
    "InstanceView",
    "Leaf",
    "LeafError",
    "Px4ParamsError",
    "Schema",
    "Store",
    "StoreError",
    "StoreFileError",
    "TransferError",
    "ValueShapeError",
    "load_schema",
    "to_json_value",
]
