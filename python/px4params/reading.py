"""The one way the product reads a file it is given: regular files only, each kind within a size
that fits it.

A FIFO, a device (``/dev/zero``), a socket or a folder given where a file is expected is
refused before a byte is read, with one line naming the file and what it is: read as a file, a
FIFO hangs the command and ``/dev/zero`` ends in a ``MemoryError``. The file is checked before
it is opened (opening a device can do something: a watchdog's starts it), opened with
``O_NONBLOCK`` (a FIFO swapped in after the check cannot hang the open) and checked again on
the open descriptor (``fstat``). At most the kind's cap plus one byte is read, so a file that
grows while it is read is refused too.

A library that reads from a file object (pyulog) is given one from :func:`open_file`; files a
library opens itself (pydsdl's definitions) are checked with :func:`check_file` first.

A refusal is an :class:`px4params.errors.InputFileError`, which is an ``OSError`` too: callers
that report ``cannot read: {strerror}`` report it as they report a missing file.
"""

from __future__ import annotations

import errno
import os
import stat

from px4params._records import TYPE_CHECKING
from px4params.errors import InputFileError

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import BinaryIO, NamedTuple
else:
    from px4params._records import NamedTuple

__all__ = [
    "AIRFRAME",
    "BENCH",
    "CACHE",
    "CLASSIC_JSON",
    "DEVTYPES",
    "DRIVERS",
    "DSDL",
    "METADATA_JSON",
    "PARAM_FILE",
    "SIGNING_KEY",
    "STORE",
    "ULOG",
    "FileKind",
    "check_file",
    "open_file",
    "read_bytes",
    "read_text",
]

KIB = 1024
MIB = 1024 * KIB
GIB = 1024 * MIB


class FileKind(NamedTuple):
    """What a file is read as (``a store file``), and the most bytes such a file may have."""

    what: str
    cap: int


# A store holds what differs from the defaults; its largest possible content is one type of
# 65,535 bytes (the codec's limit) times 256 instances (``@max_instances``' limit).
STORE = FileKind("a store file", 16 * MIB)
# The bundled drivers.toml is 20 KiB, the example benches 2 KiB.
BENCH = FileKind("a bench file", 1 * MIB)
DRIVERS = FileKind("a drivers file", 1 * MIB)
# PX4's parameters.json of a full build (1909 parameters) is 0.8 MiB.
CLASSIC_JSON = FileKind("a parameters.json", 32 * MIB)
METADATA_JSON = FileKind("a parameters.json", 32 * MIB)
# The longest bundled definition is 3 KiB; pydronecan's longest a few KiB.
DSDL = FileKind("a DSDL definition", 1 * MIB)
# QGC .params files and JSON exports: tens of KiB for a vehicle with 1900 parameters.
PARAM_FILE = FileKind("a parameter file", 16 * MIB)
AIRFRAME = FileKind("an airframe file", 1 * MIB)
DEVTYPES = FileKind("a devtypes table", 1 * MIB)
# Flight logs grow with the flight: an hour at high logging rates is a few hundred MiB.
ULOG = FileKind("a flight log", 1 * GIB)
# The cached schema model is 80 KiB.
CACHE = FileKind("a cache file", 64 * MIB)
#: A MAVLink signing key: 32 bytes, 64 hex digits or PX4's 40-byte file, with room for a newline.
SIGNING_KEY = FileKind("a signing key file", 4 * KIB)

#: Read only; a FIFO cannot block the open, a terminal does not become the controlling one
#: (flags POSIX has; Windows has none of them and no FIFOs to fear).
_READ_FLAGS = (
    os.O_RDONLY
    | getattr(os, "O_NONBLOCK", 0)
    | getattr(os, "O_NOCTTY", 0)
    | getattr(os, "O_CLOEXEC", 0)
    | getattr(os, "O_BINARY", 0)
)

_KINDS = (
    (stat.S_ISDIR, "a folder, not a file"),
    (stat.S_ISFIFO, "a FIFO (named pipe), not a regular file"),
    (stat.S_ISCHR, "a character device, not a regular file"),
    (stat.S_ISBLK, "a block device, not a regular file"),
    (stat.S_ISSOCK, "a socket, not a regular file"),
)


