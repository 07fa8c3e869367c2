#!/usr/bin/env bash
# The mutation run (scheduled with the long runs, not part of scripts/test.sh): small mistakes
# are planted in the code one at a time, and the tests that cover it are run against each; a
# mutant the tests let through is a blind spot (issue 40). Prints, per target, the mutants,
# killed (tests failed, or hung: a timeout), survived, and of those the ones listed as
# equivalent in scripts/mutation-equivalent.txt (a change no test can see, with the reason).
#
#   bash scripts/mutation.sh [TARGET ...]       default: every target below
#   MUTATION_BUDGET=600     seconds per target (default: the target's in BUDGETS below, else
#                           1800); what is left is "untested". MUTATION_BUDGET_session=600:
#                           one target's (its name with - as _)
#
# The figures of issue 40, module by module (the packages links/, gui/, migrate/, vehicle/,
# store/ have thousands of mutants: their targets do not finish in one budget on 2 shared
# cores), "before" without the tests written for the survivors, "after" with them:
#   MUTATION_BASELINE=1 bash scripts/mutation.sh session mavlink_ftp migrate-config   # before
#   bash scripts/mutation.sh session mavlink_ftp migrate-config                       # after
# Each target prints its line; the run ends with the table of each target's before and after.
# Rust, one file of the core at a time (cargo-mutants builds and tests a mutant in 3-12 s here;
# a run cut short by its budget goes on where it stopped with --iterate, which skips what was
# caught and tests again what survived):
#   MUTATION_BASELINE=1 MUTATION_RUST_TIMEOUT=20 bash scripts/mutation.sh rust-transfer   # before
#   MUTATION_RUST_TIMEOUT=20 MUTATION_RUST_ARGS=--iterate bash scripts/mutation.sh rust-transfer
# (the same for rust-scatter; of rust-store's 336 mutants one tenth was run, MUTATION_RUST_ARGS=
# "--shard 0/10"). transfer.rs's and scatter.rs's survivors after are all listed in
# scripts/mutation-equivalent.txt with the reason; the store sample's were all killed.
# mutmut 2.5.1 looks up kept results by a line's text: a mutant of a line that occurs twice in
# its file (two identical `raise` or `continue` lines) stayed "untested" in a run that started
# from earlier results. Every Python run is given scripts/mutation_lines.py as mutmut's
# mutmut_config.py, whose init() looks them up by line number too.
#   MUTATION_BASELINE=1     without the tests written for issue 40 (those marked issue40 in
#                           pyproject.toml and the files in NEW_TESTS below; Rust targets: the
#                           files in RUST_ISSUE40_TESTS): the "before" figures, in a
#                           cache of its own (a run cut short by its budget goes on where it
#                           stopped); the first full run after it starts from the baseline's
#                           results and tests again only its survivors and what it left
#   MUTATION_FRESH=1        forget the target's earlier results (kept in target/mutation)
#   MUTATION_REPORT_ONLY=1  test nothing: count the kept results again (with BASELINE=1, the
#                           baseline's), e.g. after scripts/mutation-equivalent.txt changed
#   MUTATION_BY_LINE=1      Python: run each mutant first with only those of the target's tests
#                           that execute its line (one traced run of them, kept in
#                           target/mutation/<target>.lines.json while the files and tests are
#                           the same: scripts/mutation_lines.py), and what they let through
#                           again with all of them (mutmut's --rerun-all): the verdicts of a
#                           plain run, sooner. The traced run counts in the target's budget.
#   MUTATION_RUST_FILES="crates/px4params-core/src/scalar.rs crates/px4params-core/src/bits.rs"
#                           rust-core: mutate only these files (cargo-mutants --file, paths
#                           from the repository root); default: the whole crate
#   MUTATION_RUST_TIMEOUT=120
#                           rust-core: seconds one mutant's tests may run before it counts as
#                           timed out (cargo-mutants --timeout; default 300)
#   MUTATION_RUST_ARGS="--re (int_raw|float_raw) --cargo-test-arg=--lib --cargo-test-arg=--test=codec"
#                           rust-core: more cargo-mutants options, last on its command line:
#                           --re to test chosen mutants only, --cargo-test-arg to run only the
#                           tests that cover them, --iterate to test again only what the last
#                           run did not catch (space-separated; no quoting inside)
#   The rust target's wall-clock budget is MUTATION_BUDGET too: at its end cargo-mutants is
#   interrupted and the mutants it finished are counted. Its builds are debug builds (a
#   mutant rebuilds the crate and its seven test programs; release's LTO links are the slow
#   part) with the alloc feature, one job, niced, each mutant's build (not the whole run) under
#   /tmp/px4params-build.lock when it exists (scripts/mutation-cargo.sh).
#
# Python: mutmut 2 (pip install "mutmut==2.5.1", the "mutation" extra), which mutates the
# files in place, one at a time, and restores them; so the work tree must be clean, and is
# restored with git if the run is cut short. Rust: cargo-mutants (cargo install
# cargo-mutants) over the core and the C ABI crate with their Rust tests (the C ABI's are
# crates/px4params-ffi/tests/c_abi.rs, calling its functions as C does). The survivors of each
# target are written to target/mutation/<target>.txt.
# While a run goes: do not edit this script (bash reads it as it runs, so the run's last table
# comes out wrong) and do not run `mutmut show` on a target's cache (once it rewrote the cache
# under the running mutmut, and results were lost).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
[ -d .venv ] && export PATH="$PWD/.venv/bin:$PATH"
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
export PYTHONDONTWRITEBYTECODE=1 # a mutant of the same size and second must not hit a stale .pyc
export PX4PARAMS_CACHE_DIR="${PX4PARAMS_CACHE_DIR:-$(mktemp -d)}"
BUDGET="${MUTATION_BUDGET:-1800}"
# Wall-clock seconds of each module target, enough for its whole module on 2 shared cores
# (measured: session 258 mutants ~45 min, mavlink_ftp 215 ~25 min, migrate-config 232 ~25 min).
# MUTATION_BUDGET, when set, is every target's; MUTATION_BUDGET_<target> (- as _) one's.
declare -A BUDGETS=([session]=3600 [mavlink_ftp]=2400 [migrate-config]=2400 [devid]=5400
  [admission]=7200)
BUDGETS+=([gui-admission]=2400 [gui-files]=1200 [dronecan_node]=5400) # mutlinks: 224, 110, 271 mutants
# vehicle/, store/, migrate/ module by module (issue 40, mutveh): measured on 2 shared cores.
BUDGETS+=([flight_log]=3600)
budget_for() {
  local var="MUTATION_BUDGET_${1//-/_}"
  echo "${!var:-${MUTATION_BUDGET:-${BUDGETS[$1]:-1800}}}"
}
OUT="${CARGO_TARGET_DIR:-$ROOT/target}/mutation"
mkdir -p "$OUT"
PY="python/px4params"
# The test files written to kill the survivors (issue 40): MUTATION_BASELINE=1 runs without them.
NEW_TESTS="test_session|test_migrate_config|test_mavlink_ftp"
NEW_TESTS="$NEW_TESTS|test_admission|test_dronecan_node" # links/ and gui/ (mutlinks)

