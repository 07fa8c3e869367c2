"""What works without options: ``px4params --version`` and ``autostart run`` without
``--bench`` (a bench where every configured device is present and healthy)."""

from __future__ import annotations

import hashlib
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from px4params.cli.main import main

REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"
HEALTHY_BENCH_FILE = REPO / "examples" / "two_batteries.bench.toml"


def test_version_names_package_core_and_dsdl_set() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "px4params", "--version"], capture_output=True, text=True
    )
    assert (proc.returncode, proc.stderr) == (0, "")
    package = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["version"]
    core = tomllib.loads((REPO / "Cargo.toml").read_text())["workspace"]["package"]["version"]
    files = sorted((REPO / "python/px4params/data/dsdl/px").rglob("*.dsdl"))
    digest = hashlib.sha256()
    for f in files:
        digest.update(f.relative_to(REPO / "python/px4params/data/dsdl/px").as_posix().encode())
        digest.update(b"\0" + f.read_bytes() + b"\0")
    assert proc.stdout.splitlines() == [
        f"px4params {package}",
        f"core {core} (Rust, px4params-core; store file format 2)",
        f"DSDL px: {len(files)} types (bundled), sha256 {digest.hexdigest()[:16]}",
    ]
    assert len(files) >= 40


def test_version_first_ends_the_parse(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version", "param", "show"]) == 0
    assert capsys.readouterr().out.startswith("px4params ")


def _boot(capsys: pytest.CaptureFixture[str], *words: str) -> tuple[int, list[str], str]:
    status = main(["autostart", "run", "--airframe", str(AIRFRAME), "--duration", "5", *words])
    out, err = capsys.readouterr()
    return status, out.splitlines(), err


def test_run_without_bench_boots_every_configured_device_healthy(
    capsys: pytest.CaptureFixture[str],
) -> None:
    status, lines, err = _boot(capsys)
    assert (status, err) == (0, "")
    assert lines[0] == (
        "manifest boot of a healthy bench (every configured device present, no faults): "
        "3 configured instances, 5 s simulated, seed 0"
    )
    assert lines[-1] == "commander: may arm (all 3 configured devices nominal)"
    # The same boot as on the hand-written bench of the same vehicle, device for device.
    status, by_hand, err = _boot(capsys, "--bench", str(HEALTHY_BENCH_FILE))
    assert (status, err) == (0, "")
    assert lines[1:] == by_hand[1:]
    assert [line.split()[0] for line in lines[1:4]] == ["INA238#0", "INA238#1", "AK09916#0"]


def test_run_without_bench_leaves_out_what_cannot_start(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Bus 0 is no bus: the instance cannot start, so no device is put there and arming is
    # refused for it, as on any bench.
    airframe = tmp_path / "bus0.airframe"
    airframe.write_text(
        "param add INA238#0\nparam set-default INA238#0.bus.i2c.bus_id 0\n"
        "param add AK09916#0\nparam set-default AK09916#0.bus.i2c.bus_id 1\n"
        "param set-default AK09916#0.bus.i2c.address 0x0C\n"
    )
    status = main(["autostart", "run", "--airframe", str(airframe), "--duration", "3"])
    out = capsys.readouterr().out
    assert status == 1
    assert "AK09916#0 ak09916 I2C bus 1 address 0x0C   nominal" in out
    assert "commander: arming refused (1 of 2 devices not nominal):" in out


def test_legacy_without_manifest_needs_a_bench(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    assert main(["autostart", "run", "--legacy"]) == 1
    assert capsys.readouterr() == (
        "",
        "px4params: error: --legacy without a manifest (--store or --airframe) needs --bench "
        "FILE\n",
    )
