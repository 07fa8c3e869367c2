"""MAVLink 2 message signing (mavlink.io/en/guide/message_signing.html): pymavlink signs what
we send, and what arrives is checked here by PX4's rules.

A signed frame ends with a link ID, a 48-bit timestamp (10 microsecond units since
2015-01-01 00:00 UTC) and the first 6 bytes of SHA-256 over the key and the frame. A message is
accepted when (as the MAVLink C library's ``mavlink_signature_check``, which PX4 uses):

1. its signature is right (checked first: a forged frame changes no state);
2. its stream, ``(link ID, system, component)``, is known and its timestamp is later than that
   stream's last one (a replayed frame is refused), or the stream is new, at most
   :data:`MAX_STREAMS` are known, and its timestamp is at most one minute behind ours;

then the stream's timestamp and ours move up to it. Our own frames carry ``timestamp + 1`` each.
Unsigned frames are refused, except the few PX4 accepts unsigned on a signed link
(``RADIO_STATUS``, ``ADSB_VEHICLE``, ``COLLISION``: radios and traffic do not sign). pymavlink
hands over frames of message IDs it does not know without checking them: :func:`accepted`
tells them apart.

Key files: the 32-byte secret, as 32 raw bytes, as 64 hexadecimal digits (a trailing newline
allowed), or as PX4 stores it (``mavlink/mavlink-signing-key.bin`` on the SD card: the key,
then the 8-byte timestamp, which is not used here: the clock is; PX4-Autopilot
``src/modules/mavlink/mavlink_sign_control.cpp``). Ground stations derive the key from a
passphrase with SHA-256 (MAVProxy's ``signing setup PASSPHRASE``, QGroundControl's signing
keys), so ``printf %s PASSPHRASE | sha256sum | cut -c1-64 > key.hex`` makes the file for the
same link.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import string
import threading
import time
from typing import Any

from pymavlink.dialects.v20 import common as mavlink

from px4params.errors import SigningKeyError
from px4params.reading import SIGNING_KEY, read_bytes

__all__ = [
    "MAX_STREAMS",
    "Signing",
    "accepted",
    "load_key",
    "signing_timestamp",
]

#: Seconds from the Unix epoch to 2015-01-01 00:00 UTC, MAVLink signing's epoch.
EPOCH_2015 = 1420070400
#: A new stream's first timestamp may be this far behind ours (one minute, in 10 us units).
NEW_STREAM_WINDOW = 60 * 100_000
#: Streams remembered (MAVLINK_MAX_SIGNING_STREAMS of the C library).
MAX_STREAMS = 16
#: Messages PX4 accepts unsigned on a signed link (``unsigned_messages`` of
#: ``mavlink_sign_control.cpp``).
UNSIGNED_ALLOWED = frozenset(
    {
        mavlink.MAVLINK_MSG_ID_RADIO_STATUS,
        mavlink.MAVLINK_MSG_ID_ADSB_VEHICLE,
        mavlink.MAVLINK_MSG_ID_COLLISION,
    }
)
KEY_BYTES = 32
#: PX4's key file: the key and a uint64 timestamp.
PX4_KEY_FILE_BYTES = KEY_BYTES + 8
#: A signed frame's tail: link ID (1 byte), timestamp (6), signature (6).
SIGNATURE_BYTES = 6
TIMESTAMP_BYTES = 6


def load_key(path: str | os.PathLike[str]) -> bytes:
    """The secret in key file ``path``: 32 raw bytes, 64 hex digits, or PX4's file (the key
    and its timestamp)."""
    try:
        data = read_bytes(path, SIGNING_KEY)
    except OSError as e:
        raise SigningKeyError(
            f"{os.fspath(path)}: cannot read the signing key: {e.strerror or e}"
        ) from None
    text = data.strip()
    if len(data) in (KEY_BYTES, PX4_KEY_FILE_BYTES):
        return data[:KEY_BYTES]
    if len(text) == 2 * KEY_BYTES and all(chr(c) in string.hexdigits for c in text):
        return bytes.fromhex(text.decode("ascii"))
    raise SigningKeyError(
        f"{os.fspath(path)}: not a signing key: expected 32 bytes, 64 hex digits (e.g. the "
        f"SHA-256 of the passphrase) or PX4's 40-byte key file, found {len(data)} bytes"
    )


def accepted(msg: Any) -> bool:
    """Whether a message a signing parser returned was signed and checked (or is one of the
    few allowed unsigned); pymavlink returns messages of unknown IDs unchecked."""
    return bool(msg.get_signed()) or msg.get_msgId() in UNSIGNED_ALLOWED


def signing_timestamp(now: float | None = None) -> int:
    """MAVLink signing's clock: 10 microsecond units since 2015-01-01 (``now``: Unix time)."""
    seconds = time.time() if now is None else now
    return int(max(0.0, seconds - EPOCH_2015) * 100_000)


