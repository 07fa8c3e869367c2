"""A simulated bench: boot the manifest against simulated hardware, in simulated time.

The bench file (TOML) says what is physically on the vehicle::

    [bench]                      # optional
    name = "quad with two batteries"   # shown with the file's name in reports
    description = "..."          # optional: for people reading the file, shown nowhere

    [[bus]]                      # optional: noise on a whole bus
    kind = "i2c"                 # i2c or spi
    bus_id = 1                   # 1..15
    error_rate = 0.3             # share of transfers that fail, 0..1

    [[device]]
    chip = "INA238"              # a chip some declared driver drives
    bus = "i2c"                  # i2c or spi
    bus_id = 1                   # 1..15
    address = 0x45               # I2C address 0..127, or SPI chip select 0..31
    # faults, all optional:
    absent = true                # declared but not there: nothing answers
    chip_id = 0x2260             # answers this instead of its chip's id (wrong part fitted)
    error_rate = 0.1             # flaky: share of its transfers that fail, 0..1
    dies_after = 12.5            # stops answering after this many seconds
    power_up = 2.0               # answers only after this many seconds (slow to power up)

:func:`run` boots it with a discrete event loop (nothing sleeps; a run is deterministic for a
given seed). In manifest mode each driver's ``auto`` (in declared order, at t = 0) starts one
driver instance per configured parameter instance; the instance registers with the commander,
probes (a soft reset, the chip id read, the configuration write: any failure fails the attempt)
with exponential backoff and never gives up (the driver's ``-k`` keep running), publishes its
24-bit device ID once found, and then transfers at its declared rate, counting transfers, bad
transfers and resets (after ``RESET_AFTER`` bad transfers in a row it resets and probes
again). Every ``TICK`` it reports its health:

- critical: not running (not found yet, lost after a reset, or not startable), or no good
  transfer for ``DATA_TIMEOUT``;
- warning: running, but more than ``WARN_RATIO`` of its transfers over the last ``WINDOW``
  failed;
- nominal: otherwise.

The commander knows the manifest: arming is refused while any configured instance is not
nominal, with one line per failing device. ``legacy=True`` runs today's behaviour instead:
every driver today's PX4 starts without being asked (``started_by`` probe or launcher: not the
ones a ``SENS_EN_*`` switch starts) is started with ``-X -q start`` on every I2C bus of the
bench at its default address, probes a fixed three times at boot and, if nothing answers,
quietly does not start; the commander only knows what started, so a missing device is not
reported.
"""

from __future__ import annotations

import difflib
import functools
import heapq
import math
import os
import random
import re
import tomllib
import unicodedata
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from px4params.errors import BenchFileError
from px4params.formats.keys import unknown_key
from px4params.numbers import counted
from px4params.reading import BENCH, not_text, read_text
from px4params.vehicle.autostart import Configured, describe_location
from px4params.vehicle.drivers import BUS_KINDS, Driver, Drivers

__all__ = [
    "Bench",
    "BenchBus",
    "BenchDevice",
    "BenchFileError",
    "InstanceResult",
    "RunResult",
    "load_bench",
    "parse_bench",
    "run",
]

TICK = 0.1  # s: drivers' transfers are processed, and health evaluated, in slices this long
WINDOW = 2.0  # s: the bad-transfer ratio is taken over this long
WARN_RATIO = 0.05  # more bad transfers than this share over WINDOW is a warning
DATA_TIMEOUT = 0.5  # s without a good transfer while running is critical
RESET_AFTER = 10  # bad transfers in a row make a running driver reset and probe again
PROBE_TRANSFERS = 3  # soft reset, chip id read, configuration write
PROBE_CHIP_ID_STEP = 1  # which of those reads the chip id
BACKOFF_BASE = 0.02  # s: first retry delay; doubles per failed attempt ...
BACKOFF_MAX = 1.0  # s: ... up to this
LEGACY_PROBES = 3  # today's fixed probe count
LEGACY_PROBE_GAP = 0.001  # s between today's back-to-back probes
PERF_PERIOD = 1.0  # s between perf counter records in the event log

SIMULATED_BUSES = ("i2c", "spi")
_ADDRESS_RANGE = {"i2c": 127, "spi": 31}

_OK, _NACK, _ERROR = 0, 1, 2


# -- the bench file ------------------------------------------------------------------------------


@dataclass(frozen=True)
class BenchBus:
    kind: str
    bus_id: int
    error_rate: float = 0.0


@dataclass(frozen=True)
class BenchDevice:
    chip: str
    kind: str
    bus_id: int
    address: int
    absent: bool = False
    chip_id: int | None = None
    error_rate: float = 0.0
    dies_after: float | None = None
    power_up: float = 0.0

    @property
    def location(self) -> str:
        return describe_location(self.kind, self.bus_id, self.address)


