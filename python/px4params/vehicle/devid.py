"""PX4 device IDs: the 24-bit numbers in ``CAL_MAG0_ID`` and friends.

Layout, least significant bits first (PX4's ``DeviceStructure``)::

    bits  0-2   bus type   0 unknown, 1 I2C, 2 SPI, 3 UAVCAN, 4 simulation, 5 serial, 6 MAVLink
    bits  3-7   bus        which instance of that bus type (0..31)
    bits  8-15  address    I2C address, SPI chip-select slot, UAVCAN node ID, ...
    bits 16-23  devtype    which chip; the meaning of a code depends on the firmware version

Devtype tables (which chip a code names) changed between PX4 releases, so two are available:

``legacy``
    The table of the PX4 driver guide's "Device IDs" page, transcribed below as our own data.
``px4-v1.6``, ``px4-v1.8``, ``px4-v1.11``, ``px4-v1.13``
    ``drv_sensor.h`` as PX4 1.6-1.7, 1.8-1.10, 1.11-1.12 and 1.13 had it (shipped in
    ``data/devtypes``, each file saying where it was read). ``decode_log`` reads a log with
    the table of its firmware version (``ver_sw_release``) unless told otherwise: a 2017 log's
    ``0x37`` is an ICM20602, today's a BMI270. A device whose devtype is of another sensor kind
    than its parameter (a FLOW code in ``CAL_ACC0_ID``) is flagged.
``current``
    Today's ``drv_sensor.h`` (PX4 1.14 and later), shipped as ``data/devtypes/current.tsv``
    (naming the PX4-Autopilot commit it was read from). Another file can be given instead:
    the ``path`` argument (the CLI's ``--devtypes FILE``) or ``$PX4PARAMS_DEVTYPES``. Such a
    file is either a TSV (``code<TAB>name`` per line, an optional ``code<TAB>name`` header,
    codes decimal or ``0x`` hex) or a PX4 ``drv_sensor.h`` (its ``#define DRV_..._DEVTYPE_...
    0x..`` lines); the format is recognised from the content.

Which table a file's IDs follow (the era rule): the firmware version it names (a log's
``ver_sw_release``, a QGC file's ``# Version:`` line; :func:`table_for_version`), else what the
parameters show (:func:`table_for_parameters`): ``CAL_<S>n_PRIO`` exist from PX4 1.12 on, so
today's table; without them the file predates a version in logs and QGC files (PX4 < 1.6 for
logs), read with ``px4-v1.6``, which names every code the driver guide's table names the same.

Name normalization: a macro ``DRV_<KIND>_DEVTYPE_<NAME>`` becomes name ``NAME`` and kind ``KIND``
(``DRV_MAG_DEVTYPE_AK09916`` is ``AK09916``, kind ``MAG``; ``DRV_DIFF_PRESS_DEVTYPE_SIM`` is
``SIM``, kind ``DIFF_PRESS``); ``DRV_DEVTYPE_<NAME>`` has no kind; any other spelling is kept as
given (upper-cased). A code that several macros share (0xE9 in today's header) keeps all of them,
shown joined with ``/`` (``ILABS/RGBLED_AW2023``, kind ``INS/LED``). Looking a devtype up by name
accepts, case-insensitively, the macro, ``KIND_NAME`` (``MAG_AK09916``) or the bare name when it
names one code only.

``decode_log`` reads every ``CAL_<sensor><n>_ID`` parameter of a ULog flight log (and the
``CAL_<sensor>_PRIME`` selectors, which hold a device ID too) with pyulog. An ID of 0 means
"no device".
"""

from __future__ import annotations

import difflib
import functools
import math
import os
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from px4params.errors import DeviceIdError, NumberError, ULogError
from px4params.numbers import abbreviated, parse_int

if TYPE_CHECKING:
    from px4params.formats.ulog import ULogHeader
from px4params.reading import DEVTYPES, read_text

__all__ = [
    "BUS_TYPES",
    "DEVTYPES_ENV",
    "MAX_DEVICE_ID",
    "DeviceId",
    "Devtype",
    "DevtypeTable",
    "LogDeviceId",
    "decode",
    "decode_log",
    "encode",
    "find_current_table",
    "kind_mismatch",
    "legacy_table",
    "load_table",
    "parse_device_id",
    "parse_devtypes",
    "table_for_parameters",
    "table_for_release",
    "table_for_version",
]

