"""DroneCAN parameters over SLCAN: the long names, the SLCAN adapter, the transfer receiver
(against pydronecan's frames), the node (``px4params dronecan serve``) with pydronecan as the
peer through its own SLCAN driver, and ``px4params dronecan param`` against a pydronecan node
that serves parameters.
"""

from __future__ import annotations

import subprocess
import threading
import time
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from dronecan import transport
from dronecan_bus import PX4PARAMS, VirtualBus, served, start_serving
from px4params.errors import FlatError, Px4ParamsError
from px4params.links.can_transfer import Frame, TransferReceiver, can_id, parse_can_id
from px4params.links.dronecan_client import DronecanError, parse_value, shown
from px4params.links.dronecan_params import DronecanParams
from px4params.links.slcan import SlcanAdapter, SlcanError, format_frame, parse_frame
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.store.flat import layout
from px4params.store.long_names import LongNames, leaf_names

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "two_batteries.airframe"
NODE = 1
GETSET = dronecan.uavcan.protocol.param.GetSet
OPCODE = dronecan.uavcan.protocol.param.ExecuteOpcode


def _run(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    result = subprocess.run(
        [*PX4PARAMS, *args], capture_output=True, text=True, timeout=120, check=False
    )
    if check:
        assert result.returncode == 0, result.stderr
    return result


@pytest.fixture
def vehicle_store(tmp_path: Path) -> Path:
    store = tmp_path / "vehicle.store"
    _run("run", str(EXAMPLE), "--store", str(store))
    return store


def _store(path: Path) -> px4params.Store:
    return px4params.Store.load(path, classic=BUNDLED_CLASSIC)


# -- long names -------------------------------------------------------------------------------


def test_long_names_are_the_talks(vehicle_store: Path) -> None:
    names = {
        row.name: (str(row.leaf), row.slot.path) for row in LongNames(_store(vehicle_store)).table()
    }
    # The talk's three examples, written down from its slide.
    assert names["INA238_1_BUS_TYPE"] == ("INA238#1[1]", "bus._tag")
    assert names["INA238_1_I2C_BUS_ID"] == ("INA238#1[3]", "bus.i2c.bus_id")
    assert names["INA238_1_I2C_ADDRESS"] == ("INA238#1[4]", "bus.i2c.address")
    assert names["INA238_0_SHUNT"] == ("INA238#0[6]", "shunt")
    assert "AK09916_0_ROTATION" in names
    assert not [n for n in names if n.startswith("INA238_1_SPI")]  # not the selected variant


def test_long_name_parts_of_arrays_and_colliding_variants(tmp_path: Path) -> None:
    root = tmp_path / "lt"
    root.mkdir()
    (root / "A.1.0.dsdl").write_text("uint8 x\n@sealed\n")
    (root / "U.1.0.dsdl").write_text("@union\nA.1.0 a\nuint4 b\n@sealed\n")
    (root / "W.1.0.dsdl").write_text(
        "# @max_instances 2\nU.1.0 first\nU.1.0 second\nU.1.0[2] pair\nuint3[<=2] cells\n@sealed\n"
    )
    schema = px4params.load_schema(
        [root], include_dronecan=False, use_env=False, cache_dir=tmp_path / "cache"
    )
    parts = leaf_names(layout(schema.get("lt.W")))
    # `a` and `b` are variants of both `first` and `second`: those keep their whole path.
    assert parts["first._tag"] == "FIRST_TYPE"
    assert parts["first.a.x"] == "FIRST_A_X"
    assert parts["second.b"] == "SECOND_B"
    # An array of unions: the element number stays, the variant follows it.
    assert parts["pair[1]._tag"] == "PAIR_1_TYPE"
    assert parts["pair[1].b"] == "PAIR_1_B"
    assert parts["cells._len"] == "CELLS_LEN"
    assert parts["cells[1]"] == "CELLS_1"


def test_long_names_refuse_a_clash_with_a_classic_name(tmp_path: Path) -> None:
    root = tmp_path / "lt"
    root.mkdir()
    (root / "Clash.1.0.dsdl").write_text(
        "# @param SYS\n# @max_instances 1\nuint8 autostart\n@sealed\n"
    )
    cache = tmp_path / "cache"
    schema = px4params.load_schema([root], include_dronecan=False, use_env=False, cache_dir=cache)
    # Instanced, the long name is SYS_0_AUTOSTART; shared, it is SYS_AUTOSTART, a classic one.
    LongNames(px4params.Store(schema, classic=BUNDLED_CLASSIC))  # SYS_0_AUTOSTART: no clash
    (root / "Clash.1.0.dsdl").write_text("# @param SYS\nuint8 autostart\n@sealed\n")
    schema = px4params.load_schema([root], include_dronecan=False, use_env=False, cache_dir=cache)
    with pytest.raises(FlatError, match=r"^SYS: DroneCAN name SYS_AUTOSTART \(SYS.autostart\) "):
        LongNames(px4params.Store(schema, classic=BUNDLED_CLASSIC))


# -- SLCAN --------------------------------------------------------------------------------------


def test_slcan_frame_lines_known_answers() -> None:
    # LAWICEL: T, 8 hex digits of ID, the length, the data; CR.
    frame = Frame(0x1E01017F, bytes([0x01, 0x02, 0xC0]))
    assert format_frame(frame) == b"T1E01017F3" + b"0102C0" + b"\r"
    assert format_frame(frame, stamp_ms=0x1234) == b"T1E01017F30102C01234\r"
    assert parse_frame(b"T1E01017F30102C0") == frame
    assert parse_frame(b"T1E01017F30102C01234") == frame  # time stamp ignored
    assert parse_frame(b"t1230") == Frame(0x123, b"")


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (b"X123", "'X123' is not a data frame line (expected T or t)"),
        (b"T1E0101", "expected 8 hex digits of ID and a length digit"),
        (b"T3FFFFFFF0", "ID or length out of range"),
        (b"T1E01017F9", "ID or length out of range"),
        (b"T1E01017F20102C0", "expected 2 data bytes in hex"),
        (b"T1E01017F201", "expected 2 data bytes in hex"),
        (b"T1E01017F2zz02", "expected 2 data bytes in hex"),
    ],
)
def test_slcan_bad_lines_are_named(line: bytes, message: str) -> None:
    with pytest.raises(SlcanError, match=message.replace("(", r"\(").replace(")", r"\)")):
        parse_frame(line)


