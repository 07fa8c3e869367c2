"""A DroneCAN node that serves the store's parameters, behind an SLCAN adapter on a serial line
(as flight controllers that pass CAN over USB do).

What it does (PX4's UAVCAN node and the DroneCAN specification are the model):

* ``uavcan.protocol.NodeStatus`` once a second while the host has the channel open: uptime,
  health from the manifest (:class:`~px4params.vehicle.health.ManifestHealth` through the
  ``health`` callable: nominal -> OK, warning -> WARNING, critical -> ERROR), mode OPERATIONAL,
  and as vendor status code the number of devices that are not nominal.
* ``uavcan.protocol.GetNodeInfo``: name ``org.px4params``, this package's version, a unique ID
  that stays with the store file.
* ``uavcan.protocol.param.GetSet`` by index and by name over
  :class:`~px4params.links.dronecan_params.DronecanParams` (classic parameters, every live leaf
  under its long name, the instance masks). A write is checked like every other write; a
  refused one is answered with the unchanged value and changes nothing. Writes change the
  running values; ``ExecuteOpcode`` SAVE writes them to the store file.
* ``uavcan.protocol.param.ExecuteOpcode``: SAVE saves the node's changes through the store's
  one write path (:class:`~px4params.store.session.Session`: under its lock, on top of what
  other writers saved meanwhile; refused when both changed the same leaf); ERASE writes a
  store file with every value at its default (instances stay), which takes effect at the next
  restart, as the specification says.
* ``uavcan.protocol.RestartNode`` with the right magic number: acknowledged, then the store is
  read again from its file.
* What other writers save to the store file is read within a second (the node's unsaved
  changes stay on top), so that GetSet answers with the file's values.

Requests are reassembled from frames with the DroneCAN transfer rules
(:class:`~px4params.links.can_transfer.TransferReceiver`); responses carry the request's
transfer ID and priority and span as many frames as they need. Frames for other nodes,
messages, malformed frames and requests for other services are ignored; the node keeps going.
"""

from __future__ import annotations

import select
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from px4params.dsdl.schema import Schema, load_schema
from px4params.errors import Px4ParamsError, StoreConflictError
from px4params.links import can_transfer
from px4params.links.can_transfer import CanId, Frame, Transfer, TransferReceiver
from px4params.links.dronecan_params import EMPTY, DronecanParams, variant_name
from px4params.links.identity import store_digest, version_parts
from px4params.links.serving import ServingLoop
from px4params.links.slcan import WRITE_SECONDS, SerialPort, SlcanAdapter, read_port
from px4params.store.session import Session

if TYPE_CHECKING:
    from px4params.store.store import Store

__all__ = ["HEALTH_CODES", "NODE_NAME", "DronecanParamNode"]

NODE_NAME = "org.px4params"
#: NodeStatus health per device health (the node itself works; a device failing is an error).
HEALTH_CODES = {"nominal": 0, "warning": 1, "critical": 2}
#: RestartNode's magic number.
RESTART_MAGIC = 0xACCE551B1E
OPCODE_SAVE, OPCODE_ERASE = 0, 1

_SERVICES = {
    "uavcan.protocol.GetNodeInfo": "_get_node_info",
    "uavcan.protocol.param.GetSet": "_get_set",
    "uavcan.protocol.param.ExecuteOpcode": "_execute_opcode",
    "uavcan.protocol.RestartNode": "_restart",
}


