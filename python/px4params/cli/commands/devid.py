"""``px4params devid``: PX4 device IDs (the work is in ``px4params.vehicle.devid``)."""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.parsing import ArgumentParser, RawDescriptionHelpFormatter
from px4params.errors import CommandError
from px4params.status import EXIT_OK

if TYPE_CHECKING:
    import argparse

DEVID_PARTS = ("bus_type", "bus", "address", "devtype")


def cmd_devid(args: argparse.Namespace) -> int:
    from px4params.vehicle import devid

    parser: ArgumentParser = args.devid_parser
    modes = [m for m in ("ids", "encode", "log", "list") if getattr(args, m)]
    if len(modes) != 1:
        parser.error("give device IDs, or one of --encode, --log FILE, --list")
    given = [p for p in DEVID_PARTS if getattr(args, p) is not None]
    if given and not args.encode:
        parser.error("--bus-type, --bus, --address and --devtype go with --encode")
    if args.encode and len(given) != len(DEVID_PARTS):
        missing = [f"--{p.replace('_', '-')}" for p in DEVID_PARTS if p not in given]
        parser.error(f"--encode needs {', '.join(missing)}")
    if args.devtypes is not None and args.table == "legacy":
        parser.error("--devtypes is the current table's source; it does not go with --table legacy")
    if args.table == "auto" and not args.log:
        parser.error("--table auto reads the firmware version of a --log")
    # A log is read with its firmware's table; IDs without a log with today's.
    which = args.table or ("auto" if args.log else "current")

    # Loaded before any output, so a missing current table is one error and no partial result.
    table = devid.load_table(which, args.devtypes) if which != "auto" else None
    if args.list:
        assert table is not None  # --list goes without --log: "auto" was refused above
        if args.json:
            listed = [
                {"code": r.code, "name": r.name, "kind": r.kind, "macro": r.macro} for r in table
            ]
            print(json.dumps(listed))
        else:
            for r in table:
                print(f"0x{r.code:02X}  {r.kind or '-':<10}  {r.name}")
        return EXIT_OK
    if args.log:
        from px4params.formats.ulog import read_header

        log = read_header(args.log)
        entries = devid.decode_header(log, table or "auto", args.devtypes)
        if log.corrupt:
            print(
                f"px4params: warning: {args.log}: the log is cut short or damaged: device IDs "
                "logged after the break are missing",
                file=sys.stderr,
            )
        if not entries:
            raise CommandError(f"{args.log}: no CAL_*_ID parameters in this log")
        label = next((e.device.table for e in entries if e.device), which)
        if args.json:
            rows = [e.as_dict() for e in entries]
            print(json.dumps({"file": args.log, "table": label, "parameters": rows}))
            return EXIT_OK
        width = max(len(e.param) for e in entries)
        for e in entries:
            when = f" @{e.timestamp_us / 1e6:.3f}s" if e.timestamp_us is not None else ""
            shown = e.device.describe() if e.device else f"invalid: {e.problem}"
            value = e.device.hex if e.device else ""
            warning = f"  (warning: {e.warning})" if e.warning else ""
            print(f"{e.param:<{width}} {e.value!s:>8} {value:>8}  {shown}{when}{warning}")
        print(f"(devtypes: the {label} table)")
        return EXIT_OK
    if args.encode:
        device_id = devid.encode(args.bus_type, args.bus, args.address, args.devtype, table)
        decoded = [devid.decode(device_id, table)]
    else:
        # Parse every ID before printing any, so a bad one fails the command cleanly.
        decoded = [devid.decode(devid.parse_device_id(text), table) for text in args.ids]
    if args.json:
        rows = [d.as_dict() for d in decoded]
        print(json.dumps(rows[0] if args.encode else rows))
    else:
        for d in decoded:
            print(f"{d.value} ({d.hex}): {d.describe()}")
    return EXIT_OK


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params devid``."""
    from px4params.vehicle.devid import TABLES

    p = sub.add_parser(
        name,
        help=summary,
        formatter_class=RawDescriptionHelpFormatter,
        description="""\
Decode PX4 24-bit device IDs (bits 0-2 bus type, 3-7 bus, 8-15 address,
16-23 devtype), build one with --encode, or decode every CAL_*_ID parameter
of a ULog flight log with --log. The devtype names come from --table:
'legacy' (the PX4 driver guide's table), a release's (px4-v1.6 for PX4
1.6-1.7, px4-v1.8 for 1.8-1.10, px4-v1.11 for 1.11-1.12, px4-v1.13), or
'current' (today's drv_sensor.h, shipped; --devtypes FILE or
$PX4PARAMS_DEVTYPES read another, FILE a TSV 'code<TAB>name' or a
drv_sensor.h). Codes were reassigned over the years, so --log picks the table
of the log's firmware version (without one: PX4 1.12's CAL_*_PRIO parameters
mean today's table, else px4-v1.6), and flags a devtype of another sensor
kind than its parameter. An ID of 0 means no device.""",
        epilog="""\
examples:
  px4params devid --table legacy 73225 66826 263178
  73225 (0x011E09): HMC5883 (MAG), I2C bus 1, address 0x1E
  ...
  px4params devid --encode --bus-type i2c --bus 1 --address 0x0c --devtype AK09916
  592905 (0x090C09): AK09916 (MAG), I2C bus 1, address 0x0C
  px4params devid --log flight.ulg --json
  px4params devid --list --table legacy""",
    )
    p.add_argument("ids", nargs="*", metavar="ID", help="device IDs, decimal or 0x hex")
    p.add_argument(
        "--table",
        choices=(*TABLES, "auto"),
        help="devtype table for names: legacy, current, a release's (px4-v1.6, px4-v1.8, "
        "px4-v1.11, px4-v1.13), or auto, the --log's firmware's (default: auto with --log, "
        "else current)",
    )
    p.add_argument(
        "--devtypes",
        metavar="FILE",
        help="current table: a TSV (code<TAB>name) or PX4's drv_sensor.h "
        "(default: $PX4PARAMS_DEVTYPES, else the one shipped with px4params)",
    )
    p.add_argument("--encode", action="store_true", help="build an ID from the four parts below")
    p.add_argument(
        "--bus-type",
        metavar="T",
        help="unknown, i2c, spi, uavcan, simulation, serial, mavlink, or 0..7",
    )
    p.add_argument("--bus", metavar="N", help="bus number 0..31")
    p.add_argument("--address", metavar="A", help="address 0..255 (e.g. 0x0c)")
    p.add_argument(
        "--devtype", metavar="D", help="devtype code 0..255, or a name from the table (AK09916)"
    )
    p.add_argument("--log", metavar="FILE.ulg", help="decode every CAL_*_ID of a ULog file")
    p.add_argument("--list", action="store_true", help="print the devtype table")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_devid, devid_parser=p)
