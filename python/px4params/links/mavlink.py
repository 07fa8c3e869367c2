"""A MAVLink parameter server over UDP: the store's classic and destructured parameters, served
the way PX4 serves its own, so that QGroundControl, MAVSDK or pymavlink can list, read and write
them.

What it does (PX4's ``mavlink_parameters.cpp`` is the model):

* ``HEARTBEAT`` once a second (autopilot ``MAV_AUTOPILOT_PX4``) to every peer heard from in the
  last ``peer_timeout`` seconds (a ground station sends its own heartbeat every second; a peer
  that went away is dropped, as PX4 drops a UDP link's remote) and to the ``gcs`` addresses
  given (QGroundControl waits on UDP 14550 for a vehicle to speak first).
* ``AUTOPILOT_VERSION`` on ``MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES`` or ``MAV_CMD_REQUEST_MESSAGE``
  (148), with ``MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE``: ``int32`` values travel as their
  four bytes inside the ``float`` field, as PX4 sends them.
* ``PARAM_REQUEST_LIST``: first ``_HASH_CHECK`` (index -1, ``MAV_PARAM_TYPE_UINT32``, PX4's CRC32
  over every name and value, so that a ground station can use its cache), then every parameter
  in name order, paced (``param_rate`` a second, in bursts of 20 as PX4 sends them over UDP)
  rather than at once, and only while the requester is still heard from; each requester gets
  its own list, the pace shared. A ``PARAM_SET`` of ``_HASH_CHECK`` stops the sender's list, as
  in PX4. Parameter messages must name this system's ID (PX4 ignores them for system 0).
* ``PARAM_REQUEST_READ`` by name (``_HASH_CHECK`` too) or by index.
* ``PARAM_SET``: the name must exist and the type must be the parameter's (``INT32`` or
  ``REAL32``); the value must fit the parameter (``int32``, ``float32``, or the leaf's own range,
  checked by the store). An accepted write is saved through the store (when a store file is
  given; if saving fails the write is undone) and answered with ``PARAM_VALUE``; a refused one
  changes nothing and is answered with ``PARAM_VALUE`` of the unchanged value, a ``STATUSTEXT``
  saying why and a ``PARAM_ERROR``. Writing a union tag (e.g. ``INA238_1A``) changes which leaves
  are live: the newly live ones are announced with ``PARAM_VALUE`` too. Writing an instance mask
  (``INA238_INST``, bit N for ``INA238#N``) adds and removes instances (see
  :mod:`px4params.store.flat`); the new instance's leaves are announced the same way.
* Component metadata as PX4 serves it: ``MAV_CMD_REQUEST_MESSAGE`` for ``COMPONENT_METADATA``
  (397) or ``COMPONENT_INFORMATION`` (395) is answered with the ``mftp://`` URI and CRC of the
  general metadata file, which lists ``parameters.json.xz`` (every classic, structured and
  destructured parameter of the store, :mod:`px4params.gcs.component_information`); both are
  downloaded with MAVLink FTP (``FILE_TRANSFER_PROTOCOL``, the read-only subset of
  :mod:`px4params.links.mavlink_ftp`; a session is its opener's, a burst read paced as a list).
* Every ``COMMAND_LONG`` is answered with ``COMMAND_ACK``: accepted, unsupported, or denied when
  its parameters name nothing (NaN, infinities, a message ID beyond 24 bits).
* Anything else (other messages, other targets, garbage bytes, bad CRCs) is ignored, and so is
  every message that claims this server's own system and component ID (an echo, or forged).
* With a signing key, MAVLink 2 signing (:mod:`px4params.links.mavlink_signing`): every frame
  sent is signed, and unsigned or wrongly signed frames are dropped and counted (a dropped
  ``PARAM_SET`` in ``stats["param_set_dropped"]``).
* A peer is heard from when it sends a MAVLink message (on a signed link: a signed one);
  garbage and dropped frames do not count.

The parameters are the store's classic ones and the destructured leaves of its structured
instances (:mod:`px4params.store.flat`); the structured values themselves (wider than 32 bits)
are not offered. A leaf's ``@min``/``@max`` and finite floats are enforced by the store (as for
every writer); a classic parameter's ``parameters.json`` bounds are not, as PX4 does not either.

pymavlink decodes a ``float`` field through a Python float, which turns an ``int32`` whose bit
pattern is a signalling NaN (-8388607..-4194305, 2139095041..2143289343) into another number.
This server therefore reads values from the raw payload and writes them byte-exact;
:func:`param_value_of` and :func:`param_set_message` do the same for clients.
"""

from __future__ import annotations

import math
import os
import select
import socket
import struct
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from pymavlink.dialects.v20 import common as mavlink