def _refusal(path: str, st: os.stat_result, kind: FileKind) -> InputFileError | None:
    """Why ``path`` (with status ``st``) cannot be read as ``kind``; None when it can."""
    mode = st.st_mode
    if not stat.S_ISREG(mode):
        what = next((text for test, text in _KINDS if test(mode)), "not a regular file")
        return InputFileError(errno.EINVAL, f"is {what}", path)
    if st.st_size > kind.cap:
        return _too_large(path, st.st_size, kind)
    return None


def _too_large(path: str, size: int | None, kind: FileKind) -> InputFileError:
    have = f"{_size_text(size)}; " if size is not None else ""
    return InputFileError(
        errno.EFBIG, f"too large for {kind.what} ({have}at most {_size_text(kind.cap)})", path
    )


def _size_text(size: int) -> str:
    for unit, scale in (("GiB", GIB), ("MiB", MIB), ("KiB", KIB)):
        if size >= scale:
            return f"{size / scale:.1f} {unit}".replace(".0 ", " ")
    return f"{size} bytes"


def check_file(path: str | os.PathLike[str], kind: FileKind) -> os.stat_result:
    """The status of ``path`` when it is a regular file within ``kind``'s size, for a library
    that opens it itself; raises :class:`InputFileError` (or the ``OSError`` of ``stat``)."""
    where = os.fspath(path)
    st = os.stat(where)
    refusal = _refusal(where, st, kind)
    if refusal is not None:
        raise refusal
    return st


def _open_checked(where: str, kind: FileKind) -> int:
    """A descriptor of ``where`` opened for reading once it is known to be a regular file
    within ``kind``'s size: checked before the open (opening some devices does something, a
    watchdog's starts it) and again on the descriptor (the file may have been swapped)."""
    check_file(where, kind)
    fd = os.open(where, _READ_FLAGS)
    try:
        refusal = _refusal(where, os.fstat(fd), kind)
    except BaseException:
        os.close(fd)
        raise
    if refusal is not None:
        os.close(fd)
        raise refusal
    return fd


def open_file(path: str | os.PathLike[str], kind: FileKind) -> BinaryIO:
    """``path`` opened for reading in binary, once it is known to be a regular file within
    ``kind``'s size: for a library that reads from a file object (pyulog). Raises as
    :func:`read_bytes` does."""
    return os.fdopen(_open_checked(os.fspath(path), kind), "rb")


def read_bytes(path: str | os.PathLike[str], kind: FileKind) -> bytes:
    """The whole of ``path``, a regular file of at most ``kind.cap`` bytes.

    Raises:
        InputFileError: not a regular file, or too large (also an ``OSError``).
        OSError: the file cannot be opened or read (missing, no permission, a symlink loop).
    """
    where = os.fspath(path)
    fd = _open_checked(where, kind)
    try:
        chunks: list[bytes] = []
        left = kind.cap + 1  # one byte more than allowed: a file that grew is seen
        while left > 0:
            chunk = os.read(fd, min(left, 1 * MIB))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
        if left <= 0:
            raise _too_large(where, None, kind)
        return b"".join(chunks)
    finally:
        os.close(fd)


def not_text(e: UnicodeDecodeError) -> str:
    """Why a file :func:`read_text` could not decode is not text, in our words, not the codec's:
    ``not a text file: byte 0xFF at offset 3 is not UTF-8``."""
    return f"not a text file: byte 0x{e.object[e.start]:02X} at offset {e.start} is not UTF-8"


def not_text_line(line: str) -> str | None:
    """Why ``line``, read with Python's surrogate escapes (stdin holds bytes that are not UTF-8
    as U+DC80..U+DCFF), is not text, in :func:`not_text`'s words (``not text: byte 0xFF at
    column 1 is not UTF-8``); ``None`` when it is text."""
    for column, char in enumerate(line, 1):
        if "\udc80" <= char <= "\udcff":
            return f"not text: byte 0x{ord(char) - 0xDC00:02X} at column {column} is not UTF-8"
    return None


def read_text(path: str | os.PathLike[str], kind: FileKind, errors: str = "strict") -> str:
    """:func:`read_bytes` decoded as UTF-8 (``UnicodeDecodeError`` for what is not text), without
    the byte order mark Windows editors (Notepad) put first: it is no part of the first line."""
    return read_bytes(path, kind).decode("utf-8", errors).removeprefix("\ufeff")
