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
from px4params.errors import Px4ParamsError, TransferError
from px4params.links.can_transfer import Frame, can_id, frames, reassemble

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
