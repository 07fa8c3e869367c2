"""What the page talks to: a vehicle over MAVLink, or a store file offline. Both offer the same
flat view a ground station has (classic parameters, destructured names, instance masks, by
name, as numbers), the metadata that describes it (``parameters.json``), writes that are
checked by the vehicle and answered accepted or refused with its reason, and health reports.
"""

from __future__ import annotations

import contextlib
import json
import logging
import lzma
import math
import os
import re
import struct
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

from pymavlink.dialects.v20 import common as mavlink

from px4params.errors import CommandError, Px4ParamsError
from px4params.gcs.codec import f16_from_float, float_from_f16
from px4params.links.mavlink import param_name_refusal, param_set_message, param_value_of
from px4params.reading import METADATA_JSON, read_text

__all__ = ["MavlinkVehicle", "StoreVehicle", "WriteResult"]

Listener = Callable[[dict[str, Any]], None]


class WriteResult:
    """One write's outcome: ``ok`` (acknowledged), the value the vehicle reports afterwards,
    and its reason when refused."""

    def __init__(self, name: str, ok: bool, value: int | float | None, reason: str = "") -> None:
        self.name = name
        self.ok = ok
        self.value = value
        self.reason = reason

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "ok": self.ok,
            "value": _json_number(self.value),
            "reason": self.reason,
        }


def _json_number(value: int | float | None) -> int | float | str | None:
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


class _Base:
    """Values, health lines and listeners (the page's WebSocket) shared by both kinds."""

    mode = ""

    def __init__(self) -> None:
        self.values: dict[str, int | float] = {}
        self.metadata: dict[str, Any] = {"version": 1, "parameters": []}
        #: STATUSTEXT lines (newest last) and the health of each device that reported one.
        self.messages: list[str] = []
        self.health: dict[str, dict[str, str]] = {}
        self._listeners: list[Listener] = []
        self._lock = threading.RLock()

    def listen(self, listener: Listener) -> Callable[[], None]:
        self._listeners.append(listener)
        return lambda: self._listeners.remove(listener)

    def _notify(self, event: dict[str, Any]) -> None:
        for listener in list(self._listeners):
            listener(event)

    def _status(self, text: str, whole: bool = True) -> None:
        """A STATUSTEXT from the vehicle: kept, and read for health reports unless chunks of
        it are missing (what is missing may be its instance or state)."""
        self.messages.append(text)
        del self.messages[:-200]
        report = parse_health(text) if whole else None
        if report is not None:
            self.health[report["instance"]] = report
        self._notify({"kind": "status", "text": text, "health": report})

    def state(self) -> dict[str, Any]:
        with self._lock:
            return {
                "mode": self.mode,
                "source": self.source,
                "values": {k: _json_number(v) for k, v in self.values.items()},
                "messages": self.messages[-50:],
                "health": list(self.health.values()),
            }

    source = ""


def parse_health(text: str) -> dict[str, str] | None:
    """A health report line, as the commander and ``mavlink serve --bench`` write them:
    ``health: ina238 INA238#1 on I2C bus 2 address 0x45: critical: not found``."""
    if not text.startswith("health: "):
        return None
    head, _, rest = text[len("health: ") :].partition(": ")
    state, _, reason = rest.partition(": ")
    words = head.split(" ", 2)
    if len(words) < 2 or state not in ("nominal", "warning", "critical"):
        return None
    where = words[2].removeprefix("on ") if len(words) > 2 else ""
    return {
        "driver": words[0],
        "instance": words[1],
        "location": where,
        "state": state,
        "reason": reason,
    }


# -- offline: a store file -----------------------------------------------------------------


