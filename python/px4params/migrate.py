"""Migration from today's PX4 configuration to a device manifest.

Input: a QGC ``.params`` file or a ULog flight log (its parameters, read with pyulog). Output: a
proposed airframe file of ``param add`` / ``param set-default`` lines (what ``px4params run``
and, per the talk, PX4 itself run) and a report of where each line came from and of everything
that could not be carried over. Nothing is dropped silently.

What is carried over:

* **Enabled drivers** (a driver's ``enabled_by`` switch in the driver declarations,
  ``SENS_EN_SDP3X``, ``SENS_EN_INA238``, ... not 0) become an instance on I2C bus 1 (board
  scripts start power monitors as ``<driver> -X -b 1 ...``; rc.sensors starts the others on
  every external bus) at the type's default address; the switch's value goes to the declared
  ``switch_field`` (a model number), and the declared legacy settings (``INA238_CURRENT``,
  ``SF1XX_ROT``, ...) fill their fields, rounded and clamped, with a note when the value
  changes. Legacy settings without a field (``INA226_CONFIG``, ...) are listed as not carried
  over.
* **Sensors found** (the ``CAL_<SENSOR><n>_ID`` device IDs, decoded with :mod:`.devid`): an I2C
  device whose chip a declared driver publishes (``AK09916`` on I2C bus 1 at 0x0C) becomes an
  instance of that driver's type on that bus and address, with ``CAL_MAG<n>_ROT`` as its
  rotation. Today such external devices are found by probing (``SENS_EXT_I2C_PRB``); in the
  manifest they are stated.

What is reported, not carried: internal sensors (SPI, started by the board's startup script),
DroneCAN and other buses, chips without a bundled type, enabled drivers without one, and the
probing switch the manifest replaces. Every other parameter (calibration, tuning, ...) stays a
classic parameter: the count is reported.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from px4params.dsdl.schema import Schema
from px4params.errors import MigrationError, ParamFileError, Px4ParamsError
from px4params.formats import qgc_params
from px4params.reading import PARAM_FILE, ULOG, open_file, read_text
from px4params.vehicle import devid
from px4params.vehicle.drivers import Driver, load_drivers

__all__ = [
    "MigrationError",
    "OldConfig",
    "Proposal",
    "ProposedInstance",
    "migrate",
    "read_config",
]

ULOG_MAGIC = b"ULog\x01\x12\x35"
#: MAV_PARAM_TYPE codes of float parameters in QGC files (REAL32, REAL64).
#: The I2C bus board scripts start external drivers on (``-X -b 1``).
DEFAULT_I2C_BUS = 1
_CAL_ID = re.compile(r"CAL_(?P<sensor>[A-Z]+?)(?P<n>\d+)_ID")

#: ``SENS_EN_*`` parameters that are not a driver's on/off switch, with the meaning of their
#: values in PX4's parameter metadata (parameters.json ``values``); they are reported with
#: that meaning and stay classic parameters.
NOT_DRIVER_SWITCHES: dict[str, dict[int, str]] = {
    "SENS_EN_THERMAL": {
        -1: "thermal control unavailable",
        0: "thermal control off",
        1: "thermal control enabled",
    },
}
#: ``CAL_<SENSOR><n>_ROT = -1``: PX4's metadata value "Internal" (an internal sensor forces it;
#: the board's rotation applies).
INTERNAL_ROTATION = -1


#: What options of today's start lines (board scripts) the types have no field for.
UNMAPPED_OPTIONS = {
    "ina226": "battery index (-t 1)",
    "ina228": "battery index (-t 1)",
    "ina238": "battery index (-t 1)",
}


@dataclass
class OldConfig:
    """Today's parameters: name -> value (int or float), from ``source``."""

    source: str
    kind: str  # "ULog" or "QGC .params"
    params: dict[str, int | float]
    #: Where the values came from, e.g. hardware and firmware of a log.
    details: list[str] = field(default_factory=list)
    #: Lines of the input that were not used (e.g. other components of a .params file).
    skipped: list[str] = field(default_factory=list)
    #: The firmware release of a log (ULog ``ver_sw_release``), which says which devtype table
    #: its device IDs follow; None for a .params file.
    release: int | None = None


