"""SLCAN, both ends (``px4params.links.slcan``), in-process. The rule is the LAWICEL CAN232/CANUSB
protocol as pydronecan's SLCAN driver and PX4's SLCAN bridge speak it: a command is one ASCII
line ended by CR, answered CR when done and BEL when refused; ``Tiiiiiiiildd..`` carries an
extended frame (8 hex digits of 29-bit ID, a length digit 0..8, the data in hex), ``tiiildd..`` a
standard one (11-bit ID), optionally followed by a four-hex-digit millisecond time stamp that
wraps at 60000 (``Z1``). The adapter's and host's peer here is the other end written by hand:
command lines typed as a host types them, answer lines as an adapter answers."""

from __future__ import annotations

import os
import select
import threading
import time
import types
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from px4params.links import slcan
from px4params.links.can_transfer import Frame
from px4params.links.slcan import (
    BITRATES,
    WRITE_SECONDS,
    SlcanAdapter,
    SlcanError,
    SlcanHost,
    format_frame,
    open_pty,
    open_serial,
    parse_frame,
    read_port,
)

# -- frame lines -------------------------------------------------------------------------------


def test_the_largest_ids_and_length_are_frames_one_more_is_refused() -> None:
    assert parse_frame(b"T1FFFFFFF0") == Frame(0x1FFFFFFF, b"")  # 29 bits
    assert parse_frame(b"t7FF0") == Frame(0x7FF, b"")  # 11 bits
    eight = parse_frame(b"T0000000180001020304050607")
    assert eight == Frame(1, bytes(range(8)))
    with pytest.raises(
        SlcanError, match=r"^'T200000000': ID or length out of range \(length 0..8\)$"
    ):
        parse_frame(b"T200000000")
    with pytest.raises(SlcanError, match=r"^'t8000': ID or length out of range \(length 0..8\)$"):
        parse_frame(b"t8000")


def test_a_frame_line_takes_lower_case_hex_and_a_four_digit_stamp_only() -> None:
    assert parse_frame(b"t7ff2abcd") == Frame(0x7FF, b"\xab\xcd")
    assert parse_frame(b"t7ff2abcd00ff") == Frame(0x7FF, b"\xab\xcd")
    for stamp in (b"0", b"000", b"00000"):
        with pytest.raises(SlcanError, match=r"expected 2 data bytes in hex$"):
            parse_frame(b"t7ff2abcd" + stamp)


def test_a_frame_line_without_its_length_digit_is_named() -> None:
    with pytest.raises(
        SlcanError, match=r"^'T1E01017F': expected 8 hex digits of ID and a length digit$"
    ):
        parse_frame(b"T1E01017F")
    with pytest.raises(
        SlcanError, match=r"^'t12': expected 3 hex digits of ID and a length digit$"
    ):
        parse_frame(b"t12")
    for bad in (b"tx230", b"tX230", b"TXXXXXXXX0"):  # x and X are no hex digits
        with pytest.raises(SlcanError, match=r"hex digits of ID and a length digit$"):
            parse_frame(bad)
    with pytest.raises(SlcanError, match=r"^'t1232XX00': expected 2 data bytes in hex$"):
        parse_frame(b"t1232XX00")


def test_errors_quote_the_start_of_a_long_line() -> None:
    """A line is quoted up to 20 characters (30 for bad data), so that noise stays one line."""
    with pytest.raises(SlcanError) as bad_head:
        parse_frame(b"X" + b"0123456789" * 4)
    assert (
        str(bad_head.value) == "'X0123456789012345678' is not a data frame line (expected T or t)"
    )
    with pytest.raises(SlcanError) as bad_id:
        parse_frame(b"TZZZZZZZZ0" + b"0123456789" * 4)
    assert str(bad_id.value) == (
        "'TZZZZZZZZ00123456789': expected 8 hex digits of ID and a length digit"
    )
    with pytest.raises(SlcanError) as bad_length:
        parse_frame(b"T00000001F" + b"0123456789" * 4)
    assert str(bad_length.value) == (
        "'T00000001F0123456789': ID or length out of range (length 0..8)"
    )
    with pytest.raises(SlcanError) as bad_data:
        parse_frame(b"T000000018" + b"0123456789" * 4)
    assert str(bad_data.value) == "'T00000001801234567890123456789': expected 8 data bytes in hex"


