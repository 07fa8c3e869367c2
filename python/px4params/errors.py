"""Exceptions raised by px4params.

The names and attributes here are a stable interface: the native extension imports these classes
(rather than defining its own) so that Python callers can catch one hierarchy.
"""

from __future__ import annotations

import os

__all__ = [
    "BenchFileError",
    "BoardsError",
    "BoardsFileError",
    "ClassicParamsError",
    "CodecError",
    "CommandError",
    "DecodeError",
    "DeviceIdError",
    "DriversFileError",
    "DronecanError",
    "DsdlError",
    "DuplicateKeyError",
    "EncodeError",
    "FlatError",
    "InputFileError",
    "InstanceError",
    "LeafError",
    "ManifestError",
    "MetadataError",
    "MigrationError",
    "NestingError",
    "NumberError",
    "OutputFileError",
    "ParamFileError",
    "ParameterSetError",
    "Px4ParamsError",
    "SigningKeyError",
    "SlcanError",
    "StoreConflictError",
    "StoreError",
    "StoreFileError",
    "TransferError",
    "ULogError",
    "ValueRangeError",
    "ValueShapeError",
]


class Px4ParamsError(Exception):
    """Base class of every error px4params raises on purpose."""


class DsdlError(Px4ParamsError):
    """A DSDL definition or its metadata is invalid, or could not be read.

    Attributes:
        file: path of the offending file (or root folder), if known.
        line: 1-based line number in ``file``, if known.
        message: the description without the location prefix.

    ``str()`` is a single line in compiler style: ``file:line: message``.
    """

    def __init__(
        self,
        message: str,
        file: str | os.PathLike[str] | None = None,
        line: int | None = None,
    ) -> None:
        # Pass every argument to Exception so that pickling/copying rebuilds the same error.
        super().__init__(message, file, line)
        self.message = message
        self.file: str | None = os.fspath(file) if file is not None else None
        self.line = line

    def __str__(self) -> str:
        # Parser messages may span lines; the contract is one line per error. (``re`` here:
        # importing it costs a short command as much as a third of Python's start.)
        import re

        text = re.sub(r"\s*\n\s*", " ", self.message).strip()
        if self.file is not None and self.line is not None:
            return f"{self.file}:{self.line}: {text}"
        if self.file is not None:
            return f"{self.file}: {text}"
        return text


class CodecError(Px4ParamsError):
    """A value could not be serialised or deserialised with the DroneCAN rules.

    Attributes (set by whoever raises it):
        path: where in the value the problem is, e.g. ``"bus.i2c.address"`` or ``"[4]"``.
        bit_offset: bit position in the serialised data, or None when not applicable.
        index: which item of a batch call (``encode_many``, ``decode_many``) failed, else None.
    """

    index: int | None = None


class EncodeError(CodecError):
    """A value could not be encoded (out of range, wrong type, too long, ...)."""


class DecodeError(CodecError):
    """Bytes could not be decoded into a value (truncated, invalid union tag, ...)."""


class ValueShapeError(EncodeError):
    """A value does not have the shape of its type (missing or unknown fields, wrong nesting)."""


class NumberError(Px4ParamsError, ValueError):
    """A number out of every range before it is even converted (thousands of digits, ``1e400``),
    or a JSON constant (``Infinity``, ``NaN``) that JSON does not have."""


class NestingError(NumberError):
    """JSON nested deeper than Python's reader goes (its recursion limit). A
    :class:`NumberError` for the reason :class:`DuplicateKeyError` is one."""


class DuplicateKeyError(NumberError):
    """A JSON object that names one key twice (JSON leaves its meaning open; Python's reader
    would keep the last silently). A :class:`NumberError` so that every reader of JSON values
    (:func:`px4params.numbers.load_json`) reports it where it reports those."""


class LeafError(CodecError, LookupError):
    """No leaf at that ``[k]`` index or path, or the path runs through an unselected variant."""


class InputFileError(Px4ParamsError, OSError):
    """A file given to read that is not a regular file (a FIFO, a device, a socket, a folder) or
    is larger than its kind of file can be (:mod:`px4params.reading`); nothing of it was read.

    It is an ``OSError`` too (``errno`` EINVAL or EFBIG, ``strerror`` the reason, ``filename``
    the path), so that a caller reporting ``cannot read: {strerror}`` reports it. ``str()`` is
    one line: ``FILE: is a FIFO (named pipe), not a regular file``.
    """

    def __str__(self) -> str:
        return f"{self.filename}: {self.strerror}"


class OutputFileError(Px4ParamsError, OSError):
    """A file that cannot be written (:mod:`px4params.writing`): not a regular file (a FIFO, a
    device, a folder), read-only, or the write failed; the file is left as it was and no
    temporary file stays.

    It is an ``OSError`` too (``strerror`` the reason, ``filename`` the path). ``str()`` is one
    line: ``FILE: cannot write: a FIFO, not a regular file``.
    """

    def __str__(self) -> str:
        return f"{self.filename}: {self.strerror}"


class TransferError(Px4ParamsError):
    """CAN frames do not form one valid DroneCAN transfer (wrong toggle or tail bits, mixed
    transfer IDs, missing first or last frame, repeated or reordered frames, CRC mismatch).

    ``str()`` is a single line.
    """


class SigningKeyError(Px4ParamsError):
    """A MAVLink 2 signing key file that cannot be used (missing, or not 32 bytes / 64 hex
    digits). ``str()`` is one line naming the file."""


class StoreError(Px4ParamsError):
    """A store operation was refused; the store is left exactly as it was."""


class InstanceError(StoreError, LookupError):
    """An unknown parameter, an instance number at or above ``max_instances``, an instance that
    does not exist or exists already, or no free instance left."""