def test_slcan_adapter_answers_the_commands_a_host_sends() -> None:
    adapter = SlcanAdapter()
    # pydronecan's init sequence: empty line, C, S8, O, F.
    assert adapter.feed(b"\rC\rS8\rO\rF\r") == (b"\r\r\r\rF00\r", [])
    assert adapter.open and adapter.bitrate == 1_000_000
    assert adapter.feed(b"S6\r") == (b"\x07", [])  # no bit rate change while open
    assert adapter.feed(b"V\rN\r")[0] == b"V1013\rNPX4P\r"
    replies, frames = adapter.feed(b"T1E01017F20102\rt1230\r")
    assert replies == b"Z\rz\r"
    assert frames == [Frame(0x1E01017F, b"\x01\x02"), Frame(0x123, b"")]
    assert adapter.feed(b"T1E0\r") == (b"\x07", [])  # a broken frame line: BEL, no frame
    assert adapter.deliver(Frame(0x10, b"\xff")) == b"T000000101FF\r"
    assert adapter.feed(b"C\r") == (b"\r", [])
    assert adapter.deliver(Frame(0x10, b"\xff")) == b""  # closed: nothing to the host
    assert adapter.feed(b"T1E01017F0\r") == (b"\x07", [])  # closed: sending refused
    assert adapter.feed(b"Q\r")[0] == b"\x07"
    # A runaway line (no CR for 64 bytes) is dropped whole and answered once with BEL.
    assert adapter.feed(b"T" * 200 + b"\rV\r")[0] == b"\x07V1013\r"


