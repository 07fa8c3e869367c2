"""Component metadata and the MAVLink FTP server: the protocol's answers byte for byte, the
metadata files against MAVLink's JSON schemas (with our departures listed), and every
COMMAND_LONG answered whatever its parameters."""

from __future__ import annotations

import json
import math
import os
import struct
import time
from collections.abc import Iterator
from typing import Any

import px4params
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from px4params.gcs import metadata
from px4params.gcs.component_information import ComponentFiles
from px4params.links.mavlink import MavlinkParamServer
from px4params.links.mavlink_ftp import MAX_DATA, MavftpServer, Op, make_request
from px4params.store.classic import BUNDLED_CLASSIC
from shared_data import PARAMETERS_JSON, shared_file

os.environ.setdefault("MAVLINK20", "1")
import jsonschema
from pymavlink import mavutil
from pymavlink.dialects.v20 import common as mavlink
from strategies import budget

HEADER = struct.Struct("<HBBBBBBI")


def crc32part(data: bytes, crc: int = 0) -> int:
    """PX4's crc32part, bit by bit (reflected 0xEDB88320, no inversions)."""
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xEDB88320 if crc & 1 else crc >> 1
    return crc


class Reply:
    """A response payload taken apart."""

    def __init__(self, payload: bytes) -> None:
        assert len(payload) == 251
        (self.seq, self.session, self.opcode, self.size, self.req_opcode, self.burst_complete,
         _, self.offset) = HEADER.unpack_from(payload)  # fmt: skip
        self.data = payload[12 : 12 + self.size]

    @property
    def error(self) -> int:
        assert self.opcode == Op.NAK and self.size >= 1
        return self.data[0]


def ask(server: MavftpServer, opcode: int, **kw: Any) -> list[Reply]:
    return [Reply(p) for p in server.handle(make_request(opcode, **kw))]


def one(server: MavftpServer, opcode: int, **kw: Any) -> Reply:
    (reply,) = ask(server, opcode, **kw)
    return reply


FILES = {"/a/small.txt": b"hello", "/a/big.bin": bytes(range(256)) * 200, "/top.json": b"{}"}


# -- MAVLink FTP, as PX4 answers ------------------------------------------------------------


def test_open_read_terminate() -> None:
    server = MavftpServer(FILES)
    opened = one(server, Op.OPEN_FILE_RO, seq=7, data=b"/a/small.txt")
    assert (opened.opcode, opened.req_opcode, opened.seq) == (Op.ACK, Op.OPEN_FILE_RO, 8)
    assert opened.size == 4 and struct.unpack("<I", opened.data)[0] == 5
    read = one(server, Op.READ_FILE, seq=8, session=opened.session, offset=1, size=3)
    assert (read.opcode, read.data, read.offset, read.seq) == (Op.ACK, b"ell", 1, 9)
    assert one(server, Op.READ_FILE, session=opened.session, offset=5, size=10).error == Op.ERR_EOF
    assert one(server, Op.TERMINATE_SESSION, session=opened.session).opcode == Op.ACK
    gone = one(server, Op.READ_FILE, session=opened.session, offset=0, size=3)
    assert gone.error == Op.ERR_INVALID_SESSION


