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
    chip_id_register  optional register 0..255 the probe reads; with chip_id, or neither (a
                      probe that reads no ID: it only needs the device to answer)
    chip_id           optional value 0..65535 the probe expects in that register
    rate_hz           transfers per second once running, > 0 and <= 10000
    description       optional text
    kind              optional: what the device measures (``magnetometer``, ``airspeed``, ...)
    also_chips        optional list of other chip names the driver publishes (``SDP32``)
    started_by        optional, how today's PX4 starts the driver: ``probe`` (the default:
                      rc.sensors probes every external I2C bus), ``launcher`` (the I2C launcher
                      or the board's script) or ``parameter`` (only while ``enabled_by`` is set)
    enabled_by        optional legacy on/off parameter the manifest replaces (``SENS_EN_SDP3X``);
                      required with ``started_by = "parameter"``
    enabled_values    optional list of ``enabled_by`` values that start this driver, where
                      PX4's scripts test ``param compare <switch> <value>`` (default: values
                      above 0, PX4's ``param greater <switch> 0``; a negative value starts none)
    switch_field      optional field that takes ``enabled_by``'s value (a model number)
    settings          optional table: legacy parameter -> field path of the instance
    probe             optional text: what the probe checks when it reads no ID
    sources           optional list of PX4-Autopilot paths the facts come from

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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from px4params.data import DRIVERS_TOML
from px4params.errors import DriversFileError
from px4params.formats.keys import unknown_key
from px4params.reading import DRIVERS, not_text, read_text
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
    "rate_hz",
)
_OPTIONAL = (
    "autostart",
    "default_address",
    "chip_id_register",
    "chip_id",
    "description",
    "kind",
    "also_chips",
    "started_by",
    "enabled_by",
    "enabled_values",
    "switch_field",
    "settings",
    "probe",
    "sources",
)
#: How today's PX4 starts a driver without a manifest.
STARTED_BY = ("probe", "launcher", "parameter")
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
    chip_id_register: int | None
    chip_id: int | None
    rate_hz: float
    description: str = ""
    kind: str = ""
    also_chips: tuple[str, ...] = ()
    started_by: str = "probe"
    enabled_by: str | None = None
    enabled_values: tuple[int, ...] = ()
    switch_field: str | None = None
    #: Legacy parameter -> field path.
    settings: Mapping[str, str] = field(default_factory=dict)
    probe: str = ""
    sources: tuple[str, ...] = ()

    @property
    def chips(self) -> tuple[str, ...]:
        """Every chip name the driver publishes (drv_sensor.h's), upper case."""
        return (self.chip.upper(), *(c.upper() for c in self.also_chips))

    def starts_on(self, value: int | float) -> bool:
        """Whether today's PX4 starts the driver with ``enabled_by = value``: the script's
        ``param compare`` against each of ``enabled_values``, else its ``param greater .. 0``."""
        if self.enabled_values:
            return value in self.enabled_values
        return value > 0

    @property
    def switch_test(self) -> str:
        """The test of ``enabled_by`` that starts the driver, as the board table writes PX4's
        (``SENS_EN_INA238 == 1``, ``SENS_EN_TRANGER > 0``); "" without a switch."""
        if self.enabled_by is None:
            return ""
        if self.enabled_values:
            return " or ".join(f"{self.enabled_by} == {v}" for v in self.enabled_values)
        return f"{self.enabled_by} > 0"

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
        """Chip name (upper case) -> the first driver declaring it (``chip`` or
        ``also_chips``): how the bench's devices answer a probe, and which type a device ID's
        chip is."""
        chips: dict[str, Driver] = {}
        for d in self._list:
            for chip in d.chips:
                chips.setdefault(chip, d)
        return chips

    def switches(self) -> dict[str, list[Driver]]:
        """Legacy on/off parameter (``enabled_by``) -> the drivers it starts today."""
        found: dict[str, list[Driver]] = {}
        for d in self._list:
            if d.enabled_by:
                found.setdefault(d.enabled_by, []).append(d)
        return found

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
        text = read_text(path, DRIVERS)
    except FileNotFoundError:
        raise DriversFileError(f"{source}: no such drivers file") from None
    except OSError as e:
        raise DriversFileError(f"{source}: cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise DriversFileError(f"{source}: {not_text(e)}") from None
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
    complaint = unknown_key(table, _KEYS)
    if complaint is not None:
        raise fail(complaint)
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
        if not isinstance(kind, str) or kind not in BUS_KINDS:
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
    texts = {key: table.get(key, "") for key in ("description", "kind", "probe")}
    for key, value in texts.items():
        if not isinstance(value, str):
            raise fail(f"{key} must be a string, not {value!r}")
    if ("chip_id_register" in table) != ("chip_id" in table):
        raise fail(
            "chip_id_register and chip_id go together (or neither, for a probe that reads no ID)"
        )
    also_chips = _strings(table, "also_chips", fail)
    for other in also_chips:
        if not _CHIP.fullmatch(other):
            raise fail(f"also_chips: {other!r} is not a chip name like SDP32")
    started_by = table.get("started_by", "probe")
    if started_by not in STARTED_BY:
        raise fail(f"started_by {started_by!r} is not one of: {', '.join(STARTED_BY)}")
    enabled_by = table.get("enabled_by")
    if enabled_by is not None and (
        not isinstance(enabled_by, str) or not _PARAM.fullmatch(enabled_by)
    ):
        raise fail(
            f"enabled_by {enabled_by!r} is not an upper-case parameter name like SENS_EN_SDP3X"
        )
    if started_by == "parameter" and enabled_by is None:
        raise fail('started_by = "parameter" needs enabled_by (the parameter that starts it today)')
    enabled_values = table.get("enabled_values", [])
    if not isinstance(enabled_values, list) or not all(
        isinstance(v, int) and not isinstance(v, bool) and v != 0 for v in enabled_values
    ):
        raise fail(f"enabled_values must be a list of non-zero integers, not {enabled_values!r}")
    if enabled_values and enabled_by is None:
        raise fail("enabled_values needs enabled_by")
    settings = table.get("settings", {})
    if not isinstance(settings, dict) or not all(
        isinstance(k, str) and _PARAM.fullmatch(k) and isinstance(v, str)
        for k, v in settings.items()
    ):
        raise fail('settings must be a table of legacy parameter = "field.path"')
    switch_field = table.get("switch_field")
    if switch_field is not None and (not isinstance(switch_field, str) or enabled_by is None):
        raise fail("switch_field must be a field name, with enabled_by")
    if known is not None:
        _check_fields(
            known[parameter], [*settings.values(), *([switch_field] if switch_field else [])], fail
        )

    return Driver(
        name=str(name),
        parameter=parameter,
        chip=chip,
        autostart=autostart,
        order=order,
        buses=tuple(buses),
        default_address=default_address,
        devtype=_int(table, "devtype", 0, 255, fail),
        chip_id_register=(
            _int(table, "chip_id_register", 0, 255, fail) if "chip_id_register" in table else None
        ),
        chip_id=_int(table, "chip_id", 0, 0xFFFF, fail) if "chip_id" in table else None,
        rate_hz=float(rate),
        description=texts["description"],
        kind=texts["kind"],
        also_chips=tuple(also_chips),
        started_by=started_by,
        enabled_by=enabled_by,
        enabled_values=tuple(enabled_values),
        switch_field=switch_field,
        settings=dict(settings),
        probe=texts["probe"],
        sources=tuple(_strings(table, "sources", fail)),
    )


def _strings(table: Mapping[str, Any], key: str, fail: Any) -> list[str]:
    value = table.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise fail(f"{key} must be a list of strings, not {value!r}")
    return value


def _check_fields(spec: ParamSpec, paths: Sequence[str], fail: Any) -> None:
    """Every path names a leaf of the parameter's type (in its default value)."""
    leaves = {leaf.path for leaf in spec.data_type.leaves()}
    for path in paths:
        if path not in leaves:
            raise fail(
                f"{spec.name} has no field {path!r} (its fields: {', '.join(sorted(leaves))})"
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