# -- transfers ----------------------------------------------------------------------------------


def _pydronecan_frames(
    msg: Any, *, source: int, dest: int | None, tid: int, request: bool
) -> list[Frame]:
    t = transport.Transfer(
        payload=msg,
        source_node_id=source,
        dest_node_id=dest,
        transfer_id=tid,
        service_not_message=dest is not None,
        request_not_response=request,
    )
    return [Frame(f.message_id, bytes(f.bytes)) for f in t.to_frames()]


def _long_getset_response() -> Any:
    return GETSET.Response(
        name=b"INA238_1_SOME_VERY_LONG_PARAMETER_NAME_THAT_SPANS_MANY_FRAMES",
        value=dronecan.uavcan.protocol.param.Value(integer_value=-5),
    )


def test_receiver_assembles_pydronecan_multi_frame_transfers() -> None:
    frames = _pydronecan_frames(_long_getset_response(), source=10, dest=20, tid=7, request=False)
    assert len(frames) > 5
    receiver = TransferReceiver()
    done = [receiver.feed(f) for f in frames]
    assert done[:-1] == [None] * (len(frames) - 1)
    transfer = done[-1]
    assert transfer is not None and transfer.transfer_id == 7
    assert transfer.id == parse_can_id(frames[0].can_id)
    assert (transfer.id.source_node, transfer.id.dest_node, transfer.id.request) == (10, 20, False)
    assert transfer.id.dtid == 11
    assert transfer.datas == [f.data for f in frames]


def test_receiver_ignores_broken_and_repeated_transfers() -> None:
    frames = _pydronecan_frames(_long_getset_response(), source=10, dest=20, tid=7, request=False)
    # Joined half-way: no start frame, nothing comes out.
    receiver = TransferReceiver()
    assert [receiver.feed(f) for f in frames[1:]] == [None] * (len(frames) - 1)
    # A frame lost in the middle: the toggle is wrong, the session is dropped.
    receiver = TransferReceiver()
    assert [receiver.feed(f) for f in frames[:2] + frames[3:]].count(None) == len(frames) - 1
    # The same transfer again (transfer ID 7) within the timeout: delivered once.
    receiver = TransferReceiver()
    results = [receiver.feed(f) for f in frames + frames]
    assert sum(r is not None for r in results) == 1
    # Empty frames and anonymous ones are ignored.
    assert receiver.feed(Frame(0x10, b"")) is None
    assert receiver.feed(Frame(can_id(341, source_node=1) & ~0x7F, b"\xc0")) is None


def test_receiver_keeps_interleaved_transfers_apart() -> None:
    a = _pydronecan_frames(_long_getset_response(), source=10, dest=20, tid=1, request=False)
    b = _pydronecan_frames(_long_getset_response(), source=11, dest=20, tid=1, request=False)
    receiver = TransferReceiver()
    results = [receiver.feed(f) for pair in zip(a, b, strict=True) for f in pair]
    done = [r for r in results if r is not None]
    assert [t.id.source_node for t in done] == [10, 11]


# -- the GetSet list over a store -----------------------------------------------------------------


