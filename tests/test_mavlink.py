"""The MAVLink parameter server, with pymavlink as a real client over UDP on 127.0.0.1."""

from __future__ import annotations

import functools
import hashlib
import json
import lzma
import os
import re
import select
import signal
import socket
import struct
import subprocess
import sys
import time
import types
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import px4params
import px4params.links.mavlink as mavlink_server_module
import pytest
from px4params.links.mavlink import (
    CAPABILITIES,
    MavlinkParamServer,
    param_set_message,
    param_value_of,
    software_version,
)
from px4params.store.classic import ClassicParam
from px4params.store.session import Session, open_session
from pymavlink import mavutil
from pymavlink.dialects.v20 import common as mavlink

INT32, REAL32 = mavlink.MAV_PARAM_TYPE_INT32, mavlink.MAV_PARAM_TYPE_REAL32
CLASSIC = [
    ClassicParam("SYS_AUTOSTART", "Int32", 0),
    ClassicParam("BAT1_CAPACITY", "Float", -1.0),
    ClassicParam("SENS_EXT_I2C_PRB", "Int32", 1),
]
#: The bundled instanced parameters, each with an instance mask P_INST: one per DSDL file with
#: @max_instances in the bundled px folder (read from the files here, not from the store).
INSTANCED = sorted(
    {
        re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", path.name.split(".")[0]).upper()  # BattSmbus
        for path in (Path(px4params.__file__).parent / "data" / "dsdl" / "px").glob("*.dsdl")
        if "@max_instances" in path.read_text(encoding="utf-8")
    }
)
# int32 values whose bit patterns are signalling NaNs: pymavlink's float field rewrites them.
SNAN_INT32 = (-8388607, -4194305, 2139095041, 2143289343)


# -- what a client does, written here and not taken from the server -------------------------


def value_of(msg: Any) -> int | float:
    """A PARAM_VALUE's value as a PX4 ground station reads it: REAL32 through pymavlink's
    float, INT32/UINT32 from the four value bytes of the frame itself (bytewise encoding;
    the float field would rewrite signalling-NaN patterns). The payload starts after the
    header: 10 bytes in MAVLink 2 (0xFD), 6 in MAVLink 1; MAVLink 2 trims trailing zeros."""
    if msg.param_type == REAL32:
        return float(msg.param_value)
    frame = bytes(msg.get_msgbuf())
    start = 10 if frame[0] == 0xFD else 6
    raw = (frame[start : start + frame[1]] + bytes(4))[:4]
    return struct.unpack("<I" if msg.param_type == mavlink.MAV_PARAM_TYPE_UINT32 else "<i", raw)[0]


def set_frame(mav: Any, system: int, component: int, name: str, value: float, kind: int) -> bytes:
    """A PARAM_SET frame whose value bytes are the int32's own (bytewise) or the float32's:
    packed by pymavlink with a zero value, the four value bytes (the payload's first field)
    written in, and the checksum computed again with pymavlink's CRC."""
    msg = mavlink.MAVLink_param_set_message(system, component, name.encode(), 0.0, kind)
    frame = bytearray(msg.pack(mav))
    assert frame[0] == 0xFD
    code = {REAL32: "<f", mavlink.MAV_PARAM_TYPE_UINT32: "<I"}.get(kind, "<i")
    frame[10:14] = struct.pack(code, value)
    length = frame[1]
    crc = mavutil.x25crc(bytes(frame[1 : 10 + length]))
    crc.accumulate(bytes([msg.crc_extra]))
    frame[10 + length : 12 + length] = struct.pack("<H", crc.crc)
    return bytes(frame)


def px4_hash_check(params: list[tuple[str, bytes]]) -> int:
    """PX4's param_hash_check(): crc32part (reflected CRC-32, 0xEDB88320, no inversions) over
    each parameter's name and then its four value bytes, in index (name) order."""
    crc = 0
    for name, raw in params:
        for byte in name.encode() + raw:
            crc ^= byte
            for _ in range(8):
                crc = (crc >> 1) ^ 0xEDB88320 if crc & 1 else crc >> 1
    return crc


def _name_as_received(sent: bytes) -> str:
    """A param_id as pymavlink gives it: ASCII, a byte that is none a U+FFFD (the old echo
    of b"INA238_1C\xff" came as three of them: U+FFFD's UTF-8 bytes)."""
    return sent.decode("ascii", errors="replace")


class Client:
    """A ground station: pymavlink over UDP, as QGC or MAVProxy would talk."""

    def __init__(self, port: int) -> None:
        self.conn = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}", source_system=255, source_component=190
        )
        self.conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)

    def send(self, msg: Any) -> None:
        self.conn.mav.send(msg)

    def expect(self, kind: str, timeout: float = 5.0, where: Callable[[Any], bool] | None = None):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            msg = self.conn.recv_match(type=kind, blocking=True, timeout=end - time.monotonic())
            if msg is not None and (where is None or where(msg)):
                return msg
        raise AssertionError(f"no {kind} within {timeout} s")

    def collect(self, seconds: float) -> list[Any]:
        got: list[Any] = []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            msg = self.conn.recv_match(blocking=True, timeout=end - time.monotonic())
            if msg is not None and msg.get_type() != "HEARTBEAT":
                got.append(msg)
        return got

    def read(self, name: str) -> Any:
        self.conn.mav.param_request_read_send(1, 1, name.encode(), -1)
        return self.expect("PARAM_VALUE", where=lambda m: m.param_id == name)

    def set(self, name: str, value: int | float, mav_type: int) -> None:
        self.conn.write(set_frame(self.conn.mav, 1, 1, name, value, mav_type))

    def list_all(self) -> tuple[Any, dict[str, Any]]:
        """PARAM_REQUEST_LIST, then by index whatever UDP lost, as QGC does."""
        self.conn.mav.param_request_list_send(1, 1)
        first = self.expect("PARAM_VALUE")
        values: dict[int, Any] = {}
        count = first.param_count
        while True:
            msg = self.conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=1.0)
            if msg is None:
                break
            values[msg.param_index] = msg
            if len(values) == count:
                break
        for index in set(range(count)) - set(values):
            self.conn.mav.param_request_read_send(1, 1, b"", index)
            values[index] = self.expect("PARAM_VALUE", where=lambda m, i=index: m.param_index == i)
        return first, {m.param_id: m for m in values.values()}

    @staticmethod
    def text(messages: list[Any]) -> list[str]:
        """STATUSTEXT messages joined from their chunks."""
        chunks: dict[int, list[str]] = {}
        order: list[int] = []
        for m in messages:
            if m.get_type() == "STATUSTEXT":
                key = m.id or -len(order) - 1
                if key not in chunks:
                    order.append(key)
                chunks.setdefault(key, []).append(m.text)
        return ["".join(chunks[k]) for k in order]

    def close(self) -> None:
        self.conn.close()


@pytest.fixture
def store(schema: px4params.Schema) -> px4params.Store:
    store = px4params.Store(schema, classic=CLASSIC)
    store.add("INA238#1")
    return store


@pytest.fixture
def served(store: px4params.Store, tmp_path: Path) -> Iterator[tuple[MavlinkParamServer, Client]]:
    server = MavlinkParamServer(store, "127.0.0.1", 0, save_path=tmp_path / "vehicle.store")
    server.start()
    client = Client(server.address[1])
    yield server, client
    client.close()
    server.stop()


def test_list_read_set(served: tuple[MavlinkParamServer, Client], schema, tmp_path: Path) -> None:
    """The issue's must-show: list all, read one by name, set a destructured leaf and see the
    structured value change; a wrong-type set is refused."""
    server, client = served
    first, listed = client.list_all()
    # PX4 sends _HASH_CHECK first: index -1, UINT32, CRC32 over names and values
    assert first.param_id == "_HASH_CHECK" and first.param_index == 0xFFFF
    assert first.param_type == mavlink.MAV_PARAM_TYPE_UINT32
    # PX4's hash over the parameters as listed (names in index order, their value bytes)
    names = sorted(listed)
    raw = [
        struct.pack("<f" if listed[n].param_type == REAL32 else "<i", value_of(listed[n]))
        for n in names
    ]
    assert value_of(first) == px4_hash_check(list(zip(names, raw, strict=True)))
    expected = ["SYS_AUTOSTART", "BAT1_CAPACITY", "SENS_EXT_I2C_PRB"]
    expected += [f"INA238_1{x}" for x in "ABCPQ"]
    expected += [f"{p}_INST" for p in INSTANCED]  # instance masks: bit N while P#N exists
    assert sorted(listed) == sorted(expected)
    assert first.param_count == len(expected)
    assert [listed[n].param_index for n in sorted(listed)] == list(range(len(expected)))
    assert value_of(listed["INA238_1C"]) == 0x45 and listed["INA238_1C"].param_type == INT32
    assert value_of(listed["BAT1_CAPACITY"]) == -1.0
    assert listed["INA238_1Q"].param_type == REAL32
    assert value_of(listed["INA238_1Q"]) == server.store.get("INA238#1.shunt")

    read = client.read("INA238_1C")
    assert value_of(read) == 0x45 and read.param_count == len(expected)

    client.set("INA238_1C", 0x46, INT32)
    answer = client.expect("PARAM_VALUE", where=lambda m: m.param_id == "INA238_1C")
    assert value_of(answer) == 0x46
    saved = px4params.Store.load(tmp_path / "vehicle.store", schema, classic=CLASSIC)
    assert saved.get("INA238#1")["bus"]["i2c"]["address"] == 0x46  # through the store, saved

    client.set("INA238_1C", 71.0, REAL32)  # wrong type: refused, value unchanged
    got = client.collect(0.5)
    values = [m for m in got if m.get_type() == "PARAM_VALUE"]
    assert [value_of(m) for m in values] == [0x46]
    assert Client.text(got) == ["INA238_1C: type REAL32 refused: the parameter is INT32"]
    errors = [m for m in got if m.get_type() == "PARAM_ERROR"]
    assert [(e.param_id, e.error) for e in errors] == [("INA238_1C", 7)]  # TYPE_MISMATCH
    assert errors[0].target_system == 255 and errors[0].target_component == 190
    saved = px4params.Store.load(tmp_path / "vehicle.store", schema, classic=CLASSIC)
    assert saved.get("INA238#1.bus.i2c.address") == 0x46


def test_out_of_range_and_classic_sets(served: tuple[MavlinkParamServer, Client]) -> None:
    server, client = served
    client.set("INA238_1C", 200, INT32)  # uint7
    got = client.collect(0.5)
    assert [value_of(m) for m in got if m.get_type() == "PARAM_VALUE"] == [0x45]
    assert Client.text(got) == [
        "INA238_1C: INA238#1: bus.i2c.address: value 200 is out of range (expected 0 to 127)"
    ]
    client.set("INA238_1Q", 1e6, REAL32)  # beyond a float16 too: its @max is said
    got = client.collect(0.5)
    assert Client.text(got) == [
        "INA238_1Q: INA238#1.shunt: 1000000 is outside 0.00001..0.1 (@min/@max)"
    ]
    client.set("BAT1_CAPACITY", 5000.0, REAL32)
    assert value_of(client.expect("PARAM_VALUE")) == 5000.0
    # Stored as float16 (1049 * 2**-21), but the echo is the float32 that was sent: clients
    # (MAVSDK, QGC, MAVProxy) take a write as done only when the echo equals what they sent.
    client.set("INA238_1Q", 0.0005, REAL32)
    answer = client.expect("PARAM_VALUE", where=lambda m: m.param_id == "INA238_1Q")
    sent_float32 = struct.unpack("<f", struct.pack("<f", 0.0005))[0]
    assert answer.param_value == sent_float32
    float16 = 1049 * 2**-21  # 0.000500202...: the float16 nearest 0.0005
    assert client.read("INA238_1Q").param_value == float16  # later reads: what is stored
    server.stop()
    assert server.store.get("BAT1_CAPACITY") == 5000.0
    assert server.store.get("INA238#1.shunt") == float16
    assert server.stats["accepted"] == 2 and server.stats["refused"] == 2


