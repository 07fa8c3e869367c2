"""The parameter store: structured instances (``INA238#0``), shared structured parameters and
classic PX4 parameters, in memory reserved once by the Rust core.

>>> import px4params
>>> store = px4params.Store(px4params.load_schema())
>>> store.add("INA238#0")
'INA238#0'
>>> store["INA238#0"][4] = 0x45
>>> store["INA238#0"].bus.i2c.address
69

Names: ``INA238#0`` is instance 0 of parameter ``INA238``; ``INA238#0[4]`` its leaf ``[4]``;
``INA238#0.bus.i2c.address`` a leaf by path; a shared or classic parameter has no ``#N``.
Every change is all-or-nothing: a refused one leaves the store exactly as it was.
"""

from __future__ import annotations

import binascii
import math
import os
import struct
from collections.abc import Iterator, Mapping, Sequence

from px4params import _native
from px4params._records import TYPE_CHECKING
from px4params.cache_file import cache_path, default_cache_dir, read_cached, write_cached
from px4params.dsdl.schema import DataType, Leaf, Schema, load_schema, put_at, value_at
from px4params.errors import (
    InstanceError,
    LeafError,
    Px4ParamsError,
    StoreError,
    ValueRangeError,
)
from px4params.numbers import abbreviated
from px4params.store.classic import (
    CLASSIC_ENV,
    ClassicParam,
    ClassicParamsError,
    classic_value,
    load_classic,
)
from px4params.store.key import Key
from px4params.store.spec import (
    ParamSpec,
    check_leaves,
    check_stored,
    generic_path,
    in_type_range,
    leaf_ranges,
    metadata_default,
    parameter_specs,
    stored_number,
    within,
)

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import Any, NamedTuple, NoReturn

    from px4params.store.flat import FlatMap
else:
    from px4params._records import NamedTuple

__all__ = ["DEFAULT_STORE", "STORE_ENV", "InstanceView", "Key", "Store", "default_store_path"]

#: The module that checks flat names (its code is part of the cached verdict's key).
_FLAT_MODULE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "flat.py")

#: Environment variable naming the store file (``--store FILE`` overrides it).
STORE_ENV = "PX4PARAMS_STORE"
#: The store file used when neither ``--store`` nor ``$PX4PARAMS_STORE`` names one.
DEFAULT_STORE = "px4params.store"

#: Names whose resolution a store keeps (a bound: names can come from anywhere).
_RESOLVED_MAX = 4096


def default_store_path() -> str:
    """``$PX4PARAMS_STORE``, or ``px4params.store`` in the current directory."""
    return os.environ.get(STORE_ENV) or DEFAULT_STORE


class _Param(NamedTuple):
    """A parameter of the store: structured (``spec``) or classic (``classic``)."""

    index: int  # type: ignore[assignment]  # a field named index hides tuple.index, as Leaf's must
    name: str
    spec: ParamSpec | None
    classic: ClassicParam | None

    @property
    def shared(self) -> bool:
        return self.spec is None or self.spec.shared


