#!/usr/bin/env bash
# The mutation run (scheduled with the long runs, not part of scripts/test.sh): small mistakes
# are planted in the code one at a time, and the tests that cover it are run against each; a
# mutant the tests let through is a blind spot (issue 40). Prints, per target, the mutants,
# killed (tests failed, or hung: a timeout), survived, and of those the ones listed as
# equivalent in scripts/mutation-equivalent.txt (a change no test can see, with the reason).
# Each target's figures before and after, and the commands that measured them: docs/mutation.md.
#
#   bash scripts/mutation.sh [TARGET ...]       default: the list after the targets below
#   MUTATION_BUDGET=600     seconds per target (default: the target's in BUDGETS below, else
#                           1800); what is left is "untested". MUTATION_BUDGET_session=600:
#                           one target's (its name with - as _)
#
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
#   MUTATION_PATCH=F.diff   Python: mutate only the lines F adds or changes (mutmut's
#                           --use-patch-file; `git diff BASE -- FILE > F.diff`, paths from the
#                           repository root): a module changed since its latest whole run is
#                           tested again on those lines. Its results are kept apart
#                           (target/mutation/<target>.patch.mutmut-cache; MUTATION_FRESH=1
#                           forgets them) and its figures are of those lines alone; with
#                           MUTATION_REPORT_ONLY=1, MUTATION_PATCH=1 counts them again.
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
# Each target prints its line; the run ends with the table of each target's before
# (MUTATION_BASELINE=1) and after. The packages links/, gui/, migrate/, vehicle/, store/ have
# thousands of mutants and do not finish in one budget on 2 shared cores: the Python targets
# below are one module each, and a package's name runs its modules' targets (PACKAGES) and adds
# the package's sum to the table. Rust targets are one crate, or one file of the core; a run
# cut short by its budget goes on where it stopped with MUTATION_RUST_ARGS=--iterate, which
# skips what was caught and tests again what survived.
#
# Python: mutmut 2 (pip install "mutmut==2.5.1", the "mutation" extra), which mutates the
# files in place, one at a time, and restores them; so the work tree must be clean, and is
# restored with git if the run is cut short. Rust: cargo-mutants (cargo install
# cargo-mutants) over the core and the C ABI crate with their Rust tests (the C ABI's are
# crates/px4params-ffi/tests/c_abi.rs, calling its functions as C does). The survivors of each
# target are written to target/mutation/<target>.txt (<target>.baseline.txt, <target>.patch.txt).
# mutmut 2.5.1 looks up kept results by a line's text: a mutant of a line that occurs twice in
# its file (two identical `raise` or `continue` lines) stayed "untested" in a run that started
# from earlier results. Every Python run is given scripts/mutation_lines.py as mutmut's
# mutmut_config.py, whose init() looks them up by line number too.
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
  "health|$PY/vehicle/health.py,$PY/cli/commands/health.py|tests/test_flight_log.py tests/test_dronecan.py tests/test_health.py tests/test_reading.py -k 'health or first_failure'"
  # One module at a time, where a whole package does not finish in a budget: those that matter
  # most for "a broken sensor never silent, nothing lost", each with the fast tests that cover it
  # (the tests written for its survivors first: -x stops at the first that fails).
  "session|$PY/store/session.py|tests/test_session.py tests/test_session_write_path.py -k 'not cli and not dronecan and not over_mavlink and not disjoint and not mavlink_serve'"
  "migrate-config|$PY/migrate/config.py,$PY/migrate/proposal.py|tests/test_migrate_config.py tests/test_migrate.py tests/test_migrate_defects.py tests/test_migrate_upgrade.py"
  "devid|$PY/vehicle/devid.py|tests/test_devid.py"
  "flight_log|$PY/vehicle/flight_log.py|tests/test_flight_log.py"
  "mavlink_ftp|$PY/links/mavlink_ftp.py|tests/test_mavlink_ftp.py tests/test_mavlink_metadata.py tests/test_mavlink_security.py -k 'ftp or open_read or naks or sessions_run or list_directory or crc32 or burst or slices or garbage'"
  "admission|$PY/gui/admission.py|tests/test_gui_security.py"
  # gui/ and links/ one module at a time (mutlinks), with their in-process tests only (a few
  # seconds a mutant): the tests that start the page's server or `dronecan serve` take 25-40 s
  # each on 2 shared cores (the target admission above runs the server's).
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
  # each, left out: a mutant would build them for little), and transfer's (a payload longer
  # than the 64 bytes a host gathers is read in pieces: only they receive one).
  "rust-scatter|crates/px4params-core/src/scatter.rs|--lib --test=mutants_scatter --test=codec --test=walk --test=pages --test=transfer --test=mutants_transfer"
  "rust-transfer|crates/px4params-core/src/transfer.rs|--lib --test=mutants_transfer --test=codec"
)
# The Rust test files issue 40 added: MUTATION_BASELINE=1 leaves them out (the "before").
RUST_ISSUE40_TESTS="c_abi crc file pages mutants_transfer mutants_scatter mutants_store"
# links/ and gui/, the rest module by module (issue 40, mutnet), each with in-process tests only
# (a peer's bytes written by hand or by pymavlink/pydronecan, the ASGI app driven directly).
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
# (the long runs' package targets keep them).
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
# every 60th mutant of the crate (MUTATION_RUST_ARGS="--shard 0/60 --sharding round-robin"). The
# sample cannot go on with --iterate (which drops what was caught before sharding, so the shard is
# another sample): a run cut short by its budget goes on with --re, one exact pattern per mutant
# of the sample not yet tested, each an exact regex of its name as --list prints it (re.escape,
# spaces as \s: the options are split on spaces) and --file for their files.
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_leaf"
# vehicle/ and gui/, the modules not run before, one at a time (issue 40, mutveh, second round),
# each with its in-process tests only (no page server, no Chromium).
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
# no subprocess, no server).
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
  # the smaller modules of store/, with their in-process tests
  "store-spec|$PY/store/spec.py|tests/test_spec.py -k 'not pydronecan and not page_api and not mavlink'"
  "store-long_names|$PY/store/long_names.py|tests/test_dronecan.py tests/test_flat.py tests/test_flat_on_demand.py -k long_name"
  "store-key|$PY/store/key.py|tests/test_key.py"
)
BUDGETS+=([store-paramfile]=1800 [store-classic]=1200 [store-flat]=3600 [migrate-build]=3600)
BUDGETS+=([store-spec]=1800 [store-long_names]=1200 [store-key]=1200)
NEW_TESTS="$NEW_TESTS|test_paramfile|test_classic"
# Rust (mutrust): each mutant's build takes the build lock on its own
# (scripts/mutation-cargo.sh). The tests issue 40 added for the nesting bound (MAX_DEPTH) of the
# walk and of the leaf table, and for Store::set_from's saturate flag:
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_walk mutants_table mutants_store_set_from"