@pytest.mark.parametrize("value", SNAN_INT32)
def test_int32_that_looks_like_a_signalling_nan(
    served: tuple[MavlinkParamServer, Client], value: int
) -> None:
    """SPEC: pymavlink corrupts such int32 values in the float field; the bytes are intact."""
    server, client = served
    client.set("SYS_AUTOSTART", value, INT32)
    answer = client.expect("PARAM_VALUE", where=lambda m: m.param_id == "SYS_AUTOSTART")
    assert value_of(answer) == value
    assert struct.pack("<f", answer.param_value) != struct.pack("<i", value)  # the corruption
    assert value_of(client.read("SYS_AUTOSTART")) == value
    server.stop()
    assert server.store.get("SYS_AUTOSTART") == value


def test_selecting_a_variant_announces_its_leaves(
    served: tuple[MavlinkParamServer, Client],
) -> None:
    server, client = served
    client.set("INA238_1A", 1, INT32)  # SPI
    got = [m for m in client.collect(0.7) if m.get_type() == "PARAM_VALUE"]
    assert [m.param_id for m in got] == ["INA238_1A"] + [f"INA238_1{x}" for x in "DEFG"]
    assert {m.param_count for m in got} == {10 + len(INSTANCED)}
    client.set("INA238_1E", 3, INT32)
    assert value_of(client.expect("PARAM_VALUE")) == 3
    client.set("INA238_1C", 0x46, INT32)  # the I2C address is not live any more
    got = client.collect(0.5)
    assert Client.text(got) == [
        "INA238_1C (INA238#1.bus.i2c.address) is not live: bus._tag selects variant 1, not 0 "
        "(set INA238_1A to 0)"
    ]
    assert [(m.get_type(), m.error) for m in got if m.get_type() == "PARAM_ERROR"] == [
        ("PARAM_ERROR", mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST)
    ]
    server.stop()
    assert server.store.get("INA238#1.bus.spi.chip_select") == 3


def test_unknown_names_and_indices(served: tuple[MavlinkParamServer, Client]) -> None:
    _, client = served
    client.conn.mav.param_request_read_send(1, 1, b"NO_SUCH_PARAM", -1)
    client.conn.mav.param_request_read_send(1, 1, b"", 99)
    client.conn.mav.param_request_read_send(1, 1, b"INA238_2C", -1)
    client.set("NO_SUCH_PARAM", 1, INT32)
    got = client.collect(0.7)
    assert Client.text(got) == [
        "[pm] unknown param: NO_SUCH_PARAM",
        "[pm] unknown param ID: 99",
        "INA238_2C belongs to INA238#2, which does not exist (add it first: param add INA238#2)",
        "[pm] unknown param: NO_SUCH_PARAM",
    ]
    assert not [m for m in got if m.get_type() == "PARAM_VALUE"]
    read = client.read("_HASH_CHECK")  # by name too, as PX4
    assert read.param_type == mavlink.MAV_PARAM_TYPE_UINT32
    # by index, in name order: AK09916_INST ... BAT1_CAPACITY ... INA238_1A INA238_1B INA238_1C
    names = ["SYS_AUTOSTART", "BAT1_CAPACITY", "SENS_EXT_I2C_PRB"]
    names = sorted(names + [f"INA238_1{x}" for x in "ABCPQ"] + [f"{p}_INST" for p in INSTANCED])
    client.conn.mav.param_request_read_send(1, 1, b"", names.index("INA238_1C"))
    assert client.expect("PARAM_VALUE").param_id == "INA238_1C"


def test_hash_check_set_stops_the_stream(schema: px4params.Schema) -> None:
    many = [ClassicParam(f"P{i:05d}", "Int32", i) for i in range(6000)]
    server = MavlinkParamServer(px4params.Store(schema, classic=many), "127.0.0.1", 0).start()
    client = Client(server.address[1])
    try:
        client.conn.mav.param_request_list_send(1, 1)
        first = client.expect("PARAM_VALUE")
        assert first.param_id == "_HASH_CHECK"
        client.set("_HASH_CHECK", value_of(first), mavlink.MAV_PARAM_TYPE_UINT32)
        got = [m for m in client.collect(2.5) if m.get_type() == "PARAM_VALUE"]
        assert 0 < len(got) < 6000  # stopped part-way (6000 take about 1.5 s)
    finally:
        client.close()
        server.stop()


def test_two_ground_stations_listing_at_once_each_get_the_whole_list(
    served: tuple[MavlinkParamServer, Client],
) -> None:
    # The server kept one list: a second station's request took it over, and the first got
    # 20 of 65 parameters with no word. Each asker now gets its own; one that says it has the
    # list cached (_HASH_CHECK) stops its own only.
    server, first = served
    second, third = Client(server.address[1]), Client(server.address[1])
    try:
        count = len(server.entries())
        for station in (first, second, third):
            station.conn.mav.param_request_list_send(1, 1)
        hashed = third.expect("PARAM_VALUE")
        assert hashed.param_id == "_HASH_CHECK"
        third.set("_HASH_CHECK", value_of(hashed), mavlink.MAV_PARAM_TYPE_UINT32)
        for station in (first, second):
            got = [m for m in station.collect(3.0) if m.get_type() == "PARAM_VALUE"]
            assert {m.param_index for m in got} == {0xFFFF, *range(count)}
        rest = [m for m in third.collect(1.0) if m.get_type() == "PARAM_VALUE"]
        assert len(rest) < count  # stopped part-way (or before its first value)
    finally:
        second.close()
        third.close()


def test_autopilot_version_and_heartbeat(
    served: tuple[MavlinkParamServer, Client], tmp_path: Path
) -> None:
    server, client = served
    heartbeat = client.expect("HEARTBEAT", timeout=3)
    assert heartbeat.autopilot == mavlink.MAV_AUTOPILOT_PX4
    client.conn.mav.command_long_send(
        1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION,
        0, 0, 0, 0, 0, 0,
    )  # fmt: skip
    got = [m for m in client.collect(0.5) if m.get_type() in ("AUTOPILOT_VERSION", "COMMAND_ACK")]
    # The message, then its ACK, as PX4 answers MAV_CMD_REQUEST_MESSAGE.
    assert [m.get_type() for m in got] == ["AUTOPILOT_VERSION", "COMMAND_ACK"]
    version, ack = got
    assert (ack.command, ack.result) == (
        mavlink.MAV_CMD_REQUEST_MESSAGE,
        mavlink.MAV_RESULT_ACCEPTED,
    )
    assert (ack.target_system, ack.target_component) == (255, 190)
    assert version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
    assert version.capabilities == CAPABILITIES
    # px4params 0.1.0 as PX4 encodes flight_sw_version: major, minor, patch, 255 = official
    assert px4params.__version__ == "0.1.0"
    assert version.flight_sw_version == 0x000100FF
    uid = version.uid
    assert uid != 0
    client.conn.mav.command_long_send(
        1, 1, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 0, 1, 0, 0, 0, 0, 0, 0
    )
    again = client.expect("AUTOPILOT_VERSION")
    assert (again.capabilities, again.uid) == (CAPABILITIES, uid)  # the same vehicle
    client.conn.mav.command_long_send(1, 1, mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 0, 0)
    takeoff = client.expect("COMMAND_ACK", where=lambda m: m.command == mavlink.MAV_CMD_NAV_TAKEOFF)
    assert takeoff.result == mavlink.MAV_RESULT_UNSUPPORTED
    # Another store file is another vehicle; the same file (reopened) is the same one.
    other = MavlinkParamServer(server.store, "127.0.0.1", 0, save_path=tmp_path / "another.store")
    same = MavlinkParamServer(server.store, "127.0.0.1", 0, save_path=server.save_path)
    try:
        assert other.uid[0] != uid and same.uid[0] == uid
    finally:
        other.stop()
        same.stop()


def test_malformed_and_foreign_packets_are_ignored(
    served: tuple[MavlinkParamServer, Client],
) -> None:
    server, client = served
    raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target = server.address
    good = set_frame(client.conn.mav, 1, 1, "SYS_AUTOSTART", 4001, INT32)
    bad_crc = good[:-1] + bytes([good[-1] ^ 0xFF])
    foreign = set_frame(client.conn.mav, 42, 1, "SYS_AUTOSTART", 4001, INT32)
    other_component = set_frame(client.conn.mav, 1, 77, "SYS_AUTOSTART", 4001, INT32)
    for packet in (
        b"",
        b"\x00" * 3,
        os.urandom(300),
        good[:7],
        bad_crc,
        foreign,
        other_component,
        b"\xfd\xff" + os.urandom(40),
    ):
        raw.sendto(packet, target)
    raw.close()
    client.conn.mav.param_request_read_send(1, 1, b"SYS_AUTOSTART", -1)
    answer = client.expect("PARAM_VALUE", where=lambda m: m.param_id == "SYS_AUTOSTART")
    assert value_of(answer) == 0  # still serving, and nothing was set
    server.stop()
    assert server.store.get("SYS_AUTOSTART") == 0
    assert server.stats["ignored"] >= 2 and server.stats["accepted"] == 0


def test_failed_save_undoes_the_write(store: px4params.Store, tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    lines: list[str] = []
    server = MavlinkParamServer(
        store, "127.0.0.1", 0, save_path=blocker / "sub" / "x.store", log=lines.append
    ).start()
    client = Client(server.address[1])
    try:
        client.set("INA238_1C", 0x46, INT32)
        got = client.collect(0.5)
        assert [value_of(m) for m in got if m.get_type() == "PARAM_VALUE"] == [0x45]
        assert Client.text(got)[0].startswith("INA238_1C: ")
    finally:
        client.close()
        server.stop()
    assert store.get("INA238#1.bus.i2c.address") == 0x45
    assert lines and lines[0].startswith("refused: INA238_1C: ")


def test_heartbeat_to_a_gcs_that_has_not_spoken(store: px4params.Store) -> None:
    listener = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    listener.bind(("127.0.0.1", 0))
    server = MavlinkParamServer(store, "127.0.0.1", 0, gcs=[listener.getsockname()]).start()
    try:
        ready, _, _ = select.select([listener], [], [], 3)
        assert ready
        data = listener.recv(1024)
        parser = mavlink.MAVLink(None)
        (msg,) = parser.parse_buffer(data)
        assert msg.get_type() == "HEARTBEAT" and msg.get_srcSystem() == 1
    finally:
        server.stop()
        listener.close()


def test_refuses_a_store_it_cannot_destructure(tmp_path: Path) -> None:
    root = tmp_path / "wide"
    root.mkdir()
    (root / "Wide.1.0.dsdl").write_text("# W\n# @max_instances 1\n\nuint64 x\n@sealed\n")
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    with pytest.raises(px4params.Px4ParamsError, match=r"^wide.Wide.1.0: leaf x is uint64"):
        MavlinkParamServer(px4params.Store(schema), "127.0.0.1", 0)


# -- the command line -------------------------------------------------------------------------


def _env(tmp_path: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))
    return env


def _cli(*args: str, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "px4params", *args],
        capture_output=True,
        text=True,
        env=_env(tmp_path),
        timeout=60,
    )


