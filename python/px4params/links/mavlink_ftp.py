"""The read-only part of the MAVLink FTP protocol, over files held in memory: what a ground
station needs to download component metadata (``mftp://`` URIs of COMPONENT_METADATA).

A request or response is the ``payload`` (251 bytes) of ``FILE_TRANSFER_PROTOCOL``::

    bytes 0-1  seq_number      (a response carries the request's + 1)
    byte  2    session
    byte  3    opcode          (ACK 128 / NAK 129 in responses)
    byte  4    size            (bytes of data)
    byte  5    req_opcode      (in a response: the request's opcode)
    byte  6    burst_complete
    byte  7    padding
    bytes 8-11 offset          (little-endian)
    bytes 12-  data            (239 bytes at most)

Supported: ``ResetSessions``, ``TerminateSession``, ``ListDirectory``, ``OpenFileRO``,
``ReadFile``, ``BurstReadFile`` and ``CalcFileCRC32``. Anything that would write is refused with
``NAK FileProtected``, any other opcode with ``NAK UnknownCommand`` (a response, ACK or NAK,
is not answered); unknown paths with ``NAK FileNotFound``, reads past the end with ``NAK EOF``,
bad sessions with ``NAK InvalidSession``.

Sessions a client abandons (a download interrupted, a ground station closed) are reclaimed once
they have been idle for ``session_idle`` seconds and an open finds no free one: QGroundControl's
FTPManager opens a file first and resets sessions only at the end, so without this four
abandoned downloads would answer every later open with ``NoSessionsAvailable``.
A session belongs to the client that opened it (``owner``: the MAVLink server's peer address):
another client's read, terminate or reset does not reach it (``NAK InvalidSession``), as it
would not on PX4, whose FTP serves one link at a time.
The protocol handler is pure (bytes in, bytes out); :mod:`px4params.links.mavlink` carries it.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable, Hashable, Mapping

from px4params.gcs.component_information import px4_crc32

__all__ = ["MavftpServer", "Op", "make_request"]

#: Data bytes a payload carries.
MAX_DATA = 239
_HEADER = struct.Struct("<HBBBBBBI")
#: Sessions open at once (PX4 has one; QGC and MAVProxy use one at a time).
MAX_SESSIONS = 4
#: Packets one BurstReadFile request is answered with at most; the last of them says
#: ``burst_complete`` and the client asks for the rest (PX4 stops a burst when its buffer runs
#: short, after about 35 kB).
BURST_PACKETS = 150
#: Seconds a session may stay unused before an open that finds no free session takes it over
#: (QGC retries an unanswered request after about a second, so a live download is never idle
#: this long).
SESSION_IDLE = 3.0


class Op:
    """Opcodes and NAK error codes of MAVLink FTP."""

    NONE = 0
    TERMINATE_SESSION = 1
    RESET_SESSIONS = 2
    LIST_DIRECTORY = 3
    OPEN_FILE_RO = 4
    READ_FILE = 5
    CREATE_FILE = 6
    WRITE_FILE = 7
    REMOVE_FILE = 8
    CREATE_DIRECTORY = 9
    REMOVE_DIRECTORY = 10
    OPEN_FILE_WO = 11
    TRUNCATE_FILE = 12
    RENAME = 13
    CALC_FILE_CRC32 = 14
    BURST_READ_FILE = 15
    ACK = 128
    NAK = 129

    # NAK error codes (the first data byte of a NAK)
    ERR_FAIL = 1
    ERR_FAIL_ERRNO = 2
    ERR_INVALID_DATA_SIZE = 3
    ERR_INVALID_SESSION = 4
    ERR_NO_SESSIONS_AVAILABLE = 5
    ERR_EOF = 6
    ERR_UNKNOWN_COMMAND = 7
    ERR_FILE_EXISTS = 8
    ERR_FILE_PROTECTED = 9
    ERR_FILE_NOT_FOUND = 10


_WRITES = {
    Op.CREATE_FILE,
    Op.WRITE_FILE,
    Op.REMOVE_FILE,
    Op.CREATE_DIRECTORY,
    Op.REMOVE_DIRECTORY,
    Op.OPEN_FILE_WO,
    Op.TRUNCATE_FILE,
    Op.RENAME,
}


def make_request(
    opcode: int,
    *,
    seq: int = 0,
    session: int = 0,
    offset: int = 0,
    data: bytes = b"",
    size: int | None = None,
) -> bytes:
    """A request payload (for clients and tests)."""
    header = _HEADER.pack(
        seq, session, opcode, len(data) if size is None else size, 0, 0, 0, offset
    )
    return (header + data).ljust(MAX_DATA + _HEADER.size, b"\0")


class MavftpServer:
    """Serves ``files`` (path -> bytes; paths are absolute, ``/`` separated) read-only.
    ``session_idle``: seconds after which an unused session may be reclaimed; ``clock``: the
    time in seconds (monotonic)."""

    def __init__(
        self,
        files: Mapping[str, bytes],
        *,
        session_idle: float = SESSION_IDLE,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.files = {self._normal(path): bytes(data) for path, data in files.items()}
        self.session_idle = session_idle
        self._clock = clock
        self._sessions: dict[int, tuple[str, Hashable]] = {}  # session -> (path, owner)
        self._used: dict[int, float] = {}  # session -> when last used
        #: Sessions reclaimed after being abandoned (for tests and logs).
        self.reclaimed = 0

    @staticmethod
    def _normal(path: str) -> str:
        return "/" + "/".join(p for p in path.split("/") if p and p != ".")

    def handle(self, payload: bytes, owner: Hashable = None) -> list[bytes]:
        """The response payloads to one request payload (several for a burst read) from
        client ``owner``."""
        payload = bytes(payload).ljust(_HEADER.size, b"\0")
        seq, session, opcode, size, _, _, _, offset = _HEADER.unpack_from(payload)
        data = payload[_HEADER.size : _HEADER.size + min(size, MAX_DATA)]
        if opcode in (Op.ACK, Op.NAK):
            return []  # a response, not a request: answering it, two servers would never stop
        reply = _Reply(seq, session, opcode)
        if opcode == Op.RESET_SESSIONS:
            for mine in [s for s, (_, o) in self._sessions.items() if o == owner]:
                del self._sessions[mine], self._used[mine]
            return [reply.ack()]
        opened = self._sessions.get(session)
        path = opened[0] if opened is not None and opened[1] == owner else None
        if opcode == Op.TERMINATE_SESSION:
            if path is None:
                return [reply.nak(Op.ERR_INVALID_SESSION)]
            del self._sessions[session]
            del self._used[session]
            return [reply.ack()]
        if opcode == Op.LIST_DIRECTORY:
            return [self._list(reply, _text(data), offset)]
        if opcode == Op.OPEN_FILE_RO:
            return [self._open(reply, _text(data), owner)]
        if opcode in (Op.READ_FILE, Op.BURST_READ_FILE):
            if path is None:
                return [reply.nak(Op.ERR_INVALID_SESSION)]
            self._used[session] = self._clock()
            content = self.files[path]
            if opcode == Op.READ_FILE:
                if offset >= len(content):
                    return [reply.nak(Op.ERR_EOF)]
                chunk = content[offset : offset + min(size or MAX_DATA, MAX_DATA)]
                return [reply.ack(chunk, offset=offset)]
            return self._burst(reply, content, offset)
        if opcode == Op.CALC_FILE_CRC32:
            path = self._normal(_text(data))
            if path not in self.files:
                return [reply.nak(Op.ERR_FILE_NOT_FOUND)]
            return [reply.ack(struct.pack("<I", px4_crc32(self.files[path])))]
        if opcode in _WRITES:
            return [reply.nak(Op.ERR_FILE_PROTECTED)]
        return [reply.nak(Op.ERR_UNKNOWN_COMMAND)]

    def _open(self, reply: _Reply, path: str, owner: Hashable) -> bytes:
        path = self._normal(path)
        if path not in self.files:
            return reply.nak(Op.ERR_FILE_NOT_FOUND)
        if len(self._sessions) >= MAX_SESSIONS and not self._reclaim():
            return reply.nak(Op.ERR_NO_SESSIONS_AVAILABLE)
        session = next(i for i in range(256) if i not in self._sessions)
        self._sessions[session] = (path, owner)
        self._used[session] = self._clock()
        reply.session = session
        return reply.ack(struct.pack("<I", len(self.files[path])))

    def _reclaim(self) -> bool:
        """Frees the session unused longest if it has been idle ``session_idle`` seconds."""
        oldest = min(self._used, key=self._used.__getitem__)
        if self._clock() - self._used[oldest] < self.session_idle:
            return False
        del self._sessions[oldest], self._used[oldest]
        self.reclaimed += 1
        return True

    def _list(self, reply: _Reply, path: str, offset: int) -> bytes:
        folder = self._normal(path)
        prefix = folder.rstrip("/") + "/"
        entries: dict[str, str] = {}
        for name, content in self.files.items():
            if not name.startswith(prefix):
                continue
            first, _, rest = name[len(prefix) :].partition("/")
            entries[first] = f"D{first}" if rest else f"F{first}\t{len(content)}"
        if not entries and folder != "/":
            return reply.nak(Op.ERR_FILE_NOT_FOUND)
        listed = [entries[k] for k in sorted(entries)][offset:]
        if not listed:
            return reply.nak(Op.ERR_EOF)
        out = b""
        for entry in listed:
            item = entry.encode() + b"\0"
            if len(out) + len(item) > MAX_DATA:
                break
            out += item
        return reply.ack(out, offset=offset)

    def _burst(self, reply: _Reply, content: bytes, offset: int) -> list[bytes]:
        """Data ACKs from ``offset``, as PX4 streams them: each carries its offset, the seq
        numbers count up, and the end of the file is a ``NAK EOF`` with the next seq."""
        if offset >= len(content):
            return [reply.nak(Op.ERR_EOF)]
        out = []
        for _ in range(BURST_PACKETS):
            chunk = content[offset : offset + MAX_DATA]
            out.append(reply.ack(chunk, offset=offset))
            reply.seq = (reply.seq + 1) & 0xFFFF
            offset += len(chunk)
            if offset >= len(content):
                out.append(reply.nak(Op.ERR_EOF))
                return out
        out[-1] = out[-1][:6] + b"\x01" + out[-1][7:]  # burst_complete: ask again from here
        return out


class _Reply:
    """Builds responses to one request: seq + 1, the request's session and opcode."""

    def __init__(self, seq: int, session: int, opcode: int) -> None:
        self.seq = (seq + 1) & 0xFFFF
        self.session = session
        self.opcode = opcode

    def ack(self, data: bytes = b"", *, offset: int = 0, burst_complete: bool = False) -> bytes:
        return self._pack(Op.ACK, data, offset, burst_complete)

    def nak(self, error: int) -> bytes:
        return self._pack(Op.NAK, bytes([error]), 0, False)

    def _pack(self, opcode: int, data: bytes, offset: int, burst_complete: bool) -> bytes:
        header = _HEADER.pack(
            self.seq, self.session, opcode, len(data), self.opcode, int(burst_complete), 0, offset
        )
        return (header + data).ljust(MAX_DATA + _HEADER.size, b"\0")


def _text(data: bytes) -> str:
    return data.split(b"\0", 1)[0].decode("utf-8", "replace")