MAX_DEVICE_ID = (1 << 24) - 1
DEVTYPES_ENV = "PX4PARAMS_DEVTYPES"
#: Tables of older releases: label -> (first, last) release line as (major, minor), from
#: ``data/devtypes``. A line is every patch release of it: ver_sw_release's patch byte goes to
#: 255, so no patch number can be an end.
ERA_TABLES: dict[str, tuple[tuple[int, int], tuple[int, int]]] = {
    "px4-v1.6": ((1, 6), (1, 7)),
    "px4-v1.8": ((1, 8), (1, 10)),
    "px4-v1.11": ((1, 11), (1, 12)),
    "px4-v1.13": ((1, 13), (1, 13)),
}
TABLES = ("legacy", "current", *ERA_TABLES)
#: The sensor kinds (devtype macro kinds) a calibration parameter's device may have. An IMU's
#: devtype is on every sensor of the chip: PX4's ADIS16448 driver publishes its magnetometer and
#: barometer with the IMU's device ID (DRV_IMU_DEVTYPE_ADIS16448; PX4/PX4-Autopilot
#: src/drivers/imu/analog_devices/adis16448/ADIS16448.cpp, 61d97e5).
_KINDS_OF = {
    "ACC": {"ACC", "IMU"},
    "GYRO": {"GYR", "GYRO", "IMU"},
    "MAG": {"MAG", "IMU"},
    "BARO": {"BARO", "IMU"},
}

#: Bus type codes (3 bits) and their names; code 7 is representable but has no name.
BUS_TYPES: dict[int, str] = {
    0: "unknown",
    1: "I2C",
    2: "SPI",
    3: "UAVCAN",
    4: "simulation",
    5: "serial",
    6: "MAVLink",
}
# Spellings people use on the command line for the same bus types.
_BUS_TYPE_ALIASES = {"sim": 4, "dronecan": 3, "can": 3, "uart": 5}

# Field widths and positions, as (name, shift, bits).
_FIELDS = (("bus type", 0, 3), ("bus", 3, 5), ("address", 8, 8), ("devtype", 16, 8))


_MACRO = re.compile(r"DRV_(?:(?P<kind>[A-Z0-9_]+?)_)?DEVTYPE_(?P<name>[A-Z0-9_]+)")
_DEFINE = re.compile(r"^\s*#\s*define\s+(?P<macro>DRV_\w*DEVTYPE\w*)\s+(?P<value>[^\s/]+)")
_NUMBER = re.compile(r"0[xX][0-9a-fA-F]+|[0-9]+")


@dataclass(frozen=True)
class Devtype:
    """One row of a devtype table: ``code`` names chip ``name`` of sensor class ``kind``."""

    code: int
    name: str
    kind: str | None = None

    @property
    def qualified(self) -> str:
        """``KIND_NAME``, unique within one table where the bare name may not be."""
        return f"{self.kind}_{self.name}" if self.kind else self.name

    @property
    def macro(self) -> str:
        """The ``drv_sensor.h`` spelling."""
        return f"DRV_{self.kind}_DEVTYPE_{self.name}" if self.kind else f"DRV_DEVTYPE_{self.name}"


def _normalize(raw: str, code: int) -> Devtype:
    text = raw.strip().upper()
    m = _MACRO.fullmatch(text)
    if m:
        return Devtype(code, m["name"], m["kind"])
    return Devtype(code, text)


