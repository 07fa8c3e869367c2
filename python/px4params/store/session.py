"""A session on the store file, and the file's one write path: every writer (a command or
airframe file, ``gui --store``, ``mavlink serve``, ``dronecan serve``) saves through
:meth:`Session.commit`, which takes the file's lock, reads the file again when another writer
saved since this session read it, puts only this session's changes on top (refusing a leaf
both changed) and saves atomically. A command holds the lock from reading to saving and saves
once when its work succeeded.

Writes to other files asked for during a batch (``param save FILE``, ``param export FILE``) are
deferred until the batch succeeds: a failing airframe file leaves no file half-written.
"""

from __future__ import annotations

import os
import stat
import sys
from collections.abc import Callable, Iterable

from px4params._records import TYPE_CHECKING
from px4params.dsdl.schema import load_schema
from px4params.errors import (
    KeepRunningValues,
    Px4ParamsError,
    StoreConflictError,
    StoreFileError,
)
from px4params.store.classic import BUNDLED_CLASSIC, CLASSIC_ENV
from px4params.store.store import Store, default_store_path

#: The store files this process saved, in order: a command whose output then cannot be
#: written says that its change was kept all the same (px4params.cli.main).
SAVED: list[str] = []

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, TextIO, TypeVar

    T = TypeVar("T")


