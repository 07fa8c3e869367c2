"""The DroneCAN node that serves the store (``px4params.links.dronecan_node``), in-process: the
requests are pydronecan's own transfers (``dronecan.transport.Transfer.to_frames``), fed to the
node frame by frame; its answers are read back from the SLCAN lines it writes (the Lawicel
``T`` format, parsed here by hand) and decoded by pydronecan (``Transfer.from_frames``, which
checks the tail bytes, the toggle and the multi-frame CRC). The rules: the DroneCAN
specification (uavcan.protocol.GetNodeInfo, NodeStatus, param.GetSet, param.ExecuteOpcode,
RestartNode) and docs/dronecan.md. ``tests/test_dronecan.py`` runs the same node as
``px4params dronecan serve`` behind a pty with pydronecan's SLCAN driver."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from dronecan import transport
from px4params.links.can_transfer import Frame
from px4params.links.dronecan_node import DronecanParamNode
from px4params.store.classic import BUNDLED_CLASSIC

GETSET = dronecan.uavcan.protocol.param.GetSet
OPCODE = dronecan.uavcan.protocol.param.ExecuteOpcode
RESTART = dronecan.uavcan.protocol.RestartNode
NODE_INFO = dronecan.uavcan.protocol.GetNodeInfo
NODE_STATUS = dronecan.uavcan.protocol.NodeStatus
VALUE = dronecan.uavcan.protocol.param.Value
PEER = 100  # the asking node's ID
ADDRESS = "INA238_1_I2C_ADDRESS"


class Line:
    """The serial line: what the node writes is kept; what the host sends (:meth:`send`)
    waits in a pipe, whose descriptor ``select`` watches. Most tests hand the node its frames
    directly (:meth:`DronecanParamNode.on_frame`)."""

    def __init__(self) -> None:
        self._read, self._write = os.pipe()
        self.written = bytearray()

    def fileno(self) -> int:
        return self._read

    def read(self, size: int) -> bytes:
        return os.read(self._read, size)

    def send(self, data: bytes) -> None:
        os.write(self._write, data)

    def write(self, data: bytes) -> int:
        self.written += data
        return len(data)

    def frames(self) -> list[transport.Frame]:
        """The frames written so far (and forgets them): ``T`` + 8 hex digits of identifier +
        the length digit + the data in hex (+ 4 hex digits of time stamp, when enabled)."""
        out = []
        for line in bytes(self.written).split(b"\r"):
            if line.startswith(b"T"):
                size = int(line[9:10])
                data = bytes.fromhex(line[10 : 10 + 2 * size].decode())
                out.append(transport.Frame(int(line[1:9], 16), data))
        self.written.clear()
        return out

    def close(self) -> None:
        os.close(self._read)
        os.close(self._write)


def _load(path: Path) -> px4params.Store:
    return px4params.Store.load(path, classic=BUNDLED_CLASSIC)


class Bench:
    """A node (ID ``node_id``) over ``store`` with its line open (``S8``, ``O``)."""

    def __init__(self, store: px4params.Store, schema: px4params.Schema, **kwargs: Any) -> None:
        self.line = Line()
        self.logged: list[str] = []
        self.node = DronecanParamNode(
            store, self.line, schema=schema, log=self.logged.append, **kwargs
        )
        replies, _ = self.node.adapter.feed(b"S8\rO\r")
        assert replies == b"\r\r"
        self._tid = 0

    def call(
        self,
        request: Any,
        *,
        dest: int | None = None,
        priority: int = 30,
        tid: int | None = None,
    ) -> Any:
        """Sends ``request`` from node 100; the decoded response, or None when none came."""
        if tid is None:
            tid, self._tid = self._tid, (self._tid + 1) % 32
        sent = transport.Transfer(
            transfer_id=tid,
            source_node_id=PEER,
            dest_node_id=self.node.node_id if dest is None else dest,
            payload=request,
            transfer_priority=priority,
            request_not_response=True,
            service_not_message=True,
        )
        for frame in sent.to_frames():
            self.node.on_frame(Frame(frame.message_id, bytes(frame.bytes)))
        frames = self.line.frames()
        if not frames:
            return None
        answer = transport.Transfer()
        answer.from_frames(frames)
        assert answer.is_response_to(sent), "not the response to the request"
        assert answer.transfer_priority == priority
        return answer.payload

    def getset(self, name: str = "", index: int = 0, **value: Any) -> Any:
        request = GETSET.Request(index=index, name=name.encode())
        if value:
            request.value = VALUE(**value)
        return self.call(request)

    def opcode(self, opcode: int) -> Any:
        return self.call(OPCODE.Request(opcode=opcode))

    def close(self) -> None:
        self.line.close()


@pytest.fixture
def bench(store_file: Path, schema: px4params.Schema) -> Iterator[Bench]:
    made = Bench(_load(store_file), schema, save_path=str(store_file))
    yield made
    made.close()


def _field(value: Any) -> tuple[str, Any]:
    kind = dronecan.get_active_union_field(value)
    return kind, getattr(value, kind) if kind != "empty" else None


# -- node identity and status ------------------------------------------------------------------


@pytest.mark.parametrize("node_id", [0, 128, -1])
def test_a_node_id_outside_1_to_127_is_refused(
    node_id: int, schema: px4params.Schema, store_file: Path
) -> None:
    """DroneCAN node IDs are 1..127 (0 is anonymous)."""
    with pytest.raises(
        ValueError, match=rf"^node ID {node_id} is out of range \(expected 1\.\.127\)$"
    ):
        DronecanParamNode(_load(store_file), Line(), schema=schema, node_id=node_id)


def test_the_node_answers_under_its_own_id_only(store_file: Path, schema: px4params.Schema) -> None:
    made = Bench(_load(store_file), schema, node_id=127)
    try:
        assert made.call(NODE_INFO.Request(), dest=1) is None
        info = made.call(NODE_INFO.Request())
        assert bytes(info.name) == b"org.px4params"
    finally:
        made.close()


def test_node_info_names_the_node_and_keeps_its_unique_id(
    bench: Bench, store_file: Path, schema: px4params.Schema
) -> None:
    info = bench.call(NODE_INFO.Request())
    assert bytes(info.name) == b"org.px4params"
    version = px4params.__version__.split(".")
    assert (info.software_version.major, info.software_version.minor) == (
        int(version[0]),
        int(version[1]),
    )
    assert info.software_version.optional_field_flags == 0
    assert (info.hardware_version.major, info.hardware_version.minor) == (0, 0)
    unique = bytes(info.hardware_version.unique_id)
    assert len(unique) == 16 and unique != bytes(16)
    assert info.status.health == 0 and info.status.mode == 0
    # the same store file: the same ID, after a restart of the program too
    again = Bench(_load(store_file), schema, save_path=str(store_file))
    try:
        assert bytes(again.call(NODE_INFO.Request()).hardware_version.unique_id) == unique
    finally:
        again.close()


@pytest.mark.parametrize(
    "health, bad, expected",
    [
        (("nominal", 0), 0, 0),  # OK
        (("warning", 2), 2, 1),  # WARNING
        (("critical", 3), 3, 2),  # ERROR
        (("critical", 70_000), 0xFFFF, 2),  # the 16-bit vendor code saturates
        (("unknown", 1), 1, 1),
    ],
)
def test_node_status_carries_the_devices_health(
    health: tuple[str, int], bad: int, expected: int, store_file: Path, schema: px4params.Schema
) -> None:
    made = Bench(_load(store_file), schema, health=lambda: health)
    try:
        made.node._send_status()
        (frame,) = made.line.frames()
        status = transport.Transfer()
        status.from_frames([frame])
        assert not status.service_not_message and status.data_type_id == 341
        assert status.source_node_id == made.node.node_id
        message = status.payload
        assert (message.health, message.vendor_specific_status_code) == (expected, bad)
        assert (message.mode, message.sub_mode, message.uptime_sec) == (0, 0, 0)
    finally:
        made.close()


def test_a_failing_health_source_reports_a_warning(
    store_file: Path, schema: px4params.Schema
) -> None:
    def broken() -> tuple[str, int]:
        raise RuntimeError("no log")

    made = Bench(_load(store_file), schema, health=broken)
    try:
        status = made.node.status()
        assert (status["health"], status["vendor_specific_status_code"]) == (1, 0)
        assert made.logged == ["error computing health: RuntimeError: no log"]
    finally:
        made.close()


def test_node_status_transfer_ids_count_modulo_32(bench: Bench) -> None:
    """A message's transfer ID is 5 bits, one more per transfer (wrapping to 0)."""
    ids = []
    for _ in range(34):
        bench.node._send_status()
        (frame,) = bench.line.frames()
        ids.append(frame.bytes[-1] & 0x1F)
    assert ids == [*range(32), 0, 1]


