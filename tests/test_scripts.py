"""The scripts a new user runs: ``scripts/setup.sh`` installs what px4params needs to run (the
demo's) or, with ``--test``, the test tools too; ``scripts/demo-steps.sh`` (the demo's
commands) runs in an empty folder, with no setting from the environment, and keeps its files.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

STUB = """#!/bin/sh
echo "$(basename "$0") $*" >> "$LOG"
"""


def _setup(tmp_path: Path, *args: str) -> tuple[int, list[str], str]:
    """Runs setup.sh in a copy of the checkout whose .venv has stand-ins for python and
    maturin (and apt-get, chromium and cbindgen absent): which installs it asks for."""
    root = tmp_path / "checkout"
    (root / "scripts").mkdir(parents=True)
    shutil.copy(REPO / "scripts" / "setup.sh", root / "scripts" / "setup.sh")
    tools = tmp_path / "tools"
    for folder, names in ((root / ".venv" / "bin", ("python", "maturin")), (tools, ("apt-get",))):
        folder.mkdir(parents=True)
        for name in names:
            (folder / name).write_text(STUB)
            (folder / name).chmod(0o755)
    log = tmp_path / "log"
    log.write_text("")
    # PATH: the stand-in apt-get and the shell's own tools, no chromium or cbindgen
    env = {"LOG": str(log), "PATH": f"{tools}:/usr/bin:/bin", "HOME": str(tmp_path)}
    proc = subprocess.run(
        ["bash", "scripts/setup.sh", *args], cwd=root, env=env, capture_output=True, text=True
    )
    return proc.returncode, log.read_text().splitlines(), proc.stdout + proc.stderr


def test_setup_installs_what_px4params_needs_to_run_only(tmp_path: Path) -> None:
    status, calls, _ = _setup(tmp_path)
    assert status == 0
    assert calls == [
        "python -m pip install --quiet --disable-pip-version-check maturin>=1.7,<2 uv>=0.4,<1",
        "maturin develop --uv --release",
    ]


def test_setup_test_adds_the_test_tools(tmp_path: Path) -> None:
    status, calls, _ = _setup(tmp_path, "--test")
    assert status == 0
    assert "maturin develop --uv --release --extras test" in calls
    assert any("mavproxy==" in c for c in calls)
    if os.getuid() == 0 and not shutil.which("chromium", path="/usr/bin:/bin"):
        assert any(c.startswith("apt-get install") and "chromium" in c for c in calls)


def test_setup_refuses_unknown_options(tmp_path: Path) -> None:
    status, calls, output = _setup(tmp_path, "--tests")
    assert (status, calls) == (2, [])
    assert output == "usage: bash scripts/setup.sh [--test]\n"


def test_demo_runs_in_an_empty_folder_without_hidden_settings(tmp_path: Path) -> None:
    folder = tmp_path / "demo-run"
    env = dict(os.environ)
    env["PATH"] = os.path.dirname(sys.executable) + os.pathsep + env["PATH"]
    # A store named by the environment is not the demo's: it must be neither read nor written.
    env["PX4PARAMS_STORE"] = str(tmp_path / "elsewhere.store")
    proc = subprocess.run(
        ["bash", str(REPO / "scripts" / "demo-steps.sh"), str(folder)],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "elsewhere.store").exists()
    # Every file the demo names is there after it ended.
    assert "$ px4params health run.ulg" in proc.stdout
    assert (folder / "run.ulg").read_bytes()[:7] == b"ULog\x01\x12\x35"  # a ULog's magic
    assert (folder / "vehicle.store").read_bytes()[:4] == b"PX4P"
    assert (folder / "examples" / "two_batteries.airframe").is_file()
    assert proc.stdout.rstrip().endswith(
        f"The demo's files stay in {folder} (vehicle.store, run.ulg, examples/)."
    )
    assert "manifest boot of a healthy bench" in proc.stdout
    assert "commander: may arm (all 3 configured devices nominal)" in proc.stdout


def test_package_metadata_for_an_index() -> None:
    import tomllib

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert project["readme"] == "README.md" and project["license"] == "MIT"
    license_text = (REPO / project["license-files"][0]).read_text()
    assert license_text.startswith("MIT License\n\nCopyright (c) ")
    assert "Permission is hereby granted, free of charge, to any person obtaining a copy" in (
        license_text
    )
    assert "Programming Language :: Python :: 3.11" in project["classifiers"]
    assert all(url.startswith("https://") for url in project["urls"].values())
    # abi3: one wheel for every CPython from requires-python on
    maturin = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["maturin"]
    assert "pyo3/abi3-py311" in maturin["features"] and project["requires-python"] == ">=3.11"


def test_mavsdk_is_pinned_under_its_new_name() -> None:
    """mavsdk 3.17.4 warns that the gRPC API moved to mavsdk-grpc (``mavsdk`` being the native
    binding from 4 on): the tests pin the renamed package, which imports without the warning."""
    import tomllib

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]["test"]
    assert "mavsdk-grpc==3.17.4" in extras
    assert not [r for r in extras if r.split("=")[0].split("<")[0].split(">")[0] == "mavsdk"]
    proc = subprocess.run(
        [sys.executable, "-W", "error::FutureWarning", "-c", "import mavsdk_grpc"],
        capture_output=True,
        text=True,
    )
    assert (proc.returncode, proc.stderr) == (0, "")


def _budgets(scale: str) -> subprocess.CompletedProcess[str]:
    code = "import strategies as s; print(s.budget(8), s.budget(300), s.LONG_RUN)"
    env = dict(os.environ, PX4PARAMS_HYPOTHESIS_SCALE=scale)
    return subprocess.run(
        [sys.executable, "-c", code], cwd=REPO / "tests", env=env, capture_output=True, text=True
    )


def test_property_budgets_scale_with_the_environment() -> None:
    assert _budgets("").stdout == "8 300 False\n"  # CI's
    assert _budgets("0.2").stdout == "2 60 False\n"  # quicker, every property still runs
    assert _budgets("0.01").stdout == "1 3 False\n"
    assert _budgets("50").stdout == "400 15000 True\n"  # scripts/fuzz.sh
    bad = _budgets("fast")
    assert (bad.returncode, bad.stderr) == (
        1,
        "$PX4PARAMS_HYPOTHESIS_SCALE: 'fast' is not a number (1 is CI's budget)\n",
    )
    assert _budgets("0").stderr.endswith("out of range (more than 0, less than 10000)\n")


#: How fuzz.sh finds the files whose budgets scale (split: this file is not one of them).
IMPORTS_BUDGET = "from strategies " + "import .*budget"


def test_every_property_budget_scales() -> None:
    """Every Hypothesis budget goes through strategies.budget(), so that CI stays fast and
    scripts/fuzz.sh (which runs each file importing it) multiplies them all."""
    fixed = []
    for path in sorted((REPO / "tests").glob("test_*.py")):
        if path.name == "test_scripts.py":  # (this test's own patterns)
            continue
        text = path.read_text()
        fixed += [f"{path.name}: {m}" for m in re.findall(r"max_examples=(?!budget\()\S+", text)]
        if "max_examples=" in text:
            assert re.search(IMPORTS_BUDGET, text), path.name
    assert fixed == []
    assert f'grep -l "{IMPORTS_BUDGET}"' in (REPO / "scripts/fuzz.sh").read_text()
