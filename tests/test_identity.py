"""Who a node is (links/identity.py): the version parts MAVLink's AUTOPILOT_VERSION and
DroneCAN's GetNodeInfo carry, and the unique ID that stays with a store file (ground stations
key their parameter caches by it), computed here from the rule: SHA-256 of "file:" and the
file's real path, or of "memory:" and the parameter names."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import px4params
import pytest
from px4params.links.identity import store_digest, version_parts


@pytest.mark.parametrize(
    ("version", "parts"),
    [
        ("0.1.0", (0, 1, 0, False)),
        ("2.3.4.dev5", (2, 3, 4, True)),  # PEP 440 development release
        ("1.15.300", (1, 15, 300, False)),
        ("1.2", (1, 2, 0, False)),  # missing parts are 0
        ("7", (7, 0, 0, False)),
        ("1.2.3+4", (1, 2, 3, False)),  # a local version label is not the patch
        ("1.2.3.4", (1, 2, 3, False)),  # only major, minor, patch
    ],
)
def test_version_parts_are_major_minor_patch_and_development(
    monkeypatch: pytest.MonkeyPatch, version: str, parts: tuple[int, int, int, bool]
) -> None:
    monkeypatch.setattr(px4params, "__version__", version)
    assert version_parts() == parts


def test_a_store_file_is_named_by_its_real_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "vehicle.store"
    path.write_bytes(b"")
    expected = hashlib.sha256(b"file:" + os.fsencode(os.path.realpath(path))).digest()
    assert store_digest(path, ["IGNORED"]) == expected
    assert len(expected) == 32
    link = tmp_path / "link.store"
    link.symlink_to(path)
    monkeypatch.chdir(tmp_path)
    # a symlink, a relative path, a str: the same file, the same vehicle
    assert store_digest(link, []) == store_digest("vehicle.store", []) == expected
    assert store_digest(str(path), []) == expected
    assert store_digest(tmp_path / "other.store", []) != expected


def test_a_path_that_is_not_utf8_is_named_by_its_bytes(tmp_path: Path) -> None:
    """POSIX paths are bytes: Python carries an undecodable byte as a surrogate."""
    path = os.fsdecode(os.fsencode(str(tmp_path)) + b"/caf\xe9.store")
    assert "\udce9" in path
    expected = hashlib.sha256(b"file:" + os.fsencode(os.path.realpath(path))).digest()
    assert store_digest(path, []) == expected


def test_a_store_in_memory_is_named_by_its_parameters() -> None:
    names = ["BAT1_CAPACITY", "SYS_AUTOSTART"]
    expected = hashlib.sha256(b"memory:BAT1_CAPACITY,SYS_AUTOSTART").digest()
    assert store_digest(None, names) == expected
    assert store_digest(None, iter(names)) == expected  # any iterable, read once
    assert store_digest(None, names[::-1]) != expected
    assert store_digest(None, []) == hashlib.sha256(b"memory:").digest()
