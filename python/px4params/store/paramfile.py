"""Parameter files for other tools: QGC ``.params`` files and a JSON export.

QGC ``.params``: ``#`` comment lines, then one TAB-separated line per parameter,
``vehicle-id component-id name value type`` (type 6 int32, 9 float32; floats with 18
decimals), as QGroundControl saves and loads them. Classic parameters are written as they are;
structured instances in their destructured form (one flat parameter per leaf, ``INA238_0C``,
see :mod:`px4params.store.flat`), so a ground station that knows only flat parameters can load them.

JSON: ``{"format": "px4params", "version": 1, "instances": {"INA238#0": {"value": ...,
"default": ...}}, "classic": {"SYS_AUTOSTART": 4001}}`` with every existing instance and every
classic parameter that differs from its default.

Reading either applies everything or nothing (one store transaction).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from typing import Any

from px4params.dsdl.schema import to_json_value
from px4params.errors import (
    InstanceError,
    NumberError,
    ParamFileError,
    Px4ParamsError,
    StoreFileError,
    ValueRangeError,
)
from px4params.formats import qgc_params
from px4params.formats.keys import unknown_key
from px4params.formats.qgc_params import format_line
from px4params.numbers import load_json
from px4params.reading import PARAM_FILE, not_text, read_text
from px4params.store.classic import exact_in_type, rounding_said
from px4params.store.store import Key, Store

JSON_FORMAT = "px4params"
#: The keys of a JSON export, and of each of its instances: any other is refused by name.
JSON_KEYS = ("format", "version", "instances", "classic")
_ENTRY_KEYS = ("value", "default")

#: Told each value outside its @min/@max or @value list that ``--force`` took anyway.
Forced = Callable[[str], None]

_FLAT_INSTANCE = re.compile(r"(?P<param>[A-Z0-9_]+?)_(?P<instance>\d+)(?P<letters>[A-Z]+)")


def kind_of(path: str) -> str | None:
    """``qgc`` or ``json`` by the file's extension; None for anything else (a store file)."""
    ext = os.path.splitext(path)[1].lower()
    return {".params": "qgc", ".json": "json"}.get(ext)


# -- writing ----------------------------------------------------------------------------------


def export_qgc(store: Store, *, vehicle: int = 1, component: int = 1) -> str:
    from px4params.store.flat import flat_table

    lines = [
        "# Onboard parameters for Vehicle 1, written by px4params",
        "#",
        "# Structured instances are written destructured: one flat parameter per leaf.",
        "#",
        "# Vehicle-Id\tComponent-Id\tName\tValue\tType",
    ]
    for key in store.instance_keys():
        classic = store.classic(key.param)
        if classic is not None and store.changed(key):
            lines.append(
                format_line(vehicle, component, key.param, store.get(key), classic.is_float)
            )
    for p in flat_table(store):
        lines.append(format_line(vehicle, component, p.name, p.value, p.mav_type == "float32"))
    return "\n".join(lines) + "\n"


def export_json(store: Store) -> str:
    keys = list(store.instance_keys())
    instances = {
        str(key): {
            "value": to_json_value(_without_versions(store.get(key))),
            "default": to_json_value(_without_versions(store.get(key, default=True))),
        }
        for key in keys
        if store.classic(key.param) is None and (key.instance is not None or store.changed(key))
    }
    classic = {
        key.param: to_json_value(store.get(key))
        for key in keys
        if store.classic(key.param) is not None and store.changed(key)
    }
    document = {"format": JSON_FORMAT, "version": 1, "instances": instances, "classic": classic}
    return json.dumps(document, indent=1) + "\n"


def _without_versions(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _without_versions(v) for k, v in value.items() if k != "p_version"}
    if isinstance(value, list):
        return [_without_versions(v) for v in value]
    return value


def write(store: Store, path: str) -> int:
    """Exports ``store`` to ``path`` (a ``.params`` or ``.json`` file, by its extension)."""
    return write_exported(path, exported(store, path))


def exported(store: Store, path: str) -> bytes:
    """What :func:`write` writes to ``path``: the store as it is now (``run`` writes it later,
    when the whole airframe file has succeeded)."""
    kind = kind_of(path)
    if kind is None:
        raise ParamFileError(f"{path}: export writes .params (QGC) or .json files")
    return (export_qgc(store) if kind == "qgc" else export_json(store)).encode()


def write_exported(path: str, data: bytes) -> int:
    """Writes :func:`exported`'s ``data`` to ``path``; returns its size."""
    from px4params.store.file import write_file

    try:  # as the store is saved: atomically, and only over a regular file
        return write_file(path, data, keep_backup=False)
    except StoreFileError as e:
        raise ParamFileError(str(e)) from None


# -- reading ----------------------------------------------------------------------------------


