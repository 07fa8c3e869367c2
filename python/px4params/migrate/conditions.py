"""A board row's condition (``when`` in the board table) evaluated as PX4's startup script tests
it, clause by clause, with what the configuration cannot tell kept apart and named.

A condition is clauses joined by `` and ``; a clause is an optional ``not `` before tests joined
by `` -o `` (the shell test's "or"). The tests, as ``scripts/transcribe_boards.py`` writes PX4's:

``NAME == 1``, ``NAME > 0`` (``param compare``, ``param greater``; ``!=``, ``>=``, ... alike)
    a parameter: settled by the configuration's value; not known where it has none
``$VAR == word``, ``$VAR != word``
    a variable of the board's script: settled where the builder derives it (``INA_CONFIGURED``
    from the power-monitor switches); one the hardware decides (:data:`HARDWARE_VARIABLES`, as
    the board's own script sets it) is settled where what the script tests is, else taken as
    the value the script sets first, and said so; any other is not known
``hw_type in A,B``
    the board's hardware type (``ver hwtypecmp``): settled by a log's ``ver_hw_subtype`` (the
    logger writes the same ``px4_board_sub_type()`` the command compares), else not known
``hw_base in A,B``, ``mft NAME == value``
    the board's base (``ver hwbasecmp``) and hardware manifest (``mft query``): not known
``board in A,B``
    the board (``ver hwcmp``): settled by the board's ``ver_hw`` names
``drv started (args)``
    an earlier start in the script succeeding: settled by a boot console, not known without one

A test of any other form is not known either, and its note says it could not be read: no
condition is ever taken as holding without a word.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

from px4params.vehicle.console import DriverStart

__all__ = [
    "HARDWARE_VARIABLES",
    "BoardVariables",
    "Facts",
    "HardwareVariable",
    "Setting",
    "Verdict",
    "board_variables",
    "evaluate",
    "per_bus",
]


@dataclass(frozen=True)
class Setting:
    """``set NAME value`` of a board's script, run where ``when`` holds (a condition of this
    module's form); ``line``: the line of the ``if`` that tests it."""

    value: str
    when: str
    line: int


@dataclass(frozen=True)
class HardwareVariable:
    """A board-script variable the hardware decides: the script sets it ``first`` on ``path``'s
    ``line``, then runs ``settings`` in its order (the last that runs decides; none: ``first``
    stays)."""

    first: str
    path: str
    line: int
    settings: tuple[Setting, ...] = ()


@dataclass(frozen=True)
class BoardVariables:
    """A board's hardware variables over the snapshots in ``releases``."""

    releases: tuple[str, ...]
    variables: Mapping[str, HardwareVariable]

    def __post_init__(self) -> None:
        # Callers get this mapping itself (board_variables): a read-only view keeps the table
        # as PX4's scripts have it.
        object.__setattr__(self, "variables", MappingProxyType(dict(self.variables)))


#: ``mft query -q -k MFT -s MFT_PM2 -v 0``: the board's hardware manifest lists no second
#: power-module port.
_NO_PM2_PORT = "mft MFT_PM2 == 0"
_LATER = ("v1.15.0", "v1.18", "main")
_NOW = ("v1.18", "main")
_SINCE_1_12 = ("v1.12.0", "v1.13.0", "v1.14.0", "v1.15.0", "v1.18", "main")


def _pm(releases: tuple[str, ...], path: str, line: int, when: str | None, when_line: int = 0,
        pm3: bool = False) -> BoardVariables:  # fmt: skip
    """HAVE_PM2 (and HAVE_PM3, set on the next line) yes, then no where ``when`` holds."""
    names = ("HAVE_PM2", "HAVE_PM3") if pm3 else ("HAVE_PM2",)
    settings = (Setting("no", when, when_line),) if when is not None else ()
    return BoardVariables(releases, {
        name: HardwareVariable("yes", path, line + i, settings) for i, name in enumerate(names)
    })  # fmt: skip


