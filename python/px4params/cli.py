"""The ``px4params`` command line.

Exit codes: 0 ok, 1 failed, 2 usage. Every error is one line on stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from typing import Any, TextIO

from .airframe import add_run_parser
from .cli_param import add_param_parser
from .completion import add_completion_parser
from .errors import Px4ParamsError
from .schema import DataType, Schema, load_schema, to_json_value

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


class CliError(Exception):
    """A failure to report as one line and exit 1."""


def parse_hex(text: str) -> bytes:
    """Bytes from hex such as ``daef7c00``, ``DA EF 7C 00`` or ``0xdaef7c00``."""
    cleaned = "".join(text.split()).removeprefix("0x").removeprefix("0X")
    try:
        return bytes.fromhex(cleaned)
    except ValueError:
        raise CliError(f"not hex bytes: {text.strip()!r} (expected e.g. 'daef7c00')") from None


def parse_json(text: str) -> Any:
    text = text.strip()  # a stdin line's newline would move an end-of-input error to "column 1"
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise CliError(f"not JSON: {e.msg} at column {e.colno} in {text.strip()!r}") from None
    except (ValueError, RecursionError) as e:  # e.g. a 5000-digit number, 100000 nested [
        raise CliError(f"not JSON: {e}") from None


def dump_json(value: Any) -> str:
    return json.dumps(to_json_value(value), separators=(", ", ": "))


def find_type(schema: Schema, name: str) -> DataType:
    try:
        return schema[name]
    except KeyError:
        hint = schema.suggest(name)
        extra = f" (did you mean: {', '.join(hint)}?)" if hint else " (see 'px4params types')"
        raise CliError(f"unknown type '{name}'{extra}") from None


def _schema(args: argparse.Namespace) -> Schema:
    return load_schema(args.dsdl or ())


def _each_item(item: str, stdin: TextIO, out: TextIO, convert: Callable[[str], str]) -> int:
    """Converts one item, or each line of stdin when ``item`` is ``-`` (batch use)."""
    if item != "-":
        print(convert(item), file=out)
        return EXIT_OK
    status = EXIT_OK
    for number, line in enumerate(stdin, start=1):
        if not line.strip():
            continue
        try:
            print(convert(line), file=out)
        except (CliError, Px4ParamsError, UnicodeError) as e:
            print(f"px4params: <stdin>:{number}: {e}", file=sys.stderr)
            status = EXIT_FAILED
    return status


def cmd_types(args: argparse.Namespace) -> int:
    schema = _schema(args)
    rows = []
    for key in schema:
        t = schema[key]
        tags = t.doc.get("tags", {})
        rows.append(
            {
                "key": key,
                "name": t.name,
                "version": list(t.version) if t.version else None,
                "kind": t.definition["kind"],
                "dialect": t.definition.get("dialect"),
                "min_bits": t.min_bits,
                "max_bits": t.max_bits,
                "max_instances": tags.get("max_instances"),
                "short": t.doc.get("short", ""),
            }
        )
    if args.json:
        print(json.dumps(rows, indent=2))
        return EXIT_OK
    width = max(len(r["key"]) for r in rows)
    for r in rows:
        bits = (
            f"{r['min_bits']}..{r['max_bits']}"
            if r["min_bits"] != r["max_bits"]
            else str(r["min_bits"])
        )
        print(f"{r['key']:<{width}}  {r['kind']:<6} {bits:>12} bits  {r['short']}".rstrip())
    return EXIT_OK


def cmd_encode(args: argparse.Namespace) -> int:
    t = find_type(_schema(args), args.type)

    def convert(text: str) -> str:
        return t.encode(parse_json(text), tao=not args.no_tao, saturate=args.saturate).hex()

    return _each_item(args.value, sys.stdin, sys.stdout, convert)


def cmd_decode(args: argparse.Namespace) -> int:
    t = find_type(_schema(args), args.type)

    def convert(text: str) -> str:
        return dump_json(t.decode(parse_hex(text), tao=not args.no_tao))

    return _each_item(args.hex, sys.stdin, sys.stdout, convert)


def cmd_frames(args: argparse.Namespace) -> int:
    from . import transfer

    t = find_type(_schema(args), args.type)
    half = transfer.service_half(t)
    if half is None and args.dest_node is not None:
        raise CliError(f"{t.key} is a message; --dest-node is for service requests/responses")
    if half is not None and args.dest_node is None:
        raise CliError(f"{t.key} is a service {half}; give --dest-node N (1..127)")
    if args.source_node == 0:
        raise CliError("anonymous transfers (source node 0) are not supported; give 1..127")
    dtid = args.dtid if args.dtid is not None else t.dtid
    if dtid is None:
        raise CliError(f"{t.key} has no default data type ID; give --dtid N")
    text = sys.stdin.read() if args.value == "-" else args.value
    try:
        out = transfer.frames(
            t,
            parse_json(text),
            source_node=args.source_node,
            transfer_id=args.transfer_id,
            priority=args.priority,
            dest_node=args.dest_node,
            dtid=dtid,
            canfd=args.canfd,
            saturate=args.saturate,
        )
    except ValueError as e:  # numbers out of range (EncodeError is not a ValueError)
        raise CliError(str(e)) from None
    if args.json:
        rows = [{"can_id": f.can_id, "data": f.data.hex()} for f in out]
        print(json.dumps(rows, indent=2))
    else:
        for f in out:
            print(f"{f.can_id:08x} {f.data.hex()}")
    return EXIT_OK


#: The talk's airframe lines for INA238#0, as a value.
TALK_INA238 = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}


def cmd_demo(args: argparse.Namespace) -> int:
    schema = _schema(args)
    t = schema["px.Ina238"]
    print(f"{t.key}: {t.doc.get('short', '')}")
    print("value (the talk's airframe lines):")
    for line in (
        "param add INA238#0",
        "param set-default INA238#0[3] 1",
        "param set-default INA238#0[4] 0x45",
        "param set-default INA238#0[5] 200",
        "param set-default INA238#0[6] 0.0003",
    ):
        print(f"  {line}")
    data = t.encode(TALK_INA238)
    print(f"encoded ({len(data)} bytes, DroneCAN bit packing): {data.hex(' ')}")
    print("leaves:")
    for leaf in t.leaves(data):
        value = leaf.value
        shown = f"{value:.7g}" if isinstance(value, float) else str(value)
        if leaf.path.endswith("._tag"):
            union = leaf.path.removesuffix("._tag")
            variant = next(iter(_at_path(t.decode(data), union)))
            shown += f" ({variant})"
        elif (
            isinstance(value, int) and not isinstance(value, bool) and leaf.path.endswith("address")
        ):
            shown += f" ({value:#04x})"
        print(f"  [{leaf.index}] {leaf.path:<20} {leaf.type:<8} {shown}")
    print(f"decoded back: {dump_json(t.decode(data))}")
    golden = schema_golden_vector()
    print(
        f"golden vector (0xBEDA:uint12, -1:int3, -5:int4, -1:int2, 0x88:uint4): {golden.hex(' ')}"
    )
    return EXIT_OK


def _at_path(value: Any, path: str) -> Any:
    for part in path.split("."):
        value = value[part]
    return value


def schema_golden_vector() -> bytes:
    """The DroneCAN reference vector, encoded through a throwaway schema of its five fields."""
    from .schema import Schema as _Schema

    def scalar(kind: str, bits: int, cast: str) -> dict[str, Any]:
        return {"kind": kind, "bits": bits, "cast": cast}

    fields = [
        ("a", scalar("uint", 12, "truncated")),
        ("b", scalar("int", 3, "saturated")),
        ("c", scalar("int", 4, "saturated")),
        ("d", scalar("int", 2, "saturated")),
        ("e", scalar("uint", 4, "truncated")),
    ]
    model = {
        "format": 1,
        "types": {
            "golden.Vector": {
                "name": "golden.Vector",
                "version": None,
                "kind": "struct",
                "dialect": "uavcan",
                "fields": [{"name": n, "type": ty} for n, ty in fields],
            }
        },
    }
    t = _Schema(model)["golden.Vector"]
    return t.encode({"a": 0xBEDA, "b": -1, "c": -5, "d": -1, "e": 0x88})


def cmd_metadata(args: argparse.Namespace) -> int:
    from . import cheader, metadata
    from .params import parameter_specs

    parser: argparse.ArgumentParser = args.metadata_parser
    if args.json is None and args.header is None:
        parser.error("give --json FILE, --header FILE or both")
    if args.json == "-" and args.header == "-":
        parser.error("--json and --header cannot both write to stdout (-)")
    if args.classic is not None and args.json is None:
        parser.error("--classic goes with --json (the header has no classic parameters)")
    schema = _schema(args)
    specs = parameter_specs(schema)
    # Everything is generated before anything is written: a failure leaves no half output.
    outputs: list[tuple[str, str, str]] = []
    if args.json is not None:
        classic = metadata.classic_source(args.classic)
        document = metadata.build_parameters_json(schema, classic, specs=specs)
        text = json.dumps(document, allow_nan=False) + "\n"
        count = len(document["parameters"]) - len(specs)
        outputs.append((args.json, text, f"{len(specs)} structured + {count} classic parameters"))
    if args.header is not None:
        guard = cheader.guard_from_filename(None if args.header == "-" else args.header)
        text = cheader.generate_header(schema, specs, guard=guard)
        outputs.append((args.header, text, f"C header for {len(specs)} parameters"))
    to_stdout = any(path == "-" for path, _, _ in outputs)
    for path, text, what in outputs:
        if path == "-":
            sys.stdout.write(text)
            continue
        try:
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        except OSError as e:
            raise CliError(f"{path}: cannot write: {e.strerror}") from None
        if not to_stdout:  # stdout carries the other output, unmixed
            print(f"wrote {path}: {what}")
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--dsdl",
        action="append",
        metavar="DIR",
        help="extra DSDL root namespace folder (repeatable; also $PX4PARAMS_DSDL_PATH)",
    )
    parser = argparse.ArgumentParser(
        prog="px4params",
        description="Structured, instanced PX4 parameters with DroneCAN serialization.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser(
        "types",
        parents=[common],
        help="list the loaded types",
        description="List every loaded type (bundled px types, DroneCAN standard types, --dsdl).",
        epilog="example: px4params types --json",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_types)

    for name, func, arg, what, example in (
        (
            "encode",
            cmd_encode,
            "value",
            "a JSON value",
            "px4params encode px.Ina238 "
            '\'{"bus": {"i2c": {"bus_id": 1, "address": 69}}, "current": 200, "shunt": 0.0003}\'',
        ),
        ("decode", cmd_decode, "hex", "hex bytes", "px4params decode px.Ina238 100317 20ea0c"),
    ):
        p = sub.add_parser(
            name,
            parents=[common],
            help=f"{name} a value of TYPE",
            description=f"{name.capitalize()} {what} of TYPE; '-' reads one per line from stdin.",
            epilog=f"example: {example}",
        )
        p.add_argument(
            "type", metavar="TYPE", help="type name, e.g. px.Ina238 or uavcan.protocol.NodeStatus"
        )
        p.add_argument(arg, metavar=arg.upper(), help=f"{what}, or - for one per line on stdin")
        p.add_argument("--no-tao", action="store_true", help="no tail array optimization (CAN FD)")
        if name == "encode":
            p.add_argument(
                "--saturate",
                action="store_true",
                help="clamp out-of-range numbers per the fields' cast modes (default: refuse)",
            )
        p.set_defaults(func=func)

    p = sub.add_parser(
        "frames",
        parents=[common],
        help="split a value of TYPE into DroneCAN CAN frames",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="""\
