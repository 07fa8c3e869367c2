"""PX4 boards as data: what each board's startup script starts, per PX4 release.

A PX4 flight controller starts its own sensors before any manifest is read: the board's
``init/rc.board_sensors`` (its IMUs, barometers and compasses, with the ``-R`` rotation of how
they are mounted), its ``i2c_launcher`` (power monitors found on a bus) and, behind parameters
such as ``SENS_EN_INA238``, the drivers that a switch turns on (in that script and in the
``rc.sensors`` every board runs). Migration needs to know these to leave them out of a manifest
and to keep calibration rotations apart from driver rotations.

The facts live in ``boards.toml`` beside the package data, transcribed from PX4-Autopilot at
a few snapshots (tagged releases and branches, listed in its ``[[snapshot]]`` tables) by
``scripts/transcribe_boards.py``. Its keys:

``[[snapshot]]``
    ``release`` (``"v1.14.0"``, ``"v1.18"`` for a release branch, ``"main"``), ``ref``,
    ``commit`` (40 hex digits) and ``date`` of the PX4-Autopilot tree read; optional
    ``x_b_counts_external = true`` where that tree's ``I2CBusIterator`` takes ``-X -b N`` as the
    N-th external bus (v1.11.0).
``[[board]]``, one row per board and run of snapshots over which its facts did not change
    ``name`` (PX4 target without the build label, ``px4_fmu-v6c``), ``label``, ``ver_hw`` (what
    PX4 writes as the ULog's ``ver_hw``: the target name upper-cased with ``-`` made ``_``, then
    older spellings), ``releases`` (the snapshots), ``path`` (the script read),
    ``external_i2c_buses`` / ``internal_i2c_buses`` (the board's ``src/i2c.cpp``, or its
    ``board_config.h`` where there is none, named by ``i2c_buses_path``, ``i2c_buses_lines``
    the line of each external then internal bus there), optional
    ``external_i2c_buses_when`` (a board whose ``board_config.h`` defines
    ``BOARD_OVERRIDE_I2C_BUS_EXTERNAL`` and whose ``i2c.cpp`` decides at run time which buses are
    external: ``{ when, buses, line }``, where condition ``when`` holds its external buses are
    ``buses`` and its other buses internal, elsewhere the two lists hold; ``line``: the test's
    line in ``i2c_buses_path``),
    ``i2c_launcher_buses`` with ``i2c_launcher_lines`` (the line of each bus's ``i2c_launcher
    start -b``) and optional ``i2c_launcher_when``, optional ``external_spi_buses`` with
    ``spi_buses_path`` and ``spi_buses_lines`` (a board whose scripts start a driver with ``-S``:
    its ``src/spi.cpp``'s external buses in the order of its ``px4_spi_buses``, as PX4 numbers
    them, and the line of each), and the lists ``device`` (started whatever the parameters) and
    ``switch`` (started behind a parameter).
``[[i2c_launcher]]``
    ``releases``, ``path``, ``args`` (the command it runs for a device it finds, ``{bus}`` and
    ``{index}`` filled in) and a ``probe`` list (``driver``, ``kind``, ``address``, ``line``) in
    the order it tries them: ``src/systemcmds/i2c_launcher``, the same for every board.
``[[rc_sensors]]``
    ``releases``, ``path`` and a ``switch`` list: ``ROMFS/px4fmu_common/init.d/rc.sensors``,
    the same for every board.

A device or switch entry has ``driver``, ``kind`` (mag, baro, imu, power, other), ``bus_kind``
(I2C or SPI), ``internal`` (PX4's ``-I``/``-s`` against ``-X``/``-S``), ``args`` (the start
command's options as written), ``line`` (in the newest snapshot of the row) and optional
``bus``, ``address``, ``rotation`` (the ``-R`` value, PX4's rotation enum) and ``when`` (the
shell conditions around it, e.g. ``hw_type in V6C000002,V6C002002`` or ``$HAVE_PM2 == yes``).
An ``icm20948`` or ``mpu9250`` started with ``-M`` (the driver's "Enable Magnetometer") is
listed twice, as ``imu`` and as ``mag``. A switch entry also names its ``param``.

An I2C start runs where PX4's ``I2CBusIterator`` (platforms/common/i2c.cpp) finds a bus: ``-X``
tries only external buses, ``-I`` only internal ones, and ``-b N`` only bus N if it is of that
kind, so a ``-b`` of the other kind finds none and the driver never starts
(:meth:`Board.buses_of`); at a snapshot with ``x_b_counts_external``, ``-X -b N`` is instead
the N-th external bus in the order of the board's ``px4_i2c_buses`` (``i2c_buses_lines``).
An SPI start runs where PX4's ``SPIBusIterator`` (platforms/common/spi.cpp) finds a bus: ``-s
-b N`` on internal bus N, ``-S -b N`` on the N-th of the board's external SPI buses
(``external_spi_buses``; ``-S`` alone: the first), so a board with fewer never starts it; a
``-S`` start on a board whose SPI buses the table does not know is on no bus it can name.
A switch started with ``-X`` and no ``-b`` probes every external I2C bus, so
:class:`SwitchStart` rows are one per bus the start can be on, each with the condition under
which its bus is of the start's kind (``bus_when``, from ``external_i2c_buses_when``).

A release picks the newest snapshot at or before it (a v1.16 log is read with v1.15.0's facts,
as no v1.16/v1.17 snapshot was read), a release series newer than every release snapshot picks
``main``; releases older than the oldest snapshot have no entry.
Every problem with the file is a :class:`BoardsFileError` of one line naming the file, the row
and what is wrong.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.resources
import math
import re
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NoReturn

from px4params.data import VALUE_SETS_TOML
from px4params.errors import BoardsError, BoardsFileError

__all__ = [
    "Board",
    "BoardDevice",
    "BoardTable",
    "BoardsError",
    "BoardsFileError",
    "BusOverride",
    "LauncherProbe",
    "SwitchStart",
    "load_boards",
    "parse_boards",
    "release_version",
    "render_markdown",
]

#: What a device measures, as the table names it.
KINDS = ("mag", "baro", "imu", "power", "other")
BUS_KINDS = ("I2C", "SPI")
_UPSTREAM = "PX4/PX4-Autopilot"
_MAIN = "main"
_VERSION = re.compile(r"v?(\d+)\.(\d+)(?:\.(\d+))?(?:[-+~][0-9A-Za-z.\-]*)?")


@dataclass(frozen=True)
class BoardDevice:
    """A driver the board's script starts whatever the parameters."""

    driver: str
    kind: str
    bus_kind: str
    bus: int | None
    address: int | None
    rotation: int | None
    internal: bool
    source: str
    #: Shell conditions around the start (hardware revision, an earlier start failing), or "".
    when: str = ""
    #: The start command's options as written in the script.
    args: str = ""


