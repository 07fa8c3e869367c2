"""The page's vehicle over a store file (``px4params.gui.vehicle``), in-process: health lines as
the commander and ``mavlink serve --bench`` write them (``health: DRIVER INSTANCE on WHERE:
STATE: REASON``), the state the page reads (JSON has no NaN or infinity: they travel as text),
the events its WebSocket pushes, and writes through the store's one write path."""

from __future__ import annotations

import contextlib
import errno
import hashlib
import itertools
import json
import lzma
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import px4params
import pytest
from px4params.errors import CommandError
from px4params.gui.vehicle import (
    MavlinkVehicle,
    StoreVehicle,
    WriteResult,
    _as_stored,
    _ChunkedText,
    _mftp_path,
    parse_health,
)
from px4params.links.mavlink import MavlinkParamServer, param_set_message, param_value_of
from px4params.links.mavlink_signing import Signing
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.store.session import Session
from pymavlink.dialects.v20 import common as mavlink2


@pytest.fixture
def vehicle(store_file: Path) -> Iterator[StoreVehicle]:
    made = StoreVehicle(str(store_file), None, [], poll_interval=0.05)
    yield made
    made.close()


def _within(seconds: float, call: Any) -> Any:
    """``call()``'s answer, in a thread of its own: a call that never returns fails the test
    after ``seconds`` (a generous bound) instead of hanging it."""
    answers: list[Any] = []
    running = threading.Thread(target=lambda: answers.append(call()), daemon=True)
    running.start()
    running.join(seconds)
    assert not running.is_alive(), f"still waiting after {seconds} s"
    return answers[0]


def wait_for(condition: Any, seconds: float = 10.0) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.02)
    return False


# -- a vehicle over MAVLink (issue 40: the page's MAVLink client, in-process) -------------------
# The peer is px4params' MAVLink server in a thread on 127.0.0.1 (its frames are pymavlink's,
# checked against QGC's and MAVProxy's readings in test_mavlink_clients.py), as system 7 so that
# a write reaches it only when sent to the system its heartbeat named. Subclasses change one
# answer each: silence, another value echoed, no COMPONENT_METADATA.

#: A health report 100 characters long: two STATUSTEXT chunks of 50 and an empty third, the end
#: (MAVLink 2: a chunk shorter than 50 characters ends the text).
LONG_HEALTH = "health: ina238 INA238#1 on I2C bus 2 address 0x45: critical: not found: " + "x" * 28
SHORT_HEALTH = "health: ms5611 MS5611#0: nominal"  # one STATUSTEXT, id 0


def _served_store(schema: px4params.Schema) -> px4params.Store:
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    store.set("INA238#1.bus.i2c.address", 0x45)
    return store


