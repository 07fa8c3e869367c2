#!/usr/bin/env bash
# Builds the release artifacts into OUT (default dist/): the wheel and the sdist.
#   bash scripts/package.sh [--zig] [OUT]
# The wheel is abi3 (one wheel for CPython 3.11 and later) for x86_64 Linux. Built with this
# machine's toolchain (Debian 12, glibc 2.36) it is manylinux_2_34, the oldest tag maturin's
# auditwheel check allows: Rust's standard library links pthread_key_create and friends, which
# glibc 2.34 moved into libc (also statx 2.28, getrandom 2.25, gettid 2.30, stat64 2.33).
# --zig links with zig (the ziglang package, from PyPI into .venv) against glibc 2.17's symbols
# instead: manylinux_2_17 (manylinux2014), for older distributions.
# The release build reuses target/release of 'scripts/setup.sh' (maturin develop --release).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/maturin ] && export PATH="$PWD/.venv/bin:$PATH"

compat=(--compatibility manylinux_2_34)
if [ "${1:-}" = "--zig" ]; then
    shift
    python -m pip install --quiet --disable-pip-version-check "ziglang>=0.13,<0.18"
    compat=(--zig --compatibility manylinux_2_17)
fi
out=${1:-dist}

maturin build --release "${compat[@]}" --out "$out"
maturin sdist --out "$out"
