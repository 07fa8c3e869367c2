"""The DroneCAN parameter client (``px4params.links.dronecan_client``) in-process: its SLCAN host
writes ``T`` lines to a peer that plays the remote node with pydronecan's own transfers
(``dronecan.transport.Transfer``: reassembly with the CRC and toggle checks, the encoding of the
responses), answering on the spot, so that nothing waits on a thread. The rules: the DroneCAN
specification (uavcan.protocol.param.GetSet: enumeration by index until the empty name, a read
is a GetSet with an empty value, a node that refuses a write answers its unchanged value;
ExecuteOpcode SAVE is opcode 0; service transfer IDs count modulo 32)."""

from __future__ import annotations

import os
import struct
from collections.abc import Iterator
from typing import Any

import dronecan
import pytest
from dronecan import transport
from px4params.errors import DronecanError
from px4params.links.dronecan_client import (
    DEFAULT_LOCAL_NODE,
    DronecanParamClient,
    RemoteParam,
    parse_value,
    shown,
)
from px4params.links.slcan import SlcanHost

GETSET = dronecan.uavcan.protocol.param.GetSet
OPCODE = dronecan.uavcan.protocol.param.ExecuteOpcode
VALUE = dronecan.uavcan.protocol.param.Value
NUMERIC = dronecan.uavcan.protocol.param.NumericValue
NODE = 42


def _field(value: Any) -> tuple[str, Any]:
    kind = dronecan.get_active_union_field(value)
    return kind, getattr(value, kind) if kind != "empty" else None


class RemoteNode:
    """Node 42 behind the line: three parameters (GPS_RATE_HZ takes 1..20; GPS_YAW_OFFSET is
    stored as float16, as some peripherals do), GetSet and ExecuteOpcode answered with
    pydronecan's transfers. ``silent`` requests go unanswered; ``damage`` spoils the next
    responses' CRC; ``answer_as`` answers from another node ID."""

    def __init__(self) -> None:
        self._read, self._write = os.pipe()
        self.params: dict[str, Any] = {
            "GPS_RATE_HZ": VALUE(integer_value=5),
            "GPS_SBAS": VALUE(boolean_value=1),
            "GPS_YAW_OFFSET": VALUE(real_value=0.5),
        }
        self.requests: list[transport.Transfer] = []
        self.silent = 0
        self.damage = 0
        self.save_ok = True
        self.answer_as = NODE
        self._frames: list[transport.Frame] = []

    # the SerialPort the client's SlcanHost uses
    def fileno(self) -> int:
        return self._read

    def read(self, size: int) -> bytes:
        return os.read(self._read, size)

    def write(self, data: bytes) -> int:
        for line in data.split(b"\r"):
            if not line.startswith(b"T"):
                continue
            size = int(line[9:10])
            frame = transport.Frame(
                int(line[1:9], 16), bytes.fromhex(line[10 : 10 + 2 * size].decode())
            )
            self._frames.append(frame)
            if frame.bytes[-1] & 0x40:  # the tail byte's end of transfer
                request = transport.Transfer()
                request.from_frames(self._frames)
                self._frames = []
                self._answer(request)
        return len(data)

    def close(self) -> None:
        os.close(self._read)
        os.close(self._write)

    def _answer(self, request: transport.Transfer) -> None:
        self.requests.append(request)
        if self.silent:
            self.silent -= 1
            return
        if request.dest_node_id != NODE:
            return
        kind = dronecan.get_dronecan_data_type(request.payload).full_name
        if kind == "uavcan.protocol.param.GetSet":
            payload = self._getset(request.payload)
        else:
            payload = OPCODE.Response(ok=self.save_ok and request.payload.opcode == 0)
        response = transport.Transfer(
            transfer_id=request.transfer_id,
            source_node_id=self.answer_as,
            dest_node_id=request.source_node_id,
            payload=payload,
            transfer_priority=request.transfer_priority,
            request_not_response=False,
            service_not_message=True,
        )
        frames = response.to_frames()
        out = b""
        for n, frame in enumerate(frames):
            data = bytearray(frame.bytes)
            if self.damage and len(frames) > 1 and n == 0:
                data[0] ^= 0xFF  # the transfer CRC's first byte
            out += b"T%08X%d%s\r" % (
                frame.message_id,
                len(data),
                bytes(data).hex().upper().encode(),
            )
        if self.damage and len(frames) > 1:
            self.damage -= 1
        os.write(self._write, out)

    def _getset(self, request: Any) -> Any:
        names = sorted(self.params)
        name = bytes(request.name).decode() or (
            names[request.index] if request.index < len(names) else ""
        )
        if name not in self.params:
            return GETSET.Response()
        kind, value = _field(request.value)
        if kind == "integer_value" and name == "GPS_RATE_HZ" and not 1 <= value <= 20:
            kind = "refused"
        if kind == "real_value":  # stored as float16: 0.1 reads back as 0.0999755859375
            value = struct.unpack("<e", struct.pack("<e", value))[0]
            request.value = VALUE(real_value=value)
        if kind != "empty" and kind == _field(self.params[name])[0]:
            self.params[name] = request.value
        return GETSET.Response(
            name=name.encode(),
            value=self.params[name],
            default_value=VALUE(integer_value=5) if name == "GPS_RATE_HZ" else VALUE(),
            min_value=NUMERIC(integer_value=1) if name == "GPS_RATE_HZ" else NUMERIC(),
            max_value=NUMERIC(integer_value=20) if name == "GPS_RATE_HZ" else NUMERIC(),
        )