class _Recording(MavlinkParamServer):
    """The server, noting what the page sent: its heartbeats' fields and source, the names of
    its PARAM_SETs, its PARAM_REQUEST_READs' indexes, its COMMAND_LONGs, its list requests."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.heartbeats: set[tuple[int, ...]] = set()
        self.heartbeat_count = 0
        self.sets: list[str] = []
        self.read_indexes: set[int] = set()
        self.commands: list[tuple[float, ...]] = []
        self.lists = 0

    def _handle(self, peer: Any, msg: Any) -> bool:
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            source = (msg.get_srcSystem(), msg.get_srcComponent())
            fields = (msg.type, msg.autopilot, msg.base_mode, msg.custom_mode, msg.system_status)
            self.heartbeats.add((*source, *fields))
            self.heartbeat_count += 1
        elif kind == "PARAM_SET":
            self.sets.append(_name(msg.param_id))
        elif kind == "PARAM_REQUEST_READ":
            self.read_indexes.add(msg.param_index)
        elif kind == "PARAM_REQUEST_LIST":
            self.lists += 1
        elif kind == "COMMAND_LONG":
            params = [getattr(msg, f"param{n}") for n in range(1, 8)]
            self.commands.append((msg.command, msg.confirmation, *params))
        return super()._handle(peer, msg)


def _name(param_id: Any) -> str:
    raw = param_id if isinstance(param_id, bytes) else str(param_id).encode()
    return raw.split(b"\0", 1)[0].decode()


@contextlib.contextmanager
def _peer(
    schema: px4params.Schema, server: type[_Recording] = _Recording, **options: Any
) -> Iterator[_Recording]:
    options = {"system_id": 7, "heartbeat_interval": 0.1, **options}
    served = server(_served_store(schema), "127.0.0.1", 0, **options)
    served.start()
    try:
        yield served
    finally:
        served.stop()


@contextlib.contextmanager
def _page(address: tuple[str, int], **options: Any) -> Iterator[MavlinkVehicle]:
    page = MavlinkVehicle(address, **{"timeout": 10.0, **options})
    try:
        yield page
    finally:
        page.close()


@pytest.mark.issue40
def test_a_mavlink_vehicle_is_listed_written_read_and_heard(schema: px4params.Schema) -> None:
    health = [LONG_HEALTH, SHORT_HEALTH]
    with _peer(schema, health=lambda: health, health_interval=0.2) as served:
        started = time.monotonic()
        with _page(served.address, timeout=60.0) as page:
            # the whole list, at once (not at the end of the 60 s given)
            assert time.monotonic() - started < 45
            port = served.address[1]
            assert (page.mode, page.source) == ("mavlink", f"udp 127.0.0.1:{port}")
            assert page.values == {e.name: e.value for e in served.entries()}
            assert "_HASH_CHECK" not in page.values  # PX4's list ends with it: no parameter
            assert page.values["INA238_1C"] == 0x45
            # the metadata over MAVLink FTP (the general file, then parameters.json.xz)
            assert page.metadata["version"] == 1
            described = {p["name"] for p in page.metadata["parameters"]}
            assert {"INA238_1C", "INA238_1Q", "BAT1_CAPACITY", "SYS_AUTOSTART"} <= described
            events: list[dict[str, Any]] = []
            page.listen(events.append)

            # a ground station's heartbeat (MAVLink common.xml: MAV_TYPE_GCS 6, autopilot
            # MAV_AUTOPILOT_INVALID 8; QGC's system 255, MAV_COMP_ID_MISSIONPLANNER 190)
            assert served.heartbeats == {(255, 190, 6, 8, 0, 0, 0)}
            # one while waiting for the vehicle's (each wait up to 0.5 s), then one a second
            assert served.heartbeat_count < 4 + 2 * (time.monotonic() - started)
            # MAV_CMD_REQUEST_MESSAGE (512) for COMPONENT_METADATA (397), first transmission
            # (confirmation 0), every other parameter 0 (the default; param7 0: to the sender)
            assert served.commands == [(512, 0, 397, 0, 0, 0, 0, 0, 0)]

            accepted = page.write("INA238_1C", 70)  # sent to system 7, or nobody answers
            assert (accepted.ok, accepted.value, accepted.reason) == (True, 70, "")
            assert served.sets == ["INA238_1C"]  # acknowledged: sent once
            assert served.store.get("INA238#1.bus.i2c.address") == 70
            assert {"kind": "value", "name": "INA238_1C", "value": 70} in events
            assert page.read("INA238_1C") == 70
            assert served.read_indexes == {-1}  # -1: read by param_id (MAVLink's rule)

            # refused: PARAM_VALUE with the value kept, STATUSTEXT's reason in chunks, PARAM_ERROR
            refused = page.write("INA238_1C", 200)
            assert (refused.ok, refused.value) == (False, 70)
            assert refused.reason == (
                "INA238_1C: INA238#1: bus.i2c.address: value 200 is out of range (expected 0 to "
                "127)"
            )  # a 7-bit I2C address
            assert page.values["INA238_1C"] == 70
            again = page.write("INA238_1C", 300)  # this write's reason, not the last one's
            assert again.reason == refused.reason.replace("200", "300")
            assert page._hearing == []  # a finished write no longer gathers the vehicle's texts
            unknown = page.write("NOPE_1X", 1)
            assert (unknown.ok, unknown.value, unknown.reason) == (
                False,
                None,
                "[pm] unknown param: NOPE_1X",  # PX4's words
            )
            assert page.read("NOPE_1X", timeout=0.3) is None

            floats = page.write("BAT1_CAPACITY", 5000.5)
            assert (floats.ok, floats.value) == (True, 5000.5)
            assert served.store.get("BAT1_CAPACITY") == 5000.5

            # health reports, each joined from its chunks
            assert wait_for(lambda: {"INA238#1", "MS5611#0"} <= set(page.health))
            assert page.health["INA238#1"] == parse_health(LONG_HEALTH)
            assert page.health["INA238#1"]["reason"] == "not found: " + "x" * 28
            assert page.health["MS5611#0"]["state"] == "nominal"
            assert LONG_HEALTH in page.messages and SHORT_HEALTH in page.messages
            assert LONG_HEALTH[:50] not in page.messages  # no chunk said on its own

            events.clear()
            page.refresh(10.0)
            listed = [e for e in events if e["kind"] == "values"]
            assert listed == [{"kind": "values", "values": page.state()["values"]}]
            assert listed[0]["values"]["INA238_1C"] == 70
        assert not page._thread.is_alive() and not page._heartbeats.is_alive()


class _Silent(_Recording):
    """Never answers a PARAM_SET of INA238_1P (a lost link, in one direction)."""

    def _set(self, peer: Any, name: str, msg: Any) -> None:
        if name != "INA238_1P":
            super()._set(peer, name, msg)


class _Stubborn(_Recording):
    """Answers a PARAM_SET of INA238_1P with the value it had, and no reason."""

    def _set(self, peer: Any, name: str, msg: Any) -> None:
        found = self._find(name)
        if name == "INA238_1P" and found is not None:
            self._send(self._value_msg(*found), [peer])
            return
        super()._set(peer, name, msg)


def test_a_mask_write_goes_onto_the_mask_last_heard(schema: px4params.Schema) -> None:
    # Two pages' additions made from one mask: the second one's bits go onto the mask as the
    # vehicle echoed it after the first, not onto the mask both started from.
    with _peer(schema) as served, _page(served.address) as page:
        was = page.values["INA238_INST"]
        assert was == 0b10  # INA238#1
        first = page.write("INA238_INST", was | 0b001, was)
        assert (first.ok, first.value) == (True, 0b011)
        second = page.write("INA238_INST", was | 0b100, was)
        assert (second.ok, second.value) == (True, 0b111)
        assert served.sets == ["INA238_INST", "INA238_INST"]


@pytest.mark.parametrize("name", ["SENS_EXT_I2C_PRBXYZ", "SENS_EXT_I2C_PRB\u00e9", ""])
def test_a_name_param_id_cannot_carry_is_refused_before_it_is_sent(
    schema: px4params.Schema, name: str
) -> None:
    # pymavlink cut SENS_EXT_I2C_PRBXYZ to 16 characters: the vehicle set and saved
    # SENS_EXT_I2C_PRB (three times) while the page said "no answer" (helper-111).
    with _peer(schema) as served, _page(served.address) as page:
        before = dict(page.values)
        result = page.write(name, 0, timeout=0.3)
        assert (result.ok, result.value, result.reason) == (
            False,
            None,
            f"{name}: a MAVLink parameter name is 1 to 16 ASCII characters ({len(name)} given)",
        )
        assert served.sets == [] and page.values == before
    with pytest.raises(ValueError, match="SENS_EXT_I2C_PRBXYZ: a MAVLink parameter name is 1 to"):
        param_set_message(1, 1, "SENS_EXT_I2C_PRBXYZ", 0, 6)


@pytest.mark.issue40
def test_a_write_nobody_answers_is_sent_three_times_then_refused(
    schema: px4params.Schema,
) -> None:
    with _peer(schema, _Silent) as served, _page(served.address) as page:
        before = page.values["INA238_1P"]
        result = _within(30, lambda: page.write("INA238_1P", before + 1, timeout=0.3))
        assert (result.ok, result.value, result.reason) == (
            False,
            before,
            "INA238_1P: no answer from the vehicle",
        )
        assert served.sets == ["INA238_1P"] * 3  # sent, then twice again
        assert page._waiters["INA238_1P"] == []  # nothing left waiting


@pytest.mark.issue40
def test_a_write_echoed_with_another_value_is_refused_with_that_value(
    schema: px4params.Schema,
) -> None:
    with _peer(schema, _Stubborn) as served, _page(served.address) as page:
        before = page.values["INA238_1P"]
        assert isinstance(before, int)
        result = page.write("INA238_1P", before + 1)
        assert (result.ok, result.value, result.reason) == (
            False,
            before,
            f"INA238_1P: the vehicle kept {before}",
        )


class _InformationOnly(_Recording):
    """An older vehicle: COMPONENT_INFORMATION (395) only, COMPONENT_METADATA (397) unsupported."""

    def _requested(self, message_id: int) -> Any:
        return None if message_id == 397 else super()._requested(message_id)


class _NoMetadata(_Recording):
    """A vehicle that serves neither message."""

    def _requested(self, message_id: int) -> Any:
        return None if message_id in (395, 397) else super()._requested(message_id)


@pytest.mark.issue40
def test_the_metadata_falls_back_to_component_information(schema: px4params.Schema) -> None:
    with _peer(schema, _InformationOnly) as served, _page(served.address) as page:
        assert "INA238_1C" in {p["name"] for p in page.metadata["parameters"]}


@pytest.mark.issue40
def test_a_vehicle_without_metadata_asks_for_the_file(schema: px4params.Schema) -> None:
    with _peer(schema, _NoMetadata) as served, pytest.raises(CommandError) as refused:
        port = served.address[1]
        MavlinkVehicle(served.address, timeout=10.0)
    assert str(refused.value) == (
        f"the vehicle on udp 127.0.0.1:{port} serves no parameter metadata over "
        "MAVLink FTP; give --metadata parameters.json"
    )


@pytest.mark.issue40
def test_a_metadata_file_given_is_the_metadata(schema: px4params.Schema, tmp_path: Path) -> None:
    document = {"version": 1, "parameters": [{"name": "INA238_1C", "type": "Int32"}]}
    given = tmp_path / "parameters.json"
    given.write_text(json.dumps(document))
    with _peer(schema, _NoMetadata) as served:
        with _page(served.address, metadata_file=str(given)) as page:
            assert page.metadata == document
        for bad, why in ((tmp_path / "none.json", "No such file"), (tmp_path / "x.json", "")):
            if why == "":
                bad.write_text("{not json")
            with pytest.raises(CommandError) as refused:
                MavlinkVehicle(served.address, str(bad), timeout=10.0)
            assert str(refused.value).startswith(f"{bad}: cannot read the metadata: ")
            assert why in str(refused.value) and "\n" not in str(refused.value)


@pytest.mark.issue40
def test_only_the_autopilot_component_s_heartbeat_is_the_vehicle(
    schema: px4params.Schema,
) -> None:
    """MAV_COMP_ID_AUTOPILOT1 is component 1: a camera's or gimbal's heartbeat is no vehicle."""
    with _peer(schema, component_id=100) as served, pytest.raises(CommandError) as refused:
        port = served.address[1]
        MavlinkVehicle(served.address, timeout=1.0)
    assert str(refused.value) == (
        f"no vehicle answered on udp 127.0.0.1:{port} within 1 s (a signed link "
        "drops unsigned messages: --signing-key FILE)"
    )


@pytest.mark.issue40
def test_a_write_is_acknowledged_by_the_float32_sent_or_the_float16_stored() -> None:
    """PARAM_SET carries a float as float32; a float16 leaf stores it rounded (0.0005 is
    1049 * 2**-21 in float16: 10 bits of mantissa); an integer is acknowledged by itself."""
    assert _as_stored(70, False) == (70,)
    float32, float16 = _as_stored(0.0005, True)
    assert float32 == 0.0005000000237487257  # 0x3A03126F
    assert float16 == 1049 * 2**-21
    assert _as_stored(0.5, True) == (0.5, 0.5)


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("uri", "path"),
    [
        ("mftp://[;comp=1]/etc/comp_general.json", "/etc/comp_general.json"),
        ("mftp://[;comp=1]etc/x.json.xz", "/etc/x.json.xz"),
        ("mftp:///fs/microsd/params.json", "/fs/microsd/params.json"),
        ("mftp://params.json", "/params.json"),
        ("mftp://[;comp=1]/fs/a]b.json", "/fs/a]b.json"),  # only the first ] ends the prefix
        ("mftp:///XYZ/params.json", "/XYZ/params.json"),  # only slashes go before the path
    ],
)
def test_an_mftp_uri_is_read_as_its_path(uri: str, path: str) -> None:
    """The component-information URI scheme (mavlink.io's MAVLink FTP URL): ``mftp://``, an
    optional ``[;comp=N]``, then the path on the vehicle."""
    assert _mftp_path(uri) == path


# -- health lines ------------------------------------------------------------------------------


def test_a_health_line_names_driver_instance_location_state_and_reason() -> None:
    line = "health: ina238 INA238#1 on I2C bus 2 address 0x45: critical: not found: no ACK"
    assert parse_health(line) == {
        "driver": "ina238",
        "instance": "INA238#1",
        "location": "I2C bus 2 address 0x45",
        "state": "critical",
        "reason": "not found: no ACK",
    }
    assert parse_health("health: ina238 INA238#0: nominal") == {
        "driver": "ina238",
        "instance": "INA238#0",
        "location": "",
        "state": "nominal",
        "reason": "",
    }
    assert parse_health("health: ms5611 MS5611#0 SPI 1: warning: slow")["location"] == "SPI 1"


@pytest.mark.parametrize(
    "line",
    [
        "ina238 INA238#1: critical: not found",  # no prefix
        "Health: ina238 INA238#1: critical: x",
        "health: ina238: critical: not found",  # no instance
        "health: ina238 INA238#1: broken: what",  # not a state
        "health: ina238 INA238#1 critical",
    ],
)
def test_other_lines_are_no_health_report(line: str) -> None:
    assert parse_health(line) is None


# -- state and events --------------------------------------------------------------------------


def test_status_lines_are_kept_200_shown_50_and_health_by_instance(vehicle: StoreVehicle) -> None:
    events: list[dict[str, Any]] = []
    stop = vehicle.listen(events.append)
    vehicle._status("health: ina238 INA238#1 on I2C bus 2: warning: slow")
    vehicle._status("health: ina238 INA238#1 on I2C bus 2: critical: gone")
    for n in range(250):
        vehicle._status(f"line {n}")
    stop()
    vehicle._status("after the listener left")
    assert len(vehicle.messages) == 200 and vehicle.messages[0] == "line 51"  # 253 said
    state = vehicle.state()
    assert state["messages"] == vehicle.messages[-50:]
    assert [(h["instance"], h["state"]) for h in state["health"]] == [("INA238#1", "critical")]
    assert len(events) == 252
    assert events[1] == {
        "kind": "status",
        "text": "health: ina238 INA238#1 on I2C bus 2: critical: gone",
        "health": parse_health("health: ina238 INA238#1 on I2C bus 2: critical: gone"),
    }
    assert events[2] == {"kind": "status", "text": "line 0", "health": None}


def test_the_state_names_the_store_and_carries_no_nan_or_infinity(
    vehicle: StoreVehicle, store_file: Path
) -> None:
    vehicle.values["X_NAN"] = float("nan")
    vehicle.values["X_INF"] = float("inf")
    vehicle.values["X_NINF"] = float("-inf")
    state = vehicle.state()
    assert (state["mode"], state["source"]) == ("store", str(store_file))
    values = state["values"]
    assert (values["X_NAN"], values["X_INF"], values["X_NINF"]) == ("nan", "inf", "-inf")
    assert values["INA238_1C"] == 0x45 and isinstance(values["INA238_1C"], int)


def test_a_write_result_as_the_page_reads_it() -> None:
    assert WriteResult("A", True, 1.5).as_dict() == {
        "name": "A",
        "ok": True,
        "value": 1.5,
        "reason": "",
    }
    assert WriteResult("B", False, float("nan"), "why").as_dict() == {
        "name": "B",
        "ok": False,
        "value": "nan",
        "reason": "why",
    }


# -- writes ------------------------------------------------------------------------------------


def test_a_write_is_saved_and_pushed_with_every_value(
    vehicle: StoreVehicle, store_file: Path, schema: px4params.Schema
) -> None:
    events: list[dict[str, Any]] = []
    vehicle.listen(events.append)
    result = vehicle.write("INA238_1C", 0x46)
    assert (result.ok, result.value, result.reason) == (True, 0x46, "")
    assert events == [{"kind": "values", "values": vehicle.state()["values"]}]
    assert events[0]["values"]["INA238_1C"] == 0x46
    saved = px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC)
    assert saved.get("INA238#1.bus.i2c.address") == 0x46


def test_a_refused_write_keeps_the_value_and_names_the_parameter(
    vehicle: StoreVehicle, store_file: Path
) -> None:
    events: list[dict[str, Any]] = []
    vehicle.listen(events.append)
    before = store_file.read_bytes()
    result = vehicle.write("INA238_1C", 200)
    assert (result.ok, result.value) == (False, 0x45)
    assert result.reason.startswith("INA238_1C: ") and "out of range" in result.reason
    unknown = vehicle.write("NOPE_1X", 1)
    assert (unknown.ok, unknown.value) == (False, None)
    assert unknown.reason.startswith("NOPE_1X")
    assert events == [] and store_file.read_bytes() == before


def test_another_writer_s_save_is_read_and_pushed(
    vehicle: StoreVehicle, store_file: Path, schema: px4params.Schema
) -> None:
    events: list[dict[str, Any]] = []
    vehicle.listen(events.append)
    other = Session(
        px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC), str(store_file)
    )
    other.commit(lambda: other.store.set("INA238#1.bus.i2c.address", 0x47))
    assert wait_for(lambda: vehicle.values.get("INA238_1C") == 0x47)
    assert wait_for(lambda: any(e["kind"] == "values" for e in events))
    pushed = next(e for e in events if e["kind"] == "values")
    assert pushed["values"]["INA238_1C"] == 0x47


def test_an_unreadable_save_of_another_writer_is_said_once(
    vehicle: StoreVehicle, store_file: Path
) -> None:
    events: list[dict[str, Any]] = []
    vehicle.listen(events.append)
    store_file.write_bytes(b"not a store")
    assert wait_for(lambda: bool(vehicle.messages))
    time.sleep(0.3)  # several more polls of the same bad file
    said = [m for m in vehicle.messages if m.startswith("store changed by another writer")]
    assert len(said) == 1 and said[0].startswith("store changed by another writer, not read: ")
    assert vehicle.values["INA238_1C"] == 0x45  # the values stay
    assert [e["kind"] for e in events] == ["status"]


# -- the store vehicle's remainder (issue 40) ----------------------------------------------------


@pytest.mark.issue40
def test_a_refused_write_names_the_parameter_then_the_leaf(vehicle: StoreVehicle) -> None:
    """The store's error names the instance and leaf; the page is told which parameter too."""
    result = vehicle.write("INA238_1C", 200)
    assert result.reason == (
        "INA238_1C: INA238#1: bus.i2c.address: value 200 is out of range (expected 0 to 127)"
    )  # a 7-bit I2C address


@pytest.mark.issue40
def test_after_an_unreadable_save_the_next_good_one_is_still_read(
    vehicle: StoreVehicle, store_file: Path, schema: px4params.Schema
) -> None:
    store = px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC)
    store_file.write_bytes(b"not a store")
    assert wait_for(lambda: bool(vehicle.messages))
    store.set("INA238#1.bus.i2c.address", 0x48)
    store.save(store_file)
    assert wait_for(lambda: vehicle.values.get("INA238_1C") == 0x48)


