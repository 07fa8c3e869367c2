#!/usr/bin/env bash
# Sets up px4params and runs the demo on the bundled DSDL and the example airframe: the talk's
# INA238 encoded and decoded, the airframe run into a store, its parameters shown, the autostart
# plan, and the vehicle booted on a simulated bench with and without a missing device.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$PWD/.venv/bin:$PATH"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export PX4PARAMS_STORE="$work/vehicle.store"

step() { printf '\n== %s\n$ %s\n' "$1" "${*:2}"; "${@:2}"; }

step "the talk's INA238, encoded with the DroneCAN rules" px4params demo
step "run the example airframe (the talk's five lines and more)" \
    px4params run examples/two_batteries.airframe
step "the store" px4params param show
step "the leaves of INA238#0" px4params param show -l INA238#0
step "the destructured MAVLink names" px4params param flat
step "the startup script and the plan" px4params autostart plan
step "boot on a bench where everything is present: may arm" \
    px4params autostart run --bench examples/two_batteries.bench.toml --duration 10
echo
echo "== boot on a bench with faults: arming refused, one line per device; a flight log of it"
echo "\$ px4params autostart run --bench examples/two_batteries_faults.bench.toml --duration 10 --ulog run.ulg"
if px4params autostart run --bench examples/two_batteries_faults.bench.toml --duration 10 \
    --ulog "$work/run.ulg"; then
    echo "(unexpected: the faulty bench may arm)"; exit 1
fi
echo "(exit status 1: the vehicle may not arm)"
echo
echo "== the flight log read back: which device failed, and when"
echo "\$ px4params health run.ulg"
px4params health "$work/run.ulg" | head -n 3 || true
echo
echo "px4params is installed in .venv: 'source .venv/bin/activate' puts it on PATH (or run"
echo ".venv/bin/px4params). 'bash scripts/test.sh' runs every test."
