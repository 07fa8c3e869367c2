"""CAN frames of DroneCAN transfers (native ``can_frames``/``reassemble``,
px4params.links.can_transfer and the ``px4params frames`` command) against pydronecan's
``Transfer.to_frames()``/``from_frames()``.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from dronecan import transport
from dronecan_oracle import fill, same, to_plain
from px4params import _native
from px4params.errors import EncodeError, Px4ParamsError, TransferError
from px4params.links.can_transfer import (
    DEFAULT_PRIORITY,
    CanId,
    Frame,
    TransferReceiver,
    can_id,
    frames,
    parse_can_id,
    reassemble,
)

BATTERY = "uavcan.equipment.power.BatteryInfo"
NODE_STATUS = "uavcan.protocol.NodeStatus"
GET_NODE_INFO = "uavcan.protocol.GetNodeInfo"

NODE_STATUS_VALUE: dict[str, Any] = {
    "uptime_sec": 123456,
    "health": 1,
    "mode": 2,
    "sub_mode": 3,
    "vendor_specific_status_code": 0xBEEF,
}


def battery_value(model_name: bytes) -> dict[str, Any]:
    return {
        "temperature": 300.5,
        "voltage": 12.25,
        "current": -1.5,
        "average_power_10sec": 18.0,
        "remaining_capacity_wh": 40.0,
        "full_charge_capacity_wh": 55.5,
        "hours_to_full_charge": 0.5,
        "status_flags": 0x0123,
        "state_of_health_pct": 98,
        "state_of_charge_pct": 76,
        "state_of_charge_pct_stdev": 3,
        "battery_id": 2,
        "model_instance_id": 0xDEADBEEF,
        "model_name": list(model_name),
    }


LONG_MODEL_NAME = b"PX4 Smart Battery 6S 5000mAh v2"  # 31 characters, the maximum
assert len(LONG_MODEL_NAME) == 31

NODE_INFO_VALUE: dict[str, Any] = {
    "status": NODE_STATUS_VALUE,
    "software_version": {
        "major": 1,
        "minor": 14,
        "optional_field_flags": 3,
        "vcs_commit": 0x1A2B3C4D,
        "image_crc": 0x0102030405060708,
    },
    "hardware_version": {
        "major": 3,
        "minor": 1,
        "unique_id": list(range(16)),
        "certificate_of_authenticity": [0xAA, 0xBB, 0xCC],
    },
    "name": list(b"org.px4.cubeorange.with.a.rather.long.node.name"),
}


@dataclass(frozen=True)
class Case:
    id: str
    key: str
    value: dict[str, Any]
    transfer_id: int = 0
    source_node: int = 42
    canfd: bool = False
    dest_node: int | None = None
    priority: int | None = None
    extra: dict[str, Any] = field(default_factory=dict)


CASES = [
    Case("nodestatus", NODE_STATUS, NODE_STATUS_VALUE, transfer_id=3, source_node=10),
    Case("nodestatus-prio", NODE_STATUS, NODE_STATUS_VALUE, transfer_id=31, priority=0),
    Case("battery-long-name", BATTERY, battery_value(LONG_MODEL_NAME), transfer_id=17),
    Case("battery-short-name", BATTERY, battery_value(b"x"), transfer_id=4, source_node=127),
    Case("battery-canfd-long", BATTERY, battery_value(LONG_MODEL_NAME), canfd=True),
    Case("battery-canfd-short", BATTERY, battery_value(b""), transfer_id=9, canfd=True),
    Case("nodestatus-canfd", NODE_STATUS, NODE_STATUS_VALUE, canfd=True, source_node=1),
    Case(
        "nodeinfo-response",
        f"{GET_NODE_INFO}.Response",
        NODE_INFO_VALUE,
        transfer_id=9,
        dest_node=7,
    ),
    Case(
        "nodeinfo-response-canfd",
        f"{GET_NODE_INFO}.Response",
        NODE_INFO_VALUE,
        transfer_id=30,
        dest_node=100,
        canfd=True,
        priority=16,
    ),
    Case("nodeinfo-request-empty", f"{GET_NODE_INFO}.Request", {}, transfer_id=5, dest_node=1),
]


def oracle_transfer(case: Case) -> transport.Transfer:
    """pydronecan's transfer of the case's value."""
    name, _, half = case.key.rpartition(".")
    if half in ("Request", "Response"):
        obj = getattr(dronecan.TYPENAMES[name], half)()
        kwargs: dict[str, Any] = {
            "service_not_message": True,
            "request_not_response": half == "Request",
            "dest_node_id": case.dest_node,
        }
    else:
        obj = dronecan.TYPENAMES[case.key]()
        kwargs = {}
    if case.priority is not None:
        kwargs["transfer_priority"] = case.priority
    fill(obj, case.value)
    return transport.Transfer(
        transfer_id=case.transfer_id,
        source_node_id=case.source_node,
        payload=obj,
        canfd=case.canfd,
        **kwargs,
    )


def ours(schema: px4params.Schema, case: Case) -> list[Frame]:
    kwargs = {} if case.priority is None else {"priority": case.priority}
    return frames(
        schema[case.key],
        case.value,
        source_node=case.source_node,
        transfer_id=case.transfer_id,
        dest_node=case.dest_node,
        canfd=case.canfd,
        **kwargs,
    )


def oracle_frames(case: Case) -> list[Frame]:
    return [Frame(f.message_id, bytes(f.bytes)) for f in oracle_transfer(case).to_frames()]


# --------------------------------------------------------------------------------------------------
# Frames against pydronecan


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_frames_equal_pydronecan(schema: px4params.Schema, case: Case) -> None:
    expected = oracle_frames(case)
    assert ours(schema, case) == expected
    t = schema[case.key]
    payload = t.encode(case.value, tao=not case.canfd)
    datas = _native.can_frames(
        payload, signature=t.signature, transfer_id=case.transfer_id, canfd=case.canfd
    )
    assert [bytes(d) for d in datas] == [f.data for f in expected]


def test_cases_cover_multi_frame_and_padding(schema: px4params.Schema) -> None:
    counts = {c.id: len(oracle_frames(c)) for c in CASES}
    assert counts["nodestatus"] == 1
    assert counts["battery-long-name"] > 4
    assert counts["nodeinfo-response"] > 4
    assert counts["battery-canfd-long"] == 1  # 55 bytes fit one CAN FD frame
    assert counts["nodeinfo-response-canfd"] > 1
    padded = oracle_frames(CASES[5])[-1].data  # battery-canfd-short: 24 payload bytes
    assert len(padded) in (8, 12, 16, 20, 24, 32, 48, 64)


@pytest.mark.parametrize("transfer_id", [0, 1, 30, 31])
def test_transfer_ids(schema: px4params.Schema, transfer_id: int) -> None:
    case = Case("t", BATTERY, battery_value(LONG_MODEL_NAME), transfer_id=transfer_id)
    assert ours(schema, case) == oracle_frames(case)


def test_can_id_formats() -> None:
    # Message: priority, data type ID, source node.
    assert can_id(1092, source_node=42, priority=31) == 31 << 24 | 1092 << 8 | 42
    # Service: priority, data type ID, request bit, destination, service bit, source.
    assert can_id(1, source_node=5, dest_node=9, request=True, priority=2) == (
        2 << 24 | 1 << 16 | 1 << 15 | 9 << 8 | 1 << 7 | 5
    )
    for bad in (
        {"source_node": 0},
        {"source_node": 128},
        {"source_node": 1, "priority": 32},
        {"source_node": 1, "dest_node": 0},
    ):
        with pytest.raises(ValueError):
            can_id(1, **bad)
    with pytest.raises(ValueError, match="service data type ID"):
        can_id(256, source_node=1, dest_node=2)
    with pytest.raises(ValueError, match="message data type ID"):
        can_id(65536, source_node=1)


def test_frames_argument_errors(schema: px4params.Schema) -> None:
    status, response = schema[NODE_STATUS], schema[f"{GET_NODE_INFO}.Response"]
    with pytest.raises(ValueError, match="is a message"):
        frames(status, NODE_STATUS_VALUE, source_node=1, dest_node=2)
    with pytest.raises(ValueError, match="needs a destination node"):
        frames(response, NODE_INFO_VALUE, source_node=1)
    with pytest.raises(ValueError, match="transfer ID"):
        frames(status, NODE_STATUS_VALUE, source_node=1, transfer_id=32)
    with pytest.raises(ValueError, match="no default data type ID"):
        frames(schema["px.Ina238"], {}, source_node=1)


# --------------------------------------------------------------------------------------------------
# Reassembly


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_reassemble_round_trip(schema: px4params.Schema, case: Case) -> None:
    t = schema[case.key]
    sent = ours(schema, case)
    value, transfer_id = reassemble(t, [f.data for f in sent], canfd=case.canfd)
    assert transfer_id == case.transfer_id
    expected = t.decode(t.encode(case.value, tao=not case.canfd), tao=not case.canfd)
    assert same(value, expected)
    # The native payload is the encoding, plus CAN FD padding.
    payload, native_id = _native.reassemble([f.data for f in sent], signature=t.signature)
    assert native_id == case.transfer_id
    encoded = t.encode(case.value, tao=not case.canfd)
    assert payload[: len(encoded)] == encoded
    assert not any(payload[len(encoded) :])
    if not case.canfd:
        assert payload == encoded


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_pydronecan_reads_our_frames(schema: px4params.Schema, case: Case) -> None:
    received = transport.Transfer()
    received.from_frames(
        [transport.Frame(f.can_id, f.data, canfd=case.canfd) for f in ours(schema, case)]
    )
    assert received.transfer_id == case.transfer_id
    assert received.source_node_id == case.source_node
    t = schema[case.key]
    expected = t.decode(t.encode(case.value, tao=not case.canfd), tao=not case.canfd)
    assert same(to_plain(received.payload), expected)


@pytest.fixture(scope="module")
def battery_frames(schema: px4params.Schema) -> list[bytes]:
    case = Case("errors", BATTERY, battery_value(LONG_MODEL_NAME), transfer_id=12)
    datas = [f.data for f in ours(schema, case)]
    assert len(datas) >= 6
    return datas


def with_tail(data: bytes, xor: int) -> bytes:
    return data[:-1] + bytes([data[-1] ^ xor])


def corrupt_payload(data: bytes) -> bytes:
    return bytes([data[0] ^ 0x01]) + data[1:]


# (name, frames from the good ones, pattern the one-line message must match)
BROKEN = [
    ("wrong-toggle", lambda f: [*f[:2], with_tail(f[2], 0x20), *f[3:]], r"frame 2 .*toggle"),
    ("bad-crc", lambda f: [*f[:3], corrupt_payload(f[3]), *f[4:]], r"CRC"),
    ("bad-crc-bytes", lambda f: [corrupt_payload(f[0]), *f[1:]], r"CRC"),
    (
        "mixed-transfer-id",
        lambda f: [*f[:3], with_tail(f[3], 0x01), *f[4:]],
        r"frame 3 .*transfer ID 13.*12",
    ),
    ("missing-last", lambda f: f[:-1], r"last frame .*end-of-transfer"),
    ("missing-middle", lambda f: [*f[:2], *f[3:]], r"frame 2 .*toggle"),
    ("repeated-frame", lambda f: [*f[:3], f[2], *f[3:]], r"frame 3 .*toggle"),
    ("repeated-first", lambda f: [f[0], *f], r"frame 1 .*start-of-transfer"),
    ("out-of-order", lambda f: [f[0], f[2], f[1], *f[3:]], r"frame 1 .*toggle"),
    ("no-start", lambda f: f[1:], r"first frame .*start-of-transfer"),
    ("end-too-early", lambda f: [*f[:2], with_tail(f[2], 0x40), *f[3:]], r"frame 2 .*end-of"),
]


@pytest.mark.parametrize(("name", "broken", "pattern"), BROKEN, ids=[b[0] for b in BROKEN])
def test_reassembly_errors(
    schema: px4params.Schema,
    battery_frames: list[bytes],
    name: str,
    broken: Any,
    pattern: str,
) -> None:
    datas = broken(battery_frames)
    t = schema[BATTERY]
    with pytest.raises(TransferError) as info:
        _native.reassemble(datas, signature=t.signature)
    message = str(info.value)
    assert "\n" not in message
    assert re.search(pattern, message, re.IGNORECASE), message
    assert isinstance(info.value, Px4ParamsError)
    with pytest.raises(TransferError, match=pattern):
        reassemble(t, datas)
    # pydronecan refuses them too.
    message_id = can_id(t.dtid, source_node=42)
    with pytest.raises(transport.TransferError):
        transport.Transfer().from_frames([transport.Frame(message_id, d) for d in datas])


def test_reassembly_no_frames(schema: px4params.Schema) -> None:
    with pytest.raises(TransferError, match="no frames"):
        _native.reassemble([], signature=schema[BATTERY].signature)


def test_reassembly_wrong_signature(schema: px4params.Schema, battery_frames: list[bytes]) -> None:
    # Another type's signature seeds another CRC: a multi-frame transfer of the wrong type fails.
    with pytest.raises(TransferError, match="CRC"):
        _native.reassemble(battery_frames, signature=schema[NODE_STATUS].signature)


def test_single_frame_has_no_crc(schema: px4params.Schema) -> None:
    t = schema[NODE_STATUS]
    (frame,) = frames(t, NODE_STATUS_VALUE, source_node=3, transfer_id=7)
    assert frame.data[:-1] == t.encode(NODE_STATUS_VALUE)
    assert frame.data[-1] == 0x80 | 0x40 | 7
    payload, transfer_id = _native.reassemble([frame.data], signature=0)  # no CRC to check
    assert (payload, transfer_id) == (t.encode(NODE_STATUS_VALUE), 7)


# --------------------------------------------------------------------------------------------------
# The frames command


@pytest.fixture(scope="module")
def cli_env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PX4PARAMS_DSDL_PATH", None)
    env["PX4PARAMS_CACHE_DIR"] = str(tmp_path_factory.mktemp("cache"))
    return env


def run(
    env: dict[str, str], *args: str, stdin: str | None = None
) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(
        [sys.executable, "-m", "px4params", "frames", *args],
        input=stdin,
        capture_output=True,
        text=True,
        env=env,
        cwd=Path(env["PX4PARAMS_CACHE_DIR"]),
        timeout=120,
    )
    assert "Traceback" not in proc.stdout + proc.stderr, proc.stderr
    return proc


def frame_lines(expected: list[Frame]) -> list[str]:
    return [f"{f.can_id:08x} {f.data.hex()}" for f in expected]


def test_cli_frames_match_pydronecan(cli_env: dict[str, str]) -> None:
    for case in (CASES[0], CASES[2], CASES[4], CASES[7]):
        args = [
            case.key,
            json.dumps(case.value),
            "--transfer-id",
            str(case.transfer_id),
            "--source-node",
            str(case.source_node),
        ]
        if case.canfd:
            args.append("--canfd")
        if case.dest_node is not None:
            args += ["--dest-node", str(case.dest_node)]
        proc = run(cli_env, *args)
        assert proc.returncode == 0, proc.stderr
        assert proc.stderr == ""
        assert proc.stdout.splitlines() == frame_lines(oracle_frames(case)), case.id


def test_cli_json_and_stdin(cli_env: dict[str, str]) -> None:
    case = Case("cli", BATTERY, battery_value(LONG_MODEL_NAME), transfer_id=6, priority=8)
    args = ["--transfer-id", "6", "--source-node", "42", "--priority", "8", "--json"]
    proc = run(cli_env, BATTERY, "-", *args, stdin=json.dumps(case.value) + "\n")
    assert proc.returncode == 0, proc.stderr
    rows = json.loads(proc.stdout)
    assert [(r["can_id"], bytes.fromhex(r["data"])) for r in rows] == oracle_frames(case)


def test_cli_px_type_needs_dtid(cli_env: dict[str, str], schema: px4params.Schema) -> None:
    value = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}
    one_error(run(cli_env, "px.Ina238", json.dumps(value)), "no default data type ID", "--dtid")
    proc = run(cli_env, "px.Ina238", json.dumps(value), "--dtid", "20000", "--source-node", "5")
    assert proc.returncode == 0, proc.stderr
    expected = frames(schema["px.Ina238"], value, source_node=5, dtid=20000)
    assert proc.stdout.splitlines() == frame_lines(expected)


def one_error(proc: subprocess.CompletedProcess[str], *fragments: str) -> None:
    assert proc.returncode == 1, (proc.stdout, proc.stderr)
    assert proc.stdout == ""
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("px4params: error: "), lines[0]
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])


STATUS_JSON = json.dumps(NODE_STATUS_VALUE)
CLI_ERRORS = [
    ("unknown-type", ["uavcan.NoSuch", "{}"], ["unknown type 'uavcan.NoSuch'"]),
    ("bad-json", [NODE_STATUS, "{nope"], ["not JSON"]),
    ("out-of-range", [NODE_STATUS, json.dumps({**NODE_STATUS_VALUE, "health": 9})], ["health"]),
    ("service-no-dest", [f"{GET_NODE_INFO}.Response", "{}"], ["--dest-node", "service"]),
    ("message-with-dest", [NODE_STATUS, STATUS_JSON, "--dest-node", "3"], ["is a message"]),
    ("anonymous", [NODE_STATUS, STATUS_JSON, "--source-node", "0"], ["anonymous"]),
    ("source-128", [NODE_STATUS, STATUS_JSON, "--source-node", "128"], ["source node ID"]),
    ("dest-0", [f"{GET_NODE_INFO}.Request", "{}", "--dest-node", "0"], ["destination node"]),
    ("transfer-id-32", [NODE_STATUS, STATUS_JSON, "--transfer-id", "32"], ["transfer ID"]),
    ("priority-32", [NODE_STATUS, STATUS_JSON, "--priority", "32"], ["priority"]),
    ("dtid-too-big", [NODE_STATUS, STATUS_JSON, "--dtid", "70000"], ["data type ID"]),
]


@pytest.mark.parametrize(("name", "args", "fragments"), CLI_ERRORS, ids=[e[0] for e in CLI_ERRORS])
def test_cli_errors(
    cli_env: dict[str, str], name: str, args: list[str], fragments: list[str]
) -> None:
    one_error(run(cli_env, *args), *fragments)


def test_cli_usage_errors(cli_env: dict[str, str]) -> None:
    proc = run(cli_env, NODE_STATUS, STATUS_JSON, "--transfer-id", "three")
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.splitlines()[-1].startswith("px4params frames: error: ")
    proc = run(cli_env)
    assert proc.returncode == 2


def test_cli_help(cli_env: dict[str, str]) -> None:
    proc = run(cli_env, "--help")
    assert proc.returncode == 0
    assert "example:" in proc.stdout
    assert "--canfd" in proc.stdout and "--dest-node" in proc.stdout
    # The example in the help is right.
    lines = proc.stdout.splitlines()
    command = lines[lines.index("example:") + 1 : lines.index("example:") + 3]
    assert "uavcan.protocol.NodeStatus" in command[0]
    value = json.loads(command[1].strip().strip("'"))
    expected = oracle_frames(Case("help", NODE_STATUS, value, transfer_id=3, source_node=10))
    assert lines[lines.index("example:") + 3].strip() == frame_lines(expected)[0]


# -- the transfer timeout, CAN IDs and the receiver's limits (issue 40) ------------------------
# UAVCAN v0 specification, "Transfer reception": a transfer with the same transfer ID from the
# same source is a duplicate (a redundant interface) only within the transfer timeout, 2 s;
# after it, the same transfer ID starts a new transfer (the 5-bit ID wraps every 32 transfers,
# so a node sending once a second reuses an ID every 32 s). Issue 40: bugs planted one at a
# time stayed green; each expected answer comes from the rule, not from our code.


GETSET = dronecan.uavcan.protocol.param.GetSet


class Clock:
    """A clock the test moves by hand (no sleeping, no timing in assertions)."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _frames(tid: int, *, long: bool) -> list[Frame]:
    """pydronecan's frames of one transfer from node 10: a NodeStatus message (one frame), or
    a GetSet response to node 20 (several)."""
    if long:
        payload = GETSET.Response(
            name=b"INA238_1_CURRENT", value=dronecan.uavcan.protocol.param.Value(integer_value=7)
        )
        dest, service = 20, True
    else:
        payload = dronecan.uavcan.protocol.NodeStatus(uptime_sec=42)
        dest, service = None, False
    t = transport.Transfer(
        payload=payload,
        source_node_id=10,
        dest_node_id=dest,
        transfer_id=tid,
        service_not_message=service,
        request_not_response=False,
    )
    return [Frame(f.message_id, bytes(f.bytes)) for f in t.to_frames()]