class Session:
    """The store a writer works on, and the file it is saved to: the one write path.

    Every writer (a ``param`` command or airframe file, ``gui --store``, ``mavlink serve``,
    ``dronecan serve``) changes the file through :meth:`save` or :meth:`commit`, one
    transaction: take the file's lock, re-read the file if another writer replaced it since
    this session read it, put this session's own changes (what differs from what it read) on
    top of the latest content, save atomically, release. A change to a leaf another writer
    changed too since the read (to another value), or to an instance another writer removed,
    is refused with :class:`StoreConflictError`: nothing is merged silently. Servers call
    :meth:`poll` to notice other writers' changes."""

    def __init__(
        self,
        store: Store,
        path: str,
        out: TextIO | None = None,
        *,
        autosave: bool = True,
        identity: FileIdentity | bool | None = True,
    ) -> None:
        self.store = store
        self.path = path
        self.out = out if out is not None else sys.stdout
        #: Save after each changing verb (off while an airframe file runs: it saves once).
        self.autosave = autosave
        self.changed = False
        #: Writes to other files asked for during a batch, done when the batch succeeds:
        #: (the file, the write).
        self.deferred: list[tuple[str, Callable[[], None]]] = []
        #: Files the batch reads (the airframe file): no write of the batch may replace them.
        self.inputs: list[str] = []
        #: The file as this session last read or wrote it (``True``: as it is now), and the
        #: store's content then: this session's own changes are what differs from it.
        self.identity = file_identity(path) if identity is True else identity or None
        self._base = store._native.copy()
        #: The classic records kept unchanged then (``Store.kept_classic``'s): merged too.
        self._base_kept = dict(store._foreign)
        #: The file's identity at a re-read that failed (a conflict): not tried again; and the
        #: error of a file that could not even be looked at, said once.
        self._refused: FileIdentity | None = None
        self._unreadable = ""
        #: The file did not load (``param load FILE``, the way back): its first save keeps the
        #: damaged file as ``FILE.damaged`` and leaves ``FILE.bak``, the last good save, alone.
        self.damaged = False

    def done(self) -> None:
        """Records a change; saves it unless a batch is running."""
        self.changed = True
        if self.autosave:
            self.save()

    def write_later(self, file: str, write: Callable[[], None]) -> None:
        """Writes ``file`` now, or when the batch succeeds: a failed airframe file leaves no
        file behind that it wrote half-way. Refused at once (:func:`check_writable`) where the
        write could be told to fail, or would replace a file the batch reads."""
        from px4params.writing import check_writable, same_file

        for read in self.inputs:
            if same_file(file, read):
                raise StoreFileError(
                    f"is the file this run reads ({read}): give it another name", file
                )
        check_writable(file)
        if self.autosave:
            write()
        else:
            self.deferred.append((file, write))

    def save(self) -> None:
        """Saves this session's changes (the one transaction; see the class), then the
        deferred writes. Their files are checked again first: a batch whose write cannot be
        made saves nothing, rather than the store alone."""
        from px4params.writing import check_writable

        for file, _ in self.deferred:
            check_writable(file)
        self.commit(lambda: None)
        self.changed = False
        for _, write in self.deferred:
            write()
        self.deferred.clear()

    def _save_over_damaged(self) -> None:
        from px4params.store import file as store_file

        aside = self.path + ".damaged"
        try:
            with open(self.path, "rb") as f:
                damaged = f.read()
        except OSError as e:
            raise StoreFileError(f"cannot read: {e.strerror}", self.path) from None
        store_file.write_file(aside, damaged, keep_backup=False)
        store_file.write_file(self.path, store_file.encode_file(self.store), keep_backup=False)
        self.store._native.mark_saved()
        self.damaged = False
        print(
            f"kept the damaged {self.path} as {aside}; {self.path}.bak is unchanged", file=self.out
        )

    def commit(self, change: Callable[[], T]) -> T:
        """Applies ``change`` (a function changing :attr:`store`) and saves, under the lock,
        on top of the file's latest content: all of it or, when anything fails (a conflict,
        a refused value, the disk), nothing, in memory and on disk."""
        with StoreLock(self.path):
            kept = (self.identity, self._base, self._base_kept)
            try:
                with self.store.transaction():
                    result = change()
                    self._merge_latest()
                    if self.damaged:
                        self._save_over_damaged()
                    else:
                        self.store.save(self.path)
            except BaseException as e:
                self.identity, self._base, self._base_kept = kept
                if isinstance(e, StoreConflictError):
                    raise StoreConflictError(f"{e}; nothing was saved") from None
                raise
            self._synced()
        return result

    def poll(self) -> bool:
        """For servers, often (it reads a file of kilobytes): when another writer saved,
        the store becomes its content with this session's unsaved changes on top; returns
        whether that happened. A conflict or an unreadable file is raised once per version of
        the file; the store is then left as it was."""
        try:
            now = file_identity(self.path)
        except StoreFileError as e:  # e.g. no permission any more: said once
            if self._unreadable == str(e):
                return False
            self._unreadable = str(e)
            raise
        self._unreadable = ""
        if now == self.identity or now == self._refused:
            return False
        with StoreLock(self.path):
            try:
                return self._merge_latest()
            except Px4ParamsError:
                self._refused = now
                raise

    def reload(self) -> None:
        """The file's content, under the lock, replaces the store's (unsaved changes too)."""
        with StoreLock(self.path):
            now = file_identity(self.path)
            with self.store.transaction():  # an unreadable file leaves the store as it was
                _read_latest(self.store, self.path, now)
            self.identity, self._base, self._refused = now, self.store._native.copy(), None
            self._base_kept = dict(self.store._foreign)

    def rewrite(self, change: Callable[[Store], None]) -> None:
        """Saves the file's latest content changed by ``change``, leaving the store (the
        running values) as it is: DroneCAN's ERASE, whose defaults apply at the next
        restart. The session's unsaved changes stay unsaved."""
        store = self.store
        with StoreLock(self.path):
            try:
                with store.transaction():
                    _read_latest(store, self.path, file_identity(self.path))
                    change(store)
                    store.save(self.path)
                    self.identity = file_identity(self.path)
                    self._base, self._base_kept = store._native.copy(), dict(store._foreign)
                    raise KeepRunningValues
            except KeepRunningValues:
                pass

    def _synced(self) -> None:
        """The store was just saved: the file is its content."""
        SAVED.append(self.path)
        self.identity = file_identity(self.path)
        self._base, self._base_kept = self.store._native.copy(), dict(self.store._foreign)
        self._refused = None

    def _merge_latest(self) -> bool:
        """Under the lock: when the file is not the one this session read, the store becomes
        the file's content with this session's changes on top. Raises
        :class:`StoreConflictError` (the store left as it was) when both changed the same."""
        now = file_identity(self.path)
        if now == self.identity:
            return False
        store = self.store
        ours, ours_kept = store._native.copy(), dict(store._foreign)
        with store.transaction():
            _read_latest(store, self.path, now)
            theirs, theirs_kept = store._native.copy(), dict(store._foreign)
            kept = (self._base_kept, ours_kept, theirs_kept)
            _put_on_top(store, self._base, ours, theirs, self.path, kept)
        self.identity, self._base, self._refused = now, theirs, None
        self._base_kept = theirs_kept
        return True


#: ``(device, inode, size, mtime_ns, ctime_ns, hash of the content)`` of a file. Every save (a
#: rename) changes the inode, but a freed inode is soon used again and two saves within one
#: clock tick have the same times: the content tells them apart (a store is kilobytes). Not a
#: CRC-32: a store ends with the CRC-32 of what precedes it, so every store has the same one.
FileIdentity = tuple[int, int, int, int, int, int]

