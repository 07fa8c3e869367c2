"""ULog, PX4's flight log format (PX4 dev guide, "ULog File Format"): writing it, as pyulog, Flight
Review and PX4's own log tools read it, and reading what a log says about its vehicle (the one
reader of logs' parameters, information and boot console: :func:`read_header`).

A file is a 16-byte header, then messages of ``uint16 size, uint8 type, payload``. The
definitions section (flag bits ``B`` first, then formats ``F``, information ``I``/``M`` and
parameters ``P``) comes before the data section (subscriptions ``A``, data ``D``, logged
messages ``L``). Data follows its format's fields in order, little-endian and packed; the
first field of every format is ``uint64_t timestamp`` in microseconds.

>>> log = ULogWriter()
>>> log.info("sys_name", "px4params")
>>> log.define("arming_check", [("uint64_t", "timestamp"), ("bool", "may_arm")])
>>> log.data(log.subscribe("arming_check"), 1_000_000, True)
>>> log.getvalue()[:7]
b'ULog\\x01\\x125'
"""

from __future__ import annotations

import contextlib
import io
import os
import struct
from dataclasses import dataclass, field

from px4params._records import TYPE_CHECKING
from px4params.errors import ReadBudgetExceeded, SeekBeforeStart, ULogError
from px4params.reading import ULOG, open_file

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from collections.abc import Sequence
    from typing import Any, BinaryIO

    from pyulog import ULog

#: The first seven bytes of every ULog file; the eighth is the format version.
MAGIC = b"ULog\x01\x12\x35"
VERSION = 1

#: Logged message levels, as PX4 writes them (syslog's, as ASCII digits).
LEVELS = {
    "emergency": b"0",
    "alert": b"1",
    "critical": b"2",
    "error": b"3",
    "warning": b"4",
    "notice": b"5",
    "info": b"6",
    "debug": b"7",
}

#: ULog's scalar field types and their ``struct`` codes.
_SCALARS = {
    "int8_t": "b",
    "uint8_t": "B",
    "int16_t": "h",
    "uint16_t": "H",
    "int32_t": "i",
    "uint32_t": "I",
    "int64_t": "q",
    "uint64_t": "Q",
    "float": "f",
    "double": "d",
    "bool": "?",
    "char": "c",
}