@pytest.mark.issue40
def test_a_program_that_never_closes_its_store_vehicle_still_exits(store_file: Path) -> None:
    """The watcher must not keep a page server that ended without close() alive."""
    code = (
        "from px4params.gui.vehicle import StoreVehicle\n"
        f"StoreVehicle({str(store_file)!r}, None, [], poll_interval=0.05)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], timeout=60, check=False)
    assert done.returncode == 0


class _Lossy(_Recording):
    """Loses INA238_1C's PARAM_VALUE the first time it is sent (UDP loses datagrams)."""

    lost = False

    def _send(self, msg: Any, peers: list[Any]) -> None:
        if not self.lost and msg.get_type() == "PARAM_VALUE" and _name(msg.param_id) == "INA238_1C":
            self.lost = True
            return
        super()._send(msg, peers)


@pytest.mark.issue40
def test_a_list_that_lost_a_value_is_asked_for_again(schema: px4params.Schema) -> None:
    with _peer(schema, _Lossy) as served, _page(served.address) as page:
        assert served.lost and served.lists >= 2
        assert page.values == {e.name: e.value for e in served.entries()}


class _RefusesTheSameValue(_Recording):
    """Refuses a write of INA238_1P with PARAM_ERROR although its echo holds the value sent
    (a parameter that is read-only, holding that value already)."""

    def _set(self, peer: Any, name: str, msg: Any) -> None:
        found = self._find(name)
        if name != "INA238_1P" or found is None:
            super()._set(peer, name, msg)
            return
        self._send(self._value_msg(*found), [peer])
        self._error(peer, msg, name, found[0], f"{name}: read-only", 4)  # MAV_PARAM_ERROR_READ_ONLY


@pytest.mark.issue40
def test_a_param_error_refuses_a_write_whatever_the_echo(schema: px4params.Schema) -> None:
    with _peer(schema, _RefusesTheSameValue) as served, _page(served.address) as page:
        same = page.values["INA238_1P"]
        result = page.write("INA238_1P", same)
        assert (result.ok, result.value, result.reason) == (False, same, "INA238_1P: read-only")


class _AckFirst(_Recording):
    """Sends COMMAND_ACK before the message asked for (nothing in MAVLink orders them)."""

    def _command(self, peer: Any, msg: Any) -> None:
        result, reply = self._command_result(msg)
        ack = mavlink2.MAVLink_command_ack_message(
            msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
        )
        self._send(ack, [peer])
        if reply is not None:
            self._send(reply, [peer])


class _MetadataOnly(_Recording):
    """A vehicle that serves COMPONENT_METADATA (397) and not COMPONENT_INFORMATION (395)."""

    def _requested(self, message_id: int) -> Any:
        return None if message_id == 395 else super()._requested(message_id)


@pytest.mark.issue40
@pytest.mark.parametrize("server", [_AckFirst, _MetadataOnly])
def test_the_metadata_is_read_whichever_comes_first(
    schema: px4params.Schema, server: type[_Recording]
) -> None:
    with _peer(schema, server) as served, _page(served.address) as page:
        assert "INA238_1C" in {p["name"] for p in page.metadata["parameters"]}
        assert [c[2] for c in served.commands] == [397]  # no need to ask for 395


@pytest.mark.issue40
def test_the_page_still_hears_the_vehicle_after_a_quiet_moment(schema: px4params.Schema) -> None:
    """PX4 sends a heartbeat a second: between two, the link is quiet."""
    with _peer(schema, heartbeat_interval=1.0) as served, _page(served.address) as page:
        time.sleep(0.6)
        assert page.write("INA238_1C", 71).ok
        assert served.store.get("INA238#1.bus.i2c.address") == 71


class _Files:
    """A vehicle's files read over MAVLink FTP, by path (MAVFTP.read's answer: the bytes, or
    None for a file it does not have)."""

    def __init__(self, files: dict[str, bytes]) -> None:
        self.files = files
        self.asked: list[tuple[str, int]] = []

    def read(self, path: str, size: int) -> bytes | None:
        self.asked.append((path, size))
        return self.files.get(path)


def _general(uri: str, kind: int = 1) -> bytes:
    """A general metadata file (COMP_METADATA_TYPE_PARAMETER is 1) naming the parameters' file."""
    return json.dumps(
        {"version": 1, "metadataTypes": [{"type": 0}, {"type": kind, "uri": uri}]}
    ).encode()


PARAMETERS_DOC = {"version": 1, "parameters": [{"name": "INA238_1C", "type": "Int32"}]}


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("name", "packed"),
    [
        ("p.json", json.dumps(PARAMETERS_DOC).encode()),
        ("p.json.xz", lzma.compress(json.dumps(PARAMETERS_DOC).encode())),
        ("p.json.lzma", lzma.compress(json.dumps(PARAMETERS_DOC).encode(), lzma.FORMAT_ALONE)),
    ],
)
def test_the_parameters_file_is_unpacked_by_its_name(name: str, packed: bytes) -> None:
    """QGC's reading: ``.xz`` and ``.lzma`` files are compressed, others are JSON as they are."""
    files = _Files({"/general.json": _general(f"mftp://[;comp=1]/{name}"), f"/{name}": packed})
    found = MavlinkVehicle._download(None, files, "mftp://[;comp=1]/general.json")  # type: ignore[arg-type]
    assert found == PARAMETERS_DOC
    assert [path for path, _ in files.asked] == ["/general.json", f"/{name}"]
    assert all(size >= 1 << 20 for _, size in files.asked)  # a whole file, not a part of it


