"""PX4-Autopilot's own files at the board table's snapshots, read from a fetched PX4-Autopilot
git directory where one is on this machine (``$PX4_AUTOPILOT_GIT``, colon-separated, or the
mirrors the table was transcribed from). CI has none: a test that needs one skips, saying so."""

from __future__ import annotations

import functools
import os
import subprocess
import tomllib
from pathlib import Path

_MIRRORS = (
    "/work/.mirror/PonomarevDA+PX4-Autopilot/repo",
    "/work/.mirror/dakejahl+PX4-Autopilot/repo",
)
BOARDS_TOML = Path(__file__).resolve().parents[1] / "python/px4params/data/boards.toml"


def px4_git_dirs() -> list[str]:
    """The PX4-Autopilot git directories at hand (none: empty)."""
    listed = os.environ.get("PX4_AUTOPILOT_GIT")
    dirs = listed.split(os.pathsep) if listed else list(_MIRRORS)
    return [d for d in dirs if Path(d).is_dir()]


@functools.cache
def show(dirs: tuple[str, ...], commit: str, path: str) -> str | None:
    """``path`` at ``commit`` from the first of ``dirs`` that has both; None where none has."""
    for git_dir in dirs:
        done = subprocess.run(
            ["git", f"--git-dir={git_dir}", "show", f"{commit}:{path}"],
            capture_output=True,
            text=True,
            check=False,
        )
        if done.returncode == 0:
            return done.stdout
    return None


def snapshot_commits() -> dict[str, str]:
    """Each ``[[snapshot]]`` row of the board table: release -> its full commit."""
    snapshots = tomllib.loads(BOARDS_TOML.read_text(encoding="utf-8"))["snapshot"]
    return {snap["release"]: snap["commit"] for snap in snapshots}
