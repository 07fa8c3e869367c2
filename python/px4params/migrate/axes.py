"""Driver rotations across PX4 releases whose drivers changed the axes they report.

A driver's ``-R`` is applied after the driver's own axis mapping, so where a release changed that
mapping for a chip (the IST8310 rewrite of PX4 1.12 reports ``(x, y, -z)`` where 1.11 reported
``(y, x, z)``), the same ``-R N`` is another orientation. ``data/driver_axes.toml`` lists each
change with C, the rotation with ``old report = C · new report``: a rotation R of the old release
is ``R ∘ C`` (C applied first) on the new one. The composition is computed from the rotations'
matrices (PX4's roll/pitch/yaw, :func:`matrix`), never looked up in a typed table.
"""

from __future__ import annotations

import functools
import importlib.resources
import math
import re
import tomllib
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from px4params.dsdl.loader import value_set
from px4params.errors import MigrationError
from px4params.vehicle.boards import BoardsError, release_version

__all__ = [
    "REMOVED_AT_1_12",
    "AxesChange",
    "Turned",
    "changes",
    "composed",
    "matrix",
    "removed_rotation",
    "rotations",
    "turn",
]

Matrix = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]

#: A release newer than every numbered one (the board table's ``main``).
_NEWEST = (math.inf, math.inf)
_ANGLE = re.compile(r"(Roll|Pitch|Yaw) (\d+) deg")
_DATA = "driver_axes.toml"
_KEYS = {
    "modules": list,
    "old_through": str,
    "new_from": str,
    "rotation": int,
    "internal_rotation": int,
    "only_boards": list,
    "commit": str,
    "pr": int,
    "old_source": str,
    "new_source": str,
}
_REQUIRED = ("modules", "old_through", "new_from", "rotation", "commit", "old_source", "new_source")


def matrix(roll: float, pitch: float, yaw: float) -> Matrix:
    """The rotation matrix of PX4's Euler angles in degrees, as its rotation library builds it
    (``matrix::Dcmf{matrix::Eulerf{roll, pitch, yaw}}``: yaw, then pitch, then roll, 3-2-1)."""
    r, p, y = (math.radians(a) for a in (roll, pitch, yaw))
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    return (
        (cp * cy, -cr * sy + sr * sp * cy, sr * sy + cr * sp * cy),
        (cp * sy, cr * cy + sr * sp * sy, -sr * cy + cr * sp * sy),
        (-sp, sr * cp, cr * cp),
    )


@functools.cache
def rotations() -> dict[int, Matrix]:
    """PX4's rotation enum, value -> matrix, from value_sets.toml's ``[rotation]`` names
    ("Roll 180 deg, Yaw 90 deg": rotation.h's rot_lookup roll, pitch and yaw)."""
    found = {}
    for value, name in value_set("rotation").items():
        angles = dict.fromkeys(("Roll", "Pitch", "Yaw"), 0)
        words = _ANGLE.findall(name)
        if name != "No rotation" and ", ".join(f"{a} {d} deg" for a, d in words) != name:
            raise MigrationError(
                f"value_sets.toml: rotation {value} = {name!r}: expected 'Roll R deg, Pitch P "
                "deg, Yaw Y deg' (each part optional) or 'No rotation'"
            )
        angles.update((a, int(d)) for a, d in words)
        found[int(value)] = matrix(angles["Roll"], angles["Pitch"], angles["Yaw"])
    return found


def _product(a: Matrix, b: Matrix) -> Matrix:
    rows = [tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)) for i in range(3)]
    return rows[0], rows[1], rows[2]  # type: ignore[return-value]


def _transposed(a: Matrix) -> Matrix:
    return (a[0][0], a[1][0], a[2][0]), (a[0][1], a[1][1], a[2][1]), (a[0][2], a[1][2], a[2][2])


def _value_of(m: Matrix) -> int | None:
    """The lowest enum value whose matrix is ``m`` (10 before its alias 27); None if none."""
    for value, known in sorted(rotations().items()):
        pairs = zip(sum(m, ()), sum(known, ()), strict=True)
        if all(math.isclose(x, y, abs_tol=1e-9) for x, y in pairs):
            return value
    return None


def composed(first: int, then: int, inverse: bool = False) -> int | None:
    """``then ∘ first``: the enum value of rotating by ``first``, then by ``then`` (None where
    no value names it); ``inverse``: by ``first``'s inverse."""
    table = rotations()
    a = _transposed(table[first]) if inverse else table[first]
    return _value_of(_product(table[then], a))


