"""Starting ``px4params gui`` and ``mavlink serve`` for tests: the process, and what it printed
at start (the page's URL with its token)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

CLI = [sys.executable, "-m", "px4params"]
#: The line ``px4params gui`` prints once it listens: the page's address and the run's token.
GUI_LINE = r"on (http://127\.0\.0\.1:(\d+)/)\?token=([0-9a-f]{48}) "


class Started:
    """A command that prints a line and keeps running: its process and that line's match."""

    def __init__(self, argv: list[str], pattern: str, env: dict[str, str], cwd: Path) -> None:
        self.proc = subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=cwd
        )
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        match = re.search(pattern, line)
        if match is None:
            self.stop()
            raise AssertionError(f"{argv[3:5]}: {line!r} {self.proc.stderr.read()[-2000:]}")  # type: ignore[union-attr]
        self.match = match

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


class Gui(Started):
    """``px4params gui`` on 127.0.0.1 and ``port`` (0: a free one): ``base`` is the page's address
    (``http://127.0.0.1:PORT/``), ``token`` the run's secret and ``url`` the two together, as
    printed."""

    def __init__(self, argv: list[str], env: dict[str, str], cwd: Path, port: int = 0) -> None:
        super().__init__([*CLI, "gui", *argv, "--http", f"127.0.0.1:{port}"], GUI_LINE, env, cwd)
        self.base = self.match[1]
        self.port = int(self.match[2])
        self.token = self.match[3]
        self.url = f"{self.base}?token={self.token}"
        self.host = f"127.0.0.1:{self.port}"


def env_for(tmp: Path) -> dict[str, str]:
    """The environment without the caller's PX4PARAMS_* settings (but its cache), with the
    default store in ``tmp``."""
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith("PX4PARAMS_") or k == "PX4PARAMS_CACHE_DIR"
    }
    env["PX4PARAMS_STORE"] = str(tmp / "vehicle.store")
    return env
