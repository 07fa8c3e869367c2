"""The schema model, typed: what a type's and a field's doc comments declare (``@min``,
``@unit``, ``@max_instances`` ...), read once per type into named values.

:mod:`px4params.dsdl.loader` parses the doc comments' text into the JSON-shaped model the cache
keeps and the core compiles (the ``TypeDict`` shape below). The layers above read a type through
:func:`type_def` instead: a :class:`TypeDef` with its :class:`TypeDoc` and :class:`Field`\\ s, each
field's tags a :class:`FieldDoc` (``field.doc.minimum``, ``field.doc.unit``,
``field.doc.display_format``). Each tag is read by one function of this module
(:data:`_FIELD_TAGS`, :data:`_TYPE_TAGS`); a model whose tag has the wrong shape (a hand-built
schema, an edited cache) is refused with one line naming the type, the field and the tag.

The records are small read-only classes (``dataclasses``, ``typing`` and named tuples cost a
short command their making); a type's doc and fields are read when first asked for, each once,
and so is a field's doc (its ``@default`` alone while only that is asked for: a store's defaults).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, MutableMapping

from px4params._records import TYPE_CHECKING
from px4params.errors import DsdlError, TagValueError

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, TypedDict

    class TypeSpec(TypedDict, total=False):
        """A field's type as the model holds it: ``kind`` (``uint``, ``int``, ``float``,
        ``bool``, ``void``, ``array``, ``dynarray``, ``ref``) and what that kind needs."""

        kind: str
        bits: int
        cast: str
        elem: TypeSpec
        len: int
        max: int
        name: str

    class DocDict(TypedDict, total=False):
        """A doc comment as the loader writes it: description and the parsed ``@tags``."""

        short: str
        long: str
        tags: dict[str, Any]

    class FieldDict(TypedDict, total=False):
        name: str
        type: TypeSpec
        line: int | None
        doc: DocDict

    class TypeDict(TypedDict, total=False):
        """One type of the model (``model["types"][key]``): what the cache keeps and the core
        compiles."""

        name: str
        version: list[int] | None
        kind: str
        dialect: str
        file: str
        line: int
        dtid: int | None
        doc: DocDict
        fields: list[FieldDict]
        service: str | None
        signature_override: int | None

    #: A scalar tag's value: a number of the field's type, or a bool for a bool field.
    Scalar = int | float | bool

__all__ = [
    "NO_DOC",
    "Field",
    "FieldDoc",
    "TypeDef",
    "TypeDoc",
    "length_bits",
    "tag_bits",
    "type_def",
]


def tag_bits(variants: int) -> int:
    """Width of a union tag for `variants` variants: ceil(log2(n)) (the core's
    ``layout::union_tag_bits``)."""
    return max(variants - 1, 0).bit_length()


def length_bits(max_len: int) -> int:
    """Width of a dynamic array's length prefix: ceil(log2(max + 1)) (the core's
    ``layout::array_len_bits``)."""
    return max_len.bit_length()


class _Doc:
    """A doc comment: its description and its tags, each a named attribute; a tag not given
    keeps the class's default (None, or ``()`` for a list). Read-only; equal when every value
    is. (A plain class: a named tuple of fourteen fields costs every command its making.)"""

    __hash__ = None  # type: ignore[assignment]

    def __init__(self, short: str = "", long: str = "", **tags: object) -> None:
        self.__dict__.update(tags, short=short, long=long)

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"{type(self).__name__} is read-only")

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other.__dict__ == self.__dict__

    def __repr__(self) -> str:
        given = ", ".join(f"{k}={v!r}" for k, v in self.__dict__.items())
        return f"{type(self).__name__}({given})"


class TypeDoc(_Doc):
    """A type's doc comment: its description and type tags."""

    short: str = ""
    long: str = ""
    #: ``@group``: the ground station's group, e.g. ``Sensors``.
    group: str | None = None
    #: ``@category``: ``Standard`` or ``Developer``.
    category: str | None = None
    #: ``@max_instances N``: an instanced parameter with N slots.
    max_instances: int | None = None
    #: ``@param NAME``: the parameter's name when it is not the type's.
    param: str | None = None
    #: ``@reboot_required``.
    reboot_required: bool | None = None

    @property
    def declares_parameter(self) -> bool:
        """``@max_instances`` or ``@param``: the type is a parameter."""
        return self.max_instances is not None or self.param is not None


