"""Reading today's configuration: a ULog flight log, a QGC ``.params`` file or a ``param set``
list, told apart by the content."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from px4params.errors import MigrationError, NumberError, ParamFileError, ULogError
from px4params.formats import qgc_params
from px4params.formats.ulog import MAGIC as ULOG_MAGIC
from px4params.numbers import abbreviated, parse_float, parse_int
from px4params.reading import PARAM_FILE, ULOG, open_file, read_text

if TYPE_CHECKING:
    import os

__all__ = ["OldConfig", "read_config"]

#: QGC's ``# Version: 1.13.0 beta`` header line (QGC writes the firmware version it read).
_QGC_VERSION = re.compile(r"#\s*Version:\s*v?(\d+)\.(\d+)\.(\d+)")
_QGC_HEADER = re.compile(r"#\s*(Stack|Vehicle|Version|Git Revision):\s*(.*\S)")
#: A line of an airframe-style parameter list.
#: The commands that start a `param set` list (an airframe file's shell).
_SHELL_WORDS = ("param", "if", "set", "echo", ".", "then", "else", "fi")
_PARAM_SET = re.compile(r"param\s+(set|set-default)\s+(\S+)\s+(\S+)\s*")


@dataclass
class OldConfig:
    """Today's parameters: name -> value (int or float), from ``source``."""

    source: str
    kind: str  # "ULog", "QGC .params" or "param set list"
    params: dict[str, int | float]
    #: Where the values came from, e.g. hardware and firmware of a log.
    details: list[str] = field(default_factory=list)
    #: Lines of the input that were not used (e.g. other components of a .params file).
    skipped: list[str] = field(default_factory=list)
    #: The firmware release of a log (ULog ``ver_sw_release``); None when it has none.
    release: int | None = None
    #: The firmware version (major, minor, patch) the file names: a log's release, a QGC
    #: file's ``# Version`` line; None when it names none.
    version: tuple[int, int, int] | None = None
    #: The board of a log (ULog ``ver_hw``, e.g. ``PX4_FMU_V6C``); None for parameter files.
    hardware: str | None = None
    #: The hardware type of a log (ULog ``ver_hw_subtype``, e.g. ``V30``, what ``ver hwtypecmp``
    #: compares); None where the log has none, and for parameter files.
    hw_type: str | None = None
    #: The log's boot console (``boot_console_output``), when it has one.
    console: str | None = None
    #: ``(topic, multi_id, device_id)`` of the sensors that published in the log.
    published: list[tuple[str, int, int]] = field(default_factory=list)
    #: The log is cut short or damaged: what was logged after the break is missing.
    cut: bool = False


def read_config(path: str | os.PathLike[str]) -> OldConfig:
    """Reads a ULog's parameters (their last values in the log), a QGC ``.params`` file, or a
    ``param set`` list; told apart by the content, not the name."""
    from px4params.formats.ulog import read_device_ids, read_header

    where = str(path)
    try:
        with open_file(where, ULOG) as f:
            head = f.read(len(ULOG_MAGIC))
    except OSError as e:
        raise MigrationError(f"{where}: cannot read: {e.strerror}") from None
    if head != ULOG_MAGIC:
        return _read_text(where)
    try:
        log = read_header(where)
        published = read_device_ids(where)
    except ULogError as e:
        raise MigrationError(str(e)) from None
    params = log.parameters
    if not params:
        raise MigrationError(f"{where}: the log has no parameters")
    details = [
        f"{key} {log.info[key]}" for key in ("ver_hw", "ver_sw_branch", "ver_sw") if key in log.info
    ]
    if log.release:
        details.insert(1 if "ver_hw" in log.info else 0, _release_detail(log.release))
    if log.corrupt:
        details.append(
            "the log is cut short or damaged: parameters and devices logged after the break "
            "are missing"
        )
    changed = {name for _, name, _ in log.changed_parameters}
    if changed:
        details.append(f"last values of {len(changed)} parameters changed during the log")
    release = log.release
    version = (release >> 24 & 0xFF, release >> 16 & 0xFF, release >> 8 & 0xFF) if release else None
    return OldConfig(
        where, "ULog", params, details, release=release, version=version,
        hardware=log.hardware, hw_type=_text_info(log.info.get("ver_hw_subtype")),
        console=log.boot_console, published=published, cut=log.corrupt,
    )  # fmt: skip


#: The last byte of ``ver_sw_release``: PX4's firmware type (px4_version.h's
#: ``FIRMWARE_TYPE_*``: 0 dev, 64 alpha, 128 beta, 192 release candidate, 255 release).
FIRMWARE_TYPES = {0: "dev", 64: "alpha", 128: "beta", 192: "rc"}


def _release_detail(release: int) -> str:
    """``ver_sw_release 0x01110040: PX4 1.17.0 alpha`` (a release shows no type)."""
    kind = release & 0xFF
    word = "" if kind == 255 else f" {FIRMWARE_TYPES.get(kind, f'type {kind}')}"
    version = f"{release >> 24 & 0xFF}.{release >> 16 & 0xFF}.{release >> 8 & 0xFF}"
    return f"ver_sw_release 0x{release:08X}: PX4 {version}{word}"


def _text_info(value: object) -> str | None:
    """A ULog information string (``ver_hw_subtype``); None where absent or empty."""
    return value if isinstance(value, str) and value else None


