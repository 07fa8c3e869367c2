"""QGroundControl's ``.params`` files: ``#`` comment lines, then one line per parameter,
``vehicle-id component-id name value type`` separated by TABs (as QGC writes them; spaces are
accepted too, as hand-edited files have them). ``type`` is a ``MAV_PARAM_TYPE``: 6 int32,
9 float32 (QGC writes floats with 18 decimals; so do we, but in full where 18 decimals would
round), the others as MAVLink numbers them.

A Mission Planner (``NAME,VALUE``) or MAVProxy (``NAME VALUE``) file given instead is named as
such in the error. This is the one reader of the format; the store's import, migration and the
page use it."""

from __future__ import annotations

import math
import struct
from typing import NamedTuple

from px4params.errors import NumberError, ParamFileError
from px4params.numbers import abbreviated, parse_float, parse_int

__all__ = [
    "FLOAT_TYPES",
    "INT32",
    "REAL32",
    "QgcRow",
    "autopilot_rows",
    "format_line",
    "other_ground_station_file",
    "read",
]

#: MAV_PARAM_TYPE of the two kinds PX4 has.
INT32, REAL32 = 6, 9
#: MAV_PARAM_TYPE values that hold floats (REAL32, REAL64).
FLOAT_TYPES = frozenset({9, 10})


class QgcRow(NamedTuple):
    """One parameter line: where it is, whose it is, and its value as its type says."""

    line: int
    vehicle: int
    component: int
    name: str
    value: int | float
    type: int


class Autopilot(NamedTuple):
    """The rows of a file that are its vehicle's autopilot's, and the other components'."""

    #: The autopilot's component ID: 1, else the lowest in the file.
    component: int
    rows: list[QgcRow]
    #: Every other component and how many rows it has, in ID order.
    others: list[tuple[int, int]]

    def skipped(self, where: str) -> list[str]:
        """A report line for each other component's rows, which are skipped."""
        return [
            f"{where}: component {component}: {count} parameters skipped (not the autopilot's, "
            f"component {self.component})"
            for component, count in self.others
        ]


def autopilot_rows(rows: list[QgcRow], where: str) -> Autopilot:
    """The rows of the one vehicle's autopilot (component 1, as PX4 numbers it, else the
    lowest): a QGC save of a vehicle also holds its other components' (a gimbal, a camera),
    which are not its parameters. A file of several vehicles is a :class:`ParamFileError`
    naming the first line of another one: a store, a migration, a review are one vehicle's."""
    vehicles = sorted({row.vehicle for row in rows})
    if len(vehicles) > 1:
        other = next(row for row in rows if row.vehicle != rows[0].vehicle)
        raise ParamFileError(
            f"{where}:{other.line}: vehicle {other.vehicle}: the file holds parameters of "
            f"vehicles {', '.join(map(str, vehicles))} (one vehicle's are read: split the file)"
        )
    components = sorted({row.component for row in rows})
    chosen = 1 if 1 in components or not components else components[0]
    counts = {c: sum(row.component == c for row in rows) for c in components if c != chosen}
    return Autopilot(chosen, [r for r in rows if r.component == chosen], list(counts.items()))


def read(text: str, where: str) -> list[QgcRow]:
    """Every parameter line of ``text`` (the file ``where``, for messages). A line that is not
    five fields, ids and a type that are not integers, or a value that is not a number of its
    type is a :class:`ParamFileError` naming the file, the line and the field."""
    rows: list[QgcRow] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        at = f"{where}:{number}"
        parts = [p.strip() for p in (line.split("\t") if "\t" in line else line.split())]
        if len(parts) != 5:
            expected = (
                "expected 5 TAB-separated columns (vehicle-id, component-id, name, value, type)"
            )
            other = _other_format(line)
            if other is not None:
                raise ParamFileError(f"{at}: {other}, not QGC's .params: {expected}")
            raise ParamFileError(f"{at}: {expected}, got {len(parts)}")
        vehicle, component, name, value, kind = parts
        try:
            ids = (parse_int(vehicle), parse_int(component), parse_int(kind))
        except ValueError:
            shown = ", ".join(f"'{abbreviated(t)}'" for t in (vehicle, component, kind))
            raise ParamFileError(
                f"{at}: {abbreviated(name)}: vehicle-id, component-id and type must be integers, "
                f"got {shown}"
            ) from None
        rows.append(QgcRow(number, ids[0], ids[1], name, _value(value, ids[2], at, name), ids[2]))
    return rows


def other_ground_station_file(text: str) -> tuple[int, str] | None:
    """The first parameter line of ``text`` and what it is when the file is Mission Planner's
    or MAVProxy's (see :func:`_other_format`), else None."""
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if line and not line.startswith("#"):
            found = _other_format(line) if "\t" not in line else None
            return (number, found) if found is not None else None
    return None


def _other_format(line: str) -> str | None:
    """What a two-column ``NAME,VALUE`` or ``NAME VALUE`` line is: the parameter files of
    Mission Planner (ArduPilot's ``.param``: ``NAME,VALUE``) and MAVProxy (``param save``:
    ``NAME VALUE``), which carry no ids and no type."""
    comma = [p.strip() for p in line.split(",")]
    if len(comma) == 2 and _looks_like(comma):
        return "a comma-separated NAME,VALUE line (Mission Planner's parameter file)"
    spaced = line.split()
    if len(spaced) == 2 and _looks_like(spaced):
        return "a NAME VALUE line (MAVProxy's parameter file)"
    return None


def _looks_like(pair: list[str]) -> bool:
    """A parameter name (letters, digits, ``_``) and a number."""
    name, value = pair
    if not name or not (name[0].isalpha() or name[0] == "_"):
        return False
    if not all(c.isascii() and (c.isalnum() or c == "_") for c in name):
        return False
    try:
        parse_float(value)
    except (ValueError, NumberError):
        return False
    return True


def _value(text: str, kind: int, at: str, name: str) -> int | float:
    try:
        number = parse_float(text)
        if kind not in FLOAT_TYPES and text.lstrip("+-").isdigit():
            return parse_int(text)
    except NumberError as e:
        raise ParamFileError(f"{at}: {name}: {e}") from None
    except ValueError:
        raise ParamFileError(f"{at}: {name}: value '{abbreviated(text)}' is not a number") from None
    if kind in FLOAT_TYPES:
        return number
    if not number.is_integer():
        raise ParamFileError(f"{at}: {name}: value {text!r} is not an integer (type {kind})")
    return int(number)


def _float32(value: float) -> float:
    """``value`` as a float32 holds it."""
    return float(struct.unpack("<f", struct.pack("<f", value))[0])


def format_line(vehicle: int, component: int, name: str, value: int | float, is_float: bool) -> str:
    """One line as QGC writes it: floats with 18 decimals, TAB-separated. A float32 that 18
    decimals do not keep (below 5e-19, or with digits past the 18th decimal) is written in
    full (``1.0000000031710769e-30``), which QGC reads as well: a value is never rounded away."""
    if is_float:
        text = f"{value:.18f}" if math.isfinite(value) else str(value)
        if math.isfinite(value) and _float32(float(text)) != _float32(value):
            text = repr(float(value))
        return f"{vehicle}\t{component}\t{name}\t{text}\t{REAL32}"
    return f"{vehicle}\t{component}\t{name}\t{int(value)}\t{INT32}"
