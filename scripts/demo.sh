#!/usr/bin/env bash
# Sets up px4params and runs the demo: the talk's INA238 example encoded, its leaves, decoded.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
px4params demo
