"""The MAVLink FTP server (links/mavlink_ftp.py) where the other tests leave it open: the
sequence number's wrap, the burst's length, directory listings that fill a payload, paths
written loosely, and which abandoned session is taken over when. Byte layouts are taken from
the protocol's definition (mavlink.io/en/services/ftp.html): a 12-byte header (seq uint16,
session, opcode, size, req_opcode, burst_complete, padding, offset uint32), then at most 239
data bytes."""

from __future__ import annotations

import struct
from typing import NamedTuple

from px4params.links.mavlink_ftp import MavftpServer

HEADER = struct.Struct("<HBBBBBBI")
PAYLOAD = 251
TERMINATE, RESET, LIST, OPEN_RO, READ, CRC32, BURST = 1, 2, 3, 4, 5, 14, 15
ACK, NAK = 128, 129
INVALID_SESSION, NO_SESSIONS, EOF, NOT_FOUND = 4, 5, 6, 10


def request(
    opcode: int, *, seq: int = 0, session: int = 0, offset: int = 0, data: bytes = b""
) -> bytes:
    """A request payload built by hand from the protocol's layout."""
    return (HEADER.pack(seq, session, opcode, len(data), 0, 0, 0, offset) + data).ljust(
        PAYLOAD, b"\0"
    )


class Reply(NamedTuple):
    """A response payload taken apart by the protocol's layout."""

    seq: int
    session: int
    opcode: int
    req: int
    burst_complete: int
    offset: int
    data: bytes


def replies(
    server: MavftpServer, opcode: int, *, seq: int = 0, session: int = 0, offset: int = 0,
    data: bytes = b"",
) -> list[Reply]:  # fmt: skip
    out = []
    for payload in server.handle(
        request(opcode, seq=seq, session=session, offset=offset, data=data)
    ):
        assert len(payload) == PAYLOAD
        assert payload[7] == 0  # the padding byte, zero as PX4 sends it
        seq_, session_, op, size, req, burst_complete, _, offset_ = HEADER.unpack_from(payload)
        out.append(Reply(seq_, session_, op, req, burst_complete, offset_, payload[12 : 12 + size]))
    return out


def reply(
    server: MavftpServer, opcode: int, *, seq: int = 0, session: int = 0, offset: int = 0,
    data: bytes = b"",
) -> Reply:  # fmt: skip
    (only,) = replies(server, opcode, seq=seq, session=session, offset=offset, data=data)
    return only


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_the_sequence_number_wraps_at_16_bits() -> None:
    # seq_number is a uint16: the reply to 65535 is 0.
    server = MavftpServer({"/f": b"abc"})
    opened = reply(server, OPEN_RO, seq=0xFFFF, data=b"/f")
    assert (opened.opcode, opened.seq) == (ACK, 0)


def test_a_burst_is_at_most_150_packets_the_last_saying_burst_complete() -> None:
    # The module's documented burst: 150 data packets at most, then the client asks again.
    content = bytes(range(256)) * 200  # 51200 bytes: 215 packets of 239
    server = MavftpServer({"/big": content})
    session = reply(server, OPEN_RO, data=b"/big").session
    first = replies(server, BURST, seq=10, session=session, offset=0)
    assert len(first) == 150
    assert all(r.opcode == ACK for r in first)
    assert [r.burst_complete for r in first] == [0] * 149 + [1]
    assert [r.offset for r in first] == [239 * i for i in range(150)]
    assert [r.seq for r in first] == list(range(11, 161))
    rest = replies(server, BURST, seq=160, session=session, offset=150 * 239)
    assert b"".join(r.data for r in first + rest[:-1]) == content
    assert rest[-1].opcode == NAK and rest[-1].data == bytes([EOF])
    assert all(r.burst_complete == 0 for r in rest)


def test_a_burst_of_a_file_ending_on_a_packet_boundary_ends_with_eof() -> None:
    server = MavftpServer({"/f": b"x" * 478})  # exactly two packets
    session = reply(server, OPEN_RO, data=b"/f").session
    got = replies(server, BURST, session=session, offset=0)
    assert [(r.opcode, len(r.data)) for r in got] == [(ACK, 239), (ACK, 239), (NAK, 1)]
    assert reply(server, BURST, session=session, offset=478).data == bytes([EOF])


