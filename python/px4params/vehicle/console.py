"""What a PX4 boot console says was started: the lines drivers print when an instance runs, and
the I2C launcher's lines. A log carries the console as ``boot_console_output`` (PX4 1.12 on).

The lines read, as PX4's ``I2CSPIDriverBase`` and ``i2c_launcher`` print them::

    ist8310 #0 on I2C bus 1 (external) address 0xE rotation 10
    bmm350 #0 on I2C bus 4 address 0x14 rotation 6
    ak09916 #0 on I2C bus 1 (external, equal to '-b 2')          (PX4 1.11; SPI lines to 1.12)
    ms5611 #0 on SPI bus 1 (devid=0x3d)
    INFO  [i2c_launcher] Found address 0x45, running 'ina228 -X -b 1 -t 1 start'

"(external)" is PX4's flag for a bus outside the flight controller; a line without it is an
internal bus. The bus number is PX4's (the device ID's). The "-b" of "equal to '-b 2'" is PX4
1.11's n-th external bus; since PX4-Autopilot#15679 an I2C driver's "-b" is the board's bus
number, the one its line prints, and i2c_launcher (in PX4 1.15's logs) passes the bus it
probed as "-b": its "-b" and the driver line's bus name the same bus.
"""

from __future__ import annotations

import itertools
import re
import shlex
from dataclasses import dataclass

__all__ = ["DriverStart", "started_drivers"]

_STARTED = re.compile(
    r"(?P<driver>[a-z][a-z0-9_]*) #(?P<instance>\d+) on (?P<kind>I2C|SPI) bus (?P<bus>\d+)"
    r"(?: \((?P<external>external)?[^)]*\))?"
    r"(?: address 0x(?P<address>[0-9A-Fa-f]+))?"
    r"(?: rotation (?P<rotation>\d+))?"
)
_LAUNCHER = re.compile(
    r"\[i2c_launcher\] Found address 0x(?P<address>[0-9A-Fa-f]+), running '(?P<command>[^']*)'"
)


@dataclass(frozen=True)
class DriverStart:
    """One driver instance the console shows running."""

    driver: str
    bus_kind: str  # "I2C" or "SPI"
    bus: int
    external: bool
    address: int | None
    #: The ``-R`` the driver runs with; None when the line does not say (PX4 before 1.13).
    rotation: int | None
    #: Started by ``i2c_launcher`` (which found it by probing its buses).
    launcher: bool
    line: int
    text: str

    @property
    def internal(self) -> bool:
        """On a bus inside the flight controller: SPI, or I2C without PX4's external flag."""
        return not self.external


def _launched(command: str, address: int) -> tuple[str, int | None, int]:
    words = shlex.split(command)
    bus: int | None = None
    for flag, value in itertools.pairwise(words):
        if flag == "-b" and value.isdigit():
            bus = int(value)
        elif flag == "-a" and re.fullmatch(r"0[xX][0-9a-fA-F]+|\d+", value):
            address = int(value, 0)
    return (words[0] if words else ""), bus, address


def started_drivers(console: str) -> list[DriverStart]:
    """Every driver start of a boot console, in the order printed. A launcher line and the
    driver's own line for the same device are one start (the launcher's, with the driver
    line's details)."""
    starts: list[DriverStart] = []
    launched: dict[tuple[str, int | None, int], int] = {}
    for number, raw in enumerate(console.splitlines(), start=1):
        text = raw.strip()
        m = _LAUNCHER.search(text)
        if m:
            driver, bus, address = _launched(m["command"], int(m["address"], 16))
            launched[(driver, bus, address)] = len(starts)
            starts.append(
                DriverStart(driver, "I2C", bus or 0, True, address, None, True, number, text)
            )
            continue
        m = _STARTED.match(text)
        if not m:
            continue
        start = DriverStart(
            m["driver"],
            m["kind"],
            int(m["bus"]),
            bool(m["external"]),
            int(m["address"], 16) if m["address"] else None,
            int(m["rotation"]) if m["rotation"] else None,
            False,
            number,
            text,
        )
        earlier = next(
            (
                i
                for (driver, bus, at), i in launched.items()
                if (driver, bus) == (start.driver, start.bus) and start.address in (None, at)
            ),
            None,
        )
        if earlier is not None:
            first = starts[earlier]
            starts[earlier] = DriverStart(
                first.driver, start.bus_kind, start.bus, start.external,
                start.address if start.address is not None else first.address, start.rotation, True,
                first.line, first.text,
            )  # fmt: skip
            continue
        starts.append(start)
    return starts
