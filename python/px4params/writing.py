"""The one way the product writes a file it is asked to write: the store, an exported
``.params``, ``metadata -o``, ``migrate -o``, ``health --timeline``, ``autostart run``'s
outputs.

Only a regular file is replaced, or a new one made: a FIFO would hang the command, a device
(``/dev/sda``) or a folder is no output file. The data goes to a temporary file beside the
target, is synced and renamed over it, so that a crash or a full disk leaves the old file or
the whole new one, and no temporary file. An output naming one of the command's inputs, or
another of its outputs, is refused before anything is written (:func:`check_outputs`). A
refusal is an
:class:`px4params.errors.OutputFileError` (an ``OSError`` too), one line naming the file.
"""

from __future__ import annotations

import errno
import os
import stat

from px4params._records import TYPE_CHECKING
from px4params.errors import OutputFileError

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from collections.abc import Iterable
    from typing import Any


def _refused(message: str, path: str, code: int | None) -> OutputFileError:
    return OutputFileError(code or errno.EIO, message, path)


def write_file(path: str | os.PathLike[str], data: bytes, *, keep_backup: bool) -> int:
    """Writes ``data`` to ``path`` atomically (with ``keep_backup``, the previous file becomes
    ``path.bak``); returns its size.

    Only a regular file is replaced, or a new one made: a directory, FIFO, device or socket
    is refused, as is a file without write permission (``cannot write: read-only``: a rename
    would replace it, and keep its mode). A symbolic link is followed: the file it points to
    is replaced, the link stays. Temporary files carry the writer's process ID
    (``.NAME.PID.XXXX.tmp``, ``NAME.bak.PID.tmp``); a failed save removes its own, and those
    a killed save left behind are removed by the next save in the folder."""
    given = os.fspath(path)
    target = os.path.realpath(given)
    _check_replaceable(target, given)
    folder = os.path.dirname(target)
    base = os.path.basename(target)
    try:
        import tempfile  # here: it costs a command 5 ms to import, and only saves need it

        fd, tmp = tempfile.mkstemp(prefix=f".{base}.{os.getpid()}.", suffix=".tmp", dir=folder)
    except OSError as e:
        raise _refused(f"cannot write: {e.strerror}", given, e.errno) from None
    try:
        with os.fdopen(fd, "wb") as f:
            # mkstemp makes the file private; give it the mode a new file gets (or the old
            # file's), so that other users and tools can read the store as before.
            os.fchmod(f.fileno(), _mode_for(target))
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        if keep_backup and os.path.exists(target):
            _keep_backup(target, given)
        os.replace(tmp, target)  # atomic: readers see the old file or the whole new one
        _fsync_folder(folder)
    except BaseException as e:  # every failed save leaves no temporary file
        with _ignoring_os_errors():
            os.unlink(tmp)
        if isinstance(e, OSError) and not isinstance(e, OutputFileError):
            raise _refused(f"cannot write: {e.strerror}", given, e.errno) from None
        raise
    _remove_stale(folder, base)
    return len(data)


def check_writable(path: str | os.PathLike[str]) -> None:
    """Refuses, before anything is written, what :func:`write_file` would refuse that can be
    told ahead: a path that is no regular file, a read-only file, a folder that does not exist
    or cannot be written. (A full disk is told only by writing.)"""
    given = os.fspath(path)
    target = os.path.realpath(given)
    _check_replaceable(target, given)
    folder = os.path.dirname(target) or "."
    if not os.path.isdir(folder):
        code = errno.ENOTDIR if os.path.exists(folder) else errno.ENOENT
        raise _refused(f"cannot write: {os.strerror(code)}", given, code)
    if not os.access(folder, os.W_OK | os.X_OK):
        raise _refused(f"cannot write: {os.strerror(errno.EACCES)}", given, errno.EACCES)


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether two paths name one file (through symbolic links, ``./x``, hard links)."""
    return _identity(os.fspath(a)) == _identity(os.fspath(b))


def _kind(mode: int) -> str | None:
    """What a file that is not a regular file is (None for a regular file)."""
    kinds = (
        (stat.S_ISREG, None),
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def _check_replaceable(target: str, given: str) -> None:
    """Refuses to replace anything but a writable regular file (a new path is fine)."""
    try:
        info = os.stat(target)
    except FileNotFoundError:
        return  # a new file (its folder is checked by creating the temporary file)
    except OSError as e:
        raise _refused(f"cannot write: {e.strerror}", given, e.errno) from None
    kind = _kind(info.st_mode)
    if kind is not None:
        raise _refused(f"cannot write: {kind}, not a regular file", given, errno.EINVAL)
    # (root may write a 0444 file: its mode still says read-only)
    if not info.st_mode & 0o222 or not os.access(target, os.W_OK):
        raise _refused("cannot write: read-only", given, errno.EACCES)


def _remove_stale(folder: str, base: str) -> None:
    """Removes the temporary files of saves of ``base`` whose process is gone (killed while
    saving); a running save's files are left alone."""
    with _ignoring_os_errors():
        for name in os.listdir(folder):
            pid = _saving_pid(name, base)
            if pid is not None and pid != os.getpid() and not _alive(pid):
                with _ignoring_os_errors():
                    os.unlink(os.path.join(folder, name))


