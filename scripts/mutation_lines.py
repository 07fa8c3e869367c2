"""A mutant of a Python target run first with the tests that execute its line
(scripts/mutation.sh, MUTATION_BY_LINE=1).

One file, two jobs:

- Traced run: ``python scripts/mutation_lines.py OUT FILES TESTS`` runs the target's tests
  (TESTS: the target's pytest arguments as one string) once with ``sys.settrace`` and writes OUT
  (JSON): for each line of FILES (comma-separated files or folders), the tests that execute the
  statement it belongs to, fastest first, or "all" for a statement run at import (a module's or
  class body's line: every test depends on it).
- mutmut 2.5.1's hook: scripts/mutation.sh copies this file to mutmut_config.py in the clone's
  root for the run (mutmut imports it from its working directory) and sets MUTATION_LINES to
  OUT. ``pre_mutation`` gives a mutant's run those tests only; mutmut's --rerun-all runs all of
  the target's tests on what they let through, so a verdict is never weaker than a plain run's.
  A line no traced test executes (reached only in a subprocess, say) runs them all.

``init`` also mends mutmut 2.5.1's lookup of kept results, which finds a line by its text: the
mutants of a line written twice in a file took the first one's results, and stayed untested.
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
import shlex
import sys
import threading
import time
from pathlib import Path
from typing import Any

IMPORT = -1  # the tests' index while no test runs: collection, which imports the modules


def target_files(paths: str) -> list[str]:
    """The .py files of a target's comma-separated files and folders, as mutmut names them."""
    files: list[str] = []
    for path in paths.split(","):
        if path.endswith(".py"):
            files.append(path)
        else:
            files.extend(str(p) for p in sorted(Path(path).rglob("*.py")))
    return files


def trace_key(files: list[str], tests: str) -> str:
    """What a traced run depends on: the target's files, the tests, the test arguments."""
    digest = hashlib.sha256(tests.encode())
    for path in [*files, *sorted(str(p) for p in Path("tests").rglob("*.py"))]:
        digest.update(path.encode() + b"\0" + Path(path).read_bytes())
    return digest.hexdigest()


def statement_lines(source: str) -> dict[int, range]:
    """Each line's statement, as the lines a trace may report it on: a simple statement's
    lines, a compound one's header (``if``, ``def`` with its arguments, ``except``), not its body.
    mutmut names a mutant by the line of the node it changed, which for an expression written
    over several lines need not be a line the interpreter reports."""
    spans: dict[int, range] = {}
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, (ast.stmt, ast.excepthandler, ast.match_case)):
            continue
        where: Any = getattr(node, "pattern", node)  # a case's header starts at its pattern
        first = where.lineno
        body = getattr(node, "body", None)
        last = body[0].lineno - 1 if isinstance(body, list) and body else where.end_lineno or first
        span = range(first, max(first, last) + 1)
        for line in span:
            # the innermost statement wins: a statement's span lies inside its parent's header
            # only for an expression's own lines (a lambda's), which are its parent's too
            if line not in spans or len(span) < len(spans[line]):
                spans[line] = span
    return spans