def test_no_node_status_while_the_channel_is_closed(bench: Bench) -> None:
    replies, _ = bench.node.adapter.feed(b"C\r")
    assert replies == b"\r"
    bench.node._send_status()
    bench.node.step(0)
    assert bench.line.frames() == []


def test_node_status_once_per_interval(bench: Bench) -> None:
    bench.node.status_interval = 3600
    bench.node.step(0)  # the first at once
    bench.node.step(0)  # the next not before an hour
    assert len(bench.line.frames()) == 1


# -- GetSet ------------------------------------------------------------------------------------


def test_getset_by_index_lists_every_parameter_then_the_empty_name(bench: Bench) -> None:
    names = []
    for index in range(len(bench.node.params) + 1):
        answer = bench.getset(index=index)
        names.append(bytes(answer.name).decode())
    assert names[-1] == "" and "" not in names[:-1]
    assert len(set(names[:-1])) == len(bench.node.params)
    assert ADDRESS in names and "INA238_INST" in names
    # the name wins over the index
    assert bytes(bench.getset(ADDRESS, index=0).name).decode() == ADDRESS
    assert names[0] != ADDRESS


def test_getset_reads_a_value_with_its_bounds(bench: Bench, store_file: Path) -> None:
    answer = bench.getset(ADDRESS)
    assert _field(answer.value) == ("integer_value", 0x45)
    assert _field(answer.max_value) == ("integer_value", 127)
    assert _field(answer.min_value)[0] == "integer_value"
    assert _field(answer.default_value)[0] == "integer_value"
    assert bench.logged == [] and bench.node.stats["accepted"] == 0


