#!/usr/bin/env bash
# The test command of the Python mutation targets (scripts/mutation.sh). mutmut 2 counts a
# mutant killed only when its tests exit 1, but pytest exits 2 when a mutant breaks collection
# (a syntax error, an import that fails): the product would not even import, so that mutant is
# killed too. It exits 4 when tests/conftest.py cannot be imported, which is the same (conftest
# imports the package: a mutant that breaks an import-time line, `X, Y = None`, stopped there and
# was counted as survived); a usage error, which exits 4 too, is told apart by importing the
# conftest again. Other codes pass through (5, no tests collected, stays a setup error).
# pytest runs in this very process (exec, pytest.main): mutmut's timeout kills the process it
# started, and a pytest left running under a killed shell would keep mutmut reading its output
# until it ended on its own (a mutant that makes a test wait forever stalled the whole run).
exec python -c '
import runpy
import sys

import pytest

code = int(pytest.main(sys.argv[1:]))
if code == 4:
    try:
        runpy.run_path("tests/conftest.py")
    except Exception:
        code = 2
sys.exit(1 if code == 2 else code)
' "$@"
