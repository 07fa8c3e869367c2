"""A parameter's name, parsed once where it enters (a command's argument, a file's line, a
page's request) into a :class:`Key`: parameter, instance and leaf. Every layer below takes the
key; a name is text again only where it is shown. The naming rule (``NAME#N``, or ``NAME`` for
a shared or classic parameter) is :meth:`Key.__str__`'s alone."""

from __future__ import annotations

from px4params._records import TYPE_CHECKING
from px4params.errors import InstanceError
from px4params.numbers import abbreviated

if TYPE_CHECKING:  # typing costs a command 5 ms: see px4params._records
    from typing import NamedTuple
else:
    from px4params._records import NamedTuple

__all__ = ["MAX_INSTANCE", "MAX_LEAF", "Key"]

#: A name: ``NAME``, ``NAME#N``, then ``[k]`` or ``.path``. :func:`_split_key` reads it by hand
#: (``re`` costs a short command a third of Python's start); the tests hold it to this.
_KEY = (
    r"(?P<name>[A-Za-z][A-Za-z0-9_]*)(?:#(?P<instance>0|[1-9][0-9]*))?"
    r"(?:\[(?P<index>0|[1-9][0-9]*)\]|\.(?P<path>[A-Za-z_][A-Za-z0-9_.\[\]]*))?"
)
_LETTERS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz")
_NAME_START = _LETTERS
_NAME_REST = _LETTERS | frozenset("0123456789_")
_PATH_START = _LETTERS | frozenset("_")
_PATH_REST = _NAME_REST | frozenset(".[]")


def _split_key(
    text: str, leading_zeros: bool = False
) -> tuple[str, str | None, str | None, str | None] | None:
    """The groups name, instance, index and path of ``re.fullmatch(_KEY, text)``, or None.
    (Each part ends at a character it cannot hold: the expression never backtracks.) A number
    is written without leading zeros, so that one instance has one name (``INA238#01`` is
    ``INA238#1`` typed inexactly); ``leading_zeros`` lets them through, for the hint."""
    end = len(text)
    if not end or text[0] not in _NAME_START:
        return None
    i = 1
    while i < end and text[i] in _NAME_REST:
        i += 1
    name = text[:i]
    instance = index = path = None
    if i < end and text[i] == "#":
        j = _number_end(text, i + 1, leading_zeros)
        if j == i + 1:
            return None
        instance, i = text[i + 1 : j], j
    if i < end and text[i] == "[":
        j = _number_end(text, i + 1, leading_zeros)
        if j == i + 1 or j == end or text[j] != "]":
            return None
        index, i = text[i + 1 : j], j + 1
    elif i < end and text[i] == ".":
        if i + 1 == end or text[i + 1] not in _PATH_START:
            return None
        j = i + 2
        while j < end and text[j] in _PATH_REST:
            j += 1
        path, i = text[i + 1 : j], j
        if not leading_zeros and _zero_led_index(path):
            return None
    return (name, instance, index, path) if i == end else None


def _zero_led_index(path: str) -> bool:
    """Whether an index in ``path`` (``arr[01]``) is written with a leading zero."""
    at = path.find("[0")
    while at >= 0:
        if at + 2 < len(path) and path[at + 2] in _DIGITS:
            return True
        at = path.find("[0", at + 2)
    return False


def _without_leading_zeros(path: str) -> str:
    """``path`` with its indices written without leading zeros (``arr[007]`` -> ``arr[7]``)."""
    parts = path.split("[")
    for n, part in enumerate(parts[1:], 1):
        digits = _number_end(part, 0, True)
        if digits > 1:
            parts[n] = str(int(part[:digits])) + part[digits:]
    return "[".join(parts)


#: Digits of a name: ASCII only, as PX4's (``str.isdecimal`` would take ``٣`` for 3).
_DIGITS = frozenset("0123456789")


def _number_end(text: str, i: int, leading_zeros: bool) -> int:
    """Where the number's ASCII digits from ``i`` end; ``i`` (no number) when a leading zero
    is not allowed and they have one."""
    j = i
    while j < len(text) and text[j] in _DIGITS:
        j += 1
    return i if not leading_zeros and j > i + 1 and text[i] == "0" else j