def test_getset_writes_the_running_value_not_the_file(bench: Bench, store_file: Path) -> None:
    answer = bench.getset(ADDRESS, integer_value=0x44)
    assert _field(answer.value) == ("integer_value", 0x44)
    assert bench.node.store.get("INA238#1.bus.i2c.address") == 0x44
    assert _load(store_file).get("INA238#1.bus.i2c.address") == 0x45  # until SAVE
    assert bench.logged == [f"{ADDRESS} (INA238#1[4]) = 68"]
    assert bench.node.stats["accepted"] == 1 and bench.node.stats["requests"] == 1


def test_getset_by_index_writes_too(bench: Bench) -> None:
    names = [bytes(bench.getset(index=i).name).decode() for i in range(len(bench.node.params))]
    index = names.index(ADDRESS)
    answer = bench.getset(index=index, integer_value=0x46)
    assert bytes(answer.name).decode() == ADDRESS
    assert _field(answer.value) == ("integer_value", 0x46)


@pytest.mark.parametrize(
    "value, why",
    [
        ({"integer_value": 200}, "INA238#1: bus.i2c.address: value 200 is out of range"),
        ({"real_value": 3.0}, "real_value refused: the parameter takes integer_value"),
    ],
)
def test_a_refused_write_answers_the_unchanged_value(
    bench: Bench, value: dict[str, Any], why: str
) -> None:
    answer = bench.getset(ADDRESS, **value)
    assert _field(answer.value) == ("integer_value", 0x45)
    assert bench.node.store.get("INA238#1.bus.i2c.address") == 0x45
    assert len(bench.logged) == 1 and bench.logged[0].startswith(f"refused: {ADDRESS}: ")
    assert why in bench.logged[0]
    assert bench.node.stats["refused"] == 1 and bench.node.stats["accepted"] == 0


def test_an_unknown_parameter_is_the_empty_answer(bench: Bench) -> None:
    """GetSet.Response: "empty name (and/or empty value) in the response indicates that there
    is no such parameter"."""
    for answer in (bench.getset("NO_SUCH_PARAM", integer_value=1), bench.getset(index=60_000)):
        assert bytes(answer.name) == b""
        for field in ("value", "default_value", "max_value", "min_value"):
            assert _field(getattr(answer, field))[0] == "empty", field
    # the write to no parameter is a refusal that names it
    assert bench.node.stats["refused"] == 1 and bench.node.stats["accepted"] == 0
    assert len(bench.logged) == 1 and bench.logged[0].startswith("refused: ")
    assert "NO_SUCH_PARAM" in bench.logged[0]


# -- transfers that are not ours ---------------------------------------------------------------


