"""COMPONENT_METADATA (397) and COMPONENT_INFORMATION (395), which pymavlink's dialects lack
(links/mavlink_messages.py), checked against MAVLink's serialization rules computed here: the
fields on the wire sorted by their type's size, largest first (stable, arrays by their element
type); the CRC extra byte from the message's name and its wire fields; MAVLink 2's frame (a
10-byte header, the payload's trailing zeros trimmed, X.25 CRC seeded with the extra byte).
pymavlink's parser, given the classes, is the peer that decodes the frames."""

from __future__ import annotations

import struct
import types
from typing import Any

import pytest
from px4params.links import mavlink_messages
from pymavlink import mavutil
from pymavlink.dialects.v20 import common as mavlink

SIZES = {"uint32_t": 4, "char": 1}
#: The fields as MAVLink's message definitions list them (type, name, array length).
DEFINED = {
    397: (
        "COMPONENT_METADATA",
        [("uint32_t", "time_boot_ms", 0), ("uint32_t", "file_crc", 0), ("char", "uri", 100)],
    ),
    395: (
        "COMPONENT_INFORMATION",
        [
            ("uint32_t", "time_boot_ms", 0),
            ("uint32_t", "general_metadata_file_crc", 0),
            ("char", "general_metadata_uri", 100),
            ("uint32_t", "peripherals_metadata_file_crc", 0),
            ("char", "peripherals_metadata_uri", 100),
        ],
    ),
}


def wire_order(fields: list[tuple[str, str, int]]) -> list[tuple[str, str, int]]:
    return sorted(fields, key=lambda f: -SIZES[f[0]])  # stable: definition order within a size


def crc_extra(name: str, fields: list[tuple[str, str, int]]) -> int:
    """MAVLink's CRC_EXTRA: X.25 over "NAME ", then each wire field's "type name " and, for an
    array, its length byte; the two CRC bytes XORed."""
    crc = mavutil.x25crc((name + " ").encode())
    for kind, field, length in wire_order(fields):
        crc.accumulate((kind + " " + field + " ").encode())
        if length:
            crc.accumulate(bytes([length]))
    return (crc.crc & 0xFF) ^ (crc.crc >> 8)


def unframe(frame: bytes, message_id: int, payload_size: int) -> bytes:
    """The payload of a MAVLink 2 frame, checked by hand: marker, length, ID and CRC."""
    assert frame[0] == 0xFD and len(frame) == 10 + frame[1] + 2
    assert int.from_bytes(frame[7:10], "little") == message_id
    name, fields = DEFINED[message_id]
    crc = mavutil.x25crc(frame[1 : 10 + frame[1]])
    crc.accumulate(bytes([crc_extra(name, fields)]))
    assert frame[-2:] == struct.pack("<H", crc.crc)
    payload = frame[10 : 10 + frame[1]]
    assert payload[-1:] != b"\0"  # trailing zeros trimmed
    return payload + bytes(payload_size - len(payload))


@pytest.mark.parametrize("message_id", [397, 395])
def test_each_class_is_its_definition_in_wire_order_with_its_crc_extra(message_id: int) -> None:
    name, fields = DEFINED[message_id]
    cls: Any = mavlink_messages.message_classes()[message_id]
    assert set(mavlink_messages.message_classes()) == {395, 397}
    assert (cls.id, cls.msgname, cls.__name__) == (
        message_id,
        name,
        f"MAVLink_{name.lower()}_message",
    )
    assert cls.crc_extra == crc_extra(name, fields)
    assert cls.fieldnames == [f for _, f, _ in fields]
    assert cls.fieldtypes == [k for k, _, _ in fields]
    wire = wire_order(fields)
    assert cls.ordered_fieldnames == [f for _, f, _ in wire]
    assert cls.array_lengths == [n for _, _, n in wire]
    assert cls.orders == [wire.index(f) for f in fields]
    assert cls.lengths == [1] * len(fields)  # a char array is one string
    assert cls.unpacker.size == sum(SIZES[k] * (n or 1) for k, _, n in fields)
    assert cls.instance_field is None and cls.instance_offset == -1
    assert issubclass(cls, mavlink.MAVLink_message)


def test_component_metadata_packs_as_mavlink_2_lays_it_out() -> None:
    msg = mavlink_messages.component_metadata(123456, 0xDEADBEEF, "mftp://etc/comp.json.xz")
    assert msg.get_type() == "COMPONENT_METADATA" and msg.get_msgId() == 397
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    payload = unframe(msg.pack(mav), 397, 108)
    time_ms, crc, uri = struct.unpack("<II100s", payload)
    assert (time_ms, crc) == (123456, 0xDEADBEEF)
    assert uri == b"mftp://etc/comp.json.xz".ljust(100, b"\0")
    assert (msg.time_boot_ms, msg.file_crc, msg.uri) == (
        123456,
        0xDEADBEEF,
        "mftp://etc/comp.json.xz",
    )