@pytest.mark.issue40
@pytest.mark.parametrize(
    "files",
    [
        {},  # no general file
        {"/general.json": _general("mftp:///p.json", kind=2)},  # no parameters entry
        {"/general.json": _general("https://example.com/p.json")},  # not on the vehicle
        {"/general.json": _general("mftp:///p.json")},  # listed, not there
        {"/general.json": _general("mftp:///p.json"), "/p.json": b""},  # empty
    ],
)
def test_a_vehicle_without_a_parameters_file_has_no_metadata(files: dict[str, bytes]) -> None:
    assert MavlinkVehicle._download(None, _Files(files), "mftp:///general.json") is None  # type: ignore[arg-type]


@pytest.mark.issue40
def test_the_store_vehicle_describes_its_structured_and_classic_parameters(
    vehicle: StoreVehicle,
) -> None:
    """QGC's parameters.json (version 1): the store's destructured names and the classic
    parameters it holds, each with its type."""
    types = {p["name"]: p["type"] for p in vehicle.metadata["parameters"]}
    assert vehicle.metadata["version"] == 1
    assert types["INA238_1C"] == "Int32"
    assert types["BAT1_CAPACITY"] == "Float" and types["SYS_AUTOSTART"] == "Int32"
    assert set(vehicle.values) <= set(types)


#: A MAVLink 2 signing key (32 bytes), and another.
KEY = hashlib.sha256(b"the page's link").digest()
OTHER_KEY = hashlib.sha256(b"another link").digest()


@pytest.mark.issue40
def test_a_signed_link_says_so_and_is_written_over(schema: px4params.Schema) -> None:
    with _peer(schema, signing_key=KEY) as served:
        port = served.address[1]
        with _page(served.address, signing_key=KEY) as page:
            assert page.source == f"udp 127.0.0.1:{port} (signed)"
            assert page.write("INA238_1C", 72).ok
        assert served.store.get("INA238#1.bus.i2c.address") == 72
        with pytest.raises(CommandError) as refused:
            MavlinkVehicle(served.address, timeout=1.0, signing_key=OTHER_KEY)
    # signed already: no hint about signing
    assert str(refused.value) == f"no vehicle answered on udp 127.0.0.1:{port} (signed) within 1 s"


@pytest.mark.issue40
def test_the_page_s_heartbeats_keep_the_vehicle_talking(schema: px4params.Schema) -> None:
    """The vehicle sends its status text to the ground stations it heard from lately (here
    within 3 s): a page that has nothing to ask still says it is there, once a second."""
    options = {"peer_timeout": 3.0, "health": lambda: [SHORT_HEALTH], "health_interval": 0.2}
    with _peer(schema, **options) as served, _page(served.address) as page:
        time.sleep(4.5)  # longer than the vehicle waits for a silent peer
        page.messages.clear()
        assert wait_for(lambda: SHORT_HEALTH in page.messages, 5.0)


@pytest.mark.issue40
def test_a_program_that_never_closes_its_mavlink_vehicle_still_exits(
    schema: px4params.Schema, tmp_path: Path
) -> None:
    """Neither the receiving nor the heartbeat thread keeps a page that ended without close()
    alive."""
    metadata = tmp_path / "parameters.json"
    metadata.write_text(json.dumps({"version": 1, "parameters": []}))
    with _peer(schema) as served:
        code = (
            "from px4params.gui.vehicle import MavlinkVehicle\n"
            f"MavlinkVehicle({served.address!r}, {str(metadata)!r}, timeout=10.0)\n"
        )
        done = subprocess.run([sys.executable, "-c", code], timeout=60, check=False)
    assert done.returncode == 0


# -- issue 40, sixth round (mutveh4): what the MAVLink client's surviving mutants changed -------


@pytest.mark.issue40
def test_a_float_write_answers_the_value_the_vehicle_reads_back(schema: px4params.Schema) -> None:
    """The vehicle echoes the float32 sent, so that the write is acknowledged, but a float16
    leaf keeps the float16 nearest (1049 * 2**-21 for 0.0005; 10 bits of mantissa): the write
    answers what the vehicle reads back afterwards, as the page then shows it."""
    with _peer(schema) as served, _page(served.address) as page:
        result = page.write("INA238_1Q", 0.0005)
        assert (result.ok, result.value, result.reason) == (True, 1049 * 2**-21, "")
        assert page.values["INA238_1Q"] == 1049 * 2**-21
        assert served.store.get("INA238#1.shunt") == 1049 * 2**-21


@pytest.mark.issue40
def test_a_list_still_arriving_is_not_asked_for_again(schema: px4params.Schema) -> None:
    """A vehicle paces its list (MAVLink's parameter protocol: "allow breaks between each
    message"; PX4 sends bursts): here 20 values every 0.2 s, three bursts. A pause between
    bursts is no lost list: one PARAM_REQUEST_LIST, every value."""
    with _peer(schema, param_rate=100.0) as served, _page(served.address) as page:
        assert page.values == {e.name: e.value for e in served.entries()}
        assert served.lists == 1


class _SlowToAnswer(_Recording):
    """Answers MAV_CMD_REQUEST_MESSAGE (the message, then COMMAND_ACK) one second late: a busy
    vehicle, or a slow radio link."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.late: list[tuple[float, Any, Any]] = []

    def _command(self, peer: Any, msg: Any) -> None:
        self.late.append((time.monotonic() + 1.0, peer, msg))

    def step(self, timeout: float) -> None:
        super().step(min(timeout, 0.05))
        while self.late and self.late[0][0] <= time.monotonic():
            _, peer, msg = self.late.pop(0)
            super()._command(peer, msg)


@pytest.mark.issue40
def test_a_vehicle_slow_to_answer_the_metadata_request_is_waited_for(
    schema: px4params.Schema,
) -> None:
    with _peer(schema, _SlowToAnswer) as served, _page(served.address) as page:
        assert "INA238_1C" in {p["name"] for p in page.metadata["parameters"]}
        assert [c[2] for c in served.commands] == [397]  # COMPONENT_METADATA, asked once


class _MissesTheFirstList(_Recording):
    """Never gets the page's first PARAM_REQUEST_LIST (UDP lost it)."""

    missed = False

    def _handle(self, peer: Any, msg: Any) -> bool:
        if msg.get_type() == "PARAM_REQUEST_LIST" and not self.missed:
            self.missed = True
            return True
        return super()._handle(peer, msg)


