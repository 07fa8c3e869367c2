"""The serving loop the link servers share: run until stopped, in the caller's thread or in
one of its own (tests and embedding), as a context manager."""

from __future__ import annotations

import threading
from typing import Self

__all__ = ["ServingLoop"]


class ServingLoop:
    """Subclasses define :meth:`step` (one turn, waiting up to ``timeout``) and may define
    :meth:`close` (called once the loop ends) and ``thread_name``."""

    thread_name = "px4params-server"

    def __init__(self) -> None:
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def step(self, timeout: float) -> None:  # pragma: no cover - every subclass has its own
        raise NotImplementedError

    def close(self) -> None:
        """Releases what the loop held (nothing here)."""

    def serve_forever(self, poll: float = 0.05) -> None:
        """Runs until :meth:`stop` (or Ctrl-C in the caller), then :meth:`close`."""
        try:
            while not self._stop.is_set():
                self.step(poll)
        finally:
            self.close()

    def start(self) -> Self:
        """Serves in a background thread."""
        self._thread = threading.Thread(target=self.serve_forever, name=self.thread_name)
        self._thread.daemon = True
        self._thread.start()
        return self

    def stop(self) -> None:
        """Asks the loop to end; waits for the background thread if there is one."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
