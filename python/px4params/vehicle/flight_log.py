"""A simulated bench run as a ULog (``px4params autostart run --ulog FILE``), and back
(``px4params health FILE.ulg``).

The talk: "perf counters are only streamed to ulog before and after arming. Not helpful in a
crash." Here they are streamed for the whole run, once a second, beside each driver instance's
health, so that a log cut short by a crash still says which device failed and when.

What the log holds:

- **Parameters**: what a ground station sees of the store (classic parameters, every live
  destructured name, the instance masks), so Flight Review lists them.
- **Information**: ``sys_name``, ``ver_sw``, the run (mode, bench, seed, duration); as
  multi-information, ``manifest_instance`` (one line per configured instance) and
  ``driver_instance`` (per topic multi ID: instance, driver, bus kind, bus, address) and,
  for a legacy boot, ``silently_missing`` (configured instances nothing started).
- **Topics**, one multi ID per driver instance: ``driver_health`` (on every change and once a
  second: health 0 nominal, 1 warning, 2 critical), ``driver_perf`` (once a second: transfers,
  errors, timeouts, probe attempts, time since the driver last started) and ``arming_check``
  (on every change and once a second).
- **Logged messages**: a driver started (INFO), a warning (WARNING), a device lost (ERROR), a
  lost device started again ("recovered", NOTICE), back to nominal (NOTICE), arming refused
  (WARNING) or allowed (INFO), with PX4's levels; last, at the run's duration, the run's clean
  end (INFO, :data:`END_OF_RUN`).

A log without that last message was cut short (a crash, a full card, a copy that stopped): its
story is known only up to the last moment it holds, and :func:`read_run_ulog` says from when it
is uncertain (``RunResult.log_cut_at``) instead of telling the last state as the end.
"""

from __future__ import annotations

from px4params._records import TYPE_CHECKING
from px4params.errors import ULogError
from px4params.formats.ulog import ULogWriter
from px4params.vehicle.autostart import describe_location

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from collections.abc import Mapping, Sequence
    from typing import Any

    from px4params.vehicle.autostart import Configured
    from px4params.vehicle.simbench import InstanceResult, RunResult

#: ``driver_health.health`` values.
HEALTH_CODES = {"nominal": 0, "warning": 1, "critical": 2}
HEALTH_NAMES = {code: name for name, code in HEALTH_CODES.items()}

#: ``px4params_mode`` values: a boot from the manifest, or today's opportunistic start (legacy).
MODES = ("manifest", "legacy")

#: Characters of an instance name the topics carry (``INA238#0``, ``ist8310@i2c1``).
NAME_CHARS = 24

_HEALTH_FIELDS = [
    ("uint64_t", "timestamp"),
    ("uint32_t", "device_id"),
    ("uint8_t", "health"),
    ("bool", "registered"),
    (f"char[{NAME_CHARS}]", "instance"),
]
_PERF_FIELDS = [
    ("uint64_t", "timestamp"),
    ("uint32_t", "transfers"),
    ("uint32_t", "errors"),
    ("uint32_t", "timeouts"),
    ("uint32_t", "probe_attempts"),
    ("uint64_t", "elapsed_us"),
    (f"char[{NAME_CHARS}]", "instance"),
]
_ARMING_FIELDS = [
    ("uint64_t", "timestamp"),
    ("bool", "may_arm"),
    ("uint8_t", "blocking"),
]

#: The text of the last logged message of a run's log, which says the log was not cut short.
END_OF_RUN = "px4params: end of the run"

#: The logged message level of each health a device changes to.
_LEVEL_OF = {"critical": "error", "warning": "warning", "nominal": "notice"}


def _us(t: float) -> int:
    return round(t * 1_000_000)