def _delivered(receiver: TransferReceiver, frames: list[Frame]) -> int:
    return sum(receiver.feed(f) is not None for f in frames)


@pytest.mark.issue40
@pytest.mark.parametrize("long", [False, True], ids=["single-frame", "multi-frame"])
def test_same_transfer_id_after_the_2s_timeout_is_a_new_transfer(long: bool) -> None:
    frames = _frames(5, long=long)
    assert (len(frames) > 1) == long
    clock = Clock()
    receiver = TransferReceiver(clock=clock)
    assert _delivered(receiver, frames) == 1
    clock.now += 1.0  # within the timeout: the same transfer again (a redundant interface)
    assert _delivered(receiver, frames) == 0
    clock.now += 1.5  # 2.5 s after the first: transfer ID 5 again is a new transfer
    assert _delivered(receiver, frames) == 1
    clock.now += 30.0  # and so after any longer silence
    assert _delivered(receiver, frames) == 1
    # Another transfer ID from the same source is new at once.
    assert _delivered(receiver, _frames(6, long=long)) == 1


# -- CAN IDs (issue 40's mutation run: what survived in can_transfer.py) -------------------------


def _pydronecan_can_id(payload: Any, *, source: int, dest: int | None, request: bool) -> int:
    t = transport.Transfer(
        payload=payload,
        source_node_id=source,
        dest_node_id=dest,
        transfer_id=0,
        transfer_priority=DEFAULT_PRIORITY,
        service_not_message=dest is not None,
        request_not_response=request,
    )
    return int(t.to_frames()[0].message_id)