@dataclass(frozen=True)
class SwitchStart:
    """A driver started while a parameter (``param``) has the value ``when`` names."""

    param: str
    driver: str
    bus: int
    address: int | None
    args: str
    source: str
    kind: str = "other"
    bus_kind: str = "I2C"
    rotation: int | None = None
    internal: bool = False
    when: str = ""
    #: The condition under which ``bus`` is of the start's kind (the board's
    #: :class:`BusOverride`'s ``when`` or its negation), or "" where it always is.
    bus_when: str = ""


@dataclass(frozen=True)
class BusOverride:
    """A board's own ``px4_i2c_bus_external`` (``BOARD_OVERRIDE_I2C_BUS_EXTERNAL``): where
    ``when`` holds, ``external`` are its external I2C buses and its other buses internal;
    elsewhere its ``external_i2c_buses`` and ``internal_i2c_buses`` hold. ``source`` cites the
    line of the test."""

    when: str
    external: tuple[int, ...]
    source: str


@dataclass(frozen=True)
class LauncherProbe:
    """An address the board's ``i2c_launcher`` tries on each of its buses, and the driver it
    starts there (``args`` with ``{bus}`` and ``{index}``, the battery index, to fill in)."""

    driver: str
    kind: str
    address: int
    args: str
    source: str


@dataclass(frozen=True)
class Board:
    """One board over the PX4 snapshots in ``releases``."""

    name: str
    label: str
    ver_hw: tuple[str, ...]
    devices: tuple[BoardDevice, ...]
    i2c_launcher_buses: tuple[int, ...]
    switches: tuple[SwitchStart, ...]
    source: str
    releases: tuple[str, ...] = ()
    external_i2c_buses: tuple[int, ...] = ()
    internal_i2c_buses: tuple[int, ...] = ()
    #: Shell conditions around the launcher per bus (``bus 1: $INA_CONFIGURED == no; ...``: it
    #: runs only while no SENS_EN_INA2xx switch is 1), or "".
    i2c_launcher_when: str = ""
    #: What the launcher tries on each of ``i2c_launcher_buses``, in order (empty without one).
    i2c_launcher_probes: tuple[LauncherProbe, ...] = ()
    #: The script's ``i2c_launcher start`` line of each of ``i2c_launcher_buses``, cited as a
    #: start's ``source`` is.
    i2c_launcher_sources: tuple[str, ...] = ()
    #: The newest of ``releases`` as a citation names it ("v1.15.0 (tag v1.15.0, 30e763b678,
    #: 2024-08-27)"): a line of the board's scripts is cited at it (:meth:`cite`).
    at: str = ""
    #: The board's own ``px4_i2c_bus_external``, or None: its two lists hold on all hardware.
    external_i2c_buses_when: BusOverride | None = None
    #: (bus, the line of i2c_buses_path naming it, cited) of each of its I2C buses.
    i2c_bus_sources: tuple[tuple[int, str], ...] = ()
    #: The file its I2C buses were read from ("": none, the table does not know them).
    i2c_buses_path: str = ""
    #: Its I2C buses in the order of its ``px4_i2c_buses`` (the lines of i2c_buses_path), the
    #: order PX4's I2CBusIterator visits them.
    i2c_bus_order: tuple[int, ...] = ()
    #: Whether this release's I2CBusIterator takes ``-X -b N`` as the N-th external bus in
    #: :attr:`i2c_bus_order` (v1.11.0: platforms/common/i2c.cpp:76 compares ``-b`` with
    #: ``_external_bus_counter``), not bus N (PX4 787f9c1213, first in v1.12.0).
    x_b_counts_external: bool = False
    #: Its external SPI buses in the order of its ``px4_spi_buses`` (``-S -b N`` is the N-th),
    #: each with the line of spi_buses_path naming it, cited; empty where the table does not
    #: know them (:attr:`spi_buses_path` "").
    external_spi_buses: tuple[tuple[int, str], ...] = ()
    #: The file its external SPI buses were read from ("": none).
    spi_buses_path: str = ""

    def i2c_bus_source(self, bus: int) -> str | None:
        """The line that makes I2C ``bus`` the board's (``initI2CBusInternal(2)``), cited as
        a start's ``source`` is; None where the table has none."""
        return next((source for b, source in self.i2c_bus_sources if b == bus), None)

    def cite(self, path: str, line: int) -> str:
        """``line`` of PX4-Autopilot's ``path`` as the board's rows cite theirs."""
        return _cite(path, line, self.at)

    def i2c_buses(self, internal: bool, overridden: bool = False) -> tuple[int, ...]:
        """The board's internal (or external) I2C buses; ``overridden``: as they are where its
        :attr:`external_i2c_buses_when` holds (a board without one: its lists)."""
        override = self.external_i2c_buses_when if overridden else None
        return _bus_lists(self.external_i2c_buses, self.internal_i2c_buses, override)[internal]

    def buses_of(
        self, start: BoardDevice | SwitchStart, overridden: bool = False
    ) -> tuple[int, ...]:
        """The buses a start can be on, as PX4's I2CBusIterator tries them: an I2C start's
        internal (``-I``) or external (``-X``) buses, of them its ``-b``; a ``-b`` the board
        names as of the other kind, none (PX4 never starts it). SPI, as its SPIBusIterator
        does: ``-s``'s ``-b``, () without; ``-S``, the ``-b``-th (else the first) of
        :attr:`external_spi_buses`, () where there is no such bus or the table does not know
        them. ``overridden``: where the board's :attr:`external_i2c_buses_when` holds."""
        external, internal = self.i2c_buses(False, overridden), self.i2c_buses(True, overridden)
        return _start_buses(
            start.bus, start.bus_kind, start.internal, external, internal, self._iterator()
        )

    def _iterator(self) -> _Iterator:
        return _Iterator(
            bool(self.i2c_buses_path),
            self.i2c_bus_order,
            self.x_b_counts_external,
            _spi_order(self.spi_buses_path, self.external_spi_buses),
        )

    def bus_conditions(self, start: BoardDevice | SwitchStart) -> tuple[tuple[int, str], ...]:
        """Each bus a start can be on (:meth:`buses_of`) with the condition under which it
        is of the start's kind: "" on every hardware, else the board's
        :attr:`external_i2c_buses_when` condition or its negation."""
        return _bus_conditions(
            start.bus,
            start.bus_kind,
            start.internal,
            self.external_i2c_buses,
            self.internal_i2c_buses,
            self.external_i2c_buses_when,
            self._iterator(),
        )


