"""``px4params param VERB ...``: NSH's ``param`` command on a store file (the verbs are in
``px4params.nsh.param``)."""

from __future__ import annotations

from collections.abc import Sequence

from px4params._records import TYPE_CHECKING
from px4params.cli.options import store_options
from px4params.cli.parsing import RawDescriptionHelpFormatter
from px4params.nsh.param import (
    add_verbs,
    verb_compare,
    verb_export,
    verb_find,
    verb_flat,
    verb_greater,
    verb_instances,
    verb_load,
    verb_show,
    verb_status,
)
from px4params.store.session import LockedSession, open_session

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    import argparse
    from typing import Any


#: Verbs that never write the store file: they take no lock (saves replace the file whole, so
#: a reader always reads a whole one), and leave no FILE.lock behind.
_READING_VERBS = (
    verb_compare,
    verb_export,
    verb_find,
    verb_flat,
    verb_greater,
    verb_instances,
    verb_show,
    verb_status,
)


def cmd_param(args: argparse.Namespace) -> int:
    recovering = args.verb is verb_load and args.file is not None
    if args.verb in _READING_VERBS:
        session = open_session(args.store, args.classic, args.dsdl or ())
        return int(args.verb(session, args))
    with LockedSession(
        args.store, args.classic, args.dsdl or (), start_empty_if_unreadable=recovering
    ) as session:
        return int(args.verb(session, args))


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params param`` and its verbs (with ``words``, the command line, only the
    verb it names is built in full)."""
    p = sub.add_parser(
        name,
        help=summary,
        description="PX4's param command over structured instances (INA238#0, INA238#0[4], "
        "INA238#0.bus.i2c.address) and classic parameters, on a store file.",
        epilog="examples:\n  px4params param add INA238#2\n"
        "  px4params param set-default INA238#2[4] 0x46\n"
        "  px4params param show -l INA238#2\n"
        "  px4params param compare INA238#0.current 200 && echo configured",
        formatter_class=RawDescriptionHelpFormatter,
    )
    store_options(p)
    verbs = p.add_subparsers(dest="verb_name", required=True, metavar="VERB")
    add_verbs(
        _VerbsWithStoreOptions(verbs),
        RawDescriptionHelpFormatter,
        only=_verb_in(words, name),
        cli=True,
    )
    p.set_defaults(func=cmd_param)


class _VerbsWithStoreOptions:
    """The verbs' subcommands, each also taking --store, --classic and --dsdl after the verb, as
    'run FILE --store S' does (airframe files' verbs, built by the same add_verbs, do not)."""

    def __init__(self, sub: Any) -> None:
        self._sub = sub

    def add_parser(self, name: str, **kwargs: Any) -> Any:
        parser = self._sub.add_parser(name, **kwargs)
        if kwargs.get("add_help", True):  # (not the stubs listed for a usage error)
            store_options(parser, after_verb=True)
        return parser


def _verb_in(words: Sequence[str], command: str) -> str | None:
    """The verb after ``command`` in ``words`` (skipping options and their values)."""
    rest = list(words[words.index(command) + 1 :]) if command in words else []
    while rest:
        word = rest.pop(0)
        if word in ("--store", "--classic", "--dsdl"):
            if rest:
                rest.pop(0)
        elif not word.startswith("-"):
            return word  # not a verb: every verb is a stub, and argparse names the choices
    return None