class StoreVehicle(_Base):
    """A store file edited offline with the same checks: every accepted write is saved through
    the store's one write path (:class:`~px4params.store.session.Session`: its lock, backup,
    and other writers' changes kept). What other writers save is noticed within
    ``poll_interval`` seconds and pushed to the page."""

    mode = "store"

    def __init__(
        self,
        store_path: str | None,
        classic: str | None,
        dsdl: list[str],
        *,
        poll_interval: float = 0.2,
    ) -> None:
        from px4params.gcs.metadata import build_parameters_json
        from px4params.store.session import open_session

        super().__init__()
        self._session = open_session(store_path, classic, dsdl)
        store = self._session.store
        self.source = self._session.path
        classic_params = [c for c in map(store.classic, store.parameters) if c is not None]
        self.metadata = build_parameters_json(
            store.schema, specs=store.specs, classic_params=classic_params
        )
        self._reload()
        self._closing = threading.Event()
        self._watcher = threading.Thread(
            target=self._watch, args=(poll_interval,), name="gui-store-watch", daemon=True
        )
        self._watcher.start()

    def _watch(self, interval: float) -> None:
        """Other writers' saves: read into the store, and pushed to the page."""
        while not self._closing.wait(interval):
            try:
                with self._lock:
                    changed = self._session.poll()
                    if changed:
                        self._reload()
            except (Px4ParamsError, OSError) as e:  # said once per version of the file
                self._status(f"store changed by another writer, not read: {e}")
                continue
            if changed:
                self._notify({"kind": "values", "values": self.state()["values"]})

    @property
    def store(self) -> Any:
        return self._session.store

    def _reload(self) -> None:
        from px4params.store.flat import flat_values

        self.values = flat_values(self.store)

    def write(self, name: str, value: int | float, was: int | None = None) -> WriteResult:
        """Writes ``name`` into the store file (its latest version, under its lock); ``was``:
        an instance mask's value the page made ``value`` from (only the bits changed are
        written: another writer's instances stay)."""
        from px4params.store.flat import write_flat

        with self._lock:
            try:
                self._session.commit(lambda: write_flat(self.store, name, value, was=was))
            except (Px4ParamsError, OSError) as e:
                reason = str(e) if str(e).startswith(name) else f"{name}: {e}"
                return WriteResult(name, False, self.values.get(name), reason)
            self._reload()
        self._notify({"kind": "values", "values": self.state()["values"]})
        return WriteResult(name, True, self.values.get(name))

    def close(self) -> None:
        self._closing.set()


# -- a vehicle over MAVLink ------------------------------------------------------------------


def _as_stored(value: int | float, is_float: bool) -> tuple[int | float, ...]:
    """The echoes that acknowledge a write of ``value``. A float goes out as float32;
    ``mavlink serve`` echoes that float32, and a vehicle that echoes the current value as the
    MAVLink parameter protocol words it echoes a float16 leaf as stored (rounded by the
    DroneCAN rule). Any other value echoed is what the vehicle kept."""
    if not is_float:
        return (value,)
    float32 = struct.unpack("<f", struct.pack("<f", value))[0]
    return (float32, float_from_f16(f16_from_float(value)))


#: MAV_TYPE values of components that are no vehicle (common.xml: a flight controller reports the
#: type of the vehicle it is mounted on, every other component its own kind).
_COMPONENT_TYPES = frozenset(
    {
        mavlink.MAV_TYPE_GCS,
        mavlink.MAV_TYPE_ONBOARD_CONTROLLER,
        mavlink.MAV_TYPE_GIMBAL,
        mavlink.MAV_TYPE_ADSB,
        mavlink.MAV_TYPE_CAMERA,
        mavlink.MAV_TYPE_CHARGING_STATION,
        mavlink.MAV_TYPE_FLARM,
        mavlink.MAV_TYPE_SERVO,
        mavlink.MAV_TYPE_ODID,
        mavlink.MAV_TYPE_BATTERY,
        mavlink.MAV_TYPE_PARACHUTE,
        mavlink.MAV_TYPE_LOG,
        mavlink.MAV_TYPE_OSD,
        mavlink.MAV_TYPE_IMU,
        mavlink.MAV_TYPE_GPS,
        mavlink.MAV_TYPE_WINCH,
        mavlink.MAV_TYPE_ILLUMINATOR,
        mavlink.MAV_TYPE_GRIPPER,
    }
)


