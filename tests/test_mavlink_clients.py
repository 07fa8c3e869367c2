"""Real ground-station clients against ``MavlinkParamServer`` on 127.0.0.1: MAVSDK-Python (its
gRPC API, with the mavsdk_server it bundles), MAVProxy run non-interactively, and pymavlink's
MAVFTP client downloading the component metadata announced by COMPONENT_METADATA.

Each lists every parameter, reads and writes an int and a float leaf (a float16 one), and sees
wrong types, out-of-range values and unknown names refused; after every refusal the value is
read back, in the store and over the link. Expected values are known numbers (the instance is
set up here), never what the server's own helpers compute.
"""

from __future__ import annotations

import asyncio
import json
import lzma
import os
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import px4params
import pytest
from px4params.links.mavlink import MavlinkParamServer
from px4params.store.classic import BUNDLED_CLASSIC

os.environ.setdefault("MAVLINK20", "1")  # pymavlink's mavutil: MAVLink 2 dialects
from pymavlink import mavutil

#: The float16 nearest 0.0005 (1049 * 2**-21), what a float16 leaf stores for it.
FLOAT16_0_0005 = 1049 * 2**-21
#: INA238#1 as set up below: on I2C bus 2 at 0x45 (the driver's default address), 200 A.
ADDRESS, CURRENT = 0x45, 200


@pytest.fixture
def vehicle(schema: px4params.Schema, tmp_path: Path) -> Iterator[MavlinkParamServer]:
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    store.set(
        "INA238#1",
        {"bus": {"i2c": {"bus_id": 2, "address": ADDRESS}}, "current": CURRENT, "shunt": 0.0003},
    )
    server = MavlinkParamServer(store, "127.0.0.1", 0, save_path=tmp_path / "vehicle.store")
    server.start()
    yield server
    server.stop()


def _free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


# -- MAVSDK ---------------------------------------------------------------------------------


def test_mavsdk_lists_reads_and_writes(vehicle: MavlinkParamServer) -> None:
    import mavsdk_grpc as mavsdk  # MAVSDK-Python's gRPC API under its new name (pyproject.toml)
    from mavsdk_grpc.param import ParamError

    host, port = vehicle.address
    store = vehicle.store
    results: dict[str, Any] = {}

    async def session() -> None:
        drone = mavsdk.System(port=_free_tcp_port())  # its own mavsdk_server, on a free port
        await drone.connect(system_address=f"udpout://{host}:{port}")
        async for state in drone.core.connection_state():
            if state.is_connected:
                break
        every = await drone.param.get_all_params()
        results["ints"] = {p.name: p.value for p in every.int_params}
        results["floats"] = {p.name: p.value for p in every.float_params}
        results["read_c"] = await drone.param.get_param_int("INA238_1C")
        await drone.param.set_param_int("INA238_1C", 0x46)
        results["after_c"] = await drone.param.get_param_int("INA238_1C")
        # float16 leaf: stored rounded, and the write still counts as acknowledged
        await drone.param.set_param_float("INA238_1Q", 0.0005)
        results["after_q"] = await drone.param.get_param_float("INA238_1Q")
        refused = {}
        for label, call in (
            ("range", drone.param.set_param_int("INA238_1C", 500)),
            ("type", drone.param.set_param_float("INA238_1C", 5.0)),
            ("unknown", drone.param.set_param_int("NO_SUCH_NAME", 1)),
        ):
            try:
                await call
                refused[label] = "accepted"
            except ParamError as e:
                refused[label] = e._result.result.name
            # read back over the link after every refused write
            refused[f"{label}_then"] = await drone.param.get_param_int("INA238_1C")
        results["refused"] = refused
        version = await drone.info.get_version()
        results["version"] = (
            version.flight_sw_major,
            version.flight_sw_minor,
            version.flight_sw_patch,
        )

    asyncio.run(asyncio.wait_for(session(), timeout=90))

    expected_ints = {"INA238_1A": 0, "INA238_1B": 2, "INA238_1C": ADDRESS, "INA238_1P": CURRENT}
    assert expected_ints.items() <= results["ints"].items()
    assert "SYS_AUTOSTART" in results["ints"] and "INA238_1Q" in results["floats"]
    listed = len(results["ints"]) + len(results["floats"])
    classic = sum(1 for name in store.parameters if store.classic(name) is not None)
    masks = sum(1 for name in store.parameters if store.spec(name) and not store.spec(name).shared)
    assert listed == classic + 5 + masks  # 5 live leaves of INA238#1 (A, B, C, P, Q), masks
    assert results["ints"]["INA238_INST"] == 0b10  # INA238#1 exists
    assert results["floats"]["INA238_1Q"] == pytest.approx(0.0003, rel=1e-3)
    assert results["read_c"] == ADDRESS
    assert results["after_c"] == 0x46
    assert results["after_q"] == FLOAT16_0_0005
    assert results["refused"] == {
        "range": "VALUE_OUT_OF_RANGE",
        "range_then": 0x46,
        "type": "WRONG_TYPE",
        "type_then": 0x46,
        "unknown": "DOES_NOT_EXIST",
        "unknown_then": 0x46,
    }
    assert results["version"] == (0, 1, 0)
    assert store.get("INA238#1.bus.i2c.address") == 0x46
    assert store.get("INA238#1.shunt") == FLOAT16_0_0005
    saved = px4params.Store.load(vehicle.save_path, store.schema, classic=BUNDLED_CLASSIC)
    assert saved.get("INA238#1.bus.i2c.address") == 0x46