@pytest.mark.issue40
def test_can_ids_are_pydronecans_and_a_service_frame_is_a_response_unless_told() -> None:
    status = dronecan.uavcan.protocol.NodeStatus()
    assert can_id(341, source_node=10) == _pydronecan_can_id(
        status, source=10, dest=None, request=False
    )
    response = GETSET.Response()
    request = GETSET.Request()
    # Without request=True a service frame is a response: bit 15 clear.
    assert can_id(11, source_node=10, dest_node=20) == _pydronecan_can_id(
        response, source=10, dest=20, request=False
    )
    assert can_id(11, source_node=10, dest_node=20, request=True) == _pydronecan_can_id(
        request, source=10, dest=20, request=True
    )
    # The ends of every range are valid (UAVCAN v0: message type IDs 0..65535, service type
    # IDs 0..255, node IDs 1..127, priorities 0..31).
    assert can_id(0, source_node=1, priority=0) == 1
    assert can_id(0xFFFF, source_node=127, priority=31) == 31 << 24 | 0xFFFF << 8 | 127
    assert can_id(0, source_node=1, dest_node=1, priority=0) == 1 << 8 | 1 << 7 | 1
    assert can_id(0xFF, source_node=127, dest_node=127) == (
        31 << 24 | 0xFF << 16 | 127 << 8 | 1 << 7 | 127
    )


