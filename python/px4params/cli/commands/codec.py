"""``px4params types|encode|decode|frames|demo``: the codec on the command line."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator, Sequence

from px4params._records import TYPE_CHECKING
from px4params.cli.options import dsdl_option, integer
from px4params.cli.parsing import ArgumentParser, RawDescriptionHelpFormatter
from px4params.dsdl.schema import DataType, Schema, load_schema, to_json_value, value_at
from px4params.errors import CommandError, EncodeError, NumberError, Px4ParamsError
from px4params.numbers import abbreviated, dump_json, load_json
from px4params.reading import not_text_line
from px4params.status import EXIT_FAILED, EXIT_OK

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    import argparse
    from typing import Any, TextIO


def parse_hex(text: str) -> bytes:
    """Bytes from hex such as ``daef7c00``, ``DA EF 7C 00`` or ``0xdaef7c00``."""
    cleaned = "".join(text.split()).removeprefix("0x").removeprefix("0X")
    try:
        return bytes.fromhex(cleaned)
    except ValueError:
        raise CommandError(f"not hex bytes: {text.strip()!r} (expected e.g. 'daef7c00')") from None


def parse_json(text: str) -> Any:
    import json  # for its error class (load_json imports it anyway)

    text = text.strip()  # a stdin line's newline would move an end-of-input error to "column 1"
    try:
        return load_json(text)
    except NumberError as e:
        raise CommandError(str(e)) from None
    except json.JSONDecodeError as e:
        raise CommandError(
            f"not JSON: {e.msg} at column {e.colno} in '{abbreviated(text)}'"
        ) from None
    except (ValueError, RecursionError) as e:  # e.g. a 5000-digit number, 100000 nested [
        raise CommandError(f"not JSON: {e}") from None


def value_json(value: Any) -> str:
    return dump_json(to_json_value(value))


def find_type(schema: Schema, name: str) -> DataType:
    try:
        return schema[name]
    except KeyError:
        hint = schema.suggest(name)
        extra = f" (did you mean: {', '.join(hint)}?)" if hint else " (see 'px4params types')"
        raise CommandError(f"unknown type '{name}'{extra}") from None


def _schema(args: argparse.Namespace) -> Schema:
    return load_schema(args.dsdl or ())


def _each_item(item: str, stdin: TextIO, out: TextIO, convert: Callable[[str], str]) -> int:
    """Converts one item, or each line of stdin when ``item`` is ``-`` (batch use).

    A batch prints exactly one line per input line, so that output line N answers input line
    N: the result, or ``error: <why>`` for a line that cannot be converted (also on stderr,
    with its line number; the exit status is then 1). A blank line is an item too: the empty
    payload for ``decode`` (a valid value of ``uavcan.protocol.param.Empty``, an empty
    ``ArrayCommand``, ...)."""
    if item != "-":
        _check_text(item)
        print(convert(item), file=out)
        return EXIT_OK
    status = EXIT_OK
    for number, line in _stdin_lines(stdin):
        try:
            _check_text(line)
            result = convert(line.rstrip("\r\n"))
        except (Px4ParamsError, UnicodeError) as e:
            print(f"error: {e}", file=out)
            print(f"px4params: <stdin>:{number}: {e}", file=sys.stderr)
            status = EXIT_FAILED
        else:
            print(result, file=out)
    return status


def _check_text(text: str) -> None:
    """Refuses (:class:`CommandError`) an argument or stdin line holding bytes that are not UTF-8
    (Python hands them over as surrogate escapes, which messages would show as '\\udcff')."""
    why = not_text_line(text)
    if why is not None:
        raise CommandError(why)


#: The longest line read from stdin (``frames``: the whole input): the JSON of the largest
#: value (65,535 bytes as a uint8 array) is about 260 KB. Beyond it, an endless input such as
#: ``< /dev/zero`` is refused instead of read until memory runs out.
MAX_STDIN_TEXT = 1 << 20


def _escaping(stdin: TextIO) -> TextIO:
    """``stdin`` reading bytes that are not UTF-8 as surrogate escapes, whatever the locale
    (strict, a read fails mid-batch), so that :func:`_check_text` names the line and byte."""
    reconfigure = getattr(stdin, "reconfigure", None)
    if reconfigure is not None:
        reconfigure(errors="surrogateescape")
    return stdin


def _stdin_lines(stdin: TextIO) -> Iterator[tuple[int, str]]:
    """``(number, line)`` of each line of ``stdin``, each at most :data:`MAX_STDIN_TEXT`."""
    _escaping(stdin)
    number = 0
    while True:
        line = stdin.readline(MAX_STDIN_TEXT + 1)
        if not line:
            return
        number += 1
        if len(line) > MAX_STDIN_TEXT:
            raise CommandError(f"<stdin>:{number}: {_too_long()}")
        yield number, line


def _too_long() -> str:
    return f"longer than {MAX_STDIN_TEXT:,} characters (an endless input?)"


def cmd_types(args: argparse.Namespace) -> int:
    schema = _schema(args)
    rows: list[dict[str, Any]] = []
    for key in schema:
        t = schema[key]
        rows.append(
            {
                "key": key,
                "name": t.name,
                "version": list(t.version) if t.version else None,
                "kind": "union" if t.type_def.is_union else "struct",
                "dialect": t.type_def.dialect,
                "min_bits": t.min_bits,
                "max_bits": t.max_bits,
                "max_instances": t.doc.max_instances,
                "short": t.doc.short,
            }
        )
    if args.json:
        import json

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
    schema = _schema(args)
    t = find_type(schema, args.type)

    def convert(text: str) -> str:
        value = parse_json(text)
        if args.defaults:
            from px4params.store.spec import with_defaults

            value = with_defaults(schema, t.key, value)
        try:
            return t.encode(value, tao=not args.no_tao, saturate=args.saturate).hex()
        except EncodeError as e:
            if str(e).endswith("missing field") and not args.defaults:
                # pydronecan and C structs make a missing field zero; we say how to fill it.
                raise EncodeError(
                    f"{e} (give every field, or use --defaults to fill the missing ones from the "
                    "type's defaults)"
                ) from None
            raise

    return _each_item(args.value, sys.stdin, sys.stdout, convert)


def cmd_decode(args: argparse.Namespace) -> int:
    t = find_type(_schema(args), args.type)

    def convert(text: str) -> str:
        value = t.decode(parse_hex(text), tao=not args.no_tao)
        written = value.get("p_version") if isinstance(value, dict) else None
        if t.version is not None and written is not None and written != t.version[1]:
            # Another minor version's layout read as this one's: encode refuses it back.
            print(
                f"px4params: warning: p_version {written}: the data was written by "
                f"{t.name}.{t.version[0]}.{written}, and is decoded with {t.key}'s layout",
                file=sys.stderr,
            )
        return value_json(value)

    return _each_item(args.hex, sys.stdin, sys.stdout, convert)


def cmd_frames(args: argparse.Namespace) -> int:
    from px4params.links import can_transfer  # only this command needs it

    t = find_type(_schema(args), args.type)
    half = can_transfer.service_half(t)
    if half is None and args.dest_node is not None:
        raise CommandError(f"{t.key} is a message; --dest-node is for service requests/responses")
    if half is not None and args.dest_node is None:
        raise CommandError(f"{t.key} is a service {half}; give --dest-node N (1..127)")
    if args.source_node == 0:
        raise CommandError("anonymous transfers (source node 0) are not supported; give 1..127")
    dtid = args.dtid if args.dtid is not None else t.dtid
    if dtid is None:
        raise CommandError(f"{t.key} has no default data type ID; give --dtid N")
    text = _escaping(sys.stdin).read(MAX_STDIN_TEXT + 1) if args.value == "-" else args.value
    if len(text) > MAX_STDIN_TEXT:
        raise CommandError(f"<stdin>: {_too_long()}")
    _check_text(text)
    try:
        out = can_transfer.frames(
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
        raise CommandError(str(e)) from None
    if args.json:
        import json

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
    print(f"{t.key}: {t.doc.short}")
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
            variant = next(iter(value_at(t.decode(data), union)))
            shown += f" ({variant})"
        elif (
            isinstance(value, int) and not isinstance(value, bool) and leaf.path.endswith("address")
        ):
            shown += f" ({value:#04x})"
        print(f"  [{leaf.index}] {leaf.path:<20} {leaf.type:<8} {shown}")
    print(f"decoded back: {value_json(t.decode(data))}")
    golden = schema_golden_vector()
    print(
        f"golden vector (0xBEDA:uint12, -1:int3, -5:int4, -1:int2, 0x88:uint4): {golden.hex(' ')}"
    )
    return EXIT_OK


def schema_golden_vector() -> bytes:
    """The DroneCAN reference vector, encoded through a throwaway schema of its five fields."""

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
    t = Schema(model)["golden.Vector"]
    return t.encode({"a": 0xBEDA, "b": -1, "c": -5, "d": -1, "e": 0x88})


def _add_types(p: ArgumentParser) -> None:
    p.description = "List every loaded type (bundled px types, DroneCAN standard types, --dsdl)."
    p.epilog = "example:\n  px4params types --json"
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_types)


def _add_encode(p: ArgumentParser) -> None:
    p.description = (
        "Encode a JSON value of TYPE; '-' reads one per line from stdin and prints one line "
        "per input line (the hex, or 'error: WHY')."
    )
    p.epilog = (
        "example:\n  px4params encode px.Ina238 "
        '\'{"bus": {"i2c": {"bus_id": 1, "address": 69}}, "current": 200, "shunt": 0.0003}\'\n'
        "  10031720ea0c"
    )
    _type_argument(p)
    p.add_argument("value", metavar="VALUE", help="a JSON value, or - for one per line on stdin")
    p.add_argument("--no-tao", action="store_true", help="no tail array optimization (CAN FD)")
    p.add_argument(
        "--defaults",
        action="store_true",
        help="fill the fields the value leaves out from the type's defaults (@default, else 0)",
    )
    p.add_argument(
        "--saturate",
        action="store_true",
        help="clamp out-of-range numbers of saturated fields (default: refuse them; "
        "truncated fields keep the low bits either way, as DSDL says)",
    )
    p.set_defaults(func=cmd_encode)


def _add_decode(p: ArgumentParser) -> None:
    p.description = (
        "Decode hex bytes of TYPE; '-' reads one per line from stdin and prints one line per "
        "input line (the JSON, or 'error: WHY'; a blank line is the empty payload)."
    )
    p.epilog = (
        "examples:\n  px4params decode px.Ina238 10031720ea0c\n"
        "  px4params decode px.Ina238 '10 03 17 20 ea 0c'\n"
        "  px4params decode uavcan.protocol.NodeStatus 39300000000700"
    )
    _type_argument(p)
    p.add_argument("hex", metavar="HEX", help="hex bytes, or - for one item per line on stdin")
    p.add_argument("--no-tao", action="store_true", help="no tail array optimization (CAN FD)")
    p.set_defaults(func=cmd_decode)


def _type_argument(p: ArgumentParser) -> None:
    p.add_argument(
        "type", metavar="TYPE", help="type name, e.g. px.Ina238 or uavcan.protocol.NodeStatus"
    )


def _add_frames(p: ArgumentParser) -> None:
    p.description = """\
