"""``px4params metadata``: parameters.json for ground stations, a C header and the C ABI's
store tables for firmware (the work is in ``px4params.gcs``)."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.options import dsdl_option
from px4params.cli.parsing import ArgumentParser, RawDescriptionHelpFormatter
from px4params.dsdl.schema import load_schema
from px4params.status import EXIT_OK
from px4params.writing import check_outputs, write_file

if TYPE_CHECKING:
    import argparse


def cmd_metadata(args: argparse.Namespace) -> int:
    from px4params.gcs import cheader, metadata
    from px4params.store.spec import parameter_specs

    parser: ArgumentParser = args.metadata_parser
    if args.json is None and args.header is None and args.firmware is None:
        parser.error("give --json FILE, --header FILE, --firmware FILE.c, or several")
    if [args.json, args.header, args.firmware].count("-") > 1:
        parser.error("only one of --json, --header and --firmware can write to stdout (-)")
    if args.classic is not None and args.json is None:
        parser.error("--classic goes with --json (the header has no classic parameters)")
    # (The classic parameters' file as the command reads it: named, or from the environment.)
    classic = metadata.classic_source(args.classic)
    check_outputs([args.json, args.header, args.firmware], [classic])
    schema = load_schema(args.dsdl or ())
    specs = parameter_specs(schema)
    # Everything is generated before anything is written: a failure leaves no half output.
    outputs: list[tuple[str, str, str]] = []
    if args.json is not None:
        document = metadata.build_parameters_json(schema, classic, specs=specs)
        text = json.dumps(document, allow_nan=False) + "\n"
        counts = metadata.count_entries(document)
        outputs.append(
            (
                args.json,
                text,
                f"{counts['structured']} structured ({counts['destructured']} destructured names)"
                f" + {counts['classic']} classic parameters",
            )
        )
    if args.header is not None:
        guard = cheader.guard_from_filename(None if args.header == "-" else args.header)
        text = cheader.generate_header(schema, specs, guard=guard)
        outputs.append((args.header, text, f"C header for {len(specs)} parameters"))
    if args.firmware is not None:
        from px4params.gcs import firmware
        from px4params.store.store import Store

        defaults = Store(schema, classic=[])._type_defaults()
        header = "" if args.header in (None, "-") else os.path.basename(args.header)
        text = firmware.generate_tables(schema, specs, defaults, header)
        outputs.append((args.firmware, text, f"store tables for {len(specs)} parameters"))
    to_stdout = any(path == "-" for path, _, _ in outputs)
    for path, text, what in outputs:
        if path == "-":
            sys.stdout.write(text)
            continue
        write_file(path, text.encode(), keep_backup=False)
        if not to_stdout:  # stdout carries the other output, unmixed
            print(f"wrote {path}: {what}")
    return EXIT_OK


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params metadata``."""
    p = sub.add_parser(
        name,
        help=summary,
        formatter_class=RawDescriptionHelpFormatter,
        description="""\
Write the parameter metadata of every structured parameter (the px types with
@max_instances or @param):
  --json FILE    QGC's parameters.json (version 1) with each parameter's fields
                 in [k] order and every union variant, plus the classic
                 parameters of --classic FILE or $PX4PARAMS_PARAMETERS_JSON
  --header FILE  a C header: one struct per type, sizes, parameter ids and
                 instance counts, static inline encode/decode functions, and
                 for C++ the typed parameter ids of px4params.hpp
  --firmware FILE.c
                 the C ABI's store tables (crates/px4params-ffi): compiled
                 layouts, the parameters' plan and type defaults, so that
                 firmware needs no DSDL at run time
FILE '-' writes to stdout.""",
        epilog="""\
example:
  px4params metadata --json parameters.json --header px4_params.h
  wrote parameters.json: 37 structured (2421 destructured names) + 0 classic parameters
  wrote px4_params.h: C header for 37 parameters
  px4params metadata --header px4_params.h --firmware px4_param_tables.c
  wrote px4_params.h: C header for 37 parameters
  wrote px4_param_tables.c: store tables for 37 parameters""",
    )
    dsdl_option(p)
    p.add_argument("--json", metavar="FILE", help="write parameters.json here")
    p.add_argument("--header", metavar="FILE", help="write the C header here")
    p.add_argument("--firmware", metavar="FILE.c", help="write the C ABI's store tables here")
    p.add_argument(
        "--classic",
        metavar="FILE",
        help="a PX4 parameters.json whose classic parameters to include "
        "(default: $PX4PARAMS_PARAMETERS_JSON, else none)",
    )
    p.set_defaults(func=cmd_metadata, metadata_parser=p)