def test_other_services_messages_and_broken_transfers_are_ignored(bench: Bench) -> None:
    node = bench.node
    # a service this node does not offer (uavcan.protocol.file.GetInfo, 45)
    assert (
        bench.call(
            dronecan.uavcan.protocol.file.GetInfo.Request(
                path=dronecan.uavcan.protocol.file.Path(path=b"x")
            )
        )
        is None
    )
    assert node.stats["ignored"] == 1
    # a message (NodeStatus from another node) is no request
    status = transport.Transfer(
        source_node_id=PEER, payload=NODE_STATUS(), service_not_message=False
    )
    for frame in status.to_frames():
        node.on_frame(Frame(frame.message_id, bytes(frame.bytes)))
    # a multi-frame GetSet whose CRC is wrong
    request = transport.Transfer(
        transfer_id=3,
        source_node_id=PEER,
        dest_node_id=node.node_id,
        payload=GETSET.Request(name=ADDRESS.encode(), value=VALUE(integer_value=0x44)),
        request_not_response=True,
        service_not_message=True,
    )
    frames = request.to_frames()
    assert len(frames) > 1
    first = bytearray(frames[0].bytes)
    first[0] ^= 0xFF
    for n, frame in enumerate(frames):
        node.on_frame(Frame(frame.message_id, bytes(first if n == 0 else frame.bytes)))
    assert bench.line.frames() == []
    assert node.stats["ignored"] == 2 and node.stats["requests"] == 0
    assert node.store.get("INA238#1.bus.i2c.address") == 0x45
    # the node keeps answering
    assert bytes(bench.call(NODE_INFO.Request()).name) == b"org.px4params"


def test_the_counters_count_every_request_and_every_ignored_transfer(bench: Bench) -> None:
    """The summary ``dronecan serve`` prints adds up: each answered request and each transfer
    dropped (a service not offered, a bad CRC) counts once, whichever came first."""
    node = bench.node
    file_info = dronecan.uavcan.protocol.file.GetInfo.Request(
        path=dronecan.uavcan.protocol.file.Path(path=b"x")
    )
    for _ in range(3):
        assert bench.call(file_info) is None
    assert node.stats["ignored"] == 3 and node.stats["requests"] == 0
    for _ in range(3):
        assert bytes(bench.call(NODE_INFO.Request()).name) == b"org.px4params"
    assert node.stats["requests"] == 3 and node.stats["ignored"] == 3


# -- ExecuteOpcode -----------------------------------------------------------------------------


def test_save_writes_the_running_values_to_the_file(bench: Bench, store_file: Path) -> None:
    bench.getset(ADDRESS, integer_value=0x44)
    answer = bench.opcode(OPCODE.Request().OPCODE_SAVE)
    assert (answer.ok, answer.argument) == (True, 0)
    assert _load(store_file).get("INA238#1.bus.i2c.address") == 0x44
    assert bench.logged[-1] == f"saved: {store_file}"
    assert bench.node.stats["saves"] == 1


def test_erase_writes_the_defaults_and_keeps_the_running_values(
    bench: Bench, store_file: Path
) -> None:
    answer = bench.opcode(OPCODE.Request().OPCODE_ERASE)
    assert (answer.ok, answer.argument) == (True, 0)
    saved = _load(store_file)
    assert saved.instances("INA238") == ["INA238#1"]  # instances stay
    assert not saved.changed("INA238#1")
    # the running value until the restart
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x45)
    assert bench.logged[-1] == f"erased: {store_file}"


def test_an_unknown_opcode_is_refused(bench: Bench, store_file: Path) -> None:
    before = store_file.read_bytes()
    answer = bench.opcode(7)
    assert (answer.ok, answer.argument) == (False, 0)
    assert bench.logged == ["refused: ExecuteOpcode 7 (SAVE is 0, ERASE is 1)"]
    assert store_file.read_bytes() == before and bench.node.stats["saves"] == 0


@pytest.mark.parametrize("opcode, what", [(0, "save"), (1, "erase")])
def test_save_and_erase_need_a_store_file(
    opcode: int, what: str, store_file: Path, schema: px4params.Schema
) -> None:
    made = Bench(_load(store_file), schema)
    try:
        assert made.opcode(opcode).ok is False
        assert made.logged == [f"refused: {what}: no store file (serving a store in memory)"]
    finally:
        made.close()


def test_a_save_that_cannot_write_is_refused(bench: Bench, store_file: Path) -> None:
    bench.getset(ADDRESS, integer_value=0x44)
    store_file.unlink()
    store_file.mkdir()  # the store file's name is a directory now
    assert bench.opcode(OPCODE.Request().OPCODE_SAVE).ok is False
    assert bench.logged[-1].startswith("refused: save: ")
    assert str(store_file) in bench.logged[-1]
    assert bench.node.stats["saves"] == 0


