"""``px4params migrate``: propose a device manifest from today's configuration (the work is in
``px4params.migrate``)."""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.parsing import ArgumentParser, RawDescriptionHelpFormatter
from px4params.numbers import counted
from px4params.status import EXIT_OK
from px4params.writing import check_outputs, write_file

if TYPE_CHECKING:
    import argparse

__all__ = ["add_parser"]


def cmd_migrate(args: argparse.Namespace) -> int:
    from px4params import migrate
    from px4params.dsdl.schema import load_schema
    from px4params.vehicle import devid

    parser: ArgumentParser = args.migrate_parser
    if args.devtypes is not None and args.table == "legacy":
        parser.error("--devtypes is the current table's source; it does not go with --table legacy")
    # Everything is read and checked before anything is written.
    check_outputs([args.output], [args.file, args.devtypes])
    config = migrate.read_config(args.file)
    # The device IDs follow the devtype table of the file's firmware era unless one is given.
    table = None
    if args.table or args.devtypes:
        table = devid.load_table(args.table or "current", args.devtypes)
    schema = load_schema(args.dsdl or (), include_dronecan=False)
    proposal = migrate.migrate(config, schema, table, args.board, args.target_release)
    airframe = proposal.airframe()
    if args.output is not None:
        write_file(args.output, airframe.encode(), keep_backup=False)
    if args.json:
        print(json.dumps(proposal.as_dict(), indent=2))
    elif args.output is not None:
        sys.stdout.write(proposal.report())
        print(f"\nwrote {args.output}: {counted(len(proposal.instances), 'instance')}")
    else:  # the airframe on stdout (to redirect), the report beside it on stderr
        sys.stdout.write(airframe)
        sys.stderr.write(proposal.report())
    return EXIT_OK


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params migrate``."""
    from px4params.vehicle.devid import TABLES

    p = sub.add_parser(
        name,
        help=summary,
        formatter_class=RawDescriptionHelpFormatter,
        description="""\
Read today's configuration, a QGC .params file, a 'param set' list or a ULog
flight log, and propose a device manifest: an airframe file of 'param add' /
'param set-default' lines for 'px4params run', and a report. What the board's
script starts stays out; devices found by probing (CAL_*_ID device IDs on
external I2C), drivers enabled by a switch (SENS_EN_*) and power monitors the
i2c_launcher found become instances. A log's boot console (what started, on
which bus, address and rotation) wins over every table. The report lists what
is left out and why, what could not be carried over, and every assumption
made (a guessed bus, an unknown board); nothing is dropped silently. The
board's script is judged at the file's release; the report says, for each
device it starts, whether the board's scripts of later releases still do, and
--target-release makes the proposal for the firmware the vehicle will run.""",
        epilog="""\
examples:
  px4params migrate flight.ulg -o vehicle.airframe   # report on stdout
  px4params migrate vehicle.params > vehicle.airframe # report on stderr
  px4params migrate old.ulg --table legacy --json
  px4params migrate old.ulg --target-release v1.15.0 -o vehicle.airframe
  px4params run vehicle.airframe --store vehicle.store""",
    )
    p.add_argument(
        "file", metavar="FILE", help="QGC .params file, 'param set' list or ULog (.ulg) flight log"
    )
    p.add_argument(
        "-o", "--output", metavar="AIRFRAME", help="write the airframe file here (default: stdout)"
    )
    p.add_argument("--json", action="store_true", help="the proposal and report as JSON")
    p.add_argument(
        "--table",
        choices=TABLES,
        help="devtype table for CAL_*_ID device IDs (default: the one of the file's firmware "
        "version, from a log's ver_sw_release or a QGC file's '# Version' line, else decided from "
        "its parameters; the report says where one given is not the file's own)",
    )
    p.add_argument(
        "--board",
        metavar="NAME",
        help="PX4 board name (px4_fmu-v6c, ...): what its startup script starts (default: a "
        "log's ver_hw; a .params file names no board)",
    )
    p.add_argument(
        "--target-release",
        metavar="RELEASE",
        help="the PX4 release the vehicle will run (v1.15.0, v1.16.2, main; a release the board "
        "table has no snapshot of is judged by the newest it has at or before it): a device the "
        "file's board script starts and that release's does not becomes an instance (default: "
        "the file's own release; the report names such devices)",
    )
    p.add_argument(
        "--devtypes",
        metavar="FILE",
        help="current table: a TSV (code<TAB>name) or drv_sensor.h (as for px4params devid)",
    )
    p.add_argument(
        "--dsdl",
        action="append",
        metavar="DIR",
        help="extra DSDL root namespace folder (repeatable): more parameter types",
    )
    p.set_defaults(func=cmd_migrate, migrate_parser=p)
