"""Load DSDL parameter types into one JSON-serialisable schema model.

Two parsers feed the model:

* ``.dsdl`` root namespaces (pydsdl syntax: ``Name.1.0.dsdl``, ``@sealed``) are read with pydsdl.
  They are serialised with the DroneCAN rules, so only ``@sealed`` types are accepted.
* ``.uavcan`` root namespaces (DroneCAN / UAVCAN v0) are read with pydronecan's parser; this
  includes the standard set bundled with pydronecan (``uavcan.*``, ``dronecan.*``, ...).

Metadata lives in pydsdl doc comments (``.doc``), which pydsdl assigns like this:

* The type's doc is the comment block at the very top of the file: contiguous ``#`` lines up to
  the first empty line or the first statement. An empty line inside it ends it, so separate
  paragraphs with a bare ``#`` line. For a service, the block right after ``---`` is the
  response's doc.
* A field's doc is the comment on the field's own line (after the statement) followed by the
  comment lines directly below it, up to the next empty line, statement or directive.
  Comments above a field belong to nobody.

Inside a doc the first non-empty line is the short description, the following lines the long
description, and ``@tag value`` lines (after the text) carry the metadata, PX4-annotation style.

The model is cached as JSON by :mod:`px4params.dsdl.cache`; a cache hit imports neither this
module nor pydsdl nor dronecan.
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import math
import os
import re
import sys
import tomllib
import types
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from px4params.data import VALUE_SETS_TOML
from px4params.dsdl.model import length_bits, tag_bits
from px4params.dsdl.roots import Root, dronecan_package_dir
from px4params.errors import DsdlError, NumberError, TagValueError
from px4params.numbers import FLOAT_MAX, abbreviated, parse_float, parse_int
from px4params.reading import DSDL, not_text, read_text

if TYPE_CHECKING:
    import pydsdl

__all__ = ["build_model"]

Model = dict[str, Any]
TypeSpec = dict[str, Any]

_log = logging.getLogger(__name__)

_SCALAR_KINDS = ("uint", "int", "float", "bool")

# Name under which pydronecan's parser package is loaded without running dronecan/__init__.py.
_PRIVATE_DRONECAN_DSDL = "_px4params_dronecan_dsdl"


# --------------------------------------------------------------------------------------------------
# Building the model


def build_model(roots: Sequence[Root]) -> Model:
    """The model of every type in ``roots`` (parsed now; :func:`px4params.dsdl.cache.load_model`
    caches it)."""
    builder = _ModelBuilder()
    pydsdl_roots = [r for r in roots if r.dialect == "dsdl"]
    dronecan_roots = [r for r in roots if r.dialect == "uavcan"]
    if pydsdl_roots:
        builder.add_pydsdl(pydsdl_roots)
    if dronecan_roots:
        builder.add_dronecan(dronecan_roots)
    builder.resolve_path_defaults()
    builder.check_references()
    builder.check_sizes()
    return {"types": {k: builder.types[k] for k in sorted(builder.types)}}


@dataclass
class _PathDefault:
    """``@default <path> <value>`` on a composite field, checked once every type is known."""

    file: str
    line: int | None
    owner: str
    field_name: str
    ref: TypeSpec
    path: str
    value: str
    target: dict[str, Any]


@dataclass
class _ModelBuilder:
    types: dict[str, TypeSpec] = field(default_factory=dict)
    path_defaults: list[_PathDefault] = field(default_factory=list)

    def _add(self, key: str, spec: TypeSpec) -> None:
        previous = self.types.get(key)
        if previous is not None:
            raise DsdlError(
                f"type {key} is defined twice (also in {previous['file']})", spec["file"], 1
            )
        self.types[key] = spec

    # ---- pydsdl --------------------------------------------------------------------------------

    def add_pydsdl(self, roots: Sequence[Root]) -> None:
        import pydsdl  # lazy: a cache hit must not pay for it

        _check_expansion(roots)
        for root in roots:
            lookup = [str(r.path) for r in roots if r is not root]
            try:
                composites = pydsdl.read_namespace(
                    str(root.path),
                    lookup,
                    # DroneCAN data type IDs do not follow Cyphal's regulated port-ID ranges.
                    allow_unregulated_fixed_port_id=True,
                )
            except pydsdl.InternalError as ex:
                raise DsdlError(_internal_error_text(ex), ex.path, ex.line) from ex
            except pydsdl.Error as ex:
                raise DsdlError(ex.text, ex.path, ex.line) from ex
            except Exception as ex:  # pydsdl bugs and I/O errors still surface as one error type
                raise DsdlError(f"pydsdl failed: {ex}", root.path) from ex
            for composite in composites:
                self._add_pydsdl_type(composite)

    def _add_pydsdl_type(self, t: pydsdl.CompositeType) -> None:
        import pydsdl

        file = str(Path(t.source_file_path).absolute())
        sections = _scan_pydsdl_source(_read_source(file))
        if isinstance(t, pydsdl.ServiceType):
            parts = [(t.request_type, 0), (t.response_type, 1)]
        else:
            parts = [(t, 0)]
        for part, index in parts:
            section = sections[index] if index < len(sections) else _Section()
            if isinstance(part, pydsdl.DelimitedType):
                line = next((n for n, name in section.directives if name == "extent"), 1)
                raise DsdlError(
                    f"{_pydsdl_key(part)} is not @sealed (delimited, @extent); px4params "
                    "serialises with the DroneCAN rules and supports only @sealed types",
                    file,
                    line,
                )
            key = _pydsdl_key(part)
            attrs = [a for a in section.attrs if a.is_field]
            if len(attrs) != len(part.fields):  # scanner out of step: give no line numbers
                attrs = [_Attr(line=None, is_field=True)] * len(part.fields)
            fields: list[dict[str, Any]] = []
            for f, attr in zip(part.fields, attrs, strict=True):
                ftype = _pydsdl_field_type(f.data_type, file, attr.line)
                if f.name == "p_version":
                    _check_version_fits(ftype, part.version.minor, key, file, attr.line)
                doc_lines = _doc_lines(f.doc, attr.doc, attr.line)
                doc = self._field_doc(doc_lines, file, key, f.name, ftype)
                fields.append({"name": f.name, "type": ftype, "line": attr.line, "doc": doc})
            header = _doc_lines(part.doc, section.header, 1)
            self._add(
                key,
                {
                    "name": part.full_name,
                    "version": [part.version.major, part.version.minor],
                    "kind": "union" if isinstance(part, pydsdl.UnionType) else "struct",
                    "dialect": "dsdl",
                    "file": file,
                    "line": 1,
                    "dtid": t.fixed_port_id,
                    "doc": _type_doc(header, file),
                    "fields": fields,
                    # Both halves of a service share one data type signature: the service's.
                    "service": t.full_name if isinstance(t, pydsdl.ServiceType) else None,
                    "signature_override": None,
                },
            )

    # ---- pydronecan ----------------------------------------------------------------------------

    def add_dronecan(self, roots: Sequence[Root]) -> None:
        parser = _dronecan_parser()
        try:
            with _silenced(f"{parser.__name__}.parser"):
                parsed = parser.parse_namespaces([str(r.path) for r in roots])
        except parser.DsdlException as ex:
            raise _dronecan_error(ex) from ex
        except Exception as ex:  # parser bugs and I/O errors still surface as one error type
            raise DsdlError(f"DroneCAN DSDL parser failed: {ex}") from ex
        for t in parsed:
            self._add_dronecan_type(t)

    def _add_dronecan_type(self, t: Any) -> None:
        file = os.path.abspath(t.source_file)
        sections = _scan_uavcan_source(t.source_text)
        if t.kind == t.KIND_SERVICE:
            parts = [
                (f"{t.full_name}.Request", t.request_fields, t.request_union, 0),
                (f"{t.full_name}.Response", t.response_fields, t.response_union, 1),
            ]
        else:
            parts = [(t.full_name, t.fields, t.union, 0)]
        for name, parsed_fields, is_union, index in parts:
            section = sections[index] if index < len(sections) else _UavcanSection()
            lines = section.fields
            if len(lines) != len(parsed_fields):
                lines = [(None, "")] * len(parsed_fields)
            fields = [
                {
                    "name": f.name or "",
                    "type": _dronecan_field_type(f.type),
                    "line": line,
                    "doc": {"short": comment, "long": "", "tags": {}},
                }
                for f, (line, comment) in zip(parsed_fields, lines, strict=True)
            ]
            short, long = _short_and_long(section.header)
            self._add(
                name,
                {
                    "name": name,
                    "version": list(t.version) if t.version else None,
                    "kind": "union" if is_union else "struct",
                    "dialect": "uavcan",
                    "file": file,
                    "line": 1,
                    "dtid": t.default_dtid,
                    # pydronecan files use free-form comments, not our @tags: text only.
                    "doc": {"short": short, "long": long, "tags": {}},
                    "fields": fields,
                    "service": t.full_name if t.kind == t.KIND_SERVICE else None,
                    # OVERRIDE_SIGNATURE 0x...: replaces the DSDL signature (not the nested
                    # types' extension of it); pydronecan's parser keeps it on the type.
                    "signature_override": getattr(t, "override_signature", None),
                },
            )

    # ---- field metadata ------------------------------------------------------------------------

    def _field_doc(
        self,
        lines: list[tuple[int | None, str]],
        file: str,
        owner: str,
        field_name: str,
        ftype: TypeSpec,
    ) -> dict[str, Any]:
        short, long, raw_tags = _split_doc(lines, file)
        tags: dict[str, Any] = {}
        kind = ftype["kind"]
        scalar = ftype["elem"] if kind in ("array", "dynarray") else ftype
        if scalar["kind"] not in _SCALAR_KINDS:
            scalar = None
        for tag in raw_tags:
            if tag.name not in _FIELD_TAGS:
                raise tag.error(f"unknown metadata tag @{tag.name} {_expected(_FIELD_TAGS)}", file)
            repeatable = tag.name in ("value", "bit") or (tag.name == "default" and kind == "ref")
            if tag.name in tags and not repeatable:
                raise tag.error(f"duplicate metadata tag @{tag.name}", file)
            if kind == "void":
                raise tag.error(f"@{tag.name}: padding fields take no metadata", file)
            try:
                if tag.name == "reboot_required":
                    tags[tag.name] = _parse_bool(tag.value)
                elif kind == "ref" and tag.name == "default":
                    self._queue_path_default(tag, file, owner, field_name, ftype, tags)
                elif scalar is None:
                    raise TagValueError(f"does not apply to a {_type_name(ftype)} field")
                else:
                    _apply_scalar_tag(tags, tag, scalar)
            except TagValueError as ex:
                raise tag.error(f"@{tag.name} {ex}", file) from None
        if scalar is not None:
            _check_bounds(tags, lines, file)
        return {"short": short, "long": long, "tags": tags}

    def _queue_path_default(
        self,
        tag: _Tag,
        file: str,
        owner: str,
        field_name: str,
        ftype: TypeSpec,
        tags: dict[str, Any],
    ) -> None:
        match = _PATH_DEFAULT_RE.fullmatch(tag.value)
        if match is None:
            raise TagValueError(
                f"on a composite field takes '<field.path> <value>' (e.g. i2c.address 0x45), "
                f"got {tag.value!r}"
            )
        target = tags.setdefault("default", {})
        if match["path"] in target:
            raise TagValueError(f"sets {match['path']} twice")
        target[match["path"]] = None  # keeps the written order; filled in by resolve_path_defaults
        self.path_defaults.append(
            _PathDefault(
                file, tag.line, owner, field_name, ftype, match["path"], match["value"], target
            )
        )

    def resolve_path_defaults(self) -> None:
        chosen: dict[tuple[str, str, str], str] = {}  # (owner, field, union path) -> variant
        for pd in self.path_defaults:
            try:
                leaf, leaf_tags = self._walk_default_path(pd, chosen)
                value = _scalar_value(leaf["type"], pd.value)
                _check_within(value, leaf_tags)
            except TagValueError as ex:
                raise DsdlError(f"@default {pd.path}: {ex}", pd.file, pd.line) from None
            pd.target[pd.path] = value

    def _walk_default_path(
        self, pd: _PathDefault, chosen: dict[tuple[str, str, str], str]
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        current: dict[str, Any] = {"type": pd.ref, "doc": {"tags": {}}}
        walked: list[str] = []
        for part in pd.path.split("."):
            if current["type"]["kind"] != "ref":
                raise TagValueError(f"'{'.'.join(walked)}' is not a composite field")
            spec = self.types.get(current["type"]["name"])
            if spec is None:
                raise TagValueError(f"unknown type {current['type']['name']}")
            names = [f["name"] for f in spec["fields"] if f["name"]]
            nxt = next((f for f in spec["fields"] if f["name"] == part), None)
            if nxt is None or not part:
                raise TagValueError(
                    f"{spec['name']} has no field '{part}' (has: {', '.join(names)})"
                )
            if part == "p_version":
                raise TagValueError("p_version is filled in by the code and takes no default")
            if spec["kind"] == "union":
                slot = (pd.owner, pd.field_name, ".".join(walked))
                if chosen.setdefault(slot, part) != part:
                    raise TagValueError(
                        f"selects union variant '{part}' but another @default selects "
                        f"'{chosen[slot]}'"
                    )
            walked.append(part)
            current = nxt
        if current["type"]["kind"] not in _SCALAR_KINDS:
            raise TagValueError(f"'{pd.path}' is not a scalar field")
        return current, current["doc"]["tags"]

    def check_references(self) -> None:
        for key, spec in self.types.items():
            for f in spec["fields"]:
                ref = _innermost(f["type"])
                if ref["kind"] == "ref" and ref["name"] not in self.types:
                    raise DsdlError(
                        f"{key}.{f['name']} refers to unknown type {ref['name']}",
                        spec["file"],
                        f["line"],
                    )

    def check_sizes(self) -> None:
        """Refuses a type whose largest value exceeds :data:`MAX_TYPE_BYTES`, before anything is
        sized by it (the codec reserves buffers and unrolls fixed arrays by the maximum)."""
        memo: dict[str, int] = {}

        def bits(spec: TypeSpec) -> int:
            kind = spec["kind"]
            if kind == "ref":
                return type_bits(spec["name"])
            if kind == "array":
                return int(spec["len"]) * bits(spec["elem"])
            if kind == "dynarray":
                return length_bits(int(spec["max"])) + int(spec["max"]) * bits(spec["elem"])
            return 1 if kind == "bool" else int(spec.get("bits", 0))

        def type_bits(key: str) -> int:
            if key not in memo:
                memo[key] = 0  # a cycle (refused elsewhere) must not recurse forever
                fields = [bits(f["type"]) for f in self.types[key]["fields"]]
                if self.types[key]["kind"] == "union":
                    memo[key] = tag_bits(len(fields)) + max(fields, default=0)
                else:
                    memo[key] = sum(fields)
            return memo[key]

        for key, spec in self.types.items():
            size = type_bits(key)
            if size > MAX_TYPE_BYTES * 8:
                raise DsdlError(
                    f"{key}: its largest value has {size:,} bits ({-(-size // 8):,} bytes); "
                    f"types are limited to {MAX_TYPE_BYTES:,} bytes",
                    spec["file"],
                    spec["line"],
                )


#: Fields of a type counted through every type it uses, at most: far beyond real types (the
#: bundled ones have fewer than 100), far below what makes pydsdl, which walks the same
#: structure again for every use of a type, take seconds.
MAX_EXPANDED_FIELDS = 20_000
_FIELD_LINE = re.compile(r"\s*(?P<type>[A-Za-z_][\w.]*)(?:\[[^\]]*\])?\s+[A-Za-z_]\w*\s*(?:#.*)?$")


def _check_expansion(roots: Sequence[Root]) -> None:
    """Refuses, before pydsdl reads them, types that use each other so many times over that
    pydsdl would take minutes (it recomputes a type's properties for every use): a cheap
    reading of the field lines, counting each type's fields through every type it uses."""
    uses: dict[str, list[str]] = {}
    files: dict[str, str] = {}
    for root in roots:
        namespace = os.path.basename(os.path.normpath(str(root.path)))
        for file in root.files:
            stem = os.path.basename(file).removesuffix(".dsdl")
            key = f"{namespace}.{stem}"
            try:
                lines = read_text(file, DSDL).splitlines()
            except (OSError, UnicodeDecodeError):
                continue  # pydsdl reports it
            fields = []
            for line in lines:
                match = _FIELD_LINE.match(line)
                if match and not match["type"].startswith(("uint", "int", "float", "bool", "void")):
                    ref = match["type"]
                    fields.append(ref if ref.count(".") > 2 else f"{namespace}.{ref}")
                elif match:
                    fields.append("")
            uses[key], files[key] = fields, file
    memo: dict[str, int] = {}
    for start in sorted(uses):  # depth first without recursion: chains may be thousands long
        stack = [start]
        while stack:
            key = stack[-1]
            pending = [r for r in uses[key] if r in uses and r not in memo and r not in stack]
            if pending:
                stack.extend(pending[:1])
                continue
            stack.pop()
            total = sum(1 + memo.get(r, 0) for r in uses[key])  # a cycle counts once
            memo[key] = min(total, 10 * MAX_EXPANDED_FIELDS)
    for key in sorted(uses):
        count = memo[key]
        if count > MAX_EXPANDED_FIELDS:
            raise DsdlError(
                f"{key} uses its types so many times over ({count:,} fields counted through "
                f"every use; at most {MAX_EXPANDED_FIELDS:,}): pydsdl would take seconds to "
                "minutes to read it",
                files[key],
            )


def _internal_error_text(ex: Exception) -> str:
    """What is wrong with the user's file, for an error pydsdl calls its own (it asks users to
    report it to pydsdl, which does not help them)."""
    cause = ex.__cause__ or ex.__context__
    if isinstance(cause, UnicodeDecodeError):
        return not_text(cause)
    if isinstance(cause, RecursionError):
        return (
            "types nest too deeply to read (a chain of hundreds of types referring to each other)"
        )
    text = str(getattr(ex, "text", "") or "").split("PLEASE REPORT AT")[0].strip()
    what = f"{type(cause).__name__}: {cause}" if cause is not None else text or "unknown"
    return f"pydsdl cannot read this definition ({what})"


# --------------------------------------------------------------------------------------------------
# Field types


def _pydsdl_key(t: pydsdl.CompositeType) -> str:
    return f"{t.full_name}.{t.version.major}.{t.version.minor}"


def _pydsdl_field_type(dt: pydsdl.SerializableType, file: str, line: int | None) -> TypeSpec:
    import pydsdl

    def cast(p: pydsdl.PrimitiveType) -> str:
        return (
            "truncated" if p.cast_mode == pydsdl.PrimitiveType.CastMode.TRUNCATED else "saturated"
        )

    if isinstance(dt, pydsdl.BooleanType):
        return {"kind": "bool"}
    if isinstance(dt, pydsdl.VoidType):
        return {"kind": "void", "bits": dt.bit_length}
    if isinstance(dt, pydsdl.FloatType):
        return {"kind": "float", "bits": dt.bit_length, "cast": cast(dt)}
    if isinstance(dt, pydsdl.SignedIntegerType):
        return {"kind": "int", "bits": dt.bit_length, "cast": cast(dt)}
    if isinstance(dt, pydsdl.UnsignedIntegerType):  # also byte and utf8 (8 bits)
        return {"kind": "uint", "bits": dt.bit_length, "cast": cast(dt)}
    if isinstance(dt, pydsdl.FixedLengthArrayType):
        return {
            "kind": "array",
            "elem": _pydsdl_field_type(dt.element_type, file, line),
            "len": dt.capacity,
        }
    if isinstance(dt, pydsdl.VariableLengthArrayType):
        elem = _pydsdl_field_type(dt.element_type, file, line)
        return {"kind": "dynarray", "elem": elem, "max": dt.capacity}
    if isinstance(dt, pydsdl.DelimitedType):
        raise DsdlError(
            f"{_pydsdl_key(dt)} is not @sealed; px4params supports only @sealed types", file, line
        )
    if isinstance(dt, pydsdl.CompositeType):
        return {"kind": "ref", "name": _pydsdl_key(dt)}
    raise DsdlError(f"unsupported data type {dt}", file, line)


def _dronecan_field_type(dt: Any) -> TypeSpec:
    if dt.category == dt.CATEGORY_PRIMITIVE:
        if dt.kind == dt.KIND_BOOLEAN:
            # The cast mode of a bool changes nothing but its signature; kept only if unusual.
            if dt.cast_mode == dt.CAST_MODE_TRUNCATED:
                return {"kind": "bool", "cast": "truncated"}
            return {"kind": "bool"}
        kind = {dt.KIND_UNSIGNED_INT: "uint", dt.KIND_SIGNED_INT: "int", dt.KIND_FLOAT: "float"}[
            dt.kind
        ]
        cast = "truncated" if dt.cast_mode == dt.CAST_MODE_TRUNCATED else "saturated"
        return {"kind": kind, "bits": dt.bitlen, "cast": cast}
    if dt.category == dt.CATEGORY_VOID:
        return {"kind": "void", "bits": dt.bitlen}
    if dt.category == dt.CATEGORY_ARRAY:
        elem = _dronecan_field_type(dt.value_type)
        if dt.mode == dt.MODE_STATIC:
            return {"kind": "array", "elem": elem, "len": dt.max_size}
        return {"kind": "dynarray", "elem": elem, "max": dt.max_size}  # [<N] is already N-1
    return {"kind": "ref", "name": dt.full_name}


def _innermost(t: TypeSpec) -> TypeSpec:
    while t["kind"] in ("array", "dynarray"):
        t = t["elem"]
    return t


def _check_version_fits(
    ftype: dict[str, Any], minor: int, key: str, file: str, line: int | None
) -> None:
    """``p_version`` holds the type's minor version, which the codec writes: refused where the
    field cannot hold it (firmware's walk would write it cut to the field's bits)."""
    kind, bits = ftype["kind"], ftype.get("bits", 0)
    if kind not in ("uint", "int"):
        return
    top = (1 << bits) - 1 if kind == "uint" else (1 << (bits - 1)) - 1
    if minor > top:
        raise DsdlError(
            f"{key}: p_version is {kind}{bits}, which cannot hold the type's minor version "
            f"{minor} (expected 0 to {top}: a wider p_version, or a lower minor version)",
            file,
            line,
        )


def _type_name(t: TypeSpec) -> str:
    kind: str = t["kind"]
    if kind in ("uint", "int", "float", "void"):
        return f"{kind}{t['bits']}"
    if kind == "array":
        return f"{_type_name(t['elem'])}[{t['len']}]"
    if kind == "dynarray":
        return f"{_type_name(t['elem'])}[<={t['max']}]"
    if kind == "ref":
        return str(t["name"])
    return kind


# --------------------------------------------------------------------------------------------------
# pydronecan's parser, without importing the dronecan package


def _dronecan_parser() -> types.ModuleType:
    """Return pydronecan's ``dronecan.dsdl`` package, or a private copy of it.

    ``import dronecan.dsdl`` runs ``dronecan/__init__.py``, which parses every bundled
    definition (a noticeable delay) only to be thrown away here. So unless dronecan is already
    imported, the parser package is loaded from its files under a private module name.
    """
    loaded = sys.modules.get("dronecan.dsdl")
    if loaded is not None:
        return loaded
    private = sys.modules.get(_PRIVATE_DRONECAN_DSDL)
    if private is not None:
        return private

    folder = Path(dronecan_package_dir()) / "dsdl"
    spec = importlib.util.spec_from_file_location(
        _PRIVATE_DRONECAN_DSDL, folder / "__init__.py", submodule_search_locations=[str(folder)]
    )
    if spec is None or spec.loader is None:
        raise DsdlError("cannot load pydronecan's DSDL parser", folder)
    module = importlib.util.module_from_spec(spec)

    # dsdl/common.py does `from dronecan import UAVCANException`, its only link to the package.
    # A stand-in satisfies it; it is visible only while the parser modules execute.
    stand_in = None
    if "dronecan" not in sys.modules:
        stand_in = types.ModuleType("dronecan")
        # (a module made here: mypy knows no attributes of it)
        stand_in.UAVCANException = type("UAVCANException", (Exception,), {})  # type: ignore[attr-defined]
        sys.modules["dronecan"] = stand_in
    sys.modules[_PRIVATE_DRONECAN_DSDL] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        for name in [n for n in sys.modules if n.partition(".")[0] == _PRIVATE_DRONECAN_DSDL]:
            del sys.modules[name]
        raise
    finally:
        if stand_in is not None and sys.modules.get("dronecan") is stand_in:
            del sys.modules["dronecan"]
    # The private copy's log is ours alone; its parse() logs every syntax error as an
    # "Internal error" with a traceback, which we report as a DsdlError instead.
    logging.getLogger(f"{_PRIVATE_DRONECAN_DSDL}.parser").disabled = True
    return module


@contextlib.contextmanager
def _silenced(logger_name: str) -> Iterator[None]:
    logger = logging.getLogger(logger_name)
    previous = logger.disabled
    logger.disabled = True
    try:
        yield
    finally:
        logger.disabled = previous


def _dronecan_error(ex: BaseException) -> DsdlError:
    # parse() re-wraps each error as "Internal error: <file:line: text>" without a line, and an
    # error in a nested type gets the referencing line. The innermost DsdlException in the
    # __context__ chain is the original, with the right file and line.
    chain: list[Any] = []
    seen: set[int] = set()
    current: BaseException | None = ex
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        if type(current).__name__ == "DsdlException":
            chain.append(current)
        current = current.__context__
    origin = chain[-1] if chain else ex
    file = next((c.file for c in reversed(chain) if getattr(c, "file", None)), None)
    message = str(origin.args[0]) if origin.args else str(origin)
    return DsdlError(message, file, getattr(origin, "line", None))


# --------------------------------------------------------------------------------------------------
# Source scanning (line numbers; pydsdl and pydronecan keep none for fields or comments)


@dataclass
class _Attr:
    line: int | None
    is_field: bool
    doc: list[tuple[int, str]] = field(default_factory=list)


@dataclass
class _Section:
    header: list[tuple[int, str]] = field(default_factory=list)
    attrs: list[_Attr] = field(default_factory=list)
    directives: list[tuple[int, str]] = field(default_factory=list)


def _read_source(file: str) -> str:
    try:
        return read_text(file, DSDL, errors="replace")
    except OSError:
        return ""  # only line numbers are lost


def _split_comment(line: str) -> tuple[str, str | None]:
    """Split a DSDL line into statement and ``#`` comment, ignoring ``#`` in string literals."""
    quote = None
    i = 0
    while i < len(line):
        ch = line[i]
        if quote is not None:
            if ch == "\\":
                i += 1
            elif ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch == "#":
            return line[:i], line[i:]
        i += 1
    return line, None


def _scan_pydsdl_source(text: str) -> list[_Section]:
    """Mirror pydsdl's comment attribution (see the module docstring), with line numbers."""
    sections = [_Section()]
    pending: list[tuple[int, str]] = []
    is_header = True
    queued: _Attr | None = None

    def flush() -> None:
        nonlocal pending, is_header, queued
        if is_header:
            sections[-1].header = pending
        elif queued is not None:
            queued.doc = pending
            queued = None
        is_header = False
        pending = []

    for number, raw in enumerate(text.split("\n"), start=1):
        line = raw[:-1] if raw.endswith("\r") else raw
        if line == "":  # only a truly empty line ends a comment block
            flush()
            continue
        statement, comment = _split_comment(line)
        statement = statement.strip()
        if statement:
            flush()
            if re.fullmatch(r"-{3,}", statement):
                sections.append(_Section())
                is_header = True
            elif statement.startswith("@"):
                name = re.match(r"@\s*([A-Za-z_]\w*)", statement)
                sections[-1].directives.append((number, name[1] if name else ""))
            else:
                # "T name = value" is a constant; "=" inside "[<=N]" is not.
                is_constant = "=" in re.sub(r"\[[^\]]*\]", "", statement)
                queued = _Attr(line=number, is_field=not is_constant)
                sections[-1].attrs.append(queued)
        if comment is not None:
            pending.append((number, comment[2:] if comment.startswith("# ") else comment[1:]))
    flush()
    return sections


@dataclass
class _UavcanSection:
    header: list[str] = field(default_factory=list)
    fields: list[tuple[int | None, str]] = field(default_factory=list)  # (line, trailing comment)


def _scan_uavcan_source(text: str) -> list[_UavcanSection]:
    """Find field lines the way pydronecan tokenizes, plus the leading comment block."""
    sections = [_UavcanSection()]
    header_open = True
    for number, raw in enumerate(text.splitlines(), start=1):
        code, hash_, comment = raw.partition("#")
        tokens = code.split()
        if not tokens:
            if header_open and hash_:
                sections[-1].header.append(comment[1:] if comment.startswith(" ") else comment)
            elif header_open and sections[-1].header:
                header_open = False  # an empty line ends the leading comment block
            continue
        header_open = False
        if tokens == ["---"]:
            sections.append(_UavcanSection())
            header_open = True
        elif tokens == ["@union"] or tokens[0] == "OVERRIDE_SIGNATURE" or "=" in tokens:
            continue  # directive or constant
        else:
            sections[-1].fields.append((number, comment.strip()))
    return sections


def _doc_lines(
    doc: str, scanned: list[tuple[int, str]], fallback: int | None
) -> list[tuple[int | None, str]]:
    lines = doc.split("\n") if doc else []
    if [text for _, text in scanned] == lines:
        return list(scanned)
    return [(fallback, text) for text in lines]  # scanner out of step: report the attribute line


# --------------------------------------------------------------------------------------------------
# Metadata


@dataclass
class _Tag:
    name: str
    value: str
    line: int | None

    def error(self, message: str, file: str) -> DsdlError:
        return DsdlError(message, file, self.line)


_TAG_RE = re.compile(r"@(\w*)(?:\s+(.*))?")
_PATH_DEFAULT_RE = re.compile(r"(?P<path>[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)\s+(?P<value>\S+)")
_INT_RE = re.compile(r"[+-]?(?:0[xX][0-9a-fA-F]+|[0-9]+)")
#: Instances of one parameter at most: far beyond any vehicle (PX4 publishes at most 10 of a
#: sensor), small enough that the store's memory stays reserved up front.
MAX_INSTANCES = 256
#: The largest value of a type may take at most this many bytes (what a store slot holds, 170
#: times DroneCAN's largest standard message), so that a hostile type cannot make the codec
#: reserve gigabytes.
MAX_TYPE_BYTES = 65535
_FLOAT_RE = re.compile(r"[+-]?(?:[0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)(?:[eE][+-]?[0-9]+)?")
_PARAM_NAME_RE = re.compile(r"[A-Z][A-Z0-9_]*")
_CATEGORIES = ("Standard", "Developer", "System")  # the values QGC knows


def _expected(names: Sequence[str] | dict[str, Any]) -> str:
    return f"(expected one of: {', '.join('@' + n for n in sorted(names))})"


def _split_doc(lines: list[tuple[int | None, str]], file: str) -> tuple[str, str, list[_Tag]]:
    text: list[str] = []
    tags: list[_Tag] = []
    for number, raw in lines:
        stripped = raw.strip()
        if stripped.startswith("@"):
            match = _TAG_RE.fullmatch(stripped)
            if match is None or not match[1]:
                raise DsdlError(f"malformed metadata tag {stripped!r}", file, number)
            tags.append(_Tag(match[1], (match[2] or "").strip(), number))
        elif tags:
            if stripped:  # text after the tags would silently belong to nothing
                raise DsdlError(
                    f"description text after the metadata tags: {stripped!r} "
                    "(write the description before the @tags)",
                    file,
                    number,
                )
        else:
            text.append(raw.rstrip())
    short, long = _short_and_long(text)
    return short, long, tags


def _short_and_long(text: list[str]) -> tuple[str, str]:
    lines = list(text)
    while lines and not lines[0].strip():
        lines.pop(0)
    if not lines:
        return "", ""
    short = lines.pop(0).strip()
    while lines and not lines[0].strip():
        lines.pop(0)
    while lines and not lines[-1].strip():
        lines.pop()
    return short, "\n".join(line.rstrip() for line in lines)


def _parse_bool(text: str) -> bool:
    if text == "true":
        return True
    if text == "false":
        return False
    raise TagValueError(f"expects true or false, got {text!r}")


def _parse_number(text: str) -> int | float:
    try:
        if _INT_RE.fullmatch(text):
            return parse_int(text, 16 if "x" in text[:3].lower() else 10)
        if _FLOAT_RE.fullmatch(text):
            value = parse_float(text)
            if math.isfinite(value):
                return value
    except NumberError as e:
        raise TagValueError(str(e)) from None
    raise TagValueError(f"expects a number (69, 0x45, -1, 0.0003, 1e-3), got {text!r}")


def _parse_int(text: str, minimum: int, maximum: int | None = None) -> int:
    value = _parse_number(text) if _INT_RE.fullmatch(text) else None
    if not isinstance(value, int) or value < minimum or (maximum is not None and value > maximum):
        expected = f"{minimum}..{maximum}" if maximum is not None else f">= {minimum}"
        raise TagValueError(f"expects an integer {expected}, got '{abbreviated(text)}'")
    return value


def _parse_text(text: str) -> str:
    if not text:
        raise TagValueError("expects a value")
    return text


def _parse_category(text: str) -> str:
    if text not in _CATEGORIES:
        raise TagValueError(f"expects one of {', '.join(_CATEGORIES)}, got {text!r}")
    return text


def _parse_param_name(text: str) -> str:
    if not _PARAM_NAME_RE.fullmatch(text) or len(text) > 16:
        raise TagValueError(
            f"expects an upper-case parameter name of at most 16 characters, got {text!r}"
        )
    return text


_TYPE_TAGS: dict[str, Callable[[str], Any]] = {
    "group": _parse_text,
    "category": _parse_category,
    "max_instances": lambda text: _parse_int(text, 1, MAX_INSTANCES),
    "reboot_required": _parse_bool,
    "param": _parse_param_name,
}

_FIELD_TAGS = (
    "unit",
    "default",
    "min",
    "max",
    "decimal",
    "increment",
    "value",
    "values",
    "bit",
    "reboot_required",
    "format",
)


def _type_doc(lines: list[tuple[int | None, str]], file: str) -> dict[str, Any]:
    short, long, raw_tags = _split_doc(lines, file)
    tags: dict[str, Any] = {}
    for tag in raw_tags:
        parse = _TYPE_TAGS.get(tag.name)
        if parse is None:
            raise tag.error(f"unknown metadata tag @{tag.name} {_expected(_TYPE_TAGS)}", file)
        if tag.name in tags:
            raise tag.error(f"duplicate metadata tag @{tag.name}", file)
        try:
            tags[tag.name] = parse(tag.value)
        except TagValueError as ex:
            raise tag.error(f"@{tag.name} {ex}", file) from None
    return {"short": short, "long": long, "tags": tags}


def _int_range(t: TypeSpec) -> tuple[int, int]:
    bits = t["bits"]
    if t["kind"] == "uint":
        return 0, (1 << bits) - 1
    return -(1 << (bits - 1)), (1 << (bits - 1)) - 1


def _scalar_value(t: TypeSpec, text: str) -> int | float | bool:
    """Parse a value of scalar type ``t`` and check that the type can hold it."""
    kind = t["kind"]
    if kind == "bool":
        return _parse_bool(text)
    if kind not in ("uint", "int", "float"):
        raise TagValueError(f"does not apply to a {_type_name(t)} field")
    number = _parse_number(text)
    if kind == "float":
        value = float(number)
        if abs(value) > FLOAT_MAX[t["bits"]]:
            raise TagValueError(f"{text} does not fit {_type_name(t)}")
        return value
    if not isinstance(number, int):
        raise TagValueError(f"expects an integer for {_type_name(t)}, got {text!r}")
    low, high = _int_range(t)
    if not low <= number <= high:
        raise TagValueError(f"{text} is out of range for {_type_name(t)} ({low}..{high})")
    return number


def _apply_scalar_tag(tags: dict[str, Any], tag: _Tag, scalar: TypeSpec) -> None:
    name, text = tag.name, tag.value
    numeric = scalar["kind"] != "bool"
    if name == "default":
        tags[name] = _scalar_value(scalar, text)
        return
    if not numeric:
        raise TagValueError("does not apply to a bool field")
    if name == "unit":
        tags[name] = _parse_text(text)
    elif name == "format":
        # how ground stations show the number: "hex" for addresses, as datasheets write them
        if text != "hex" or scalar["kind"] == "float":
            raise TagValueError(f"expects hex on an integer field, got {text!r}")
        tags[name] = text
    elif name in ("min", "max"):
        tags[name] = _scalar_value(scalar, text)
    elif name == "decimal":
        tags[name] = _parse_int(text, 0)
    elif name == "increment":
        value = _scalar_value(scalar, text)
        if value <= 0:
            raise TagValueError(f"expects a positive number, got {text!r}")
        tags[name] = value
    elif name == "values":
        entries = tags.setdefault("value", [])
        for number_text, description in value_set(text).items():
            number = _scalar_value(scalar, number_text)
            if any(existing == number for existing, _ in entries):
                raise TagValueError(f"{text}: lists {number_text} twice")
            entries.append([number, description])
    elif name in ("value", "bit"):
        match = re.fullmatch(r"(\S+)\s+(.+)", text)
        if match is None:
            raise TagValueError(f"expects '<number> <description>', got {text!r}")
        if name == "value":
            number = _scalar_value(scalar, match[1])
        else:
            if scalar["kind"] == "float":
                raise TagValueError("does not apply to a float field")
            number = _parse_int(match[1], 0)
            if number >= scalar["bits"]:
                raise TagValueError(f"bit {number} does not exist in {_type_name(scalar)}")
        entries = tags.setdefault(name, [])
        if any(existing == number for existing, _ in entries):
            raise TagValueError(f"lists {match[1]} twice")
        entries.append([number, match[2].strip()])


_value_sets: dict[str, dict[str, str]] = {}


def value_set(name: str) -> dict[str, str]:
    """The value list ``name`` of ``data/value_sets.toml`` (``@values rotation``)."""
    if not _value_sets:
        with open(VALUE_SETS_TOML, "rb") as f:
            _value_sets.update(tomllib.load(f))
    found = _value_sets.get(name.strip())
    if found is None:
        known = ", ".join(sorted(_value_sets))
        raise TagValueError(f"names no value list {name.strip()!r} (expected one of: {known})")
    return found


def _check_within(value: int | float | bool, tags: dict[str, Any]) -> None:
    if isinstance(value, bool):
        return
    low, high = tags.get("min"), tags.get("max")
    if low is not None and value < low:
        raise TagValueError(f"{value} is below the field's @min {low}")
    if high is not None and value > high:
        raise TagValueError(f"{value} is above the field's @max {high}")


def _check_bounds(tags: dict[str, Any], lines: list[tuple[int | None, str]], file: str) -> None:
    def line_of(name: str) -> int | None:
        return next((n for n, text in lines if text.strip().startswith(f"@{name}")), None)

    low, high = tags.get("min"), tags.get("max")
    if low is not None and high is not None and low > high:
        raise DsdlError(f"@min {low} is greater than @max {high}", file, line_of("max"))
    if "default" in tags:
        try:
            _check_within(tags["default"], tags)
        except TagValueError as ex:
            raise DsdlError(f"@default {ex}", file, line_of("default")) from None
