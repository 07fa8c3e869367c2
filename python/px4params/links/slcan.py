"""SLCAN (the LAWICEL serial line CAN protocol), both ends: an adapter with a node behind it, and
a host that drives an adapter.

A line is ASCII ending in CR. The host sends commands; the adapter answers CR (done) or BEL
(refused)::

    O / C / L          open, close, open listen-only
    S0 .. S8           bit rate 10k, 20k, 50k, 100k, 125k, 250k, 500k, 800k, 1M (closed only)
    V / v / N          versions / serial number: answered "V1013", "vSTM32", "NA123" + CR
    F                  status flags: "F00" + CR
    Z0 / Z1            time stamps off / on
    Tiiiiiiiildd..     send an extended frame (29-bit ID, length 0..8, data): answered "Z" + CR
    tiiildd..          send a standard frame (11-bit ID): answered "z" + CR

Received frames go to the host as the same ``T``/``t`` lines (with a four-digit millisecond time
stamp when ``Z1``), only while the channel is open. pydronecan's SLCAN driver, the DroneCAN GUI
tool and PX4's own SLCAN bridge speak this subset. CAN FD lines and remote frames are refused
with BEL.
"""

from __future__ import annotations

import binascii
import contextlib
import os
import select
import time
from typing import Protocol

from px4params.errors import SlcanError
from px4params.links.can_transfer import Frame

__all__ = [
    "ACK",
    "BITRATES",
    "NACK",
    "SerialPort",
    "SlcanAdapter",
    "SlcanError",
    "SlcanHost",
    "format_frame",
    "open_pty",
    "open_serial",
    "parse_frame",
    "read_port",
]

ACK = b"\r"
NACK = b"\x07"
#: ``S<n>``: bit rates in bit/s.
BITRATES = (10_000, 20_000, 50_000, 100_000, 125_000, 250_000, 500_000, 800_000, 1_000_000)
#: A line longer than the longest valid one (``T`` + 8 + 1 + 16 + 4) is noise: dropped.
_MAX_LINE = 64
#: Seconds a write waits for the other end to read before what is left is dropped (a
#: GetNodeInfo answer, 8 frames, takes 25 ms at 115200 baud).
WRITE_SECONDS = 0.5


class SerialPort(Protocol):
    """What both ends need of a serial line: a file descriptor to wait on, read and write."""

    def fileno(self) -> int: ...
    def read(self, size: int) -> bytes: ...
    def write(self, data: bytes) -> int | None: ...


def parse_frame(line: bytes) -> Frame:
    """A ``T``/``t`` line (without its CR; a time stamp after the data is ignored) as a frame.

    Raises:
        SlcanError: not a data frame line, or a bad ID, length or data.
    """
    text = line.decode("ascii", "replace")
    if text[:1] not in ("T", "t"):
        raise SlcanError(f"'{text[:20]}' is not a data frame line (expected T or t)")
    id_len = 8 if text[0] == "T" else 3
    head = text[1 : 2 + id_len]
    if len(head) != id_len + 1 or not _is_hex(head):
        raise SlcanError(f"'{text[:20]}': expected {id_len} hex digits of ID and a length digit")
    can_id, length = int(head[:-1], 16), int(head[-1], 16)
    if can_id >= 1 << (29 if id_len == 8 else 11) or length > 8:
        raise SlcanError(f"'{text[:20]}': ID or length out of range (length 0..8)")
    data_hex = text[2 + id_len : 2 + id_len + 2 * length]
    rest = text[2 + id_len + 2 * length :]
    if len(data_hex) != 2 * length or not _is_hex(data_hex) or (rest and len(rest) != 4):
        raise SlcanError(f"'{text[:30]}': expected {length} data bytes in hex")
    return Frame(can_id, binascii.unhexlify(data_hex))


def format_frame(frame: Frame, *, stamp_ms: int | None = None) -> bytes:
    """The ``T`` line of an extended frame (CR included), with a time stamp when given."""
    line = f"T{frame.can_id:08X}{len(frame.data)}{frame.data.hex().upper()}"
    if stamp_ms is not None:
        line += f"{stamp_ms % 60_000:04X}"
    return line.encode("ascii") + ACK


def _is_hex(text: str) -> bool:
    return all(c in "0123456789abcdefABCDEF" for c in text)


