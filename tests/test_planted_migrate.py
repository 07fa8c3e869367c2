"""``px4params migrate`` rounds a legacy float setting that feeds an integer field to the
nearest integer, a value exactly between two integers upwards (migrate.py: "rounded and
clamped"; ``math.floor(v + 0.5)``): ``INA238_CURRENT`` (PX4's INA238 driver: the maximum
expected current, a float in A) feeds the INA238 type's ``current`` (uint10, whole A), so
2.5 A becomes 3 A. Issue 40: with Python's ``round`` (half to even: 2.5 -> 2) the suite stayed
green, as its values were never halves.

Checked end to end: the proposed airframe file is run into a store, and the store's value read.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import px4params
import pytest
from px4params.store.classic import BUNDLED_CLASSIC

CLI = [sys.executable, "-m", "px4params"]


def _cli(*args: str, cwd: Path) -> str:
    result = subprocess.run(
        [*CLI, *args], capture_output=True, text=True, timeout=120, cwd=cwd, check=False
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


@pytest.mark.parametrize(
    ("legacy", "expected"),
    [("2.5", 3), ("100.5", 101), ("2.4999", 2), ("7.5", 8)],
)
def test_a_legacy_value_exactly_between_two_integers_rounds_half_up(
    tmp_path: Path, legacy: str, expected: int
) -> None:
    # A QGC .params file: vehicle, component, name, value, MAVLink type (6 INT32, 9 REAL32).
    rows = [("SENS_EN_INA238", "1", 6), ("INA238_CURRENT", legacy, 9)]
    old = tmp_path / "old.params"
    old.write_text("".join(f"1\t1\t{name}\t{value}\t{kind}\n" for name, value, kind in rows))
    # No device IDs to decode: the legacy table, so that no current table (../shared) is needed.
    _cli("migrate", str(old), "--table", "legacy", "-o", "new.airframe", cwd=tmp_path)
    _cli("run", "new.airframe", "--store", "vehicle.store", cwd=tmp_path)
    store = px4params.Store.load(tmp_path / "vehicle.store", classic=BUNDLED_CLASSIC)
    assert store.instances("INA238") == ["INA238#0"]
    assert store.get("INA238#0.current") == expected