class DevtypeTable:
    """Devtype codes (0..255) to chip names; a code may have several entries."""

    def __init__(self, label: str, source: str, entries: Iterable[Devtype]) -> None:
        self.label = label
        self.source = source
        self._by_code: dict[int, tuple[Devtype, ...]] = {}
        for entry in entries:
            have = self._by_code.get(entry.code, ())
            if entry not in have:  # a file may repeat a row; keep one
                self._by_code[entry.code] = (*have, entry)

    def __repr__(self) -> str:
        return f"DevtypeTable({self.label!r}, {self.source!r}, {len(self._by_code)} codes)"

    def __iter__(self) -> Iterator[Devtype]:
        for code in sorted(self._by_code):
            yield from self._by_code[code]

    def __len__(self) -> int:
        """The number of distinct codes."""
        return len(self._by_code)

    def lookup(self, code: int) -> tuple[Devtype, ...]:
        return self._by_code.get(code, ())

    def name_of(self, code: int) -> str | None:
        """The chip name(s) for ``code``, joined with ``/``, or None when the table lacks it."""
        entries = self.lookup(code)
        return "/".join(e.name for e in entries) if entries else None

    def kind_of(self, code: int) -> str | None:
        kinds = [e.kind for e in self.lookup(code) if e.kind]
        return "/".join(dict.fromkeys(kinds)) if kinds else None

    def resolve(self, name: str) -> int:
        """The code of a devtype given by macro, ``KIND_NAME`` or bare name (case-insensitive)."""
        key = name.strip().upper()
        exact = {e.code: e for e in self if key in (e.macro, e.qualified)}
        found = exact or {e.code: e for e in self if e.name == key}
        if len(found) == 1:
            return next(iter(found))
        if found:
            options = ", ".join(f"{e.qualified} (0x{e.code:02X})" for e in found.values())
            raise DeviceIdError(
                f"devtype {name!r} is ambiguous in the {self.label} table: "
                f"give one of {options}, or a code"
            )
        spellings = sorted({s for e in self for s in (e.name, e.qualified)})
        close = difflib.get_close_matches(key, spellings, n=3)
        hint = f"did you mean {', '.join(close)}? " if close else ""
        raise DeviceIdError(
            f"unknown devtype {name!r} in the {self.label} table ({hint}give a code 0..255 "
            f"or a name from 'px4params devid --list --table {self.label}')"
        )


# The driver guide's devtype table, as (code, kind, name). The later revision of the page adds
# the simulator codes 0x03, 0x14, 0x15 and 0x23 to the earlier one; both agree on the rest.
_LEGACY_ROWS: tuple[tuple[int, str, str], ...] = (
    (0x01, "MAG", "HMC5883"),
    (0x02, "MAG", "LSM303D"),
    (0x03, "MAG", "ACCELSIM"),  # the guide's spelling for the simulated magnetometer
    (0x04, "MAG", "MPU9250"),
    (0x11, "ACC", "LSM303D"),
    (0x12, "ACC", "BMA180"),
    (0x13, "ACC", "MPU6000"),
    (0x14, "ACC", "ACCELSIM"),
    (0x15, "ACC", "GYROSIM"),
    (0x16, "ACC", "MPU9250"),
    (0x21, "GYR", "MPU6000"),
    (0x22, "GYR", "L3GD20"),
    (0x23, "GYR", "GYROSIM"),
    (0x24, "GYR", "MPU9250"),
    (0x31, "RNG", "MB12XX"),
    (0x32, "RNG", "LL40LS"),
)


@functools.cache
def legacy_table() -> DevtypeTable:
    """The PX4 driver guide's devtype table."""
    rows = (Devtype(code, name, kind) for code, kind, name in _LEGACY_ROWS)
    return DevtypeTable("legacy", "the PX4 driver guide", rows)


def _parse_code(token: str, where: str) -> int:
    token = token.strip().strip("()").rstrip("uUlL")
    if not _NUMBER.fullmatch(token):
        raise DeviceIdError(f"{where}: devtype code {token!r} is not a number")
    try:
        code = parse_int(token, 16 if token[:2].lower() == "0x" else 10)
    except NumberError as e:
        raise DeviceIdError(f"{where}: devtype code {e}") from None
    if code > 0xFF:
        raise DeviceIdError(f"{where}: devtype code {token} is out of range 0..255 (0x00..0xFF)")
    return code


def parse_devtypes(text: str, source: str = "<devtypes>") -> list[Devtype]:
    """Rows of a TSV (``code<TAB>name``) or of a ``drv_sensor.h``, told apart by the content."""
    lines = text.splitlines()
    rows: list[Devtype] = []
    if any(re.match(r"\s*#\s*define\s", line) for line in lines):
        for number, line in enumerate(lines, start=1):
            m = _DEFINE.match(line)
            if m:
                code = _parse_code(m["value"], f"{source}:{number}")
                rows.append(_normalize(m["macro"], code))
    else:
        for number, line in enumerate(lines, start=1):
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            fields = line.split("\t")
            if [f.strip().lower() for f in fields] == ["code", "name"]:
                continue  # the header row
            if len(fields) != 2 or not fields[1].strip():
                raise DeviceIdError(
                    f"{source}:{number}: expected 'code<TAB>name' "
                    f"(e.g. '0x09<TAB>DRV_MAG_DEVTYPE_AK09916'), got {line.strip()!r}"
                )
            rows.append(_normalize(fields[1], _parse_code(fields[0], f"{source}:{number}")))
    if not rows:
        raise DeviceIdError(
            f"{source}: no devtypes found (expected 'code<TAB>name' lines or a drv_sensor.h "
            "with '#define DRV_..._DEVTYPE_... 0x..' lines)"
        )
    return rows


