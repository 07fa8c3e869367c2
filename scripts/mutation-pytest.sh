#!/usr/bin/env bash
# The test command of the Python mutation targets (scripts/mutation.sh). mutmut 2 counts a
# mutant killed only when its tests exit 1, but pytest exits 2 when a mutant breaks collection
# (a syntax error, an import that fails): the product would not even import, so that mutant is
# killed too. Other codes pass through (5, no tests collected, stays a setup error).
python -m pytest "$@"
rc=$?
[ "$rc" -eq 2 ] && exit 1
exit "$rc"
