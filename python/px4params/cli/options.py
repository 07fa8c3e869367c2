"""Options several commands share."""

from __future__ import annotations

import math
from collections.abc import Callable

from px4params.cli.parsing import SUPPRESS, ArgumentParser, type_error


def identifier(what: str, high: int) -> Callable[[str], int]:
    """An argparse type: a decimal ID 1..``high`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        # (digits counted first: Python will not convert thousands of them)
        if not text.isdigit() or len(text) > 5 or not 1 <= int(text) <= high:
            raise type_error(f"'{text[:20]}' is not a {what} (expected 1..{high})")
        return int(text)

    return parse


def integer(text: str) -> int:
    """An argparse type: an integer, decimal or ``0x`` hexadecimal, as parameter values are."""
    try:
        return int(text.strip(), 0)
    except ValueError:  # (Python will not convert thousands of digits either)
        raise type_error(f"'{text[:20]}' is not an integer (decimal, or 0x hexadecimal)") from None


#: The longest simulated bench boot: a day (a boot settles within seconds; simulated time is
#: cheap, 600 s take 0.3 s, but not free).
MAX_SIMULATED_SECONDS = 24 * 3600.0


def seconds(high: float) -> Callable[[str], float]:
    """An argparse type: a duration in seconds, more than 0 and at most ``high``. NaN, the
    infinities and negative numbers are refused as the command line is read (a server would
    otherwise start and fail every time it used the duration)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not 0 < value <= high:  # (False for NaN)
            raise type_error(
                f"expected seconds more than 0 and at most {high:g}, not '{text[:20]}'"
            )
        return value

    return parse


def dsdl_option(p: ArgumentParser) -> None:
    """``--dsdl DIR``: the extra DSDL roots every schema-loading command takes."""
    p.add_argument(
        "--dsdl",
        action="append",
        metavar="DIR",
        help="extra DSDL root namespace folder (repeatable; also $PX4PARAMS_DSDL_PATH)",
    )


def file_name(text: str) -> str:
    """A file option's value: a name (an empty one, from an unset shell variable, would have
    meant the default file without a word)."""
    if not text:
        raise type_error("an empty name is no file")
    return text


def store_name(text: str) -> str:
    """``--store``'s value: a file name, not ``-`` (standard input or output elsewhere): a
    store is locked, read and replaced in place."""
    if text == "-":
        raise type_error("'-' is no store file here (a store is locked and replaced: name a file)")
    return file_name(text)


def store_options(p: ArgumentParser, *, after_verb: bool = False) -> None:
    """``--store``, ``--classic`` and ``--dsdl``. ``after_verb``: on a verb of a command that
    takes them before its verbs too (``param --store S show`` and ``param show --store S``):
    given after the verb they win, and absent they leave the command's own (no default)."""
    from px4params.store.classic import CLASSIC_ENV  # (here: decode reads no store)

    unset = {"default": SUPPRESS} if after_verb else {}
    p.add_argument(
        "--store",
        type=store_name,
        metavar="FILE",
        help="store file (default: $PX4PARAMS_STORE, else ./px4params.store)",
        **unset,
    )
    p.add_argument(
        "--classic",
        type=file_name,
        metavar="JSON",
        help="PX4 parameters.json with the classic parameters "
        f"(default: ${CLASSIC_ENV}, else a bundled minimal set)",
        **unset,
    )
    p.add_argument(
        "--dsdl",
        action="append",
        metavar="DIR",
        help="extra DSDL root namespace folder (repeatable)",
        **unset,
    )


def bench_options(p: ArgumentParser, reported: str) -> None:
    """``--bench FILE.toml`` and ``--bench-duration S`` of the servers; ``reported`` says how
    they report the devices' health."""
    p.add_argument(
        "--bench",
        metavar="FILE.toml",
        help=f"boot the manifest on this simulated bench and report {reported}",
    )
    p.add_argument(
        "--bench-duration",
        type=seconds(MAX_SIMULATED_SECONDS),
        default=10.0,
        metavar="S",
        help="simulated seconds of each bench boot (default 10)",
    )