#: can_id's arguments, then the number refused: its name, range and value as the message gives
#: them ("priority must be an integer in 0..31, got 32").
OUT_OF_RANGE: list[tuple[dict[str, Any], str, str, str]] = [
    ({"dtid": 341, "source_node": 10, "priority": 32}, "priority", "0..31", "32"),
    ({"dtid": 341, "source_node": 10, "priority": -1}, "priority", "0..31", "-1"),
    ({"dtid": 341, "source_node": 0}, "source node ID", "1..127", "0"),
    ({"dtid": 341, "source_node": 128}, "source node ID", "1..127", "128"),
    ({"dtid": 341, "source_node": True}, "source node ID", "1..127", "True"),
    ({"dtid": 341, "source_node": 1.0}, "source node ID", "1..127", "1.0"),
    ({"dtid": 65536, "source_node": 10}, "message data type ID", "0..65535", "65536"),
    ({"dtid": -1, "source_node": 10}, "message data type ID", "0..65535", "-1"),
    ({"dtid": 256, "source_node": 10, "dest_node": 20}, "service data type ID", "0..255", "256"),
    ({"dtid": -1, "source_node": 10, "dest_node": 20}, "service data type ID", "0..255", "-1"),
    ({"dtid": 11, "source_node": 10, "dest_node": 0}, "destination node ID", "1..127", "0"),
    ({"dtid": 11, "source_node": 10, "dest_node": 128}, "destination node ID", "1..127", "128"),
]