from px4params.errors import Px4ParamsError, StoreConflictError
from px4params.gcs.component_information import ComponentFiles, px4_crc32
from px4params.links import mavlink_messages
from px4params.links.identity import store_digest, version_parts
from px4params.links.mavlink_ftp import SESSION_IDLE, MavftpServer
from px4params.links.mavlink_signing import Signing, accepted
from px4params.links.serving import ServingLoop
from px4params.store import flat
from px4params.store.session import Session
from px4params.store.spec import MAX_NAME_LEN

if TYPE_CHECKING:
    from px4params.store.store import Store

__all__ = [
    "HASH_PARAM",
    "MavlinkParamServer",
    "ParamEntry",
    "param_hash",
    "param_set_message",
    "param_value_of",
]

HASH_PARAM = "_HASH_CHECK"
#: Message IDs of COMPONENT_METADATA and COMPONENT_INFORMATION (not in pymavlink's dialects).
COMPONENT_METADATA = 397
COMPONENT_INFORMATION = 395
CAPABILITIES = (
    mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE | mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
)
_INT32, _REAL32 = mavlink.MAV_PARAM_TYPE_INT32, mavlink.MAV_PARAM_TYPE_REAL32
_TYPE_NAMES = {_INT32: "INT32", _REAL32: "REAL32", mavlink.MAV_PARAM_TYPE_UINT32: "UINT32"}
#: MAV_PARAM_ERROR codes common.xml added after the pymavlink we use: a type PX4 has no
#: parameter of (it has INT32 and REAL32), and the other one of those two.
_TYPE_UNSUPPORTED = 6
_TYPE_MISMATCH = 7
#: STATUSTEXT carries 50 characters per chunk.
_TEXT_CHUNK = 50
#: Parameters sent per burst while streaming a list (PX4 sends up to 20 at once over UDP);
#: bursts follow each other at ``param_rate``, so that one request datagram is not answered
#: with the whole list at once, and a slow client's socket buffer does not overflow. Incoming
#: messages (a _HASH_CHECK stop) are read between bursts.
_STREAM_BURST = 20
#: PARAM_VALUE messages a second while streaming a list (about 19 kB/s): PX4's 1909 parameters
#: in 4 s.
PARAM_RATE = 500.0
#: Seconds a peer stays one after it was last heard from (ground stations send a heartbeat
#: every second).
PEER_TIMEOUT = 5.0
#: How often the store file is looked at for other writers' changes (one ``stat``), seconds.
_POLL_INTERVAL = 0.2
#: Peers remembered (for heartbeats and change notices); the oldest is forgotten beyond this.
_MAX_PEERS = 16

Address = tuple[str, int]


@dataclass(frozen=True)
class ParamEntry:
    """One parameter as MAVLink carries it: name, ``MAV_PARAM_TYPE_*`` and the four bytes."""

    name: str
    mav_type: int
    raw: bytes

    @property
    def value(self) -> int | float:
        value: int | float = struct.unpack("<i" if self.mav_type == _INT32 else "<f", self.raw)[0]
        return value


def _payload_of(msg: Any) -> bytes:
    """The payload bytes of a received message, from its frame: pymavlink's ``get_payload()``
    slices the frame after a MAVLink 1 header even for MAVLink 2 frames, whose header is four
    bytes longer, so for MAVLink 2 it starts with the component and message IDs."""
    frame = bytes(msg.get_msgbuf())
    header = 10 if frame[:1] == b"\xfd" else 6
    return frame[header : header + frame[1]]


def _param_id_of(msg: Any) -> bytes:
    """A received message's ``param_id`` as sent, up to its first NUL (pymavlink gives it as
    ASCII text, each byte that is not one a U+FFFD)."""
    payload = _payload_of(msg).ljust(msg.unpacker.size, b"\0")  # MAVLink 2 trims zeros
    raw = msg.unpacker.unpack(payload)[msg.ordered_fieldnames.index("param_id")]
    return bytes(raw).split(b"\0", 1)[0]


def param_value_of(msg: Any) -> int | float:
    """The value of a received ``PARAM_VALUE`` or ``PARAM_SET``, read from the payload bytes
    (bytewise encoding: ``int32`` types as integers), immune to pymavlink's NaN rewriting."""
    raw = (_payload_of(msg) + bytes(4))[:4]  # MAVLink 2 trims trailing zero bytes
    if msg.param_type == mavlink.MAV_PARAM_TYPE_REAL32:
        return float(struct.unpack("<f", raw)[0])
    if msg.param_type == mavlink.MAV_PARAM_TYPE_UINT32:
        return int(struct.unpack("<I", raw)[0])
    return int(struct.unpack("<i", raw)[0])


def _raw_of(value: int | float, mav_type: int) -> bytes:
    if mav_type == _REAL32:
        return struct.pack("<f", value)
    if mav_type == mavlink.MAV_PARAM_TYPE_UINT32:
        return struct.pack("<I", value)
    return struct.pack("<i", value)


