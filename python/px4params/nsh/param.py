"""NSH's ``param`` verbs over structured instances and classic parameters, on a session's store
(shared by ``px4params param`` and airframe files).

Every verb that changes something saves the store when it succeeds (as PX4 autosaves); a
refused change saves nothing and leaves the file as it was.
"""

from __future__ import annotations

import math
import os
import struct
import sys

from px4params._records import TYPE_CHECKING
from px4params.dsdl.schema import Leaf, to_json_value
from px4params.errors import (
    CommandError,
    InstanceError,
    NumberError,
    ParamFileError,
    Px4ParamsError,
    StoreFileError,
)
from px4params.numbers import (
    FLOAT_MAX,
    abbreviated,
    dump_json,
    load_json,
    parse_float,
    parse_int,
)
from px4params.status import EXIT_FAILED, EXIT_OK
from px4params.store.classic import rounding_said
from px4params.store.session import Session
from px4params.store.store import Key, Store

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    import argparse
    from collections.abc import Callable
    from typing import Any, TextIO

    #: A verb: the session, the parsed command line (argparse's namespace, or one alike).
    Verb = Callable[[Session, argparse.Namespace], int]

# Pattern strings, and ``re`` imported on first use: commands that parse no number do not pay
# for it.
_INT = r"[+-]?(0[xX][0-9a-fA-F]+|[0-9]+)"
_FLOAT = r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?"


# -- values given as text -------------------------------------------------------------------


def parse_number(text: str, kind: str, where: str) -> int | float | bool:
    """``text`` as a value of a leaf of type ``kind`` (``uint7``, ``float16``, ``bool``, classic
    ``Int32``/``Float``): decimal or 0x hex integers, floats only for float leaves. Anything
    else is refused (PX4's ``param set`` silently reads ``0x45`` as 0; we do not)."""
    import re

    t = text.strip()
    if kind == "bool":
        lowered = t.lower()
        if lowered in ("1", "true"):
            return True
        if lowered in ("0", "false"):
            return False
        raise CommandError(f"{where}: '{text}' is not a boolean (expected 0, 1, true or false)")
    try:
        if kind.startswith("float") or kind == "Float":
            if re.fullmatch(_INT, t):
                return float(parse_int(t, 16 if "x" in t[:3].lower() else 10))
            if re.fullmatch(_FLOAT, t) or t.lower() in ("nan", "inf", "+inf", "-inf"):
                return parse_float(t, stored=True)
            raise CommandError(
                f"{where}: '{abbreviated(text)}' is not a number (expected e.g. 0.0003, 2e-4 or 5)"
            )
        if re.fullmatch(_INT, t):
            return parse_int(t, 16 if "x" in t[:3].lower() else 10)
    except NumberError as e:
        raise CommandError(f"{where}: {e}") from None
    raise CommandError(
        f"{where}: '{abbreviated(text)}' is not an integer (expected decimal or 0x hex, e.g. 69 or "
        "0x45)"
    )


def parse_value(store: Store, key: Key, text: str, leaf: Leaf | None = None) -> Any:
    """The value ``text`` given for ``key``: a number for a leaf or a classic parameter, JSON
    for a whole structured value. ``leaf`` is the key's leaf when the caller has read it."""
    classic = store.classic(key.param)
    if classic is not None:
        return parse_number(text, classic.type, str(key))
    if key.leaf is None:
        try:
            return load_json(text, stored=True)
        except NumberError as e:
            raise CommandError(f"{key}: {e}") from None
        except (RecursionError, ValueError) as e:  # json.JSONDecodeError is a ValueError
            msg = getattr(e, "msg", str(e))
            raise CommandError(
                f"{key}: a whole value is JSON ({msg} in '{abbreviated(text)}'); "
                f'e.g. \'{{"bus": {{"i2c": {{"bus_id": 1, "address": 69}}}}, ...}}\''
            ) from None
    if leaf is None:
        leaf = store.leaf(key)
    kind = (
        "uint"
        if leaf.path.endswith(("._tag", "._len")) or leaf.path in ("_tag", "_len")
        else leaf.type
    )
    return parse_number(text, kind, str(key))