def test_a_save_over_another_writer_s_change_of_the_same_leaf_is_refused(
    bench: Bench, store_file: Path
) -> None:
    bench.getset(ADDRESS, integer_value=0x44)
    other = _load(store_file)
    other.set("INA238#1.bus.i2c.address", 0x47)
    other.save(store_file)
    answer = bench.opcode(OPCODE.Request().OPCODE_SAVE)
    assert answer.ok is False
    assert _load(store_file).get("INA238#1.bus.i2c.address") == 0x47
    # refused whole; the node shows the file's value, so that the client may set it again
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x47)
    assert bench.logged[-1].startswith("refused: save: ")
    assert bench.logged[-1].endswith("; the node's values are the file's again")
    assert bench.node.stats["saves"] == 0


def test_another_writer_s_save_is_read_with_the_node_s_changes_on_top(
    bench: Bench, store_file: Path
) -> None:
    bench.getset("INA238_1_CURRENT", integer_value=150)
    other = _load(store_file)
    other.set("INA238#1.bus.i2c.address", 0x47)
    other.save(store_file)
    bench.node.step(0)
    bench.line.frames()  # the NodeStatus the turn sent
    assert bench.logged[-1] == "store changed by another writer: values read again"
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x47)
    assert _field(bench.getset("INA238_1_CURRENT").value) == ("integer_value", 150)


# -- RestartNode -------------------------------------------------------------------------------


def test_restart_needs_the_magic_number(bench: Bench) -> None:
    bench.getset(ADDRESS, integer_value=0x44)
    answer = bench.call(RESTART.Request(magic_number=0x1234))
    assert answer.ok is False
    assert bench.logged[-1] == "refused: RestartNode magic number 0x1234"
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x44)


def test_restart_reads_the_store_file_again(bench: Bench, store_file: Path) -> None:
    """Unsaved values are lost at a restart; after ERASE, the defaults take effect."""
    bench.getset(ADDRESS, integer_value=0x44)
    assert bench.call(RESTART.Request(magic_number=RESTART.Request().MAGIC_NUMBER)).ok
    assert bench.logged[-1] == "restarted: values read again from the store file"
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x45)
    assert bench.opcode(OPCODE.Request().OPCODE_ERASE).ok
    assert bench.call(RESTART.Request(magic_number=RESTART.Request().MAGIC_NUMBER)).ok
    default = _load(store_file).get("INA238#1.bus.i2c.address")
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", default)


def test_restart_in_memory_is_a_new_store(store_file: Path, schema: px4params.Schema) -> None:
    """Without a store file there is nothing to read again: a node without storage starts
    as a new store (Store.reset_to_initial: no instance, every value its default)."""
    made = Bench(_load(store_file), schema)
    try:
        made.getset(ADDRESS, integer_value=0x44)
        assert made.call(RESTART.Request(magic_number=RESTART.Request().MAGIC_NUMBER)).ok
        assert made.logged[-1] == "restarted: values read again from the store file"
        assert bytes(made.getset(ADDRESS).name) == b""
        assert _field(made.getset("INA238_INST").value) == ("integer_value", 0)
    finally:
        made.close()


def test_a_restart_over_an_unreadable_file_keeps_the_values(bench: Bench, store_file: Path) -> None:
    bench.getset(ADDRESS, integer_value=0x44)
    store_file.write_bytes(b"not a store")
    assert bench.call(RESTART.Request(magic_number=RESTART.Request().MAGIC_NUMBER)).ok
    assert bench.logged[-1].startswith("restart: the store file cannot be read, values kept: ")
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x44)


# -- defaults ----------------------------------------------------------------------------------


