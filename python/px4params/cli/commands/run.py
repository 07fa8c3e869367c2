"""``px4params run FILE``: an airframe file of ``param`` lines on the store, all or nothing
(the interpreter is ``px4params.nsh.airframe``)."""

from __future__ import annotations

import io
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.options import store_options
from px4params.cli.parsing import RawDescriptionHelpFormatter
from px4params.nsh import airframe
from px4params.status import EXIT_FAILED, EXIT_OK
from px4params.store.session import LockedSession

if TYPE_CHECKING:
    import argparse

_DESCRIPTION = """\
Run a file of param lines as PX4's startup and airframe scripts have them:
  param VERB ...        any verb of 'px4params param' (the talk's lines verbatim)
  set VAR value         and $VAR or ${VAR} in later lines
  if param compare|greater ... / then / else / fi   (nestable)
  echo ...              comments (#) and blank lines
A failing line is reported as FILE:LINE: message and stops the run; nothing of
the file is kept (the store is written once, when every line succeeded). With
--keep-going every failing line is reported, the lines that succeeded are kept
and saved, and the run still fails."""


def cmd_run(args: argparse.Namespace) -> int:
    with LockedSession(args.store, args.classic, args.dsdl or ()) as session:
        session.inputs.append(args.file)  # a `param save` of the file itself is refused
        out = session.out
        if not args.keep_going:
            # All or nothing, what the lines print too: a failed run shows only its error.
            session.out = io.StringIO()
        result = airframe.run_file(args.file, session, keep_going=args.keep_going, err=sys.stderr)
    if isinstance(session.out, io.StringIO) and not result.errors:
        out.write(session.out.getvalue())
    return EXIT_FAILED if result.errors else EXIT_OK


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params run``."""
    p = sub.add_parser(
        name,
        help=summary,
        description=_DESCRIPTION,
        epilog="example:\n  px4params examples   # the example files, into ./examples\n"
        "  px4params run examples/two_batteries.airframe --store vehicle.store",
        formatter_class=RawDescriptionHelpFormatter,
    )
    p.add_argument("file", metavar="FILE", help="airframe or startup file")
    p.add_argument(
        "--keep-going",
        action="store_true",
        help="report every failing line and keep what succeeded",
    )
    store_options(p)
    p.set_defaults(func=cmd_run)