# -- showing values -------------------------------------------------------------------------


def short_float(value: float, kind: str) -> str:
    """The shortest decimal that stores as the same float16/float32 (``0.0003``, not
    ``0.0002999305725097656``)."""
    if not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    code = {"float16": "<e", "float32": "<f", "Float": "<f"}.get(kind)
    if code is None:
        return repr(value)
    target = struct.pack(code, value)
    largest = FLOAT_MAX[16 if code == "<e" else 32]
    for digits in range(1, 18):
        text = f"{value:.{digits}g}"
        # Not beyond the largest finite value, which the store refuses when it is typed back
        # (3.4028235e38 rounds to FLT_MAX but is above it; 7e4 is no float16 at all).
        if abs(float(text)) > largest:
            continue
        if struct.pack(code, float(text)) == target:
            if "e" in text and 1e-4 <= abs(value) < 1e16:  # 5000, not 5e+03
                text = f"{float(text):f}".rstrip("0").rstrip(".")
            return text
    return repr(value)


def shown_value(store: Store, name: str | Key, *, default: bool = False) -> str:
    """A value on one line: a classic number, or a structured value without its p_version
    fields, floats as short as they are stored."""
    name = Key.parse(name)
    classic = store.classic(name.param)
    value = store.get(name, default=default)
    if classic is not None:
        return short_float(value, "Float") if classic.is_float else str(value)
    kinds = {leaf.path: leaf.type for leaf in store.leaves(name, default=default)}
    return _compact(value, "", kinds)


