#!/usr/bin/env bash
# The test command of the Python mutation targets (scripts/mutation.sh). mutmut 2 counts a
# mutant killed only when its tests exit 1, but pytest exits 2 when a mutant breaks collection
# (a syntax error, an import that fails): the product would not even import, so that mutant is
# killed too. Other codes pass through (5, no tests collected, stays a setup error).
# pytest runs in this very process (exec, pytest.main): mutmut's timeout kills the process it
# started, and a pytest left running under a killed shell would keep mutmut reading its output
# until it ended on its own (a mutant that makes a test wait forever stalled the whole run).
exec python -c '
import sys

import pytest

code = int(pytest.main(sys.argv[1:]))
sys.exit(1 if code == 2 else code)
' "$@"