def test_the_defaults_follow_px4_and_the_specification(
    store_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Node ID 1 (PX4's UAVCAN_NODE_ID default, docs/dronecan.md); NodeStatus at least once
    per MAX_BROADCASTING_PERIOD_MS (NodeStatus.uavcan); other writers' saves read "within a
    second". The protocol's own types are the bundled DroneCAN ones, whatever
    PX4PARAMS_DSDL_PATH holds (a broken type there does not stop the node)."""
    broken = tmp_path / "types" / "px"
    broken.mkdir(parents=True)
    (broken / "Broken.1.0.dsdl").write_text("uint8 x\nthis is not DSDL\n@sealed\n")
    store = _load(store_file)
    monkeypatch.setenv("PX4PARAMS_DSDL_PATH", str(broken))
    line = Line()
    try:
        node = DronecanParamNode(store, line)
        assert node.node_id == 1
        assert node.status_interval <= NODE_STATUS().MAX_BROADCASTING_PERIOD_MS / 1000
        assert node.poll_interval < 1.0
        node.adapter.feed(b"S8\rO\r")
        request = transport.Transfer(
            source_node_id=PEER,
            dest_node_id=1,
            payload=NODE_INFO.Request(),
            request_not_response=True,
            service_not_message=True,
        )
        for frame in request.to_frames():
            node.on_frame(Frame(frame.message_id, bytes(frame.bytes)))
        answer = transport.Transfer()
        answer.from_frames(line.frames())
        assert bytes(answer.payload.name) == b"org.px4params"
    finally:
        line.close()


def test_a_node_given_a_session_saves_to_its_file(
    store_file: Path, schema: px4params.Schema
) -> None:
    """`dronecan serve` hands the node its Session (the store's one write path): SAVE writes
    that file, and the node's unique ID is the one it has when given the path."""
    from px4params.store.session import Session

    store = _load(store_file)
    made = Bench(store, schema, session=Session(store, str(store_file)))
    by_path = Bench(_load(store_file), schema, save_path=str(store_file))
    try:
        made.getset(ADDRESS, integer_value=0x44)
        assert made.opcode(OPCODE.Request().OPCODE_SAVE).ok
        assert made.logged[-1] == f"saved: {store_file}"
        assert _load(store_file).get("INA238#1.bus.i2c.address") == 0x44
        assert made.node.unique_id == by_path.node.unique_id
    finally:
        made.close()
        by_path.close()


def test_a_node_without_a_store_file_keeps_turning(
    store_file: Path, schema: px4params.Schema
) -> None:
    """Serving a store in memory: there is no file to look at, and each turn sends its
    NodeStatus and reads the line as with one."""
    made = Bench(_load(store_file), schema)
    try:
        made.node.status_interval = 0.0  # due at every turn
        for _ in range(3):
            made.node.step(0)
        assert len(made.line.frames()) == 3 and made.logged == []
    finally:
        made.close()


def test_a_turn_answers_what_the_host_wrote_on_the_line(bench: Bench) -> None:
    """The host's SLCAN lines (Lawicel: ``V`` asks the version, ``T`` + identifier + length +
    data sends a frame) are read by a turn of the loop and answered on the line."""
    node = bench.node
    node.status_interval = 3600
    node.step(0)  # the first NodeStatus
    bench.line.frames()
    bench.line.send(b"V\r")
    node.step(0)
    assert bytes(bench.line.written) == b"V1013\r"
    bench.line.written.clear()
    request = transport.Transfer(
        transfer_id=5,
        source_node_id=PEER,
        dest_node_id=node.node_id,
        payload=NODE_INFO.Request(),
        request_not_response=True,
        service_not_message=True,
    )
    (frame,) = request.to_frames()
    data = bytes(frame.bytes)
    bench.line.send(b"T%08X%d%s\r" % (frame.message_id, len(data), data.hex().upper().encode()))
    node.step(0)
    answer = transport.Transfer()
    answer.from_frames(bench.line.frames())
    assert answer.is_response_to(request) and bytes(answer.payload.name) == b"org.px4params"


def test_a_turn_with_nothing_to_read_does_not_wait() -> None:
    """step(0) returns at once when nothing is due and nothing waits on the line (generous
    bound: ten turns well under a second each)."""
    import time

    line = Line()
    try:
        store = px4params.Store(px4params.load_schema(use_env=False), classic=BUNDLED_CLASSIC)
        node = DronecanParamNode(store, line)
        node.status_interval = 3600
        started = time.monotonic()
        for _ in range(10):
            node.step(0)
        assert time.monotonic() - started < 5.0
    finally:
        line.close()


# -- GetSet's edges (issue 40, mutlinks3: the survivors of the dronecan_node target) ------------


def test_the_counters_count_each_accepted_and_each_refused_write(bench: Bench) -> None:
    """The summary of ``dronecan serve`` counts every write: two accepted, then two refused
    (out of range: the address is a 7-bit I2C address), each once."""
    node = bench.node
    for address in (0x44, 0x46):
        assert _field(bench.getset(ADDRESS, integer_value=address).value)[1] == address
    for address in (200, 300):
        assert _field(bench.getset(ADDRESS, integer_value=address).value)[1] == 0x46
    assert (node.stats["accepted"], node.stats["refused"], node.stats["requests"]) == (2, 2, 4)
    assert len(bench.logged) == 4 and bench.logged[2].startswith(f"refused: {ADDRESS}: ")


def test_a_name_that_is_not_ascii_is_no_parameter(bench: Bench) -> None:
    """Parameter names are ASCII (PX4's, and GetSet's uint8 name field as pydronecan fills
    it): a name with a byte above 0x7F names no parameter. It is the empty answer, a write
    to it a refusal naming it, and the node answers the next request."""
    request = GETSET.Request(name=b"INA238\xff_ADDR")
    answer = bench.call(request)
    assert bytes(answer.name) == b"" and _field(answer.value)[0] == "empty"
    request.value = VALUE(integer_value=0x44)
    answer = bench.call(request)
    assert bytes(answer.name) == b"" and _field(answer.value)[0] == "empty"
    assert bench.node.stats["refused"] == 1 and bench.node.stats["accepted"] == 0
    assert len(bench.logged) == 1 and bench.logged[0].startswith("refused: INA238")
    assert "no such parameter" in bench.logged[0]
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x45)


def test_a_write_by_an_index_past_the_end_is_the_empty_answer_alone(bench: Bench) -> None:
    """GetSet: with an empty name the index picks the parameter; an index past the last one
    picks none, so a value sent with it is written nowhere: the answer is the empty one
    ("no such parameter"), no value changed, and there is no name to refuse or log."""
    before = {i: _field(bench.getset(index=i).value) for i in range(len(bench.node.params))}
    bench.node.stats["requests"] = 0
    answer = bench.getset(index=len(bench.node.params), integer_value=0x44)
    assert bytes(answer.name) == b"" and _field(answer.value)[0] == "empty"
    assert bench.logged == []
    assert (bench.node.stats["accepted"], bench.node.stats["refused"]) == (0, 0)
    after = {i: _field(bench.getset(index=i).value) for i in range(len(bench.node.params))}
    assert after == before


def test_erase_after_a_save_writes_the_defaults_over_the_saved_value(
    bench: Bench, store_file: Path
) -> None:
    """ERASE (ExecuteOpcode 1): "the parameters are reset to their defaults" in the node's
    storage. A changed address saved first (0x44; PX4's INA238 default is 0x45) is the
    default in the file after ERASE; the running value stays 0x44 until the restart."""
    bench.getset(ADDRESS, integer_value=0x44)
    assert bench.opcode(OPCODE.Request().OPCODE_SAVE).ok
    assert _load(store_file).get("INA238#1.bus.i2c.address") == 0x44
    assert bench.opcode(OPCODE.Request().OPCODE_ERASE).ok
    saved = _load(store_file)
    assert saved.get("INA238#1.bus.i2c.address") == 0x45 and not saved.changed("INA238#1")
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x44)


def test_a_store_file_another_writer_left_unreadable_is_named_once_and_not_read(
    bench: Bench, store_file: Path
) -> None:
    """A turn that finds the store file changed but unreadable (another writer left it
    truncated) keeps the node's values and says why, once for that version of the file."""
    store_file.write_bytes(store_file.read_bytes()[:10])
    for _ in range(2):
        bench.node._next_poll = 0.0  # the file is due to be looked at now
        bench.node.step(0)
    bench.line.frames()  # the NodeStatus the turns sent
    assert len(bench.logged) == 1
    assert bench.logged[0].startswith(f"store changed by another writer, not read: {store_file}")
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x45)


