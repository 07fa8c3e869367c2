"""The store's one write path (issue 35): every writer changes the file through one transaction,
so that a change made by one (``px4params param set`` in a shell) is never reverted by another
(a server saving what it read at start); changes that collide are refused, naming the leaf;
and a save replaces only a writable regular file, never a FIFO, a device, a directory or a
read-only store, and leaves no temporary file when it fails.

Each defect is reproduced as the audit found it; the soak test with four writers at once is
``test_writers_soak.py``."""

from __future__ import annotations

import fcntl
import os
import socket
import stat
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from px4params.errors import StoreConflictError, StoreFileError
from px4params.links.mavlink import MavlinkParamServer
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.store.flat import write_flat
from px4params.store.session import Session, open_session
from pymavlink.dialects.v20 import common as mavlink
from strategies import budget

ROOT = Path(__file__).resolve().parents[1]
AIRFRAME = ROOT / "examples" / "two_batteries.airframe"
CLI = [sys.executable, "-m", "px4params"]
INT32 = mavlink.MAV_PARAM_TYPE_INT32


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=120, check=False)


def param(store: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return cli("param", "--store", str(store), *args)


@pytest.fixture
def store(tmp_path: Path) -> Path:
    """The example airframe's store: INA238#0 and INA238#1 on I2C, 200 A, 0x45."""
    path = tmp_path / "vehicle.store"
    assert cli("run", str(AIRFRAME), "--store", str(path)).returncode == 0
    return path


def stored(path: Path) -> px4params.Store:
    return px4params.Store.load(path, classic=BUNDLED_CLASSIC)


def wait_for(condition: object, timeout: float = 20.0) -> bool:
    """Polls ``condition()`` until true; False after ``timeout`` (a bound for "never")."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():  # type: ignore[operator]
            return True
        time.sleep(0.05)
    return False


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


# -- lost updates while a server runs -----------------------------------------------------------


@pytest.fixture
def mavlink_served(store: Path) -> Iterator[tuple[MavlinkParamServer, object, list[str]]]:
    from test_mavlink import Client

    lines: list[str] = []
    session = open_session(str(store), None)
    server = MavlinkParamServer(
        session.store, "127.0.0.1", 0, session=session, log=lines.append
    ).start()
    client = Client(server.address[1])
    client.read("INA238_0P")  # the server knows this peer from now on
    yield server, client, lines
    client.close()
    server.stop()


def test_a_cli_write_survives_mavlink_serve_and_its_peer_is_told(
    store: Path, mavlink_served: tuple[MavlinkParamServer, object, list[str]]
) -> None:
    """The audit: 19 of 100 CLI writes lost against ``mavlink serve`` (it saved what it read
    at start, without the lock)."""
    from test_mavlink import value_of

    _, client, _ = mavlink_served
    assert param(store, "set", "INA238#0.current", "300").returncode == 0
    # The ground station is told, without asking: PARAM_VALUE of the flat name.
    told = client.expect(  # type: ignore[attr-defined]
        "PARAM_VALUE", timeout=10, where=lambda m: m.param_id == "INA238_0P"
    )
    assert value_of(told) == 300
    client.set("INA238_1C", 0x46, INT32)  # type: ignore[attr-defined]
    client.expect("PARAM_VALUE", where=lambda m: m.param_id == "INA238_1C")  # type: ignore[attr-defined]
    after = stored(store)
    assert after.get("INA238#0.current") == 300  # the shell's change is still there
    assert after.get("INA238#1.bus.i2c.address") == 0x46


def test_mavlink_serve_saves_under_the_lock(
    store: Path, mavlink_served: tuple[MavlinkParamServer, object, list[str]]
) -> None:
    """While another writer holds the store's lock, an accepted PARAM_SET waits for it."""
    _, client, _ = mavlink_served
    before = store.read_bytes()
    with open(str(store) + ".lock", "a") as lock:
        fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
        client.set("INA238_1C", 0x47, INT32)  # type: ignore[attr-defined]
        time.sleep(1.0)  # the server has the message; it must not save while the lock is held
        assert store.read_bytes() == before
    client.expect("PARAM_VALUE", where=lambda m: m.param_id == "INA238_1C")  # type: ignore[attr-defined]
    assert stored(store).get("INA238#1.bus.i2c.address") == 0x47


def test_a_leaf_changed_by_both_is_refused_over_mavlink(store: Path) -> None:
    """A ground station writes a leaf that the shell changed since the server last read the
    file (the server looks only once here): refused, naming the leaf; the shell's value
    stays and the ground station is shown it."""
    from test_mavlink import Client, value_of

    lines: list[str] = []
    session = open_session(str(store), None)
    server = MavlinkParamServer(
        session.store, "127.0.0.1", 0, session=session, log=lines.append, poll_interval=1e9
    ).start()
    client = Client(server.address[1])
    try:
        client.read("INA238_1C")
        assert param(store, "set", "INA238#1.bus.i2c.address", "0x50").returncode == 0
        client.set("INA238_1C", 0x46, INT32)
        got = client.collect(2.0)
    finally:
        client.close()
        server.stop()
    assert [e.param_id for e in got if e.get_type() == "PARAM_ERROR"] == ["INA238_1C"]
    assert Client.text(got) == [
        f"INA238_1C: INA238#1.bus.i2c.address was changed here and by another writer since "
        f"this writer read {store}; nothing was saved"
    ]
    # The ground station is shown the value that stays: the shell's.
    shown = [
        value_of(m) for m in got if m.get_type() == "PARAM_VALUE" and m.param_id == "INA238_1C"
    ]
    assert shown and shown[-1] == 0x50
    assert stored(store).get("INA238#1.bus.i2c.address") == 0x50
    assert any(line.startswith("refused: INA238_1C: INA238#1.bus.i2c.address") for line in lines)


def test_a_cli_write_survives_gui_writes_and_an_added_instance_stays(store: Path) -> None:
    """The audit: 100% of CLI writes lost at the page's next write, and an instance added
    from the shell deleted by the next unrelated write."""
    from px4params.gui.vehicle import StoreVehicle

    vehicle = StoreVehicle(str(store), None, [])
    events: list[dict[str, object]] = []
    vehicle.listen(events.append)
    try:
        assert param(store, "set", "INA238#0.current", "300").returncode == 0
        assert param(store, "add", "INA238#3").returncode == 0
        # The page is told (its WebSocket gets the values) ...
        assert wait_for(lambda: vehicle.values.get("INA238_0P") == 300)
        assert wait_for(lambda: any(e.get("kind") == "values" for e in events))
        # ... and its own writes keep the shell's.
        result = vehicle.write("INA238_1P", 250)
        assert result.ok, result.reason
    finally:
        vehicle.close()
    after = stored(store)
    assert after.get("INA238#0.current") == 300
    assert after.get("INA238#1.current") == 250
    assert after.instances("INA238") == ["INA238#0", "INA238#1", "INA238#3"]


def test_an_instance_added_from_the_shell_survives_a_stale_mask_write(store: Path) -> None:
    """A writer that has not seen INA238#3 yet adds INA238#2 through the mask (bits 0, 1, 2):
    its change is 'add #2', not 'exactly #0..#2'."""
    session = open_session(str(store), None)
    assert param(store, "add", "INA238#3").returncode == 0
    session.commit(lambda: write_flat(session.store, "INA238_INST", 0b0111))
    assert stored(store).instances("INA238") == [f"INA238#{n}" for n in range(4)]


def _getset(peer: Any, name: bytes, value: int | None = None) -> Any:
    """GetSet by name (a write when ``value`` is given), with time for a loaded machine."""
    from test_dronecan import GETSET

    request = GETSET.Request(name=name)
    if value is not None:
        request.value = dronecan.uavcan.protocol.param.Value(integer_value=value)
    return peer.call(request, timeout=10.0)


def _save(peer: Any) -> Any:
    from test_dronecan import OPCODE

    return peer.call(OPCODE.Request(opcode=OPCODE.Request().OPCODE_SAVE), timeout=10.0)


def test_a_cli_write_survives_a_dronecan_save(store: Path) -> None:
    """The audit: 100% of CLI writes lost at DroneCAN's SAVE. The node's view follows the file
    too: GetSet answers with the shell's value within a second."""
    from dronecan_bus import served
    from test_dronecan import Peer, _field

    with served(store) as pty:
        peer = Peer(pty)
        try:
            _getset(peer, b"INA238_1_CURRENT", 150)  # unsaved until SAVE
            assert param(store, "set", "INA238#0.current", "300").returncode == 0
            assert wait_for(
                lambda: _field(_getset(peer, b"INA238_0_CURRENT").value) == ("integer_value", 300)
            )
            assert _field(_getset(peer, b"INA238_1_CURRENT").value) == ("integer_value", 150)
            assert _save(peer).ok
        finally:
            peer.close()
    after = stored(store)
    assert after.get("INA238#0.current") == 300
    assert after.get("INA238#1.current") == 150


def test_a_dronecan_save_of_a_leaf_the_shell_changed_is_refused(store: Path) -> None:
    from dronecan_bus import served
    from test_dronecan import Peer, _field

    with served(store) as pty:
        peer = Peer(pty)
        try:
            _getset(peer, b"INA238_1_CURRENT", 150)
            assert param(store, "set", "INA238#1.current", "160").returncode == 0
            assert not _save(peer).ok
            # refused whole: the node shows the file's value again
            assert _field(_getset(peer, b"INA238_1_CURRENT").value) == ("integer_value", 160)
        finally:
            peer.close()
    assert stored(store).get("INA238#1.current") == 160
    output = served.output  # type: ignore[attr-defined]
    assert (
        f"refused: save: INA238#1.current was changed here and by another writer since this "
        f"writer read {store}; nothing was saved; the node's values are the file's again\n"
    ) in output


# -- the transaction, writer against writer ------------------------------------------------------


def test_two_sessions_changing_different_leaves_keep_both(store: Path) -> None:
    first, second = open_session(str(store), None), open_session(str(store), None)
    first.store.set("INA238#0.current", 300)
    first.save()
    second.store.set("INA238#0.bus.i2c.address", 0x50)
    second.store.set_default("INA238#1.shunt", 0.001)
    second.save()
    after = stored(store)
    assert after.get("INA238#0.current") == 300
    assert after.get("INA238#0.bus.i2c.address") == 0x50
    assert after.leaf("INA238#1.shunt", default=True).value == pytest.approx(0.001, rel=1e-3)
    assert second.store.get("INA238#0.current") == 300  # the writer now holds the latest


def test_two_sessions_changing_one_leaf_the_second_is_refused(store: Path) -> None:
    first, second = open_session(str(store), None), open_session(str(store), None)
    first.store.set("INA238#0.current", 300)
    first.save()
    saved = store.read_bytes()
    second.store.set("INA238#0.current", 310)
    second.store.set("INA238#1.current", 311)
    with pytest.raises(StoreConflictError) as refused:
        second.save()
    assert str(refused.value) == (
        f"INA238#0.current was changed here and by another writer since this writer read "
        f"{store}; nothing was saved"
    )
    assert store.read_bytes() == saved
    # The same value from both is no conflict.
    third = open_session(str(store), None)
    first.store.set("SYS_AUTOSTART", 4001)
    first.save()
    third.store.set("SYS_AUTOSTART", 4001)
    third.save()


def test_an_edit_of_an_instance_another_writer_removed_is_refused(store: Path) -> None:
    editing, removing = open_session(str(store), None), open_session(str(store), None)
    removing.store.remove("INA238#1")
    removing.save()
    with pytest.raises(StoreConflictError, match=r"^INA238#1 was removed by another writer but "):
        editing.commit(lambda: editing.store.set("INA238#1.current", 100))
    assert "INA238#1" not in stored(store)
    assert editing.store.get("INA238#1.current") == 200  # the refused change is undone


def test_a_variant_switched_here_keeps_a_leaf_changed_there(store: Path) -> None:
    here, there = open_session(str(store), None), open_session(str(store), None)
    there.store.set("INA238#1.current", 300)
    there.save()
    here.commit(lambda: here.store.set("INA238#1.bus._tag", 1))  # SPI
    after = stored(store)
    assert after.get("INA238#1.current") == 300
    assert "spi" in after.get("INA238#1")["bus"]


#: What a writer may do to one instance of INA238 (k), in the property below, by the part of
#: the value it changes: its current, its bus, or the whole instance (a default set is the
#: whole instance's: the value follows it only while no leaf of the value differs).
EDITS = {
    "current": [lambda k, v: ("set", f"INA238#{k}.current", v % 1024)],
    "bus": [
        lambda k, v: ("set", f"INA238#{k}.bus.i2c.address", v % 128),
        lambda k, v: ("set", f"INA238#{k}.bus._tag", 1),  # SPI: another shape
    ],
    "whole": [
        lambda k, v: ("set-default", f"INA238#{k}.current", v % 1024),
        lambda k, v: ("remove", f"INA238#{k}", None),
        lambda k, v: ("add", f"INA238#{k}", None),
    ],
}


def _apply(store: px4params.Store, edits: list[tuple[str, str, int | None]]) -> None:
    for verb, name, value in edits:
        try:
            if verb == "set":
                store.set(name, value)
            elif verb == "set-default":
                store.set_default(name, value)
            elif verb == "remove":
                store.remove(name)
            else:
                store.add(name)
        except px4params.Px4ParamsError:
            pass  # (an edit of a removed instance, an instance added twice: skipped)


@st.composite
def two_writers(draw: st.DrawFn) -> tuple[list[tuple[str, str, int | None]], ...]:
    """Two writers' edits of INA238's instances: an instance is either one writer's (any
    edit), or split (one writer changes its current, the other its bus)."""
    edits: list[list[tuple[str, str, int | None]]] = [[], []]
    owners = []
    for _ in range(4):
        if draw(st.booleans()):
            writer = draw(st.sampled_from([0, 1]))
            owners.append({part: writer for part in EDITS})
        else:
            writer = draw(st.sampled_from([0, 1]))
            owners.append({"current": writer, "bus": 1 - writer})
    for _ in range(draw(st.integers(1, 10))):
        k = draw(st.integers(0, 3))
        part = draw(st.sampled_from(sorted(owners[k])))
        edit = draw(st.sampled_from(EDITS[part]))
        edits[owners[k][part]].append(edit(k, draw(st.integers(0, 5000))))
    return edits[0], edits[1]


@settings(max_examples=budget(25), deadline=None)
@given(edits=two_writers())
def test_writers_of_disjoint_parts_lose_nothing(
    schema: px4params.Schema, tmp_path_factory: pytest.TempPathFactory, edits: Any
) -> None:
    """Two writers read the file, each changes its own instances or its own part of a shared
    one (values, defaults, a union variant, removing and adding), one saves, then the other:
    the file holds both writers' changes, as if they had written one after the other."""
    mine, theirs = edits
    path = tmp_path_factory.mktemp("disjoint") / "vehicle.store"
    start = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    start.add("INA238#0")
    start.add("INA238#1")
    start.save(path)
    first, second = open_session(str(path), None), open_session(str(path), None)
    _apply(first.store, mine)
    first.save()
    _apply(second.store, theirs)
    second.save()
    expected = stored(path.with_name("vehicle.store.bak"))  # what the first one saved
    _apply(expected, theirs)
    final = stored(path)
    assert list(final.names()) == list(expected.names())
    for name in final.names():
        assert final.encoded(name) == expected.encoded(name), name
        assert final.encoded(name, default=True) == expected.encoded(name, default=True), name


# -- files the store never touches --------------------------------------------------------------


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _socket(path: Path) -> Path:
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.bind(str(path))
    sock.close()
    return path


def _directory(path: Path) -> Path:
    path.mkdir()
    return path


@pytest.mark.parametrize(
    ("make", "kind"),
    [(_fifo, "a FIFO"), (_socket, "a socket"), (_directory, "a directory")],
    ids=["fifo", "socket", "directory"],
)
@pytest.mark.parametrize("verb", ["save", "export"])
def test_save_and_export_refuse_what_is_not_a_regular_file(
    store: Path, tmp_path: Path, make: object, kind: str, verb: str
) -> None:
    """The audit: ``param save FIFO`` replaced the FIFO with a regular file (and moved it to
    FIFO.bak)."""
    target = make(tmp_path / ("x.params" if verb == "export" else "x.store"))  # type: ignore[operator]
    mode = os.lstat(target).st_mode
    result = param(store, verb, str(target))
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {target}: cannot write: {kind}, not a regular file\n"
    )
    assert os.lstat(target).st_mode == mode
    assert not Path(str(target) + ".bak").exists()
    assert leftovers(tmp_path) == []