@pytest.fixture
def remote() -> Iterator[RemoteNode]:
    node = RemoteNode()
    yield node
    node.close()


@pytest.fixture
def client(remote: RemoteNode) -> DronecanParamClient:
    return DronecanParamClient(SlcanHost(remote), NODE, timeout=2.0, retries=2)


def _requests(remote: RemoteNode) -> list[tuple[int, int, int, int]]:
    """(source, destination, transfer ID, priority) of each request the node got."""
    return [
        (t.source_node_id, t.dest_node_id, t.transfer_id, t.transfer_priority)
        for t in remote.requests
    ]


# -- values as text ----------------------------------------------------------------------------


def test_values_are_shown_as_the_cli_prints_them() -> None:
    assert shown({"integer_value": -5}) == "-5"
    assert shown({"real_value": 0.1}) == "0.1"
    assert shown({"real_value": 1 / 3}) == "0.333333333"  # nine significant digits
    assert shown({"real_value": float("inf")}) == "inf"
    assert shown({"real_value": float("nan")}) == "nan"
    assert shown({"boolean_value": 1}) == "true" and shown({"boolean_value": 0}) == "false"
    assert shown({"string_value": list(b"GPS")}) == "'GPS'"
    assert shown({"string_value": list(b"\xffGPS")}) == "'\ufffdGPS'"  # not UTF-8: replaced
    assert shown({"empty": {}}) == "(empty)"


def test_text_is_parsed_as_the_parameter_s_kind() -> None:
    assert parse_value(" 0x10 ", {"integer_value": 0}) == {"integer_value": 16}
    assert parse_value("-9223372036854775808", {"integer_value": 0}) == {
        "integer_value": -(1 << 63)
    }
    assert parse_value("9223372036854775807", {"integer_value": 0}) == {
        "integer_value": (1 << 63) - 1
    }
    assert parse_value("2.5", {"real_value": 0.0}) == {"real_value": 2.5}
    for word, flag in (("1", 1), ("TRUE", 1), ("on", 1), ("0", 0), ("False", 0), ("OFF", 0)):
        assert parse_value(word, {"boolean_value": 0}) == {"boolean_value": flag}, word
    assert parse_value(" text ", {"string_value": []}) == {"string_value": b"text"}


