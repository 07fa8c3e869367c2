"""What the package ships besides code, found in one place: the bundled DSDL root namespaces
(``dsdl/px``), the driver declarations (``drivers.toml``), a minimal set of classic PX4
parameters (``classic_parameters.json``), MAVLink messages pymavlink lacks (``mavlink/``) and
the example files ``px4params examples`` copies out (``examples/``)."""

from __future__ import annotations

import os

_HERE = os.path.dirname(os.path.abspath(__file__))

#: Each subfolder is a root namespace of DSDL parameter types (today: ``px``).
DSDL_DIR = os.path.join(_HERE, "dsdl")
#: Value lists DSDL fields name with ``@values NAME`` (PX4's rotation enum, ...).
VALUE_SETS_TOML = os.path.join(_HERE, "value_sets.toml")
#: The bundled driver declarations (see ``px4params.vehicle.drivers``).
DRIVERS_TOML = os.path.join(_HERE, "drivers.toml")
#: Classic parameters used when no PX4 ``parameters.json`` is given (see ``store.classic``).
CLASSIC_PARAMETERS_JSON = os.path.join(_HERE, "classic_parameters.json")
#: Devtype tables of older PX4 releases (``px4-v1.6.tsv`` ...), with their version ranges.
DEVTYPES_DIR = os.path.join(_HERE, "devtypes")
#: MAVLink messages pymavlink's dialects lack (COMPONENT_METADATA, COMPONENT_INFORMATION).
MAVLINK_COMPONENT_XML = os.path.join(_HERE, "mavlink", "component_information.xml")
#: The example airframe, its benches and a QGC export of the same vehicle configured the classic
#: way (the checkout's ``examples/`` links to them; ``px4params examples DIR`` copies them out).
EXAMPLES_DIR = os.path.join(_HERE, "examples")
