"""Parameter files and the page: a QGC ``.params`` file, an airframe file or a px4params JSON
export read into a *review* (what would change, parameter by parameter, against the vehicle's
values), and the vehicle's configuration written out as ``.params`` or as an airframe file.

The vehicle is seen as a ground station sees it, by flat names; an airframe or JSON file needs
the structured view, so they are applied to a scratch store set to the vehicle's values (with
the bundled types, or the offline store's), and the store's flat view compared."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Mapping
from typing import Any

from px4params.errors import CommandError, Px4ParamsError
from px4params.formats import qgc_params
from px4params.gcs.metadata import QGC_TYPE, destructured_names
from px4params.numbers import abbreviated
from px4params.store.classic import ClassicParam

__all__ = ["export_airframe", "export_params", "review_file"]

#: Order in which changes are written: instance masks first (they make instances), then union
#: tags and array lengths (they make leaves live), then the rest.
_FIRST, _SECOND = "_INST", ("A",)


def review_file(
    filename: str,
    text: str,
    values: Mapping[str, Any],
    metadata: Mapping[str, Any],
    store: Any = None,
) -> dict[str, Any]:
    """The changes ``text`` (a ``.params``, airframe or JSON file named ``filename``) would make
    to ``values``: ``{"changes": [{"name", "current", "new"}], "notes": [...]}``."""
    kind = os.path.splitext(filename)[1].lower()
    # The page's name for the file, as messages show it (a NUL, an escape: written out).
    if not filename.isprintable() or len(filename) > 255:
        filename = abbreviated(filename)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as e:  # JSON's "\ud800": no text a file can hold
        raise CommandError(
            f"{filename}: not text: a lone surrogate (U+{ord(text[e.start]):04X}) at character "
            f"{e.start}"
        ) from None
    if kind == ".params":
        new, notes = _read_params(filename, text, values)
    else:
        scratch = _scratch_store(values, metadata, store)
        if kind == ".json":
            with tempfile.TemporaryDirectory() as tmp:
                path = _scratch_copy(tmp, "review.json", text)
                from px4params.store import paramfile

                try:
                    notes = paramfile.read(scratch, path, reset=False)
                except Px4ParamsError as e:  # named as the page named the file, not the copy
                    raise CommandError(str(e).replace(path, filename)) from None
        else:  # an airframe file of param lines
            notes = _run_airframe(scratch, filename, text)
        from px4params.store.flat import flat_values

        new = flat_values(scratch)
    changes = [
        {"name": name, "current": values.get(name), "new": value}
        for name, value in new.items()
        if values.get(name) != value
    ]
    changes.sort(key=_write_order)
    return {"changes": changes, "notes": notes}


def _write_order(change: Mapping[str, Any]) -> tuple[int, str]:
    name = str(change["name"])
    if name.endswith(_FIRST):
        return 0, name
    if name[-1:] in _SECOND and name[:-1][-1:].isdigit():
        return 1, name
    return 2, name


def _read_params(
    filename: str, text: str, values: Mapping[str, Any]
) -> tuple[dict[str, Any], list[str]]:
    new: dict[str, Any] = {}
    notes: list[str] = []
    autopilot = qgc_params.autopilot_rows(qgc_params.read(text, filename), filename)
    notes += autopilot.skipped(filename)
    for row in autopilot.rows:
        if row.name not in values:
            notes.append(
                f"{filename}:{row.line}: {row.name}: the vehicle has no such parameter; skipped"
            )
            continue
        new[row.name] = row.value
    return new, notes


def _classic_of(metadata: Mapping[str, Any]) -> list[ClassicParam]:
    """The classic parameters of a metadata document: Int32/Float entries that are not a
    structured parameter's destructured names or instance mask (``INA238_CURRENT`` is
    classic, ``INA238_1C`` is not)."""
    destructured = set().union(
        *(destructured_names(e) for e in metadata["parameters"] if e.get("type") == QGC_TYPE)
    )
    found = []
    for entry in metadata["parameters"]:
        if entry.get("type") not in ("Int32", "Float"):
            continue
        if entry["name"] in destructured:
            continue
        default = entry.get("default", 0)
        found.append(
            ClassicParam(
                entry["name"],
                entry["type"],
                default if isinstance(default, int | float) else 0,
                entry,
            )
        )
    return found


def _scratch_store(values: Mapping[str, Any], metadata: Mapping[str, Any], store: Any) -> Any:
    """A store with the vehicle's values (a copy of the offline store, or the bundled types and
    the metadata's classic parameters set to what the vehicle reports)."""
    import px4params
    from px4params.store.flat import write_flat

    if store is not None:
        scratch = px4params.Store(
            store.schema, classic=[c for c in map(store.classic, store.parameters) if c]
        )
    else:
        scratch = px4params.Store(
            px4params.load_schema(include_dronecan=False), classic=_classic_of(metadata)
        )
    for name, value in sorted(values.items(), key=lambda kv: _write_order({"name": kv[0]})):
        with contextlib.suppress(Px4ParamsError):  # one this side does not know: its default
            write_flat(scratch, name, value)
    return scratch


def _run_airframe(scratch: Any, filename: str, text: str) -> list[str]:
    import io

    from px4params.nsh.airframe import run_file
    from px4params.store.session import Session

    with tempfile.TemporaryDirectory() as tmp:
        path = _scratch_copy(tmp, "review.airframe", text)
        session = Session(scratch, os.path.join(tmp, "scratch.store"), io.StringIO())
        errors = io.StringIO()
        # A page's file touches nothing on this computer but the scratch store: its lines
        # that would save, export, load or import another file are passed over, and said.
        result = run_file(path, session, keep_going=False, err=errors, files=False)
        if result.errors:
            raise CommandError(" ".join(e.replace(path, filename) for e in result.errors))
    return [line.replace(path, filename) for line in result.skipped]


def _scratch_copy(folder: str, name: str, text: str) -> str:
    """``text`` written in ``folder`` as ``name``; its path. The page's name for the file is
    only shown: as the copy's name, '..', a NUL or 300 characters made the write fail (500)."""
    path = os.path.join(folder, name)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def export_params(values: Mapping[str, Any], metadata: Mapping[str, Any], store: Any = None) -> str:
    """The vehicle's configuration as a QGC ``.params`` file."""
    from px4params.store.paramfile import export_qgc

    return export_qgc(_scratch_store(values, metadata, store))


def export_airframe(
    values: Mapping[str, Any], metadata: Mapping[str, Any], store: Any = None
) -> str:
    """The vehicle's configuration as an airframe file: ``param add`` and ``param set-default``
    lines per instance leaf (defaults the pilot may change, as airframes set them), and the
    classic parameters that differ from their defaults."""
    scratch = _scratch_store(values, metadata, store)
    lines = ["# Airframe written by px4params gui", ""]
    for spec in scratch.specs:
        for instance in scratch.instances(spec.name):
            if not spec.shared:
                lines.append(f"param add {instance}")
            for leaf in scratch.leaves(instance):
                if leaf.path.endswith("p_version") or leaf.type == "tail":
                    continue
                value = leaf.value
                shown = repr(float(value)) if isinstance(value, float) else str(int(value))
                lines.append(f"param set-default {instance}[{leaf.index}] {shown}")
            lines.append("")
    for name in scratch.parameters:
        classic = scratch.classic(name)
        if classic is not None and scratch.changed(name):
            lines.append(f"param set-default {name} {scratch.get(name)}")
    return "\n".join(lines).rstrip() + "\n"