# target | files to mutate (comma-separated) | pytest arguments (the tests that cover them)
# The small targets are those of issue 40's own run; the package targets are CI's long run.
TARGETS=(
  "can_transfer|$PY/links/can_transfer.py|tests/test_dronecan.py tests/test_can_transfer.py tests/test_fuzz.py -k '(receiver or frame or transfer or can_id or reassembl) and not cli'"
  "dronecan_params|$PY/links/dronecan_params.py|tests/test_dronecan.py tests/test_dronecan_params.py -k 'long_name or getset or refused or writing or boolean'"
  "health|$PY/vehicle/health.py,$PY/cli/commands/health.py|tests/test_flight_log.py tests/test_dronecan.py tests/test_health.py -k 'health or first_failure'"
  "links|$PY/links|tests/test_dronecan.py tests/test_can_transfer.py tests/test_mavlink.py tests/test_mavlink_clients.py tests/test_mavlink_metadata.py tests/test_dronecan_params.py"
  "gui|$PY/gui|tests/test_gui.py tests/test_gui_files.py tests/test_gui_page.py::test_a_websocket_from_a_foreign_origin_is_refused tests/test_gui_page.py::test_a_valid_then_invalid_entry_leaves_nothing_in_the_review"
  "migrate|$PY/migrate|tests/test_migrate.py tests/test_migrate_defects.py tests/test_migrate_corpus.py"
  "vehicle|$PY/vehicle|tests/test_autostart.py tests/test_simbench.py tests/test_devid.py tests/test_flight_log.py tests/test_health.py"
  "store|$PY/store|tests/test_store.py tests/test_storefile.py tests/test_flat.py tests/test_param_cli.py"
  # One module at a time, where a whole package does not finish in a budget: those that matter
  # most for "a broken sensor never silent, nothing lost", each with the fast tests that cover it
  # (the tests written for its survivors first: -x stops at the first that fails).
  "session|$PY/store/session.py|tests/test_session.py tests/test_session_write_path.py -k 'not cli and not dronecan and not over_mavlink and not disjoint and not mavlink_serve'"
  "migrate-config|$PY/migrate/config.py,$PY/migrate/proposal.py|tests/test_migrate_config.py tests/test_migrate.py tests/test_migrate_defects.py"
  "devid|$PY/vehicle/devid.py|tests/test_devid.py"
  "flight_log|$PY/vehicle/flight_log.py|tests/test_flight_log.py"
  "mavlink_ftp|$PY/links/mavlink_ftp.py|tests/test_mavlink_ftp.py tests/test_mavlink_metadata.py tests/test_mavlink_security.py -k 'ftp or open_read or naks or sessions_run or list_directory or crc32 or burst or slices or garbage'"
  "admission|$PY/gui/admission.py|tests/test_gui_security.py"
  # gui/ and links/ one module at a time (mutlinks), with their in-process tests only (a few
  # seconds a mutant): the tests that start the page's server or `dronecan serve` take 25-40 s
  # each on 2 shared cores (the target admission above runs the server's). Issue 40's figures:
  #   MUTATION_BASELINE=1 bash scripts/mutation.sh gui-admission gui-files dronecan_node
  #   bash scripts/mutation.sh gui-admission gui-files dronecan_node
  "gui-admission|$PY/gui/admission.py|tests/test_admission.py tests/test_gui_security.py::test_the_hosts_answered"
  "gui-files|$PY/gui/files.py|tests/test_gui_files.py"
  "dronecan_node|$PY/links/dronecan_node.py|tests/test_dronecan_node.py tests/test_fuzz.py::test_dronecan_node_answers_or_ignores"
  "rust-core|crates/px4params-core|"
  "rust-ffi|crates/px4params-ffi|"
  # One file of the core each, with cargo test options choosing the tests that reach it (none:
  # all of the crate's). Nothing in the core calls file.rs: only tests/file.rs reaches it.
  "rust-file|crates/px4params-core/src/file.rs|--test=file"
  # store.rs: its own tests, the leaf tables', the file's and the pages' (which go through it).
  "rust-store|crates/px4params-core/src/store.rs|--lib --test=mutants_store --test=store --test=store_alloc --test=table --test=file --test=pages --test=mutants_store_set_from"
  "rust-pages|crates/px4params-core/src/pages.rs|"
  "rust-crc|crates/px4params-core/src/crc.rs|"
  # The receive path: the unit tests in the file (--lib) and the test programs that read
  # values in pieces through it (codec, walk, pages; straight and store have one such test
  # each, left out: a mutant would build them for little).
  "rust-scatter|crates/px4params-core/src/scatter.rs|--lib --test=mutants_scatter --test=codec --test=walk --test=pages"
  "rust-transfer|crates/px4params-core/src/transfer.rs|--lib --test=mutants_transfer --test=codec"
)
# The Rust test files issue 40 added: MUTATION_BASELINE=1 leaves them out (the "before").
RUST_ISSUE40_TESTS="c_abi crc file pages mutants_transfer mutants_scatter mutants_store"
# links/ and gui/, the rest module by module (issue 40, mutnet), each with in-process tests only
# (a peer's bytes written by hand or by pymavlink/pydronecan, the ASGI app driven directly):
#   MUTATION_BASELINE=1 MUTATION_BUDGET_slcan=1200 bash scripts/mutation.sh slcan    # before
#   MUTATION_BUDGET_slcan=1200 bash scripts/mutation.sh slcan                        # after
TARGETS+=(
  "slcan|$PY/links/slcan.py|tests/test_slcan.py tests/test_dronecan.py tests/test_fuzz.py::test_slcan_adapter_takes_any_bytes -k 'slcan or serial_line'"
)
BUDGETS+=([slcan]=1200)
NEW_TESTS="$NEW_TESTS|test_slcan"
# links/mavlink.py: the server driven turn by turn in-process (tests/test_mavlink.py's
# TestTurnByTurn, marked issue40: the baseline runs the module's other fast tests only); its
# ~700 mutants do not finish in one budget here: a run goes on where the last one stopped.
TARGETS+=(
  "mavlink|$PY/links/mavlink.py|tests/test_mavlink.py -k 'TurnByTurn or bytewise or param_value_of or development_version or signalling_nan'"
)
BUDGETS+=([mavlink]=1800)
# gui/app.py: its routes and WebSocket over ASGI in-process (no test in-process reached it
# before: the page's server tests take 25-40 s a mutant, so there is no "before" run).
TARGETS+=("gui-app|$PY/gui/app.py|tests/test_app.py")
BUDGETS+=([gui-app]=1200)
NEW_TESTS="$NEW_TESTS|test_app"
# links/mavlink_signing.py: frames signed by hand (hashlib) and by pymavlink, in-process.
TARGETS+=(
  "mavlink_signing|$PY/links/mavlink_signing.py|tests/test_mavlink_signing.py tests/test_mavlink_security.py -k 'signing or key_files or timestamp_rules'"
)
BUDGETS+=([mavlink_signing]=900)
NEW_TESTS="$NEW_TESTS|test_mavlink_signing"
# links/dronecan_client.py: against a node played with pydronecan's transfers, in-process.
TARGETS+=(
  "dronecan_client|$PY/links/dronecan_client.py|tests/test_dronecan_client.py tests/test_dronecan.py::test_values_are_parsed_by_the_parameters_kind"
)
BUDGETS+=([dronecan_client]=900)
NEW_TESTS="$NEW_TESTS|test_dronecan_client"
# gui/vehicle.py: StoreVehicle, health lines and the page's state, in-process (MavlinkVehicle's
# lines are reached by the page's server tests only).
TARGETS+=("gui-vehicle|$PY/gui/vehicle.py|tests/test_gui_vehicle.py")
BUDGETS+=([gui-vehicle]=900)
NEW_TESTS="$NEW_TESTS|test_gui_vehicle"
# store/ and vehicle/autostart.py one module at a time (mutstore, issue 40), "nothing lost"
# first: the store file, the store, autostart. Each with
# its in-process tests only (a few seconds a mutant): test_storefile.py's saver killed mid-write
# runs subprocesses (20 s a mutant) and test_store.py's state machine 17 s, both left out here
# (the long runs' package targets keep them). Issue 40's figures:
#   MUTATION_BASELINE=1 bash scripts/mutation.sh store-file store-store autostart
#   bash scripts/mutation.sh store-file store-store autostart
# (migrate/build.py is not a target of its own: its tests take 22 s a mutant here.)
TARGETS+=(
  "store-file|$PY/store/file.py|tests/test_file.py tests/test_storefile.py -k 'not killing'"
  # store.py with test_store.py and test_spec.py's in-process tests (the store's range check:
  # issue 40's "before" of store-store was measured with test_store.py alone)
  "store-store|$PY/store/store.py|tests/test_store.py tests/test_spec.py -k 'not TestStoreMachine and not cli and not param_set and not force_says and not airframe and not params_file and not json_export and not mavlink and not dronecan and not page and not long_list'"
  "autostart|$PY/vehicle/autostart.py|tests/test_autostart.py"
)
BUDGETS+=([store-file]=1800 [store-store]=3600 [autostart]=1800)
NEW_TESTS="$NEW_TESTS|test_file" # store/ (mutstore; the others are marked issue40)
# The whole core, a sample spread over every file (issue 40, mutcore): round-robin sharding takes
# every 60th mutant of the crate's 3628 (61). The sample cannot go on with --iterate (which drops
# what was caught before sharding, so the shard is another sample): a run cut short by its budget
# goes on with --re, one exact pattern per mutant of the sample not yet tested.
#   MUTATION_BASELINE=1 MUTATION_BUDGET=1800 MUTATION_RUST_TIMEOUT=120 \
#     MUTATION_RUST_ARGS="--shard 0/60 --sharding round-robin" bash scripts/mutation.sh rust-core
#   MUTATION_BUDGET=1800 MUTATION_RUST_TIMEOUT=120 \
#     MUTATION_RUST_ARGS="--shard 0/60 --sharding round-robin" bash scripts/mutation.sh rust-core
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_leaf"
# vehicle/ and gui/, the modules not run before, one at a time (issue 40, mutveh, second round),
# each with its in-process tests only (no page server, no Chromium):
#   MUTATION_BASELINE=1 nice bash scripts/mutation.sh timeline console     # before
#   nice bash scripts/mutation.sh timeline console                         # after
# Measured (mutants, killed, survived of which equivalent, kill rate): console before 67, 55,
# 12 (4), 87.3%; after 67, 62, 4 (4), 100% (1 untested: a `continue` line that occurs twice,
# planted by hand: killed); timeline before 201, 63, 138 (34), 37.7%; after 201, 166, 35 (34),
# 99.4% (the survivor: the legend's swatches 10 px below their words, no test yet).
# drivers, boards, gui-manifest and the remainders of gui-vehicle, gui-app, autostart: not run.
TARGETS+=(
  "timeline|$PY/vehicle/timeline.py|tests/test_timeline.py tests/test_simbench.py -k 'timeline or svg'"
  "console|$PY/vehicle/console.py|tests/test_console.py tests/test_migrate_defects.py -k 'console or launcher or started or rotation or internal_bus'"
  "drivers|$PY/vehicle/drivers.py|tests/test_simbench.py tests/test_autostart.py"
  "boards|$PY/vehicle/boards.py|tests/test_boards.py"
  "gui-manifest|$PY/gui/manifest.py|tests/test_gui_manifest.py"
)
BUDGETS+=([timeline]=900 [console]=900 [drivers]=3600 [boards]=5400 [gui-manifest]=3600)
BUDGETS+=([gui-vehicle]=2400 [gui-app]=2400 [autostart]=3600) # the remainders, run afresh
NEW_TESTS="$NEW_TESTS|test_timeline|test_console"
# store/ and migrate/, the modules not run before (mutfiles, issue 40), "nothing lost" first:
# the .params/JSON files, each with its in-process tests only (main() called in the process,
# no subprocess, no server). Issue 40's figures:
#   MUTATION_BASELINE=1 nice bash scripts/mutation.sh store-paramfile store-classic   # before
#   nice bash scripts/mutation.sh store-paramfile store-classic                       # after
# (measured: paramfile 177 mutants, before 76.3%, after 175 killed, 2 untested (lines written
# twice, planted by hand: killed); classic 104, before 61.2%, after 103 killed + 1 equivalent.
# store-flat: 588 mutants; its before was a 360 s sample, MUTATION_BUDGET_store_flat=360: 18
# tested, 2 survivors, both killed by test_flat.py's issue40 tests when planted by hand.)
TARGETS+=(
  "store-paramfile|$PY/store/paramfile.py|tests/test_paramfile.py tests/test_param_cli.py tests/test_cli_bad_inputs.py tests/test_storefile.py -k '(paramfile or export or bad_parameter or unknown_names or import or destructured or (bad_input and (params or json)) or other_ground) and not killing'"
)
# the classic parameters' parameters.json and values (cache included)
TARGETS+=(
  "store-classic|$PY/store/classic.py|tests/test_classic.py tests/test_store.py tests/test_metadata.py tests/test_cli_bad_inputs.py -k '(test_classic or classic or parameters_json or refused_changes or SYS_AUTOSTART or BAT1) and not TestStoreMachine'"
)
# flat.py with test_flat.py's in-process tests (its Hypothesis round trip through the store
# left out: 9 s a mutant); migrate/build.py with the migration's in-process tests (the CLI's
# subprocess tests left out: 3-5 s a mutant now, not the 22 s of the tests with subprocesses).
# Neither finishes in one budget here (~500 and ~600 mutants): a run goes on where it stopped.
TARGETS+=(
  "store-flat|$PY/store/flat.py|tests/test_flat.py -k 'not round_trip_through_the_store'"
  "migrate-build|$PY/migrate/build.py|tests/test_migrate.py tests/test_migrate_defects.py tests/test_migrate_config.py -k 'not cli and not needs_no_checkout'"
  # the smaller modules of store/, with their in-process tests (not run yet: no figures)
  "store-spec|$PY/store/spec.py|tests/test_spec.py -k 'not pydronecan and not page_api and not mavlink'"
  "store-long_names|$PY/store/long_names.py|tests/test_dronecan.py tests/test_flat.py tests/test_flat_on_demand.py -k long_name"
  "store-key|$PY/store/key.py|tests/test_key.py"
)
BUDGETS+=([store-paramfile]=1800 [store-classic]=1200 [store-flat]=3600 [migrate-build]=3600)
BUDGETS+=([store-spec]=1800 [store-long_names]=1200 [store-key]=1200)
NEW_TESTS="$NEW_TESTS|test_paramfile|test_classic"
# Rust, issue 40 (mutrust): every run at most 600 s (MUTATION_BUDGET=600), going on in the next
# (--iterate for a file target; the rust-core sample with --re, one pattern per mutant it has
# not tested yet). Each mutant's build takes the build lock on its own (scripts/mutation-cargo.sh).
#   MUTATION_BUDGET=600 MUTATION_RUST_TIMEOUT=60 bash scripts/mutation.sh rust-ffi
#   MUTATION_BUDGET=600 MUTATION_RUST_TIMEOUT=20 MUTATION_RUST_ARGS=--iterate \
#     bash scripts/mutation.sh rust-scatter
#   MUTATION_BASELINE=1 MUTATION_BUDGET=600 MUTATION_RUST_TIMEOUT=20 \
#     MUTATION_RUST_ARGS="--shard 1/10" bash scripts/mutation.sh rust-store          # before
#   MUTATION_BUDGET=600 MUTATION_RUST_TIMEOUT=20 MUTATION_RUST_ARGS="--shard 1/10" \
#     bash scripts/mutation.sh rust-store                                             # after
# The rust-core sample goes on with one --re per mutant not yet tested, each an exact regex of
# its name as --list prints it (re.escape, spaces as \s: the options are split on spaces) and
# --file for their files; cargo-mutants 27.1.0 keeps "delete field" mutants of those files
# whatever --re/--exclude-re say (counted apart: not in the sample). --baseline skip after the
# first run saves the unmutated build.
# The nesting bound (MAX_DEPTH) of the walk and of the leaf table: mutants_walk, mutants_table;
# Store::set_from's saturate flag: mutants_store_set_from (rust-core runs it; add
# --test=mutants_store_set_from to rust-store's tests to count it there).
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_walk mutants_table mutants_store_set_from"
# Measured 2026-11-26 (after, 5 runs of 600 s): rust-core sample 61 mutants, 56 tested, 50
# caught, 6 missed (all in scripts/mutation-equivalent.txt), 2 unviable, 3 untested (store.rs);
# rust-ffi 77 mutants, 70 caught, 7 unviable (one run, 2.5 min).

# links/ module by module (issue 40, mutlinks): mavlink.py's target again (this entry replaces
# the one above: the last entry of a name wins), mavlink_messages.py, identity.py, serving.py,
# each with in-process tests only (the server driven turn by turn, pymavlink building and
# parsing the frames; threads, no subprocesses), -x stopping at the first test that fails.
# (A test named by node ID must not be in a NEW_TESTS file: the baseline strips the file's name.)
#   MUTATION_BASELINE=1 nice bash scripts/mutation.sh mavlink mavlink_messages identity serving
#   nice bash scripts/mutation.sh mavlink mavlink_messages identity serving
# mavlink.py's ~550 mutants take 2-11 s each here: a run cut short by its budget goes on where
# it stopped (MUTATION_BUDGET_mavlink=5400 for the rest).
# Measured (2 shared cores, load 6): before/after tested 109/67 of mavlink's 544 (kill rate
# 40.4%/98.4%), mavlink_messages 95/73 of 102 (56.9%/97.7%), identity 23/23 (52.4%/100%),
# serving 13/13 (25.0%/100%), equivalents left out of the rates.
TARGETS+=(
  "mavlink|$PY/links/mavlink.py|tests/test_mavlink.py -k 'TurnByTurn or bytewise or param_value_of or development_version or signalling_nan'"
  "mavlink_messages|$PY/links/mavlink_messages.py|tests/test_mavlink_messages.py tests/test_mavlink_metadata.py::test_every_command_long_is_answered"
  "identity|$PY/links/identity.py|tests/test_identity.py tests/test_mavlink.py::test_autopilot_version_and_heartbeat"
  "serving|$PY/links/serving.py|tests/test_serving.py tests/test_mavlink.py::test_list_read_set"
)
BUDGETS+=([mavlink]=3600 [mavlink_messages]=900 [identity]=600 [serving]=600)
NEW_TESTS="$NEW_TESTS|test_mavlink_messages|test_identity|test_serving"

