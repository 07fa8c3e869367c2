#!/usr/bin/env bash
# Installs everything px4params needs on a fresh machine of this kind (Rust toolchain and
# CPython 3.11 present): the package itself (built by maturin) with its test dependencies.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore \
    -e ".[test]"