def _fmuv3(releases: tuple[str, ...], board: str, shift: int = 0) -> BoardVariables:
    """BOARD_FMUV3 of fmu-v2's and fmu-v3's script: 0, then 20 or 21 by which IMU answers on
    a Cube (``ver hwtypecmp V30``: an MPU6000 on SPI 4 is a Cube 2.0, an MPU9250 a 2.1) or a
    Pixhack (``V2M``, on SPI 1). A start the boot console shows settles it; ``shift``: the
    release's lines before the test, less than v1.12.0's."""

    def on(bus: int, answered: str, first: str = "") -> str:
        failed = f"not {first} started (-s -b {bus} -R 10 start) and " if first else ""
        return f"{failed}{answered} started (-s -b {bus} -R 10 start)"

    # Each `if <driver> -s -b <bus> -R 10 start` line; its `set BOARD_FMUV3` is two below.
    settings = (
        Setting("20", f"hw_type in V30 and {on(4, 'mpu6000')}", 27 - shift),
        Setting("21", f"hw_type in V30 and {on(4, 'mpu9250', 'mpu6000')}", 33 - shift),
        Setting("20", f"hw_type in V2M and {on(1, 'mpu6000')}", 50 - shift),
        Setting("21", f"hw_type in V2M and {on(1, 'mpu9250', 'mpu6000')}", 56 - shift),
    )
    path = f"boards/px4/{board}/init/rc.board_sensors"
    return BoardVariables(releases, {"BOARD_FMUV3": HardwareVariable("0", path, 20 - shift,
                                                                     settings)})  # fmt: skip


#: The board-script variables the hardware decides, per board and release, as each board's
#: own script sets them (read in PX4-Autopilot at the board table's snapshots; the v1.14.0
#: scripts at the commits whose power-monitor lines are the table's: 43d85931 for fmu-v5x
#: and fmu-v6x, 7c2da8d1 for ark fmu-v6x). Every board tests HAVE_PM2 (and HAVE_PM3) only
#: after ``set HAVE_PM2 yes``; all but one then set ``no`` by the hardware manifest (v1.15 on)
#: or the hardware type (v1.14); radiolink PIX6 never does.
HARDWARE_VARIABLES: dict[str, tuple[BoardVariables, ...]] = {
    "accton-godwit_ga1": (_pm(_NOW, "boards/accton-godwit/ga1/init/rc.board_sensors", 5,
                              _NO_PM2_PORT, 8),),
    "ark_fmu-v6s": (_pm(_NOW, "boards/ark/fmu-v6s/init/rc.board_sensors", 5, _NO_PM2_PORT, 8,
                        pm3=True),),
    "ark_fmu-v6x": (
        _pm(("v1.14.0",), "boards/ark/fmu-v6x/init/rc.board_sensors", 5,
            "hw_type in ARKV6X005000,ARKV6X005001,ARKV6X005002,ARKV6X005003,ARKV6X005004", 7),
        _pm(_LATER, "boards/ark/fmu-v6x/init/rc.board_sensors", 5, _NO_PM2_PORT, 8, pm3=True),
    ),
    "auterion_fmu-v6x": (_pm(_NOW, "boards/auterion/fmu-v6x/init/rc.board_sensors", 5,
                             _NO_PM2_PORT, 8),),
    "cuav_fmu-v6x": (_pm(_NOW, "boards/cuav/fmu-v6x/init/rc.board_sensors", 5, _NO_PM2_PORT,
                         8),),
    "cuav_x25-evo": (_pm(_NOW, "boards/cuav/x25-evo/init/rc.board_sensors", 5, _NO_PM2_PORT,
                         7),),
    "cuav_x25-mega": (_pm(_NOW, "boards/cuav/x25-mega/init/rc.board_sensors", 5, _NO_PM2_PORT,
                          7),),
    "cuav_x25-super": (_pm(_NOW, "boards/cuav/x25-super/init/rc.board_sensors", 5,
                           _NO_PM2_PORT, 7),),
    "px4_fmu-v5x": (
        _pm(("v1.14.0",), "boards/px4/fmu-v5x/init/rc.board_sensors", 6,
            "hw_type in V5X005000,V5X005001,V5X005002", 8),
        _pm(_LATER, "boards/px4/fmu-v5x/init/rc.board_sensors", 6, _NO_PM2_PORT, 8),
    ),
    "px4_fmu-v6x": (
        _pm(("v1.14.0",), "boards/px4/fmu-v6x/init/rc.board_sensors", 5,
            "hw_type in V6X005000,V6X005001,V6X005003,V6X005004", 7),
        _pm(_LATER, "boards/px4/fmu-v6x/init/rc.board_sensors", 5, _NO_PM2_PORT, 8),
    ),
    "px4_fmu-v6xrt": (_pm(_LATER, "boards/px4/fmu-v6xrt/init/rc.board_sensors", 19,
                          _NO_PM2_PORT, 22),),
    "radiolink_PIX6": (_pm(_NOW, "boards/radiolink/PIX6/init/rc.board_sensors", 6, None),),
    "zeroone_x6": (_pm(_NOW, "boards/zeroone/x6/init/rc.board_sensors", 5, _NO_PM2_PORT, 8),),
    # BOARD_FMUV3 (read at v1.12.0, v1.15.0, release/1.18 and main: the same lines 20 to 58;
    # v1.13.0 and v1.14.0 not read, taken as those: their `if ... start` rows are at 27, 33, 50
    # and 56 too, their later rows at v1.15.0's lines; v1.11.0's one line earlier, as its rows)
    **{
        f"px4_{board}": (_fmuv3(("v1.11.0",), board, shift=1), _fmuv3(_SINCE_1_12, board))
        for board in ("fmu-v2", "fmu-v3")
    },
}  # fmt: skip


