#!/usr/bin/env bash
# Sets up px4params and the test tools in .venv (scripts/setup.sh --test), then runs every test
# and lint: cargo fmt, clippy and tests; the wheel built and installed outside the checkout
# (tests/test_wheel.py); ruff; the import layers (lint-imports); the types (mypy, and stubtest of
# the compiled extension against its stub); pytest (which also runs the
# doctests and every command example of the README, docs/ and --help). Each step says how long
# the run has taken so far, and pytest lists its slowest tests (CI's budget: 15 minutes on 2
# cores; the long property runs are scripts/fuzz.sh's).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
export PATH="$PWD/.venv/bin:$PATH"

echo "== rust: fmt, clippy, tests (${SECONDS} s so far)"
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --features px4params-core/alloc -- -D warnings
cargo clippy -p px4params-core --features compact -- -D warnings
cargo test -p px4params-core --features alloc
# The firmware build's codec (without the fast paths for flat leaf lists): same bytes, same errors.
cargo test -p px4params-core --features alloc,compact
# The C ABI called from Rust as C calls it (its C programs run under pytest: tests/test_firmware.py).
cargo test -p px4params-ffi

echo "== the wheel and sdist (release build: reuses setup's), for tests/test_wheel.py (${SECONDS} s so far)"
dist=$(mktemp -d)
bash scripts/package.sh "$dist"
# tests/test_wheel.py installs it into a new venv outside the checkout and runs the smoke test
export PX4PARAMS_WHEEL="$(echo "$dist"/*.whl)"

echo "== python: ruff, import layers, types, pytest (${SECONDS} s so far)"
ruff check python tests benches
ruff format --check python tests benches
lint-imports
# The package's types (pyproject.toml's [tool.mypy]); then the built extension against
# _native.pyi (the allowlist holds only what stubtest cannot see, each with its reason).
mypy
python -m mypy.stubtest px4params._native --mypy-config-file pyproject.toml \
    --allowlist scripts/stubtest-allowlist.txt
# The CLI tests run the installed command; keep their model cache inside the run.
export PX4PARAMS_CACHE_DIR="${PX4PARAMS_CACHE_DIR:-$(mktemp -d)}"
# Two workers, each test file whole on one (its module fixtures, servers and browsers, start
# once): many tests wait on sockets and timeouts, which the other worker's tests fill. The real
# ground stations then run alone: their own resend timers (MAVSDK sends a PARAM_SET again when
# no answer comes in time, and took the late answer for the next request's) are not ours to
# stretch, and a loaded machine answers late.
python -m pytest -q -p no:cacheprovider -n 2 --dist loadfile --durations=15 \
    --ignore=tests/test_mavlink_clients.py
python -m pytest -q -p no:cacheprovider --durations=5 tests/test_mavlink_clients.py
echo "== all passed in ${SECONDS} s"
