"""Firmware code size (issues 17 and 39): the core built for size (``compact``) stays within its
targets, as ``benches/size.py`` measures them on small ``no_std`` probes (seconds to build), on
the host and on Cortex-M7 (``thumbv7em-none-eabihf``, what PX4's FMUv5x/v6x fly)."""

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
    # The sizes reached as ceilings (codec 5,189 bytes, core 13,054: the core grew by 152 as
    # the codec lost 153, issue 39; the same source varies by a few bytes between builds;
    # issue 17: 6 and 16 KiB).
    assert rows["codec"][2:] == ["5,216", "ok"], proc.stdout
    assert rows["core"][2:] == ["13,088", "ok"], proc.stdout
    assert rows["all"][2] == "-", proc.stdout
    assert proc.returncode == 0, proc.stdout + proc.stderr


def _target_installed(triple: str) -> bool:
    sysroot = subprocess.run(
        ["rustc", "--print", "sysroot"], capture_output=True, text=True, check=True
    ).stdout.strip()
    return (Path(sysroot) / "lib" / "rustlib" / triple).is_dir()


def test_the_cortex_m7_build_is_within_its_size_targets() -> None:
    triple = "thumbv7em-none-eabihf"
    missing = [t for t in ("cargo", "rustc", "arm-none-eabi-gcc", "arm-none-eabi-size", "nm")]
    missing = [tool for tool in missing if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed: no Cortex-M7 image can be linked")
    if not _target_installed(triple):
        pytest.skip(f"Rust target {triple} not installed (rustup target add {triple})")
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benches" / "size.py"), "--target", triple],
        capture_output=True,
        text=True,
        timeout=900,
    )
    rows = {line.split()[0]: line.split()[1:] for line in proc.stdout.splitlines()[1:]}
    # Issue 39's targets: codec 4 KiB (4,086 reached: no error value over 16 bytes is moved in
    # the walk, so newlib's memcpy is not linked), core 10 KiB (10,150: docs/firmware.md#size).
    assert rows["codec"][2:] == ["4,096", "ok"], proc.stdout
    assert rows["core"][2:] == ["10,240", "ok"], proc.stdout
    # The C baseline is measured beside it where its sources are.
    anchor = ROOT.parent / "shared" / "anchors" / "dronecan-c"
    if anchor.is_dir():
        assert "C: canard.c (gcc -Os) .text" in proc.stdout, proc.stdout
    assert proc.returncode == 0, proc.stdout + proc.stderr