def test_a_listing_fills_the_payload_and_goes_on_from_the_entry_asked_for() -> None:
    # 21 entries "Fname_NN\t1\0" of 11 bytes: 21 fit in 239 bytes (231), the 22nd does not.
    files = {f"/d/name_{n:02}": b"x" for n in range(30)}
    server = MavftpServer(files)
    first = reply(server, LIST, data=b"/d")
    entries = first.data.split(b"\0")[:-1]
    assert entries == [f"Fname_{n:02}\t1".encode() for n in range(21)]
    second = reply(server, LIST, data=b"/d", offset=21)
    assert second.offset == 21
    assert second.data.split(b"\0")[:-1] == [f"Fname_{n:02}\t1".encode() for n in range(21, 30)]


def test_a_listing_of_exactly_239_bytes_is_one_payload() -> None:
    # 21 entries of 11 bytes (231) and one of 8 ("Fzzz\t10" and its NUL): 239 bytes exactly.
    files = {f"/d/n_{n:02}xxx": b"x" for n in range(21)}
    files["/d/zzz"] = b"y" * 10
    server = MavftpServer(files)
    listed = reply(server, LIST, data=b"/d")
    assert len(listed.data) == 239
    assert listed.data.endswith(b"Fzzz\t10\0")


def test_an_empty_root_is_listed_as_the_end_not_as_missing() -> None:
    # "/" always exists: with no files its listing is at its end (EOF), not FileNotFound.
    server = MavftpServer({})
    assert reply(server, LIST, data=b"/").data == bytes([EOF])
    assert reply(server, LIST, data=b"/nothing").data == bytes([NOT_FOUND])


def test_a_folder_named_with_a_trailing_slash_is_the_folder() -> None:
    server = MavftpServer({"/a/b/c.txt": b"12", "/a/x": b"1"})
    assert reply(server, LIST, data=b"/a/").data.split(b"\0")[:-1] == [b"Db", b"Fx\t1"]
    assert reply(server, LIST, data=b"/a/b").data.split(b"\0")[:-1] == [b"Fc.txt\t2"]


def test_paths_are_read_as_a_shell_reads_them() -> None:
    # Repeated slashes and "." are the same path; the name ends at the first NUL.
    server = MavftpServer({"etc//meta/./f.json": b"{}"})
    for path in (b"/etc/meta/f.json", b"//etc/./meta//f.json", b"etc/meta/f.json\0junk"):
        opened = reply(server, OPEN_RO, data=path)
        assert opened.opcode == ACK, path
        assert struct.unpack("<I", opened.data)[0] == 2


def test_a_read_takes_at_most_239_bytes_whatever_size_says() -> None:
    server = MavftpServer({"/f": bytes(range(256)) * 2})
    session = reply(server, OPEN_RO, data=b"/f").session
    header = HEADER.pack(0, session, READ, 255, 0, 0, 0, 10)
    (payload,) = server.handle(header.ljust(PAYLOAD, b"\0"))
    size = payload[4]
    assert size == 239 and payload[12 : 12 + size] == (bytes(range(256)) * 2)[10:249]


def test_a_file_name_longer_than_size_says_is_cut_where_size_says() -> None:
    # Only `size` data bytes are the request's: "/f" of "/fx" with size 2.
    server = MavftpServer({"/f": b"1"})
    header = HEADER.pack(0, 0, OPEN_RO, 2, 0, 0, 0, 0)
    (payload,) = server.handle((header + b"/fx").ljust(PAYLOAD, b"\0"))
    assert payload[3] == ACK


def test_terminate_and_reset_free_sessions_for_new_opens() -> None:
    clock = Clock()
    server = MavftpServer({"/f": b"1"}, clock=clock)
    sessions = [reply(server, OPEN_RO, data=b"/f").session for _ in range(4)]
    assert sessions == [0, 1, 2, 3]  # the lowest free number, as PX4 numbers them
    assert reply(server, TERMINATE, session=2).opcode == ACK
    assert reply(server, OPEN_RO, data=b"/f").session == 2
    assert reply(server, OPEN_RO, data=b"/f").data == bytes([NO_SESSIONS])
    # a terminated session is forgotten: it is never the "oldest" to take over later
    assert reply(server, TERMINATE, session=0).opcode == ACK
    clock.now += 60
    assert reply(server, OPEN_RO, data=b"/f").session == 0
    assert server.reclaimed == 0
    assert reply(server, RESET).opcode == ACK
    assert reply(server, READ, session=1).data == bytes([INVALID_SESSION])
    assert [reply(server, OPEN_RO, data=b"/f").session for _ in range(4)] == [0, 1, 2, 3]
    assert server.reclaimed == 0


