"""Data from other projects, not in this repository: the folder $PX4PARAMS_SHARED_DATA, by
default ``shared/data`` beside the repository. A test that needs a file of it is skipped, with
the reason, where the file is absent."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from px4params.vehicle import devid

SHARED_ENV = "PX4PARAMS_SHARED_DATA"
SHARED_DATA = Path(
    os.environ.get(SHARED_ENV) or Path(__file__).resolve().parents[2] / "shared" / "data"
)
CURRENT_TSV = "px4_devtypes_current.tsv"  # today's drv_sensor.h devtypes
SAMPLE_LOG = "sample_log_small.ulg"  # a real PX4 flight log
PARAMETERS_JSON = "px4_parameters.json"  # a real parameters.json from a PX4 build


def shared_file(name: str) -> Path:
    """The shared file `name`; skips the test where it is absent."""
    path = SHARED_DATA / name
    if not path.is_file():
        pytest.skip(f"{name} not found in {SHARED_DATA} (set ${SHARED_ENV} to its folder)")
    return path


def current_devtypes() -> devid.DevtypeTable:
    """Today's devtype table, read from the shared TSV."""
    return devid.load_table("current", shared_file(CURRENT_TSV))
