#!/usr/bin/env bash
# Sets up px4params in the checkout's own virtual environment, .venv (never the system
# interpreter): the Python dependencies, then the Rust extension built by maturin and the
# package installed editable. Run it again after pulling: only what changed is rebuilt.
#   bash scripts/setup.sh          what px4params needs to run ([project.dependencies]): the demo
#   bash scripts/setup.sh --test   and what the tests need: the test extras, MAVProxy, and
#                                  Debian's chromium, cbindgen and gcc-arm-none-eabi where apt-get can
#                                  install them, and Rust's thumbv7em-none-eabihf target
set -euo pipefail
cd "$(dirname "$0")/.."

with_tests=false
case "${1:-}" in
    --test) with_tests=true ;;
    "") ;;
    *) echo "usage: bash scripts/setup.sh [--test]" >&2; exit 2 ;;
esac

python=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    echo "== creating .venv with $("$python" --version)"
    "$python" -m venv .venv
fi
export VIRTUAL_ENV="$PWD/.venv"

echo "== build tools into .venv (pip: maturin, uv)"
# uv installs the package: its console script starts without importing `re` (pip's costs
# every px4params command about 8 ms).
.venv/bin/python -m pip install --quiet --disable-pip-version-check "maturin>=1.7,<2" "uv>=0.4,<1"

if [ -e target/release/.fingerprint ]; then
    echo "== building the Rust extension (maturin, release; incremental, usually seconds)"
else
    echo "== building the Rust extension (maturin, release): the first build takes about 2 minutes on 2 cores"
fi
if ! $with_tests; then
    .venv/bin/maturin develop --uv --release
    echo "== ready: 'source .venv/bin/activate' puts px4params on PATH (or run .venv/bin/px4params)"
    exit 0
fi
.venv/bin/maturin develop --uv --release --extras test

# MAVProxy, a ground station the tests drive: without its declared GUI dependencies (vtk,
# opencv, matplotlib: hundreds of MB it does not need to list and set parameters).
.venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps "mavproxy==1.8.75"

# The Cortex-M7 size test (tests/test_size.py) builds the core for PX4's FMUv5x/v6x: Rust's
# thumbv7em-none-eabihf target (about 30 MB, where rustup manages the toolchain) and
# Debian's gcc-arm-none-eabi below to link it; without either that test skips.
if command -v rustup >/dev/null 2>&1; then
    rustup target add thumbv7em-none-eabihf >/dev/null 2>&1 \
        || echo "(thumbv7em-none-eabihf could not be added: the Cortex-M7 size test will skip)"
fi

# Debian packages the tests use: Chromium for the page's browser tests (Playwright cannot
# download browsers here), cbindgen, which checks the C ABI's committed header, and
# gcc-arm-none-eabi (49 MB download) for the Cortex-M7 size test. Installed with apt where
# this runs as root on Debian; elsewhere those tests skip.
missing=()
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
command -v cbindgen >/dev/null 2>&1 || missing+=(cbindgen)
command -v arm-none-eabi-gcc >/dev/null 2>&1 || missing+=(gcc-arm-none-eabi)
if [ ${#missing[@]} -gt 0 ] && command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
    echo "== installing Debian's ${missing[*]} for the tests (apt-get, about a minute)"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null \
        || echo "(${missing[*]} could not be installed: the tests that need them will skip)"
fi

echo "== ready: 'source .venv/bin/activate' puts px4params on PATH (or run .venv/bin/px4params)"