class ULogWriter:
    """Builds a ULog file in memory: definitions first, then data, in timestamp order."""

    def __init__(self, start_us: int = 0) -> None:
        self._out = bytearray(MAGIC + bytes([VERSION]) + struct.pack("<Q", start_us))
        # Flag bits: no compatibility flags, no appended data.
        self._message(b"B", bytes(16) + bytes(24))
        self._packers: dict[str, struct.Struct] = {}
        self._subscriptions: list[struct.Struct] = []
        self._multi_ids: dict[str, int] = {}
        self._in_data = False
        self._last_us = start_us

    def _message(self, kind: bytes, payload: bytes) -> None:
        if len(payload) > 0xFFFF:
            raise ULogError(
                f"ULog message '{kind.decode()}' of {len(payload)} bytes (at most 65535)"
            )
        self._out += struct.pack("<HB", len(payload), kind[0]) + payload

    def _definition(self, what: str) -> None:
        if self._in_data:
            raise ULogError(f"{what} after the first data message: definitions come first")

    # -- definitions ------------------------------------------------------------------------

    def define(self, name: str, fields: Sequence[tuple[str, str]]) -> None:
        """A message format: ``fields`` are ``(type, name)``, e.g. ``("char[24]", "instance")``;
        the first must be ``("uint64_t", "timestamp")``."""
        self._definition(f"format {name}")
        if not fields or tuple(fields[0]) != ("uint64_t", "timestamp"):
            raise ULogError(f"format {name}: the first field must be uint64_t timestamp")
        codes = "".join(_code(kind, f"{name}.{field}") for kind, field in fields)
        self._packers[name] = struct.Struct("<" + codes)
        text = f"{name}:" + "".join(f"{kind} {field};" for kind, field in fields)
        self._message(b"F", text.encode())

    def info(self, key: str, value: str | int | float, *, multi: bool = False) -> None:
        """An information message (``multi``: one of several values under one key)."""
        self._definition(f"information {key}")
        head, body = _typed(key, value)
        kind, prefix = (b"M", b"\x00") if multi else (b"I", b"")
        self._message(kind, prefix + bytes([len(head)]) + head + body)

    def parameter(self, name: str, value: int | float) -> None:
        """A parameter's value at the start of the log: ``int32_t`` for an int, else ``float``."""
        self._definition(f"parameter {name}")
        head, body = _typed(name, value)
        self._message(b"P", bytes([len(head)]) + head + body)

    # -- data -------------------------------------------------------------------------------

    def subscribe(self, name: str) -> int:
        """Starts logging a defined message: its next instance (multi ID 0, 1, ...); returns the
        ID its data is written under."""
        packer = self._packers.get(name)
        if packer is None:
            raise ULogError(f"no format {name} defined")
        self._in_data = True
        msg_id = len(self._subscriptions)
        multi_id = self._multi_ids.get(name, 0)
        if msg_id > 0xFFFF or multi_id > 0xFF:
            raise ULogError(f"too many subscriptions of {name}")
        self._multi_ids[name] = multi_id + 1
        self._message(b"A", struct.pack("<BH", multi_id, msg_id) + name.encode())
        self._subscriptions.append(packer)
        return msg_id

    def data(self, msg_id: int, timestamp_us: int, *values: object) -> None:
        """One sample of subscription ``msg_id``: its timestamp, then the other fields."""
        self._advance(timestamp_us)
        packed = self._subscriptions[msg_id].pack(
            timestamp_us, *(v.encode() if isinstance(v, str) else v for v in values)
        )
        self._message(b"D", struct.pack("<H", msg_id) + packed)

    def log(self, level: str, timestamp_us: int, text: str) -> None:
        """A logged message (``level`` one of :data:`LEVELS`)."""
        self._in_data = True
        self._advance(timestamp_us)
        self._message(b"L", LEVELS[level] + struct.pack("<Q", timestamp_us) + text.encode())

    def _advance(self, timestamp_us: int) -> None:
        if timestamp_us < self._last_us:
            raise ULogError(
                f"timestamp {timestamp_us} us is before the previous one ({self._last_us} us)"
            )
        self._last_us = timestamp_us

    @property
    def last_timestamp_us(self) -> int:
        """The latest timestamp written so far: nothing may be written before it."""
        return self._last_us

    def getvalue(self) -> bytes:
        return bytes(self._out)


def _code(kind: str, where: str) -> str:
    base, bracket, count = kind.partition("[")
    code = _SCALARS.get(base)
    if code is None:
        raise ULogError(f"{where}: unknown ULog type {kind!r}")
    if not bracket:
        return code
    n = count[:-1]
    if not n.isdigit() or not count.endswith("]"):
        raise ULogError(f"{where}: bad array type {kind!r}")
    return f"{n}s" if base == "char" else code * int(n)


def _typed(key: str, value: str | int | float) -> tuple[bytes, bytes]:
    """An information or parameter key with its type (``char[9] sys_name``) and the value."""
    if isinstance(value, str):
        body = value.encode()
        return f"char[{len(body)}] {key}".encode(), body
    if isinstance(value, int):  # bool included
        return f"int32_t {key}".encode(), struct.pack("<i", int(value))
    return f"float {key}".encode(), struct.pack("<f", value)


