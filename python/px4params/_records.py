"""``NamedTuple`` without importing :mod:`typing` at run time.

Importing ``typing`` costs a short command about 5 ms (a third of a bare interpreter's start),
and the modules a ``px4params param show`` or ``decode`` runs need nothing from it but
``NamedTuple``. Those modules import this one at run time and ``typing`` only for type checkers::

    from px4params._records import TYPE_CHECKING

    if TYPE_CHECKING:
        from typing import Any, NamedTuple
    else:
        from px4params._records import NamedTuple

The class statement builds what ``typing.NamedTuple`` builds: a ``collections.namedtuple``
with the annotated fields (trailing ones may have defaults) and the body's methods, properties
and docstring set on it. ``tests/test_layout.py`` checks that those commands do not import
``typing``.
"""

from __future__ import annotations

import collections

__all__ = ["TYPE_CHECKING", "NamedTuple"]

#: False at run time; type checkers take any name ``TYPE_CHECKING`` as true.
TYPE_CHECKING = False

_SKIPPED = frozenset({"__module__", "__qualname__", "__annotations__", "__dict__", "__weakref__"})


class _NamedTupleMeta(type):
    def __new__(mcls, name: str, bases: tuple[type, ...], namespace: dict[str, object]) -> type:
        if namespace.get("_is_the_base"):
            return super().__new__(mcls, name, bases, namespace)
        annotations = namespace.get("__annotations__")
        fields = list(annotations) if isinstance(annotations, dict) else []
        defaults = [namespace[f] for f in fields if f in namespace]
        with_default = [f for f in fields if f in namespace]
        if with_default != fields[len(fields) - len(with_default) :]:
            raise TypeError(f"{name}: fields without a default cannot follow fields with one")
        # (mypy reads namedtuple() as a class statement, which needs literal names and defaults)
        record = collections.namedtuple(  # type: ignore[misc]
            name,
            fields,
            defaults=defaults or None,  # type: ignore[misc]
            module=str(namespace.get("__module__")),
        )
        record.__qualname__ = str(namespace.get("__qualname__", name))
        for key, value in namespace.items():
            if key not in _SKIPPED and key not in fields:
                setattr(record, key, value)
        return record


class NamedTuple(metaclass=_NamedTupleMeta):
    """Base class of records (see the module doc)."""

    _is_the_base = True