class Signing:
    """The signing state of one link: our key, link ID and timestamp, and the streams heard.
    :meth:`parser` makes parsers that sign what they pack and refuse what the rules above
    refuse, :meth:`attach` does the same to an existing ``MAVLink`` object (a mavutil
    connection's); what is refused is counted in :attr:`dropped`.

    Our timestamp moves as frames are signed and as frames are accepted: whoever sends from
    threads holds :attr:`lock` while a frame is signed and written, and the check moves the
    timestamp under it too, so that no frame leaves with a timestamp already used."""

    def __init__(self, key: bytes, link_id: int = 0, *, now: float | None = None) -> None:
        if len(key) != KEY_BYTES:
            raise SigningKeyError(f"a signing key is {KEY_BYTES} bytes, not {len(key)}")
        self.state = mavlink.MAVLinkSigning()
        self.state.secret_key = key
        self.state.link_id = link_id
        self.state.sign_outgoing = True
        self.state.timestamp = signing_timestamp(now)
        self.state.allow_unsigned_callback = self._unsigned
        #: Frames refused: ``unsigned``, ``badly_signed`` (wrong signature, replayed or old
        #: timestamp), and how many of them were ``PARAM_SET``.
        self.dropped = {"unsigned": 0, "badly_signed": 0, "param_set": 0}
        self.lock = threading.Lock()
        self._bad = False

    def attach(self, mav: mavlink.MAVLink) -> mavlink.MAVLink:
        """``mav`` signs every frame it packs from now on and accepts frames by the rules."""
        mav.signing = self.state

        def check(msgbuf: bytearray, system: int, component: int) -> bool:
            return self.check(bytes(msgbuf), system, component)

        mav.check_signature = check
        return mav

    def parser(self, file: Any) -> mavlink.MAVLink:
        """A parser (robust: refused frames become ``BAD_DATA``) that checks signatures."""
        parser = self.attach(mavlink.MAVLink(file))
        parser.robust_parsing = True
        return parser

    def _unsigned(self, mav: Any, message_id: int) -> bool:
        """pymavlink asks this about every frame it did not accept as signed."""
        bad, self._bad = self._bad, False
        if message_id in UNSIGNED_ALLOWED and not bad:
            return True
        self.dropped["badly_signed" if bad else "unsigned"] += 1
        if message_id == mavlink.MAVLINK_MSG_ID_PARAM_SET:
            self.dropped["param_set"] += 1
        return False

    def check(self, frame: bytes, system: int, component: int) -> bool:
        """PX4's acceptance of a signed frame (rules 1 and 2 above)."""
        # 1. the signature, computed here: it reads nothing a sender uses and changes nothing
        #    (a forged frame moves no timestamp)
        signed_part, signature = frame[:-SIGNATURE_BYTES], frame[-SIGNATURE_BYTES:]
        digest = hashlib.sha256(self.state.secret_key + signed_part).digest()
        if not hmac.compare_digest(digest[:SIGNATURE_BYTES], signature):
            self._bad = True
            return False
        # 2. the timestamp, per stream; ours follows the clock too (the spec's advice), so that
        #    a long run does not let old new-stream frames through
        link_id = signed_part[-TIMESTAMP_BYTES - 1]
        stamp = int.from_bytes(signed_part[-TIMESTAMP_BYTES:], "little")
        key = (link_id, system, component)
        with self.lock:
            state = self.state
            state.timestamp = max(state.timestamp, signing_timestamp())
            streams = state.stream_timestamps
            last = streams.get(key)
            if last is None:
                fresh = len(streams) < MAX_STREAMS and stamp + NEW_STREAM_WINDOW >= state.timestamp
            else:
                fresh = stamp > last
            if fresh:
                streams[key] = stamp
                state.timestamp = max(state.timestamp, stamp)
        if not fresh:
            self._bad = True
        return fresh
