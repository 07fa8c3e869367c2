"""The ``px4params`` command: parse the command line, import the one command it names, run it.

Exit codes are in ``status.py``. Every error a command raises on purpose
(:class:`px4params.errors.Px4ParamsError`) is one line on stderr, never a traceback.
"""

from __future__ import annotations

import errno
import os
import sys
from collections.abc import Sequence

from px4params._records import TYPE_CHECKING
from px4params.cli.parsing import SUPPRESS, ArgumentParser
from px4params.errors import Px4ParamsError
from px4params.status import EXIT_BROKEN_PIPE, EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK

if TYPE_CHECKING:
    import argparse

#: Every command, in the order ``--help`` lists them: its module in ``px4params.cli.commands``
#: (imported only when the command runs) and its one-line summary.
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("codec", "encode the talk's INA238 example and show its leaves"),
    "types": ("codec", "list the loaded types"),
    "encode": ("codec", "encode a value of TYPE"),
    "decode": ("codec", "decode a value of TYPE"),
    "frames": ("codec", "split a value of TYPE into DroneCAN CAN frames"),
    "param": ("param", "PX4's param command over structured instances and classic parameters"),
    "run": ("run", "run an airframe file of param lines (all or nothing)"),
    "autostart": (
        "autostart",
        "driver autostart from the manifest: startup script, plan, simulated bench run",
    ),
    "health": ("health", "the per-device story of a flight log from 'autostart run --ulog'"),
    "devid": ("devid", "decode, encode or list PX4 device IDs (CAL_MAG0_ID, ...)"),
    "migrate": (
        "migrate",
        "propose a device manifest (airframe file) from a .params file or a ULog",
    ),
    "metadata": (
        "metadata",
        "write parameters.json for ground stations and a C header for firmware",
    ),
    "mavlink": ("mavlink", "serve the store's parameters over MAVLink (UDP)"),
    "dronecan": (
        "dronecan",
        "serve the store's parameters as a DroneCAN node over SLCAN, or reach a remote node's",
    ),
    "gui": ("gui", "a ground-station page for the manifest, over MAVLink or a store file"),
    "examples": ("examples", "copy the example airframe, benches and .params file into a folder"),
    "completion": ("completion", "shell completion script (bash), or the names it completes"),
}

_DESCRIPTION = """\
Structured, instanced PX4 parameters: a device manifest in the vehicle's
parameters, stored bit-packed with the DroneCAN rules, from which drivers
autostart and arming is checked."""


def version_lines() -> list[str]:
    """What ``px4params --version`` prints: the package, the compiled core it runs on (a wheel
    pairs them; a stale extension in a checkout would not) and the bundled DSDL set, as a type
    count and a digest of its files (two installs with one digest have the same types)."""
    import hashlib

    from px4params import __version__
    from px4params.dsdl.roots import collect_roots
    from px4params.dsdl.schema import core_version
    from px4params.reading import DSDL, read_bytes

    lines = [f"px4params {__version__}"]
    core, store_format = core_version()
    lines.append(f"core {core} (Rust, px4params-core; store file format {store_format})")
    for root in collect_roots([], include_dronecan=False):
        digest = hashlib.sha256()
        for path in root.files:
            digest.update(os.path.relpath(path, root.path).replace(os.sep, "/").encode() + b"\0")
            digest.update(read_bytes(path, DSDL) + b"\0")
        name = os.path.basename(root.path)
        count = len(root.files)
        lines.append(f"DSDL {name}: {count} types (bundled), sha256 {digest.hexdigest()[:16]}")
    return lines


def declare(only: str | None = None, words: Sequence[str] = ()) -> ArgumentParser:
    """The command line's grammar (see ``parsing.py``): the whole of it, or with ``only`` that
    one command's (the others appear in ``--help`` by name and summary, without importing their
    modules). ``words``, the command line, lets a command declare only the part it runs
    (``param show``)."""
    parser = ArgumentParser(
        prog="px4params",
        description=_DESCRIPTION,
        epilog="'px4params COMMAND --help' shows a command's options and examples.",
    )
    parser.add_argument(
        "--version",
        action="store_true",
        default=SUPPRESS,  # main() answers it before parsing: no attribute in the namespace
        help="print the versions of the package, its compiled core and its DSDL types, and exit",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (module_name, summary) in COMMANDS.items():
        if only is None or name == only:
            module = __import__(f"px4params.cli.commands.{module_name}", fromlist=["add_parser"])
            module.add_parser(sub, name, summary, words)
        elif only not in COMMANDS:  # listed by name for --help and usage errors
            sub.add_parser(name, help=summary, add_help=False)
    return parser


def build_parser(only: str | None = None, words: Sequence[str] = ()) -> argparse.ArgumentParser:
    """argparse's parser of :func:`declare`'s grammar."""
    return declare(only, words).argparse()


def _command_in(argv: Sequence[str]) -> str | None:
    """The command ``argv`` names (its first word that is not an option), if it is one."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def _escaped(text: str) -> str:
    """``text`` with a file name's bytes that are not UTF-8 (held as surrogate escapes) shown
    as ``\\xfe``, and any other lone surrogate as ``\\ud800``."""
    try:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate no file name holds (from JSON text, say)
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def main(argv: Sequence[str] | None = None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    saved_before = len(_saved_stores())  # (main may run more than once in a process: tests)
    try:
        status = _run(words)
        # Written now, so that a full disk is this command's error (not a traceback of the
        # interpreter's flush at exit).
        sys.stdout.flush()
        return status
    except (Px4ParamsError, UnicodeError) as e:
        print(f"px4params: error: {_escaped(str(e))}", file=sys.stderr)
        return EXIT_FAILED
    except BrokenPipeError:  # the reader is gone: nobody to tell
        _drop_output()
        return EXIT_BROKEN_PIPE
    except OSError as e:
        if e.filename is not None or e.errno not in _OUTPUT_ERRNOS:
            raise
        _drop_output()
        kept = list(dict.fromkeys(_saved_stores()[saved_before:]))
        said = f" (the change was saved all the same, to {', '.join(kept)})" if kept else ""
        print(f"px4params: error: cannot write the output: {e.strerror}{said}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED


def _saved_stores() -> list[str]:
    """The store files this command saved (none where it never opened a store)."""
    session = sys.modules.get("px4params.store.session")
    return list(getattr(session, "SAVED", ()))


def _run(words: list[str]) -> int:
    """The command ``words`` ask for, its exit status; ``--version`` and ``--help`` print and
    end (their output's errors are reported as every command's)."""
    if words[:1] == ["--version"]:  # (as argparse's version action: it ends the parse)
        print("\n".join(version_lines()))
        return EXIT_OK
    command = _command_in(words)
    # Without a command there is nothing to run: the parser reports usage or prints --help.
    parser = declare(only=command or "", words=words)
    try:
        args = parser.parse_args(words)
    except SystemExit as e:
        if e.code not in (0, None):  # a usage error: usage and the error on stderr
            raise
        return EXIT_OK  # --help printed
    return int(args.func(args))


#: Errors of writing the output (``> /dev/full``, a full disk or quota, a file size limit, a
#: failing device): file errors of commands carry their file's name, these do not.
_OUTPUT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


def _drop_output() -> None:
    """Points standard output at ``/dev/null``, so that what is still buffered does not fail
    again when the interpreter flushes it at exit."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # not a file (a test's StringIO), or closed
        pass