def test_a_session_idle_3_seconds_is_taken_over_by_default() -> None:
    # SESSION_IDLE: 3 s, longer than QGC's retry of an unanswered request (about 1 s).
    clock = Clock()
    server = MavftpServer({"/f": b"1"}, clock=clock)
    for _ in range(4):
        reply(server, OPEN_RO, data=b"/f")
    clock.now += 2.5
    assert reply(server, OPEN_RO, data=b"/f").data == bytes([NO_SESSIONS])
    clock.now += 0.5  # idle 3.0 s exactly: "idle for session_idle seconds"
    taken = reply(server, OPEN_RO, data=b"/f")
    assert (taken.opcode, taken.session, server.reclaimed) == (ACK, 0, 1)


def test_the_session_unused_longest_is_taken_over_and_the_old_client_is_told() -> None:
    clock = Clock()
    server = MavftpServer({"/f": b"abc"}, session_idle=5.0, clock=clock)
    for _ in range(4):
        reply(server, OPEN_RO, data=b"/f")
        clock.now += 1
    reply(server, READ, session=0)  # session 0 read last: 1 is now unused longest
    clock.now += 10
    assert reply(server, OPEN_RO, data=b"/f").session == 1
    assert reply(server, OPEN_RO, data=b"/f").session == 2
    assert server.reclaimed == 2
    # the reclaimed session now serves its new owner's file from the start
    assert reply(server, READ, session=1).data == b"abc"


def test_a_crc_of_a_path_written_loosely_is_the_files() -> None:
    server = MavftpServer({"/a/f": b"123456789"})
    got = reply(server, CRC32, data=b"a//f")
    # PX4's crc32part of "123456789": CRC-32 without its inversions (0x2DFD2D88)
    assert (got.opcode, got.data) == (ACK, struct.pack("<I", 0x2DFD2D88))


def test_opcodes_and_errors_are_the_protocols_numbers() -> None:
    # mavlink.io/en/services/ftp.html, "Payload Format": the opcodes and NAK error codes.
    from px4params.links.mavlink_ftp import Op

    protocol = {
        "NONE": 0, "TERMINATE_SESSION": 1, "RESET_SESSIONS": 2, "LIST_DIRECTORY": 3,
        "OPEN_FILE_RO": 4, "READ_FILE": 5, "CREATE_FILE": 6, "WRITE_FILE": 7,
        "REMOVE_FILE": 8, "CREATE_DIRECTORY": 9, "REMOVE_DIRECTORY": 10, "OPEN_FILE_WO": 11,
        "TRUNCATE_FILE": 12, "RENAME": 13, "CALC_FILE_CRC32": 14, "BURST_READ_FILE": 15,
        "ACK": 128, "NAK": 129,
        "ERR_FAIL": 1, "ERR_FAIL_ERRNO": 2, "ERR_INVALID_DATA_SIZE": 3,
        "ERR_INVALID_SESSION": 4, "ERR_NO_SESSIONS_AVAILABLE": 5, "ERR_EOF": 6,
        "ERR_UNKNOWN_COMMAND": 7, "ERR_FILE_EXISTS": 8, "ERR_FILE_PROTECTED": 9,
        "ERR_FILE_NOT_FOUND": 10,
    }  # fmt: skip
    assert {name: getattr(Op, name) for name in protocol} == protocol


def test_every_writing_opcode_is_refused_as_protected_and_others_as_unknown() -> None:
    # By number: CreateFile 6 .. Rename 13 write (FileProtected, 9); 0, 16.. are unknown (7).
    server = MavftpServer({"/f": b"1"})
    for opcode in range(6, 14):
        got = reply(server, opcode, seq=5, data=b"/f")
        assert (got.opcode, got.req, got.seq, got.data) == (NAK, opcode, 6, b"\x09")
    for opcode in (0, 16, 127, 130, 255):
        assert reply(server, opcode, data=b"/f").data == b"\x07", opcode
    # (ACK 128 and NAK 129 are responses, never answered: test_mavlink_metadata)


