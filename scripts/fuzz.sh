#!/usr/bin/env bash
# The long fuzz and property run (scheduled, not in every CI run): the same Hypothesis tests as
# CI with PX4PARAMS_HYPOTHESIS_SCALE times the examples (default 50) and no cap on array
# lengths, and the bad-input catalogue; prints the statistics Hypothesis gathered.
#   bash scripts/fuzz.sh [SCALE]
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"
export PX4PARAMS_HYPOTHESIS_SCALE="${1:-50}"
exec pytest -q -p no:cacheprovider --hypothesis-show-statistics \
    tests/test_fuzz.py tests/test_bad_inputs.py tests/test_pydronecan_diff.py \
    tests/test_codec_api.py tests/test_store.py tests/test_storefile.py