class FieldDoc(_Doc):
    """A field's doc comment: its description and field tags (of its elements, for an array)."""

    short: str = ""
    long: str = ""
    #: ``@unit``, e.g. ``A``, ``Ohm``.
    unit: str | None = None
    #: ``@min`` / ``@max``.
    minimum: int | float | None = None
    maximum: int | float | None = None
    #: ``@default`` of a scalar field.
    default: int | float | bool | None = None
    #: ``@default <path> <value>`` of a composite field: path (``i2c.address``) -> value.
    path_defaults: Mapping[str, int | float | bool] | None = None
    #: ``@decimal``: decimal places a ground station shows.
    decimal_places: int | None = None
    #: ``@increment``: a ground station's step.
    increment: int | float | None = None
    #: ``@value N text`` and ``@values SET``: the named values, in order.
    values: tuple[tuple[int | float | bool, str], ...] = ()
    #: ``@bit N text``: the named bits of a bitmask, in order.
    bits: tuple[tuple[int, str], ...] = ()
    #: ``@reboot_required``.
    reboot_required: bool | None = None
    #: ``@format``: how a ground station shows the number (``hex``), else None.
    display_format: str | None = None

    @property
    def declared_default(self) -> int | float | bool | Mapping[str, int | float | bool] | None:
        """``@default`` as declared: a scalar, a composite field's paths, or None."""
        return self.path_defaults if self.path_defaults is not None else self.default


#: The doc of a field that has none (DroneCAN's types carry text only).
NO_DOC = FieldDoc()


#: A declared default not read yet.
_UNREAD: Any = object()


class Field:
    """One field of a type, padding included (``kind == "void"``, no name). Read-only.

    A field made from the model (``source``: the type's key, its file and the model's field)
    reads its doc comment when first asked for, and its ``@default`` alone while only that
    is asked for: a command's store builds every parameter's default, but shows the other
    tags (units, ranges, value names) of the few it prints, if any."""

    __slots__ = ("_default", "_doc", "_source", "is_padding", "kind", "line", "name", "type")

    def __init__(
        self,
        name: str,
        type: TypeSpec,
        doc: FieldDoc | None = None,
        line: int | None = None,
        *,
        source: tuple[str, str | None, Mapping[str, Any]] | None = None,
    ) -> None:
        self.name = name
        #: The field's type, JSON-shaped as the core compiles it.
        self.type = type
        self._doc = doc if doc is not None or source is not None else NO_DOC
        self._source = source
        self._default: Any = _UNREAD
        #: Its line in the DSDL file, where known.
        self.line = line
        #: ``uint``, ``int``, ``float``, ``bool``, ``void``, ``array``, ``dynarray``, ``ref``.
        self.kind: str = type["kind"]
        #: ``voidN``: padding, no data.
        self.is_padding = self.kind == "void"

    @property
    def doc(self) -> FieldDoc:
        """The field's doc comment and tags (read once, when first asked for)."""
        doc = self._doc
        if doc is None:
            assert self._source is not None
            doc = self._doc = _field_doc(*self._source)
        return doc

    @property
    def declared_default(
        self,
    ) -> int | float | bool | Mapping[str, int | float | bool] | None:
        """``doc.declared_default``: read alone, without the other tags, until the doc is."""
        if self._doc is not None:
            return self._doc.declared_default
        if self._default is _UNREAD:
            assert self._source is not None
            self._default = _declared_default(*self._source)
        return self._default  # type: ignore[no-any-return]

    def __repr__(self) -> str:
        return f"Field(name={self.name!r}, type={self.type!r}, doc={self.doc!r})"