def _compact(value: Any, prefix: str, kinds: dict[str, str]) -> str:
    if isinstance(value, dict):
        items = [
            f"{k}: {_compact(v, f'{prefix}{k}.', kinds)}"
            for k, v in value.items()
            if k != "p_version"
        ]
        return "{" + ", ".join(items) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(_compact(v, prefix, kinds) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return short_float(value, kinds.get(prefix[:-1], "float64"))
    return str(value)


def shown_leaf(leaf: Leaf) -> str:
    if isinstance(leaf.value, float):
        return short_float(leaf.value, leaf.type)
    if isinstance(leaf.value, bool):
        return "true" if leaf.value else "false"
    return str(leaf.value)


def _matches(name: str, patterns: list[str]) -> bool:
    if not patterns:
        return True
    import fnmatch

    return any(fnmatch.fnmatchcase(name.upper(), p.upper()) for p in patterns)


# -- verbs ----------------------------------------------------------------------------------


def verb_add(s: Session, a: argparse.Namespace) -> int:
    with s.store.transaction():
        added = [s.store.add(name) for name in a.names]
    s.done()
    for name in added:
        print(name, file=s.out)
    return EXIT_OK


def verb_rm(s: Session, a: argparse.Namespace) -> int:
    with s.store.transaction():
        for name in a.names:
            s.store.remove(name)
    s.done()
    return EXIT_OK


def resolve_name(store: Store, name: str) -> Key:
    """``name`` parsed once into the key every later step takes; a destructured flat name
    (``INA238_1C``) becomes the leaf it stands for (``INA238#1[4]``), so that both spellings
    set the same leaf. A flat name whose leaf is not live (another union variant selected) or
    whose instance does not exist says so."""
    try:
        key = Key.parse(name)
        if key.param in store.parameters:
            return key
    except InstanceError:
        pass
    from px4params.store.flat import flat_map

    fmap = flat_map(store)
    if name in fmap:
        return fmap.find(name).leaf
    return Key.parse(name)  # neither: the store's own error names the problem


def _say_forced(what: str) -> None:
    """The warning of a value ``--force`` stored (``paramfile.write_forcing``'s ``forced``)."""
    print(f"px4params: warning: --force: {what}; stored anyway", file=sys.stderr)


def _write(s: Session, name: str, text: str, *, default: bool, force: bool = False) -> None:
    key = resolve_name(s.store, name)
    # The leaf is read once: its type parses the number and says whether it rounds to zero.
    leaf = s.store.leaf(key) if key.leaf is not None and s.store.spec(key.param) else None
    value = parse_value(s.store, key, text, leaf)
    from px4params.store.paramfile import write_forcing

    write = s.store.set_default if default else s.store.set
    write_forcing("", _say_forced if force else None, write, key, value)
    classic = s.store.classic(key.param)
    rounded = rounding_said(classic, value) if classic is not None else None
    if rounded is not None:
        print(f"px4params: warning: {rounded}", file=sys.stderr)
    if isinstance(value, float) and value != 0 and math.isfinite(value):
        stored = s.store.get(key, default=default)
        if stored == 0:
            # The DroneCAN rules round it to zero (as pydronecan and libcanard do): said once.
            print(
                f"px4params: warning: {key}: {text.strip()} is below the smallest "
                f"{_float_kind(s.store, key, leaf) or 'float'} and is stored as 0",
                file=sys.stderr,
            )


def verb_set(s: Session, a: argparse.Namespace) -> int:
    if a.fail not in (None, "fail"):
        raise CommandError(f"unexpected '{a.fail}' after the value (only 'fail' may follow)")
    _write(s, a.name, a.value, default=False, force=getattr(a, "force", False))
    s.done()
    return EXIT_OK


def verb_set_default(s: Session, a: argparse.Namespace) -> int:
    try:
        _write(s, a.name, a.value, default=True, force=getattr(a, "force", False))
    except InstanceError as e:
        if a.silent and "unknown parameter" in str(e):
            return EXIT_FAILED
        raise
    s.done()
    return EXIT_OK


def _compare(s: Session, a: argparse.Namespace, greater: bool) -> int:
    key = resolve_name(s.store, a.name)
    try:
        current = s.store.get(key)
    except InstanceError:
        if a.silent:
            return EXIT_FAILED
        raise
    for text in a.values:
        wanted = parse_value(s.store, key, text)
        if isinstance(current, float) and isinstance(wanted, int | float):
            kind = _float_kind(s.store, key)
            wanted = float(short_float(float(wanted), kind)) if kind else float(wanted)
            current_cmp: Any = float(short_float(current, kind)) if kind else current
        else:
            current_cmp = current
        if isinstance(current_cmp, dict):
            if greater:
                raise CommandError(f"{key}: greater compares numbers, not whole values")
            matched = _same_value(s.store, key, wanted)
        else:
            matched = current_cmp > wanted if greater else current_cmp == wanted
        if matched:
            return EXIT_OK
    return EXIT_FAILED


def _float_kind(store: Store, key: Key, leaf: Leaf | None = None) -> str | None:
    classic = store.classic(key.param)
    if classic is not None:
        return "Float" if classic.is_float else None
    if leaf is None:
        leaf = store.leaf(key)
    return leaf.type if leaf.type.startswith("float") else None


def _same_value(store: Store, key: Key, wanted: Any) -> bool:
    data_type = store.data_type(key)
    try:
        return data_type.encode(wanted, tao=False) == store.encoded(key)
    except Px4ParamsError:
        return False


def verb_compare(s: Session, a: argparse.Namespace) -> int:
    return _compare(s, a, greater=False)


def verb_greater(s: Session, a: argparse.Namespace) -> int:
    return _compare(s, a, greater=True)


def verb_show(s: Session, a: argparse.Namespace) -> int:
    store = s.store
    if a.leaves:
        return _show_leaves(s, a)
    if a.quiet:
        if len(a.filters) != 1 or "*" in a.filters[0]:
            raise CommandError("show -q takes one exact name")
        key = resolve_name(store, a.filters[0])
        shown = shown_value(store, key) if key.leaf is None else shown_leaf(store.leaf(key))
        print(shown, file=s.out)
        return EXIT_OK
    for f in a.filters:
        if "[" in f or "." in f:
            raise CommandError(
                f"show lists instances and parameters; for the leaf {f} use show -q {f}, "
                "for all leaves show -l INSTANCE"
            )
    rows = []
    used_index = 0
    position = {p: i for i, p in enumerate(store.parameters)}
    for key in store.instance_keys():
        name = str(key)
        index = position[key.param]
        used, unsaved = store.state(key)
        changed = store.changed(key)
        structured = store.classic(key.param) is None
        # PX4 shows used parameters; a manifest's instances are always of interest.
        if not (a.all or structured or used or changed):
            continue
        if a.changed and not changed:
            continue
        if not _matches(name, a.filters):
            continue
        rows.append((name, index, used_index if used else -1, used, unsaved, changed))
        used_index += int(used)
    if a.json:
        listed = [
            {
                "name": name,
                "index": index,
                "value": to_json_value(store.get(name)),
                "default": to_json_value(store.get(name, default=True)),
                "changed": changed,
                "saved": not unsaved,
                "used": used,
            }
            for name, index, _, used, unsaved, changed in rows
        ]
        _print_json(listed, s.out)
        return EXIT_OK
    print("Symbols: x = used, + = saved, * = unsaved", file=s.out)
    for name, index, uindex, used, unsaved, changed in rows:
        mark = ("*" if unsaved else "+") if changed else " "
        print(
            f"{'x' if used else ' '} {mark} {name} [{uindex},{index}] : {shown_value(store, name)}",
            file=s.out,
        )
    total = len(list(store.names()))
    print(f"\n {len(rows)}/{total} parameters shown.", file=s.out)
    return EXIT_OK


def _show_leaves(s: Session, a: argparse.Namespace) -> int:
    store = s.store
    if len(a.filters) != 1:
        raise CommandError("show -l takes one instance, e.g. show -l INA238#0")
    key = Key.parse(a.filters[0])
    leaves = store.leaves(key)
    if key.leaf is not None:  # one leaf, or the leaves under a path (show -l INA238#0.bus)
        part = key.leaf
        leaves = [
            leaf
            for leaf in leaves
            if (
                leaf.index == part
                if isinstance(part, int)
                else leaf.path == part or leaf.path.startswith((f"{part}.", f"{part}["))
            )
        ]
        if not leaves:
            whole = key._replace(leaf=None)
            raise CommandError(
                f"{key}: no such leaf in the value (show -l {whole} lists its leaves)"
            )
    data_type = store.data_type(key)
    defaults = {leaf.path: leaf for leaf in store.leaves(key, default=True)}
    rows: list[dict[str, Any]] = []
    for leaf in leaves:
        field = data_type.field_at(leaf.path)
        default = defaults.get(leaf.path)
        rows.append(
            {
                "index": leaf.index,
                "path": leaf.path,
                "type": leaf.type,
                "value": leaf.value,
                "default": default.value if default is not None else None,
                "unit": (field.doc.unit if field is not None else None) or "",
                "shown": shown_leaf(leaf),
                "default_shown": shown_leaf(default) if default is not None else "-",
            }
        )
    if a.json:
        for row in rows:
            del row["shown"], row["default_shown"]
        _print_json(to_json_value(rows), s.out)
        return EXIT_OK
    width = max(len(r["path"]) for r in rows)
    for r in rows:
        print(
            f"[{r['index']}] {r['path']:<{width}} {r['type']:<8} {r['shown']:>10} "
            f"{r['default_shown']:>10} {r['unit']}".rstrip(),
            file=s.out,
        )
    return EXIT_OK


def _expand(store: Store, patterns: list[str]) -> list[Key]:
    """Names matching ``patterns``: a trailing ``*`` matches, a parameter name stands for all
    its instances, and destructured flat names for their leaves."""
    keys = list(store.instance_keys())
    found: list[Key] = []
    for p in patterns:  # exact, as PX4's names (an inexact one is refused with a hint)
        if "*" in p:
            import fnmatch

            found += [k for k in keys if fnmatch.fnmatchcase(str(k), p)]
        elif p in store.parameters and store.spec(p) is not None and "#" not in p:
            spec = store.spec(p)
            shared = spec is None or spec.shared
            found += [Key(p, None, None)] if shared else list(store.instance_keys(p))
        else:
            found.append(resolve_name(store, p))
    return found


def verb_reset(s: Session, a: argparse.Namespace) -> int:
    with s.store.transaction():
        for name in _expand(s.store, a.names):
            s.store.reset(name)
    s.done()
    return EXIT_OK


def verb_reset_all(s: Session, a: argparse.Namespace) -> int:
    keep = {key.whole for key in _expand(s.store, a.excludes)}
    for key in keep:  # a misspelt exclude would reset the very value it was to keep
        s.store.spec(key.param)
    with s.store.transaction():
        for key in list(s.store.instance_keys()):
            if key not in keep:
                s.store.reset(key)
    s.done()
    _say_kept_classic(s.store, "kept, not reset")
    return EXIT_OK


def _say_kept_classic(store: Store, what: str) -> None:
    """Warns of the store's classic values this parameter set lacks (``Store.kept_classic``),
    which a command that goes over every value leaves out."""
    kept = store.kept_classic
    if kept:
        many = len(kept) > 1
        # (A name this set has was stored as its other type: see store/file.py)
        why = " or another type in it" if set(kept) & set(store.parameters) else ""
        print(
            f"px4params: warning: {len(kept)} classic value{'s' if many else ''} of the store "
            f"{what}: {', '.join(kept)} (not in this parameter set{why}: give --classic the "
            f"parameters.json that has {'them' if many else 'it'})",
            file=sys.stderr,
        )


def verb_touch(s: Session, a: argparse.Namespace) -> int:
    for name in _expand(s.store, a.names):
        s.store.mark_used(name)
    return EXIT_OK


def verb_save(s: Session, a: argparse.Namespace) -> int:
    from px4params.writing import same_file

    # The store's own file, however it is named (a symbolic link to it, ./x): a copy of the
    # store at this line written there would replace what the run saves.
    if not a.file or same_file(a.file, s.path):
        s.done()  # the store's own file: now, or when the airframe file has succeeded
        if s.autosave:
            print(f"saved {s.path}", file=s.out)
        return EXIT_OK
    from px4params.store import file as store_file
    from px4params.store import paramfile

    file = a.file
    if os.path.realpath(file) == os.path.realpath(s.path) + ".lock":
        # Replaced by a new file, the lock another writer holds would no longer keep it out.
        raise StoreFileError(f"is {s.path}'s lock file: give the save another name", file)
    # By its extension, as load reads it: a .params file saved as a store loaded back as text.
    text = paramfile.kind_of(file) is not None
    # The store as it is at this line (a backup before changes), written when the airframe
    # file has succeeded.
    data = paramfile.exported(s.store, file) if text else store_file.encode_file(s.store)

    def write() -> None:
        if text:
            size = paramfile.write_exported(file, data)
        else:
            from px4params.store.session import StoreLock

            # Under that store's lock: a writer of it in the middle of a change would otherwise
            # save over this save, which said "saved" (helper-110).
            with StoreLock(file):
                size = store_file.write_file(file, data, keep_backup=True)
        print(f"saved {file} ({size} bytes)", file=s.out)
        if text:  # (a store file keeps them)
            _say_kept_classic(s.store, f"not written to {file}")

    s.write_later(file, write)
    return EXIT_OK


def _load(s: Session, a: argparse.Namespace, merge: bool) -> int:
    from px4params.store import paramfile

    source = a.file or s.path
    # What a reset drops without the file bringing it back is said: instances are devices.
    before = [] if merge else [k for k in s.store.instance_keys() if k.instance is not None]
    if paramfile.kind_of(source):
        force = getattr(a, "force", None)  # (the command line's alone)
        try:
            report = paramfile.read(
                s.store, source, reset=not merge, forced=_say_forced if force else None
            )
        except ParamFileError as e:
            if force is None or not e.bounds_only:
                raise
            verb = "import" if merge else "load"
            raise ParamFileError(f"{e} ('param {verb} --force' takes it)") from None
    else:
        try:
            report = s.store.import_from(source) if merge else s.store.load_from(source)
        except StoreFileError:
            paramfile.refuse_other_ground_station_file(source)  # (Mission Planner's .param)
            raise
    for line in report:
        print(line, file=s.out)
    gone = [str(key) for key in before if key not in s.store]
    if gone:
        print(
            f"removed {len(gone)} instance{'s' if len(gone) > 1 else ''} not in {source}: "
            f"{', '.join(gone)} ('param load' resets the store first; 'param import' keeps "
            "what a file does not name)",
            file=s.out,
        )
    if a.file:  # loading the store's own file changes nothing to save
        s.done()
    return EXIT_OK


def verb_load(s: Session, a: argparse.Namespace) -> int:
    return _load(s, a, merge=False)


def verb_import(s: Session, a: argparse.Namespace) -> int:
    return _load(s, a, merge=True)


def verb_export(s: Session, a: argparse.Namespace) -> int:
    from px4params.store import paramfile

    if paramfile.kind_of(a.file) is None:
        raise CommandError(f"{a.file}: export writes .params (QGC) or .json files")
    file = a.file
    data = paramfile.exported(s.store, file)  # the store as it is at this line

    def write() -> None:
        size = paramfile.write_exported(file, data)
        print(f"wrote {file} ({size} bytes)", file=s.out)
        _say_kept_classic(s.store, f"not written to {file}")

    s.write_later(file, write)
    return EXIT_OK


def verb_status(s: Session, a: argparse.Namespace) -> int:
    store = s.store
    instances = [key for key in store.instance_keys() if key.instance is not None]
    slots, size = store.capacity
    exists = os.path.exists(s.path)
    status = {
        "store": s.path,
        "file_bytes": os.path.getsize(s.path) if exists else None,
        "structured_parameters": len(store.specs),
        "classic_parameters": len(store.parameters) - len(store.specs),
        "instances": len(instances),
        "changed": len(store.changed()),
        "kept_classic": len(store.kept_classic),
        "reserved_slots": slots,
        "reserved_bytes": size,
    }
    if a.json:
        _print_json(status, s.out)
        return EXIT_OK
    file_text = f"{status['file_bytes']} bytes" if exists else "not saved yet"
    print(f"store: {s.path} ({file_text})", file=s.out)
    print(
        f"parameters: {status['structured_parameters']} structured, "
        f"{status['classic_parameters']} classic",
        file=s.out,
    )
    print(f"instances: {len(instances)} ({', '.join(map(str, instances)) or 'none'})", file=s.out)
    print(f"changed from defaults: {status['changed']}", file=s.out)
    if store.kept_classic:
        print(
            f"classic values of another parameter set, kept: {len(store.kept_classic)} "
            f"({', '.join(store.kept_classic)})",
            file=s.out,
        )
    print(f"memory reserved: {size} bytes in {slots} slots", file=s.out)
    return EXIT_OK


def verb_find(s: Session, a: argparse.Namespace) -> int:
    key = Key.parse(a.name)
    index = s.store.parameters.index(s.store._param(key.param).name)
    print(f"Found param {key.param} at index {index}", file=s.out)
    return EXIT_OK


def verb_flat(s: Session, a: argparse.Namespace) -> int:
    from px4params.store.flat import flat_table

    table = [p for p in flat_table(s.store) if _matches(p.name, a.filters)]
    if a.json:
        _print_json([p.as_dict() for p in table], s.out)
        return EXIT_OK
    for p in table:
        shown = short_float(p.value, "float32") if isinstance(p.value, float) else str(p.value)
        print(
            f"{p.name:<16} {p.leaf:<14} {p.instance}.{p.path:<24} {p.mav_type:<6} {shown}",
            file=s.out,
        )
    return EXIT_OK


def verb_instances(s: Session, a: argparse.Namespace) -> int:
    names = s.store.instances(a.param)
    if a.json:
        _print_json(names, s.out)
    else:
        for name in names:
            print(name, file=s.out)
    return EXIT_OK


# -- the parser -----------------------------------------------------------------------------

VERBS: dict[str, tuple[Verb, str, str]] = {}


class _Unbuilt:
    """Stands in for the parser of a verb that is not being run: its arguments are skipped
    (a command builds only the verb it runs; argparse costs about 0.3 ms a parser)."""

    def add_argument(self, *args: Any, **kwargs: Any) -> None:
        pass


class _VerbParsers:
    """Adds the verbs' parsers to ``sub``: every one, or with ``only`` just that verb's (the
    others' arguments go to an :class:`_Unbuilt`)."""

    def __init__(self, sub: Any, only: str | None, formatter_class: Any) -> None:
        self.sub = sub
        self.only = only
        self.formatter_class = formatter_class

    def __call__(self, name: str, func: Verb, summary: str, example: str) -> Any:
        VERBS[name] = (func, summary, example)
        if self.only is not None and name != self.only:
            return _Unbuilt()
        p = self.sub.add_parser(
            name,
            help=summary,
            description=summary,
            epilog=f"example:\n  {example}",
            formatter_class=self.formatter_class,
        )
        p.set_defaults(verb=func)
        return p


def add_verbs(
    sub: Any, formatter_class: Any, only: str | None = None, *, cli: bool = False
) -> None:
    """The ``param`` verbs (shared by ``px4params param`` and airframe files) on ``sub``,
    argparse's subcommands or those of ``px4params.cli.parsing`` (whose declaration argparse
    builds only when asked: ``formatter_class`` is the help formatter of argparse's or its
    stand-in there). With ``only``, just that verb's parser is built (all of them, listed by
    name, when it is no verb). ``cli`` adds what only the command line takes (``--force``:
    an airframe file states values, it does not override ranges)."""
    _add_verbs(_VerbParsers(sub, only, formatter_class), cli)
    if only is not None and only not in VERBS:  # no verb: list them all for the usage error
        for name, (_, summary, _) in VERBS.items():
            sub.add_parser(name, help=summary, add_help=False)


_FORCE_HELP = (
    "store a value outside its field's @min/@max or @value list anyway (said on stderr); a "
    "NaN or an infinity is refused all the same"
)


_FORCE_FILE_HELP = (
    "take a .params or .json file's values outside their field's @min/@max or @value list "
    "(as 'param set --force' stored them; each said on stderr)"
)


def _add_verbs(verb: _VerbParsers, cli: bool) -> None:
    p = verb(
        "add",
        verb_add,
        "add instances (NAME#N, or NAME for the next free one)",
        "px4params param add INA238#2",
    )
    p.add_argument("names", nargs="+", metavar="NAME")
    p = verb(
        "rm",
        verb_rm,
        "remove instances (the others keep their numbers)",
        "px4params param rm INA238#1",
    )
    p.add_argument("names", nargs="+", metavar="NAME")
    p = verb(
        "set",
        verb_set,
        "set a value, a leaf ([k] or path) or a classic parameter",
        "px4params param set INA238#0[4] 0x45",
    )
    p.add_argument("name")
    p.add_argument("value")
    p.add_argument("fail", nargs="?", help="accepted for NSH compatibility: errors always fail")
    if cli:
        p.add_argument("--force", action="store_true", help=_FORCE_HELP)
    p = verb(
        "set-default",
        verb_set_default,
        "set a default (the value follows unless it was changed)",
        "px4params param set-default INA238#0[6] 0.0003",
    )
    p.add_argument(
        "-s", dest="silent", action="store_true", help="an unknown parameter fails silently"
    )
    p.add_argument("name")
    p.add_argument("value")
    if cli:
        p.add_argument("--force", action="store_true", help=_FORCE_HELP)
    for name, func, summary in (
        ("compare", verb_compare, "exit 0 if NAME equals one of the values, else 1"),
        ("greater", verb_greater, "exit 0 if NAME is greater than one of the values, else 1"),
    ):
        limit = 200 if name == "compare" else 100
        p = verb(name, func, summary, f"px4params param {name} INA238#0.current {limit}")
        p.add_argument(
            "-s", dest="silent", action="store_true", help="an unknown parameter fails silently"
        )
        p.add_argument("name")
        p.add_argument("values", nargs="+", metavar="VALUE")
    p = verb(
        "show",
        verb_show,
        "show instances and changed or used classic parameters (-a: all)",
        "px4params param show -l INA238#0",
    )
    p.add_argument("-a", dest="all", action="store_true", help="every parameter")
    p.add_argument("-c", dest="changed", action="store_true", help="only changed ones")
    p.add_argument("-q", dest="quiet", action="store_true", help="only the value of one name")
    p.add_argument(
        "-l",
        dest="leaves",
        action="store_true",
        help="the leaves of one instance (or one leaf, or those under a path: INA238#0.bus): "
        "[k] path type value default unit",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("filters", nargs="*", metavar="FILTER", help="names, a trailing * matches")
    p = verb(
        "reset",
        verb_reset,
        "set values back to their defaults",
        "px4params param reset INA238#*",
    )
    p.add_argument("names", nargs="+", metavar="NAME")
    p = verb(
        "reset_all",
        verb_reset_all,
        "reset every value except the excluded",
        "px4params param reset_all SYS_AUTOSTART",
    )
    p.add_argument("excludes", nargs="*", metavar="EXCLUDE")
    p = verb("touch", verb_touch, "mark as used (within one run)", "px4params param touch INA238#0")
    p.add_argument("names", nargs="+", metavar="NAME")
    for name, func, summary in (
        ("save", verb_save, "save the store (to FILE)"),
        ("load", verb_load, "reset, then load FILE (a store, QGC .params or .json file)"),
        ("import", verb_import, "merge FILE (a store, QGC .params or .json file)"),
    ):
        p = verb(name, func, summary, f"px4params param {name} backup.store")
        p.add_argument("file", nargs="?", metavar="FILE")
        if cli:
            p.add_argument("--force", action="store_true", help=_FORCE_FILE_HELP)
    p = verb(
        "export",
        verb_export,
        "write a QGC .params file (instances destructured) or a .json export",
        "px4params param export vehicle.params",
    )
    p.add_argument("file", metavar="FILE")
    p = verb("status", verb_status, "show the store file and its use", "px4params param status")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p = verb("find", verb_find, "show a parameter's index", "px4params param find INA238")
    p.add_argument("name")
    p = verb(
        "flat",
        verb_flat,
        "the destructured flat parameters (MAVLink names) of every instance",
        "px4params param flat INA238_0*",
    )
    p.add_argument("filters", nargs="*", metavar="FILTER", help="names, a trailing * matches")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p = verb(
        "instances",
        verb_instances,
        "list a parameter's instances in order",
        "px4params param instances INA238",
    )
    p.add_argument("param")
    p.add_argument("--json", action="store_true", help="machine-readable output")


def _print_json(value: object, out: TextIO) -> None:
    print(dump_json(value), file=out)