def _saving_pid(name: str, base: str) -> int | None:
    """The process of a save of ``base`` whose temporary file is ``name``, or None for any
    other name. Exactly the names such a save makes: ``.v.store.20261128.PID.XXXX.tmp`` is a
    save of v.store.20261128 (running), not one of v.store by a process 20261128. (Without
    ``re``: a command that only reads must not pay for importing it.)"""
    if not name.endswith(".tmp"):
        return None
    if name.startswith(f".{base}."):
        parts = name[len(base) + 2 : -len(".tmp")].split(".")
        unique = parts[-1] if len(parts) == 2 else ""  # mkstemp's letters, digits and _
        if unique and unique.replace("_", "").isalnum() and unique.isascii():
            return _number(parts[0])
    elif name.startswith(f"{base}.bak."):
        return _number(name[len(base) + 5 : -len(".tmp")])
    return None


def _number(text: str) -> int | None:
    return int(text) if text.isascii() and text.isdigit() else None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: alive
        return True
    return True


def _mode_for(target: str) -> int:
    try:
        return os.stat(target).st_mode & 0o777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _keep_backup(target: str, given: str) -> None:
    """``target.bak`` becomes the current file, without a moment where ``target`` is gone. A
    ``.bak`` that is not a regular file (or a link) is refused, naming it."""
    backup = target + ".bak"
    shown = backup if os.path.islink(given) else given + ".bak"
    try:
        mode = os.lstat(backup).st_mode
    except FileNotFoundError:
        mode = stat.S_IFREG
    except OSError as e:
        raise _refused(f"cannot keep the previous save: {e.strerror}", shown, e.errno) from None
    if not stat.S_ISLNK(mode) and _kind(mode) is not None:
        raise _refused(
            f"cannot keep the previous save here: {_kind(mode)}, not a regular file",
            shown,
            errno.EINVAL,
        )
    staging = f"{backup}.{os.getpid()}.tmp"
    with _ignoring_os_errors():
        os.unlink(staging)
    try:
        try:
            os.link(target, staging)
        except OSError:  # no hard links here: copy instead
            with open(target, "rb") as src, open(staging, "wb") as dst:
                dst.write(src.read())
                dst.flush()
                os.fsync(dst.fileno())
        os.replace(staging, backup)
    except OSError as e:
        with _ignoring_os_errors():
            os.unlink(staging)
        raise _refused(f"cannot keep the previous save: {e.strerror}", shown, e.errno) from None


def _fsync_folder(folder: str) -> None:
    with _ignoring_os_errors():
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


class _ignoring_os_errors:
    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: Any, value: Any, tb: Any) -> bool:
        return kind is not None and issubclass(kind, OSError)


#: The first bytes of a px4params store file (docs/store-format.md).
STORE_MAGIC = b"PX4P"


def check_outputs(
    outputs: Iterable[str | os.PathLike[str] | None],
    inputs: Iterable[str | os.PathLike[str] | None],
) -> None:
    """Refuses, before anything is written, an output path that names one of the command's
    input files (``migrate x.params -o x.params`` would replace the vehicle's file with the
    airframe), an output given twice (the second write would replace the first), or a store
    file (a report, header or log written over it would lose the vehicle's configuration,
    with no ``.bak`` as ``param save`` keeps). Paths are compared as files (a symbolic link or
    ``./x`` is the same file); ``-`` and None are skipped. One line: ``OUT: is the input file
    IN: give the output another path``."""
    named = [os.fspath(p) for p in inputs if p is not None and os.fspath(p) != "-"]
    taken = {_identity(path): f"the input file {path}" for path in reversed(named)}
    for path in outputs:
        if path is None or os.fspath(path) == "-":
            continue
        given = os.fspath(path)
        key = _identity(given)
        if key in taken:
            raise _refused(f"is {taken[key]}: give the output another path", given, errno.EINVAL)
        if _is_store(given):
            raise _refused(
                "is a px4params store file: give the output another path (or move the store first)",
                given,
                errno.EEXIST,
            )
        taken[key] = "another output of this command"


def _is_store(path: str) -> bool:
    """Whether ``path`` is a store file: a regular file (a FIFO is not opened, which would wait
    for a writer) whose first bytes are :data:`STORE_MAGIC`."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return False
        with open(path, "rb") as f:
            return f.read(len(STORE_MAGIC)) == STORE_MAGIC
    except OSError:  # missing, or not to be read: not a store this command would replace
        return False


def _identity(path: str) -> str:
    """What makes two paths one file: device and inode where it exists, else its real path."""
    try:
        info = os.stat(path)
    except OSError:
        return os.path.realpath(path)
    return f"{info.st_dev}:{info.st_ino}"