class Store:
    """Structured and classic parameters, with defaults and per-instance state.

    ``schema`` defaults to the bundled types; ``classic`` is a list of classic parameters or a
    PX4 ``parameters.json`` path (default: ``$PX4PARAMS_PARAMETERS_JSON``, else none).
    """

    def __init__(
        self,
        schema: Schema | None = None,
        *,
        classic: Sequence[ClassicParam] | str | os.PathLike[str] | None = None,
    ) -> None:
        self.schema = schema if schema is not None else load_schema()
        if classic is None and os.environ.get(CLASSIC_ENV):
            classic = os.environ[CLASSIC_ENV]
        if isinstance(classic, str | os.PathLike):
            classic = load_classic(classic)
        # One layout for all the store's types, compiled before the types are looked up, so
        # that they are taken from it rather than compiled one by one.
        native_schema = self.schema._native
        self.specs = parameter_specs(self.schema)
        params: list[_Param] = []
        rows: list[tuple[str, str, int | None]] = []
        for spec in self.specs:
            params.append(_Param(len(params), spec.name, spec, None))
            rows.append((spec.name, spec.data_type.key, spec.max_instances))
        structured = {p.name for p in params}
        for c in classic or ():
            if c.name in structured:
                raise StoreError(f"classic parameter {c.name} has the name of a structured one")
            params.append(_Param(len(params), c.name, None, c))
            rows.append((c.name, "@float32" if c.is_float else "@int32", None))
        self._params = {p.name: p for p in params}
        if len(self._params) != len(params):
            raise StoreError("two classic parameters have the same name")
        self._order = params
        self._resolved: dict[str | Key, tuple[_Param, int, Key]] = {}
        # Leaf names read before, as the core's arguments: Store.get of a leaf in one call.
        self._leaf_reads: dict[str | Key, tuple[int, int, int | str]] = {}
        self._native = _native.Store(native_schema, rows)
        for p in params:
            self._native.set_type_default(p.index, self._type_default(p))
        self._native.mark_saved()
        self._initial = self._native.copy()
        # The destructured (MAVLink) names must be valid for every type: checked here, so that
        # a type with a leaf over 32 bits or a clashing name is refused at load. The check
        # depends only on the schema and the classic names, so once passed it is remembered
        # in the cache folder and the names are worked out on first use.
        self._destructured: FlatMap | None = None
        verdict = _flat_check_file(self)
        if verdict is None or read_cached(*verdict) is not True:
            self._destructured = self.destructured
            if verdict is not None:
                write_cached(*verdict, True)
        #: Classic records of a loaded file whose parameters this store lacks (or has as the
        #: other type), kept to be saved.
        self._foreign: dict[str, bytes] = {}

    @property
    def kept_classic(self) -> list[str]:
        """Classic parameters of a loaded file that this store's set lacks, or has as the other
        type where the value does not fit it (another ``--classic`` parameters.json): their
        values are kept and saved with the store, but no command of this set shows, exports or
        resets them."""
        return sorted(self._foreign)

    @property
    def destructured(self) -> FlatMap:
        """The destructured (flat, MAVLink) names of this store's parameters."""
        if self._destructured is None:
            from px4params.store.flat import FlatMap

            self._destructured = FlatMap(self)
        return self._destructured

    def _type_defaults(self) -> list[bytes]:
        """Each structured parameter's type default (encoded without tail array
        optimization), in parameter order."""
        return [self._type_default(p) for p in self._order if p.classic is None]

    def _type_default(self, p: _Param) -> bytes:
        if p.classic is not None:
            return _classic_bytes(p.classic, p.classic.default)
        assert p.spec is not None
        value = metadata_default(self.schema, p.spec.data_type.key)
        return p.spec.data_type.encode(value, tao=False)

    # -- names --------------------------------------------------------------------------------

    @property
    def parameters(self) -> list[str]:
        """Every parameter name: structured ones (sorted), then classic ones (file order)."""
        return [p.name for p in self._order]

    def spec(self, name: str) -> ParamSpec | None:
        """The structured parameter ``name`` (None for a classic one)."""
        return self._param(name).spec

    def classic(self, name: str) -> ClassicParam | None:
        """The classic parameter ``name`` (None for a structured one)."""
        return self._param(name).classic

    def _param(self, name: str) -> _Param:
        p = self._params.get(name)  # exact, as PX4's names
        if p is None:
            import difflib

            hint = difflib.get_close_matches(name.strip().upper(), list(self._params), n=3)
            extra = f" (did you mean: {', '.join(hint)}?)" if hint else ""
            raise InstanceError(f"unknown parameter '{abbreviated(name)}'{extra}")
        return p

    def _resolve(self, text: str | Key) -> tuple[_Param, int, Key]:
        # A name resolves the same way for the store's life (whether the instance exists is
        # the core's to say): each text is parsed once.
        try:
            found = self._resolved.get(text)
        except TypeError:  # not a name at all: Key.parse says so
            found = None
        if found is not None:
            return found
        key = Key.parse(text)
        p = self._param(key.param)
        if p.shared:
            if key.instance is not None:
                raise InstanceError(f"{p.name} is not instanced: write {p.name}, not {text}")
            found = (p, 0, key)
        elif key.instance is None:
            raise InstanceError(f"{p.name} has instances: name one, e.g. {p.name}#0")
        else:
            found = (p, key.instance, key)
        if len(self._resolved) >= _RESOLVED_MAX:
            self._resolved.clear()
        self._resolved[text] = found  # text is a str or a Key here: Key.parse took it
        return found

    def _instance_name(self, p: _Param, instance: int) -> str:
        return str(self._instance_key(p, instance))

    def _instance_key(self, p: _Param, instance: int) -> Key:
        return Key(p.name, None if p.shared else instance, None)

    def instance_key(self, param: str, instance: int) -> Key:
        """The key of ``param``'s instance ``instance`` (of the parameter, for a shared or
        classic one), whether or not it exists."""
        return self._instance_key(self._param(param), instance)

    def data_type(self, name: str | Key) -> DataType:
        """The type of a structured parameter."""
        p = self._param(Key.parse(name).param)
        if p.spec is None:
            raise InstanceError(f"{p.name} is a classic parameter, not a structured one")
        return p.spec.data_type

    # -- instances ----------------------------------------------------------------------------

    def add(self, name: str | Key) -> str:
        """Adds ``INA238#N``, or the lowest free instance for ``INA238``; returns its name."""
        key = Key.parse(name)
        p = self._param(key.param)
        if key.leaf is not None:
            raise InstanceError(f"add takes an instance, not a leaf: {name}")
        if p.shared:
            raise InstanceError(f"{p.name}: {_one_value(p)} has no instances to add")
        number = self._native.add(p.index, key.instance)
        return self._instance_name(p, number)

    def remove(self, name: str | Key) -> None:
        """Removes an instance; the others keep their numbers."""
        p, instance, key = self._resolve(name)
        if key.leaf is not None:
            raise InstanceError(f"rm takes an instance, not a leaf: {name}")
        if p.shared:
            raise InstanceError(f"{p.name}: {_one_value(p)} has no instances to remove")
        self._native.remove(p.index, instance)

    def instances(self, param: str | Key) -> list[str]:
        """The instances of ``param`` that exist, in order (what a driver's ``auto`` starts)."""
        return [str(key) for key in self.instance_keys(Key.parse(param).param)]

    def names(self) -> Iterator[str]:
        """Every existing instance and every shared or classic parameter, in store order."""
        return (str(key) for key in self.instance_keys())

    def instance_keys(self, param: str | None = None) -> Iterator[Key]:
        """:meth:`names` (of ``param`` alone: :meth:`instances`) as keys, to pass on without
        parsing them again."""
        for p in self._order if param is None else (self._param(param),):
            for i in self._native.instances(p.index):
                yield self._instance_key(p, i)

    def __contains__(self, name: object) -> bool:
        if not isinstance(name, str | Key):
            return False
        try:
            p, instance, _ = self._resolve(name)
            return self._native.slot(p.index, instance)[0]
        except InstanceError:
            return False

    def __iter__(self) -> Iterator[str]:
        return self.names()

    def __getitem__(self, name: str | Key) -> InstanceView:
        p, instance, key = self._resolve(name)
        if key.leaf is not None:
            raise InstanceError(f"store[...] takes an instance; use store.get('{name}')")
        if not self._native.slot(p.index, instance)[0]:  # also checks the range
            raise InstanceError(
                f"{self._instance_name(p, instance)}: instance does not exist "
                "(add it first: param add)"
            )
        return InstanceView(self, p, instance)

    # -- values -------------------------------------------------------------------------------

    def get(self, name: str | Key, *, default: bool = False) -> Any:
        """A whole value (dict; a number for a classic parameter) or one leaf's value."""
        try:
            read = self._leaf_reads.get(name)
        except TypeError:  # not a name at all: _resolve says so
            read = None
        if read is not None:
            index, number, leaf = read
            try:
                return self._native.get_leaf_value(index, number, leaf, default)
            except Px4ParamsError:
                pass  # (the instance was removed, ...) worded below
        p, instance, key = self._resolve(name)
        if key.leaf is not None:
            if p.classic is not None:
                return self.leaf(key, default=default).value  # which refuses it
            try:  # the value alone: no Leaf, no path or type text
                value = self._native.get_leaf_value(p.index, instance, key.leaf, default)
            except LeafError as e:
                raise _naming_the_field(e, key) from None
            if len(self._leaf_reads) >= _RESOLVED_MAX:
                self._leaf_reads.clear()
            self._leaf_reads[name] = (p.index, instance, key.leaf)
            return value
        data = self._native.get(p.index, instance, default=default)
        if p.classic is not None:
            return _classic_from_bytes(p.classic, data)
        assert p.spec is not None
        return p.spec.data_type.decode(data, tao=False)

    def leaf(self, name: str | Key, *, default: bool = False) -> Leaf:
        """One leaf, named ``NAME#N[k]`` or ``NAME#N.path``."""
        p, instance, key = self._resolve(name)
        if key.leaf is None or p.classic is not None:
            raise InstanceError(f"'{name}' names no leaf (expected NAME#N[k] or NAME#N.path)")
        try:
            return Leaf(*self._native.get_leaf(p.index, instance, key.leaf, default=default))
        except LeafError as e:
            raise _naming_the_field(e, key) from None

    def leaves(self, name: str | Key, *, default: bool = False) -> list[Leaf]:
        """Every leaf of an instance's value (or default) in ``[k]`` order."""
        p, instance, _ = self._resolve(name)
        if p.spec is None:
            raise InstanceError(f"{p.name} is a classic parameter: it has no leaves")
        data = self._native.get(p.index, instance, default=default)
        return p.spec.data_type.leaves(data, tao=False)

    def _whole(self, name: str | Key, what: str) -> tuple[_Param, int]:
        """An instance or parameter named without a leaf (``what`` says who asks)."""
        p, instance, key = self._resolve(name)
        if key.leaf is not None:
            raise InstanceError(f"{what} takes an instance or parameter, not a leaf: {name}")
        return p, instance

    def encoded(self, name: str | Key, *, default: bool = False) -> bytes:
        """An instance's stored bytes (DroneCAN rules, no tail array optimization)."""
        p, instance = self._whole(name, "encoded")
        return self._native.get(p.index, instance, default=default)

    def set(
        self, name: str | Key, value: Any, *, saturate: bool = False, force: bool = False
    ) -> None:
        """Sets a whole value, a leaf (``NAME#N[k]``, ``NAME#N.path``) or a classic parameter.

        A value outside its field's ``@min``/``@max`` or a NaN or infinity is refused
        (:class:`ValueRangeError`, nothing written); ``force`` lets the ``@min``/``@max``
        pass (``param set --force``), never a NaN or an infinity."""
        self._write(name, value, False, saturate, force)

    def set_default(
        self, name: str | Key, value: Any, *, saturate: bool = False, force: bool = False
    ) -> None:
        """Sets the default, like ``param set-default``: the value follows unless changed.
        Checked as :meth:`set` checks a value."""
        self._write(name, value, True, saturate, force)

    def _write(
        self, name: str | Key, value: Any, default: bool, saturate: bool, force: bool = False
    ) -> None:
        # (Positional arguments here and in _check_leaf: every write passes through them.)
        p, instance, key = self._resolve(name)
        if p.classic is not None:
            if key.leaf is not None:
                raise InstanceError(f"{p.name} is a classic parameter: it has no leaves")
            try:
                data = _classic_bytes(p.classic, value)
            except ClassicParamsError as e:
                raise ClassicParamsError(f"{p.name}: {e}") from None
            self._check_encoded(p, 0, data, force=force)
            self._native.set_encoded(p.index, 0, data, default=default)
            # A value kept as the other type (store/file.py) gives way to the one set here.
            self._foreign.pop(p.name, None)
        elif key.leaf is None:
            self._check_value(p, instance, value, default, saturate=saturate, force=force)
            self._native.set_value(p.index, instance, value, default=default, saturate=saturate)
        else:
            whole = None if default else self._default_variant(p, instance, key.leaf, value)
            if whole is not None:
                self._write(self._instance_key(p, instance), whole, False, saturate, force)
                return
            self._check_leaf(p, instance, key.leaf, value, default, saturate, force)
            try:
                self._native.set_leaf(
                    p.index, instance, key.leaf, value, default=default, saturate=saturate
                )
            except LeafError as e:
                raise _naming_the_field(e, key) from None

    def _default_variant(self, p: _Param, instance: int, leaf: int | str, value: Any) -> Any:
        """The whole value a write of union tag ``leaf`` gives when it switches to the variant
        the instance's default selects: that variant as the default holds it. (DSDL's rule, the
        variant's zeros, would leave address 0 after a switch to SPI and back to I2C; PX4's
        flat parameters would keep the address.) None for any other write: the core makes
        it leaf by leaf."""
        if type(value) is not int or not _has_union(p):
            return None  # (no look-up for the writes of types without a union: most)
        path = leaf
        if not isinstance(path, str):
            try:
                path = self._native.get_leaf(p.index, instance, path, default=False)[1]
            except Px4ParamsError:
                return None  # no such instance or leaf: the write says so
        parent, _, last = path.rpartition(".")
        if last != "_tag":
            return None
        try:  # the default's tag first: a switch to another variant reads nothing more
            if value != self._native.get_leaf_value(p.index, instance, path, True):
                return None
            if value == self._native.get_leaf_value(p.index, instance, path, False):
                return None  # no switch: the variant's values stay
        except Px4ParamsError:
            return None  # the default has no such union (another variant or length above it)
        key = self._instance_key(p, instance)
        default_value = self.get(key, default=True)
        if not parent:
            return default_value
        whole = self.get(key)
        put_at(whole, parent, value_at(default_value, parent))
        return whole

    # The store's one range check (every entry point writes through these): worked out on the
    # value as it would be stored, before anything is written, so a refusal changes nothing.
    # Only the leaves a write changes are checked: a value stored with --force stays writable.

    def _check_value(
        self, p: _Param, instance: int, value: Any, default: bool, *, saturate: bool, force: bool
    ) -> None:
        assert p.spec is not None
        if not leaf_ranges(p.spec.data_type):
            return
        try:
            data = p.spec.data_type.encode(value, tao=False, saturate=saturate)
        except Px4ParamsError:
            return  # not a value of the type: the write says what is wrong with it
        self._check_encoded(p, instance, data, force=force, default=default)

    def _check_encoded(
        self, p: _Param, instance: int, data: bytes, *, force: bool, default: bool = False
    ) -> None:
        if p.spec is None:
            if p.classic is not None and p.classic.is_float and len(data) == 4:
                (number,) = struct.unpack("<f", data)
                if not math.isfinite(number):
                    raise ValueRangeError(
                        f"{p.name}: {number} is not a finite number (Float: NaN and infinities "
                        "are refused)"
                    )
            return
        data_type = p.spec.data_type
        ranges = leaf_ranges(data_type)
        if not ranges:
            return
        try:
            leaves = data_type.leaves(data, tao=False)
        except Px4ParamsError:
            return  # not a value of the type: the write says so
        check_leaves(
            self._instance_name(p, instance),
            _changed_leaves(leaves, self._stored_leaves(p, instance, default)),
            ranges,
            bounds=not force,
        )

    def _stored_leaves(self, p: _Param, instance: int, default: bool) -> list[Leaf]:
        """The leaves stored now (none for an instance that does not exist)."""
        assert p.spec is not None
        try:
            data = self._native.get(p.index, instance, default=default)
            return p.spec.data_type.leaves(data, tao=False)
        except Px4ParamsError:
            return []

    def _check_leaf(
        self,
        p: _Param,
        instance: int,
        target: int | str,
        value: Any,
        default: bool,
        saturate: bool,
        force: bool,
    ) -> None:
        if p.spec is None:
            return
        data_type = p.spec.data_type
        ranges = leaf_ranges(data_type)
        if not ranges:
            return
        # The leaf is looked up once: by the core for a write by [k] (its path says which
        # range applies); for a write by path (a union tag or a length too), only when a
        # refusal needs its type.
        found: tuple[int, str, str, Any] | None = None
        if isinstance(target, str):
            path = target  # a leaf named by its path: no need to ask the core
        else:
            try:
                found = self._native.get_leaf(p.index, instance, target, default=default)
            except Px4ParamsError:
                return  # no such instance or leaf: the write says so
            path = found[1]
        # A union tag or an array length brings other leaves into the value: check them all.
        whole = path.endswith(("_tag", "_len"))
        if not whole:
            rng = ranges.get(generic_path(path))
            if rng is None:
                return
            if not saturate:  # a plain number: checked without the codec (the common case)
                stored = stored_number(value, rng)
                if stored is None and not force and _finite_number(value):
                    # Beyond the leaf's float width (1e6 for a float16): outside any
                    # @min/@max the field can have, which is what the refusal names.
                    stored = value
                if stored is not None:
                    if within(stored, rng, not force):
                        return
                    # Refused: but a leaf that does not exist is the write's own error, worded
                    # by the core, and so is, with --force, a value its type cannot hold. The
                    # field's @min/@max come before its type's range (0.00001..0.1, not a
                    # float16's -65504..65504).
                    if found is None:
                        try:
                            found = self._native.get_leaf(
                                p.index, instance, target, default=default
                            )
                        except Px4ParamsError:
                            return
                    holds = in_type_range(value, found[2])
                    if not force or holds:
                        where = f"{self._instance_name(p, instance)}.{path}"
                        check_stored(where, stored, rng, not force, value, forcible=holds)
                    return
        try:
            now = self._native.get(p.index, instance, default=default)
            data = data_type.set_leaf(now, target, value, tao=False, saturate=saturate)
            leaves = (
                _changed_leaves(data_type.leaves(data, tao=False), data_type.leaves(now, tao=False))
                if whole
                else [data_type.get_leaf(data, target, tao=False)]
            )
        except Px4ParamsError:
            return  # a value the leaf cannot hold: the write says so, in the store's words
        check_leaves(
            self._instance_name(p, instance),
            leaves,
            ranges,
            bounds=not force,
            given=None if whole else value,
        )

    def set_encoded(self, name: str | Key, data: bytes, *, default: bool = False) -> None:
        """Sets a whole value from its stored bytes (checked before it is taken, its leaves
        against their ``@min``/``@max`` too)."""
        p, instance, _ = self._resolve(name)
        self._check_encoded(p, instance, bytes(data), force=False, default=default)
        self._native.set_encoded(p.index, instance, bytes(data), default=default)
        if p.classic is not None:  # (a value kept as the other type gives way)
            self._foreign.pop(p.name, None)

    def reset(self, name: str | Key) -> None:
        """Sets a value, or one leaf (``INA238#0[4]``), back to its default."""
        p, instance, key = self._resolve(name)
        if key.leaf is None:
            self._native.reset(p.index, instance)
            if p.classic is not None:  # (a value kept as the other type is reset too)
                self._foreign.pop(p.name, None)
            return
        # The value's leaf [k], found by its path in the default: where a union selects another
        # variant, or an array is shorter, the same index names another field there.
        path = self.leaf(key).path
        parent, _, last = path.rpartition(".")
        if last in ("_tag", "_len"):
            # A union's tag or an array's length: the union or array as the default has it
            # (the default's variant with its values, not the variant's zeros).
            whole = key._replace(leaf=None)
            value, default_value = self.get(whole), self.get(whole, default=True)
            if not parent:  # the value itself is the union
                self.set(whole, default_value)
                return
            put_at(value, parent, value_at(default_value, parent))
            self.set(whole, value)
            return
        try:
            default = self.leaf(key._replace(leaf=path), default=True)
        except LeafError as e:
            raise LeafError(
                f"{e} (the default value has another shape: no default for it)"
            ) from None
        self.set(key, default.value)

    def reset_all(self) -> None:
        """Sets every value back to its default (instances stay)."""
        for name in list(self.names()):
            self.reset(name)

    def reset_to_initial(self) -> None:
        """Back to a new store: no instance, every value its default."""
        self._native.restore(self._initial)
        self._foreign = {}

    def changed(self, name: str | Key | None = None) -> Any:
        """Whether ``name`` differs from its default; without a name, every name that does."""
        if name is not None:
            p, instance = self._whole(name, "changed")
            return self._native.changed(p.index, instance)
        return [n for n in self.names() if self.changed(n)]

    def state(self, name: str | Key) -> tuple[bool, bool]:
        """``(used, unsaved)`` of an instance or parameter."""
        p, instance = self._whole(name, "state")
        _, used, unsaved = self._native.slot(p.index, instance)
        return used, unsaved

    def mark_used(self, name: str | Key) -> None:
        """Marks an instance as read by a driver (PX4's ``x`` in ``param show``)."""
        p, instance = self._whole(name, "touch")
        self._native.mark_used(p.index, instance)

    @property
    def capacity(self) -> tuple[int, int]:
        """``(slots, bytes)`` of memory reserved for every parameter's values and defaults."""
        return self._native.capacity

    # -- all-or-nothing batches ---------------------------------------------------------------

    def transaction(self) -> _Transaction:
        """``with store.transaction():`` applies every change in the block, or none if it
        raises."""
        return _Transaction(self)

    # -- files --------------------------------------------------------------------------------

    def save(self, path: str | os.PathLike[str] | None = None) -> int:
        """Saves atomically (the previous file is kept as ``FILE.bak``); returns its size."""
        from px4params.store.file import save

        size = save(self, path if path is not None else default_store_path())
        self._native.mark_saved()
        return size

    def load_from(self, path: str | os.PathLike[str] | None = None) -> list[str]:
        """Resets the store, then applies the file (``param load``); returns the report."""
        from px4params.store.file import apply_file

        return apply_file(self, path if path is not None else default_store_path(), merge=False)

    def import_from(self, path: str | os.PathLike[str] | None = None) -> list[str]:
        """Merges the file into the store (``param import``); returns the report."""
        from px4params.store.file import apply_file

        return apply_file(self, path if path is not None else default_store_path(), merge=True)

    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str] | None = None,
        schema: Schema | None = None,
        *,
        classic: Sequence[ClassicParam] | str | os.PathLike[str] | None = None,
    ) -> Store:
        """A new store with the file's content."""
        store = cls(schema, classic=classic)
        store.load_from(path)
        return store

    def __repr__(self) -> str:
        return f"<Store {len(list(self.names()))} instances of {len(self._order)} parameters>"

    def __copy__(self) -> Store:
        """``copy.copy(store)`` (and ``copy.deepcopy``): another store with the same content,
        changed on its own (the schema, which nothing changes, is shared). A plain copy of the
        attributes would share the core's memory: a change to either showed in both."""
        other = object.__new__(Store)
        other.__dict__.update(self.__dict__)
        other._native = self._native.copy()
        other._foreign = dict(self._foreign)
        other._resolved = dict(self._resolved)
        other._leaf_reads = dict(self._leaf_reads)
        other._destructured = None  # (it names the store it was made for)
        return other

    def __deepcopy__(self, memo: dict[int, Any]) -> Store:
        return self.__copy__()

    def __reduce__(self) -> NoReturn:
        raise TypeError(
            "a Store is not pickled: save it to a store file (store.save(path)) and load that "
            "(Store.load(path)), or send store.encoded(name) values"
        )