@pytest.mark.issue40
def test_a_list_request_nobody_answers_is_sent_again(schema: px4params.Schema) -> None:
    """MAVLink's parameter protocol: the ground station times out "after resends" when no
    PARAM_VALUE comes; a lost request is sent again, and the list comes whole."""
    with _peer(schema, _MissesTheFirstList) as served, _page(served.address) as page:
        assert served.missed and served.lists == 1  # the second request, answered
        assert page.values == {e.name: e.value for e in served.entries()}


class _FailsOnce:
    """The page's UDP socket, whose next read fails once (the kernel out of buffers)."""

    def __init__(self, sock: Any) -> None:
        self.sock = sock
        self.failed = False

    def recvfrom(self, size: int) -> Any:
        if not self.failed:
            self.failed = True
            raise OSError(errno.ENOBUFS, "No buffer space available")
        return self.sock.recvfrom(size)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.sock, name)


@pytest.mark.issue40
def test_a_failed_read_of_the_socket_does_not_deafen_the_page(schema: px4params.Schema) -> None:
    with _peer(schema) as served, _page(served.address) as page:
        failing = _FailsOnce(page._conn.port)
        page._conn.port = failing
        assert wait_for(lambda: failing.failed)
        assert page.write("INA238_1C", 73).ok  # its PARAM_VALUE still heard
        assert served.store.get("INA238#1.bus.i2c.address") == 73


class _Unread(_Recording):
    """Never answers a PARAM_REQUEST_READ of INA238_1P (lost, one way or the other)."""

    def _read(self, peer: Any, msg: Any, name: str, index: int) -> None:
        if name != "INA238_1P":
            super()._read(peer, msg, name, index)


@pytest.mark.issue40
def test_a_read_nobody_answers_is_none_and_never_hangs(schema: px4params.Schema) -> None:
    with _peer(schema, _Unread) as served, _page(served.address) as page:
        assert _within(30, lambda: page.read("INA238_1P", 0.3)) is None
        assert page._waiters["INA238_1P"] == []  # nothing left waiting


@pytest.mark.issue40
def test_a_refusal_names_its_reason_after_hundreds_of_status_lines(
    schema: px4params.Schema,
) -> None:
    """The page keeps the last 200 STATUSTEXT lines; a vehicle reporting health for minutes
    fills them (here 25 lines every 50 ms): a refused write still says the vehicle's reason."""
    options = {"health": lambda: [SHORT_HEALTH] * 25, "health_interval": 0.05}
    with _peer(schema, **options) as served, _page(served.address) as page:
        assert wait_for(lambda: len(page.messages) == 200)
        refused = page.write("INA238_1C", 200)
        assert (refused.ok, refused.value) == (False, 0x45)
        assert refused.reason == (
            "INA238_1C: INA238#1: bus.i2c.address: value 200 is out of range (expected 0 to 127)"
        )


class _NoParameters(_Recording):
    """A component without parameters: it ignores PARAM_REQUEST_LIST (MAVLink's parameter
    protocol)."""

    def _handle(self, peer: Any, msg: Any) -> bool:
        if msg.get_type() == "PARAM_REQUEST_LIST":
            self.lists += 1
            return True
        return super()._handle(peer, msg)


@pytest.mark.issue40
def test_a_list_never_answered_is_asked_again_until_the_timeout(schema: px4params.Schema) -> None:
    """The ground station "should simply timeout (after resends) if no PARAM_VALUE is
    received" (MAVLink's parameter protocol): the page asks again, then has no values."""
    with _peer(schema, _NoParameters) as served, _page(served.address, timeout=3.0) as page:
        assert page.values == {}
        assert served.lists >= 2


# -- whose messages are the vehicle's: other components and systems on the same link -----------
# A vehicle's link carries more than its autopilot: a camera or gimbal (other component IDs),
# a companion computer, another ground station, another vehicle. The peer below sends their
# frames through its own socket, each packed by pymavlink with its sender's system and component.


def _say_as(served: _Recording, sender: tuple[int, int], messages: list[Any], peers: Any) -> None:
    """``messages`` sent to ``peers`` from the peer's socket as ``sender`` (system, component)
    sends them."""
    packer = mavlink2.MAVLink(None, srcSystem=sender[0], srcComponent=sender[1])
    for msg in messages:
        frame = msg.pack(packer)
        packer.seq = (packer.seq + 1) % 256
        for peer in peers:
            served._sock.sendto(frame, peer)


#: The camera's parameters: one of its own, one with the name of one of the vehicle's.
CAMERA_PARAMS = [("CAM_EV", 0.5), ("INA238_1C", 99.0)]


class _WithCamera(_Recording):
    """A vehicle with a camera (MAV_COMP_ID_CAMERA, 100) whose list reaches the page too
    (MAVLink's parameter protocol: the recipient of PARAM_REQUEST_LIST broadcasts its values,
    and a request to component 0, as a ground station sends it, reaches every component): here
    right after the vehicle's list, saying the camera has 1000 parameters."""

    def _stream_some(self) -> None:
        super()._stream_some()
        if not self._streams:  # the vehicle's list is sent: the camera's follows
            real32 = mavlink2.MAV_PARAM_TYPE_REAL32
            camera = [
                mavlink2.MAVLink_param_value_message(name.encode(), value, real32, 1000, index)
                for index, (name, value) in enumerate(CAMERA_PARAMS)
            ]
            _say_as(self, (self.system_id, 100), camera, self._peers(None))


@pytest.mark.issue40
def test_only_the_vehicle_s_component_s_parameters_are_the_vehicle_s(
    schema: px4params.Schema,
) -> None:
    """PARAM_VALUE names its sender; the camera's values (its param_count and param_index
    with them) are the camera's: none is taken for the vehicle's, none overwrites one of the
    vehicle's, and its count of 1000 does not make the page think values are missing."""
    with _peer(schema, _WithCamera) as served, _page(served.address) as page:
        assert page.read("INA238_1C") == 0x45  # after the camera's values, in order
        assert page.values == {e.name: e.value for e in served.entries()}
        assert served.lists == 1  # the list was whole: not asked for again


#: Heartbeats of component 1 that are no vehicle's autopilot (system, MAV_TYPE, MAV_AUTOPILOT).
NOT_A_VEHICLE = [
    # another ground station
    (42, mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID),
    # a companion computer whose software says it is an autopilot: its type says it is none
    (43, mavlink2.MAV_TYPE_ONBOARD_CONTROLLER, mavlink2.MAV_AUTOPILOT_PX4),
    # the vehicle's type, as components once reported their system's, but no flight controller
    (44, mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_INVALID),
]


class _AmongOthers(_Recording):
    """Before each of its heartbeats, those of ``NOT_A_VEHICLE``."""

    def _heartbeat(self) -> None:
        for system, kind, autopilot in NOT_A_VEHICLE:
            beat = mavlink2.MAVLink_heartbeat_message(kind, autopilot, 0, 0, 0, 3)
            _say_as(self, (system, 1), [beat], self._peers(None))
        super()._heartbeat()


@pytest.mark.issue40
def test_the_vehicle_is_the_heartbeat_of_an_autopilot_on_a_vehicle(
    schema: px4params.Schema,
) -> None:
    """common.xml's HEARTBEAT: a component that is no flight controller sends
    MAV_AUTOPILOT_INVALID; a flight controller sends the type of its vehicle, every other
    component its own kind. The page talks to system 7 (MAV_TYPE_GENERIC, MAV_AUTOPILOT_PX4),
    whose heartbeat comes after the three others'."""
    with _peer(schema, _AmongOthers) as served, _page(served.address) as page:
        assert page.values == {e.name: e.value for e in served.entries()}
        assert page.write("INA238_1C", 74).ok  # sent to system 7, or nobody answers
        assert served.store.get("INA238#1.bus.i2c.address") == 74


#: Three texts in two chunks each (MAVLink 2 STATUSTEXT: 50 characters a chunk), from three
#: senders that each gave their text the id 5: the vehicle, its camera, and another vehicle.
CHUNKED = {
    (7, 1): "health: ina238 INA238#1 on I2C bus 2 address 0x45: critical: not found",
    (7, 100): "camera: storage full, no photo taken, video recording stopped",
    (8, 1): "health: ms5611 MS5611#0 on SPI bus 1: critical: no answer since boot",
}

#: A gimbal's (MAV_COMP_ID_GIMBAL, 154) text of 50 characters: one chunk, whole, of id 0.
WHOLE = "gimbal: nominal; pitch and yaw calibrated; all ok."


@pytest.mark.issue40
def test_status_text_chunks_are_joined_per_sender_and_id(schema: px4params.Schema) -> None:
    """STATUSTEXT's id is "unique (opaque)" to its sender, and id 0 marks the only chunk of a
    text, to be shown at once (common.xml): the first chunks of three senders' texts of id 5,
    a whole text in one chunk of 50 characters, then the second chunks make four texts, none
    mixed with another."""
    warning = mavlink2.MAV_SEVERITY_WARNING

    def chunk(text: str, seq: int, text_id: int = 5) -> Any:
        part = text[50 * seq : 50 * (seq + 1)].encode()
        return mavlink2.MAVLink_statustext_message(warning, part, text_id, seq)

    with _peer(schema) as served, _page(served.address) as page:
        to_page = [("127.0.0.1", page._conn.port.getsockname()[1])]
        for seq in (0, 1):
            for sender, text in CHUNKED.items():
                _say_as(served, sender, [chunk(text, seq)], to_page)
            if seq == 0:
                _say_as(served, (7, 154), [chunk(WHOLE, 0, text_id=0)], to_page)
        assert wait_for(lambda: len(page.messages) >= 4)
        time.sleep(0.1)  # nothing more comes
        assert page.messages == [WHOLE, *CHUNKED.values()]


