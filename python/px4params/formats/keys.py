"""The keys of a document read from a file (JSON objects, TOML tables): a misspelled key is an
error that names it, never a key silently ignored (a JSON export's ``"instancez"`` read as no
instances would empty the store)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

__all__ = ["unknown_key"]


def unknown_key(keys: Iterable[str], allowed: Sequence[str], what: str = "key") -> str | None:
    """The complaint about the first of ``keys`` that is not ``allowed``: ``unknown key 'x'
    (did you mean 'y'?)``, else ``(expected: a, b)``; None when every key is allowed."""
    for key in keys:
        if key not in allowed:
            import difflib  # (only on an error: a command pays nothing for it)

            hint = difflib.get_close_matches(str(key), allowed, n=1)
            extra = f"did you mean '{hint[0]}'?" if hint else f"expected: {', '.join(allowed)}"
            return f"unknown {what} '{key}' ({extra})"
    return None