def _mentions(line: str, name: str) -> bool:
    """Whether ``line`` names the parameter ``name`` as a whole word: ``BAT1_N`` is not named
    by a line about ``BAT1_N_CELLS`` (parameter names are letters, digits and ``_``)."""
    word = r"[A-Za-z0-9_]"
    return re.search(rf"(?<!{word}){re.escape(name)}(?!{word})", line) is not None


#: STATUSTEXT (common.xml): characters a chunk holds; the mark shown where chunks are missing;
#: seconds a text waits for its next chunk (QGC waits 1 s); texts waiting at once, beyond which
#: the oldest is shown as it is (a flood, or a link losing last chunks, holds no more memory).
_CHUNK_CHARS = 50
_MISSING = "[...]"
_CHUNK_WAIT = 1.0
_TEXTS_WAITING = 16
#: Seconds a text may be shown after its wait ends (the receive thread looks every 0.2 s).
_SHOW_LATE = 0.5
#: Texts shown lately whose repeated chunks are still known as repeats (a chunk seen twice
#: within _CHUNK_WAIT of the text's showing is the same chunk again).
_TEXTS_SHOWN = 64


class _ChunkedText:
    """One STATUSTEXT text arriving in chunks: its chunks by ``chunk_seq``, the seq of its last
    chunk once known, and when it stops waiting (a while after its latest new chunk).

    Its last chunk is the one holding a NUL (shorter than 50 characters decoded), or, once it
    waited its while, the highest heard: PX4 (``STATUSTEXT.hpp``) sends a text's chunks at once
    and sends no empty chunk after a full last one, so a text of 50 or 100 characters ends with
    a full chunk, as QGC shows it."""

    def __init__(self) -> None:
        self.parts: dict[int, str] = {}
        self.last: int | None = None
        self.deadline = 0.0

    def add(self, seq: int, text: str, now: float) -> None:
        if seq in self.parts:  # a duplicate: UDP or a router sent it twice
            return
        self.parts[seq] = text
        self.deadline = now + _CHUNK_WAIT
        if len(text) < _CHUNK_CHARS:
            self.last = seq

    def waited(self) -> None:
        """Its while is over: every chunk heard is full (a shorter one is last), the highest
        ends it."""
        if self.last is None:
            self.last = max(self.parts)

    @property
    def whole(self) -> bool:
        return self.last is not None and all(s in self.parts for s in range(self.last + 1))

    def text(self) -> str:
        """The chunks in chunk_seq order, each run of missing ones (and a missing end) marked."""
        end = self.last if self.last is not None else max(self.parts)
        out: list[str] = []
        gap = False
        for seq in range(end + 1):
            part = self.parts.get(seq)
            if part is not None:
                out.append(part)
            elif not gap:
                out.append(_MISSING)
            gap = part is None
        if self.last is None:
            out.append(_MISSING)
        return "".join(out)


#: Seconds between the page's heartbeats (MAVLink's HEARTBEAT: 1 Hz).
_HEARTBEAT_PERIOD = 1.0