#: What rc.sensors (ROMFS/px4fmu_common/init.d, run by rcS after the board's rc.board_sensors,
#: in the same shell) no longer sees: fmu-v2's and fmu-v3's scripts end with `unset
#: BOARD_FMUV3` (boards/px4/fmu-v2/init/rc.board_sensors:109 at v1.11.0, :110 at v1.12.0), no
#: other board sets it, so rc.sensors' `if [ $BOARD_FMUV3 = 21 ]` (v1.11.0:123, v1.12.0:159) is
#: false on every board.
UNSET_BEFORE_RC_SENSORS = frozenset({"BOARD_FMUV3"})


def board_variables(board: str, releases: Sequence[str]) -> Mapping[str, HardwareVariable]:
    """The hardware variables of ``board``'s script in the newest of ``releases`` (empty for a
    board whose script sets none)."""
    for entry in HARDWARE_VARIABLES.get(board, ()):
        if releases and releases[-1] in entry.releases:
            return entry.variables
    return {}


_OPERATORS = {
    "==": lambda a, b: a == b,
    "!=": lambda a, b: a != b,
    ">=": lambda a, b: a >= b,
    "<=": lambda a, b: a <= b,
    ">": lambda a, b: a > b,
    "<": lambda a, b: a < b,
}
_PARAM_TEST = re.compile(r"([A-Z][A-Z0-9_]*) (==|!=|>=|<=|>|<) (-?\d+(?:\.\d+)?)")
_VARIABLE_TEST = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*) (==|!=) (\S+)")
_LIST_TEST = re.compile(r"(hw_type|hw_base|board) in (\S+)")
_MANIFEST_TEST = re.compile(r"mft [A-Z0-9_]+ == \S+")
_STARTED_TEST = re.compile(r"([a-z][a-z0-9_]*) started \((.*)\)")
_NUMBER = re.compile(r"0[xX][0-9a-fA-F]+|\d+")
_BUS_CLAUSE = re.compile(r"bus (\d+): (.*)")


@dataclass(frozen=True)
class Facts:
    """What a condition's tests are settled by."""

    params: Mapping[str, int | float]
    #: Board-script variables the builder derived (``INA_CONFIGURED``) -> their value.
    variables: Mapping[str, str]
    #: The board's ``ver_hw`` names (``board in``).
    ver_hw: Sequence[str]
    #: The boot console's starts; None without a boot console.
    starts: Sequence[DriverStart] | None
    #: What the configuration is, for the notes ("a QGC .params").
    kind: str
    #: The hardware type (a log's ``ver_hw_subtype``); None where nothing says.
    hw_type: str | None = None
    #: The variables the board's script sets from the hardware (:func:`board_variables`).
    hardware: Mapping[str, HardwareVariable] = field(default_factory=dict)
    #: A line of the board's scripts as the board table cites it (``Board.cite``); None: as
    #: ``path:line``.
    cite: Callable[[str, int], str] | None = None
    #: Variables the board's script unset before the script of the row evaluated ran
    #: (:data:`UNSET_BEFORE_RC_SENSORS`): every test of one is false.
    unset: frozenset[str] = frozenset()


@dataclass(frozen=True)
class Verdict:
    """Whether a condition holds: True or False, or None where a test nothing settles decides
    it."""

    holds: bool | None
    #: Each clause taken as PX4's default or not known, and why.
    open: tuple[tuple[str, str], ...] = ()

    @property
    def unchecked(self) -> tuple[str, ...]:
        """Each of :attr:`open` as "clause (why)"."""
        return tuple(f"{clause} ({why})" for clause, why in self.open)


@dataclass(frozen=True)
class _Test:
    value: bool | None  # None: not known
    why: str = ""  # "": settled; else why it is PX4's default or not known


def _started(args: str, start: DriverStart) -> bool:
    """Whether a console start is the one ``args`` (the script's options) asks for."""
    words = args.split()
    for flag, value in itertools.pairwise(words):
        if flag == "-b" and value.isdigit() and int(value) != start.bus:
            return False
        if flag == "-a" and _NUMBER.fullmatch(value) and start.address not in (None, int(value, 0)):
            return False
    spi = bool({"-s", "-S"} & set(words))
    if spi != (start.bus_kind == "SPI"):
        return False
    return not (("-I" in words and start.external) or ("-X" in words and start.internal))