class DronecanParamNode(ServingLoop):
    """Serves ``store`` as node ``node_id`` on ``port`` (an SLCAN serial line, this end being
    the adapter).

    ``save_path``: the store file SAVE writes and RestartNode reads (None: in memory only).
    ``health``: returns ``(health, not_nominal)``, e.g. from
    :class:`~px4params.vehicle.health.ManifestHealth`; None reports OK.
    ``log``: called with one line per write, refusal, save and restart.
    """

    thread_name = "dronecan-node"

    def __init__(
        self,
        store: Store,
        port: SerialPort,
        *,
        node_id: int = 1,
        save_path: str | None = None,
        health: Callable[[], tuple[str, int]] | None = None,
        log: Callable[[str], None] | None = None,
        status_interval: float = 1.0,
        schema: Schema | None = None,
        session: Session | None = None,
        poll_interval: float = 0.2,
    ) -> None:
        if not 1 <= node_id <= 127:
            raise ValueError(f"node ID {node_id} is out of range (expected 1..127)")
        super().__init__()
        self.store = store
        self.port = port
        self.node_id = node_id
        if session is None and save_path is not None:
            session = Session(store, save_path)
        self.session = session
        if save_path is None and session is not None:
            save_path = session.path
        self.save_path = save_path
        self.poll_interval = poll_interval
        self._next_poll = 0.0
        self.health = health
        self.log = log or (lambda line: None)
        self.status_interval = status_interval
        self.params = DronecanParams(store)
        self.adapter = SlcanAdapter()
        types = schema or load_schema([], include_dronecan=True, use_env=False)
        #: (request, response) of each service offered.
        self._services = {
            name: (types[f"{name}.Request"], types[f"{name}.Response"]) for name in _SERVICES
        }
        self._node_status = types["uavcan.protocol.NodeStatus"]
        self._by_dtid = {request.dtid: name for name, (request, _) in self._services.items()}
        self.receiver = TransferReceiver(self._for_us)
        self.unique_id = store_digest(self.save_path, store.parameters)[:16]
        self._started = time.monotonic()
        self._next_status = 0.0
        self._status_tid = 0
        #: Counters, for tests and the CLI's summary.
        self.stats = {
            "requests": 0,
            "ignored": 0,
            "accepted": 0,
            "refused": 0,
            "saves": 0,
            "dropped": 0,
        }
        #: Writes dropped since the host last read.
        self._dropped = 0

    # -- lifecycle ----------------------------------------------------------------------------

    def step(self, timeout: float) -> None:
        """One turn: read what the host wrote (waiting up to ``timeout``), answer, and send
        NodeStatus when it is due."""
        now = time.monotonic()
        if now >= self._next_status:
            self._next_status = now + self.status_interval
            self._send_status()
        if self.session is not None and now >= self._next_poll:
            self._next_poll = now + self.poll_interval
            self._poll_store()
        wait = max(0.0, min(timeout, self._next_status - now))
        ready, _, _ = select.select([self.port.fileno()], [], [], wait)
        if not ready:
            return
        replies, frames = self.adapter.feed(read_port(self.port))
        if replies:
            self._write(replies)
        for frame in frames:
            self.on_frame(frame)

    # -- frames and transfers -----------------------------------------------------------------

    def _for_us(self, ident: CanId) -> bool:
        return ident.service and ident.request and ident.dest_node == self.node_id

    def on_frame(self, frame: Frame) -> None:
        """Takes one frame from the bus; answers the request it completes, if any."""
        transfer = self.receiver.feed(frame)
        if transfer is None:
            return
        name = self._by_dtid.get(transfer.id.dtid)
        if name is None:
            self.stats["ignored"] += 1  # a service this node does not offer
            return
        request_type = self._services[name][0]
        try:
            request, _ = can_transfer.reassemble(request_type, transfer.datas)
        except Px4ParamsError:  # a bad CRC, or not a value of the type
            self.stats["ignored"] += 1
            return
        self.stats["requests"] += 1
        response = getattr(self, _SERVICES[name])(request)
        self._respond(name, transfer, response)

    def _respond(self, name: str, transfer: Transfer, response: dict[str, Any]) -> None:
        frames = can_transfer.frames(
            self._services[name][1],
            response,
            source_node=self.node_id,
            transfer_id=transfer.transfer_id,
            priority=transfer.id.priority,
            dest_node=transfer.id.source_node,
            dtid=transfer.id.dtid,
        )
        self._send(frames)
        if name == "uavcan.protocol.RestartNode" and response["ok"]:
            self._reload()

    def _send(self, frames: list[Frame]) -> None:
        out = b"".join(self.adapter.deliver(f) for f in frames)
        if out:
            self._write(out)

    def _write(self, data: bytes) -> None:
        """Writes to the host. A host that does not read loses what is written meanwhile, as
        a CAN adapter drops the frames its host does not take: said once, and again when it
        reads again; the node goes on answering and stopping."""
        went = False
        # Once the host has stopped reading, a write waits for no one: it goes only if the
        # line takes it at once (else a backlog of requests would each wait WRITE_SECONDS).
        if not self._dropped or select.select([], [self.port.fileno()], [], 0)[1]:
            try:
                written = self.port.write(data)
                went = written is None or written >= len(data)  # (pyserial: None is all)
            except OSError:  # pyserial's write timeout (SerialTimeoutException) is one
                pass
        if went:
            if self._dropped:
                self.log(f"the host reads again: {self._dropped} writes to it were dropped")
                self._dropped = 0
            return
        self.stats["dropped"] += 1
        if not self._dropped:
            self.log(
                f"the host is not reading: what the node sends is dropped until it does "
                f"({WRITE_SECONDS} s waited)"
            )
        self._dropped += 1

    # -- NodeStatus and GetNodeInfo ----------------------------------------------------------

    def status(self) -> dict[str, Any]:
        """The current NodeStatus value."""
        health, bad = "nominal", 0
        if self.health is not None:
            try:
                health, bad = self.health()
            except Exception as e:  # a failing health source must not stop the node
                self.log(f"error computing health: {type(e).__name__}: {e}")
                health = "warning"
        return {
            "uptime_sec": int(time.monotonic() - self._started) & 0xFFFFFFFF,
            "health": HEALTH_CODES.get(health, 1),
            "mode": 0,  # OPERATIONAL
            "sub_mode": 0,
            "vendor_specific_status_code": min(bad, 0xFFFF),
        }

    def _send_status(self) -> None:
        if not self.adapter.open:
            return
        frames = can_transfer.frames(
            self._node_status,
            self.status(),
            source_node=self.node_id,
            transfer_id=self._status_tid,
        )
        self._status_tid = (self._status_tid + 1) % 32
        self._send(frames)

    def _get_node_info(self, request: dict[str, Any]) -> dict[str, Any]:
        major, minor, _, _ = version_parts()
        return {
            "status": self.status(),
            "software_version": {
                "major": major,
                "minor": minor,
                "optional_field_flags": 0,
                "vcs_commit": 0,
                "image_crc": 0,
            },
            "hardware_version": {
                "major": 0,
                "minor": 0,
                "unique_id": list(self.unique_id),
                "certificate_of_authenticity": [],
            },
            "name": NODE_NAME.encode(),
        }

    # -- parameters ---------------------------------------------------------------------------

    def _get_set(self, request: dict[str, Any]) -> dict[str, Any]:
        name = bytes(request["name"]).decode("ascii", "replace")
        if not name:
            found = self.params.name_at(request["index"])
            name = found or ""
        value = request["value"]
        if name and variant_name(value) != "empty":
            try:
                change = self.params.set(name, value)
            except Px4ParamsError as e:
                self.stats["refused"] += 1
                self.log(f"refused: {e}")
            else:
                self.stats["accepted"] += 1
                self.log(change)
        entry = self.params.entry(name) if name else None
        if entry is None:  # no such parameter: empty name and value, as the spec says
            return {
                "value": EMPTY,
                "default_value": EMPTY,
                "max_value": EMPTY,
                "min_value": EMPTY,
                "name": b"",
            }
        return {
            "value": entry.value,
            "default_value": entry.default,
            "max_value": entry.max,
            "min_value": entry.min,
            "name": entry.name.encode(),
        }

    def _execute_opcode(self, request: dict[str, Any]) -> dict[str, Any]:
        opcode = request["opcode"]
        ok = False
        if opcode == OPCODE_SAVE:
            ok = self._save(erase=False)
        elif opcode == OPCODE_ERASE:
            ok = self._save(erase=True)
        else:
            self.log(f"refused: ExecuteOpcode {opcode} (SAVE is 0, ERASE is 1)")
        return {"argument": 0, "ok": ok}

    def _poll_store(self) -> None:
        """Other writers' saves: read into the store (this node's unsaved changes on top)."""
        assert self.session is not None
        try:
            changed = self.session.poll()
        except Px4ParamsError as e:  # said once per version of the file
            self.log(f"store changed by another writer, not read: {e}")
            return
        if changed:
            self.params = DronecanParams(self.store)
            self.log("store changed by another writer: values read again")

    def _save(self, *, erase: bool) -> bool:
        what = "erase" if erase else "save"
        if self.session is None:
            self.log(f"refused: {what}: no store file (serving a store in memory)")
            return False
        try:
            if erase:
                # Every value at its default goes to the file; the running values stay until
                # the next restart.
                self.session.rewrite(lambda store: store.reset_all())
            else:
                self.session.commit(lambda: None)
        except StoreConflictError as e:
            # Refused whole; the values shown become the file's, so that GetSet tells the
            # truth and the client can set its changes again.
            note = "; the node's values are the file's again"
            try:
                self.session.reload()
            except Px4ParamsError:  # unreadable: the running values stay
                note = ""
            self.log(f"refused: {what}: {e}{note}")
            return False
        except (Px4ParamsError, OSError) as e:
            self.log(f"refused: {what}: {e}")
            return False
        finally:
            self.params = DronecanParams(self.store)  # other writers' changes may be in
        self.stats["saves"] += 1
        self.log(f"{'erased' if erase else 'saved'}: {self.save_path}")
        return True

    def _restart(self, request: dict[str, Any]) -> dict[str, Any]:
        ok = request["magic_number"] == RESTART_MAGIC
        if not ok:
            self.log(f"refused: RestartNode magic number {request['magic_number']:#x}")
        return {"ok": ok}

    def _reload(self) -> None:
        """A restart: the running values become the store file's again."""
        if self.session is None:
            self.store.reset_to_initial()
        else:
            try:
                self.session.reload()  # a bad file leaves the running values
            except Px4ParamsError as e:
                self.log(f"restart: the store file cannot be read, values kept: {e}")
                return
        self.params = DronecanParams(self.store)
        self._started = time.monotonic()
        self.log("restarted: values read again from the store file")