def test_make_request_builds_the_protocols_layout() -> None:
    from px4params.links.mavlink_ftp import make_request

    assert make_request(OPEN_RO, data=b"/f") == request(OPEN_RO, data=b"/f")
    assert make_request(READ, seq=7, session=2, offset=300) == request(
        READ, seq=7, session=2, offset=300
    )
    sized = make_request(READ, session=1, size=80)
    assert len(sized) == PAYLOAD and sized[4] == 80 and sized[12:] == bytes(239)


def test_a_folder_whose_name_ends_in_x_lists_its_own_files() -> None:
    server = MavftpServer({"/boX/f": b"1", "/bo/g": b"22"})
    assert reply(server, LIST, data=b"/boX").data.split(b"\0")[:-1] == [b"Ff\t1"]
    assert reply(server, LIST, data=b"/bo").data.split(b"\0")[:-1] == [b"Fg\t2"]


def test_an_entry_that_does_not_fit_ends_the_listing_there() -> None:
    # The client asks again from the number of entries it got: a later, shorter entry must
    # not be slipped in after one left out (it would be listed twice, the other never).
    files = {f"/d/name_{n:02}": b"x" for n in range(21)}  # 21 x 11 bytes: 231
    files["/d/name_21_long"] = b"x"  # 16 bytes: does not fit
    files["/d/zz"] = b"x"  # "Fzz\t1" and its NUL: 6 bytes, would fit
    server = MavftpServer(files)
    first = reply(server, LIST, data=b"/d").data.split(b"\0")[:-1]
    assert len(first) == 21 and first[-1] == b"Fname_20\t1"
    rest = reply(server, LIST, data=b"/d", offset=21).data.split(b"\0")[:-1]
    assert rest == [b"Fname_21_long\t1", b"Fzz\t1"]


def test_plain_acks_and_naks_carry_no_offset_and_only_their_data() -> None:
    server = MavftpServer({"/f": b"abc"})
    opened = reply(server, OPEN_RO, data=b"/f")
    assert (opened.offset, opened.burst_complete, opened.data) == (0, 0, struct.pack("<I", 3))
    for got in (reply(server, TERMINATE, session=opened.session), reply(server, RESET)):
        assert (got.opcode, got.offset, got.burst_complete, got.data) == (ACK, 0, 0, b"")
    missing = reply(server, OPEN_RO, data=b"/none", offset=77)
    assert (missing.opcode, missing.offset, missing.burst_complete) == (NAK, 0, 0)
    assert missing.data == bytes([NOT_FOUND])


def test_a_path_that_is_not_utf8_is_not_found_not_an_exception() -> None:
    server = MavftpServer({"/f": b"1"})
    for opcode in (OPEN_RO, LIST, CRC32):
        assert reply(server, opcode, data=b"/\xff\xfe").data == bytes([NOT_FOUND]), opcode


def test_a_session_is_the_openers_and_another_client_reaches_none_of_it() -> None:
    # Any peer could read, terminate or reset another's session (its number is the lowest
    # free one): each belongs to the client that opened it now.
    server = MavftpServer({"/f": b"abc"})
    pilot, other = ("127.0.0.1", 14550), ("127.0.0.1", 9999)

    def answer(opcode: int, owner: object, session: int = 0) -> tuple[int, bytes]:
        data = b"/f" if opcode == OPEN_RO else b""  # (a read's size 0: a whole payload)
        (payload,) = server.handle(request(opcode, session=session, data=data), owner=owner)
        _, _, op, size, *_ = HEADER.unpack_from(payload)
        return op, payload[12 : 12 + size]

    assert answer(OPEN_RO, pilot)[0] == ACK
    for opcode in (READ, TERMINATE):
        assert answer(opcode, other) == (NAK, bytes([INVALID_SESSION]))
    assert answer(RESET, other) == (ACK, b"")  # the other's own sessions: none
    assert answer(READ, pilot) == (ACK, b"abc")  # still the pilot's
    assert answer(OPEN_RO, other) == (ACK, struct.pack("<I", 3))  # another session: 1
    assert answer(READ, other, session=1) == (ACK, b"abc")
    assert answer(RESET, pilot) == (ACK, b"")  # the pilot's alone
    assert answer(READ, pilot) == (NAK, bytes([INVALID_SESSION]))
    assert answer(READ, other, session=1) == (ACK, b"abc")
