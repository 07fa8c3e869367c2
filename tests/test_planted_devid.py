"""``px4params devid --log`` reads a log of PX4 1.7.x with the 1.6 era's devtype table
(docs/device-ids.md: "``px4-v1.6`` ... are ``drv_sensor.h`` as PX4 1.6-1.7"; ``px4-v1.8`` from
1.8). Issue 40: with that era ending at 1.6.99, the suite stayed green: no test log is of 1.7.

No real 1.7 ULog is at hand (``../shared/data/qgc_px4_mocklink.params`` is PX4 1.7.2 but a
``.params`` file carries no firmware version), so the logs are written here byte by byte from
the ULog specification (PX4 dev guide, "ULog File Format"): the header, the flag bits, an
information message ``uint32_t ver_sw_release`` (major, minor, patch, type in its four bytes,
type 255 a release) and a parameter ``int32_t CAL_MAG0_ID``.

The known answer that tells the eras apart: devtype 0x03 of a magnetometer was
``DRV_MAG_DEVTYPE_ACCELSIM`` in drv_sensor.h as PX4 1.6-1.7 had it (and in the PX4 driver
guide's table of that time), ``DRV_MAG_DEVTYPE_MAGSIM`` from 1.8.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import pytest

CLI = [sys.executable, "-m", "px4params"]
#: A simulated magnetometer: bus type 4 (simulation), bus 1, address 0, devtype 0x03.
SIM_MAG = 0x03 << 16 | 0 << 8 | 1 << 3 | 4


def _message(kind: str, body: bytes) -> bytes:
    return struct.pack("<HB", len(body), ord(kind)) + body


def _key_value(key: str, value: bytes) -> bytes:
    return bytes([len(key)]) + key.encode() + value


def write_ulog(path: Path, release: tuple[int, int, int, int], device_id: int) -> None:
    major, minor, patch, kind = release
    data = b"ULog\x01\x12\x35" + b"\x01" + struct.pack("<Q", 0)  # magic, version 1, start
    data += _message("B", bytes(8) + bytes(8) + bytes(3 * 8))  # no flags, no appended data
    version = major << 24 | minor << 16 | patch << 8 | kind
    data += _message("I", _key_value("uint32_t ver_sw_release", struct.pack("<I", version)))
    data += _message("P", _key_value("int32_t CAL_MAG0_ID", struct.pack("<i", device_id)))
    path.write_bytes(data)


@pytest.mark.parametrize(
    ("release", "table", "name"),
    [
        ((1, 7, 0, 255), "px4-v1.6", "ACCELSIM"),
        ((1, 7, 2, 255), "px4-v1.6", "ACCELSIM"),  # MockLink's PX4 version
        ((1, 7, 4, 128), "px4-v1.6", "ACCELSIM"),  # a 1.7.4 beta
        ((1, 6, 0, 255), "px4-v1.6", "ACCELSIM"),
        ((1, 8, 0, 255), "px4-v1.8", "MAGSIM"),
    ],
    ids=["1.7.0", "1.7.2", "1.7.4beta", "1.6.0", "1.8.0"],
)
def test_a_px4_1_7_log_is_read_with_the_1_6_era_table(
    tmp_path: Path, release: tuple[int, int, int, int], table: str, name: str
) -> None:
    log = tmp_path / "era.ulg"
    write_ulog(log, release, SIM_MAG)
    result = subprocess.run(
        [*CLI, "devid", "--log", str(log), "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env={k: v for k, v in os.environ.items() if k != "PX4PARAMS_DEVTYPES"},
    )
    assert result.returncode == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["table"] == table
    (entry,) = doc["parameters"]
    assert entry["param"] == "CAL_MAG0_ID" and entry["value"] == SIM_MAG
    assert entry["device"]["devtype"] == 3
    assert entry["device"]["devtype_name"] == name
    assert entry["device"]["devtype_kind"] == "MAG"