def run_ulog(
    result: RunResult,
    parameters: Mapping[str, int | float],
    manifest: Sequence[Configured] = (),
    *,
    version: str = "",
) -> bytes:
    """The ULog of ``result`` (a run with its events recorded), with ``parameters`` (name ->
    value, as :func:`px4params.store.flat.flat_values` gives them) and the ``manifest``."""
    if result.events is None:
        raise ValueError("the run's events were not recorded (run(..., record_events=True))")
    log = ULogWriter()
    log.define("driver_health", _HEALTH_FIELDS)
    log.define("driver_perf", _PERF_FIELDS)
    log.define("arming_check", _ARMING_FIELDS)
    log.info("sys_name", "px4params")
    log.info("ver_sw", version or "unknown")
    log.info("ver_hw", "PX4PARAMS_BENCH")
    log.info("px4params_mode", result.mode)
    log.info("px4params_bench", result.bench)
    if result.bench_name:
        log.info("px4params_bench_name", result.bench_name)
    log.info("px4params_seed", result.seed)
    log.info("px4params_duration_us", str(_us(result.duration)))
    for c in manifest:
        line = f"{c.instance} {c.driver.name if c.driver else '-'} on {c.location}"
        log.info("manifest_instance", line, multi=True)
    for line in result.silently_missing:  # a legacy boot compared with the manifest
        log.info("silently_missing", line, multi=True)
    for inst in result.instances:  # in multi ID order
        line = f"{inst.name} {inst.driver} {inst.kind} {inst.bus_id} {inst.address}"
        log.info("driver_instance", line, multi=True)
    for name, value in parameters.items():
        log.parameter(name, value)
    _Stream(log, result).play()
    log.log("info", max(_us(result.duration), log.last_timestamp_us), END_OF_RUN)
    return log.getvalue()


class _Stream:
    """Replays a run's events into the data section."""

    def __init__(self, log: ULogWriter, result: RunResult) -> None:
        self.log = log
        self.result = result
        self.health_ids: dict[str, int] = {}
        self.perf_ids: dict[str, int] = {}
        self.arming_id: int | None = None
        self.health: dict[str, str] = {}
        self.device_ids: dict[str, int] = {}
        self.started_at: dict[str, float] = {}
        self.lost: set[str] = set()
        self.registered = {i.name: i.registered for i in result.instances}
        self.may_arm = False
        self.last_perf_t = -1.0
        # Instances in the order the result lists them get multi IDs 0, 1, ... per topic.
        for inst in result.instances:
            self.health_ids[inst.name] = log.subscribe("driver_health")
            self.perf_ids[inst.name] = log.subscribe("driver_perf")
        self.arming_id = log.subscribe("arming_check")

    def play(self) -> None:
        for event in sorted(self.result.events or (), key=lambda e: e["t"]):
            handler = getattr(self, f"on_{event['event']}", None)
            if handler is not None:
                handler(event, _us(event["t"]))

    # -- topics -------------------------------------------------------------------------------

    def _health_sample(self, name: str, at: int) -> None:
        msg_id = self.health_ids.get(name)
        if msg_id is None:  # an instance the result leaves out (a quiet legacy start)
            return
        code = HEALTH_CODES[self.health.get(name, "critical")]
        registered = self.registered.get(name, True)
        self.log.data(msg_id, at, self.device_ids.get(name, 0), code, registered, name)

    def _arming_sample(self, at: int) -> None:
        blocking = sum(1 for h in self.health.values() if h != "nominal")
        assert self.arming_id is not None
        self.log.data(self.arming_id, at, self.may_arm, min(blocking, 255))

    # -- events -------------------------------------------------------------------------------

    def on_register(self, e: dict[str, Any], at: int) -> None:
        name = e["instance"]
        if name in self.health:  # a legacy driver registers once it runs: health follows
            return
        self.health[name] = "critical"  # until the first answer: what the commander assumes
        self._health_sample(name, at)
        self.log.log("debug", at, f"{e['driver']} {name} on {_where(e)}: critical: starting")

    def on_started(self, e: dict[str, Any], at: int) -> None:
        name = e["instance"]
        self.device_ids[name] = int(e.get("device_id") or 0)
        self.started_at[name] = e["t"]
        again = name in self.lost  # the device was lost and answers again
        self.lost.discard(name)
        self.log.log(
            "notice" if again else "info",
            at,
            f"{e['driver']} {name}: {'recovered: started again' if again else 'started'} on "
            f"{_where(e)} (device ID {e['device_id_hex']}, after {e['attempts']} probe attempts)",
        )

    def on_reset(self, e: dict[str, Any], at: int) -> None:
        name = e["instance"]
        self.started_at.pop(name, None)
        self.lost.add(name)
        lost = f"{e['driver']} {name}: device lost on {_where(e)}: {e['reason']}"
        # At the moment it was lost (the simulation notices it at the end of its time slice),
        # unless something later is written already.
        self.log.log("error", max(_us(e.get("at", e["t"])), self.log.last_timestamp_us), lost)

    def on_start_failed(self, e: dict[str, Any], at: int) -> None:
        self.log.log(
            "debug", at, f"{e['driver']} on {_where(e)}: quiet start found nothing ({e['reason']})"
        )

    def on_health(self, e: dict[str, Any], at: int) -> None:
        name, level = e["instance"], e["health"]
        self.health[name] = level
        self._health_sample(name, at)
        text = "nominal" if level == "nominal" else f"{level}: {e.get('reason') or ''}".rstrip(": ")
        self.log.log(_LEVEL_OF[level], at, f"{e['driver']} {name} on {_where(e)}: {text}")

    def on_perf(self, e: dict[str, Any], at: int) -> None:
        name = e["instance"]
        if e["t"] != self.last_perf_t:  # once a second: the commander's answer too
            self.last_perf_t = e["t"]
            self._arming_sample(at)
        self._health_sample(name, at)
        msg_id = self.perf_ids.get(name)
        if msg_id is None:
            return
        since = self.started_at.get(name)
        elapsed = _us(e["t"] - since) if since is not None else 0
        self.log.data(
            msg_id,
            at,
            e["transfers"],
            e["bad_transfers"],
            e["resets"],
            e.get("probe_attempts", 0),
            elapsed,
            name,
        )

    def on_arming(self, e: dict[str, Any], at: int) -> None:
        self.may_arm = bool(e["may_arm"])
        self._arming_sample(at)
        if self.may_arm:
            self.log.log("info", at, "commander: may arm: every manifest device is nominal")
        else:
            blocking = sorted(n for n, h in self.health.items() if h != "nominal")
            which = ", ".join(blocking) if blocking else "devices still starting"
            self.log.log("warning", at, f"commander: arming refused: {which}")