@pytest.mark.issue40
@pytest.mark.parametrize(("arguments", "what", "limits", "given"), OUT_OF_RANGE)
def test_can_id_refuses_numbers_out_of_range_by_name(
    arguments: dict[str, Any], what: str, limits: str, given: str
) -> None:
    with pytest.raises(ValueError) as refused:
        can_id(**arguments)
    assert str(refused.value) == f"{what} must be an integer in {limits}, got {given}"


# -- frames, CAN IDs read back, the receiver's limits (what survived in can_transfer.py) --------


@pytest.mark.issue40
@pytest.mark.parametrize(
    "fields",
    [
        CanId(31, 0xFFFF, 127),
        CanId(0, 0, 1),
        CanId(17, 341, 10),
        CanId(31, 0xFF, 127, 127, True),
        CanId(0, 0, 1, 1, False),
        CanId(30, 11, 10, 20, True),
    ],
)
def test_parse_can_id_reads_back_every_field(fields: CanId) -> None:
    identifier = can_id(
        fields.dtid,
        source_node=fields.source_node,
        priority=fields.priority,
        dest_node=fields.dest_node,
        request=fields.request,
    )
    parsed = parse_can_id(identifier)
    assert parsed == fields
    assert parsed.service == (fields.dest_node is not None)
    if fields.dest_node is None:  # a message: no destination, not a request
        assert (parsed.dest_node, parsed.request) == (None, False)


