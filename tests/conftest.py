"""Shared fixtures: the bundled schema, loaded once per test session, and a saved store."""

from __future__ import annotations

from pathlib import Path

import px4params
import pytest
from px4params.store.classic import BUNDLED_CLASSIC


@pytest.fixture(scope="session")
def schema() -> px4params.Schema:
    return px4params.load_schema(use_env=False)


@pytest.fixture
def store_file(tmp_path: Path, schema: px4params.Schema) -> Path:
    """A saved store with one INA238 (instance 1) at I2C address 0x45; a test file's own
    `store_file` fixture, where it has one, takes its place."""
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("INA238#1")
    store.set("INA238#1.bus.i2c.address", 0x45)
    path = tmp_path / "vehicle.store"
    store.save(path)
    return path