class TypeDef:
    """One type of the schema: a struct or union with its doc and fields.

    Read-only. Its doc and fields are read from the model when first asked for, each once (a
    command's store looks at every type's dialect, but at the fields of its parameters only).
    """

    __slots__ = (
        "_data_fields",
        "_definition",
        "_doc",
        "_fields",
        "dialect",
        "file",
        "is_union",
        "key",
        "name",
        "service",
        "version",
    )

    def __init__(self, key: str, definition: TypeDict | Mapping[str, Any]) -> None:
        version = definition.get("version")
        file = definition.get("file")
        self._definition = definition
        self._doc: TypeDoc | None = None
        self._fields: tuple[Field, ...] | None = None
        self._data_fields: list[Field] | None = None
        self.key = key
        #: Full name without version, e.g. ``px.Ina238``.
        self.name = str(definition["name"])
        self.is_union: bool = definition["kind"] == "union"
        #: ``dsdl`` (our ``.dsdl`` types, with tags) or ``uavcan`` (DroneCAN's ``.uavcan``).
        self.dialect: str | None = definition.get("dialect")
        #: The service a request or response belongs to, else None.
        self.service: str | None = definition.get("service")
        self.version = (int(version[0]), int(version[1])) if version else None
        self.file = str(file) if file is not None else None

    @property
    def doc(self) -> TypeDoc:
        """The type's doc comment and type tags."""
        if self._doc is None:
            self._doc = _type_doc(self.key, self._definition)
        return self._doc

    @property
    def fields(self) -> tuple[Field, ...]:
        """Every field in order, padding included."""
        if self._fields is None:
            key, file = self.key, self.file
            self._fields = tuple(
                Field(str(f["name"]), f["type"], None, f.get("line"), source=(key, file, f))
                for f in self._definition["fields"]
            )
        return self._fields

    @property
    def versioned(self) -> bool:
        """Our own types (``.dsdl``): they carry ``p_version`` and tags."""
        return self.dialect == "dsdl"

    @property
    def data_fields(self) -> list[Field]:
        """The fields that hold data (no padding)."""
        if self._data_fields is None:
            self._data_fields = [f for f in self.fields if not f.is_padding]
        return self._data_fields

    def field(self, name: str) -> Field | None:
        """The field ``name``, or None."""
        return next((f for f in self.fields if f.name == name and not f.is_padding), None)

    def __repr__(self) -> str:
        return f"<TypeDef {self.key}>"


def type_def(
    key: str,
    definition: TypeDict | Mapping[str, Any],
    memo: MutableMapping[str, TypeDef] | None = None,
) -> TypeDef:
    """``definition`` (the model's type ``key``) as a :class:`TypeDef` (once: kept in ``memo``,
    the schema's). Its doc and fields raise :class:`DsdlError` naming the type, field and tag
    when a tag has the wrong shape."""
    if memo is None:
        return TypeDef(key, definition)
    found = memo.get(key)
    if found is None:
        found = memo[key] = TypeDef(key, definition)
    return found


# -- reading tags: one function per tag ---------------------------------------------------------


def _text(value: object) -> str:
    if not isinstance(value, str) or not value:
        raise TagValueError(f"expects text, got {value!r}")
    return value


def _flag(value: object) -> bool:
    if not isinstance(value, bool):
        raise TagValueError(f"expects true or false, got {value!r}")
    return value


