#!/usr/bin/env bash
# The long fuzz and property run (scheduled, not in every CI run): every Hypothesis test of CI
# (each test file whose budgets come from tests/strategies.py's budget()) with
# PX4PARAMS_HYPOTHESIS_SCALE times the examples (default 50), no cap on array lengths and a
# deadline that reports a slow input, and the bad-input catalogue; prints the statistics
# Hypothesis gathered. CI runs the same tests at scale 1 (PX4PARAMS_HYPOTHESIS_SCALE=0.2 is a
# quicker run while working).
#   bash scripts/fuzz.sh [SCALE]
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"
export PX4PARAMS_HYPOTHESIS_SCALE="${1:-50}"
mapfile -t files < <(grep -l "from strategies import .*budget" tests/test_*.py)
exec pytest -q -p no:cacheprovider --hypothesis-show-statistics \
    tests/test_cli_bad_inputs.py "${files[@]}"
