"""The page's vehicle over a store file (``px4params.gui.vehicle``), in-process: health lines as
the commander and ``mavlink serve --bench`` write them (``health: DRIVER INSTANCE on WHERE:
STATE: REASON``), the state the page reads (JSON has no NaN or infinity: they travel as text),
the events its WebSocket pushes, and writes through the store's one write path."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import px4params
import pytest
from px4params.gui.vehicle import StoreVehicle, WriteResult, parse_health
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.store.session import Session


@pytest.fixture
def vehicle(store_file: Path) -> Iterator[StoreVehicle]:
    made = StoreVehicle(str(store_file), None, [], poll_interval=0.05)
    yield made
    made.close()


def wait_for(condition: Any, seconds: float = 10.0) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.02)
    return False


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
