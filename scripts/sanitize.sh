#!/usr/bin/env bash
# The records and client tests under AddressSanitizer + UndefinedBehaviorSanitizer: built in the
# clang tree of fuzz/run.sh (build-fuzz/, -fsanitize=fuzzer-no-link,address,undefined
# -fno-sanitize-recover=undefined on every target: one sanitizer build for the fuzzers and these
# tests) and run by ctest there. scripts/test.sh runs it when clang is installed
# (PIEZOID_SANITIZE=0 skips it).
#
#   scripts/sanitize.sh            the subset below
#   scripts/sanitize.sh REGEX      the tests whose ctest name matches REGEX (built first)
#
# The subset: every test that reads, windows, fits, checks, exports or replays user records
# (io_records, the records tests of the fit, its criteria, checks, extrapolation, excitation and
# stepper, and the client tests of the records commands, the property test of issue 37 among
# them). Left out for time, not for a reason of their own: the records tests that run whole
# diagnoses or real-like fits (records_diagnose, records_reallike, records_creep_spectrum,
# records_rate_dependence, records_check, records_decision, records_noise_floor,
# records_spectrum_solve, records_verdict, records_preisach) and the client tests of other
# commands (boucwen, committee, dahl, identify, the HGANN fin export, the job files, the
# dashboard's guard); their code paths are in the regular run, and records_preisach's window
# inside the rest (the crash of issue 37) is in the property test. Sanitizer build and run: see
# docs/performance.md, "Sanitizers".
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${PIEZOID_FUZZ_BUILD_DIR:-build-fuzz}
if ! command -v "${PIEZOID_FUZZ_CXX:-clang++}" >/dev/null 2>&1; then
  echo "sanitize: clang++ not found: the sanitizer run is skipped (scripts/deps.sh installs clang)"
  exit 0
fi
TESTS=(io_records_test records_fit_test records_criterion_test records_excitation_test records_stepper_test
       client_compensate_test client_export_c_test client_rate_dependence_cli_test client_records_property_test)
REGEX=${1:-}
if [ -n "$REGEX" ]; then
  fuzz/run.sh --configure
  mapfile -t TESTS < <(cd "$BUILD" && ctest -N -R "$REGEX" | sed -n 's/^ *Test *#[0-9]*: *//p')
else
  fuzz/run.sh --configure
  REGEX="^($(IFS='|'; echo "${TESTS[*]}"))\$"
fi
[ ${#TESTS[@]} -gt 0 ] || { echo "sanitize: no test matches $REGEX" >&2; exit 2; }
cmake --build "$BUILD" --target "${TESTS[@]}"
# detect_leaks: protobuf, the kinds' registry and spdlog keep process-lifetime allocations.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
(cd "$BUILD" && ctest --output-on-failure -j"$(nproc)" --timeout 900 -R "$REGEX")