def test_cli_serve_and_ctrl_c(tmp_path: Path, schema: px4params.Schema) -> None:
    store_file = tmp_path / "v.store"
    proc = subprocess.Popen(
        [sys.executable, "-m", "px4params", "mavlink", "serve", "--udp", "127.0.0.1:0",
         "--store", str(store_file)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(tmp_path),
        # Ctrl-C reaches it even where this run was started with SIGINT ignored (a
        # background job of a script), which Python would otherwise keep ignoring
        preexec_fn=functools.partial(signal.signal, signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        banner = proc.stdout.readline()
        assert re.match(r"serving (\d+) parameters \(\1 classic, 0 destructured\) on udp ", banner)
        announced = proc.stdout.readline()
        assert announced.startswith("component metadata: mftp://px4params/general.json (crc 0x")
        assert "(store: " in banner and "new: written on the first accepted change" in banner
        port = int(banner.split("on udp 127.0.0.1:")[1].split()[0])
        client = Client(port)
        client.conn.mav.param_request_list_send(1, 1)
        first = client.expect("PARAM_VALUE")
        assert first.param_id == "_HASH_CHECK"
        assert first.param_count == int(banner.split()[1])
        client.close()
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert err == ""
    assert out.startswith("stopped: ") and "0 writes accepted, 0 refused" in out


def test_cli_serves_a_saved_store(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    store_file = tmp_path / "v.store"
    assert (
        _cli("param", "--store", str(store_file), "add", "INA238#0", tmp_path=tmp_path).returncode
        == 0
    )
    proc = subprocess.Popen(
        [sys.executable, "-m", "px4params", "mavlink", "serve", "--udp", "127.0.0.1:0",
         "--store", str(store_file), "--sysid", "7"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(tmp_path),
        # Ctrl-C reaches it even where this run was started with SIGINT ignored (a
        # background job of a script), which Python would otherwise keep ignoring
        preexec_fn=functools.partial(signal.signal, signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        banner = proc.stdout.readline()
        assert re.match(r"serving \d+ parameters \(\d+ classic, 5 destructured\)", banner)
        assert proc.stdout.readline().startswith("component metadata: ")
        assert "as system 7, component 1" in banner
        port = int(banner.split("on udp 127.0.0.1:")[1].split()[0])
        client = Client(port)
        client.conn.write(set_frame(client.conn.mav, 7, 1, "INA238_0P", 100, INT32))
        assert value_of(client.expect("PARAM_VALUE")) == 100
        assert proc.stdout.readline() == "INA238_0P = 100, saved\n"
        client.close()
    finally:
        proc.terminate()  # SIGTERM stops as cleanly as Ctrl-C
        out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert "1 writes accepted" in out
    monkeypatch.delenv("PX4PARAMS_PARAMETERS_JSON", raising=False)
    assert open_session(str(store_file), None).store.get("INA238#0.current") == 100


def test_cli_errors(tmp_path: Path) -> None:
    r = _cli("mavlink", "serve", "--udp", "localhost", tmp_path=tmp_path)
    assert r.returncode == 2
    assert r.stderr.splitlines()[-1] == (
        "px4params mavlink serve: error: argument --udp: 'localhost' is not HOST:PORT "
        "(expected e.g. 127.0.0.1:14550, port 0..65535)"
    )
    r = _cli("mavlink", "serve", "--udp", "127.0.0.1:70000", tmp_path=tmp_path)
    assert r.returncode == 2 and "is not HOST:PORT" in r.stderr
    r = _cli("mavlink", "serve", "--udp", "127.0.0.1:0", "--sysid", "0", tmp_path=tmp_path)
    assert r.returncode == 2 and "'0' is not a MAVLink ID (expected 1..255)" in r.stderr
    r = _cli("mavlink", tmp_path=tmp_path)
    assert r.returncode == 2

    busy = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    busy.bind(("127.0.0.1", 0))
    port = busy.getsockname()[1]
    try:
        r = _cli("mavlink", "serve", "--udp", f"127.0.0.1:{port}", "--store",
                 str(tmp_path / "s"), tmp_path=tmp_path)  # fmt: skip
    finally:
        busy.close()
    assert r.returncode == 1
    assert r.stderr == (
        f"px4params: error: cannot listen on udp 127.0.0.1:{port}: Address already in use\n"
    )

    broken = tmp_path / "broken.store"
    broken.write_bytes(b"not a store file at all")
    r = _cli("mavlink", "serve", "--udp", "127.0.0.1:0", "--store", str(broken),
             tmp_path=tmp_path)  # fmt: skip
    assert r.returncode == 1
    assert r.stderr.startswith(f"px4params: error: {broken}: ") and r.stderr.count("\n") == 1

    wide = tmp_path / "wide"
    wide.mkdir()
    (wide / "Wide.1.0.dsdl").write_text("# W\n# @max_instances 1\n\nfloat64 x\n@sealed\n")
    r = _cli("mavlink", "serve", "--udp", "127.0.0.1:0", "--dsdl", str(wide), "--store",
             str(tmp_path / "w.store"), tmp_path=tmp_path)  # fmt: skip
    assert r.returncode == 1
    assert r.stderr == (
        "px4params: error: wide.Wide.1.0: leaf x is float64: destructured parameters carry at "
        "most 32 bits (MAVLink), so this type cannot be a parameter\n"
    )


def test_cli_help_has_examples(tmp_path: Path) -> None:
    r = _cli("mavlink", "serve", "--help", tmp_path=tmp_path)
    assert r.returncode == 0 and "examples:" in r.stdout and "--gcs" in r.stdout


def test_instances_added_and_removed_through_the_mask(
    served: tuple[MavlinkParamServer, Client], schema: px4params.Schema, tmp_path: Path
) -> None:
    """INA238_INST: bit N while INA238#N exists; writing it adds and removes instances."""
    server, client = served
    assert value_of(client.read("INA238_INST")) == 0b0010
    client.set("INA238_INST", 0b1001, INT32)  # add #0 and #3, remove #1
    got = [m for m in client.collect(0.7) if m.get_type() == "PARAM_VALUE"]
    assert value_of(got[0]) == 0b1001 and got[0].param_id == "INA238_INST"
    announced = {m.param_id for m in got[1:]}
    assert {f"INA238_{n}{x}" for n in (0, 3) for x in "ABCPQ"} <= announced
    assert value_of(client.read("INA238_0C")) == 0x45  # a new instance has its defaults
    client.conn.mav.param_request_read_send(1, 1, b"INA238_1C", -1)
    assert Client.text(client.collect(0.5)) == [
        "INA238_1C belongs to INA238#1, which does not exist (add it first: param add INA238#1)"
    ]
    client.set("INA238_INST", 0b10000, INT32)  # INA238 has 4 instance slots
    got = client.collect(0.5)
    assert Client.text(got) == [
        "INA238_INST: value 16 is not a mask of INA238's 4 instances (expected 0 to 15)"
    ]
    assert value_of(client.read("INA238_INST")) == 0b1001  # refused: unchanged, read back
    server.stop()
    assert server.store.instances("INA238") == ["INA238#0", "INA238#3"]
    saved = px4params.Store.load(tmp_path / "vehicle.store", schema, classic=CLASSIC)
    assert saved.instances("INA238") == ["INA238#0", "INA238#3"]


# -- the server turn by turn, in this thread (issue 40) -----------------------------------------


class Station:
    """A ground station on a UDP socket of its own: pymavlink's encoder (system 255, component
    190, as QGC) and a fresh pymavlink parser per datagram for what comes back. The server is
    driven turn by turn (:meth:`MavlinkParamServer.step`) in this thread, so that each turn's
    answers are all there when it returns (loopback UDP delivers at once) and no test waits."""

    def __init__(self, server: MavlinkParamServer, system: int = 255, component: int = 190):
        self.server = server
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.mav = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
        self.frames: list[bytes] = []  # the datagrams of the last receive, raw

    def send(self, msg: Any) -> None:
        data = msg if isinstance(msg, bytes) else msg.pack(self.mav)
        self.sock.sendto(data, self.server.address)

    def receive(self) -> list[Any]:
        got: list[Any] = []
        self.frames = []
        while True:
            try:
                data = self.sock.recv(65535)
            except BlockingIOError:
                return got
            self.frames.append(data)
            got += mavlink.MAVLink(None).parse_buffer(data) or []

    def exchange(self, msg: Any) -> list[Any]:
        """Sends ``msg``, turns the server once; what came back (heartbeats left out)."""
        self.send(msg)
        return turn(self.server, self)

    def close(self) -> None:
        self.sock.close()


def turn(server: MavlinkParamServer, station: Station) -> list[Any]:
    server.step(0.0)
    return [m for m in station.receive() if m.get_type() != "HEARTBEAT"]


def values(messages: list[Any]) -> list[tuple[str, int | float, int, int]]:
    """The PARAM_VALUEs as (name, value, index, count)."""
    return [
        (m.param_id, value_of(m), m.param_index, m.param_count)
        for m in messages
        if m.get_type() == "PARAM_VALUE"
    ]


def kinds(messages: list[Any]) -> list[str]:
    return [m.get_type() for m in messages]


#: The parameters of the ``store`` fixture in PX4's index order (names sorted).
NAMES = sorted(
    ["SYS_AUTOSTART", "BAT1_CAPACITY", "SENS_EXT_I2C_PRB"]
    + [f"INA238_1{x}" for x in "ABCPQ"]
    + [f"{p}_INST" for p in INSTANCED]
)


@pytest.fixture
def turns(store: px4params.Store, tmp_path: Path) -> Iterator[tuple[MavlinkParamServer, Station]]:
    """The server (store file saved in tmp_path, heartbeats due once an hour, lists streamed as
    fast as the turns come) and one ground station that has spoken (a HEARTBEAT)."""
    lines: list[str] = []
    server = MavlinkParamServer(
        store,
        "127.0.0.1",
        0,
        save_path=tmp_path / "vehicle.store",
        heartbeat_interval=3600,
        param_rate=1e9,
        log=lines.append,
    )
    server.logged = lines  # type: ignore[attr-defined]
    station = Station(server)
    station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
    yield server, station
    station.close()
    server.close()


@pytest.fixture
def polled(
    store: px4params.Store, tmp_path: Path
) -> Iterator[tuple[MavlinkParamServer, Station, Path, list[str]]]:
    """The server over a saved store file it reads again at every turn (poll_interval 0: what
    another writer saves is seen at once), the file, its log lines, and one ground station that
    has spoken (a HEARTBEAT)."""
    path = tmp_path / "vehicle.store"
    store.save(path)
    lines: list[str] = []
    server = MavlinkParamServer(
        store, "127.0.0.1", 0, save_path=path, poll_interval=0, log=lines.append
    )
    station = Station(server)
    station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
    yield server, station, path, lines
    station.close()
    server.close()


@pytest.mark.issue40
class TestTurnByTurnSetup:
    """What the server sets up and when its turns act (issue 40, mutlinks): before
    TestTurnByTurn, so that the mutation run's -x meets them first (these are the tests that
    catch mutants of the constructor and of the turn's timing)."""

    def test_param_value_of_a_payload_trimmed_below_10_bytes(self) -> None:
        """MAVLink 2 trims the payload's trailing zeros: a PARAM_SET with no name and type 0 keeps
        6 bytes (value, target system and component), still LEN bytes after the 10-byte header."""
        frame = set_frame(mavlink.MAVLink(None), 1, 1, "", 0x01020304, 0)
        assert frame[1] == 6
        (parsed,) = mavlink.MAVLink(None).parse_buffer(frame)
        assert param_value_of(parsed) == 0x01020304

    def test_by_default_it_listens_on_loopback_at_udp_14550(
        self, store: px4params.Store, monkeypatch: pytest.MonkeyPatch
    ) -> None:
        """MAVLink's UDP convention: 14550 is the ground station's port; loopback unless a host
        is given. The socket is asked for that address (and given a free port: a test must not
        take 14550 from a ground station on this machine)."""
        asked: list[Any] = []

        class Recording(socket.socket):
            def bind(self, address: Any) -> None:
                asked.append(address)
                super().bind(("127.0.0.1", 0))

        fake = types.SimpleNamespace(
            socket=Recording, AF_INET=socket.AF_INET, SOCK_DGRAM=socket.SOCK_DGRAM
        )
        monkeypatch.setattr(mavlink_server_module, "socket", fake)
        server = MavlinkParamServer(store)
        server.close()
        assert asked == [("127.0.0.1", 14550)]

    def test_a_server_given_only_a_session_saves_through_it_and_names_the_store_by_its_file(
        self, store: px4params.Store, tmp_path: Path, schema: px4params.Schema
    ) -> None:
        path = tmp_path / "vehicle.store"
        store.save(path)
        lines: list[str] = []
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, session=Session(store, str(path)), log=lines.append,
            heartbeat_interval=3600,
        )  # fmt: skip
        station = Station(server)
        try:
            got = station.exchange(set_frame(station.mav, 1, 1, "SYS_AUTOSTART", 4001, INT32))
            index = NAMES.index("SYS_AUTOSTART")
            assert values(got) == [("SYS_AUTOSTART", 4001, index, len(NAMES))]
            capabilities = mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES
            command = mavlink.MAVLink_command_long_message(
                1, 1, capabilities, 0, 1, 0, 0, 0, 0, 0, 0
            )
            version = station.exchange(command)[0]
        finally:
            station.close()
            server.close()
        assert lines == ["SYS_AUTOSTART = 4001, saved"]
        saved = px4params.Store.load(path, schema, classic=CLASSIC)
        assert saved.get("SYS_AUTOSTART") == 4001
        digest = hashlib.sha256(("file:" + os.path.realpath(path)).encode()).digest()
        assert version.uid == int.from_bytes(digest[:8], "little")
        assert bytes(version.uid2) == digest[8:26]

    def test_the_counters_start_at_zero_and_count_what_happened(
        self, store: px4params.Store
    ) -> None:
        server = MavlinkParamServer(store, "127.0.0.1", 0)
        station = Station(server)
        try:
            read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
            assert len(values(station.exchange(read))) == 1  # no peer for the first heartbeat
        finally:
            station.close()
            server.close()
        assert server.stats == {
            "received": 1,
            "ignored": 0,
            "sent": 1,
            "accepted": 0,
            "refused": 0,
            "unsigned": 0,
            "badly_signed": 0,
            "param_set_dropped": 0,
        }

    def test_with_a_signing_key_unsigned_frames_are_dropped_and_counted(
        self, store: px4params.Store
    ) -> None:
        """MAVLink 2 signing: a signed link drops unsigned frames (and a PARAM_SET among them
        changes nothing)."""
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, signing_key=bytes(range(32)), heartbeat_interval=3600
        )
        station = Station(server)
        try:
            read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
            assert station.exchange(read) == []
            assert station.exchange(set_frame(station.mav, 1, 1, "SYS_AUTOSTART", 7, INT32)) == []
        finally:
            station.close()
            server.close()
        assert (server.stats["unsigned"], server.stats["param_set_dropped"]) == (2, 1)
        assert server.stats["received"] == 0 and store.get("SYS_AUTOSTART") == 0

    def test_the_parameter_metadata_downloaded_with_mavlink_ftp_has_the_classic_entries(
        self, schema: px4params.Schema
    ) -> None:
        """As QGC does: COMPONENT_METADATA (by MAV_CMD_REQUEST_MESSAGE) gives the general
        file's mftp:// URI and CRC; the general file names the parameters' file (xz) and its
        CRC; both are read with MAVLink FTP (OpenFileRO, ReadFile until EOF). The store's
        classic parameters are there with their parameters.json entries as PX4 wrote them."""
        entry = {"name": "SYS_AUTOSTART", "type": "Int32", "default": 0, "group": "System"}
        store = px4params.Store(schema, classic=[ClassicParam("SYS_AUTOSTART", "Int32", 0, entry)])
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=3600)
        station = Station(server)
        try:
            command = mavlink.MAVLink_command_long_message(
                1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, 397, 0, 0, 0, 0, 0, 0
            )
            station.exchange(command)
            frame = next(f for f in station.frames if int.from_bytes(f[7:10], "little") == 397)
            payload = (frame[10 : 10 + frame[1]] + bytes(108))[:108]
            _, general_crc, uri = struct.unpack("<II100s", payload)
            general = ftp_download(station, uri.split(b"\0")[0].decode())
            assert px4_hash_check([("", general)]) == general_crc  # crc32part over the bytes
            (listed,) = json.loads(general)["metadataTypes"]
            assert listed["type"] == 1  # COMP_METADATA_TYPE_PARAMETER
            compressed = ftp_download(station, listed["uri"])
        finally:
            station.close()
            server.close()
        assert px4_hash_check([("", compressed)]) == listed["fileCrc"]
        document = json.loads(lzma.decompress(compressed))
        assert document["parameters"][0] == entry

    # -- what is due at once, and how long a turn may wait (issue 40, mutlinks) -----------------

    def test_at_a_clock_reading_0_the_first_turn_does_all_that_is_due(
        self, store: px4params.Store, tmp_path: Path, schema: px4params.Schema, clock: Clock
    ) -> None:
        """time.monotonic()'s origin is undefined (it may read 0 or less): the first turn
        sends the heartbeat and the health report, looks at the store file and sends a
        requested list's first burst."""
        clock.now = 0.0
        path = tmp_path / "vehicle.store"
        store.save(path)
        gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        gcs.bind(("127.0.0.1", 0))
        gcs.setblocking(False)
        line = "health: INA238#1 critical"
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, save_path=path, gcs=[gcs.getsockname()], health=lambda: [line]
        )
        try:
            other = Session(px4params.Store.load(path, schema, classic=CLASSIC), str(path))
            other.commit(lambda: other.store.set("SYS_AUTOSTART", 4001))
            mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
            gcs.sendto(mavlink.MAVLink_param_request_list_message(1, 1).pack(mav), server.address)
            server.step(0.0)
            got = [m for f in _datagrams(gcs) for m in mavlink.MAVLink(None).parse_buffer(f)]
        finally:
            gcs.close()
            server.close()
        assert kinds(got) == ["HEARTBEAT", "STATUSTEXT"] + ["PARAM_VALUE"] * 21
        assert got[1].text == line
        index = NAMES.index("SYS_AUTOSTART")
        assert (
            values(got[2:4])
            == [
                ("SYS_AUTOSTART", 4001, index, len(NAMES)),  # another writer's save, announced
                ("_HASH_CHECK", values(got[3:4])[0][1], 0xFFFF, len(NAMES)),  # the list's start
            ]
        )

    def test_the_store_file_is_looked_at_again_once_poll_interval_has_passed(
        self, store: px4params.Store, tmp_path: Path, schema: px4params.Schema, clock: Clock
    ) -> None:
        clock.now = 0.0
        path = tmp_path / "vehicle.store"
        store.save(path)
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, save_path=path, heartbeat_interval=3600, poll_interval=0.25
        )
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))  # polled
            other = Session(px4params.Store.load(path, schema, classic=CLASSIC), str(path))
            other.commit(lambda: other.store.set("SYS_AUTOSTART", 4001))
            clock.now = 0.25  # exactly poll_interval later
            assert [name for name, *_ in values(turn(server, station))] == ["SYS_AUTOSTART"]
        finally:
            station.close()
            server.close()

    def test_a_turn_waits_for_datagrams_no_longer_than_until_the_next_heartbeat(
        self, store: px4params.Store, clock: Clock, monkeypatch: pytest.MonkeyPatch
    ) -> None:
        """A quiet link still gets its heartbeat on time: a turn given 10 s to wait for a
        datagram waits only until the next heartbeat is due."""
        waits: list[float] = []

        def waiting(readers: Any, writers: Any, errors: Any, timeout: float) -> Any:
            waits.append(timeout)
            return select.select(readers, writers, errors, 0)

        monkeypatch.setattr(mavlink_server_module, "select", types.SimpleNamespace(select=waiting))
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=0.5)
        try:
            server.step(10.0)  # a heartbeat is due now; the next in 0.5 s
            clock.now += 0.25
            server.step(10.0)
        finally:
            server.close()
        assert waits == [0.5, 0.25]

    def test_while_a_list_streams_a_turn_waits_no_longer_than_until_the_next_burst(
        self, store: px4params.Store, clock: Clock, monkeypatch: pytest.MonkeyPatch
    ) -> None:
        """The list's bursts go out at param_rate even when nothing arrives."""
        waits: list[float] = []

        def waiting(readers: Any, writers: Any, errors: Any, timeout: float) -> Any:
            waits.append(timeout)
            return select.select(readers, writers, errors, 0)

        monkeypatch.setattr(mavlink_server_module, "select", types.SimpleNamespace(select=waiting))
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=3600, param_rate=40)
        station = Station(server)  # bursts of 20 at 40 a second: one every 0.5 s
        try:
            station.send(mavlink.MAVLink_param_request_list_message(1, 1))
            server.step(10.0)  # no stream yet when it waits; then the first burst
            assert len(values(station.receive())) == 20
            clock.now += 0.25
            server.step(10.0)
        finally:
            station.close()
            server.close()
        assert waits == [10.0, 0.25]