def test_getset_entries_carry_the_right_variants(vehicle_store: Path) -> None:
    store = _store(vehicle_store)
    params = DronecanParams(store)
    address = params.entry("INA238_1_I2C_ADDRESS")
    assert address is not None
    assert address.value == {"integer_value": 0x45}
    assert address.default == {"integer_value": 0x45}
    assert (address.min, address.max) == ({"integer_value": 0}, {"integer_value": 127})  # uint7
    shunt = params.entry("INA238_1_SHUNT")
    assert shunt is not None and set(shunt.value) == {"real_value"}
    # The shunt's @min/@max (px/Ina238.1.1.dsdl), which the store enforces, not float16's.
    assert (shunt.min, shunt.max) == ({"real_value": 0.00001}, {"real_value": 0.1})
    mask = params.entry("INA238_INST")
    assert mask is not None and mask.value == {"integer_value": 0b11}
    autostart = params.entry("SYS_AUTOSTART")
    assert autostart is not None and autostart.max == {"integer_value": 9999999}  # metadata
    names = [params.name_at(i) for i in range(len(params))]
    assert names == sorted(names, key=str.encode)
    assert params.name_at(len(params)) is None and params.entry("NOPE") is None


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        (
            "INA238_1_I2C_ADDRESS",
            {"real_value": 3.0},
            "real_value refused: the parameter takes integer_value",
        ),
        (
            "INA238_1_I2C_ADDRESS",
            {"integer_value": 128},
            "value 128 is out of range (expected 0 to 127)",
        ),
        (
            "INA238_1_SHUNT",
            {"integer_value": 1},
            "integer_value refused: the parameter takes real_value",
        ),
        ("INA238_INST", {"integer_value": -1}, "is not a mask of INA238's"),
        ("SYS_AUTOSTART", {"integer_value": 1 << 40}, "SYS_AUTOSTART"),
        ("NOPE", {"integer_value": 1}, "NOPE: no such parameter"),
    ],
)
def test_refused_writes_change_nothing(
    vehicle_store: Path, name: str, value: dict[str, Any], message: str
) -> None:
    store = _store(vehicle_store)
    params = DronecanParams(store)
    before = {n: store.encoded(n) for n in store.names()}
    with pytest.raises(Px4ParamsError, match=message.replace("(", r"\(").replace(")", r"\)")) as e:
        params.set(name, value)
    assert str(e.value).startswith(name)
    assert {n: store.encoded(n) for n in store.names()} == before


def test_writing_a_tag_or_a_mask_changes_the_list(vehicle_store: Path) -> None:
    store = _store(vehicle_store)
    params = DronecanParams(store)
    assert params.set("INA238_1_BUS_TYPE", {"integer_value": 1}).startswith("INA238_1_BUS_TYPE")
    assert params.entry("INA238_1_I2C_ADDRESS") is None
    assert params.entry("INA238_1_SPI_BUS_ID") is not None
    assert (
        params.set("INA238_INST", {"integer_value": 0b101})
        == "INA238_INST: added INA238#2, removed INA238#1"
    )
    assert params.entry("INA238_2_CURRENT") is not None
    assert store.instances("INA238") == ["INA238#0", "INA238#2"]


# -- the node, with pydronecan as the peer -----------------------------------------------------


class Peer:
    """A pydronecan node on an SLCAN line (its own driver), asking one node for things."""

    def __init__(self, path: str, node_id: int = 100) -> None:
        self.node = dronecan.make_node(path, node_id=node_id, bitrate=1_000_000)
        self.statuses: list[Any] = []
        self.node.add_handler(dronecan.uavcan.protocol.NodeStatus, self._status)

    def _status(self, event: Any) -> None:
        if event.transfer.source_node_id == NODE:
            self.statuses.append(event.message)

    def call(self, request: Any, timeout: float = 3.0) -> Any:
        got: list[Any] = []
        self.node.request(request, NODE, lambda e: got.append(e), timeout=timeout)
        deadline = time.monotonic() + timeout + 1
        while not got and time.monotonic() < deadline:
            self.node.spin(0.01)
        assert got and got[0] is not None, f"no response to {type(request).__name__}"
        return got[0].response

    def getset(self, index: int = 0, name: bytes = b"", **value: Any) -> Any:
        v = dronecan.uavcan.protocol.param.Value(**value) if value else None
        request = GETSET.Request(index=index, name=name)
        if v is not None:
            request.value = v
        return self.call(request)

    def close(self) -> None:
        self.node.close()