@pytest.mark.parametrize(
    ("text", "like", "why"),
    [
        (
            "9223372036854775808",
            {"integer_value": 0},
            "'9223372036854775808' is not an integer (int64)",
        ),
        (
            "-9223372036854775809",
            {"integer_value": 0},
            "'-9223372036854775809' is not an integer (int64)",
        ),
        ("1.5", {"integer_value": 0}, "'1.5' is not an integer (int64)"),
        ("fast", {"real_value": 0.0}, "'fast' is not a number"),
        ("yes", {"boolean_value": 0}, "'yes' is not true or false"),
        ("1", {"empty": {}}, "'1' is not nothing: the parameter has no value"),
    ],
)
def test_text_that_is_not_of_the_kind_is_named(text: str, like: dict[str, Any], why: str) -> None:
    with pytest.raises(DronecanError) as refused:
        parse_value(text, like)
    assert str(refused.value) == why


# -- node IDs ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("node", "local", "why"),
    [
        (0, 127, "node ID 0 is out of range (expected 1..127)"),
        (128, 127, "node ID 128 is out of range (expected 1..127)"),
        (42, 0, "local node ID 0 is out of range (expected 1..127)"),
        (42, 128, "local node ID 128 is out of range (expected 1..127)"),
        (42, 42, "node ID 42 is also this program's node ID (--local-node)"),
    ],
)
def test_node_ids_are_checked(remote: RemoteNode, node: int, local: int, why: str) -> None:
    with pytest.raises(DronecanError) as refused:
        DronecanParamClient(SlcanHost(remote), node, local_node=local)
    assert str(refused.value) == why


def test_the_client_is_node_127_by_default_and_node_ids_1_and_127_are_valid(
    remote: RemoteNode,
) -> None:
    assert DEFAULT_LOCAL_NODE == 127  # the DroneCAN GUI tool's
    client = DronecanParamClient(SlcanHost(remote), 1)
    assert client.local_node == 127 and (client.timeout, client.retries) == (1.0, 2)
    DronecanParamClient(SlcanHost(remote), 127, local_node=1)


# -- GetSet ------------------------------------------------------------------------------------