def refuse_other_ground_station_file(path: str) -> None:
    """Raises a :class:`ParamFileError` naming the format when ``path`` (not a store file) is
    Mission Planner's or MAVProxy's parameter file; returns otherwise."""
    from px4params.formats.qgc_params import other_ground_station_file

    try:
        found = other_ground_station_file(read_text(path, PARAM_FILE))
    except (OSError, UnicodeDecodeError):
        return
    if found is not None:
        line, what = found
        raise ParamFileError(
            f"{path}:{line}: {what}, not a store file or QGC's .params: param load and import "
            "read store files, .params (QGC) and .json"
        )


def read(store: Store, path: str, *, reset: bool, forced: Forced | None = None) -> list[str]:
    """Applies a ``.params`` or JSON file (after resetting the store when ``reset``); all of
    it or, on any error, nothing. Returns report lines. A value outside its field's
    ``@min``/``@max`` or ``@value`` list (one set with ``param set --force``, exported) is
    refused, or with ``forced`` taken and told to it."""
    kind = kind_of(path)
    try:
        text = read_text(path, PARAM_FILE)
    except OSError as e:
        raise ParamFileError(f"{path}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError as e:
        raise ParamFileError(f"{path}: {not_text(e)}") from None
    with store.transaction():
        if reset:
            store.reset_to_initial()
        if kind == "qgc":
            return _read_qgc(store, path, text, forced)
        return _read_json(store, path, text, forced)


def write_forcing(
    where: str, forced: Forced | None, write: Callable[..., object], *args: Any
) -> None:
    """``write(*args)``; where ``forced`` is given (``--force``), a refused value is written
    again with ``force=True``, which takes one outside its ``@min``/``@max`` or ``@value`` list
    and still refuses a NaN or a value beyond its type in its own words, and, once stored, told
    to ``forced`` (named by ``where``, when given)."""
    try:
        write(*args)
    except ValueRangeError as e:
        if forced is None:
            raise
        write(*args, force=True)
        forced(f"{where}: {e}" if where else str(e))


def _refused(message: str, cause: Exception) -> ParamFileError:
    """The file refused for ``cause``, saying whether only a value's bounds were broken."""
    bounds = isinstance(cause, ValueRangeError) and cause.bounds_only
    return ParamFileError(message, bounds_only=bounds)


def _read_qgc(store: Store, path: str, text: str, forced: Forced | None) -> list[str]:
    from px4params.store.flat import write_live

    report: list[str] = []
    skipped = 0
    first_line: dict[str, int] = {}
    added: dict[Key, int] = {}  # instances the file made, by the line naming one first
    named: set[str] = set()
    # The store is the autopilot's, as migrate and the page take it.
    autopilot = qgc_params.autopilot_rows(qgc_params.read(text, path), path)
    report += autopilot.skipped(path)
    for row in autopilot.rows:
        where, name, number_value = f"{path}:{row.line}", row.name, row.value
        if first_line.setdefault(name, row.line) != row.line:  # which of two values is meant?
            raise ParamFileError(f"{where}: {name}: also set on line {first_line[name]}")
        if row.type not in (qgc_params.INT32, qgc_params.REAL32):
            raise ParamFileError(
                f"{where}: {name}: type '{row.type}' is not 6 (int32) or 9 (float)"
            )
        if row.type == qgc_params.REAL32:
            number_value = float(number_value)
        try:
            if name in store.parameters:
                classic = store.classic(name)
                if classic is not None:
                    typed = _of_type(where, name, row, classic.is_float, report)
                    if typed is None:
                        continue
                    number_value = typed
                write_forcing(where, forced, store.set, name, number_value)
                continue
            match = _FLAT_INSTANCE.fullmatch(name)
            if match is None or match["param"] not in store.parameters:
                report.append(f"{where}: {name}: not a parameter of this store; skipped")
                skipped += 1
                continue
            fmap = store.destructured
            instance, slot = fmap.owner(name)
            typed = _of_type(where, name, row, slot.mav_type == "float32", report)
            if typed is None:
                continue
            number_value = typed
            if instance not in store:
                store.add(instance)
                added.setdefault(instance, row.line)
            named.add(name)
            live = fmap.live(name, instance, slot)
            write_forcing(f"{where}: {name}", forced, write_live, store, live, number_value)
        except ParamFileError:
            raise
        except Px4ParamsError as e:  # named as the file names it, and as the store does
            text = str(e) if str(e).startswith(name) else f"{name}: {e}"
            raise _refused(f"{where}: {text}", e) from None
    if skipped:
        report.append(f"{path}: {skipped} parameters not in this store were skipped")
    report += _added(store, path, added, named)
    return report


def _added(store: Store, path: str, added: dict[Key, int], named: set[str]) -> list[str]:
    """What a ``.params`` file's reading added: each instance it made, by the line that named
    it first, and the leaves the file did not set, which keep the type's defaults (a file of
    ``INA238_2C`` alone makes INA238#2 on bus 0, which cannot start)."""
    from px4params.store.flat import flat_table

    lines = []
    for instance, line in added.items():
        unset = [
            p.name for p in flat_table(store) if p.instance == instance and p.name not in named
        ]
        kept = f"; {', '.join(unset)} not set by the file: the type's defaults" if unset else ""
        lines.append(f"{path}:{line}: added {instance}{kept}")
    return lines


def _of_type(
    where: str, name: str, row: qgc_params.QgcRow, is_float: bool, report: list[str]
) -> int | float | None:
    """The row's value as the parameter's type holds it. A parameter whose type changed between
    PX4 releases (RC10_REV, COM_DISARM_LAND: a file of an older vehicle) is converted where no
    digit is lost, and said; else skipped and said, as QGroundControl skips a type mismatch."""
    expected = qgc_params.REAL32 if is_float else qgc_params.INT32
    value = row.value
    if row.type == expected:
        return value
    names = {qgc_params.INT32: "INT32 (6)", qgc_params.REAL32: "REAL32 (9)"}
    said = f"{where}: {name}: {names[row.type]} in the file, {names[expected]} here"
    exact = exact_in_type(value, is_float)
    if exact is None:
        report.append(f"{said}: {_shown(value)} does not fit; skipped")
        return None
    report.append(
        f"{said} (its type changed between PX4 releases): {_shown(value)} taken as {_shown(exact)}"
    )
    return exact


def _shown(value: int | float) -> str:
    return repr(value) if isinstance(value, float) else str(value)


def _read_json(store: Store, path: str, text: str, forced: Forced | None) -> list[str]:
    try:
        document = load_json(text, stored=True)
    except json.JSONDecodeError as e:
        raise ParamFileError(f"{path}:{e.lineno}: not JSON: {e.msg}") from None
    except (NumberError, RecursionError) as e:
        raise ParamFileError(f"{path}: {e}") from None
    if not isinstance(document, dict) or document.get("format") != JSON_FORMAT:
        raise ParamFileError(f'{path}: not a px4params JSON export (no "format": "px4params")')
    version = document.get("version")
    if type(version) is not int or version != 1:  # (true and 1.0 == 1 in Python, not here)
        raise ParamFileError(f"{path}: JSON export version {json.dumps(version)} (expected 1)")
    complaint = unknown_key(document, JSON_KEYS, "top-level key")
    if complaint is not None:
        raise ParamFileError(f"{path}: {complaint}; nothing was changed")
    instances = document.get("instances", {})
    classic = document.get("classic", {})
    for section, value in (("instances", instances), ("classic", classic)):
        if not isinstance(value, dict):
            raise ParamFileError(
                f"{path}: '{section}' must be an object, not {_json_kind(value)}; nothing was "
                "changed"
            )
    for name, entry in instances.items():
        try:
            key = Key.parse(name)
            if key.leaf is not None or store.classic(key.param) is not None:
                raise ParamFileError(
                    f"{name}: 'instances' holds whole structured parameters (INA238#0, not a "
                    "leaf or a classic parameter)"
                )
            if not isinstance(entry, dict):  # ({} adds the instance with its defaults)
                raise ParamFileError(f'{name}: expected {{"value": ..., "default": ...}}')
            complaint = unknown_key(entry, _ENTRY_KEYS)
            if complaint is not None:
                raise ParamFileError(f"{name}: {complaint}")
            if key.instance is not None and key not in store:
                store.add(key)
            if "default" in entry:
                write_forcing(
                    f"{path}: instances", forced, store.set_default, key, entry["default"]
                )
            if "value" in entry:
                write_forcing(f"{path}: instances", forced, store.set, key, entry["value"])
        except (Px4ParamsError, InstanceError) as e:
            raise _refused(f"{path}: instances: {e}", e) from None
    report = []
    for name, value in classic.items():
        try:
            key = Key.parse(name)
            param = store.classic(key.param)
            if param is None:
                raise ParamFileError(f"{name}: not a classic parameter of this store")
            if isinstance(value, bool):  # a structured leaf refuses one too
                raise ParamFileError(f"{name}: expected a number, got {_json_kind(value)}")
            store.set(key, value)  # (PX4 enforces no classic @min/@max: nothing to force)
            rounded = rounding_said(param, value)
            if rounded is not None:
                report.append(f"{path}: classic: {rounded}")
        except Px4ParamsError as e:
            raise _refused(f"{path}: classic: {e}", e) from None
    return report


def _json_kind(value: Any) -> str:
    """How JSON names the kind of ``value``: ``an array``, ``null``, ``a string``, ..."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    kinds = {list: "an array", str: "a string", int: "a number", float: "a number"}
    return kinds.get(type(value), "an object")