class SlcanAdapter:
    """The adapter end: feed it what the host wrote; it returns the answer bytes and the frames
    the host sent. :meth:`deliver` formats a frame from the bus for the host."""

    #: What ``V`` and ``v`` and ``N`` answer.
    VERSION = b"V1013"
    DETAILS = b"vpx4params"
    SERIAL = b"NPX4P"

    def __init__(self) -> None:
        self.open = False
        self.listen_only = False
        self.bitrate = 1_000_000
        self.timestamps = False
        self._line = bytearray()
        self._dropping = False
        self._started = time.monotonic()
        #: Counters: lines answered, refused (BEL), frames from the host.
        self.stats = {"commands": 0, "refused": 0, "frames": 0}

    def feed(self, data: bytes) -> tuple[bytes, list[Frame]]:
        """Answers for every complete line in ``data`` and the frames they carried."""
        replies = bytearray()
        frames: list[Frame] = []
        for byte in data:
            if byte in (0x0D, 0x0A):
                if self._dropping:
                    self._dropping = False
                    replies += NACK
                    self.stats["refused"] += 1
                elif self._line or byte == 0x0D:
                    reply, frame = self._command(bytes(self._line))
                    replies += reply
                    if frame is not None:
                        frames.append(frame)
                self._line.clear()
            elif len(self._line) >= _MAX_LINE:
                self._line.clear()
                self._dropping = True
            elif not self._dropping:
                self._line.append(byte)
        return bytes(replies), frames

    def deliver(self, frame: Frame) -> bytes:
        """The line that gives ``frame`` to the host (nothing while the channel is closed)."""
        if not self.open:
            return b""
        stamp = int((time.monotonic() - self._started) * 1000) if self.timestamps else None
        return format_frame(frame, stamp_ms=stamp)

    def _command(self, line: bytes) -> tuple[bytes, Frame | None]:
        self.stats["commands"] += 1
        head, arg = line[:1], line[1:]
        if not line:
            return ACK, None  # an empty line resets the host's parser: answered
        if head in (b"T", b"t"):
            if not self.open or self.listen_only:
                return self._refuse()
            try:
                frame = parse_frame(line)
            except SlcanError:
                return self._refuse()
            self.stats["frames"] += 1
            return (b"Z" if head == b"T" else b"z") + ACK, frame
        if head in (b"O", b"L") and not arg:
            if self.open:
                return self._refuse()
            self.open, self.listen_only = True, head == b"L"
            return ACK, None
        if head == b"C" and not arg:
            self.open = False  # closing a closed channel is fine: hosts do it first
            return ACK, None
        if head == b"S" and len(arg) == 1 and arg.isdigit() and int(arg) < len(BITRATES):
            if self.open:
                return self._refuse()
            self.bitrate = BITRATES[int(arg)]
            return ACK, None
        if head == b"Z" and arg in (b"0", b"1"):
            self.timestamps = arg == b"1"
            return ACK, None
        if line == b"V":
            return self.VERSION + ACK, None
        if line == b"v":
            return self.DETAILS + ACK, None
        if line == b"N":
            return self.SERIAL + ACK, None
        if line == b"F":
            return b"F00" + ACK, None
        return self._refuse()

    def _refuse(self) -> tuple[bytes, None]:
        self.stats["refused"] += 1
        return NACK, None