@dataclass(frozen=True)
class AxesChange:
    """One driver's axes change (a ``[[change]]`` of driver_axes.toml)."""

    modules: tuple[str, ...]
    old_through: str
    new_from: str
    rotation: int
    internal_rotation: int | None
    only_boards: tuple[str, ...]
    commit: str
    pr: int | None
    old_source: str
    new_source: str

    def side(self, release: str | tuple[int, ...] | None) -> str | None:
        """``old`` or ``new``: the axes a release's driver reports (None: the newest, ``new``);
        None for a release between the two the facts were read at."""
        series = _series(release)
        if series <= _series(self.old_through):
            return "old"
        return "new" if series >= _series(self.new_from) else None

    @property
    def cite(self) -> str:
        pr = f", PR #{self.pr}" if self.pr is not None else ""
        return f"PX4 commit {self.commit}{pr}"


def _series(release: str | tuple[int, ...] | None) -> tuple[float, float]:
    if release is None or release == "main":
        return _NEWEST
    if isinstance(release, tuple):
        return float(release[0]), float(release[1])
    major, minor, _ = release_version(release)
    return float(major), float(minor)


@functools.cache
def changes() -> tuple[AxesChange, ...]:
    """The bundled table, each key checked."""
    text = importlib.resources.files("px4params.data").joinpath(_DATA).read_text(encoding="utf-8")
    return parse_changes(tomllib.loads(text))


def parse_changes(top: dict[str, Any]) -> tuple[AxesChange, ...]:
    """driver_axes.toml's ``[[change]]`` tables; a key missing, unknown or of the wrong type, a
    release or rotation that is none is refused in one line naming the change and the key."""
    out = []
    for i, row in enumerate(top.get("change", ()), 1):
        where = f"{_DATA}: change {i}"
        for key in set(row) - set(_KEYS):
            raise MigrationError(f"{where}: unknown key {key!r} (expected {', '.join(_KEYS)})")
        for key in _REQUIRED:
            if key not in row:
                raise MigrationError(f"{where}: {key} missing")
        for key, value in row.items():
            if not isinstance(value, _KEYS[key]) or isinstance(value, bool):
                raise MigrationError(
                    f"{where}: {key} = {value!r}: expected a {_KEYS[key].__name__}"
                )
        for key in ("rotation", "internal_rotation"):
            if key in row and row[key] not in rotations():
                raise MigrationError(
                    f"{where}: {key} = {row[key]}: not a value of PX4's rotation enum"
                )
        for key in ("old_through", "new_from"):
            try:
                release_version(row[key])
            except BoardsError as e:
                raise MigrationError(f"{where}: {key}: {e}") from None
        out.append(
            AxesChange(
                tuple(row["modules"]),
                row["old_through"],
                row["new_from"],
                row["rotation"],
                row.get("internal_rotation"),
                tuple(row.get("only_boards", ())),
                row["commit"],
                row.get("pr"),
                row["old_source"],
                row["new_source"],
            )
        )
    return tuple(out)


@dataclass(frozen=True)
class Turned:
    """What :func:`turn` made of a rotation: the ``rotation`` for the manifest's release, why
    (``why``: for the rotation's own reason) and the instance's note."""

    rotation: int
    why: str
    note: str
    #: Whose axes changed, when, and the PX4 commit ("" where the rotation is taken as is).
    what: str = ""