def test_a_list_goes_by_index_until_the_empty_name(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    seen: list[int] = []
    listed = list(client.list(progress=seen.append))
    assert [(p.index, p.name) for p in listed] == [
        (0, "GPS_RATE_HZ"),
        (1, "GPS_SBAS"),
        (2, "GPS_YAW_OFFSET"),
    ]
    assert seen == [1, 2, 3]
    assert listed[0] == RemoteParam(
        0,
        "GPS_RATE_HZ",
        {"integer_value": 5},
        {"integer_value": 5},
        {"integer_value": 1},
        {"integer_value": 20},
    )
    assert listed[1].value == {"boolean_value": 1} and listed[2].value == {"real_value": 0.5}
    # four GetSets by index, each a read (an empty value) from node 127 to 42
    assert [t.payload.index for t in remote.requests] == [0, 1, 2, 3]
    assert {_field(t.payload.value)[0] for t in remote.requests} == {"empty"}
    assert {bytes(t.payload.name) for t in remote.requests} == {b""}


def test_requests_carry_node_ids_priority_and_counting_transfer_ids(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    for _ in range(33):
        assert client.get("GPS_SBAS") is not None
    client.save()
    sent = _requests(remote)
    assert {(s, d, p) for s, d, _, p in sent} == {(127, NODE, 31)}  # pydronecan's, the lowest
    # per service, modulo 32
    assert [tid for _, _, tid, _ in sent[:33]] == [*range(32), 0]
    assert sent[33][2] == 0  # ExecuteOpcode counts on its own


def test_a_read_by_name_answers_the_parameter_or_none(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    param = client.get("GPS_RATE_HZ")
    assert param is not None and param.index is None and param.value == {"integer_value": 5}
    assert client.get("NOPE") is None
    assert bytes(remote.requests[0].payload.name) == b"GPS_RATE_HZ"


def test_a_write_returns_what_the_node_answered(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    assert client.set("GPS_RATE_HZ", {"integer_value": 10}).value == {"integer_value": 10}
    assert _field(remote.params["GPS_RATE_HZ"]) == ("integer_value", 10)
    assert client.set("GPS_SBAS", {"boolean_value": 0}).value == {"boolean_value": 0}
    # stored rounded (float16): accepted, and the node's value returned
    assert client.set("GPS_YAW_OFFSET", {"real_value": 0.1}).value == {
        "real_value": 0.0999755859375
    }
    # a write is a read first, then the GetSet with the value
    assert _field(remote.requests[0].payload.value)[0] == "empty"
    assert _field(remote.requests[1].payload.value) == ("integer_value", 10)


def test_a_write_the_node_keeps_its_value_for_is_refused(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    with pytest.raises(DronecanError) as refused:
        client.set("GPS_RATE_HZ", {"integer_value": 50})
    assert str(refused.value) == "node 42 refused GPS_RATE_HZ = 50: it kept 5"
    # the same value written again is no refusal
    assert client.set("GPS_RATE_HZ", {"integer_value": 5}).value == {"integer_value": 5}


def test_a_write_of_another_kind_is_refused(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    with pytest.raises(DronecanError) as refused:
        client.set("GPS_RATE_HZ", {"real_value": 7.0})
    assert str(refused.value) == "node 42 refused GPS_RATE_HZ = 7: it kept 5"


def test_a_write_to_a_parameter_the_node_lacks_is_named(client: DronecanParamClient) -> None:
    with pytest.raises(DronecanError) as refused:
        client.set("NOPE", {"integer_value": 1})
    assert str(refused.value) == "node 42 has no parameter NOPE"


def test_save_is_opcode_0_and_a_refusal_is_named(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    client.save()
    assert (remote.requests[0].payload.opcode, remote.requests[0].payload.argument) == (0, 0)
    remote.save_ok = False
    with pytest.raises(DronecanError) as refused:
        client.save()
    assert str(refused.value) == "node 42 refused to save its parameters"


# -- silence, retries and stray answers ----------------------------------------------------------


def test_silence_is_retried_then_named(remote: RemoteNode) -> None:
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=0.05, retries=2)
    remote.silent = 2
    assert client.get("GPS_SBAS") is not None  # the third try is answered
    assert [tid for _, _, tid, _ in _requests(remote)] == [0, 1, 2]
    remote.silent = 3
    with pytest.raises(DronecanError) as silent:
        client.get("GPS_SBAS")
    assert str(silent.value) == (
        "node 42 did not answer GetSet (3 tries, 0.05 s each): is it on the bus, with that node ID?"
    )
    remote.silent = 1
    with pytest.raises(
        DronecanError, match=r"did not answer ExecuteOpcode \(1 tries, 0.05 s each\)"
    ):
        DronecanParamClient(SlcanHost(remote), NODE, timeout=0.05, retries=0).save()


def test_answers_from_another_node_are_not_taken(remote: RemoteNode) -> None:
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=0.05, retries=0)
    remote.answer_as = 43
    with pytest.raises(DronecanError, match=r"^node 42 did not answer GetSet"):
        client.get("GPS_SBAS")


def test_a_damaged_answer_is_dropped_and_the_retry_taken(remote: RemoteNode) -> None:
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=0.1, retries=1)
    remote.damage = 1  # the first multi-frame answer fails its CRC
    param = client.get("GPS_YAW_OFFSET")
    assert param is not None and param.value == {"real_value": 0.5}
    assert len(remote.requests) == 2


def test_a_late_answer_to_an_earlier_request_is_not_taken_for_the_next(
    remote: RemoteNode,
) -> None:
    """The transfer ID tells answers apart: GPS_RATE_HZ's answer arriving after it was given
    up on is not GPS_SBAS's."""
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=0.05, retries=0)
    held: list[transport.Transfer] = []
    answer = remote._answer

    def late(request: transport.Transfer) -> None:
        if not held:
            held.append(request)  # unanswered for now
            remote.requests.append(request)
            return
        answer(held[0])  # the stale answer (transfer ID 0) first, then this one's
        answer(request)

    remote._answer = late  # type: ignore[method-assign]
    with pytest.raises(DronecanError, match=r"^node 42 did not answer GetSet"):
        client.get("GPS_RATE_HZ")
    param = client.get("GPS_SBAS")
    assert param is not None and param.name == "GPS_SBAS"
    assert [t.transfer_id for t in remote.requests] == [0, 0, 1]


@pytest.mark.issue40
def test_the_client_needs_only_dronecan_s_standard_types(
    remote: RemoteNode, tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """GetSet and ExecuteOpcode are standard DroneCAN types: the extra namespaces of
    $PX4PARAMS_DSDL_PATH (the store's own types, here a broken one) are not read."""
    broken = tmp_path / "dsdl" / "broken"
    broken.mkdir(parents=True)
    (broken / "Thing.dsdl").write_text("this is not DSDL\n")
    monkeypatch.setenv("PX4PARAMS_DSDL_PATH", str(tmp_path / "dsdl"))
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=2.0)
    param = client.get("GPS_RATE_HZ")
    assert param is not None and param.value == {"integer_value": 5}


@pytest.mark.issue40
def test_a_name_that_is_not_utf8_is_shown_with_the_replacement_character(
    remote: RemoteNode, client: DronecanParamClient
) -> None:
    """DroneCAN parameter names are ASCII; a node that answers other bytes gets its name shown
    with U+FFFD where a byte is not UTF-8, and the parameter is still listed."""
    getset = remote._getset

    def latin1(request: Any) -> Any:
        response = getset(request)
        if bytes(response.name) == b"GPS_SBAS":
            response.name = b"GPS_SBAS\xb0"
        return response

    remote._getset = latin1  # type: ignore[method-assign]
    assert [p.name for p in client.list()] == ["GPS_RATE_HZ", "GPS_SBAS\ufffd", "GPS_YAW_OFFSET"]


@pytest.mark.issue40
def test_a_list_ends_at_index_8191_the_largest_getset_carries(remote: RemoteNode) -> None:
    """GetSet's index is a uint13: a node that never answers the empty name (it names a
    parameter at every index) is listed to index 8191, and no further request is made."""

    def endless(request: Any) -> Any:
        return GETSET.Response(name=b"P%d" % request.index, value=VALUE(integer_value=1))

    remote._getset = endless  # type: ignore[method-assign]
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=2.0, retries=0)
    listed = list(client.list())
    assert len(listed) == 8192 and listed[-1].name == "P8191"
    assert len(remote.requests) == 8192


@pytest.mark.issue40
def test_a_parameter_gone_when_written_is_named(remote: RemoteNode) -> None:
    """A node answers GetSet for a name it lacks with the empty name (the specification): when
    the write is so answered (the parameter went away after it was read, e.g. the node
    restarted with other parameters), the write fails naming the node and the parameter."""
    getset = remote._getset

    def gone_on_write(request: Any) -> Any:
        if _field(request.value)[0] != "empty":
            return GETSET.Response()
        return getset(request)

    remote._getset = gone_on_write  # type: ignore[method-assign]
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=2.0, retries=0)
    with pytest.raises(DronecanError) as refused:
        client.set("GPS_RATE_HZ", {"integer_value": 7})
    assert str(refused.value) == "node 42 has no parameter GPS_RATE_HZ"
    assert len(remote.requests) == 2  # the read, then the write


@pytest.mark.issue40
def test_a_write_answered_with_the_float32_sent_is_kept_even_when_unchanged(
    remote: RemoteNode,
) -> None:
    """DroneCAN's real_value is a float32: a node that stores float32 answers 0.1 as
    0.100000001490116; that is the value sent, kept, also when the node held it already."""
    getset = remote._getset

    def float32_node(request: Any) -> Any:
        kind, value = _field(request.value)
        if kind == "real_value":
            remote.params[bytes(request.name).decode()] = VALUE(real_value=value)
            request.value = VALUE(empty=dronecan.uavcan.protocol.param.Empty())  # answered as read
        return getset(request)

    remote._getset = float32_node  # type: ignore[method-assign]
    client = DronecanParamClient(SlcanHost(remote), NODE, timeout=2.0, retries=0)
    for _ in range(2):  # 0.5 -> 0.1, then 0.1 again
        param = client.set("GPS_YAW_OFFSET", {"real_value": 0.1})
        assert param.value == {"real_value": struct.unpack("<f", struct.pack("<f", 0.1))[0]}
