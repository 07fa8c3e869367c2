"""What the page knows about the manifest beyond ``parameters.json``: the declared drivers as
the "Add a device" picker (grouped by what they measure, with each chip's name, what it needs
and the values a new instance starts from), and every configured or staged instance read back
from the flat values a ground station sees, with its location as PX4's ``status`` prints it and
what would stop its driver from starting it (the autostart rules of
:func:`~px4params.vehicle.autostart.configured_value`).

    GET  /api/manifest          {"drivers": [...], "boards": [...]} the picker, in the page's
                                order (with each instance slot's name, which the page shows
                                as it is), and the boards whose own starts are known
    POST /api/manifest          {"values": {flat name: value}, "board": name or null}
                                -> {"devices": [...]}: the instances those values configure,
                                with their problems (on that board)
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route

from px4params.errors import BoardsError
from px4params.store.key import Key
from px4params.vehicle.autostart import Configured, configured_value, shared_locations
from px4params.vehicle.boards import Board, load_boards
from px4params.vehicle.drivers import Driver, Drivers

__all__ = ["PICKER_GROUPS", "board_starts", "devices", "picker", "routes", "status_location"]

#: The picker's groups, in order, and the driver kinds (``kind`` in drivers.toml) each holds;
#: every other kind, and a parameter no driver declares, is under "other".
PICKER_GROUPS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("magnetometers", ("magnetometer", "IMU (magnetometer passthrough)")),
    ("power monitors", ("power monitor", "battery")),
    ("airspeed", ("airspeed", "airspeed / barometer")),
    ("distance", ("distance",)),
    ("barometers", ("barometer",)),
)
OTHER = "other"
#: How many bus numbers a new instance's bus gets: PX4 numbers buses from 1.
FIRST_BUS = 1
_BUS_WORDS = {"i2c": "I2C", "spi": "SPI", "serial": "serial", "dronecan": "DroneCAN"}


def status_location(kind: str, bus_id: int, address: int) -> str:
    """Where a device is, as pilots say it: ``I2C bus 1, 0x45``, ``SPI bus 1, chip select 2``.
    PX4's ``<driver> status`` prints the same facts in this order (``Running on I2C Bus 1,
    Address 0x45``: ``I2CSPIDriverBase::print_status``, PX4-Autopilot
    platforms/common/i2c_spi_buses.cpp); the address in hex with two digits as there."""
    if kind == "i2c":
        return f"I2C bus {bus_id}, 0x{address:02X}"
    if kind == "spi":
        return f"SPI bus {bus_id}, chip select {address}"
    if kind == "dronecan":
        return f"DroneCAN interface {bus_id}, node {address}"
    if kind == "sim":
        return f"simulation, instance {address}"
    if kind == "mavlink":
        return f"MAVLink instance {bus_id}, system {address}"
    if kind == "serial":
        return f"serial port {bus_id}"
    return "no bus"


def _group(driver: Driver | None) -> str:
    kind = driver.kind if driver is not None else ""
    return next((group for group, kinds in PICKER_GROUPS if kind in kinds), OTHER)


def _needs(driver: Driver | None) -> str:
    """What a chip needs to start, in words: ``I2C, address 0x45 (the driver's default)``."""
    if driver is None:
        return "no driver declared: nothing starts it"
    ways = []
    for bus in driver.buses:
        if bus == "i2c" and driver.default_address is not None:
            ways.append(f"I2C, address 0x{driver.default_address:02X} (the driver's default)")
        else:
            ways.append(_BUS_WORDS.get(bus, bus))
    text = " or ".join(ways)
    if not driver.autostart:
        text += "; its driver does not autostart"
    return text


def _variant_starts(driver: Driver) -> dict[str, dict[str, int]]:
    """Per bus kind the driver accepts, the fields an instance put on it starts with instead
    of zeros that cannot start: bus 1 and, on I2C, the driver's default address."""
    starts: dict[str, dict[str, int]] = {}
    for bus in driver.buses:
        if bus in ("i2c", "spi"):
            starts[bus] = {"bus_id": FIRST_BUS}
        if bus == "i2c" and driver.default_address is not None:
            starts[bus]["address"] = driver.default_address
    return starts


def _instance_names(parameter: str, slots: int) -> list[str]:
    """The names of ``parameter``'s instance slots in number order, as the page shows them
    (the page composes no name: the rule is :class:`Key`'s alone)."""
    return [str(Key(parameter, n, None)) for n in range(slots)]


def picker(metadata: Mapping[str, Any], drivers: Drivers) -> list[dict[str, Any]]:
    """Every instanced structured parameter of ``metadata`` as the picker lists it, grouped
    (:data:`PICKER_GROUPS` order, then "other") and by chip name within a group. ``start``
    is what a new instance is staged with: the driver's first bus kind (``bus``) and, per bus
    kind it accepts, the fields that differ from the DSDL defaults (``variants``). ``order``
    is the driver's start order (None without a driver); ``instances`` names each instance
    slot (``INA238#0`` ...), by number."""
    found = []
    for entry in metadata.get("parameters", ()):
        if entry.get("type") != "Custom" or entry.get("max_instances") is None:
            continue
        driver = drivers.for_parameter(entry["name"])
        start: dict[str, Any] = {}
        if driver is not None:
            start = {"bus": driver.buses[0], "variants": _variant_starts(driver)}
        found.append(
            {
                "parameter": entry["name"],
                "driver": driver.name if driver is not None else None,
                "chips": list(driver.chips) if driver is not None else [entry["name"]],
                "kind": driver.kind if driver is not None else "",
                "group": _group(driver),
                "order": driver.order if driver is not None else None,
                "buses": list(driver.buses) if driver is not None else [],
                "default_address": driver.default_address if driver is not None else None,
                "needs": _needs(driver),
                "start": start,
                "instances": _instance_names(entry["name"], entry["max_instances"]),
            }
        )
    order = [g for g, _ in PICKER_GROUPS] + [OTHER]
    return sorted(found, key=lambda d: (order.index(d["group"]), d["chips"][0]))


def _union_tags(fields: Sequence[Mapping[str, Any]]) -> dict[str, Mapping[str, Any]]:
    """Union tag fields by path (``bus._tag``), nested ones inside variants included."""
    found: dict[str, Mapping[str, Any]] = {}
    for f in fields:
        if f.get("role") == "union_tag":
            found[f["path"]] = f
            for variant in f.get("variants", ()):
                found.update(_union_tags(variant.get("fields", ())))
    return found


def _instance_value(
    entry: Mapping[str, Any], number: int | None, values: Mapping[str, Any]
) -> dict[str, Any]:
    """One instance's value rebuilt from its destructured flat parameters (``INA238_1B``...):
    only the selected variants' leaves, nested as ``Store.get`` returns them."""
    unions = _union_tags(entry.get("fields", ()))
    prefix = entry["name"] + "_" + ("" if number is None else str(number))
    flat = {f["path"]: values.get(prefix + f["letter"]) for f in entry.get("flat", ())}
    value: dict[str, Any] = {}
    for path, leaf in flat.items():
        if leaf is None or path.endswith(("._tag", "._len")):
            continue
        parts = path.split(".")
        selected = True
        for depth in range(1, len(parts)):
            union = ".".join(parts[:depth]) + "._tag"
            if union in unions:
                tag = flat.get(union)
                names = [v["name"] for v in unions[union].get("variants", ())]
                if not (
                    isinstance(tag, int) and 0 <= tag < len(names) and names[tag] == parts[depth]
                ):
                    selected = False
        if not selected:
            continue
        node = value
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = leaf
    return value


def _rotation_words(entry: Mapping[str, Any], rotation: int) -> str:
    """``10 (Roll 180 deg, Yaw 90 deg)``: the rotation with its name from the field's values."""
    field: Mapping[str, Any] = next(
        (f for f in entry.get("fields", ()) if f.get("path") == "rotation"), {}
    )
    name = next((v["description"] for v in field.get("values", ()) if v["value"] == rotation), "")
    return f"{rotation} ({name})" if name else str(rotation)


def board_starts(
    board: Board, c: Configured, value: Mapping[str, Any], entry: Mapping[str, Any]
) -> str | None:
    """Why device ``c`` cannot start on ``board``: the board's own script starts the same
    driver at the same place first (PX4's I2C/SPI drivers refuse a second instance there, so
    the manifest's start fails), a compass with its own ``-R`` rotation; None when it does not."""
    if c.driver is None or c.bus_kind not in ("i2c", "spi"):
        return None
    for start in board.devices:
        if start.driver != c.driver.name or start.bus_kind.lower() != c.bus_kind:
            continue
        # the hardware on which the bus is of the start's kind (a Cube's bus 2 is external)
        bus_when = dict(board.bus_conditions(start)).get(c.bus_id)
        if bus_when is None:
            continue
        address = start.address if start.address is not None else c.driver.default_address
        if c.bus_kind == "i2c" and address != c.address:
            continue
        mine = value.get("rotation")
        started = f"{start.driver} {start.args}"
        if start.kind == "mag" or start.rotation is not None or isinstance(mine, int):
            # a sensor's orientation: whose rotation PX4 uses
            started += ", no rotation given" if start.rotation is None else ", rotation "
            if start.rotation is not None:
                started += _rotation_words(entry, start.rotation)
        ours = ""
        if isinstance(mine, int):
            ours = f"; this instance's rotation {_rotation_words(entry, mine)} is not used"
        condition = " and ".join(w for w in (start.when, bus_when) if w)
        when = f" when {condition}" if condition else ""
        what = "compass" if start.kind == "mag" else c.driver.kind
        return (
            f"the board {board.label} starts this {what} itself{when} ({started}) "
            f"before the manifest{ours}"
        )
    return None


def devices(
    values: Mapping[str, Any],
    metadata: Mapping[str, Any],
    drivers: Drivers,
    board: Board | None = None,
) -> list[dict[str, Any]]:
    """The instances ``values`` configure (each parameter's ``_INST`` mask), in start order,
    each with its location in ``status`` form and the problems that would stop it starting:
    autostart's, two instances at one bus address, and on ``board`` a device its own script
    already starts."""
    entries = {
        e["name"]: e
        for e in metadata.get("parameters", ())
        if e.get("type") == "Custom" and e.get("max_instances") is not None
    }
    declared = [d.parameter for d in drivers if d.parameter in entries]
    order = declared + sorted(set(entries) - set(declared))
    found: list[Configured] = []
    stored: dict[str, dict[str, Any]] = {}
    for parameter in order:
        mask = values.get(parameter + "_INST")
        if not isinstance(mask, int):
            continue
        for n in range(entries[parameter]["max_instances"]):
            if (mask >> n) & 1:
                value = _instance_value(entries[parameter], n, values)
                name = str(Key(parameter, n, None))
                stored[name] = value
                found.append(configured_value(value, drivers, parameter, name))
    found = shared_locations(found)
    if board is not None:
        for k, c in enumerate(found):
            why = (
                None
                if c.problems
                else board_starts(board, c, stored[c.instance], entries[c.parameter])
            )
            if why is not None:
                found[k] = replace(c, problems=(why,))
    return [
        {
            "instance": c.instance,
            "parameter": c.parameter,
            "driver": c.driver.name if c.driver is not None else None,
            "kind": c.driver.kind if c.driver is not None else "",
            "location": status_location(c.bus_kind, c.bus_id, c.address),
            "problems": list(c.problems),
        }
        for c in found
    ]


def _boards() -> list[dict[str, str]]:
    """Every board of the bundled table (its newest facts), for the page's board choice; none
    when the installation has no table."""
    try:
        return [{"name": b.name, "label": b.label} for b in load_boards().all()]
    except (BoardsError, OSError):
        return []


def routes(vehicle: Any, drivers: Drivers) -> list[Route]:
    """The ``/api/manifest`` route over ``vehicle``'s metadata."""

    async def manifest(request: Request) -> Response:
        if request.method == "GET":
            return JSONResponse({"drivers": picker(vehicle.metadata, drivers), "boards": _boards()})
        try:
            body = await request.json()
            values, name = body["values"], body.get("board")
            if not isinstance(values, dict):
                raise TypeError("values is not an object")
            for key, value in values.items():
                if isinstance(value, bool) or not isinstance(value, int | float):
                    raise TypeError(f"values: {key} is {json.dumps(value)}, not a number")
            if name is not None and not isinstance(name, str):
                raise TypeError("board is not a name")
        except (ValueError, KeyError, TypeError, AttributeError) as e:
            return JSONResponse(
                {"error": f"expected {{'values': {{name: value}}, 'board': name}}: {e}"}, 400
            )
        board = None
        if name:
            try:
                board = load_boards().by_name(name)
            except BoardsError as e:
                return JSONResponse({"error": str(e)}, 400)
            if board is None:
                return JSONResponse({"error": f"board {name!r}: not in the board table"}, 400)
        return JSONResponse({"devices": devices(values, vehicle.metadata, drivers, board)})

    return [Route("/api/manifest", manifest, methods=["GET", "POST"])]