@dataclass(frozen=True)
class _Iterator:
    """What PX4's bus iterators need of a board beyond its two I2C lists: ``known``, the lists
    are its ``px4_i2c_buses`` (its i2c.cpp); ``order``, their order there; ``counts``, ``-X -b
    N`` is the N-th external bus of that order (:attr:`Board.x_b_counts_external`);
    ``spi_external``, its external SPI buses in their order (None: not known)."""

    known: bool
    order: tuple[int, ...]
    counts: bool
    spi_external: tuple[int, ...] | None


def _spi_order(path: str, buses: Sequence[tuple[int, str]]) -> tuple[int, ...] | None:
    """A board's external SPI buses as the iterator counts them; None where none were read."""
    return tuple(bus for bus, _ in buses) if path else None


def _bus_lists(
    external: Sequence[int], internal: Sequence[int], override: BusOverride | None
) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(external, internal) I2C buses of a board, as its override makes them where given."""
    if override is None:
        return tuple(external), tuple(internal)
    every = sorted({*external, *internal})
    return (
        tuple(b for b in every if b in override.external),
        tuple(b for b in every if b not in override.external),
    )


def _start_buses(
    bus: int | None,
    bus_kind: str,
    internal: bool,
    external_buses: Sequence[int],
    internal_buses: Sequence[int],
    iterator: _Iterator,
) -> tuple[int, ...]:
    """See :meth:`Board.buses_of`. Where the lists are the board's ``px4_i2c_buses`` (its
    i2c.cpp), the only buses PX4's iterator visits, a ``-b`` neither names finds none; a
    board whose buses the table does not know keeps its ``-b``."""
    if bus_kind != "I2C":
        if internal:
            return (bus,) if bus is not None else ()
        # -S: the N-th external SPI bus (SPIBusIterator's _external_bus_counter), -S alone 1
        spi, nth = iterator.spi_external or (), 1 if bus is None else bus
        return (spi[nth - 1],) if 1 <= nth <= len(spi) else ()
    own, other = (internal_buses, external_buses) if internal else (external_buses, internal_buses)
    if bus is None:
        return tuple(own)
    known = iterator.known
    if not internal and known and iterator.counts:
        counted = [b for b in iterator.order if b in own]  # ++_external_bus_counter per bus
        return (counted[bus - 1],) if 1 <= bus <= len(counted) else ()
    if bus in own or not (known or bus in other):
        return (bus,)
    return ()


def _bus_conditions(
    bus: int | None,
    bus_kind: str,
    internal: bool,
    external: Sequence[int],
    internal_buses: Sequence[int],
    override: BusOverride | None,
    iterator: _Iterator,
) -> tuple[tuple[int, str], ...]:
    """See :meth:`Board.bus_conditions`."""
    plain = _start_buses(bus, bus_kind, internal, external, internal_buses, iterator)
    if override is None:
        return tuple((b, "") for b in plain)
    lists = _bus_lists(external, internal_buses, override)
    over = _start_buses(bus, bus_kind, internal, *lists, iterator)
    found = [(b, "" if b in over else f"not {override.when}") for b in plain]
    found += [(b, override.when) for b in over if b not in plain]
    return tuple(sorted(found))


#: A board's switch starts as read, before expansion per bus: (starts with their sources,
#: external I2C buses, internal I2C buses, its override of them, what its I2CBusIterator
#: needs beyond them, ver_hw).
_Pending = tuple[
    list[tuple[dict[str, Any], str]],
    tuple[int, ...],
    tuple[int, ...],
    BusOverride | None,
    _Iterator,
    tuple[str, ...],
]


def _cite(path: str, line: int, at: str) -> str:
    return f"{_UPSTREAM} {path}:{line} at {at}"


@dataclass(frozen=True)
class _Snapshot:
    release: str
    ref: str
    commit: str
    date: str
    order: tuple[float, ...]
    #: PX4's I2CBusIterator there takes ``-X -b N`` as the N-th external bus (see
    #: :attr:`Board.x_b_counts_external`).
    x_b_counts_external: bool

    def describe(self) -> str:
        return f"{self.release} ({self.ref}, {self.commit[:10]}, {self.date})"


def release_version(release: str | int) -> tuple[int, int, int]:
    """``(major, minor, patch)`` of a PX4 release: ``"v1.13.0"``, ``"1.15.0-beta1"``, or a ULog's
    ``ver_sw_release`` integer (``0xMMmmpptt``)."""
    if isinstance(release, int) and not isinstance(release, bool):
        if not 0 <= release < 1 << 32:
            raise BoardsError(f"release {release} is no ULog ver_sw_release (0 .. 2**32-1)")
        return (release >> 24, (release >> 16) & 0xFF, (release >> 8) & 0xFF)
    if isinstance(release, str):
        m = _VERSION.fullmatch(release.strip())
        if m:
            return (int(m.group(1)), int(m.group(2)), int(m.group(3) or 0))
    raise BoardsError(f"release {release!r} is no PX4 version (expected e.g. 'v1.13.0')")


def _snapshot_order(release: str) -> tuple[float, ...]:
    if release == _MAIN:
        return (math.inf,)
    return tuple(float(x) for x in release_version(release))


class BoardTable:
    """Every board of ``boards.toml``, looked up by ULog ``ver_hw`` or by name, per release."""

    def __init__(
        self,
        snapshots: Sequence[_Snapshot],
        rows: Mapping[tuple[str, str], Board],
        names: Sequence[str],
        ver_hw: Mapping[str, str],
        rc_sensors: Mapping[str, Sequence[tuple[Mapping[str, Any], str]]] | None = None,
        pending: Mapping[tuple[str, str], _Pending] | None = None,
    ) -> None:
        self._snapshots = tuple(sorted(snapshots, key=lambda s: s.order))
        self._rows = dict(rows)
        self._names = tuple(names)
        self._ver_hw = dict(ver_hw)
        #: release -> rc.sensors switch starts as written (no bus: every external bus).
        self._rc_sensors = dict(rc_sensors or {})
        #: (board, release) -> switch starts not yet expanded per bus (most are never asked for).
        self._pending = dict(pending or {})

    def _row(self, key: tuple[str, str]) -> Board | None:
        board = self._rows.get(key)
        if board is not None and key in self._pending:
            starts, external, internal, override, iterator, ver_hw = self._pending.pop(key)
            switches = tuple(
                switch
                for start, source in starts
                for switch in _expand(start, source, external, internal, override, iterator, ver_hw)
            )
            board = self._rows[key] = dataclasses.replace(board, switches=switches)
        return board

    @property
    def releases(self) -> tuple[str, ...]:
        """The snapshots the table was read from, oldest first."""
        return tuple(s.release for s in self._snapshots)

    def snapshot_for(self, release: str | int | None) -> str | None:
        """The snapshot whose facts hold for ``release`` (None, or a release series newer than
        every release snapshot: today's, ``main``); None when the release is older than every
        snapshot."""
        if release is None:
            return self._snapshots[-1].release
        wanted = tuple(float(x) for x in release_version(release))
        released = [s for s in self._snapshots if s.release != _MAIN]
        if (
            self._snapshots[-1].release == _MAIN
            and released
            and wanted[:2] > released[-1].order[:2]
        ):
            return _MAIN  # a release newer than every release snapshot: today's main
        chosen = None
        for snap in self._snapshots:
            if snap.order <= wanted:
                chosen = snap.release
        return chosen

    def by_name(self, name: str, release: str | int | None = None) -> Board | None:
        """The board ``name`` (``px4_fmu-v6c``) as PX4 ``release`` starts it (None: today).

        A board missing from that release's snapshot is described by its nearest row: its oldest
        when the release is older (a vendor branch had the board before the tag did: the MR-Tropic
        log of ``v1.15.0-beta``), its newest when the board was later removed. None when the
        release is older than every snapshot or the table has no such board."""
        snap = self.snapshot_for(release)
        if snap is None:
            return None
        found = self._row((name, snap))
        if found is not None:
            return found
        rows = self.variants(name)
        if not rows:
            return None
        order = [s.release for s in self._snapshots]
        return rows[0] if order.index(rows[0].releases[0]) > order.index(snap) else rows[-1]

    def for_ulog(self, ver_hw: str, release: str | int | None) -> Board | None:
        """The board a ULog's ``ver_hw`` (``PX4_FMU_V6C``) names, as ``release`` (the log's
        ``ver_sw_release``, None if it has none) starts it."""
        name = self._ver_hw.get(ver_hw.strip().upper())
        return None if name is None else self.by_name(name, release)

    def all(self) -> tuple[Board, ...]:
        """Every board once, as the newest snapshot that has it describes it."""
        newest: dict[str, Board] = {}
        for snap in self._snapshots:
            for name in self._names:
                row = self._row((name, snap.release))
                if row is not None:
                    newest[name] = row
        return tuple(newest[n] for n in self._names if n in newest)

    def boards_for(self, release: str | int | None) -> list[Board]:
        """Every board as PX4 ``release`` starts it (None: today), in the table's order; none
        when the release is older than every snapshot."""
        snap = self.snapshot_for(release)
        return [] if snap is None else self._boards_at(snap)

    def _boards_at(self, release: str) -> list[Board]:
        found = (self._row(key) for key in list(self._rows) if key[1] == release)
        return [row for row in found if row is not None]

    def variants(self, name: str) -> tuple[Board, ...]:
        """Every row of board ``name``, oldest first (one per run of unchanged snapshots)."""
        newest: dict[tuple[str, ...], Board] = {}  # a TOML row, as its newest snapshot reads
        for snap in self._snapshots:
            row = self._row((name, snap.release))
            if row is not None:
                newest[row.releases] = row
        return tuple(newest.values())


# -- reading the file -------------------------------------------------------------------------


class _Row:
    """Checks the keys of one TOML table, naming it in every error."""

    def __init__(self, file: str, where: str, table: Any) -> None:
        self.file, self.where = file, where
        if not isinstance(table, dict):
            self.fail(f"expected a table, got {type(table).__name__}")
        self.table: dict[str, Any] = table

    def fail(self, problem: str) -> NoReturn:
        raise BoardsFileError(f"{self.file}: {self.where}: {problem}")

    def only(self, required: Sequence[str], optional: Sequence[str] = ()) -> None:
        for key in required:
            if key not in self.table:
                self.fail(f"missing key {key!r}")
        for key in self.table:
            if key not in required and key not in optional:
                self.fail(
                    f"unknown key {key!r} (expected one of {', '.join((*required, *optional))})"
                )

    def text(self, key: str, default: str | None = None) -> str:
        value = self.table.get(key, default)
        if not isinstance(value, str) or (default is None and not value):
            self.fail(f"{key} {value!r} is not a non-empty string")
        return value

    def optional_number(self, key: str, low: int, high: int) -> int | None:
        return None if self.table.get(key) is None else self.number(key, low, high)

    def number(self, key: str, low: int, high: int) -> int:
        value = self.table.get(key)
        if not isinstance(value, int) or isinstance(value, bool):
            self.fail(f"{key} {value!r} is not an integer")
        if not low <= value <= high:
            self.fail(f"{key} {value} is out of range {low}..{high}")
        return value

    def choice(self, key: str, choices: Sequence[str]) -> str:
        value = self.table.get(key)
        if not isinstance(value, str) or value not in choices:
            self.fail(f"{key} {value!r} is not one of {', '.join(choices)}")
        return value

    def flag(self, key: str) -> bool:
        value = self.table.get(key)
        if not isinstance(value, bool):
            self.fail(f"{key} {value!r} is not true or false")
        return value

    def numbers(self, key: str, low: int, high: int) -> tuple[int, ...]:
        value = self.table.get(key, [])
        if not isinstance(value, list) or not all(
            isinstance(v, int) and not isinstance(v, bool) and low <= v <= high for v in value
        ):
            self.fail(f"{key} {value!r} is not a list of integers {low}..{high}")
        return tuple(value)

    def texts(self, key: str) -> tuple[str, ...]:
        value = self.table.get(key)
        if (
            not isinstance(value, list)
            or not value
            or not all(isinstance(v, str) and v for v in value)
        ):
            self.fail(f"{key} {value!r} is not a non-empty list of strings")
        return tuple(value)

    def tables(self, key: str) -> list[Any]:
        value = self.table.get(key, [])
        if not isinstance(value, list):
            self.fail(f"{key} is not a list of tables")
        return value


_START_KEYS = ("driver", "kind", "bus_kind", "internal", "args", "line")
_START_OPTIONAL = ("bus", "address", "rotation", "when")
_DRIVER = re.compile(r"[a-z][a-z0-9_]*")
_PARAM = re.compile(r"[A-Z][A-Z0-9_]*")
_NAME = re.compile(r"[a-z0-9][a-z0-9-]*_[A-Za-z0-9][A-Za-z0-9_.-]*")


@functools.cache
def _rotation_max() -> int:
    """The largest value of PX4's rotation enum, as ``value_sets.toml`` lists it."""
    with open(VALUE_SETS_TOML, "rb") as f:
        return max(int(k) for k in tomllib.load(f)["rotation"])


