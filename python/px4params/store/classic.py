"""Classic PX4 parameters: flat ``int32`` / ``float`` values described by a ``parameters.json``.

The file is QGC's component metadata as a PX4 build writes it (``{"version": 1, "parameters":
[...]}``, each entry with at least ``name``, ``type`` ``Int32`` or ``Float`` and ``default``).
Entries are kept whole, so that metadata written back out loses nothing.
"""

from __future__ import annotations

import math
import os
import struct
import time
from collections.abc import Mapping
from types import MappingProxyType

from px4params._records import TYPE_CHECKING
from px4params.cache_file import (
    INTERPRETER,
    cache_path,
    default_cache_dir,
    discard,
    file_stamp,
    is_racy,
    read_cached,
    write_cached,
)
from px4params.data import CLASSIC_PARAMETERS_JSON
from px4params.errors import ClassicParamsError
from px4params.reading import CLASSIC_JSON, not_text, read_text

_NAME_START = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZ")
_NAME_REST = _NAME_START | frozenset("0123456789_")

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, NamedTuple, NoReturn
else:
    from px4params._records import NamedTuple

__all__ = [
    "BUNDLED_CLASSIC",
    "CLASSIC_ENV",
    "ClassicParam",
    "ClassicParamsError",
    "classic_value",
    "exact_in_type",
    "float32_holds",
    "load_classic",
    "rounding_said",
]

#: Environment variable naming the ``parameters.json`` whose classic parameters the store holds.
CLASSIC_ENV = "PX4PARAMS_PARAMETERS_JSON"
#: The classic parameters used when none are named: the few that airframes next to a device
#: manifest and the migration from today's configuration need (``data/classic_parameters.json``).
BUNDLED_CLASSIC = CLASSIC_PARAMETERS_JSON

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
_TYPES = ("Int32", "Float")


class ClassicParam(NamedTuple):
    """One classic parameter."""

    name: str
    #: ``Int32`` or ``Float``, as in parameters.json.
    type: str
    default: int | float
    #: The whole parameters.json entry.
    entry: Mapping[str, Any] = MappingProxyType({})

    @property
    def is_float(self) -> bool:
        return self.type == "Float"

    def __repr__(self) -> str:  # without the entry, which can be long
        return f"ClassicParam(name={self.name!r}, type={self.type!r}, default={self.default!r})"


def exact_in_type(value: int | float, is_float: bool) -> int | float | None:
    """``value`` as a classic parameter of the other type holds it, where no digit is lost: an
    integer a float32 holds exactly (every one up to 2**24, and 33554432, ... above) as a
    float, a whole float in int32's range as an integer; else None. Each way takes what the
    other gives, so a value carried there and back is the same. (A parameter whose type
    changed between PX4 releases: RC10_REV, COM_DISARM_LAND.)"""
    if is_float:
        return float(value) if float32_holds(value) else None
    whole = math.isfinite(value) and float(value).is_integer()
    return int(value) if whole and INT32_MIN <= value <= INT32_MAX else None


def float32_holds(value: int | float) -> bool:
    """Whether a float32 holds ``value`` exactly (2**24 + 1 it rounds to 2**24)."""
    try:
        return bool(struct.unpack("<f", struct.pack("<f", value))[0] == value)
    except (OverflowError, struct.error):
        return False


def rounding_said(param: ClassicParam, value: object) -> str | None:
    """What a Float parameter set to a whole number a float32 does not hold stores instead
    (``16777217 is stored as 16777216``); None where it stores the number itself."""
    whole = type(value) is int or (type(value) is float and value.is_integer())
    if not param.is_float or not whole or float32_holds(value):  # type: ignore[arg-type]
        return None
    try:
        stored = int(struct.unpack("<f", struct.pack("<f", value))[0])
    except (OverflowError, struct.error):
        return None  # (refused as out of range where it is set)
    return (
        f"{param.name}: {int(value)} is stored as {stored} (a Float holds whole numbers "  # type: ignore[call-overload]
        "exactly only up to 2**24)"
    )


def load_classic(path: str | os.PathLike[str]) -> list[ClassicParam]:
    """The classic parameters of a ``parameters.json``, in file order (checked once per version
    of the file: later calls read them from a :mod:`px4params.cache_file`)."""
    where = os.fspath(path)
    key = _cache_key(where)
    cache = cache_path(default_cache_dir(), "classic", key) if key else ""
    cached = read_cached(cache, key) if key else None
    if cached is not None:
        if isinstance(cached, list) and all(map(_is_cached_row, cached)):
            return [ClassicParam(*row) for row in cached]
        discard(cache, "not a list of classic parameters")
    params = _parse_classic(where)
    if key:
        write_cached(cache, key, [(p.name, p.type, p.default, dict(p.entry)) for p in params])
    return params