def _exact_name_hint(text: str) -> str | None:
    """The name ``text`` was probably meant to be, written exactly (no padding, the parameter
    part in upper case, ASCII digits without leading zeros), when that is a name and not
    ``text``; else None."""
    import unicodedata

    candidate = "".join(
        str(unicodedata.decimal(c)) if c.isdecimal() and c not in _DIGITS else c
        for c in text.strip()
    )
    match = _split_key(candidate, leading_zeros=True)
    if match is None:
        return None
    name, instance, index, path = match
    exact = name.upper()
    if instance is not None:
        exact += f"#{int(instance)}"
    if index is not None:
        exact += f"[{int(index)}]"
    elif path is not None:
        exact += f".{_without_leading_zeros(path)}"
    return exact if exact != text else None


#: Instance numbers are 16-bit in the core (``max_instances`` is far below).
MAX_INSTANCE = 0xFFFF
#: Leaf numbers beyond this name no leaf of any storable value.
MAX_LEAF = 1 << 31


class Key(NamedTuple):
    """A parsed name: parameter, instance (None for shared and classic ones) and leaf."""

    param: str
    instance: int | None
    leaf: int | str | None

    @classmethod
    def parse(cls, text: str | Key) -> Key:
        """``text`` parsed (a :class:`Key` is returned as it is: a name typed by a user is parsed
        once, where it enters, and the key is passed on)."""
        if isinstance(text, Key):
            return text
        if not isinstance(text, str):  # the Python API: a list or a number is no name either
            raise InstanceError(
                f"{abbreviated(repr(text))} is not a parameter name (a {type(text).__name__}; "
                "expected text or a Key)"
            )
        match = _split_key(text)
        if match is not None and match[0] != match[0].upper():
            match = None  # lower case: PX4's names are exact
        if not match:
            hint = _exact_name_hint(text) if len(text) <= 1000 else None
            if hint is not None:
                shown = text if len(text) <= 32 else abbreviated(text)  # padding shown
                raise InstanceError(
                    f"'{shown}' is not a parameter name: names are exact, in upper case with "
                    f"ASCII digits and no spaces, as PX4's (did you mean {hint}?)"
                )
            raise InstanceError(
                f"'{abbreviated(text)}' is not a parameter name (expected NAME, NAME#N, "
                "NAME#N[k] or NAME#N.path, e.g. INA238#0.bus.i2c.address)"
            )
        name, instance, index, path = match
        # (digits counted first: Python will not convert thousands of them)
        if instance is not None and (len(instance) > 5 or int(instance) > MAX_INSTANCE):
            raise InstanceError(
                f"{abbreviated(text)}: instance {abbreviated(instance)} is out of range"
            )
        leaf: int | str | None = None
        if index is not None:
            if len(index) > 10 or int(index) > MAX_LEAF:
                raise InstanceError(f"{abbreviated(text)}: no leaf [{abbreviated(index)}]")
            leaf = int(index)
        elif path is not None:
            leaf = path
        return cls(name, int(instance) if instance else None, leaf)

    def at(self, leaf: int | str) -> Key:
        """Leaf ``[k]`` (an int) or path ``leaf`` of this key's instance or parameter, checked
        as :meth:`parse` checks a name's leaf part (and refused in its words)."""
        kind = type(leaf)
        if kind is int:
            if 0 <= leaf <= MAX_LEAF:  # type: ignore[operator]
                return _new_key(Key, (self[0], self[1], leaf))
            return Key.parse(f"{self.whole}[{leaf}]")  # which refuses it
        if kind is str and leaf[:1] in _PATH_START and _PATH_REST.issuperset(leaf):  # type: ignore[index,arg-type]
            return _new_key(Key, (self[0], self[1], leaf))
        return Key.parse(f"{self.whole}.{leaf}")  # which refuses it

    @property
    def whole(self) -> Key:
        """The instance or parameter, without the leaf."""
        return self if self.leaf is None else Key(self.param, self.instance, None)

    def __str__(self) -> str:
        name = self.param if self.instance is None else f"{self.param}#{self.instance}"
        if isinstance(self.leaf, int):
            return f"{name}[{self.leaf}]"
        return name if self.leaf is None else f"{name}.{self.leaf}"

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)  # (a tuple takes no format spec: "{key:<14}")


#: A key from parts already checked (``Key(...)`` is a Python call: a write pays for it).
_new_key = tuple.__new__