class MavlinkVehicle(_Base):
    """A vehicle (``px4params mavlink serve`` or a PX4) over MAVLink on UDP, as a ground station
    talks to it: heartbeats, the parameter list, component metadata over MAVLink FTP (or a
    ``parameters.json`` given), writes with PARAM_SET read back, STATUSTEXT. With
    ``signing_key`` the link is signed (MAVLink 2 signing)."""

    mode = "mavlink"

    def __init__(
        self,
        address: tuple[str, int],
        metadata_file: str | None = None,
        *,
        timeout: float = 10.0,
        signing_key: bytes | None = None,
    ) -> None:
        super().__init__()
        os.environ.setdefault("MAVLINK20", "1")
        from pymavlink import mavutil

        from px4params.links import mavlink_messages

        host, port = address
        self.source = f"udp {host}:{port}"
        self._conn = mavutil.mavlink_connection(
            f"udpout:{host}:{port}", source_system=255, source_component=190, dialect="common"
        )
        self._signed = signing_key is not None
        send_lock = threading.Lock()
        if signing_key is not None:
            from px4params.links.mavlink_signing import Signing

            # MAVLink 2 signing (pymavlink's signing state and checks on the connection): every
            # message signed, and what arrives accepted by PX4's rules; unsigned and wrongly
            # signed messages are dropped. Accepting a frame moves the timestamp sends use:
            # one lock for both
            signing = Signing(signing_key)
            signing.attach(self._conn.mav)
            send_lock = signing.lock
            self.source += " (signed)"
        self._serialize_sends(send_lock)
        self._mav = mavutil.mavlink
        mavlink_messages.register(self._mav)
        self._system = 1
        self._component = 1
        self._stop = threading.Event()
        self._waiters: dict[str, list[Any]] = {}
        #: STATUSTEXT texts waiting for chunks, by sender (system, component) and id, oldest first.
        self._chunks: dict[tuple[int, int, int], _ChunkedText] = {}
        #: Texts shown lately, by the same key: until when a chunk heard again is a repeat,
        #: and their chunks.
        self._shown: dict[tuple[int, int, int], tuple[float, dict[int, str]]] = {}
        #: When the vehicle's texts now waiting for chunks are shown at the latest (0: none
        #: waits); a refused write waits for them, its reason may be one.
        self._texts_due = 0.0
        #: Each write's list of what the vehicle says while it waits (its reason, if refused).
        self._hearing: list[list[str]] = []
        self._count = 0
        self._heartbeats = threading.Thread(target=self._beat, name="gui-heartbeat", daemon=True)
        self._heartbeats.start()
        try:
            self._connect(timeout)
            self.metadata = self._load_metadata(metadata_file, timeout)
        except BaseException:  # no vehicle, or no metadata: the page says nothing more
            self._stop.set()
            self._heartbeats.join(timeout=2)
            self._conn.close()
            raise
        self._thread = threading.Thread(target=self._receive, name="gui-mavlink", daemon=True)
        self._thread.start()
        self.refresh(timeout)

    # -- connection ------------------------------------------------------------------------

    def _serialize_sends(self, lock: threading.Lock) -> None:
        """One frame at a time on the connection, under ``lock``. The heartbeat thread, writes
        and pymavlink's FTP download all send on it, and pymavlink numbers and signs a frame
        before writing it without a lock: a signed vehicle drops a frame whose timestamp is not
        above the last one it took (a replay), so a frame signed first must also be written
        first."""
        mav = self._conn.mav
        send = mav.send

        def send_one(message: Any, force_mavlink1: bool = False) -> None:
            with lock:
                send(message, force_mavlink1=force_mavlink1)

        mav.send = send_one  # every *_send method and mavftp go through MAVLink.send

    def _send_heartbeat(self) -> None:
        mav = self._mav
        self._conn.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)

    def _connect(self, timeout: float) -> None:
        """The vehicle's heartbeat waited for (the page's own go out at their rate meanwhile:
        a heartbeat for each heard would be hundreds a second on a busy link)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            msg = self._conn.recv_match(type="HEARTBEAT", blocking=True, timeout=0.5)
            if msg is not None and self._is_vehicle(msg):
                self._system = msg.get_srcSystem()
                return
        hint = (
            "" if self._signed else " (a signed link drops unsigned messages: --signing-key FILE)"
        )
        raise CommandError(f"no vehicle answered on {self.source} within {timeout:.0f} s{hint}")

    def _is_vehicle(self, heartbeat: Any) -> bool:
        """A vehicle's autopilot, as common.xml's HEARTBEAT tells it: a component that is no
        flight controller sends MAV_AUTOPILOT_INVALID, and a flight controller the type of its
        vehicle (a GCS, companion computer or camera its own); MAV_COMP_ID_AUTOPILOT1 (1)."""
        return (
            heartbeat.get_srcComponent() == self._component
            and heartbeat.autopilot != self._mav.MAV_AUTOPILOT_INVALID
            and heartbeat.type not in _COMPONENT_TYPES
        )

    def _load_metadata(self, metadata_file: str | None, timeout: float) -> dict[str, Any]:
        if metadata_file is not None:
            try:
                return dict(json.loads(read_text(metadata_file, METADATA_JSON)))
            except (OSError, ValueError) as e:
                raise CommandError(f"{metadata_file}: cannot read the metadata: {e}") from None
        document = self._fetch_metadata(timeout)
        if document is None:
            raise CommandError(
                f"the vehicle on {self.source} serves no parameter metadata over MAVLink FTP; "
                "give --metadata parameters.json"
            )
        return document

    def _fetch_metadata(self, timeout: float) -> dict[str, Any] | None:
        """COMPONENT_METADATA, then the general file and parameters.json(.xz) over MAVLink FTP,
        as QGC fetches them."""
        from pymavlink import mavftp

        mav = self._mav
        uri = None
        for message_id, kind in ((397, "COMPONENT_METADATA"), (395, "COMPONENT_INFORMATION")):
            self._conn.mav.command_long_send(
                self._system,
                self._component,
                mav.MAV_CMD_REQUEST_MESSAGE,
                0,
                message_id,
                0,
                0,
                0,
                0,
                0,
                0,
            )
            end = time.monotonic() + min(timeout, 3.0)
            while time.monotonic() < end and uri is None:
                msg = self._conn.recv_match(type=[kind, "COMMAND_ACK"], blocking=True, timeout=0.5)
                if msg is None:
                    continue
                if msg.get_type() == kind:
                    uri = msg.uri if message_id == 397 else msg.general_metadata_uri
                elif msg.command == mav.MAV_CMD_REQUEST_MESSAGE and msg.result != 0:
                    break
            if uri:
                break
        if not uri or not uri.startswith("mftp://"):
            return None
        ftp = mavftp.MAVFTP(self._conn, self._system, self._component)
        with _quiet_logging():  # pymavlink's mavftp warns about reads shorter than asked
            return self._download(ftp, uri)

    def _download(self, ftp: Any, uri: str) -> dict[str, Any] | None:
        general = ftp.read(_mftp_path(uri), 1 << 20)
        if not general:
            return None
        entries = json.loads(general).get("metadataTypes", [])
        parameters = next((e for e in entries if e.get("type") == 1), None)
        if parameters is None or not str(parameters.get("uri", "")).startswith("mftp://"):
            return None
        data = ftp.read(_mftp_path(parameters["uri"]), 1 << 26)
        if not data:
            return None
        if parameters["uri"].endswith((".xz", ".lzma")):
            data = lzma.decompress(data)
        return dict(json.loads(data))

    def _beat(self) -> None:
        """The page's heartbeat, one at once and then one a second (MAVLink's rate for every
        component, a ground station's too), from construction to close()."""
        while True:
            with contextlib.suppress(OSError):
                self._send_heartbeat()
            if self._stop.wait(_HEARTBEAT_PERIOD):
                return

    def _receive(self) -> None:
        while not self._stop.is_set():
            self._show_overdue()  # at least every 0.2 s: the wait for a message below
            try:
                msg = self._conn.recv_match(blocking=True, timeout=0.2)
            except (OSError, ValueError):
                continue
            if msg is None:
                continue
            kind = msg.get_type()
            # Every component answers PARAM_REQUEST_LIST with its own parameters (a camera's,
            # a gimbal's): only the vehicle's are the vehicle's
            from_vehicle = (msg.get_srcSystem(), msg.get_srcComponent()) == (
                self._system,
                self._component,
            )
            if kind == "PARAM_VALUE" and from_vehicle:
                self._param_value(msg)
            elif kind == "STATUSTEXT":
                self._statustext(msg)
            elif kind == "PARAM_ERROR" and from_vehicle:
                with self._lock:
                    for waiter in self._waiters.get(msg.param_id, []):
                        waiter.append(("error", msg))

    def _statustext(self, msg: Any) -> None:
        """STATUSTEXT, its 50-character chunks joined by ``chunk_seq`` (MAVLink 2: id 0 is a
        text in one chunk). An id is its sender's: two senders' texts of the same id are two
        texts. A text is shown once whole (every chunk up to its last, see
        :class:`_ChunkedText`), when another text of its id starts (chunk_seq 0 again, another
        text: the id wrapped), when it waited ``_CHUNK_WAIT`` for a chunk, or when it is the
        oldest of too many waiting; missing chunks are marked, never glued over (as QGC does).
        A chunk heard again (UDP, a router) is dropped, also shortly after its text was
        shown."""
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        text_id = getattr(msg, "id", 0)
        if not text_id:
            self._said(sender, msg.text, whole=True)
            return
        key = (*sender, text_id)
        seq = getattr(msg, "chunk_seq", 0)
        now = time.monotonic()
        waiting = self._chunks.get(key)
        shown = self._shown.get(key) if waiting is None else None
        if shown is not None and shown[0] > now and shown[1].get(seq) == msg.text:
            return
        if waiting is not None and seq == 0 and waiting.parts.get(0, msg.text) != msg.text:
            self._show_chunked(key)
            waiting = None
        if waiting is None:
            if len(self._chunks) >= _TEXTS_WAITING:
                self._show_chunked(next(iter(self._chunks)))
            waiting = self._chunks[key] = _ChunkedText()
        waiting.add(seq, msg.text, now)
        if waiting.whole:
            self._show_chunked(key)
        self._due()

    def _show_chunked(self, key: tuple[int, int, int], *, waited: bool = False) -> None:
        waiting = self._chunks.pop(key)
        if waited:
            waiting.waited()
        self._shown.pop(key, None)
        self._shown[key] = (time.monotonic() + _CHUNK_WAIT, waiting.parts)
        while len(self._shown) > _TEXTS_SHOWN:
            del self._shown[next(iter(self._shown))]
        self._said((key[0], key[1]), waiting.text(), whole=waiting.whole)

    def _show_overdue(self) -> None:
        """The texts that waited too long for a chunk, as they are."""
        now = time.monotonic()
        overdue = [k for k, waiting in self._chunks.items() if waiting.deadline <= now]
        for key in overdue:
            self._show_chunked(key, waited=True)
        if overdue:
            self._due()

    def _due(self) -> None:
        """When the vehicle's texts waiting for chunks are shown at the latest."""
        vehicle = (self._system, self._component)
        self._texts_due = max(
            (w.deadline for k, w in self._chunks.items() if k[:2] == vehicle), default=0.0
        )

    def _said(self, sender: tuple[int, int], text: str, *, whole: bool) -> None:
        if sender == (self._system, self._component):  # a camera's text is no write's reason
            with self._lock:
                for said in self._hearing:
                    said.append(text)
        self._status(text, whole)

    def _param_value(self, msg: Any) -> None:
        name = msg.param_id
        if name == "_HASH_CHECK":
            return
        value = param_value_of(msg)
        with self._lock:
            self._count = msg.param_count
            self.values[name] = value
            for waiter in self._waiters.get(name, []):
                waiter.append(("value", value))
        self._notify({"kind": "value", "name": name, "value": _json_number(value)})

    # -- parameters --------------------------------------------------------------------------

    def refresh(self, timeout: float = 10.0) -> None:
        """The whole list again: PARAM_REQUEST_LIST, sent again after half a second without a
        new value (UDP lost the request, or values of the list) until every value is in."""
        with self._lock:
            self.values.clear()
            self._count = 0
        self._conn.mav.param_request_list_send(self._system, self._component)
        end = time.monotonic() + timeout
        quiet = time.monotonic()
        seen = 0
        while time.monotonic() < end:
            time.sleep(0.1)
            with self._lock:
                have, count = len(self.values), self._count
            if count and have >= count:
                break
            if have != seen:
                seen, quiet = have, time.monotonic()
            # no value yet counts too: the request itself was lost
            elif time.monotonic() - quiet > 0.5:
                self._conn.mav.param_request_list_send(self._system, self._component)
                quiet = time.monotonic()
        self._notify({"kind": "values", "values": self.state()["values"]})

    @contextlib.contextmanager
    def _waiting(self, name: str) -> Iterator[list[Any]]:
        """A list that gathers what the vehicle answers about ``name`` (its PARAM_VALUE and
        PARAM_ERROR) while the block runs. Writes run in threads: several lists may wait on
        one name, equal while they hold the same answers, so each is forgotten by identity."""
        answers: list[Any] = []
        with self._lock:
            self._waiters.setdefault(name, []).append(answers)
        try:
            yield answers
        finally:
            with self._lock:
                self._waiters[name] = [w for w in self._waiters[name] if w is not answers]

    def write(
        self, name: str, value: int | float, was: int | None = None, timeout: float = 1.5
    ) -> WriteResult:
        """PARAM_SET (PX4's bytewise int32 encoding), then the vehicle's answer: acknowledged
        when the echo carries the value sent (a float as float32, or as the float16 a narrower
        leaf stores), refused with PARAM_ERROR and STATUSTEXT's reason (or when it echoes
        another value), and read back. ``was``: an instance mask's value the page made
        ``value`` from: the bits it changes go onto the mask as last heard from the vehicle."""
        from px4params.store.flat import merged_mask

        refusal = param_name_refusal(name)
        if refusal is not None:  # the message would carry another name, cut short
            return WriteResult(name, False, None, refusal)
        now = self.values.get(name)
        if was is not None and type(value) is int and type(now) is int and name.endswith("_INST"):
            value = merged_mask(now, was, value)
        mav = self._mav
        is_float = isinstance(value, float)
        kind = mav.MAV_PARAM_TYPE_REAL32 if is_float else mav.MAV_PARAM_TYPE_INT32
        said: list[str] = []  # the vehicle's STATUSTEXT (self.messages keeps only the last 200)
        with self._lock:
            self._hearing.append(said)
        try:
            with self._waiting(name) as answers:
                for _attempt in range(3):
                    message = param_set_message(self._system, self._component, name, value, kind)
                    self._conn.mav.send(message)
                    end = time.monotonic() + timeout
                    while time.monotonic() < end and not answers:
                        time.sleep(0.02)
                    if answers:
                        break
                time.sleep(0.1)  # a PARAM_ERROR and STATUSTEXT follow a refusal's PARAM_VALUE
            errors = [a for a in answers if a[0] == "error"]
            values = [a[1] for a in answers if a[0] == "value"]
            echoed = values[0] if values else None
            refused = bool(errors) or echoed not in _as_stored(value, is_float)
            if answers and refused:
                self._await_reason(name, said)
        finally:
            with self._lock:
                self._hearing = [h for h in self._hearing if h is not said]
        if not answers:
            return WriteResult(
                name, False, self.values.get(name), f"{name}: no answer from the vehicle"
            )
        if refused:
            reasons = [m for m in said if _mentions(m, name)]
            reason = reasons[0] if reasons else f"{name}: the vehicle kept {echoed}"
            return WriteResult(name, False, echoed, reason)
        read = self.read(name)
        return WriteResult(name, True, read if read is not None else echoed)

    def _await_reason(self, name: str, said: list[str]) -> None:
        """A refusal's reason may be a text still waiting for chunks: one of 50 or 100
        characters from PX4 ends with a full chunk and is shown only after its wait. Until
        the vehicle's waiting texts are shown (or a line names ``name``)."""
        while not any(_mentions(m, name) for m in said):
            due = self._texts_due
            if not due or time.monotonic() > due + _SHOW_LATE:
                return
            time.sleep(0.02)

    def read(self, name: str, timeout: float = 1.0) -> int | float | None:
        with self._waiting(name) as answers:
            self._conn.mav.param_request_read_send(self._system, self._component, name.encode(), -1)
            end = time.monotonic() + timeout
            while time.monotonic() < end and not answers:
                time.sleep(0.02)
        values = [a[1] for a in answers if a[0] == "value"]
        return values[0] if values else None

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self._heartbeats.join(timeout=2)
        self._conn.close()


@contextlib.contextmanager
def _quiet_logging() -> Any:
    logging.disable(logging.WARNING)
    try:
        yield
    finally:
        logging.disable(logging.NOTSET)


def _mftp_path(uri: str) -> str:
    """The path of an ``mftp://`` URI (``[;comp=N]`` dropped), as QGC reads it."""
    rest = uri[len("mftp://") :]
    if rest.startswith("[;comp="):
        rest = rest.split("]", 1)[1]
    return "/" + rest.lstrip("/")