def _is_cached_row(row: Any) -> bool:
    """Whether a cached row is ``(name, type, default, entry)`` as :func:`load_classic` wrote."""
    return (
        isinstance(row, list | tuple)
        and len(row) == 4
        and isinstance(row[0], str)
        and row[1] in _TYPES
        and isinstance(row[2], int | float)
        and isinstance(row[3], dict)
    )


def _cache_key(where: str) -> str | None:
    """What the cached parameters of ``where`` are valid for: its real path and stamp (inode,
    size, times: :func:`px4params.cache_file.file_stamp`); None for a file changed within the
    time stamps' resolution (parsed every time)."""
    try:
        real = os.path.realpath(where)
        st = os.stat(real)
        code = os.stat(__file__)  # the checks below decide what is cached
    except (OSError, ValueError):
        return None  # reported by the parse
    if is_racy(st, time.time()):
        return None
    return f"px4params-classic {INTERPRETER} {__file__} {file_stamp(code)}\n{real} {file_stamp(st)}"


def _parse_classic(where: str) -> list[ClassicParam]:
    import json  # only on a cache miss: json costs a command 2 ms to import

    def constant(token: str) -> NoReturn:
        # Python's json takes NaN and Infinity, which JSON has not (and json.dumps then refuses)
        raise ClassicParamsError(f"{where}: not JSON: {token} is not a JSON number")

    def finite(number: str) -> float:
        value = float(number)
        if not math.isfinite(value):
            raise ClassicParamsError(f"{where}: the number {number[:40]} does not fit a double")
        return value

    try:
        text = read_text(where, CLASSIC_JSON)
        document = json.loads(text, parse_constant=constant, parse_float=finite)
    except OSError as e:
        raise ClassicParamsError(f"{where}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError as e:
        raise ClassicParamsError(f"{where}: {not_text(e)}") from None
    except json.JSONDecodeError as e:
        raise ClassicParamsError(f"{where}: not JSON: {e}") from None
    if not isinstance(document, dict) or not isinstance(document.get("parameters"), list):
        raise ClassicParamsError(
            f"{where}: not a parameters.json (expected an object with a 'parameters' list)"
        )
    version = document.get("version")
    if isinstance(version, bool) or version != 1:
        raise ClassicParamsError(
            f"{where}: parameters.json version {json.dumps(version)} (expected 1)"
        )
    params: list[ClassicParam] = []
    seen: set[str] = set()
    for number, entry in enumerate(document["parameters"]):
        where_entry = f"{where}: parameters[{number}]"
        if not isinstance(entry, dict):
            raise ClassicParamsError(f"{where_entry}: expected an object")
        name, kind = entry.get("name"), entry.get("type")
        if not isinstance(name, str) or not name or len(name) > 16:
            raise ClassicParamsError(f"{where_entry}: 'name' must be 1 to 16 characters")
        if not (name[0] in _NAME_START and all(c in _NAME_REST for c in name)):
            # What names a parameter everywhere else (the store, MAVLink, the output files)
            raise ClassicParamsError(
                f"{where_entry}: 'name' {json.dumps(name)} is not a PX4 parameter name "
                "(upper-case letters, digits and '_', a letter first)"
            )
        if kind not in _TYPES:
            raise ClassicParamsError(
                f"{where_entry} ({name}): 'type' {kind!r} is not Int32 or Float"
            )
        if name in seen:
            raise ClassicParamsError(f"{where_entry}: duplicate parameter {name}")
        seen.add(name)
        try:
            default = classic_value(kind, entry.get("default", 0))
        except ClassicParamsError as e:
            raise ClassicParamsError(f"{where_entry} ({name}): default: {e}") from None
        params.append(ClassicParam(name, kind, default, entry))
    return params


def classic_value(kind: str, value: Any) -> int | float:
    """``value`` as a classic parameter of type ``kind`` holds it (floats rounded to float32)."""
    if isinstance(value, bool):
        value = int(value)
    if kind == "Int32":
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if not isinstance(value, int):
            raise ClassicParamsError(f"expected an integer, got {value!r}")
        if not INT32_MIN <= value <= INT32_MAX:
            raise ClassicParamsError(
                f"value {value} is out of range (expected {INT32_MIN} to {INT32_MAX})"
            )
        return value
    if not isinstance(value, int | float):
        raise ClassicParamsError(f"expected a number, got {value!r}")
    value = float(value)
    try:  # by rounding, not by comparing: 3.4028235e38, float32's largest as printed, rounds to it
        single = struct.unpack("<f", struct.pack("<f", value))[0]
    except OverflowError:
        raise ClassicParamsError(f"value {value} does not fit a float32") from None
    return float(single)