@pytest.mark.issue40
class TestTurnByTurn:
    """PX4's parameter protocol (mavlink_parameters.cpp), the MAVLink parameter and command
    protocols, as a ground station sees them, one server turn at a time."""

    def test_a_message_in_the_servers_own_name_is_never_answered(
        self, turns: tuple[MavlinkParamServer, Station], store: px4params.Store
    ) -> None:
        # One forged FTP NAK from system 1 component 1 (the server's own ID, as an echo or a
        # misconfigured second component would send): the server NAKed it to the sender, and a
        # sender that was itself answered itself 226,304 times in 10 s (helper-111).
        server, station = turns
        own = Station(server, system=1, component=1)
        try:
            nak = (struct.pack("<HBBBBBBI", 1, 0, 129, 1, 5, 0, 0, 0) + b"\x07").ljust(251, b"\0")
            ftp = mavlink.MAVLink_file_transfer_protocol_message(0, 1, 1, list(nak))
            assert own.exchange(ftp) == []
            before = store.get("BAT1_CAPACITY")
            assert own.exchange(set_frame(own.mav, 1, 1, "BAT1_CAPACITY", 1234.0, 9)) == []
            assert own.exchange(mavlink.MAVLink_param_request_list_message(1, 1)) == []
            assert store.get("BAT1_CAPACITY") == before
            assert server.stats["ignored"] == 3 and server.stats["accepted"] == 0
            # the same from the ground station's ID is a write
            answer = station.exchange(set_frame(station.mav, 1, 1, "BAT1_CAPACITY", 1234.0, 9))
            assert values(answer)[0][:2] == ("BAT1_CAPACITY", 1234.0)
        finally:
            own.close()

    def test_a_list_is_the_hash_then_every_parameter_in_name_order_20_a_turn(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        first = station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
        assert kinds(first) == ["PARAM_VALUE"] * 20  # PX4: up to 20 at once over UDP
        assert first[0].param_id == "_HASH_CHECK" and first[0].param_index == 0xFFFF
        assert first[0].param_type == mavlink.MAV_PARAM_TYPE_UINT32
        listed = values(first)[1:] + values(turn(server, station))
        assert len(listed) == 39
        listed += values(turn(server, station))
        assert [name for name, _, _, _ in listed] == NAMES
        assert [index for _, _, index, _ in listed] == list(range(len(NAMES)))
        assert {count for _, _, _, count in [*listed, *values(first[:1])]} == {len(NAMES)}
        raw = [struct.pack("<f" if isinstance(v, float) else "<i", v) for _, v, _, _ in listed]
        hashed = px4_hash_check(list(zip(NAMES, raw, strict=True)))
        assert value_of(first[0]) == hashed
        assert turn(server, station) == []  # the list is done

    def test_a_list_request_during_a_stream_restarts_it_without_the_hash(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        _server, station = turns
        station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
        again = values(station.exchange(mavlink.MAVLink_param_request_list_message(1, 1)))
        assert [(name, index) for name, _, index, _ in again] == list(
            zip(NAMES[:20], range(20), strict=True)
        )

    def test_a_hash_check_set_stops_the_stream_and_is_no_write(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        first = station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
        stop = set_frame(station.mav, 1, 1, "_HASH_CHECK", value_of(first[0]), 6)
        assert station.exchange(stop) == []
        assert turn(server, station) == []
        assert server.stats["refused"] == 0 and server.stats["accepted"] == 0

    def test_bursts_follow_each_other_at_the_parameter_rate(self, store: px4params.Store) -> None:
        server = MavlinkParamServer(store, "127.0.0.1", 0, param_rate=20 / 3600)  # an hour
        station = Station(server)
        try:
            first = station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
            assert len(values(first)) == 20
            assert turn(server, station) == []  # the next burst is an hour away
        finally:
            station.close()
            server.close()

    def test_a_stream_stops_when_its_requester_falls_silent(self, store: px4params.Store) -> None:
        server = MavlinkParamServer(store, "127.0.0.1", 0, param_rate=1e9, peer_timeout=0.5)
        station = Station(server)
        try:
            assert len(station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))) == 20
            time.sleep(0.6)  # longer than peer_timeout: the requester is gone
            assert turn(server, station) == []
            assert turn(server, station) == []
        finally:
            station.close()
            server.close()

    def test_requests_for_another_system_or_component_are_ignored_broadcasts_answered(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        before = dict(server.stats)
        for system, component in ((2, 1), (1, 2), (0, 2), (2, 0)):
            read = mavlink.MAVLink_param_request_read_message(system, component, b"", 0)
            assert station.exchange(read) == []
            command = mavlink.MAVLink_command_long_message(
                system, component, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, 148, 0, 0, 0, 0, 0, 0
            )
            assert station.exchange(command) == []
        assert server.stats["received"] - before["received"] == 8
        assert server.stats["ignored"] - before["ignored"] == 8
        # Component 0 is every component of this system: answered.
        read = mavlink.MAVLink_param_request_read_message(1, 0, b"", 0)
        assert values(station.exchange(read)) == [(NAMES[0], 0, 0, len(NAMES))]
        # System 0: a command is a broadcast, as PX4 takes it; a parameter message is not
        # (PX4's mavlink_parameters.cpp takes its own system ID alone): a broadcast PARAM_SET
        # would change every vehicle that hears it.
        for system, component in ((0, 0), (0, 1)):
            read = mavlink.MAVLink_param_request_read_message(system, component, b"", 0)
            assert station.exchange(read) == []
            listed = mavlink.MAVLink_param_request_list_message(system, component)
            assert station.exchange(listed) == []
            write = set_frame(station.mav, system, component, "INA238_1C", 0x46, INT32)
            assert station.exchange(write) == []
            command = mavlink.MAVLink_command_long_message(
                system, component, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, 148, 0, 0, 0, 0, 0, 0
            )
            assert kinds(station.exchange(command)) == ["AUTOPILOT_VERSION", "COMMAND_ACK"]
        assert server.store.get("INA238#1.bus.i2c.address") == 0x45
        assert server.stats["ignored"] - before["ignored"] == 8 + 6

    def test_a_read_by_index_ignores_the_name_and_the_last_index_is_count_minus_one(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        _server, station = turns
        by_index = mavlink.MAVLink_param_request_read_message(1, 1, b"SYS_AUTOSTART", 0)
        assert values(station.exchange(by_index)) == [(NAMES[0], 0, 0, len(NAMES))]
        last = len(NAMES) - 1
        read = mavlink.MAVLink_param_request_read_message(1, 1, b"", last)
        assert values(station.exchange(read)) == [(NAMES[last], 0, last, len(NAMES))]
        by_name = mavlink.MAVLink_param_request_read_message(1, 1, b"INA238_1C", -1)
        index = NAMES.index("INA238_1C")
        assert values(station.exchange(by_name)) == [("INA238_1C", 0x45, index, len(NAMES))]

    def test_a_read_of_the_hash_by_name_is_the_hash(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        _server, station = turns
        read = mavlink.MAVLink_param_request_read_message(1, 1, b"_HASH_CHECK", -1)
        (got,) = station.exchange(read)
        first = station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))[0]
        assert (got.param_id, got.param_index, got.param_count) == ("_HASH_CHECK", 0xFFFF, 45)
        assert got.param_type == mavlink.MAV_PARAM_TYPE_UINT32
        assert value_of(got) == value_of(first)

    @pytest.mark.parametrize(
        ("name", "index", "text", "error_index"),
        [
            (b"NO_SUCH_PARAM", -1, "[pm] unknown param: NO_SUCH_PARAM", -1),
            # any negative index reads by name (PX4's rule); the error echoes the request's
            (b"NO_SUCH_PARAM", -2, "[pm] unknown param: NO_SUCH_PARAM", -2),
            # a name that is not text: its own bytes echoed, so that the asker can match them
            (b"INA238_1C\xff", -1, "[pm] unknown param: INA238_1C?", -1),
            (b"", 45, "[pm] unknown param ID: 45", 45),
            (b"", 32767, "[pm] unknown param ID: 32767", 32767),
        ],
    )
    def test_an_unknown_read_is_a_statustext_and_a_param_error_to_the_asker(
        self,
        turns: tuple[MavlinkParamServer, Station],
        name: bytes,
        index: int,
        text: str,
        error_index: int,
    ) -> None:
        server, station = turns
        got = station.exchange(mavlink.MAVLink_param_request_read_message(1, 1, name, index))
        assert kinds(got) == ["STATUSTEXT", "PARAM_ERROR"]
        assert (got[0].text, got[0].severity) == (text, mavlink.MAV_SEVERITY_WARNING)
        error = got[1]
        assert (error.target_system, error.target_component) == (255, 190)
        assert (error.param_id, error.param_index) == (_name_as_received(name), error_index)
        assert error.error == mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST
        assert server.stats["refused"] == 0  # a read refuses nothing

    def test_a_write_is_echoed_to_every_peer_saved_and_logged(
        self, turns: tuple[MavlinkParamServer, Station], schema: px4params.Schema, tmp_path: Path
    ) -> None:
        server, station = turns
        other = Station(server, system=254, component=191)
        try:
            other.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            got = station.exchange(set_frame(station.mav, 1, 1, "INA238_1C", 0x46, INT32))
            index = NAMES.index("INA238_1C")
            assert values(got) == [("INA238_1C", 0x46, index, len(NAMES))]
            assert values(other.receive()) == [("INA238_1C", 0x46, index, len(NAMES))]
        finally:
            other.close()
        assert server.logged == ["INA238_1C = 70, saved"]  # type: ignore[attr-defined]
        saved = px4params.Store.load(tmp_path / "vehicle.store", schema, classic=CLASSIC)
        assert saved.get("INA238#1.bus.i2c.address") == 0x46
        assert server.stats["accepted"] == 1 and server.stats["refused"] == 0

    def test_a_write_in_memory_is_logged_without_saved(self, store: px4params.Store) -> None:
        lines: list[str] = []
        server = MavlinkParamServer(store, "127.0.0.1", 0, log=lines.append)
        station = Station(server)
        try:
            got = station.exchange(set_frame(station.mav, 1, 1, "BAT1_CAPACITY", 0.1, REAL32))
            assert [name for name, *_ in values(got)] == ["BAT1_CAPACITY"]
        finally:
            station.close()
            server.close()
        assert lines == ["BAT1_CAPACITY = 0.100000001"]  # float32 0.1, to 9 digits
        assert store.get("BAT1_CAPACITY") == struct.unpack("<f", struct.pack("<f", 0.1))[0]

    def test_a_mavlink_1_write_is_read_from_its_shorter_header(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        msg = mavlink.MAVLink_param_set_message(1, 1, b"SYS_AUTOSTART", 0.0, INT32)
        frame = bytearray(msg.pack(station.mav, force_mavlink1=True))
        assert frame[0] == 0xFE  # MAVLink 1: a 6-byte header
        frame[6:10] = struct.pack("<i", 4001)
        crc = mavutil.x25crc(bytes(frame[1 : 6 + frame[1]]))
        crc.accumulate(bytes([msg.crc_extra]))
        frame[6 + frame[1] :] = struct.pack("<H", crc.crc)
        got = station.exchange(bytes(frame))
        assert [(n, v) for n, v, _, _ in values(got)] == [("SYS_AUTOSTART", 4001)]
        assert server.store.get("SYS_AUTOSTART") == 4001

    @pytest.mark.parametrize(
        ("name", "value", "kind", "why", "code"),
        [
            # MAV_PARAM_ERROR: 7 TYPE_MISMATCH, 6 TYPE_UNSUPPORTED (common.xml; they were all
            # 2, VALUE_OUT_OF_RANGE: helper-111)
            ("INA238_1C", 70.0, REAL32, "INA238_1C: type REAL32 refused: the parameter is INT32",
             7),
            ("INA238_1C", 70, 5, "INA238_1C: type UINT32 refused: the parameter is INT32", 6),
            ("INA238_1C", 70, 4, "INA238_1C: type 4 refused: the parameter is INT32", 6),
            ("BAT1_CAPACITY", 5, INT32,
             "BAT1_CAPACITY: type INT32 refused: the parameter is REAL32", 7),
            ("INA238_1C", 200, INT32, "INA238_1C: INA238#1: bus.i2c.address: value 200 is out of "
             "range (expected 0 to 127)", mavlink.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE),
        ],
    )  # fmt: skip
    def test_a_refused_write_answers_the_unchanged_value_a_statustext_and_a_param_error(
        self,
        turns: tuple[MavlinkParamServer, Station],
        name: str,
        value: float,
        kind: int,
        why: str,
        code: int,
    ) -> None:
        server, station = turns
        got = station.exchange(set_frame(station.mav, 1, 1, name, value, kind))
        # the value, the reason (in 50-character chunks), the error: in that order
        chunks = -(-len(why) // 50)
        assert kinds(got) == ["PARAM_VALUE"] + ["STATUSTEXT"] * chunks + ["PARAM_ERROR"]
        index = NAMES.index(name)
        shown = {"INA238_1C": 0x45, "BAT1_CAPACITY": -1.0}[name]
        assert values(got) == [(name, shown, index, len(NAMES))]
        assert Client.text(got) == [why]
        error = got[-1]
        assert (error.param_id, error.param_index, error.target_system) == (name, index, 255)
        assert error.error == code
        assert server.logged == [f"refused: {why}"]  # type: ignore[attr-defined]
        assert server.stats["refused"] == 1 and server.stats["accepted"] == 0
        assert server.store.get("INA238#1.bus.i2c.address") == 0x45
        assert server.store.get("BAT1_CAPACITY") == -1.0

    def test_a_float_write_echoes_the_float32_sent_and_reads_the_stored_float16(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """Ground stations take a write as done when the echo equals what they sent; the
        leaf keeps the float16 nearest (1049 * 2**-21 for 0.0005)."""
        server, station = turns
        got = station.exchange(set_frame(station.mav, 1, 1, "INA238_1Q", 0.0005, REAL32))
        sent = struct.unpack("<f", struct.pack("<f", 0.0005))[0]
        index = NAMES.index("INA238_1Q")
        assert values(got) == [("INA238_1Q", sent, index, len(NAMES))]
        read = mavlink.MAVLink_param_request_read_message(1, 1, b"INA238_1Q", -1)
        assert values(station.exchange(read)) == [("INA238_1Q", 1049 * 2**-21, index, len(NAMES))]
        assert server.logged == [f"INA238_1Q = {1049 * 2**-21:.9g}, saved"]  # type: ignore[attr-defined]

    @pytest.mark.parametrize(
        ("name", "why"),
        [
            (
                "INA238_2C",
                "INA238_2C belongs to INA238#2, which does not exist (add it first: "
                "param add INA238#2)",
            ),
            (
                "INA238_1D",
                "INA238_1D (INA238#1.bus.spi.bus_id) is not live: bus._tag selects variant 0, "
                "not 1 (set INA238_1A to 1)",
            ),
        ],
    )
    def test_a_name_that_is_not_live_is_refused_with_the_reason(
        self, turns: tuple[MavlinkParamServer, Station], name: str, why: str
    ) -> None:
        server, station = turns
        read = mavlink.MAVLink_param_request_read_message(1, 1, name.encode(), -1)
        got = station.exchange(read)
        assert Client.text(got) == [why] and kinds(got)[-1] == "PARAM_ERROR"
        got = station.exchange(set_frame(station.mav, 1, 1, name, 1, INT32))
        assert Client.text(got) == [why] and values(got) == []
        assert got[-1].error == mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST
        assert server.logged == [f"refused: {why}"]  # type: ignore[attr-defined]

    def test_a_write_to_an_unknown_name_is_refused_without_a_value(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        got = station.exchange(set_frame(station.mav, 1, 1, "NO_SUCH_PARAM", 1, INT32))
        assert kinds(got) == ["STATUSTEXT", "PARAM_ERROR"]
        assert got[0].text == "[pm] unknown param: NO_SUCH_PARAM"
        assert (got[1].param_index, got[1].error) == (-1, mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST)
        assert server.stats["refused"] == 1

    def test_a_write_that_selects_a_variant_announces_its_leaves_to_every_peer(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        got = values(station.exchange(set_frame(station.mav, 1, 1, "INA238_1A", 1, INT32)))
        count = len(NAMES) + 2  # B, C (I2C) go; D, E, F, G (SPI) come
        assert [(name, count_) for name, _, _, count_ in got] == [
            (n, count) for n in ["INA238_1A", "INA238_1D", "INA238_1E", "INA238_1F", "INA238_1G"]
        ]
        assert got[0][1] == 1
        assert server.logged == ["INA238_1A = 1, saved"]  # type: ignore[attr-defined]

    def test_a_mask_write_logs_the_instances_it_changed(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        got = values(station.exchange(set_frame(station.mav, 1, 1, "INA238_INST", 0b11, INT32)))
        assert got[0][:2] == ("INA238_INST", 3)
        assert {name for name, *_ in got[1:]} == {f"INA238_0{x}" for x in "ABCPQ"}
        assert server.logged[-1] == "INA238_INST = 3, saved"  # type: ignore[attr-defined]
        assert len(server.logged) == 2 and "INA238#0" in server.logged[0]  # type: ignore[attr-defined]

    def test_another_writer_s_save_is_announced_to_every_peer(
        self,
        polled: tuple[MavlinkParamServer, Station, Path, list[str]],
        schema: px4params.Schema,
    ) -> None:
        server, station, path, lines = polled
        other = Session(px4params.Store.load(path, schema, classic=CLASSIC), str(path))
        other.commit(lambda: other.store.set("SYS_AUTOSTART", 4001))
        got = values(turn(server, station))
        index = NAMES.index("SYS_AUTOSTART")
        assert got == [("SYS_AUTOSTART", 4001, index, len(NAMES))]
        assert lines == ["store changed by another writer: 1 parameters announced"]
        assert turn(server, station) == []  # said once

    @pytest.mark.parametrize(
        ("command", "param1", "result", "reply"),
        [
            (mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1, 0, "AUTOPILOT_VERSION"),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 148, 0, "AUTOPILOT_VERSION"),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 397, 0, 397),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 395, 0, 395),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 0, 3, None),  # HEARTBEAT: not on request
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 2**24 - 1, 3, None),  # the largest ID: none such
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 2**24, 2, None),  # beyond 24 bits: denied
            (mavlink.MAV_CMD_REQUEST_MESSAGE, -1, 2, None),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 148.5, 2, None),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, float("nan"), 2, None),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, float("inf"), 2, None),
            (mavlink.MAV_CMD_NAV_TAKEOFF, 0, 3, None),
        ],
    )
    def test_every_command_long_gets_one_ack_to_its_sender_after_its_reply(
        self,
        turns: tuple[MavlinkParamServer, Station],
        command: int,
        param1: float,
        result: int,
        reply: str | int | None,
    ) -> None:
        _server, station = turns
        msg = mavlink.MAVLink_command_long_message(1, 1, command, 0, param1, 0, 0, 0, 0, 0, 0)
        got = station.exchange(msg)
        ids = [int.from_bytes(frame[7:10], "little") for frame in station.frames]
        if isinstance(reply, int):  # not in pymavlink's common dialect: by its message ID
            assert ids == [reply, mavlink.MAVLINK_MSG_ID_COMMAND_ACK]
        else:
            assert kinds(got) == ([reply] if reply else []) + ["COMMAND_ACK"]
        ack = got[-1]
        assert (ack.command, ack.result, ack.progress, ack.result_param2) == (command, result, 0, 0)
        assert (ack.target_system, ack.target_component) == (255, 190)
        assert result == {0: mavlink.MAV_RESULT_ACCEPTED, 2: mavlink.MAV_RESULT_DENIED}.get(
            result, mavlink.MAV_RESULT_UNSUPPORTED
        )

    def test_autopilot_version_is_px4s_encoding_of_this_package_and_store(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        msg = mavlink.MAVLink_command_long_message(
            1, 1, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 0, 1, 0, 0, 0, 0, 0, 0
        )
        version = station.exchange(msg)[0]
        assert version.capabilities == (
            mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
            | mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
        )
        assert px4params.__version__ == "0.1.0"
        assert version.flight_sw_version == 0x000100FF  # 0.1.0, official release (255)
        assert (version.middleware_sw_version, version.os_sw_version) == (0, 0)
        assert (version.board_version, version.vendor_id, version.product_id) == (0, 0, 0)
        assert list(version.flight_custom_version) == [0] * 8
        digest = hashlib.sha256(("file:" + os.path.realpath(server.save_path)).encode()).digest()
        assert version.uid == int.from_bytes(digest[:8], "little")
        assert bytes(version.uid2) == digest[8:26]

    def test_heartbeats_go_to_the_gcs_before_it_speaks_and_once_an_interval(
        self, store: px4params.Store
    ) -> None:
        gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        gcs.bind(("127.0.0.1", 0))
        gcs.setblocking(False)
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, gcs=[gcs.getsockname()], system_id=7, component_id=9,
            heartbeat_interval=3600,
        )  # fmt: skip
        try:
            server.step(0.0)
            server.step(0.0)  # the next is an hour away
            (frame,) = _datagrams(gcs)
            (beat,) = mavlink.MAVLink(None).parse_buffer(frame)
            assert (beat.get_srcSystem(), beat.get_srcComponent()) == (7, 9)
            assert (beat.type, beat.autopilot) == (
                mavlink.MAV_TYPE_GENERIC,
                mavlink.MAV_AUTOPILOT_PX4,
            )
            assert beat.base_mode == mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            assert (beat.custom_mode, beat.system_status) == (0, mavlink.MAV_STATE_STANDBY)
            assert beat.mavlink_version == 3
        finally:
            gcs.close()
            server.close()

    def test_heartbeats_reach_the_16_latest_peers_heard_within_the_timeout(
        self, store: px4params.Store
    ) -> None:
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=0, peer_timeout=3600)
        stations = [Station(server) for _ in range(17)]
        try:
            for station in stations:
                station.send(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
                server.step(0.0)
            for station in stations:
                station.receive()
            server.step(0.0)
            beats = [len(station.receive()) for station in stations]
            assert beats == [0] + [1] * 16  # the oldest of 17 is forgotten
        finally:
            for station in stations:
                station.close()
            server.close()

    def test_a_peer_silent_longer_than_the_timeout_gets_no_heartbeat(
        self, store: px4params.Store
    ) -> None:
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=0, peer_timeout=0.5)
        gone, staying = Station(server), Station(server)
        try:
            gone.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            time.sleep(0.6)
            staying.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            gone.receive()
            server.step(0.0)
            assert gone.receive() == [] and kinds(staying.receive()) == ["HEARTBEAT"]
        finally:
            gone.close()
            staying.close()
            server.close()

    # A heartbeat with its CRC broken; and a frame of an ID the dialect lacks (STX, length 1,
    # flags 0 0, seq 0, system 255, component 190, ID 0xABCDE, one payload byte, any CRC):
    # random bytes often hold one, and pymavlink hands it back unchecked (no CRC_EXTRA).
    @pytest.mark.parametrize(
        "garbage",
        [
            "bad_crc",
            bytes([0xFD, 1, 0, 0, 0, 255, 190, 0xDE, 0xBC, 0x0A, 7, 0x12, 0x34]),
        ],
        ids=["bad_crc", "unknown_message_id"],
    )
    def test_garbage_is_counted_and_makes_no_peer(
        self, store: px4params.Store, garbage: str | bytes
    ) -> None:
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=0)
        station = Station(server)
        try:
            if isinstance(garbage, bytes):
                parsed = mavlink.MAVLink(None).parse_buffer(garbage)
                assert parsed[0].get_type() == "UNKNOWN_703710"
                frame = garbage
            else:
                good = mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(station.mav)
                frame = good[:-1] + bytes([good[-1] ^ 0xFF])
            station.send(frame)
            server.step(0.0)
            server.step(0.0)
            assert station.receive() == []  # not a peer: no heartbeat
            assert server.stats["ignored"] == 1 and server.stats["received"] == 0
        finally:
            station.close()
            server.close()

    @pytest.mark.parametrize(
        ("length", "chunks"),
        [(50, [50]), (51, [50, 1]), (100, [50, 50, 0]), (120, [50, 50, 20])],
    )
    def test_long_health_lines_are_statustext_chunks_of_50_with_an_id(
        self, store: px4params.Store, length: int, chunks: list[int]
    ) -> None:
        line = ("health: INA238#1 critical " * 10)[:length]
        server = MavlinkParamServer(store, "127.0.0.1", 0, health=lambda: [line], health_interval=0)
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            got = turn(server, station)
            assert [len(m.text) for m in got] == chunks
            assert "".join(m.text for m in got) == line
            assert [m.chunk_seq for m in got] == list(range(len(chunks)))
            assert {m.id for m in got} == {0 if len(chunks) == 1 else 1}
            assert {m.severity for m in got} == {mavlink.MAV_SEVERITY_WARNING}
            got = turn(server, station)  # the next report: the next id
            assert {m.id for m in got} == {0 if len(chunks) == 1 else 2}
        finally:
            station.close()
            server.close()

    def test_statustext_ids_wrap_from_65535_to_1(self, store: px4params.Store) -> None:
        line = "x" * 60
        server = MavlinkParamServer(store, "127.0.0.1", 0, health=lambda: [line], health_interval=0)
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            ids = [turn(server, station)[0].id for _ in range(3)]
            server._text_id = 0xFFFE  # 65534 texts later
            ids += [turn(server, station)[0].id for _ in range(2)]
            assert ids == [1, 2, 3, 0xFFFF, 1]  # the first turn had no peer to tell
        finally:
            station.close()
            server.close()

    def test_a_failing_health_source_is_logged_and_the_server_goes_on(
        self, store: px4params.Store
    ) -> None:
        def broken() -> list[str]:
            raise RuntimeError("no sensors")

        lines: list[str] = []
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, health=broken, health_interval=0, log=lines.append
        )
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
            assert values(station.exchange(read)) == [(NAMES[0], 0, 0, len(NAMES))]
            assert lines[0] == "error reporting health: RuntimeError: no sensors"
        finally:
            station.close()
            server.close()

    def test_a_handler_that_fails_is_logged_counted_and_the_server_goes_on(
        self, turns: tuple[MavlinkParamServer, Station], monkeypatch: pytest.MonkeyPatch
    ) -> None:
        server, station = turns

        def broken(peer: Any, msg: Any) -> None:
            raise ValueError("bug")

        monkeypatch.setattr(server, "_command", broken)
        msg = mavlink.MAVLink_command_long_message(1, 1, 400, 0, 0, 0, 0, 0, 0, 0, 0)
        ignored = server.stats["ignored"]
        assert station.exchange(msg) == []
        assert server.logged == ["error handling COMMAND_LONG: ValueError: bug"]  # type: ignore[attr-defined]
        assert server.stats["ignored"] == ignored + 1
        read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
        assert len(values(station.exchange(read))) == 1

    # -- the defaults' timing, on a clock the test moves (issue 40: PARAM_RATE, PEER_TIMEOUT) --

    def test_a_list_streams_20_parameters_every_40_ms_by_default(
        self, store: px4params.Store, clock: Clock
    ) -> None:
        """500 PARAM_VALUEs a second (PX4's 1909 parameters in about 4 s), in bursts of 20."""
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=3600)
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            first = station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
            assert len(values(first)) == 20
            clock.now += 0.03995  # 20 / 500 s is 0.04 s
            assert turn(server, station) == []
            clock.now += 0.0001
            assert [name for name, *_ in values(turn(server, station))] == NAMES[19:39]
        finally:
            station.close()
            server.close()

    def test_a_peer_is_one_for_5_s_after_it_was_last_heard_by_default(
        self, store: px4params.Store, clock: Clock
    ) -> None:
        """Ground stations send a HEARTBEAT every second: 5 s of silence and it is gone."""
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=0)
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            station.receive()
            clock.now += 4.99
            server.step(0.0)
            assert kinds(station.receive()) == ["HEARTBEAT"]
            clock.now += 0.02  # 5.01 s of silence
            server.step(0.0)
            assert station.receive() == []
        finally:
            station.close()
            server.close()

    def test_heartbeats_go_once_a_second_by_default(
        self, store: px4params.Store, clock: Clock
    ) -> None:
        """MAVLink's heartbeat: 1 Hz."""
        server = MavlinkParamServer(store, "127.0.0.1", 0)
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            station.receive()  # the first turn's heartbeat had no peer to go to
            beats = []
            for _ in range(4):
                clock.now += 0.5
                server.step(0.0)
                beats.append(len(station.receive()))
            assert beats == [0, 1, 0, 1]
        finally:
            station.close()
            server.close()

    def test_health_is_reported_every_2_s_by_default(
        self, store: px4params.Store, clock: Clock
    ) -> None:
        line = "health: INA238#1 critical"
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, heartbeat_interval=3600, health=lambda: [line]
        )
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            reports = []
            for _ in range(4):  # the first turn had no peer to tell
                clock.now += 1.0
                reports.append([m.text for m in turn(server, station)])
            assert reports == [[], [line], [], [line]]
        finally:
            station.close()
            server.close()

    def test_the_store_file_is_looked_at_every_200_ms_by_default(
        self,
        store: px4params.Store,
        tmp_path: Path,
        schema: px4params.Schema,
        clock: Clock,
    ) -> None:
        path = tmp_path / "vehicle.store"
        store.save(path)
        server = MavlinkParamServer(store, "127.0.0.1", 0, save_path=path, heartbeat_interval=3600)
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))  # polled
            other = Session(px4params.Store.load(path, schema, classic=CLASSIC), str(path))
            other.commit(lambda: other.store.set("SYS_AUTOSTART", 4001))
            clock.now += 0.19
            assert turn(server, station) == []
            clock.now += 0.02
            assert [name for name, *_ in values(turn(server, station))] == ["SYS_AUTOSTART"]
        finally:
            station.close()
            server.close()

    def test_the_sequence_number_counts_every_frame_and_wraps_after_255(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """MAVLink's header: seq, one byte, one more for each frame sent (ground stations count
        lost frames by its gaps)."""
        server, station = turns
        frames: list[bytes] = []
        for _ in range(6):  # 46 frames a list
            station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
            frames += station.frames
            while turn(server, station):
                frames += station.frames
        assert len(frames) == 6 * 46
        seqs = [frame[4] for frame in frames]
        assert seqs == [(seqs[0] + i) % 256 for i in range(len(frames))]

    def test_a_frame_after_line_noise_in_a_datagram_is_answered_and_the_noise_counted(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """MAVLink parsers skip bytes until a start marker (PX4's mavlink_parse_char)."""
        server, station = turns
        read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0).pack(station.mav)
        ignored = server.stats["ignored"]
        got = station.exchange(b"\x00\x01noise" + read)
        assert values(got) == [(NAMES[0], 0, 0, len(NAMES))]
        assert server.stats["ignored"] - ignored == 1  # one BAD_DATA: pymavlink joins the run


class Clock:
    """mavlink.py's ``time``: ``monotonic()`` is ``now``, which the test moves."""

    def __init__(self, now: float) -> None:
        self.now = now

    def monotonic(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> Clock:
    fake = Clock(1000.0)
    monkeypatch.setattr(mavlink_server_module, "time", fake)
    return fake


def _datagrams(sock: socket.socket) -> list[bytes]:
    out = []
    while True:
        try:
            out.append(sock.recv(65535))
        except BlockingIOError:
            return out


def ftp_download(station: Station, uri: str) -> bytes:
    """A file read with MAVLink FTP as QGC reads an mftp:// URI (the path after the scheme
    and an optional [;comp=N]): OpenFileRO, then ReadFile at each offset until the NAK EOF
    (payload: seq u16, session, opcode, size, req_opcode, burst_complete, padding u8,
    offset u32, data)."""
    path = re.sub(r"^mftp://(\[[^\]]*\])?", "", uri).encode()
    header = struct.Struct("<HBBBBBBI")

    def ask(opcode: int, session: int = 0, offset: int = 0, data: bytes = b"") -> tuple:
        request = (header.pack(0, session, opcode, len(data), 0, 0, 0, offset) + data).ljust(
            251, b"\0"
        )
        msg = mavlink.MAVLink_file_transfer_protocol_message(0, 1, 1, list(request))
        (reply,) = [m for m in station.exchange(msg) if m.get_type() == "FILE_TRANSFER_PROTOCOL"]
        raw = bytes(reply.payload)
        _, session, code, size, _, _, _, _ = header.unpack_from(raw)
        return session, code, raw[12 : 12 + size]

    session, code, data = ask(4, data=path)  # OpenFileRO
    assert code == 128, f"open {path!r}: NAK {data!r}"
    (length,) = struct.unpack("<I", data)
    content = b""
    for _ in range(length // 239 + 2):  # bounded: one ReadFile per 239 bytes, then EOF
        _, code, data = ask(5, session, len(content))  # ReadFile
        if code == 129:
            assert data[:1] == bytes([6])  # EOF
            break
        content += data
    assert len(content) == length
    ask(1, session)  # TerminateSession
    return content


@pytest.mark.issue40
@pytest.mark.parametrize("value", [0, 1, -1, 2**31 - 1, -(2**31), *SNAN_INT32])
def test_a_param_set_message_carries_an_int32_bytewise(value: int) -> None:
    msg = param_set_message(1, 1, "SYS_AUTOSTART", value, INT32)
    (parsed,) = mavlink.MAVLink(None).parse_buffer(msg.pack(mavlink.MAVLink(None)))
    assert (parsed.target_system, parsed.target_component) == (1, 1)
    assert (parsed.param_id, parsed.param_type) == ("SYS_AUTOSTART", INT32)
    assert value_of(parsed) == value and param_value_of(parsed) == value


@pytest.mark.issue40
def test_param_value_of_reads_uint32_and_real32_and_mavlink_1() -> None:
    uint32 = param_set_message(1, 1, "_HASH_CHECK", 0xFFFFFFFF, mavlink.MAV_PARAM_TYPE_UINT32)
    (parsed,) = mavlink.MAVLink(None).parse_buffer(uint32.pack(mavlink.MAVLink(None)))
    assert param_value_of(parsed) == 0xFFFFFFFF
    real = param_set_message(1, 1, "BAT1_CAPACITY", 0.5, REAL32)
    frame = real.pack(mavlink.MAVLink(None), force_mavlink1=True)
    (parsed,) = mavlink.MAVLink(None).parse_buffer(frame)
    assert frame[0] == 0xFE and param_value_of(parsed) == 0.5
    assert isinstance(param_value_of(parsed), float)
    zero = param_set_message(1, 1, "SYS_AUTOSTART", 0, INT32)  # MAVLink 2 trims the zeros
    (parsed,) = mavlink.MAVLink(None).parse_buffer(zero.pack(mavlink.MAVLink(None)))
    assert param_value_of(parsed) == 0


@pytest.mark.issue40
def test_a_development_version_is_release_type_0(monkeypatch: pytest.MonkeyPatch) -> None:
    """PX4's flight_sw_version: major, minor, patch, then FIRMWARE_VERSION_TYPE (0 dev, 255
    official)."""
    monkeypatch.setattr(px4params, "__version__", "2.3.4.dev5")
    assert software_version() == 0x020304_00
    monkeypatch.setattr(px4params, "__version__", "1.15.300")
    assert software_version() == 0x010F2CFF  # each part one byte (300 & 0xFF = 0x2C)


# -- the receive loop and the stream's failure (issue 40, mutlinks2) ----------------------------


class _FailingOnce:
    """The server's socket, whose next ``recvfrom`` fails once as a socket reports an ICMP
    error (port unreachable) for an earlier datagram (Windows does on any UDP socket, Linux on
    a connected one): the datagrams queued behind it are still there."""

    def __init__(self, sock: socket.socket, error: OSError) -> None:
        self._real = sock
        self._error: OSError | None = error

    def recvfrom(self, size: int) -> tuple[bytes, Any]:
        if self._error is not None:
            error, self._error = self._error, None
            raise error
        return self._real.recvfrom(size)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real, name)


@pytest.mark.issue40
class TestTurnByTurnReceiving:
    """How one turn reads and streams (issue 40, mutlinks2): each turn is bounded, and a
    failure on the way drops only what it concerns."""

    def test_a_turn_reads_at_most_256_datagrams_and_the_next_turn_the_rest(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """Under a flood a turn stops reading after 256 datagrams (so that heartbeats and a
        list's bursts go on); what is left waits in the socket for the next turn."""
        server, station = turns
        # room for the flood (the default buffer holds about 256 such datagrams; Linux doubles
        # what is asked, up to twice rmem_max, 212992 by default)
        server._sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        heartbeat = mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(station.mav)
        received = server.stats["received"]
        for _ in range(257):
            station.send(heartbeat)
        server.step(0.0)
        assert server.stats["received"] - received == 256
        server.step(0.0)
        assert server.stats["received"] - received == 257

    def test_a_heartbeat_is_received_not_ignored(self, store: px4params.Store) -> None:
        """A ground station's HEARTBEAT is a message the server takes (it makes the sender a
        peer): counted received, not ignored, and answered by nothing but heartbeats."""
        server = MavlinkParamServer(store, "127.0.0.1", 0, heartbeat_interval=3600)
        station = Station(server)
        try:
            assert station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3)) == []
        finally:
            station.close()
            server.close()
        assert (server.stats["received"], server.stats["ignored"]) == (1, 0)

    def test_a_socket_error_does_not_keep_the_turn_from_the_datagrams_behind_it(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        server._sock = _FailingOnce(server._sock, ConnectionRefusedError(111, "refused"))  # type: ignore[assignment]
        read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
        assert values(station.exchange(read)) == [(NAMES[0], 0, 0, len(NAMES))]

    def test_a_stream_that_fails_is_dropped_logged_once_and_the_server_goes_on(
        self, turns: tuple[MavlinkParamServer, Station], monkeypatch: pytest.MonkeyPatch
    ) -> None:
        """A bug while streaming a list must not stop the server: that stream ends (the ground
        station asks again by index for what it lacks), the error is logged, reads go on."""
        server, station = turns

        def broken(index: int, entry: Any) -> Any:
            raise ValueError("bug")

        monkeypatch.setattr(server, "_value_msg", broken)
        got = station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
        assert [m.param_id for m in got] == ["_HASH_CHECK"]  # the hash, then the failure
        assert server.logged == ["error streaming parameters: ValueError: bug"]  # type: ignore[attr-defined]
        monkeypatch.undo()
        assert turn(server, station) == []  # dropped: nothing more of that list
        assert turn(server, station) == []
        assert server.logged == ["error streaming parameters: ValueError: bug"]  # type: ignore[attr-defined]
        read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
        assert values(station.exchange(read)) == [(NAMES[0], 0, 0, len(NAMES))]


def signed_station(server: MavlinkParamServer, key: bytes) -> Station:
    """A ground station that signs what it sends with ``key`` (pymavlink's own signing: link
    0, its timestamp the signing clock, 10 us units since 2015-01-01)."""
    station = Station(server)
    station.mav.signing.secret_key = key
    station.mav.signing.link_id = 0
    station.mav.signing.timestamp = int((time.time() - 1420070400) * 100_000)
    station.mav.signing.sign_outgoing = True
    return station


@pytest.mark.issue40
class TestTurnByTurnSigned:
    """A signed link turn by turn (issue 40, mutlinks2): PX4 (mavlink_sign_control.cpp) takes
    signed frames with the link's key, and drops the rest, counting them."""

    KEY = bytes(range(32))

    @pytest.fixture
    def signed(self, store: px4params.Store) -> Iterator[MavlinkParamServer]:
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, signing_key=self.KEY, heartbeat_interval=3600
        )
        yield server
        server.close()

    def test_a_frame_signed_with_the_key_is_answered(self, signed: MavlinkParamServer) -> None:
        station = signed_station(signed, self.KEY)
        try:
            read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
            got = station.exchange(read)
            assert values(got) == [(NAMES[0], 0, 0, len(NAMES))]
            assert all(frame[2] & mavlink.MAVLINK_IFLAG_SIGNED for frame in station.frames)
        finally:
            station.close()
        assert signed.stats["received"] == 1
        assert (signed.stats["unsigned"], signed.stats["badly_signed"]) == (0, 0)

    def test_a_frame_signed_with_another_key_is_dropped_and_counted_badly_signed(
        self, signed: MavlinkParamServer
    ) -> None:
        station = signed_station(signed, bytes(32))
        try:
            read = mavlink.MAVLink_param_request_read_message(1, 1, b"", 0)
            assert station.exchange(read) == []
        finally:
            station.close()
        assert (signed.stats["unsigned"], signed.stats["badly_signed"]) == (0, 1)
        assert signed.stats["received"] == 0

    def test_an_unsigned_frame_of_an_unknown_message_id_is_dropped_and_counted_unsigned(
        self, signed: MavlinkParamServer
    ) -> None:
        """A frame of an ID the dialect lacks (STX, length 1, flags 0 0, seq 0, system 255,
        component 190, ID 0xABCDE): pymavlink hands it over without checking its signature;
        on a signed link it is an unsigned frame like any other."""
        station = Station(signed)
        try:
            unknown = bytes([0xFD, 1, 0, 0, 0, 255, 190, 0xDE, 0xBC, 0x0A, 7, 0x12, 0x34])
            assert station.exchange(unknown) == []
        finally:
            station.close()
        assert (signed.stats["unsigned"], signed.stats["badly_signed"]) == (1, 0)
        assert (signed.stats["received"], signed.stats["ignored"]) == (0, 0)

    @pytest.mark.parametrize("signing", [True, False], ids=["signed", "unsigned"])
    def test_a_datagram_the_parser_fails_on_is_counted_ignored_and_makes_no_peer(
        self, store: px4params.Store, monkeypatch: pytest.MonkeyPatch, signing: bool
    ) -> None:
        """pymavlink raises assorted errors on some garbage: the datagram is one ignored."""
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, signing_key=self.KEY if signing else None, heartbeat_interval=0
        )
        station = signed_station(server, self.KEY) if signing else Station(server)

        def failing(self: Any, data: bytes) -> list[Any]:
            raise struct.error("unpack requires a buffer of 9 bytes")

        try:
            heartbeat = mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(station.mav)
            station.send(heartbeat[:-1] + bytes([heartbeat[-1] ^ 0xFF]))  # its CRC broken
            server.step(0.0)
            assert server.stats["ignored"] == 1
            monkeypatch.setattr(mavlink.MAVLink, "parse_buffer", failing)
            station.send(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            server.step(0.0)
            monkeypatch.undo()
            server.step(0.0)
            assert station.receive() == []  # no peer: no heartbeat
        finally:
            station.close()
            server.close()
        assert (server.stats["ignored"], server.stats["received"]) == (2, 0)


@pytest.mark.issue40
class TestTurnByTurnQuiet:
    """What the server does not do (issue 40, mutlinks3: the survivors of the mavlink target in
    lines 424-821): a stream that ends, is stopped or loses its requester says nothing in the
    log; messages it does not serve get no answer and no log line; refusals count one each."""

    def test_a_list_streamed_to_its_end_logs_nothing(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        listed = values(station.exchange(mavlink.MAVLink_param_request_list_message(1, 1)))
        for _ in range(5):
            listed += values(turn(server, station))
        assert len(listed) == 1 + len(NAMES)
        assert server.logged == []  # type: ignore[attr-defined]

    def test_a_hash_check_set_stops_the_stream_without_a_log_line(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        first = station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))
        station.exchange(set_frame(station.mav, 1, 1, "_HASH_CHECK", value_of(first[0]), 6))
        for _ in range(3):
            assert turn(server, station) == []
        assert server.logged == []  # type: ignore[attr-defined]

    def test_a_stream_whose_requester_fell_silent_stops_without_a_log_line(
        self, store: px4params.Store
    ) -> None:
        lines: list[str] = []
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, param_rate=1e9, peer_timeout=0.5, log=lines.append
        )
        station = Station(server)
        try:
            assert len(station.exchange(mavlink.MAVLink_param_request_list_message(1, 1))) == 20
            time.sleep(0.6)  # longer than peer_timeout: the requester is gone
            for _ in range(3):
                assert turn(server, station) == []
            assert lines == []
        finally:
            station.close()
            server.close()

    def test_each_refused_write_counts_once(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        for value in (200, 300):  # a 7-bit I2C address: out of range
            got = station.exchange(set_frame(station.mav, 1, 1, "INA238_1C", value, INT32))
            assert kinds(got)[-1] == "PARAM_ERROR"
        assert server.stats["refused"] == 2 and server.stats["accepted"] == 0

    def test_a_read_of_a_name_that_is_not_ascii_is_refused_in_ascii(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """param_id is ASCII (MAVLink's char[16]); a byte above 0x7F names no parameter. The
        refusal is PX4's, the STATUSTEXT (ASCII as well) showing the byte as '?'."""
        server, station = turns
        got = station.exchange(mavlink.MAVLink_param_request_read_message(1, 1, b"BAT\xff", -1))
        assert kinds(got) == ["STATUSTEXT", "PARAM_ERROR"]
        assert Client.text(got) == ["[pm] unknown param: BAT?"]
        assert server.logged == []  # type: ignore[attr-defined]

    def test_messages_it_does_not_serve_get_no_answer_and_no_log_line(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """A mission request addressed to this system and a SYSTEM_TIME (which addresses no
        one) are no parameter, command or FTP traffic: each is counted ignored, nothing more."""
        server, station = turns
        ignored = server.stats["ignored"]
        assert station.exchange(mavlink.MAVLink_mission_request_list_message(1, 1, 0)) == []
        assert station.exchange(mavlink.MAVLink_system_time_message(0, 0)) == []
        assert server.stats["ignored"] == ignored + 2
        assert server.logged == []  # type: ignore[attr-defined]

    def test_sent_counts_every_datagram_sent(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """The CLI's summary: each datagram sent to each peer counts once (a whole list here:
        the hash and every parameter, one datagram each)."""
        server, station = turns
        sent = server.stats["sent"]
        station.send(mavlink.MAVLink_param_request_list_message(1, 1))
        datagrams = 0
        for _ in range(5):
            turn(server, station)
            datagrams += len(station.frames)
        assert datagrams == 1 + len(NAMES)
        assert server.stats["sent"] == sent + datagrams

    def test_each_accepted_write_counts_once(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        server, station = turns
        for value in (0x44, 0x46):
            got = station.exchange(set_frame(station.mav, 1, 1, "INA238_1C", value, INT32))
            assert [v for _, v, _, _ in values(got)] == [value]
        assert server.stats["accepted"] == 2 and server.stats["refused"] == 0

    def test_another_writer_s_save_of_two_parameters_announces_both_and_counts_them(
        self,
        polled: tuple[MavlinkParamServer, Station, Path, list[str]],
        schema: px4params.Schema,
    ) -> None:
        server, station, path, lines = polled
        other = Session(px4params.Store.load(path, schema, classic=CLASSIC), str(path))
        other.commit(lambda: other.store.set("SYS_AUTOSTART", 4001))
        other.commit(lambda: other.store.set("INA238#1.bus.i2c.address", 0x46))
        got = {name: value for name, value, _, _ in values(turn(server, station))}
        assert got == {"SYS_AUTOSTART": 4001, "INA238_1C": 0x46}
        assert lines == ["store changed by another writer: 2 parameters announced"]

    def test_mavlink_ftp_answers_go_to_the_asker_on_network_0(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """FILE_TRANSFER_PROTOCOL's target_network is 0 (broadcast, as PX4 sends it); the
        answer is addressed to the asking system and component (255, 190)."""
        _server, station = turns
        reset = bytes([0, 0, 0, 8]) + bytes(247)  # seq 0, session 0, ResetSessions
        got = station.exchange(mavlink.MAVLink_file_transfer_protocol_message(0, 1, 1, list(reset)))
        (answer,) = [m for m in got if m.get_type() == "FILE_TRANSFER_PROTOCOL"]
        assert (answer.target_network, answer.target_system, answer.target_component) == (
            0,
            255,
            190,
        )

    def test_a_logged_integer_shows_every_digit_and_a_float_9_significant(self) -> None:
        """The log line of a write ("NAME = value"): an int32 as its digits (10 of them at
        most), a float32 to 9 significant digits (enough to tell every float32 apart)."""
        shown = mavlink_server_module._shown
        assert shown(2_147_483_647) == "2147483647" and shown(-2_147_483_648) == "-2147483648"
        assert shown(0.1) == "0.1" and shown(1 / 3) == "0.333333333"
        assert shown(float("nan")) == "nan"

    def test_every_request_it_serves_is_counted_received_not_ignored(
        self, turns: tuple[MavlinkParamServer, Station]
    ) -> None:
        """A list, a read, a write, a command and an FTP request addressed to this server are
        served: the CLI's summary counts them received, none ignored."""
        server, station = turns
        ignored, received = server.stats["ignored"], server.stats["received"]
        reset = bytes([0, 0, 0, 8]) + bytes(247)  # MAVLink FTP ResetSessions
        for msg in (
            mavlink.MAVLink_param_request_list_message(1, 1),
            mavlink.MAVLink_param_request_read_message(1, 1, b"", 0),
            set_frame(station.mav, 1, 1, "INA238_1C", 0x46, INT32),
            mavlink.MAVLink_command_long_message(
                1, 1, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 0, 1, 0, 0, 0, 0, 0, 0
            ),
            mavlink.MAVLink_file_transfer_protocol_message(0, 1, 1, list(reset)),
        ):
            assert station.exchange(msg) != []
        assert server.stats["received"] == received + 5
        assert server.stats["ignored"] == ignored

    def test_a_store_file_another_writer_left_unreadable_is_named_once(
        self,
        polled: tuple[MavlinkParamServer, Station, Path, list[str]],
    ) -> None:
        server, station, path, lines = polled
        path.write_bytes(path.read_bytes()[:10])  # truncated by another writer
        for _ in range(2):
            assert turn(server, station) == []
        assert len(lines) == 1
        assert lines[0].startswith(f"store changed by another writer, not read: {path}")


@pytest.mark.issue40
def test_a_param_set_message_packs_bytewise_as_mavlink_2_unless_asked_for_1() -> None:
    """Packed as pymavlink packs its own messages of the v20 dialect: a MAVLink 2 frame
    (magic 0xFD) by default, MAVLink 1 (0xFE) only with force_mavlink1."""
    msg = param_set_message(1, 1, "SYS_AUTOSTART", 4001, INT32)
    own = mavlink.MAVLink_param_set_message(1, 1, b"SYS_AUTOSTART", 0.0, INT32)
    assert own.pack(mavlink.MAVLink(None))[0] == 0xFD
    assert msg.pack(mavlink.MAVLink(None))[0] == 0xFD
    assert msg.pack(mavlink.MAVLink(None), force_mavlink1=True)[0] == 0xFE


@pytest.mark.issue40
class TestTurnByTurnFileAndClock:
    """A write over another writer's save of the same parameter, and the boot time the
    metadata messages carry (issue 40, mutlinks3)."""

    def test_a_write_over_another_writer_s_save_of_it_is_refused_showing_the_file_s_value(
        self, store: px4params.Store, tmp_path: Path, schema: px4params.Schema
    ) -> None:
        """The store's one write path refuses a write to a leaf another writer changed since
        this server read the file (nothing merged silently); the ground station is shown the
        file's value (as PX4 answers a refused PARAM_SET with the value it keeps)."""
        path = tmp_path / "vehicle.store"
        store.save(path)
        server = MavlinkParamServer(
            store, "127.0.0.1", 0, save_path=path, poll_interval=3600, heartbeat_interval=3600
        )
        station = Station(server)
        try:
            station.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
            other = Session(px4params.Store.load(path, schema, classic=CLASSIC), str(path))
            other.commit(lambda: other.store.set("SYS_AUTOSTART", 4001))
            got = station.exchange(set_frame(station.mav, 1, 1, "SYS_AUTOSTART", 4002, INT32))
            shown = {value for name, value, _, _ in values(got) if name == "SYS_AUTOSTART"}
            assert shown == {4001}
            assert kinds(got)[-1] == "PARAM_ERROR"
            assert got[-1].param_index == NAMES.index("SYS_AUTOSTART")
            assert server.stats["refused"] == 1 and server.store.get("SYS_AUTOSTART") == 4001
        finally:
            station.close()
            server.close()

    @pytest.mark.parametrize("message_id", [397, 395])  # COMPONENT_METADATA, _INFORMATION
    def test_the_metadata_messages_carry_the_milliseconds_since_the_server_started(
        self, turns: tuple[MavlinkParamServer, Station], message_id: int
    ) -> None:
        """time_boot_ms (MAVLink: time since system boot, in ms), the messages' first field.
        The server has been up for 100000 s here; the test itself takes well under 60 s."""
        server, station = turns
        server._started -= 100_000
        station.exchange(
            mavlink.MAVLink_command_long_message(
                1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, message_id, 0, 0, 0, 0, 0, 0
            )
        )
        frame = next(f for f in station.frames if int.from_bytes(f[7:10], "little") == message_id)
        (time_boot_ms,) = struct.unpack("<I", (frame[10 : 10 + frame[1]] + bytes(4))[:4])
        assert 100_000_000 <= time_boot_ms < 100_060_000