# -- reading ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class ULogHeader:
    """What a log says about its vehicle: the information messages, the parameters at the start
    and their changes during the log, and the boot console (``boot_console_output``, which PX4
    logs since 1.12: every line the startup scripts printed)."""

    path: str
    info: dict[str, Any]
    initial_parameters: dict[str, int | float]
    #: ``(timestamp_us, name, value)`` of every parameter change logged, in time order.
    changed_parameters: list[tuple[int, str, int | float]] = field(default_factory=list)
    boot_console: str | None = None
    #: pyulog found data it could not read (a log cut short, or damaged): what came after it,
    #: parameters and messages, is missing.
    corrupt: bool = False

    @property
    def parameters(self) -> dict[str, int | float]:
        """Every parameter's last value in the log."""
        params = dict(self.initial_parameters)
        for _, name, value in self.changed_parameters:
            params[name] = value
        return params

    @property
    def release(self) -> int | None:
        """``ver_sw_release`` (major, minor, patch, type in its four bytes), None when the log
        has none (PX4 before 1.6) or it is 0."""
        value = self.info.get("ver_sw_release")
        return int(value) if isinstance(value, int) and value else None

    @property
    def hardware(self) -> str | None:
        """``ver_hw``, the board (``PX4_FMU_V5``, ``CUBEPILOT_CUBEORANGE``, ``PX4_SITL``)."""
        value = self.info.get("ver_hw")
        return str(value) if value else None


def read_header(path: str | os.PathLike[str]) -> ULogHeader:
    """Reads a log's definitions (no data messages: fast on large logs). A file that cannot be
    read or is not a ULog is a :class:`ULogError` naming it."""
    log = parse(path, [])
    changes = [(int(t), str(n), v) for t, n, v in log.changed_parameters]
    console = None
    parts = log.msg_info_multiple_dict.get("boot_console_output")
    if parts:  # one list of string pieces per logged copy; the first is the boot
        console = "".join(str(piece) for piece in parts[0])
    return ULogHeader(
        os.fspath(path),
        dict(log.msg_info_dict),
        dict(log.initial_parameters),
        changes,
        console,
        bool(log.file_corruption),
    )


#: How many times its size pyulog may read of a file (and 64 MiB more) before it is taken to go
#: round in circles. A whole log is read about once (1.1 times with appended data); getting past
#: damage rereads up to 64 KiB per byte skipped. pyulog 1.3.0 steps back over a damaged
#: message by the size it claims, not by what it read, which can bring it back where it was,
#: for ever (a 60 kB log with one size byte changed).
READ_BUDGET = 256


class _BudgetedFile:
    """A binary file whose reads stop, with :class:`ReadBudgetExceeded`, after ``budget``
    bytes: what pyulog calls of its file, no more. It also tells whether the file ended inside
    a message (:attr:`cut`), which pyulog takes for the log's end without a word."""

    def __init__(self, file: BinaryIO, budget: int) -> None:
        self._file = file
        self._budget = budget
        #: The size a message header just read declares: pyulog reads its body next.
        self._body: int | None = None
        #: The file ended inside a message: its header, or the body the header declared.
        self.cut = False
        #: Where the zeros that end the file begin (a card that lost power leaves its
        #: preallocated tail zero): reads end there. None until a header of zeros was read.
        self._zeros_from: int | None = None
        #: Where a nonzero byte was found after zeros: no need to look again before it.
        self._nonzero_at = -1

    def read(self, size: int = -1) -> bytes:
        if self._zeros_from is not None and self._file.tell() >= self._zeros_from:
            return b""
        data = self._file.read(size)
        self._budget -= len(data)
        if self._budget < 0:
            raise ReadBudgetExceeded
        if size == 3 and data == b"\0\0\0" and self._ends_in_zeros(self._file.tell() - 3):
            # No message is 3 zero bytes (type 0 is none): pyulog would step over the zeros one
            # byte at a time, 2 s a megabyte. The log ends where they start, cut.
            self._zeros_from = self._file.tell() - 3
            self.cut = True
            return b""
        # A message is a 3-byte header (uint16 size, uint8 type) and that many bytes. A read of
        # a header that finds no byte is the end; one that finds 1 or 2, or a body that finds
        # fewer than its header said, is a cut.
        body, self._body = self._body, None
        if size == body and body:
            self.cut |= len(data) < size
        elif size == 3:
            self.cut |= 0 < len(data) < 3
            if len(data) == 3:
                self._body = int.from_bytes(data[:2], "little")
        return data

    def _ends_in_zeros(self, start: int) -> bool:
        """Whether every byte from ``start`` to the file's end is zero (read past once: a
        nonzero byte found is remembered)."""
        if start < self._nonzero_at:
            return False
        here = self._file.tell()
        try:
            self._file.seek(start)
            position = start
            while chunk := self._file.read(1 << 20):
                stripped = chunk.lstrip(b"\0")
                if stripped:
                    self._nonzero_at = position + len(chunk) - len(stripped)
                    return False
                position += len(chunk)
            return True
        finally:
            self._file.seek(here)

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        # (The file's own error would be "[Errno 22] Invalid argument".)
        position = self._file.tell()
        start = {os.SEEK_SET: 0, os.SEEK_CUR: position}.get(whence)
        if start is not None and start + offset < 0:
            raise SeekBeforeStart(position, offset)
        return self._file.seek(offset, whence)

    def tell(self) -> int:
        return self._file.tell()

    def close(self) -> None:
        self._file.close()