def test_component_information_puts_the_crcs_before_the_uris_and_has_no_peripherals() -> None:
    msg = mavlink_messages.component_information(7, 0x01020304, "mftp://etc/comp.json")
    payload = unframe(msg.pack(mavlink.MAVLink(None)), 395, 212)
    assert struct.unpack("<III100s100s", payload) == (
        7,
        0x01020304,
        0,  # no peripherals file
        b"mftp://etc/comp.json".ljust(100, b"\0"),
        bytes(100),
    )
    assert (msg.general_metadata_uri, msg.peripherals_metadata_uri) == ("mftp://etc/comp.json", "")


def test_a_uri_of_100_characters_fills_the_field_without_a_nul() -> None:
    uri = "mftp://" + "x" * 93
    msg = mavlink_messages.component_metadata(0, 1, uri)
    payload = unframe(msg.pack(mavlink.MAVLink(None)), 397, 108)
    assert payload[8:] == uri.encode()


def test_a_class_takes_a_string_field_as_text_or_bytes_up_to_its_nul() -> None:
    cls: Any = mavlink_messages.message_classes()[397]
    assert cls(1, 2, "mftp://a").uri == "mftp://a"
    from_bytes = cls(1, 2, b"mftp://b\0junk")
    assert from_bytes.uri == "mftp://b"
    assert struct.unpack("<II100s", unframe(from_bytes.pack(mavlink.MAVLink(None)), 397, 108))[
        2
    ] == (
        b"mftp://b\0junk".ljust(100, b"\0")  # the bytes are sent as given
    )
    assert cls(1, 2, b"mftp://\xe9").uri == "mftp://\ufffd"  # not ASCII: replaced, no error
    with pytest.raises(ValueError, match="zip"):
        cls(1, 2)  # every field is needed


def test_there_is_no_mavlink_1_frame_of_an_id_above_255() -> None:
    """MAVLink 1's header has one byte for the message ID: pymavlink refuses to pack it."""
    msg = mavlink_messages.component_metadata(0, 0, "mftp://x")
    with pytest.raises(struct.error, match="ubyte format requires 0 <= number <= 255"):
        msg.pack(mavlink.MAVLink(None), force_mavlink1=True)


def test_registered_classes_are_decoded_by_pymavlinks_parser() -> None:
    mavlink_messages.register(mavlink)
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    frame = mavlink_messages.component_metadata(99, 0xCAFEF00D, "mftp://etc/c.json").pack(mav)
    (got,) = mavlink.MAVLink(None).parse_buffer(frame)
    assert got.get_type() == "COMPONENT_METADATA"
    assert (got.time_boot_ms, got.file_crc, got.uri) == (99, 0xCAFEF00D, "mftp://etc/c.json")
    assert got.to_dict() == {
        "mavpackettype": "COMPONENT_METADATA",
        "time_boot_ms": 99,
        "file_crc": 0xCAFEF00D,
        "uri": "mftp://etc/c.json",
    }
    info = mavlink_messages.component_information(5, 6, "mftp://i").pack(mav)
    (got,) = mavlink.MAVLink(None).parse_buffer(info)
    assert (got.time_boot_ms, got.general_metadata_file_crc, got.general_metadata_uri) == (
        5,
        6,
        "mftp://i",
    )
    assert (got.peripherals_metadata_file_crc, got.peripherals_metadata_uri) == (0, "")


def test_register_adds_to_a_dialect_and_keeps_its_own_definitions() -> None:
    dialect = types.ModuleType("dialect")
    own = object()
    dialect.mavlink_map = {395: own, 0: own}  # type: ignore[attr-defined]
    mavlink_messages.register(dialect)
    assert dialect.mavlink_map[395] is own and dialect.mavlink_map[0] is own  # type: ignore[attr-defined]
    assert dialect.mavlink_map[397] is mavlink_messages.message_classes()[397]  # type: ignore[attr-defined]
    assert set(dialect.mavlink_map) == {0, 395, 397}  # type: ignore[attr-defined]


def test_a_telemetry_log_holding_the_messages_is_indexed_by_mavutils_mmap_reader(
    tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A .tlog (each frame after its 8-byte big-endian time in microseconds, as QGC and
    MAVProxy write them) with COMPONENT_METADATA in it, read by pymavlink's mavmmaplog (the
    indexing reader of MAVExplorer): it asks each message class for its instance field, a
    field name or None (no field of these messages tells instances apart)."""
    monkeypatch.setattr(mavutil, "mavlink", mavlink)  # the MAVLink 2 dialect, for this log
    mavlink_messages.register(mavlink)
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    frames = [
        mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(mav),
        mavlink_messages.component_metadata(99, 0xCAFEF00D, "mftp://etc/c.json").pack(mav),
        mavlink_messages.component_metadata(100, 0xCAFEF00D, "mftp://etc/d.json").pack(mav),
    ]
    path = tmp_path / "flight.tlog"
    path.write_bytes(
        b"".join(struct.pack(">Q", 1_700_000_000_000_000 + i) + f for i, f in enumerate(frames))
    )
    log = mavutil.mavmmaplog(str(path))
    try:
        assert log.counts == {0: 1, 397: 2}
        assert log.messages["COMPONENT_METADATA"].uri == "mftp://etc/c.json"
        got = log.recv_match(type="COMPONENT_METADATA")
        assert (got.time_boot_ms, got.file_crc, got.uri) == (99, 0xCAFEF00D, "mftp://etc/c.json")
    finally:
        log.close()
