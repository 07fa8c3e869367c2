"""Files in the user's cache folder that spare a command work it did before (the DSDL model,
the classic parameters of a ``parameters.json``).

A cache file holds a value in this interpreter's marshal format, which loads about twice as
fast as JSON and needs no ``json`` import. It is written atomically and read back only when its
CRC-32 matches (marshal is not meant for damaged input) and the key stored in it is the key
asked for; anything else is a miss, and the caller rebuilds the value and writes it again.
"""

from __future__ import annotations

import binascii
import marshal
import os
import sys

from px4params._records import TYPE_CHECKING
from px4params.reading import CACHE, read_bytes

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any

#: Environment variable naming the cache folder.
CACHE_ENV = "PX4PARAMS_CACHE_DIR"

#: Files modified this recently (seconds) may change again within the file system's time stamp
#: resolution without their time changing (git's "racy" files): keys must cover their contents.
RACY_SECONDS = 2.0

#: A cache file: these four bytes, the CRC-32 of the rest (little-endian), the marshalled
#: ``(key, value)``.
_MAGIC = b"P4MC"

#: Part of every key: marshal's format belongs to the interpreter that wrote it.
INTERPRETER = f"{sys.implementation.cache_tag} marshal {marshal.version}"


def file_stamp(st: os.stat_result) -> str:
    """What tells one version of a file from another without reading it: its device and inode
    (a file replaced by a rename is another), size, and modification and change times. The
    change time is the one ``cp -p``, ``rsync -t``, ``tar`` and ``touch -d`` cannot set back:
    they restore the modification time of an edited file, and the edit still changes ``ctime``."""
    return f"{st.st_dev}:{st.st_ino} {st.st_size} {st.st_mtime_ns} {st.st_ctime_ns}"


def is_racy(st: os.stat_result, now: float) -> bool:
    """Whether the file was written so shortly before ``now`` (``time.time()``) that another
    write could follow without changing its stamp: its key must then cover its contents."""
    return max(st.st_mtime_ns, st.st_ctime_ns) > (now - RACY_SECONDS) * 1e9


def discard(path: str, why: str) -> None:
    """Removes a cache file whose content cannot be used although its CRC matched (written by
    something else, or edited), with a note on stderr: the caller rebuilds it."""
    print(f"px4params: note: {path}: {why}; rebuilding it", file=sys.stderr)
    try:  # noqa: SIM105 - contextlib.suppress costs every command 1 ms to import
        os.unlink(path)
    except OSError:
        pass


def default_cache_dir() -> str:
    """``$PX4PARAMS_CACHE_DIR``, else ``$XDG_CACHE_HOME/px4params``, else ``~/.cache/px4params``."""
    explicit = os.environ.get(CACHE_ENV)
    if explicit:
        return explicit
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg:
        return os.path.join(xdg, "px4params")
    return os.path.join(os.path.expanduser("~"), ".cache", "px4params")


def cache_path(directory: str, kind: str, key: str) -> str:
    """The file for ``key``: ``KIND-CRC.marshal`` in ``directory`` (the key is checked on read,
    so two keys with one CRC only miss)."""
    crc = binascii.crc32(key.encode("utf-8", "surrogateescape"))
    return os.path.join(directory, f"{kind}-{crc:08x}.marshal")


def read_cached(path: str, key: str) -> Any:
    """The value cached in ``path`` under ``key``; None when missing, damaged or for another
    key."""
    try:
        data = read_bytes(path, CACHE)
    except OSError:
        return None
    body = memoryview(data)[8:]
    if data[:4] != _MAGIC or data[4:8] != binascii.crc32(body).to_bytes(4, "little"):
        return None
    try:
        stored = marshal.loads(body)
    except (ValueError, EOFError, TypeError):
        return None
    if not isinstance(stored, tuple) or len(stored) != 2 or stored[0] != key:
        return None
    return stored[1]


def write_cached(path: str, key: str, value: Any) -> None:
    """Caches ``value`` under ``key`` in ``path``: best effort, since a read-only or full cache
    folder must not stop a command."""
    folder, name = os.path.split(path)
    tmp = os.path.join(folder, f".{name}.{os.getpid()}.tmp")
    try:
        body = marshal.dumps((key, value))
        os.makedirs(folder, exist_ok=True)
        with open(tmp, "wb") as out:
            out.write(_MAGIC + binascii.crc32(body).to_bytes(4, "little") + body)
        os.replace(tmp, path)  # atomic: readers see the old file or the whole new one
    except (OSError, ValueError):
        try:  # noqa: SIM105 - contextlib.suppress costs every command 1 ms to import
            os.unlink(tmp)
        except OSError:
            pass