def _where(e: Mapping[str, Any]) -> str:
    return describe_location(e["bus"], e["bus_id"], e["address"])


# -- reading a log back ------------------------------------------------------------------------


#: The fields :func:`read_run_ulog` reads of each topic :func:`run_ulog` writes.
_FIELDS = {
    "driver_health": ("timestamp", "health", "registered", "device_id"),
    "driver_perf": ("timestamp", "transfers", "errors", "timeouts", "probe_attempts"),
    "arming_check": ("timestamp", "may_arm"),
}


def read_run_ulog(path: str) -> RunResult:
    """The run a ULog written by :func:`run_ulog` tells (``px4params health``): every instance
    with its health timeline, starts and resets, last perf counters, and the commander's
    answers. :class:`ULogError` for a file that is not such a log."""
    from px4params.formats.ulog import parse
    from px4params.vehicle.simbench import InstanceResult, RunResult, blocks_arming

    ulog = parse(path, None)
    info = ulog.msg_info_dict
    if "px4params_mode" not in info:
        raise ULogError(
            f"{path}: not a log of 'px4params autostart run --ulog' (no px4params_mode information)"
        )
    mode = _text(path, "px4params_mode", info["px4params_mode"])
    if mode not in MODES:
        known = " or ".join(repr(m) for m in MODES)
        raise ULogError(f"{path}: px4params_mode is {mode[:40]!r}, not {known} (a damaged log?)")
    # (An empty manifest's run has no driver instance: a run with no devices.)
    lines = ulog.msg_info_multiple_dict.get("driver_instance", [])
    topics = {(d.name, d.multi_id): d.data for d in ulog.data_list}
    for (topic, multi_id), data in topics.items():
        missing = [f for f in _FIELDS.get(topic, ()) if f not in data]
        if missing:
            raise ULogError(
                f"{path}: {topic} {multi_id} has no field {missing[0]!r} (a log of 'autostart "
                f"run --ulog' has {', '.join(_FIELDS[topic])})"
            )
    said = _messages(ulog.logged_messages)
    health_names = _sample_names(topics, "driver_health")
    perf_names = _sample_names(topics, "driver_perf")
    instances: list[InstanceResult] = []
    for position, parts in enumerate(lines):
        fields = _text(path, f"driver_instance {position}", parts).split(" ")
        if len(fields) != 5 or not fields[3].isdigit() or not fields[4].isdigit():
            raise ULogError(f"{path}: driver_instance {position}: cannot read {''.join(parts)!r}")
        name, driver, kind, bus_id, address = fields
        inst = InstanceResult(name, driver, None, kind, int(bus_id), int(address))
        health = topics.get(("driver_health", _multi_id_of(name, position, health_names)))
        if health is not None:
            _health_story(inst, health, said)
        perf = topics.get(("driver_perf", _multi_id_of(name, position, perf_names)))
        if perf is not None and len(perf["timestamp"]):
            inst.transfers = int(perf["transfers"][-1])
            inst.bad_transfers = int(perf["errors"][-1])
            inst.resets = int(perf["timeouts"][-1])
            inst.probe_attempts = int(perf["probe_attempts"][-1])
        for t, what in said.get((name, "mark"), []):
            inst.marks.append((t, what))
            if what == "start" and inst.started_at is None:
                inst.started_at = t
        instances.append(inst)
    _check_manifest_told(path, mode, ulog, instances)
    arming_data = topics.get(("arming_check", 0))
    arming: list[tuple[float, bool]] = []
    if arming_data is not None:
        for stamp, ok in zip(arming_data["timestamp"], arming_data["may_arm"], strict=True):
            if not arming or arming[-1][1] != bool(ok):
                arming.append((int(stamp) / 1e6, bool(ok)))
    legacy = mode == "legacy"
    # The devices the commander knows of: with the manifest, every one it lists (one nothing
    # can start too); today (legacy), those a driver registered. One that ends blocking keeps
    # the vehicle from arming, whatever the log's last answer says (a log that says both is
    # damaged, or of a newer writer's codes). (This rule, by helper-108, from its branch.)
    blocking = [
        i
        for i in instances
        if (i.registered or not legacy) and blocks_arming(i.health, legacy=legacy)
    ]
    may_arm = bool(arming and arming[-1][1]) and not blocking
    clean_end = not ulog.file_corruption and any(
        m.message == END_OF_RUN for m in ulog.logged_messages[-1:]
    )
    return RunResult(
        mode=mode,
        seed=_whole(path, info, "px4params_seed"),
        duration=_whole(path, info, "px4params_duration_us") / 1e6,
        bench=_text(path, "px4params_bench", info.get("px4params_bench", "")),
        bench_name=_text(path, "px4params_bench_name", info.get("px4params_bench_name", "")),
        instances=instances,
        may_arm=may_arm,
        failures=[i.failure_line() for i in blocking] if not may_arm else [],
        silently_missing=[
            _text(path, f"silently_missing {n}", parts)
            for n, parts in enumerate(ulog.msg_info_multiple_dict.get("silently_missing", []))
        ],
        arming=arming,
        log_cut_at=None if clean_end else _last_moment(ulog),
    )


