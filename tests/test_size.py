"""Firmware code size (issue 17): the core built for size (``compact``) stays within its
targets, as ``benches/size.py`` measures them on small ``no_std`` probes (seconds to build)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_the_firmware_build_is_within_its_size_targets() -> None:
    missing = [tool for tool in ("cargo", "size", "nm") if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed: the probes cannot be built and read")
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benches" / "size.py")],
        capture_output=True,
        text=True,
        timeout=900,
    )
    rows = {line.split()[0]: line.split()[1:] for line in proc.stdout.splitlines()[1:]}
    # probe: host .text, compact .text, target, verdict
    assert rows["codec"][2:] == ["6,144", "ok"], proc.stdout
    assert rows["core"][2:] == ["16,384", "ok"], proc.stdout
    assert rows["all"][2] == "-", proc.stdout
    assert proc.returncode == 0, proc.stdout + proc.stderr