# links/ module by module (issue 40, mutlinks): mavlink.py's target again (this entry replaces
# the one above: the last entry of a name wins), mavlink_messages.py, identity.py, serving.py,
# each with in-process tests only (the server driven turn by turn, pymavlink building and
# parsing the frames; threads, no subprocesses), -x stopping at the first test that fails.
# (A test named by node ID must not be in a NEW_TESTS file: the baseline strips the file's name.)
# mavlink.py's ~550 mutants take 2-11 s each here: a run cut short by its budget goes on where
# it stopped.
TARGETS+=(
  "mavlink|$PY/links/mavlink.py|tests/test_mavlink.py -k 'TurnByTurn or bytewise or param_value_of or development_version or signalling_nan'"
  "mavlink_messages|$PY/links/mavlink_messages.py|tests/test_mavlink_messages.py tests/test_mavlink_metadata.py::test_every_command_long_is_answered"
  "identity|$PY/links/identity.py|tests/test_identity.py tests/test_mavlink.py::test_autopilot_version_and_heartbeat"
  "serving|$PY/links/serving.py|tests/test_serving.py tests/test_mavlink.py::test_list_read_set"
)
BUDGETS+=([mavlink]=3600 [mavlink_messages]=900 [identity]=600 [serving]=600)
NEW_TESTS="$NEW_TESTS|test_mavlink_messages|test_identity|test_serving"