# -- MAVProxy -------------------------------------------------------------------------------


def _mavproxy() -> str:
    script = Path(sys.executable).with_name("mavproxy.py")
    if not script.exists():
        pytest.skip("MAVProxy is not installed (scripts/setup.sh installs mavproxy==1.8.75)")
    return str(script)


def test_mavproxy_lists_and_sets(vehicle: MavlinkParamServer) -> None:
    host, port = vehicle.address
    # MAVProxy reads commands from stdin once it runs; --cmd would run before the parameters
    # have arrived. Its FTP parameter download is off (param_ftp 0): that path asks for
    # @PARAM/param.pck, which a PX4 has not either (tested below: answered FileNotFound).
    lines = [
        (8, "param show INA238_1*"),
        (0, "param set INA238_1C 70"),
        (1.5, "param set INA238_1Q 0.0005"),
        (1.5, "param set INA238_1C 500"),
        (2, "param show INA238_1*"),
        (0, "param status"),
        (1, ""),
    ]
    script = "; ".join(f"sleep {wait}; echo '{text}'" for wait, text in lines)
    command = (
        f"({script}) | {sys.executable} {_mavproxy()} --master=udpout:{host}:{port} "
        "--no-state --default-modules=param --cmd='set param_ftp 0'"
    )
    proc = subprocess.run(
        command,
        shell=True,
        capture_output=True,
        text=True,
        timeout=90,
        cwd=vehicle.save_path.parent,
    )
    out = proc.stdout
    assert "Detected vehicle 1:1" in out, out[-2000:]
    store = vehicle.store
    classic = sum(1 for n in store.parameters if store.classic(n) is not None)
    masks = sum(1 for n in store.parameters if store.spec(n) and not store.spec(n).shared)
    listed = classic + 5 + masks
    assert f"Received {listed} parameters" in out
    assert f"Have {listed}/{listed} params" in out
    first, second = out.split("INA238_1A", 2)[1:3]
    assert "INA238_1C        69" in first and "INA238_1P        200" in first
    assert "INA238_1C        70" in second  # the int set, as MAVProxy shows it afterwards
    assert (
        "AP: INA238_1C: INA238#1: bus.i2c.address: value 500 is out of range (expected 0 to 127)"
        in out
    )
    assert vehicle.store.get("INA238#1.bus.i2c.address") == 70  # refused 500 changed nothing
    assert vehicle.store.get("INA238#1.shunt") == FLOAT16_0_0005


# -- MAVLink FTP: metadata as QGC fetches it ------------------------------------------------


def _client(vehicle: MavlinkParamServer) -> Any:
    from px4params.links import mavlink_messages

    host, port = vehicle.address
    conn = mavutil.mavlink_connection(
        f"udpout:{host}:{port}", source_system=255, source_component=190, dialect="common"
    )
    mavlink_messages.register(mavutil.mavlink)  # COMPONENT_METADATA is not in pymavlink yet
    conn.mav.heartbeat_send(6, 8, 0, 0, 0)
    return conn


def _path(uri: str) -> str:
    """What QGC's FTPManager makes of an mftp:// URI: the path after the scheme."""
    assert uri.startswith("mftp://")
    return "/" + uri[len("mftp://") :].lstrip("/")


def _bitwise_crc32part(data: bytes) -> int:
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xEDB88320 if crc & 1 else crc >> 1
    return crc