def find_current_table(path: str | os.PathLike[str] | None = None) -> Path:
    """The file the current devtype table is read from (see the module documentation)."""
    from px4params.data import DEVTYPES_DIR

    if path is not None:
        given, origin = Path(path), "devtypes file"
    elif os.environ.get(DEVTYPES_ENV):
        given, origin = Path(os.environ[DEVTYPES_ENV]), f"${DEVTYPES_ENV}"
    else:
        return Path(DEVTYPES_DIR, "current.tsv")
    if not given.exists():  # (what exists but is no file, reading names: a folder, a FIFO)
        raise DeviceIdError(f"{origin} not found: {given}")
    return given


# Keyed by the file's identity and modification time, so an edited file is read again.
@functools.lru_cache(maxsize=8)
def _read_table(path: str, _mtime_ns: int, _size: int) -> DevtypeTable:
    try:
        text = read_text(path, DEVTYPES, errors="replace")
    except OSError as e:
        raise DeviceIdError(f"cannot read devtypes file {path}: {e.strerror}") from None
    return DevtypeTable("current", path, parse_devtypes(text, path))


def load_table(which: str = "current", path: str | os.PathLike[str] | None = None) -> DevtypeTable:
    """The ``legacy`` table, a release's (``px4-v1.6`` ...), or the ``current`` one read from
    ``path`` or the usual places."""
    if which == "legacy":
        return legacy_table()
    if which in ERA_TABLES:
        return _era_table(which)
    if which != "current":
        raise DeviceIdError(
            f"unknown devtype table {which!r} (expected one of: {', '.join(TABLES)})"
        )
    found = find_current_table(path)
    try:
        stat = found.stat()
    except OSError as e:
        raise DeviceIdError(f"cannot read devtypes file {found}: {e.strerror}") from None
    return _read_table(str(found), stat.st_mtime_ns, stat.st_size)


@functools.cache
def _era_table(label: str) -> DevtypeTable:
    from px4params.data import DEVTYPES_DIR

    path = os.path.join(DEVTYPES_DIR, f"{label}.tsv")
    with open(path, encoding="utf-8") as f:
        return DevtypeTable(label, path, parse_devtypes(f.read(), path))


def table_for_version(version: tuple[int, int, int]) -> str:
    """The table of firmware ``version`` (major, minor, patch): a release's table where one is
    shipped, ``legacy`` before 1.6, ``current`` from 1.14 on."""
    for label, (first, last) in ERA_TABLES.items():
        if first <= version[:2] <= last:
            return label
    return "legacy" if version < (1, 6, 0) else "current"


def table_for_release(release: int | None, params: Mapping[str, Any] | None = None) -> str:
    """The table for a log of firmware ``release`` (ULog's ``ver_sw_release``: major, minor,
    patch and type in its four bytes); without one, the era rule of :func:`table_for_parameters`
    (``params``, the log's parameters; none given: ``px4-v1.6``)."""
    if not release:
        return table_for_parameters(params or {})[0]
    return table_for_version((release >> 24 & 0xFF, release >> 16 & 0xFF, release >> 8 & 0xFF))


#: Parameters PX4 has from 1.12 on: ``CAL_ACC0_PRIO`` ... (the priority that replaced ``_EN``).
_PRIO_PARAM = re.compile(r"CAL_(ACC|GYRO|MAG|BARO)\d_PRIO")