class _RawParamValue(mavlink.MAVLink_param_value_message):  # type: ignore[misc]  # untyped
    """PARAM_VALUE whose value bytes are written as given (not through a Python float)."""

    def __init__(self, name: str, raw: bytes, mav_type: int, count: int, index: int) -> None:
        super().__init__(name.encode(), 0.0, mav_type, count, index)
        self.raw = raw

    def pack(self, mav: mavlink.MAVLink, force_mavlink1: bool = False) -> bytes:
        fields = (self.param_count, self.param_index, self._param_id_raw, self.param_type)
        payload = bytearray(self.unpacker.pack(0.0, *fields))
        payload[0:4] = self.raw
        frame: bytes = self._pack(
            mav, self.crc_extra, bytes(payload), force_mavlink1=force_mavlink1
        )
        return frame


class _RawParamSet(mavlink.MAVLink_param_set_message):  # type: ignore[misc]  # untyped
    """PARAM_SET whose value bytes are written as given."""

    def __init__(self, system: int, component: int, name: str, raw: bytes, mav_type: int) -> None:
        super().__init__(system, component, name.encode(), 0.0, mav_type)
        self.raw = raw

    def pack(self, mav: mavlink.MAVLink, force_mavlink1: bool = False) -> bytes:
        fields = (self.target_system, self.target_component, self._param_id_raw, self.param_type)
        payload = bytearray(self.unpacker.pack(0.0, *fields))
        payload[0:4] = self.raw
        frame: bytes = self._pack(
            mav, self.crc_extra, bytes(payload), force_mavlink1=force_mavlink1
        )
        return frame


def param_set_message(
    target_system: int, target_component: int, name: str, value: int | float, mav_type: int
) -> mavlink.MAVLink_param_set_message:
    """A ``PARAM_SET`` with the value encoded bytewise (for clients: ``conn.mav.send(msg)``).
    :class:`ValueError` for a name the message cannot carry whole."""
    refusal = param_name_refusal(name)
    if refusal is not None:
        raise ValueError(refusal)
    return _RawParamSet(target_system, target_component, name, _raw_of(value, mav_type), mav_type)


def param_name_refusal(name: str) -> str | None:
    """Why ``name`` cannot travel in a MAVLink ``param_id`` (16 ASCII characters at most:
    pymavlink would cut it, and the vehicle would set another parameter), or None."""
    if not name.isascii() or len(name) > MAX_NAME_LEN or not name:
        return (
            f"{name}: a MAVLink parameter name is 1 to {MAX_NAME_LEN} ASCII characters "
            f"({len(name)} given)"
        )
    return None


def param_hash(entries: Iterable[ParamEntry]) -> int:
    """PX4's ``param_hash_check``: CRC32 over each parameter's name and value bytes in index
    order (QGroundControl computes the same over its cache)."""
    crc = 0
    for entry in entries:
        crc = px4_crc32(entry.name.encode(), crc)
        crc = px4_crc32(entry.raw, crc)
    return crc


def _unchecked(msg: Any) -> bool:
    """Whether pymavlink gave back bytes it could not check: BAD_DATA, or a frame of an
    unknown message ID (``MAVLink_unknown``, no CRC_EXTRA to check its CRC with)."""
    return msg.get_type() == "BAD_DATA" or isinstance(msg, mavlink.MAVLink_unknown)


def _name_of(raw: Any) -> str:
    text = raw.decode("ascii", "replace") if isinstance(raw, bytes) else str(raw)
    return text.split("\0", 1)[0]


class _Sink:
    """pymavlink's encoder wants a file; the server sends the bytes itself."""

    def write(self, data: bytes) -> None:  # pragma: no cover - never called
        pass


