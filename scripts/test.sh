#!/usr/bin/env bash
# Sets up px4params and runs every test and lint: cargo fmt/clippy/test, ruff, pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

echo "== rust: fmt, clippy, tests"
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --features px4params-core/alloc -- -D warnings
cargo test -p px4params-core --features alloc

echo "== python: ruff, pytest"
ruff check python tests benches
ruff format --check python tests benches
# The CLI tests run the installed command; keep their model cache inside the run.
export PX4PARAMS_CACHE_DIR="${PX4PARAMS_CACHE_DIR:-$(mktemp -d)}"
python3 -m pytest -q -p no:cacheprovider