def test_save_refuses_a_device_node(store: Path, tmp_path: Path) -> None:
    """The audit: as root, ``param save /dev/full`` replaced the machine's /dev/full. The same
    device (1, 7) made here, so that the test never risks the real one."""
    device = tmp_path / "full"
    try:
        os.mknod(device, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    except PermissionError:
        pytest.skip("making a device node needs root (CAP_MKNOD)")
    result = param(store, "save", str(device))
    assert result.stderr == (
        f"px4params: error: {device}: cannot write: a character device, not a regular file\n"
    )
    assert stat.S_ISCHR(os.lstat(device).st_mode)
    assert leftovers(tmp_path) == []


def test_a_symbolic_link_loop_is_one_error_as_target_and_as_store(
    store: Path, tmp_path: Path
) -> None:
    loop = tmp_path / "loop.store"
    loop.symlink_to(loop.name)
    saved = param(store, "save", str(loop))
    assert saved.returncode == 1
    assert saved.stderr == (
        f"px4params: error: {loop}: cannot write: Too many levels of symbolic links\n"
    )
    used = param(loop, "set", "INA238#0.current", "300")
    assert used.returncode == 1
    assert used.stderr == (
        f"px4params: error: {loop}: cannot read: Too many levels of symbolic links\n"
    )
    assert loop.is_symlink() and leftovers(tmp_path) == []


def test_a_read_only_store_is_refused_not_replaced(store: Path) -> None:
    """The audit: a 0444 store was silently replaced (and kept mode 0444). Root may write it;
    its mode still says read-only."""
    store.chmod(0o444)
    before = store.read_bytes()
    inode = store.stat().st_ino
    result = param(store, "set", "INA238#0.current", "300")
    assert result.returncode == 1
    assert result.stderr == f"px4params: error: {store}: cannot write: read-only\n"
    assert store.read_bytes() == before and store.stat().st_ino == inode
    assert leftovers(store.parent) == []


def test_a_lock_that_cannot_be_taken_is_an_error(store: Path) -> None:
    """The audit: a lock file that could not be opened (a directory) was skipped."""
    lock = Path(str(store) + ".lock")
    if lock.exists():
        lock.unlink()
    lock.mkdir()
    before = store.read_bytes()
    result = param(store, "set", "INA238#0.current", "300")
    assert result.returncode == 1
    assert result.stderr == f"px4params: error: {lock}: cannot lock the store: Is a directory\n"
    assert store.read_bytes() == before
    # Reading needs no lock.
    shown = param(store, "show", "-q", "INA238#0.current")
    assert shown.returncode == 0 and shown.stdout == "200\n"
    # In-process, the same.
    with pytest.raises(StoreFileError, match="cannot lock the store: Is a directory"):
        Session(stored(store), str(store)).save()


def test_a_lock_that_is_a_fifo_is_refused_without_hanging(store: Path) -> None:
    lock = Path(str(store) + ".lock")
    if lock.exists():
        lock.unlink()
    os.mkfifo(lock)
    result = param(store, "set", "INA238#0.current", "300")
    assert result.stderr == (
        f"px4params: error: {lock}: cannot lock the store: not a regular file\n"
    )


def test_a_backup_that_is_a_directory_is_named_and_nothing_is_left(store: Path) -> None:
    """The audit: with FILE.bak a directory every save failed naming the wrong file and left
    ``FILE.bak.PID.tmp`` behind."""
    backup = Path(str(store) + ".bak")
    if backup.exists():
        backup.unlink()
    backup.mkdir()
    before = store.read_bytes()
    result = param(store, "set", "INA238#0.current", "300")
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {backup}: cannot keep the previous save here: a directory, not a "
        "regular file\n"
    )
    assert store.read_bytes() == before
    assert leftovers(store.parent) == []


def test_threads_of_one_process_take_turns(store: Path) -> None:
    """The lock keeps this process's threads apart too (flock is one per process): four
    threads, each its own leaf, ten writes each, none lost."""
    leaves = [f"INA238#{n}.{leaf}" for n in (0, 1) for leaf in ("current", "bus.i2c.bus_id")]
    sessions = [open_session(str(store), None) for _ in leaves]
    errors: list[BaseException] = []

    def write(session: Session, leaf: str) -> None:
        try:
            for value in range(1, 11):
                session.commit(lambda value=value: session.store.set(leaf, value))
        except BaseException as e:  # collected for the assertion below
            errors.append(e)

    pairs = zip(sessions, leaves, strict=True)
    threads = [threading.Thread(target=write, args=pair) for pair in pairs]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not errors, errors
    after = stored(store)
    assert {leaf: after.get(leaf) for leaf in leaves} == dict.fromkeys(leaves, 10)
