"""Autostart from the manifest: the generated startup script and each driver's plan.

The talk's build system generates a startup script of ``<driver> auto`` lines, one per driver
that declares autostart, in declared order. The script is made at build time, before any
vehicle is configured, so it lists **every** autostart driver, configured or not: a driver's
``auto`` with no configured instance starts nothing (``ina226 auto`` on a vehicle without an
INA226). :func:`script` follows that.

At boot each ``auto`` runs the talk's loop::

    for (auto config : param_find_instances(params::INA238)) { ... module_start(cli, ...); }

:func:`configured` is that loop over a store: one :class:`Configured` per existing instance,
with its bus, address and settings, and the problems that would stop its driver from starting
(a bus kind the driver does not accept, bus number 0, ...).
"""

from __future__ import annotations

import io
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from px4params.errors import DeviceIdError, ManifestError, Px4ParamsError
from px4params.store.store import Store, default_store_path
from px4params.vehicle.devid import encode
from px4params.vehicle.drivers import BUS_KINDS, Driver, Drivers

__all__ = [
    "Configured",
    "ManifestError",
    "PlanEntry",
    "configured",
    "configured_value",
    "describe_location",
    "load_manifest",
    "plan",
    "plan_lines",
    "script",
    "shared_locations",
]

# Bus kind -> how its "address" field is called in px.Bus, and its range.
_ADDRESS_FIELD = {
    "i2c": "address",
    "spi": "chip_select",
    "sim": "instance",
    "dronecan": "node_id",
    "mavlink": "system_id",
    "serial": None,
}
_BUS_FIELD = {"i2c": "bus_id", "spi": "bus_id", "dronecan": "interface", "mavlink": "instance"}


@dataclass(frozen=True)
class Configured:
    """One configured instance, as its driver's ``auto`` finds it."""

    instance: str
    parameter: str
    driver: Driver | None
    bus_kind: str
    bus_id: int
    address: int
    settings: dict[str, Any]
    problems: tuple[str, ...] = field(default=())

    @property
    def location(self) -> str:
        """``I2C bus 1 address 0x45``."""
        return describe_location(self.bus_kind, self.bus_id, self.address)

    @property
    def device_id(self) -> int | None:
        """The 24-bit device ID the driver publishes for this instance (None without a driver,
        or when the location does not fit a device ID)."""
        if self.driver is None or self.bus_kind not in BUS_KINDS:
            return None
        try:
            return encode(BUS_KINDS[self.bus_kind], self.bus_id, self.address, self.driver.devtype)
        except DeviceIdError:
            return None

    @property
    def startable(self) -> bool:
        return self.driver is not None and self.driver.autostart and not self.problems

    def as_dict(self) -> dict[str, Any]:
        return {
            "instance": self.instance,
            "parameter": self.parameter,
            "driver": self.driver.name if self.driver else None,
            "bus": self.bus_kind,
            "bus_id": self.bus_id,
            "address": self.address,
            "location": self.location,
            "settings": self.settings,
            "problems": list(self.problems),
            "device_id": self.device_id,
        }


def describe_location(kind: str, bus_id: int, address: int) -> str:
    """Where a device is, in words: ``I2C bus 1 address 0x45``, ``SPI bus 1 chip select 2``."""
    if kind == "i2c":
        return f"I2C bus {bus_id} address 0x{address:02X}"
    if kind == "spi":
        return f"SPI bus {bus_id} chip select {address}"
    if kind == "dronecan":
        return f"DroneCAN interface {bus_id} node {address}"
    if kind == "sim":
        return f"simulation instance {address}"
    if kind == "mavlink":
        return f"MAVLink instance {bus_id} system {address}"
    return f"{kind} {bus_id}"


def script(drivers: Drivers) -> list[str]:
    """The startup script's lines: ``<driver> auto`` for every autostart driver, in order."""
    return [d.auto_line for d in drivers.autostart()]