#: Opening a FIFO must not wait for a writer (POSIX only: elsewhere there are no FIFOs).
_NONBLOCK = getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
#: Files larger than this (not a store) are told apart by their status alone.
_IDENTITY_READ_MAX = 1 << 24


def file_identity(path: str) -> FileIdentity | None:
    """The file's identity, None when there is no file. A FIFO or device is not read."""
    try:
        fd = os.open(path, os.O_RDONLY | _NONBLOCK)
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as e:
        raise StoreFileError(f"cannot read: {e.strerror}", path) from None
    try:
        info = os.fstat(fd)
        content = 0
        if stat.S_ISREG(info.st_mode) and info.st_size <= _IDENTITY_READ_MAX:
            chunks = []
            while chunk := os.read(fd, 1 << 16):
                chunks.append(chunk)
            content = hash(b"".join(chunks))  # (SipHash: identities stay in this process)
    except OSError as e:
        raise StoreFileError(f"cannot read: {e.strerror}", path) from None
    finally:
        os.close(fd)
    return (info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns, info.st_ctime_ns, content)


def _read_latest(store: Store, path: str, identity: FileIdentity | None) -> None:
    if identity is None:  # removed by someone: a new store
        store.reset_to_initial()
    else:
        store.load_from(path)


# -- putting one writer's changes on top of another's -------------------------------------------

#: A store's content: (parameter index, instance) -> (value bytes, default bytes).
Content = dict[tuple[int, int], tuple[bytes, bytes]]


def _content(store: Store, native: Any) -> Content:
    return {
        (p.index, i): (native.get(p.index, i, default=False), native.get(p.index, i, default=True))
        for p in store._order
        for i in native.instances(p.index)
    }


def _put_on_top(
    store: Store,
    base_native: Any,
    ours_native: Any,
    theirs: Any,
    path: str,
    kept: tuple[dict[str, bytes], dict[str, bytes], dict[str, bytes]] = ({}, {}, {}),
) -> None:
    """The store holds ``theirs`` (the file's latest content); puts on top of it what
    ``ours`` changed since ``base`` (what this writer read): whole instances added or removed,
    values and defaults leaf by leaf, and the classic records kept unchanged (``kept``: base,
    ours, theirs). Raises :class:`StoreConflictError` for a leaf both changed to different
    values, an instance one removed while the other changed it, a value whose shape (union
    variant, array length) both changed differently, or a classic parameter changed here that
    the other writer changed as the other type (a kept record)."""
    base = _content(store, base_native)
    ours = _content(store, ours_native)
    latest = _content(store, theirs)
    params = {p.index: p for p in store._order}
    conflicts: list[str] = []
    base_kept, ours_kept, theirs_kept = kept
    changed_here = {
        params[key[0]].name
        for key in base.keys() | ours.keys()
        if params[key[0]].classic is not None and ours.get(key) != base.get(key)
    }
    for name in sorted(base_kept.keys() | ours_kept.keys() | theirs_kept.keys() | changed_here):
        was, held, found = base_kept.get(name), ours_kept.get(name), theirs_kept.get(name)
        # (set here, the kept record given way: whatever the other writer did to it clashes)
        if found != was and (name in changed_here or held not in (was, found)):
            conflicts.append(f"{name} was changed here and by another writer (as the other type)")
        elif held is None and was is not None:  # set here since: the kept record gave way
            store._foreign.pop(name, None)
        elif held is not None and held != was:
            store._foreign[name] = held
    writes: list[tuple[tuple[int, int], tuple[bytes, bytes] | None]] = []
    for key in sorted(base.keys() | ours.keys()):
        before, mine, now = base.get(key), ours.get(key), latest.get(key)
        if mine in (before, now):
            continue  # not changed here, or changed the same way by both
        p = params[key[0]]
        name = store._instance_name(p, key[1])
        if now == before:
            writes.append((key, mine))  # changed here only
        elif mine is None:
            conflicts.append(f"{name} was removed here but changed by another writer")
        elif now is None:
            conflicts.append(f"{name} was removed by another writer but changed here")
        else:
            value, default = (
                _merge_value(
                    p, name, what, None if before is None else before[part], mine[part],
                    now[part], conflicts,
                )
                for part, what in ((0, ""), (1, "default of "))
            )  # fmt: skip
            writes.append((key, (value, default)))
    if conflicts:
        more = f" (and {len(conflicts) - 1} more)" if len(conflicts) > 1 else ""
        raise StoreConflictError(f"{conflicts[0]} since this writer read {path}{more}")
    native = store._native
    for (index, instance), written in writes:
        if written is None:
            native.remove(index, instance)
            continue
        if (index, instance) not in latest:
            native.add(index, instance)
        native.set_encoded(index, instance, written[1], default=True)
        native.set_encoded(index, instance, written[0], default=False)


