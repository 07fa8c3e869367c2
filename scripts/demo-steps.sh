#!/usr/bin/env bash
# The demo's commands (scripts/demo.sh sets up .venv first), run in the folder DIR with the
# px4params on PATH and nothing from the environment: the example files copied out, the talk's
# INA238 encoded, the example airframe run into a store and shown, the autostart plan, boots on
# a healthy bench and on one with faults (with a flight log, read back). DIR is kept.
#   bash scripts/demo-steps.sh DIR
set -euo pipefail
[ $# = 1 ] || { echo "usage: bash scripts/demo-steps.sh DIR" >&2; exit 2; }
# Only the files named on each command line: no store or other setting from the environment.
unset PX4PARAMS_STORE PX4PARAMS_PARAMETERS_JSON PX4PARAMS_DSDL_PATH PX4PARAMS_DRIVERS
mkdir -p "$1"
cd "$1"

step() { printf '\n== %s\n$ %s\n' "$1" "${*:2}"; "${@:2}"; }

step "the example files, copied out of the package" px4params examples
step "the talk's INA238, encoded with the DroneCAN rules" px4params demo
step "run the example airframe (the talk's five lines and more)" \
    px4params run examples/two_batteries.airframe --store vehicle.store
step "the store" px4params param --store vehicle.store show
step "the leaves of INA238#0" px4params param --store vehicle.store show -l INA238#0
step "the destructured MAVLink names" px4params param --store vehicle.store flat
step "the startup script's plan" px4params autostart plan --store vehicle.store
step "boot on a bench where every configured device is present: may arm" \
    px4params autostart run --store vehicle.store --duration 10
echo
echo "== boot on a bench with faults: arming refused, one line per device; a flight log of it"
echo "\$ px4params autostart run --store vehicle.store --bench examples/two_batteries_faults.bench.toml --duration 10 --ulog run.ulg"
if px4params autostart run --store vehicle.store --bench examples/two_batteries_faults.bench.toml \
    --duration 10 --ulog run.ulg; then
    echo "(unexpected: the faulty bench may arm)"; exit 1
fi
echo "(exit status 1: the vehicle may not arm)"
echo
echo "== the flight log read back: which device failed, and when"
echo "\$ px4params health run.ulg"
px4params health run.ulg | head -n 3 || true
echo
echo "The demo's files stay in $PWD (vehicle.store, run.ulg, examples/)."
