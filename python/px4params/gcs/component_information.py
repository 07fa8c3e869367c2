"""Component metadata as PX4 serves it over MAVLink: a *general* metadata file that lists the
other metadata files (here: the parameters) by URI and CRC, and the parameter metadata itself,
``parameters.json`` compressed with xz. A ground station learns the general file's URI and CRC
from COMPONENT_METADATA (older ones: COMPONENT_INFORMATION) and downloads the files over MAVLink
FTP (``mftp://`` URIs; :mod:`px4params.links.mavlink_ftp` serves them).

The general file, as PX4 writes it (``COMP_METADATA_TYPE_GENERAL``)::

    {"version": 1, "metadataTypes": [
        {"type": 1, "uri": "mftp://px4params/parameters.json.xz", "fileCrc": 3054931723}]}

CRCs are PX4's ``crc32part`` with seed 0 (:func:`px4_crc32`): ``fileCrc`` over the file as
served (compressed), the general file's CRC (in COMPONENT_METADATA) over the general file. QGC
keys its metadata cache by them, so they change whenever the content does.
"""

from __future__ import annotations

import json
import lzma
import zlib
from collections.abc import Sequence
from typing import Any

from px4params.dsdl.schema import Schema
from px4params.gcs.metadata import build_parameters_json
from px4params.store.classic import ClassicParam
from px4params.store.spec import ParamSpec

__all__ = [
    "COMP_METADATA_TYPE_GENERAL",
    "COMP_METADATA_TYPE_PARAMETER",
    "ComponentFiles",
    "mftp_uri",
    "px4_crc32",
]

#: MAVLink's COMP_METADATA_TYPE values.
COMP_METADATA_TYPE_GENERAL = 0
COMP_METADATA_TYPE_PARAMETER = 1

#: Where the files are on the component's MAVLink FTP server.
GENERAL_PATH = "/px4params/general.json"
PARAMETERS_PATH = "/px4params/parameters.json.xz"


def px4_crc32(data: bytes, crc: int = 0) -> int:
    """PX4's ``crc32part(data, len, crc)``: the reflected CRC-32 (polynomial 0xEDB88320)
    without zlib's initial and final inversion (``zlib.crc32`` computes the inverted form)."""
    return zlib.crc32(data, crc ^ 0xFFFFFFFF) ^ 0xFFFFFFFF


def mftp_uri(path: str, component_id: int = 1) -> str:
    """The ``mftp://`` URI of ``path`` on component ``component_id``'s MAVLink FTP server, as
    PX4 writes it (``mftp://etc/extras/...``; ``[;comp=N]`` when not the autopilot, 1)."""
    where = path.lstrip("/")
    return f"mftp://{where}" if component_id == 1 else f"mftp://[;comp={component_id}]/{where}"


class ComponentFiles:
    """The metadata files of one component: the general file, the parameter metadata (xz), and
    what COMPONENT_METADATA announces (the general file's URI and CRC)."""

    def __init__(
        self,
        schema: Schema,
        specs: Sequence[ParamSpec],
        classic: Sequence[ClassicParam],
        *,
        component_id: int = 1,
    ) -> None:
        document = build_parameters_json(schema, specs=specs, classic_params=classic)
        text = json.dumps(document, allow_nan=False, separators=(",", ":")).encode("utf-8")
        #: parameters.json, compressed as PX4 ships it (xz container, CRC32 check).
        self.parameters = lzma.compress(text, format=lzma.FORMAT_XZ, check=lzma.CHECK_CRC32)
        self.component_id = component_id
        general: dict[str, Any] = {
            "version": 1,
            "metadataTypes": [
                {
                    "type": COMP_METADATA_TYPE_PARAMETER,
                    "uri": mftp_uri(PARAMETERS_PATH, component_id),
                    "fileCrc": px4_crc32(self.parameters),
                }
            ],
        }
        self.general = json.dumps(general, separators=(",", ":")).encode("utf-8")
        self.general_crc = px4_crc32(self.general)
        self.general_uri = mftp_uri(GENERAL_PATH, component_id)

    @property
    def files(self) -> dict[str, bytes]:
        """Path -> bytes, for the FTP server."""
        return {GENERAL_PATH: self.general, PARAMETERS_PATH: self.parameters}