def test_a_line_that_is_not_ascii_is_refused_by_name() -> None:
    with pytest.raises(SlcanError, match=r"^'\ufffd123' is not a data frame line"):
        parse_frame(b"\xff123")


def test_a_frame_is_written_in_upper_case_with_its_id_padded_to_eight_digits() -> None:
    assert format_frame(Frame(0xAB, b"\xfe\x0a")) == b"T000000AB2FE0A\r"
    assert format_frame(Frame(0x1FFFFFFF, b"")) == b"T1FFFFFFF0\r"


def test_a_time_stamp_is_four_hex_digits_that_wrap_at_a_minute() -> None:
    frame = Frame(1, b"")
    assert format_frame(frame, stamp_ms=0) == b"T0000000100000\r"
    assert format_frame(frame, stamp_ms=59_999) == b"T000000010EA5F\r"
    assert format_frame(frame, stamp_ms=60_000) == b"T0000000100000\r"
    assert format_frame(frame, stamp_ms=60_001 + 60_000) == b"T0000000100001\r"


# -- the adapter end ---------------------------------------------------------------------------


def test_each_command_is_answered_cr_when_done_and_bel_when_refused() -> None:
    adapter = SlcanAdapter()
    assert adapter.feed(b"v\r") == (b"vpx4params\r", [])
    assert adapter.feed(b"F\r") == (b"F00\r", [])
    for wrong in (
        b"V1",
        b"v1",
        b"N1",
        b"F1",
        b"O1",
        b"L1",
        b"C1",
        b"Z2",
        b"Z",
        b"S",
        b"S9",
        b"S10",
    ):
        assert adapter.feed(wrong + b"\r") == (b"\x07", []), wrong
    assert adapter.feed(b"Sx\r") == (b"\x07", [])
    assert not adapter.open and adapter.bitrate == 1_000_000


def test_every_bit_rate_digit_sets_its_rate() -> None:
    """LAWICEL's table: S0 10 kbit/s, S1 20k, S2 50k, S3 100k, S4 125k, S5 250k, S6 500k,
    S7 800k, S8 1 Mbit/s."""
    lawicel = [10_000, 20_000, 50_000, 100_000, 125_000, 250_000, 500_000, 800_000, 1_000_000]
    adapter = SlcanAdapter()
    for digit, rate in enumerate(lawicel):
        assert adapter.feed(b"S%d\r" % digit) == (b"\r", [])
        assert adapter.bitrate == rate
    assert list(BITRATES) == lawicel


def test_open_twice_is_refused_and_close_twice_is_not() -> None:
    adapter = SlcanAdapter()
    assert adapter.feed(b"C\r") == (b"\r", [])
    assert adapter.feed(b"O\r") == (b"\r", []) and adapter.open
    assert adapter.feed(b"O\r") == (b"\x07", []) and adapter.open
    assert adapter.feed(b"L\r") == (b"\x07", []) and not adapter.listen_only
    assert adapter.feed(b"C\rC\r") == (b"\r\r", []) and not adapter.open


def test_listen_only_refuses_to_send_but_delivers() -> None:
    adapter = SlcanAdapter()
    assert adapter.feed(b"L\r") == (b"\r", [])
    assert adapter.open and adapter.listen_only
    assert adapter.feed(b"T000000010\rt0010\r") == (b"\x07\x07", [])
    assert adapter.deliver(Frame(2, b"\x01")) == b"T00000002101\r"
    # closed and opened with O: sending again
    assert adapter.feed(b"C\rO\r") == (b"\r\r", [])
    assert not adapter.listen_only
    assert adapter.feed(b"t0010\r") == (b"z\r", [Frame(1, b"")])