# vehicle/ and gui/ (issue 40, mutveh, third round): gui/manifest.py with its in-process tests
# (/api/manifest driven over ASGI, no server, no browser); the tests written for its survivors
# are marked issue40 in tests/test_gui_manifest.py. Issue 40's figures:
#   MUTATION_BASELINE=1 nice bash scripts/mutation.sh gui-manifest    # before
#   nice bash scripts/mutation.sh gui-manifest                        # after
# Measured (2 shared cores, load 4-8): before 308 mutants, 200 killed, 108 survived, 64.9%
# (22 min); after 305 tested, 298 killed, 7 survived (all 7 equivalent), 100%; 3 untested: the
# `continue` lines that occur three times (mutmut 2's line-text lookup), each planted by hand
# as `break`: killed. timeline's last survivor (the legend's swatches 10 px below their words)
# is killed by test_timeline.py's test_timeline_legend_swatch_sits_on_the_row_of_its_words:
# timeline after, run afresh (13 min): 201 mutants, 201 tested, 167 killed, 34 survived (all 34
# equivalent), 100%.
# drivers, boards and the remainders of gui-vehicle, gui-app, autostart: not run yet.
# store/key.py, store/long_names.py, store/spec.py (mutstore, issue 40, second round): these
# entries replace the ones above. key.py's parser is held to the name expression by
# test_store.py's tests of names (test_key.py alone reached it only through the store), and the
# long names' tests written for issue 40 are tests/test_long_names.py. Issue 40's figures:
#   MUTATION_BASELINE=1 nice bash scripts/mutation.sh store-key store-long_names
#   nice bash scripts/mutation.sh store-key store-long_names
# Measured (2 shared cores, load ~6; equivalents left out of the rates): store-key 188 mutants,
# before 185 tested, 31 survived (10 equivalent), 88.0%; after 188 tested, 12 survived (10
# equivalent), 98.9%: the two left are `len(instance) > 6` and `len(index) > 11`, which only a
# number with leading zeros tells apart (INA238#000001): whether such a name is exact is open
# (INA238#01 is taken as INA238#1). store-long_names 138, before 115 tested (23 left by the
# budget), 42 survived (12 equivalent), 70.9%; after 136 tested, 14 survived (all equivalent),
# 100%; the 2 untested are lines written twice (`@property`, `parts = self._parts[...]`),
# planted by hand: killed. store-spec (416 mutants): not run yet.
# store.py's known survivors (store-store): `tao=True` in the leaf check's get_leaf and
# `if saturate:` for `if not saturate:` are killed by test_store.py's
# test_a_saturated_leaf_write_is_held_to_its_range_as_stored (planted by hand); `stored = None`
# by test_key.py's test_a_write_by_path_looks_its_leaf_up_once (not among store-store's tests).
TARGETS+=(
  "store-key|$PY/store/key.py|tests/test_key.py tests/test_store.py -k 'test_key or names_are_split or parsed_once or inexact_name or under_an_inexact or destructured_name_is_exact or naming_errors or not_text'"
  "store-long_names|$PY/store/long_names.py|tests/test_long_names.py tests/test_dronecan.py tests/test_flat.py tests/test_flat_on_demand.py -k 'long_name or test_long_names'"
)
NEW_TESTS="$NEW_TESTS|test_long_names"
BUDGETS+=([store-long_names]=2400) # 1200 s left 23 of 138 untested at load 6
# store/spec.py (mutstore2, issue 40, third round): this entry replaces the one above. Its
# in-process tests only: the CLI tests of test_spec.py start 36 subprocesses (9 s a mutant
# against 3 s). Figures and commands: the mutstore2 block at the end of this script.
TARGETS+=(
  "store-spec|$PY/store/spec.py|tests/test_spec.py -k 'not pydronecan and not page_api and not mavlink and not param_set and not force_says and not airframe and not params_file and not json_export'"
)

# Rust, issue 40 (mutrust, second round; its figures at the end of this script): these
# entries replace the ones above. pages.rs and crc.rs with the test programs that reach them
# (all of the crate's would rebuild twenty test programs per mutant): pages.rs through its
# own tests, the store's pages test and the scattered reads; crc.rs through the transfers (the
# CRC of a multi-frame transfer) and the store file's CRCs.
TARGETS+=(
  "rust-pages|crates/px4params-core/src/pages.rs|--lib --test=pages --test=store --test=codec"
  "rust-crc|crates/px4params-core/src/crc.rs|--lib --test=crc --test=transfer --test=mutants_transfer --test=file"
  # store.rs: as above, and the tests written for its shards' survivors (the leaf tables'
  # slot count; set_translated)
  "rust-store|crates/px4params-core/src/store.rs|--lib --test=mutants_store --test=store --test=store_alloc --test=table --test=file --test=pages --test=mutants_store_set_from --test=mutants_store_tables --test=mutants_store_translated"
)
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_store_tables mutants_store_translated"

# Rust, issue 40 (mutrust2, third round): firmware's code. A firmware build (feature `compact`:
# plan.rs's NoPlans) runs code a host build never reaches: crc.rs's CRC-16 half a byte at a
# time (crc16's and crc16_pieces' `SLICES == 0` branches, crc16_nibble, the nibble table,
# crc16_shifted that fills it) and store.rs's set_leaf_copied (set_leaf_at without leaf
# tables) and the `!Active::TABLES` turns into it. These targets build every test program with
# --features=compact as well as the target's alloc (the option goes to every cargo command);
# the mutants are those of that code only (one --re each, by line as of this commit, or by
# function), so that the host's code, dead in this build, is not counted again:
#   MUTATION_BUDGET=1200 MUTATION_RUST_TIMEOUT=60 MUTATION_RUST_ARGS="--re crc.rs:(7[3-6]|11[01]|12[7-9]|13[0-2]|16[7-9]|17[6-9]|18[0-3]):" \
#     bash scripts/mutation.sh rust-compact-crc
#   MUTATION_BUDGET=1200 MUTATION_RUST_TIMEOUT=60 MUTATION_RUST_ARGS="--re set_leaf_copied --re delete\s!\sin\sStore<D,\sS,\sB,\sT>::read$ --re store.rs:749:12:" \
#     bash scripts/mutation.sh rust-compact-store
# (cargo-mutants 27.1.0 adds the file's "delete field" mutants whatever --re says.)
TARGETS+=(
  "rust-compact-crc|crates/px4params-core/src/crc.rs|--features=compact --lib --test=crc --test=transfer --test=mutants_transfer --test=file"
  "rust-compact-store|crates/px4params-core/src/store.rs|--features=compact --test=store --test=mutants_store --test=table --test=mutants_store_tables --test=mutants_store_set_from --test=mutants_store_saturate"
)
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_store_saturate"
# file.rs (this entry replaces the one above): its tests and those written for its survivors.
TARGETS+=("rust-file|crates/px4params-core/src/file.rs|--test=file --test=mutants_file")
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_file"
# Measured 2026-11-27 (mutrust2; 2 shared cores, load 10-15, every build behind other helpers'
# under the build lock; equivalents left out of the rates; each run MUTATION_RUST_TIMEOUT=60
# CARGO_PROFILE_DEV_DEBUG=0; a second run at a time with CARGO_TARGET_DIR=target/lane2):
#   MUTATION_BASELINE=1 MUTATION_BUDGET=2400 bash scripts/mutation.sh rust-pages       # before
#   MUTATION_BUDGET=2400 bash scripts/mutation.sh rust-pages                           # after
#   (each cut by its budget 3 short: the rest with MUTATION_RUST_ARGS=--iterate after, and
#   MUTATION_RUST_ARGS="--re pages.rs:139:" before)
#   MUTATION_BUDGET=2400 MUTATION_RUST_ARGS="--shard 0/2" bash scripts/mutation.sh rust-file
#   CARGO_TARGET_DIR=target/lane2 MUTATION_BUDGET=2400 MUTATION_RUST_ARGS="--shard 1/2" \
#     bash scripts/mutation.sh rust-file                                               # after
#   and rust-compact-store, rust-compact-crc as above (MUTATION_BUDGET 2400, 800).
#   target              run     mutants tested killed timeout survived(equiv.) unviable untested rate
#   rust-pages          before  64      59     52     0       7(0)             5        0        88.1%
#   rust-pages          after   64      59     59     0       0                5        0        100%
#   rust-file           after   231     203    195    2       6(5)             28       0        99.5%
#   rust-compact-store  after   13      13     9      0       4(3)             0        0        90.0%
#   rust-compact-crc    after   39      34     32     0       2(2)             5        0        100%
# rust-file has no "before": its baseline runs the lib's tests alone, and nothing in the lib
# calls file.rs (tests/file.rs, issue 40's, is its only caller): every viable mutant would
# survive. Its one survivor not equivalent, 362:14 (take refusing exactly the bytes left: an
# unknown kind or a bad table line in the last bytes before the trailer named as "past the
# end"), is killed by tests/mutants_file.rs (planted by hand: 2 tests red, tests/file.rs
# green; the earlier entry calling it equivalent is removed); rust-file runs it now: with it,
# MUTATION_RUST_ARGS="--re file.rs:362:14:" killed that line's 3 mutants (after: 100%).
# rust-compact-store: the four set_leaf_copied mutants listed above as "unreached" are killed
# in this build (its saturate field by tests/mutants_store_saturate.rs only: planted by hand
# under --features compact, red, the target's other tests green); set_from's saturate field
# (877:39) by mutants_store_set_from (planted by hand: red), which the target runs now (the
# run above was without it); the other three equivalent. rust-compact-crc's two survivors
# are equivalent in this build (crc16_pieces' turn, crc16_shifted's or in the nibble table). Not run in this round: rust-crc (host; 179 mutants), rust-store's
# untested shards 2-6 (~124), rust-ffi (its figures of 2026-11-26 above; no "before").
# gui/app.py, gui/vehicle.py and vehicle/drivers.py's survivors (issue 40, mutveh3). The
# earlier tests of test_app.py and test_gui_vehicle.py are the "before" (the tests written for
# this round's survivors are marked issue40): the files leave NEW_TESTS, else the baseline
# would strip every test file of these targets (and pytest, given none, run the whole suite).
# Figures and commands: the mutveh3 block at the end of this script.
NEW_TESTS=$(echo "$NEW_TESTS" | tr '|' '\n' | grep -vxE 'test_(app|gui_vehicle)' | paste -sd'|')
# drivers.py: tests/test_drivers.py (each key, each refusal whole, the lookups) first.
TARGETS+=(
  "drivers|$PY/vehicle/drivers.py|tests/test_drivers.py tests/test_simbench.py tests/test_autostart.py"
)
NEW_TESTS="$NEW_TESTS|test_drivers"
# store/spec.py, store/flat.py, migrate/build.py (mutstore3, issue 40, fourth round).
# migrate/build.py's tables of PX4 facts are held by tests/test_migrate_build.py (first: -x stops
# at the first test that fails); the baseline leaves it out. This entry replaces the one above.
TARGETS+=(
  "migrate-build|$PY/migrate/build.py|tests/test_migrate_build.py tests/test_migrate.py tests/test_migrate_defects.py tests/test_migrate_config.py -k 'not cli and not needs_no_checkout'"
)
NEW_TESTS="$NEW_TESTS|test_migrate_build"
# Runs (2 shared cores, load 9-16; each in a clone of its own, the kept results copied into
# target/mutation, where the next run of a target goes on from them):
#   MUTATION_BUDGET_store_spec=2400 nice bash scripts/mutation.sh store-spec   # then 3000 more
#   MUTATION_BUDGET_store_flat=4200 nice bash scripts/mutation.sh store-flat   # stopped at 55 min
#   MUTATION_BASELINE=1 MUTATION_BUDGET_migrate_build=2400 nice bash scripts/mutation.sh migrate-build
#   MUTATION_BUDGET_migrate_build=2750 nice bash scripts/mutation.sh migrate-build
#   MUTATION_REPORT_ONLY=1 bash scripts/mutation.sh store-spec store-flat migrate-build  # recount
# Measured 2026-11-27 (equivalents left out of the rates):
#   store-spec     before (mutstore2's; its results were lost): 416, 207 tested, 91 killed,
#                  116 survived (19 equivalent), 209 untested, 48.4%
#                  after: 416, 237 tested, 218 killed, 19 survived (all 19 equivalent), 179
#                  untested, 100% (RPMCommand's naming: test_spec.py's upper-snake cases)
#   store-flat     before: mutstore2's 360 s sample only (18 tested, 2 survived)
#                  after (afresh, 55 min): 588, 95 tested, 90 killed, 2 timed out, 3 survived
#                  (all 3 equivalent), 493 untested, 100%; a second run with the later tests
#                  spent its 27 min testing the first's timeouts again (each up to 10 times the
#                  suite's time), and was not kept
#   migrate-build  before: 670, 96 tested, 62 killed, 34 survived (7 equivalent), 574 untested,
#                  69.7%; after: 670, 180 tested, 146 killed, 34 survived (15 equivalent), 490
#                  untested, 88.5%. Of its 19 others, 12 are killed by tests/test_migrate_build.py's
#                  tests written after the run (each planted by hand: red); of the last 7,
#                  planted by hand, 6 are killed by tests/test_migrate_corpus.py (real logs and
#                  .params in ../shared/data; not among this target's tests: slow under load):
#                  line 194's suffix pattern, board_device's lines 226, 233, 234 (2); the last,
#                  229's "external_i2c_buses" (a board row's -X without -b), by
#                  test_a_row_without_a_bus_starts_on_the_external_buses_only (planted: red).
# store-flat's known survivors (union tag width, signed p_version, empty arrays) lie past line
# 240, which this round's runs did not reach: killed by test_flat.py's tests (planted by hand)
# or listed equivalent (pydsdl refuses arrays of capacity 0).

