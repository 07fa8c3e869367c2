"""A store's memory plan and its types' compiled layouts as plain data, for tables that
firmware keeps in ``const`` memory (``px4params.gcs.firmware`` writes them as C)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from px4params import _native
from px4params.dsdl.schema import Schema
from px4params.store.spec import ParamSpec


def layout_tables(
    schema: Schema,
    specs: Sequence[ParamSpec],
    type_defaults: Sequence[bytes],
    extra_keys: Sequence[str] = (),
) -> dict[str, Any]:
    """The core's tables for a store of ``specs`` (with their type defaults) whose layout
    holds only the types they use, plus ``extra_keys`` (older versions): ``nodes``, ``fields``,
    ``names``, ``segments``, ``flat``, ``defs``, ``capacity`` and ``roots`` (extra key: root
    node), as ``_native.Store.tables`` gives them."""
    closure = schema._closure([s.data_type.key for s in specs] + list(extra_keys))
    rows = [(s.name, s.data_type.key, s.max_instances) for s in specs]
    store = _native.Store(_native.Schema(closure), rows)
    for index, default in enumerate(type_defaults):
        store.set_type_default(index, default)
    return store.tables(list(extra_keys))