@pytest.mark.issue40
def test_frames_defaults_and_refusals(schema: px4params.Schema) -> None:
    status = schema.get("uavcan.protocol.NodeStatus")
    getset = schema.get("uavcan.protocol.param.GetSet.Request")
    value = {"uptime_sec": 1, "health": 0, "mode": 0, "sub_mode": 0,
             "vendor_specific_status_code": 0}  # fmt: skip
    (frame,) = frames(status, value, source_node=10)
    assert frame.data[-1] == 0xC0  # start and end of transfer, toggle 0, transfer ID 0
    assert frame.can_id == can_id(341, source_node=10)
    with pytest.raises(EncodeError):  # uint2 health: 4 does not fit, no saturation unless asked
        frames(status, {**value, "health": 4}, source_node=10)
    saturated = frames(status, {**value, "health": 4}, source_node=10, saturate=True)
    assert reassemble(status, [f.data for f in saturated])[0]["health"] == 3
    refusals = [
        ({"dest_node": 20}, "uavcan.protocol.NodeStatus is a message; a destination node is "
         "for services"),
        ({}, "uavcan.protocol.param.GetSet.Request is a service request; it needs a "
         "destination node"),
        ({"transfer_id": 32}, "transfer ID must be an integer in 0..31, got 32"),
    ]  # fmt: skip
    for arguments, message in refusals:
        data_type = status if "dest_node" in arguments or "transfer_id" in arguments else getset
        with pytest.raises(ValueError) as refused:
            frames(data_type, value if data_type is status else {}, source_node=10, **arguments)
        assert str(refused.value).startswith(message), str(refused.value)
    response = schema.get("uavcan.protocol.param.GetSet.Response")
    (first, *_) = frames(response, _getset_response("X"), source_node=10, dest_node=20)
    assert parse_can_id(first.can_id).request is False  # a response
    with pytest.raises(ValueError) as refused:
        frames(response, _getset_response("X"), source_node=10)
    assert str(refused.value) == (
        "uavcan.protocol.param.GetSet.Response is a service response; it needs a destination node"
    )
    with pytest.raises(ValueError) as refused:  # a px type has no DroneCAN data type ID
        frames(schema.get("px.Tmp102"), {}, source_node=10)
    assert str(refused.value) == "px.Tmp102.1.0 has no default data type ID; give one"