class Tracer:
    """A pytest plugin recording which test executes which line of the target's files."""

    def __init__(self, files: list[str]) -> None:
        self.by_real = {os.path.realpath(f): f for f in files}
        self.nodeids: list[str] = []
        self.seconds: list[float] = []
        self.current = IMPORT
        # (file, line) -> the indices of the tests that ran it (IMPORT: run at import)
        self.ran: dict[tuple[str, int], set[int]] = {}

    def _global(self, frame: Any, event: str, arg: Any) -> Any:
        name = self.by_real.get(frame.f_code.co_filename)
        if name is None:
            return None
        # a module's or class body's code runs once, at import, whichever test imported it
        at_import = not frame.f_code.co_flags & 0x2  # inspect.CO_NEWLOCALS: a function's

        def local(frame: Any, event: str, arg: Any) -> Any:
            if event == "line":
                who = IMPORT if at_import else self.current
                self.ran.setdefault((name, frame.f_lineno), set()).add(who)
            return local

        return local

    # pytest's hooks: each test's setup, call and teardown lie between these two
    def pytest_runtest_logstart(self, nodeid: str, location: Any) -> None:
        self.current = len(self.nodeids)
        self.nodeids.append(nodeid)
        self.seconds.append(time.perf_counter())

    def pytest_runtest_logfinish(self, nodeid: str, location: Any) -> None:
        self.seconds[self.current] = time.perf_counter() - self.seconds[self.current]
        self.current = IMPORT

    def run(self, args: list[str]) -> int:
        import pytest

        sys.settrace(self._global)
        threading.settrace(self._global)  # threads a test starts
        try:
            return int(pytest.main(args, plugins=[self]))
        finally:
            sys.settrace(None)
            threading.settrace(None)  # type: ignore[arg-type,unused-ignore]

    def table(self, files: list[str]) -> dict[str, dict[str, Any]]:
        """Per file, per line: the tests of its statement, fastest first, or "all"."""
        speed = sorted(range(len(self.nodeids)), key=lambda i: self.seconds[i])
        rank = {test: r for r, test in enumerate(speed)}
        table: dict[str, dict[str, Any]] = {}
        for name in files:
            lines: dict[str, Any] = {}
            for line, span in statement_lines(Path(name).read_text()).items():
                who = set().union(*(self.ran.get((name, n), set()) for n in span))
                if IMPORT in who:
                    lines[str(line)] = "all"
                elif who:
                    lines[str(line)] = sorted(who, key=rank.__getitem__)
            table[name] = lines
        return table


def trace(out: str, paths: str, tests: str) -> int:
    """Writes OUT for the target, unless it holds a trace of the same files and tests."""
    files = target_files(paths)
    key = trace_key(files, tests)
    try:
        if json.loads(Path(out).read_text())["key"] == key:
            print(f"{out}: the traced run of these files and tests, kept")
            return 0
    except (OSError, ValueError, KeyError):
        pass
    tracer = Tracer(files)
    code = tracer.run([*shlex.split(tests), "-q", "-p", "no:cacheprovider"])
    data = {"key": key, "tests": tracer.nodeids, "lines": tracer.table(files)}
    Path(out).write_text(json.dumps(data))
    return code


# mutmut 2.5.1's hooks (this file as mutmut_config.py) ------------------------------------------

_table: dict[str, Any] | None = None


def _lines() -> dict[str, Any] | None:
    global _table
    if _table is None and os.environ.get("MUTATION_LINES"):
        _table = json.loads(Path(os.environ["MUTATION_LINES"]).read_text())
    return _table


def narrowed(command: str, nodeids: list[str]) -> str:
    """The target's test command with its test files replaced by these tests (its options, -k
    and -m, kept: the traced run had them too)."""
    words = shlex.split(command)
    kept = [w for w in words if not (w.startswith("tests/") and w.split("::")[0].endswith(".py"))]
    return shlex.join([*kept, *nodeids])


def pre_mutation(context: Any) -> None:
    """mutmut calls this before each mutant's tests: only the tests that execute its line."""
    table = _lines()
    if table is None:
        return
    tests = table["lines"].get(context.filename, {}).get(str(context.current_line_index + 1))
    if isinstance(tests, list):
        nodeids = [table["tests"][i] for i in tests]
        context.config.test_command = narrowed(context.config.test_command, nodeids)


def init() -> None:
    """mutmut calls this once, before the run: kept results looked up by line number too."""
    import mutmut.cache  # type: ignore[import-untyped]

    def cached_statuses(filename: str, mutations: Any, hash_of_tests: str) -> dict[Any, str]:
        # mutmut 2.5.1 keys its lines by text: a line written twice took the first one's
        # results; the lookup of one mutant (cached_mutation_status) takes its line number
        return {
            m: mutmut.cache.cached_mutation_status(filename, m, hash_of_tests) for m in mutations
        }

    mutmut.cache.get_cached_mutation_statuses = cached_statuses


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: python scripts/mutation_lines.py OUT FILES TESTS")
    sys.exit(trace(*sys.argv[1:]))
