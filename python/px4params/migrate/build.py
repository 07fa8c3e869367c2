"""Building the proposal: which device of today's configuration becomes a manifest instance, and
why every other one does not (see the package documentation)."""

from __future__ import annotations

import dataclasses
import math
import re
import struct
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from px4params.dsdl.model import NO_DOC
from px4params.dsdl.schema import Schema
from px4params.errors import BoardsError, MigrationError, Px4ParamsError
from px4params.migrate import axes
from px4params.migrate.conditions import (
    UNSET_BEFORE_RC_SENSORS,
    Facts,
    Verdict,
    board_variables,
    evaluate,
    per_bus,
)
from px4params.migrate.config import OldConfig, shown_value
from px4params.migrate.proposal import LeftOut, Proposal, ProposedInstance
from px4params.vehicle import devid
from px4params.vehicle.console import DriverStart, started_drivers
from px4params.vehicle.drivers import Driver, load_drivers

if TYPE_CHECKING:
    from px4params.vehicle.boards import BoardTable

__all__ = ["migrate"]

#: The I2C bus proposed for a switch-started driver when nothing says which (PX4 starts them
#: with ``-X``, on every external bus; board scripts start power monitors ``-X -b 1``).
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
#: Why a device found by probing runs with rotation 0 where no boot console shows its start.
PROBED_WITHOUT_R = "rc.sensors starts it without -R"
#: The first PX4 whose boot console prints a driver's every -R but 0
#: (platforms/common/i2c_spi_buses.cpp: `if (cli.rotation != 0)`, from PX4 47b9016f5e, first
#: in v1.12.0; PX4 1.11 prints none).
CONSOLE_SHOWS_ROTATION = (1, 12, 0)
#: ``CAL_<SENSOR><n>_ROT = -1``: PX4's metadata value "Internal": the sensor is the flight
#: controller's, started by the board's script on the board's rotation.
INTERNAL_ROTATION = -1

#: Drivers whose start line takes a battery index, ``-t`` ("battery index for calibration
#: values"; without it the driver uses 1: ina226_main.cpp's ``cli.custom2 = 1``, ina228's and
#: ina238's ``cli.custom1 = 1``), which their types have no field for.
BATTERY_INDEX_DRIVERS = ("ina226", "ina228", "ina238")
_BATTERY_INDEX = re.compile(r"(?:^|\s)-t\s+(\d+)")
#: The command of a boot console's i2c_launcher line (``running 'ina228 -X -b 1 -t 1 start'``).
_LAUNCHED = re.compile(r"running '([^']*)'")
#: Driver modules PX4 renamed: the old name (older boot consoles, board scripts) -> today's.
RENAMED_MODULES = {
    "ms4525_airspeed": "ms4525do",  # PX4 1.13
    "ms5525_airspeed": "ms5525dso",  # PX4 1.13
    "sdp3x_airspeed": "sdp3x",  # PX4 1.13
    "sf1xx": "lightware_laser_i2c",  # PX4 1.12 (v1.11.0's rc.sensors: sf1xx start -X)
}
#: Devtype names PX4 1.13 changed (drv_sensor.h's ``DRV_DIFF_PRESS_DEVTYPE_MS4525`` became
#: ``..._MS4525DO``): an older era's name -> the driver declarations' chip.
RENAMED_CHIPS = {"MS4525": "MS4525DO", "MS5525": "MS5525DSO"}
#: What a module's (or its instance's) name adds to the chip's: ``bmi088_i2c``, whose
#: instances are ``bmi088_i2c_accel``, ``_gyro`` (PX4's src/drivers/imu/bosch/bmi088_i2c),
#: ``icm20948_i2c_passthrough``, ``ms4525_airspeed`` (PX4 before 1.13).
_MODULE_SUFFIX = re.compile(r"(_i2c)?(_(accel|gyro|mag|baro|airspeed|i2c_passthrough))?$")
#: The sensor kind of a log topic, as a calibration slot names it.
_TOPIC_KIND = {
    "sensor_accel": "ACC",
    "sensor_gyro": "GYRO",
    "sensor_mag": "MAG",
    "sensor_baro": "BARO",
    "differential_pressure": "DIFF_PRESS",
    "distance_sensor": "DIST",
}