Encode a JSON value of TYPE and print the CAN frames of one DroneCAN transfer
of it, one per line: the 29-bit CAN ID and the frame data (tail byte
included), both in hex. A multi-frame transfer starts with its CRC; on CAN FD
the payload has no tail array optimization and is padded to a valid frame
length. For a service half (TYPE ending in .Request or .Response) give
--dest-node.""",
        epilog="""\
example:
  px4params frames uavcan.protocol.NodeStatus --source-node 10 --transfer-id 3 \\
    '{"uptime_sec": 5, "health": 0, "mode": 0, "sub_mode": 0, "vendor_specific_status_code": 0}'
  1f01550a 05000000000000c3""",
    )
    p.add_argument(
        "type", metavar="TYPE", help="type name, e.g. uavcan.equipment.power.BatteryInfo"
    )
    p.add_argument("value", metavar="JSON", help="the value as JSON, or - to read it from stdin")
    p.add_argument(
        "--transfer-id", type=int, default=0, metavar="N", help="transfer ID 0..31 (default 0)"
    )
    p.add_argument(
        "--source-node", type=int, default=1, metavar="N", help="source node ID 1..127 (default 1)"
    )
    p.add_argument(
        "--dest-node", type=int, metavar="N", help="destination node ID 1..127 (services only)"
    )
    p.add_argument(
        "--priority", type=int, default=31, metavar="N", help="priority 0..31 (default 31, lowest)"
    )
    p.add_argument("--dtid", type=int, metavar="N", help="data type ID (default: the type's own)")
    p.add_argument("--canfd", action="store_true", help="CAN FD frames (up to 64 bytes)")
    p.add_argument(
        "--saturate",
        action="store_true",
        help="clamp out-of-range numbers per the fields' cast modes (default: refuse)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_frames)

    p = sub.add_parser(
        "metadata",
        parents=[common],
        help="write parameters.json for ground stations and a C header for firmware",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="""\