#: Parameters PX4 1.13 did not have and later releases do: a file holding one is of PX4 1.14 or
#: later, whatever else it lacks (a ``param set-default`` list never names a version, and a
#: docs asset holds only the parameters of its vehicle's tuning, often no ``CAL_*`` at all).
#: Each defined in PX4-Autopilot main (read in dakejahl/PX4-Autopilot
#: bb59c637cd74e04c000a0b8e35aac184251150d6) at the path given, and absent from the whole tree
#: of the v1.13 release line (aviant-tech/PX4-Autopilot 6308d5d260855f05b93e9e166e74bd806e434cd9,
#: v1.13.2 to 1.13.6), which has no msp_osd driver at all, and from older trees (2016:
#: bkueng/PX4-Autopilot 954a59ebbe; v1.11.3: auxoncorp/PX4-Autopilot 0e01909469).
AFTER_PX4_1_13: dict[str, str] = {
    "OSD_SYMBOLS": "src/drivers/osd/msp_osd/module.yaml",
    "OSD_SCROLL_RATE": "src/drivers/osd/msp_osd/module.yaml",
    "MPC_VEL_MAN_SIDE": "src/modules/mc_pos_control/multicopter_position_mode_params.yaml",
    "FW_THR_ASPD_MIN": "src/lib/fw_performance_model/performance_model_params.yaml",
    "FW_T_THR_DAMPING": "src/modules/fw_lateral_longitudinal_control/fw_lat_long_params.yaml",
}


def table_for_parameters(params: Mapping[str, Any]) -> tuple[str, str]:
    """The table for a file that names no firmware version, decided from its parameters, and
    why (one line for the report)."""
    newer = sorted(n for n in params if n in AFTER_PX4_1_13)
    if newer:
        return "current", (
            f"no firmware version: {newer[0]} exists (PX4 1.14 and later; not in 1.13, "
            f"{AFTER_PX4_1_13[newer[0]]}), so today's devtype table is assumed"
        )
    prio = sorted(n for n in params if _PRIO_PARAM.fullmatch(n))
    if prio:
        return "current", (
            f"no firmware version: {prio[0]} exists (PX4 1.12 and later), so today's devtype "
            "table is assumed"
        )
    return "px4-v1.6", (
        "no firmware version and no CAL_*_PRIO parameters (PX4 before 1.12): the px4-v1.6 "
        "devtype table is assumed (files without a version predate it: ULog's ver_sw_release "
        "and QGC's '# Version' came with PX4 1.6)"
    )


def kind_mismatch(param: str, device: DeviceId) -> str | None:
    """Why ``device`` cannot be what calibration parameter ``param`` holds (a flow sensor's
    devtype in ``CAL_ACC0_ID``: the table is probably of another era), or None."""
    sensor = re.fullmatch(r"CAL_([A-Z]+?)\d*_ID", param)
    if sensor is None or device.no_device or not device.devtype_kind:
        return None
    allowed = _KINDS_OF.get(sensor[1])
    kinds = set(device.devtype_kind.split("/"))
    if allowed is None or kinds & allowed:
        return None
    return (
        f"devtype 0x{device.devtype:02X} is {device.devtype_kind} in the {device.table} table, "
        f"which does not fit {param} ({'/'.join(sorted(allowed))}): the log may be of another "
        "era (--table)"
    )


def _table(table: DevtypeTable | str | None) -> DevtypeTable | None:
    return load_table(table) if isinstance(table, str) else table


@dataclass(frozen=True)
class DeviceId:
    """A decoded device ID. ``devtype_name``/``bus_type_name`` are None when not known."""

    value: int
    bus_type: int
    bus_type_name: str | None
    bus: int
    address: int
    devtype: int
    devtype_name: str | None
    devtype_kind: str | None
    table: str | None  # the label of the table the devtype was looked up in

    def __int__(self) -> int:
        return self.value

    @property
    def no_device(self) -> bool:
        """PX4 stores 0 for a calibration slot with no sensor."""
        return self.value == 0

    @property
    def hex(self) -> str:
        return f"0x{self.value:06X}"

    def describe(self) -> str:
        """One line such as ``AK09916 (MAG), I2C bus 1, address 0x0C``."""
        if self.no_device:
            return "no device"
        if self.devtype_name is not None:
            chip = self.devtype_name + (f" ({self.devtype_kind})" if self.devtype_kind else "")
        else:
            chip = f"devtype 0x{self.devtype:02X}"
            if self.table:
                chip += f" (not in the {self.table} table)"
        # Types 0 and 7 name no bus kind, so say the code rather than "unknown bus 0".
        named = self.bus_type_name if self.bus_type in range(1, 7) else None
        bus = f"{named} bus {self.bus}" if named else f"bus type {self.bus_type}, bus {self.bus}"
        # The address byte means different things per bus type, as the driver guide shows.
        if self.bus_type == 2:
            at = f"device {self.address}"
        elif self.bus_type == 3:
            at = f"node {self.address}"
        else:
            at = f"address 0x{self.address:02X}"
        return f"{chip}, {bus}, {at}"

    def as_dict(self) -> dict[str, Any]:
        return {
            "id": self.value,
            "hex": self.hex,
            "no_device": self.no_device,
            "bus_type": self.bus_type,
            "bus_type_name": self.bus_type_name,
            "bus": self.bus,
            "address": self.address,
            "devtype": self.devtype,
            "devtype_name": self.devtype_name,
            "devtype_kind": self.devtype_kind,
            "table": self.table,
            "description": self.describe(),
        }


