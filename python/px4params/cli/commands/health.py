"""``px4params health FILE.ulg``: the per-device story of a flight log written by
``px4params autostart run --ulog`` (the work is in ``px4params.vehicle.flight_log``)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from px4params._records import TYPE_CHECKING
from px4params.cli.parsing import RawDescriptionHelpFormatter
from px4params.numbers import counted
from px4params.status import EXIT_FAILED, EXIT_OK
from px4params.writing import check_outputs, write_file

if TYPE_CHECKING:
    import argparse

    from px4params.vehicle.simbench import InstanceResult, RunResult


def cmd_health(args: argparse.Namespace) -> int:
    from px4params.vehicle.flight_log import read_run_ulog

    check_outputs([args.timeline], [args.log])
    result = read_run_ulog(args.log)
    if args.timeline:
        from px4params.vehicle.timeline import render_svg

        write_file(args.timeline, render_svg(result).encode(), keep_backup=False)
    if args.json:
        print(json.dumps(result.as_dict(), indent=2))
    else:
        for line in story(result, args.log):
            print(line)
        if args.timeline:
            print(f"wrote health timeline to {args.timeline}")
    # A log cut short cannot tell that the vehicle may arm: what came after its end is unknown.
    return EXIT_OK if result.may_arm and result.log_cut_at is None else EXIT_FAILED


def story(result: RunResult, path: str) -> list[str]:
    """The log as a reader wants it: the verdict, the first failure, then each device. For a
    log cut short, the verdict and each device's state are as of where it ends, said so."""
    verdict = result.verdict
    cut = result.log_cut_at
    end = "at the end" if cut is None else f"at {cut:.2f} s, where the log ends"
    lines = [
        f"{path}: {result.mode} boot of {result.bench_label}, {result.duration:g} s (seed "
        f"{result.seed}): {verdict} {end}"
    ]
    if cut is not None:
        lines.append(
            f"warning: the log ends at {cut:.2f} s without the run's clean end (cut short?): "
            f"its story is uncertain from {cut:.2f} s on, and nothing after is known"
        )
    first = _first_failure(result)
    if first is not None:
        t, inst, reason = first
        lines.append(f"first failure: {inst.name} ({inst.driver}) at {t:.2f} s: {reason}")
    changes = ", ".join(f"{'may arm' if ok else 'refused'} at {t:.2f} s" for t, ok in result.arming)
    lines.append(f"commander: {changes or 'no answer logged'}")
    if result.arming and result.arming[-1][1] and not result.may_arm:
        # The verdict is the devices' (a damaged log, or one cut between a device's sample and
        # the commander's next answer): say why it overrules the commander's last word.
        lines.append(
            f"warning: the commander's last answer is 'may arm', but {end} these devices block "
            "arming:"
        )
        lines += [f"  {line}" for line in result.failures]
    for inst in result.instances:
        device = f", device ID 0x{inst.device_id:06X}" if inst.device_id else ""
        lines.append(f"{inst.name} ({inst.driver} on {inst.location}{device})")
        events = [
            (t, f"{level}{': ' + reason if reason else ''}") for t, level, reason in inst.timeline
        ]
        events += [
            (t, "started" if what == "start" else "lost (driver reset)") for t, what in inst.marks
        ]
        for t, text in sorted(events, key=lambda e: e[0]):
            lines.append(f"  {t:7.2f} s  {text}")
        lines.append(
            f"  {end}: {inst.health}; {counted(inst.transfers, 'transfer')}, "
            f"{counted(inst.bad_transfers, 'error')}, {counted(inst.resets, 'timeout')}, "
            f"{counted(inst.probe_attempts, 'probe attempt')}"
        )
    if result.silently_missing:
        lines.append("silently missing (configured, never started, no message):")
        lines += [f"  {line}" for line in result.silently_missing]
    return lines


def _first_failure(result: RunResult) -> tuple[float, InstanceResult, str] | None:
    """The earliest moment a device that had been running went critical (lost), else the
    earliest critical entry of any device."""
    lost = [
        (t, inst, reason)
        for inst in result.instances
        for t, level, reason in inst.timeline
        if level == "critical" and inst.started_at is not None and t > inst.started_at
    ]
    if lost:
        return min(lost, key=lambda x: x[0])
    return None


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    p = sub.add_parser(
        name,
        help=summary,
        description="Read a flight log written by 'px4params autostart run --ulog' (with "
        "pyulog) and tell each device's story: when it started, every change of its health "
        "with the reason, resets, its last perf counters, and the commander's answers. The "
        "first line after the header names the first device that was lost, and when. A log "
        "without the run's clean end (cut short) is said to be, with the moment from which its "
        "story is uncertain; states are then as of that moment.\n"
        "Exit code 0: the log ends with 'may arm'; 1: arming refused, a log cut short (or an "
        "error).",
        epilog="""\
examples:
  px4params autostart run --airframe examples/two_batteries.airframe \\
    --bench examples/two_batteries_faults.bench.toml --ulog run.ulg   # exit status 1
  px4params health run.ulg --timeline run.svg   # the same story: exit status 1""",
        formatter_class=RawDescriptionHelpFormatter,
    )
    p.add_argument("log", metavar="FILE.ulg", help="the flight log")
    p.add_argument("--timeline", metavar="FILE.svg", help="write the health timeline picture")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_health)