def _getset_response(name: str) -> dict[str, Any]:
    empty = {"empty": {}}
    return {"value": {"integer_value": -5}, "default_value": empty, "max_value": empty,
            "min_value": empty, "name": name}  # fmt: skip


@pytest.mark.issue40
def test_reassemble_reads_classic_can_by_default(schema: px4params.Schema) -> None:
    response = schema.get("uavcan.protocol.param.GetSet.Response")
    sent = frames(response, _getset_response("INA238_1_SOME_LONG_NAME"), source_node=10,
                  dest_node=20, transfer_id=9)  # fmt: skip
    assert len(sent) > 2  # multi-frame, the name's length left out (tail array optimization)
    got, transfer_id = reassemble(response, [f.data for f in sent])
    assert transfer_id == 9
    assert bytes(got["name"]) == b"INA238_1_SOME_LONG_NAME"
    assert got["value"] == {"integer_value": -5}


def _hand_made_frames(count: int, tid: int = 3) -> list[Frame]:
    """``count`` frames of one transfer from node 10, tail bytes by the rule (start bit on the
    first, end bit on the last, toggle alternating from 0), payload bytes arbitrary."""
    identifier = can_id(341, source_node=10)
    out = []
    for n in range(count):
        tail = (0x80 if n == 0 else 0) | (0x40 if n == count - 1 else 0) | (n & 1) << 5 | tid
        out.append(Frame(identifier, bytes(7) + bytes([tail])))
    return out


