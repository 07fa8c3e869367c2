"""A session on the store file: open it (a new store when there is none), hold its lock while a
command or a whole airframe file works on it, and save once when the work succeeded.

Writes to other files asked for during a batch (``param save FILE``, ``param export FILE``) are
deferred until the batch succeeds: a failing airframe file leaves no file half-written.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterable

from px4params._records import TYPE_CHECKING
from px4params.dsdl.schema import load_schema
from px4params.errors import StoreFileError
from px4params.store.classic import BUNDLED_CLASSIC, CLASSIC_ENV
from px4params.store.store import Store, default_store_path

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import IO, TextIO


class Session:
    """The store a ``param`` command (or a whole airframe file) works on, and the file it is
    saved to."""

    def __init__(
        self, store: Store, path: str, out: TextIO | None = None, *, autosave: bool = True
    ) -> None:
        self.store = store
        self.path = path
        self.out = out if out is not None else sys.stdout
        #: Save after each changing verb (off while an airframe file runs: it saves once).
        self.autosave = autosave
        self.changed = False
        #: Writes to other files asked for during a batch, done when the batch succeeds.
        self.deferred: list[Callable[[], None]] = []

    def done(self) -> None:
        """Records a change; saves it unless a batch is running."""
        self.changed = True
        if self.autosave:
            self.save()

    def write_later(self, write: Callable[[], None]) -> None:
        """Writes a file now, or when the batch succeeds: a failed airframe file leaves no
        file behind that it wrote half-way."""
        if self.autosave:
            write()
        else:
            self.deferred.append(write)

    def save(self) -> None:
        self.store.save(self.path)
        self.changed = False
        for write in self.deferred:
            write()
        self.deferred.clear()


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
    if _exists(path):
        try:
            store.load_from(path)
        except StoreFileError as e:
            if start_empty_if_unreadable:
                store.reset_to_initial()
            else:
                backup = path + ".bak"
                hint = (
                    f"; the previous save is in {backup}: px4params param load {backup}"
                    if os.path.exists(backup)
                    else ""
                )
                raise StoreFileError(f"{e.message}{hint}", e.file, e.offset) from None
    return Session(store, path, out or sys.stdout)


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
    """Holds ``FILE.lock`` while a command reads, changes and saves the store, so that two
    commands at once do not lose one's change (POSIX advisory lock; elsewhere, no lock):
    ``with StoreLock(path):``. A class, not ``contextlib.contextmanager``: contextlib costs
    every command 1 ms to import."""

    def __init__(self, path: str) -> None:
        self._path = path
        self._handle: IO[str] | None = None

    def __enter__(self) -> None:
        try:
            import fcntl
        except ImportError:  # not POSIX
            return
        try:
            # By the file's real path: two names of one file (a symbolic link) share the lock.
            handle = open(os.path.realpath(self._path) + ".lock", "a")
        except OSError:
            return  # a read-only folder: reading still works, saving will report the problem
        try:
            fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
        except BaseException:
            handle.close()
            raise
        self._handle = handle

    def __exit__(self, *exc: object) -> None:
        if self._handle is not None:
            self._handle.close()  # closing releases the lock
            self._handle = None


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
        self._lock.__enter__()
        try:
            return open_session(store_path, classic, dsdl, start_empty_if_unreadable=start_empty)
        except BaseException:
            self._lock.__exit__()
            raise

    def __exit__(self, *exc: object) -> None:
        self._lock.__exit__()