def _one_value(p: _Param) -> str:
    """What a parameter without instances is: a classic one or a shared structured one."""
    return "a classic parameter" if p.classic is not None else "a shared parameter"


def _has_union(p: _Param) -> bool:
    """Whether a structured parameter's type holds a union anywhere (its flat layout, every
    variant's leaves, has a union tag), worked out once per type."""
    if p.spec is None:
        return False
    data_type = p.spec.data_type
    found = data_type.derived.get("has_union")
    if found is None:
        from px4params.store.flat import layout

        found = any(slot.role == "union_tag" for slot in layout(data_type).slots)
        data_type.derived["has_union"] = found
    return bool(found)


def _finite_number(value: object) -> bool:
    """A plain ``int`` or finite ``float`` (not a bool, not beyond every double)."""
    if type(value) is not int and type(value) is not float:
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:  # an int beyond every double: the codec refuses it
        return False


def _changed_leaves(leaves: list[Leaf], before: list[Leaf]) -> list[Leaf]:
    """The leaves of ``leaves`` that ``before`` does not hold with the same path and value."""
    kept = {(leaf.path, repr(leaf.value)) for leaf in before}
    return [leaf for leaf in leaves if (leaf.path, repr(leaf.value)) not in kept]


def _naming_the_field(error: LeafError, key: Key) -> LeafError:
    """The core cannot name a field it did not find; the key can: ``no such field: nope``."""
    text = str(error)
    if isinstance(key.leaf, str) and text.endswith("no such field"):
        return LeafError(f"{text}: {key.leaf}")
    return error


