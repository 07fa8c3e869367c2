"""The serving loop the link servers share (links/serving.py): turns until stopped, then
releases what it held once; in the caller's thread or a daemon thread of its own, named for
debuggers; as a context manager."""

from __future__ import annotations

import threading
from typing import Any

import pytest
from px4params.links.serving import ServingLoop


class Counting(ServingLoop):
    """Counts its turns and closes; stops itself after ``turns`` turns (from its own thread)."""

    thread_name = "counting-loop"

    def __init__(self, turns: int = 3, fail_at: int | None = None) -> None:
        super().__init__()
        self.turns, self.fail_at = turns, fail_at
        self.timeouts: list[float] = []
        self.closed = 0
        self.threads: list[threading.Thread] = []

    def step(self, timeout: float) -> None:
        self.timeouts.append(timeout)
        self.threads.append(threading.current_thread())
        if len(self.timeouts) == self.fail_at:
            raise RuntimeError("turn failed")
        if len(self.timeouts) >= self.turns:
            self.stop()  # from inside the loop: must not wait for its own thread

    def close(self) -> None:
        self.closed += 1


def test_serve_forever_turns_until_stopped_then_closes_once() -> None:
    loop = Counting(turns=3)
    loop.serve_forever()
    assert loop.timeouts == [0.05, 0.05, 0.05]  # the default turn: 50 ms
    assert loop.threads == [threading.current_thread()] * 3  # in the caller's thread
    assert loop.closed == 1


def test_serve_forever_passes_its_poll_to_every_turn() -> None:
    loop = Counting(turns=2)
    loop.serve_forever(poll=0.25)
    assert loop.timeouts == [0.25, 0.25]


def test_a_stopped_loop_takes_no_turn_and_still_closes() -> None:
    loop = Counting()
    loop.stop()  # no thread: returns at once
    loop.serve_forever()
    assert loop.timeouts == [] and loop.closed == 1


def test_a_failing_turn_ends_the_loop_closed_and_the_error_reaches_the_caller() -> None:
    loop = Counting(turns=5, fail_at=2)
    with pytest.raises(RuntimeError, match=r"^turn failed$"):
        loop.serve_forever()
    assert len(loop.timeouts) == 2 and loop.closed == 1


class Waiting(ServingLoop):
    """Turns until stopped from outside; each turn waits its timeout (as a socket would)."""

    def __init__(self) -> None:
        super().__init__()
        self.turned = threading.Event()
        self.closed = 0
        self.thread: threading.Thread | None = None

    def step(self, timeout: float) -> None:
        self.thread = threading.current_thread()
        self.turned.set()
        threading.Event().wait(min(timeout, 0.01))

    def close(self) -> None:
        self.closed += 1


def test_start_serves_in_a_named_daemon_thread_and_stop_waits_for_it() -> None:
    loop = Waiting()
    assert loop.start() is loop
    try:
        assert loop.turned.wait(10)
        thread: Any = loop.thread
        assert thread is not threading.current_thread()
        assert thread.daemon and thread.name == "px4params-server"  # the default name
    finally:
        loop.stop()
    assert not thread.is_alive() and loop.closed == 1  # stop returned after close


def test_a_subclass_names_its_thread() -> None:
    loop = Counting(turns=2)
    loop.start()
    loop._thread.join(10)  # type: ignore[union-attr]  # it stops itself
    assert [t.name for t in loop.threads] == ["counting-loop"] * 2
    assert loop.closed == 1
    loop.stop()  # after the thread ended: returns at once


def test_the_loop_is_a_context_manager_serving_in_its_thread() -> None:
    with Waiting() as loop:
        assert isinstance(loop, Waiting)
        assert loop.turned.wait(10)
        thread: Any = loop.thread
        assert thread.is_alive()
    assert not thread.is_alive() and loop.closed == 1


def test_close_of_the_base_loop_holds_nothing() -> None:
    assert ServingLoop().close() is None