class _SaysMore(_Recording):
    """Before its reason for refusing a write, says two lines about parameters whose names
    hold the written one (say, a preflight check's): ``NAME_CELLS`` and ``SENS_NAME``."""

    def _refuse(self, peer: Any, msg: Any, name: str, found: Any, why: str, code: int) -> None:
        for other in (f"{name}_CELLS", f"SENS_{name}"):
            self._statustext(f"Preflight Fail: {other} not set", [peer])
        super()._refuse(peer, msg, name, found, why, code)


@pytest.mark.issue40
def test_a_refusal_s_reason_names_the_parameter_as_a_whole_word(
    schema: px4params.Schema,
) -> None:
    """A line about BAT1_N_CELLS or SENS_BAT1_N is no reason for refusing BAT1_N."""
    with _peer(schema, _SaysMore) as served, _page(served.address) as page:
        refused = page.write("BAT1_N", 3)
        assert (refused.ok, refused.reason) == (False, "[pm] unknown param: BAT1_N")
        assert "Preflight Fail: BAT1_N_CELLS not set" in page.messages  # said, not the reason


class _CameraAnswersToo(_Recording):
    """Before the vehicle answers a write, the camera (component 100) refuses a parameter of
    the same name with PARAM_ERROR and says a line naming it (its answer to another ground
    station's write, say)."""

    def _set(self, peer: Any, name: str, msg: Any) -> None:
        error = mavlink2.MAVLink_param_error_message(
            msg.get_srcSystem(),
            msg.get_srcComponent(),
            name.encode(),
            -1,
            mavlink2.MAV_PARAM_ERROR_READ_ONLY,
        )
        line = mavlink2.MAVLink_statustext_message(
            mavlink2.MAV_SEVERITY_WARNING, f"{name}: the camera's".encode(), 0, 0
        )
        _say_as(self, (self.system_id, 100), [line, error], [peer])
        super()._set(peer, name, msg)


@pytest.mark.issue40
def test_only_the_vehicle_refuses_its_writes_and_says_why(schema: px4params.Schema) -> None:
    """The camera's PARAM_ERROR refuses no write of the vehicle, and its line is shown but no
    reason: the reason is what the vehicle said."""
    with _peer(schema, _CameraAnswersToo) as served, _page(served.address) as page:
        accepted = page.write("INA238_1C", 75)
        assert (accepted.ok, accepted.value, accepted.reason) == (True, 75, "")
        assert served.store.get("INA238#1.bus.i2c.address") == 75
        refused = page.write("INA238_1C", 200)
        assert (refused.ok, refused.value) == (False, 75)
        assert refused.reason == (
            "INA238_1C: INA238#1: bus.i2c.address: value 200 is out of range (expected 0 to 127)"
        )
        assert "INA238_1C: the camera's" in page.messages


# -- STATUSTEXT chunks joined by chunk_seq ---------------------------------------------------------
# common.xml's STATUSTEXT: a text longer than 50 characters goes in chunks of one non-zero id,
# ``chunk_seq`` counting them from 0, and the chunk holding a NUL (shorter than 50 characters
# once decoded) is the last. PX4 (src/modules/mavlink/streams/STATUSTEXT.hpp) sends every text
# with an id, all its chunks at once, and no empty chunk after a full last one: its text of 50 or
# 100 characters ends with a full chunk. UDP loses, repeats and reorders datagrams: the page
# joins the chunks by chunk_seq, marks where chunks are missing, and shows a text it cannot
# tell is whole after a bounded wait (QGC waits 1 s), as it is.


def _chunks(text: str) -> list[str]:
    """``text`` cut as px4params' server cuts it: 50 characters a chunk, and an empty one
    after a last chunk of 50 (its NUL ends the text)."""
    parts = [text[i : i + 50] for i in range(0, len(text), 50)]
    return [*parts, ""] if len(parts[-1]) == 50 else parts


def _px4_chunks(text: str) -> list[str]:
    """``text`` cut as PX4 cuts it: 50 characters a chunk, and nothing after the last (the
    loop sends the rest and stops once at most 50 characters are left)."""
    return [text[i : i + 50] for i in range(0, len(text), 50)]


def _tell(
    served: _Recording,
    page: MavlinkVehicle,
    text_id: int,
    parts: dict[int, str] | list[tuple[int, str]],
) -> None:
    """The chunks ``parts`` (by chunk_seq, in the order given; as pairs, a chunk may come
    twice) of a text of ``text_id``, sent to the page as the vehicle (system 7, component 1)."""
    to_page = [("127.0.0.1", page._conn.port.getsockname()[1])]
    warning = mavlink2.MAV_SEVERITY_WARNING
    pairs = parts.items() if isinstance(parts, dict) else parts
    chunks = [
        mavlink2.MAVLink_statustext_message(warning, part.encode(), text_id, seq)
        for seq, part in pairs
    ]
    _say_as(served, (7, 1), chunks, to_page)


def _shown_at(page: MavlinkVehicle) -> list[tuple[float, str]]:
    """When (time.monotonic()) each text is shown from now on, and the text."""
    shown: list[tuple[float, str]] = []
    page.listen(
        lambda event: (
            shown.append((time.monotonic(), event["text"])) if event["kind"] == "status" else None
        )
    )
    return shown


#: A health report of three chunks (50, 50 and 17 characters).
THREE_CHUNKS = (
    "health: ina238 INA238#1 on I2C bus 2 address 0x45: critical: no answer since boot, "
    + "checked the wiring and the address"
)


@pytest.mark.issue40
def test_status_text_chunks_are_joined_by_chunk_seq_and_a_gap_is_marked(
    schema: px4params.Schema,
) -> None:
    """The second chunk before the first, then the third: the text in chunk_seq order. The
    same text again with its second chunk lost: shown with "[...]" where it is missing, never
    glued, and read as no health report (what is missing may be its instance or state)."""
    first, second, third = _chunks(THREE_CHUNKS)
    assert [len(p) for p in (first, second, third)] == [50, 50, 17]
    with _peer(schema) as served, _page(served.address) as page:
        _tell(served, page, 21, {1: second, 0: first, 2: third})
        _tell(served, page, 22, {0: first, 2: third})
        assert wait_for(lambda: len(page.messages) >= 2, 5.0)
        time.sleep(0.1)  # nothing more comes
        assert page.messages == [THREE_CHUNKS, first + "[...]" + third]
        assert page.health == {"INA238#1": parse_health(THREE_CHUNKS)}  # from the whole one


@pytest.mark.issue40
def test_a_text_is_shown_once_whole_whatever_the_order_of_its_chunks(
    schema: px4params.Schema,
) -> None:
    """The last chunk (shorter than 50) before a middle one: the text is not whole yet, and
    is shown once, whole, when the middle one comes."""
    first, second, third = _chunks(THREE_CHUNKS)
    with _peer(schema) as served, _page(served.address) as page:
        _tell(served, page, 23, {0: first, 2: third, 1: second})
        assert wait_for(lambda: page.messages, 5.0)
        time.sleep(0.1)  # nothing more comes
        assert page.messages == [THREE_CHUNKS]
        assert page._chunks == {}  # no text left waiting for its deadline


@pytest.mark.issue40
def test_a_chunk_heard_twice_is_one_chunk(schema: px4params.Schema) -> None:
    """UDP and routers may deliver a datagram twice: chunk 0 again while the text waits for
    its others, and again once the text was shown, is the same chunk, no new text."""
    first, second, third = _chunks(THREE_CHUNKS)
    with _peer(schema) as served, _page(served.address) as page:
        _tell(served, page, 24, [(0, first), (0, first), (1, second), (2, third)])
        assert wait_for(lambda: page.messages, 5.0)
        _tell(served, page, 24, [(0, first), (2, third)])
        time.sleep(0.2)  # the repeats are taken in
        assert page.messages == [THREE_CHUNKS]
        assert page._chunks == {}  # no text left waiting for its deadline


#: A health report of exactly 50 characters (one full chunk from PX4).
HEALTH_50 = "health: ms5611 MS5611#0: critical: no answer at 0x"
assert len(LONG_HEALTH) == 100 and len(HEALTH_50) == 50