@pytest.mark.parametrize(
    "message_id, kind", [(397, "COMPONENT_METADATA"), (395, "COMPONENT_INFORMATION")]
)
def test_mavftp_fetches_the_metadata(
    vehicle: MavlinkParamServer, message_id: int, kind: str
) -> None:
    from pymavlink import mavftp
    from pymavlink.dialects.v20 import common as mavlink

    conn = _client(vehicle)
    try:
        conn.mav.command_long_send(
            1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, message_id, 0, 0, 0, 0, 0, 0
        )
        announced = conn.recv_match(type=[kind], blocking=True, timeout=5)
        assert announced is not None, f"no {kind}"
        uri = announced.uri if message_id == 397 else announced.general_metadata_uri
        crc = announced.file_crc if message_id == 397 else announced.general_metadata_file_crc
        ftp = mavftp.MAVFTP(conn, 1, 1)
        general_bytes = ftp.read(_path(uri), 1 << 20)
        assert general_bytes is not None
        assert _bitwise_crc32part(general_bytes) == crc
        general = json.loads(general_bytes)
        assert general["version"] == 1
        (entry,) = general["metadataTypes"]
        assert entry["type"] == 1  # COMP_METADATA_TYPE_PARAMETER
        packed = ftp.read(_path(entry["uri"]), 1 << 24)
        assert packed is not None and _bitwise_crc32part(packed) == entry["fileCrc"]
        document = json.loads(lzma.decompress(packed))
    finally:
        conn.close()
    assert document["version"] == 1
    by_name = {p["name"]: p for p in document["parameters"]}
    c = by_name["INA238_1C"]
    assert (c["type"], c["shortDesc"], c["min"], c["max"], c["default"]) == (
        "Int32",
        "INA238 #1: bus.i2c.address",
        0,
        127,
        0x45,
    )
    assert by_name["INA238_1Q"]["type"] == "Float" and by_name["INA238_1Q"]["units"] == "Ohm"
    assert by_name["INA238"]["type"] == "Custom"
    assert by_name["SYS_AUTOSTART"]["type"] == "Int32"  # the store's classic parameters too


def test_mavftp_cli_downloads_by_path(vehicle: MavlinkParamServer, tmp_path: Path) -> None:
    """pymavlink's own command-line FTP client, as a user would run it."""
    host, port = vehicle.address
    target = tmp_path / "general.json"
    proc = subprocess.run(
        [sys.executable, "-m", "pymavlink.mavftp", "--device", f"udpout:{host}:{port}",
         "get", "/px4params/general.json", str(target)],
        capture_output=True, text=True, timeout=60, env={**os.environ, "MAVLINK20": "1"},
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout[-1500:] + proc.stderr[-1500:]
    assert json.loads(target.read_text())["metadataTypes"][0]["type"] == 1


def test_parameter_download_over_ftp_is_refused_as_px4_does(
    vehicle: MavlinkParamServer, caplog: pytest.LogCaptureFixture
) -> None:
    """MAVProxy first asks for @PARAM/param.pck (ArduPilot's parameter file); the answer is
    FileNotFound, after which it lists parameters with PARAM_REQUEST_LIST."""
    from pymavlink import mavftp

    conn = _client(vehicle)
    try:
        ftp = mavftp.MAVFTP(conn, 1, 1)
        assert ftp.read("@PARAM/param.pck", 1000) is None
        # the client's reading of our NAK FileNotFound (not a time-out)
        assert "OpenFileRO failed, file/directory not found" in caplog.text
    finally:
        conn.close()


# -- the page's own client (px4params gui --udp) --------------------------------------------


class CurrentValueEcho(MavlinkParamServer):
    """``mavlink serve`` acknowledging a write as the MAVLink parameter protocol words it
    (mavlink.io/en/services/parameter.html: after PARAM_SET the recipient broadcasts the
    *current* value): a float16 leaf's echo is the value it stores, not the float32 sent."""

    def _echo(self, msg: Any, index: int, stored: Any) -> Any:
        return self._value_msg(index, stored)


@pytest.mark.parametrize("server", [MavlinkParamServer, CurrentValueEcho])
def test_the_pages_client_writes_a_float16_leaf(
    schema: px4params.Schema, tmp_path: Path, server: type[MavlinkParamServer]
) -> None:
    """The page's MAVLink client takes a float16 leaf's write as acknowledged whether the
    vehicle echoes the float32 sent or the float16 it stores, and reports the stored value;
    another value echoed is still a refusal."""
    from px4params.gui.vehicle import MavlinkVehicle

    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    served = server(store, "127.0.0.1", 0, save_path=tmp_path / "vehicle.store")
    served.start()
    page = None
    try:
        page = MavlinkVehicle(served.address, timeout=10.0)
        result = page.write("INA238_1Q", 0.0005)
        assert (result.ok, result.reason) == (True, "")
        assert result.value == FLOAT16_0_0005  # what is stored, read back
        assert served.store.get("INA238#1.shunt") == FLOAT16_0_0005
        refused = page.write("INA238_1Q", 1e6)  # beyond a float16 too: its @max is said
        assert not refused.ok and refused.value == FLOAT16_0_0005
        assert refused.reason == (
            "INA238_1Q: INA238#1.shunt: 1000000 is outside 0.00001..0.1 (@min/@max)"
        )
    finally:
        if page is not None:
            page.close()
        served.stop()
