"""DroneCAN transfers: a value as the CAN frames that carry it, and frames back to a value.

The frame data (payload pieces, transfer CRC, CAN FD padding, tail bytes) comes from the native
core; this module adds the 29-bit CAN IDs and the link to a
:class:`~px4params.dsdl.schema.DataType`.

CAN IDs (DroneCAN / UAVCAN v0):

* message frame: ``priority << 24 | dtid << 8 | source_node`` (bit 7, service, clear);
* service frame: ``priority << 24 | dtid << 16 | request << 15 | dest_node << 8 | 1 << 7 |
  source_node``.

Anonymous messages (source node 0) are not supported.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

from px4params import _native
from px4params.dsdl.schema import DataType

__all__ = [
    "DEFAULT_PRIORITY",
    "CanId",
    "Frame",
    "Transfer",
    "TransferReceiver",
    "can_id",
    "frames",
    "parse_can_id",
    "reassemble",
    "service_half",
]

#: pydronecan's default transfer priority (the lowest).
DEFAULT_PRIORITY = 31


class Frame(NamedTuple):
    """One CAN frame: 29-bit extended ID and data bytes (tail byte included)."""

    can_id: int
    data: bytes


def _check(what: str, value: int, low: int, high: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ValueError(f"{what} must be an integer in {low}..{high}, got {value!r}")


def can_id(
    dtid: int,
    *,
    source_node: int,
    priority: int = DEFAULT_PRIORITY,
    dest_node: int | None = None,
    request: bool = False,
) -> int:
    """The 29-bit CAN ID of a message frame, or of a service frame when ``dest_node`` is given.

    Raises:
        ValueError: a number out of range (source and destination node 1..127, priority 0..31,
            message data type ID 0..65535, service data type ID 0..255).
    """
    _check("priority", priority, 0, 31)
    _check("source node ID", source_node, 1, 127)
    if dest_node is None:
        _check("message data type ID", dtid, 0, 0xFFFF)
        return priority << 24 | dtid << 8 | source_node
    _check("service data type ID", dtid, 0, 0xFF)
    _check("destination node ID", dest_node, 1, 127)
    return priority << 24 | dtid << 16 | int(request) << 15 | dest_node << 8 | 1 << 7 | source_node


def service_half(data_type: DataType) -> str | None:
    """``"request"`` or ``"response"`` for a half of a service, None for a message."""
    if not data_type.type_def.service:
        return None
    return "request" if data_type.name.endswith(".Request") else "response"


def frames(
    data_type: DataType,
    value: Mapping[str, Any],
    *,
    source_node: int,
    transfer_id: int = 0,
    priority: int = DEFAULT_PRIORITY,
    dest_node: int | None = None,
    dtid: int | None = None,
    canfd: bool = False,
    saturate: bool = False,
) -> list[Frame]:
    """The frames of one transfer of ``value`` (encoded without TAO on CAN FD).

    A service half needs ``dest_node``; ``dtid`` defaults to the type's own.

    Raises:
        EncodeError: ``value`` does not fit the type.
        ValueError: no data type ID, a number out of range, or ``dest_node`` given for a message
            or missing for a service.
    """
    half = service_half(data_type)
    if half is None and dest_node is not None:
        raise ValueError(f"{data_type.key} is a message; a destination node is for services")
    if half is not None and dest_node is None:
        raise ValueError(f"{data_type.key} is a service {half}; it needs a destination node")
    if dtid is None:
        dtid = data_type.dtid
        if dtid is None:
            raise ValueError(f"{data_type.key} has no default data type ID; give one")
    _check("transfer ID", transfer_id, 0, 31)
    identifier = can_id(
        dtid,
        source_node=source_node,
        priority=priority,
        dest_node=dest_node,
        request=half == "request",
    )
    payload = data_type.encode(value, tao=not canfd, saturate=saturate)
    datas = _native.can_frames(
        payload, signature=data_type.signature, transfer_id=transfer_id, canfd=canfd
    )
    return [Frame(identifier, bytes(d)) for d in datas]


def reassemble(
    data_type: DataType, datas: Sequence[bytes], *, canfd: bool = False
) -> tuple[dict[str, Any], int]:
    """The value and transfer ID carried by the frames' data (tail bytes included).

    Raises:
        TransferError: the frames are not one valid transfer (toggle, start/end bits, transfer
            IDs, CRC).
        DecodeError: the payload is not a value of the type.
    """
    payload, transfer_id = _native.reassemble(
        [bytes(d) for d in datas], signature=data_type.signature
    )
    # CAN FD padding of a multi-frame transfer is zero bytes after the value.
    value = data_type.decode(payload, tao=not canfd, allow_trailing=canfd)
    return value, int(transfer_id)


class CanId(NamedTuple):
    """The fields of a 29-bit DroneCAN CAN ID."""

    priority: int
    dtid: int
    source_node: int
    #: None for a message.
    dest_node: int | None = None
    request: bool = False

    @property
    def service(self) -> bool:
        return self.dest_node is not None


def parse_can_id(identifier: int) -> CanId:
    """The inverse of :func:`can_id` (anonymous messages give source node 0)."""
    priority, source = identifier >> 24 & 0x1F, identifier & 0x7F
    if identifier & 0x80:
        return CanId(
            priority,
            identifier >> 16 & 0xFF,
            source,
            identifier >> 8 & 0x7F,
            bool(identifier & 0x8000),
        )
    return CanId(priority, identifier >> 8 & 0xFFFF, source)


class Transfer(NamedTuple):
    """A complete transfer as received: its ID fields, transfer ID and frame data (tail bytes
    included, CRC not yet checked: that needs the data type's signature, see
    :func:`reassemble`)."""

    id: CanId
    transfer_id: int
    datas: list[bytes]


#: DroneCAN's transfer timeout: a session silent this long is forgotten.
TRANSFER_TIMEOUT = 2.0
#: Frames of one transfer at most (GetNodeInfo's largest response needs 60 on classic CAN).
MAX_TRANSFER_FRAMES = 256


class TransferReceiver:
    """Frames in, complete transfers out, per the DroneCAN rules: one session per (type, kind,
    source, destination); a transfer starts with a start-of-transfer frame whose toggle bit is
    clear, every next frame has the same transfer ID and the other toggle, the last has the
    end bit. A frame that breaks the rules drops the session; frames without a session (a
    transfer joined half-way) are ignored; a transfer repeated with the same transfer ID
    within the timeout (a redundant interface) is delivered once.

    ``accept`` says which transfers to assemble (by their ID fields), e.g. only services
    addressed to this node.
    """

    def __init__(self, accept: Any = None, *, clock: Any = time.monotonic) -> None:
        self._accept = accept
        self._clock = clock
        self._sessions: dict[tuple[Any, ...], tuple[int, int, float, list[bytes]]] = {}
        self._done: dict[tuple[Any, ...], tuple[int, float]] = {}
        #: Frames ignored (foreign, malformed, out of order), for logs and tests.
        self.ignored = 0

    def feed(self, frame: Frame) -> Transfer | None:
        """The transfer ``frame`` completes, or None."""
        ident = parse_can_id(frame.can_id)
        if not frame.data or ident.source_node == 0:
            self.ignored += 1
            return None
        if self._accept is not None and not self._accept(ident):
            return None
        tail = frame.data[-1]
        start, end, toggle, tid = tail & 0x80, tail & 0x40, (tail >> 5) & 1, tail & 0x1F
        key = (ident.dtid, ident.service, ident.request, ident.source_node, ident.dest_node)
        now = self._clock()
        if start:
            if toggle:
                self.ignored += 1
                return None
            last = self._done.get(key)
            if last is not None and last[0] == tid and now - last[1] < TRANSFER_TIMEOUT:
                self.ignored += 1  # the same transfer again
                return None
            self._sessions[key] = (tid, 0, now, [])
        session = self._sessions.get(key)
        if session is None:
            self.ignored += 1
            return None
        expected_tid, expected_toggle, started, datas = session
        if tid != expected_tid or toggle != expected_toggle or now - started > TRANSFER_TIMEOUT:
            del self._sessions[key]
            self.ignored += 1
            return None
        datas.append(bytes(frame.data))
        if len(datas) > MAX_TRANSFER_FRAMES:
            del self._sessions[key]
            self.ignored += 1
            return None
        if not end:
            self._sessions[key] = (expected_tid, expected_toggle ^ 1, started, datas)
            return None
        del self._sessions[key]
        self._done[key] = (tid, now)
        if len(self._done) > 4096:  # many peers over a long time: forget the oldest
            self._done.pop(next(iter(self._done)))
        return Transfer(ident, tid, datas)