def _read_text(where: str) -> OldConfig:
    try:
        text = read_text(where, PARAM_FILE)
    except OSError as e:
        raise MigrationError(f"{where}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError as e:  # (a Latin-1 byte in a comment: its line is named)
        at = e.object[: e.start].count(b"\n") + 1
        raise MigrationError(
            f"{where}:{at}: neither a ULog file nor a QGC .params text file (byte "
            f"0x{e.object[e.start]:02X} is not UTF-8)"
        ) from None
    first = next(
        (
            line.strip()
            for line in text.splitlines()
            if line.strip() and not line.lstrip().startswith("#")
        ),
        "",
    )
    # Shell (an airframe file, `param set` lines, maybe inside an `if`) starts with one of its
    # commands; anything else is read as QGC's, which names other stations' files.
    if first.split(" ", 1)[0] in _SHELL_WORDS:
        return _read_param_list(text, where)
    try:
        read = qgc_params.read(text, where)
        autopilot = qgc_params.autopilot_rows(read, where)
    except ParamFileError as e:
        raise MigrationError(str(e)) from None
    if not read:
        raise MigrationError(f"{where}: no parameters (not a QGC .params file?)")
    chosen = autopilot.component
    params: dict[str, int | float] = {}
    first_line: dict[str, int] = {}
    twice: list[str] = []
    for r in autopilot.rows:
        if r.name in first_line and params[r.name] != r.value:
            # QGC writes each once: which one did the vehicle hold?
            raise MigrationError(
                f"{where}:{r.line}: {r.name}: also set on line {first_line[r.name]}, to "
                f"{shown_value(params[r.name])}"
            )
        if r.name in first_line:  # (two files joined: the same value twice says one thing)
            twice.append(f"line {r.line}: {r.name} again, as on line {first_line[r.name]}")
            continue
        first_line[r.name] = r.line
        params[r.name] = r.value
    skipped = [
        f"component {c}: {count} parameters (not the autopilot's)" for c, count in autopilot.others
    ] + twice
    details = [f"component {chosen}"]
    version = None
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.startswith("#"):
            break
        h = _QGC_HEADER.match(line.strip())
        if h and h[1] == "Stack" and not h[2].upper().startswith("PX4"):
            # QGC names the autopilot's firmware here ("PX4", "PX4 Pro", "ArduPilot"): another
            # stack's parameters, device IDs and version number mean nothing to PX4.
            raise MigrationError(
                f"{where}:{number}: '# Stack: {abbreviated(h[2])}': not a PX4 parameter file "
                "(QGC writes 'PX4' or 'PX4 Pro' there for PX4's)"
            )
        m = _QGC_VERSION.match(line.strip())
        if m:
            version = (int(m[1]), int(m[2]), int(m[3]))
        if h:
            details.append(f"{h[1]}: {h[2]}")
    return OldConfig(where, "QGC .params", params, details, skipped, version=version)


def shown_value(value: object) -> str:
    """A parameter's value in a report line: a float to 9 significant digits (a float32's)."""
    if isinstance(value, float):
        return f"{value:.9g}"
    return str(value)


def _number(value: str, where: str) -> int | float:
    """A ``param set`` line's value: an integer stays one (PX4's INT32), the rest are floats."""
    try:
        return parse_int(value) if re.fullmatch(r"[+-]?\d+", value) else parse_float(value)
    except (NumberError, ValueError):
        raise MigrationError(f"{where}: value '{abbreviated(value)}' is not a number") from None


#: How many lines a ``param set`` list's report names one by one (then it counts the rest).
SHOWN_LINES = 10


def _read_param_list(text: str, where: str) -> OldConfig:
    """``param set NAME VALUE`` / ``param set-default NAME VALUE`` lines (an airframe file's
    syntax; several on a line joined by ``;``); other shell commands are not run, each named
    with its line in the report, and ``param set`` lines inside ``if ... fi`` are read as if
    every condition held, which the report says."""
    params: dict[str, int | float] = {}
    set_on: dict[str, int] = {}
    overridden: list[str] = []
    other: list[str] = []
    conditional: list[int] = []
    depth = 0  # of the `if`s around
    for number, raw in enumerate(text.splitlines(), start=1):
        line = re.sub(r"(^|\s)#.*$", "", raw).strip()  # the shell's comments
        for command in filter(None, (c.strip() for c in line.split(";"))):
            word, _, rest = command.partition(" ")
            if word in ("then", "else"):  # (`then param set ...` runs what follows)
                command = rest.strip()
                word = command.partition(" ")[0]
            m = _PARAM_SET.fullmatch(command)
            if word == "if":
                depth += 1
            elif word == "fi":
                depth = max(depth - 1, 0)
            elif m is not None:
                if depth:
                    conditional.append(number)
                value = _number(m[3], f"{where}:{number}: {m[2]}")
                if m[2] in params and params[m[2]] != value:
                    # the shell runs both: the last holds, and the first is said
                    before = shown_value(params[m[2]])
                    overridden.append(
                        f"line {set_on[m[2]]}: {m[2]} {before}: set again on line {number} "
                        f"({shown_value(value)}), which holds"
                    )
                params[m[2]], set_on[m[2]] = value, number
            elif command:
                other.append(f"line {number}: '{abbreviated(command)}'")
    if not params:
        raise MigrationError(f"{where}: no 'param set' lines")
    skipped = [f"{line}: not a 'param set NAME VALUE' command, not read" for line in other]
    if len(skipped) > SHOWN_LINES:
        more = len(skipped) - SHOWN_LINES
        skipped = [*skipped[:SHOWN_LINES], f"... and {more} more lines of other commands"]
    skipped += overridden
    details = []
    if conditional:
        numbers = list(dict.fromkeys(conditional))
        lines = ", ".join(map(str, numbers))
        details.append(
            f"'param set' inside if ... fi (line{'s' if len(numbers) > 1 else ''} {lines}): "
            "read as if every condition held"
        )
    return OldConfig(where, "param set list", params, details, skipped)
