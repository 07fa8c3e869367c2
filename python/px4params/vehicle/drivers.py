"""Driver declarations: which PX4 drivers autostart from the manifest, in what order, on which
buses, and how the simulated bench recognises their chips.

The declarations live in one TOML file, ``drivers.toml`` beside this module (``--drivers FILE``
or ``$PX4PARAMS_DRIVERS`` choose another). It is the equivalent of the talk's CMakeLists.txt
entries: one ``[[driver]]`` table per driver with these keys (all required unless noted)::

    name              PX4 module name: lower case, digits, underscores (``ina238``); unique
    parameter         structured parameter whose instances ``<name> auto`` starts (``INA238``);
                      unique, and a parameter of the schema when one is given to check against
    chip              chip name as in drv_sensor.h's DRV_<KIND>_DEVTYPE_<CHIP> (``INA238``)
    autostart         optional bool, default true: listed in the generated startup script
    order             start order, an integer >= 0, lower first; unique
    buses             non-empty list of bus kinds, the variants of px.Bus:
                      i2c, spi, serial, dronecan, sim, mavlink
    default_address   I2C address 0..127 used when none is configured; required with "i2c"
    devtype           devtype code 0..255 of the published device ID (today's drv_sensor.h)
    chip_id_register  register 0..255 the probe reads
    chip_id           value 0..65535 the probe expects in that register
    rate_hz           transfers per second once running, > 0 and <= 10000
    description       optional text

Every problem is a :class:`DriversFileError` whose text is one line naming the file, the driver
and what is wrong, e.g. ``drivers.toml: driver 'ina238': default_address 200 is out of range
0..127``.
"""

from __future__ import annotations

import difflib
import os
import re
import tomllib
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from px4params.data import DRIVERS_TOML
from px4params.errors import DriversFileError
from px4params.store.spec import ParamSpec

__all__ = [
    "BUS_KINDS",
    "DEFAULT_DRIVERS",
    "DRIVERS_ENV",
    "Driver",
    "Drivers",
    "DriversFileError",
    "load_drivers",
    "parse_drivers",
]

#: The bundled declarations.
DEFAULT_DRIVERS = Path(DRIVERS_TOML)
#: Environment variable naming another declarations file (``--drivers FILE`` overrides it).
DRIVERS_ENV = "PX4PARAMS_DRIVERS"

#: Bus kinds (the variants of ``px.Bus``) and their PX4 device ID bus types. Note the union's
#: tag order (i2c, spi, serial, ...) is not the device ID numbering.
BUS_KINDS: dict[str, int] = {
    "i2c": 1,
    "spi": 2,
    "serial": 5,
    "dronecan": 3,
    "sim": 4,
    "mavlink": 6,
}

_NAME = re.compile(r"[a-z][a-z0-9_]*")
_PARAM = re.compile(r"[A-Z][A-Z0-9_]*")
_CHIP = re.compile(r"[A-Za-z0-9_]+")
_REQUIRED = (
    "name",
    "parameter",
    "chip",
    "order",
    "buses",
    "devtype",
    "chip_id_register",
    "chip_id",
    "rate_hz",
)
_OPTIONAL = ("autostart", "default_address", "description")
_KEYS = _REQUIRED + _OPTIONAL
MAX_RATE_HZ = 10_000


@dataclass(frozen=True)
class Driver:
    """One declared driver."""

    name: str
    parameter: str
    chip: str
    autostart: bool
    order: int
    buses: tuple[str, ...]
    default_address: int | None
    devtype: int
    chip_id_register: int
    chip_id: int
    rate_hz: float
    description: str = ""

    @property
    def auto_line(self) -> str:
        """The startup script line, ``ina238 auto``."""
        return f"{self.name} auto"

    @property
    def legacy_line(self) -> str:
        """Today's opportunistic start of the driver on external I2C buses."""
        return f"{self.name} -X -q start"


class Drivers:
    """The declarations of one file, in start order (``order``, lowest first)."""

    def __init__(self, drivers: Sequence[Driver], source: str) -> None:
        self.source = source
        self._list = sorted(drivers, key=lambda d: d.order)
        self._by_name = {d.name: d for d in self._list}
        self._by_parameter = {d.parameter: d for d in self._list}

    def __iter__(self) -> Iterator[Driver]:
        return iter(self._list)

    def __len__(self) -> int:
        return len(self._list)

    def __getitem__(self, name: str) -> Driver:
        return self._by_name[name]

    def for_parameter(self, parameter: str) -> Driver | None:
        """The driver whose ``auto`` starts instances of ``parameter``, if one is declared."""
        return self._by_parameter.get(parameter)

    def autostart(self) -> list[Driver]:
        """The drivers of the generated startup script, in order."""
        return [d for d in self._list if d.autostart]

    def chips(self) -> dict[str, Driver]:
        """Chip name (upper case) -> the first driver declaring it: how the bench's devices
        answer a probe."""
        chips: dict[str, Driver] = {}
        for d in self._list:
            chips.setdefault(d.chip.upper(), d)
        return chips

    def missing(self, specs: Sequence[ParamSpec]) -> list[str]:
        """Instanced parameters of ``specs`` that no driver starts."""
        return [s.name for s in specs if not s.shared and s.name not in self._by_parameter]


