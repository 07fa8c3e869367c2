"""scripts/mutation_lines.py, the mutation run's tests by line (scripts/mutation.sh,
MUTATION_BY_LINE=1): a traced run of a tiny project's tests says which test executes which
line; mutmut 2.5.1 given it as mutmut_config.py runs a mutant first with those tests, and with
all of them what they let through; and finds the kept results of a line written twice."""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import Any

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "mutation_lines.py"
MUTMUT = shutil.which("mutmut", path=str(Path(sys.executable).parent))

# The module under test: f and g each `return 1` (the same line twice), a constant read at
# import, and one statement over three lines.
MODULE = """\
LIMIT = 3


def f(x):
    return 1


def g(x):
    if x > LIMIT:
        return 2
    return 1


def h(x):
    total = (x
             + 1)
    return total
"""
TEST_F = """\
from mod import f


def test_f():
    assert f(0) == 1
"""
TEST_G = """\
from mod import g


def test_g_small():
    assert g(0) == 1


def test_g_large():
    assert g(9) == 2
"""
TEST_H = """\
from mod import h


def test_h():
    assert h(1) == 2
"""


def _project(root: Path, tests: dict[str, str]) -> None:
    (root / "tests").mkdir(parents=True)
    (root / "mod.py").write_text(MODULE)
    for name, text in tests.items():
        (root / "tests" / name).write_text(text)


def _env(root: Path, **more: str) -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(root), PYTHONDONTWRITEBYTECODE="1", **more)


def _trace(root: Path, tests: str = "tests") -> dict[str, Any]:
    out = root / "lines.json"
    subprocess.run(
        [sys.executable, str(SCRIPT), str(out), "mod.py", tests],
        cwd=root,
        env=_env(root),
        check=True,
        capture_output=True,
    )
    traced: dict[str, Any] = json.loads(out.read_text())
    return traced