def _field(value: Any) -> tuple[str, Any]:
    kind = dronecan.get_active_union_field(value)
    return kind, getattr(value, kind) if kind != "empty" else None


def test_pydronecan_reads_and_writes_the_manifest(vehicle_store: Path) -> None:
    with served(vehicle_store) as path:
        peer = Peer(path)
        try:
            info = peer.call(dronecan.uavcan.protocol.GetNodeInfo.Request())
            assert bytes(info.name).decode() == "org.px4params"
            assert (info.software_version.major, info.software_version.minor) == (0, 1)
            assert len(bytes(info.hardware_version.unique_id)) == 16

            # Enumerate by index until the empty name: every parameter exactly once.
            names: list[str] = []
            values: dict[str, tuple[str, Any]] = {}
            for index in range(200):
                response = peer.getset(index=index)
                name = bytes(response.name).decode()
                if not name:
                    break
                names.append(name)
                values[name] = _field(response.value)
            assert len(names) == len(set(names)) == len(DronecanParams(_store(vehicle_store)))
            assert values["INA238_1_I2C_ADDRESS"] == ("integer_value", 0x45)
            assert values["INA238_0_SHUNT"][0] == "real_value"
            assert values["SYS_AUTOSTART"] == ("integer_value", 0)
            assert "INA238_INST" in names and "INA238_1_BUS_TYPE" in names

            # By name: 0x44, then SAVE; the store file has INA238#1[4] = 0x44.
            response = peer.getset(name=b"INA238_1_I2C_ADDRESS", integer_value=0x44)
            assert _field(response.value) == ("integer_value", 0x44)
            assert _field(response.max_value) == ("integer_value", 127)
            assert _store(vehicle_store).get("INA238#1[4]") == 0x45  # not saved yet
            assert peer.call(OPCODE.Request(opcode=OPCODE.Request().OPCODE_SAVE)).ok
            assert _store(vehicle_store).get("INA238#1[4]") == 0x44

            # Refused: the wrong type and out of range; the unchanged value comes back.
            response = peer.getset(name=b"INA238_1_I2C_ADDRESS", real_value=3.0)
            assert _field(response.value) == ("integer_value", 0x44)
            response = peer.getset(name=b"INA238_1_I2C_ADDRESS", integer_value=200)
            assert _field(response.value) == ("integer_value", 0x44)
            # An unknown name: empty name and value.
            response = peer.getset(name=b"NO_SUCH_PARAM", integer_value=1)
            assert bytes(response.name) == b"" and _field(response.value)[0] == "empty"
            peer.call(OPCODE.Request(opcode=OPCODE.Request().OPCODE_SAVE))
            assert _store(vehicle_store).get("INA238#1[4]") == 0x44

            # NodeStatus arrives once a second.
            deadline = time.monotonic() + 3
            while len(peer.statuses) < 2 and time.monotonic() < deadline:
                peer.node.spin(0.05)
            assert len(peer.statuses) >= 2
            assert peer.statuses[-1].health == 0 and peer.statuses[-1].mode == 0
        finally:
            peer.close()
    output = served.output  # type: ignore[attr-defined]
    assert "INA238_1_I2C_ADDRESS (INA238#1[4]) = 68" in output
    assert (
        "refused: INA238_1_I2C_ADDRESS: real_value refused: the parameter takes integer_value"
        in output
    )
    assert (
        "refused: INA238_1_I2C_ADDRESS: INA238#1: bus.i2c.address: value 200 is out of range"
        in output
    )