class MavlinkParamServer(ServingLoop):
    """Serves ``store`` over UDP at ``host:port`` (port 0 picks a free one: see ``address``).

    ``save_path``: the store file accepted writes are saved to (None: kept in memory only),
    or ``session``: the store's session (:class:`~px4params.store.session.Session`, the one
    write path: its lock, other writers' changes kept). Changes other writers save to the
    file are noticed within ``poll_interval`` seconds and announced to every peer with
    ``PARAM_VALUE``, as a write is.
    ``gcs``: addresses to send heartbeats to before they speak (e.g. QGC's 127.0.0.1:14550).
    ``log``: called with one line per accepted or refused write.
    ``ftp_session_idle``: seconds after which an abandoned MAVLink FTP session is reclaimed.
    ``peer_timeout``: seconds after which a silent peer gets no more heartbeats, health text or
    list stream. ``param_rate``: PARAM_VALUE messages a second while streaming a list.
    ``signing_key``: the link's MAVLink 2 signing key (32 bytes; None: unsigned, as PX4 by
    default).
    """

    thread_name = "mavlink-params"

    def __init__(
        self,
        store: Store,
        host: str = "127.0.0.1",
        port: int = 14550,
        *,
        save_path: str | os.PathLike[str] | None = None,
        system_id: int = 1,
        component_id: int = 1,
        gcs: Iterable[Address] = (),
        log: Callable[[str], None] | None = None,
        heartbeat_interval: float = 1.0,
        health: Callable[[], list[str]] | None = None,
        health_interval: float = 2.0,
        ftp_session_idle: float = SESSION_IDLE,
        peer_timeout: float = PEER_TIMEOUT,
        param_rate: float = PARAM_RATE,
        signing_key: bytes | None = None,
        session: Session | None = None,
        poll_interval: float = _POLL_INTERVAL,
    ) -> None:
        super().__init__()
        self.store = store
        self.flat = flat.flat_map(store)  # refuses a store whose leaves cannot be destructured
        if session is None and save_path is not None:
            session = Session(store, os.fspath(save_path))
        self.session = session
        if save_path is None and session is not None:
            save_path = session.path
        self.save_path = save_path
        self.poll_interval = poll_interval
        self._next_poll = 0.0
        self.system_id = system_id
        self.component_id = component_id
        self.log = log or (lambda line: None)
        self.heartbeat_interval = heartbeat_interval
        #: Lines reporting each device's health (``health: ina238 INA238#1 on ...: critical:
        #: ...``), sent as STATUSTEXT every ``health_interval`` seconds to every peer.
        self.health = health
        self.health_interval = health_interval
        self._next_health = 0.0
        self._gcs = list(gcs)
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self._sock.bind((host, port))
        except OSError:
            self._sock.close()
            raise
        self._sock.setblocking(False)
        self._mav = mavlink.MAVLink(_Sink(), srcSystem=system_id, srcComponent=component_id)
        #: The link's signing state (None: unsigned).
        self.signing = Signing(signing_key) if signing_key is not None else None
        if self.signing is not None:
            self.signing.attach(self._mav)
        self.peer_timeout = peer_timeout
        self._burst_pause = _STREAM_BURST / param_rate
        self._seen: dict[Address, float] = {}  # peer -> when last heard, oldest first
        self._entries: list[ParamEntry] | None = None
        #: The lists being sent: peer -> its next index (-1: the hash first). Each asker gets
        #: its own: a second ground station's request took the first one's list over.
        self._streams: dict[Address, int] = {}
        #: MAVLink FTP burst reads being sent: peer -> (its system and component, the payloads
        #: left), paced with the lists; a peer's next burst replaces what is left of its last.
        self._bursts: dict[Address, tuple[tuple[int, int], deque[bytes]]] = {}
        self._next_heartbeat = 0.0
        self._next_burst = 0.0
        self._text_id = 0
        #: AUTOPILOT_VERSION's uid and uid2 for this store.
        self.uid = store_uid(self.save_path, store.parameters)
        #: The metadata files (general, parameters.json.xz) and the FTP server that serves them.
        classic = [c for c in map(store.classic, store.parameters) if c is not None]
        self.metadata = ComponentFiles(
            store.schema, store.specs, classic, component_id=component_id
        )
        self.ftp = MavftpServer(self.metadata.files, session_idle=ftp_session_idle)
        self._started = time.monotonic()
        #: Counters, for tests and the CLI's summary.
        self.stats = {"received": 0, "ignored": 0, "sent": 0, "accepted": 0, "refused": 0}
        #: Frames dropped by signing: unsigned, wrongly signed (key, replayed or old
        #: timestamp), and the PARAM_SETs among them.
        self.stats |= {"unsigned": 0, "badly_signed": 0, "param_set_dropped": 0}

    # -- lifecycle ----------------------------------------------------------------------------

    @property
    def address(self) -> Address:
        host, port = self._sock.getsockname()[:2]
        return str(host), int(port)

    def close(self) -> None:
        """The socket, once the loop has ended."""
        self._sock.close()

    def step(self, timeout: float) -> None:
        """One turn: read what arrived (waiting up to ``timeout``), stream, heartbeat."""
        now = time.monotonic()
        if now >= self._next_heartbeat:
            self._heartbeat()
            self._next_heartbeat = now + self.heartbeat_interval
        if self.health is not None and now >= self._next_health:
            self._next_health = now + self.health_interval
            self._report_health()
        if self.session is not None and now >= self._next_poll:
            self._next_poll = now + self.poll_interval
            self._poll_store()
        timeout = min(timeout, max(0.0, self._next_heartbeat - now))
        if self._streams or self._bursts:
            timeout = min(timeout, max(0.0, self._next_burst - now))
        readable, _, _ = select.select([self._sock], [], [], timeout)
        if readable:
            self._read_all()
        if (self._streams or self._bursts) and time.monotonic() >= self._next_burst:
            self._next_burst = time.monotonic() + self._burst_pause
            try:
                self._stream_some()
            except Exception as e:  # a bug must not stop the server: drop the streams
                self._streams.clear()
                self._bursts.clear()
                self.log(f"error streaming parameters: {type(e).__name__}: {e}")

    # -- receiving ----------------------------------------------------------------------------

    def _read_all(self) -> None:
        for _ in range(256):  # bounded, so that streaming and heartbeats go on under a flood
            try:
                data, peer = self._sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable from a peer that went away
                continue
            for msg in self._parse(peer[:2], data):
                self.stats["received"] += 1
                try:
                    handled = self._handle(peer[:2], msg)
                except Exception as e:  # a bug must not stop the server; count and go on
                    self.log(f"error handling {msg.get_type()}: {type(e).__name__}: {e}")
                    handled = False
                if not handled:
                    self.stats["ignored"] += 1

    def _parse(self, peer: Address, data: bytes) -> list[Any]:
        # A fresh parser per datagram: over UDP a frame never spans datagrams, so garbage in one
        # (a bogus length byte) cannot swallow the frames of the next. The signing state (the
        # streams' timestamps) lives on in self.signing.
        if self.signing is not None:
            parser = self.signing.parser(_Sink())
        else:
            parser = mavlink.MAVLink(_Sink())
            parser.robust_parsing = True  # bad bytes become BAD_DATA, not exceptions
        try:
            messages = parser.parse_buffer(data) or []
        except Exception:  # pymavlink raises assorted errors on garbage
            messages = None
        if self.signing is not None:
            dropped = self.signing.dropped
            if messages is not None:  # frames of unknown IDs come back unchecked: drop them
                kept = [m for m in messages if m.get_type() == "BAD_DATA" or accepted(m)]
                dropped["unsigned"] += len(messages) - len(kept)
                messages = kept
            self.stats["unsigned"] = dropped["unsigned"]
            self.stats["badly_signed"] = dropped["badly_signed"]
            self.stats["param_set_dropped"] = dropped["param_set"]
        if messages is None:
            self.stats["ignored"] += 1
            return []
        # A frame of an ID the dialect lacks comes back unchecked (its CRC needs the ID's
        # CRC_EXTRA; MAVLink's C parser, PX4's, checks it with 0 and drops what fails):
        # garbage, as a bad CRC is.
        good = [m for m in messages if not _unchecked(m)]
        self.stats["ignored"] += len(messages) - len(good)
        if good and (self.signing is None or any(m.get_signed() for m in good)):
            self._heard(peer)  # garbage, or on a signed link anything unsigned, makes no peer
        return good

    def _heard(self, peer: Address) -> None:
        """Remembers ``peer`` as heard from now (most recent last), forgetting the peers
        silent for longer than ``peer_timeout`` and the oldest beyond ``_MAX_PEERS``."""
        now = time.monotonic()
        self._seen.pop(peer, None)
        for old in [p for p, t in self._seen.items() if now - t > self.peer_timeout]:
            del self._seen[old]
        if len(self._seen) >= _MAX_PEERS:
            self._seen.pop(next(iter(self._seen)))
        self._seen[peer] = now

    def _alive(self, peer: Address) -> bool:
        heard = self._seen.get(peer)
        return heard is not None and time.monotonic() - heard <= self.peer_timeout

    def _for_us(self, msg: Any, *, broadcast: bool = True) -> bool:
        """Whether ``msg`` is addressed to this component; system 0 (broadcast) counts only
        where ``broadcast``: PX4 takes parameter messages addressed to its own system ID alone
        (mavlink_parameters.cpp), so that a broadcast PARAM_SET does not change every vehicle
        that hears it, and commands and FTP to system 0 too."""
        systems = (0, self.system_id) if broadcast else (self.system_id,)
        return msg.target_system in systems and msg.target_component in (0, self.component_id)

    def _handle(self, peer: Address, msg: Any) -> bool:
        if (msg.get_srcSystem(), msg.get_srcComponent()) == (self.system_id, self.component_id):
            # Our own ID: an echo of what we sent, another component misconfigured with our ID,
            # or a forged datagram. Answering it could answer ourselves forever.
            return False
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            return True
        if kind == "PARAM_REQUEST_LIST" and self._for_us(msg, broadcast=False):
            # A request during its stream restarts it without the hash, as PX4 does.
            self._streams[peer] = 0 if peer in self._streams else -1
            return True
        if kind == "PARAM_REQUEST_READ" and self._for_us(msg, broadcast=False):
            self._read(peer, msg, _name_of(msg.param_id), msg.param_index)
            return True
        if kind == "PARAM_SET" and self._for_us(msg, broadcast=False):
            self._set(peer, _name_of(msg.param_id), msg)
            return True
        if kind == "COMMAND_LONG" and self._for_us(msg):
            self._command(peer, msg)
            return True
        if kind == "FILE_TRANSFER_PROTOCOL" and self._for_us(msg):
            self._file_transfer(peer, msg)
            return True
        return False

    # -- parameters ---------------------------------------------------------------------------

    def entries(self) -> list[ParamEntry]:
        """Every parameter served, in index order (by name, as PX4 sorts them)."""
        if self._entries is None:
            rows: list[ParamEntry] = []
            for name, value in flat.flat_values(self.store).items():
                kind = _REAL32 if isinstance(value, float) else _INT32
                rows.append(ParamEntry(name, kind, _raw_of(value, kind)))
            rows.sort(key=lambda e: e.name.encode())
            self._entries = rows
        return self._entries

    def _find(self, name: str) -> tuple[int, ParamEntry] | None:
        for index, entry in enumerate(self.entries()):
            if entry.name == name:
                return index, entry
        return None

    def _value_msg(self, index: int, entry: ParamEntry) -> _RawParamValue:
        return _RawParamValue(entry.name, entry.raw, entry.mav_type, len(self.entries()), index)

    def _hash_msg(self) -> _RawParamValue:
        raw = struct.pack("<I", param_hash(self.entries()))
        # index -1 as PX4 sends it: the uint16 field holds 65535
        uint32 = mavlink.MAV_PARAM_TYPE_UINT32
        return _RawParamValue(HASH_PARAM, raw, uint32, len(self.entries()), 0xFFFF)

    def _stream_some(self) -> None:
        """One burst of the lists being sent, shared among their askers (the pace is the
        server's, however many ask)."""
        entries = self.entries()
        share = max(1, _STREAM_BURST // (len(self._streams) + len(self._bursts)))
        for peer, (to, left) in list(self._bursts.items()):
            for _ in range(min(share, len(left))):
                self._send_ftp(to, left.popleft(), peer)
            if not left or not self._alive(peer):
                del self._bursts[peer]
        for peer, index in list(self._streams.items()):
            if not self._alive(peer):  # the asker went away (or never was: a forged source)
                del self._streams[peer]
                continue
            for _ in range(share):
                if index == -1:
                    self._send(self._hash_msg(), [peer])
                elif index < len(entries):
                    self._send(self._value_msg(index, entries[index]), [peer])
                else:
                    break
                index += 1
            if index >= len(entries):
                del self._streams[peer]
            else:
                self._streams[peer] = index

    def _read(self, peer: Address, msg: Any, name: str, index: int) -> None:
        if index < 0:
            if name == HASH_PARAM:
                self._send(self._hash_msg(), [peer])
                return
            found = self._find(name)
            if found is None:  # the request's own index echoed (any negative one reads by name)
                self._error(peer, msg, name, index, self._missing(name))
                return
            self._send(self._value_msg(*found), [peer])
            return
        entries = self.entries()
        if index >= len(entries):
            self._error(peer, msg, name, index, f"[pm] unknown param ID: {index}")
            return
        self._send(self._value_msg(index, entries[index]), [peer])

    def _missing(self, name: str) -> str:
        if name in self.flat:
            try:
                self.flat.find(name)
            except Px4ParamsError as e:  # not live, or its instance does not exist
                return str(e)
        return f"[pm] unknown param: {name}"

    def _set(self, peer: Address, name: str, msg: Any) -> None:
        if name == HASH_PARAM:
            self._streams.pop(peer, None)  # it has our parameters cached: its list stops
            return
        found = self._find(name)
        if found is None:
            self._refuse(
                peer, msg, name, None, self._missing(name), mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST
            )
            return
        entry = found[1]
        if msg.param_type != entry.mav_type:
            given = _TYPE_NAMES.get(msg.param_type, str(msg.param_type))
            self._refuse(
                peer,
                msg,
                name,
                found,
                f"{name}: type {given} refused: the parameter is {_TYPE_NAMES[entry.mav_type]}",
                _TYPE_MISMATCH if msg.param_type in (_INT32, _REAL32) else _TYPE_UNSUPPORTED,
            )
            return
        value = param_value_of(msg)
        before = self.entries()

        def change() -> str:
            return flat.write_flat(self.store, name, value)

        try:
            if self.session is not None:  # saved through the one write path
                line = self.session.commit(change)
            else:
                with self.store.transaction():
                    line = change()
        except (Px4ParamsError, OSError) as e:
            # flat errors name the parameter already; store errors name the leaf
            why = str(e) if str(e).startswith(name) else f"{name}: {e}"
            if isinstance(e, StoreConflictError) and self.session is not None:
                self._poll_store()  # the file's values, announced to every peer
                found = self._find(name) or found
            self._refuse(peer, msg, name, found, why, mavlink.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE)
            return
        if self.flat.mask_spec(name) is not None:
            self.log(line)
        self._entries = None
        self.stats["accepted"] += 1
        new = self._find(name)
        assert new is not None
        shown = _shown(new[1].value)
        self.log(f"{name} = {shown}" + (", saved" if self.save_path is not None else ""))
        everyone = self._peers(peer)
        self._send(self._echo(msg, *new), everyone)
        # A union tag, array length or instance mask written: announce the leaves that became
        # live (with the new count; a ground station re-reads the list when the count drops),
        # and what other writers saved meanwhile.
        self._announce(before, everyone, skip=name)

    def _announce(self, before: list[ParamEntry], peers: list[Address], skip: str = "") -> int:
        """PARAM_VALUE to ``peers`` for every parameter that is new or has another value than
        in ``before``; returns how many."""
        old = {e.name: e for e in before}
        sent = 0
        for i, e in enumerate(self.entries()):
            if e.name != skip and old.get(e.name) != e:
                self._send(self._value_msg(i, e), peers)
                sent += 1
        return sent

    def _poll_store(self) -> None:
        """Other writers' saves: read into the store, and announced to every peer."""
        assert self.session is not None
        before = self.entries()
        try:
            changed = self.session.poll()
        except Px4ParamsError as e:  # said once per version of the file
            self.log(f"store changed by another writer, not read: {e}")
            return
        if changed:
            self._entries = None
            count = self._announce(before, self._peers(None))
            self.log(f"store changed by another writer: {count} parameters announced")

    def _echo(self, msg: Any, index: int, stored: ParamEntry) -> _RawParamValue:
        """The PARAM_VALUE that acknowledges an accepted write. A float leaf stored narrower
        than float32 (float16) holds the value rounded; ground stations (MAVSDK, QGC,
        MAVProxy) take a write as acknowledged only when the echo equals what they sent, so
        the echo carries the float32 they sent; reads and lists report the stored value."""
        if stored.mav_type == _REAL32:
            sent = (_payload_of(msg) + bytes(4))[:4]
            return _RawParamValue(stored.name, sent, _REAL32, len(self.entries()), index)
        return self._value_msg(index, stored)

    def _refuse(
        self,
        peer: Address,
        msg: Any,
        name: str,
        found: tuple[int, ParamEntry] | None,
        why: str,
        code: int,
    ) -> None:
        self.stats["refused"] += 1
        self.log(f"refused: {why}")
        if found is not None:  # the unchanged value, so that the ground station shows it
            self._send(self._value_msg(*found), [peer])
        self._error(peer, msg, name, found[0] if found else -1, why, code)

    def _error(
        self,
        peer: Address,
        msg: Any,
        name: str,
        index: int,
        why: str,
        code: int = mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST,
    ) -> None:
        self._statustext(why, [peer])
        error = mavlink.MAVLink_param_error_message(
            msg.get_srcSystem(),
            msg.get_srcComponent(),
            # the request's own bytes, so that the asker can match the error to it (a name
            # that is not text was answered with U+FFFD's three bytes for each odd byte)
            _param_id_of(msg),
            max(-0x8000, min(index, 0x7FFF)),  # an int16
            code,
        )
        self._send(error, [peer])

    # -- other messages -----------------------------------------------------------------------

    def _command(self, peer: Address, msg: Any) -> None:
        """Every COMMAND_LONG gets a COMMAND_ACK: accepted, or unsupported for what this server
        does not do, or denied for parameters that name nothing (NaN, infinities, huge)."""
        result, reply = self._command_result(msg)
        if reply is not None:  # the message first, then the ACK, as PX4 does
            self._send(reply, [peer])
        ack = mavlink.MAVLink_command_ack_message(
            msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
        )
        self._send(ack, [peer])

    def _command_result(self, msg: Any) -> tuple[int, Any | None]:
        if msg.command == mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES:
            return mavlink.MAV_RESULT_ACCEPTED, self.autopilot_version()
        if msg.command != mavlink.MAV_CMD_REQUEST_MESSAGE:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        message_id = _message_id(msg.param1)
        if message_id is None:
            return mavlink.MAV_RESULT_DENIED, None
        reply = self._requested(message_id)
        if reply is None:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        return mavlink.MAV_RESULT_ACCEPTED, reply

    def _requested(self, message_id: int) -> Any | None:
        """The message MAV_CMD_REQUEST_MESSAGE asks for, if this server provides it."""
        if message_id == mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION:
            return self.autopilot_version()
        uptime = int((time.monotonic() - self._started) * 1000) & 0xFFFFFFFF
        if message_id == COMPONENT_METADATA:
            return mavlink_messages.component_metadata(
                uptime, self.metadata.general_crc, self.metadata.general_uri
            )
        if message_id == COMPONENT_INFORMATION:
            return mavlink_messages.component_information(
                uptime, self.metadata.general_crc, self.metadata.general_uri
            )
        return None

    def _file_transfer(self, peer: Address, msg: Any) -> None:
        """MAVLink FTP: every response goes to the requester's system and component, a burst
        read's paced as a parameter list is: one 20-byte request is answered with up to 37 kB,
        which at once, to a forged source, made the server an amplifier."""
        to = (msg.get_srcSystem(), msg.get_srcComponent())
        payloads = self.ftp.handle(bytes(msg.payload), owner=peer)
        if len(payloads) > 1:
            self._bursts[peer] = (to, deque(payloads))
            return
        for payload in payloads:
            self._send_ftp(to, payload, peer)

    def _send_ftp(self, to: tuple[int, int], payload: bytes, peer: Address) -> None:
        reply = mavlink.MAVLink_file_transfer_protocol_message(0, *to, list(payload))
        self._send(reply, [peer])

    def autopilot_version(self) -> mavlink.MAVLink_autopilot_version_message:
        """PX4's AUTOPILOT_VERSION: capabilities, the package's version as flight software
        version (PX4's encoding: major, minor, patch, release type in the four bytes) and a uid
        that stays the same for the same store."""
        zeros = [0] * 8
        return mavlink.MAVLink_autopilot_version_message(
            CAPABILITIES,
            software_version(),
            0,
            0,
            0,
            zeros,
            zeros,
            zeros,
            0,
            0,
            self.uid[0],
            list(self.uid[1]),
        )

    def _heartbeat(self) -> None:
        targets = self._peers(None)
        if not targets:
            return
        msg = mavlink.MAVLink_heartbeat_message(
            mavlink.MAV_TYPE_GENERIC,
            mavlink.MAV_AUTOPILOT_PX4,
            mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            0,
            mavlink.MAV_STATE_STANDBY,
            3,
        )
        self._send(msg, targets)

    def _report_health(self) -> None:
        peers = self._peers(None)
        if not peers or self.health is None:
            return
        try:
            lines = self.health()
        except Exception as e:  # a failing health source must not stop the server
            self.log(f"error reporting health: {type(e).__name__}: {e}")
            return
        for line in lines:
            self._statustext(line, peers)

    def _statustext(self, text: str, peers: list[Address]) -> None:
        """STATUSTEXT, split into 50-character chunks with an id when longer (MAVLink 2)."""
        data = text.encode("ascii", "replace")
        if len(data) <= _TEXT_CHUNK:
            chunks, text_id = [data], 0
        else:
            self._text_id = self._text_id % 0xFFFF + 1
            text_id = self._text_id
            chunks = [data[i : i + _TEXT_CHUNK] for i in range(0, len(data), _TEXT_CHUNK)]
            if len(chunks[-1]) == _TEXT_CHUNK:
                chunks.append(b"")  # the end is marked by a NUL
        for seq, chunk in enumerate(chunks):
            msg = mavlink.MAVLink_statustext_message(
                mavlink.MAV_SEVERITY_WARNING, chunk, text_id, seq
            )
            self._send(msg, peers)

    def _peers(self, first: Address | None) -> list[Address]:
        """The peers heard from recently, the ``gcs`` addresses, and ``first`` first."""
        peers = [p for p in self._seen if self._alive(p)]
        peers += [g for g in self._gcs if g not in peers]
        if first is not None and first not in peers:
            peers.insert(0, first)
        return peers

    def _send(self, msg: Any, peers: list[Address]) -> None:
        buf = msg.pack(self._mav)
        self._mav.seq = (self._mav.seq + 1) % 256
        for peer in peers:
            for _ in range(50):
                try:
                    self._sock.sendto(buf, peer)
                    self.stats["sent"] += 1
                    break
                except BlockingIOError:  # send buffer full (list streaming): wait, don't drop
                    select.select([], [self._sock], [], 0.01)
                except OSError:  # a peer that cannot be reached must not stop the others
                    break


def _message_id(param: float) -> int | None:
    """A message ID given in a float command parameter, or None if it is none (NaN, inf,
    fractional, negative or beyond MAVLink 2's 24 bits)."""
    if not math.isfinite(param) or param != int(param) or not 0 <= param < 1 << 24:
        return None
    return int(param)


def software_version() -> int:
    """This package's version as PX4 encodes ``flight_sw_version``: major, minor and patch in
    the top three bytes, the release type in the lowest (255 official, 0 development)."""
    major, minor, patch, development = version_parts()
    release = 0 if development else 255
    return (major & 0xFF) << 24 | (minor & 0xFF) << 16 | (patch & 0xFF) << 8 | release


def store_uid(
    store_path: str | os.PathLike[str] | None, parameters: Iterable[str]
) -> tuple[int, bytes]:
    """``(uid, uid2)`` of AUTOPILOT_VERSION for a store (:func:`identity.store_digest`)."""
    digest = store_digest(store_path, parameters)
    return int.from_bytes(digest[:8], "little") or 1, digest[8:26]


def _shown(value: int | float) -> str:
    if isinstance(value, float) and math.isfinite(value):
        return f"{value:.9g}"
    return str(value)