def _start(row: _Row, switch: bool) -> dict[str, Any]:
    row.only(("param", *_START_KEYS) if switch else _START_KEYS, _START_OPTIONAL)
    driver = row.text("driver")
    if not _DRIVER.fullmatch(driver):
        row.fail(f"driver {driver!r} is not a PX4 module name (lower case, digits, _)")
    fields: dict[str, Any] = {
        "driver": driver,
        "kind": row.choice("kind", KINDS),
        "bus_kind": row.choice("bus_kind", BUS_KINDS),
        "bus": row.optional_number("bus", 0, 255),
        "address": row.optional_number("address", 0, 127),
        "rotation": row.optional_number("rotation", 0, _rotation_max()),
        "internal": row.flag("internal"),
        "args": row.text("args"),
        "when": row.text("when", ""),
        "line": row.number("line", 1, 100_000),
    }
    if switch:
        param = row.text("param")
        if not _PARAM.fullmatch(param):
            row.fail(f"param {param!r} is not a PX4 parameter name")
        fields["param"] = param
    return fields


def parse_boards(text: str, file: str = "boards.toml") -> BoardTable:
    """Read a board table from TOML text (see the module's docstring for the keys)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise BoardsFileError(f"{file}: not TOML: {exc}") from None
    top = _Row(file, "top level", doc)
    top.only(("snapshot", "board"), ("rc_sensors", "i2c_launcher"))

    snapshots: dict[str, _Snapshot] = {}
    for i, table in enumerate(top.tables("snapshot"), 1):
        row = _Row(file, f"snapshot {i}", table)
        row.only(("release", "ref", "commit", "date"), ("x_b_counts_external",))
        release = row.text("release")
        row.where = f"snapshot {release!r}"
        try:
            order = _snapshot_order(release)
        except BoardsError:
            row.fail("release is not 'main' nor a PX4 version like 'v1.14.0'")
        commit = row.text("commit")
        if not re.fullmatch(r"[0-9a-f]{40}", commit):
            row.fail(f"commit {commit!r} is not 40 hex digits")
        if release in snapshots:
            row.fail("release appears twice")
        snapshots[release] = _Snapshot(
            release,
            row.text("ref"),
            commit,
            row.text("date"),
            order,
            "x_b_counts_external" in row.table and row.flag("x_b_counts_external"),
        )
    if not snapshots:
        top.fail("no [[snapshot]] table")

    def releases_of(row: _Row) -> tuple[_Snapshot, ...]:
        keys = row.texts("releases")
        for key in keys:
            if key not in snapshots:
                row.fail(f"release {key!r} is not a [[snapshot]] (known: {', '.join(snapshots)})")
        return tuple(snapshots[k] for k in keys)

    def cite(path: str, line: int, snaps: Sequence[_Snapshot]) -> str:
        return _cite(path, line, max(snaps, key=lambda s: s.order).describe())

    common: dict[str, list[tuple[dict[str, Any], str]]] = {}
    for i, table in enumerate(top.tables("rc_sensors"), 1):
        row = _Row(file, f"rc_sensors {i}", table)
        row.only(("releases", "path", "switch"))
        snaps = releases_of(row)
        path = row.text("path")
        starts = []
        for j, entry in enumerate(row.tables("switch"), 1):
            start = _start(_Row(file, f"{row.where} switch {j}", entry), switch=True)
            starts.append((start, cite(path, start["line"], snaps)))
        for snap in snaps:
            if snap.release in common:
                row.fail(f"release {snap.release!r} has two [[rc_sensors]] rows")
            common[snap.release] = starts

    launcher: dict[str, tuple[LauncherProbe, ...]] = {}
    for i, table in enumerate(top.tables("i2c_launcher"), 1):
        row = _Row(file, f"i2c_launcher {i}", table)
        row.only(("releases", "path", "args", "probe"))
        snaps = releases_of(row)
        path, args = row.text("path"), row.text("args")
        probes = []
        for j, entry in enumerate(row.tables("probe"), 1):
            probe = _Row(file, f"{row.where} probe {j}", entry)
            probe.only(("driver", "kind", "address", "line"))
            line = probe.number("line", 1, 100_000)
            probes.append(
                LauncherProbe(
                    driver=probe.text("driver"),
                    kind=probe.choice("kind", KINDS),
                    address=probe.number("address", 0, 127),
                    args=args,
                    source=cite(path, line, snaps),
                )
            )
        for snap in snaps:
            if snap.release in launcher:
                row.fail(f"release {snap.release!r} has two [[i2c_launcher]] rows")
            launcher[snap.release] = tuple(probes)

    rows: dict[tuple[str, str], Board] = {}
    pending: dict[tuple[str, str], _Pending] = {}
    names: list[str] = []
    ver_hw_names: dict[str, str] = {}
    for i, table in enumerate(top.tables("board"), 1):
        row = _Row(file, f"board {i}", table)
        row.only(
            (
                "name",
                "label",
                "ver_hw",
                "releases",
                "path",
                "external_i2c_buses",
                "internal_i2c_buses",
                "i2c_launcher_buses",
                "device",
                "switch",
            ),
            (
                "i2c_buses_path",
                "i2c_buses_lines",
                "external_i2c_buses_when",
                "i2c_launcher_when",
                "i2c_launcher_lines",
                "external_spi_buses",
                "spi_buses_path",
                "spi_buses_lines",
            ),
        )
        name = row.text("name")
        if not _NAME.fullmatch(name):
            row.fail(f"name {name!r} is not a PX4 target name like 'px4_fmu-v6c'")
        row.where = f"board {name!r}"
        snaps = releases_of(row)
        row.where = f"board {name!r} at {', '.join(s.release for s in snaps)}"
        path = row.text("path")
        ver_hw = row.texts("ver_hw")
        for hw in ver_hw:
            if hw != hw.upper():
                row.fail(f"ver_hw {hw!r} is not upper case (PX4 writes it upper case)")
            if ver_hw_names.setdefault(hw, name) != name:
                row.fail(f"ver_hw {hw!r} already names board {ver_hw_names[hw]!r}")
        external = row.numbers("external_i2c_buses", 0, 255)
        internal = row.numbers("internal_i2c_buses", 0, 255)
        buses_path = row.text("i2c_buses_path", "")
        override = _override(row, external, internal, buses_path, snaps, cite)
        bus_lines = row.numbers("i2c_buses_lines", 1, 100_000)
        if bus_lines and not buses_path:
            row.fail("i2c_buses_lines but no i2c_buses_path (the file they are lines of)")
        if bus_lines and len(bus_lines) != len(external) + len(internal):
            row.fail(
                f"i2c_buses_lines {list(bus_lines)} do not give one line for each of "
                f"external_i2c_buses {list(external)} and internal_i2c_buses {list(internal)}"
            )
        bus_sources = tuple(
            (bus, cite(buses_path, n, snaps))
            for bus, n in zip((*external, *internal), bus_lines, strict=False)
        )
        # px4_i2c_buses' order, as its lines give it (none given: the lists' order)
        lines = dict(zip((*external, *internal), bus_lines, strict=False))
        bus_order = tuple(sorted((*external, *internal), key=lambda b: lines.get(b, 0)))
        spi_path, spi_buses = _spi_buses(row, snaps, cite)
        devices = []
        for j, entry in enumerate(row.tables("device"), 1):
            start = _start(_Row(file, f"{row.where} device {j}", entry), switch=False)
            devices.append(
                BoardDevice(
                    driver=start["driver"],
                    kind=start["kind"],
                    bus_kind=start["bus_kind"],
                    bus=start["bus"],
                    address=start["address"],
                    rotation=start["rotation"],
                    internal=start["internal"],
                    source=cite(path, start["line"], snaps),
                    when=start["when"],
                    args=start["args"],
                )
            )
        own = []
        for j, entry in enumerate(row.tables("switch"), 1):
            start = _start(_Row(file, f"{row.where} switch {j}", entry), switch=True)
            own.append((start, cite(path, start["line"], snaps)))
        sources = [f"{_UPSTREAM} {path} at {', '.join(s.describe() for s in snaps)}"]
        if buses_path:
            sources.append(f"I2C buses from {buses_path}")
        if spi_path:
            sources.append(f"SPI buses from {spi_path}")
        for snap in snaps:
            key = (name, snap.release)
            if key in rows:
                row.fail(f"release {snap.release!r} already has a row for this board")
            # expanded to SwitchStarts per bus when the board is first asked for (BoardTable._row)
            pending[key] = (
                own + common.get(snap.release, []),
                external,
                internal,
                override,
                _Iterator(
                    bool(buses_path),
                    bus_order,
                    snap.x_b_counts_external,
                    _spi_order(spi_path, spi_buses),
                ),
                ver_hw,
            )
            rc_sensors = (
                " and ROMFS/px4fmu_common/init.d/rc.sensors" if snap.release in common else ""
            )
            launcher_buses = row.numbers("i2c_launcher_buses", 0, 255)
            if launcher_buses and snap.release not in launcher:
                row.fail(f"i2c_launcher_buses but no [[i2c_launcher]] row for {snap.release!r}")
            launcher_lines = row.numbers("i2c_launcher_lines", 1, 100_000)
            if len(launcher_lines) != len(launcher_buses):
                row.fail(
                    f"i2c_launcher_lines {list(launcher_lines)} do not give one line for each of "
                    f"i2c_launcher_buses {list(launcher_buses)}"
                )
            rows[key] = Board(
                name=name,
                label=row.text("label"),
                ver_hw=ver_hw,
                devices=tuple(devices),
                i2c_launcher_buses=launcher_buses,
                switches=(),
                source="; ".join(sources) + rc_sensors,
                releases=tuple(s.release for s in snaps),
                external_i2c_buses=external,
                internal_i2c_buses=internal,
                i2c_launcher_when=row.text("i2c_launcher_when", ""),
                i2c_launcher_probes=launcher[snap.release] if launcher_buses else (),
                i2c_launcher_sources=tuple(cite(path, n, snaps) for n in launcher_lines),
                at=max(snaps, key=lambda s: s.order).describe(),
                external_i2c_buses_when=override,
                i2c_bus_sources=bus_sources,
                i2c_buses_path=buses_path,
                i2c_bus_order=bus_order,
                x_b_counts_external=snap.x_b_counts_external,
                external_spi_buses=spi_buses,
                spi_buses_path=spi_path,
            )
        if name not in names:
            names.append(name)
    return BoardTable(tuple(snapshots.values()), rows, names, ver_hw_names, common, pending)


def _spi_buses(
    row: _Row, snaps: Sequence[_Snapshot], cite: Callable[[str, int, Sequence[_Snapshot]], str]
) -> tuple[str, tuple[tuple[int, str], ...]]:
    """A board row's ``spi_buses_path`` and its ``external_spi_buses``, each with its line of
    that file cited: the three keys together or none."""
    keys = ("external_spi_buses", "spi_buses_path", "spi_buses_lines")
    given = [k for k in keys if k in row.table]
    if not given:
        return "", ()
    if len(given) != len(keys):
        missing = [k for k in keys if k not in given]
        row.fail(f"{given[0]} but no {' or '.join(missing)} (the three go together)")
    buses = row.numbers("external_spi_buses", 0, 255)
    path = row.text("spi_buses_path")
    bus_lines = row.numbers("spi_buses_lines", 1, 100_000)
    if len(bus_lines) != len(buses):
        row.fail(
            f"spi_buses_lines {list(bus_lines)} do not give one line for each of "
            f"external_spi_buses {list(buses)}"
        )
    return path, tuple((bus, cite(path, n, snaps)) for bus, n in zip(buses, bus_lines, strict=True))


def _override(
    row: _Row,
    external: Sequence[int],
    internal: Sequence[int],
    buses_path: str,
    snaps: Sequence[_Snapshot],
    cite: Callable[[str, int, Sequence[_Snapshot]], str],
) -> BusOverride | None:
    """A board row's ``external_i2c_buses_when``, checked: one test (migration negates it),
    buses of the board, a line of ``i2c_buses_path``."""
    key = "external_i2c_buses_when"
    if key not in row.table:
        return None
    entry = _Row(row.file, f"{row.where} {key}", row.table[key])
    entry.only(("when", "buses", "line"))
    when = entry.text("when")
    if " and " in when or when.startswith("not "):
        entry.fail(f"when {when!r} is not one test (its negation is written 'not WHEN')")
    buses = entry.numbers("buses", 0, 255)
    strange = [b for b in buses if b not in external and b not in internal]
    if strange:
        entry.fail(
            f"buses {strange} are not I2C buses of the board (external {list(external)}, "
            f"internal {list(internal)})"
        )
    line = entry.number("line", 1, 100_000)
    if not buses_path:
        row.fail(f"{key} but no i2c_buses_path (the file its line {line} is in)")
    return BusOverride(when, buses, cite(buses_path, line, snaps))


def _expand(
    start: Mapping[str, Any],
    source: str,
    external: Sequence[int],
    internal: Sequence[int],
    override: BusOverride | None,
    iterator: _Iterator,
    ver_hw: Sequence[str],
) -> list[SwitchStart]:
    """One SwitchStart per bus the start can run on (:meth:`Board.bus_conditions`): ``-b N``
    names one, if of the start's kind; ``-X``/``-I`` without it probe every external/internal
    I2C bus of the board; ``-S`` the ``-b``-th (else the first) of its external SPI buses where
    the table knows them, elsewhere no bus. A start another board's ``ver hwcmp`` keeps is not
    this board's."""
    for clause in start["when"].split(" and "):
        negated = clause.startswith("not ")
        if clause.removeprefix("not ").startswith("board in "):
            listed = clause.removeprefix("not ").removeprefix("board in ").split(",")
            if any(hw in listed for hw in ver_hw) == negated:
                return []
    buses = _bus_conditions(
        start["bus"], start["bus_kind"], start["internal"], external, internal, override, iterator
    )
    return [
        SwitchStart(
            param=start["param"],
            driver=start["driver"],
            bus=bus,
            address=start["address"],
            args=start["args"],
            source=source,
            kind=start["kind"],
            bus_kind=start["bus_kind"],
            rotation=start["rotation"],
            internal=start["internal"],
            when=start["when"],
            bus_when=bus_when,
        )
        for bus, bus_when in buses
    ]