def _merge_value(
    p: Any,
    name: str,
    what: str,
    before: bytes | None,
    mine: bytes,
    now: bytes,
    conflicts: list[str],
) -> bytes:
    """One value (or default) changed here (``mine``) and by another writer (``now``), merged
    leaf by leaf: each side's changed leaves go on top of the other's value; a leaf both
    changed (to different values), or one changed inside a variant or array element the other
    side replaced, is a conflict."""
    if mine in (before, now):
        return now
    if now == before:
        return mine
    if p.spec is None or before is None:  # a classic parameter (one number), or added twice
        done = "added" if before is None else "changed"
        conflicts.append(f"{what}{name} was {done} here and by another writer")
        return now
    data_type = p.spec.data_type

    def leaves(data: bytes) -> dict[str, Any]:
        return {leaf.path: leaf for leaf in data_type.leaves(data, tao=False)}

    old, ours, latest = leaves(before), leaves(mine), leaves(now)
    # Start from the side that changed the value's shape (union variant, array length), if
    # only one did, and put the other side's changed leaves on top of it.
    if ours.keys() != old.keys() and latest.keys() == old.keys():
        result, changes = mine, latest
    else:
        result, changes = now, ours
    first = leaves(result)
    for path, leaf in changes.items():
        if path in old and _same(leaf.value, old[path].value):
            continue  # not changed on that side
        target = leaves(result).get(path)  # again: a tag or length set may move leaves
        if target is not None and _same(target.value, leaf.value):
            continue  # changed the same way by both
        start = first.get(path)
        if target is None or (
            start is not None and (path not in old or not _same(start.value, old[path].value))
        ):
            conflicts.append(f"{what}{name}.{path} was changed here and by another writer")
            continue
        result = data_type.set_leaf(result, target.index, leaf.value, tao=False)
    return result


def _same(a: object, b: object) -> bool:
    """Equal leaf values (NaN equals NaN: a NaN left alone is not a change)."""
    return a == b or (a != a and b != b)


def open_session(
    store_path: str | None,
    classic: str | None,
    dsdl: Iterable[str] = (),
    out: TextIO | None = None,
    *,
    start_empty_if_unreadable: bool = False,
) -> Session:
    """The store in ``store_path`` (default file when None); a new, empty one when the file
    does not exist yet (or, with ``start_empty_if_unreadable``, cannot be used: for ``param
    load FILE``, the way back from a damaged store)."""
    path = store_path or default_store_path()
    # Parameters are px types: DroneCAN's standard messages are not needed (and slow to load).
    schema = load_schema(list(dsdl), include_dronecan=False)
    source = classic or os.environ.get(CLASSIC_ENV) or BUNDLED_CLASSIC
    store = Store(schema, classic=source)
    # Taken before reading: a save in between makes the next transaction read the file again.
    identity = file_identity(path)
    if identity is not None or _exists(path):
        try:
            store.load_from(path)
        except StoreFileError as e:
            if start_empty_if_unreadable:
                store.reset_to_initial()
                session = Session(store, path, out or sys.stdout, identity=identity)
                session.damaged = True
                return session
            else:
                backup = path + ".bak"
                hint = (
                    f"; the previous save is in {backup}: px4params param load {backup}"
                    if os.path.exists(backup)
                    else ""
                )
                raise StoreFileError(f"{e.message}{hint}", e.file, e.offset) from None
    return Session(store, path, out or sys.stdout, identity=identity)


def _exists(path: str) -> bool:
    """Whether there is a file to load at ``path``: a link loop or a folder without access
    is one (its reading reports it), where ``os.path.exists`` would start an empty store."""
    try:
        os.stat(path)
    except FileNotFoundError:
        return False
    except OSError:
        return True
    return True