def test_a_refused_save_whose_file_cannot_be_read_again_keeps_the_values_without_saying_so(
    bench: Bench, store_file: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SAVE over another writer's change of the same leaf is refused; when the file cannot
    be read back either (it broke meanwhile, played here by its reload failing), the node's
    values stay and its refusal does not claim they became the file's."""
    from px4params.errors import StoreFileError

    bench.getset(ADDRESS, integer_value=0x44)
    other = _load(store_file)
    other.set("INA238#1.bus.i2c.address", 0x47)
    other.save(store_file)

    def unreadable() -> None:
        raise StoreFileError("cannot read: Input/output error", store_file)

    monkeypatch.setattr(bench.node.session, "reload", unreadable)
    assert bench.opcode(OPCODE.Request().OPCODE_SAVE).ok is False
    assert bench.logged[-1].startswith("refused: save: ")
    assert bench.logged[-1].endswith("; nothing was saved")
    assert _field(bench.getset(ADDRESS).value) == ("integer_value", 0x44)


def test_each_save_counts_once(bench: Bench, store_file: Path) -> None:
    """The summary of ``dronecan serve`` counts the saves: two SAVEs and an ERASE, three."""
    for opcode in (OPCODE.Request().OPCODE_SAVE, OPCODE.Request().OPCODE_SAVE, 1):
        assert bench.opcode(opcode).ok
    assert bench.node.stats["saves"] == 3


def test_a_restart_starts_the_uptime_again(bench: Bench) -> None:
    """NodeStatus.uptime_sec: other nodes tell that a node restarted by its uptime going
    backwards (the DroneCAN specification). After RestartNode it counts from 0 again."""
    bench.node._started -= 100  # the node has been up for 100 s
    assert bench.call(NODE_INFO.Request()).status.uptime_sec >= 100
    assert bench.call(RESTART.Request(magic_number=RESTART.Request().MAGIC_NUMBER)).ok
    assert bench.call(NODE_INFO.Request()).status.uptime_sec < 100


class StalledLine(Line):
    """A serial line whose host stopped reading: every write times out, as pyserial's does
    (``SerialTimeoutException``, an ``OSError``), until :attr:`reading` is set again;
    :attr:`full` says whether the line selects as not writable meanwhile (its buffer full)."""

    def __init__(self) -> None:
        super().__init__()
        self.reading = False
        self.full = False
        self.writes = 0

    def fileno(self) -> int:
        # A serial line's one descriptor selects writable when its buffer has room: the
        # pipe's writing end stands in, its reading end (never writable) for a full buffer
        # (the node is handed its frames directly here).
        return self._read if self.full else self._write

    def write(self, data: bytes) -> int:
        import serial

        self.writes += 1
        if not self.reading:
            raise serial.SerialTimeoutException("Write timeout")
        return super().write(data)


def test_a_write_timeout_drops_the_answer_and_the_node_goes_on(
    store_file: Path, schema: px4params.Schema
) -> None:
    # `dronecan serve --slcan DEVICE` exited with a traceback when the host stopped reading.
    bench = Bench(_load(store_file), schema)
    line = StalledLine()
    bench.line.close()
    bench.line = bench.node.port = line
    try:
        for _ in range(3):
            assert bench.call(NODE_INFO.Request()) is None  # answered, and dropped
        assert bench.node.stats["dropped"] == 3
        assert bench.logged == [  # said once
            "the host is not reading: what the node sends is dropped until it does (0.5 s waited)"
        ]
        line.reading = True
        assert bytes(bench.call(NODE_INFO.Request()).name) == b"org.px4params"
        assert bench.logged[1:] == ["the host reads again: 3 writes to it were dropped"]
        assert bench.node.stats["dropped"] == 3
        # A second stall is said again; while the line's buffer is full, nothing is written
        # and nothing waits: a backlog of requests each waited 0.5 s.
        line.reading = False
        assert bench.call(NODE_INFO.Request()) is None
        line.full, writes, started = True, line.writes, time.monotonic()
        for _ in range(20):
            assert bench.call(NODE_INFO.Request()) is None
        assert line.writes == writes and time.monotonic() - started < 0.5
        assert bench.logged[2:] == [bench.logged[0]]
        line.reading, line.full = True, False
        bench.node._write(b"\r")  # an SLCAN command's 1-byte reply gets through: read again
        assert bench.logged[3:] == ["the host reads again: 21 writes to it were dropped"]
        assert bench.node.stats["dropped"] == 24
    finally:
        line.close()


def test_a_write_the_line_takes_only_part_of_is_a_drop(
    store_file: Path, schema: px4params.Schema
) -> None:
    # A pty's write gives up after its wait with part of the answer written: what did not go
    # is dropped, and said.
    class HalfLine(Line):
        def write(self, data: bytes) -> int:
            super().write(data[:1])
            return 1

    bench = Bench(_load(store_file), schema)
    bench.line.close()
    bench.line = bench.node.port = HalfLine()
    try:
        bench.node._write(b"T1E0\r")
        assert bench.node.stats["dropped"] == 1
        assert bench.logged == [
            "the host is not reading: what the node sends is dropped until it does (0.5 s waited)"
        ]
    finally:
        bench.line.close()