class SlcanHost:
    """The host end, driving an adapter on ``port``: :meth:`start` opens the channel,
    :meth:`send` and :meth:`receive` carry frames."""

    def __init__(self, port: SerialPort, *, timeout: float = 1.0) -> None:
        self.port = port
        self.timeout = timeout
        self._buffer = bytearray()
        self._frames: list[Frame] = []

    def start(self, bitrate: int = 1_000_000) -> None:
        """Closes the channel (some adapters refuse to reopen an open one), sets the bit rate,
        opens it.

        Raises:
            SlcanError: the adapter did not acknowledge (it names the command).
        """
        if bitrate not in BITRATES:
            raise SlcanError(
                f"bit rate {bitrate} is not an SLCAN rate ({', '.join(map(str, BITRATES))})"
            )
        self._command(b"", required=False)
        self._command(b"C", required=False)
        self._command(b"S%d" % BITRATES.index(bitrate))
        self._command(b"O")

    def stop(self) -> None:
        self.port.write(b"C\r")

    def _command(self, command: bytes, *, required: bool = True) -> None:
        self.port.write(command + ACK)
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            for line, end in self._lines(deadline - time.monotonic()):
                if end == NACK and required:
                    raise SlcanError(f"the adapter refused '{command.decode()}' (BEL)")
                if line[:1] in (b"T", b"t"):
                    self._keep(line)
                    continue
                return
        if required:
            raise SlcanError(
                f"the adapter did not answer '{command.decode()}' within {self.timeout:g} s "
                "(is it an SLCAN adapter?)"
            )

    def send(self, frame: Frame) -> None:
        self.port.write(format_frame(frame))

    def receive(self, timeout: float) -> Frame | None:
        """The next frame from the bus, waiting up to ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while not self._frames:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            for line, _ in self._lines(left):
                self._keep(line)
        return self._frames.pop(0)

    def _keep(self, line: bytes) -> None:
        if line[:1] in (b"T", b"t"):
            with contextlib.suppress(SlcanError):  # noise: a frame is lost, as on a bus
                self._frames.append(parse_frame(line))

    def _lines(self, timeout: float) -> list[tuple[bytes, bytes]]:
        """Complete lines (without the end byte) and their end bytes, reading for up to
        ``timeout`` seconds when none is buffered."""
        if not any(b in self._buffer for b in (0x0D, 0x07)):
            ready, _, _ = select.select([self.port.fileno()], [], [], max(0.0, timeout))
            if ready:
                self._buffer += read_port(self.port)
        lines: list[tuple[bytes, bytes]] = []
        start = 0
        for i, byte in enumerate(self._buffer):
            if byte in (0x0D, 0x07):
                lines.append((bytes(self._buffer[start:i]).strip(b"\n"), bytes([byte])))
                start = i + 1
        del self._buffer[:start]
        return lines


def read_port(port: SerialPort) -> bytes:
    """What is waiting on a port that ``select`` found readable.

    Raises:
        SlcanError: the line is gone (a USB device unplugged, the other end of a pty closed).
    """
    try:
        chunk = port.read(4096)
    except OSError as e:  # pyserial's SerialException is one
        raise SlcanError(f"the serial line failed: {e}") from None
    if not chunk:
        raise SlcanError("the serial line was closed")
    return chunk


class _FdPort:
    """A file descriptor (a pty's master end) as a :class:`SerialPort`."""

    def __init__(self, fd: int, keep_open: int | None = None) -> None:
        self.fd = fd
        self._keep_open = keep_open

    def fileno(self) -> int:
        return self.fd

    def read(self, size: int) -> bytes:
        try:
            return os.read(self.fd, size)
        except OSError:  # the other end closed (EIO on Linux)
            return b""

    def write(self, data: bytes) -> int:
        """Writes ``data``, waiting at most :data:`WRITE_SECONDS` for the other end to read;
        returns how many bytes went (fewer: the rest is dropped, as an adapter drops frames
        its host does not take)."""
        view, deadline = memoryview(data), time.monotonic() + WRITE_SECONDS
        while view:
            try:
                written = os.write(self.fd, view)
            except BlockingIOError:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                select.select([], [self.fd], [], left)
                continue
            view = view[written:]
        return len(data) - len(view)

    def close(self) -> None:
        os.close(self.fd)
        if self._keep_open is not None:
            os.close(self._keep_open)


def open_pty() -> tuple[_FdPort, str]:
    """A pseudo-terminal in raw mode: the master end as a port, and the path of the slave end
    for a client to open (``/dev/pts/N``)."""
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    os.set_blocking(master, False)
    # The slave end stays open here too, so that the master does not read EIO between clients.
    return _FdPort(master, keep_open=slave), path


def open_serial(device: str, baudrate: int = 115_200) -> SerialPort:
    """A serial device (USB CDC, a UART, a pty) in raw mode.

    Raises:
        SlcanError: it cannot be opened (the message says why).
    """
    import serial

    try:
        port: SerialPort = serial.Serial(
            device, baudrate=baudrate, timeout=0, write_timeout=WRITE_SECONDS
        )
        return port
    except (serial.SerialException, OSError, ValueError) as e:
        raise SlcanError(f"cannot open serial device {device}: {e}") from None