# -- the table as documentation ----------------------------------------------------------------


def _cell(value: object) -> str:
    if value is None or value == "":
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    return str(value).replace("|", "\\|")


def _starts_table(
    starts: Sequence[BoardDevice | SwitchStart | tuple[Mapping[str, Any], str]],
    board: Board | None = None,
) -> list[str]:
    """The rows of ``starts``; ``board``'s devices started with ``-S`` show the SPI bus PX4
    counts their ``-b`` to ("none": the board has no such external bus)."""
    lines = [
        "| switch | driver | kind | bus | address | -R | internal | when | options | line |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for start in starts:
        if isinstance(start, tuple):
            f = dict(start[0])
            f["source"] = start[1]
            if f["bus"] is None and f["bus_kind"] == "I2C":
                f["bus"] = "every " + ("internal" if f["internal"] else "external")
        else:
            f = vars(start)
        bus = f["bus_kind"] + (f" {f['bus']}" if f["bus"] is not None else "")
        if (
            board is not None
            and board.spi_buses_path
            and isinstance(start, BoardDevice)
            and start.bus_kind == "SPI"
            and not start.internal
        ):
            found = board.buses_of(start)
            bus = f"SPI {found[0]}" if found else "SPI none"
        address = f"0x{f['address']:02x}" if f["address"] is not None else ""
        line = f["source"].split(" ")[1].rsplit(":", 1)[-1]
        cells = (
            f.get("param", ""),
            f["driver"],
            f["kind"],
            bus,
            address,
            f["rotation"],
            f["internal"],
            f["when"],
            f"`{f['args'].removesuffix(' start')}`",
            line,
        )
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return lines


def render_markdown(table: BoardTable) -> str:
    """The generated part of ``docs/boards.md``: the snapshots, every board with its rows, and
    rc.sensors' switch starts (a test keeps the page equal to this)."""
    out = ["### Snapshots read", ""]
    out += ["| release | PX4-Autopilot ref | commit | date |", "|---|---|---|---|"]
    for snap in table._snapshots:
        out.append(f"| {snap.release} | {snap.ref} | `{snap.commit}` | {snap.date} |")
    out += ["", "### Boards", ""]
    out += ["| board | label | ver_hw | rows (snapshots) |", "|---|---|---|---|"]
    for board in table.all():
        rows = " / ".join(", ".join(v.releases) for v in table.variants(board.name))
        hw = ", ".join(board.ver_hw)
        out.append(f"| [{board.name}](#{board.name}) | {board.label} | {hw} | {rows} |")
    for board in table.all():
        out += ["", f"#### {board.name}", ""]
        for variant in table.variants(board.name):
            out.append(
                f"**{', '.join(variant.releases)}**: {variant.source.split(' and ROMFS')[0]}."
            )
            out.append("")
            launcher = ", ".join(str(b) for b in variant.i2c_launcher_buses) or "none"
            when = f" ({variant.i2c_launcher_when})" if variant.i2c_launcher_when else ""
            override = variant.external_i2c_buses_when
            overridden = (
                f"; where {override.when} ({override.source.split(' ')[1]}), external "
                f"{list(override.external)}"
                if override is not None
                else ""
            )
            out.append(
                f"I2C buses: external {list(variant.external_i2c_buses)}, internal "
                f"{list(variant.internal_i2c_buses)}{overridden}; i2c_launcher scans: "
                f"{launcher}{when}."
            )
            if variant.spi_buses_path:
                spi = [bus for bus, _ in variant.external_spi_buses]
                out += [
                    "",
                    f"External SPI buses, in the order `-S -b N` counts them: {spi} "
                    f"({variant.spi_buses_path}).",
                ]
            own = [s for s in variant.switches if "/rc.sensors:" not in s.source]
            if variant.devices or own:
                out += ["", *_starts_table([*variant.devices, *own], variant)]
            nowhere = [
                d.source.split(" ")[1].rsplit(":", 1)[-1]
                for d in variant.devices
                if d.bus_kind == "I2C" and d.bus is not None and not variant.buses_of(d)
            ]
            if nowhere:
                out += [
                    "",
                    f"Started on no bus: line {', '.join(nowhere)} (its -b is a bus of the "
                    "other kind, which PX4's -I or -X does not try).",
                ]
            out.append("")
    out += ["### What i2c_launcher tries on each of its buses", ""]
    seen_probes: list[tuple[LauncherProbe, ...]] = []
    for snap in table._snapshots:
        at = table._boards_at(snap.release)
        probes = next((b.i2c_launcher_probes for b in at if b.i2c_launcher_probes), ())
        if not probes or probes in seen_probes:
            continue
        seen_probes.append(probes)
        out += [f"**from {snap.release}**: `{probes[0].args}`", ""]
        out += ["| address | driver | kind | source |", "|---|---|---|---|"]
        out += [f"| 0x{p.address:02x} | {p.driver} | {p.kind} | {p.source} |" for p in probes]
        out.append("")
    out += ["### Switch starts every board runs (ROMFS/px4fmu_common/init.d/rc.sensors)", ""]
    seen: list[int] = []
    for snap in table._snapshots:
        starts = table._rc_sensors.get(snap.release)
        if starts is None or id(starts) in seen:
            continue
        seen.append(id(starts))
        releases = [r for r, s in table._rc_sensors.items() if s is starts]
        out += [f"**{', '.join(releases)}**", "", *_starts_table(list(starts)), ""]
    return "\n".join(out).rstrip("\n") + "\n"


@functools.cache
def load_boards() -> BoardTable:
    """The bundled board table (read once)."""
    resource = importlib.resources.files("px4params.data").joinpath("boards.toml")
    return parse_boards(resource.read_text(encoding="utf-8"), "boards.toml")