def _count(value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise TagValueError(f"expects a whole number of at least 0, got {value!r}")
    return value


def _positive(value: object) -> int:
    if _count(value) < 1:
        raise TagValueError(f"expects a whole number of at least 1, got {value!r}")
    return value  # type: ignore[return-value]


def _number(value: object) -> int | float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TagValueError(f"expects a number, got {value!r}")
    return value


def _scalar(value: object) -> int | float | bool:
    if not isinstance(value, int | float):  # (a bool is an int)
        raise TagValueError(f"expects a number or true/false, got {value!r}")
    return value


def _named(value: object, number: Callable[[object], Any]) -> tuple[tuple[Any, str], ...]:
    if type(value) is list:  # as the loader writes it, checked in one loop (rotation has 40)
        pairs = []
        for item in value:
            if type(item) is not list or len(item) != 2:
                break
            n, text = item
            if type(n) is not int or type(text) is not str or (n < 0 and number is not _scalar):
                break
            pairs.append((n, text))
        else:
            return tuple(pairs)
    if not isinstance(value, list | tuple):
        raise TagValueError(f"expects a list of [number, description], got {value!r}")
    out = []
    for item in value:
        if not isinstance(item, list | tuple) or len(item) != 2 or not isinstance(item[1], str):
            raise TagValueError(f"expects [number, description], got {item!r}")
        out.append((number(item[0]), item[1]))
    return tuple(out)


def _values(value: object) -> tuple[tuple[int | float | bool, str], ...]:
    return _named(value, _scalar)


def _bits(value: object) -> tuple[tuple[int, str], ...]:
    return _named(value, _count)


def _display_format(value: object) -> str:
    if value != "hex":
        raise TagValueError(f"expects hex, got {value!r}")
    return "hex"


def _field_default(value: object) -> tuple[str, object]:
    """``@default``: a scalar, or (a composite field's) a table of path -> scalar."""
    if isinstance(value, dict):
        paths = {}
        for path, item in value.items():
            if not isinstance(path, str) or not path:
                raise TagValueError(f"expects field paths, got {path!r}")
            paths[path] = _scalar(item)
        return "path_defaults", paths
    return "default", _scalar(value)


def _as(name: str, read: Callable[[object], object]) -> Callable[[object], tuple[str, object]]:
    return lambda value: (name, read(value))


#: Each field tag as the model keys it -> the function that reads it into ``FieldDoc``'s name.
_FIELD_TAGS: dict[str, Callable[[object], tuple[str, object]]] = {
    "unit": _as("unit", _text),
    "min": _as("minimum", _number),
    "max": _as("maximum", _number),
    "default": _field_default,
    "decimal": _as("decimal_places", _count),
    "increment": _as("increment", _number),
    "value": _as("values", _values),
    "bit": _as("bits", _bits),
    "reboot_required": _as("reboot_required", _flag),
    "format": _as("display_format", _display_format),
}

#: Each type tag -> the function that reads it (``TypeDoc``'s names are the tags').
_TYPE_TAGS: dict[str, Callable[[object], object]] = {
    "group": _text,
    "category": _text,
    "max_instances": _positive,
    "param": _text,
    "reboot_required": _flag,
}


def _doc_parts(where: str, doc: object) -> tuple[str, str, Mapping[str, Any]]:
    if doc is None:
        return "", "", {}
    if not isinstance(doc, dict):
        raise TagValueError(f"{where}: doc is not a table: {doc!r}")
    short, long, tags = doc.get("short") or "", doc.get("long") or "", doc.get("tags") or {}
    if not isinstance(short, str) or not isinstance(long, str) or not isinstance(tags, dict):
        raise TagValueError(f"{where}: doc's short, long or tags has the wrong shape")
    return short, long, tags


def _type_doc(key: str, definition: Mapping[str, Any]) -> TypeDoc:
    file = definition.get("file")
    try:
        short, long, tags = _doc_parts(key, definition.get("doc"))
    except TagValueError as e:
        raise DsdlError(str(e), file) from None
    values: dict[str, object] = {}
    for tag, value in tags.items():
        read = _TYPE_TAGS.get(tag)
        try:
            if read is None:
                raise TagValueError(f"is not a type tag (expected one of {', '.join(_TYPE_TAGS)})")
            values[tag] = read(value)
        except TagValueError as e:
            raise DsdlError(f"{key}: @{tag} {e}", file) from None
    return TypeDoc(short, long, **values)


def _declared_default(
    key: str, file: str | None, field: Mapping[str, Any]
) -> int | float | bool | Mapping[str, int | float | bool] | None:
    """A field's ``@default`` (a scalar or a composite field's paths) read alone, refused in
    :func:`_field_doc`'s words."""
    where = f"{key}.{field.get('name') or '(padding)'}"
    line = field.get("line")
    try:
        value = _doc_parts(where, field.get("doc"))[2].get("default")
    except TagValueError as e:
        raise DsdlError(str(e), file, line) from None
    if value is None:
        return None
    try:
        return _field_default(value)[1]  # type: ignore[return-value]
    except TagValueError as e:
        raise DsdlError(f"{where}: @default {e}", file, line) from None


def _field_doc(key: str, file: str | None, field: Mapping[str, Any]) -> FieldDoc:
    where = f"{key}.{field.get('name') or '(padding)'}"
    line = field.get("line")
    try:
        short, long, tags = _doc_parts(where, field.get("doc"))
    except TagValueError as e:
        raise DsdlError(str(e), file, line) from None
    if not short and not long and not tags:
        return NO_DOC
    values: dict[str, object] = {}
    for tag, value in tags.items():
        read = _FIELD_TAGS.get(tag)
        try:
            if read is None:
                expected = ", ".join(_FIELD_TAGS)
                raise TagValueError(f"is not a field tag (expected one of {expected})")
            name, parsed = read(value)
        except TagValueError as e:
            raise DsdlError(f"{where}: @{tag} {e}", file, line) from None
        values[name] = parsed
    return FieldDoc(short, long, **values)