Write the parameter metadata of every structured parameter (the px types with
@max_instances or @param):
  --json FILE    QGC's parameters.json (version 1) with each parameter's fields
                 in [k] order and every union variant, plus the classic
                 parameters of --classic FILE or $PX4PARAMS_PARAMETERS_JSON
  --header FILE  a C header: one struct per type, sizes, parameter ids and
                 instance counts, static inline encode/decode functions
FILE '-' writes to stdout.""",
        epilog="""\
example:
  px4params metadata --json parameters.json --classic build/parameters.json \\
    --header px4_params.h
  wrote parameters.json: 9 structured + 1909 classic parameters
  wrote px4_params.h: C header for 9 parameters""",
    )
    p.add_argument("--json", metavar="FILE", help="write parameters.json here")
    p.add_argument("--header", metavar="FILE", help="write the C header here")
    p.add_argument(
        "--classic",
        metavar="FILE",
        help="a PX4 parameters.json whose classic parameters to include "
        "(default: $PX4PARAMS_PARAMETERS_JSON, else none)",
    )
    p.set_defaults(func=cmd_metadata, metadata_parser=p)

    p = sub.add_parser(
        "demo",
        parents=[common],
        help="encode the talk's INA238 example and show its leaves",
        description="Encode the talk's INA238#0 example, print its leaves [0]..[6] and bytes, "
        "decode it back.",
        epilog="example: px4params demo",
    )
    p.set_defaults(func=cmd_demo)

    add_devid_parser(sub)
    add_param_parser(sub)
    add_run_parser(sub)
    add_completion_parser(sub)
    from .cli_mavlink import add_parser as add_mavlink_parser  # here: it imports this module
    from .cli_migrate import add_parser as add_migrate_parser

    add_mavlink_parser(sub)
    add_migrate_parser(sub)
    from .cli_autostart import add_autostart_parser  # here: it imports this module

    add_autostart_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (CliError, Px4ParamsError, UnicodeError) as e:
        print(f"px4params: error: {e}", file=sys.stderr)
        return EXIT_FAILED
    except BrokenPipeError:
        return EXIT_FAILED
    except KeyboardInterrupt:
        return 130


# --- devid: PX4 device IDs (the work is in devid.py) -------------------------------------------

DEVID_PARTS = ("bus_type", "bus", "address", "devtype")


def cmd_devid(args: argparse.Namespace) -> int:
    from . import devid

    parser: argparse.ArgumentParser = args.devid_parser
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

    # Loaded before any output, so a missing current table is one error and no partial result.
    table = devid.load_table(args.table, args.devtypes)
    if args.list:
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
        entries = devid.decode_log(args.log, table)
        if not entries:
            raise CliError(f"{args.log}: no CAL_*_ID parameters in this log")
        if args.json:
            rows = [e.as_dict() for e in entries]
            print(json.dumps({"file": args.log, "table": table.label, "parameters": rows}))
            return EXIT_OK
        width = max(len(e.param) for e in entries)
        for e in entries:
            when = f" @{e.timestamp_us / 1e6:.3f}s" if e.timestamp_us is not None else ""
            shown = e.device.describe() if e.device else f"invalid: {e.problem}"
            value = e.device.hex if e.device else ""
            print(f"{e.param:<{width}} {e.value!s:>8} {value:>8}  {shown}{when}")
        return EXIT_OK
    if args.encode:
        value = devid.encode(args.bus_type, args.bus, args.address, args.devtype, table)
        decoded = [devid.decode(value, table)]
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


def add_devid_parser(sub: Any) -> None:
    from .devid import TABLES

    p = sub.add_parser(
        "devid",
        help="decode, encode or list PX4 device IDs (CAL_MAG0_ID, ...)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="""\
Decode PX4 24-bit device IDs (bits 0-2 bus type, 3-7 bus, 8-15 address,
16-23 devtype), build one with --encode, or decode every CAL_*_ID parameter
of a ULog flight log with --log. The devtype names come from --table:
'legacy' (the PX4 driver guide's table) or 'current' (today's drv_sensor.h,
read from --devtypes FILE, $PX4PARAMS_DEVTYPES, or
../shared/data/px4_devtypes_current.tsv; FILE is a TSV 'code<TAB>name' or a
drv_sensor.h). An ID of 0 means no device.""",
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
        choices=TABLES,
        default="current",
        help="devtype table for names (default: current)",
    )
    p.add_argument(
        "--devtypes",
        metavar="FILE",
        help="current table: a TSV (code<TAB>name) or PX4's drv_sensor.h "
        "(default: $PX4PARAMS_DEVTYPES, then ../shared/data/px4_devtypes_current.tsv)",
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