Encode a JSON value of TYPE and print the CAN frames of one DroneCAN transfer
of it, one per line: the 29-bit CAN ID and the frame data (tail byte
included), both in hex. A multi-frame transfer starts with its CRC; on CAN FD
the payload has no tail array optimization and is padded to a valid frame
length. For a service half (TYPE ending in .Request or .Response) give
--dest-node."""
    p.epilog = """\
example:
  px4params frames uavcan.protocol.NodeStatus --source-node 10 --transfer-id 3 \\
    '{"uptime_sec": 5, "health": 0, "mode": 0, "sub_mode": 0, "vendor_specific_status_code": 0}'
  1f01550a 05000000000000c3"""
    p.add_argument(
        "type", metavar="TYPE", help="type name, e.g. uavcan.equipment.power.BatteryInfo"
    )
    p.add_argument("value", metavar="JSON", help="the value as JSON, or - to read it from stdin")
    p.add_argument(
        "--transfer-id", type=integer, default=0, metavar="N", help="transfer ID 0..31 (default 0)"
    )
    p.add_argument(
        "--source-node",
        type=integer,
        default=1,
        metavar="N",
        help="source node ID 1..127 (default 1)",
    )
    p.add_argument(
        "--dest-node", type=integer, metavar="N", help="destination node ID 1..127 (services only)"
    )
    p.add_argument(
        "--priority",
        type=integer,
        default=31,
        metavar="N",
        help="priority 0..31 (default 31, lowest)",
    )
    p.add_argument(
        "--dtid", type=integer, metavar="N", help="data type ID (default: the type's own)"
    )
    p.add_argument("--canfd", action="store_true", help="CAN FD frames (up to 64 bytes)")
    p.add_argument(
        "--saturate",
        action="store_true",
        help="clamp out-of-range numbers of saturated fields (default: refuse them; "
        "truncated fields keep the low bits either way, as DSDL says)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_frames)


def _add_demo(p: ArgumentParser) -> None:
    p.description = (
        "Encode the INA238#0 example of the PX4 Device Manifest talk, print its leaves "
        "[0]..[6] and bytes, decode it back."
    )
    p.epilog = "example:\n  px4params demo"
    p.set_defaults(func=cmd_demo)


_ADDERS: dict[str, Callable[[ArgumentParser], None]] = {
    "types": _add_types,
    "encode": _add_encode,
    "decode": _add_decode,
    "frames": _add_frames,
    "demo": _add_demo,
}


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers the codec command ``name`` on the main parser's subcommands."""
    p = sub.add_parser(name, help=summary, formatter_class=RawDescriptionHelpFormatter)
    dsdl_option(p)
    _ADDERS[name](p)