def _sample_names(topics: Mapping[tuple[str, int], Any], topic: str) -> dict[int, bytes]:
    """The instance each multi ID of ``topic`` is about, as its first sample's ``instance``
    field names it (cut to :data:`NAME_CHARS`); none for a multi ID without samples or field."""
    names: dict[int, bytes] = {}
    for (name, multi_id), data in topics.items():
        if name != topic or "instance[0]" not in data or not len(data["timestamp"]):
            continue
        chars = bytearray()
        while f"instance[{len(chars)}]" in data:  # pyulog: a column per character
            chars.append(int(data[f"instance[{len(chars)}]"][0]) & 0xFF)
        names[multi_id] = bytes(chars).split(b"\0", 1)[0]
    return names


def _multi_id_of(name: str, position: int, names: Mapping[int, bytes]) -> int | None:
    """The multi ID of instance ``name``'s samples: its place among the driver_instance lines,
    unless the samples there name another instance (a line lost from a damaged log moves the
    rest up), then the one multi ID whose samples name it."""
    key = name.encode()[:NAME_CHARS]
    if names.get(position) == key:
        return position
    elsewhere = [multi_id for multi_id, said in names.items() if said == key]
    if len(elsewhere) == 1:
        return elsewhere[0]
    return position if position not in names else None