# gui/manifest.py (issue 40, mutveh, third round) runs its in-process tests (/api/manifest
# driven over ASGI, no server, no browser); the tests written for its survivors are marked
# issue40 in tests/test_gui_manifest.py.
# store/key.py, store/long_names.py (mutstore, issue 40, second round): these entries replace
# the ones above. key.py's parser is held to the name expression by test_store.py's tests of
# names (test_key.py alone reached it only through the store), and the long names' tests
# written for issue 40 are tests/test_long_names.py.
TARGETS+=(
  "store-key|$PY/store/key.py|tests/test_key.py tests/test_store.py -k 'test_key or names_are_split or parsed_once or inexact_name or under_an_inexact or destructured_name_is_exact or naming_errors or not_text'"
  "store-long_names|$PY/store/long_names.py|tests/test_long_names.py tests/test_dronecan.py tests/test_flat.py tests/test_flat_on_demand.py -k 'long_name or test_long_names'"
)
NEW_TESTS="$NEW_TESTS|test_long_names"
BUDGETS+=([store-long_names]=2400) # 1200 s left 23 of 138 untested at load 6
# store/spec.py (mutstore2, issue 40, third round): this entry replaces the one above. Its
# in-process tests only: the CLI tests of test_spec.py start 36 subprocesses (9 s a mutant
# against 3 s).
TARGETS+=(
  "store-spec|$PY/store/spec.py|tests/test_spec.py -k 'not pydronecan and not page_api and not mavlink and not param_set and not force_says and not airframe and not params_file and not json_export'"
)

# Rust, issue 40 (mutrust, second round): these entries replace the ones above. pages.rs and
# crc.rs with the test programs that reach them (all of the crate's would rebuild twenty test
# programs per mutant): pages.rs through its
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
# the mutants are those of that code only (one --re each, by line or by function: the patterns
# in docs/mutation.md), so that the host's code, dead in this build, is not counted again.
# (cargo-mutants 27.1.0 adds the file's "delete field" mutants whatever --re says.)
TARGETS+=(
  "rust-compact-crc|crates/px4params-core/src/crc.rs|--features=compact --lib --test=crc --test=transfer --test=mutants_transfer --test=file"
  "rust-compact-store|crates/px4params-core/src/store.rs|--features=compact --test=store --test=mutants_store --test=table --test=mutants_store_tables --test=mutants_store_set_from --test=mutants_store_saturate --test=mutants_store_translated --test=file"
)
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_store_saturate"
# file.rs (this entry replaces the one above): its tests and those written for its survivors.
TARGETS+=("rust-file|crates/px4params-core/src/file.rs|--test=file --test=mutants_file")
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_file"
# gui/app.py, gui/vehicle.py and vehicle/drivers.py's survivors (issue 40, mutveh3). The
# earlier tests of test_app.py and test_gui_vehicle.py are the "before" (the tests written for
# this round's survivors are marked issue40): the files leave NEW_TESTS, else the baseline
# would strip every test file of these targets (and pytest, given none, run the whole suite).
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
  "migrate-build|$PY/migrate/build.py|tests/test_migrate_build.py tests/test_migrate_board_rows.py tests/test_migrate_upgrade.py tests/test_migrate.py tests/test_migrate_defects.py tests/test_migrate_config.py -k 'not cli and not needs_no_checkout'"
)
NEW_TESTS="$NEW_TESTS|test_migrate_build"
# (11-27 night) and the conditions' and the driver axes' tests, which reach build.py too:
TARGETS+=(
  "migrate-build|$PY/migrate/build.py|tests/test_migrate_build.py tests/test_migrate_board_rows.py tests/test_migrate_upgrade.py tests/test_migrate_axes.py tests/test_migrate_conditions.py tests/test_migrate.py tests/test_migrate_defects.py tests/test_migrate_config.py -k 'not cli and not needs_no_checkout'"
)