def test_erase_takes_effect_at_restart(vehicle_store: Path) -> None:
    with served(vehicle_store) as path:
        peer = Peer(path)
        try:
            peer.getset(name=b"INA238_1_CURRENT", integer_value=150)
            assert peer.call(OPCODE.Request(opcode=OPCODE.Request().OPCODE_ERASE)).ok
            # The running value stays until the restart ...
            assert _field(peer.getset(name=b"INA238_1_CURRENT").value) == ("integer_value", 150)
            restart = dronecan.uavcan.protocol.RestartNode
            assert not peer.call(restart.Request(magic_number=1234)).ok
            assert peer.call(restart.Request(magic_number=restart.Request().MAGIC_NUMBER)).ok
            # ... after which every value is its default (the airframe's 200 A).
            assert _field(peer.getset(name=b"INA238_1_CURRENT").value) == ("integer_value", 200)
        finally:
            peer.close()
    assert _store(vehicle_store).get("INA238#1.current") == 200


def test_bench_health_reaches_node_status(vehicle_store: Path) -> None:
    bench = EXAMPLE.with_name("two_batteries_faults.bench.toml")
    store = _store(vehicle_store)
    store.set("INA238#1.bus.i2c.address", 0x44)  # nothing answers there on this bench
    store.save(vehicle_store)
    with served(vehicle_store, "--bench", str(bench), "--bench-duration", "5") as path:
        peer = Peer(path)
        try:
            deadline = time.monotonic() + 5
            while not peer.statuses and time.monotonic() < deadline:
                peer.node.spin(0.05)
            status = peer.statuses[-1]
            # ERROR: INA238#1 is critical; the other two are warnings (bad transfers).
            assert (status.health, status.vendor_specific_status_code) == (2, 3)
        finally:
            peer.close()


def test_node_survives_garbage_and_foreign_frames(vehicle_store: Path) -> None:
    with served(vehicle_store) as path:
        with open(path, "r+b", buffering=0) as line:
            line.write(b"C\rS8\rO\r")
            line.write(b"T" * 300 + b"\r" + b"T1E0\rTZZZZZZZZ8\r")
            # A GetSet request for node 5 (not us) and a lone middle frame for us.
            line.write(
                format_frame(
                    Frame(can_id(11, source_node=9, dest_node=5, request=True), b"\x00\x00\x01")
                )
            )
            line.write(
                format_frame(
                    Frame(can_id(11, source_node=9, dest_node=1, request=True), b"\x00\x25")
                )
            )
            line.write(b"C\r")
        peer = Peer(path)
        try:
            info = peer.call(dronecan.uavcan.protocol.GetNodeInfo.Request())
            assert bytes(info.name) == b"org.px4params"
        finally:
            peer.close()


def test_a_host_that_stops_reading_loses_answers_not_the_node(vehicle_store: Path) -> None:
    """A host that sends requests and reads nothing (a paused GUI tool): the node crashed on a
    serial port's write timeout, and on a pty blocked in its write, answering nothing and
    ignoring SIGTERM. Now what the host does not take is dropped, as an adapter drops frames;
    the node answers again once the host reads, and stops on SIGTERM."""
    import os
    import re
    import select
    import signal
    import tty

    proc, first = start_serving(vehicle_store)
    try:
        assert first.startswith("slcan: /dev/"), first
        line = os.open(first.split()[1], os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(line)

        def request(tid: int) -> bytes:  # GetNodeInfo (data type 1), one frame, no payload
            ident = can_id(1, source_node=100, dest_node=NODE, request=True)
            return format_frame(Frame(ident, bytes([0xC0 | tid % 32])))

        os.write(line, b"C\rS8\rO\r")
        deadline = time.monotonic() + 20
        sent = 0
        while sent < 400 and time.monotonic() < deadline:  # 400 answers of 8 frames: unread
            try:
                os.write(line, request(sent))
                sent += 1
            except BlockingIOError:
                time.sleep(0.01)
        assert sent == 400
        time.sleep(1.5)
        # The host reads again: what waited, then a new request is answered.
        while select.select([line], [], [], 0.5)[0]:
            os.read(line, 65536)
        os.write(line, request(7))
        answer = b""  # the request's "Z" (sent), then the answer's frames
        until = time.monotonic() + 5
        while b"\rT" not in answer and time.monotonic() < until:
            if select.select([line], [], [], 0.5)[0]:
                answer += os.read(line, 65536)
        assert answer.startswith(b"Z\rT"), answer
        os.close(line)
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=5)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert "the host is not reading: what the node sends is dropped until it does" in out
    assert re.search(r"the host reads again: \d+ writes to it were dropped", out), out
    assert re.search(r", \d+ writes to a host that did not read dropped\n", out), out
    assert "Traceback" not in out


