"""Four writers at once on one store file, each through its own door (issue 35's must-show):

* ``px4params param set`` loops (one process per write, a loop per leaf) on INA238#0,
* the page's HTTP API (``px4params gui --store``) on INA238#1,
* pymavlink ``PARAM_SET`` against ``px4params mavlink serve --store`` on INA238#2,
* pydronecan GetSet + SAVE against ``px4params dronecan serve --store`` on INA238#3,

each at least 200 distinct writes to its own three leaves (current, I2C bus, I2C address).
Checked: nothing lost (the final file holds every writer's last value of each of its leaves),
every version of the file seen during the run loads, and each server's view follows the file:
the MAVLink peer is shown the other writers' changes (its last PARAM_VALUE of every other
writer's leaf is the final value), the page's values and the DroneCAN node's GetSet answers
are the file's.

Servers bind 127.0.0.1 (the DroneCAN node a pseudo-terminal); every loop and wait is bounded.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from gui_server import GUI_LINE
from px4params.errors import Px4ParamsError
from px4params.links.mavlink import param_set_message, param_value_of
from px4params.store.classic import BUNDLED_CLASSIC
from pymavlink.dialects.v20 import common as mavlink

ROOT = Path(__file__).resolve().parents[1]
AIRFRAME = ROOT / "examples" / "two_batteries.airframe"
CLI = [sys.executable, "-m", "px4params"]
WRITES = 200
#: Each writer's leaves: (path in the instance, flat letter, DroneCAN long-name part, values).
LEAVES = [
    ("current", "P", "CURRENT", 1000),  # uint10
    ("bus.i2c.bus_id", "B", "I2C_BUS_ID", 15),  # uint4
    ("bus.i2c.address", "C", "I2C_ADDRESS", 127),  # uint7
]
#: How long each writer took (shown with -s).
TOOK: dict[str, float] = {}
#: An upper bound for the whole run (a "does not hang"), not a measurement.
DEADLINE = 240.0


def plan(instance: int) -> list[tuple[str, int]]:
    """A writer's writes: ``(leaf path, value)``, cycling over its leaves, each value
    different from the one before it on the same leaf (so that every write is a change)."""
    writes = []
    for n in range(WRITES):
        path, _, _, top = LEAVES[n % len(LEAVES)]
        writes.append((path, (n // len(LEAVES) + instance) % top + 1))
    return writes


def last_values(instance: int) -> dict[str, int]:
    return {path: value for path, value in plan(instance)}


def _env(tmp: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp / "cache"))
    env["PYTHONUNBUFFERED"] = "1"
    return env


class Server:
    """A ``px4params`` server whose output goes to a file (a pipe would fill up and stop it),
    and the first match of ``pattern`` in it."""

    def __init__(self, argv: list[str], pattern: str, tmp: Path, name: str) -> None:
        self.log = tmp / f"{name}.log"
        with open(self.log, "w") as out:
            self.proc = subprocess.Popen(
                [*CLI, *argv], stdout=out, stderr=subprocess.STDOUT, env=_env(tmp), cwd=tmp
            )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            match = re.search(pattern, self.log.read_text())
            if match is not None:
                self.match = match
                return
            if self.proc.poll() is not None:
                break
            time.sleep(0.05)
        self.stop()
        raise AssertionError(f"{name} did not start: {self.log.read_text()[-2000:]}")

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


@pytest.fixture
def store(tmp_path: Path) -> Path:
    path = tmp_path / "vehicle.store"
    env = _env(tmp_path)
    for argv in (
        ["run", str(AIRFRAME), "--store", str(path)],
        ["param", "--store", str(path), "add", "INA238#2"],
        ["param", "--store", str(path), "add", "INA238#3"],
    ):
        subprocess.run([*CLI, *argv], env=env, check=True, capture_output=True, timeout=60)
    return path


@pytest.fixture
def servers(store: Path, tmp_path: Path) -> Iterator[dict[str, Server]]:
    started: dict[str, Server] = {}
    try:
        started["gui"] = Server(
            ["gui", "--store", str(store), "--http", "127.0.0.1:0"],
            GUI_LINE,
            tmp_path,
            "gui",
        )
        started["mavlink"] = Server(
            ["mavlink", "serve", "--udp", "127.0.0.1:0", "--store", str(store)],
            r"on udp 127\.0\.0\.1:(\d+) ",
            tmp_path,
            "mavlink",
        )
        started["dronecan"] = Server(
            ["dronecan", "serve", "--slcan-pty", "--store", str(store)],
            r"slcan: (/dev/\S+)",
            tmp_path,
            "dronecan",
        )
        yield started
    finally:
        for server in started.values():
            server.stop()


# -- the writers ---------------------------------------------------------------------------------


def cli_writer(store: Path, tmp: Path) -> None:
    """``param set`` processes, one leaf's writes after another's, three leaves at once (as
    three shells would)."""
    env = _env(tmp)
    failed: list[str] = []

    def loop(leaf: str) -> None:
        for path, value in plan(0):
            if path != leaf or failed:
                continue
            done = subprocess.run(
                [*CLI, "param", "--store", str(store), "set", f"INA238#0.{path}", str(value)],
                env=env,
                capture_output=True,
                text=True,
                timeout=60,
            )
            if done.returncode != 0:
                failed.append(done.stderr)

    shells = [threading.Thread(target=loop, args=(path,)) for path, *_ in LEAVES]
    for shell in shells:
        shell.start()
    for shell in shells:
        shell.join(timeout=DEADLINE)
    assert not failed and not any(s.is_alive() for s in shells), failed[:1]


def page_writer(url: str, token: str) -> None:
    for path, value in plan(1):
        name = "INA238_1" + next(letter for p, letter, _, _ in LEAVES if p == path)
        body = json.dumps({"changes": [{"name": name, "value": value}]}).encode()
        request = urllib.request.Request(
            url + "api/write",
            data=body,
            headers={"content-type": "application/json", "authorization": f"token {token}"},
        )
        with urllib.request.urlopen(request, timeout=30) as response:
            (result,) = json.load(response)["results"]
        assert result["ok"] and result["value"] == value, result


class MavlinkPeer:
    """A ground station (pymavlink) that writes INA238#2's leaves with PARAM_SET, each answered
    before the next (sent again if UDP lost it), and keeps the last PARAM_VALUE of every name
    it is sent."""

    def __init__(self, port: int) -> None:
        os.environ.setdefault("MAVLINK20", "1")
        from pymavlink import mavutil

        self.conn = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}", source_system=255, source_component=190
        )
        self.beat = 0.0
        self.seen: dict[str, int | float] = {}
        self.told = 0  # PARAM_VALUEs received for other writers' leaves

    def receive(self, timeout: float) -> Any:
        # A heartbeat a second, as ground stations send: the server talks only to peers it
        # heard from in the last few seconds.
        if time.monotonic() - self.beat >= 1.0:
            self.beat = time.monotonic()
            self.conn.mav.heartbeat_send(
                mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0
            )
        msg = self.conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=timeout)
        if msg is not None:
            self.seen[msg.param_id] = param_value_of(msg)
            if not msg.param_id.startswith("INA238_2"):
                self.told += 1
        return msg

    def set(self, name: str, value: int) -> None:
        for _ in range(20):
            self.conn.mav.send(param_set_message(1, 1, name, value, mavlink.MAV_PARAM_TYPE_INT32))
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline:
                msg = self.receive(deadline - time.monotonic())
                if msg is not None and msg.param_id == name and self.seen[name] == value:
                    return
        raise AssertionError(f"{name} = {value}: no PARAM_VALUE answered it")

    def write_all(self, until: threading.Event) -> None:
        """Its writes, then listening (as a ground station does: UDP drops what waits unread
        in a full socket buffer) until ``until`` is set."""
        for path, value in plan(2):
            self.set("INA238_2" + next(letter for p, letter, _, _ in LEAVES if p == path), value)
        while not until.is_set():
            self.receive(0.1)

    def close(self) -> None:
        self.conn.close()


def dronecan_writer(pty: str) -> None:
    from test_dronecan import GETSET, OPCODE, Peer, _field

    peer = Peer(pty)

    def call(request: Any) -> Any:
        """A response, asked again when none came (pydronecan's SLCAN process is slow to
        pass frames on a loaded machine; GetSet of a value and SAVE may be repeated)."""
        for _ in range(5):
            try:
                return peer.call(request, timeout=10.0)
            except AssertionError:  # no response
                continue
        raise AssertionError(f"no response to {type(request).__name__} in 5 tries")

    try:
        for path, value in plan(3):
            name = "INA238_3_" + next(part for p, _, part, _ in LEAVES if p == path)
            request = GETSET.Request(name=name.encode())
            request.value = dronecan.uavcan.protocol.param.Value(integer_value=value)
            assert _field(call(request).value) == ("integer_value", value), name
            assert call(OPCODE.Request(opcode=OPCODE.Request().OPCODE_SAVE)).ok
    finally:
        peer.close()


def dronecan_view(pty: str) -> dict[str, int]:
    """Every writer's leaves as the DroneCAN node answers GetSet (read only)."""
    from test_dronecan import GETSET, Peer, _field

    peer = Peer(pty, node_id=101)
    try:
        view = {}
        for i in range(4):
            for _, _, part, _ in LEAVES:
                name = f"INA238_{i}_{part}"
                view[name] = _field(peer.call(GETSET.Request(name=name.encode()), 10.0).value)[1]
        return view
    finally:
        peer.close()