def read_config(path: str | os.PathLike[str]) -> OldConfig:
    """Reads a ULog's parameters (their last values in the log) or a QGC ``.params`` file."""
    where = os.fspath(path)
    try:
        with open_file(where, ULOG) as f:
            head = f.read(len(ULOG_MAGIC))
    except OSError as e:
        raise MigrationError(f"{where}: cannot read: {e.strerror}") from None
    if head == ULOG_MAGIC:
        return _read_ulog(where)
    return _read_params(where)


def _read_ulog(where: str) -> OldConfig:
    from pyulog import ULog  # only ULog input needs it

    try:
        file = open_file(where, ULOG)
    except OSError as e:
        raise MigrationError(f"{where}: cannot read: {e.strerror}") from None
    try:
        with file, contextlib.redirect_stdout(io.StringIO()):  # pyulog prints warnings
            log = ULog(file, message_name_filter_list=[])
    except Exception as e:  # pyulog signals bad data with assorted exceptions
        raise MigrationError(f"{where}: not a readable ULog file ({e})") from None
    params: dict[str, int | float] = dict(log.initial_parameters)
    changed = []
    for _, name, value in log.changed_parameters:
        params[name] = value
        changed.append(name)
    if not params:
        raise MigrationError(f"{where}: the log has no parameters")
    info = log.msg_info_dict
    details = [f"{key} {info[key]}" for key in ("ver_hw", "ver_sw_branch", "ver_sw") if key in info]
    if changed:
        details.append(f"last values of {len(set(changed))} parameters changed during the log")
    release = info.get("ver_sw_release")
    return OldConfig(where, "ULog", params, details, release=int(release) if release else None)


