"""MAVLink messages that pymavlink's dialects lack, as pymavlink message classes: COMPONENT_METADATA
(397) and COMPONENT_INFORMATION (395), with which PX4 tells a ground station where its metadata
files are.

The definitions are MAVLink XML (``px4params/data/mavlink/component_information.xml``), read with
pymavlink's own parser (``pymavlink.generator.mavparse``), which computes the wire order and the
CRC extra byte; the classes pack and unpack through pymavlink's ``MAVLink_message``, exactly as
its generated classes do. :func:`register` makes a dialect's parser decode them.
"""

from __future__ import annotations

import functools
import struct
from types import ModuleType
from typing import Any

from pymavlink.dialects.v20 import common as mavlink

from px4params.data import MAVLINK_COMPONENT_XML

__all__ = ["component_information", "component_metadata", "message_classes", "register"]

#: struct format characters of MAVLink's field types.
_FORMAT = {
    "char": "s",
    "uint8_t": "B",
    "int8_t": "b",
    "uint16_t": "H",
    "int16_t": "h",
    "uint32_t": "I",
    "int32_t": "i",
    "uint64_t": "Q",
    "int64_t": "q",
    "float": "f",
    "double": "d",
}


@functools.cache
def message_classes() -> dict[int, type[mavlink.MAVLink_message]]:
    """The classes of the XML's messages, by message ID."""
    from pymavlink.generator import mavparse

    xml = mavparse.MAVXML(MAVLINK_COMPONENT_XML, mavparse.PROTOCOL_2_0)
    return {m.id: _message_class(m) for m in xml.message}


def _message_class(m: Any) -> type[mavlink.MAVLink_message]:
    wire = m.ordered_fields
    fmt = "<" + "".join(f"{f.array_length or ''}{_FORMAT[f.type]}" for f in wire)
    native = "<" + "".join("c" if f.type == "char" else _FORMAT[f.type] for f in wire)
    names = [f.name for f in m.fields]
    wire_names = [f.name for f in wire]
    strings = {f.name for f in m.fields if f.type == "char" and f.array_length}

    def __init__(self: Any, *values: Any) -> None:
        mavlink.MAVLink_message.__init__(self, m.id, m.name)
        self._fieldnames = names
        self._instance_field = None
        self._instance_offset = -1
        for name, value in zip(names, values, strict=True):
            if name in strings:
                raw = value if isinstance(value, bytes) else str(value).encode("ascii")
                setattr(self, name, raw.split(b"\0", 1)[0].decode("ascii", errors="replace"))
                setattr(self, f"_{name}_raw", raw)
            else:
                setattr(self, name, value)

    def pack(self: Any, mav: mavlink.MAVLink, force_mavlink1: bool = False) -> bytes:
        values = [
            getattr(self, f"_{n}_raw") if n in strings else getattr(self, n) for n in wire_names
        ]
        frame: bytes = self._pack(
            mav, m.crc_extra, self.unpacker.pack(*values), force_mavlink1=force_mavlink1
        )
        return frame

    attributes = {
        "__doc__": f"{m.name} (MAVLink message {m.id}), from px4params' MAVLink XML.",
        "__init__": __init__,
        "pack": pack,
        "id": m.id,
        "msgname": m.name,
        "fieldnames": names,
        "ordered_fieldnames": wire_names,
        "fieldtypes": [f.type for f in m.fields],
        "fielddisplays_by_name": {},
        "fieldenums_by_name": {},
        "fieldunits_by_name": {},
        "native_format": bytearray(native, "ascii"),
        "orders": [wire_names.index(n) for n in names],
        "lengths": [1] * len(wire),
        "array_lengths": [f.array_length for f in wire],
        "crc_extra": m.crc_extra,
        "unpacker": struct.Struct(fmt),
        "instance_field": None,
        "instance_offset": -1,
    }
    class_name = f"MAVLink_{m.name.lower()}_message"
    return type(class_name, (mavlink.MAVLink_message,), attributes)


def register(dialect: ModuleType = mavlink) -> None:
    """Makes ``dialect``'s parser decode these messages too (for clients and tests)."""
    for message_id, cls in message_classes().items():
        dialect.mavlink_map.setdefault(message_id, cls)


def component_metadata(time_boot_ms: int, file_crc: int, uri: str) -> mavlink.MAVLink_message:
    """COMPONENT_METADATA: where the general metadata file is, and its CRC."""
    cls = message_classes()[397]
    return cls(time_boot_ms, file_crc, uri.encode("ascii"))


def component_information(time_boot_ms: int, file_crc: int, uri: str) -> mavlink.MAVLink_message:
    """COMPONENT_INFORMATION, the older message: the same, and no peripherals file."""
    cls = message_classes()[395]
    return cls(time_boot_ms, file_crc, uri.encode("ascii"), 0, b"")
