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
    # The sizes reached as ceilings (codec 5,342 bytes, core 12,902; the same source varies by
    # a few bytes between builds; issue 17: 6 and 16 KiB).
    assert rows["codec"][2:] == ["5,376", "ok"], proc.stdout
    assert rows["core"][2:] == ["12,928", "ok"], proc.stdout
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
    # The sizes reached as ceilings (codec 4,470 bytes, core 9,986); issue 39 aims at 4 KiB
    # (4,096) and 10 KiB (10,240): the core's is met, the codec's not yet (newlib's memcpy,
    # which moving whole errors links, is most of what is left: docs/firmware.md#size).
    assert rows["codec"][2:] == ["4,512", "ok"], proc.stdout
    assert rows["core"][2:] == ["10,016", "ok"], proc.stdout
    assert int(rows["core"][1].replace(",", "")) <= 10 * 1024, proc.stdout
    # The C baseline is measured beside it where its sources are.
    anchor = ROOT.parent / "shared" / "anchors" / "dronecan-c"
    if anchor.is_dir():
        assert "C: canard.c (gcc -Os) .text" in proc.stdout, proc.stdout
    assert proc.returncode == 0, proc.stdout + proc.stderr