def _read_params(where: str) -> OldConfig:
    try:
        text = read_text(where, PARAM_FILE)
    except OSError as e:
        raise MigrationError(f"{where}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError:
        raise MigrationError(f"{where}: neither a ULog file nor a QGC .params text file") from None
    try:
        read = qgc_params.read(text, where)
    except ParamFileError as e:
        raise MigrationError(str(e)) from None
    rows = [(r.vehicle, r.component, r.name, r.value) for r in read]
    if not rows:
        raise MigrationError(f"{where}: no parameters (not a QGC .params file?)")
    # The autopilot is component 1; other components (gimbals, ...) are not the vehicle's.
    components = sorted({c for _, c, _, _ in rows})
    chosen = 1 if 1 in components else components[0]
    params = {name: value for _, c, name, value in rows if c == chosen}
    skipped = [
        f"component {c}: {sum(1 for r in rows if r[1] == c)} parameters (not the autopilot's)"
        for c in components
        if c != chosen
    ]
    return OldConfig(where, "QGC .params", params, [f"component {chosen}"], skipped)


# -- the proposal -----------------------------------------------------------------------------


@dataclass
class ProposedInstance:
    """One instance of the manifest, its values and why it is proposed."""

    name: str
    #: Where it comes from, e.g. ``CAL_MAG1_ID 592905: AK09916 (MAG), I2C bus 1, address 0x0C``.
    origin: str
    #: Field path -> value, in the order to set them.
    values: dict[str, Any]
    notes: list[str] = field(default_factory=list)
    #: Filled in by :func:`migrate`: path -> ``[k]`` index.
    indices: dict[str, int] = field(default_factory=dict)


@dataclass
class Proposal:
    """What :func:`migrate` proposes: the instances and the report."""

    config: OldConfig
    table: str
    instances: list[ProposedInstance] = field(default_factory=list)
    #: Sensors found (device IDs) that are not part of the manifest, one line each.
    not_in_manifest: list[str] = field(default_factory=list)
    #: Parameters whose job the manifest takes over.
    replaced: list[str] = field(default_factory=list)
    #: ``SENS_EN_*`` parameters that are 0: no driver to carry over.
    disabled: list[str] = field(default_factory=list)
    #: What could not be carried over, one line each, never dropped silently.
    not_carried: list[str] = field(default_factory=list)
    #: Parameters that were used to build the proposal.
    used: set[str] = field(default_factory=set)

    @property
    def unchanged(self) -> int:
        """Parameters left as they are (classic parameters, not part of the manifest)."""
        return len(set(self.config.params) - self.used)

    def airframe(self) -> str:
        """The airframe file: ``param add`` / ``param set-default`` lines with comments."""
        lines = [
            f"# Device manifest migrated by px4params from {Path(self.config.source).name} "
            f"({self.config.kind})",
            "# Review before use: see the migration report.",
        ]
        if not self.instances:
            lines.append("# No device could be carried over.")
        for inst in self.instances:
            lines += ["", f"# {inst.name}: {inst.origin}", f"param add {inst.name}"]
            for path, value in inst.values.items():
                lines.append(f"# [{inst.indices[path]}] {path}")
                lines.append(
                    f"param set-default {inst.name}[{inst.indices[path]}] {_text(path, value)}"
                )
        return "\n".join(lines) + "\n"

    def report(self) -> str:
        c = self.config
        out = [f"Migration of {c.source} ({c.kind}, {len(c.params)} parameters)"]
        out += [f"  {d}" for d in c.details]
        out.append(f"  device IDs decoded with the {self.table} devtype table")

        def section(title: str, rows: list[str]) -> None:
            out.append("")
            out.append(f"{title}:" if rows else f"{title}: none")
            out.extend(f"  {r}" for r in rows)

        rows = []
        for inst in self.instances:
            rows.append(f"{inst.name}: {inst.origin}")
            shown = ", ".join(f"{p} = {_text(p, v)}" for p, v in inst.values.items())
            rows.append(f"  {shown}")
            rows.extend(f"  note: {n}" for n in inst.notes)
        section("Instances proposed", rows)
        section("Sensors found but not in the manifest", self.not_in_manifest)
        section("Replaced by the manifest", self.replaced)
        if self.disabled:
            out.append(f"  not enabled, nothing to carry over: {', '.join(self.disabled)}")
        section("Not carried over", self.not_carried + [f"{s}" for s in c.skipped])
        out.append("")
        out.append(
            f"Unchanged: {self.unchanged} other parameters stay classic parameters "
            "(calibration, tuning, ...); the manifest does not replace them."
        )
        return "\n".join(out) + "\n"

    def as_dict(self) -> dict[str, Any]:
        return {
            "source": self.config.source,
            "kind": self.config.kind,
            "parameters": len(self.config.params),
            "table": self.table,
            "instances": [
                {
                    "name": i.name,
                    "origin": i.origin,
                    "values": {p: _json(v) for p, v in i.values.items()},
                    "indices": i.indices,
                    "notes": i.notes,
                }
                for i in self.instances
            ],
            "not_in_manifest": self.not_in_manifest,
            "replaced": self.replaced,
            "disabled": self.disabled,
            "not_carried": self.not_carried + self.config.skipped,
            "unchanged": self.unchanged,
            "airframe": self.airframe(),
        }


def _text(path: str, value: Any) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return f"{value:.9g}"
    if path.endswith("address"):
        return f"0x{value:02X}"
    return str(value)


def _json(value: Any) -> Any:
    return value if not isinstance(value, float) or math.isfinite(value) else str(value)


# -- building it ------------------------------------------------------------------------------


class _Builder:
    def __init__(self, config: OldConfig, schema: Schema, table: devid.DevtypeTable) -> None:
        from px4params.store.store import Store

        self.config = config
        self.params = config.params
        self.store = Store(schema, classic=[])  # scratch: checks every value and gives [k]
        self.specs = {s.name: s for s in self.store.specs}
        self.drivers = load_drivers(None, self.store.specs)
        self.table = table
        self.proposal = Proposal(config, table.label)

    def use(self, *names: str) -> None:
        self.proposal.used.update(n for n in names if n in self.params)

    def add(self, param: str, bus: int, address: int, origin: str) -> ProposedInstance:
        """The instance of ``param`` on I2C ``bus`` at ``address``: a new one, or the one
        proposed already for the same device (found twice, e.g. enabled and calibrated)."""
        for inst in self.proposal.instances:
            if inst.name.partition("#")[0] == param and (
                inst.values["bus.i2c.bus_id"],
                inst.values["bus.i2c.address"],
            ) == (bus, address):
                inst.notes.append(f"also {origin}")
                return inst
        instance = self.store.add(param)
        values: dict[str, Any] = {}
        if self.store.get(f"{instance}.bus._tag") != 0:
            values["bus._tag"] = 0  # I2C
        values["bus.i2c.bus_id"] = bus
        values["bus.i2c.address"] = address
        for path, value in values.items():  # the tag first: it resets the variant
            self.store.set_default(f"{instance}.{path}", value)
        inst = ProposedInstance(instance, origin, values)
        self.proposal.instances.append(inst)
        return inst

    def field_value(self, inst: ProposedInstance, path: str, legacy: str, value: Any) -> bool:
        """Carries ``legacy = value`` into field ``path``; False (and a not-carried line) when
        the field cannot hold it. A float setting (a physical quantity: current, shunt) is
        rounded and clamped to the field's range, with a note; an integer setting (an
        enumeration such as a rotation) out of range is not carried."""
        param = inst.name.partition("#")[0]
        leaf = self.store.leaf(f"{inst.name}.{path}")
        tags = _field_tags(self.specs[param].data_type, path)
        lo, hi = tags.get("min"), tags.get("max")
        fitted: Any = value
        if isinstance(value, float):
            if leaf.type.startswith(("uint", "int")):
                fitted = math.floor(value + 0.5) if math.isfinite(value) else value
            if lo is not None and fitted < lo:
                fitted = type(fitted)(lo)
            if hi is not None and fitted > hi:
                fitted = type(fitted)(hi)
        elif (lo is not None and value < lo) or (hi is not None and value > hi):
            self.proposal.not_carried.append(
                f"{legacy} = {_shown(value)}: {inst.name}.{path} must be {lo}..{hi}"
            )
            return False
        try:
            self.store.set_default(f"{inst.name}.{path}", fitted)
        except (Px4ParamsError, OverflowError, ValueError) as e:
            self.proposal.not_carried.append(f"{legacy} = {_shown(value)}: {e}")
            return False
        stored = self.store.get(f"{inst.name}.{path}")
        inst.values[path] = stored
        if _differs(value, stored):
            unit = f" {tags['unit']}" if "unit" in tags else ""
            limits = f", {lo}..{hi}" if lo is not None or hi is not None else ""
            inst.notes.append(
                f"{legacy} = {_shown(value)}{unit} becomes {path} = {_shown(stored)}{unit} "
                f"({leaf.type}{limits})"
            )
        return True

    def run(self) -> Proposal:
        self.enabled_drivers()
        self.devices()
        self.probing()
        for inst in self.proposal.instances:
            leaves = {leaf.path: leaf.index for leaf in self.store.leaves(inst.name)}
            inst.indices = {path: leaves[path] for path in inst.values}
        return self.proposal

    def enabled_drivers(self) -> None:
        switches = self.drivers.switches()
        names = {n for n in self.params if n.startswith("SENS_EN_") or n in switches}
        for name in sorted(names):
            value = self.params[name]
            self.use(name)
            if name in NOT_DRIVER_SWITCHES:
                meaning = NOT_DRIVER_SWITCHES[name].get(int(value), "a value PX4 does not list")
                self.proposal.not_carried.append(
                    f"{name} = {_shown(value)} ({meaning}): not a driver switch; it stays a "
                    "classic parameter"
                )
                continue
            if not value:
                self.proposal.disabled.append(name)
                continue
            declared = switches.get(name) or self.undeclared(name)
            if not declared:
                self.proposal.not_carried.append(
                    f"{name} = {_shown(value)}: no bundled parameter type "
                    f"{name.removeprefix('SENS_EN_')}; the driver stays enabled by this classic "
                    "parameter, outside the manifest"
                )
                continue
            starting = [d for d in declared if d.starts_on(value)]
            if not starting:
                wanted = ", ".join(str(v) for d in declared for v in d.enabled_values)
                self.proposal.not_carried.append(
                    f"{name} = {_shown(value)}: starts no I2C driver of the manifest (its "
                    f"{', '.join(d.name for d in declared)} starts on {wanted}); it stays a "
                    "classic parameter"
                )
                continue
            for driver in starting:
                self.enabled_driver(name, value, driver)

    def undeclared(self, switch: str) -> list[Driver]:
        """A type of an extra DSDL folder without a driver declaration: ``SENS_EN_<NAME>``
        enables parameter ``NAME``'s driver, started as the power monitors are."""
        spec = self.specs.get(switch.removeprefix("SENS_EN_"))
        if not switch.startswith("SENS_EN_") or spec is None or spec.shared:
            return []
        driver = Driver(
            name=spec.name.lower(),
            parameter=spec.name,
            chip=spec.name,
            autostart=True,
            order=0,
            buses=("i2c",),
            default_address=None,
            devtype=0,
            chip_id_register=None,
            chip_id=None,
            rate_hz=1.0,
            started_by="launcher",
            enabled_by=switch,
        )
        return [driver]

    def enabled_driver(self, switch: str, value: int | float, driver: Driver) -> None:
        spec = self.specs[driver.parameter]
        address = _default_address(self.store, spec.name)
        where = (
            f"on I2C bus {DEFAULT_I2C_BUS}"
            if driver.started_by == "launcher"
            else f"on every external I2C bus (proposed: bus {DEFAULT_I2C_BUS}, check it)"
        )
        inst = self.add(
            spec.name,
            DEFAULT_I2C_BUS,
            address,
            f"{switch} = {_shown(value)}: {driver.name} started today {where} at the driver's "
            f"default address 0x{address:02X}",
        )
        if driver.switch_field:
            self.field_value(inst, driver.switch_field, switch, value)
        for old, path in driver.settings.items():
            if old in self.params:
                self.use(old)
                self.field_value(inst, path, old, self.params[old])
        for old in sorted(self.params):
            if old.startswith(f"{spec.name}_") and old not in driver.settings:
                self.use(old)
                self.proposal.not_carried.append(
                    f"{old} = {_shown(self.params[old])}: {spec.name} has no field for it"
                )
        options = UNMAPPED_OPTIONS.get(driver.name)
        if options:
            inst.notes.append(
                f"today's start line also sets the {options}: {spec.name} has no field for it"
            )

    def devices(self) -> None:
        found: dict[int, list[str]] = {}
        for name in sorted(self.params):
            m = _CAL_ID.fullmatch(name)
            value = self.params[name]
            if not m:
                continue
            self.use(name)
            if isinstance(value, float) and value.is_integer():
                value = int(value)
            if not isinstance(value, int) or not 0 <= value <= devid.MAX_DEVICE_ID:
                self.proposal.not_carried.append(f"{name} = {_shown(value)}: not a device ID")
                continue
            if value:
                found.setdefault(value, []).append(name)
        # CAL_<SENSOR>_PRIME selects one of the devices above: used, nothing of its own.
        self.use(*(n for n in self.params if re.fullmatch(r"CAL_[A-Z]+_PRIME", n)))
        for value, names in found.items():
            self.device(value, names)

    def device(self, value: int, names: list[str]) -> None:
        dev = devid.decode(value, self.table)
        where = f"{', '.join(names)} = {value}: {dev.describe()}"
        disabled = [
            f"{en} = 0"
            for n in names
            if (en := n.removesuffix("_ID") + "_EN") in self.params and not self.params[en]
        ]
        self.use(*(n.removesuffix("_ID") + "_EN" for n in names))
        off = f" (disabled: {', '.join(disabled)})" if disabled else ""
        # The type of the driver that publishes the chip; else a type named as the chip (an
        # extra DSDL folder's, without a driver declaration).
        chips = self.drivers.chips()
        chip_names = (dev.devtype_name or "").split("/")
        param = next((chips[c].parameter for c in chip_names if c in chips), None)
        spec = self.specs.get(param or next((c for c in chip_names if c in self.specs), ""))
        if dev.bus_type != 1:  # not I2C
            what = {
                2: "internal SPI sensor: started by the board's startup script, not by the "
                "manifest",
                3: "DroneCAN sensor: found on the CAN bus, not by the manifest",
            }.get(dev.bus_type, "not an I2C device: not part of the manifest")
            self.proposal.not_in_manifest.append(f"{where}{off}: {what}")
            return
        if spec is None:
            chip = dev.devtype_name or f"devtype 0x{dev.devtype:02X}"
            self.proposal.not_carried.append(
                f"{where}{off}: no bundled parameter type for {chip}; today it is found by "
                "probing, in the manifest it needs a type"
            )
            return
        inst = self.add(spec.name, dev.bus, dev.address, where)
        if disabled:
            inst.notes.append(f"{', '.join(disabled)}: the sensor was disabled for use")
        sensor = _CAL_ID.fullmatch(names[0])
        assert sensor is not None
        rotation = f"CAL_{sensor['sensor']}{sensor['n']}_ROT"
        if rotation in self.params:
            self.use(rotation)
            has_field = any(leaf.path == "rotation" for leaf in self.store.leaves(inst.name))
            value_rot = self.params[rotation]
            if not has_field:
                self.proposal.not_carried.append(
                    f"{rotation} = {_shown(value_rot)}: {spec.name} has no rotation field"
                )
            elif value_rot == INTERNAL_ROTATION:
                # PX4's "Internal": the sensor is the flight controller's, on its rotation.
                paths = {leaf.path for leaf in self.store.leaves(inst.name)}
                if "internal" in paths and self.field_value(inst, "internal", rotation, True):
                    inst.notes.append(
                        f"{rotation} = -1 (Internal): internal = true, rotation left 0 (the "
                        "board's)"
                    )
                else:
                    inst.notes.append(f"{rotation} = -1 (Internal): rotation left 0 (the board's)")
            else:
                self.field_value(inst, "rotation", rotation, value_rot)

    def probing(self) -> None:
        name = "SENS_EXT_I2C_PRB"
        if name not in self.params:
            return
        self.use(name)
        value = self.params[name]
        if value:
            found = [i.name for i in self.proposal.instances]
            self.proposal.replaced.append(
                f"{name} = {_shown(value)}: external I2C devices were found by probing; the "
                f"manifest states them ({', '.join(found) or 'none found'}) and a missing one "
                "fails the arming check instead of being skipped silently"
            )
        else:
            self.proposal.replaced.append(
                f"{name} = 0: probing was off; the manifest starts the devices it lists"
            )


def _default_address(store: Any, param: str) -> int:
    from px4params.store.spec import metadata_default

    spec = store.spec(param)
    value = metadata_default(store.schema, spec.data_type.key)
    bus = value.get("bus", {})
    return int(bus.get("i2c", {}).get("address", 0))


def _field_tags(data_type: Any, path: str) -> dict[str, Any]:
    """The ``@min``/``@max``/``@unit`` tags of a top-level field."""
    for f in data_type.definition["fields"]:
        if f["name"] == path:
            return dict((f.get("doc") or {}).get("tags") or {})
    return {}


def _differs(old: Any, new: Any) -> bool:
    if isinstance(old, float) or isinstance(new, float):
        return struct.pack("<f", float(old)) != struct.pack("<f", float(new))
    return bool(old != new)


def _shown(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.9g}"
    return str(value)


def migrate(
    config: OldConfig,
    schema: Schema | None = None,
    table: devid.DevtypeTable | str = "current",
) -> Proposal:
    """Proposes a manifest for ``config`` (see the module doc)."""
    from px4params.dsdl.schema import load_schema

    names = devid.load_table(table) if isinstance(table, str) else table
    return _Builder(config, schema or load_schema(include_dronecan=False), names).run()