@pytest.mark.issue40
def test_a_px4_text_of_50_or_100_characters_is_whole_after_its_wait(
    schema: px4params.Schema,
) -> None:
    """PX4 sends no chunk after a full last one: the page cannot tell the text ended until no
    chunk came for its wait (1 s), then shows it as it is, whole, and reads its health."""
    with _peer(schema) as served, _page(served.address) as page:
        shown = _shown_at(page)
        sent = time.monotonic()
        _tell(served, page, 41, dict(enumerate(_px4_chunks(LONG_HEALTH))))
        _tell(served, page, 42, dict(enumerate(_px4_chunks(HEALTH_50))))
        assert wait_for(lambda: len(shown) >= 2, 10.0)
        time.sleep(0.1)  # nothing more comes
        assert sorted(text for _, text in shown) == sorted([LONG_HEALTH, HEALTH_50])
        assert min(at for at, _ in shown) >= sent + 1.0  # not before its wait was over
        assert page.health == {
            "INA238#1": parse_health(LONG_HEALTH),
            "MS5611#0": parse_health(HEALTH_50),
        }


class _SaysLikePx4(_Recording):
    """Cuts its texts as PX4 does (every text with an id, no chunk after a full last one), and
    refuses INA238_1C's writes with a reason of 100 characters."""

    #: The reason: two full chunks.
    REASON = (
        "INA238_1C: value 200 is out of range for INA238#1 on I2C bus 2 at address 0x45 "
        + "(expected: 0 to 127)."
    )

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.texts = 0

    def _statustext(self, text: str, peers: list[Any]) -> None:
        self.texts += 1
        warning = mavlink2.MAV_SEVERITY_WARNING
        for seq, part in enumerate(_px4_chunks(text)):
            msg = mavlink2.MAVLink_statustext_message(warning, part.encode(), self.texts, seq)
            self._send(msg, peers)

    def _refuse(self, peer: Any, msg: Any, name: str, found: Any, why: str, code: int) -> None:
        reason = self.REASON if name == "INA238_1C" else why
        super()._refuse(peer, msg, name, found, reason, code)


assert len(_SaysLikePx4.REASON) == 100


@pytest.mark.issue40
def test_a_refusal_s_reason_of_100_characters_from_px4_is_named(
    schema: px4params.Schema,
) -> None:
    """A refusal's reason from PX4 that ends with a full chunk is shown only after its wait:
    the refused write waits for it, and names it."""
    with _peer(schema, _SaysLikePx4) as served, _page(served.address) as page:
        refused = page.write("INA238_1C", 200)
        assert (refused.ok, refused.value, refused.reason) == (False, 0x45, _SaysLikePx4.REASON)
        assert page.messages[-1] == _SaysLikePx4.REASON  # shown as it is


#: A text of 150 characters, three full chunks.
THREE_FULL_CHUNKS = "camera: storage full; photos are kept in memory until the card is changed " + (
    "or the memory is full, then the oldest are dropped: change the card soon...."
)
assert len(THREE_FULL_CHUNKS) == 150


@pytest.mark.issue40
def test_a_text_whose_chunks_stop_coming_is_shown_marked_after_its_wait(
    schema: px4params.Schema,
) -> None:
    """A text's middle chunk never comes: shown with "[...]" where it is missing once it
    waited a second for it (QGC waits 1 s), and read as no health report (what is missing
    may be its instance or state)."""
    lost = THREE_FULL_CHUNKS
    with _peer(schema) as served, _page(served.address) as page:
        shown = _shown_at(page)
        sent = time.monotonic()
        _tell(served, page, 31, {0: lost[:50], 2: lost[100:]})
        assert wait_for(lambda: shown, 10.0)
        time.sleep(0.1)  # nothing more comes
        assert [text for _, text in shown] == [lost[:50] + "[...]" + lost[100:]]
        assert shown[0][0] >= sent + 1.0  # not before its wait was over
        assert page.health == {}  # an incomplete text is no health report


@pytest.mark.issue40
def test_a_text_is_shown_at_once_marked_when_another_of_its_id_starts(
    schema: px4params.Schema, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A text's first chunk, then another text of its id starting (chunk_seq 0 again, another
    text: the id wrapped): the first shown at once, its end marked missing, the second whole
    and apart from it. Texts wait 10 s here: neither is shown by its wait."""
    monkeypatch.setattr("px4params.gui.vehicle._CHUNK_WAIT", 10.0)
    earlier = "camera: storage full, no photo taken, video recording stopped"
    later = "gimbal: pitch calibration done, yaw calibration started, hold still"
    with _peer(schema) as served, _page(served.address) as page:
        _tell(served, page, 32, {0: _chunks(earlier)[0]})
        _tell(served, page, 32, dict(enumerate(_chunks(later))))
        assert wait_for(lambda: len(page.messages) >= 2, 5.0)
        time.sleep(0.1)  # nothing more comes
        assert page.messages == [earlier[:50] + "[...]", later]


def test_a_texts_chunks_wait_a_second_and_each_run_of_lost_ones_is_marked_once() -> None:
    """QGC's wait: a text waits 1 s after its latest new chunk. Lost chunks, as the page
    joins them: a lost first chunk is marked, two lost in a row are marked once, a lost end
    (no short chunk came, and the wait is over) too."""
    full = [f"{n}" * 50 for n in range(5)]
    text = _ChunkedText()
    text.add(1, full[1], 100.0)
    assert text.deadline == 101.0
    text.add(4, "end", 100.25)
    assert text.deadline == 101.25 and not text.whole
    assert text.text() == "[...]" + full[1] + "[...]" + "end"
    cut = _ChunkedText()
    cut.add(0, full[0], 7.0)
    cut.add(2, full[2], 7.5)
    cut.waited()
    assert (cut.whole, cut.text()) == (False, full[0] + "[...]" + full[2])
    ended = _ChunkedText()
    ended.add(0, full[0], 7.0)
    assert ended.text() == full[0] + "[...]"  # still waiting: its end may come


@pytest.mark.issue40
def test_a_new_text_of_an_id_just_shown_is_shown_too(
    schema: px4params.Schema, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A text shown whole, then, within the wait a repeated chunk is dropped in, another text
    of its id (the id wrapped): that one is no repeat, and is shown whole as well."""
    monkeypatch.setattr("px4params.gui.vehicle._CHUNK_WAIT", 10.0)
    earlier = "camera: storage full, no photo taken, video recording stopped"
    later = "gimbal: pitch calibration done, yaw calibration started, hold still"
    with _peer(schema) as served, _page(served.address) as page:
        _tell(served, page, 33, dict(enumerate(_chunks(earlier))))
        assert wait_for(lambda: page.messages, 5.0)
        _tell(served, page, 33, dict(enumerate(_chunks(later))))
        assert wait_for(lambda: len(page.messages) >= 2, 5.0)
        assert page.messages == [earlier, later]