def _hook() -> ModuleType:
    spec = importlib.util.spec_from_file_location("mutation_lines", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_each_line_is_given_the_tests_that_execute_it(tmp_path: Path) -> None:
    _project(tmp_path, {"test_f.py": TEST_F, "test_g.py": TEST_G, "test_h.py": TEST_H})
    traced = _trace(tmp_path)
    lines = traced["lines"]["mod.py"]

    def tests_of(line: int) -> object:
        who = lines.get(str(line))
        return who if who in (None, "all") else sorted(traced["tests"][i] for i in who)

    f = "tests/test_f.py::test_f"
    g_small, g_large = "tests/test_g.py::test_g_small", "tests/test_g.py::test_g_large"
    assert tests_of(1) == "all"  # LIMIT = 3: run at import, which every test needs
    assert tests_of(4) == "all"  # def f(x): the function is made at import
    assert tests_of(5) == [f]
    assert tests_of(9) == [g_large, g_small]  # if x > LIMIT: both
    assert tests_of(10) == [g_large]
    assert tests_of(11) == [g_small]
    # a statement over two lines: its second line is the statement's, whatever the trace says
    assert tests_of(15) == tests_of(16) == ["tests/test_h.py::test_h"]


def test_a_mutant_runs_the_tests_of_its_line_with_the_target_s_options(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _project(tmp_path, {"test_f.py": TEST_F, "test_g.py": TEST_G, "test_h.py": TEST_H})
    (tmp_path / "lines.json").write_text(json.dumps(_trace(tmp_path)))
    hook = _hook()
    command = "bash run.sh -x -q tests/test_f.py tests/test_g.py -k 'not slow'"

    def narrowed(line: int) -> str:
        context = SimpleNamespace(
            filename="mod.py",
            current_line_index=line - 1,  # mutmut counts lines from 0
            config=SimpleNamespace(test_command=command),
        )
        hook.pre_mutation(context)
        return str(context.config.test_command)

    monkeypatch.setenv("MUTATION_LINES", str(tmp_path / "lines.json"))
    assert narrowed(10) == "bash run.sh -x -q -k 'not slow' tests/test_g.py::test_g_large"
    assert narrowed(1) == command  # a line run at import: every test
    assert narrowed(13) == command  # a line no test executes (blank here): every test


def _mutmut(root: Path, *args: str, **env: str) -> None:
    assert MUTMUT is not None
    subprocess.run(
        # (a base of 10 s over mutmut's 2x the clean run: on a loaded machine a test that
        # starts a process took longer than that and was a timeout, not a kill)
        [MUTMUT, "run", "--paths-to-mutate", "mod.py", "--tests-dir", "tests", "--simple-output",
         "--no-progress", "--test-time-base", "10", *args],
        cwd=root, env=_env(root, **env), check=False, capture_output=True, timeout=600,
    )  # fmt: skip


def _statuses(root: Path, line: int) -> list[str]:
    """mutmut's kept results of the mutants of ``line``, with the tests' hash they are of."""
    rows = (
        sqlite3.connect(root / ".mutmut-cache")
        .execute(
            "SELECT Mutant.status, Mutant.tested_against_hash = MiscData.value FROM Mutant"
            " JOIN Line ON Mutant.line = Line.id, MiscData WHERE MiscData.key = 'hash_of_tests'"
            " AND Line.line_number = ? ORDER BY Mutant.id",
            (line - 1,),
        )
        .fetchall()
    )
    return [status if current else "untested" for status, current in rows]


@pytest.mark.skipif(MUTMUT is None, reason="mutmut is not installed (the 'mutation' extra)")
def test_a_mutant_its_line_s_tests_let_through_is_run_with_all_of_them(tmp_path: Path) -> None:
    # g's `return 2` is executed by test_g_runs, which checks nothing, and checked by
    # test_g_elsewhere in another process, where no trace sees it: the traced test lets its
    # mutant through, all of the tests kill it
    _project(tmp_path, {"test_f.py": TEST_F})
    (tmp_path / "tests" / "test_g.py").write_text(
        "import subprocess, sys\n\nfrom mod import g\n\n\ndef test_g_runs():\n    g(9)\n\n\n"
        "def test_g_elsewhere():\n    code = 'from mod import g; assert g(9) == 2'\n"
        "    subprocess.run([sys.executable, '-c', code], check=True)\n"
    )
    traced = _trace(tmp_path)
    assert [traced["tests"][i] for i in traced["lines"]["mod.py"]["10"]] == [
        "tests/test_g.py::test_g_runs"
    ]
    (tmp_path / "lines.json").write_text(json.dumps(traced))
    shutil.copy(SCRIPT, tmp_path / "mutmut_config.py")
    _mutmut(tmp_path, "--runner", "python -m pytest -x -q tests", "--rerun-all",
            MUTATION_LINES=str(tmp_path / "lines.json"))  # fmt: skip
    assert _statuses(tmp_path, 10) == ["ok_killed"]  # return 2 -> return 3
    assert _statuses(tmp_path, 5) == ["ok_killed"]  # f's return 1, by test_f


@pytest.mark.skipif(MUTMUT is None, reason="mutmut is not installed (the 'mutation' extra)")
def test_the_second_of_two_equal_lines_is_tested_in_a_run_that_goes_on(tmp_path: Path) -> None:
    # first run: g untested by any test, its `return 1` (line 11) survives as f's (line 5) is
    # killed; second run, with g's tests: line 11's mutant is tested again and killed, not
    # taken for line 5's by its text (mutmut 2.5.1's own lookup left it untested)
    _project(tmp_path, {"test_f.py": TEST_F})
    shutil.copy(SCRIPT, tmp_path / "mutmut_config.py")
    _mutmut(tmp_path, "--runner", "python -m pytest -x -q tests")
    assert _statuses(tmp_path, 5) == ["ok_killed"]
    assert _statuses(tmp_path, 11) == ["bad_survived"]
    (tmp_path / "tests" / "test_g.py").write_text(TEST_G)
    _mutmut(tmp_path, "--runner", "python -m pytest -x -q tests")
    assert _statuses(tmp_path, 11) == ["ok_killed"]