def parse(path: str | os.PathLike[str], topics: Sequence[str] | None) -> ULog:
    """pyulog's reading of the log at ``path``, with the data messages of ``topics`` (``None``:
    all of them). Raises :class:`ULogError` naming the file when it cannot be read, is not a
    ULog, pyulog refuses it, or pyulog reads :data:`READ_BUDGET` times its size without
    finishing."""
    from pyulog import ULog  # only reading logs needs it

    where = os.fspath(path)
    try:
        file = open_file(where, ULOG)
    except OSError as e:
        raise ULogError(f"{where}: cannot read: {e.strerror or e}") from None
    with file:
        if file.read(len(MAGIC)) != MAGIC:
            raise ULogError(f"{where}: not a ULog file (it does not start with ULog's magic bytes)")
        file.seek(0)
        size = os.fstat(file.fileno()).st_size
        budgeted = _BudgetedFile(file, READ_BUDGET * size + 64 * 1024 * 1024)
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # pyulog prints its warnings
                log = ULog(budgeted, message_name_filter_list=topics)
            if budgeted.cut:
                # pyulog's flag for a log it could not read whole, which a cut one is: every
                # reader of the log says so (migrate's log_cut, devid's warning, health's end).
                log._file_corrupt = True
            return log
        except SeekBeforeStart as e:
            raise ULogError(
                f"{where}: not a readable ULog file (a damaged message before byte {e.position}: "
                f"pyulog stepped back {-e.offset} bytes over it, past the file's start)"
            ) from None
        except ReadBudgetExceeded:
            raise ULogError(
                f"{where}: not a readable ULog file (pyulog read more than {READ_BUDGET} times "
                f"its {size} bytes without finishing: a damaged message sends it round in circles)"
            ) from None
        except Exception as e:  # pyulog signals bad data with assorted exceptions
            raise ULogError(f"{where}: not a readable ULog file ({e})") from None


#: Topics whose samples carry the publishing sensor's ``device_id``.
SENSOR_TOPICS = (
    "sensor_accel",
    "sensor_gyro",
    "sensor_mag",
    "sensor_baro",
    "differential_pressure",
    "distance_sensor",
)


def read_device_ids(path: str | os.PathLike[str]) -> list[tuple[str, int, int]]:
    """``(topic, multi_id, device_id)`` of every sensor that published in the log (the sensor
    topics above; each distinct non-zero ``device_id`` once, in the order logged). Only those
    topics are parsed."""
    log = parse(path, list(SENSOR_TOPICS))
    found: list[tuple[str, int, int]] = []
    for data in log.data_list:
        ids = data.data.get("device_id")
        if ids is None:
            continue
        for value in dict.fromkeys(int(v) for v in ids):
            if value:
                found.append((data.name, int(data.multi_id), value))
    return found