def _check_id(value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise DeviceIdError(f"a device ID is an int, not {type(value).__name__}")
    if not 0 <= value <= MAX_DEVICE_ID:
        raise DeviceIdError(
            f"device ID {value} does not fit in 24 bits (expected 0..{MAX_DEVICE_ID}, "
            f"0x000000..0x{MAX_DEVICE_ID:06X})"
        )
    return value


def parse_device_id(text: str) -> int:
    """A device ID written in decimal, ``0x`` hex, or as an integral float (``73225.0``, as old
    ``.px4log`` dumps print parameters)."""
    token = text.strip()
    value: int | None = None
    try:
        if re.fullmatch(r"[+-]?0[xX][0-9a-fA-F]+", token):
            value = parse_int(token, 16)
        elif re.fullmatch(r"[+-]?[0-9]+", token):
            value = parse_int(token, 10)
        elif re.fullmatch(r"[+-]?[0-9]+\.0*", token):
            value = parse_int(token.partition(".")[0], 10)
    except NumberError as e:
        raise DeviceIdError(f"not a device ID: {e}") from None
    if value is None:
        raise DeviceIdError(
            f"not a device ID: '{abbreviated(text)}' (expected decimal, 0x hex or a whole number "
            f"such as 73225.0, 0..{MAX_DEVICE_ID})"
        )
    return _check_id(value)


def decode(value: int, table: DevtypeTable | str | None = "current") -> DeviceId:
    """Split a 24-bit device ID into its fields, naming the devtype from ``table`` (``"legacy"``,
    ``"current"``, a loaded table, or None for no names)."""
    _check_id(value)
    bus_type, bus, address, devtype = (
        (value >> shift) & ((1 << bits) - 1) for _, shift, bits in _FIELDS
    )
    names = _table(table)
    return DeviceId(
        value=value,
        bus_type=bus_type,
        bus_type_name=BUS_TYPES.get(bus_type),
        bus=bus,
        address=address,
        devtype=devtype,
        devtype_name=names.name_of(devtype) if names else None,
        devtype_kind=names.kind_of(devtype) if names else None,
        table=names.label if names else None,
    )


def _number(value: int | str, what: str, bits: int) -> int:
    """``value`` as an int in the field's range; strings may be decimal or ``0x`` hex."""
    top = (1 << bits) - 1
    if isinstance(value, str):
        token = value.strip()
        if not _NUMBER.fullmatch(token.lstrip("+-")):
            raise DeviceIdError(f"{what} {value!r} is not a number (expected 0..{top})")
        try:
            number = parse_int(token, 16 if token.lstrip("+-")[:2].lower() == "0x" else 10)
        except NumberError as e:
            raise DeviceIdError(f"{what}: {e}") from None
        shown = token
    elif isinstance(value, bool) or not isinstance(value, int):
        raise DeviceIdError(f"{what} must be an int, not {type(value).__name__}")
    else:
        number, shown = value, str(value)
    if not 0 <= number <= top:
        extra = f", 0x00..0x{top:02X}" if bits == 8 else ""
        raise DeviceIdError(f"{what} {shown} is out of range 0..{top}{extra}")
    return number


def _bus_type(value: int | str) -> int:
    if isinstance(value, str) and not _NUMBER.fullmatch(value.strip().lstrip("+-")):
        key = value.strip().lower()
        for code, name in BUS_TYPES.items():
            if name.lower() == key:
                return code
        if key in _BUS_TYPE_ALIASES:
            return _BUS_TYPE_ALIASES[key]
        names = ", ".join(n.lower() for n in BUS_TYPES.values())
        raise DeviceIdError(f"unknown bus type {value!r} (expected one of: {names}, or 0..7)")
    return _number(value, "bus type", 3)


def encode(
    bus_type: int | str,
    bus: int | str,
    address: int | str,
    devtype: int | str,
    table: DevtypeTable | str | None = None,
) -> int:
    """Build a device ID. Strings are accepted for every part: numbers in decimal or ``0x`` hex,
    bus types by name (``i2c``, ``spi``, ...), devtypes by name looked up in ``table`` (default:
    the current table, loaded only when a name needs it)."""
    if isinstance(devtype, str) and not _NUMBER.fullmatch(devtype.strip().lstrip("+-")):
        devtype = (_table(table) or load_table("current")).resolve(devtype)
    parts = (
        _bus_type(bus_type),
        _number(bus, "bus", 5),
        _number(address, "address", 8),
        _number(devtype, "devtype", 8),
    )
    value = 0
    for part, (_, shift, _bits) in zip(parts, _FIELDS, strict=True):
        value |= part << shift
    return value


@dataclass(frozen=True)
class LogDeviceId:
    """One device ID parameter of a flight log.

    ``device`` is None (and ``problem`` says why) when the value is not a 24-bit device ID.
    ``timestamp_us`` is None for the value at the start of the log, else the time of a change
    logged during the flight (for example after an in-flight calibration).
    """

    param: str
    value: int | float
    device: DeviceId | None
    problem: str | None = None
    timestamp_us: int | None = None
    #: The devtype's sensor kind does not fit the parameter (see :func:`kind_mismatch`).
    warning: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "param": self.param,
            "value": self.value,
            "timestamp_us": self.timestamp_us,
            "device": self.device.as_dict() if self.device else None,
            "problem": self.problem,
            "warning": self.warning,
        }