def load_drivers(
    path: str | os.PathLike[str] | None = None, specs: Sequence[ParamSpec] | None = None
) -> Drivers:
    """Reads and checks a declarations file: ``path``, else ``$PX4PARAMS_DRIVERS``, else the
    bundled one. With ``specs``, every declared parameter must be one of them."""
    if path is None:
        path = os.environ.get(DRIVERS_ENV) or DEFAULT_DRIVERS
    source = os.fspath(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise DriversFileError(f"{source}: no such drivers file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise DriversFileError(f"{source}: cannot read: {getattr(e, 'strerror', e)}") from None
    return parse_drivers(text, source, specs)


def parse_drivers(
    text: str, source: str = "<drivers>", specs: Sequence[ParamSpec] | None = None
) -> Drivers:
    """Checks declarations given as TOML text (see the module documentation)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise DriversFileError(f"{source}: not TOML: {e}") from None
    unknown = [k for k in doc if k != "driver"]
    if unknown:
        raise DriversFileError(
            f"{source}: unknown top-level key '{unknown[0]}' (expected [[driver]] tables)"
        )
    tables = doc.get("driver")
    if not isinstance(tables, list) or not tables:
        raise DriversFileError(f"{source}: no [[driver]] tables")
    known = {s.name: s for s in specs} if specs is not None else None
    drivers: list[Driver] = []
    for number, table in enumerate(tables, start=1):
        drivers.append(_driver(table, number, source, known))
    _check_unique(drivers, source)
    return Drivers(drivers, source)


def _driver(table: Any, number: int, source: str, known: Mapping[str, ParamSpec] | None) -> Driver:
    # Name the driver as soon as it has a usable name, so every later message can use it.
    name = table.get("name") if isinstance(table, dict) else None
    who = f"driver '{name}'" if isinstance(name, str) and _NAME.fullmatch(name) else None
    where = f"{source}: {who or f'driver #{number}'}"

    def fail(message: str) -> DriversFileError:
        return DriversFileError(f"{where}: {message}")

    if not isinstance(table, dict):
        raise fail("is not a table")
    for key in table:
        if key not in _KEYS:
            hint = difflib.get_close_matches(key, _KEYS, n=1)
            extra = f" (did you mean '{hint[0]}'?)" if hint else f" (expected: {', '.join(_KEYS)})"
            raise fail(f"unknown key '{key}'{extra}")
    for key in _REQUIRED:
        if key not in table:
            raise fail(f"missing key '{key}'")
    if who is None:
        raise fail(
            f"name {table['name']!r} is not a PX4 module name (lower case letters, digits, _)"
        )

    parameter = _text(table, "parameter", fail)
    if not _PARAM.fullmatch(parameter):
        raise fail(f"parameter {parameter!r} is not an upper-case parameter name like INA238")
    if known is not None:
        spec = known.get(parameter)
        if spec is None:
            hint = difflib.get_close_matches(parameter, list(known), n=1)
            extra = f" (did you mean {hint[0]}?)" if hint else ""
            raise fail(f"parameter {parameter} is not a parameter of the schema{extra}")
        if spec.shared:
            raise fail(f"parameter {parameter} is shared (has no instances to start)")
    chip = _text(table, "chip", fail)
    if not _CHIP.fullmatch(chip):
        raise fail(f"chip {chip!r} is not a chip name like INA238")

    autostart = table.get("autostart", True)
    if not isinstance(autostart, bool):
        raise fail(f"autostart must be true or false, not {autostart!r}")
    order = _int(table, "order", 0, 1_000_000, fail)

    buses = table["buses"]
    if not isinstance(buses, list) or not buses:
        raise fail(f"buses must be a non-empty list of bus kinds ({', '.join(BUS_KINDS)})")
    for kind in buses:
        if kind not in BUS_KINDS:
            raise fail(f"unknown bus kind {kind!r} (expected one of: {', '.join(BUS_KINDS)})")
    if len(set(buses)) != len(buses):
        raise fail(f"buses lists a kind twice: {buses}")

    default_address: int | None = None
    if "default_address" in table:
        default_address = _int(table, "default_address", 0, 127, fail)
    elif "i2c" in buses:
        raise fail("missing key 'default_address' (required for an i2c driver)")

    rate = table["rate_hz"]
    if isinstance(rate, bool) or not isinstance(rate, int | float):
        raise fail(f"rate_hz must be a number, not {rate!r}")
    if not 0 < rate <= MAX_RATE_HZ:
        raise fail(f"rate_hz {rate} is out of range (expected > 0 and <= {MAX_RATE_HZ})")
    description = table.get("description", "")
    if not isinstance(description, str):
        raise fail(f"description must be a string, not {description!r}")

    return Driver(
        name=str(name),
        parameter=parameter,
        chip=chip,
        autostart=autostart,
        order=order,
        buses=tuple(buses),
        default_address=default_address,
        devtype=_int(table, "devtype", 0, 255, fail),
        chip_id_register=_int(table, "chip_id_register", 0, 255, fail),
        chip_id=_int(table, "chip_id", 0, 0xFFFF, fail),
        rate_hz=float(rate),
        description=description,
    )


def _text(table: Mapping[str, Any], key: str, fail: Any) -> str:
    value = table[key]
    if not isinstance(value, str):
        raise fail(f"{key} must be a string, not {value!r}")
    return value


def _int(table: Mapping[str, Any], key: str, low: int, high: int, fail: Any) -> int:
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int):
        raise fail(f"{key} must be an integer, not {value!r}")
    if not low <= value <= high:
        hexed = f", 0x{low:02X}..0x{high:02X}" if high <= 0xFFFF and high > 31 else ""
        raise fail(f"{key} {value} is out of range {low}..{high}{hexed}")
    return value


def _check_unique(drivers: Sequence[Driver], source: str) -> None:
    seen: dict[tuple[str, Any], str] = {}
    for d in drivers:
        for key, value in (("name", d.name), ("parameter", d.parameter), ("order", d.order)):
            other = seen.get((key, value))
            if other is not None:
                what = "is declared twice" if key == "name" else f"{key} {value} is also {other}'s"
                raise DriversFileError(f"{source}: driver '{d.name}': {what}")
            seen[(key, value)] = d.name