class StoreLock:
    """Holds ``FILE.lock`` while a writer reads, changes and saves the store, so that two
    writers at once do not lose one's change: ``with StoreLock(path):``. A POSIX advisory
    lock (``flock``) between processes, and a lock between the threads of this one; taken
    again by the thread that holds it, it nests. A lock file that cannot be opened or locked
    (a directory, a FIFO, no permission to make it) is an error: :class:`StoreFileError`
    naming it. Where there is no ``flock`` (not POSIX) only the threads are kept apart. A
    class, not ``contextlib.contextmanager``: contextlib costs every command 1 ms to import."""

    def __init__(self, path: str) -> None:
        # By the file's real path: two names of one file (a symbolic link) share the lock.
        self.lock_path = os.path.realpath(path) + ".lock"
        self._held: _Held | None = None

    def __enter__(self) -> None:
        held = _HELD.setdefault(self.lock_path, _Held())
        held.thread_lock.acquire()
        try:
            if held.depth == 0:
                held.fd = _take_lock(self.lock_path)
            held.depth += 1
        except BaseException:
            held.thread_lock.release()
            raise
        self._held = held

    def __exit__(self, *exc: object) -> None:
        held, self._held = self._held, None
        if held is None:
            return
        held.depth -= 1
        if held.depth == 0 and held.fd is not None:
            os.close(held.fd)  # closing releases the lock
            held.fd = None
        held.thread_lock.release()


class _Held:
    """A lock file this process holds: the descriptor, how deep, and the threads' lock."""

    def __init__(self) -> None:
        import threading  # here: a command that never locks does not pay for it

        self.thread_lock = threading.RLock()
        self.fd: int | None = None
        self.depth = 0


#: Lock files this process knows, by real path (``setdefault`` is atomic: no lock needed).
_HELD: dict[str, _Held] = {}


def _take_lock(lock_path: str) -> int | None:
    """Opens and ``flock``s ``lock_path`` (made when missing): a regular file, opened without
    following a link and without blocking on a FIFO; its descriptor, or None without flock."""
    try:
        import fcntl
    except ImportError:  # not POSIX
        return None
    flags = os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC
    try:
        fd = os.open(lock_path, os.O_RDWR | flags, 0o666)
    except OSError as e:
        # A read-only lock file: flock needs no write access.
        fd = _open_or(-1, lock_path, os.O_RDONLY | (flags & ~os.O_CREAT))
        if isinstance(e, FileNotFoundError) and not os.path.isdir(os.path.dirname(lock_path)):
            # (Named as the store, not its lock file: the folder is what is missing.)
            store = lock_path.removesuffix(".lock")
            raise StoreFileError(f"no folder {os.path.dirname(store)}", store) from None
        if not isinstance(e, PermissionError) or fd < 0:
            raise StoreFileError(f"cannot lock the store: {e.strerror}", lock_path) from None
    try:
        kind = os.fstat(fd).st_mode
        if not stat.S_ISREG(kind):
            what = "a directory" if stat.S_ISDIR(kind) else "not a regular file"
            raise StoreFileError(f"cannot lock the store: {what}", lock_path)
        fcntl.flock(fd, fcntl.LOCK_EX)
    except OSError as e:
        os.close(fd)
        raise StoreFileError(f"cannot lock the store: {e.strerror}", lock_path) from None
    except BaseException:
        os.close(fd)
        raise
    return fd


def _open_or(fallback: int, path: str, flags: int) -> int:
    """``os.open(path, flags)``, or ``fallback`` when it fails."""
    try:
        return os.open(path, flags)
    except OSError:
        return fallback


class LockedSession:
    """:func:`open_session` under the store's lock, held until the block ends:
    ``with LockedSession(path, classic) as session:``."""

    def __init__(
        self,
        store_path: str | None,
        classic: str | None,
        dsdl: Iterable[str] = (),
        *,
        start_empty_if_unreadable: bool = False,
    ) -> None:
        self._args = (store_path, classic, list(dsdl), start_empty_if_unreadable)
        self._lock = StoreLock(store_path or default_store_path())

    def __enter__(self) -> Session:
        store_path, classic, dsdl, start_empty = self._args
        # Reading needs no lock (saves replace the file whole): when it cannot be taken, a
        # save tries again and reports why it cannot, before writing anything. A store that is
        # no regular file (a FIFO, /dev/null) is refused as it is read: no FILE.lock beside it.
        self._locked = _is_file_or_none(store_path or default_store_path()) and _try_lock(
            self._lock
        )
        try:
            return open_session(store_path, classic, dsdl, start_empty_if_unreadable=start_empty)
        except BaseException:
            self.__exit__()
            raise

    def __exit__(self, *exc: object) -> None:
        if self._locked:
            self._lock.__exit__()


def _is_file_or_none(path: str) -> bool:
    """Whether ``path`` is a regular file (through links) or nothing yet."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except FileNotFoundError:
        return True
    except OSError:  # its reading says why
        return False


def _try_lock(lock: StoreLock) -> bool:
    try:
        lock.__enter__()
    except StoreFileError:
        return False
    return True
