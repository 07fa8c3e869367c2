"""Strict and bounded inputs (issue 35): the one file reader, strict JSON/TOML/.params inputs,
DSDL folders walked once, airframe lines in linear time, caches that cannot lie, output errors,
truncated logs and the servers' durations. The catalogue of bad inputs (``test_bad_inputs.py``)
runs every file kind as a FIFO, a device, a folder, a link loop and an over-size file."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from px4params.errors import InputFileError
from px4params.reading import FileKind, check_file, open_file, read_bytes, read_text

ROOT = Path(__file__).resolve().parents[1]
AIRFRAME = ROOT / "examples" / "two_batteries.airframe"
CLI = [sys.executable, "-m", "px4params"]
SMALL = FileKind("a test file", 10)


def cli(*args: str, cwd: Path | None = None, **kwargs: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*CLI, *args],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=cwd,
        check=False,
        **kwargs,  # type: ignore[arg-type]
    )


@pytest.fixture
def store(tmp_path: Path) -> Path:
    path = tmp_path / "v.store"
    assert cli("run", str(AIRFRAME), "--store", str(path)).returncode == 0
    return path


# -- 1: one bounded reader ----------------------------------------------------------------------


def test_a_regular_file_within_its_cap_is_read_whole(tmp_path: Path) -> None:
    path = tmp_path / "ten"
    path.write_bytes(b"0123456789")
    assert read_bytes(path, SMALL) == b"0123456789"
    assert read_text(path, SMALL) == "0123456789"
    assert check_file(path, SMALL).st_size == 10
    with open_file(path, SMALL) as f:
        assert f.read() == b"0123456789"


def test_a_file_over_its_cap_is_refused_with_both_sizes(tmp_path: Path) -> None:
    path = tmp_path / "eleven"
    path.write_bytes(b"0" * 11)
    message = f"^{path}: too large for a test file \\(11 bytes; at most 10 bytes\\)$"
    for read in (read_bytes, check_file, open_file):
        with pytest.raises(InputFileError, match=message) as caught:
            read(path, SMALL)
    # An OSError too: callers that report "cannot read: {strerror}" report it.
    assert isinstance(caught.value, OSError) and caught.value.filename == str(path)
    big = tmp_path / "big"
    with open(big, "wb") as f:
        f.truncate(17 * 1024 * 1024 + 1)  # sparse: no disk used
    from px4params.reading import STORE

    with pytest.raises(InputFileError, match=r"too large for a store file \(17 MiB; at most 16"):
        read_bytes(big, STORE)


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for read in (read_bytes, check_file, open_file):
        with pytest.raises(InputFileError, match=f"^{fifo}: is a FIFO \\(named pipe\\), not a"):
            read(fifo, SMALL)


def test_devices_folders_and_sockets_are_refused_before_reading(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match=r"^/dev/zero: is a character device, not a regular"):
        read_bytes("/dev/zero", SMALL)
    with pytest.raises(InputFileError, match=f"^{tmp_path}: is a folder, not a file$"):
        read_bytes(tmp_path, SMALL)
    path = tmp_path / "sock"
    server = socket.socket(socket.AF_UNIX)
    try:
        server.bind(str(path))
        with pytest.raises(InputFileError, match=f"^{path}: is a socket, not a regular file$"):
            read_bytes(path, SMALL)
    finally:
        server.close()


def test_a_link_loop_and_a_missing_file_are_the_system_errors(tmp_path: Path) -> None:
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    with pytest.raises(OSError, match="Too many levels of symbolic links"):
        read_bytes(loop, SMALL)
    with pytest.raises(FileNotFoundError):
        read_bytes(tmp_path / "missing", SMALL)


def test_every_product_read_goes_through_the_reader() -> None:
    """No module but the reader opens a file for reading (writes, the package's own data and
    the ground-station codec, which stands alone, excepted)."""
    allowed = {
        "reading.py": "the reader",
        "gcs/codec.py": "copied into ground stations: imports nothing of px4params",
        "vehicle/devid.py": "the bundled era tables (package data)",
        "dsdl/loader.py": "the bundled value_sets.toml (package data)",
        "store/file.py": "the backup copy of the file being saved (the write path)",
        "store/session.py": "the lock file",
    }
    package = ROOT / "python" / "px4params"
    found = []
    for path in package.rglob("*.py"):
        name = path.relative_to(package).as_posix()
        for number, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#")[0]
            reads = re.search(r"(?<![\w.])open\(|\.read_text\(|\.read_bytes\(", code)
            if reads and '"w"' not in code and '"wb"' not in code and name not in allowed:
                found.append(f"{name}:{number}: {line.strip()}")
    assert found == []
