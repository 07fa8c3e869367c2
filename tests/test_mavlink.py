"""The MAVLink parameter server, with pymavlink as a real client over UDP on 127.0.0.1."""

from __future__ import annotations

import os
import re
import select
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import px4params
import pytest
from px4params.links.mavlink import CAPABILITIES, MavlinkParamServer
from px4params.store.classic import ClassicParam
from px4params.store.session import open_session
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
    assert [(e.param_id, e.error) for e in errors] == [
        ("INA238_1C", mavlink.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE)
    ]
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
    client.set("INA238_1Q", 1e6, REAL32)  # float16 tops out at 65504
    got = client.collect(0.5)
    assert Client.text(got) == [
        "INA238_1Q: INA238#1: shunt: value 1000000 is out of range (expected -65504 to 65504)"
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


def test_autopilot_version_and_heartbeat(served: tuple[MavlinkParamServer, Client]) -> None:
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
    other = MavlinkParamServer(server.store, "127.0.0.1", 0, save_path="/tmp/another.store")
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
