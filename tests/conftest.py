"""Shared fixtures: the bundled schema, loaded once per test session."""

from __future__ import annotations

import px4params
import pytest


@pytest.fixture(scope="session")
def schema() -> px4params.Schema:
    return px4params.load_schema(use_env=False)