# -- the run -------------------------------------------------------------------------------------


def run_all(
    writers: dict[str, Callable[[], None]], others_done: threading.Event
) -> dict[str, BaseException]:
    """Runs the writers at once; their exceptions by name. ``others_done`` is set when all
    but the last have finished (the last listens until then)."""
    failed: dict[str, BaseException] = {}

    def run(name: str, write: Callable[[], None]) -> None:
        start = time.monotonic()
        try:
            write()
        except BaseException as e:  # reported by the test
            failed[name] = e
        TOOK[name] = time.monotonic() - start

    threads = [threading.Thread(target=run, args=item, daemon=True) for item in writers.items()]
    for t in threads:
        t.start()
    deadline = time.monotonic() + DEADLINE
    for n, t in enumerate(threads):
        if n == len(threads) - 1:
            others_done.set()
        t.join(timeout=max(0.0, deadline - time.monotonic()))
    for name, t in zip(writers, threads, strict=True):
        if t.is_alive():
            failed[name] = TimeoutError(f"{name} still writing after {DEADLINE:.0f} s")
    return failed


def test_four_writers_lose_nothing(store: Path, servers: dict[str, Server], tmp_path: Path) -> None:
    peer = MavlinkPeer(int(servers["mavlink"].match[1]))
    peer.receive(0.2)  # the server learns of this peer from its heartbeat
    samples: list[bytes] = []
    sampling = threading.Event()

    def sample() -> None:
        while not sampling.is_set():
            try:
                data = store.read_bytes()
            except FileNotFoundError:  # (never: a save replaces the file in one rename)
                data = b""
            if not samples or samples[-1] != data:
                samples.append(data)
            time.sleep(0.02)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    started = time.monotonic()
    others_done = threading.Event()
    failed = run_all(
        {
            "cli": lambda: cli_writer(store, tmp_path),
            "page": lambda: page_writer(servers["gui"].match[1], servers["gui"].match[3]),
            "dronecan": lambda: dronecan_writer(servers["dronecan"].match[1]),
            "mavlink": lambda: peer.write_all(others_done),
        },
        others_done,
    )
    took = time.monotonic() - started
    sampling.set()
    sampler.join(timeout=10)
    assert not failed, {name: repr(e) for name, e in failed.items()}

    # 0 lost: every writer's last value of each of its leaves is in the file.
    final = px4params.Store.load(store, classic=BUNDLED_CLASSIC)
    for instance in range(4):
        got = {path: final.get(f"INA238#{instance}.{path}") for path, *_ in LEAVES}
        assert got == last_values(instance), f"INA238#{instance}"

    # Every version of the file seen while the four wrote loads.
    check = tmp_path / "sample.store"
    for n, data in enumerate(samples):
        check.write_bytes(data)
        try:
            px4params.Store.load(check, classic=BUNDLED_CLASSIC)
        except Px4ParamsError as e:
            raise AssertionError(f"version {n} of {len(samples)} does not load: {e}") from None

    # The MAVLink peer was shown the others' changes: its view of their leaves is the file's.
    expected = {
        f"INA238_{instance}{letter}": final.get(f"INA238#{instance}.{path}")
        for instance in (0, 1, 3)
        for path, letter, _, _ in LEAVES
    }
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline and any(peer.seen.get(k) != v for k, v in expected.items()):
        peer.receive(0.2)
    peer.close()
    assert {k: peer.seen.get(k) for k in expected} == expected
    assert peer.told > 0

    # The page's view (what its WebSocket pushed) and the DroneCAN node's are the file's too.
    flat = {
        f"INA238_{i}{letter}": final.get(f"INA238#{i}.{path}")
        for i in range(4)
        for path, letter, _, _ in LEAVES
    }
    page: dict[str, Any] = {}
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        state = urllib.request.Request(
            servers["gui"].match[1] + "api/state",
            headers={"authorization": f"token {servers['gui'].match[3]}"},
        )
        with urllib.request.urlopen(state, timeout=30) as r:
            page = json.load(r)["values"]
        if all(page.get(k) == v for k, v in flat.items()):
            break
        time.sleep(0.2)
    assert {k: page.get(k) for k in flat} == flat
    assert dronecan_view(servers["dronecan"].match[1]) == {
        f"INA238_{i}_{part}": final.get(f"INA238#{i}.{path}")
        for i in range(4)
        for path, _, part, _ in LEAVES
    }
    assert len(samples) > 20
    print(
        f"\n4 x {WRITES} writes in {took:.1f} s; {len(samples)} versions of the file sampled; "
        f"the MAVLink peer got {peer.told} PARAM_VALUE of other writers' leaves; each "
        f"writer's time: {', '.join(f'{k} {v:.1f} s' for k, v in TOOK.items())}"
    )
