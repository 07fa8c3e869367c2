"""A board row's condition (``when`` in the board table) evaluated as PX4's startup script tests
it, clause by clause, with what the configuration cannot tell kept apart and named.

A condition is clauses joined by `` and ``; a clause is an optional ``not `` before tests joined
by `` -o `` (the shell test's "or"). The tests, as ``scripts/transcribe_boards.py`` writes PX4's:

``NAME == 1``, ``NAME > 0`` (``param compare``, ``param greater``; ``!=``, ``>=``, ... alike)
    a parameter: settled by the configuration's value; not known where it has none
``$VAR == word``, ``$VAR != word``
    a variable of the board's script: settled where the builder derives it (``INA_CONFIGURED``
    from the power-monitor switches); :data:`HARDWARE_VARIABLES` are the hardware's, taken as
    PX4's default and said so; any other is not known
``hw_type in A,B``, ``hw_base in A,B``
    the board's hardware revision (``ver hwtypecmp``, ``ver hwbasecmp``): not known
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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from px4params.vehicle.console import DriverStart

__all__ = ["HARDWARE_VARIABLES", "Facts", "Verdict", "evaluate", "per_bus"]

#: Board-script variables the hardware decides: name -> (PX4's value unless the hardware says
#: otherwise, why). Each script that tests them sets them first: ``set HAVE_PM2 yes``, then
#: ``no`` where the board has no second power-module port, by the hardware manifest (``mft
#: query -q -k MFT -s MFT_PM2 -v 0``: boards/px4/fmu-v6x, boards/cuav/fmu-v6x) or the hardware
#: type (``ver hwtypecmp``: boards/px4/fmu-v5x, boards/ark/fmu-v6x, which sets HAVE_PM3 alike).
HARDWARE_VARIABLES: dict[str, tuple[str, str]] = {
    "HAVE_PM2": (
        "yes",
        "the board's script sets HAVE_PM2 yes, and no on hardware without a second power-module "
        "port, which the parameters do not tell",
    ),
    "HAVE_PM3": (
        "yes",
        "the board's script sets HAVE_PM3 yes, and no on hardware without a third power-module "
        "port, which the parameters do not tell",
    ),
}
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


@dataclass(frozen=True)
class Verdict:
    """Whether a condition holds: True or False, or None where a test nothing settles decides
    it; ``unchecked`` names each clause taken as PX4's default or not known, with why."""

    holds: bool | None
    unchecked: tuple[str, ...] = ()


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
        if name in facts.variables:
            return _Test((facts.variables[name] == word) == equal)
        if name in HARDWARE_VARIABLES:
            default, why = HARDWARE_VARIABLES[name]
            return _Test((default == word) == equal, why)
        return _Test(None, f"${name} is set by the board's script from what the {facts.kind} "
                     "does not tell")  # fmt: skip
    m = _LIST_TEST.fullmatch(text)
    if m:
        if m[1] == "board":
            return _Test(any(hw in m[2].split(",") for hw in facts.ver_hw))
        return _Test(None, "the hardware revision, which the parameters do not tell")
    m = _STARTED_TEST.fullmatch(text)
    if m:
        if facts.starts is None:
            return _Test(None, f"a {facts.kind} has no boot console to say")
        return _Test(any(s.driver == m[1] and _started(m[2], s) for s in facts.starts))
    return _Test(None, "a test px4params cannot read")


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
    unchecked = tuple(f"{c} ({t.why})" for c, t in clauses if t.why)
    if any(t.value is None for _, t in clauses):
        return Verdict(None, unchecked)
    return Verdict(all(t.value for _, t in clauses), unchecked)


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