def configured(store: Store, drivers: Drivers) -> list[Configured]:
    """Every existing instance of every parameter, in start order: instances of declared
    drivers first (by driver order, then instance number), then those no driver starts."""
    found: list[Configured] = []
    by_driver = {d.parameter for d in drivers}
    params = [d.parameter for d in drivers] + sorted(
        s.name for s in store.specs if not s.shared and s.name not in by_driver
    )
    for parameter in params:
        try:
            instances = store.instances(parameter)
        except Px4ParamsError:  # declared for a parameter this store's schema lacks
            continue
        for name in instances:
            found.append(configured_value(store.get(name), drivers, parameter, name))
    return shared_locations(found)


def shared_locations(found: Sequence[Configured]) -> list[Configured]:
    """``found`` (in start order) with each instance at a bus address an earlier one already
    has marked: both would talk to the same device, so only the first starts."""
    marked = list(found)
    taken: dict[tuple[str, int, int], str] = {}
    for n, c in enumerate(marked):
        if c.problems or c.bus_kind not in ("i2c", "spi"):
            continue
        key = (c.bus_kind, c.bus_id, c.address)
        if key in taken:
            marked[n] = replace(c, problems=(f"{c.location} is already {taken[key]}'s",))
        else:
            taken[key] = c.instance
    return marked


def configured_value(value: Any, drivers: Drivers, parameter: str, name: str) -> Configured:
    """Instance ``name`` of ``parameter`` holding ``value`` (as ``Store.get`` returns it), as
    its driver's ``auto`` finds it, with what would stop the driver from starting it."""
    driver = drivers.for_parameter(parameter)
    bus = value.get("bus") if isinstance(value, dict) else None
    problems: list[str] = []
    kind, bus_id, address = "none", 0, 0
    if isinstance(bus, dict) and len(bus) == 1:
        kind, fields = next(iter(bus.items()))
        bus_field, address_field = _BUS_FIELD.get(kind), _ADDRESS_FIELD.get(kind)
        bus_id = int(fields.get(bus_field, 0)) if bus_field else 0
        address = int(fields.get(address_field, 0)) if address_field else 0
        if kind == "serial":
            bus_id = int(fields.get("port", 0))
    else:
        problems.append("its value has no bus")
    settings = {
        k: v for k, v in (value.items() if isinstance(value, dict) else ()) if k not in _SKIPPED
    }
    if driver is None:
        problems.append(f"no driver declared for parameter {parameter}")
    elif not driver.autostart:
        problems.append(f"driver {driver.name} does not autostart")
    elif kind in BUS_KINDS and kind not in driver.buses:
        problems.append(
            f"bus kind {kind} is not accepted by {driver.name} (accepts: {', '.join(driver.buses)})"
        )
    elif kind in ("i2c", "spi") and bus_id == 0:
        problems.append(f"{kind} bus_id is 0 (unset; buses are numbered from 1)")
    elif kind == "i2c" and not 0x03 <= address <= 0x77:
        problems.append(f"I2C address 0x{address:02X} is reserved (use 0x03..0x77)")
    return Configured(
        instance=name,
        parameter=parameter,
        driver=driver,
        bus_kind=kind,
        bus_id=bus_id,
        address=address,
        settings=settings,
        problems=tuple(problems),
    )


_SKIPPED = ("p_version", "bus")


@dataclass(frozen=True)
class PlanEntry:
    """One driver of the plan and the instances its ``auto`` starts."""

    driver: Driver | None
    parameter: str
    instances: tuple[Configured, ...]

    def as_dict(self) -> dict[str, Any]:
        d = self.driver
        return {
            "driver": d.name if d else None,
            "parameter": self.parameter,
            "autostart": d.autostart if d else False,
            "order": d.order if d else None,
            "devtype": d.devtype if d else None,
            "instances": [c.as_dict() for c in self.instances],
        }