@pytest.mark.issue40
def test_the_texts_shown_lately_are_remembered_up_to_64(
    schema: px4params.Schema, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Repeats are dropped against the last 64 texts shown (within their wait): the 64th
    text's first chunk heard again is no new text; once 65 were shown, the first's is."""
    monkeypatch.setattr("px4params.gui.vehicle._CHUNK_WAIT", 30.0)
    texts = [f"text {text_id:03}: " + "y" * 50 for text_id in range(1, 66)]
    with _peer(schema) as served, _page(served.address) as page:
        for text_id, text in enumerate(texts[:64], 1):
            _tell(served, page, text_id, dict(enumerate(_chunks(text))))
            assert wait_for(lambda n=text_id: len(page.messages) >= n, 10.0)
        _tell(served, page, 1, {0: _chunks(texts[0])[0]})
        time.sleep(0.2)  # the repeat is taken in
        assert (len(page.messages), page._chunks) == (64, {})
        _tell(served, page, 65, dict(enumerate(_chunks(texts[64]))))
        assert wait_for(lambda: len(page.messages) >= 65, 10.0)
        _tell(served, page, 1, {0: _chunks(texts[0])[0]})
        assert wait_for(lambda: page._chunks, 5.0)  # forgotten: a new text, waiting for more
        assert list(page._chunks) == [(7, 1, 1)]


@pytest.mark.issue40
def test_texts_waiting_for_chunks_are_bounded_in_number(
    schema: px4params.Schema, monkeypatch: pytest.MonkeyPatch
) -> None:
    """300 texts that each send their first chunk only (a flood, or a link losing the rest):
    at most 16 wait at once, the oldest shown marked when a 17th starts (its end may be
    missing), the 16 left shown as they are after their wait, and every one of the 300 is
    shown once, in order, none dropped. Texts wait 3 s here, so that only the last 16 are
    shown by their wait however slowly the page takes them in."""
    monkeypatch.setattr("px4params.gui.vehicle._CHUNK_WAIT", 3.0)
    shown: list[str] = []
    texts = [f"text {text_id:03}: " + "x" * 40 for text_id in range(1, 301)]
    with _peer(schema) as served, _page(served.address) as page:
        page.listen(
            lambda event: shown.append(event["text"]) if event["kind"] == "status" else None
        )
        waiting = []
        for text_id, text in enumerate(texts, 1):
            _tell(served, page, text_id, {0: text})
            # each text taken in before the next (a burst of 300 datagrams can overflow the
            # socket's buffer on a loaded machine): it waits for its chunks or is shown
            assert wait_for(lambda n=text_id: len(page._chunks) + len(shown) >= n, 10.0)
            waiting.append(len(page._chunks))
        assert wait_for(lambda: len(shown) == 300, 10.0)
        assert max(waiting) <= 16
        assert shown == [t + "[...]" for t in texts[:-16]] + texts[-16:]
        assert page._chunks == {}


# -- writes of one parameter at once; the page's heartbeat on a busy link -------------------------
# The app runs each write in a worker thread (asyncio.to_thread), and the link carries more
# senders than the vehicle.


class _LateAndLossy(_Recording):
    """Answers a write of INA238_1C late, once ``answer`` is set (a busy vehicle, a slow radio
    link), except a write of 1, which is lost on the way."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.late: list[tuple[Any, Any]] = []
        self.answer = threading.Event()

    def _set(self, peer: Any, name: str, msg: Any) -> None:
        if name != "INA238_1C":
            super()._set(peer, name, msg)
        elif param_value_of(msg) != 1:
            self.late.append((peer, msg))

    def step(self, timeout: float) -> None:
        super().step(min(timeout, 0.05))
        while self.late and self.answer.is_set():
            peer, msg = self.late.pop(0)
            super()._set(peer, "INA238_1C", msg)


@pytest.mark.issue40
def test_a_write_given_up_leaves_another_write_of_the_parameter_waiting(
    schema: px4params.Schema,
) -> None:
    """The page's writes run in threads. A write of 70 waits for its late answer; meanwhile a
    write of 1 to the same parameter is lost and given up (three tries of 0.1 s). Giving up
    stops that write's waiting only: the write of 70 still hears its answer, which the vehicle
    sends only then, and is accepted (the two wait on lists equal while both are empty; only
    the one given up is forgotten)."""
    with _peer(schema, _LateAndLossy) as served, _page(served.address) as page:
        answers: list[Any] = []  # the write's result, or what it raised

        def write_70() -> None:
            try:  # one try: its answer comes well within 30 s
                answers.append(page.write("INA238_1C", 70, 30.0))
            except Exception as e:
                answers.append(e)

        writing = threading.Thread(target=write_70, daemon=True)
        writing.start()
        assert wait_for(lambda: served.sets == ["INA238_1C"], 5.0)  # waiting, first
        lost = page.write("INA238_1C", 1, timeout=0.1)
        assert served.late and not answers  # given up before the vehicle answered 70
        served.answer.set()
        writing.join(10)
        assert (lost.ok, lost.reason) == (False, "INA238_1C: no answer from the vehicle")
        assert len(answers) == 1 and isinstance(answers[0], WriteResult), answers
        assert (answers[0].ok, answers[0].value, answers[0].reason) == (True, 70, "")
        assert served.sets == ["INA238_1C"] * 4  # 70 once, 1 three times
        assert page._waiters["INA238_1C"] == []  # nothing left waiting


class _Crowded(_Recording):
    """A link crowded by others, with no vehicle yet: at each of its heartbeats (every 10 ms)
    those of 20 other senders (ground stations, companions), and none of its own."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.others = 0

    def _heartbeat(self) -> None:
        beat = mavlink2.MAVLink_heartbeat_message(
            mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3
        )
        for system in range(100, 120):
            _say_as(self, (system, 190), [beat], self._peers(None))
            self.others += 1


@pytest.mark.issue40
def test_the_page_beats_once_a_second_while_connecting_on_a_crowded_link(
    schema: px4params.Schema, monkeypatch: pytest.MonkeyPatch
) -> None:
    """MAVLink's heartbeat is 1 Hz (a ground station's too), however many others the page
    hears: waiting 1.5 s for a vehicle among some thousand others' heartbeats, it sends two
    (at once, and a second later), and none once it gave up. Counted as the page sends them
    (the vehicle may read the last one later), and all reach the vehicle."""
    sent_at: list[float] = []
    send_heartbeat = MavlinkVehicle._send_heartbeat

    def noted(page: MavlinkVehicle) -> None:
        sent_at.append(time.monotonic())
        send_heartbeat(page)

    monkeypatch.setattr(MavlinkVehicle, "_send_heartbeat", noted)
    with _peer(schema, _Crowded, heartbeat_interval=0.01) as served:
        started = time.monotonic()
        with pytest.raises(CommandError):
            MavlinkVehicle(served.address, timeout=1.5)
        gave_up = time.monotonic()
        time.sleep(1.2)
        assert served.others > 500  # the crowd was there
        assert 2 <= len(sent_at) <= 1 + (gave_up - started)  # at once, and a second later
        assert all(b - a >= 0.99 for a, b in itertools.pairwise(sent_at))  # 1 Hz
        assert max(sent_at) < gave_up  # none after giving up
        assert wait_for(lambda: served.heartbeat_count == len(sent_at), 5.0)


@pytest.mark.issue40
def test_signed_frames_leave_in_the_order_they_were_signed_from_every_thread(
    schema: px4params.Schema,
) -> None:
    """MAVLink 2 signing: a receiver drops a frame whose timestamp is not above the last one it
    took from that link, as a replay. The page sends from several threads on one connection
    (its heartbeat, writes, the FTP download), so each frame must be signed and written in one
    step. Here a thread may lose the processor between signing a frame and writing it."""
    with _peer(schema, signing_key=KEY) as served, _page(served.address, signing_key=KEY) as page:
        conn = page._conn
        write = conn.write
        order = threading.Lock()
        stamps: list[int] = []

        def write_late(frame: bytes) -> None:
            time.sleep(0.0005 * (frame[4] % 4))  # by sequence number: an uneven wait
            with order:
                # a signed MAVLink 2 frame ends: link id, 6-byte timestamp, 6-byte signature
                stamps.append(int.from_bytes(frame[-12:-6], "little"))
                write(frame)

        conn.write = write_late

        def send() -> None:
            for _ in range(25):
                conn.mav.heartbeat_send(6, 8, 0, 0, 0)

        threads = [threading.Thread(target=send) for _ in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10.0)
        assert page.write("INA238_1C", 71).ok  # a write's PARAM_SET goes the same way
        conn.write = write
    assert len(stamps) >= 101
    assert stamps == sorted(set(stamps))


@pytest.mark.issue40
def test_signed_frames_leave_with_rising_timestamps_while_signed_frames_arrive(
    schema: px4params.Schema,
) -> None:
    """MAVLink 2 signing: the page's timestamp moves up with every frame it signs and every
    signed frame it accepts (to the frame's, when later), and every frame it sends carries one
    above the last it sent (a signed vehicle drops any other as a replay). Here the vehicle's
    signed frames arrive, each checked by the page's receive thread, while four threads send;
    the interpreter switches threads every microsecond, so a check and a send interleave."""
    with _peer(schema, signing_key=KEY) as served, _page(served.address, signing_key=KEY) as page:
        conn = page._conn
        write = conn.write
        stamps: list[int] = []

        def write_noted(frame: bytes) -> None:
            # a signed MAVLink 2 frame ends: link id, 6-byte timestamp, 6-byte signature
            stamps.append(int.from_bytes(frame[-12:-6], "little"))
            write(frame)

        # the vehicle's frames, signed as another peer signs them: its own link id, and a clock
        # ahead of the page's (the page's timestamp moves up to the vehicle's)
        vehicle = mavlink2.MAVLink(None, srcSystem=7, srcComponent=1)
        Signing(KEY, link_id=3, now=time.time() + 60).attach(vehicle)
        beat = mavlink2.MAVLink_heartbeat_message(
            mavlink2.MAV_TYPE_GENERIC, mavlink2.MAV_AUTOPILOT_PX4, 0, 0, 0, 4
        )
        frames = [beat.pack(vehicle) for _ in range(10000)]
        to_page = ("127.0.0.1", conn.port.getsockname()[1])
        accepted_before = page._conn.mav.signing.goodsig_count

        def arrive() -> None:
            for n, frame in enumerate(frames):
                served._sock.sendto(frame, to_page)
                if n % 10 == 0:
                    time.sleep(0.001)  # the page's socket buffer keeps up

        def send() -> None:
            while arriving.is_alive():
                conn.mav.heartbeat_send(6, 8, 0, 0, 0)

        switching = sys.getswitchinterval()
        conn.write = write_noted
        sys.setswitchinterval(1e-6)
        try:
            arriving = threading.Thread(target=arrive)
            threads = [arriving, *(threading.Thread(target=send) for _ in range(4))]
            for t in threads:
                t.start()
            for t in threads:
                t.join(60.0)
        finally:
            sys.setswitchinterval(switching)
            conn.write = write
        # the vehicle's frames were checked meanwhile (some, at least: UDP may drop some)
        assert page._conn.mav.signing.goodsig_count - accepted_before > 100
    assert len(stamps) >= 1000
    repeated_or_older = [(a, b) for a, b in itertools.pairwise(stamps) if b <= a]
    assert repeated_or_older == []