@pytest.mark.issue40
def test_receiver_takes_256_frames_and_drops_a_longer_transfer() -> None:
    receiver = TransferReceiver()
    done = [receiver.feed(f) for f in _hand_made_frames(256)]
    assert done[-1] is not None and len(done[-1].datas) == 256
    receiver = TransferReceiver()
    assert all(receiver.feed(f) is None for f in _hand_made_frames(257))
    assert receiver.ignored == 1  # the 257th frame drops the session


@pytest.mark.issue40
def test_receiver_counts_what_it_ignores_and_skips_what_it_does_not_accept() -> None:
    sent = _hand_made_frames(3)
    receiver = TransferReceiver()
    assert receiver.ignored == 0
    # Joined half-way: two frames without a session, each counted once.
    assert [receiver.feed(f) for f in sent[1:]] == [None, None]
    assert receiver.ignored == 2
    # Only services addressed to node 1 accepted: a message is skipped, not counted.
    picky = TransferReceiver(lambda ident: ident.dest_node == 1)
    assert [picky.feed(f) for f in sent] == [None, None, None]
    assert picky.ignored == 0
    everyone = TransferReceiver(lambda ident: True)
    assert [everyone.feed(f) is not None for f in sent] == [False, False, True]


@pytest.mark.issue40
def test_receiver_counts_each_kind_of_ignored_frame() -> None:
    clock = Clock()
    one = _hand_made_frames(1)  # a single-frame transfer, transfer ID 3
    cases: list[tuple[str, list[Frame]]] = [
        ("empty frames", [Frame(one[0].can_id, b""), Frame(one[0].can_id, b"")]),
        ("anonymous frames", [Frame(one[0].can_id & ~0x7F, one[0].data)] * 2),
        ("start frames with the toggle set",
         [Frame(one[0].can_id, bytes([0xA3])), Frame(one[0].can_id, bytes([0xA4]))]),
        ("the same transfer twice again", one * 3),
        ("frames of another transfer ID in a session",
         _hand_made_frames(3)[:1] + _hand_made_frames(3, tid=4)[1:2]
         + _hand_made_frames(3, tid=5)[:1] + _hand_made_frames(3, tid=6)[1:2]),
        ("two transfers of 257 frames", _hand_made_frames(257) + _hand_made_frames(257, tid=4)),
    ]  # fmt: skip
    for what, sent in cases:
        receiver = TransferReceiver(clock=clock)
        for frame in sent:
            receiver.feed(frame)
        assert receiver.ignored == 2, what


@pytest.mark.issue40
def test_receiver_remembers_4096_finished_transfers() -> None:
    """Duplicates are told apart by the last transfer of each session; the oldest record goes
    once more than 4096 sessions finished (many peers over a long time)."""

    def single(dtid: int) -> Frame:
        return Frame(can_id(dtid, source_node=10), bytes([0xC0 | 3]))

    receiver = TransferReceiver()
    assert [receiver.feed(single(d)) is not None for d in range(4096)] == [True] * 4096
    assert receiver.feed(single(0)) is None  # all 4096 remembered: a duplicate
    assert receiver.feed(single(4096)) is not None  # the 4097th: the oldest is forgotten
    assert receiver.feed(single(0)) is not None  # so this is a new transfer