@pytest.mark.parametrize(
    "opcode, kw, error",
    [
        (Op.OPEN_FILE_RO, {"data": b"/nope"}, Op.ERR_FILE_NOT_FOUND),
        (Op.OPEN_FILE_RO, {"data": b"@PARAM/param.pck"}, Op.ERR_FILE_NOT_FOUND),
        (Op.CALC_FILE_CRC32, {"data": b"/nope"}, Op.ERR_FILE_NOT_FOUND),
        (Op.LIST_DIRECTORY, {"data": b"/nope"}, Op.ERR_FILE_NOT_FOUND),
        (Op.READ_FILE, {"session": 3, "size": 10}, Op.ERR_INVALID_SESSION),
        (Op.BURST_READ_FILE, {"session": 3, "size": 10}, Op.ERR_INVALID_SESSION),
        (Op.TERMINATE_SESSION, {"session": 3}, Op.ERR_INVALID_SESSION),
        (Op.CREATE_FILE, {"data": b"/x"}, Op.ERR_FILE_PROTECTED),
        (Op.WRITE_FILE, {"data": b"x"}, Op.ERR_FILE_PROTECTED),
        (Op.REMOVE_FILE, {"data": b"/top.json"}, Op.ERR_FILE_PROTECTED),
        (Op.CREATE_DIRECTORY, {"data": b"/d"}, Op.ERR_FILE_PROTECTED),
        (Op.REMOVE_DIRECTORY, {"data": b"/a"}, Op.ERR_FILE_PROTECTED),
        (Op.OPEN_FILE_WO, {"data": b"/top.json"}, Op.ERR_FILE_PROTECTED),
        (Op.TRUNCATE_FILE, {"data": b"/top.json"}, Op.ERR_FILE_PROTECTED),
        (Op.RENAME, {"data": b"/top.json\0/x"}, Op.ERR_FILE_PROTECTED),
        (99, {}, Op.ERR_UNKNOWN_COMMAND),
        (Op.NONE, {}, Op.ERR_UNKNOWN_COMMAND),
    ],
)
def test_naks_carry_the_right_error(opcode: int, kw: dict[str, Any], error: int) -> None:
    reply = one(MavftpServer(FILES), opcode, seq=41, **kw)
    assert (reply.opcode, reply.req_opcode, reply.seq, reply.error) == (Op.NAK, opcode, 42, error)


@pytest.mark.parametrize("opcode", [Op.ACK, Op.NAK])
def test_a_response_is_never_answered(opcode: int) -> None:
    # A NAK answered with a NAK: two servers, or one hearing itself, answered each other forever
    # (helper-111: 226,304 messages in 10 s from one forged datagram).
    server = MavftpServer(FILES)
    assert ask(server, opcode, seq=41, data=b"\x07") == []
    assert one(server, Op.LIST_DIRECTORY, seq=1, data=b"/").opcode == Op.ACK  # still serving


def test_sessions_run_out_and_reset_frees_them() -> None:
    server = MavftpServer(FILES)
    sessions = {one(server, Op.OPEN_FILE_RO, data=b"/top.json").session for _ in range(4)}
    assert len(sessions) == 4
    assert one(server, Op.OPEN_FILE_RO, data=b"/top.json").error == Op.ERR_NO_SESSIONS_AVAILABLE
    assert one(server, Op.RESET_SESSIONS).opcode == Op.ACK
    assert one(server, Op.OPEN_FILE_RO, data=b"/top.json").opcode == Op.ACK


def test_list_directory() -> None:
    server = MavftpServer(FILES)
    root = one(server, Op.LIST_DIRECTORY, data=b"/")
    assert root.data.split(b"\0")[:-1] == [b"Da", b"Ftop.json\t2"]
    sub = one(server, Op.LIST_DIRECTORY, data=b"/a")
    assert sub.data.split(b"\0")[:-1] == [b"Fbig.bin\t51200", b"Fsmall.txt\t5"]
    second = one(server, Op.LIST_DIRECTORY, data=b"/a", offset=1)  # offset: entry index
    assert second.data.split(b"\0")[:-1] == [b"Fsmall.txt\t5"]
    assert one(server, Op.LIST_DIRECTORY, data=b"/a", offset=2).error == Op.ERR_EOF


def test_crc32_is_px4s() -> None:
    reply = one(MavftpServer(FILES), Op.CALC_FILE_CRC32, data=b"/a/big.bin")
    assert reply.size == 4
    assert struct.unpack("<I", reply.data)[0] == crc32part(FILES["/a/big.bin"])
    # The same bit-by-bit CRC with zlib's inversions gives CRC-32's catalogue check value, so
    # the definition above is the CRC-32 register without them.
    assert crc32part(b"123456789", 0xFFFFFFFF) ^ 0xFFFFFFFF == 0xCBF43926
    assert crc32part(b"123456789") == 0x2DFD2D88