class InstanceView:
    """One instance: ``view[4]``, ``view[4] = 0x45``, ``view.bus.i2c.address``, ``view.value``.

    Attribute access walks the path and returns a leaf's value, or a view of a nested struct.
    """

    __slots__ = ("_instance", "_key", "_param", "_prefix", "_store")
    _store: Store
    _param: _Param
    _instance: int
    _key: Key
    _prefix: str

    def __init__(self, store: Store, param: _Param, instance: int, prefix: str = "") -> None:
        object.__setattr__(self, "_store", store)
        object.__setattr__(self, "_param", param)
        object.__setattr__(self, "_instance", instance)
        object.__setattr__(self, "_prefix", prefix)
        #: The instance's key, which every leaf's key is made from.
        object.__setattr__(self, "_key", store._instance_key(param, instance))

    @property
    def name(self) -> str:
        """``INA238#0``."""
        return str(self._key)

    @property
    def value(self) -> Any:
        """The whole value (of the nested part, for a nested view)."""
        whole = self._store.get(self._key)
        for step in filter(None, self._prefix.split(".")):
            whole = whole[step]
        return whole

    @property
    def default(self) -> Any:
        """The instance's default value."""
        return self._store.get(self._key, default=True)

    def set(self, value: Mapping[str, Any]) -> None:
        """Sets the whole value."""
        if self._prefix:
            raise InstanceError(f"{self.name}.{self._prefix}: set whole values on the instance")
        self._store.set(self._key, value)

    def leaves(self) -> list[Leaf]:
        """Every leaf in ``[k]`` order."""
        return self._store.leaves(self._key)

    def _target(self, item: int | str) -> Key:
        if isinstance(item, int) and not isinstance(item, bool):
            if self._prefix:
                raise InstanceError(f"{self.name}.{self._prefix}: [k] counts from the instance")
            return self._key.at(item)
        return self._key.at(f"{self._prefix}{item}")

    def __getitem__(self, item: int | str) -> Any:
        return self._store.leaf(self._target(item)).value

    def __setitem__(self, item: int | str, value: Any) -> None:
        self._store.set(self._target(item), value)

    def __getattr__(self, attr: str) -> Any:
        if attr.startswith("__"):
            raise AttributeError(attr)
        path = f"{self._prefix}{attr}"
        try:
            return self._store.leaf(self._key.at(path)).value
        except LeafError as e:  # a struct or union: walk into it
            if "not a leaf" not in str(e):
                raise
        return InstanceView(self._store, self._param, self._instance, f"{path}.")

    def __setattr__(self, attr: str, value: Any) -> None:
        self._store.set(self._key.at(f"{self._prefix}{attr}"), value)

    def __repr__(self) -> str:
        return f"<{self.name}{'.' + self._prefix[:-1] if self._prefix else ''} {self.value!r}>"


