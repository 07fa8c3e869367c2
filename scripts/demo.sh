#!/usr/bin/env bash
# Sets up px4params in .venv with what it needs to run (not the test tools: see scripts/setup.sh)
# and runs the demo (scripts/demo-steps.sh) in the folder demo-run/ of the checkout, which stays.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$PWD/.venv/bin:$PATH"
rm -rf demo-run
bash scripts/demo-steps.sh demo-run
echo "px4params is installed in .venv: 'source .venv/bin/activate' puts it on PATH (or run"
echo ".venv/bin/px4params). 'bash scripts/test.sh' adds the test tools and runs every test."