def _text(path: str, key: str, value: Any) -> str:
    """An information value the writer gives as text: a string, or a multi-information value's
    parts (pyulog gives bytes or numbers for a value of another type: a damaged log)."""
    if isinstance(value, list) and all(isinstance(part, str) for part in value):
        return "".join(value)
    if not isinstance(value, str):
        raise ULogError(f"{path}: {key} is {str(value)[:40]!r}, not text (a damaged log?)")
    return value


def _whole(path: str, info: Mapping[str, Any], key: str) -> int:
    """An information value the writer gives as a whole number (0 where the log has none)."""
    value = info.get(key, 0)
    if isinstance(value, int) or (isinstance(value, str) and value.isascii() and value.isdigit()):
        return int(value)
    raise ULogError(f"{path}: {key} is {str(value)[:40]!r}, not a whole number (a damaged log?)")


def _check_manifest_told(
    path: str, mode: str, ulog: Any, instances: Sequence[InstanceResult]
) -> None:
    """Every configured instance of a manifest boot has its driver's story in the log (the
    run gives each one, started or not): one the log lacks would be left out of the story,
    and out of the verdict, without a word."""
    if mode != "manifest":
        return  # a legacy boot names drivers, and says what it missed (silently_missing)
    told = {inst.name for inst in instances}
    for parts in ulog.msg_info_multiple_dict.get("manifest_instance", []):
        name = "".join(str(part) for part in parts).split(" ", 1)[0]
        if name not in told:
            raise ULogError(
                f"{path}: manifest instance {name} has no driver story (driver_instance): "
                "a damaged log?"
            )


def _last_moment(ulog: Any) -> float:
    """The latest time a log holds anything for (seconds): samples or logged messages. A log
    cut there may have lost part of what happened at that very moment."""
    stamps = [int(ulog.last_timestamp)] + [int(m.timestamp) for m in ulog.logged_messages[-1:]]
    return max(stamps) / 1e6


def _messages(logged: Sequence[Any]) -> dict[tuple[str, Any], list[tuple[float, str]]]:
    """What the logged messages say per instance: ``(name, t_us)`` -> health texts, and
    ``(name, "mark")`` -> starts and resets, as :class:`_Stream` words them."""
    said: dict[tuple[str, Any], list[tuple[float, str]]] = {}
    for m in logged:
        words = m.message.split(" ", 2)
        if len(words) < 3:
            continue
        name, rest = words[1].rstrip(":"), words[2]
        t = int(m.timestamp) / 1e6
        if words[1].endswith(":") and rest.startswith(("started on ", "recovered: started again")):
            said.setdefault((name, "mark"), []).append((t, "start"))
        elif words[1].endswith(":") and rest.startswith("device lost on "):
            said.setdefault((name, "mark"), []).append((t, "reset"))
        elif rest.startswith("on ") and ": " in rest:
            said.setdefault((name, int(m.timestamp)), []).append((t, rest.split(": ", 1)[1]))
    return said


def _health_story(inst: InstanceResult, data: Mapping[str, Any], said: Mapping[Any, Any]) -> None:
    codes, stamps = data["health"], data["timestamp"]
    previous = None
    for stamp, code in zip(stamps, map(int, codes), strict=True):
        # A code beyond those known (a newer writer's, or damage) is read as the worst known,
        # and says so.
        level = HEALTH_NAMES.get(code, "critical")
        unknown = code not in HEALTH_NAMES
        texts = said.get((inst.name, int(stamp)), [])
        reason = texts[-1][1] if texts else ""
        if reason.startswith(f"{level}: "):
            reason = reason[len(level) + 2 :]
        elif reason in ("nominal", level):  # a level logged without a reason (_Stream.on_health)
            reason = ""
        if unknown and not reason:
            reason = f"health code {code}, unknown here: taken as critical"
        # By code, not level: two unknown codes in a row are two entries, each with its reason.
        if code != previous or (texts and reason != inst.reason):
            inst.timeline.append((int(stamp) / 1e6, level, reason))
            inst.reason = reason
        previous = code
        inst.health = level
    if len(stamps):
        inst.registered = bool(data["registered"][-1])
        device_id = int(data["device_id"][-1])
        inst.device_id = device_id or None