def turn(
    modules: Iterable[str],
    rotation: int,
    why: str,
    file_version: tuple[int, int, int] | None,
    release: str | None,
    internal: bool,
    board: str | None,
) -> Turned | None:
    """The rotation ``rotation`` (and ``why``) a driver of one of ``modules`` ran with at the
    file's ``file_version``, for the manifest's ``release`` (None: the newest): where the
    driver reports other axes there, the rotation giving the same orientation, said in one
    note; where that is not known (no release, an unchecked one, no board), the rotation as
    is, said why. None where no axes change lies between. ``internal``: on an internal bus;
    ``board``: the board's PX4 name (None: not known)."""
    names = set(modules)
    change = next((c for c in changes() if names & set(c.modules)), None)
    if change is None or rotation not in rotations():
        # a value PX4's enum lacks (v1.11's 41-45, a corrupt log's) is not turned: the
        # rotation field's range check reports it
        return None
    module = change.modules[0]
    if len(change.modules) > 1:  # renamed: the old release's name, and today's
        module = f"{change.modules[0]} (today {change.modules[-1]})"
    c = change.rotation
    bus = ""
    if change.internal_rotation is not None:  # the old driver's report depended on the bus
        c = change.internal_rotation if internal else change.rotation
        bus = " on an internal bus" if internal else " on an external bus"
    what = f"{module}{bus} reports other axes from PX4 {change.new_from} ({change.cite})"
    then = change.side(release)
    own = change.side(file_version) if file_version is not None else None
    if file_version is not None and own == then:
        return None
    if change.only_boards and board not in change.only_boards:
        if board is None:
            built = ", ".join(change.only_boards)
            return _as_is(
                rotation,
                why,
                f"{what} where the build had the old driver ({built}), and the board is not known",
            )
        return None
    if own is not None and then is None:
        # the target's axes are the unknown: what the rotation becomes on each side read
        turned = composed(c, rotation, inverse=own == "new")
        since = (
            f"PX4 {change.new_from} or newer"
            if own == "old"
            else f"PX4 {change.old_through} or older"
        )
        would = f"it is {turned}" if turned is not None else "no -R value names it"
        return _as_is(
            rotation,
            why,
            f"{what}, and the axes of PX4 {release} were not checked "
            f"(PX4 {change.old_through} reports the old ones): for {since} {would}",
        )
    if own is None or then is None:
        # the other side's rotation, for the one who knows the file's release
        other, since = (
            ("old", f"PX4 {change.old_through} or older")
            if then == "new"
            else ("new", f"PX4 {change.new_from} or newer")
        )
        turned = composed(c, rotation, inverse=other == "new")
        would = (
            f"for a file of {since} it is {turned}"
            if turned is not None
            else (f"for a file of {since} no -R value names it")
        )
        if file_version is None:
            return _as_is(rotation, why, f"the file names no PX4 release, and {what}: {would}")
        shown = "v" + ".".join(map(str, file_version))
        return _as_is(
            rotation,
            why,
            f"{what}, and the axes of PX4 {shown} were not checked "
            f"(PX4 {change.old_through} reports the old ones): {would}",
        )
    shown = "v" + ".".join(map(str, file_version or ()))
    new = composed(c, rotation, inverse=own == "new")
    if new is None:
        return _as_is(
            rotation,
            why,
            f"{what}, and no -R value gives its orientation of PX4 {shown} on the other axes "
            f"({rotation} after {c}): check it, and set it by calibration",
        )
    return Turned(
        new,
        f"{rotation} on PX4 {shown} ({why}), turned for {change.modules[-1]}'s axes",
        f"rotation {new} (was {rotation} on PX4 {shown}: {why}): {what}: the same orientation as "
        "before",
        what,
    )


#: PX4 1.11's rotations 41-45 as roll, pitch, yaw (src/lib/conversion/rotation.h's rot_lookup
#: at v1.11.0, 71db0903a9, lines 149-153), gone from v1.12.0 (00e955cc3e, "rotations: sync
#: rotation enum, SENS_BOARD_ROT, CAL_MAGx_ROT with MAV_SENSOR_ORIENTATION"): from then an
#: external magnetometer's CAL_MAGn_ROT beyond the enum is reset to 0 ("invalid rotation ...,
#: resetting to rotation none", src/lib/sensor_calibration/Magnetometer.cpp:160-164 at v1.12.0).
REMOVED_AT_1_12 = {
    41: (270, 0, 180),
    42: (270, 0, 270),
    43: (0, 90, 180),
    44: (0, 9, 180),
    45: (0, 45, 0),
}


def removed_rotation(
    param: str, value: float, file_version: tuple[int, int, int] | None, release: str | None
) -> str | None:
    """A note for ``param = value``, a rotation of PX4 1.11 that the manifest's ``release``
    (None: the newest) no longer has: PX4 resets it to 0, the value of the same rotation is
    said (computed from the angles), or that none is; None where nothing is lost."""
    angles = REMOVED_AT_1_12.get(int(value)) if float(value).is_integer() else None
    if angles is None or _series(release) < (1, 12):
        return None
    if file_version is not None and _series(file_version) >= (1, 12):
        return None  # PX4 of the file itself had reset it
    same = _value_of(matrix(*angles))
    then = (
        f"set {param} = {same}, the same rotation"
        if same is not None
        else "no value of today's enum is that rotation: calibrate the compass again"
    )
    number = int(value)
    return (
        f"{param} = {number}: PX4 1.12 and later have no rotation {number} (removed by PX4 "
        f"commit 00e955cc3e) and reset it to 0 at boot; {then}"
    )


def _as_is(rotation: int, why: str, because: str) -> Turned:
    return Turned(rotation, why, f"rotation {rotation} taken as is ({why}): {because}")
