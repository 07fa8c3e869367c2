"""Starting ``px4params gui`` and ``mavlink serve`` for tests: the process, and what it printed
at start (the page's URL with its token); the store they serve, made from the example airframe.
The browser that opens the page is in ``tests/browser.py``."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import px4params
from px4params.store.classic import BUNDLED_CLASSIC

CLI = [sys.executable, "-m", "px4params"]
REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"
#: The bench with faults: INA238#1 fails, what the health views show.
FAULTS = REPO / "examples" / "two_batteries_faults.bench.toml"
#: The line ``px4params gui`` prints once it listens: the page's address and the run's token.
GUI_LINE = r"on (http://127\.0\.0\.1:(\d+)/)\?token=([0-9a-f]{48}) "
#: The line ``mavlink serve`` prints once it listens: its UDP port.
SERVE_LINE = r"on udp 127\.0\.0\.1:(\d+) "


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


def make_store(tmp: Path) -> Path:
    """``px4params run`` of the example airframe in ``tmp``: the store file it saved there."""
    subprocess.run(
        [*CLI, "run", str(AIRFRAME)],
        env=env_for(tmp),
        cwd=tmp,
        check=True,
        capture_output=True,
        timeout=120,
    )
    return tmp / "vehicle.store"


def load_store(store_file: Path) -> px4params.Store:
    """The store file as a vehicle saved it (the bundled types and classic parameters)."""
    return px4params.Store.load(
        store_file, px4params.load_schema(include_dronecan=False), classic=BUNDLED_CLASSIC
    )


def serve(store_file: Path, bench: Path = FAULTS) -> Started:
    """``px4params mavlink serve`` on 127.0.0.1 (a free UDP port: ``match[1]``) over
    ``store_file`` with ``bench``, run in the store's folder."""
    tmp = store_file.parent
    argv = [*CLI, "mavlink", "serve", "--udp", "127.0.0.1:0", "--store", str(store_file)]
    return Started([*argv, "--bench", str(bench)], SERVE_LINE, env_for(tmp), tmp)


def gui_on_store(store_file: Path, port: int = 0) -> Gui:
    """``px4params gui --store`` over ``store_file`` (offline), run in the store's folder."""
    tmp = store_file.parent
    return Gui(["--store", str(store_file)], env_for(tmp), tmp, port)


def gui_on_udp(served: Started, tmp: Path) -> Gui:
    """``px4params gui --udp`` talking to ``served`` (:func:`serve`), run in ``tmp``."""
    return Gui(["--udp", f"127.0.0.1:{served.match[1]}"], env_for(tmp), tmp)