class _Builder:
    def __init__(
        self,
        config: OldConfig,
        schema: Schema,
        table: devid.DevtypeTable,
        board: Any,
        assumptions: list[str],
        upgrade: _Upgrade | None = None,
        for_release: str | None = None,
    ) -> None:
        from px4params.store.store import Store

        self.config = config
        self.params = config.params
        self.store = Store(schema, classic=[])  # scratch: checks every value and gives [k]
        self.specs = {s.name: s for s in self.store.specs}
        self.drivers = load_drivers(None, self.store.specs)
        self.table = table
        self.board = board
        self.proposal = Proposal(config, table.label, assumptions=assumptions)
        self.proposal.board = getattr(board, "name", None)
        self.starts = started_drivers(config.console) if config.console else []
        self.claimed: set[int] = set()  # boot console starts accounted for
        self._facts: Facts | None = None
        upgrade = upgrade or _Upgrade("", (), None, None)
        #: The release whose board script the file's configuration ran (its snapshot).
        self.file_release = upgrade.file_release
        #: The board's row at each later release compared, oldest first, up to the target.
        self.releases = upgrade.releases
        #: The release the proposal is made for, where not the file's own.
        self.target = upgrade.target
        #: The release the manifest's rotations are for (--target-release; None: the newest).
        self.for_release = for_release

    def use(self, *names: str) -> None:
        self.proposal.used.update(n for n in names if n in self.params)

    def assume(self, line: str) -> None:
        if line not in self.proposal.assumptions:
            self.proposal.assumptions.append(line)

    def leave_out(
        self, found: str, device: str, reason: str, why: str, later: _Later | None = None
    ) -> None:
        line = f"{found}: {device}: {why}"
        shown = later.line if later is not None and later.line else None
        self.proposal.left_out.append(LeftOut(found, device, reason, line, shown))

    def add(self, param: str, bus: int, address: int, origin: str) -> ProposedInstance:
        """The instance of ``param`` on I2C ``bus`` at ``address``: a new one, or the one
        proposed already for the same device (found twice, e.g. enabled and calibrated)."""
        for inst in self.proposal.instances:
            if inst.key.param == param and (
                inst.values["bus.i2c.bus_id"],
                inst.values["bus.i2c.address"],
            ) == (bus, address):
                inst.notes.append(f"also {origin}")
                return inst
        inst = ProposedInstance(self.store.add(param), origin, {})
        values = inst.values
        if self.store.get(inst.key.at("bus._tag")) != 0:
            values["bus._tag"] = 0  # I2C
        values["bus.i2c.bus_id"] = bus
        values["bus.i2c.address"] = address
        for path, value in values.items():  # the tag first: it resets the variant
            self.store.set_default(inst.key.at(path), value)
        override = getattr(self.board, "external_i2c_buses_when", None)
        if (
            override is not None
            and bus in self.board.internal_i2c_buses
            and bus in override.external
            and evaluate(override.when, self.facts()).holds
        ):
            inst.notes.append(
                f"I2C bus {bus} is external where {override.when} ({override.source}): the "
                "board's -I starts try no bus there, rc.sensors' -X starts do"
            )
        self.proposal.instances.append(inst)
        return inst

    def field_value(self, inst: ProposedInstance, path: str, legacy: str, value: Any) -> bool:
        """Carries ``legacy = value`` into field ``path``; False (and a not-carried line) when
        the field cannot hold it. A float setting (a physical quantity: current, shunt) is
        rounded to nearest (``math.floor(v + 0.5)``) and clamped to the field's range, with a
        note, unless it is zero or less where the field's quantity is positive; an integer
        setting (an enumeration such as a rotation) out of range is not carried."""
        key = inst.key.at(path)
        leaf = self.store.leaf(key)
        field = self.specs[key.param].data_type.field_at(path)
        doc = field.doc if field is not None else NO_DOC
        lo, hi = doc.minimum, doc.maximum
        fitted: Any = value
        if isinstance(value, float) and lo is not None and lo > 0 and value <= 0:
            # A quantity that must be positive given as zero or less (a current of -5 A) is
            # no setting to round into the range: the field keeps the default.
            self.proposal.not_carried.append(
                f"{legacy} = {shown_value(value)}: {inst.name}.{path} must be {lo}..{hi}"
            )
            return False
        if isinstance(value, float):
            if leaf.type.startswith(("uint", "int")):
                fitted = math.floor(value + 0.5) if math.isfinite(value) else value
            if lo is not None and fitted < lo:
                fitted = type(fitted)(lo)
            if hi is not None and fitted > hi:
                fitted = type(fitted)(hi)
        elif (lo is not None and value < lo) or (hi is not None and value > hi):
            self.proposal.not_carried.append(
                f"{legacy} = {shown_value(value)}: {inst.name}.{path} must be {lo}..{hi}"
            )
            return False
        try:
            self.store.set_default(key, fitted)
        except (Px4ParamsError, OverflowError, ValueError) as e:
            self.proposal.not_carried.append(f"{legacy} = {shown_value(value)}: {e}")
            return False
        stored = self.store.get(key)
        inst.values[path] = stored
        if _differs(value, stored):
            unit = f" {doc.unit}" if doc.unit is not None else ""
            limits = f", {lo}..{hi}" if lo is not None or hi is not None else ""
            inst.notes.append(
                f"{legacy} = {shown_value(value)}{unit} becomes {path} = "
                f"{shown_value(stored)}{unit} ({leaf.type}{limits})"
            )
        return True

    def set_rotation(
        self, inst: ProposedInstance, rotation: int, why: str, turned: str | None = None
    ) -> None:
        """The driver's rotation (its ``-R``), where the type has the field; ``turned``: what
        :meth:`axes_rotation` said of it."""
        has_field = any(leaf.path == "rotation" for leaf in self.store.leaves(inst.key))
        if (
            has_field
            and self.field_value(inst, "rotation", "the driver's -R", rotation)
            and (rotation or turned)
        ):
            inst.notes.append(turned or f"rotation {rotation}: {why}")

    def axes_rotation(
        self, chips: set[str], bus: int, rotation: tuple[int, str]
    ) -> tuple[tuple[int, str], str | None]:
        """A rotation of the file's release for the manifest's release, where the chip's
        driver reports other axes there (:func:`.axes.turn`), and the note saying so."""
        turned = self.turned(chips, bus, rotation, self.for_release)
        return (rotation, None) if turned is None else ((turned.rotation, turned.why), turned.note)

    def turned(
        self,
        chips: set[str],
        bus: int,
        rotation: tuple[int, str],
        release: str | None,
        started: Iterable[str] = (),
    ) -> axes.Turned | None:
        """:func:`.axes.turn` of a device's rotation of the file's release, for ``release``;
        ``started``: the driver modules board rows start it with (an IMU no declared driver
        drives is known by those alone)."""
        by_chip = self.drivers.chips()
        modules = {by_chip[c].name for c in chips if c in by_chip} | set(started)
        return axes.turn(
            modules,
            *rotation,
            self.config.version,
            release,
            self.on_internal_bus(bus),
            getattr(self.board, "name", None),
        )

    def run(self) -> Proposal:
        self.enabled_drivers()
        self.devices()
        self.console_starts()
        self.launcher_buses()
        self.probing()
        for inst in self.proposal.instances:
            leaves = {leaf.path: leaf.index for leaf in self.store.leaves(inst.key)}
            inst.indices = {path: leaves[path] for path in inst.values}
        return self.proposal

    # -- what names what -----------------------------------------------------------------

    def start_chips(self, start: DriverStart | str) -> set[str]:
        """The chip names a started driver module publishes (drv_sensor.h's spelling)."""
        name = start if isinstance(start, str) else start.driver
        module = RENAMED_MODULES.get(name, name)
        try:
            return set(self.drivers[module].chips)
        except KeyError:
            return {_MODULE_SUFFIX.sub("", module).upper()}

    def start_driver(self, start: DriverStart) -> Driver | None:
        module = RENAMED_MODULES.get(start.driver, start.driver)
        try:
            return self.drivers[module]
        except KeyError:
            return None

    def evidence(self, dev: devid.DeviceId) -> tuple[int, DriverStart] | None:
        """The boot console start of device ``dev`` (same chip, bus and, where the line says,
        address)."""
        chips = _chips(dev)
        kind = {1: "I2C", 2: "SPI"}.get(dev.bus_type)
        for i, start in enumerate(self.starts):
            if i in self.claimed or start.bus_kind != kind or start.bus != dev.bus:
                continue
            if kind == "I2C" and start.address is not None and start.address != dev.address:
                continue
            if self.start_chips(start) & chips:
                return i, start
        return None

    def board_device(
        self, chips: set[str], bus: int, address: int | None, board: Any = None
    ) -> tuple[Any, Verdict] | None:
        """The board table's row that starts this I2C device, and its condition's verdict: the
        first whose condition holds, else the first that nothing here settles (a row that does
        not run here is passed over); None where no row runs or may run. ``board``: the
        board's row of another release (default: the file's)."""
        board = board or self.board
        if board is None:
            return None
        # A board whose I2C buses the table does not know: a row without -b may be on any bus.
        known = bool(getattr(board, "i2c_buses_path", ""))
        undecided = None
        for row in board.devices:
            if row.bus_kind.upper() != "I2C" or not (self.start_chips(row.driver) & chips):
                continue
            # -I or -X: the board's internal or external buses, of them its -b (a -b of the
            # other kind: none), each with the hardware it is of that kind on
            on = dict(board.bus_conditions(row)) if known or row.bus is not None else {}
            if (known or row.bus is not None) and bus not in on:
                continue
            at = self.row_address(row)
            if at is not None and address is not None and at != address:
                continue
            verdict = self.start_verdict(row, on.get(bus, ""), board)
            if verdict.holds:
                return row, verdict
            if verdict.holds is None and undecided is None:
                undecided = row, verdict
        return undecided

    def row_address(self, row: Any) -> int | None:
        """The I2C address a board or switch row starts its driver at: its -a, else the
        driver's default; None where neither is known."""
        at: int | None = row.address
        if at is None and row.driver in {d.name for d in self.drivers}:
            at = self.drivers[row.driver].default_address
        return at

    def board_starts(
        self, chips: set[str], bus: int, address: int | None, board: Any = None
    ) -> tuple[Any, Verdict] | None:
        """The board row that starts this I2C device at ``board``'s release (default: the
        file's), the one place that decides it: a row whose condition holds, or one nothing
        here settles on an internal bus, which only the board's script starts drivers on
        (rc.sensors probes with -X only); None where the board's script does not start it."""
        row = self.board_device(chips, bus, address, board)
        if row is not None and (row[1].holds or self.on_internal_bus(bus, board)):
            return row
        return None

    def release_start(
        self, board: Any, chips: set[str], bus: int, address: int | None
    ) -> _Start | None:
        """How the scripts of ``board``'s release start this I2C device with this file's
        parameters: the board's own row (:meth:`board_starts`), else a switch row (rc.sensors'
        probe, a SENS_EN_* switch) whose condition holds; None where nothing starts it."""
        row = self.board_starts(chips, bus, address, board)
        if row is not None:
            return _Start(row[0], True, row[0].rotation or 0)
        for switch in board.switches:
            if switch.bus_kind.upper() != "I2C" or switch.bus != bus:
                continue
            at = self.row_address(switch)
            if not (self.start_chips(switch.driver) & chips) or (
                at is not None and address is not None and at != address
            ):
                continue
            if self.start_verdict(switch, switch.bus_when, board).holds:
                return _Start(switch, False, switch.rotation or 0)
        return None

    def later(self, chips: set[str], bus: int, address: int | None) -> _Later | None:
        """What the board's scripts of the releases after the file's (up to the target
        release, else the newest the table knows) do with an I2C device the file's board
        script starts: one line citing the file's start and each release where that changed;
        ``propose`` where at the last of them the board's script no longer starts it. None
        where no board row of the file's release starts it or no later release is known."""
        first = self.board_starts(chips, bus, address)
        if first is None or not self.releases:
            return None
        row = first[0]
        before = _Start(row, True, row.rotation or 0)
        spans: list[tuple[str, str, _Start | None]] = []  # first and last release, the start
        for release, board in self.releases:
            now = self.release_start(board, chips, bus, address)
            if spans and _same_start(spans[-1][2], now):  # cited where it changed
                spans[-1] = (spans[-1][0], release, spans[-1][2])
            else:
                spans.append((release, release, now))
        last = spans[-1][2]
        old = f"'{row.driver} {row.args}' ({row.source})"
        if last is not None and all(_same_start(before, now) for _, _, now in spans):
            newest = self.release_start(self.releases[-1][1], chips, bus, address) or last
            return _Later(
                f"still started by the board's script through PX4 {spans[-1][1]}: "
                f"'{newest.row.driver} {newest.row.args}' ({newest.row.source})",
                False,
                before.rotation,
                old,
            )
        changes = [
            f"{_span(a, b)}: {_describe(now, before, self.board)}"
            for a, b, now in spans
            if not _same_start(before, now)
        ]
        gone = None  # the first release of the last run without the board's start
        for a, _, now in spans:
            gone = (gone or a) if now is None or not now.board else None
        propose = gone is not None
        if propose and self.target is not None:
            then = (
                f"at {self.target} the board's script does not start it: the manifest does, "
                f"with the -R {before.rotation} the file's line gives"
            )
        elif gone is not None:
            then = (
                f"on PX4 {gone} and later the board's script does not start it, the manifest "
                f"must: --target-release {gone} (or later) proposes it as an instance"
            )
        elif last is not None and last.rotation != before.rotation:
            # the board's new -R may be the old orientation on a driver's new axes
            drivers = (before.row.driver, last.row.driver)
            turned = self.turned(chips, bus, (before.rotation, ""), spans[-1][1], drivers)
            then = f"the board's script still starts it, with -R {last.rotation}: "
            if turned is not None and turned.what and turned.rotation == last.rotation:
                then += f"the same orientation ({turned.what})"
            else:
                then += "check its calibration after the update"
        else:
            then = "the board's script still starts it"
        line = f"the board's script of PX4 {self.file_release} starts it with {old}; " + (
            "; ".join(changes) + f": {then}"
        )
        return _Later(line, propose and self.target is not None, before.rotation, old)

    def taken_later(self, chips: set[str], bus: int, address: int | None) -> _Taken | None:
        """Of an I2C device the file's board script does not start: the first later release
        whose board script does, where the last release compared (the target, else the
        newest) still does; None otherwise."""
        if not self.releases or not self.board_starts(chips, bus, address, self.releases[-1][1]):
            return None
        for release, board in self.releases:
            row = self.board_starts(chips, bus, address, board)
            if row is not None:
                return _Taken(release, row[0])
        return None

    def taken_line(self, taken: _Taken, rotation: tuple[int, str]) -> str:
        """What :meth:`taken_later` found, in one line: an instance would start the device a
        second time on that firmware."""
        row = taken.row
        turned = ""
        if (row.rotation or 0) != rotation[0]:
            turned = (
                f", with -R {row.rotation or 0} where PX4 {self.file_release} ran it with "
                f"{rotation[0]} ({rotation[1]}; check its calibration after the update)"
            )
        said = (
            f"the board's script starts it from PX4 {taken.release}: '{row.driver} {row.args}' "
            f"({row.source}){turned}"
        )
        if self.target is not None:
            return f"{said}; on PX4 {self.target} it is the board's, not the manifest's"
        return (
            f"{said}: for that firmware --target-release {taken.release} (or later) leaves it out"
        )

    def start_verdict(self, row: Any, bus_when: str, board: Any = None) -> Verdict:
        """Whether a board row runs, on a bus that is of its kind where ``bus_when`` holds
        (:meth:`Board.bus_conditions`; "": always): that clause, where nothing settles it,
        cites the board's own px4_i2c_bus_external. ``board``: the row's board (default: the
        file's)."""
        board = board or self.board
        facts = self.facts(board)
        if "/rc.sensors:" in getattr(row, "source", ""):
            facts = dataclasses.replace(facts, unset=UNSET_BEFORE_RC_SENSORS)
        verdict = evaluate(" and ".join(c for c in (row.when, bus_when) if c), facts)
        override = getattr(board, "external_i2c_buses_when", None)
        if not bus_when or override is None:
            return verdict
        kind = "internal" if row.internal else "external"
        open_ = tuple(
            (c, f"{why}; the bus is {kind} only there: {override.source}" if c == bus_when else why)
            for c, why in verdict.open
        )
        return Verdict(verdict.holds, open_)

    def on_internal_bus(self, bus: int, board: Any = None) -> bool:
        """Whether I2C ``bus`` is internal on this vehicle: on the board's lists, and where its
        own px4_i2c_bus_external makes it external on some hardware, that hardware settled not
        to be this one. ``board``: the board's row of another release (default: the file's)."""
        board = board or self.board
        if bus not in getattr(board, "internal_i2c_buses", ()):
            return False
        override = getattr(board, "external_i2c_buses_when", None)
        if override is None or bus not in override.external:
            return True
        verdict = evaluate(override.when, self.facts(board))
        return verdict.holds is False and not verdict.open

    def other_kind_rows(self, chips: set[str], bus: int, address: int | None) -> list[Any]:
        """The board's rows that would start this I2C device but for their ``-b``, a bus of
        the other kind on every hardware (``-X -b 2`` where bus 2 is internal): PX4 finds no
        bus for them, and they start nothing."""
        found = []
        for row in getattr(self.board, "devices", ()):
            if (
                row.bus_kind.upper() != "I2C"
                or row.bus != bus
                or self.board.bus_conditions(row)
                or not (self.start_chips(row.driver) & chips)
            ):
                continue
            at = self.row_address(row)
            if at is None or address is None or at == address:
                found.append(row)
        return found

    def probe_rotation(self, chips: set[str]) -> tuple[int, str] | None:
        """The ``-R`` rc.sensors' probing passes this chip's driver in the board table's
        release (PX4 1.11: ``ak09916 -X -R 6 start``), and where it says so; None if none or
        the probe does not run here. A probe nothing here settles is taken (the device was
        found, and the probe is what starts it) and named."""
        for row in getattr(self.board, "switches", ()):
            if not (
                row.param == "SENS_EXT_I2C_PRB"
                and row.rotation
                and self.start_chips(row.driver) & chips
            ):
                continue
            verdict = self.start_verdict(row, row.bus_when)
            if verdict.holds is False:
                continue
            if verdict.unchecked:
                self.assume(
                    f"'{row.driver} {row.args}' ({row.source}) runs only where "
                    f"{' and '.join(verdict.unchecked)}: its -R {row.rotation} taken"
                )
            return (
                row.rotation,
                f"rc.sensors probes it with '{row.driver} {row.args}' ({row.source})",
            )
        return None

    def shown_rotation(self, start: DriverStart | None) -> int | None:
        """The rotation a boot console start shows the driver running with: its -R, 0 where a
        console of PX4 1.12 on prints none; None where the console does not say."""
        if start is None or start.rotation is not None:
            return start.rotation if start is not None else None
        version = self.config.version
        return 0 if version is not None and version >= CONSOLE_SHOWS_ROTATION else None

    def driver_rotation(self, start: DriverStart | None, chips: set[str]) -> tuple[int, str]:
        """The driver's rotation of a device found by probing, and why: the boot console's,
        else the probe's ``-R``, else 0 (probing passes none)."""
        shown = self.shown_rotation(start)
        if shown is not None:
            return shown, (
                "the driver's -R (boot console)" if shown else "the boot console shows no -R"
            )
        return self.probe_rotation(chips) or (0, PROBED_WITHOUT_R)

    def started_by_board(
        self,
        found: str,
        chips: set[str],
        bus: int,
        address: int | None,
        start: DriverStart | None,
        internal_rot: str | None,
        baro: bool,
        if_run: str,
        disabled: bool = False,
    ) -> str | None:
        """Why the board's script starts this I2C device, or None when it does not (the
        rules in the order they are trusted). ``found``: the device as the report names it;
        ``if_run``: :meth:`rotation_if_run`'s clause; ``disabled``: every slot of it is, so
        it is not proposed either way."""
        for other in self.other_kind_rows(chips, bus, address):
            kind = "external" if other.internal else "internal"
            self.assume(
                f"{found}: the board's '{other.driver} {other.args}' ({other.source}) did not "
                f"start it: I2C bus {bus} is {kind} "
                f"({self.board.i2c_bus_source(bus) or _buses_path(self.board)}), and PX4's "
                f"{'-I' if other.internal else '-X'} tries no bus of that kind "
                "(platforms/common/i2c.cpp, I2CBusIterator::next), so that line starts nothing"
            )
        row = self.board_device(chips, bus, address)
        started = self.board_starts(chips, bus, address)
        if started is not None and started[1].holds:
            self.assume_row(found, *started, "taken as holding (PX4's default)")
            return f"started by the board's script ({started[0].source})"
        if started is not None and row is not None:
            # Found on an internal bus, which rc.sensors never probes (-X only): the row ran.
            return (
                f"started by the board's script ({row[0].source}); it runs only where "
                f"{' and '.join(row[1].unchecked)}, and being found on internal I2C bus {bus} "
                f"({_buses_path(self.board)}) shows it did"
            )
        by_board = self.other_rules(chips, start, internal_rot, baro)
        if row is not None and by_board is None and disabled:
            self.assume_row(found, *row, "left out as disabled, not as the board's on a guess")
        elif row is not None and by_board is None:
            self.assume_row(found, *row, "proposed, not left out on a guess" + if_run)
        return by_board

    def rotation_if_run(
        self,
        chips: set[str],
        bus: int,
        address: int | None,
        start: DriverStart | None,
        rotation: tuple[int, str],
    ) -> str:
        """What the board row nothing settles for this device says of its rotation ``rotation``
        (:meth:`driver_rotation`'s), "" where nothing: where a boot console shows the driver's
        rotation and it is not the row's -R, the row did not start it; else the rotation holds
        only where the row does not run (it starts the device with its own -R, and then the
        device is the board's)."""
        row = self.board_device(chips, bus, address)
        if row is None or row[1].holds is not None:
            return ""
        value, why = rotation
        if row[0].rotation is None or row[0].rotation == value:
            return ""
        shown = self.shown_rotation(start)
        if start is not None and shown is not None:
            runs = f"with -R {shown}" if shown else "without -R"
            return (
                f"; boot console line {start.line} shows it runs {runs}, not with that line's "
                f"-R {row[0].rotation}: that line did not start it"
            )
        return (
            f"; its rotation {value} ({why}) holds only where that line does not run: where "
            f"it runs, it starts the device with -R {row[0].rotation} and the device is the "
            "board's, not the manifest's"
        )

    def note_unsettled_row(
        self, inst: ProposedInstance, chips: set[str], bus: int, address: int | None, if_run: str
    ) -> None:
        """Notes on a proposed instance what :meth:`rotation_if_run`'s clause ``if_run`` says of
        the board row nothing settles that starts the same device."""
        row = self.board_device(chips, bus, address)
        if if_run and row is not None:
            inst.notes.append(
                f"the board's '{row[0].driver} {row[0].args}' ({row[0].source}) runs only where "
                f"{' and '.join(row[1].unchecked)}{if_run}"
            )

    def assume_row(self, found: str, row: Any, verdict: Verdict, then: str) -> None:
        """Names what a board row's condition rests on, where something does."""
        if verdict.unchecked:
            self.assume(
                f"{found}: the board's '{row.driver} {row.args}' ({row.source}) runs only where "
                f"{' and '.join(verdict.unchecked)}: {then}"
            )

    def other_rules(
        self,
        chips: set[str],
        start: DriverStart | None,
        internal_rot: str | None,
        baro: bool,
    ) -> str | None:
        """Why the board's scripts start an I2C device no board row settles, or None."""
        if start is not None and start.internal and not start.launcher:
            return (
                f"on an internal bus (boot console line {start.line}): started by the board's "
                "startup scripts"
            )
        if internal_rot is not None:
            return f"{internal_rot} = -1 (Internal): started by the board's script"
        probed = self.probe_rotation(chips)
        if start is not None and start.rotation and not start.launcher:
            if probed is not None and probed[0] == start.rotation:
                return None  # rc.sensors' probe passes this -R itself
            return (
                f"runs with rotation {start.rotation} (boot console line {start.line}): "
                "rc.sensors probes without -R, so the board's script started it"
            )
        if baro:
            self.assume(
                "I2C barometers without a board table row are taken as started by the board's "
                "script (barometers sit on the flight controller)"
            )
            return "a barometer: assumed started by the board's script"
        return None

    # -- drivers enabled by a switch ---------------------------------------------------------

    def enabled_drivers(self) -> None:
        switches = self.drivers.switches()
        names = {n for n in self.params if n.startswith("SENS_EN_") or n in switches}
        for name in sorted(names):
            value = self.params[name]
            self.use(name)
            if name in NOT_DRIVER_SWITCHES:
                meaning = NOT_DRIVER_SWITCHES[name].get(int(value), "a value PX4 does not list")
                self.proposal.not_carried.append(
                    f"{name} = {shown_value(value)} ({meaning}): not a driver switch; it stays a "
                    "classic parameter"
                )
                continue
            if not value:
                self.proposal.disabled.append(name)
                continue
            declared = switches.get(name) or self.undeclared(name)
            if not declared:
                self.proposal.not_carried.append(
                    f"{name} = {shown_value(value)}: no bundled parameter type "
                    f"{name.removeprefix('SENS_EN_')}; the driver stays enabled by this classic "
                    "parameter, outside the manifest"
                )
                continue
            starting = [d for d in declared if d.starts_on(value)]
            if not starting:
                wanted = "; ".join(f"{d.name} starts on {d.switch_test}" for d in declared)
                self.proposal.not_carried.append(
                    f"{name} = {shown_value(value)}: starts no I2C driver of the manifest (its "
                    f"{wanted}); it stays a classic parameter"
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

    def facts(self, board: Any = None) -> Facts:
        """What the board rows' conditions are settled by. PX4's board scripts set
        INA_CONFIGURED yes in the block of each power-monitor switch's test (boards/px4/
        fmu-v6x/init/rc.board_sensors: `if param compare SENS_EN_INA226 1`), so it follows
        from those switches as their drivers' declarations test them. ``board``: the board's
        row of another release, whose scripts no boot console of this file shows running."""
        if board is not None and board is not self.board:
            own = self.facts()
            return Facts(
                own.params,
                own.variables,
                tuple(board.ver_hw),
                None,
                own.kind,
                own.hw_type,
                board_variables(board.name, board.releases),
                board.cite,
            )
        if self._facts is None:
            ina = any(
                d.starts_on(self.params[d.enabled_by])
                for d in self.drivers
                if d.enabled_by
                and _INA_SWITCH.fullmatch(d.enabled_by)
                and d.enabled_by in self.params
            )
            self._facts = Facts(
                self.params,
                {"INA_CONFIGURED": "yes" if ina else "no"},
                tuple(getattr(self.board, "ver_hw", ())),
                self.starts if self.config.console is not None else None,
                self.config.kind,
                self.config.hw_type,
                board_variables(
                    getattr(self.board, "name", ""), getattr(self.board, "releases", ())
                ),
                getattr(self.board, "cite", None),
            )
        return self._facts

    def running_rows(self, switch: str, driver: Driver) -> list[Any]:
        """The board's rows of ``switch`` starting ``driver`` that PX4 runs with this
        configuration: every clause of a row's condition is evaluated; a row that holds only
        by PX4's default of what nothing here tells, or that nothing here settles, is said
        so, naming the clause and the row's line."""
        rows = []
        for row in getattr(self.board, "switches", ()):
            if row.param != switch or RENAMED_MODULES.get(row.driver, row.driver) != driver.name:
                continue
            verdict = self.start_verdict(row, row.bus_when)
            on_bus = f" on I2C bus {row.bus}" if row.bus_when else ""
            start = f"'{row.driver} {row.args}' ({row.source}){on_bus} runs only where"
            unchecked = " and ".join(verdict.unchecked)
            if verdict.holds:
                rows.append(row)
                if unchecked:
                    self.assume(f"{switch}: {start} {unchecked}: taken as holding (PX4's default)")
            elif verdict.holds is None:
                self.assume(f"{switch}: {start} {unchecked}: not proposed from it")
            elif unchecked:
                self.assume(
                    f"{switch}: {start} {unchecked}: by PX4's default it does not run, not "
                    "proposed from it"
                )
        return rows

    def switch_places(self, switch: str, driver: Driver) -> list[_Place]:
        """Where the switch starts the driver, per instance: from the boot console, else the
        board's switch rows that run, else a guess (reported)."""
        places = []
        lines = [
            r
            for r in getattr(self.board, "switches", ())
            if r.param == switch and RENAMED_MODULES.get(r.driver, r.driver) == driver.name
        ]
        for i, start in enumerate(self.starts):
            if (
                i not in self.claimed
                and start.bus_kind == "I2C"
                and self.start_driver(start) == driver
            ):
                self.claimed.add(i)
                # A driver's own line prints no options: the board's line on that bus has them.
                args = _launched_args(start) or next(
                    (r.args for r in lines if r.bus == start.bus), None
                )
                places.append(
                    _Place(
                        start.bus,
                        start.address,
                        f"boot console line {start.line}: '{start.text}'",
                        args,
                    )
                )
        if places:
            return places
        rows = self.running_rows(switch, driver)
        # A start with -b is on that bus; one without is PX4's -X: every external bus is
        # tried, the device is found on one of them.
        pinned = [r for r in rows if re.search(r"(^|\s)-b\s", r.args)]
        if pinned:
            return [
                _Place(
                    r.bus,
                    r.address,
                    f"the board starts it with '{r.driver} {r.args}' ({r.source})",
                    r.args,
                )
                for r in pinned
            ]
        if rows:
            first = rows[0]
            buses = ", ".join(str(b) for b in sorted({r.bus for r in rows}))
            self.assume(
                f"{switch}: {self.board.name} starts '{first.driver} {first.args}' on every "
                f"external I2C bus ({buses}; {first.source}), so the bus it is found on is not "
                f"known: bus {first.bus} proposed"
            )
            return [_Place(first.bus, first.address, "", first.args)]
        if self.config.console is not None:
            self.assume(
                f"{switch}: the boot console shows no {driver.name} start (not connected at "
                f"boot?); proposed on I2C bus {DEFAULT_I2C_BUS}"
            )
        how = (
            "-X -b 1 on the board"
            if driver.started_by == "launcher"
            else "-X, on every external bus"
        )
        self.assume(
            f"{switch}: I2C bus {DEFAULT_I2C_BUS} is a guess (PX4 starts {driver.name} {how}; "
            "nothing here says which bus it is on)"
        )
        return [_Place(DEFAULT_I2C_BUS, None, "", None)]

    def enabled_driver(self, switch: str, value: int | float, driver: Driver) -> None:
        spec = self.specs[driver.parameter]
        for place in self.switch_places(switch, driver):
            at = place.address
            address = at if at is not None else _default_address(self.store, spec.name)
            where = f"on I2C bus {place.bus}" + (f" ({place.why})" if place.why else "")
            default = " at the driver's default address" if at is None else " at address"
            inst = self.add(
                spec.name,
                place.bus,
                address,
                f"{switch} = {shown_value(value)}: {driver.name} started {where}{default} "
                f"0x{address:02X}",
            )
            if driver.switch_field:
                self.field_value(inst, driver.switch_field, switch, value)
            for old, path in driver.settings.items():
                if old in self.params:
                    self.use(old)
                    self.field_value(inst, path, old, self.params[old])
            if driver.name in BATTERY_INDEX_DRIVERS:
                inst.notes.append(_battery_note(spec.name, place.args))
        for old in sorted(self.params):
            if old.startswith(f"{spec.name}_") and old not in driver.settings:
                self.use(old)
                self.proposal.not_carried.append(
                    f"{old} = {shown_value(self.params[old])}: {spec.name} has no field for it"
                )

    # -- devices of the calibration slots ---------------------------------------------------

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
                self.proposal.not_carried.append(f"{name} = {shown_value(value)}: not a device ID")
                continue
            if value:
                found.setdefault(value, []).append(name)
        # CAL_<SENSOR>_PRIME selects one of the devices above: used, nothing of its own.
        self.use(*(n for n in self.params if re.fullmatch(r"CAL_[A-Z]+_PRIME", n)))
        # Sensors that published in the log without a calibration slot (a barometer before
        # PX4 1.12, an airspeed sensor, a rangefinder): found the same way.
        for topic, multi_id, value in self.config.published:
            if value not in found and value <= devid.MAX_DEVICE_ID:
                found.setdefault(value, []).append(f"{topic} {multi_id}")
            elif value in found and not found[value][0].startswith("CAL_"):
                found[value].append(f"{topic} {multi_id}")
        for value, names in found.items():
            self.device(value, names)

    def disabled_slots(self, names: list[str]) -> list[str]:
        """``CAL_<S>n_PRIO = 0`` (PX4 1.12 on) and ``CAL_<S>n_EN = 0`` (before) of the slots."""
        off = []
        for n in names:
            for suffix in ("_PRIO", "_EN"):
                setting = n.removesuffix("_ID") + suffix
                if setting in self.params:
                    self.use(setting)
                    if not self.params[setting]:
                        off.append(f"{setting} = 0")
        return off

    def device(self, value: int, names: list[str]) -> None:
        dev = devid.decode(value, self.table)
        found = f"{', '.join(names)} = {value}"
        where = f"{found}: {dev.describe()}"
        off = self.disabled_slots(names)
        # Disabled when every calibration slot holding it is (a log's topics have no switch).
        slots = [n for n in names if n.startswith("CAL_")]
        all_off = bool(slots) and all(
            any(o.startswith(n.removesuffix("_ID") + "_") for o in off) for n in slots
        )
        rotations = {
            rot: self.params[rot]
            for n in names
            if (rot := n.removesuffix("_ID") + "_ROT") in self.params and n.startswith("CAL_MAG")
        }
        twice = ""
        kinds = [_slot_kind(n) for n in names]
        repeated = sorted({k for k in kinds if kinds.count(k) > 1})
        if repeated:
            slots = [n for n, k in zip(names, kinds, strict=True) if k in repeated]
            twice = f"; {' and '.join(slots)} hold the same device (reported once)"
            if len(set(rotations.values())) > 1:
                shown = ", ".join(f"{r} = {shown_value(v)}" for r, v in rotations.items())
                twice += f", with different rotations ({shown})"
        # A devtype of another kind than every slot holding it (a temperature sensor's in
        # CAL_MAG0_ID): the table is of another era, and the chip is not this one.
        mismatches = [devid.kind_mismatch(n, dev) for n in slots]
        if slots and all(mismatches):
            self.leave_out(found, dev.describe(), "kind", f"not proposed: {mismatches[0]}{twice}")
            return
        chips = _chips(dev, kinds)
        if dev.bus_type == 2:  # SPI
            hit = self.evidence(dev)
            if hit:
                self.claimed.add(hit[0])
            # the console says where PX4 found it; a device ID alone does not
            why = f"{_spi_started(hit is not None and hit[1].external)}, not by the manifest"
            disabled = f" (disabled: {', '.join(off)})" if off else ""
            self.leave_out(found, dev.describe() + disabled, "board", why + twice)
            return
        if dev.bus_type != 1:  # not I2C
            reason, what = {
                3: ("dronecan", "DroneCAN sensor: found on the CAN bus, not by the manifest"),
                4: ("simulation", "simulated sensor: not part of the manifest"),
            }.get(dev.bus_type, ("other bus", "not an I2C device: not part of the manifest"))
            self.leave_out(found, dev.describe(), reason, what + twice)
            return
        hit = self.evidence(dev)
        start = hit[1] if hit else None
        if hit:
            self.claimed.add(hit[0])
        internal = next((r for r, v in rotations.items() if v == INTERNAL_ROTATION), None)
        kind = {k for _, k in _named(dev, kinds)}
        baro = "BARO" in kind or all(k == "BARO" for k in kinds)
        rotation = self.driver_rotation(start, chips)
        if_run = self.rotation_if_run(chips, dev.bus, dev.address, start, rotation)
        board = self.started_by_board(
            where, chips, dev.bus, dev.address, start, internal, baro, if_run, all_off
        )
        disabled = f" (disabled: {', '.join(off)})" if off else ""
        later = self.later(chips, dev.bus, dev.address) if board is not None else None
        if board is not None and (later is None or not later.propose):
            self.leave_out(found, dev.describe(), "board", f"{board}{disabled}{twice}", later)
            return
        if all_off:
            why = f"disabled ({', '.join(off)}): not proposed, an instance would make it required"
            self.leave_out(found, dev.describe(), "disabled", why + twice, later)
            return
        if later is not None:  # the target's board script no longer starts it
            rotation = (later.rotation, f"the -R of PX4 {self.file_release}'s start (above)")
        rotation, turned = self.axes_rotation(chips, dev.bus, rotation)
        taken = self.taken_later(chips, dev.bus, dev.address) if board is None else None
        if taken is not None and self.target is not None:
            why = self.taken_line(taken, rotation)
            self.leave_out(found, dev.describe(), "board", f"{why}{disabled}{twice}")
            return
        # The type of the driver that publishes the chip; else a type named as the chip (an
        # extra DSDL folder's, without a driver declaration).
        by_chip = self.drivers.chips()
        param = next((by_chip[c].parameter for c in sorted(chips) if c in by_chip), None)
        spec = self.specs.get(param or next((c for c in sorted(chips) if c in self.specs), ""))
        if spec is None:
            chip = dev.devtype_name or f"devtype 0x{dev.devtype:02X}"
            self.proposal.not_carried.append(
                f"{where}{disabled}: no bundled parameter type for {chip}; today it is found by "
                f"probing, in the manifest it needs a type{twice}"
            )
            return
        origin = (
            where if start is None else f"{where}; boot console line {start.line}: '{start.text}'"
        )
        inst = self.add(spec.name, dev.bus, dev.address, origin)
        if later is not None:
            inst.notes.append(later.line)
        if taken is not None:
            inst.notes.append(self.taken_line(taken, rotation))
        if off:
            which = "one of its slots was" if len(off) == 1 else f"{len(off)} of its slots were"
            inst.notes.append(f"{', '.join(off)}: {which} disabled for use")
        if twice:
            inst.notes.append(twice.removeprefix("; "))
        if later is None and start is None and not self.params.get("SENS_EXT_I2C_PRB", 1):
            # Only probing starts such a device, and the file turned it off.
            inst.notes.append(
                "SENS_EXT_I2C_PRB = 0: PX4 probed for no external I2C sensor, so nothing in the "
                "file says this one was started (its calibration may be of an earlier setup); "
                "the manifest starts it and arming requires it: drop its line if it is gone"
            )
        self.set_rotation(inst, *rotation, turned)
        self.note_unsettled_row(inst, chips, dev.bus, dev.address, if_run)
        for rot, v in rotations.items():
            if not v:
                continue
            inst.notes.append(
                f"{rot} = {shown_value(v)} stays a classic parameter: calibration applies it; the "
                f"driver's rotation is {rotation[0]} ({rotation[1]})"
            )
            if removed := axes.removed_rotation(rot, v, self.config.version, self.for_release):
                inst.notes.append(removed)

    # -- what the boot console shows, beyond the slots ---------------------------------------

    def console_starts(self) -> None:
        for i, start in enumerate(self.starts):
            if i in self.claimed:
                continue
            at = f", address 0x{start.address:02X}" if start.address is not None else ""
            device = f"{start.driver}, {start.bus_kind} bus {start.bus}{at}"
            found = f"boot console line {start.line}"
            if start.bus_kind == "SPI":
                self.leave_out(found, device, "board", _spi_started(start.external))
                continue
            chips = self.start_chips(start)
            kinds = {e.kind for e in self.table if e.name in chips}
            rotation = self.driver_rotation(start, chips)
            if_run = self.rotation_if_run(chips, start.bus, start.address, start, rotation)
            board = self.started_by_board(
                f"{found}: {device}",
                chips,
                start.bus,
                start.address,
                start,
                None,
                kinds == {"BARO"},
                if_run,
            )
            later = self.later(chips, start.bus, start.address) if board is not None else None
            if board is not None and (later is None or not later.propose):
                # the line is already named: not twice
                self.leave_out(found, device, "board", board.replace(f" ({found})", ""), later)
                continue
            if later is not None:  # the target's board script no longer starts it
                rotation = (later.rotation, f"the -R of PX4 {self.file_release}'s start (above)")
            rotation, turned = self.axes_rotation(chips, start.bus, rotation)
            taken = self.taken_later(chips, start.bus, start.address) if board is None else None
            if taken is not None and self.target is not None:
                self.leave_out(found, device, "board", self.taken_line(taken, rotation))
                continue
            driver = self.start_driver(start)
            if driver is None:
                self.proposal.not_carried.append(
                    f"{found}: '{start.text}': no bundled parameter type for {start.driver}; it "
                    "stays started as today"
                )
                continue
            spec = self.specs[driver.parameter]
            address = start.address
            if address is None:
                address = _default_address(self.store, spec.name)
                self.assume(
                    f"{found}: '{start.text}' names no address (PX4 1.11 prints none, later "
                    f"releases only one the driver sets): {driver.name}'s default "
                    f"0x{address:02X} assumed"
                )
            how = (
                "found by i2c_launcher" if start.launcher else "started outside the board's script"
            )
            if later is not None:  # the file's board script started it, the target's does not
                how = f"started by the board's script of PX4 {self.file_release}"
            inst = self.add(spec.name, start.bus, address, f"{found}: '{start.text}' ({how})")
            if later is not None:
                inst.notes.append(later.line)
            if taken is not None:
                inst.notes.append(self.taken_line(taken, rotation))
            self.set_rotation(inst, *rotation, turned)
            self.note_unsettled_row(inst, chips, start.bus, start.address, if_run)
            if driver.name in BATTERY_INDEX_DRIVERS:
                inst.notes.append(_battery_note(spec.name, _launched_args(start)))

    def launcher_buses(self) -> None:
        """The board's i2c_launcher scans, where the boot console does not show what it found:
        each bus's condition evaluated, what nothing here settles named."""
        buses = tuple(getattr(self.board, "i2c_launcher_buses", ()) or ())
        if not buses or any(s.launcher for s in self.starts):
            return
        when = getattr(self.board, "i2c_launcher_when", "") or ""
        conditions = per_bus(when) if when else {}
        facts = self.facts()
        # Each bus's `i2c_launcher start -b` line, as a start row cites its own (the table gives
        # one for each bus).
        sources = dict(zip(buses, self.board.i2c_launcher_sources, strict=True))
        scanned, notes = [], []
        for bus in buses:
            # A form not read as "bus N: ..." is evaluated whole: its tests are named unread.
            verdict = evaluate(when if conditions is None else conditions.get(bus, ""), facts)
            unchecked = " and ".join(verdict.unchecked)
            if verdict.holds is False:
                if unchecked:
                    notes.append(f"bus {bus} not, by PX4's default: {unchecked} ({sources[bus]})")
                continue
            scanned.append(bus)
            if unchecked:
                notes.append(f"bus {bus} only where {unchecked} ({sources[bus]})")
        if not scanned and not notes:
            return  # a power-monitor switch is 1: the switch's own starts are the truth
        what = (
            "the boot console shows none it started"
            if self.config.console is not None
            else f"a {self.config.kind} does not say which it found"
        )
        shown = ", ".join(str(b) for b in scanned) or "none"
        unless = " when no SENS_EN_INA2xx is 1" if "INA_CONFIGURED" in when else ""
        said = f"; {'; '.join(notes)}" if notes else ""
        self.assume(
            f"the board's i2c_launcher scans I2C bus {shown} for power monitors (INA226, INA228, "
            f"INA238){unless}: {what}{said}"
        )

    def probing(self) -> None:
        name = "SENS_EXT_I2C_PRB"
        if name not in self.params:
            return
        self.use(name)
        value = self.params[name]
        if value:
            found = [i.name for i in self.proposal.instances]
            self.proposal.replaced.append(
                f"{name} = {shown_value(value)}: external I2C devices were found by probing; the "
                f"manifest states its devices ({', '.join(found) or 'none'}) and a missing one "
                "fails the arming check instead of being skipped silently"
            )
        else:
            self.proposal.replaced.append(
                f"{name} = 0: probing was off; the manifest starts the devices it lists"
            )


@dataclass(frozen=True)
class _Upgrade:
    """The releases after the file's whose board scripts a proposal is compared with:
    ``file_release`` (the file's snapshot), each later release with the board's row there
    (oldest first, up to ``target``, else the newest), ``target`` (None: the file's own)."""

    file_release: str
    releases: tuple[tuple[str, Any], ...]
    target: str | None
    #: ``target`` as the user named it (v1.16.0 for the v1.15.0 snapshot).
    asked: str | None


@dataclass(frozen=True)
class _Start:
    """How a release's scripts start a device: ``row`` (a board or switch row), ``board``
    (the board's own start, not a switch's) and its -R (0 without)."""

    row: Any
    board: bool
    rotation: int


@dataclass(frozen=True)
class _Later:
    """What later releases do with a device the file's board script starts (:meth:`_Builder.
    later`): the report's ``line``; ``propose``: the target's board script does not start it;
    the ``rotation`` the file's start gave it and that start (``old``), cited."""

    line: str
    propose: bool
    rotation: int
    old: str


@dataclass(frozen=True)
class _Taken:
    """The first later ``release`` whose board script starts a device, with its ``row``."""

    release: str
    row: Any


def _same_start(a: _Start | None, b: _Start | None) -> bool:
    """Whether two releases start a device alike: neither, or both the board's (or both a
    switch's) with the same -R; a line that only moved is the same start."""
    if a is None or b is None:
        return a is b
    return (a.board, a.rotation) == (b.board, b.rotation)


def _span(first: str, last: str) -> str:
    return f"PX4 {first}" if first == last else f"PX4 {first} .. {last}"


def _describe(now: _Start | None, before: _Start, board: Any) -> str:
    """A later release's start of a device against the file's, ``before``."""
    if now is None:
        script = board.source.partition(" at ")[0]
        return f"no start (not in {script}, nor behind a switch this file sets)"
    rotation = ""
    if now.rotation != before.rotation:
        rotation = f", rotation {now.rotation} (was {before.rotation})"
    how = "the board's" if now.board else f"not the board's; only where {now.row.when}:"
    return f"{how} '{now.row.driver} {now.row.args}' ({now.row.source}){rotation}"


def _buses_path(board: Any) -> str:
    """The file the board's I2C buses were read from."""
    return getattr(board, "i2c_buses_path", "") or "the board's I2C buses"


def _named(dev: devid.DeviceId, slot_kinds: Iterable[str] = ()) -> list[tuple[str, str]]:
    """The (chip, kind) pairs a device's devtype names; of a devtype two chips share (PX4
    1.13's 0x4C: SDP33 DIFF_PRESS, LPS33HW BARO), those of the slots' sensor kinds."""
    names = (dev.devtype_name or "").split("/")
    kinds = (dev.devtype_kind or "").split("/")
    if len(kinds) != len(names):  # no kind for each chip: every chip, every kind
        return [(n, k) for n in names for k in kinds]
    pairs = list(zip(names, kinds, strict=True))
    fitting = [(n, k) for n, k in pairs if k in set(slot_kinds)]
    return fitting if len(pairs) > 1 and fitting else pairs


def _chips(dev: devid.DeviceId, slot_kinds: Iterable[str] = ()) -> set[str]:
    """The chip names of a device's devtype (of the slots' kinds, see :func:`_named`), older
    eras' names as today's drivers know them."""
    names = {n for n, _ in _named(dev, slot_kinds)} - {""}
    return names | {RENAMED_CHIPS[n] for n in names if n in RENAMED_CHIPS}


def _slot_kind(name: str) -> str:
    """``MAG`` of ``CAL_MAG0_ID``, ``BARO`` of the log topic ``sensor_baro 0``."""
    m = _CAL_ID.fullmatch(name)
    return m["sensor"] if m else _TOPIC_KIND.get(name.partition(" ")[0], name)


def _default_address(store: Any, param: str) -> int:
    from px4params.store.spec import metadata_default

    spec = store.spec(param)
    value = metadata_default(store.schema, spec.data_type.key)
    bus = value.get("bus", {})
    return int(bus.get("i2c", {}).get("address", 0))


def _differs(old: Any, new: Any) -> bool:
    if isinstance(old, float) or isinstance(new, float):
        return struct.pack("<f", float(old)) != struct.pack("<f", float(new))
    return bool(old != new)


#: The power-monitor switches that keep PX4's i2c_launcher from running (SENS_EN_INA238, ...).
_INA_SWITCH = re.compile(r"SENS_EN_INA2\d\d")


def _launched_args(start: DriverStart) -> str | None:
    """The options of an i2c_launcher line's command (a driver's own line prints none)."""
    m = _LAUNCHED.search(start.text) if start.launcher else None
    return m[1] if m else None


def _battery_note(param: str, args: str | None) -> str:
    """What today's start line (its options ``args``; None: not known) gives as the battery
    index, which ``param`` has no field for."""
    if args is None:
        return (
            "today's start line also sets a battery index (-t), which nothing here names "
            f"(without -t the driver uses 1): {param} has no field for it"
        )
    m = _BATTERY_INDEX.search(args)
    index = f"-t {m[1]}" if m else "no -t: the driver's 1"
    return f"today's start line also sets the battery index ({index}): {param} has no field for it"


@dataclass(frozen=True)
class _Place:
    """Where a switch starts its driver: bus, address (None: the driver's default), why (the
    evidence, or "") and the start line's options where known (for its battery index)."""

    bus: int
    address: int | None
    why: str
    args: str | None


def migrate(
    config: OldConfig,
    schema: Schema | None = None,
    table: devid.DevtypeTable | str | None = None,
    board: Any = None,
    target_release: str | None = None,
) -> Proposal:
    """Proposes a manifest for ``config`` (see the module doc). ``table``: the devtype table
    (default: the one of the file's firmware era); ``board``: a board of
    :mod:`px4params.vehicle.boards` or its PX4 name (default: a log's ``ver_hw``'s);
    ``target_release``: the PX4 release the vehicle will run, such as v1.16.2 or main (default: the
    file's own): a device the file's board script starts and the target's does not becomes an
    instance."""
    from px4params.dsdl.schema import load_schema

    assumptions: list[str] = []
    if table is None:
        if config.version is not None:
            table = devid.table_for_version(config.version)
        else:
            table, why = devid.table_for_parameters(config.params)
            assumptions.append(why)
    names = devid.load_table(table) if isinstance(table, str) else table
    if config.version is not None and names.label != devid.table_for_version(config.version):
        # a table asked for that is not the file's own era's: its device IDs may name other chips
        version = ".".join(map(str, config.version))
        assumptions.append(
            f"--table {names.label}: the file is of PX4 {version}, whose device IDs follow the "
            f"{devid.table_for_version(config.version)} devtype table; they are decoded with "
            f"{names.label} as asked (without --table, the file's own)"
        )
    chosen = _board(config, board, assumptions)
    upgrade = _upgrade(config, chosen, target_release, assumptions)
    builder = _Builder(
        config,
        schema or load_schema(include_dronecan=False),
        names,
        chosen,
        assumptions,
        upgrade,
        target_release,
    )
    proposal = builder.run()
    proposal.target_release = upgrade.asked
    proposal.compared = [release for release, _ in upgrade.releases]
    if chosen is None and board is None and config.hardware is None:
        _name_boards_it_fits(proposal, builder, target_release)
    hitl = config.params.get("SYS_HITL", 0)
    if hitl > 0:
        # ROMFS/px4fmu_common/init.d/rcS: `if param greater SYS_HITL 0` runs the simulator's
        # sensors instead of rc.board_sensors and rc.sensors
        proposal.assumptions.append(
            f"SYS_HITL = {shown_value(hitl)}: hardware in the loop, where PX4 starts neither the "
            "board's sensor script nor rc.sensors (rcS); what it logged is the simulator's, and "
            "the proposal is for the vehicle flying with SYS_HITL 0"
        )
    return proposal


#: Boards whose SPI sensors a file matches that are tried as its board: more, and the sensors
#: say too little to name one.
MAX_BOARD_GUESSES = 4


def _name_boards_it_fits(proposal: Proposal, builder: _Builder, target: str | None) -> None:
    """A file that names no board (a .params file) is migrated without the board's script, so
    an instance may be a device the board starts itself (fmu-v5's GPS mast compass: ``ist8310
    -X -b 1 -R 10``), which the manifest would start again on other options. Where the file's
    SPI sensors are those of at most :data:`MAX_BOARD_GUESSES` boards of the table, each of
    those under which a proposed instance is the board's is named in a note of that instance:
    the integrator knows the board, the file does not."""
    table = _board_table()
    config = proposal.config
    ids = (v for n, v in config.params.items() if _CAL_ID.fullmatch(n) and isinstance(v, int))
    devices = [devid.decode(v, builder.table) for v in ids if 0 < v <= devid.MAX_DEVICE_ID]
    spi = {frozenset(c) for dev in devices if dev.bus_type == 2 and (c := _chips(dev))}
    if table is None or not spi or not proposal.instances:
        return
    version = "v" + ".".join(map(str, config.version)) if config.version else None
    fits = []
    for board in table.boards_for(version):
        started = [builder.start_chips(d.driver) for d in board.devices if d.bus_kind == "SPI"]
        if all(any(chips & s for s in started) for chips in spi):
            fits.append(board.name)
    if len(fits) > MAX_BOARD_GUESSES:
        return
    sensors = ", ".join(sorted({"/".join(sorted(chips)) for chips in spi}))
    for name in fits:
        try:
            theirs = migrate(config, builder.store.schema, builder.table, name, target)
        except MigrationError:  # a board the table has only for other releases
            continue
        kept = {inst.origin.partition(": ")[0] for inst in theirs.instances}
        for inst in proposal.instances:
            found = inst.origin.partition(": ")[0]
            left = next((x for x in theirs.left_out if x.found == found), None)
            if found in kept or left is None or left.reason != "board":
                continue
            why = left.line.removeprefix(f"{left.found}: {left.device}: ")
            line = (
                f"{inst.name}: the file's SPI sensors ({sensors}) are ones {name} starts; on a "
                f"{name}, this {left.device.partition(' ')[0]} is the board's own, {why}: "
                f"--board {name} leaves it out"
            )
            inst.notes.append(line)


def _upgrade(config: OldConfig, board: Any, target: str | None, assumptions: list[str]) -> _Upgrade:
    """The board's rows at the releases after the file's, up to ``target`` (None: the newest
    the table knows, compared only); a ``target`` between two of the table's snapshots is judged
    by the older (said in ``assumptions``); one that is no PX4 version, older than every snapshot
    or older than the file's, is refused."""
    table = _board_table()
    known = table.releases if table is not None else ()
    if target is not None:  # as PX4 spells them: MAIN, V1.15.0 are main, v1.15.0
        target = target.strip().lower()
    asked = target
    if target is not None and target not in known:
        # a release between two snapshots runs the older one's scripts, as a log of it is read
        target = _snapshot_of(table, target, known)
    if table is None or board is None or not hasattr(board, "releases"):
        if target is not None:
            assumptions.append(
                f"--target-release {asked}: no board known, so no board script is compared "
                "(--board NAME names it)"
            )
        return _Upgrade("", (), None, None)
    if target != asked:
        assumptions.append(
            f"--target-release {asked}: the board table has no {asked}; its scripts are "
            f"taken as at {target}, "
            + (
                "the newest release it has at or before it"
                if target != known[-1]
                else "the newest it has (newer than every release it has)"
            )
        )
    # The file's snapshot; a file naming no release is judged with today's row (its newest).
    version = "v" + ".".join(map(str, config.version)) if config.version else None
    own = (table.snapshot_for(version) if version else None) or board.releases[-1]
    variants = table.variants(board.name)
    first = variants[0].releases[0] if variants else own
    judged = max(own, board.releases[0], key=known.index)  # a row newer than the file's release
    if version and known.index(first) > known.index(own):
        # The board came after the file's release in the table (a vendor branch had it first):
        # a later release's script is what the file is judged by.
        assumptions.append(
            f"board {board.name}: in the board table from PX4 {first} on, not at {own}, the "
            f"newest release it has at or before this file's {version[1:]}; what its script "
            f"starts is taken as at {judged}"
        )
    elif version and _not_its_own(config.version, own):
        # the file's release is not in the table: said as --target-release says it
        newest = "newer than every release it has" if own == "main" else "at or before it"
        assumptions.append(
            f"board {board.name}: the board table has no {version[1:]}, this file's release; "
            f"what its script starts is taken as at {own} ({newest})"
        )
    own = judged
    later = known[known.index(own) + 1 :]
    if target is not None:
        if known.index(target) < known.index(own):
            # a file naming no release has no release to be older than: say what was taken
            whose = (
                f"the file's PX4 {own}"
                if version
                else (f"PX4 {own}, taken for a file that names no release (no '# Version' line)")
            )
            raise MigrationError(
                f"--target-release {asked}: older than {whose} (expected one of "
                f"{', '.join(known[known.index(own) :])})"
            )
        later = later[: later.index(target) + 1] if target in later else ()
    # by_name takes a version; None is the newest snapshot (main)
    rows = tuple((r, table.by_name(board.name, None if r == known[-1] else r)) for r in later)
    return _Upgrade(
        own,
        tuple((r, row) for r, row in rows if row is not None),
        target if target != own else None,
        asked if target != own else None,
    )


def _not_its_own(version: tuple[int, int, int] | None, snapshot: str) -> bool:
    """Whether the board table's ``snapshot`` is of another release series than ``version``
    (``main`` is of none)."""
    from px4params.vehicle.boards import release_version  # (the table's module: loaded)

    return snapshot == "main" or version is None or version[:2] != release_version(snapshot)[:2]


def _spi_started(external: bool) -> str:
    """Who started an SPI sensor, by where the boot console placed it: a board's script starts
    its own (``-s``); one on an external bus (``-S``, shown "(external, equal to '-b N')") is
    started by a board's script or by a switch of rc.sensors (``SENS_EN_ADIS164X``)."""
    if external:
        return "SPI sensor on an external bus: started by PX4's startup scripts"
    return "internal SPI sensor: started by the board's startup script"


def _snapshot_of(table: BoardTable | None, release: str, known: tuple[str, ...]) -> str:
    """The snapshot of the board table whose scripts PX4 ``release`` runs."""
    if table is None:
        raise MigrationError(
            f"--target-release {release}: this installation has no board table to judge it by"
        )
    expected = f"expected a PX4 version from {known[0]} on, such as v1.16.0, or {known[-1]}"
    try:
        snapshot = table.snapshot_for(release)
    except BoardsError:
        snapshot, problem = None, "not a PX4 release"
    else:
        problem = "older than every release of the board table"
    if snapshot is None:
        raise MigrationError(f"--target-release {release}: {problem} ({expected})")
    return snapshot


def _board_table() -> BoardTable | None:
    """The bundled board table, or None where this installation has none."""
    try:
        from px4params.vehicle.boards import load_boards
    except ImportError:  # the board table is not part of this installation
        return None
    return load_boards()


def _board(config: OldConfig, board: Any, assumptions: list[str]) -> Any:
    """The board whose table applies, or None (with the assumption said)."""
    if board is not None and not isinstance(board, str):
        return board
    if board is not None:
        table = _board_table()
        if table is None:
            raise MigrationError(
                f"--board {board}: this installation has no board table (px4params.vehicle.boards)"
            )
        version = "v" + ".".join(map(str, config.version)) if config.version else None
        found = table.by_name(board, version)
        if found is None and table.variants(board):
            # A board the table has, but not for a release this old: its scripts then differ.
            raise MigrationError(
                f"--board {board}: the board table describes PX4 {table.releases[0]} and later, "
                f"{config.source} is of PX4 {'.'.join(map(str, config.version or ()))} (run "
                "without --board: the parameters and assumptions decide)"
            )
        if found is None:
            raise MigrationError(
                f"unknown board {board!r} (expected a PX4 board name such as px4_fmu-v6c)"
            )
        return found
    if config.hardware is not None:
        table = _board_table()
        # The release picks the board's facts of that PX4 version.
        found = table.for_ulog(config.hardware, config.release) if table is not None else None
        if found is None:
            where = "not in the board table" if table is not None else "no board table here"
            known = [b for b in table.all() if config.hardware.upper() in b.ver_hw] if table else []
            if known and table is not None and config.version is not None:
                where = (
                    f"{known[0].name} in the board table from PX4 {table.releases[0]} on, not "
                    f"for this log's {'.'.join(map(str, config.version))}"
                )
            assumptions.append(
                f"board {config.hardware}: {where}; what its script starts is judged from the "
                "parameters and the boot console"
            )
        return found
    assumptions.append(
        f"no board information in a {config.kind}: sensors with CAL_MAGn_ROT = -1 (Internal) "
        "and I2C barometers are taken as the board's, other external I2C sensors as found by "
        "probing (--board NAME uses the board's table)"
    )
    return None
