#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, -fsanitize=fuzzer,address,undefined) in build-fuzz/ and runs
# each for a bounded time from its seed corpus: fuzz_master (the master's decoders, fuzz/corpus/),
# fuzz_records (the record-set reader, fuzz/corpus-records/) and fuzz_fit_model (the fit.json
# loader, the export and the step kernels, fuzz/corpus-fit-model/). New inputs go to
# build-fuzz/corpus-<target>/, never to the repository; a crashing input is saved as
# build-fuzz/<target>-crash-* and the script fails.
#
#   fuzz/run.sh [SECONDS=60] [libFuzzer options…]   the seconds split between the targets: half
#                                                    to fuzz_master, a quarter to each of the others
#   fuzz/run.sh --only TARGET SECONDS [options…]     one target, e.g. fuzz/run.sh --only fuzz_records 600
#   fuzz/run.sh --regen-corpus                       rewrites fuzz/corpus/ (fuzz/make_corpus.cc); the
#                                                    records and fit.json seeds are files written by hand
#                                                    (fuzz/corpus-records/README) and by piezoid fit
#   fuzz/run.sh --configure                          only configures build-fuzz/ (scripts/sanitize.sh
#                                                    builds its tests there: one sanitizer build for both)
#
# Without clang it says so and exits 0 (scripts/test.sh runs it when clang is installed).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${PIEZOID_FUZZ_BUILD_DIR:-build-fuzz}
CXX=${PIEZOID_FUZZ_CXX:-clang++}
CC=${PIEZOID_FUZZ_CC:-clang}
if ! command -v "$CXX" >/dev/null 2>&1; then
  echo "fuzz: $CXX not found: fuzzing skipped (scripts/deps.sh installs clang)"
  exit 0
fi
LAUNCHER=()
command -v ccache >/dev/null 2>&1 && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
# Tests are configured (not built) so that scripts/sanitize.sh can build some in this same tree.
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release "${LAUNCHER[@]}" \
  -DCMAKE_C_COMPILER="$CC" -DCMAKE_CXX_COMPILER="$CXX" \
  -DCMAKE_CXX_FLAGS_RELEASE="-O1 -gline-tables-only" -DCMAKE_C_FLAGS_RELEASE="-O1 -gline-tables-only" \
  -DPIEZOID_FUZZ=ON -DPIEZOID_BUILD_TESTS=ON -DPIEZOID_BUILD_BENCH=OFF >/dev/null
if [ "${1:-}" = "--configure" ]; then
  exit 0
fi
if [ "${1:-}" = "--regen-corpus" ]; then
  cmake --build "$BUILD" --target make_corpus
  rm -f fuzz/corpus/*
  "$BUILD/fuzz/make_corpus" fuzz/corpus
  ls fuzz/corpus
  exit 0
fi
# detect_leaks: the registry and protobuf keep process-lifetime allocations.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

# run TARGET SEED_CORPUS SECONDS [options…]
run() {
  local target=$1 seeds=$2 seconds=$3
  shift 3
  mkdir -p "$BUILD/corpus-$target"
  (set -x
   "$BUILD/fuzz/$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=8192 \
     -print_final_stats=1 -artifact_prefix="$BUILD/$target-" "$@" "$BUILD/corpus-$target" "$seeds")
}

if [ "${1:-}" = "--only" ]; then
  target=${2:?--only TARGET SECONDS}
  seconds=${3:?--only TARGET SECONDS}
  shift 3
  case $target in
    fuzz_master) seeds=fuzz/corpus ;;
    fuzz_records) seeds=fuzz/corpus-records ;;
    fuzz_fit_model) seeds=fuzz/corpus-fit-model ;;
    *) echo "fuzz: unknown target $target (fuzz_master, fuzz_records, fuzz_fit_model)" >&2; exit 2 ;;
  esac
  cmake --build "$BUILD" --target "$target"
  run "$target" "$seeds" "$seconds" "$@"
  exit 0
fi
SECONDS_TO_RUN=${1:-60}
shift || true
cmake --build "$BUILD" --target fuzz_master fuzz_records fuzz_fit_model
quarter=$(( SECONDS_TO_RUN / 4 > 0 ? SECONDS_TO_RUN / 4 : 1 ))
half=$(( SECONDS_TO_RUN - 2 * quarter > 0 ? SECONDS_TO_RUN - 2 * quarter : 1 ))
run fuzz_master fuzz/corpus "$half" "$@"
run fuzz_records fuzz/corpus-records "$quarter" "$@"
run fuzz_fit_model fuzz/corpus-fit-model "$quarter" "$@"
