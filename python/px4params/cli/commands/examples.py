"""``px4params examples [DIR]``: copy the bundled example files (``px4params.data``'s
``examples/``) out of the package, so that the docs' commands run wherever it is installed."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from px4params.cli.parsing import RawDescriptionHelpFormatter
from px4params.data import EXAMPLES_DIR
from px4params.errors import CommandError
from px4params.status import EXIT_OK

if TYPE_CHECKING:
    import argparse

#: Where the docs and --help examples expect the files: ``examples/two_batteries.airframe``.
DEFAULT_DIR = "examples"

_DESCRIPTION = """\
Copy the example files into DIR (default ./examples, created if missing):
  two_batteries.airframe           a manifest: two INA238 power monitors, a GPS compass
  two_batteries.bench.toml         a bench where all three are present and healthy
  two_batteries_faults.bench.toml  a bench with a lost monitor, a slow compass, a noisy bus
  two_batteries.params             the same vehicle configured today (QGC export), to migrate
A file already in DIR with the same content is left alone; one that differs is
never overwritten: nothing is copied and the command fails."""

_EPILOG = """\
example:
  px4params examples
  px4params run examples/two_batteries.airframe --store vehicle.store"""


def bundled_examples() -> list[str]:
    """The names of the example files the package ships, sorted."""
    return sorted(
        e.name
        for e in os.scandir(EXAMPLES_DIR)
        if e.is_file() and not e.name.startswith((".", "_"))
    )


def _read(path: str) -> bytes:
    with open(path, "rb") as f:
        return f.read()


def copy_examples(folder: str) -> tuple[list[str], list[str]]:
    """Copies the examples into ``folder``: (the paths written, the paths already there with
    the same content). A path that exists with other content, or a ``folder`` that is not a
    folder, is a :class:`CommandError` before anything is written."""
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise CommandError(f"{folder}: exists and is not a folder")
    if os.path.islink(folder) and not os.path.exists(folder):
        # makedirs would say "File exists" of a link to a folder that does not.
        raise CommandError(
            f"{folder}: a symbolic link to {os.readlink(folder)}, which does not exist "
            "(create that folder or choose another DIR)"
        )
    missing: list[str] = []
    present: list[str] = []
    for name in bundled_examples():
        target = os.path.join(folder, name)
        if not os.path.lexists(target):
            missing.append(name)
            continue
        try:
            same = os.path.isfile(target) and _read(target) == _read(
                os.path.join(EXAMPLES_DIR, name)
            )
        except OSError as e:
            raise CommandError(f"{target}: cannot read: {e.strerror}") from None
        if not same:
            raise CommandError(
                f"{target} exists and differs from the bundled example: nothing copied "
                "(move it away or choose another DIR)"
            )
        present.append(target)
    written: list[str] = []
    try:
        os.makedirs(folder, exist_ok=True)
        for name in missing:
            target = os.path.join(folder, name)
            # "x": a file that appeared since the check above is not overwritten either
            with open(target, "xb") as f:
                f.write(_read(os.path.join(EXAMPLES_DIR, name)))
            written.append(target)
    except OSError as e:
        raise CommandError(f"{e.filename or folder}: cannot write: {e.strerror}") from None
    return written, present


def cmd_examples(args: argparse.Namespace) -> int:
    written, present = copy_examples(args.dir)
    for path in written:
        print(f"wrote {path}")
    if present:
        print(f"{len(present)} already there with the same content: {', '.join(present)}")
    return EXIT_OK


def add_parser(sub: Any, name: str, summary: str, words: Sequence[str] = ()) -> None:
    """Registers ``px4params examples``."""
    p = sub.add_parser(
        name,
        help=summary,
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "dir",
        metavar="DIR",
        nargs="?",
        default=DEFAULT_DIR,
        help=f"folder to copy them into (default: {DEFAULT_DIR})",
    )
    p.set_defaults(func=cmd_examples)