def plan(store: Store, drivers: Drivers) -> list[PlanEntry]:
    """Per declared driver, in start order, the instances its ``auto`` starts (possibly none);
    then parameters with instances but no declared driver."""
    entries: list[PlanEntry] = []
    found = configured(store, drivers)
    for d in drivers:
        mine = tuple(c for c in found if c.parameter == d.parameter)
        entries.append(PlanEntry(d, d.parameter, mine))
    declared = {d.parameter for d in drivers}
    for parameter in dict.fromkeys(c.parameter for c in found if c.parameter not in declared):
        mine = tuple(c for c in found if c.parameter == parameter)
        entries.append(PlanEntry(None, parameter, mine))
    return entries


def format_settings(settings: dict[str, Any]) -> str:
    """``current=200 shunt=0.0003``: floats to float16-ish precision, nested values as JSON."""
    parts = []
    for k, v in settings.items():
        if isinstance(v, float):
            shown = f"{v:.5g}"
        elif isinstance(v, dict | list):
            shown = json.dumps(v, separators=(",", ":"))
        else:
            shown = str(v).lower() if isinstance(v, bool) else str(v)
        parts.append(f"{k}={shown}")
    return " ".join(parts)


# -- where the manifest comes from ---------------------------------------------------------------


def load_manifest(
    store_path: str | os.PathLike[str] | None,
    airframe: str | os.PathLike[str] | None = None,
    dsdl: Sequence[str] = (),
) -> Store:
    """The manifest to boot. With ``airframe``: a fresh store with the file run on it by
    ``px4params run``'s interpreter (nothing is saved). Otherwise the store file ``store_path``
    (default: ``$PX4PARAMS_STORE``, else ``./px4params.store``), which must exist."""
    from px4params.dsdl.schema import load_schema
    from px4params.errors import CommandError
    from px4params.nsh.airframe import run_file
    from px4params.store.classic import BUNDLED_CLASSIC, CLASSIC_ENV
    from px4params.store.session import Session, open_session

    if airframe is None:
        path = os.fspath(store_path) if store_path is not None else default_store_path()
        if not Path(path).is_file():
            raise ManifestError(
                f"no store file {path} (write one with 'px4params run AIRFRAME --store {path}', "
                "or give --store FILE or --airframe FILE)"
            )
        return open_session(path, None, dsdl).store

    class Unsaved(Session):
        """A session whose store is never written: the airframe only builds the manifest."""

        def save(self) -> None:
            self.changed = False

    # The same parameter set as 'px4params param' and 'px4params run' use.
    schema = load_schema(list(dsdl), include_dronecan=False)
    classic = os.environ.get(CLASSIC_ENV) or BUNDLED_CLASSIC
    session = Unsaved(Store(schema, classic=classic), "", io.StringIO())
    errors = io.StringIO()
    try:
        result = run_file(os.fspath(airframe), session, keep_going=False, err=errors)
    except CommandError as e:
        raise ManifestError(str(e)) from None
    if result.errors:
        raise ManifestError(result.errors[0])
    return session.store


def plan_lines(entries: Sequence[PlanEntry]) -> list[str]:
    """The plan as text, one driver header then one line per instance; the drivers with
    nothing to start are named together on the last line."""
    lines: list[str] = []
    idle: list[str] = []
    for e in entries:
        d = e.driver
        if d is not None and not e.instances:
            idle.append(d.name)
            continue
        if d is None:
            lines.append(f"(no driver) parameter {e.parameter}: {len(e.instances)} instance(s)")
        else:
            auto = "" if d.autostart else ", no autostart"
            count = len(e.instances)
            lines.append(
                f"{d.name} auto  (order {d.order}, parameter {d.parameter}, "
                f"devtype 0x{d.devtype:02X}{auto}): "
                + f"{count} instance{'s' if count != 1 else ''}"
            )
        for c in e.instances:
            ident = c.device_id
            if c.problems:
                tail = "NOT STARTED: " + "; ".join(c.problems)
            elif ident is not None:
                tail = f"device id {ident} (0x{ident:06X})"
            else:
                tail = ""
            settings = format_settings(c.settings)
            lines.append(f"  {c.instance:<12} {c.location:<24} {settings}  {tail}".rstrip())
    if idle:
        lines.append(f"nothing to start ({len(idle)} drivers): {', '.join(idle)}")
    return lines