#: Parameter names that hold device IDs: CAL_MAG0_ID, CAL_ACC1_ID, CAL_GYRO0_ID, CAL_BARO0_ID,
#: ... and the CAL_<sensor>_PRIME selectors.
LOG_PARAM = re.compile(r"CAL_[A-Z]+[0-9]*_ID|CAL_[A-Z]+_PRIME")


def _log_entry(
    param: str, value: Any, names: DevtypeTable | None, timestamp_us: int | None
) -> LogDeviceId:
    number = value
    if isinstance(value, float) and math.isfinite(value) and value.is_integer():
        number = int(value)  # very old firmware logged every parameter as a float
    if isinstance(number, int) and 0 <= number <= MAX_DEVICE_ID:
        device = decode(number, names)
        warning = kind_mismatch(param, device)
        return LogDeviceId(param, number, device, None, timestamp_us, warning)
    problem = f"{value!r} is not a 24-bit device ID"
    return LogDeviceId(param, value, None, problem, timestamp_us)


def decode_log(
    path: str | os.PathLike[str],
    table: DevtypeTable | str | None = "auto",
    devtypes: str | os.PathLike[str] | None = None,
) -> list[LogDeviceId]:
    """Every device ID parameter of a ULog file (sorted by name; changes during the log follow
    their parameter's initial value, in time order). ``table`` ``auto`` picks the table of the
    log's firmware version (:func:`table_for_release`; ``devtypes`` is the current table's
    file)."""
    from px4params.formats.ulog import read_header

    try:
        log = read_header(path)
    except ULogError as e:
        raise DeviceIdError(str(e)) from None
    return decode_header(log, table, devtypes)


def decode_header(
    log: ULogHeader,
    table: DevtypeTable | str | None = "auto",
    devtypes: str | os.PathLike[str] | None = None,
) -> list[LogDeviceId]:
    """:func:`decode_log` of a log already read (``log.corrupt``: those logged after the
    damage are missing)."""
    if table == "auto":
        table = load_table(table_for_release(log.release, log.initial_parameters), devtypes)
    names = _table(table)
    entries: list[LogDeviceId] = []
    for param in sorted(log.initial_parameters):
        if LOG_PARAM.fullmatch(param):
            value = log.initial_parameters[param]
            entries.append(_log_entry(param, value, names, None))
            for time_us, changed, new in log.changed_parameters:
                if changed == param:
                    entries.append(_log_entry(param, new, names, time_us))
    return entries