def test_a_line_may_end_in_lf_and_an_empty_lf_line_is_not_answered() -> None:
    adapter = SlcanAdapter()
    assert adapter.feed(b"V\n") == (b"V1013\r", [])
    assert adapter.feed(b"V\r\n") == (b"V1013\r", [])  # CR LF: one answer
    assert adapter.feed(b"\n\n") == (b"", [])
    assert adapter.feed(b"\r") == (b"\r", [])  # an empty CR line resets the host's parser
    assert adapter.stats["commands"] == 3


def test_a_line_split_over_reads_is_one_command() -> None:
    adapter = SlcanAdapter()
    assert adapter.feed(b"O") == (b"", [])
    assert adapter.feed(b"\rT0000") == (b"\r", [])
    assert adapter.feed(b"00011") == (b"", [])
    assert adapter.feed(b"AA\r") == (b"Z\r", [Frame(1, b"\xaa")])


def test_a_line_of_64_bytes_is_read_and_a_longer_one_dropped_whole() -> None:
    adapter = SlcanAdapter()
    assert adapter.feed(b"V" * 64 + b"\r") == (b"\x07", [])
    assert adapter.stats == {"commands": 1, "refused": 1, "frames": 0}
    # 65 bytes: dropped unread (no command), BEL once, the rest of it ignored up to its end
    assert adapter.feed(b"V" * 65 + b"\r") == (b"\x07", [])
    assert adapter.stats == {"commands": 1, "refused": 2, "frames": 0}
    assert adapter.feed(b"O" * 70 + b"\nO\r") == (b"\x07\r", [])
    assert adapter.open
    assert adapter.stats == {"commands": 2, "refused": 3, "frames": 0}


def test_a_runaway_line_s_bel_follows_the_answers_before_it() -> None:
    adapter = SlcanAdapter()
    assert adapter.feed(b"V\r" + b"X" * 70 + b"\rN\r") == (b"V1013\r\x07NPX4P\r", [])


def test_the_counters_count_lines_refusals_and_frames() -> None:
    adapter = SlcanAdapter()
    adapter.feed(b"O\rT000000010\rt0010\rQ\rQ\r")
    assert adapter.stats == {"commands": 5, "refused": 2, "frames": 2}