# scalar.rs and error.rs on their own (mutrust3): the programs that reach them, not all twenty
# of the crate's; their baselines leave the issue-40 files out (a baseline of rust-core with
# MUTATION_RUST_FILES takes every test program of the crate).
TARGETS+=(
  "rust-error|crates/px4params-core/src/error.rs|--lib --test=codec --test=walk --test=mutants_walk --test=store --test=mutants_store --test=file"
  "rust-scalar|crates/px4params-core/src/scalar.rs|--lib --test=scalar --test=mutants_scalar --test=mutants_store_saturate --test=codec --test=walk --test=mutants_walk --test=store --test=mutants_store --test=file"
)
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_scalar"

# scatter.rs's firmware build (the lead, 11-28): without the gathering plan a transfer's payload
# is never one run, so the contiguous() offered to readers differs from the host's.
TARGETS+=("rust-compact-scatter|crates/px4params-core/src/scatter.rs|--features=compact --lib --test=mutants_scatter --test=codec --test=walk --test=pages --test=transfer --test=mutants_transfer")


# translate's report (the rust-core sample's last survivor, the lead):
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_translate"


# The tests written for the survivors of codec.rs, rules.rs, layout.rs, value.rs, compile.rs,
# translate.rs (the lead, sixth round):
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_compile mutants_rules"

# The tests written for the survivors of program.rs and straight.rs (mutcore, seventh round):
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_program mutants_straight"
RUST_ISSUE40_TESTS="$RUST_ISSUE40_TESTS mutants_interp"

# The two product files no target held (the lead, 11-27 night): migrate/conditions.py, which
# decides whether a board script's line runs on the vehicle (its own tests, and the board-row and
# migration tests that evaluate real boards' conditions), and vehicle/simbench.py.
TARGETS+=(
  "migrate-conditions|$PY/migrate/conditions.py|tests/test_migrate_conditions.py tests/test_migrate_board_rows.py tests/test_migrate_build.py tests/test_migrate_upgrade.py tests/test_migrate.py tests/test_boards.py -k 'not cli and not needs_no_checkout'"
  "simbench|$PY/vehicle/simbench.py|tests/test_simbench.py tests/test_flight_log.py"
)
BUDGETS+=([migrate-conditions]=3600 [simbench]=3600)

# The last files of the five packages no target held (the lead, 11-28): migrate/axes.py (the
# drivers whose axes PX4 changed, with the migration tests that turn a rotation) and
# store/layout_tables.py (the store's tables that `metadata --firmware` writes as C).
TARGETS+=(
  "migrate-axes|$PY/migrate/axes.py|tests/test_migrate_axes.py tests/test_migrate_upgrade.py tests/test_migrate_build.py tests/test_migrate_board_rows.py tests/test_migrate_corpus.py -k 'not cli and not needs_no_checkout'"
  "store-layout_tables|$PY/store/layout_tables.py|tests/test_firmware.py"
)
BUDGETS+=([migrate-axes]=3600 [store-layout_tables]=1200)

