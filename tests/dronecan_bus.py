"""Test helpers for DroneCAN over SLCAN: a virtual CAN bus with SLCAN adapters on pseudo-
terminals (so that two hosts, e.g. pydronecan and ``px4params dronecan param``, can talk), and
``px4params dronecan serve`` started as a subprocess."""

from __future__ import annotations

import os
import select
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from px4params.links.slcan import SlcanAdapter, open_pty

PX4PARAMS = [sys.executable, "-m", "px4params"]


class VirtualBus:
    """``ports`` SLCAN adapters on one virtual CAN bus: a frame one host sends reaches every
    other open one. Runs in a thread until :meth:`close`."""

    def __init__(self, ports: int = 2) -> None:
        opened = [open_pty() for _ in range(ports)]
        self.ports = [port for port, _ in opened]
        self.paths = [path for _, path in opened]
        self.adapters = [SlcanAdapter() for _ in range(ports)]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        fds = {port.fileno(): n for n, port in enumerate(self.ports)}
        while not self._stop.is_set():
            ready, _, _ = select.select(list(fds), [], [], 0.05)
            for fd in ready:
                n = fds[fd]
                data = self.ports[n].read(4096)
                replies, frames = self.adapters[n].feed(data)
                if replies:
                    self.ports[n].write(replies)
                for frame in frames:
                    for m, adapter in enumerate(self.adapters):
                        if m != n and (line := adapter.deliver(frame)):
                            self.ports[m].write(line)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        for port in self.ports:
            port.close()


def start_serving(
    store: Path, *extra: str, timeout: float = 20.0
) -> tuple[subprocess.Popen[str], str]:
    """Starts ``px4params dronecan serve --slcan-pty --store STORE``: the process and the first
    line it printed within ``timeout`` (``slcan: /dev/pts/N ...``, naming the pty; "" if none)."""
    proc = subprocess.Popen(
        [*PX4PARAMS, "dronecan", "serve", "--slcan-pty", "--store", str(store), *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if select.select([proc.stdout], [], [], 0.5)[0]:
            return proc, proc.stdout.readline()
        if proc.poll() is not None:
            break
    return proc, ""


@contextmanager
def served(store: Path, *extra: str, timeout: float = 20.0) -> Iterator[str]:
    """``px4params dronecan serve --slcan-pty --store STORE``: yields the pty's path; stops
    the server (SIGTERM) at the end. Its output is in ``served.output`` afterwards."""
    proc, first = start_serving(store, *extra, timeout=timeout)
    try:
        assert first.startswith("slcan: /dev/"), f"no pty announced: {first!r}"
        yield first.split()[1]
    finally:
        proc.terminate()
        try:
            out, _ = proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
        served.output = first + out  # type: ignore[attr-defined]