# -- the client, against a pydronecan node that serves parameters -----------------------------


class PydronecanParamNode:
    """A pydronecan node (ID 42) with three parameters, answering GetSet and ExecuteOpcode."""

    def __init__(self, path: str) -> None:
        value = dronecan.uavcan.protocol.param.Value
        self.params: dict[str, Any] = {
            "GPS_RATE_HZ": value(integer_value=5),
            "GPS_SBAS": value(boolean_value=1),
            "GPS_YAW_OFFSET": value(real_value=0.5),
        }
        self.saved = 0
        self.node = dronecan.make_node(path, node_id=42, bitrate=1_000_000)
        self.node.add_handler(GETSET, self._getset)
        self.node.add_handler(OPCODE, self._opcode)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.node.spin(0.02)

    def _getset(self, event: Any) -> Any:
        request = event.request
        names = sorted(self.params)
        name = bytes(request.name).decode() or (
            names[request.index] if request.index < len(names) else ""
        )
        if name not in self.params:
            return GETSET.Response()
        kind, _ = _field(request.value)
        in_range = kind != "integer_value" or 1 <= request.value.integer_value <= 20
        if kind != "empty" and kind == _field(self.params[name])[0] and in_range:
            self.params[name] = request.value  # GPS_RATE_HZ takes 1..20
        return GETSET.Response(name=name.encode(), value=self.params[name])

    def _opcode(self, event: Any) -> Any:
        self.saved += 1
        return OPCODE.Response(ok=True)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self.node.close()


@pytest.fixture
def remote() -> Any:
    bus = VirtualBus(2)
    node = PydronecanParamNode(bus.paths[1])
    try:
        yield bus.paths[0], node
    finally:
        node.close()
        bus.close()


def test_client_lists_gets_sets_and_saves_a_pydronecan_node(remote: Any) -> None:
    path, node = remote
    where = ["--slcan", path, "--node", "42"]
    listed = _run("dronecan", "param", "list", *where).stdout.splitlines()
    assert listed == [
        "GPS_RATE_HZ = 5",
        "GPS_SBAS = true",
        "GPS_YAW_OFFSET = 0.5",
        "3 parameters on node 42",
    ]
    assert (
        _run("dronecan", "param", "set", *where, "GPS_RATE_HZ", "10").stdout == "GPS_RATE_HZ = 10\n"
    )
    assert node.params["GPS_RATE_HZ"].integer_value == 10
    assert (
        _run("dronecan", "param", "set", *where, "GPS_SBAS", "false").stdout == "GPS_SBAS = false\n"
    )
    assert (
        _run("dronecan", "param", "get", *where, "GPS_YAW_OFFSET").stdout
        == "GPS_YAW_OFFSET = 0.5\n"
    )
    _run("dronecan", "param", "save", *where)
    assert node.saved == 1

    refused = _run("dronecan", "param", "set", *where, "GPS_RATE_HZ", "50", check=False)
    assert (refused.returncode, refused.stdout) == (1, "")
    assert refused.stderr == "px4params: error: node 42 refused GPS_RATE_HZ = 50: it kept 10\n"
    wrong = _run("dronecan", "param", "set", *where, "GPS_RATE_HZ", "fast", check=False)
    assert wrong.stderr == "px4params: error: GPS_RATE_HZ: 'fast' is not an integer (int64)\n"
    missing = _run("dronecan", "param", "get", *where, "NOPE", check=False)
    assert missing.stderr == "px4params: error: node 42 has no parameter NOPE\n"