def _test(text: str, facts: Facts) -> _Test:
    m = _PARAM_TEST.fullmatch(text)
    if m:
        if m[1] not in facts.params:
            return _Test(None, f"{m[1]} is not in the {facts.kind}")
        return _Test(_OPERATORS[m[2]](facts.params[m[1]], float(m[3])))
    m = _VARIABLE_TEST.fullmatch(text)
    if m:
        name, equal, word = m[1], m[2] == "==", m[3]
        if name in facts.unset:
            # nsh's `[ $X = 21 ]` of an unset X is `[ = 21 ]`: a test missing its operand, false
            return _Test(False)
        if name in facts.variables:
            return _Test((facts.variables[name] == word) == equal)
        if name in facts.hardware:
            value, why = _hardware_variable(name, facts.hardware[name], facts)
            return _Test((value == word) == equal, why)
        return _Test(None, f"${name} is set by PX4's startup scripts from what the {facts.kind} "
                     "does not tell")  # fmt: skip
    m = _LIST_TEST.fullmatch(text)
    if m:
        if m[1] == "board":
            return _Test(any(hw in m[2].split(",") for hw in facts.ver_hw))
        if m[1] == "hw_type" and facts.hw_type is not None:
            return _Test(facts.hw_type in m[2].split(","))
        return _Test(None, "the hardware revision, which the parameters do not tell")
    if _MANIFEST_TEST.fullmatch(text):
        return _Test(None, "the board's hardware manifest, which the parameters do not tell")
    m = _STARTED_TEST.fullmatch(text)
    if m:
        if facts.starts is None:
            return _Test(None, f"a {facts.kind} has no boot console to say")
        return _Test(any(s.driver == m[1] and _started(m[2], s) for s in facts.starts))
    return _Test(None, "a test px4params cannot read")


def _hardware_variable(name: str, var: HardwareVariable, facts: Facts) -> tuple[str, str]:
    """The value the board's script gives ``name``, and why it is taken ("": settled): the
    last setting settled as run, else ``first``; the settings after it that nothing settles
    are named with their lines, a reason they all share once."""
    value, open_ = var.first, list[tuple[Setting, Verdict]]()
    for setting in var.settings:
        verdict = evaluate(setting.when, facts)
        if verdict.holds and not verdict.open:
            value, open_ = setting.value, []
        elif verdict.holds is not False or verdict.open:
            open_.append((setting, verdict))
    if not open_:
        return value, ""
    whys = {why for _, verdict in open_ for _, why in verdict.open}
    shared = len(whys) == 1 and sum(len(v.open) for _, v in open_) > 1
    said = [
        f"line {s.line}: {s.value} where "
        + " and ".join(c if shared else f"{c} ({why})" for c, why in v.open)
        for s, v in open_
    ]
    where = facts.cite(var.path, var.line) if facts.cite else f"{var.path}:{var.line}"
    tail = f"; for each, {whys.pop()}" if shared else ""
    return value, f"{where} sets {name} {var.first}; {'; '.join(said)}{tail}"


def _clause(text: str, facts: Facts) -> _Test:
    """One clause: ``not`` before tests joined by ``-o``."""
    negated = text.startswith("not ")
    tests = [_test(t.strip(), facts) for t in text.removeprefix("not ").split(" -o ")]
    if any(t.value is True and not t.why for t in tests):
        value: bool | None = True
        why = ""
    elif all(t.value is False and not t.why for t in tests):
        value, why = False, ""
    else:
        open_ = [t for t in tests if t.why]
        why = "; ".join(t.why for t in open_)
        value = None if any(t.value is None for t in tests) else any(t.value for t in tests)
    if negated and value is not None:
        value = not value
    return _Test(value, why)


def evaluate(when: str, facts: Facts) -> Verdict:
    """Whether ``when`` holds (see the module doc); "" always does."""
    if not when.strip():
        return Verdict(True)
    clauses = [(c, _clause(c, facts)) for c in when.split(" and ")]
    if any(t.value is False and not t.why for _, t in clauses):
        return Verdict(False)  # settled: the rest does not matter
    open_ = tuple((c, t.why) for c, t in clauses if t.why)
    if any(t.value is None for _, t in clauses):
        return Verdict(None, open_)
    return Verdict(all(t.value for _, t in clauses), open_)


def per_bus(when: str) -> dict[int, str] | None:
    """``bus 1: A; bus 2: B`` (a launcher's condition per bus) -> {1: "A", 2: "B"}; None when
    the text is not of that form."""
    found: dict[int, str] = {}
    for part in when.split(";"):
        m = _BUS_CLAUSE.fullmatch(part.strip())
        if m is None:
            return None
        found[int(m[1])] = m[2]
    return found