# gui/vehicle.py's MAVLink client (issue 40, mutveh4, sixth round): the 198 mutants mutveh3's
# round left untested (179 on lines 319-496) and every survivor again. The kept results had
# been tested against an older tests directory, so this round's first run tested all 211 not
# killed. Each goes on from the kept results (target/mutation/gui-vehicle.mutmut-cache):
#   bash scripts/mutation-by-id.sh gui-vehicle python/px4params/gui/vehicle.py \
#     tests/test_gui_vehicle.py 197 11:05    # before: test_gui_vehicle.py as it was (5a6d6e3)
#   MUTATION_BUDGET_gui_vehicle=5400 nice bash scripts/mutation.sh gui-vehicle          # after
#   MUTATION_REPORT_ONLY=1 bash scripts/mutation.sh gui-vehicle
# Here each ran in three lanes at once (three clones of the work tree, each `mutmut run ID` over
# its share of the IDs with the target's whole test command, the three caches merged by
# mutant): a surviving mutant took 60-80 s at load 10-12, too slow for one lane. The baseline
# mutmut measured (116 s: a cold PX4PARAMS_CACHE_DIR under load) was set to 45 s in the caches,
# as its timeout is ten baselines (a hanging mutant would have held a lane 19 minutes). "After"
# tested the before's survivors and timeout and the new mutants of the lines this round changed
# (7 mutants gone with their lines, 11 new), registered as mutation.sh's full run registers them.
# Measured 2026-11-27 (2 shared cores, load 9-12; equivalents left out of the rates):
#   target       run     mutants tested killed timeout survived equivalent untested kill rate
#   gui-vehicle  before      377    377    306       1       70         57        0     95.9%
#   gui-vehicle  after       381    381    322       0       59         59        0    100.0%
# The before's 13 other survivors, each killed by a test of test_gui_vehicle.py written for it
# (each planted by hand: red): metadata's `continue` -> `break` on a quiet 0.5 s by
# test_a_vehicle_slow_to_answer_the_metadata_request_is_waited_for; the receive loop's except
# `continue` -> `break` by test_a_failed_read_of_the_socket_does_not_deafen_the_page; the write's
# read-back (`read = None`, `read is None`) by test_a_float_write_answers_the_value_the_vehicle_
# reads_back; the read's wait `and` -> `or` by test_a_read_nobody_answers_is_none_and_never_hangs;
# _mftp_path's lstrip("XX/XX") by test_an_mftp_uri_is_read_as_its_path's new case; refresh's
# `quiet = None` after a re-ask by test_a_list_never_answered_is_asked_again_until_the_timeout;
# refresh's first `quiet = None` and `have == seen` by test_a_list_request_nobody_answers_is_sent_
# again; the re-ask line's four went with the line (rewritten by the fix below): of its three
# new mutants `+ quiet` is killed by test_a_list_still_arriving_is_not_asked_for_again, `>=` and
# `> 1.5` are equivalent. The write nobody answers is now bounded by its test (its wait's `and`
# -> `or`, the before's timeout, fails within 30 s instead of hanging the run). The new lines'
# 8 other mutants (write hearing its STATUSTEXT) are killed. After: none untested, and every
# survivor listed equivalent in scripts/mutation-equivalent.txt.
# Two bugs fixed in gui/vehicle.py with their tests (red before the fix): a lost first
# PARAM_REQUEST_LIST was never sent again (refresh re-asked only once a value had come: the page
# stayed empty until its timeout), and once the page held its 200 STATUSTEXT lines (minutes of
# health reports) every refused write said "the vehicle kept N" instead of the vehicle's reason
# (write looked for it past len(self.messages), which stays 200).
# migrate/build.py's untested part (mutmig4, issue 40, fifth round): the run goes on from the kept
# results of the round before (180 tested), in a clone of its own; tests/test_migrate_build.py's
# tests written meanwhile (each planted by hand: red) are counted by the next run:
#   cp /tmp/saved-mut/migrate-build*.mutmut-cache target/mutation/   # the kept results
#   MUTATION_BUDGET_migrate_build=5400 nice bash scripts/mutation.sh migrate-build   # before
#   MUTATION_BUDGET_migrate_build=2640 nice bash scripts/mutation.sh migrate-build   # after
#   MUTATION_BUDGET_migrate_build=1500 nice bash scripts/mutation.sh migrate-build   # after, 2
#   bash scripts/mutation-by-id.sh ...  # the lines written twice: `mutmut run ID` for each
#   MUTATION_REPORT_ONLY=1 bash scripts/mutation.sh migrate-build                  # the count
# mutmut 2 stops a mutant's tests after 10 times the suite's time it measured unmutated (kept in
# the cache while the tests are unchanged): measured at a quiet moment (3.4 s), the survivors'
# whole-suite runs timed out at load 9-12 and counted as caught. Before each run the kept
# cache's baseline_time_elapsed was set to 8-12 s (and hash_of_tests to the tests' own, so that
# it is used): sqlite3 target/mutation/migrate-build.mutmut-cache "UPDATE MiscData SET
# value='10.0' WHERE key='baseline_time_elapsed'"; the 3 timeouts of the first minutes of the
# before run (survivors listed equivalent) were marked untested again and tested.
# Measured 2026-11-27 (2 shared cores, load 9-12; equivalents left out of the rates):
#   migrate-build  before: 670, 651 tested, 564 killed, 0 timed out, 87 survived (15
#                  equivalent), 19 untested, 88.7%
#                  after: 670, 670 tested, 634 killed, 0 timed out, 36 survived (34
#                  equivalent), 0 untested, 99.7%
# The untested of the full runs were the lines written twice (14 `continue`, `options =
# UNMAPPED_OPTIONS.get(...)`, `chips = _chips(dev)`, `return True`, `where = (`, UNMAPPED_OPTIONS'
# closing `}`), whose kept result mutmut 2 looks up by the line's text: `mutmut run ID` each
# (as scripts/mutation-by-id.sh does) killed all 19 (each also planted by hand: red). Mutant
# 670 is of an older text of line 358: `mutmut apply 670` changes nothing (listed equivalent).
# Two survivors are not equivalent and have no test: line 536's `split("/")` and 537's "BARO" in
# the devtype's kind tell a barometer apart only for PX4 1.13's devtype 0x4C (SDP33 and LPS33HW
# share it): an SDP33 on differential_pressure is then left out as "a barometer", where both
# mutants propose it as SDP3X#0, which looks right; a test of today's answer would hold a
# defect in place (left to migrate/build.py's owner).
# Fixed after the run (migfix): the slot's sensor kind picks the chip of a shared devtype
# (test_a_devtype_two_chips_share_is_the_chip_of_the_slots_sensor_kind), so those two lines are
# gone; the new lines' mutants (_named, _chips, _MODULE_SUFFIX, the rename in board rows, the
# disabled slots' count) were run after it (the lead, from mutmig4's kept results; 30 min budget):
#   MUTATION_BUDGET_migrate_build=1800 nice bash scripts/mutation.sh migrate-build
#   migrate-build  after the fix: 687, 686 tested, 650 killed, 0 timed out, 36 survived (all 36
#                  equivalent: the fix's 7 listed with reasons), 1 untested (a line written
#                  twice, by mutmut 2's lookup by text), 100%
# mutrust3 (issue 40): scalar.rs and error.rs targets; figures in the block below.
# scalar.rs and error.rs on their own (the runs above were rust-core with MUTATION_RUST_FILES
# and these tests in MUTATION_RUST_ARGS; these targets run the same, and leave the issue-40
# files out of a baseline): the programs that reach them, not all twenty of the crate's.
TARGETS+=(
  "rust-error|crates/px4params-core/src/error.rs|--lib --test=codec --test=walk --test=mutants_walk --test=store --test=mutants_store --test=file"
  "rust-scalar|crates/px4params-core/src/scalar.rs|--lib --test=scalar --test=mutants_scalar --test=mutants_store_saturate --test=codec --test=walk --test=mutants_walk --test=store --test=mutants_store --test=file"
)
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_scalar"

# Rust, issue 40 (mutrust3, fourth round): rust-store's shards 2-6 of 10 run whole (with the
# earlier rounds' shards 0, 1, 7, 8, 9 every shard of store.rs is now run), rust-ffi's "before",
# and a first run of scalar.rs and error.rs (rust-core). A shard's results replace the last
# run's in target/mutation/<target>/: each was copied aside before the next. Two runs at a time,
# the second with CARGO_TARGET_DIR=target/lane2 (its own target directory and results); every
# run CARGO_PROFILE_DEV_DEBUG=0, each mutant's build under the build lock:
#   MUTATION_BASELINE=1 MUTATION_BUDGET=1500 MUTATION_RUST_TIMEOUT=60 \
#     MUTATION_RUST_ARGS="--shard 2/10" bash scripts/mutation.sh rust-store            # before
#   MUTATION_BUDGET=1500 MUTATION_RUST_TIMEOUT=60 MUTATION_RUST_ARGS="--shard 2/10" \
#     bash scripts/mutation.sh rust-store                                               # after
#   (and the same for shards 3, 4, 5, 6)
#   MUTATION_BASELINE=1 MUTATION_BUDGET=1800 MUTATION_RUST_TIMEOUT=60 bash scripts/mutation.sh rust-ffi
#   MUTATION_BUDGET=1800 MUTATION_RUST_TIMEOUT=60 bash scripts/mutation.sh rust-ffi
#   MUTATION_RUST_FILES=crates/px4params-core/src/error.rs MUTATION_BUDGET=2400 MUTATION_RUST_TIMEOUT=60 \
#     MUTATION_RUST_ARGS="--shard 0/2 --cargo-arg=--lib --cargo-arg=--test=codec --cargo-arg=--test=walk --cargo-arg=--test=mutants_walk --cargo-arg=--test=store --cargo-arg=--test=mutants_store --cargo-arg=--test=file" \
#     bash scripts/mutation.sh rust-core                                                # and --shard 1/2
#   MUTATION_RUST_FILES=crates/px4params-core/src/scalar.rs MUTATION_BUDGET=2400 MUTATION_RUST_TIMEOUT=60 \
#     MUTATION_RUST_ARGS="--shard 0/6 --cargo-arg=--test=scalar --cargo-arg=--test=mutants_store_saturate --cargo-arg=--lib --cargo-arg=--test=codec --cargo-arg=--test=walk --cargo-arg=--test=mutants_walk --cargo-arg=--test=store --cargo-arg=--test=mutants_store --cargo-arg=--test=file" \
#     bash scripts/mutation.sh rust-core                                                # and shards 1/6 .. 5/6
# Measured 2026-11-27 (2 shared cores, load 9-12, the build lock shared with other helpers'
# builds; equivalents left out of the rates):
#   target             run     mutants tested caught timeout missed(equiv.) unviable untested rate
#   rust-store s2      before  34      23     18     0       5(0)           11       0        78.3%
#   rust-store s2      after   34      23     23     0       0              11       0        100%
#   rust-store s3      before  34      28     17     0       11(10)         6        0        94.4%
#   rust-store s3      after   34      28     18     0       10(10)         6        0        100%
#   rust-store s4      before  34      33     14     0       19(3)          1        0        46.7%
#   rust-store s4      after   34      33     30     0       3(3)           1        0        100%
#   rust-store s5      before  34      33     24     0       9(8)           1        0        96.0%
#   rust-store s5      after   34      33     24     0       9(8)           1        0        96.0%
#   rust-store s6      before  34      23     23     0       0              11       0        100%
#   rust-store s6      after   34      23     23     0       0              11       0        100%
#   rust-store s2-6    before  170     140    96     0       44(21)         30       0        80.7%
#   rust-store s2-6    after   170     140    118    0       22(21)         30       0        99.2%
#   rust-store s2-6    after+  170     140    119    0       21(21)         30       0        100%
#   rust-ffi           before  77      70     0      0       70(0)          7        0        0%
#   rust-ffi           after   77      70     70     0       0              7        0        100%
#   rust-core error.rs after   61      52     51     0       1(1)           9        0        100%
#   rust-core scalar.rs after  214     212    200    0       12(9)          2        0        98.5%
#   rust-core scalar.rs after+ 214     212    203    0       9(9)           2        0        100%
#   (after+: uint_to_f64's three mutants run again with tests/mutants_scalar.rs, all caught:
#   MUTATION_RUST_FILES=crates/px4params-core/src/scalar.rs MUTATION_RUST_ARGS="--re scalar.rs:201:5: <the
#   tests above> --cargo-arg=--test=mutants_scalar" bash scripts/mutation.sh rust-core)
# The one open survivor of the store's after, 1045:30 (resolved_area's instance taken as
# index + first_slot - 1: each later parameter's resolved leaves shifted past its own area, into
# another's where the tables are given more room than table_slots asks for), is killed by
# tests/mutants_store_tables.rs's every_instance_reads_its_own_leaves_with_more_table_memory_than_needed,
# written after the run (planted by hand: red, "forty#1[1]" read as Int(-771), by another
# parameter's resolved leaf; restored: green), and by the run of that place's mutants after it (after+ above):
#   MUTATION_BUDGET=900 MUTATION_RUST_TIMEOUT=60 MUTATION_RUST_ARGS="--re store.rs:1045:30:" \
#     bash scripts/mutation.sh rust-store
# (both of 1045:30's caught, and the file's eight "delete field" mutants that cargo-mutants
# 27.1.0 adds whatever --re says: 6 caught, 2 equivalent). The other survivors are listed in
# scripts/mutation-equivalent.txt (mutrust3's sections): the seek's arm and seek itself,
# table/resolved/resolve as speed-ups, the located arm's unreached scalar case. rust-ffi's
# before has no test: tests/c_abi.rs, its only one, was written for issue 40 (the baseline
# leaves it out), so every viable mutant survives it. scalar.rs's open survivors, uint_to_f64
# -> 0.0 / 1.0 / -1.0 (a float field given an unsigned integer: no test wrote one), are killed
# by tests/mutants_scalar.rs (written after the run; 0.0 and 1.0 planted by hand: both tests
# red); its others and error.rs's one are or'ed disjoint bits, or int_to_f64's branch for
# 32-bit cores, which a host build never takes (scripts/mutation-equivalent.txt). The tests
# given to error.rs and scalar.rs are those that reach them (their unit tests, codec, walk,
# store, file, scalar, the saturated store writes), not all of the crate's twenty programs
# (each mutant would link them all): the targets rust-error and rust-scalar above run the
# same, and their baselines leave the issue-40 files out (the runs above were before them:
# a baseline of rust-core with MUTATION_RUST_FILES takes every test program of the crate).
# Their "before" (run as these targets, each in two halves):
#   MUTATION_BASELINE=1 MUTATION_RUST_ARGS="--shard 0/2" bash scripts/mutation.sh rust-error   # and 1/2
#   MUTATION_BASELINE=1 MUTATION_RUST_ARGS="--shard 0/2" bash scripts/mutation.sh rust-scalar  # and 1/2
#   rust-error  before 61 mutants, 52 tested, 51 caught, 1 missed (1 equivalent), 9 unviable, 100%
#               (the same as after: the tests issue 40 added catch nothing more here)
#   rust-scalar before 214 mutants, 212 tested, 200 caught, 12 missed (9 equivalent), 2 unviable,
#               98.5% (the same as the after run above, before tests/mutants_scalar.rs:
#               uint_to_f64's three the open ones; with it, 100%)
# bits.rs (258 mutants): not run.
# store/spec.py and store/flat.py (mutstore4, issue 40, fifth round): the untested remainders of
# both, going on from mutstore3's kept results, one mutant at a time (scripts/mutation-by-id.sh's
# loop: the mutants not tested with the current tests first, in file order, then the earlier
# results not killed) with mutmut's --rerun-all and a mutmut_config.py of its own (not in the
# repository): its pre_mutation hook runs a mutant first with those of the target's tests that
# execute its line (node IDs from one run of the target's tests traced with sys.settrace, the
# fastest first); what they let through is run again with all of the target's tests
# (--rerun-all), so a survivor is always one of the whole target's; a line executed at import
# runs them all. store-flat ran in up to four copies of the work tree at once, each given its
# own lines, their caches merged by mutant. The baseline time kept from
# the runs' start (store-flat 20 s, store-spec 12 s, measured at load 3) was kept when the tests
# changed: measured again at load 12 it was 72 s and 35 s, and a hanging mutant (mutmut's
# timeout is 10 baselines) would have cost 12 minutes.
#   before: the tests as they were (commit 5a6d6e3), 09:20-09:53, then the tests written for
#   this round's first survivors (commit 3c41a61) and the runs again from where they stopped
#   (the targets' entries are unchanged; mutation-by-id.sh's mutmut run given --rerun-all and
#   the hook above, its first line the first untested one):
#   bash scripts/mutation-by-id.sh store-spec python/px4params/store/spec.py \
#     "tests/test_spec.py -k 'not pydronecan and not page_api and not mavlink and not param_set and not force_says and not airframe and not params_file and not json_export'" 319 11:04
#   bash scripts/mutation-by-id.sh store-flat python/px4params/store/flat.py \
#     "tests/test_flat.py -k 'not round_trip_through_the_store'" 190 11:04
#   MUTATION_REPORT_ONLY=1 bash scripts/mutation.sh store-spec store-flat      # the figures
# Measured 2026-11-27 (2 shared cores, load 8-13; equivalents left out of the rates; the
# results kept from earlier rounds count as before):
#   target      run     mutants tested killed timeout survived equivalent untested kill rate
#   store-spec  before      416    294    279       0       15          9      122     97.9%
#   store-spec  after       416    416    388       0       28         27        0     99.7%
#   store-flat  before      588    201    187       0       14          8      387     96.9%
#   store-flat  after       588    579    544       3       32         20        9     97.9%
# "before" stopped at 09:53 (the new tests were written meanwhile): its untested are those it
# had not reached. The survivors not equivalent after are each killed by a test written after
# the runs' tests (commit 3c41a61), planted by hand (mutmut apply in a copy): red, restored,
# green. store-spec: _FLOAT_MAX's 65505 (test_in_type_range_is_the_dsdl_types_own_range's
# 65505 case). store-flat: the length's max(2, ...) (test_a_dynamic_arrays_length_has_the_
# bits_of_its_maximum), the three "XXvalueXX" roles (test_every_leaf_that_is_no_tag_nor_length_
# has_the_role_value), to_flat's two tao=True (test_a_value_and_its_stored_bytes_give_the_same_
# letters), the tag's <= (test_a_union_tag_one_past_the_last_variant_is_refused), the mask
# loop's break (test_a_shared_parameter_has_no_instance_mask), find from at + 2 (test_a_
# parameter_name_ending_in_an_underscore_has_flat_names_too), "XX0123456789XX" (test_the_24th_
# letter_x_follows_an_instance_number), _why's two and/or (test_a_leaf_that_is_not_live_names_
# the_first_requirement_that_fails). store-flat's 9 untested are earlier rounds' results not
# tested again with these tests before 11:05: 8 survivors, all listed equivalent (lines 133
# twice, 156, 190, 241, 244, 249, 254), and letters()'s divmod(number - 2) timeout (an endless
# loop, as its twin number -= 1, tested again: timeout). The timeouts: those two and _parse's
# find from at - 1 and end = 1 (endless loops).