def test_client_reports_a_silent_node_and_a_missing_device(remote: Any, tmp_path: Path) -> None:
    path, _ = remote
    silent = _run(
        "dronecan",
        "param",
        "get",
        "--slcan",
        path,
        "--node",
        "43",
        "--timeout",
        "0.2",
        "X",
        check=False,
    )
    assert silent.returncode == 1
    assert silent.stderr == (
        "px4params: error: node 43 did not answer GetSet (3 tries, 0.2 s each): is it on the "
        "bus, with that node ID?\n"
    )
    absent = _run(
        "dronecan", "param", "list", "--slcan", str(tmp_path / "nope"), "--node", "1", check=False
    )
    assert absent.returncode == 1 and "Traceback" not in absent.stderr
    assert absent.stderr.startswith(
        f"px4params: error: cannot open serial device {tmp_path / 'nope'}: "
    )
    usage = _run("dronecan", "param", "list", "--slcan", path, "--node", "0", check=False)
    assert usage.returncode == 2
    assert "'0' is not a DroneCAN node ID (expected 1..127)" in usage.stderr


def test_client_against_our_own_node(vehicle_store: Path) -> None:
    with served(vehicle_store) as path:
        where = ["--slcan", path, "--node", "1"]
        listed = _run("dronecan", "param", "list", *where).stdout.splitlines()
        assert "INA238_1_I2C_ADDRESS = 69  (default 69, 0 .. 127)" in listed
        out = _run("dronecan", "param", "set", *where, "INA238_1_SHUNT", "0.0005").stdout
        assert out.startswith("INA238_1_SHUNT = 0.0005002")  # float16, rounded by the store
        bad = _run("dronecan", "param", "set", *where, "INA238_1_I2C_ADDRESS", "300", check=False)
        assert (
            bad.stderr
            == "px4params: error: node 1 refused INA238_1_I2C_ADDRESS = 300: it kept 69\n"
        )
        _run("dronecan", "param", "save", *where)
    assert _store(vehicle_store).get("INA238#1.shunt") == pytest.approx(0.0005, rel=1e-3)


def test_values_are_parsed_by_the_parameters_kind() -> None:
    assert parse_value("0x44", {"integer_value": 1}) == {"integer_value": 0x44}
    assert parse_value("on", {"boolean_value": 0}) == {"boolean_value": 1}
    assert parse_value("1e-3", {"real_value": 0.0}) == {"real_value": 0.001}
    with pytest.raises(DronecanError, match=r"^'maybe' is not true or false$"):
        parse_value("maybe", {"boolean_value": 0})
    with pytest.raises(DronecanError, match=r"is not an integer \(int64\)"):
        parse_value(str(1 << 63), {"integer_value": 0})
    assert shown({"empty": {}}) == "(empty)" and shown({"real_value": 0.1}) == "0.1"


def test_dronecan_serve_refuses_a_missing_device(tmp_path: Path) -> None:
    result = _run(
        "dronecan",
        "serve",
        "--slcan",
        str(tmp_path / "ttyNONE"),
        "--store",
        str(tmp_path / "s"),
        check=False,
    )
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert result.stderr.startswith(
        f"px4params: error: cannot open serial device {tmp_path / 'ttyNONE'}"
    )


def test_dronecan_help_lists_the_verbs() -> None:
    out = _run("dronecan", "--help").stdout
    assert "serve" in out and "param" in out


def test_a_failing_serial_line_is_one_error() -> None:
    from px4params.links.slcan import read_port

    class Unplugged:
        def fileno(self) -> int:
            return 0

        def read(self, size: int) -> bytes:
            raise OSError(5, "Input/output error")

        def write(self, data: bytes) -> int:
            return len(data)

    with pytest.raises(
        SlcanError, match=r"^the serial line failed: \[Errno 5\] Input/output error$"
    ):
        read_port(Unplugged())
