"""Migration from today's PX4 configuration to a device manifest.

Input: a QGC ``.params`` file, a ``param set`` / ``param set-default`` list (airframe syntax), or
a ULog flight log (its parameters, information, boot console and the ``device_id`` of every
sensor that published). Output: a proposed airframe
file of ``param add`` / ``param set-default`` lines (what ``px4params run`` and, per the talk,
PX4 itself run) and a report of where each line came from, of everything that could not be
carried over and of every assumption made. Nothing is dropped silently.

What the manifest takes over is what today's PX4 starts *outside* the board's own script:

* **Devices found by probing** (``rc.sensors`` with ``SENS_EXT_I2C_PRB``): an external I2C
  sensor of a ``CAL_<S>n_ID`` device ID (decoded with the devtype table of the file's firmware
  era, :mod:`.vehicle.devid`) whose chip a declared driver publishes. Probing starts drivers
  without ``-R``: the instance's rotation is 0; ``CAL_MAGn_ROT`` is calibration's and stays a
  classic parameter. A rotation of the file's release is turned where the driver reports other
  axes on the release the manifest is for (:mod:`.axes`: PX4 1.12's IST8310 rewrite, ...).
* **Drivers started by a switch** (``SENS_EN_MS4525DO``, ``SENS_EN_INA238``, ...): on the buses
  the evidence or the board's switch rows give, else on I2C bus 1 with a line saying so.
* **Power monitors ``i2c_launcher`` found** (a log's boot console says so).

Left out, each with its reason: sensors the board's script starts (a board table row, PX4's
"Internal" ``CAL_MAGn_ROT = -1``, an internal bus in the boot console, a ``-R`` rotation, which
probing never passes), disabled slots (``CAL_<S>n_PRIO = 0`` from PX4 1.12 on, ``_EN = 0``
before), DroneCAN and simulated sensors. Evidence first: the boot console (what actually
started, on which bus, address and rotation) wins over every table. A board row is taken only
when its whole condition holds (:mod:`.conditions`, clause by clause; a log's hardware type
settles ``ver hwtypecmp``); one resting on what the configuration cannot tell (the hardware,
an earlier start without a boot console) is taken only as PX4's default, or not at all, and
the report names the clause and the row's line. Such a device row never drops a device: the
device is proposed, unless it sits on one of the board's internal I2C buses, which only the
board's script starts drivers on. A row starts a device only on a bus PX4 tries for it
(:meth:`.vehicle.boards.Board.bus_conditions`): a ``-b`` of the other kind (``-X`` on an internal
bus) starts nothing, and where the board's own ``px4_i2c_bus_external`` makes a bus external on
some hardware (fmu-v2/v3 on a Cube, ``hw_type`` V30), that hardware is one more clause.

The board's script is judged at the file's own release (:meth:`.vehicle.boards.BoardTable.
snapshot_for`), and again at each later release the table knows: a device left out because a
board row starts it gets one line saying whether those releases still start it (the board's row,
or a switch row such as rc.sensors' probe whose condition the parameters settle), citing the
file's line and each release where that changed. ``target_release`` makes the proposal for the
firmware the vehicle will run: a device the target's board script no longer starts becomes an
instance with the ``-R`` its old line gave it, and a device found by probing that the target's
board script starts itself is left out as the board's (without a target: a note on its
instance). The default stays the file's release: the file does not say which firmware comes
next, and the report names every such device.
"""

from px4params.errors import MigrationError
from px4params.migrate.build import migrate
from px4params.migrate.config import OldConfig, read_config
from px4params.migrate.proposal import LeftOut, Proposal, ProposedInstance

__all__ = [
    "LeftOut",
    "MigrationError",
    "OldConfig",
    "Proposal",
    "ProposedInstance",
    "migrate",
    "read_config",
]