# The whole core's 1/60 sample again (the lead, issue 40, after the one interpreter merged:
# interp.rs, walk.rs rewritten; the sample is the crate's every 60th mutant as it is now, 68 of
# ~4,060, so another sample than 2026-11-26's), one run each on a quiet machine (~6 min):
#   MUTATION_BASELINE=1 MUTATION_BUDGET=900 MUTATION_RUST_TIMEOUT=120 \
#     MUTATION_RUST_ARGS="--shard 0/60 --sharding round-robin" bash scripts/mutation.sh rust-core
#   MUTATION_BUDGET=1800 MUTATION_RUST_TIMEOUT=120 \
#     MUTATION_RUST_ARGS="--shard 0/60 --sharding round-robin" bash scripts/mutation.sh rust-core
# (the after run first, its results copied aside: both write target/mutation/rust-core).
# Measured 2026-11-27 (equivalents left out of the rates):
#   rust-core sample  before: 68 mutants, 58 tested, 45 caught, 13 missed (3 equivalent), 10
#                     unviable, 0 untested, 81.8%
#                     after: 68, 58 tested, 54 caught, 4 missed (3 equivalent), 10 unviable, 0
#                     untested, 98.2%; with mutants_translate (written for the fourth: translate's
#                     report -> (), planted by hand: red) 100%
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_translate"

# bits.rs on its own (the lead, issue 40; after only, cut by its 25 min budget at load 2-4):
#   MUTATION_RUST_FILES="crates/px4params-core/src/bits.rs" MUTATION_BUDGET=1500 \
#     MUTATION_RUST_TIMEOUT=120 bash scripts/mutation.sh rust-core
#   bits.rs  after: 258 mutants, 180 tested, 164 caught, 3 timed out, 13 missed (all 13
#            equivalent: field_mask_halves' | -> ^ listed now, the others by earlier rounds), 7
#            unviable, 71 untested (budget), 100% of tested

# Six files of the core whole (the lead, issue 40, sixth round: codec.rs, rules.rs, layout.rs,
# value.rs, compile.rs, translate.rs; 298 mutants). A mutant rebuilds every test program it
# runs, so the first pass ran ten (--lib, codec, parity, walk, program, straight, store and
# three mutants_*; 20-30 s a mutant at load 5-8), stopped by the session's clock; its survivors
# were then run again with every test program of the crate (--re, one exact pattern each):
#   F="crates/px4params-core/src/codec.rs crates/px4params-core/src/rules.rs ..."   # the six
#   T="--iterate --cargo-arg=--lib --cargo-arg=--test=codec --cargo-arg=--test=parity ..."
#   CARGO_PROFILE_DEV_DEBUG=0 MUTATION_RUST_FILES="$F" MUTATION_BUDGET=5000 \
#     MUTATION_RUST_TIMEOUT=45 MUTATION_RUST_ARGS="$T" bash scripts/mutation.sh rust-core
#   CARGO_PROFILE_DEV_DEBUG=0 MUTATION_RUST_FILES="$F" MUTATION_RUST_TIMEOUT=60 \
#     MUTATION_RUST_ARGS="--re=^<survivor>$ ..." bash scripts/mutation.sh rust-core
# Measured 2026-11-27 (equivalents left out of the rate):
#   first pass   298 mutants, 212 tested: 187 caught or did not build (the earlier passes' 50
#                are counted together by --iterate; 19 unviable in the last), 4 timed out, 21
#                survived; 86 untested (the rest of translate.rs and value.rs: budget)
#   survivors again with every test program: 13 caught (mutants_compile and mutants_rules,
#                written for them: check_bits -> Ok, the array arm of push, both Display impls,
#                scalar_raw's signed fast path == -> != and its Int, Uint(0|1), Int(0|1) arms,
#                scalar_bits' Void arm; and translate_value(_with) -> Ok(0/1) by the store's
#                translation tests), 8 survived: 5 equivalent (the plan-or-walk dispatch in
#                codec.rs x4, translate's leave > -> >=), 3 killed by the test written after
#                the rerun (mutants_translate: a type as deep as the codec follows translates
#                with its report; DEPTH_MAX's * -> + planted: red, * -> / leaves fewer
#                frames still; the array frame's name.is_empty() guard -> false planted: red)
#   after        212 tested, 0 survivors that are not equivalent: 100% of tested
# Then, on a quiet machine (~5 s a mutant), the rest (MUTATION_RUST_FILES one file each, the
# same ten test programs, translate.rs with mutants_store_translated too, timeout 30 s):
#   value.rs      48 mutants: 38 caught, 10 unviable, 0 survived
#   translate.rs  83 mutants: 74 caught, 7 unviable, 2 survived: leave's > -> >= (equivalent)
#                 and begin_array's && -> || (an array inside elements reported kept on its
#                 own: mutants_translate's deep type now checks the report names the array
#                 once; planted: red)
#   the six files: 298 mutants, all tested, 5 survivors, all equivalent: 100%
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_compile mutants_rules"

# Four more files of the core (mutcore, issue 40, seventh round: program.rs, table.rs, bits.rs,
# straight.rs; interp.rs, leaf.rs and walk.rs were other helpers'). Each file on its own with
# the test programs that reach it (grep: only tests/program.rs calls program.rs; table.rs the
# table's and the store's tests; bits.rs and straight.rs nearly every program), on 2 shared
# cores at load 2-4 (4-20 s a mutant); then each first-pass survivor again by name (one --re
# each, its words exact, any line: the fix moved program.rs's lines) with every test program
# that reaches its file and the tests written for the survivors:
#   F=crates/px4params-core/src/program.rs   # and table.rs, bits.rs, straight.rs
#   T="--cargo-arg=--test=program"   # one --cargo-arg each: table: --test=table,
#     # mutants_table, mutants_store_tables; bits: --lib, bits, codec, straight (two runs,
#     # the second with --iterate); straight: a sample, --shard k/8 --sharding round-robin
#     # with straight, parity, codec (shards 0 and 1; 2 and 3 with the rerun's programs)
#   CARGO_PROFILE_DEV_DEBUG=0 MUTATION_RUST_FILES=$F MUTATION_BUDGET=2400 \
#     MUTATION_RUST_TIMEOUT=60 MUTATION_RUST_ARGS="$T" bash scripts/mutation.sh rust-core
#   CARGO_PROFILE_DEV_DEBUG=0 MUTATION_RUST_FILES=$F MUTATION_RUST_TIMEOUT=90 \
#     MUTATION_RUST_ARGS="<programs> --re=program\.rs:\d+:\d+:\sreplace\s\+\swith\s\*...$ ..." \
#     bash scripts/mutation.sh rust-core
# The rerun's programs: program.rs: program, mutants_program; table.rs: --lib, table,
# mutants_table, mutants_store_tables, store, mutants_store, store_alloc,
# mutants_store_set_from, mutants_store_saturate, mutants_store_translated, file, pages;
# straight.rs: --lib, straight, parity, codec, mutants_straight, walk, mutants_walk, transfer,
# file, store, mutants_rules, leaf_path. Two files ran at a time, each with a target directory
# of its own (CARGO_TARGET_DIR, which moves target/mutation too), their builds one at a time
# under the build lock (scripts/mutation-cargo.sh).
# Measured 2026-11-27 (equivalents left out of the rate; "first" is the first pass, "after"
# with the tests written for its survivors; the new equivalence lines went to the lead):
#   file         run    mutants tested caught timeout survived(equiv.) unviable untested rate
#   program.rs   first      247    232    195       1       36(20)          15        0  92.5%
#   program.rs   after      247    232    211       1       20(20)          15        0   100%
#   table.rs     first      251    231    192       3       36(28)          20        0  96.1%
#   table.rs     after      251    231    200       3       28(28)          20        0   100%
#   bits.rs      first      258    248    226       5       17(17)          10        0   100%
#   straight.rs  first      233    230    190       0       40(26)           3      232  93.1%
#   straight.rs  after      233    230    204       0       26(26)           3      232   100%
# Then straight.rs's other half (the lead, shards 4-7 of 8, quiet machine, ~3 s a mutant, with
# the rerun's programs from the start; "after" with a_byte_string_after_four_bits_takes_the_
# whole_bytes_left, written for measure's 724:38 / -> %: planted by hand, red):
#   for k in 4 5 6 7; do CARGO_PROFILE_DEV_DEBUG=0 MUTATION_RUST_FILES=$F MUTATION_BUDGET=600 \
#     MUTATION_RUST_TIMEOUT=60 MUTATION_RUST_ARGS="--shard $k/8 --sharding round-robin \
#     --cargo-arg=--lib <the rerun's programs>" bash scripts/mutation.sh rust-core; done
#   straight.rs  s4-7       232    232    204       1       27(17)           0        0  95.3%
#   straight.rs  s4-7 after 232    232    205       1       26(17)           0        0  95.8%
# Nine survivors not yet examined (the session's time): 94:23 || -> && in compile, 128:56 and
# 128:68 in small's version guard, 181:46 in raw_of, 421:30 and 424:35 in encode_small,
# 304:25 in Out::spill, 731:13 in measure, 889:72 in read_elements.
# bits.rs: whole at last (the earlier run left 71 untested); its 17 survivors all listed by
# earlier rounds; no test written. straight.rs: a sample, shards 0 to 3 of 8 (every 8th
# mutant, round-robin); the other mutants untested (time).
# program.rs: the first pass found a real bug: a struct at the nesting bound holding fields,
# and an array whose elements pass it, had a program that encoded what the walk refuses
# (TooDeep; a 64-level struct chain as 1 byte): fixed in program.rs (each field's and
# element's depth checked as the walk counts it). tests/mutants_program.rs (a program answers
# as the walk, or declines, from MAX_DEPTH - 3 to MAX_DEPTH + 3 levels of structs, unions,
# arrays and structs holding unions; a p_version that is a struct; dynamic arrays up to and
# past their maximum, arrays of primitives and of composites told apart) kills 16: the depth
# checks' 12, root, the version guard, primitive() -> None, the length guard. 20 equivalent:
# speed-ups (Fixed, the window sizes, scalar_at's Uint arm, a field compiled as a value of its
# own, the byte-string fast path's guard), unions' tags of 1 bit or more, dynamic arrays'
# lengths of 1 bit or more, the last item's depth. Not run: the binding's Python tests over an
# extension built from each mutant (a release build each): the 20 are equivalent for any
# ValueSource whose byte() agrees with element(), as the binding's does.
# table.rs: tests/mutants_table.rs (appended) kills 8: LeafTable::read's 4 (leaf by leaf
# against hand-worked bytes and leaf::seek, with its p_version flag), is_empty -> true, the
# union-number limit's 2 (unions numbered 2^19 - 1 to 2^19 + 1) and, written after the rerun,
# a union variant's depth + 1 -> * 1 (unions in unions around MAX_DEPTH; planted: red). The
# store's tests kill none of the others: the store's speed-ups (resolved leaves, read_known,
# the bound of a valid stored value), or'ed disjoint bits, END/GOTO/WALK as 0, a run past
# 2^32 bits (listed: unreachable, not equivalent).
# straight.rs: tests/mutants_straight.rs (a byte string after the fixed run, alone after its
# prefix and 70 long; a p_version given another version, too large for its field, twice;
# floats beyond float16 and float32, integers and a byte of 300; the leaves a value takes from
# a longer list; each against the walk and hand-worked bytes) kills 13 (3 of them, in shard 2,
# written after its run: planted, red); the rerun's other programs one (measure's n > max ->
# >=). 26 equivalent (1 listed before): small plans and fast paths refused where the general
# loop or the casting rules give the same bits, orders of one byte, disjoint bits, `at` and a
# 4-byte store after the value's end. Shards 2 and 3 ran with the rerun's programs and the
# mutants_straight of their start, so their first pass is nearly their after.
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_program mutants_straight"

