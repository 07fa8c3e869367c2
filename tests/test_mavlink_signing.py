"""MAVLink 2 signing (``px4params.links.mavlink_signing``) in-process, by the rules of the
MAVLink guide (mavlink.io/en/guide/message_signing.html) and the C library's
``mavlink_signature_check`` that PX4 uses: a signed frame sets incompat flag 0x01 and ends in a
link ID, a 48-bit little-endian timestamp (10 us units since 2015-01-01 00:00 UTC) and the
first 6 bytes of SHA-256(key + the frame up to and including the timestamp); a stream is
(link ID, system, component); a frame must be later than its stream's last; a new stream at most
one minute behind our clock, and at most 16 streams. Frames are built here by hand (the
signature computed with hashlib) or by pymavlink as another peer signs them."""

from __future__ import annotations

import hashlib
import struct
import time
from pathlib import Path
from typing import Any

import pytest
from px4params.errors import SigningKeyError
from px4params.links import mavlink_messages
from px4params.links.mavlink_signing import (
    MAX_STREAMS,
    Signing,
    accepted,
    load_key,
    signing_timestamp,
)
from pymavlink import mavutil
from pymavlink.dialects.v20 import common as mavlink

KEY = bytes(range(32))
#: 2015-01-01 00:00:00 UTC as Unix time.
JAN_2015 = 1420070400
MINUTE = 60 * 100_000  # in signing's 10 us units


def signed(msg: Any, *, stamp: int, link: int = 0, key: bytes = KEY, system: int = 255) -> bytes:
    """``msg`` as a signed MAVLink 2 frame, by hand: pymavlink packs it unsigned, the incompat
    flag 0x01 is set, the CRC computed again (it covers the flags), then link ID, timestamp
    and SHA-256(key + frame + link + timestamp)[:6] appended."""
    frame = bytearray(msg.pack(mavlink.MAVLink(None, srcSystem=system, srcComponent=190)))
    assert frame[0] == 0xFD
    frame[2] |= 0x01
    length = frame[1]
    crc = mavutil.x25crc(bytes(frame[1 : 10 + length]))
    crc.accumulate(bytes([msg.crc_extra]))
    frame[10 + length : 12 + length] = struct.pack("<H", crc.crc)
    tail = bytes([link]) + stamp.to_bytes(6, "little")
    return bytes(frame) + tail + hashlib.sha256(key + bytes(frame) + tail).digest()[:6]


def heartbeat() -> Any:
    return mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3)


def parse(signing: Signing, frame: bytes) -> list[Any]:
    return signing.parser(None).parse_buffer(frame) or []


def kinds(messages: list[Any]) -> list[str]:
    return [m.get_type() for m in messages]


@pytest.fixture
def ahead() -> tuple[Signing, int]:
    """A link whose clock is an hour ahead of the wall clock (so that the wall clock, which
    the check follows too, never overtakes it during a test), and that timestamp."""
    signing = Signing(KEY, now=time.time() + 3600)
    return signing, signing.state.timestamp


# -- the clock and the key ---------------------------------------------------------------------


def test_the_signing_clock_counts_10_microseconds_since_2015() -> None:
    assert signing_timestamp(JAN_2015) == 0
    assert signing_timestamp(JAN_2015 + 1.5) == 150_000
    assert signing_timestamp(JAN_2015 + 86400) == 8_640_000_000
    assert signing_timestamp(JAN_2015 - 10) == 0  # never negative
    before = signing_timestamp(time.time())
    now = signing_timestamp()
    assert before <= now <= signing_timestamp(time.time())


def test_a_link_starts_at_the_given_time_and_signs_with_its_link_id() -> None:
    signing = Signing(KEY, link_id=7, now=JAN_2015 + 2)
    assert signing.state.timestamp == 200_000
    assert (signing.state.secret_key, signing.state.link_id) == (KEY, 7)
    assert signing.state.sign_outgoing
    ours = signing.parser(None)
    frame = heartbeat().pack(ours)
    assert frame[2] & 0x01 and frame[-13] == 7
    assert frame[-6:] == hashlib.sha256(KEY + frame[:-6]).digest()[:6]
    stamps = [int.from_bytes(f[-12:-6], "little") for f in (frame, heartbeat().pack(ours))]
    assert stamps == [200_000, 200_001]  # each of our frames one tick later


def test_a_link_signs_as_link_0_by_default() -> None:
    assert heartbeat().pack(Signing(KEY).parser(None))[-13] == 0