@dataclass(frozen=True)
class Bench:
    source: str
    #: Its ``[bench] name``, "" where the file gives none.
    name: str
    buses: dict[tuple[str, int], BenchBus]
    devices: dict[tuple[str, int, int], BenchDevice]

    def i2c_buses(self) -> list[int]:
        """Every I2C bus the bench has (with a device or a [[bus]] entry), in order."""
        ids = {b for k, b in self.buses if k == "i2c"} | {
            b for k, b, _ in self.devices if k == "i2c"
        }
        return sorted(ids)


_BENCH_KEYS = ("bench", "bus", "device")
_BENCH_TABLE_KEYS = ("name", "description")
_BUS_KEYS = ("kind", "bus_id", "error_rate")
_DEVICE_KEYS = (
    "chip",
    "bus",
    "bus_id",
    "address",
    "absent",
    "chip_id",
    "error_rate",
    "dies_after",
    "power_up",
)


def load_bench(path: str | os.PathLike[str], drivers: Drivers) -> Bench:
    """Reads and checks a bench file; chips must be ones ``drivers`` declare."""
    source = os.fspath(path)
    try:
        text = read_text(path, BENCH)
    except FileNotFoundError:
        raise BenchFileError(f"{source}: no such bench file") from None
    except OSError as e:
        raise BenchFileError(f"{source}: cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise BenchFileError(f"{source}: {not_text(e)}") from None
    return parse_bench(text, source, drivers)


#: The source of the bench ``autostart run`` boots without ``--bench`` (the report's first line
#: and the flight log name it).
HEALTHY_BENCH = "a healthy bench (every configured device present, no faults)"


def healthy_bench(manifest: Sequence[Configured]) -> Bench:
    """The bench a manifest describes when nothing is wrong: each startable instance's chip at
    its configured location, answering at once, with no faults (one per location: a second
    instance there is refused by ``configured`` itself)."""
    devices: dict[tuple[str, int, int], BenchDevice] = {}
    for c in manifest:
        if c.problems or c.driver is None or c.bus_kind not in SIMULATED_BUSES:
            continue  # not startable: the run reports it as the manifest has it
        key = (c.bus_kind, c.bus_id, c.address)
        devices.setdefault(key, BenchDevice(c.driver.chip, c.bus_kind, c.bus_id, c.address))
    return Bench(HEALTHY_BENCH, "", {}, devices)


def parse_bench(text: str, source: str, drivers: Drivers) -> Bench:
    """Checks a bench given as TOML text (see the module documentation)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise BenchFileError(f"{source}: not TOML: {e}") from None
    _check_keys(doc, _BENCH_KEYS, lambda m: BenchFileError(f"{source}: {m}"), "top-level key")
    meta = doc.get("bench", {})
    if not isinstance(meta, dict):
        raise BenchFileError(f"{source}: [bench] must be a table")
    _check_keys(meta, _BENCH_TABLE_KEYS, lambda m: BenchFileError(f"{source}: [bench]: {m}"))
    name = meta.get("name", "")
    if not isinstance(name, str):
        raise BenchFileError(f"{source}: [bench]: name must be a string, not {name!r}")
    # The name is printed and logged: a control character (an escape sequence, a newline)
    # would act on the terminal or split the line rather than be shown.
    control = next((c for c in name if unicodedata.category(c) == "Cc"), None)
    if control is not None:
        raise BenchFileError(
            f"{source}: [bench]: name holds the control character U+{ord(control):04X} (a name "
            "is one line of printable text)"
        )

    buses: dict[tuple[str, int], BenchBus] = {}
    for number, table in enumerate(_tables(doc, "bus", source), start=1):
        bus = _bus(table, f"{source}: bus #{number}")
        if (bus.kind, bus.bus_id) in buses:
            raise BenchFileError(
                f"{source}: bus #{number}: {bus.kind} bus {bus.bus_id} is declared twice"
            )
        buses[(bus.kind, bus.bus_id)] = bus

    chips = drivers.chips()
    devices: dict[tuple[str, int, int], BenchDevice] = {}
    for number, table in enumerate(_tables(doc, "device", source), start=1):
        device = _device(table, number, source, chips)
        key = (device.kind, device.bus_id, device.address)
        if key in devices:
            raise BenchFileError(
                f"{source}: device #{number} ({device.chip}): {device.location} already has "
                f"a {devices[key].chip}"
            )
        devices[key] = device
    return Bench(source, name, buses, devices)


def _tables(doc: dict[str, Any], key: str, source: str) -> list[Any]:
    tables = doc.get(key, [])
    if not isinstance(tables, list):
        raise BenchFileError(f"{source}: '{key}' must be [[{key}]] tables")
    return tables


def _check_keys(
    table: dict[str, Any],
    allowed: Sequence[str],
    error: Callable[[str], BenchFileError],
    what: str = "key",
) -> None:
    complaint = unknown_key(table, allowed, what)
    if complaint is not None:
        raise error(complaint)


def _bus(table: Any, where: str) -> BenchBus:
    def fail(message: str) -> BenchFileError:
        return BenchFileError(f"{where}: {message}")

    if not isinstance(table, dict):
        raise fail("is not a table")
    _check_keys(table, _BUS_KEYS, fail)
    kind = _kind(table, fail)
    return BenchBus(kind, _bus_id(table, fail), _rate(table, "error_rate", fail))


def _device(table: Any, number: int, source: str, chips: dict[str, Driver]) -> BenchDevice:
    chip = table.get("chip") if isinstance(table, dict) else None
    where = f"{source}: device #{number}" + (f" ({chip})" if isinstance(chip, str) else "")

    def fail(message: str) -> BenchFileError:
        return BenchFileError(f"{where}: {message}")

    if not isinstance(table, dict):
        raise fail("is not a table")
    _check_keys(table, _DEVICE_KEYS, fail)
    for key in ("chip", "bus", "bus_id", "address"):
        if key not in table:
            raise fail(f"missing key '{key}'")
    if not isinstance(chip, str):
        raise fail(f"chip must be a string, not {chip!r}")
    if chip.upper() not in chips:
        hint = difflib.get_close_matches(chip.upper(), list(chips), n=1)
        extra = f"did you mean {hint[0]}?" if hint else f"known: {', '.join(sorted(chips))}"
        raise fail(f"unknown chip '{chip}' (no declared driver drives it; {extra})")
    kind = _kind(table, fail, key="bus")
    bus_id = _bus_id(table, fail)
    address = table["address"]
    top = _ADDRESS_RANGE[kind]
    if isinstance(address, bool) or not isinstance(address, int):
        raise fail(f"address must be an integer (e.g. 0x45), not {address!r}")
    if not 0 <= address <= top:
        what = "I2C address" if kind == "i2c" else "SPI chip select"
        # (no hex for a negative number: TOML has none, and "0x-1" is no number)
        shown = f"{address} (0x{address:X})" if address >= 0 else str(address)
        raise fail(f"{what} {shown} is out of range 0..{top} (0x00..0x{top:02X})")
    where = f"{source}: device #{number} ({chip} on {describe_location(kind, bus_id, address)})"

    absent = table.get("absent", False)
    if not isinstance(absent, bool):
        raise fail(f"absent must be true or false, not {absent!r}")
    chip_id = table.get("chip_id")
    if chip_id is not None and (
        isinstance(chip_id, bool) or not isinstance(chip_id, int) or not 0 <= chip_id <= 0xFFFF
    ):
        raise fail(f"chip_id must be an integer 0..0xFFFF, not {chip_id!r}")
    dies_after = table.get("dies_after")
    if dies_after is not None:
        dies_after = _seconds(table, "dies_after", fail)
    return BenchDevice(
        chip=chips[chip.upper()].chip,
        kind=kind,
        bus_id=bus_id,
        address=address,
        absent=absent,
        chip_id=chip_id,
        error_rate=_rate(table, "error_rate", fail),
        dies_after=dies_after,
        power_up=_seconds(table, "power_up", fail) if "power_up" in table else 0.0,
    )


def _kind(table: dict[str, Any], fail: Callable[[str], BenchFileError], key: str = "kind") -> str:
    if key not in table:
        raise fail(f"missing key '{key}'")
    kind = table[key]
    if not isinstance(kind, str) or kind not in SIMULATED_BUSES:
        also = " (not simulated)" if isinstance(kind, str) and kind in BUS_KINDS else ""
        raise fail(f"{key} {kind!r} is not a simulated bus kind{also} (expected i2c or spi)")
    return str(kind)


def _bus_id(table: dict[str, Any], fail: Callable[[str], BenchFileError]) -> int:
    if "bus_id" not in table:
        raise fail("missing key 'bus_id'")
    value = table["bus_id"]
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 15:
        raise fail(f"bus_id must be an integer 1..15, not {value!r}")
    return value


def _rate(table: dict[str, Any], key: str, fail: Callable[[str], BenchFileError]) -> float:
    value = table.get(key, 0.0)
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 <= value <= 1:
        raise fail(f"{key} must be a number from 0 to 1 (a share of transfers), not {value!r}")
    return float(value)


def _seconds(table: dict[str, Any], key: str, fail: Callable[[str], BenchFileError]) -> float:
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 <= value < math.inf:
        raise fail(f"{key} must be a number of seconds >= 0, not {value!r}")
    return float(value)


# -- the simulation ------------------------------------------------------------------------------


class _Link:
    """What a driver instance reaches at its location: the device there (if any) and the bus."""

    __slots__ = ("answer", "off_at", "on_at", "p", "present", "rng")

    def __init__(self, bench: Bench, kind: str, bus_id: int, address: int, rng: random.Random):
        device = bench.devices.get((kind, bus_id, address))
        bus = bench.buses.get((kind, bus_id))
        self.rng = rng
        self.present = device is not None and not device.absent
        bus_rate = bus.error_rate if bus else 0.0
        dev_rate = device.error_rate if device else 0.0
        self.p = 1.0 - (1.0 - bus_rate) * (1.0 - dev_rate)  # either fails the transfer
        self.on_at = device.power_up if device else 0.0
        self.off_at = device.dies_after if device and device.dies_after is not None else math.inf
        self.answer: BenchDevice | None = device

    def transfer(self, t: float) -> int:
        if not self.present or not self.on_at <= t < self.off_at:
            return _NACK
        if self.p and self.rng.random() < self.p:
            return _ERROR
        return _OK


def blocks_arming(health: str, *, legacy: bool) -> bool:
    """Whether a device the commander knows of, at ``health``, keeps the vehicle from arming.
    With the manifest: anything but nominal. Today (legacy) only a started sensor that stopped
    delivering (critical) does; drivers report no health of their own. (The run and the reading
    of its log both judge by this.)"""
    return health == "critical" if legacy else health != "nominal"


@dataclass
class InstanceResult:
    """One driver instance after a run."""

    name: str
    driver: str
    parameter: str | None
    kind: str
    bus_id: int
    address: int
    health: str = "critical"
    reason: str = "starting"
    registered: bool = True
    started_at: float | None = None
    device_id: int | None = None
    transfers: int = 0
    bad_transfers: int = 0
    resets: int = 0
    probe_attempts: int = 0
    #: (time, health, reason) at every change of health, or of the kind of reason.
    timeline: list[tuple[float, str, str]] = field(default_factory=list)
    #: (time, what): "start" when the probe found the chip, "reset" when the driver reset.
    marks: list[tuple[float, str]] = field(default_factory=list)

    @property
    def location(self) -> str:
        return describe_location(self.kind, self.bus_id, self.address)

    def failure_line(self) -> str:
        """The commander's line for this instance: driver, instance, bus, address, reason."""
        reason = f": {self.reason}" if self.reason else ""
        return f"{self.driver} {self.name} on {self.location}: {self.health}{reason}"

    def as_dict(self) -> dict[str, Any]:
        return {
            "instance": self.name,
            "driver": self.driver,
            "parameter": self.parameter,
            "bus": self.kind,
            "bus_id": self.bus_id,
            "address": self.address,
            "location": self.location,
            "registered": self.registered,
            "health": self.health,
            "reason": self.reason,
            "started_at": self.started_at,
            "device_id": self.device_id,
            "device_id_hex": f"0x{self.device_id:06X}" if self.device_id is not None else None,
            "perf": {
                "transfers": self.transfers,
                "bad_transfers": self.bad_transfers,
                "resets": self.resets,
                "probe_attempts": self.probe_attempts,
            },
            "timeline": [[t, h, r] for t, h, r in self.timeline],
            "marks": [[t, what] for t, what in self.marks],
        }


@dataclass
class RunResult:
    """What a bench run shows: each instance, and the commander's verdict."""

    mode: str  # "manifest" or "legacy"
    seed: int
    duration: float
    bench: str
    instances: list[InstanceResult]
    may_arm: bool
    #: One line per device that keeps the vehicle from arming.
    failures: list[str]
    #: Legacy: the ``-q start`` commands that found nothing and said nothing: ``line``, and
    #: ``device``, the chip the bench has at that location (None for an empty location).
    quiet: list[dict[str, Any]] = field(default_factory=list)
    #: Legacy: configured instances nothing started (only with a manifest to compare).
    silently_missing: list[str] = field(default_factory=list)
    #: (time, may arm) at every change of the commander's answer.
    arming: list[tuple[float, bool]] = field(default_factory=list)
    events: list[dict[str, Any]] | None = None
    #: Read from a log cut short (no clean end): the last moment it holds, from which on what
    #: it tells is uncertain; None for a whole run.
    log_cut_at: float | None = None
    #: The bench's ``[bench] name`` ("": none, or a log that does not say).
    bench_name: str = ""

    @property
    def verdict(self) -> str:
        """The commander's answer as reports say it: ``may arm``, ``arming refused``, or, of a
        log cut before its first answer, ``no arming answer logged`` (not a refusal)."""
        if self.log_cut_at is not None and not self.arming:
            return "no arming answer logged"
        return "may arm" if self.may_arm else "arming refused"

    @property
    def bench_label(self) -> str:
        """The bench as reports name it: its name and file, or the file alone."""
        return f"{self.bench_name} ({self.bench})" if self.bench_name else self.bench

    def as_dict(self) -> dict[str, Any]:
        return {
            "mode": self.mode,
            "seed": self.seed,
            "duration": self.duration,
            "bench": self.bench,
            "bench_name": self.bench_name,
            "may_arm": self.may_arm,
            "failures": self.failures,
            "quiet": self.quiet,
            "silently_missing": self.silently_missing,
            "arming": [[t, ok] for t, ok in self.arming],
            "instances": [i.as_dict() for i in self.instances],
            "log_cut_at": self.log_cut_at,
        }


class _Instance:
    """A running driver instance (the state machine); results go to ``self.out``."""

    def __init__(
        self,
        sim: _Sim,
        out: InstanceResult,
        driver: Driver | None,
        link: _Link | None,
        legacy: bool,
        problems: Sequence[str] = (),
    ) -> None:
        self.sim = sim
        self.out = out
        self.driver = driver
        self.link = link
        self.legacy = legacy
        self.problems = list(problems)
        self.state = "idle"  # idle, probing, running, stopped (legacy gave up), unstartable
        self.attempts = 0  # since the last (re)start
        self.last_probe = "starting"
        self.lost: tuple[float, str] | None = None
        self.since = 0.0  # running since
        self.rate = driver.rate_hz if driver else 1.0
        self.next_k = 1
        self.consecutive_bad = 0
        self.last_good = 0.0
        self.tick_good = 0
        self.tick_bad = 0
        size = max(1, round(WINDOW / TICK))
        self.window: deque[tuple[int, int]] = deque([(0, 0)] * size, maxlen=size)
        self.window_good = 0
        self.window_bad = 0

    # -- probing -----------------------------------------------------------------------------

    def probe(self, t: float) -> None:
        assert self.link is not None and self.driver is not None
        self.attempts += 1
        self.out.probe_attempts += 1
        ok, reason = self._probe_once(t)
        out = self.out
        sim = self.sim
        sim.log(t, "probe", out, attempt=self.attempts, ok=ok, reason=reason or None)
        if ok:
            self.state = "running"
            self.since = t
            self.next_k = 1
            self.consecutive_bad = 0
            self.last_good = t
            if out.started_at is None:
                out.started_at = round(t, 6)
            out.marks.append((round(t, 6), "start"))
            out.device_id = sim.device_id(self.driver, out)
            sim.log(
                t,
                "started",
                out,
                device_id=out.device_id,
                device_id_hex=f"0x{out.device_id:06X}",
                attempts=self.attempts,
            )
            if self.legacy:
                sim.register(self, t)
            return
        self.last_probe = reason
        if self.legacy and out.started_at is None:  # today's start: three probes, then quiet
            if self.attempts < LEGACY_PROBES:
                sim.schedule(t + LEGACY_PROBE_GAP, self.probe)
            else:  # today's -q start: give up, say nothing
                self.state = "stopped"
                sim.log(t, "start_failed", out, quiet=True, reason=reason)
            return
        # (the exponent bounded: 2.0 ** 1024 overflows a float, an hour of probes later)
        delay = min(BACKOFF_BASE * 2.0 ** min(self.attempts - 1, 64), BACKOFF_MAX)
        sim.schedule(t + delay, self.probe)

    def _probe_once(self, t: float) -> tuple[bool, str]:
        link, driver, out = self.link, self.driver, self.out
        assert link is not None and driver is not None
        for step in range(PROBE_TRANSFERS):
            out.transfers += 1
            result = link.transfer(t)
            if result != _OK:
                out.bad_transfers += 1
                self.tick_bad += 1
                return False, "no ACK" if result == _NACK else "bus error"
            self.tick_good += 1
            if step == PROBE_CHIP_ID_STEP and driver.chip_id is not None:
                value = self.sim.chip_answer(link.answer, driver)
                if value != driver.chip_id:
                    return False, (
                        f"wrong chip id 0x{value:X} in register 0x{driver.chip_id_register:02X} "
                        f"(expected 0x{driver.chip_id:X})"
                    )
        return True, ""

    # -- running -----------------------------------------------------------------------------

    def run_until(self, now: float) -> None:
        """Does the transfers due up to ``now`` (at ``since + k / rate``)."""
        rate, since = self.rate, self.since
        first, last = self.next_k, int((now - since) * rate + 1e-9)
        if last < first:
            return
        link, out = self.link, self.out
        assert link is not None
        count = last - first + 1
        t_first, t_last = since + first / rate, since + last / rate
        if link.present and not link.p and link.on_at <= t_first and t_last < link.off_at:
            # A clean stretch: no need to look at transfers one by one.
            out.transfers += count
            self.tick_good += count
            self.consecutive_bad = 0
            self.last_good = t_last
            self.next_k = last + 1
            return
        rnd, p, present = link.rng.random, link.p, link.present
        on_at, off_at = link.on_at, link.off_at
        good = bad = 0
        consecutive = self.consecutive_bad
        for k in range(first, last + 1):
            tk = since + k / rate
            if present and on_at <= tk < off_at and not (p and rnd() < p):
                good += 1
                consecutive = 0
                self.last_good = tk
                continue
            bad += 1
            consecutive += 1
            if consecutive >= RESET_AFTER:
                self._count(good, bad)
                self._reset(tk, now)
                return
        self._count(good, bad)
        self.consecutive_bad = consecutive
        self.next_k = last + 1

    def _count(self, good: int, bad: int) -> None:
        self.out.transfers += good + bad
        self.out.bad_transfers += bad
        self.tick_good += good
        self.tick_bad += bad

    def _reset(self, at: float, now: float) -> None:
        self.out.resets += 1
        self.out.marks.append((round(at, 6), "reset"))
        self.state = "probing"
        self.attempts = 0
        self.consecutive_bad = 0
        self.lost = (at, f"{RESET_AFTER} bad transfers in a row")
        self.last_probe = "reset"
        self.sim.log(now, "reset", self.out, at=round(at, 6), reason=self.lost[1])
        # Never before the slice being processed, so the event loop's time only moves forward.
        self.sim.schedule(max(at + BACKOFF_BASE, now), self.probe)

    # -- health ------------------------------------------------------------------------------

    def evaluate(self, now: float) -> tuple[str, str]:
        """Health at ``now``, after this slice's transfers."""
        old_good, old_bad = self.window[0]
        self.window.append((self.tick_good, self.tick_bad))
        self.window_good += self.tick_good - old_good
        self.window_bad += self.tick_bad - old_bad
        self.tick_good = self.tick_bad = 0
        state = self.state
        if state == "unstartable":
            return "critical", "not started: " + "; ".join(self.problems)
        if state == "probing":
            if self.lost is not None:
                at, why = self.lost
                return "critical", (
                    f"lost: reset at {at:.2f} s after {why}; "
                    f"{counted(self.attempts, 'probe attempt')} "
                    f"since, last: {self.last_probe}"
                )
            return "critical", (
                f"not found: {self.last_probe} "
                f"({counted(self.attempts, 'probe attempt')}, still retrying)"
            )
        if state != "running":
            return "critical", self.last_probe
        # (the slack: a tick's time is a float product, so that 0.5 s after a transfer at 3.9 s
        # is 0.5000000000000004 s at 4.4 s, but 0.5 s at 5.4 s after 4.9 s)
        if now - self.last_good > DATA_TIMEOUT + 1e-9:
            return "critical", f"no data for {now - self.last_good:.1f} s"
        total = self.window_good + self.window_bad
        if total and self.window_bad > WARN_RATIO * total:
            share = self.window_bad / total
            return "warning", (
                f"{share:.0%} bad transfers in the last {WINDOW:g} s ({self.window_bad} of {total})"
            )
        return "nominal", ""


_DIGITS = re.compile(r"\d+(?:\.\d+)?")


def _gist(reason: str) -> str:
    """A reason without its numbers: "no ACK (3 probe attempts...)" ~ "no ACK (4 ...)"."""
    return _DIGITS.sub("#", reason)


class _Sim:
    """The event loop, the commander and the event log of one run."""

    def __init__(
        self,
        bench: Bench,
        drivers: Drivers,
        seed: int,
        duration: float,
        legacy: bool,
        record: bool,
    ) -> None:
        self.bench = bench
        self.drivers = drivers
        self.chips = drivers.chips()
        self.seed = seed
        self.duration = duration
        self.legacy = legacy
        self.mode = "legacy" if legacy else "manifest"
        self.events: list[dict[str, Any]] | None = [] if record else None
        self.queue: list[tuple[float, int, Callable[[float], None]]] = []
        self.seq = 0
        self.instances: list[_Instance] = []
        self.registered: list[_Instance] = []
        self.arming: list[tuple[float, bool]] = []

    # -- plumbing ----------------------------------------------------------------------------

    def schedule(self, t: float, action: Callable[[float], None]) -> None:
        self.seq += 1  # ties keep scheduling order: deterministic
        heapq.heappush(self.queue, (t, self.seq, action))

    def log(self, t: float, event: str, inst: InstanceResult | None = None, **fields: Any) -> None:
        if self.events is None:
            return
        record: dict[str, Any] = {"t": round(t, 6), "event": event}
        if inst is not None:
            record.update(
                instance=inst.name,
                driver=inst.driver,
                bus=inst.kind,
                bus_id=inst.bus_id,
                address=inst.address,
            )
        record.update(fields)
        self.events.append(record)

    def rng(self, name: str, kind: str, bus_id: int, address: int) -> random.Random:
        # One generator per driver instance, seeded from its identity: adding a device to the
        # bench does not change what happens to the others.
        return random.Random(f"{self.seed}:{self.mode}:{name}:{kind}{bus_id}:{address}")

    def chip_answer(self, device: BenchDevice | None, driver: Driver) -> int:
        """What ``driver``'s chip id read returns from ``device``."""
        if device is None:
            return 0
        if device.chip_id is not None:
            return device.chip_id
        real = self.chips[device.chip.upper()]
        # A chip answers its id only in its own id register; elsewhere it reads 0.
        same_register = real.chip_id_register == driver.chip_id_register
        return real.chip_id or 0 if same_register else 0

    def device_id(self, driver: Driver, out: InstanceResult) -> int:
        from px4params.vehicle.devid import encode

        return encode(BUS_KINDS[out.kind], out.bus_id, out.address, driver.devtype)

    def register(self, inst: _Instance, t: float) -> None:
        inst.out.registered = True
        self.registered.append(inst)
        self.log(t, "register", inst.out)

    # -- booting -----------------------------------------------------------------------------

    def boot_manifest(self, manifest: Sequence[Configured]) -> None:
        by_driver: dict[str, list[Configured]] = {}
        orphans: list[Configured] = []
        for c in manifest:
            if c.driver is not None and c.driver.autostart:
                by_driver.setdefault(c.driver.name, []).append(c)
            else:
                orphans.append(c)
        for driver in self.drivers.autostart():
            mine = by_driver.get(driver.name, [])
            self.schedule(0.0, functools.partial(self._auto, driver=driver, mine=mine))
        for c in orphans:  # known to the commander from the manifest; nothing starts them
            out = self._result(c.instance, c.driver.name if c.driver else "-", c)
            out.registered = False
            inst = _Instance(self, out, c.driver, None, legacy=False, problems=c.problems)
            self._add(inst, 0.0, "unstartable")
            self.registered.append(inst)

    def _add(self, inst: _Instance, t: float, state: str) -> None:
        inst.state = state
        if state == "unstartable":
            inst.out.reason = "not started: " + "; ".join(inst.problems)
        inst.out.timeline.append((t, inst.out.health, inst.out.reason))
        self.instances.append(inst)

    def _result(self, name: str, driver: str, c: Configured) -> InstanceResult:
        return InstanceResult(name, driver, c.parameter, c.bus_kind, c.bus_id, c.address)

    def _auto(self, t: float, driver: Driver, mine: Sequence[Configured]) -> None:
        self.log(t, "auto", None, driver=driver.name, instances=[c.instance for c in mine])
        for c in mine:
            out = self._result(c.instance, driver.name, c)
            link = None
            if not c.problems and c.bus_kind in SIMULATED_BUSES:
                link = _Link(
                    self.bench,
                    c.bus_kind,
                    c.bus_id,
                    c.address,
                    self.rng(c.instance, c.bus_kind, c.bus_id, c.address),
                )
            problems = list(c.problems)
            if link is None and not problems:
                problems.append(f"bus kind {c.bus_kind} is not simulated by the bench")
            inst = _Instance(self, out, driver, link, legacy=False, problems=problems)
            self._add(inst, t, "unstartable" if problems else "probing")
            self.register(inst, t)  # drivers register with the commander at start
            if not problems:
                self.schedule(t, inst.probe)

    def boot_legacy(self) -> None:
        buses = self.bench.i2c_buses()
        for driver in self.drivers:
            if "i2c" not in driver.buses or driver.default_address is None:
                continue
            if driver.started_by == "parameter":  # only while its SENS_EN_* is set
                continue
            self.schedule(0.0, functools.partial(self._legacy_start, driver=driver, buses=buses))

    def _legacy_start(self, t: float, driver: Driver, buses: Sequence[int]) -> None:
        self.log(t, "legacy_start", None, driver=driver.name, command=driver.legacy_line)
        address = driver.default_address
        assert address is not None
        for bus_id in buses:
            name = f"{driver.name}@i2c{bus_id}"
            out = InstanceResult(name, driver.name, None, "i2c", bus_id, address, registered=False)
            link = _Link(self.bench, "i2c", bus_id, address, self.rng(name, "i2c", bus_id, address))
            inst = _Instance(self, out, driver, link, legacy=True)
            self._add(inst, t, "probing")
            self.schedule(t, inst.probe)

    # -- running -----------------------------------------------------------------------------

    def tick(self, now: float, number: int) -> None:
        perf = self.events is not None and number % round(PERF_PERIOD / TICK) == 0
        for inst in self.instances:
            if inst.state == "running":
                inst.run_until(now)
            level, reason = inst.evaluate(now)
            out = inst.out
            # A new entry when the level changes, or the kind of reason does (counts aside).
            if level != out.health or _gist(reason) != _gist(out.reason):
                out.timeline.append((round(now, 6), level, reason))
                if out.registered or not self.legacy:
                    self.log(now, "health", out, health=level, reason=reason or None)
            out.health, out.reason = level, reason
            if perf and out.registered:
                self.log(
                    now,
                    "perf",
                    out,
                    transfers=out.transfers,
                    bad_transfers=out.bad_transfers,
                    resets=out.resets,
                    probe_attempts=out.probe_attempts,
                )
        ok = self.may_arm()
        if not self.arming or self.arming[-1][1] != ok:
            self.arming.append((round(now, 6), ok))
            self.log(now, "arming", None, may_arm=ok)

    def blocks(self, inst: _Instance) -> bool:
        return blocks_arming(inst.out.health, legacy=self.legacy)

    def may_arm(self) -> bool:
        return not any(self.blocks(i) for i in self.registered)

    def run(self) -> None:
        # Slices of TICK; the last one ends exactly at the run's end.
        ticks = max(1, math.ceil(self.duration / TICK - 1e-9))
        for number in range(1, ticks + 1):
            at = min(number * TICK, self.duration)
            self.schedule(at, functools.partial(self.tick, number=number))
        queue = self.queue
        while queue:
            t, _, action = heapq.heappop(queue)
            if t > self.duration + 1e-9:
                break
            action(t)


def run(
    bench: Bench,
    drivers: Drivers,
    manifest: Sequence[Configured] | None,
    *,
    duration: float = 10.0,
    seed: int = 0,
    legacy: bool = False,
    record_events: bool = False,
) -> RunResult:
    """Boots ``manifest`` (the configured instances, :func:`autostart.configured`) on ``bench``
    for ``duration`` simulated seconds. With ``legacy``, today's opportunistic start runs
    instead and ``manifest`` (optional) only names what went silently missing."""
    if not duration > 0 or math.isinf(duration):
        raise BenchFileError(f"duration must be a positive number of seconds, not {duration}")
    if not legacy and manifest is None:
        raise BenchFileError("a manifest run needs the configured instances")
    sim = _Sim(bench, drivers, seed, duration, legacy, record_events)
    sim.log(0.0, "boot", None, mode=sim.mode, seed=seed, duration=duration, bench=bench.source)
    if legacy:
        sim.boot_legacy()
    else:
        sim.boot_manifest(manifest or ())
    sim.run()

    instances = [i for i in sim.instances if not (legacy and i.state == "stopped")]
    failures = [i.out.failure_line() for i in sim.registered if sim.blocks(i)]
    quiet = []
    for i in sim.instances:
        if legacy and i.state == "stopped":
            out = i.out
            there = bench.devices.get((out.kind, out.bus_id, out.address))
            command = i.driver.legacy_line if i.driver else "?"
            line = (
                f"'{command}' on I2C bus {out.bus_id} at 0x{out.address:02X}: {i.last_probe} "
                f"after {LEGACY_PROBES} probes; not started, no message"
            )
            quiet.append({"line": line, "device": there.chip if there else None})
    missing: list[str] = []
    if legacy and manifest:
        running = {
            (i.out.driver, i.out.kind, i.out.bus_id, i.out.address)
            for i in sim.instances
            if i.out.started_at is not None
        }
        for c in manifest:
            key = (c.driver.name if c.driver else "-", c.bus_kind, c.bus_id, c.address)
            if key not in running:
                driver = c.driver.name if c.driver else "-"
                missing.append(
                    f"{driver} {c.instance} on {c.location}: never started, nobody was told"
                )
    sim.log(
        duration,
        "verdict",
        None,
        may_arm=sim.may_arm(),
        failures=failures,
        silently_missing=missing,
    )
    return RunResult(
        mode=sim.mode,
        seed=seed,
        duration=duration,
        bench=bench.source,
        bench_name=bench.name,
        instances=[i.out for i in instances],
        may_arm=sim.may_arm(),
        failures=failures,
        quiet=quiet,
        silently_missing=missing,
        arming=sim.arming,
        events=sim.events,
    )