class ValueRangeError(StoreError, ValueError):
    """A value outside its field's ``@min``/``@max`` or not in its ``@value`` list, or a NaN or
    infinity where the type takes none; nothing was written.

    Attributes:
        bounds_only: True when only ``@min``/``@max`` or the ``@value`` list were broken (what
            ``param set --force`` may override); False for a non-finite float, which nothing
            overrides.
    """

    def __init__(self, message: str, *, bounds_only: bool = False) -> None:
        super().__init__(message)
        self.bounds_only = bounds_only


class StoreFileError(StoreError):
    """A store file cannot be used: not ours, another format version or schema, truncated, or
    corrupted (a CRC mismatch). Nothing of it was applied.

    Attributes:
        file: the file's path.
        offset: byte offset of the problem in the file, when known.
    """

    def __init__(self, message: str, file: str | os.PathLike[str], offset: int | None = None):
        super().__init__(message, file, offset)
        self.message = message
        self.file = os.fspath(file)
        self.offset = offset

    def __str__(self) -> str:
        where = f" (at byte {self.offset})" if self.offset is not None else ""
        return f"{self.file}: {self.message}{where}"


class StoreConflictError(StoreError):
    """A change refused because another writer changed the same thing since this one read the
    store: the same leaf (or classic parameter) to another value, or the instance it edits
    removed. Nothing was written; the message names the first such leaf and how many there are.
    """


class SlcanError(Px4ParamsError):
    """An SLCAN line that is not a frame, or an adapter that does not answer as one should."""


class DronecanError(Px4ParamsError):
    """The remote DroneCAN node did not answer, answered something else, or refused."""


class DeviceIdError(Px4ParamsError):
    """A PX4 device ID, one of its parts, a devtype table or a flight log could not be used
    (out of range, unknown name, unreadable file, ...). ``str()`` is a single line.
    """


class MetadataError(Px4ParamsError):
    """The parameter set cannot be written as one ``parameters.json`` (e.g. a name clash)."""


class ParameterSetError(Px4ParamsError):
    """The DSDL types do not make a valid parameter set (e.g. two types with one name)."""


class FlatError(ParameterSetError):
    """A type or parameter set cannot be destructured (a leaf wider than 32 bits, a name longer
    than 16 characters or clashing with another), or a flat name or value is refused."""


class ClassicParamsError(Px4ParamsError):
    """A ``parameters.json`` that cannot be used, or a classic value of the wrong kind."""


class ParamFileError(Px4ParamsError):
    """A ``.params`` or JSON parameter file that cannot be used; names the file and line.

    Attributes:
        bounds_only: True when the file was refused only for a value outside its field's
            ``@min``/``@max`` or ``@value`` list (what ``param load --force`` takes).
    """

    def __init__(self, message: str, *, bounds_only: bool = False) -> None:
        super().__init__(message)
        self.bounds_only = bounds_only


class MigrationError(Px4ParamsError):
    """The configuration cannot be read (missing, not a ``.params`` file or ULog, malformed)."""


class BenchFileError(Px4ParamsError):
    """A bench file cannot be used. ``str()`` is one line: file, entry, problem."""


class DriversFileError(Px4ParamsError):
    """The driver declarations cannot be used. ``str()`` is one line: file, driver, problem."""


class BoardsError(Px4ParamsError):
    """A board look-up that cannot be answered as asked (a release that is no PX4 version)."""


class BoardsFileError(BoardsError):
    """The board table (``boards.toml``) cannot be used. ``str()`` is one line: file, row,
    problem."""


class ManifestError(Px4ParamsError):
    """There is no manifest to boot (no store file, or an airframe file that fails)."""


class ULogError(Px4ParamsError):
    """A flight log (ULog) that cannot be written as asked, or read back as a log of
    ``px4params autostart run --ulog``."""


class ReadBudgetExceeded(Exception):
    """A library read more of a file than its budget (:func:`px4params.formats.ulog.parse`
    turns it into a :class:`ULogError`). Not a ``ValueError`` or ``IndexError``: pyulog
    catches those and goes on."""


class SeekBeforeStart(Exception):
    """A library asked to move to before a file's first byte (pyulog steps back over a damaged
    message by the size the message claims, which can be more than it read);
    :func:`px4params.formats.ulog.parse` turns it into a :class:`ULogError` naming where.

    Attributes:
        position: the byte the library stood at.
        offset: the move it asked for (negative).
    """

    def __init__(self, position: int, offset: int) -> None:
        super().__init__(f"a seek by {offset} from byte {position}")
        self.position = position
        self.offset = offset


class CommandError(Px4ParamsError):
    """A command that failed (a ``param`` verb, an airframe line, a CLI command): reported as
    one line, exit status 1."""


# -- Signals within one module ---------------------------------------------------------------
# Raised and caught inside the module named; never reach a caller, so not in ``__all__``. They
# are here because every exception class of the package is (tests/test_errors.py). The one
# exception to that rule: ``px4params.gcs.codec``'s, as that file is copied into ground stations
# alone (an import-linter contract keeps it from importing this module).


class LeftToArgparse(Exception):
    """:mod:`px4params.cli.parsing`: its small interpreter leaves this command line to argparse."""


class TagValueError(Exception):
    """:mod:`px4params.dsdl.loader` and :mod:`px4params.dsdl.model`: a metadata tag's value is
    invalid; the caller adds the tag's name and location and raises :class:`DsdlError`."""


class KeepRunningValues(Exception):
    """:mod:`px4params.store.session`: undoes ``Session.rewrite``'s change of the running
    values on purpose (the transaction rolls back, the file keeps the change)."""


class NshArgumentError(Exception):
    """:mod:`px4params.nsh.airframe`: argparse's usage error on one NSH command line, reported
    as that line's error."""