def test_a_key_is_32_bytes() -> None:
    with pytest.raises(SigningKeyError, match=r"^a signing key is 32 bytes, not 31$"):
        Signing(KEY[:31])


@pytest.mark.parametrize(
    ("content", "key"),
    [
        (KEY, KEY),
        (KEY + (123).to_bytes(8, "little"), KEY),  # PX4's file: key, then its timestamp
        (KEY.hex().encode(), KEY),
        (KEY.hex().upper().encode() + b"\n", KEY),
        (b"  " + KEY.hex().encode() + b"\r\n", KEY),
    ],
)
def test_key_files_raw_px4s_or_hex(tmp_path: Path, content: bytes, key: bytes) -> None:
    path = tmp_path / "key"
    path.write_bytes(content)
    assert load_key(path) == key


@pytest.mark.parametrize("content", [b"x" * 31, b"g" * 64, KEY.hex().encode()[:63], b""])
def test_a_file_that_is_no_key_says_what_was_expected(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "key"
    path.write_bytes(content)
    with pytest.raises(SigningKeyError) as refused:
        load_key(path)
    assert str(refused.value) == (
        f"{path}: not a signing key: expected 32 bytes, 64 hex digits (e.g. the SHA-256 of the "
        f"passphrase) or PX4's 40-byte key file, found {len(content)} bytes"
    )


def test_a_missing_key_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "none.key"
    with pytest.raises(SigningKeyError) as refused:
        load_key(path)
    assert str(refused.value) == f"{path}: cannot read the signing key: No such file or directory"


# -- acceptance --------------------------------------------------------------------------------


def test_a_frame_signed_by_the_rule_is_accepted(ahead: tuple[Signing, int]) -> None:
    signing, now = ahead
    (msg,) = parse(signing, signed(heartbeat(), stamp=now))
    assert msg.get_type() == "HEARTBEAT" and msg.get_signed() and accepted(msg)
    assert signing.dropped == {"unsigned": 0, "badly_signed": 0, "param_set": 0}


def test_a_wrong_key_or_a_changed_byte_is_badly_signed(ahead: tuple[Signing, int]) -> None:
    signing, now = ahead
    assert kinds(parse(signing, signed(heartbeat(), stamp=now, key=bytes(32)))) == ["BAD_DATA"]
    frame = bytearray(signed(heartbeat(), stamp=now + 1))
    frame[-1] ^= 0x01
    assert kinds(parse(signing, bytes(frame))) == ["BAD_DATA"]
    assert signing.dropped == {"unsigned": 0, "badly_signed": 2, "param_set": 0}
    # a forged frame changes nothing: the stream is still new, its first stamp still good
    assert kinds(parse(signing, signed(heartbeat(), stamp=now))) == ["HEARTBEAT"]


def test_a_replayed_or_older_frame_of_a_stream_is_refused(ahead: tuple[Signing, int]) -> None:
    signing, now = ahead
    first = signed(heartbeat(), stamp=now + 10)
    assert kinds(parse(signing, first)) == ["HEARTBEAT"]
    assert kinds(parse(signing, first)) == ["BAD_DATA"]  # the same stamp again
    assert kinds(parse(signing, signed(heartbeat(), stamp=now + 9))) == ["BAD_DATA"]
    assert kinds(parse(signing, signed(heartbeat(), stamp=now + 11))) == ["HEARTBEAT"]
    # another link ID or system is another stream, with its own last stamp
    assert kinds(parse(signing, signed(heartbeat(), stamp=now + 5, link=1))) == ["HEARTBEAT"]
    assert kinds(parse(signing, signed(heartbeat(), stamp=now + 5, system=254))) == ["HEARTBEAT"]
    assert signing.dropped["badly_signed"] == 2


def test_a_new_stream_may_start_one_minute_behind_our_clock_and_no_more(
    ahead: tuple[Signing, int],
) -> None:
    signing, now = ahead
    assert kinds(parse(signing, signed(heartbeat(), stamp=now - MINUTE, link=1))) == ["HEARTBEAT"]
    old = signed(heartbeat(), stamp=now - MINUTE - 1, link=2)
    assert kinds(parse(signing, old)) == ["BAD_DATA"]
    assert signing.dropped["badly_signed"] == 1


def test_our_clock_moves_up_to_the_latest_accepted_stamp(ahead: tuple[Signing, int]) -> None:
    signing, now = ahead
    later = now + 10 * MINUTE
    assert kinds(parse(signing, signed(heartbeat(), stamp=later))) == ["HEARTBEAT"]
    assert signing.state.timestamp == later
    # a new stream is now measured against the later clock
    assert kinds(parse(signing, signed(heartbeat(), stamp=now, link=1))) == ["BAD_DATA"]
    frame = heartbeat().pack(signing.parser(None))
    assert int.from_bytes(frame[-12:-6], "little") == later


def test_our_clock_follows_the_wall_clock_too() -> None:
    signing = Signing(KEY, now=JAN_2015)  # a clock stuck in 2015
    wall = signing_timestamp()
    # a frame 30 s behind the wall clock is a good new stream, but one 2 min behind is not
    assert kinds(parse(signing, signed(heartbeat(), stamp=wall - MINUTE // 2))) == ["HEARTBEAT"]
    assert signing.state.timestamp >= wall
    assert kinds(parse(signing, signed(heartbeat(), stamp=wall - 2 * MINUTE, link=1))) == [
        "BAD_DATA"
    ]


def test_at_most_16_streams_are_known(ahead: tuple[Signing, int]) -> None:
    signing, now = ahead
    assert MAX_STREAMS == 16
    for link in range(16):
        assert kinds(parse(signing, signed(heartbeat(), stamp=now, link=link))) == ["HEARTBEAT"]
    assert kinds(parse(signing, signed(heartbeat(), stamp=now, link=16))) == ["BAD_DATA"]
    assert kinds(parse(signing, signed(heartbeat(), stamp=now + 1, link=3))) == ["HEARTBEAT"]


def test_unsigned_frames_are_refused_and_param_sets_counted(ahead: tuple[Signing, int]) -> None:
    signing, _ = ahead
    plain = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    assert kinds(parse(signing, heartbeat().pack(plain))) == ["BAD_DATA"]
    param_set = mavlink.MAVLink_param_set_message(1, 1, b"SYS_AUTOSTART", 1.0, 6)
    assert kinds(parse(signing, param_set.pack(plain))) == ["BAD_DATA"]
    assert kinds(parse(signing, param_set.pack(plain))) == ["BAD_DATA"]
    assert signing.dropped == {"unsigned": 3, "badly_signed": 0, "param_set": 2}


def test_a_badly_signed_param_set_is_counted_as_badly_signed(ahead: tuple[Signing, int]) -> None:
    signing, now = ahead
    param_set = mavlink.MAVLink_param_set_message(1, 1, b"SYS_AUTOSTART", 1.0, 6)
    assert kinds(parse(signing, signed(param_set, stamp=now, key=bytes(32)))) == ["BAD_DATA"]
    assert signing.dropped == {"unsigned": 0, "badly_signed": 1, "param_set": 1}


@pytest.mark.parametrize(
    "msg",
    [
        mavlink.MAVLink_radio_status_message(200, 190, 80, 50, 40, 0, 0),
        mavlink.MAVLink_adsb_vehicle_message(1, 0, 0, 0, 0, 0, 0, 0, b"TEST", 0, 1, 0, 0),
        mavlink.MAVLink_collision_message(0, 1, 0, 0, 10.0, 5.0, 5.0),
    ],
)
def test_radios_and_traffic_pass_unsigned_as_px4_lets_them(
    ahead: tuple[Signing, int], msg: Any
) -> None:
    signing, now = ahead
    plain = mavlink.MAVLink(None, srcSystem=51, srcComponent=68)
    (got,) = parse(signing, msg.pack(plain))
    assert got.get_type() == msg.get_type() and not got.get_signed() and accepted(got)
    # but not with a bad signature
    assert kinds(parse(signing, signed(msg, stamp=now, key=bytes(32)))) == ["BAD_DATA"]
    assert signing.dropped == {"unsigned": 0, "badly_signed": 1, "param_set": 0}


def test_frames_of_ids_pymavlink_does_not_know_are_not_accepted_unsigned() -> None:
    """pymavlink returns such frames without checking them: ``accepted`` tells."""
    signing = Signing(KEY)
    plain = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    frame = mavlink_messages.component_metadata(0, 0, "mftp://x").pack(plain)
    messages = parse(signing, frame)
    assert [accepted(m) for m in messages if m.get_type() != "BAD_DATA"] in ([], [False])


def test_an_attached_connection_signs_and_checks(ahead: tuple[Signing, int]) -> None:
    signing, now = ahead
    conn = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    assert signing.attach(conn) is conn and conn.signing is signing.state
    assert conn.parse_buffer(signed(heartbeat(), stamp=now))[0].get_type() == "HEARTBEAT"
    frame = heartbeat().pack(conn)
    assert frame[-6:] == hashlib.sha256(KEY + frame[:-6]).digest()[:6]