def test_burst_read_streams_to_eof_like_px4() -> None:
    server = MavftpServer(FILES)
    session = one(server, Op.OPEN_FILE_RO, data=b"/a/big.bin").session
    content = FILES["/a/big.bin"]
    got = bytearray()
    offset, seq, rounds = 0, 100, 0
    while True:
        rounds += 1
        replies = ask(server, Op.BURST_READ_FILE, seq=seq, session=session, offset=offset, size=80)
        for i, reply in enumerate(replies):
            assert reply.seq == (seq + 1 + i) & 0xFFFF and reply.req_opcode == Op.BURST_READ_FILE
        data = [r for r in replies if r.opcode == Op.ACK]
        for r in data:
            assert r.offset == len(got) and 0 < r.size <= MAX_DATA
            got += r.data
        if replies[-1].opcode == Op.NAK:
            assert replies[-1].error == Op.ERR_EOF
            break
        assert replies[-1].burst_complete == 1  # ask again from where it ended
        offset, seq = len(got), replies[-1].seq
    assert bytes(got) == content
    assert rounds == 2  # 51200 bytes: more than one burst of packets


@settings(max_examples=budget(60), deadline=None)
@given(st.binary(max_size=3000), st.integers(0, 3100), st.integers(0, 255))
def test_reads_are_slices(content: bytes, offset: int, size: int) -> None:
    server = MavftpServer({"/f": content})
    session = one(server, Op.OPEN_FILE_RO, data=b"/f").session
    reply = one(server, Op.READ_FILE, session=session, offset=offset, size=size)
    if offset >= len(content):
        assert reply.error == Op.ERR_EOF
    else:
        assert reply.data == content[offset : offset + min(size or MAX_DATA, MAX_DATA)]


@settings(max_examples=budget(200), deadline=None)
@given(st.binary(min_size=0, max_size=260))
def test_garbage_requests_never_raise(payload: bytes) -> None:
    for reply in MavftpServer(FILES).handle(payload):
        assert len(reply) == 251 and reply[3] in (Op.ACK, Op.NAK)


# -- the metadata files against MAVLink's schemas ------------------------------------------
# Our transcription of the rules of mavlink/mavlink's component_metadata/parameter.schema.json
# and general.schema.json (the schema files are not part of any package we can depend on).

PARAMETER_ITEM = {
    "type": "object",
    "required": ["name", "type"],
    "additionalProperties": False,
    "properties": {
        "name": {"type": "string"},
        "type": {"enum": ["Uint8", "Int8", "Uint16", "Int16", "Uint32", "Int32", "Float"]},
        "shortDesc": {"type": "string"},
        "longDesc": {"type": "string"},
        "units": {"type": "string"},
        "default": {"type": "number"},
        "decimalPlaces": {"type": "integer", "minimum": 0},
        "min": {"type": "number"},
        "max": {"type": "number"},
        "increment": {"type": "number"},
        "rebootRequired": {"type": "boolean"},
        "group": {"type": "string"},
        "category": {"type": "string"},
        "volatile": {"type": "boolean"},
        "values": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["value", "description"],
                "properties": {"value": {"type": "number"}, "description": {"type": "string"}},
            },
        },
        "bitmask": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["index", "description"],
                "properties": {
                    "index": {"type": "integer"},
                    "description": {"type": "string"},
                },
            },
        },
    },
}
PARAMETER_SCHEMA = {
    "type": "object",
    "required": ["version", "parameters"],
    "properties": {
        "version": {"type": "integer", "minimum": 2},
        "translation": {"type": "object"},
        "parameters": {"type": "array", "items": PARAMETER_ITEM},
    },
}
GENERAL_SCHEMA = {
    "type": "object",
    "required": ["version", "metadataTypes"],
    "additionalProperties": False,
    "properties": {
        "version": {"type": "integer", "minimum": 1},
        "vendorName": {"type": "string"},
        "modelName": {"type": "string"},
        "firmwareVersion": {"type": "string", "pattern": r"^\d+\.\d+\.\d+(\.\d+)?$"},
        "hardwareVersion": {"type": "string", "pattern": r"^\d+\.\d+\.\d+(\.\d+)?$"},
        "metadataTypes": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["type", "uri"],
                "additionalProperties": False,
                "properties": {
                    "type": {"type": "integer"},
                    "uri": {"type": "string"},
                    "fileCrc": {"type": "integer"},
                    "uriFallback": {"type": "string"},
                    "fileCrcFallback": {"type": "integer"},
                    "translationUri": {"type": "string"},
                    "translationUriFallback": {"type": "string"},
                },
            },
        },
    },
}