# The five packages issue 40 names, each as the targets of its files: a package mutated whole
# does not finish in a budget on 2 cores, each file with the tests that reach it does. A
# package's row in the table is the sum of its files' (health's target also holds
# cli/commands/health.py; the packages' __init__.py files hold only docstrings and imports).
declare -A PACKAGES=(
  [links]="can_transfer dronecan_client dronecan_node dronecan_params identity mavlink mavlink_ftp mavlink_messages mavlink_signing serving slcan"
  [gui]="gui-admission gui-app gui-files gui-manifest gui-vehicle"
  [migrate]="migrate-axes migrate-build migrate-conditions migrate-config"
  [vehicle]="autostart boards console devid drivers flight_log health simbench timeline"
  [store]="session store-classic store-file store-flat store-key store-layout_tables store-long_names store-paramfile store-spec store-store"
)

if [ "$#" -eq 0 ]; then
  set -- links gui migrate vehicle store rust-core rust-ffi
fi
packages=()
expanded=()
for name in "$@"; do
  if [ -n "${PACKAGES[$name]:-}" ]; then
    packages+=("$name")
    read -ra members <<<"${PACKAGES[$name]}"
    expanded+=("${members[@]}")
  else
    expanded+=("$name")
  fi
done
set -- "${expanded[@]}"

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
  elif [ -n "${MUTATION_PATCH:-}" ]; then
    # the lines of a diff, in a cache of their own (a whole run's stays as it was)
    cache="$OUT/$name.patch.mutmut-cache"
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
    local patch=()
    [ -z "${MUTATION_PATCH:-}" ] || patch=(--use-patch-file "$(realpath "$MUTATION_PATCH")")
    MUTATION_LINES="$lines" timeout --signal=INT --kill-after=60 "$budget" mutmut run \
      --paths-to-mutate "$paths" --tests-dir "$tests_dir" \
      --runner "bash scripts/mutation-pytest.sh -x -q -p no:cacheprovider $tests" \
      "${rerun[@]}" "${patch[@]}" --simple-output --no-progress >"$OUT/$name.log" 2>&1 || true
    restore
    trap - EXIT INT TERM
  fi
  python - "$name" "${cache%.mutmut-cache}.txt" "${cache%.mutmut-cache}.figures" <<'EOF'
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
# "after" the run with every test, "lines" the lines of MUTATION_PATCH's diff; the kill rate
# leaves the equivalent survivors out.
runs=(before after)
[ -z "${MUTATION_PATCH:-}" ] || runs=(lines)
table=""
for name in "$@"; do
  for run in "${runs[@]}"; do
    f="$OUT/$name.figures"
    [ "$run" = before ] && f="$OUT/$name.baseline.figures"
    [ "$run" = lines ] && f="$OUT/$name.patch.figures"
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
# Each package named: the sum of its files' figures, where every file has them.
for package in "${packages[@]}"; do
  for run in before after; do
    sums=(0 0 0 0 0 0 0) have=0
    read -ra members <<<"${PACKAGES[$package]}"
    for name in "${members[@]}"; do
      f="$OUT/$name.figures"
      [ "$run" = before ] && f="$OUT/$name.baseline.figures"
      [ -f "$f" ] || continue
      have=$((have + 1))
      read -ra numbers <"$f"
      for i in 0 1 2 3 4 5 6; do sums[i]=$((sums[i] + numbers[i])); done
    done
    if [ "$have" -eq 0 ]; then
      continue
    elif [ "$have" -lt "${#members[@]}" ]; then
      echo "$package ($run): figures of $have of its ${#members[@]} targets only: no sum"
      continue
    fi
    read -r mutants tested killed timeout survived equivalents untested <<<"${sums[*]}"
    rate=-
    [ "$tested" -gt "$equivalents" ] &&
      rate=$(awk "BEGIN { printf \"%.1f%%\", 100 * ($killed + $timeout) / ($tested - $equivalents) }")
    printf '%-16s %-6s %7s %6s %6s %7s %8s %10s %8s %9s\n' "$package/" "$run" "$mutants" \
      "$tested" "$killed" "$timeout" "$survived" "$equivalents" "$untested" "$rate"
  done
done