def _classic_bytes(param: ClassicParam, value: Any) -> bytes:
    number = classic_value(param.type, value)
    return struct.pack("<f" if param.is_float else "<i", number)


def _classic_from_bytes(param: ClassicParam, data: bytes) -> int | float:
    value: int | float = struct.unpack("<f" if param.is_float else "<i", data)[0]
    return value


class _Transaction:
    """:meth:`Store.transaction` (a class: ``contextlib`` costs every command 1 ms to import)."""

    def __init__(self, store: Store) -> None:
        self._store = store

    def __enter__(self) -> Store:
        store = self._store
        self._backup, self._foreign = store._native.copy(), dict(store._foreign)
        return store

    def __exit__(self, kind: object, error: object, trace: object) -> None:
        if kind is not None:  # BaseException included: an interrupt changes nothing either
            self._store._native.restore(self._backup)
            self._store._foreign = self._foreign


def _flat_check_file(store: Store) -> tuple[str, str] | None:
    """Where the verdict of the flat-name check of ``store``'s schema and classic names is
    cached, and under which key; None for a schema not loaded through the model cache."""
    model_key = store.schema.model.get("key")
    if not isinstance(model_key, str):
        return None
    try:
        code = os.stat(_FLAT_MODULE)
    except OSError:
        return None
    classic = ",".join(sorted(p.name for p in store._order if p.classic is not None))
    key = (
        f"px4params-flat-check {code.st_size} {code.st_mtime_ns}\n{model_key}\n"
        f"classic {binascii.crc32(classic.encode()):08x} {len(classic)}"
    )
    return cache_path(default_cache_dir(), "flatcheck", key), key