#: Our departures from parameter.schema.json, each deliberate (see docs/ground-stations.md):
#: the document's version is 1 (QGC reads only 1, as PX4 writes it; the schema asks for 2);
#: a structured entry's type is "Custom" (QGC's type for values that are not numbers), its
#: default the encoding as a hex string (what QGC can hold of a Custom value), and it carries
#: our keys beside QGC's.
DEPARTURES_VERSION = 1
DEPARTURES_STRUCTURED = {
    "type": "Custom",
    "default": "hex string",
    "keys": {"max_instances", "dsdl_type", "max_bytes", "default_value", "fields", "flat"},
}


def _errors(schema: dict[str, Any], instance: Any) -> list[Any]:
    return list(jsonschema.Draft7Validator(schema).iter_errors(instance))


@pytest.fixture(scope="module")
def document(schema: px4params.Schema) -> dict[str, Any]:
    return metadata.build_parameters_json(schema, shared_file(PARAMETERS_JSON))


def _flat_names(document: dict[str, Any]) -> set[str]:
    names = set()
    for entry in document["parameters"]:
        if entry.get("flat") and entry["max_instances"]:
            names.add(f"{entry['name']}_INST")  # the instance mask
        for letter in (f["letter"] for f in entry.get("flat", ())):
            if entry["max_instances"] is None:
                names.add(f"{entry['name']}_{letter}")
            else:
                names |= {f"{entry['name']}_{n}{letter}" for n in range(entry["max_instances"])}
    return names


def test_classic_and_destructured_entries_pass_the_schema(document: dict[str, Any]) -> None:
    flat_names = _flat_names(document)
    checked = {"classic": 0, "destructured": 0}
    for entry in document["parameters"]:
        if entry["type"] == "Custom":
            continue
        assert _errors(PARAMETER_ITEM, entry) == [], entry["name"]
        checked["destructured" if entry["name"] in flat_names else "classic"] += 1
    assert checked == {"classic": 1909, "destructured": len(flat_names)}
    assert "INA238_3Q" in flat_names


def test_structured_entries_depart_only_as_documented(document: dict[str, Any]) -> None:
    structured = [e for e in document["parameters"] if e["type"] == "Custom"]
    assert structured
    for entry in structured:
        assert entry["type"] == DEPARTURES_STRUCTURED["type"]
        bytes.fromhex(entry["default"])  # a hex string
        extra = set(entry) - set(PARAMETER_ITEM["properties"])
        assert extra == DEPARTURES_STRUCTURED["keys"], entry["name"]
        # Without the departures the entry is valid.
        plain = {k: v for k, v in entry.items() if k not in extra}
        plain.update(type="Int32", default=0)
        assert _errors(PARAMETER_ITEM, plain) == [], entry["name"]
    # The whole document, version aside, is valid once the departures are taken out.
    assert document["version"] == DEPARTURES_VERSION
    errors = _errors(PARAMETER_SCHEMA, document)
    departures = {"version"} | {
        f"parameters/{i}" for i, e in enumerate(document["parameters"]) if e["type"] == "Custom"
    }
    for error in errors:
        where = "/".join(str(p) for p in list(error.absolute_path)[:2]) or error.validator
        assert where in departures or where == "minimum", error.message


def test_the_general_file_passes_its_schema(schema: px4params.Schema) -> None:
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    files = ComponentFiles(store.schema, store.specs, [])
    general = json.loads(files.general)
    assert _errors(GENERAL_SCHEMA, general) == []
    (entry,) = general["metadataTypes"]
    assert entry["fileCrc"] == crc32part(files.parameters)
    assert files.general_crc == crc32part(files.general)
    assert entry["uri"] == "mftp://px4params/parameters.json.xz"  # PX4's form: mftp://etc/...


