"""The store's session (store/session.py) where test_session_write_path.py leaves it open: what a
session made by a server (``Session(store, path)``) takes the file to be, where a batch's output
goes, and that a run that changes nothing leaves the store file (and its backup) alone."""

from __future__ import annotations

import fcntl
import io
import os
from collections.abc import Callable
from pathlib import Path

import px4params
import pytest
from px4params.nsh.airframe import run_file
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.store.session import Session, open_session


@pytest.fixture
def store_file(schema: px4params.Schema, tmp_path: Path) -> Path:
    """A store with INA238#0, saved twice: the file and its backup (``FILE.bak``) differ."""
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("INA238#0")
    path = tmp_path / "vehicle.store"
    store.save(path)
    store.set("INA238#0.current", 150)
    store.save(path)
    return path


def _lock_is_free(store_file: Path) -> bool:
    """Whether another open file of the store's lock could take it now (flock is per open
    file, so this works within one process too)."""
    with open(f"{store_file}.lock", "a") as other:
        try:
            fcntl.flock(other.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        fcntl.flock(other.fileno(), fcntl.LOCK_UN)
        return True


def test_a_server_session_takes_the_file_as_it_is_now(
    schema: px4params.Schema, store_file: Path
) -> None:
    """``Session(store, path)`` (how mavlink serve and dronecan serve make theirs) starts from
    the file as it is: with no other writer, poll() finds nothing new."""
    store = px4params.Store.load(store_file, classic=BUNDLED_CLASSIC)
    session = Session(store, str(store_file))
    assert session.poll() is False
    # another writer saves: now poll() notices, once
    other = open_session(str(store_file), None)
    other.store.set("INA238#0.current", 175)
    other.save()
    assert session.poll() is True
    assert store.get("INA238#0.current") == 175
    assert session.poll() is False


def test_a_session_opened_on_a_file_takes_it_as_read(store_file: Path) -> None:
    session = open_session(str(store_file), None)
    assert session.poll() is False
    session.store.set("INA238#0.current", 160)
    session.save()
    assert session.poll() is False  # its own save is not another writer's


def test_a_batch_prints_to_the_sessions_output(
    schema: px4params.Schema, store_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = tmp_path / "hello.txt"
    script.write_text("echo hello from the file\n")
    out = io.StringIO()
    store = px4params.Store.load(store_file, classic=BUNDLED_CLASSIC)
    session = Session(store, str(store_file), out)
    result = run_file(str(script), session, keep_going=False, err=io.StringIO())
    assert result.errors == []
    assert out.getvalue() == "hello from the file\n"
    assert capsys.readouterr().out == ""


def test_a_file_that_changes_nothing_leaves_the_store_and_its_backup_alone(
    store_file: Path, tmp_path: Path
) -> None:
    """Saving nothing new would still replace the file and turn the backup of the last real
    save (``FILE.bak``) into a copy of the file: the way back would be lost."""
    script = tmp_path / "nothing.txt"
    script.write_text("# only a comment\necho nothing to change\nparam show -q INA238#0.current\n")
    backup = Path(f"{store_file}.bak")
    before = (os.stat(store_file).st_ino, store_file.read_bytes(), backup.read_bytes())
    session = open_session(str(store_file), None, out=io.StringIO())
    result = run_file(str(script), session, keep_going=False, err=io.StringIO())
    assert result.errors == []
    assert (os.stat(store_file).st_ino, store_file.read_bytes(), backup.read_bytes()) == before


def test_a_batch_saves_its_changes_once_at_its_end(store_file: Path, tmp_path: Path) -> None:
    script = tmp_path / "change.txt"
    script.write_text("param set INA238#0.current 180\nparam set INA238#0.current 190\n")
    session = open_session(str(store_file), None, out=io.StringIO())
    result = run_file(str(script), session, keep_going=False, err=io.StringIO())
    assert result.errors == []
    saved = px4params.Store.load(store_file, classic=BUNDLED_CLASSIC)
    assert saved.get("INA238#0.current") == 190
    # one save: the backup is the file as it was before the run (150), not a middle state
    backup = px4params.Store.load(f"{store_file}.bak", classic=BUNDLED_CLASSIC)
    assert backup.get("INA238#0.current") == 150


def test_a_removed_store_file_leaves_a_servers_values_alone(store_file: Path) -> None:
    """poll() reads other writers' saves; a file someone removed is no save: the running
    values stay. A change saved after it is one to an instance the other writer removed
    (the class's rule): refused, nothing written."""
    from px4params.errors import StoreConflictError

    session = open_session(str(store_file), None)
    os.remove(store_file)
    assert session.poll() is False
    assert session.store.get("INA238#0.current") == 150
    with pytest.raises(StoreConflictError, match=r"^INA238#0 was removed by another writer"):
        session.commit(lambda: session.store.set("INA238#0.current", 170))
    assert session.store.get("INA238#0.current") == 150
    assert not store_file.exists()
    # A save now is this session's change (INA238#1 added) on top of the removed file's
    # (nothing); removed again after that save of its own, the running values stay too.
    session.store.add("INA238#1")
    session.save()
    assert session.store.instances("INA238") == ["INA238#1"]
    os.remove(store_file)
    assert session.poll() is False
    assert session.store.instances("INA238") == ["INA238#1"]


def test_a_store_file_that_cannot_be_read_is_said_once_per_error(
    store_file: Path, tmp_path: Path
) -> None:
    """A server polls often: an unreadable file (here a symbolic link loop) is reported
    once, not at every poll, and again after it was readable in between."""
    from px4params.errors import StoreFileError

    link = tmp_path / "link.store"
    link.symlink_to(store_file)
    session = open_session(str(link), None)
    assert session.poll() is False

    def loop() -> None:
        link.unlink()
        link.symlink_to(link)

    def mend() -> None:
        link.unlink()
        link.symlink_to(store_file)

    loop()
    with pytest.raises(StoreFileError) as said:
        session.poll()
    assert str(said.value) == f"{link}: cannot read: Too many levels of symbolic links"
    assert session.poll() is False
    assert session.poll() is False
    mend()
    assert session.poll() is False  # the same file as before: nothing new
    loop()
    with pytest.raises(StoreFileError):
        session.poll()


def test_a_conflict_found_by_poll_is_said_once_per_version_of_the_file(store_file: Path) -> None:
    """A server's unsaved change and another writer's save of the same leaf: poll() raises
    the conflict once for that version of the file and leaves the store as it was."""
    from px4params.errors import StoreConflictError

    server = open_session(str(store_file), None)
    server.store.set("INA238#0.current", 160)  # not saved yet
    other = open_session(str(store_file), None)
    other.store.set("INA238#0.current", 170)
    other.save()
    with pytest.raises(StoreConflictError, match=r"^INA238#0.current was changed here and by "):
        server.poll()
    assert server.store.get("INA238#0.current") == 160
    assert server.poll() is False  # the same version: not said again
    other.store.set("INA238#0.current", 171)
    other.save()
    with pytest.raises(StoreConflictError):
        server.poll()  # a new version, still in conflict: said again


def test_reload_takes_the_file_as_it_is_dropping_unsaved_changes(store_file: Path) -> None:
    """DroneCAN's OpCode LOAD: the file's content replaces the running values."""
    session = open_session(str(store_file), None)
    session.store.set("INA238#0.current", 160)  # not saved
    other = open_session(str(store_file), None)
    other.store.add("INA238#1")
    other.save()
    session.reload()
    assert session.store.get("INA238#0.current") == 150
    assert session.store.instances("INA238") == ["INA238#0", "INA238#1"]
    assert session.poll() is False  # what it read is now its view of the file


def test_rewrite_changes_the_file_and_leaves_the_running_values(store_file: Path) -> None:
    """DroneCAN's OpCode ERASE: the file's latest content, changed, is saved; the running
    values (and the session's unsaved changes) stay until the next restart."""
    session = open_session(str(store_file), None)
    session.store.set("INA238#0.current", 160)  # not saved
    other = open_session(str(store_file), None)
    other.store.add("INA238#1")
    other.save()
    session.rewrite(lambda store: store.set("INA238#0.current", 120))
    saved = px4params.Store.load(store_file, classic=BUNDLED_CLASSIC)
    assert saved.get("INA238#0.current") == 120
    assert saved.instances("INA238") == ["INA238#0", "INA238#1"]  # the other's save is kept
    assert session.store.get("INA238#0.current") == 160
    assert session.store.instances("INA238") == ["INA238#0"]
    assert session.poll() is False  # its own save is not another writer's


def test_after_a_rewrite_another_writers_save_is_merged_under_the_running_values(
    store_file: Path,
) -> None:
    session = open_session(str(store_file), None)
    session.store.set("INA238#0.current", 160)  # not saved
    session.rewrite(lambda store: store.set("INA238#0.current", 120))
    other = open_session(str(store_file), None)
    assert other.store.get("INA238#0.current") == 120
    other.store.set("INA238#0.bus.i2c.address", 0x46)
    other.save()
    assert session.poll() is True
    assert session.store.get("INA238#0.bus.i2c.address") == 0x46
    assert session.store.get("INA238#0.current") == 160  # its own unsaved change stays


def test_a_store_path_that_is_a_fifo_is_refused_without_waiting_for_a_writer(
    tmp_path: Path,
) -> None:
    """Opening a FIFO for reading waits for a writer unless it is opened non-blocking: the
    store must be refused at once (a bound of 20 s stands for "never")."""
    import threading

    from px4params.errors import StoreFileError

    fifo = tmp_path / "vehicle.store"
    os.mkfifo(fifo)
    outcome: list[BaseException | None] = []

    def open_it() -> None:
        try:
            open_session(str(fifo), None)
            outcome.append(None)
        except BaseException as e:  # handed to the test's thread
            outcome.append(e)

    worker = threading.Thread(target=open_it, daemon=True)
    worker.start()
    worker.join(20)
    if worker.is_alive():
        with open(fifo, "wb"):  # lets the blocked open go on, so the thread can end
            pass
        worker.join(20)
        pytest.fail("opening a store that is a FIFO waited for a writer")
    (error,) = outcome
    assert isinstance(error, StoreFileError)
    assert str(error) == f"{fifo}: cannot read: is a FIFO (named pipe), not a regular file"


def test_a_files_identity_reads_its_content_up_to_16_mib(tmp_path: Path) -> None:
    """Two saves within one clock tick on a reused inode differ only in content: a store
    (kilobytes) is told apart by it; files over 16 MiB (never a store) by status alone."""
    from px4params.store.session import file_identity

    path = tmp_path / "big"
    data = bytes(range(256)) * (1 << 16)  # 16 MiB exactly
    path.write_bytes(data)
    identity = file_identity(str(path))
    assert identity is not None and identity[5] == hash(data)
    path.write_bytes(data + b"!")
    larger = file_identity(str(path))
    assert larger is not None and larger[2] == len(data) + 1 and larger[5] != hash(data + b"!")


def test_a_file_that_fails_while_being_read_is_named_with_the_systems_reason() -> None:
    """/proc/self/mem opens as a regular file but reading its first page fails (EIO): the
    error names the file and the reason, as every other unreadable store."""
    from px4params.errors import StoreFileError
    from px4params.store.session import file_identity

    if not os.path.exists("/proc/self/mem"):
        pytest.skip("no /proc/self/mem here (Linux's procfs)")
    with pytest.raises(StoreFileError) as refused:
        file_identity("/proc/self/mem")
    assert str(refused.value) == "/proc/self/mem: cannot read: Input/output error"


def _refusal(
    store_file: Path,
    here: Callable[[px4params.Store], object],
    there: Callable[[px4params.Store], object],
) -> str:
    """The conflict message when this writer does ``here`` and another writer, saving first,
    did ``there`` (each a function of a Store); the file keeps the other writer's save."""
    from px4params.errors import StoreConflictError

    session, other = open_session(str(store_file), None), open_session(str(store_file), None)
    there(other.store)
    other.save()
    saved = store_file.read_bytes()
    with pytest.raises(StoreConflictError) as refused:
        session.commit(lambda: here(session.store))
    assert store_file.read_bytes() == saved
    return str(refused.value)


def test_an_instance_removed_here_but_changed_there_is_refused(store_file: Path) -> None:
    message = _refusal(
        store_file,
        lambda s: s.remove("INA238#0"),
        lambda s: s.set("INA238#0.current", 175),
    )
    assert message == (
        f"INA238#0 was removed here but changed by another writer since this writer read "
        f"{store_file}; nothing was saved"
    )


def test_a_default_changed_by_both_is_refused_naming_the_default(store_file: Path) -> None:
    message = _refusal(
        store_file,
        lambda s: s.set_default("INA238#0.current", 120),
        lambda s: s.set_default("INA238#0.current", 130),
    )
    assert message == (
        f"default of INA238#0.current was changed here and by another writer since this "
        f"writer read {store_file}; nothing was saved"
    )


def _set_both(store: px4params.Store, current: int, address: int) -> None:
    store.set("INA238#0.current", current)
    store.set("INA238#0.bus.i2c.address", address)


def test_several_conflicts_are_counted_after_the_first(store_file: Path) -> None:
    two = _refusal(store_file, lambda s: _set_both(s, 160, 0x46), lambda s: _set_both(s, 170, 0x47))
    # the first in the value's leaf order (the bus before the current), then how many more
    assert two == (
        f"INA238#0.bus.i2c.address was changed here and by another writer since this writer read "
        f"{store_file} (and 1 more); nothing was saved"
    )


def test_a_removal_and_a_change_here_both_go_on_top_of_another_writers_save(
    store_file: Path,
) -> None:
    setup = open_session(str(store_file), None)
    setup.store.add("INA238#1")
    setup.save()
    session, other = open_session(str(store_file), None), open_session(str(store_file), None)
    other.store.set("SYS_AUTOSTART", 4001)
    other.save()

    def change() -> None:
        session.store.remove("INA238#0")
        session.store.set("INA238#1.current", 180)

    session.commit(change)
    saved = px4params.Store.load(store_file, classic=BUNDLED_CLASSIC)
    assert saved.instances("INA238") == ["INA238#1"]
    assert saved.get("INA238#1.current") == 180
    assert saved.get("SYS_AUTOSTART") == 4001


def test_a_classic_parameter_changed_by_both_is_refused(store_file: Path) -> None:
    message = _refusal(
        store_file,
        lambda s: s.set("SYS_AUTOSTART", 4001),
        lambda s: s.set("SYS_AUTOSTART", 4002),
    )
    assert message == (
        f"SYS_AUTOSTART was changed here and by another writer since this writer read "
        f"{store_file}; nothing was saved"
    )


def _add_with_current(store: px4params.Store, current: int) -> None:
    store.add("INA238#1")
    store.set("INA238#1.current", current)


def test_an_instance_added_by_both_with_other_values_is_refused(store_file: Path) -> None:
    message = _refusal(
        store_file, lambda s: _add_with_current(s, 160), lambda s: _add_with_current(s, 170)
    )
    assert message == (
        f"INA238#1 was added here and by another writer since this writer read "
        f"{store_file}; nothing was saved"
    )


def test_a_leaf_changed_inside_the_variant_this_writer_replaced_is_refused(
    store_file: Path,
) -> None:
    """The other writer changed the I2C address; this one switched the bus to SPI: the
    address would be lost without a word, so the switch is refused."""
    message = _refusal(
        store_file,
        lambda s: s.set("INA238#0.bus._tag", 1),
        lambda s: s.set("INA238#0.bus.i2c.address", 0x46),
    )
    assert message == (
        f"INA238#0.bus.i2c.address was changed here and by another writer since this writer "
        f"read {store_file}; nothing was saved"
    )


def test_a_leaf_changed_the_same_way_by_both_is_no_conflict(store_file: Path) -> None:
    """Both set the address to 0x46; only this writer changed the current: both kept."""
    session, other = open_session(str(store_file), None), open_session(str(store_file), None)
    other.store.set("INA238#0.bus.i2c.address", 0x46)
    other.save()
    session.store.set("INA238#0.bus.i2c.address", 0x46)
    session.store.set("INA238#0.current", 300)
    session.save()
    saved = px4params.Store.load(store_file, classic=BUNDLED_CLASSIC)
    assert saved.get("INA238#0.bus.i2c.address") == 0x46
    assert saved.get("INA238#0.current") == 300


def test_a_type_ending_in_a_dynamic_array_is_merged_leaf_by_leaf(tmp_path: Path) -> None:
    """A store holds values without the tail array optimisation (DroneCAN's TAO applies to a
    message's last dynamic array only on the wire): merging must read them so. One writer
    changes ``a``, the other the second element of the trailing array: both kept."""
    root = tmp_path / "tst"
    root.mkdir()
    (root / "Tail.1.0.dsdl").write_text(
        "# Tail\n# @max_instances 2\n\nuint4 p_version\nuint8 a\nuint8[<=3] tail\n@sealed\n"
    )
    dsdl = [str(root)]
    schema = px4params.load_schema(dsdl, use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("TAIL#0")
    store.set("TAIL#0", {"a": 1, "tail": [1, 2]})
    path = str(tmp_path / "vehicle.store")
    store.save(path)
    here, there = open_session(path, None, dsdl), open_session(path, None, dsdl)
    there.store.set("TAIL#0.a", 7)
    there.save()
    here.store.set("TAIL#0.tail[1]", 9)
    here.save()
    saved = open_session(path, None, dsdl).store.get("TAIL#0")
    assert (saved["a"], saved["tail"]) == (7, [1, 9])


def test_a_batch_of_a_session_opened_with_an_output_prints_there(
    store_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = tmp_path / "hello.txt"
    script.write_text("echo hello\n")
    out = io.StringIO()
    session = open_session(str(store_file), None, out=out)
    assert run_file(str(script), session, keep_going=False, err=io.StringIO()).errors == []
    assert (out.getvalue(), capsys.readouterr().out) == ("hello\n", "")


def test_the_classic_parameters_given_are_the_ones_used(store_file: Path, tmp_path: Path) -> None:
    """``--classic FILE``: a parameters.json of PX4's format (QGC's component metadata)."""
    classic = tmp_path / "parameters.json"
    classic.write_text(
        '{"version": 1, "parameters": [{"name": "BENCH_ONLY", "type": "Int32", "default": 7}]}'
    )
    session = open_session(str(store_file), str(classic))
    assert session.store.get("BENCH_ONLY") == 7


def test_a_damaged_store_is_refused_with_the_way_back(store_file: Path) -> None:
    """A store that cannot be read is an error naming it (never an empty store that the next
    save would write over it), with the previous save's ``param load`` when there is one."""
    from px4params.errors import StoreFileError

    store_file.write_bytes(b"not a store at all")
    with pytest.raises(StoreFileError) as refused:
        open_session(str(store_file), None)
    backup = f"{store_file}.bak"
    hint = f"; the previous save is in {backup}: px4params param load {backup}"
    assert str(refused.value) == (
        f"{store_file}: not a px4params store file (no PX4P header){hint} (at byte 0)"
    )
    os.remove(backup)
    with pytest.raises(StoreFileError) as without:
        open_session(str(store_file), None)
    assert str(without.value) == (
        f"{store_file}: not a px4params store file (no PX4P header) (at byte 0)"
    )
    # `param load FILE` asks for an empty store instead: the way back
    empty = open_session(str(store_file), None, start_empty_if_unreadable=True).store
    assert empty.instances("INA238") == []


def test_a_store_path_under_a_file_is_an_error_not_a_new_store(store_file: Path) -> None:
    from px4params.errors import StoreFileError

    with pytest.raises(StoreFileError) as refused:
        open_session(f"{store_file}/vehicle.store", None)
    assert str(refused.value) == f"{store_file}/vehicle.store: cannot read: Not a directory"


def test_a_lock_taken_again_by_its_thread_is_held_until_the_outer_block_ends(
    store_file: Path,
) -> None:
    """StoreLock nests: leaving the inner block must not release the file's flock."""
    from px4params.store.session import StoreLock

    with StoreLock(str(store_file)):
        with StoreLock(str(store_file)):
            assert not _lock_is_free(store_file)
        assert not _lock_is_free(store_file)  # the outer block still holds it
    assert _lock_is_free(store_file)


def test_a_locked_session_holds_the_lock_for_its_block_only(store_file: Path) -> None:
    from px4params.store.session import LockedSession

    with LockedSession(str(store_file), None) as session:
        assert session.store.get("INA238#0.current") == 150
        assert not _lock_is_free(store_file)
    assert _lock_is_free(store_file)


def test_a_locked_session_locks_a_new_or_default_store_and_nothing_else(
    store_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A store that is no regular file (a FIFO) is refused as it is read: no FILE.lock beside
    it (/dev/null.lock was made). A store not made yet, or the default one, is locked."""
    from px4params.errors import StoreFileError
    from px4params.store.session import LockedSession

    fifo = tmp_path / "fifo.store"
    os.mkfifo(fifo)
    for odd in (fifo, tmp_path / "vehicle.store" / "inside.store"):  # (a file as a folder)
        with pytest.raises(StoreFileError), LockedSession(str(odd), None):
            pass
        assert not Path(f"{odd}.lock").exists()
    new = tmp_path / "new.store"
    with LockedSession(str(new), None):
        assert not _lock_is_free(new)
    monkeypatch.setenv("PX4PARAMS_STORE", str(store_file))
    with LockedSession(None, None):  # the default store
        assert not _lock_is_free(store_file)
    assert _lock_is_free(store_file)


def test_a_lock_file_that_is_a_symbolic_link_is_refused(store_file: Path, tmp_path: Path) -> None:
    """The lock is opened without following a link: a link planted at FILE.lock (to a file
    of someone else's) is an error naming it, not a lock taken on the link's target."""
    from px4params.errors import StoreFileError

    elsewhere = tmp_path / "elsewhere"
    elsewhere.write_text("")
    lock = Path(f"{store_file}.lock")
    lock.symlink_to(elsewhere)
    session = open_session(str(store_file), None)
    with pytest.raises(StoreFileError) as refused:
        session.save()
    assert str(refused.value) == f"{lock}: cannot lock the store: Too many levels of symbolic links"


def test_a_lock_the_file_system_cannot_take_is_an_error_and_leaks_nothing(
    store_file: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """flock fails with ENOLCK on an NFS mount without its lock daemon: the save is an error
    naming the lock file and the reason, the store is left as it was, and the lock file's
    descriptor is closed (a long-running page or node would otherwise run out of them)."""
    import errno

    from px4params.errors import StoreFileError

    def no_locks(fd: int, operation: int) -> None:
        raise OSError(errno.ENOLCK, os.strerror(errno.ENOLCK))

    before = store_file.read_bytes()
    session = open_session(str(store_file), None)
    open_fds = len(os.listdir("/proc/self/fd"))
    monkeypatch.setattr(fcntl, "flock", no_locks)
    with pytest.raises(StoreFileError) as refused:
        session.save()
    lock = f"{store_file}.lock"
    assert str(refused.value) == f"{lock}: cannot lock the store: No locks available"
    assert len(os.listdir("/proc/self/fd")) == open_fds
    assert store_file.read_bytes() == before


def test_a_locked_session_of_a_damaged_store_is_an_error(store_file: Path) -> None:
    from px4params.errors import StoreFileError
    from px4params.store.session import LockedSession

    store_file.write_bytes(b"not a store at all")
    with (
        pytest.raises(StoreFileError, match=r"not a px4params store file"),
        LockedSession(str(store_file), None),
    ):
        pass
    assert _lock_is_free(store_file)  # the lock is given back on the error


def _denied_writing_locks(monkeypatch: pytest.MonkeyPatch) -> None:
    """Opening a ``.lock`` file for writing fails as for a user without write access (the
    tests run as root, whom the kernel never refuses); every other open is the real one."""
    real_open = os.open

    def open_as_user(path: str, flags: int, mode: int = 0o777, **kw: object) -> int:
        if str(path).endswith(".lock") and flags & (os.O_RDWR | os.O_WRONLY):
            raise PermissionError(13, "Permission denied", str(path))
        return real_open(path, flags, mode)

    monkeypatch.setattr(os, "open", open_as_user)


def test_a_lock_file_the_user_may_only_read_is_locked_all_the_same(
    store_file: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """flock needs no write access: a lock file made by another user (mode 0644) is opened
    read-only and locked."""
    from px4params.store.session import StoreLock

    Path(f"{store_file}.lock").write_text("")
    _denied_writing_locks(monkeypatch)
    with StoreLock(str(store_file)):
        assert not _lock_is_free(store_file)
    assert _lock_is_free(store_file)


def test_a_lock_file_the_user_may_not_make_is_an_error(
    store_file: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from px4params.errors import StoreFileError
    from px4params.store.session import StoreLock

    lock = Path(f"{store_file}.lock")
    _denied_writing_locks(monkeypatch)
    with pytest.raises(StoreFileError) as refused, StoreLock(str(store_file)):
        pass
    assert str(refused.value) == f"{lock}: cannot lock the store: Permission denied"
    assert not lock.exists()


def test_a_read_only_lock_file_that_is_a_link_is_refused(
    store_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from px4params.errors import StoreFileError
    from px4params.store.session import StoreLock

    elsewhere = tmp_path / "elsewhere"
    elsewhere.write_text("")
    lock = Path(f"{store_file}.lock")
    lock.symlink_to(elsewhere)
    _denied_writing_locks(monkeypatch)
    with pytest.raises(StoreFileError) as refused, StoreLock(str(store_file)):
        pass
    assert str(refused.value) == f"{lock}: cannot lock the store: Permission denied"


@pytest.mark.parametrize("kind", ["directory", "fifo"])
def test_a_read_only_lock_that_is_no_regular_file_is_refused_at_once(
    store_file: Path, monkeypatch: pytest.MonkeyPatch, kind: str
) -> None:
    """Opened read-only (no write access), a FIFO must not wait for a writer and a folder
    must not be locked: each is named (a bound of 20 s stands for "never")."""
    import threading

    from px4params.errors import StoreFileError
    from px4params.store.session import StoreLock

    lock = Path(f"{store_file}.lock")
    if kind == "directory":
        lock.mkdir()
    else:
        os.mkfifo(lock)
    _denied_writing_locks(monkeypatch)
    outcome: list[BaseException | None] = []

    def take() -> None:
        try:
            with StoreLock(str(store_file)):
                outcome.append(None)
        except BaseException as e:  # handed to the test's thread
            outcome.append(e)

    worker = threading.Thread(target=take, daemon=True)
    worker.start()
    worker.join(20)
    if worker.is_alive():
        with open(lock, "wb"):  # lets the blocked open go on, so the thread can end
            pass
        worker.join(20)
        pytest.fail("a read-only FIFO lock waited for a writer")
    (error,) = outcome
    what = "a directory" if kind == "directory" else "not a regular file"
    assert isinstance(error, StoreFileError)
    assert str(error) == f"{lock}: cannot lock the store: {what}"


def test_a_batch_whose_deferred_write_can_no_longer_be_made_saves_nothing(
    store_file: Path, schema: px4params.Schema, tmp_path: Path
) -> None:
    # Checked when asked for and again before the store is saved: the folder went away in
    # between, and the store alone would have been saved with the batch reported as failed.
    store = px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC)
    before = store_file.read_bytes()
    session = Session(store, str(store_file), autosave=False)
    folder = tmp_path / "out"
    folder.mkdir()
    written: list[str] = []
    session.write_later(str(folder / "x.params"), lambda: written.append("x.params"))
    store.add("AK09916#0")
    session.changed = True
    folder.rmdir()
    with pytest.raises(px4params.Px4ParamsError) as e:
        session.save()
    assert str(e.value) == f"{folder}/x.params: cannot write: No such file or directory"
    assert written == [] and store_file.read_bytes() == before


def test_a_batch_write_over_a_file_it_reads_is_refused(
    store_file: Path, schema: px4params.Schema, tmp_path: Path
) -> None:
    store = px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC)
    session = Session(store, str(store_file), autosave=False)
    airframe = tmp_path / "vehicle.airframe"
    airframe.write_text("param add INA238#0\n")
    session.inputs.append(str(airframe))
    link = tmp_path / "link.airframe"
    link.symlink_to(airframe)
    with pytest.raises(px4params.StoreFileError) as refused:
        session.write_later(str(link), lambda: None)
    assert str(refused.value) == (
        f"{link}: is the file this run reads ({airframe}): give it another name"
    )
    assert session.deferred == []


# -- a classic value kept as the other type (store file format 3) ---------------------------------


def _classic_sets(tmp_path: Path) -> tuple[str, str]:
    """Two parameters.json of one parameter whose type changed between PX4 releases."""
    import json

    paths = []
    for name, kind, default in (("today", "Float", 2.0), ("before", "Int32", 2)):
        entry = {"name": "COM_DISARM_LAND", "type": kind, "default": default}
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps({"version": 1, "parameters": [entry]}))
        paths.append(str(path))
    return paths[0], paths[1]


def _kept_by_the_older_set(tmp_path: Path) -> tuple[str, str, Session]:
    """A store saved by today's set with COM_DISARM_LAND 2.5, and a session of the older set,
    which keeps that record (its Int32 cannot take 2.5): (path, today's set, the session)."""
    today, before = _classic_sets(tmp_path)
    path = str(tmp_path / "v.store")
    first = open_session(path, today)
    first.store.set("COM_DISARM_LAND", 2.5)
    first.save()
    return path, today, open_session(path, before)


@pytest.mark.parametrize("theirs", [4.5, None])
def test_a_value_kept_as_the_other_type_changed_by_another_writer_is_a_conflict(
    tmp_path: Path, theirs: float | None
) -> None:
    """A session of the older set holds COM_DISARM_LAND 2.5 as a kept record (its Int32 cannot
    take it) and shows the default. Another writer, of today's set, saves 4.5 (kept here too):
    setting the parameter here would have replaced it unseen."""
    from px4params.errors import StoreConflictError

    path, today, older = _kept_by_the_older_set(tmp_path)
    assert older.store.kept_classic == ["COM_DISARM_LAND"]
    other = open_session(path, today)
    if theirs is None:
        other.store.reset("COM_DISARM_LAND")  # the kept record goes: a change too
    else:
        other.store.set("COM_DISARM_LAND", theirs)
    other.save()
    with pytest.raises(StoreConflictError) as refused:
        older.commit(lambda: older.store.set("COM_DISARM_LAND", 7))
    assert str(refused.value) == (
        f"COM_DISARM_LAND was changed here and by another writer (as the other type) since "
        f"this writer read {path}; nothing was saved"
    )
    expected = 2.0 if theirs is None else theirs
    assert open_session(path, today).store.get("COM_DISARM_LAND") == expected


def test_a_kept_value_set_here_replaces_it_when_the_other_writer_changed_something_else(
    tmp_path: Path,
) -> None:
    path, today, older = _kept_by_the_older_set(tmp_path)
    other = open_session(path, today)
    other.store.add("INA238#0")
    other.save()
    older.commit(lambda: older.store.set("COM_DISARM_LAND", 2))  # its default here
    again = open_session(path, today)
    assert again.store.get("COM_DISARM_LAND") == 2.0 and "INA238#0" in again.store
