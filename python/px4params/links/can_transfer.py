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

from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

from px4params import _native
from px4params.dsdl.schema import DataType

__all__ = [
    "DEFAULT_PRIORITY",
    "Frame",
    "can_id",
    "frames",
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
    if not data_type.definition.get("service"):
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