# -- every COMMAND_LONG is answered ---------------------------------------------------------


@pytest.fixture
def vehicle(schema: px4params.Schema) -> Iterator[MavlinkParamServer]:
    lines: list[str] = []
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    server = MavlinkParamServer(store, "127.0.0.1", 0, log=lines.append)
    server.lines = lines  # type: ignore[attr-defined]
    server.start()
    yield server
    server.stop()


ODD = [math.nan, math.inf, -math.inf, 1e30, -1e30, -1.0, 0.5, 2.0**24, 2.0**24 - 1, 3.4e38]
GOOD = [148.0, 397.0, 395.0, 0.0, 1.0]


def test_every_command_long_is_answered(vehicle: MavlinkParamServer) -> None:
    host, port = vehicle.address
    conn = mavutil.mavlink_connection(
        f"udpout:{host}:{port}", source_system=255, source_component=190
    )
    commands = [
        mavlink.MAV_CMD_REQUEST_MESSAGE,
        mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
        mavlink.MAV_CMD_NAV_TAKEOFF,
        mavlink.MAV_CMD_COMPONENT_ARM_DISARM,
        mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN,
        0,
        65535,
    ]
    sent: list[tuple[int, float]] = []
    try:
        for command in commands:
            for param1 in ODD + GOOD:
                conn.mav.command_long_send(1, 1, command, 0, param1, param1, math.nan, 0, 0, 0, 0)
                sent.append((command, param1))
                time.sleep(0.002)
        acks: list[Any] = []
        end = time.monotonic() + 10
        while len(acks) < len(sent) and time.monotonic() < end:
            msg = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=1)
            if msg is not None:
                acks.append(msg)
    finally:
        conn.close()
    assert [a.command for a in acks] == [c for c, _ in sent]
    results = {
        (c, "odd" if p in ODD or math.isnan(p) else p): a.result
        for (c, p), a in zip(sent, acks, strict=True)
    }
    request = mavlink.MAV_CMD_REQUEST_MESSAGE
    assert results[(request, "odd")] == mavlink.MAV_RESULT_DENIED
    for message_id in (148.0, 397.0, 395.0):
        assert results[(request, message_id)] == mavlink.MAV_RESULT_ACCEPTED
    assert results[(request, 0.0)] == mavlink.MAV_RESULT_UNSUPPORTED  # HEARTBEAT: not on request
    assert results[(mavlink.MAV_CMD_NAV_TAKEOFF, "odd")] == mavlink.MAV_RESULT_UNSUPPORTED
    assert not [line for line in vehicle.lines if line.startswith("error")]  # type: ignore[attr-defined]
    assert all(a.target_system == 255 and a.target_component == 190 for a in acks)


_SERVER: list[MavlinkParamServer] = []


def _handler() -> MavlinkParamServer:
    """One server (not started) whose replies are captured instead of sent."""
    if not _SERVER:
        store = px4params.Store(px4params.load_schema(include_dronecan=False))
        server = MavlinkParamServer(store, "127.0.0.1", 0)
        server._sock.close()  # never serves: only its command handler is called
        _SERVER.append(server)
    return _SERVER[0]


@settings(max_examples=budget(60), deadline=None)
@given(st.integers(0, 65535), st.floats(allow_nan=True, allow_infinity=True, width=32))
def test_any_command_gets_one_answer(command: int, param1: float) -> None:
    """The command handler alone: one COMMAND_ACK (and at most one message before it) for any
    command number and any param1."""
    server = _handler()
    sent: list[Any] = []
    server._send = lambda msg, peers: sent.append(msg)  # type: ignore[method-assign]
    msg = mavlink.MAVLink_command_long_message(1, 1, command, 0, param1, 0, 0, 0, 0, 0, 0)
    msg._header = mavlink.MAVLink_header(76, srcSystem=255, srcComponent=190)
    server._command(("127.0.0.1", 1), msg)
    assert [m.get_type() for m in sent][-1] == "COMMAND_ACK"
    assert len(sent) <= 2 and sent[-1].command == command