def test_time_stamps_count_milliseconds_since_the_adapter_started(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    clock = [100.0]
    monkeypatch.setattr(slcan, "time", types.SimpleNamespace(monotonic=lambda: clock[0]))
    adapter = SlcanAdapter()
    assert adapter.feed(b"O\rZ1\r") == (b"\r\r", [])
    clock[0] = 101.5
    assert adapter.deliver(Frame(1, b"")) == b"T00000001005DC\r"  # 1500 ms
    clock[0] = 100.0 + 61.5
    assert adapter.deliver(Frame(1, b"")) == b"T00000001005DC\r"  # wrapped at 60 000 ms
    assert adapter.feed(b"Z0\r") == (b"\r", [])
    assert adapter.deliver(Frame(1, b"")) == b"T000000010\r"


# -- the host end ------------------------------------------------------------------------------


class Peer:
    """The adapter side of the line as a port: what the host writes goes to ``answer``, whose
    bytes wait in a pipe for the host to read."""

    def __init__(self, answer: Callable[[bytes], bytes]) -> None:
        self._read, self._write = os.pipe()
        self.answer = answer
        self.written = bytearray()

    def fileno(self) -> int:
        return self._read

    def read(self, size: int) -> bytes:
        return os.read(self._read, size)

    def write(self, data: bytes) -> int:
        self.written += data
        reply = self.answer(data)
        if reply:
            os.write(self._write, reply)
        return len(data)

    def push(self, data: bytes) -> None:
        os.write(self._write, data)

    def close(self) -> None:
        os.close(self._read)
        os.close(self._write)


@pytest.fixture
def adapter_peer() -> Iterator[tuple[SlcanAdapter, Peer]]:
    adapter = SlcanAdapter()
    peer = Peer(lambda data: adapter.feed(data)[0])
    yield adapter, peer
    peer.close()


def test_the_host_resets_closes_sets_the_rate_then_opens(
    adapter_peer: tuple[SlcanAdapter, Peer],
) -> None:
    adapter, peer = adapter_peer
    SlcanHost(peer, timeout=2).start(500_000)
    assert bytes(peer.written) == b"\rC\rS6\rO\r"
    assert adapter.open and adapter.bitrate == 500_000
    SlcanHost(peer).stop()
    assert peer.written.endswith(b"\rC\r") and not adapter.open


def test_the_host_starts_at_1_mbit_by_default(adapter_peer: tuple[SlcanAdapter, Peer]) -> None:
    adapter, peer = adapter_peer
    SlcanHost(peer, timeout=2).start()
    assert bytes(peer.written) == b"\rC\rS8\rO\r" and adapter.bitrate == 1_000_000


def test_the_host_waits_a_second_for_an_answer_by_default() -> None:
    peer = Peer(lambda data: b"\r")
    try:
        assert SlcanHost(peer).timeout == 1.0
    finally:
        peer.close()


def test_the_host_refuses_a_rate_slcan_has_no_digit_for() -> None:
    peer = Peer(lambda data: b"\r")
    try:
        with pytest.raises(SlcanError) as refused:
            SlcanHost(peer).start(1_500_000)
        assert str(refused.value) == (
            "bit rate 1500000 is not an SLCAN rate (10000, 20000, 50000, 100000, 125000, "
            "250000, 500000, 800000, 1000000)"
        )
        assert peer.written == b""
    finally:
        peer.close()


def test_the_host_tolerates_a_refused_reset_and_close_but_not_a_refused_open() -> None:
    refuse = {b"\r", b"C\r"}
    peer = Peer(lambda data: b"\x07" if data in refuse else b"\r")
    try:
        SlcanHost(peer, timeout=2).start()  # an adapter that refuses C while closed: fine
        refuse.add(b"O\r")
        with pytest.raises(SlcanError, match=r"^the adapter refused 'O' \(BEL\)$"):
            SlcanHost(peer, timeout=2).start()
    finally:
        peer.close()


def test_a_silent_adapter_is_named_with_the_command_and_the_wait() -> None:
    peer = Peer(lambda data: b"")
    try:
        with pytest.raises(SlcanError) as silent:
            SlcanHost(peer, timeout=0.05).start()
        assert str(silent.value) == (
            "the adapter did not answer 'S8' within 0.05 s (is it an SLCAN adapter?)"
        )
        assert bytes(peer.written) == b"\rC\rS8\r"  # the reset and close may go unanswered
    finally:
        peer.close()


def test_frames_that_arrive_before_an_answer_are_kept_for_receive() -> None:
    frames = b"T000000010\rt0021AB\r"
    peer = Peer(lambda data: frames + b"\r" if data == b"O\r" else b"\r")
    try:
        host = SlcanHost(peer, timeout=2)
        host.start()
        assert host.receive(1) == Frame(1, b"")
        assert host.receive(1) == Frame(2, b"\xab")
        assert host.receive(0.01) is None
    finally:
        peer.close()


def test_the_host_receives_frames_in_order_dropping_noise(
    adapter_peer: tuple[SlcanAdapter, Peer],
) -> None:
    adapter, peer = adapter_peer
    host = SlcanHost(peer, timeout=2)
    host.start()
    adapter.feed(b"Z1\r")
    peer.push(
        adapter.deliver(Frame(0x10, b"\x01")) + b"TZZ\r" + b"\n" + adapter.deliver(Frame(0x11, b""))
    )
    peer.push(b"T0000001")  # half a line: waits for its end
    assert host.receive(1) == Frame(0x10, b"\x01")
    assert host.receive(1) == Frame(0x11, b"")
    assert host.receive(0.01) is None
    peer.push(b"22BEEF\r")
    assert host.receive(1) == Frame(0x12, b"\xbe\xef")
    assert host.receive(0) is None


def test_the_host_sends_a_frame_as_a_t_line(adapter_peer: tuple[SlcanAdapter, Peer]) -> None:
    adapter, peer = adapter_peer
    host = SlcanHost(peer, timeout=2)
    host.start()
    sent: list[Frame] = []
    peer.answer = lambda data: (lambda out: sent.extend(out[1]) or out[0])(adapter.feed(data))
    host.send(Frame(0x1E01017F, b"\x01\x02"))
    assert peer.written.endswith(b"T1E01017F20102\r") and sent == [Frame(0x1E01017F, b"\x01\x02")]


# -- serial lines ------------------------------------------------------------------------------


def test_a_closed_line_is_one_error() -> None:
    class Closed:
        def fileno(self) -> int:
            return 0

        def read(self, size: int) -> bytes:
            return b""

        def write(self, data: bytes) -> int:
            return len(data)

    with pytest.raises(SlcanError, match=r"^the serial line was closed$"):
        read_port(Closed())


def test_read_port_reads_up_to_4096_bytes() -> None:
    sizes = []

    class Port:
        def fileno(self) -> int:
            return 0

        def read(self, size: int) -> bytes:
            sizes.append(size)
            return b"x"

        def write(self, data: bytes) -> int:
            return len(data)

    assert read_port(Port()) == b"x" and sizes == [4096]


def test_a_pty_carries_bytes_both_ways_and_reads_nothing_once_closed() -> None:
    port, path = open_pty()
    client = os.open(path, os.O_RDWR | os.O_NOCTTY)
    try:
        assert port.write(b"V1013\r") == 6
        assert os.read(client, 100) == b"V1013\r"  # raw mode: CR stays CR
        os.write(client, b"O\r")
        select.select([port.fileno()], [], [], 5)
        assert read_port(port) == b"O\r"
    finally:
        os.close(client)
        port.close()
    assert port.read(10) == b""  # the descriptor is gone: nothing, no exception


def test_a_pty_write_larger_than_its_buffer_waits_for_the_reader() -> None:
    port, path = open_pty()
    client = os.open(path, os.O_RDWR | os.O_NOCTTY)
    data = bytes(range(256)) * 1024  # 256 KiB, far beyond a pty's buffer
    got = bytearray()

    def drain() -> None:
        while len(got) < len(data):
            ready, _, _ = select.select([client], [], [], 10)
            if not ready:
                return
            got.extend(os.read(client, 65536))

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    try:
        assert port.write(data) == len(data)
        reader.join(timeout=30)
        assert bytes(got) == data
    finally:
        os.close(client)
        port.close()


def test_a_pty_write_nobody_reads_gives_up_after_its_wait() -> None:
    # A host that stops reading: the write waited for it forever (the node then answered
    # nothing and ignored SIGTERM); now it waits WRITE_SECONDS and says how much went.
    assert WRITE_SECONDS == 0.5  # as docs/dronecan.md says
    port, path = open_pty()
    client = os.open(path, os.O_RDWR | os.O_NOCTTY)
    data = bytes(range(256)) * 1024  # far beyond a pty's buffer
    try:
        started = time.monotonic()
        went = port.write(data)
        took = time.monotonic() - started
        assert 0 < went < len(data)
        assert WRITE_SECONDS <= took < WRITE_SECONDS + 2
        # What went is what the reader gets: the start of the data, whole.
        got = bytearray()
        while select.select([client], [], [], 0.2)[0]:
            got += os.read(client, 65536)
        assert bytes(got) == data[:went]
    finally:
        os.close(client)
        port.close()


def test_open_serial_opens_a_device_raw_and_names_one_that_is_missing(tmp_path: object) -> None:
    port, path = open_pty()
    try:
        device = open_serial(path)
        try:
            os.write(port.fileno(), b"t0010\r\n")
            select.select([device.fileno()], [], [], 5)
            assert read_port(device) == b"t0010\r\n"  # raw: no CR/LF translation
        finally:
            device.close()  # type: ignore[attr-defined]
    finally:
        port.close()
    missing = f"{tmp_path}/ttyNONE"
    with pytest.raises(SlcanError, match=f"^cannot open serial device {missing}: "):
        open_serial(missing)


# -- the host's waits (issue 40, mutlinks2) ----------------------------------------------------


@pytest.mark.issue40
@pytest.mark.parametrize("noise", [0x0E, 0x08], ids=["SO", "BS"])
def test_a_noisy_half_line_does_not_keep_the_host_from_the_lines_after_it(noise: int) -> None:
    """A control byte of line noise (not CR, not BEL) in a line not yet ended: the line is
    read on until its CR and dropped as noise; the frames after it are received."""
    peer = Peer(lambda data: b"")
    try:
        host = SlcanHost(peer)
        peer.push(bytes([noise]) + b"T000")  # half a line, starting with noise
        assert host.receive(0.01) is None
        peer.push(b"00010\r" + format_frame(Frame(0x12, b"\xbe\xef")))
        assert host.receive(1) == Frame(0x12, b"\xbe\xef")
    finally:
        peer.close()


@pytest.mark.issue40
def test_the_host_waits_for_the_line_no_longer_than_the_time_it_was_given(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """receive(timeout) waits up to ``timeout`` seconds: each wait on the silent line is at
    most what is left of it."""
    waits: list[float] = []

    def recording(read: list[int], write: list[int], error: list[int], wait: float) -> Any:
        waits.append(wait)
        return select.select(read, write, error, wait)

    monkeypatch.setattr(slcan, "select", types.SimpleNamespace(select=recording))
    peer = Peer(lambda data: b"")
    try:
        assert SlcanHost(peer).receive(0.05) is None
    finally:
        peer.close()
    assert waits and all(0 <= wait <= 0.05 for wait in waits)


@pytest.mark.issue40
def test_a_line_with_noise_before_its_t_is_dropped_not_read_as_a_frame() -> None:
    """A frame line starts with T or t; a stray byte before it (not an LF, which ends a CR LF
    line) makes the line noise, lost as on a bus."""
    peer = Peer(lambda data: b"")
    try:
        host = SlcanHost(peer)
        peer.push(b"X" + format_frame(Frame(0x11, b"\x01")) + format_frame(Frame(0x12, b"")))
        assert host.receive(1) == Frame(0x12, b"")
        assert host.receive(0) is None
    finally:
        peer.close()


@pytest.mark.issue40
def test_a_pty_opened_and_closed_leaves_no_descriptor_open() -> None:
    """Both ends of the pseudo-terminal (the master, and the slave kept open so that the
    master does not read EIO between clients) are closed with the port."""
    before = set(os.listdir("/proc/self/fd"))
    port, _ = open_pty()
    assert len(set(os.listdir("/proc/self/fd")) - before) == 2
    port.close()
    assert set(os.listdir("/proc/self/fd")) == before


@pytest.mark.issue40
def test_a_pty_s_port_does_not_block() -> None:
    """The serving loop writes and reads the master end only when select says it can, and a
    write to a full pty waits in select (BlockingIOError), not in the kernel: the master end
    is non-blocking; a read with nothing waiting gives nothing at once."""
    port, _ = open_pty()
    try:
        assert os.get_blocking(port.fileno()) is False
        assert port.read(10) == b""
    finally:
        port.close()


@pytest.mark.issue40
def test_open_serial_reads_what_is_waiting_at_115200_baud_by_default() -> None:
    """pyserial's timeout 0 returns what is waiting at once (the port is read after select
    found it readable, never to wait for 4096 bytes); 115200 baud is the UART rate the
    figures of docs/dronecan.md assume (a USB CDC line ignores it)."""
    port, path = open_pty()
    try:
        device = open_serial(path)
        try:
            assert (device.baudrate, device.timeout) == (115_200, 0)  # type: ignore[attr-defined]
        finally:
            device.close()  # type: ignore[attr-defined]
    finally:
        port.close()