if [ "$#" -eq 0 ]; then
  set -- can_transfer dronecan_params health links gui migrate vehicle store rust-core rust-ffi
fi

restore() {
  # mutmut restores each file after its mutant; a run cut short (budget, Ctrl-C) may not.
  git checkout -- python 2>/dev/null || true
  find python -name '*.py.bak' -delete 2>/dev/null || true
  rm -f mutmut_config.py
}

python_target() {
  local name=$1 paths=$2 tests=$3
  if ! command -v mutmut >/dev/null; then
    echo "$name: skipped: mutmut is not installed (pip install 'mutmut==2.5.1')"
    return
  fi
  if [ -n "$(git status --porcelain -- python)" ]; then
    echo "$name: refused: python/ has uncommitted changes (mutmut edits files in place)" >&2
    exit 1
  fi
  # The cache of each target is kept: a later run tests again only what survived or was not
  # reached (mutmut keeps killed mutants killed). It notices new tests by a hash of the tests
  # directory: the baseline hashes a copy of its own test files, so that the next full run
  # tests its survivors again.
  local tests_dir=tests cache
  if [ "${MUTATION_BASELINE:-0}" = 1 ]; then
    tests=$(echo "$tests" | sed -E "s#(^| )tests/($NEW_TESTS)\.py##g")
    tests="-m 'not issue40' $tests" # and the tests marked for issue 40 (pyproject.toml's marker)
    tests_dir=$(mktemp -d)
    for f in $tests; do
      case $f in tests/*.py) cp "$f" "$tests_dir/" ;; esac
    done
    cache="$OUT/$name.baseline.mutmut-cache"
  else
    cache="$OUT/$name.mutmut-cache"
    [ -f "$cache" ] || [ ! -f "$OUT/$name.baseline.mutmut-cache" ] ||
      cp "$OUT/$name.baseline.mutmut-cache" "$cache"
  fi
  [ "${MUTATION_FRESH:-0}" = 1 ] && rm -f "$cache"
  rm -f .mutmut-cache
  [ -f "$cache" ] && cp "$cache" .mutmut-cache
  if [ "${MUTATION_REPORT_ONLY:-0}" = 1 ]; then
    if [ ! -f .mutmut-cache ]; then
      echo "$name: no results kept in $cache: nothing to report"
      return
    fi
  else
    trap restore EXIT
    trap 'restore; exit 130' INT TERM
    # mutmut imports mutmut_config.py from its working directory: its hooks (see the file)
    cp scripts/mutation_lines.py mutmut_config.py
    local budget started=$SECONDS lines="" rerun=()
    budget=$(budget_for "$name")
    if [ "${MUTATION_BY_LINE:-0}" = 1 ]; then
      lines="$OUT/$name.lines.json"
      timeout --signal=INT --kill-after=60 "$budget" python scripts/mutation_lines.py \
        "$lines" "$paths" "$tests" >"$OUT/$name.lines.log" 2>&1 ||
        echo "$name: the traced run's tests failed (see $OUT/$name.lines.log)" >&2
      rerun=(--rerun-all)
      budget=$((budget - (SECONDS - started)))
      [ "$budget" -gt 0 ] || budget=1
    fi
    MUTATION_LINES="$lines" timeout --signal=INT --kill-after=60 "$budget" mutmut run \
      --paths-to-mutate "$paths" --tests-dir "$tests_dir" \
      --runner "bash scripts/mutation-pytest.sh -x -q -p no:cacheprovider $tests" \
      "${rerun[@]}" --simple-output --no-progress >"$OUT/$name.log" 2>&1 || true
    restore
    trap - EXIT INT TERM
  fi
  python - "$name" "$OUT/$name.txt" "${cache%.mutmut-cache}.figures" <<'EOF'
"""Counts the cache's mutants and lists each survivor as path, original line, mutated line;
writes the figures as one tab-separated line for the table at the end."""
import sqlite3
import subprocess
import sys
from pathlib import Path

name, report, figures = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
equivalent = {}
for line in Path("scripts/mutation-equivalent.txt").read_text().splitlines():
    if line.strip() and not line.startswith("#"):
        path, old, new, why = line.split("\t")
        equivalent[(path, old, new)] = why
db = sqlite3.connect(".mutmut-cache")
rows = db.execute(
    "SELECT Mutant.id, Mutant.status, SourceFile.filename, Line.line_number,"
    " Mutant.tested_against_hash FROM Mutant"
    " JOIN Line ON Mutant.line = Line.id JOIN SourceFile ON Line.sourcefile = SourceFile.id"
).fetchall()
(tests_hash,) = db.execute("SELECT value FROM MiscData WHERE key = 'hash_of_tests'").fetchone()
counts = {"killed": 0, "timeout": 0, "survived": 0, "untested": 0}
survivors, equivalents = [], 0
for mutant, status, path, number, tested_against in rows:
    if status != "ok_killed" and tested_against != tests_hash:
        status = "untested"  # a result of earlier tests, not yet tested again with these
    if status in ("ok_killed", "ok_suspicious"):
        counts["killed"] += 1
    elif status == "bad_timeout":
        counts["timeout"] += 1
    elif status == "bad_survived":
        counts["survived"] += 1
        diff = subprocess.run(
            ["mutmut", "show", str(mutant)], capture_output=True, text=True, check=False
        ).stdout.splitlines()
        old = next((d[1:].strip() for d in diff if d.startswith("-") and not d.startswith("---")), "")
        new = next((d[1:].strip() for d in diff if d.startswith("+") and not d.startswith("+++")), "")
        why = equivalent.get((path, old, new))
        equivalents += why is not None
        mark = f"equivalent: {why}" if why else "SURVIVED"
        survivors.append(f"{path}:{number + 1}\t{old}\t{new}\t{mark}")
    else:
        counts["untested"] += 1
tested = len(rows) - counts["untested"]
detected = counts["killed"] + counts["timeout"]
rate = f"{100 * detected / (tested - equivalents):.1f}%" if tested > equivalents else "-"
report.write_text("".join(f"{s}\n" for s in survivors))
numbers = (len(rows), tested, counts["killed"], counts["timeout"], counts["survived"])
figures.write_text("\t".join(map(str, (*numbers, equivalents, counts["untested"], rate))) + "\n")
print(
    f"{name}: {len(rows)} mutants, {tested} tested: {counts['killed']} killed, "
    f"{counts['timeout']} timed out, {counts['survived']} survived ({equivalents} equivalent), "
    f"{counts['untested']} untested; kill rate {rate} (killed + timed out over tested less "
    f"equivalent); survivors in {report}"
)
EOF
  mv .mutmut-cache "$cache"
}

rust_target() {
  local name=$1 path=$2 tests=$3
  # crates/<package>, or crates/<package>/src/<file>.rs to mutate that file only.
  local package
  package=$(echo "$path" | cut -d/ -f2)
  if ! cargo mutants --version >/dev/null 2>&1; then
    echo "$name: skipped: cargo-mutants is not installed (cargo install cargo-mutants)"
    return
  fi
  # Builds share the machine: one job, and each mutant's build under the build lock when there
  # is one (cargo-mutants runs cargo as $CARGO: scripts/mutation-cargo.sh takes the lock per
  # build, so a long run never keeps other builds out for longer than one build).
  local scope=()
  case $path in *.rs) scope+=(--file "$path") ;; esac
  for f in ${MUTATION_RUST_FILES:-}; do
    scope+=(--file "$f")
  done
  local features=()
  [ "$package" = px4params-core ] && features=(--features alloc)
  # The tests: the target's cargo test options, else all of the crate's. The baseline leaves
  # out the test files issue 40 added, and the doc tests (cargo runs them only on their own).
  # Given to every cargo command (--cargo-arg), so that a mutant builds only the test
  # programs that run: the others would cost a build each and tell nothing.
  local chosen=() t f
  for t in $tests; do
    if [ "${MUTATION_BASELINE:-0}" = 1 ] && [[ " $RUST_ISSUE40_TESTS " == *" ${t#--test=} "* ]]; then
      continue
    fi
    chosen+=("--cargo-arg=$t")
  done
  if [ "${MUTATION_BASELINE:-0}" = 1 ] && [ -z "$tests" ]; then
    for f in "crates/$package"/tests/*.rs; do
      t=$(basename "$f" .rs)
      case " $RUST_ISSUE40_TESTS " in *" $t "*) continue ;; esac
      chosen+=("--cargo-arg=--test=$t")
    done
  fi
  if [ "${MUTATION_BASELINE:-0}" = 1 ]; then
    # never an empty choice, which would be every test
    [[ " ${chosen[*]} " == *" --cargo-arg=--lib "* ]] || chosen+=(--cargo-arg=--lib)
  fi
  # shellcheck disable=SC2206 # extra options, split on spaces on purpose
  local extra=(${MUTATION_RUST_ARGS:-})
  # An interrupted cargo-mutants keeps the lists of the mutants it finished. cargo-mutants is
  # run as itself, not as `cargo mutants` (cargo would set CARGO to its own path).
  # Its own target directory: cargo names a workspace member's artifacts by its path inside
  # the workspace, so a mutated copy's and the work tree's collide, and a work tree build after
  # a run was seen to take the last mutant's library for up to date.
  # MUTATION_REPORT_ONLY=1: count the last run's lists again (after the equivalents changed).
  [ "${MUTATION_REPORT_ONLY:-0}" = 1 ] ||
    env CARGO_TARGET_DIR="$OUT/cargo-target" MUTATION_REAL_CARGO="$(command -v cargo)" \
      CARGO="$ROOT/scripts/mutation-cargo.sh" timeout --signal=INT --kill-after=60 "$BUDGET" \
      nice cargo-mutants mutants --package "$package" "${features[@]}" --jobs 1 \
      --timeout "${MUTATION_RUST_TIMEOUT:-300}" "${scope[@]}" "${chosen[@]}" --output "$OUT/$name" \
      "${extra[@]}" >"$OUT/$name.log" 2>&1 || true
  local results="$OUT/$name/mutants.out"
  local caught missed timeout unviable
  caught=$( (wc -l <"$results/caught.txt") 2>/dev/null || echo 0)
  # With --iterate, what earlier runs caught (or found unviable) is skipped and listed here.
  local earlier
  earlier=$( (wc -l <"$results/previously_caught.txt") 2>/dev/null || echo 0)
  missed=$( (wc -l <"$results/missed.txt") 2>/dev/null || echo 0)
  timeout=$( (wc -l <"$results/timeout.txt") 2>/dev/null || echo 0)
  unviable=$( (wc -l <"$results/unviable.txt") 2>/dev/null || echo 0)
  # Each survivor, marked equivalent where scripts/mutation-equivalent.txt gives the reason.
  local equivalents total
  read -r equivalents total < <(python3 - "$results" "$OUT/$name.txt" <<'EOF'
"""Marks cargo-mutants' missed mutants ("path:line:col: what") listed as equivalent; prints
their count and the number of mutants in scope."""
import json
import sys
from pathlib import Path

results, report = Path(sys.argv[1]), Path(sys.argv[2])
missed = results / "missed.txt"
scope = results / "mutants.json"
total = len(json.loads(scope.read_text())) if scope.exists() else 0
equivalent = {}
for line in Path("scripts/mutation-equivalent.txt").read_text().splitlines():
    if line.strip() and not line.startswith("#"):
        path, what, tool, why = line.split("\t")
        if tool == "(cargo-mutants)":
            equivalent[(path, what)] = why
lines, count = [], 0
for entry in missed.read_text().splitlines() if missed.exists() else []:
    where, what = entry.split(": ", 1)
    path, line, column = where.split(":")
    # By the words, or where the same words name several mutants, by line:col and words.
    why = equivalent.get((path, what)) or equivalent.get((path, f"{line}:{column}: {what}"))
    count += why is not None
    lines.append(f"{entry}\t{f'equivalent: {why}' if why else 'SURVIVED'}")
report.write_text("".join(f"{s}\n" for s in lines))
print(count, total)
EOF
  )
  # With --iterate, mutants.json holds only this run's mutants: the earlier ones are in scope too.
  total=$((total + earlier))
  local untested=$((total - earlier - caught - missed - timeout - unviable))
  echo "$name: $total mutants, $((caught + missed + timeout)) viable tested: $caught killed," \
    "$timeout timed out, $missed survived ($equivalents equivalent); $unviable unviable (did" \
    "not build); $untested untested (budget); $earlier caught by earlier runs (--iterate);" \
    "survivors in $OUT/$name.txt"
}

for name in "$@"; do
  entry=""
  for t in "${TARGETS[@]}"; do
    [ "${t%%|*}" = "$name" ] && entry=$t
  done
  if [ -z "$entry" ]; then
    echo "unknown target $name (expected one of: ${TARGETS[*]%%|*})" >&2
    exit 1
  fi
  IFS='|' read -r _ paths tests <<<"$entry"
  case $name in
    rust-*) rust_target "$name" "$paths" "$tests" ;;
    *) python_target "$name" "$paths" "$tests" ;;
  esac
done

# The table of the Python targets of this run: "before" is the baseline's (MUTATION_BASELINE=1),
# "after" the run with every test; the kill rate leaves the equivalent survivors out.
table=""
for name in "$@"; do
  for run in before after; do
    f="$OUT/$name.figures"
    [ "$run" = before ] && f="$OUT/$name.baseline.figures"
    if [ -f "$f" ]; then
      table+="$name|$run|$(tr '\t' '|' <"$f")"$'\n'
    fi
  done
done
if [ -n "$table" ]; then
  echo
  printf '%-16s %-6s %7s %6s %6s %7s %8s %10s %8s %9s\n' target run mutants tested killed \
    timeout survived equivalent untested "kill rate"
  while IFS='|' read -r name run mutants tested killed timeout survived equivalents untested rate; do
    printf '%-16s %-6s %7s %6s %6s %7s %8s %10s %8s %9s\n' "$name" "$run" "$mutants" "$tested" \
      "$killed" "$timeout" "$survived" "$equivalents" "$untested" "$rate"
  done <<<"${table%$'\n'}"
fi
# links/, second round (issue 40, mutlinks): mavlink.py's constructor and turn timing tested
# (tests/test_mavlink.py's TestTurnByTurnSetup, before TestTurnByTurn so that -x meets them
# first), mavlink_messages.py through pymavlink's mavmmaplog. The runs, each going on from the
# kept results (target/mutation/<target>.mutmut-cache):
#   MUTATION_BUDGET_mavlink=1800 nice bash scripts/mutation.sh mavlink
#   nice bash scripts/mutation.sh mavlink_messages
#   MUTATION_BUDGET_mavlink_signing=1500 nice bash scripts/mutation.sh mavlink_signing
#   MUTATION_BUDGET_slcan=840 nice bash scripts/mutation.sh slcan
# Measured 2026-11-27 (2 shared cores, load 7; equivalents left out of the rates): mavlink 544
# mutants, 193 tested, 171 killed, 2 timed out, 20 survived (18 equivalent), 351 untested,
# 98.9% (the 2 others, line 353's wait for the next burst, killed by
# test_while_a_list_streams_a_turn_waits_no_longer_than_until_the_next_burst, planted by hand:
# written after the run); mavlink_messages 102, all tested, 66 killed, 36 equivalent, 100%;
# mavlink_signing 115, all tested, 113 killed, 2 equivalent, 100%; slcan 308, 245 tested,
# 236 killed, 9 equivalent, 63 untested, 100%. dronecan_node and dronecan_client: not run.

# vehicle/ (issue 40, mutveh2, fourth round): boards.py with test_boards.py alone (in-process:
# parse_boards on TOML written in the test, the bundled table, render_markdown; 3-5 s a mutant),
# and autostart.py's remainder, run afresh with test_autostart.py. The tests written for the
# survivors are marked issue40 (the baseline leaves them out). Issue 40's figures:
#   MUTATION_BASELINE=1 nice bash scripts/mutation.sh boards autostart     # before
#   nice bash scripts/mutation.sh boards autostart                         # after
# (MUTATION_BUDGET_autostart=1500 was enough for the baseline's 216 mutants, 15 min at load 7.)
# Measured 2026-11-27 (2 shared cores, load 6-8; equivalents left out of the rates):
#   boards     before 665 mutants, 665 tested, 561 killed, 104 survived (0 equivalent), 84.4%;
#              after  665 mutants, 664 tested, 634 killed, 30 survived (30 equivalent), 100%
#              (12 min); the 1 untested is render_markdown's rc.sensors `continue` (a line
#              written twice: mutmut 2's line-text lookup), planted by hand as `break`: killed by
#              test_docs_list_a_launcher_of_one_address_and_every_rc_sensors_row.
#   autostart  before 216 mutants, 216 tested, 117 killed, 99 survived (7 equivalent), 56.0%
#              (15 min); after 216 mutants, 215 tested, 203 killed, 12 survived (12 equivalent),
#              100% (the tests mutstore wrote killed 80; of the last 11, the 5 tests written for
#              them killed 6, 5 are equivalent); the 1 untested is Configured.startable's
#              `@property` (a line written three times),
#              planted by hand (removed): killed by six tests of test_autostart.py.
#   drivers    (never run before) MUTATION_BASELINE=1 MUTATION_BUDGET_drivers=1500, then
#              MUTATION_BUDGET_drivers=600 (test_simbench.py, test_autostart.py; 24 + 6 min):
#              before 322 mutants, 322 tested, 260 killed, 62 survived, 80.7%; after 322, 322
#              tested, 265 killed, 57 survived (none listed equivalent yet), 82.3% (the
#              existing issue40 tests killed 3, test_autostart.py's
#              test_a_declaration_with_a_bad_parameter_or_chip_name_is_named 2). Not worked
#              yet: ~23 are in drivers.toml's error paths (the `raise fail(...)` lines: some
#              messages no test of this target checks whole, e.g. "is shared", "also_chips"),
#              ~21 Driver dataclass defaults, the rest
#              parse_drivers' ranges and Drivers' lookups (target/mutation/drivers.txt lists
#              them). gui-app, gui-vehicle: not run here.
# Rust, issue 40 (mutrust, second round): rust-store's shards 1-9 of 10 (slice sharding of
# store.rs's 336 mutants: 39 in shard 0, 34 each in 1-8, 25 in 9), each run at most 600 s, two
# runs at a time (the second with CARGO_TARGET_DIR=target/lane2: a target directory of its own):
#   MUTATION_BASELINE=1 MUTATION_BUDGET=600 MUTATION_RUST_TIMEOUT=60 \
#     MUTATION_RUST_ARGS="--shard 2/10" bash scripts/mutation.sh rust-store            # before
# then the before's survivors and timeouts of several shards tested again with every test (the
# after's tests include the before's, so what the before caught stays caught), and the
# mutants a shard's budget left, by name (one --re per mutant, as the rust-core sample):
#   MUTATION_BUDGET=600 MUTATION_RUST_TIMEOUT=60 MUTATION_RUST_ARGS="--re ^<name>$ ..." \
#     bash scripts/mutation.sh rust-store                                               # after
# MUTATION_RUST_TIMEOUT=20 timed the unmutated baseline out at load 6-9 (table.rs's property
# tests take 11 s alone, 20-36 s there): 60 s. CARGO_PROFILE_DEV_DEBUG=0 (no debug info) halves
# a mutant's build. tests/store_alloc.rs is flaky under load (its counting allocator counts
# every thread's allocations: 4 extra ones in 1 run of 12 on an unmutated tree): two kills and
# two baselines were its flake; those two mutants were tested again by hand (183:30 survives the
# before's tests; resolved_area's Some((1, 1)) fails table.rs).
# Measured 2026-11-27 (load 6-9; equivalents left out of the rates), per shard before / after:
#   shard  mutants  tested  caught  timeout  missed(equiv.)  unviable  untested  kill rate
#   1      34       29/29   14/29   2/0      13(0)/0         5         0/0       55.2%/100%
#   2      34       17/17   12/17   0/0      5(0)/0          7         10/10     70.6%/100%
#   3      34       5/8     3/5     0/0      2(1)/3(3)       3         26/23     75.0%/100%
#   4      34       7/8     3/7     0/0      4(1)/1(1)       0         27/26     50.0%/100%
#   5      34       8/7     4/4     0/0      4(4)/3(3)       0         26/27     100%/100%
#   6      34       8/8     8/8     0/0      0/0             8         18/18     100%/100%
#   7      34       22/22   21/22   0/0      1(0)/0          0         12/12     95.5%/100%
#   8      34       26/26   18/19   0/0      8(7)/7(7)       0         8/8       94.7%/100%
#   9      25       23/23   22/22   0/0      1(1)/1(1)       2         0/0       100%/100%
#   1-9    297      145/148 105/133 2/0      38(14)/15(15)   25        127/124   81.7%/100%
# (the after tested some mutants the before did not reach: cargo-mutants 27.1.0 runs the
# "delete field" mutants of the file whatever --re says; 1236:37 of shard 8 was planted by hand.)
# Shard 1's 2 timeouts were at MUTATION_RUST_TIMEOUT=20 (both caught after). Shards 1, 7, 8, 9
# are (nearly) whole; about half of shards 2-6 is not run yet: go on with one --re per untested
# mutant (shard 9's after is a run of the shard with every test). The rust-core sample's
# store.rs mutants, planted by hand: 609:17 (changed) and 1147:9 (values_equal -> true) fail
# tests/mutants_store.rs, 1237:14 (+= -> -=) table.rs; 1039:9 (resolved_area -> None) is
# equivalent, 264:9 unviable.
# rust-crc (179 mutants: crc.rs's const tables give many): a before run of 472 s tested 12, all
# caught; rust-pages (66 mutants) and rust-file: not run in this round.
# store/spec.py and store/flat.py (mutstore2, issue 40, third round). store-spec's entry is
# redefined above (before the main loop, so that it takes effect): test_spec.py's in-process
# tests only. The runs (each goes on from target/mutation/<target>.mutmut-cache):
#   MUTATION_FRESH=1 MUTATION_BASELINE=1 MUTATION_BUDGET_store_spec=1800 nice bash scripts/mutation.sh store-spec
#   nice bash scripts/mutation.sh store-spec                           # after (1800 s)
#   MUTATION_BUDGET_store_flat=1140 nice bash scripts/mutation.sh store-flat   # after, afresh
#   MUTATION_REPORT_ONLY=1 bash scripts/mutation.sh store-spec store-flat      # the recount
# Measured 2026-11-27 (2 shared cores, load 6-9; equivalents left out of the rates):
#   store-spec before: 416 mutants, 207 tested, 91 killed, 0 timed out, 116 survived
#     (19 equivalent), 209 untested: 48.4%
#   store-spec after: 416, 293 tested, 256 killed, 0 timed out, 37 survived (26 equivalent),
#     123 untested: 95.9%. Of the 11 others, 10 are killed by tests written after the run
#     (test_spec.py's integer bounds next to the type's own and the public checks' bounds
#     default, each planted by hand: red); the one left: `"0" <= before <= "XX9XX"` in
#     default_param_name, which only a type name with two capitals in a row tells apart
#     (RPMCommand: RPMCOMMAND or RPM_COMMAND?), and no doc says which: open.
#   store-flat after (no before of its own here: the earlier 360 s sample, above): 588 mutants,
#     201 tested, 177 killed, 2 timed out, 22 survived (6 equivalent), 387 untested: 91.8%. Of
#     the 16 others, 12 are killed by test_flat.py's tests written after the run (planted by
#     hand: red); 4 left: `if n else 1` for an array of no elements (twice; pydsdl may refuse
#     such arrays: not checked), p_version of kind int, and a 2-variant union's tag as uint2.
# migrate-build: not run.
# links/, third round (issue 40, mutlinks2): mavlink.py's untested part, slcan.py's 63 untested
# and dronecan_client.py, each going on from the kept results (target/mutation/<target>.*):
#   MUTATION_BUDGET_mavlink=3000 nice bash scripts/mutation.sh mavlink     # 3000 s: 87 mutants
#   MUTATION_BUDGET_slcan=900 nice bash scripts/mutation.sh slcan
#   MUTATION_BUDGET_dronecan_client=1380 nice bash scripts/mutation.sh dronecan_client
# dronecan_client had no run before: no "before" figures (its baseline, tests of other files
# only, was not run). Measured 2026-11-27 (2 shared cores, load 5-8; equivalents left out of
# the rates; each run's survivors tested against the tests of its start, so the tests written
# after a run were checked by planting each survivor by hand: red, restored, green):
#   target           mutants tested killed timeout survived equivalent untested kill rate
#   mavlink  before      544    109     40       0       69         10      435     40.4%
#   mavlink  after       544    280    238       2       40         24      264     93.8%
#   slcan    after       308    307    282       4       21         11        1     96.6%
#   dronecan_client      193    193    178       1       14          6        0     95.7%
# Of the survivors not equivalent, killed by the tests written after the run (planted by hand):
# mavlink all 16 (test_mavlink.py's TestTurnByTurnReceiving, TestTurnByTurnSigned); slcan 9 of
# 10 (test_slcan.py's issue40 tests at its end; the one left: open_serial's write_timeout 2 for
# 3, a bound no rule fixes and no test can tell without timing) and its untested one (`return
# b""` in _FdPort.read, a line written twice: killed); dronecan_client all 8
# (test_dronecan_client.py's issue40 tests at its end). mavlink's 264 untested (lines 424-821)
# not run again in this round (a mavlink run after new tests first tests its 40 survivors
# again, ~40 s each here). dronecan_node, a first 560 s afresh (no results were kept here):
#   MUTATION_BUDGET_dronecan_node=560 nice bash scripts/mutation.sh dronecan_node
# 271 mutants, 95 tested (lines 55-140), 86 killed, 9 survived (all 9 equivalent, listed
# before), 176 untested, 100%.

# gui/app.py, gui/vehicle.py, vehicle/drivers.py (issue 40, mutveh3, fifth round). The tests
# written for this round are marked issue40 (tests/test_drivers.py is new: NEW_TESTS); the
# baselines run test_app.py's and test_gui_vehicle.py's earlier tests (the block before the
# run loop). Each run niced, in a clone of its own (mutmut mutates files in place):
#   MUTATION_BASELINE=1 MUTATION_BUDGET_gui_app=1800 nice bash scripts/mutation.sh gui-app
#   (cut by its budget at 88 of 121; then again, MUTATION_BUDGET_gui_app=1200, for the rest)
#   MUTATION_BUDGET_gui_app=1500 nice bash scripts/mutation.sh gui-app                   # after
#   MUTATION_BASELINE=1 nice bash scripts/mutation.sh gui-vehicle   # stopped (SIGTERM) once
#     past StoreVehicle (line 205): no baseline test constructs a MavlinkVehicle or calls
#     _as_stored/_mftp_path, so each mutant of lines 200-496 would survive it
#   bash scripts/mutation-by-id.sh gui-vehicle python/px4params/gui/vehicle.py \
#     tests/test_gui_vehicle.py 197 08:06     # after: MavlinkVehicle's mutants first, by ID
#   MUTATION_FRESH=1 MUTATION_BUDGET_drivers=4200 nice bash scripts/mutation.sh drivers   # after
#   MUTATION_REPORT_ONLY=1 [MUTATION_BASELINE=1] bash scripts/mutation.sh gui-app gui-vehicle drivers
# Measured 2026-11-27 (2 shared cores, load 12-16; equivalents left out of the rates):
#   target       run     mutants tested killed timeout survived equivalent untested kill rate
#   gui-app      before      121    121    113       0        8          5        0     97.4%
#   gui-app      after       121    119    114       0        5          5        2    100.0%
#   gui-vehicle  before      377    112     93       0       19         14      265     94.9%
#   gui-vehicle  after       377    179    166       0       13         13      198    100.0%
#   drivers      after       322    322    315       0        7          7        0    100.0%
# drivers' before is mutveh2's (322 mutants, 265 killed, 57 survived, 82.3%; no baseline run
# this round). gui-app's 2 untested are the mutants of `store = getattr(vehicle, "store", None)`
# (a line written twice: mutmut 2's line-text lookup), planted by hand ("XXstoreXX", None):
# killed by test_the_files_of_a_store_with_its_own_types_carry_their_parameters.
# gui-vehicle is not finished: 198 untested. 179 are on lines 319-496 (the rest of
# _fetch_metadata, _download, the receive and heartbeat threads, STATUSTEXT chunks, refresh,
# write, read, close, _mftp_path), never reached at ~40 s a mutant (load 15): go on with
# scripts/mutation-by-id.sh as above. Of those, planted by hand and red with
# test_gui_vehicle.py's issue40 tests: the receive loop's `continue` -> `break` on a quiet
# 0.2 s, errors' "error" tag, ".lzma", the ACK's `and` -> `or`, the heartbeat thread's
# `while not` -> `while`, both threads' daemon=False, " (signed)", the connect wait's
# blocking=False, _mftp_path's split("]", 2). The other 19 are on lines before 197, tested
# against earlier test files of this round (18 survived: 14 equivalent; the 4 others,
# StoreVehicle's classic_params None and metadata None, the watcher's daemon=False and its
# `continue` -> `break`, are killed by the issue40 tests, each planted by hand).
# drivers' first run with test_drivers.py (before its last three tests): 313 killed, 9
# survived; the frozen dataclass and parse_drivers' "<drivers>" default are killed by
# test_a_declaration_cannot_be_changed_once_read and test_declarations_given_as_text_are_named_as_such.
# links/, fourth round (issue 40, mutlinks3): mavlink.py's untested part, dronecan_node.py's
# rest, slcan.py's and dronecan_client.py's last untested, each going on from the kept results
# (target/mutation/<target>.mutmut-cache), the survivors of earlier runs not tested again (their
# results carried over to the run's tests: a survivor stays one until planted by hand).
#   MUTATION_BUDGET_dronecan_node=4200 nice bash scripts/mutation.sh dronecan_node
#   MUTATION_BUDGET_slcan=540 nice bash scripts/mutation.sh slcan
#   MUTATION_BUDGET_dronecan_client=540 nice bash scripts/mutation.sh dronecan_client
#   MUTATION_BUDGET_mavlink=3100 nice bash scripts/mutation.sh mavlink     # in 3 lanes, see below
#   MUTATION_REPORT_ONLY=1 bash scripts/mutation.sh mavlink dronecan_node slcan dronecan_client
# mavlink.py's ~250 untested at 1 a minute (load 10-15) ran in three copies of the work tree at
# once, each given a mutmut_config.py (not in the repository) whose pre_mutation skipped the
# mutants outside its lines (0-based [0,599), [599,719), [719,)) and ran each mutant first with
# the target's tests about its function only (-k narrowed); the three caches were merged by
# mutant. Narrowed survivors were first run again with all of the target's tests (mutmut's
# rerun_all): at load 15 that run outlasted mutmut's timeout (10 x the 20 s baseline), so 14
# "timeouts" were survivors of the narrowed tests: counted as survivors below, each planted by
# hand; later narrowed survivors were left to be planted by hand (no rerun).
# Measured 2026-11-27 (2 shared cores, load 7-15; equivalents left out of the rates):
#   target           run    mutants tested killed timeout survived equivalent untested kill rate
#   mavlink          before     544    109     40       0       69         14      435     42.1%
#   mavlink          after      544    523    444       2       77         39       21     92.1%
#   dronecan_node    before     271    141     46       0       95         12      130     35.7%
#   dronecan_node    after      271    269    241       1       27         16        2     95.7%
#   slcan            after      308    307    286       4       17         12        1     98.3%
#   dronecan_client  after      193    191    179       1       11          6        2     97.3%
# Of the survivors not equivalent, all are killed by tests (each planted by hand: red):
# mavlink's 18 of earlier runs by test_mavlink.py's TestTurnByTurnReceiving/Signed and the
# bytewise tests, one by test_a_param_set_message_packs_bytewise_as_mavlink_2_unless_asked_for_1;
# this round's 20 by TestTurnByTurnQuiet and TestTurnByTurnFileAndClock (written for them);
# dronecan_node's 11 by test_dronecan_node.py (the tests at its end, written for them, and the
# counters' test); slcan's 5 and dronecan_client's 5 by their test files' issue40 tests.
# Untested: dronecan_node's 2 and dronecan_client's 2 are lines written twice, planted by hand:
# red (test_a_restart_starts_the_uptime_again written for one); slcan's 1 likewise (mutlinks2).
# mavlink's 21: lines written more than once (`return True` five times in _handle, the `0,`
# fields of AUTOPILOT_VERSION and HEARTBEAT, `self._stream = None`, ...: mutmut 2's line-text
# lookup); 8 planted by hand: the five `return True` of _handle (killed by
# test_every_request_it_serves_is_counted_received_not_ignored, written for them), line 503's
# `self._stream = None`, 716's `0,`, 422's `now = time.monotonic()` (killed by earlier tests); the
# other 13 planted by hand by the lead (each `mutmut apply <id>` from the merged cache in a clone,
# then tests/test_mavlink.py -x): all 13 red (`address` without @property, `signing is None` twice,
# the target check's `and` as `or`, AUTOPILOT_VERSION's and HEARTBEAT's `0,` fields as 1,
# PARAM_ERROR, COMMAND_ACK, HEARTBEAT and STATUSTEXT built as None). mavlink: none untested open.
# No "before" of dronecan_client, slcan (no baseline runs: no time on the shared cores).
# rust-crc on the host (issue 40, lead, 2026-11-27; load 2-3):
#   MUTATION_BUDGET=1500 MUTATION_RUST_TIMEOUT=60 CARGO_PROFILE_DEV_DEBUG=0 bash scripts/mutation.sh rust-crc
#   rust-crc: 179 mutants, 156 viable tested: 136 killed, 20 survived (20 equivalent: 4 as
#   before, 16 in firmware's code that a host build never runs, killed by rust-compact-crc), 23
#   unviable, 0 untested: 100%.
# MUTATION_BY_LINE=1 (issue 40, muttools): each mutant first with the tests that execute its
# line, then all of the target's if those let it through (scripts/mutation_lines.py). No kept
# results were left from the earlier rounds, so each target ran afresh, in a clone of its own
# (git clone; /tmp/shared -> /work/shared; the built _native.abi3.so copied in):
#   MUTATION_BY_LINE=1 MUTATION_FRESH=1 MUTATION_BUDGET_store_flat=3600 nice bash scripts/mutation.sh store-flat
#   MUTATION_BY_LINE=1 MUTATION_FRESH=1 MUTATION_BUDGET_migrate_build=240 nice bash scripts/mutation.sh migrate-build
#   MUTATION_IDS="<the 43 mutants of lines written twice>" MUTATION_BY_LINE=1 nice bash \
#     scripts/mutation-by-id.sh migrate-build python/px4params/migrate/build.py "<its tests>" 1 14:00
#   MUTATION_BY_LINE=1 MUTATION_BUDGET_migrate_build=2700 nice bash scripts/mutation.sh migrate-build
# Measured 2026-11-27 (2 shared cores, load 4-9, beside the lead's cargo-mutants):
#   target         run    mutants tested killed timeout survived equivalent untested kill rate
#   store-flat     after      588    385    370       2       13         13      203    100.0%
#   migrate-build  after      686    524    496       0       28         26      162     99.6%
# store-flat's 9 left untested by mutstore4 are tested: lines 133 (twice), 156, 190, 241, 244,
# 249, 254 survive, all 8 listed equivalent; letters()'s divmod(number - 2) times out (an
# endless loop), as number -= 1 on line 112. Its 203 untested are lines 505-774 (budget).
# migrate-build's lines written twice (43 mutants: `continue`, `return False`, `)`, ...), each by
# ID: 41 killed, 2 survived (field_value's two `return False`, listed equivalent); 162 untested
# (budget: lines 606-825). Its 2 other survivors, line 389's `getattr(r, "when", "")` as
# "XXwhenXX" and the row filter's `and` as `or`, are of lines written after the equivalents were
# listed (left to migrate/build.py's owner).
# Plain against by line, store-spec afresh, both at once (900 s each, load 4-10):
#   MUTATION_FRESH=1 MUTATION_BUDGET_store_spec=900 nice bash scripts/mutation.sh store-spec
#   MUTATION_BY_LINE=1 MUTATION_FRESH=1 MUTATION_BUDGET_store_spec=900 nice bash scripts/mutation.sh store-spec
# plain tested 84, by line 88 (its traced run, 31 s, included), the same verdicts for the 84
# (killed or suspicious alike): ~10.5 s against ~9.7 s a mutant. Most of a mutant's time here
# is pytest's start and collection, paid by both; by line gains where the killing test comes
# late in the file and on survivors of a long suite.
