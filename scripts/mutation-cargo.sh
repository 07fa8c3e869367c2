#!/usr/bin/env bash
# cargo for cargo-mutants (scripts/mutation.sh's rust targets, which set CARGO to this script):
# each build of a mutant takes /tmp/px4params-build.lock for that build only, so a run of many
# mutants lets other builds in between. Tests run outside the lock (they build nothing: the
# build phase's `cargo test --no-run` built them), so that a wait for the lock is never counted
# in a mutant's test timeout. MUTATION_REAL_CARGO: the cargo to run (mutation.sh sets it).
set -euo pipefail
cargo=${MUTATION_REAL_CARGO:-cargo}
builds=0
case ${1:-} in build | check | rustc) builds=1 ;; esac
for arg in "$@"; do
  [ "$arg" = --no-run ] && builds=1
done
if [ "$builds" = 1 ] && [ -e /tmp/px4params-build.lock ]; then
  exec flock /tmp/px4params-build.lock nice "$cargo" "$@"
fi
exec nice "$cargo" "$@"
