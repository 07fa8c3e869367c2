"""The other direction: this program as a DroneCAN node on an SLCAN adapter, reading and writing
a remote node's parameters (a DroneCAN peripheral: a GPS, a power module, an ESC).

It uses ``uavcan.protocol.param.GetSet`` (enumeration by index until the empty name, reads
and writes by name) and ``uavcan.protocol.param.ExecuteOpcode`` SAVE, with the same frames and
transfer rules as the node (:mod:`px4params.links.can_transfer`). Each request is retried
``retries`` times when no response comes within ``timeout`` seconds.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from typing import Any, NamedTuple

from px4params.dsdl.schema import DataType, Schema, load_schema
from px4params.errors import DronecanError, Px4ParamsError
from px4params.links import can_transfer
from px4params.links.can_transfer import CanId, TransferReceiver
from px4params.links.dronecan_params import EMPTY, variant_name
from px4params.links.slcan import SlcanHost

__all__ = ["DronecanError", "DronecanParamClient", "RemoteParam", "parse_value", "shown"]

#: The DroneCAN GUI tool's node ID; free on most buses.
DEFAULT_LOCAL_NODE = 127
_GETSET = "uavcan.protocol.param.GetSet"
_OPCODE = "uavcan.protocol.param.ExecuteOpcode"


class RemoteParam(NamedTuple):
    """A remote parameter as GetSet returned it (values as ``Value`` variants)."""

    index: int | None  # type: ignore[assignment]  # a field named index hides tuple.index, as Leaf's must
    name: str
    value: dict[str, Any]
    default: dict[str, Any]
    min: dict[str, Any]
    max: dict[str, Any]


def shown(value: dict[str, Any]) -> str:
    """A ``Value`` variant as text: ``42``, ``0.5``, ``true``, ``"text"``, ``(empty)``."""
    kind = variant_name(value)
    if kind == "empty":
        return "(empty)"
    number = value[kind]
    if kind == "boolean_value":
        return "true" if number else "false"
    if kind == "string_value":
        return repr(bytes(number).decode("utf-8", "replace"))
    if kind == "real_value":
        return f"{number:.9g}" if math.isfinite(number) else str(number)
    return str(number)


def parse_value(text: str, like: dict[str, Any]) -> dict[str, Any]:
    """``text`` as a ``Value`` of the variant ``like`` has (the parameter's current value).

    Raises:
        DronecanError: the text is not a value of that kind (the message says what is).
    """
    kind = variant_name(like)
    word = text.strip()
    try:
        if kind == "integer_value":
            number = int(word, 0)
            if not -(1 << 63) <= number < 1 << 63:
                raise ValueError
            return {kind: number}
        if kind == "real_value":
            return {kind: float(word)}
        if kind == "boolean_value":
            flags = {"1": 1, "true": 1, "on": 1, "0": 0, "false": 0, "off": 0}
            return {kind: flags[word.lower()]}
        if kind == "string_value":
            return {kind: word.encode()}
    except (ValueError, KeyError):
        pass
    expected = {
        "integer_value": "an integer (int64)",
        "real_value": "a number",
        "boolean_value": "true or false",
    }.get(kind, "nothing: the parameter has no value")
    raise DronecanError(f"'{text}' is not {expected}")


class DronecanParamClient:
    """Talks to node ``node`` through ``host`` as node ``local_node``."""

    def __init__(
        self,
        host: SlcanHost,
        node: int,
        *,
        local_node: int = DEFAULT_LOCAL_NODE,
        timeout: float = 1.0,
        retries: int = 2,
        schema: Schema | None = None,
    ) -> None:
        for what, number in (("node ID", node), ("local node ID", local_node)):
            if not 1 <= number <= 127:
                raise DronecanError(f"{what} {number} is out of range (expected 1..127)")
        if node == local_node:
            raise DronecanError(f"node ID {node} is also this program's node ID (--local-node)")
        self.host = host
        self.node = node
        self.local_node = local_node
        self.timeout = timeout
        self.retries = retries
        types = schema or load_schema([], include_dronecan=True, use_env=False)
        self._types: dict[str, tuple[DataType, DataType]] = {
            name: (types[f"{name}.Request"], types[f"{name}.Response"])
            for name in (_GETSET, _OPCODE)
        }
        self._tids: dict[int, int] = {}
        self.receiver = TransferReceiver(self._for_us)

    def _for_us(self, ident: CanId) -> bool:
        return (
            ident.service
            and not ident.request
            and ident.dest_node == self.local_node
            and ident.source_node == self.node
        )

    def call(self, service: str, request: dict[str, Any]) -> dict[str, Any]:
        """Sends ``request`` and returns the response (retried on silence).

        Raises:
            DronecanError: no response after the retries.
        """
        request_type, response_type = self._types[service]
        dtid = request_type.dtid
        assert dtid is not None
        for _ in range(self.retries + 1):
            tid = self._tids.get(dtid, 0)
            self._tids[dtid] = (tid + 1) % 32
            for frame in can_transfer.frames(
                request_type,
                request,
                source_node=self.local_node,
                transfer_id=tid,
                dest_node=self.node,
                priority=can_transfer.DEFAULT_PRIORITY,
            ):
                self.host.send(frame)
            response = self._wait(response_type, dtid, tid)
            if response is not None:
                return response
        tries = self.retries + 1
        raise DronecanError(
            f"node {self.node} did not answer {service.rsplit('.', 1)[-1]} "
            f"({tries} tries, {self.timeout:g} s each): is it on the bus, with that node ID?"
        )

    def _wait(self, response_type: DataType, dtid: int, tid: int) -> dict[str, Any] | None:
        deadline = time.monotonic() + self.timeout
        while (left := deadline - time.monotonic()) > 0:
            frame = self.host.receive(left)
            if frame is None:
                return None
            transfer = self.receiver.feed(frame)
            if transfer is None or transfer.id.dtid != dtid or transfer.transfer_id != tid:
                continue
            try:
                value, _ = can_transfer.reassemble(response_type, transfer.datas)
            except Px4ParamsError:
                continue  # a damaged response: wait for the retry
            return value
        return None

    # -- parameters ---------------------------------------------------------------------------

    def get(self, name: str | None = None, index: int | None = None) -> RemoteParam | None:
        """The parameter ``name`` (or at ``index``); None when the node has no such one."""
        request = {"index": index or 0, "value": EMPTY, "name": (name or "").encode()}
        return self._getset(request, index)

    def _getset(self, request: dict[str, Any], index: int | None) -> RemoteParam | None:
        response = self.call(_GETSET, request)
        found = bytes(response["name"]).decode("utf-8", "replace")
        if not found:
            return None
        return RemoteParam(
            index,
            found,
            response["value"],
            response["default_value"],
            response["min_value"],
            response["max_value"],
        )

    def list(self, progress: Callable[[int], None] | None = None) -> Iterator[RemoteParam]:
        """Every parameter, by index from 0 until the node answers with an empty name."""
        for index in range(1 << 13):
            param = self.get(index=index)
            if param is None:
                return
            if progress is not None:
                progress(index + 1)
            yield param

    def set(self, name: str, value: dict[str, Any]) -> RemoteParam:
        """Writes ``value`` to ``name``; returns the parameter as the node answered (a node may
        store a number rounded, e.g. to float16).

        Raises:
            DronecanError: no such parameter, or the node kept its value (refused).
        """
        before = self.get(name)
        if before is None:
            raise DronecanError(f"node {self.node} has no parameter {name}")
        request = {"index": 0, "value": value, "name": name.encode()}
        param = self._getset(request, None)
        if param is None:
            raise DronecanError(f"node {self.node} has no parameter {name}")
        if not _same(param.value, value) and (
            _same(param.value, before.value) or variant_name(param.value) != variant_name(value)
        ):
            raise DronecanError(
                f"node {self.node} refused {name} = {shown(value)}: it kept {shown(param.value)}"
            )
        return param

    def save(self) -> None:
        """ExecuteOpcode SAVE: the node writes its parameters to its non-volatile storage."""
        response = self.call(_OPCODE, {"opcode": 0, "argument": 0})
        if not response["ok"]:
            raise DronecanError(f"node {self.node} refused to save its parameters")


def _same(got: dict[str, Any], sent: dict[str, Any]) -> bool:
    """Whether the node kept what was sent (a float32 read back equals the float32 sent)."""
    kind = variant_name(sent)
    if variant_name(got) != kind:
        return False
    if kind == "real_value":
        import struct

        def f32(x: float) -> bytes:
            try:
                return struct.pack("<f", x)
            except OverflowError:
                return b"inf"

        return f32(got[kind]) == f32(sent[kind])
    return bool(got[kind] == sent[kind])
