"""The store's core object with its leaf lookups counted, for tests that hold a write or a read
to a number of core calls (``tests/test_key.py``, ``tests/test_dronecan_params.py``)."""

from __future__ import annotations

from collections import Counter
from typing import Any

import px4params
import pytest

#: The core's calls that find a leaf or decode a value.
COUNTED = ("get_leaf", "get_leaf_value", "set_leaf", "get", "leaves")


class CountingCore:
    """The store's core object, its leaf lookups counted (every other call passed on)."""

    def __init__(self, native: Any) -> None:
        self.native = native
        self.calls: Counter[str] = Counter()

    def __getattr__(self, name: str) -> Any:
        method = getattr(self.native, name)
        if name not in COUNTED:
            return method

        def counted(*args: Any, **kwargs: Any) -> Any:
            self.calls[name] += 1
            return method(*args, **kwargs)

        return counted


def count_core_calls(store: px4params.Store, monkeypatch: pytest.MonkeyPatch) -> CountingCore:
    """``store``'s core calls counted from now on (until the test ends)."""
    counting = CountingCore(store._native)
    monkeypatch.setattr(store, "_native", counting)
    return counting
