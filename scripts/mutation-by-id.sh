#!/usr/bin/env bash
# Goes on with a Python target of scripts/mutation.sh one mutant at a time (mutmut 2.5.1's
# `mutmut run ID`), from its kept results (target/mutation/<target>.mutmut-cache), testing
# first the mutants on lines from FIRST_LINE on: where a run in file order would spend its
# budget on lines whose mutants are known (e.g. gui/vehicle.py's MavlinkVehicle, reached by no
# test of the baseline), and never reach the rest. Stops starting mutants after DEADLINE (UTC HH:MM).
# Afterwards count the results with MUTATION_REPORT_ONLY=1 bash scripts/mutation.sh <target>.
#
#   bash scripts/mutation-by-id.sh gui-vehicle python/px4params/gui/vehicle.py \
#     tests/test_gui_vehicle.py 197 08:06
# MUTATION_IDS="114 116 131": these mutants only (mutmut's IDs in the kept results), in this
# order. MUTATION_BY_LINE=1: each first with the tests of its line, as scripts/mutation.sh's
# (its traced run, target/mutation/<target>.lines.json, must be there: run mutation.sh so once).
set -euo pipefail
cd "$(dirname "$0")/.."
name=$1 paths=$2 tests=$3 first=${4:-1} deadline=${5:-23:59}
out="${CARGO_TARGET_DIR:-$PWD/target}/mutation"
[ -f "$out/$name.mutmut-cache" ] || { echo "$name: no kept results in $out" >&2; exit 1; }
if [ -n "$(git status --porcelain -- python)" ]; then
  echo "$name: refused: python/ has uncommitted changes (mutmut edits files in place)" >&2
  exit 1
fi
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}" PYTHONDONTWRITEBYTECODE=1
export PX4PARAMS_CACHE_DIR="${PX4PARAMS_CACHE_DIR:-$(mktemp -d)}"
cp "$out/$name.mutmut-cache" .mutmut-cache
cp scripts/mutation_lines.py mutmut_config.py # mutmut's hooks (see the file)
lines="" rerun=()
if [ "${MUTATION_BY_LINE:-0}" = 1 ]; then
  lines="$out/$name.lines.json" rerun=(--rerun-all)
  [ -f "$lines" ] || { echo "$name: no traced run in $lines (scripts/mutation.sh makes it)" >&2; exit 1; }
fi
finish() {
  git checkout -- python 2>/dev/null || true
  find python -name '*.py.bak' -delete 2>/dev/null || true
  rm -f mutmut_config.py
  mv .mutmut-cache "$out/$name.mutmut-cache"
}
trap finish EXIT
trap 'exit 130' INT TERM
# what is not killed yet: the lines from FIRST_LINE on first, each group in mutmut's order
ids=${MUTATION_IDS:-}
[ -n "$ids" ] || ids=$(python3 - "$first" <<'EOF'
import sqlite3
import sys

first = int(sys.argv[1])
rows = sqlite3.connect(".mutmut-cache").execute(
    "SELECT Mutant.id, Line.line_number FROM Mutant JOIN Line ON Mutant.line = Line.id"
    " WHERE Mutant.status != 'ok_killed' ORDER BY Mutant.id"
).fetchall()
print(*[i for i, n in rows if n + 1 >= first], *[i for i, n in rows if n + 1 < first])
EOF
)
for id in $ids; do
  if [[ "$(date -u +%H:%M)" > "$deadline" ]]; then
    echo "$name: stopped at $deadline"
    break
  fi
  MUTATION_LINES="$lines" timeout --kill-after=30 600 mutmut run --paths-to-mutate "$paths" \
    --tests-dir tests --runner "bash scripts/mutation-pytest.sh -x -q -p no:cacheprovider $tests" \
    "${rerun[@]}" --simple-output --no-progress "$id" >>"$out/$name.log" 2>&1 || true
  git checkout -- python
done
