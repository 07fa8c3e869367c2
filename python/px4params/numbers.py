"""Numbers from users and files, parsed with bounds that no valid value comes near.

No parameter, leaf, instance number or device ID field is wider than 64 bits, so an integer of
more than :data:`MAX_DIGITS` digits is out of range whatever it names. Python refuses to
convert more than 4300 digits at all (and takes quadratic time below that), so a long number
is refused here, before conversion, with a message that names it shortly.

Floats follow one rule everywhere: a finite number written out of float64's range (``1e400``)
is refused, not read as infinity; infinities and NaN are written ``inf``, ``-inf`` and ``nan``
(as strings in JSON, whose numbers have none).
"""

from __future__ import annotations

import math
import sys

from px4params.errors import DuplicateKeyError, NestingError, NumberError

#: The largest finite float16, float32 and float64, by width in bits: beyond them a value is
#: out of a float field's range (an infinity where the field truncates).
FLOAT_MAX = {16: 65504.0, 32: 3.4028234663852886e38, 64: sys.float_info.max}

__all__ = [
    "MAX_DIGITS",
    "NumberError",
    "abbreviated",
    "counted",
    "dump_json",
    "load_json",
    "parse_float",
    "parse_int",
]

#: Far beyond 64 bits (20 decimal digits), far below Python's limit of 4300.
MAX_DIGITS = 64


def abbreviated(text: str) -> str:
    """``text`` itself when short, else its ends and its length: ``999999...999999 (5000
    digits)``; a character that does not print (a NUL, an escape, a tab) as Python writes it
    in a string (``15\\x000``): messages show what was given, and no terminal control."""
    text = text.strip()
    if not text.isprintable():
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    if len(text) <= 32:
        return text
    return f"{text[:12]}...{text[-6:]} ({len(text)} characters)"


def parse_int(text: str, base: int = 10) -> int:
    """``text`` (already checked to be an integer literal of ``base``; sign and ``0x`` allowed)
    as an int.

    Raises:
        NumberError: more than :data:`MAX_DIGITS` digits.
    """
    digits = text.strip().lstrip("+-")
    if digits[:2].lower() in ("0x", "0b", "0o"):
        digits = digits[2:]
    if len(digits) > MAX_DIGITS:
        raise NumberError(
            f"{abbreviated(text)} is out of range ({len(digits)} digits: no value is wider "
            "than 64 bits)"
        )
    return int(text.strip(), base)


def parse_float(text: str, *, stored: bool = False) -> float:
    """``text`` as a float: ``inf``/``nan`` as written; a finite number beyond float64's range
    (``1e400``) is refused. ``stored``: for a store's value, which takes finite numbers only,
    so the refusal does not suggest writing ``inf``.

    Raises:
        NumberError: out of float64's range.
        ValueError: not a number.
    """
    value = float(text)
    if math.isinf(value) and "inf" not in text.lower():
        hint = "a stored float is a finite number" if stored else "write inf or -inf for infinity"
        raise NumberError(f"{abbreviated(text)} is out of range of a float64 ({hint})")
    return value


def _stored_float(text: str) -> float:
    return parse_float(text, stored=True)


def _json_int(text: str) -> int:
    return parse_int(text)


_CONSTANTS = {"Infinity": "inf", "-Infinity": "-inf", "NaN": "nan"}


def _json_constant(name: str) -> float:
    raise NumberError(f'{name} is not JSON; write "{_CONSTANTS[name]}" (a string) instead')


def load_json(text: str, *, stored: bool = False) -> object:
    """``json.loads`` with the bounds above: long integers, ``1e400`` and the non-standard
    ``Infinity``/``NaN`` are refused (:class:`NumberError`), and an object naming a key twice
    (:class:`DuplicateKeyError`, a NumberError), and nesting deeper than Python's recursion
    limit (:class:`NestingError`, a NumberError); other errors are as ``json.loads`` raises
    them. ``stored``: as :func:`parse_float` takes it."""
    import json  # here: a command that reads no JSON does not pay 2 ms to import it

    try:
        return json.loads(
            text,
            parse_int=_json_int,
            parse_float=_stored_float if stored else parse_float,
            parse_constant=_json_constant,
            object_pairs_hook=_json_object,
        )
    except RecursionError:  # (Python's words: "maximum recursion depth exceeded while ...")
        raise NestingError(
            f"JSON nested deeper than this reader goes ({sys.getrecursionlimit()} levels; a "
            "parameter's value has a few)"
        ) from None


def _json_object(pairs: list[tuple[str, object]]) -> dict[str, object]:
    found: dict[str, object] = {}
    for key, value in pairs:
        if key in found:
            raise DuplicateKeyError(f"the key {abbreviated(key)!r} is given twice in one object")
        found[key] = value
    return found


def dump_json(value: object, separators: tuple[str, str] = (", ", ": ")) -> str:
    """``json.dumps(value, separators=separators)``, written here for plain values (numbers,
    ASCII strings, lists, dicts with string keys): importing ``json`` imports ``re``, which
    costs a short command a third of Python's start. Anything else is json's to write."""
    parts: list[str] = []
    try:
        plain = _json_parts(value, parts, *separators)
    except RecursionError:  # deep, or a cycle (which json reports)
        plain = False
    if plain:
        return "".join(parts)
    import json

    return json.dumps(value, separators=separators)


def _json_parts(value: object, parts: list[str], item: str, key: str) -> bool:
    """Appends ``value``'s JSON text to ``parts``; False if it is not a plain value."""
    if isinstance(value, str):
        if not (value.isascii() and value.isprintable()) or '"' in value or "\\" in value:
            return False  # escapes: json's
        parts.append(f'"{value}"')
    elif value is None or value is True or value is False:
        parts.append("null" if value is None else "true" if value else "false")
    elif isinstance(value, int):
        parts.append(int.__repr__(value))
    elif isinstance(value, float):
        if not math.isfinite(value):
            return False  # NaN, Infinity: json's
        parts.append(float.__repr__(value))
    elif isinstance(value, (list, tuple)):
        parts.append("[")
        for i, element in enumerate(value):
            if i:
                parts.append(item)
            if not _json_parts(element, parts, item, key):
                return False
        parts.append("]")
    elif isinstance(value, dict):
        parts.append("{")
        for i, (name, element) in enumerate(value.items()):
            if i:
                parts.append(item)
            if not isinstance(name, str) or not _json_parts(name, parts, item, key):
                return False
            parts.append(key)
            if not _json_parts(element, parts, item, key):
                return False
        parts.append("}")
    else:
        return False
    return True


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """``count`` and ``noun``, made plural unless it is one: ``counted(1, "instance")`` is
    ``1 instance``, ``counted(2, "probe attempt")`` ``2 probe attempts``.

    >>> counted(1, "timeout"), counted(0, "timeout"), counted(3, "entry", "entries")
    ('1 timeout', '0 timeouts', '3 entries')
    """
    return f"{count} {noun if count == 1 else plural or noun + 's'}"
